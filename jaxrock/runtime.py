"""What importing jaxrock does to the process's JAX, and when: float64 and the persistent
compilation cache (`jaxrock.cache`), set the moment JAX is imported.

Importing jaxrock does not import JAX (the command line prints its help and refuses bad arguments
without it; the package's names are imported on first use). So that every array of the process is
float64 as before, `install()` (run by `import jaxrock`) configures JAX right after JAX's own import
finishes, whoever imports it, or at once if JAX is already imported:

- `jax_enable_x64` on (jaxrock runs in float64 only; `JAXROCK_X64` other than 1 is refused);
- the persistent compilation cache (`jaxrock.cache.enable_compilation_cache`).

`use_cpu_cores()` (called by the command line; a library user's choice) gives the CPU backend one
device per core. Nothing is written to the environment, so child processes are left as they were.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys


def check_x64_variable() -> None:
    if os.environ.get("JAXROCK_X64", "1") != "1":
        raise ImportError(f"JAXROCK_X64 = {os.environ['JAXROCK_X64']!r}: jaxrock runs in float64 only (its float32 mode gave "
                          "wrong answers and was removed); unset the variable")


def configure_jax() -> None:
    """float64 and the persistent compilation cache, on the imported JAX."""
    import jax

    from .cache import enable_compilation_cache

    jax.config.update("jax_enable_x64", True)
    enable_compilation_cache()


_AFTER_IMPORT: list = []  # callables run once JAX is imported (`on_jax_import`)


class _AfterJaxImport(importlib.abc.MetaPathFinder):
    """Finds `jax` as the other finders do, and runs `_AFTER_IMPORT` once its module has executed."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname != "jax":
            return None
        sys.meta_path.remove(self)  # used once: the finders below find JAX's own spec
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        execute = spec.loader.exec_module

        def exec_module(module):
            execute(module)
            for fn in _AFTER_IMPORT:
                fn()

        spec.loader.exec_module = exec_module
        return spec


def on_jax_import(fn) -> None:
    """Run `fn()` as soon as JAX is imported (before anything uses it), or now if it is."""
    if "jax" in sys.modules:
        fn()
        return
    _AFTER_IMPORT.append(fn)
    if not any(isinstance(f, _AfterJaxImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _AfterJaxImport())


def cpu_cores() -> int:
    """The CPU cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def use_cpu_cores(n: int | None = None) -> None:
    """Give JAX's CPU backend one device per core, so that a sweep on a CPU runs one chunk per core.

    A device runs one computation at a time, whatever its cores (`jaxrock.run_sweep`). Takes effect
    if called before JAX starts its backends (its first computation); later, the backends keep their
    devices. The command line calls it first thing. Left alone where `XLA_FLAGS` already sets a host
    device count. Nothing is written to the environment.

    Arguments:
        n: the number of CPU devices; default None: the cores this process may run on (`cpu_cores()`).

    Example:
        ```python
        import jaxrock

        jaxrock.use_cpu_cores()  # before the first JAX computation
        ```
    """
    if "xla_force_host_platform_device_count" in os.environ.get("XLA_FLAGS", ""):
        return
    n = cpu_cores() if n is None else int(n)

    def configure():
        import jax

        try:
            jax.config.update("jax_num_cpu_devices", n)
        except RuntimeError:  # the backends have started: they keep their devices
            pass

    on_jax_import(configure)


def install() -> None:
    """Configure JAX now if it is imported, else as soon as it is."""
    check_x64_variable()
    on_jax_import(configure_jax)


__all__ = ["install", "configure_jax", "check_x64_variable", "on_jax_import", "use_cpu_cores", "cpu_cores"]
