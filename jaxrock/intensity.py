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
- `cav` [m/s]: cumulative absolute velocity ∫ |a| dt (EPRI 1991; `eqsig.im.calc_cav`: the trapezoidal
  rule on |a| at the samples), of the samples as read.
- `pgv_pga` [s]: pgv / pga, a proxy of the period of the record's dominant pulse; NaN without motion.
- `dt` [s], `duration` [s] = (n − 1) dt.

A record's measure scales with the record (`pga`, `pgv`, `pgd`, `cav` linearly, `arias`
quadratically, `pgv_pga` not at all), so the intensity of a record scaled by s is s^power times its
measure (`SCALING`; used by `jaxrock.analyses.suite.suite_fragility`).

Beyond the table of `record_measures`:

- `spectral_acceleration`: the pseudo-spectral acceleration Sa(T) = ω² max |u| [m/s²] of a linear
  oscillator, integrated exactly for the record's piecewise-linear üg (Nigam and Jennings 1968, with
  `eqsig.sdof`), its peak sought between the samples and in the free vibration after the record's end.
- `parse_im`, `parse_ims`, `intensity_of`: the intensity measures of a fragility (the command
  line's `--im`): `pga`, `pgv`, `pgd`, `arias`, `cav` (and `pgv_pga`, which does not scale), `sa:<T>`,
  `sa:T1`, and the rocking block's dimensionless `pga_ratio` = PGA / (g tanα) and `pgv_ratio` =
  PGV p / (g tanα).
"""

from __future__ import annotations

import numpy as np

from ._validate import JaxrockInputError, check_positive

MEASURES = {  # name → (long name, units)
    "pga": ("peak ground acceleration", "m/s2"),
    "pgv": ("peak ground velocity (baseline-corrected)", "m/s"),
    "pgd": ("peak ground displacement (baseline-corrected)", "m"),
    "arias": ("Arias intensity", "m/s"),
    "d5_95": ("significant duration D5-95", "s"),
    "cav": ("cumulative absolute velocity", "m/s"),
    "pgv_pga": ("ratio pgv / pga", "s"),
    "dt": ("time step", "s"),
    "duration": ("duration (n - 1) dt", "s"),
}
SCALING = {"pga": 1, "pgv": 1, "pgd": 1, "arias": 2, "cav": 1, "pgv_pga": 0}  # measure of a record scaled by s: s**power × measure


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
    - `cav` [m/s]: cumulative absolute velocity ∫ |a| dt (`eqsig.im.calc_cav`, trapezoidal on |a|), of the
      samples as read;
    - `pgv_pga` [s]: pgv / pga, a proxy of the dominant pulse's period (unchanged by scaling); NaN
      for a record without motion;
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
    pga, pgv = float(raw.pga), float(corrected.pgv)
    return {
        "pga": pga,
        "pgv": pgv,
        "pgd": float(corrected.pgd),
        "arias": float(eqsig.im.calc_arias_intensity(raw)[-1]),
        "d5_95": _significant_duration(raw),
        "cav": float(eqsig.im.calc_cav(raw)[-1]),
        "pgv_pga": pgv / pga if pga > 0 else float("nan"),
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
    (`SCALING`: `pga`, `pgv`, `pgd`, `cav` linearly, `arias` quadratically, `pgv_pga` not at all).

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


# -- spectral acceleration ---------------------------------------------------------------------------
_PER_PERIOD = 128  # points per oscillator period at which |u| is evaluated (samples, then exact sub-steps)
_MIN_SUB = 4  # fewest sub-steps per sample step (a response at the record's own frequencies)
_MAX_SUB = 256  # most sub-steps per sample step (periods far below dt: the response follows üg)
_OMEGA = 6.2831853  # 2π as eqsig.sdof.nigam_and_jennings_response writes it (so the sub-steps match its steps)


def _sdof_peaks(acc: np.ndarray, dt: float, periods: np.ndarray, damping: float) -> np.ndarray:
    """Sa = ω² max |u| [m/s²] of linear oscillators (1-D `periods`, > 0) under the piecewise-linear
    ground acceleration `acc` [m/s²], zero after its last sample."""
    import eqsig.sdof

    u, v, _ = eqsig.sdof.nigam_and_jennings_response(acc, dt, periods, damping)  # exact at the samples
    w = _OMEGA / periods
    f = -np.asarray(acc, dtype=float)  # the load of u'' + 2ζωu' + ω²u = −üg, as eqsig steps it
    f0, df = f[:-1], np.diff(f)
    peak = np.abs(u).max(axis=1)
    for k, period in enumerate(periods):
        # between samples: the exact state at t_i + τ, from the state at t_i (eqsig's Nigam-Jennings
        # matrices for a step τ, the load linear from f_i to its value at τ), at ≥ _PER_PERIOD points a
        # period and ≥ _MIN_SUB a sample step
        m = min(max(int(np.ceil(_PER_PERIOD * dt / period)), _MIN_SUB), _MAX_SUB)
        for lo in range(1, m, 32):
            frac = (np.arange(lo, min(lo + 32, m)) / m)[:, None]
            a, b = eqsig.sdof.compute_a_and_b(damping, w[k], dt * frac)
            us = a[0][0] * u[k, :-1] + a[0][1] * v[k, :-1] + b[0][0] * f0 + b[0][1] * (f0 + frac * df)
            peak[k] = max(peak[k], float(np.abs(us).max()))
        # after the end (üg = 0): the free vibration, whose largest |u| comes within half a damped period
        wd = w[k] * np.sqrt(1.0 - damping**2)
        h = period / _PER_PERIOD
        t = h * np.arange(1, int(np.ceil(np.pi / wd / h)) + 2)
        a, _ = eqsig.sdof.compute_a_and_b(damping, w[k], t)
        peak[k] = max(peak[k], float(np.abs(a[0][0] * u[k, -1] + a[0][1] * v[k, -1]).max()))
    return w**2 * peak


def _record_acc(record) -> tuple[np.ndarray, float]:
    """The record's samples × scale [m/s²] up to its `length`, and its step [s]."""
    acc = np.asarray(record.acc, dtype=float) * float(record.scale)
    length = getattr(record, "length", None)
    if length is not None:
        acc = acc[: int(np.asarray(length))]
    return acc, float(record.dt)


def _check_damping(damping) -> float:
    d = float(damping)
    if not (0.0 <= d < 1.0):
        raise JaxrockInputError(f"damping = {d:g} is outside the valid range [0, 1)")
    return d


def spectral_acceleration(record, periods, damping: float = 0.05) -> np.ndarray:
    """The pseudo-spectral acceleration Sa(T) = ω² max |u| [m/s²] of a record.

    u is the relative displacement of a linear oscillator of period T = 2π/ω and damping ratio ζ,
    u'' + 2ζωu' + ω²u = −üg, from rest. üg is the record as `jaxrock.Record` defines it: its samples
    (× `scale`, up to its `length`) linear between them, zero after the last. The response is exact
    for such a üg (Nigam and Jennings 1968, `eqsig.sdof.nigam_and_jennings_response`, at any T/dt:
    no subdivision is needed for stability or accuracy at the samples). Where eqsig's spectrum takes
    max |u| at the samples only (and replaces Sa by the PGA below T = 6 dt: 38 % low at T = 5 dt on El
    Centro), here max |u| is also sought between them, at ≥ 128 points a period and ≥ 4 a sample step
    (exact sub-steps with eqsig's matrices), and in the free vibration after the record's end. So Sa
    is never above the exact value, and below it by at most 1 − cos(π/128) = 3e-4 for a peak of the
    oscillator's own vibration, (π dt / 4P)²/2 for a response at a period P of the record (3e-5 at
    100 samples a cycle). Measured: within 2e-4 of `scipy.signal.lsim` on El Centro for T from dt/2
    to 3 s and ζ = 0, 0.05, 0.2; within 3e-4 of the steady state under a sine. Sa(T → 0) → PGA (T ≪
    dt: the oscillator follows üg; 4e-6 at T = dt/100, 3e-4 at dt/10), Sa(T → ∞) → ω² PGD.

    Sa scales linearly with the record. The response at all periods is one integration of the record
    (vectorised over the unique periods): about 15 µs a sample, plus the sub-steps at T < 128 dt.

    Arguments:
        record (Record): the ground-motion record (`jaxrock.Record`).
        periods (ArrayLike): the oscillators' periods T [s], finite and > 0, any shape.
        damping (float): the damping ratio ζ [–], in [0, 1); default 0.05.

    Returns:
        Sa [m/s²], of the shape of `periods`.

    Raises:
        JaxrockInputError: when a period is not a finite number > 0 or ζ is outside [0, 1).

    Example:
        ```python
        import jaxrock
        from jaxrock.intensity import spectral_acceleration
        spectral_acceleration(jaxrock.el_centro(), [0.2, 0.5, 1.0]) / jaxrock.G  # Sa [g], ζ = 5 %
        ```
    """
    t = np.asarray(periods, dtype=float)
    check_positive("periods", t)
    d = _check_damping(damping)
    acc, dt = _record_acc(record)
    unique, inverse = np.unique(t.ravel(), return_inverse=True)
    return _sdof_peaks(acc, dt, unique, d)[inverse].reshape(t.shape)


# -- the intensity measures of a fragility (`--im`) ---------------------------------------------------
IM_MEASURES = tuple(SCALING)  # the record measures an intensity can be (pgv_pga: power 0, no fragility's)
IM_FORMS = ("pga, pgv, pgd, arias, cav, pgv_pga, tp, omega_ratio, sa:<T> (Sa at period T [s] > 0, ζ = 5 %, e.g. sa:0.5), "
            "sa:T1 (Sa at the column's first period), pga_ratio (PGA/(g tanα)), pgv_ratio (PGV p/(g tanα))")
_RATIOS = {  # name → (units, scaling power, the arguments it needs)
    "tp": ("s", 0, ()),
    "omega_ratio": ("1", 0, ("p",)),
    "pga_ratio": ("1", 1, ("tan_alpha",)),
    "pgv_ratio": ("1", 1, ("tan_alpha", "p")),
}


def parse_im(spec: str) -> tuple[str, str, int, tuple[str, ...]]:
    """One intensity measure of a fragility (an item of the command line's `--im`).

    The forms: a record measure (`IM_MEASURES`: `pga` [m/s²], `pgv` [m/s], `pgd` [m], `arias` [m/s],
    `cav` [m/s], and `pgv_pga` [s], which does not grow with the record: scaling power 0, no measure
    to fit a fragility against, a check of sufficiency); `tp` [s], the record's pulse period
    (`pulse_period`), and `omega_ratio` = 2π/(Tp p) [–] (needs `p`), the paper's ω_p/p for a record,
    both of scaling power 0; `sa:<T>`, the pseudo-spectral acceleration [m/s²] at period T [s] (finite, > 0;
    ζ = 5 %; `spectral_acceleration`); `sa:T1`, Sa at the column's first period (needs `period`);
    `pga_ratio` = PGA / (g tanα) [–] (needs `tan_alpha`) and `pgv_ratio` = PGV p / (g tanα) [–] (needs
    `tan_alpha` and `p`), the rocking block's dimensionless intensities. Case and surrounding blanks
    are ignored.

    Arguments:
        spec (str): the measure, e.g. "pga", "sa:0.5", "sa:T1", "pgv_ratio".

    Returns:
        (name, units, scaling power, needs): the canonical name (e.g. "sa:0.5", "sa:T1"), its units,
        the power p such that the measure of a record scaled by s is s^p times the record's (`SCALING`:
        2 for `arias`, 0 for `pgv_pga`, 1 for the others), and the names of the `intensity_of` arguments it needs.

    Raises:
        JaxrockInputError: for an unknown form (one line listing the valid ones), or `sa:<T>` whose T
            is not a finite number > 0.

    Example:
        ```python
        from jaxrock.intensity import parse_im
        parse_im("sa:0.50")  # ("sa:0.5", "m/s2", 1, ())
        parse_im("pgv_ratio")  # ("pgv_ratio", "1", 1, ("tan_alpha", "p"))
        ```
    """
    text = str(spec).strip()
    key = text.lower()
    if key in IM_MEASURES:
        return key, MEASURES[key][1], SCALING[key], ()
    if key in _RATIOS:
        return (key, *_RATIOS[key])
    if key.startswith("sa:"):
        arg = key[3:].strip()
        if arg == "t1":
            return "sa:T1", "m/s2", 1, ("period",)
        try:
            period = float(arg)
        except ValueError:
            period = float("nan")
        if not (np.isfinite(period) and period > 0):
            raise JaxrockInputError(f"--im {text!r}: the period of sa:<T> must be a finite number > 0 [s] "
                                    "(e.g. sa:0.5), or sa:T1 for the column's first period")
        return f"sa:{period:.12g}", "m/s2", 1, ()
    raise JaxrockInputError(f"--im {text!r} is not an intensity measure; valid: {IM_FORMS}")


def parse_ims(text: str, *, allow_scale: bool = False) -> list[str]:
    """The intensity measures of a comma-separated list (the command line's `--im`, e.g. "sa:T1,pgv").

    Arguments:
        text (str): the measures, separated by commas (`parse_im` reads each).
        allow_scale (bool): whether "scale" (the scale factor itself, not a measure) is an item too;
            default False.

    Returns:
        The canonical name of each item (`parse_im`), in order.

    Raises:
        JaxrockInputError: for an empty item, an item `parse_im` refuses, or a measure given twice
            (after canonicalisation: "sa:0.5,sa:.50" is one measure twice).

    Example:
        ```python
        from jaxrock.intensity import parse_ims
        parse_ims("sa:T1, PGV")  # ["sa:T1", "pgv"]
        ```
    """
    out = []
    for item in str(text).split(","):
        if not item.strip():
            raise JaxrockInputError(f"--im {text!r} has an empty item; give measures separated by commas, e.g. sa:T1,pgv")
        name = "scale" if allow_scale and item.strip().lower() == "scale" else parse_im(item)[0]
        if name in out:
            raise JaxrockInputError(f"--im {text!r} gives {name} twice; give each measure once")
        out.append(name)
    return out


def _cells(im: str, name: str, x, needed: bool) -> np.ndarray | None:
    """A cell array of `intensity_of`, checked (finite, > 0) where the measure `im` needs it."""
    if x is None:
        return None
    a = np.asarray(x, dtype=float)
    if needed:
        try:
            check_positive(name, a)
        except JaxrockInputError as e:
            raise JaxrockInputError(f"--im {im}: {e}") from None
    return a


def intensity_of(spec: str, records, *, period=None, tan_alpha=None, p=None) -> np.ndarray:
    """The value of an intensity measure (`parse_im`) for each record, over the cells of a sweep.

    The cells' shape is the broadcast shape of `tan_alpha` and `p` (those given); when neither is
    given, that of `period`. `period` is broadcast against (n_records, *cell_shape) by NumPy's rules:
    of shape (*cell_shape,) it is the same for every record, of shape (n_records, *cell_shape) one per
    record. A measure that depends on the record only is broadcast over the cells. Sa is computed once
    per record for all the unique periods it needs (`spectral_acceleration`, ζ = 5 %).

    Arguments:
        spec (str): the measure: `pga`, `pgv`, `pgd`, `arias`, `cav`, `pgv_pga`, `sa:<T>`, `sa:T1`,
            `pga_ratio`, `pgv_ratio` (`parse_im`).
        records (Sequence[Record]): the records (`jaxrock.Record`, e.g. `read_records`).
        period (ArrayLike | None): the column's first period T1 [s], finite and > 0 (needed by `sa:T1`).
        tan_alpha (ArrayLike | None): the block's slenderness tanα = b/h [–], finite and > 0 (needed
            by `pga_ratio`, `pgv_ratio`).
        p (ArrayLike | None): the block's frequency parameter p = √(3g/(4R)) [rad/s], finite and > 0
            (needed by `pgv_ratio`).

    Returns:
        The measures, shape (n_records, *cell_shape), in the units of `parse_im` (g = `jaxrock.G`).

    Raises:
        JaxrockInputError: for a spec `parse_im` refuses, a needed argument missing or not finite and
            > 0, or arrays whose shapes do not broadcast.

    Example:
        ```python
        import jaxrock
        from jaxrock.intensity import intensity_of
        recs = jaxrock.read_records("builtin")
        intensity_of("pga_ratio", recs, tan_alpha=[0.1, 0.2])  # shape (5, 2)
        intensity_of("sa:T1", recs, period=[0.1, 0.3, 0.5])  # shape (5, 3), Sa [m/s²]
        ```
    """
    name, _, _, needs = parse_im(spec)
    records = list(records)
    for arg, value in (("period", period), ("tan_alpha", tan_alpha), ("p", p)):
        if arg in needs and value is None:
            raise JaxrockInputError(f"--im {name} needs {arg} (the column's "
                                    + {"period": "first period [s]", "tan_alpha": "slenderness tanα",
                                       "p": "frequency parameter p [rad/s]"}[arg] + ")")
    t1 = _cells(name, "period", period, "period" in needs)
    ta = _cells(name, "tan_alpha", tan_alpha, "tan_alpha" in needs)
    pp = _cells(name, "p", p, "p" in needs)
    try:
        given = [a.shape for a in (ta, pp) if a is not None]
        cell_shape = np.broadcast_shapes(*given) if given else (t1.shape if t1 is not None else ())
        shape = (len(records), *cell_shape)
        if t1 is not None:
            t1 = np.broadcast_to(t1, shape)
    except ValueError:
        raise JaxrockInputError(f"--im {name}: the shapes of period {np.shape(period)}, tan_alpha "
                                f"{np.shape(tan_alpha)} and p {np.shape(p)} do not broadcast "
                                f"(period: (*cells,) or (n_records = {len(records)}, *cells))") from None
    lead = (slice(None),) + (None,) * len(cell_shape)  # a record's value over the cells
    if name == "sa:T1":
        values = np.empty(shape)
        for i, record in enumerate(records):
            values[i] = spectral_acceleration(record, t1[i])  # unique periods once (vectorised)
        return values
    if name.startswith("sa:"):
        values = np.array([float(spectral_acceleration(record, float(name[3:]))) for record in records])
        return np.broadcast_to(values[lead], shape).copy()
    measures = [record_measures(record) for record in records]
    if name in _RATIOS:
        from .geometry import G
    if name in ("tp", "omega_ratio"):
        tp = np.array([pulse_period(record) for record in records])[lead]
        values = tp if name == "tp" else 2 * np.pi / tp / pp
    elif name == "pga_ratio":
        values = np.array([m["pga"] for m in measures])[lead] / (G * ta)
    elif name == "pgv_ratio":
        values = np.array([m["pgv"] for m in measures])[lead] * pp / (G * ta)
    else:
        values = np.array([m[name] for m in measures])[lead]
    return np.broadcast_to(values, shape).astype(float, copy=True)


PULSE_PERIODS = np.geomspace(0.05, 10.0, 160)  # the search grid of `pulse_period` [s]


def pulse_period(record, damping: float = 0.05) -> float:
    """The record's predominant pulse period Tp [s]: the period of the peak of its pseudo-velocity
    spectrum PSV(T) = Sa(T) T/2π (ζ = 5 %; Alavi and Krawinkler 2004, Mavroeidis and Papageorgiou
    2003 relate it to the period of a near-fault velocity pulse), on a grid of 160 periods from
    0.05 to 10 s refined by a parabola through the peak and its neighbours in ln T. Not a wavelet fit
    of the velocity pulse (Baker 2007): on a record without a pulse it is the period where the
    record's velocity spectrum peaks. With the column's p it gives the rocking block's frequency
    ratio ω_p/p = 2π/(Tp p) of the paper's spectra (`omega_ratio`), which does not grow with the
    record (scaling power 0).

    Arguments:
        record (Record): the ground-motion record.
        damping (float): the oscillators' damping ratio ζ, in [0, 1); default 0.05.

    Returns:
        Tp [s].

    Example:
        ```python
        import jaxrock
        from jaxrock.intensity import pulse_period
        pulse_period(jaxrock.el_centro())
        ```
    """
    T = PULSE_PERIODS
    lv = np.log(spectral_acceleration(record, T, damping) * T)
    k = int(np.clip(np.argmax(lv), 1, T.size - 2))
    x, y = np.log(T[k - 1:k + 2]), lv[k - 1:k + 2]
    curv = y[0] - 2 * y[1] + y[2]
    shift = 0.5 * (y[0] - y[2]) / curv if curv < 0 else 0.0
    return float(np.exp(x[1] + np.clip(shift, -1.0, 1.0) * (x[2] - x[1])))


__all__ = ["PULSE_PERIODS", "pulse_period", "IM_FORMS", "IM_MEASURES", "MEASURES", "SCALING", "intensity_of", "parse_im", "parse_ims",
           "record_measures", "spectral_acceleration", "suite_measures"]
