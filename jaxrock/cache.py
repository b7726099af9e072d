"""What a process keeps for the next one: JAX's persistent compilation cache, on by default.

A jaxrock command spends most of a short run compiling; the compiled kernels are kept on disk so
that a second run loads them instead (`benchmarks/bench_latency.py` measures both).

- Where: `JAXROCK_CACHE_DIR` if set, else the user's cache folder (`platformdirs`:
  `~/.cache/jaxrock` on Linux, honouring `XDG_CACHE_HOME`), in a subfolder per jaxrock release and
  JAX version (`xla/jaxrock-<release>-jax-<version>`), so that an upgrade never reads an older
  release's entries and old folders can simply be deleted.
- Off: `JAXROCK_CACHE_DIR=off` (or `0`, or empty).
- What importing jaxrock does to the process (once JAX is imported: `jaxrock.runtime`): it sets
  JAX's `jax_compilation_cache_dir` to that folder and `jax_persistent_cache_min_compile_time_secs`
  to 0 (every kernel is kept: a spectrum compiles ~40 small ones besides its loops), unless the
  process has already chosen a cache folder of its own (`JAX_COMPILATION_CACHE_DIR` or
  `jax.config`), which is then left as it is.
  JAX keys each entry by the compiled program itself, its compiler version and flags, so a
  changed kernel is a new entry, never a stale hit. JAX reads the setting at its first
  compilation: import jaxrock before compiling anything to have it.
"""

from __future__ import annotations

import os
from importlib import metadata
from pathlib import Path

VARIABLE = "JAXROCK_CACHE_DIR"
_OFF = ("", "0", "off", "none")


def cache_root() -> Path | None:
    """The folder jaxrock keeps its caches in (`JAXROCK_CACHE_DIR` or the user's cache folder),
    or None when switched off."""
    value = os.environ.get(VARIABLE)
    if value is not None:
        return None if value.strip().lower() in _OFF else Path(value).expanduser()
    import platformdirs

    return Path(platformdirs.user_cache_dir("jaxrock", appauthor=False))


def package_version() -> str:
    """jaxrock's version, from git tags (setuptools-scm, at build or install time): `0.1.0` at the tag
    v0.1.0, `0.1.1.devN+g<commit>` N commits after it (`.dYYYYMMDD` added for uncommitted changes);
    "unknown" for a source tree never installed. An editable install (`pip install -e .`) would keep
    the version of its install after a pull or a commit: where the checkout's HEAD is no longer the
    installed commit, `.head.<commit>` names the code that runs (read from `.git`, no subprocess)."""
    try:
        from ._version import commit_id, version
    except ImportError:  # pragma: no cover
        try:
            return metadata.version("jaxrock")
        except metadata.PackageNotFoundError:
            return "unknown"
    head = _checkout_head()
    if head is None or (commit_id and head.startswith(commit_id.removeprefix("g"))):
        return version
    return f"{version}{'.' if '+' in version else '+'}head.{head[:9]}"


def _checkout_head(git: Path | None = None) -> str | None:
    """The commit checked out where this package's source lives (or in the folder `git`), if that is
    a git work tree."""
    git = Path(__file__).resolve().parents[1] / ".git" if git is None else git
    try:
        head = (git / "HEAD").read_text(encoding="utf-8").strip()
        if not head.startswith("ref: "):
            return head or None  # a detached HEAD
        ref = head.removeprefix("ref: ")
        if (git / ref).is_file():
            return (git / ref).read_text(encoding="utf-8").strip() or None
        for line in (git / "packed-refs").read_text(encoding="utf-8").splitlines():
            if line.endswith(" " + ref):
                return line.split()[0]
    except OSError:  # not a checkout (an installed wheel), or .git is a worktree's file
        return None
    return None


def _release() -> str:
    """The release part of the version (`0.1.1` of `0.1.1.dev7+g91a0631`): the cache folder's name.
    JAX keys every entry by the compiled program, so builds between two releases share a folder."""
    import re

    m = re.match(r"\d+(\.\d+)*", package_version())
    return m.group() if m else "unknown"


def _versions() -> str:
    return f"jaxrock-{_release()}-jax-{metadata.version('jax')}"


def compilation_cache_dir() -> Path | None:
    """The persistent compilation cache's folder for this jaxrock and JAX (None: switched off)."""
    root = cache_root()
    return None if root is None else root / "xla" / _versions()


def enable_compilation_cache() -> Path | None:
    """Point JAX's persistent compilation cache at `compilation_cache_dir()` unless the process
    chose its own; returns the folder in use (None: no persistent cache)."""
    import jax

    own = jax.config.jax_compilation_cache_dir
    if own:
        return Path(own)
    path = compilation_cache_dir()
    if path is None:
        return None
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return path


__all__ = ["VARIABLE", "package_version", "cache_root", "compilation_cache_dir", "enable_compilation_cache"]
