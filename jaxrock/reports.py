"""Reports: the workflows that run an analysis and write its files — numbers (`jaxrock.io`) and
figures (`jaxrock.plotting`) — for the CLI, the experiments and scripts: the damper calibration
(table, figure 7, calibrated c̄), a spectrum's netCDF and PNG, a record spectrum's netCDF, CSV and
PNG."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .analyses.calibration import CALIBRATION_ANGLES, CalibrationResult, PowerLawFit, calibrate_cbar, fit_power_law, rm_targets, warm_up
from .analyses.fragility import BETA_MIN
from .analyses.free_rocking import FIG7_CBARS, FIG7_TAN_ALPHAS, SpringFamily, energy_ratio_grid
from .io.files import text_head, write_output
from .io.tables import write_table
from .plotting import plot_calibration, plot_energy_ratio, plot_record_spectrum, plot_spectrum

import matplotlib.pyplot as plt  # noqa: E402  (after jaxrock.plotting chose the backend)


@dataclass
class CalibrationReport:
    """What `calibration_report` computed and wrote (numpy arrays; `table` is a list of row dicts)."""

    result: CalibrationResult
    fit: PowerLawFit
    fit_paper_range: PowerLawFit | None  # over the points with 0.1 ≤ tanα ≤ 0.3 (the paper's); None: fewer than 3 there
    table: list[dict]
    fig7_theta0_over_alpha: np.ndarray
    fig7_r2: np.ndarray  # (n_tanα, n_c̄, n_θ)
    files: dict[str, Path] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)

    def format_table(self) -> str:
        head = f"{'tanα':>6} {'α [rad]':>8} {'target r²':>10} {'c̄ calib':>9} {'c̄ eq.17':>9} {'ratio':>6} {'residual':>9} {'iters':>5}"
        rows = [head]
        for r in self.table:
            rows.append(
                f"{r['tan_alpha']:6.4g} {r['alpha']:8.4f} {r['target_r2']:10.4f} {r['cbar_calibrated']:9.4f} "
                f"{r['cbar_eq17']:9.4f} {r['cbar_calibrated'] / r['cbar_eq17']:6.3f} {r['residual_rms']:9.2e} {r['iterations']:5d}"
            )
        rows.append(f"fit over tanα ∈ [{self.table[0]['tan_alpha']:g}, {self.table[-1]['tan_alpha']:g}]: {self.fit}  (paper: k = 0.02, n = 2)")
        rows.append("fit over tanα ∈ [0.1, 0.3]: "
                    + (f"{self.fit_paper_range}" if self.fit_paper_range is not None else "none (fewer than 3 of the tanα are in it)"))
        return "\n".join(rows)


def calibration_report(
    out_dir="out",
    *,
    tan_alphas=None,
    theta0_over_alpha=CALIBRATION_ANGLES,
    family: SpringFamily | None = None,
    fig7_theta0_over_alpha=None,
    progress: bool = True,
    max_iter: int = 300,
) -> CalibrationReport:
    """Calibrate c̄ over a range of tanα, fit c̄ = k (α/0.1)^n, and write the table and figures.

    Written to `out_dir`: `calibration.csv` (tanα, α, target r², calibrated c̄, eq. 17 c̄, residual,
    …), `fig07_energy_ratio.png` (r_eq² against θ₀/α for tanα = 0.1, 0.2, 0.3 and c̄ = 0.02, 0.08,
    0.18, RM r² levels as horizontal lines) and `calibration_cbar.png`. Imports matplotlib.

    Arguments:
        out_dir (str | os.PathLike): the output folder, made if missing; default "out".
        tan_alphas (ArrayLike | None): the slendernesses tanα, each in (0, 1); default None: 13 values
            over [0.05, 0.35].
        theta0_over_alpha (Sequence[float]): the calibration angles θ₀/α, each in (0, 1); default
            `CALIBRATION_ANGLES`.
        family: the spring models calibrated (`SpringFamily`); default None: `SpringFamily()`.
        fig7_theta0_over_alpha (ArrayLike | None): the θ₀/α of figure 7; default None: 32 values over
            [0.05, 0.98].
        progress: show progress bars; default True.
        max_iter: the calibration's most iterations (`calibrate_cbar`), ≥ 1; default 300.

    Returns:
        The data (`CalibrationReport`; `format_table()` gives the printable table).

    Raises:
        JaxrockInputError: as `calibrate_cbar` raises it (a tanα or θ₀/α outside (0, 1), `max_iter` < 1).

    Example:
        ```python
        import jaxrock
        report = jaxrock.calibration_report("out", tan_alphas=[0.1, 0.2, 0.3])
        print(report.format_table())
        ```
    """
    family = SpringFamily() if family is None else family
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ta = np.round(np.linspace(0.05, 0.35, 13), 6) if tan_alphas is None else np.asarray(tan_alphas, dtype=float)
    xs7 = np.linspace(0.05, 0.98, 32) if fig7_theta0_over_alpha is None else np.asarray(fig7_theta0_over_alpha, dtype=float)
    seconds = {}

    # compile (and run once) the per-iteration pass first, to report compile and run time apart
    t0 = time.perf_counter()
    warm_up(ta, theta0_over_alpha, family)
    seconds["compile"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = calibrate_cbar(ta, theta0_over_alpha=theta0_over_alpha, family=family, progress=progress, max_iter=max_iter)
    seconds["calibration"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    r7 = np.asarray(energy_ratio_grid(FIG7_TAN_ALPHAS, FIG7_CBARS, xs7, family=family))
    targets7 = np.asarray(rm_targets(family, FIG7_TAN_ALPHAS))
    seconds["figure7"] = time.perf_counter() - t0

    fit = fit_power_law(res.alpha, res.cbar)
    sel = (np.asarray(res.tan_alpha) >= 0.1 - 1e-9) & (np.asarray(res.tan_alpha) <= 0.3 + 1e-9)
    fit_pr = fit_power_law(np.asarray(res.alpha)[sel], np.asarray(res.cbar)[sel]) if sel.sum() >= 3 else None

    table = []
    for i in range(len(ta)):
        table.append(
            dict(
                tan_alpha=float(res.tan_alpha[i]),
                alpha=float(res.alpha[i]),
                target_r2=float(res.target[i]),
                cbar_calibrated=float(res.cbar[i]),
                cbar_eq17=float(res.cbar_eq17[i]),
                residual_rms=float(res.residual[i]),
                bias=float(res.bias[i]),
                r2_min=float(np.min(res.r2[i])),
                r2_max=float(np.max(res.r2[i])),
                iterations=int(res.iterations[i]),
                converged=bool(res.converged[i]),
            )
        )
    files = {
        "table": out / "calibration.csv",
        "figure7": out / "fig07_energy_ratio.png",
        "calibration": out / "calibration_cbar.png",
    }
    write_table(files["table"], table, footer=f"fit: {fit}; paper eq. 17: k = 0.02, n = 2")
    plt.close(plot_energy_ratio(FIG7_TAN_ALPHAS, FIG7_CBARS, xs7, r7, targets7, path=files["figure7"]))
    plt.close(plot_calibration(res, fit, path=files["calibration"]))
    return CalibrationReport(
        result=res,
        fit=fit,
        fit_paper_range=fit_pr,
        table=table,
        fig7_theta0_over_alpha=xs7,
        fig7_r2=r7,
        files=files,
        seconds=seconds,
    )


def spectrum_files(spec, out: Path, title: str) -> tuple[Path, Path]:
    """Write a `Spectrum` as `<out>.nc` (netCDF, `Spectrum.save`) and its figure as `<out>.png`."""
    nc = spec.save(Path(f"{out}.nc"))
    png = Path(f"{out}.png")
    plt.close(plot_spectrum(spec, title=title, path=png))
    return nc, png


def record_spectrum_files(rs, out: Path, label: str, title: str) -> tuple[Path, Path, Path]:
    """Write a `RecordSpectrum` as `<out>.nc`, `<out>.csv` (height, least scale, bracket's lower end,
    uncertain, the worst status of the height's runs) and its figure as `<out>.png`."""
    nc = rs.save(Path(f"{out}.nc"))
    csv_path = Path(f"{out}.csv")
    rows = [{"height": float(h), "least_scale": float(s), "bracket_low": float(lo)} for h, s, lo in zip(rs.height, rs.scale, rs.bracket_low)]
    if rs.uncertain is not None:
        rows = [{**row, "uncertain": int(u)} for row, u in zip(rows, rs.uncertain)]
    if rs.worst_status is not None:
        from .results import STATUS_NAMES

        rows = [{**row, "worst_status": STATUS_NAMES[int(w)]} for row, w in zip(rows, rs.worst_status)]
    write_table(csv_path, rows)
    png = Path(f"{out}.png")
    plt.close(plot_record_spectrum([rs], [label], path=png, title=title))
    return nc, csv_path, png


def _count(x) -> int | float:
    """A count of overturned observations: an integer, or a sum of probabilities (an ensemble's)."""
    v = float(x)
    return int(v) if v == int(v) else v


def fragility_rows(ds) -> list[dict]:
    """A record suite's fragility (`jaxrock.analyses.suite.run_suite`), one row per model and cell
    (the sweep's fixed quantities, the cell's values, the intensity measure, the median and β with
    their 5–95 % bootstrap bounds, the outcomes counted): `fragility.csv`'s rows."""
    cells = [d for d in ds.least_scale.dims if d not in ("model", "record")]
    fixed = {c: float(ds[c]) for c in ds.coords if ds[c].ndim == 0}
    rows = []
    for idx in np.ndindex(*(ds.sizes[d] for d in ("model", *cells))):
        one = ds.isel(dict(zip(("model", *cells), idx)))
        (m_lo, m_hi), (b_lo, b_hi) = one.fragility_median_ci.values, one.fragility_beta_ci.values
        rows.append({"model": str(one.model.values), **fixed, **{d: float(one[d]) for d in cells}, "im": ds.attrs.get("im", ""),
                     "median": float(one.fragility_median), "median_5": float(m_lo), "median_95": float(m_hi),
                     "beta": float(one.fragility_beta), "beta_5": float(b_lo), "beta_95": float(b_hi), "n": int(one.fragility_n),
                     "n_overturned": _count(one.fragility_n_overturned), "n_failed": int(one.fragility_n_failed)})
    return rows


def suite_files(ds, out: Path, title: str) -> dict[str, Path]:
    """Write a record suite (`jaxrock.analyses.suite.run_suite`) into the folder `out`: the dataset
    `suite.zarr` (xarray.open_zarr), `least_scale.csv`, the fragility table `fragility.csv` and
    `fragility.md`, and the figures `least_scale.png` and `fragility.png`."""
    import shutil
    import warnings

    from .plotting import plot_fragility, plot_suite_scales

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    z = out / "suite.zarr"
    tmp = out / "tmp_suite.zarr"
    shutil.rmtree(tmp, ignore_errors=True)
    with warnings.catch_warnings():  # consolidated metadata is "not part of the format 3 specification": xarray reads it, and warns without it
        warnings.simplefilter("ignore")
        ds.to_zarr(tmp, mode="w", zarr_format=3, consolidated=True)
    shutil.rmtree(z, ignore_errors=True)
    tmp.rename(z)
    files["dataset"] = z
    cells = [d for d in ds.least_scale.dims if d not in ("model", "record")]
    fixed = {c: float(ds[c]) for c in ds.coords if ds[c].ndim == 0}  # the sweep's fixed quantities (2h, tanα, ...)
    rows = []
    for idx in np.ndindex(*(ds.sizes[d] for d in ("model", "record", *cells))):
        sel = dict(zip(("model", "record", *cells), idx))
        one = ds.isel(sel)
        rows.append({"model": str(one.model.values), "record": str(one.record.values), **fixed, **{d: float(one[d]) for d in cells},
                     "least_scale": float(one.least_scale), "bracket_low": float(one.bracket_low),
                     "bracket_width": float(one.bracket_width), "windows": int(one.windows), "worst_status": int(one.worst_status),
                     "uncertain": int(one.least_scale_uncertain)})
    files["least_scale"] = write_table(out / "least_scale.csv", rows)
    units = ds.fragility_median.attrs.get("units", "")
    im = ds.attrs.get("im", "")
    rows = fragility_rows(ds)
    head = ["model", *cells, f"median {im} [{units}]", "5–95 %", "β", "5–95 %", "overturned / runs", "failed"]
    md = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]  # no empty column where the suite has one cell
    for r in rows:
        md.append("| " + " | ".join([r["model"], *(f"{r[d]:g}" for d in cells), f"{r['median']:.4g}",
                                     f"{r['median_5']:.4g}–{r['median_95']:.4g}", f"{r['beta']:.3f}", f"{r['beta_5']:.3f}–{r['beta_95']:.3f}",
                                     f"{r['n_overturned']:g} / {r['n']}", f"{r['n_failed']}"]) + " |")
    files["fragility"] = write_table(out / "fragility.csv", rows)
    note = (f"Lognormal fragility P = Φ(ln(x/θ)/β) by maximum likelihood of every record × factor outcome of the sweep "
            f"(Baker 2015, multiple stripes), x = {im}; intervals: bootstrap over records ({ds.fragility_median_boot.sizes['bootstrap']} "
            f"resamplings). β = {BETA_MIN:g} marks outcomes one intensity separates exactly.")
    text = f"# {title}" + "".join(f", {k} = {v:g}" for k, v in fixed.items()) + "\n\n" + "\n".join(md) + f"\n\n{note}\n"
    files["table"] = write_output(out / "fragility.md", lambda tmp: Path(tmp).write_text(text, encoding="utf-8"), text_head(text))
    plt.close(plot_suite_scales(ds, path=out / "least_scale.png", title=f"{title}: least overturning scale factor"))
    plt.close(plot_fragility(ds, path=out / "fragility.png", title=f"{title}: fragility"))
    files["least_scale_png"], files["fragility_png"] = out / "least_scale.png", out / "fragility.png"
    return files


__all__ = ["CalibrationReport", "calibration_report", "spectrum_files", "record_spectrum_files", "suite_files"]


PELICUN_DEMANDS = {"pga": ("Peak Ground Acceleration", "g"), "pgv": ("Peak Ground Velocity", "mps")}  # + Sa: "Peak Spectral Acceleration|T"


def _cell_rows(risk):
    """(model index, cell index tuple, {name: value}) of every model × cell of a risk dataset."""
    cells = [d for d in risk.ds_median.dims if d not in ("model", "damage_state", "im")]
    fixed = {c: float(risk[c]) for c in risk.coords if risk[c].ndim == 0}
    for m in range(risk.sizes["model"]):
        for idx in np.ndindex(*(risk.sizes[d] for d in cells)):
            yield m, dict(zip(cells, idx)), {"model": str(risk.model.values[m]), **fixed, **{d: float(risk[d][i]) for d, i in zip(cells, idx)}}


def _pelicun_demand(spec: str, T1: float):
    """pelicun's demand type and unit of an intensity measure, and the factor from jaxrock's SI
    value; None for a measure pelicun has no demand type for."""
    from .geometry import G

    if spec in PELICUN_DEMANDS:
        name, unit = PELICUN_DEMANDS[spec]
        return name, unit, (1.0 / G if unit == "g" else 1.0)
    if spec.startswith("sa:"):
        period = T1 if spec == "sa:T1" else float(spec[3:])
        return f"Peak Spectral Acceleration|{period:.4g}", "g", 1.0 / G
    return None


def risk_files(risk, out: Path, title: str) -> dict[str, Path]:
    """Write a suite's risk analysis (`jaxrock.analyses.risk.risk_analysis`) into `out`: the damage
    states' fragilities `damage_states.csv` and `damage_states.png`, their pelicun fragility table
    `pelicun_fragility.csv` (pelicun's columns: Demand-Type, Demand-Unit, LSk-Family, LSk-Theta_0 the
    median, LSk-Theta_1 the dispersion; one row per model × column × measure pelicun names: PGA, PGV,
    Sa), the IDA curves `ida.csv` and `ida.png` and their median and 16/84 % curves `ida_fractiles.csv`, the measures' efficiency and sufficiency
    `efficiency.csv` and `efficiency.md`, and with a hazard the mean annual frequencies `risk.csv`,
    `risk.md` and the deaggregation `deaggregation.png`."""
    from .plotting import plot_damage_states, plot_deaggregation, plot_ida

    out = Path(out)
    files = {}
    ims, units = [str(i) for i in risk.im.values], list(risk.attrs["im_units"])
    states = risk.damage_state.values
    rows, pel, eff, maf = [], [], [], []
    for m, sel, head in _cell_rows(risk):
        one = risk.isel(model=m, **sel)
        for i, spec in enumerate(ims):
            for s, d in enumerate(states):
                f = one.isel(im=i, damage_state=s)
                rows.append({**head, "im": spec, "im_units": units[i], "damage_state": float(d), "median": float(f.ds_median),
                             "median_5": float(f.ds_median_ci[0]), "median_95": float(f.ds_median_ci[1]), "beta": float(f.ds_beta),
                             "beta_5": float(f.ds_beta_ci[0]), "beta_95": float(f.ds_beta_ci[1]), "n": int(f.ds_n),
                             "n_reached": _count(f.ds_n_reached), "crosses_next": int(f.crosses)})
            demand = _pelicun_demand(spec, float(one.column_period))
            if demand is not None and np.isfinite(one.ds_median.isel(im=i).values).all():
                name, unit, factor = demand
                ident = ".".join([head["model"], *(f"{k}={v:g}" for k, v in head.items() if k != "model")])
                row = {"ID": ident, "Incomplete": 0, "Demand-Type": name, "Demand-Unit": unit, "Demand-Offset": 0, "Demand-Directional": 1}
                for s in range(states.size):
                    f = one.isel(im=i, damage_state=s)
                    row |= {f"LS{s + 1}-Family": "lognormal", f"LS{s + 1}-Theta_0": float(f.ds_median) * factor,
                            f"LS{s + 1}-Theta_1": float(f.ds_beta)}
                pel.append(row)
            f = one.isel(im=i, damage_state=-1)
            eff.append({**head, "im": spec, "im_units": units[i], "beta": float(f.ds_beta), "separated": int(float(f.ds_beta) == BETA_MIN),
                        "ida_median": float(one.ida_median[i]), "ida_beta": float(one.ida_beta[i]),
                        "ida_n_collapsed": int(one.ida_n_collapsed[i]), "sufficiency_slope": float(one.sufficiency_slope[i]),
                        "sufficiency_p": float(one.sufficiency_p[i])})
        if "maf" in risk:
            for s, d in enumerate(states):
                lam = float(one.maf[s])
                maf.append({**head, "im": ims[0], "damage_state": float(d), "separated": int(float(one.ds_beta[s, 0]) == BETA_MIN), "maf": lam, "maf_16": float(one.maf_band[s, 0]),
                            "maf_84": float(one.maf_band[s, 1]), "return_period": 1.0 / lam if lam > 0 else float("inf"),
                            f"p_{risk.attrs['years']:g}_years": float(one.p_years[s])})
    files["damage_states"] = write_table(out / "damage_states.csv", rows)
    if pel:
        files["pelicun"] = write_table(out / "pelicun_fragility.csv", pel)
    ida = []
    cells = [d for d in risk.ds_median.dims if d not in ("model", "damage_state", "im")]
    for m, sel, head in _cell_rows(risk):
        one = risk.isel(model=m, **sel)
        for r in range(risk.sizes["record"]):
            for k in range(risk.sizes["scale"]):
                ida.append({**head, "record": str(risk.record.values[r]), "scale": float(risk.scale[k]),
                            **{spec: float(one.ida_im[i, r, k]) for i, spec in enumerate(ims)},
                            "max_theta": float(one.ida_edp[r, k]), "resurrections": int(one.windows[r])})
    files["ida"] = write_table(out / "ida.csv", ida, footer="max_theta: max θ/α of the run, 1 from overturning on; resurrections: "
                               "the record's turns from overturned back to standing as the factor grows")
    from .analyses.risk import ida_curves

    fractiles = []
    for m, sel, head in _cell_rows(risk):
        one = risk.isel(model=m, **sel)
        grid, (p16, p50, p84) = ida_curves(one.ida_edp.transpose("record", "scale").values,
                                           one.ida_im.isel(im=0).transpose("record", "scale").values)
        fractiles += [{**head, ims[0]: float(x), "max_theta_16": float(a), "max_theta_50": float(b), "max_theta_84": float(c)}
                      for x, a, b, c in zip(grid, p16, p50, p84)]
    files["ida_fractiles"] = write_table(out / "ida_fractiles.csv", fractiles, footer="percentiles of max θ/α over the records at each "
                                         "intensity (each record's curve interpolated in ln x within its own range)")
    files["efficiency_csv"] = write_table(out / "efficiency.csv", eff)
    # the summary: per model and measure, the median over the columns of each dispersion
    md = ["| model | measure | β (overturning, stripes) | β (truncated IDA) | sufficiency slope (p) |", "|---|---|---|---|---|"]
    best = {}
    for mod in risk.model.values:
        for spec in ims:
            # a column whose outcomes one intensity separates, or with fewer than 3 overturning records, has no dispersion to compare
            mine = [e for e in eff if e["model"] == str(mod) and e["im"] == spec and not e["separated"] and e["ida_n_collapsed"] >= 3]
            b = np.nanmedian([e["beta"] for e in mine]) if any(np.isfinite(e["beta"]) for e in mine) else np.nan
            bi = np.nanmedian([e["ida_beta"] for e in mine]) if any(np.isfinite(e["ida_beta"]) for e in mine) else np.nan
            sl = np.nanmedian([e["sufficiency_slope"] for e in mine]) if any(np.isfinite(e["sufficiency_slope"]) for e in mine) else np.nan
            pv = np.nanmedian([e["sufficiency_p"] for e in mine]) if any(np.isfinite(e["sufficiency_p"]) for e in mine) else np.nan
            md.append(f"| {mod} | {spec} | {b:.3f} | {bi:.3f} | {sl:.3f} ({pv:.2g}) |")
            if np.isfinite(bi):
                best.setdefault(str(mod), []).append((bi, spec))
    note = ("Efficiency: the dispersion β of each measure's overturning fit (median over the columns with at least 3 overturning "
            "records and outcomes no intensity separates); the smaller, the more "
            "efficient. Sufficiency: the slope of ln(collapse intensity / median) against ln(ω_p/p) over the records (ω_p = 2π/Tp, "
            "Tp the peak of the record's velocity spectrum); "
            "a sufficient measure leaves none (p large). Most efficient (truncated IDA): "
            + (", ".join(f"{k}: " + " = ".join(sp for b, sp in v if b <= min(v)[0] * (1 + 1e-9)) for k, v in best.items()) or "none fitted")
            + " (measures proportional to each other on a column, PGA and PGA/(g tanα), tie).")
    text = f"# {title}: intensity measures\n\n" + "\n".join(md) + f"\n\n{note}\n"
    files["efficiency"] = write_output(out / "efficiency.md", lambda tmp: Path(tmp).write_text(text, encoding="utf-8"), text_head(text))
    plt.close(plot_damage_states(risk, path=out / "damage_states.png", title=f"{title}: damage states ({ims[0]})"))
    plt.close(plot_ida(risk, path=out / "ida.png", title=f"{title}: IDA curves ({ims[0]})"))
    files["damage_states_png"], files["ida_png"] = out / "damage_states.png", out / "ida.png"
    if maf:
        files["risk_csv"] = write_table(out / "risk.csv", maf)
        years = risk.attrs["years"]
        md = [f"| model | {' | '.join(cells)} | damage state | MAF [1/yr] | 16–84 % | return period [yr] | P in {years:g} yr |",
              "|" + "---|" * (6 + len(cells))]
        for r in maf:
            md.append("| " + " | ".join([r["model"], *(f"{r[d]:g}" for d in cells), f"{r['damage_state']:g}",
                                         f"{r['maf']:.3g}" + (" †" if r["separated"] else ""),
                                         f"{r['maf_16']:.3g}–{r['maf_84']:.3g}", f"{r['return_period']:.4g}",
                                         f"{r[f'p_{years:g}_years']:.3g}"]) + " |")
        note = (f"Mean annual frequency λ = ∫ P(DS | x) |dλ/dx| dx of each damage state (max θ/α ≥ the state; 1: overturning) "
                f"against {ims[0]}, hazard {risk.attrs['hazard']}; band: bootstrap over records; P = 1 − exp(−λ T). † one "
                f"intensity separates the state's outcomes (β = {BETA_MIN:g}: a step, its band degenerate): too few runs reach "
                "it to fit a dispersion; widen --scale.")
        text = f"# {title}: risk\n\n" + "\n".join(md) + f"\n\n{note}\n"
        files["risk"] = write_output(out / "risk.md", lambda tmp: Path(tmp).write_text(text, encoding="utf-8"), text_head(text))
        plt.close(plot_deaggregation(risk, path=out / "deaggregation.png", title=f"{title}: deaggregation over {ims[0]}"))
        files["deaggregation_png"] = out / "deaggregation.png"
    return files


__all__ += ["risk_files"]
