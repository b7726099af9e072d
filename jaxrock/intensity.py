"""Intensity measures of ground-motion records: the metadata of a suite (`suite_measures`).

Computed with `eqsig` (a maintained library of earthquake-signal measures) from the record as it
is read (its `scale` applied), in SI units:

- `pga` [m/s²]: max |a|, of the samples as read (no processing).
- `pgv` [m/s], `pgd` [m]: max |v|, max |u|, with v and u integrated by the trapezoidal rule from
  rest after a baseline correction: the least-squares straight line of the acceleration over the
  record is removed first (`eqsig.AccSignal.remove_poly(1)`), so that a small offset of the
  accelerometer's zero does not grow into a drift of the velocity and a parabola of the
  displacement. Records processed for a database (PEER's are band-passed) change by < 0.1 %.
- `arias` [m/s]: Arias intensity π/(2g) ∫ a² dt (trapezoidal, g = 9.81 m/s²), of the samples as read.
- `d5_95` [s]: significant duration (Trifunac and Brady 1975): the time between 5 % and 95 % of
  the Arias intensity (`eqsig.im.calc_sig_dur`: samples strictly inside, so to within one dt);
  NaN for a record without motion or too short to have both crossings.
- `dt` [s], `duration` [s] = (n − 1) dt.

A record's measure scales with the record (`pga`, `pgv`, `pgd` linearly, `arias` quadratically),
so the intensity of a record scaled by s is s^power times its measure (`SCALING`; used by
`jaxrock.analyses.suite.suite_fragility`).
"""

from __future__ import annotations

import numpy as np

MEASURES = {  # name → (long name, units)
    "pga": ("peak ground acceleration", "m/s2"),
    "pgv": ("peak ground velocity (baseline-corrected)", "m/s"),
    "pgd": ("peak ground displacement (baseline-corrected)", "m"),
    "arias": ("Arias intensity", "m/s"),
    "d5_95": ("significant duration D5-95", "s"),
    "dt": ("time step", "s"),
    "duration": ("duration (n - 1) dt", "s"),
}
SCALING = {"pga": 1, "pgv": 1, "pgd": 1, "arias": 2}  # measure of a record scaled by s: s**power × measure


def record_measures(record) -> dict[str, float]:
    """The intensity measures (`MEASURES`) of one record.

    Computed with `eqsig` from the record as it is read (its `scale` applied), in SI units:

    - `pga` [m/s²]: max |a|, of the samples as read (no processing);
    - `pgv` [m/s], `pgd` [m]: max |v|, max |u|, integrated by the trapezoidal rule from rest after the
      least-squares straight line of the acceleration is removed (`eqsig.AccSignal.remove_poly(1)`),
      so that a small zero offset does not grow into a drift; records processed for a database change
      by < 0.1 %;
    - `arias` [m/s]: Arias intensity π/(2g) ∫ a² dt (trapezoidal, g = 9.81 m/s²), of the samples as read;
    - `d5_95` [s]: significant duration (Trifunac and Brady 1975), the time between 5 % and 95 % of the
      Arias intensity (to within one dt); NaN for a record without motion or too short for both crossings;
    - `dt` [s], `duration` [s] = (n − 1) dt.

    Arguments:
        record (Record): the ground-motion record (`jaxrock.Record`).

    Returns:
        Measure name → value, the names and units of `MEASURES`.

    Example:
        ```python
        import jaxrock
        jaxrock.record_measures(jaxrock.el_centro())["pga"]  # ≈ 0.3129 g = 3.07 m/s²
        ```
    """
    import eqsig

    acc = np.asarray(record.acc, dtype=float) * float(record.scale)
    dt = float(record.dt)
    raw = eqsig.AccSignal(acc, dt)
    corrected = eqsig.AccSignal(acc.copy(), dt)
    corrected.remove_poly(1)
    return {
        "pga": float(raw.pga),
        "pgv": float(corrected.pgv),
        "pgd": float(corrected.pgd),
        "arias": float(eqsig.im.calc_arias_intensity(raw)[-1]),
        "d5_95": _significant_duration(raw),
        "dt": dt,
        "duration": dt * (acc.size - 1),
    }


def _significant_duration(signal) -> float:
    """D5-95 [s]; NaN where it is undefined: a record without motion (Arias intensity 0) or one
    too short for eqsig to find both crossings."""
    import eqsig

    if not np.any(signal.values):
        return float("nan")
    try:
        return float(eqsig.im.calc_sig_dur(signal))
    except (IndexError, ValueError):
        return float("nan")


def suite_measures(records):
    """The intensity measures of every record of a suite, as an `xarray.Dataset`.

    One variable per measure of `record_measures` (with its `long_name` and `units`), over the
    dimension `record`, whose coordinate is the records' names. A measure scales with the record
    (`SCALING`: `pga`, `pgv`, `pgd` linearly, `arias` quadratically).

    Arguments:
        records (Sequence[Record]): the records (e.g. `read_records`).

    Returns:
        (xarray.Dataset): the measures over dimension `record`.

    Example:
        ```python
        import jaxrock
        ds = jaxrock.suite_measures(jaxrock.read_records("builtin"))
        ds["pga"].values  # one PGA [m/s²] per record
        ```
    """
    import xarray as xr

    rows = [record_measures(r) for r in records]
    return xr.Dataset(
        {k: (("record",), np.array([r[k] for r in rows]), {"long_name": ln, "units": u}) for k, (ln, u) in MEASURES.items()},
        coords={"record": ("record", np.asarray([r.name for r in records], dtype=object))},
    )


__all__ = ["MEASURES", "SCALING", "record_measures", "suite_measures"]
