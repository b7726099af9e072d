"""Input checks that run on concrete values, before anything is traced or compiled.

Every public constructor calls these on its arguments. Under `jax.vmap`/`jax.jit` the values
are tracers and cannot be inspected; the checks are then skipped (the same values were checked
when the batch was built outside the transformation, e.g. by `overturning_spectrum`).
"""

from __future__ import annotations

import math

import jax
import numpy as np


class JaxrockInputError(ValueError):
    """Bad input: names the parameter, the value and the valid range."""


def is_concrete(x) -> bool:
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def _values(x):
    return np.asarray(x, dtype=float).ravel()


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
    v = _values(x)
    lb = "(" if lo_open else "["
    rb = ")" if hi_open else "]"
    rng = f"{lb}{lo:g}, {hi:g}{rb}"
    if v.size == 0:
        raise JaxrockInputError(f"{name} is empty; expected values in {rng}")
    bad = ~np.isfinite(v)
    if math.isfinite(lo) or lo_open:
        bad |= (v <= lo) if lo_open else (v < lo)
    if math.isfinite(hi) or hi_open:
        bad |= (v >= hi) if hi_open else (v > hi)
    if bad.any():
        first = v[bad][0]
        raise JaxrockInputError(f"{name} = {first:g} is outside the valid range {rng}")


def check_positive(name: str, x) -> None:
    check_range(name, x, 0.0, math.inf, lo_open=True, hi_open=True)


def check_nonnegative(name: str, x) -> None:
    check_range(name, x, 0.0, math.inf, hi_open=True)


def check_grid(name: str, values, lo: float = 0.0) -> np.ndarray:
    """A grid axis: non-empty, finite, > lo, strictly increasing."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        raise JaxrockInputError(f"{name} grid is empty; give at least one value > {lo:g}")
    check_range(name, v, lo, math.inf, lo_open=True, hi_open=True)
    if v.size > 1 and not np.all(np.diff(v) > 0):
        raise JaxrockInputError(f"{name} grid must be strictly increasing (got {v[:4]}...)")
    return v


def check_writable(name: str, path) -> None:
    """`path` can be written (its folder is created): probed by writing, not by permission bits,
    so that a run fails here, before its work, not after it."""
    import tempfile
    from pathlib import Path

    path = Path(path)
    if path.is_dir():
        raise JaxrockInputError(f"{name} {path}: is a folder; expected a file path")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".jaxrock-write-test-"):
            pass
        if path.exists():
            open(path, "ab").close()
    except OSError as e:
        blocker = next((a for a in path.parents if a.exists()), None)
        why = f"{blocker} is a file, not a folder" if blocker is not None and not blocker.is_dir() else (e.strerror or str(e))
        raise JaxrockInputError(f"{name} {path}: cannot write there ({why}); choose another path") from None
