"""Input checks that run on concrete values, before anything is traced or compiled.

Every public constructor calls these on its arguments. Under `jax.vmap`/`jax.jit` the values
are tracers and cannot be inspected; the checks are then skipped (the same values were checked
when the batch was built outside the transformation, e.g. by `overturning_spectrum`).

The module imports no JAX (the command line checks its arguments with it before JAX is loaded):
nothing can be a tracer before JAX is imported, and `within_limits` imports it when called.
"""

from __future__ import annotations

import math
import os
import sys
from typing import NamedTuple

import numpy as np


class JaxrockInputError(ValueError):
    """Bad input, refused in one line that names the parameter, the value and the valid range.

    A `ValueError`. Raised by the public constructors and functions on concrete values, before
    anything is traced or compiled; under `jax.vmap`/`jax.jit` the values are tracers and a run
    reports `Status.invalid_input` instead.

    Example:
        ```python
        try:
            jaxrock.Block.from_slenderness(10.0, 1.5)
        except jaxrock.JaxrockInputError as e:
            print(e)  # tan_alpha = 1.5 is outside the valid range [0.001, 1)
        ```
    """


def is_concrete(x) -> bool:
    jax = sys.modules.get("jax")  # not imported yet: no value can be a tracer
    return jax is None or not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def _values(name: str, x) -> np.ndarray:
    """The real values of `x`, or a one-line refusal of what is not a number."""
    if x is None:
        raise JaxrockInputError(f"{name} is missing (None); give a number")
    a = np.asarray(x)
    if a.dtype.kind == "c":
        raise JaxrockInputError(f"{name} = {complex(a.ravel()[0])} is complex; give a real number")
    if a.dtype.kind not in "biuf":
        raise JaxrockInputError(f"{name} = {x!r} is not a number")
    return a.astype(float).ravel()


def in_range(v, lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False, hi_open: bool = False):
    """Elementwise: finite and within the interval (NumPy or JAX arrays alike; NaN is outside)."""
    return (abs(v) < math.inf) & ((v > lo) if lo_open else (v >= lo)) & ((v < hi) if hi_open else (v <= hi))


def is_number(text: str) -> bool:
    """Whether `float` reads the text."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def check_range(
    name: str,
    x,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> None:
    """Raise `JaxrockInputError` unless every value of `x` is finite and in the interval."""
    if not is_concrete(x):
        return
    v = _values(name, x)
    lb = "(" if lo_open else "["
    rb = ")" if hi_open else "]"
    rng = f"{lb}{lo:g}, {hi:g}{rb}"
    if v.size == 0:
        raise JaxrockInputError(f"{name} is empty; expected values in {rng}")
    bad = ~in_range(v, lo, hi, lo_open=lo_open, hi_open=hi_open)
    if bad.any():
        first = v[bad][0]
        if not np.isfinite(first):
            valid = "any finite number" if math.isinf(lo) and math.isinf(hi) else f"finite, in {rng}"
            raise JaxrockInputError(f"{name} = {first:g} is not a finite number; valid: {valid}")
        raise JaxrockInputError(f"{name} = {first:g} is outside the valid range {rng}")


class Limit(NamedTuple):
    """The valid range of one parameter, declared once: checked with a one-line error on concrete
    values (`check_limits`, at construction) and as a traced flag under `jax.vmap`/`jax.jit`
    (`within_limits`, which `simulate` turns into `Status.invalid_input`)."""

    name: str
    value: object
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    ndim: int = 0  # dimensions of the value for one scene (1: a record's samples)


def check_limits(limits) -> None:
    for lim in limits:
        check_range(lim.name, lim.value, lim.lo, lim.hi, lo_open=lim.lo_open, hi_open=lim.hi_open)


def check_one_scene(limits) -> None:
    """Refuse, in one line, parameters that hold many values where a run takes one scene (shapes
    are known even under `jax.jit`; under `jax.vmap` each lane sees one value)."""
    for lim in limits:
        if np.ndim(lim.value) != lim.ndim:
            raise JaxrockInputError(f"{lim.name} has shape {np.shape(lim.value)}; simulate runs one scene: vmap it "
                                    "(jax.vmap(simulate)) or use overturning_spectrum / run_batch for many")


def within_limits(limits):
    """Whether every value is finite and within its limit: a JAX boolean (traceable)."""
    import jax.numpy as jnp

    ok = jnp.asarray(True)
    for lim in limits:
        ok &= jnp.all(in_range(jnp.asarray(lim.value), lim.lo, lim.hi, lo_open=lim.lo_open, hi_open=lim.hi_open))
    return ok


def check_positive(name: str, x) -> None:
    check_range(name, x, 0.0, math.inf, lo_open=True, hi_open=True)


def check_grid(name: str, values, lo: float = 0.0) -> np.ndarray:
    """A grid axis: non-empty, finite, > lo, strictly increasing."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        raise JaxrockInputError(f"{name} grid is empty; give at least one value > {lo:g}")
    check_range(name, v, lo, math.inf, lo_open=True, hi_open=True)
    if v.size > 1 and not np.all(np.diff(v) > 0):
        raise JaxrockInputError(f"{name} grid must be strictly increasing (got {v[:4]}...)")
    return v


MADE_FOLDERS: list = []  # folders `check_writable` made in this process (a refused command removes them while empty)


def remove_made_folders() -> None:
    """Remove the folders `check_writable` made that are still empty, innermost first: a command
    refused after its outputs were checked leaves no empty folder behind."""
    while MADE_FOLDERS:
        try:
            MADE_FOLDERS.pop().rmdir()
        except OSError:  # not empty (something was written), or gone
            pass


def check_file_kind(name: str, path) -> None:
    """An output path names a regular file or nothing yet: a symbolic link (jaxrock does not
    write through links into files it did not make), a folder, a device or a FIFO is refused."""
    from pathlib import Path

    path = Path(path)
    where = f"{name} {path}" if name else f"{path}"
    if path.is_symlink():
        raise JaxrockInputError(f"{where}: is a symbolic link (to {os.path.realpath(path)}); jaxrock does not write "
                                f"through links into files it did not make: name the file itself, or another path")
    if path.is_dir():
        raise JaxrockInputError(f"{where}: is a folder; expected a file path")
    if path.exists() and not path.is_file():
        raise JaxrockInputError(f"{where}: is not a regular file (a device, a FIFO or a socket); expected a file path")


def check_writable(name: str, path) -> None:
    """`path` can be written (its folder is created): probed by writing, not by permission bits,
    so that a run fails here, before its work, not after it."""
    import tempfile
    from pathlib import Path

    path = Path(path)
    check_file_kind(name, path)
    try:
        missing = [d for d in (path.parent, *path.parent.parents) if not d.exists()]
        path.parent.mkdir(parents=True, exist_ok=True)
        MADE_FOLDERS.extend(reversed(missing))  # outermost first
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".jaxrock-write-test-"):
            pass
        if path.exists():
            open(path, "ab").close()
    except OSError as e:
        blocker = next((a for a in path.parents if a.exists()), None)
        why = f"{blocker} is a file, not a folder" if blocker is not None and not blocker.is_dir() else (e.strerror or str(e))
        raise JaxrockInputError(f"{name} {path}: cannot write there ({why}); choose another path") from None
