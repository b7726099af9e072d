"""A time history as a file (`jaxrock simulate --save`): netCDF (CF-1.8, `jaxrock.io.cf`) or CSV, by
the suffix: time `t` [s], the ground acceleration [m/s²] and every field of the history
(`jaxrock.outputs.HISTORY_FIELDS` names and units), with the run's summary and status beside it
(netCDF: scalar variables; CSV: a footer line). That summary is the history run's, to the end of
the saved window: its impacts are those the history shows, where a summary run (no `Save`) stops
as soon as its answer is fixed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._validate import JaxrockInputError
from ..outputs import HISTORY_FIELDS, SUMMARY

SUFFIXES = (".nc", ".csv")


def check_history_path(name: str, path) -> Path:
    """`path` ends in .nc or .csv and can be written (refused in one line naming `name` otherwise)."""
    from .files import check_output

    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise JaxrockInputError(f"{name} {path}: unknown suffix {path.suffix or '(none)'!r}; valid: .nc (netCDF) or .csv")
    check_output(name, path)
    return path


def save_history(sol, ground, path, attrs: dict, title: str) -> Path:
    """Write the history of `sol` (a `Solution` with `ts` and `history`) and the ground
    acceleration `ground` (at `sol.ts`) to `path`, netCDF or CSV by its suffix."""
    from ..results import status_names

    path = Path(path)
    t = np.asarray(sol.ts, dtype=float)
    columns = {"ground_acceleration": (np.asarray(ground, dtype=float), "ground acceleration", "m s-2")}
    columns.update({k: (np.asarray(sol.history[k], dtype=float), *HISTORY_FIELDS[k]) for k in HISTORY_FIELDS if k in sol.history})
    summary = {o.name: float(np.asarray(getattr(sol, o.name))) for o in SUMMARY}
    status = str(status_names(sol.status))
    if path.suffix.lower() == ".csv":
        from .tables import write_table

        rows = [{"t": float(ti), **{k: float(c[0][i]) for k, c in columns.items()}} for i, ti in enumerate(t)]
        footer = f"{title}; " + ", ".join(f"{k} = {v:.17g}" for k, v in summary.items()) + f", status = {status}"
        return write_table(path, rows, footer=footer)
    import xarray as xr

    from . import cf
    from .files import write_output
    from ..outputs import OUTPUTS

    ds = xr.Dataset(
        {k: (("t",), v, {"long_name": long_name, "units": units}) for k, (v, long_name, units) in columns.items()},
        # t: seconds from the excitation's own origin (a pulse's centre: negative before it), not a calendar time (no epoch)
        coords={"t": ("t", t, {"long_name": "time from the excitation's origin (a pulse's centre, a record's start)", "units": "s"})},
        attrs={**attrs, "status": status},
    )
    for name, v in summary.items():
        ds[name] = xr.Variable(*cf.output_variable(OUTPUTS[name], np.asarray(v), ()))
    ds = cf.encode(ds, title)
    return write_output(path, lambda tmp: cf.write_netcdf(ds, tmp))
