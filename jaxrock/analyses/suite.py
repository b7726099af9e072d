"""Record suites: the least overturning scale factor of every record for every column (the paper's
figure 10, for a suite), refined by a vmapped bisection.

`least_overturning_scale` runs a record sweep (`jaxrock.analyses.sweep`: records × the column's
quantities × a `scale` axis, resumable in a store), takes in each cell (record, size, slenderness,
...) the first factor of the sweep that overturns the column, and bisects between it and the factor
before it (0 below the first): each round runs every cell of a record in one vmapped batch (models
per scene), so a suite costs `refine` batches per record after its sweep. The bracket [low, least]
is reported with its width.

Overturning is not monotone in the factor (a rocking column that overturns at s may survive a
larger one): the least factor found is the least within its bracket; an overturning window
narrower than the sweep's step below it is missed, and where the bracket holds several windows
the bisection ends at one of their edges. `windows` counts, per cell, the sweep's turns from
overturned back to standing: 0 where the sweep saw a monotone outcome. On records it is seldom 0:
22 of 24 cells (3 records × 4 sizes × 2 slendernesses, RM) turned at least once in a sweep of step
0.025 — the least factor of a record is a property of the sweep's resolution; the fragility
(`jaxrock.analyses.fragility`) uses every outcome of the sweep instead.
"""

from __future__ import annotations

import numpy as np

from .._validate import JaxrockInputError
from .sweep import Sweep, run_sweep, run_values


def least_overturning_scale(sweep: Sweep, store=None, *, refine: int = 8, progress: bool = True, devices=None,
                            history: str | None = None):
    """The least overturning factor of each record for each column of the record sweep `sweep`
    (`Sweep.make(..., records=..., scale=[...])`, `scale` an axis), as an `xarray.Dataset`:

    - the sweep's outputs (`overturned`, `max_theta`, ..., `status`) over all its axes;
    - over its axes without `scale`: `least_scale` (+inf where no factor of the sweep overturns),
      `bracket_low` (the largest factor known not to overturn below it; NaN where none
      overturns), `bracket_width` = least_scale − bracket_low (after `refine` bisections: the
      sweep's step / 2^refine), and `worst_status`, the largest status code of the cell's runs
      (sweep and bisection: 0 = every run ok), and `windows` (module docstring).

    `store`, `progress`, `devices`, `history` as `run_sweep` (the sweep is resumable; the
    bisection is rerun)."""
    from tqdm.auto import tqdm

    from .. import interrupt

    if not sweep.records or "scale" not in sweep.axes:
        raise JaxrockInputError("least_overturning_scale needs a record sweep with a scale axis: Sweep.make(..., records=[...], scale=[...])")
    if int(refine) < 0:
        raise JaxrockInputError(f"refine = {refine}; valid: an integer >= 0")
    assert sweep.dims[0] == "record" and sweep.dims[-1] == "scale"  # AXIS_ORDER: records outermost, scale innermost
    ds = run_sweep(sweep, store, progress=progress, devices=devices, history=history).drop_vars("chunk_done")
    sc = sweep.axes["scale"]
    over, status = ds.overturned.values, ds.status.values  # (record, *cells, scale)
    has = over.any(axis=-1)
    k = np.argmax(over, axis=-1)
    hi = np.where(has, sc[k], np.inf)
    lo = np.where(has, np.where(k > 0, sc[np.maximum(k - 1, 0)], 0.0), np.nan)
    worst = status.max(axis=-1)
    cell_dims = sweep.dims[1:-1]
    cells = sweep.values_at(tuple(slice(0, len(sweep.axes[d])) for d in cell_dims), cell_dims)  # every column, C order
    with tqdm(total=len(sweep.records) * int(refine), desc="bisection", unit="batch", disable=not progress) as bar:
        for r in range(len(sweep.records)):
            todo = has[r].ravel()
            if not todo.any():
                bar.update(int(refine))
                continue
            h, l, w = hi[r].ravel().copy(), lo[r].ravel().copy(), worst[r].ravel().copy()
            v = {name: x[todo] for name, x in cells.items()} | {"record": np.full(int(todo.sum()), r)}
            for _ in range(int(refine)):
                interrupt.stop_point()
                mid = 0.5 * (l[todo] + h[todo])
                out = run_values(sweep, v | {"scale": mid}, devices)
                yes = out["overturned"].astype(bool)
                h[todo] = np.where(yes, mid, h[todo])
                l[todo] = np.where(yes, l[todo], mid)
                w[todo] = np.maximum(w[todo], out["status"])
                bar.update()
            hi[r], lo[r], worst[r] = h.reshape(hi[r].shape), l.reshape(lo[r].shape), w.reshape(worst[r].shape)
    dims = sweep.dims[:-1]
    ds["least_scale"] = (dims, hi, {"long_name": "least scale factor that overturns (inf: none of the sweep)", "units": "1"})
    ds["bracket_low"] = (dims, lo, {"long_name": "largest scale factor below least_scale known not to overturn", "units": "1"})
    ds["bracket_width"] = (dims, hi - lo, {"long_name": "least_scale - bracket_low", "units": "1"})
    ds["windows"] = (dims, (over[..., :-1] & ~over[..., 1:]).sum(-1).astype(np.int32),
                     {"long_name": "times the sweep's outcome turns from overturned to not as the factor grows (0: monotone)"})
    ds["worst_status"] = (dims, worst.astype(np.int32), {"long_name": "largest jaxrock.Status code of the cell's runs (0: all ok)"})
    ds.attrs["refine"] = int(refine)
    return ds


__all__ = ["least_overturning_scale"]
