"""From fragility to risk: damage states, IDA curves, intensity measures and hazard, from a suite.

A record suite (`jaxrock.analyses.suite.run_suite`) runs every record at every factor s of its
sweep and bisects each least overturning factor. `risk_analysis` reads that dataset again, with
no new run:

- **Damage states** (`damage_states`, thresholds d of max θ/α in (0, 1]): a run reaches state d
  when its max θ/α ≥ d or it overturned; d = 1 is overturning itself (its verdict, or its
  ensemble probability `p_overturn` where the suite has one). Each state's lognormal fragility is
  fitted per state by `fit_lognormal` (Baker 2015's multiple-stripe MLE on every record × factor
  outcome, bootstrap over records), against each intensity measure. States are nested (reaching
  0.5 is reaching 0.1), so their medians rise; their curves may still cross where β differ:
  `crosses` says where within the suite's intensities.
- **IDA** (Vamvatsikos and Cornell 2002): each record's curve of max θ/α against its intensity
  x = s^k · IM over the factors, flat at 1 from overturning on (a standing run's max θ/α is drawn
  up to 1); `windows` counts the "resurrections" (the record stands again at a larger factor).
  The median and 16/84 % curves are percentiles over the records at each intensity of a common
  grid (each record's curve interpolated in ln x; a record counts only within its own range).
  A truncated-IDA fit (Baker 2015; `fit_truncated_ida`) takes each record's least overturning
  factor (bisected) as its collapse intensity, censored at the sweep's largest factor.
- **Intensity measures** (`jaxrock.intensity.intensity_of`): PGA, PGV, CAV, Sa(T) at a given period
  or the column's first period T₁ (eq. 21, the column's material), and the rocking-specific
  PGA/(g tanα) and PGV·p/(g tanα). Their **efficiency** is the dispersion β of each fit (the
  smaller, the fewer records a given confidence needs; Luco and Cornell 2007), their
  **sufficiency** the slope of the collapse intensities' residuals against ln(ω_p/p), the paper's
  frequency ratio with the record's pulse period Tp (`jaxrock.intensity.pulse_period`, ω_p = 2π/Tp),
  with its p-value (a sufficient measure leaves no trend: rocking overturning depends strongly on
  ω_p/p, so PGA is not expected to be sufficient).
- **Hazard** (`jaxrock.analyses.hazard`): the mean annual frequency of each damage state,
  λ_DS = ∫ P(DS | x) |dλ/dx| dx, for the first intensity measure, with the bootstrap band (each
  bootstrap fit integrated alike), the probability 1 − exp(−λ_DS T) in T years, and the
  deaggregation of λ_DS over x.
"""

from __future__ import annotations

import numpy as np

from .._validate import JaxrockInputError
from .fragility import BAND, N_BOOT, fit_lognormal, fit_truncated_ida

IDA_GRID = 64  # intensities of the IDA percentile curves


def check_damage_states(states) -> np.ndarray:
    """The damage-state thresholds of max θ/α: strictly increasing, each in (0, 1] (1: overturning)."""
    d = np.atleast_1d(np.asarray(states, dtype=float))
    if d.size == 0 or not np.all(np.isfinite(d) & (d > 0) & (d <= 1)) or np.any(np.diff(d) <= 0):
        raise JaxrockInputError(f"damage states {','.join(f'{v:g}' for v in d)}: valid: increasing thresholds of max θ/α in (0, 1] "
                                "(1: overturning), e.g. 0.1,0.5,1")
    return d


def _cells(ds):
    """The suite's column cells: their dims and, broadcast over them, tanα, 2h, E, ρ, the first
    fixed-base period T₁ (eq. 21) and the frequency parameter p (`jaxrock.Block.p`)."""
    import xarray as xr

    from ..geometry import Block
    from ..spring import Column, first_period_eq21

    template = ds.least_scale.isel({d: 0 for d in ("model", "record") if d in ds.least_scale.dims}, drop=True)
    dims = list(template.dims)
    concrete = Column.concrete()
    get = lambda name, default: xr.broadcast(ds[name] if name in ds else xr.DataArray(float(default)), template)[0].values.astype(float)
    cells = {"tan_alpha": get("tan_alpha", np.nan), "height": get("height", np.nan), "E": get("E", concrete.E),
             "rho": get("rho", concrete.rho)}
    cells["period"] = np.asarray(first_period_eq21(cells["height"], cells["tan_alpha"], cells["E"], cells["rho"]))
    cells["p"] = np.asarray(Block.from_slenderness(cells["height"], cells["tan_alpha"]).p)
    return dims, cells


def _intensities(spec, records, cells):
    """x of every record × cell for a factor of 1 (n_records, *cells) and its scaling power."""
    from ..intensity import intensity_of, parse_im

    name, units, power, _ = parse_im(spec)
    ta = cells["tan_alpha"]
    x = np.broadcast_to(intensity_of(spec, records, period=cells["period"], tan_alpha=ta, p=cells["p"]), (len(records), *ta.shape))
    return np.asarray(x, dtype=float), units, power


def _outcomes(ds, states):
    """(model, record, *cells, scale, state) probabilities that each run reaches each state."""
    over = ds.overturned.transpose("model", "record", ..., "scale").values.astype(bool)
    peak = ds.max_theta.transpose("model", "record", ..., "scale").values
    last = (ds.p_overturn if "p_overturn" in ds else ds.overturned).transpose("model", "record", ..., "scale").values.astype(float)
    return np.stack([last if d >= 1.0 else ((peak >= d) | over).astype(float) for d in states], axis=-1)


def ida_curves(edp, x, grid_size: int = IDA_GRID):
    """Median and 16/84 % IDA curves over records: `edp`, `x` (record, scale) → (grid, (3, grid)).

    Each record's curve is interpolated in ln x within its own range; a percentile at an intensity
    is over the records whose range covers it (NaN where none does)."""
    lx = np.log(x)
    grid = np.exp(np.linspace(lx.min(), lx.max(), int(grid_size)))
    at = np.full((x.shape[0], grid.size), np.nan)
    for r in range(x.shape[0]):
        inside = (np.log(grid) >= lx[r].min() - 1e-12) & (np.log(grid) <= lx[r].max() + 1e-12)
        at[r, inside] = np.interp(np.log(grid[inside]), lx[r], edp[r])
    with np.errstate(all="ignore"):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # an intensity no record covers: NaN
            q = np.nanpercentile(at, [16.0, 50.0, 84.0], axis=0)
    return grid, q


def _sufficiency(capacity, proxy, median):
    """Slope and p-value of ln(capacity/median) against ln(proxy) (ω_p/p) over the collapsed records."""
    from scipy.stats import linregress

    ok = np.isfinite(capacity) & np.isfinite(proxy) & (proxy > 0)
    if ok.sum() < 3 or not np.isfinite(median) or np.ptp(np.log(proxy[ok])) == 0:
        return np.nan, np.nan
    fit = linregress(np.log(proxy[ok]), np.log(capacity[ok] / median))
    return float(fit.slope), float(fit.pvalue)


def risk_analysis(ds, records, *, damage_states=(1.0,), ims=("pga",), hazard=None, years: float = 50.0,
                  n_boot: int | None = None, seed: int = 0):
    """Damage-state fragilities, IDA curves, intensity-measure efficiency and hazard of a suite.

    See the module docstring (`jaxrock.analyses.risk`) for the methods. Nothing is run again: every
    number comes from the suite's sweep and bisection.

    Arguments:
        ds (xarray.Dataset): a suite (`jaxrock.run_suite`), with its `model` dimension.
        records (Sequence[Record]): the suite's records, in its order (for Sa, CAV, ...).
        damage_states (Sequence[float]): thresholds of max θ/α, increasing in (0, 1]; 1: overturning.
        ims (Sequence[str]): intensity measures (`jaxrock.intensity.parse_im`: "pga", "pgv", "cav",
            "arias", "sa:0.5", "sa:T1", "pga_ratio", "pgv_ratio", ...); the first is the hazard's.
        hazard (HazardCurve | None): the hazard curve of the first measure, in its SI units; None: no
            risk integration.
        years: the exposure time T of the probabilities [years], > 0.
        n_boot: bootstrap resamplings of the records; default `N_BOOT`.
        seed: the bootstrap's seed.

    Returns:
        (xarray.Dataset): over `model`, the cells, `damage_state`, `im`: `ds_median`, `ds_beta` with
            5–95 % intervals and bootstrap fits, `crosses`; `ida_median`, `ida_beta` (truncated IDA),
            `sufficiency_slope`, `sufficiency_p`; over `record`, `scale`: `ida_im`, `ida_edp`; with a
            hazard, `maf`, its band `maf_band` (16–84 % of the bootstrap), `p_years`.

    Raises:
        JaxrockInputError: on thresholds or measures out of range, or `years` not > 0.

    Example:
        ```python
        import jaxrock
        from jaxrock.analyses.risk import risk_analysis
        recs = jaxrock.read_records("builtin")
        ds = jaxrock.run_suite("rigid", recs, scale=[0.5, 1, 2, 4], height=4.0, tan_alpha=0.2, progress=False)
        risk = risk_analysis(ds, recs, damage_states=[0.1, 0.5, 1], ims=["sa:T1", "pgv"])
        risk.ds_median.sel(im="pgv")
        ```
    """
    import xarray as xr

    from ..intensity import parse_im

    states = check_damage_states(damage_states)
    ims = list(ims)
    if not ims or len(set(ims)) < len(ims):
        raise JaxrockInputError(f"im {','.join(ims)}: give one or more distinct intensity measures")
    for spec in ims:
        if parse_im(spec)[2] == 0:
            raise JaxrockInputError(f"--im {spec}: does not scale with the record (a fragility needs a measure that grows with the factor)")
    if not (np.isfinite(years) and years > 0):
        raise JaxrockInputError(f"years = {years}; valid: a number > 0 (the exposure time)")
    n_boot = N_BOOT if n_boot is None else int(n_boot)
    cell_dims, cells = _cells(ds)
    shape = cells["tan_alpha"].shape
    models = list(ds.model.values)
    scale = ds.scale.values.astype(float)
    reached = _outcomes(ds, states)  # (model, record, *cells, scale, state)
    ok = ds.status.transpose("model", "record", ..., "scale").values == 0
    over = ds.overturned.transpose("model", "record", ..., "scale").values.astype(bool)
    peak = ds.max_theta.transpose("model", "record", ..., "scale").values
    least = ds.least_scale.transpose("model", "record", ...).values
    n_rec = ds.sizes["record"]
    group = np.broadcast_to(np.arange(n_rec)[:, None], (n_rec, scale.size))
    from ..intensity import intensity_of

    proxy = np.asarray(intensity_of("omega_ratio", records, p=cells["p"]), dtype=float)  # (record, *cells): ω_p/p
    S, I = len(states), len(ims)
    med = np.full((len(models), *shape, S, I), np.nan)
    beta, med_ci, beta_ci = med.copy(), np.full(med.shape + (2,), np.nan), np.full(med.shape + (2,), np.nan)
    med_boot, beta_boot = np.full(med.shape + (n_boot,), np.nan), np.full(med.shape + (n_boot,), np.nan)
    n_obs = np.zeros(med.shape, dtype=np.int32)
    n_hit = np.zeros(med.shape)
    ida_med, ida_beta = np.full((len(models), *shape, I), np.nan), np.full((len(models), *shape, I), np.nan)
    ida_med_ci = np.full((len(models), *shape, I, 2), np.nan)
    ida_n = np.zeros((len(models), *shape, I), dtype=np.int32)
    suff_slope, suff_p = ida_med.copy(), ida_med.copy()
    ida_im = np.zeros((I, n_rec, *shape, scale.size))
    units = []
    for i, spec in enumerate(ims):
        x1, u, power = _intensities(spec, records, cells)
        units.append(u)
        ida_im[i] = x1[..., None] * scale**power
        for m in range(len(models)):
            for c in np.ndindex(*shape):
                x = x1[(slice(None), *c)][:, None] * scale[None, :] ** power  # (record, scale)
                good = ok[(m, slice(None), *c)]
                for s in range(S):
                    y = reached[(m, slice(None), *c, slice(None), s)]
                    if not good.any():
                        continue
                    f = fit_lognormal(x[good], y[good], group[good], n_boot=n_boot, seed=seed)
                    at = (m, *c, s, i)
                    med[at], beta[at], med_ci[at], beta_ci[at] = f["median"], f["beta"], f["median_ci"], f["beta_ci"]
                    med_boot[at], beta_boot[at], n_obs[at], n_hit[at] = f["median_boot"], f["beta_boot"], f["n"], f["n_overturned"]
                cap = least[(m, slice(None), *c)] ** power * x1[(slice(None), *c)]
                top = scale.max() ** power * x1[(slice(None), *c)]
                if np.isfinite(cap).any():
                    t = fit_truncated_ida(cap, top, n_boot=n_boot, seed=seed)
                    ida_med[(m, *c, i)], ida_beta[(m, *c, i)], ida_med_ci[(m, *c, i)] = t["median"], t["beta"], t["median_ci"]
                    ida_n[(m, *c, i)] = t["n_overturned"]
                    suff_slope[(m, *c, i)], suff_p[(m, *c, i)] = _sufficiency(cap, proxy[(slice(None), *c)], t["median"])
    # the family's curves cross where a lower state's probability falls below a higher one's
    lo_x, hi_x = ida_im.reshape(I, -1).min(1), ida_im.reshape(I, -1).max(1)
    grid = np.exp(np.linspace(np.log(lo_x), np.log(hi_x), 200))  # (200, I)
    from .fragility import probability

    with np.errstate(invalid="ignore"):
        P = probability(grid[:, None, :], med[..., None, :, :], beta[..., None, :, :])  # (model, *cells, 200, S, I)
    crosses = np.zeros(med.shape, dtype=bool)
    crosses[..., :-1, :] = (P[..., :-1, :] < P[..., 1:, :] - 1e-9).any(axis=-3)
    edp = np.where(over, 1.0, np.minimum(peak, 1.0))
    lead = ("model", *cell_dims)
    coords = {"model": ds.model, **{d: ds[d] for d in cell_dims}, "damage_state": ("damage_state", states, {"units": "max theta/alpha"}),
              "im": ("im", np.asarray(ims, dtype=object)), "bound": ("bound", np.array([5.0, 95.0]), {"units": "percent"}),
              "record": ds.record, "scale": ds.scale}
    out = xr.Dataset(
        {
            "ds_median": ((*lead, "damage_state", "im"), med, {"long_name": "damage-state fragility median (the im's units)"}),
            "ds_beta": ((*lead, "damage_state", "im"), beta, {"long_name": "damage-state fragility dispersion", "units": "1"}),
            "ds_median_ci": ((*lead, "damage_state", "im", "bound"), med_ci, {"long_name": "bootstrap 5-95 % interval of ds_median"}),
            "ds_beta_ci": ((*lead, "damage_state", "im", "bound"), beta_ci, {"long_name": "bootstrap 5-95 % interval of ds_beta"}),
            "ds_median_boot": ((*lead, "damage_state", "im", "bootstrap"), med_boot, {"long_name": "median of each bootstrap fit"}),
            "ds_beta_boot": ((*lead, "damage_state", "im", "bootstrap"), beta_boot, {"long_name": "beta of each bootstrap fit"}),
            "ds_n": ((*lead, "damage_state", "im"), n_obs, {"long_name": "observations (runs ending ok)"}),
            "ds_n_reached": ((*lead, "damage_state", "im"), n_hit, {"long_name": "observations that reached the state"}),
            "crosses": ((*lead, "damage_state", "im"), crosses, {
                "long_name": "this state's curve falls below the next state's somewhere within the suite's intensities"}),
            "ida_median": ((*lead, "im"), ida_med, {"long_name": "truncated-IDA fit: median collapse intensity (Baker 2015)"}),
            "ida_median_ci": ((*lead, "im", "bound"), ida_med_ci, {"long_name": "bootstrap 5-95 % interval of ida_median"}),
            "ida_n_collapsed": ((*lead, "im"), ida_n, {"long_name": "records that overturned within the sweep (the others censored)"}),
            "ida_beta": ((*lead, "im"), ida_beta, {"long_name": "truncated-IDA fit: record-to-record dispersion", "units": "1"}),
            "sufficiency_slope": ((*lead, "im"), suff_slope, {"long_name": "slope of ln(collapse im / ida_median) against ln(omega_p/p)"}),
            "sufficiency_p": ((*lead, "im"), suff_p, {"long_name": "p-value of sufficiency_slope (small: the measure is not sufficient)"}),
            "column_period": (tuple(cell_dims), cells["period"], {"long_name": "column's first fixed-base period T1 (eq. 21): sa:T1's",
                                                                  "units": "s"}),
            "ida_im": (("im", "record", *cell_dims, "scale"), ida_im, {"long_name": "each run's intensity s^k IM(record)"}),
            "ida_edp": (("model", "record", *cell_dims, "scale"), edp, {
                "long_name": "max theta/alpha of each run, 1 from overturning on (flat-lining)", "units": "1"}),
            "windows": ds.windows.transpose("model", "record", ...),
        },
        coords=coords,
        attrs={"im_units": list(units), "n_boot": n_boot, "seed": seed,
               "fit": "per damage state: lognormal CDF by maximum likelihood of the sweep's outcomes (Baker 2015, multiple stripes), "
                      "bootstrap over records; IDA: truncated at the sweep's largest factor (Baker 2015)"},
    )
    if hazard is not None:
        from .hazard import mean_annual_frequency, probability_in_years

        maf = mean_annual_frequency(med[..., 0], beta[..., 0], hazard)
        boot = mean_annual_frequency(med_boot[..., 0, :], beta_boot[..., 0, :], hazard)
        with np.errstate(all="ignore"):
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                bnd = np.moveaxis(np.nanpercentile(boot, BAND, axis=-1), 0, -1)
        out["maf"] = ((*lead, "damage_state"), maf, {"long_name": f"mean annual frequency of the damage state ({ims[0]})", "units": "1/year"})
        out["maf_band"] = ((*lead, "damage_state", "band"), bnd, {"long_name": "bootstrap 16-84 % band of maf", "units": "1/year"})
        out["p_years"] = ((*lead, "damage_state"), probability_in_years(maf, years), {
            "long_name": f"probability of reaching the damage state in {years:g} years (Poisson)", "units": "1"})
        # the deaggregation of each state's frequency over the measure: P(DS | x) |dλ/dx| x / λ_DS, a density in ln x
        m0, b0 = med[..., 0], beta[..., 0]
        fin = np.isfinite(m0) & np.isfinite(b0)
        lo = np.nanmin(np.where(fin, m0 * np.exp(-4.0 * b0), np.nan)) if fin.any() else 1.0
        hi = np.nanmax(np.where(fin, m0 * np.exp(4.0 * b0), np.nan)) if fin.any() else 2.0
        xg = np.exp(np.linspace(np.log(lo), np.log(hi), 200))
        with np.errstate(invalid="ignore", divide="ignore"):
            dens = probability(xg, m0[..., None], b0[..., None]) * hazard.slope_density(xg) * xg / maf[..., None]
        out["deaggregation"] = ((*lead, "damage_state", "hazard_im"), dens, {
            "long_name": "share of the damage state's mean annual frequency per unit ln x: P(DS|x) |dλ/dx| x / maf", "units": "1"})
        out = out.assign_coords(band=("band", np.asarray(BAND), {"units": "percent"}),
                                hazard_im=("hazard_im", xg, {"long_name": ims[0], "units": units[0]}))
        out.attrs.update({"years": float(years), "hazard": f"a curve of {hazard.im.size} points from {hazard.im[0]:.4g} to {hazard.im[-1]:.4g} {units[0]}"})
    return out


__all__ = ["check_damage_states", "ida_curves", "risk_analysis", "IDA_GRID"]
