"""The `jaxrock` commands (typer): each parses its options, calls the library and prints; files are
written by `jaxrock.reports` and the analyses themselves."""

from __future__ import annotations

import math
import os
import re
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from . import guards
from .guards import (report, say, EXIT_INTERRUPTED, EXIT_UNTRUSTED, _estimate, _exit_if_untrusted, _guarded,
                     _history, _hold, _interrupted, _OneLineErrors, _resume_command, _status_counts, record_run_seconds,
                     SENSITIVITY_COST, cell_seconds)
from ..outputs import OUTPUTS, RESULT_COLUMNS
from ..scene import (BUILTIN_SUITE, DEFAULT_BACKBONE, DEFAULT_MODEL, DEFAULT_PULSE, DEFAULT_SMOOTHING, MAX_ENSEMBLE, MAX_REFINE, PULSES,
                     RECORD_ALIASES, TAN_ALPHA, UNDAMPED, builtin_record_names, model_kinds, model_params, parameter_help,
                     pulse_params)
from .options import (MAX_PLOT_POINTS, BackboneKind, ModelKind, PulseKind, _axis, _check_count, _check_refine, _excitation,
                      _integrator, build_model, figure_path, parse_values, solution_summary, spectrum_summary, SENSITIVITY_HELP,
                      LIST_HELP as _LIST, check_pulse_params, split_params, uncertain_line, with_params)

JSON_OPTION = typer.Option(False, "--json", help="print the summary as one JSON document on stdout instead of text (units in its "
                           "'units'; null: never, or not computed); warnings stay on stderr")
FORCE_OPTION = typer.Option(False, "--force", help="let outputs replace existing files that jaxrock did not write "
                            "(without it such a file is refused; symbolic links always are)")
BACKBONE_DEFAULTS = ", ".join(f"{v} {k}" for k, v in DEFAULT_BACKBONE.items())
SMOOTHING_DEFAULTS = ", ".join(f"{v:g} {k}" for k, v in DEFAULT_SMOOTHING.items())
UNDAMPED_HELP = "no energy loss: " + ", ".join(f"{k} = {v:g}" for k, v in UNDAMPED.items()) + " (whichever the model takes)"

RATIO_UNITS = {"omega_ratio": "1 (omega_p/p')", "accel_ratio": "1 (a_p/(g tan alpha'))"}  # --json: the grid's axes

app = typer.Typer(
    cls=_OneLineErrors,
    add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
    context_settings={"help_option_names": ["-h", "--help"]},
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help texts are shown as written: units "[m]" and ranges "a:b:n" are not markup
    help="Rocking bodies under earthquakes (Vassiliou, Mackie & Stojadinovic 2014), in JAX (float64).",
)



@app.command()
@_guarded
@with_params()
def spectrum(
    model: ModelKind = typer.Option(ModelKind(DEFAULT_MODEL), help=parameter_help("model", valid=False)),
    height: float = typer.Option(10.0, help="full height 2h [m]"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα = b/h, in (0, 1)"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h, in [tanα, 1)"),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles"),
    omega_min: float = typer.Option(1.0, help="smallest ω_p/p"),
    omega_max: float = typer.Option(15.0, help="largest ω_p/p"),
    n_omega: int = typer.Option(48, help="number of ω_p/p values"),
    accel_min: float = typer.Option(0.5, help="smallest a_p/(g tanα)"),
    accel_max: float = typer.Option(10.0, help="largest a_p/(g tanα)"),
    n_accel: int = typer.Option(48, help="number of a_p/(g tanα) values"),
    out: str = typer.Option("out/spectrum", help="output stem: writes <out>.nc (netCDF) and <out>.png; a folder (or a path "
                            "ending in /) means <out>/spectrum.nc and .png"),
    undamped: bool = typer.Option(False, "--undamped", help=UNDAMPED_HELP),
    checkpoint: bool = typer.Option(True, "--checkpoint/--no-checkpoint", help="keep finished batches in the folder <out>.checkpoint; a rerun resumes"),
    batch_size: int = typer.Option(4096, help="largest number of cells per vmapped batch (memory bound); the grid is split into batches "
                                   "of sizes the compiled passes share"),
    refine: int = typer.Option(10, min=0, max=MAX_REFINE, help="bisections of the uplift and overturning lines between grid rows (0: grid lines)"),
    tol: Optional[float] = typer.Option(
        None, help="spring models: run generalized-α at this local tolerance in (0, 0.1), its global error checked by a run at 10x "
        "the tolerance (status inaccurate beyond 1e-2 in θ/α; see README); default: the model's default integrator"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP + "; off by default on pulses "
                                     "(none of 240 seeded pulse cells changed verdict, benchmarks/study_uncertain.py)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a grid estimated beyond 1 h or 2 GB"),
    **params: Optional[float],
):
    """Overturning spectrum: max θ/α over a grid of (ω_p/p, a_p/(g tanα)) (paper figures 6, 9, 11)."""
    from ..io.files import check_output, output_stem

    wr = _axis("omega", omega_min, omega_max, n_omega)
    ar = _axis("accel", accel_min, accel_max, n_accel)
    _check_count("--batch-size", batch_size)
    model_kw, pulse_kw = split_params(params)
    check_pulse_params(pulse.value, pulse_kw)
    m = build_model(model, height, tan_alpha, tan_alpha_base, undamped=undamped, **model_kw)
    integ = _integrator(model, tol)
    out = output_stem(out, "spectrum")
    for suffix in (".nc", ".png"):
        check_output("--out", Path(f"{out}{suffix}"))
    _hold(out, "--out")
    kind = "spring-ga" if (model == ModelKind.spring and tol is not None) else model.value
    _estimate(wr.size * ar.size, kind, yes, per_cell=cell_seconds(kind) * (SENSITIVITY_COST if sensitivity else 1.0))
    ck = Path(f"{out}.checkpoint") if checkpoint else None
    t0 = time.perf_counter()
    from ..analyses.spectra import overturning_spectrum
    from ..interrupt import Interrupted

    try:
        spec = overturning_spectrum(m, wr, ar, pulse=pulse.value, pulse_params=pulse_kw, integrator=integ, batch_size=batch_size, progress=not quiet,
                                    checkpoint=ck, keep_checkpoint=True, refine=refine, sensitivity=sensitivity)
    except Interrupted:
        _interrupted(ck, wr.size * ar.size)
    seconds = time.perf_counter() - t0
    import equinox as eqx

    spec = eqx.tree_at(lambda s: s.attrs, spec, {**spec.attrs, "model_kind": model.value, "undamped": int(undamped),
                                                  "history": _history()})
    from ..reports import spectrum_files

    title = f"{model.value}{' (undamped)' if undamped else ''}, {pulse.value} pulse{''.join(f' {k} = {v:g}' for k, v in pulse_kw.items())}, 2h = {height:g} m, tanα = {tan_alpha:g}"
    nc, png = spectrum_files(spec, out, title)
    if ck is not None and ck.exists():  # kept until the result files are written
        import shutil

        shutil.rmtree(ck)
    say(spectrum_summary(spec, seconds))
    say(f"wrote {nc} and {png}")
    from ..outputs import OUTPUTS, computed

    report("spectrum", {"model": model.value, "pulse": pulse.value, **pulse_kw, "height": height, "tan_alpha": tan_alpha,
                        "tan_alpha_base": tan_alpha_base, "alpha": spec.attrs["alpha"], "p": spec.attrs["p"],
                        "omega_ratio": spec.omega_ratio, "accel_ratio": spec.accel_ratio, "cells": spec.max_theta.size,
                        "overturned": int(spec.overturned.sum()), "uplifted": int(spec.uplifted.sum()),
                        "uncertain": int(spec.uncertain.sum()) if computed(OUTPUTS["uncertain"], {"sensitivity": spec.sensitivity}) else None,
                        "uplift_boundary": spec.uplift_boundary, "overturn_boundary": spec.overturn_boundary,
                        "status": _status_counts(spec.status), "seconds": seconds, "files": [nc, png]},
           {"height": "m", "alpha": "rad", "p": "rad/s", "seconds": "s", **RATIO_UNITS,
            "uplift_boundary": "1 (a_p/(g tan alpha') per omega_ratio; null: none in the grid)", "overturn_boundary": "1 (as uplift_boundary)"})
    _exit_if_untrusted(_status_counts(spec.status), "cell(s)")


def _simulate(model, excitation, save=None, integrator=None, sensitivity: bool = False):
    """`jaxrock.simulate` through a kernel kept between processes (`jaxrock.analyses.kernels`);
    with its sensitivity, compiled in this process (`jaxrock.simulate`)."""
    if sensitivity:
        from ..model import simulate as run

        return run(model, excitation, save=save, integrator=integrator, sensitivity=True)
    from ..analyses import kernels

    return kernels.simulate(model, excitation, save=save, integrator=integrator)


@app.command()
@_guarded
@with_params()
def simulate(
    height: float = typer.Option(10.0, help="full height 2h [m]"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα = b/h, in (0, 1)"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h"),
    model: ModelKind = typer.Option(ModelKind(DEFAULT_MODEL), help=parameter_help("model", valid=False)),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles"),
    a_p: Optional[float] = typer.Option(None, "--a-p", help="pulse amplitude [m/s²] (default: --accel-ratio 4)"),
    accel_ratio: Optional[float] = typer.Option(None, help="pulse amplitude as a_p/(g tanα) (default 4)"),
    omega_p: Optional[float] = typer.Option(None, help="pulse frequency [rad/s] (default 2π)"),
    omega_ratio: Optional[float] = typer.Option(None, help="pulse frequency as ω_p/p"),
    record: Optional[str] = typer.Option(None, help=f"a record file (.AT2 or two-column) or a packaged record ({builtin_record_names()}), instead of a pulse"),
    scale: float = typer.Option(1.0, help="factor on the record"),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    undamped: bool = typer.Option(False, "--undamped", help=UNDAMPED_HELP),
    backbone: Optional[BackboneKind] = typer.Option(None, help=f"spring: base-spring backbone (default {BACKBONE_DEFAULTS}; the bilinear "
                                                    "at θy = 1e-5 α′ is within 1e-3 of the sharp limit, README)"),
    smoothing: Optional[float] = typer.Option(None, help=f"spring: pre-yield rotation θs/α′ in (0, 1) (default {SMOOTHING_DEFAULTS})"),
    tol: Optional[float] = typer.Option(None, help="spring models: run generalized-α at this local tolerance in (0, 1); default: the model's default integrator"),
    plot: Optional[str] = typer.Option(None, help="write a time-history plot here (PNG; another suffix matplotlib knows, e.g. .pdf, "
                                       "picks that format)"),
    save_path: Optional[str] = typer.Option(None, "--save", help="write the time history here: time, ground acceleration and every "
                                            "field the model gives, with the summary (.nc: netCDF, CF-1.8; .csv)"),
    t_free: Optional[float] = typer.Option(None, help="plot and history: free-rocking time after the excitation [s] (default 2 × 2π/p)"),
    n_points: Optional[int] = typer.Option(None, help=f"plot and history: number of saved time points, 2 to {MAX_PLOT_POINTS:,} (default 1500)"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    **params: Optional[float],
):
    """One scene: prints max θ/α, overturning, uplift, impacts and the run status; --plot draws
    and --save writes its time history."""
    model_kw, pulse_kw = split_params(params)
    m = build_model(model, height, tan_alpha, tan_alpha_base, undamped=undamped, backbone=backbone, smoothing=smoothing, **model_kw)
    exc, desc = _excitation(m.block, pulse.value, record, scale, a_p, accel_ratio, omega_p, omega_ratio, units, pulse_kw)
    integ = _integrator(model, tol)
    if plot is None and save_path is None:
        from .._validate import JaxrockInputError

        for flag, v in (("--t-free", t_free), ("--n-points", n_points)):
            if v is not None:
                raise JaxrockInputError(f"{flag} applies to the time history: give --plot FILE.png or --save FILE.nc as well")
    else:
        from .._validate import JaxrockInputError, check_positive
        from ..io.history_file import check_history_path

        plot = None if plot is None else figure_path("--plot", plot)
        save_path = None if save_path is None else check_history_path("--save", save_path)
        n_points = 1500 if n_points is None else n_points
        if not 2 <= n_points <= MAX_PLOT_POINTS:
            raise JaxrockInputError(f"--n-points = {n_points}; valid: an integer in [2, {MAX_PLOT_POINTS:,}] (a figure shows a few thousand)")
        if t_free is not None:
            check_positive("--t-free", t_free)
    import jax

    t0 = time.perf_counter()
    sol = jax.block_until_ready(_simulate(m, exc, integrator=integ, sensitivity=sensitivity))  # JAX returns before it has computed
    seconds = time.perf_counter() - t0
    say(f"{model.value} model, 2h = {height:g} m, tanα = {tan_alpha:g}; {desc}")
    say(solution_summary(sol, m))
    say(f"run time {seconds:.2f} s (with compilation)")
    from ..interrupt import stop_point

    stop_point()
    written = []
    if plot is not None or save_path is not None:
        p = float(m.block.p_r)
        tf = 2 * 2 * math.pi / p if t_free is None else t_free
        t_start, t_end = float(exc.t_start), float(exc.t_end)
        if record is None:  # the pulse window is generous (|üg| < 1e-13 a_p): show its core, |ω_p t| <= 8
            w = float(exc.omega_p)
            t_start, t_end = max(t_start, -8.0 / w), min(t_end, 8.0 / w)
        ts = np.linspace(t_start, t_end + tf, n_points)
        from ..plotting import plot_history
        from ..results import Save

        hist = _simulate(m, exc, save=Save(ts, m.history_fields if save_path is not None else ("theta",)), integrator=integ)
        title = f"{model.value}, 2h = {height:g} m, tanα = {tan_alpha:g}; {desc}"
        if plot is not None:
            import matplotlib.pyplot as plt

            plt.close(plot_history(hist, exc, model=m, path=plot, title=title.replace("; ", "\n")))
            written.append(plot)
        if save_path is not None:
            import jax

            from ..io.history_file import save_history
            from ..io.provenance import file_attrs

            attrs = {"model_kind": model.value, "excitation": desc, "height": height, "tan_alpha": tan_alpha,
                     **({} if tan_alpha_base is None else {"tan_alpha_base": tan_alpha_base}), **file_attrs(m, integ),
                     "history": _history()}
            written.append(save_history(hist, jax.vmap(exc)(hist.ts), save_path, attrs, f"jaxrock time history: {title}"))
        say(f"wrote {', '.join(str(w) for w in written)}")
    from ..outputs import OUTPUTS
    from ..results import status_codes, status_names

    report("simulate", {"model": model.value, "excitation": desc, "height": height, "tan_alpha": tan_alpha,
                        "tan_alpha_base": tan_alpha_base, "alpha": float(m.block.alpha_r), "p": float(m.block.p_r),
                        **{k: np.asarray(getattr(sol, k)) for k in OUTPUTS}, "status": str(status_names(sol.status)),
                        "seconds": seconds, "files": written},
           {"height": "m", "alpha": "rad", "p": "rad/s", "seconds": "s", **{k: o.units for k, o in OUTPUTS.items()}})
    _exit_if_untrusted(_status_counts(status_codes(sol.status)), "run")


# ----------------------------------------------------------------------------------------------
# batch
# ----------------------------------------------------------------------------------------------
@app.command(help=(
    "Run a CSV of scenes (vmapped, grouped by structure) and write a results CSV.\n\n"
    f"Columns: height, tan_alpha | width, [tan_alpha_base], [model: {' | '.join(model_kinds())}], "
    f"[pulse: {' | '.join(PULSES)} | {RECORD_ALIASES[0]} | FILE], a_p | accel_ratio, omega_p | omega_ratio, [scale], "
    f"{', '.join(f'[{k}]' for k in (*model_params(), *pulse_params()))}. Results: the inputs plus {', '.join(RESULT_COLUMNS)}."))
@_guarded
def batch(
    scenes: Path = typer.Argument(..., help="scenes CSV (one scene per row; see `jaxrock.io.scenes_file`)"),
    results: str = typer.Argument(..., help="results CSV to write (a folder, or a path ending in /: <folder>/<scenes stem>_results.csv)"),
    resume: bool = typer.Option(False, "--resume", help="skip rows already in the results file"),
    chunk_size: int = typer.Option(256, help="rows per vmapped batch"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    force: bool = FORCE_OPTION,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
):
    from .._validate import check_writable
    from ..io.results_file import count_results, results_path_for

    results = results_path_for(scenes, results)
    check_writable("results", results)
    from ..analyses.scenes import run_scenes
    from ..interrupt import Interrupted

    try:
        rep = run_scenes(scenes, results, resume=resume, chunk_size=chunk_size, progress=not quiet, force=force, sensitivity=sensitivity)
    except Interrupted:
        typer.echo(f"interrupted: {count_results(results):,} rows kept in {results}; resume with: {_resume_command('--resume')}",
                   err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    say(
        f"{rep.n_rows} rows: {rep.n_run} run in {rep.n_groups} group(s), {rep.n_skipped} skipped (already done); "
        f"{rep.seconds:.1f} s"
    )
    say("; ".join(f"{OUTPUTS[k].label}: {v}" for k, v in rep.flag_counts.items()) + "; status: "
               + ", ".join(f"{k} {v}" for k, v in rep.status_counts.items()))
    say(f"wrote {rep.path}")
    report("batch", {"rows": rep.n_rows, "run": rep.n_run, "groups": rep.n_groups, "skipped": rep.n_skipped, **rep.flag_counts,
                     "status": rep.status_counts, "seconds": rep.seconds, "files": [rep.path]}, {"seconds": "s"})
    _exit_if_untrusted(rep.status_counts, "row(s)")


# ----------------------------------------------------------------------------------------------
# record spectrum
# ----------------------------------------------------------------------------------------------
@app.command("record-spectrum")
@_guarded
def record_spectrum(
    record: str = typer.Option(RECORD_ALIASES[0], help=f"record file (.AT2 or two-column text), or a packaged record ({builtin_record_names()})"),
    model: ModelKind = typer.Option(ModelKind(DEFAULT_MODEL), help=parameter_help("model", valid=False)),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′"),
    heights: str = typer.Option("1,2,3,5,7,10,15,20", help="body heights 2h [m]: '1,2,5' or 'a:b:n'"),
    scales: str = typer.Option(
        "0.5:12:16",
        help="record factors of the vmapped sweep ('1,2,5' or 'a:b:n'); the first that overturns is then refined by "
        "bisection. A coarse sweep is cheap (a vmapped record run costs about as much per lane as a bisection step) "
        "but can miss a narrow overturning window between two factors",
    ),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    refine: int = typer.Option(8, help="bisections refining the least overturning factor (resolution: sweep step / 2^refine)"),
    tol: Optional[float] = typer.Option(None, help="spring models: generalized-α at this local tolerance (default: the model's default integrator)"),
    out: str = typer.Option("out/record_spectrum", help="output stem: <out>.nc, <out>.csv, <out>.png; a folder (or a path "
                            "ending in /) means <out>/record_spectrum.*"),
    sensitivity: bool = typer.Option(True, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a sweep estimated beyond 1 h"),
):
    """Least scale factor of a record that overturns the body, per height (paper figure 10)."""
    from .._validate import JaxrockInputError
    from ..io.files import check_output, output_stem

    hs = parse_values("--heights", heights)
    sc = parse_values("--scales", scales)
    _check_refine(refine)
    m = build_model(model, float(hs[0]), tan_alpha, tan_alpha_base)
    integ = _integrator(model, tol)
    exc, desc = _excitation(m.block, DEFAULT_PULSE, record, 1.0, None, None, None, None, units)
    out = output_stem(out, "record_spectrum")
    for suffix in (".nc", ".csv", ".png"):
        check_output("--out", Path(f"{out}{suffix}"))
    _hold(out, "--out")
    per_run = record_run_seconds(model.value, float(exc.t_end - exc.t_start)) * (SENSITIVITY_COST if sensitivity else 1.0)
    _estimate(hs.size * (sc.size + refine), model.value, yes, what="record runs", per_cell=per_run)
    from ..analyses.spectra import record_overturning_scale
    from ..reports import record_spectrum_files

    t0 = time.perf_counter()
    rs = record_overturning_scale(m, exc, hs, sc, refine=refine, integrator=integ, progress=not quiet, sensitivity=sensitivity)
    seconds = time.perf_counter() - t0
    import equinox as eqx

    rs = eqx.tree_at(lambda r: r.attrs, rs, {**rs.attrs, "model_kind": model.value, "history": _history()})
    nc, csv_path, png = record_spectrum_files(rs, out, f"{model.value}, tanα = {tan_alpha:g}", f"least overturning factor of {desc}")
    say(f"{desc}; {model.value} model, tanα = {tan_alpha:g}; {len(hs)} heights × {len(sc)} factors in {seconds:.1f} s")
    say(f"{'2h [m]':>8} {'least factor':>13}")
    doubt = np.zeros(rs.height.size, bool) if rs.uncertain is None else np.asarray(rs.uncertain, bool)
    from ..results import STATUS_NAMES

    for h, s, u, w in zip(rs.height, rs.scale, doubt, rs.worst_status):
        say(f"{h:8.3g} {('> %g' % sc[-1]) if not np.isfinite(s) else ('%.4g' % s):>13}{'  (uncertain)' if u else ''}"
                   f"{f'  (a run {STATUS_NAMES[int(w)]})' if w else ''}")
    say(uncertain_line(rs.uncertain, what="least factor(s)"))
    say(f"wrote {nc}, {csv_path}, {png}")
    report("record-spectrum", {"record": desc, "model": model.value, "tan_alpha": tan_alpha, "tan_alpha_base": tan_alpha_base,
                               "scale": sc, "height": rs.height, "least_scale": rs.scale, "bracket_low": rs.bracket_low,
                               "uncertain": rs.uncertain, "worst_status": [STATUS_NAMES[int(w)] for w in rs.worst_status],
                               "seconds": seconds, "files": [nc, csv_path, png]},
           {"height": "m", "seconds": "s", "least_scale": "1 (factor on the record; null: none of the sweep overturns)"})
    _exit_if_untrusted(_status_counts(rs.worst_status), "height(s)")


# ----------------------------------------------------------------------------------------------
# sweep
# ----------------------------------------------------------------------------------------------
@app.command()
@_guarded
@with_params(lists=True)
def sweep(
    model: ModelKind = typer.Option(ModelKind(DEFAULT_MODEL), help=parameter_help("model", valid=False)),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles (pulse sweeps)"),
    accel_ratio: Optional[str] = typer.Option(None, help=f"a_p/(g tanα′): {_LIST} (pulse sweeps; default 0.5:10:48)"),
    omega_ratio: Optional[str] = typer.Option(None, help=f"ω_p/p′: {_LIST} (pulse sweeps; default 1:15:48)"),
    records: Optional[str] = typer.Option(None, help="a record sweep instead of pulses: record files, folders of records (.AT2, "
                                          f".txt, .dat, .csv), packaged records ({builtin_record_names()}) or '{BUILTIN_SUITE}' (all of them), separated by commas"),
    units: Optional[str] = typer.Option(None, help="acceleration units of two-column record files (default g)"),
    scale: Optional[str] = typer.Option(None, help=f"record factor: {_LIST} (record sweeps; default 1)"),
    height: str = typer.Option("10", help=f"full height 2h [m]: {_LIST}"),
    tan_alpha: str = typer.Option("0.2", help=f"slenderness tanα: {_LIST}"),
    tan_alpha_base: Optional[str] = typer.Option(None, help=f"extended base tanα′ ≥ tanα: {_LIST}"),
    smoothing: Optional[str] = typer.Option(None, help=f"spring: pre-yield rotation θs/α′ in (0, 1): {_LIST}"),
    backbone: Optional[BackboneKind] = typer.Option(None, help=f"spring: base-spring backbone (default {BACKBONE_DEFAULTS})"),
    tol: Optional[float] = typer.Option(None, help="spring models: generalized-α at this local tolerance (default: the model's default integrator)"),
    store: Path = typer.Option(Path("out/sweep.zarr"), help="the Zarr store (xarray.open_zarr reads it); a rerun of the same "
                               "command resumes it, one with other parameters is refused"),
    chunk_size: int = typer.Option(1024, help="most scenes per chunk: one vmapped batch, one Zarr chunk, one Dask task (1024: the fastest of 256, 1024, 4096 on the rigid model, benchmarks/bench_sweep.py)"),
    devices: Optional[int] = typer.Option(None, help="run chunks on this many local devices, one chunk per device at a time "
                                          "(default: all; on a CPU, one device per core)"),
    scheduler: Optional[str] = typer.Option(None, help="address of a running Dask scheduler (tcp://host:8786): each chunk is a "
                                            "task of its workers, which write into --store (a folder they all see); needs "
                                            "jaxrock[distributed]"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a sweep estimated beyond 1 h or 2 GB"),
    **params: Optional[str],
):
    """Every scene of a product of axes (pulses or records × sizes × slendernesses × model
    parameters) into a chunked Zarr store: resumable, a chunk per local device at a time, or spread
    over a Dask cluster."""
    from .._validate import JaxrockInputError, check_writable
    from ..scene import sweep_quantities, takes

    _check_count("--chunk-size", chunk_size)
    if devices is not None:
        _check_count("--devices", devices)
    lists = {"height": height, "tan_alpha": tan_alpha, "tan_alpha_base": tan_alpha_base, **params, "smoothing": smoothing,
             "accel_ratio": accel_ratio, "omega_ratio": omega_ratio, "scale": scale}
    given = {}
    for name, text in lists.items():
        if text is None:
            continue
        flag = "--" + name.replace("_", "-")
        if (name in model_params() or name == "smoothing") and model.value not in takes(name):
            raise JaxrockInputError(f"{flag} applies to --model {' / '.join(takes(name))} only, not {model.value}")
        if name in pulse_params():
            check_pulse_params(pulse.value, {name: text}, records is not None)
        v = parse_values(flag, text)
        given[name] = float(v[0]) if v.size == 1 else v
    if records is None:
        if scale is not None:
            raise JaxrockInputError("--scale applies to record sweeps (--records), not to pulses")
        given.setdefault("accel_ratio", np.linspace(0.5, 10.0, 48))
        given.setdefault("omega_ratio", np.linspace(1.0, 15.0, 48))
        recs = None
    else:
        for name in ("accel_ratio", "omega_ratio"):
            if name in given:
                raise JaxrockInputError(f"--{name.replace('_', '-')} applies to pulse sweeps, not to --records")
        from ..io.records import read_records

        recs = read_records([r for r in records.split(",") if r.strip()], units=units)
    if scheduler is not None and devices is not None:
        raise JaxrockInputError("--devices applies to this process; with --scheduler each worker uses its own devices")
    devs = None if scheduler is not None else _local_devices(devices)
    if store.name in ("", ".", ".."):
        raise JaxrockInputError(f"--store {str(store)!r}: names the current or a parent folder, not a store; "
                                "give a folder of its own, e.g. --store out/sweep.zarr")
    if store.exists() and not store.is_dir():
        raise JaxrockInputError(f"--store {store}: is a file; expected a Zarr store folder (new or made by this sweep)")
    check_writable("--store", store.with_name(store.name + ".lock"))
    from ..analyses.sweep import Sweep

    sw = Sweep.make(model.value, pulse=None if recs else pulse.value, records=recs, integrator=_integrator(model, tol),
                    backbone=None if backbone is None else backbone.value, chunk_size=chunk_size, sensitivity=sensitivity, **given)
    dearer = SENSITIVITY_COST if sensitivity else 1.0
    if recs:
        seconds = max(float(r.t_end - r.t_start) for r in recs)
        per_run = record_run_seconds(model.value, seconds) * dearer
        _estimate(sw.size, model.value, yes, what="record runs", per_cell=per_run)
    else:
        kind = "spring-ga" if (model == ModelKind.spring and tol is not None) else model.value
        _estimate(sw.size, kind, yes, what="scenes", per_cell=cell_seconds(kind) * dearer)
    client = None
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:
            raise JaxrockInputError("--scheduler needs Dask's distributed: pip install 'jaxrock[distributed]'") from None
        _probe_scheduler(scheduler)
        try:
            client = guards._held.enter_context(Client(scheduler, timeout="10s", set_as_default=False))  # dask.compute elsewhere stays local
        except Exception as e:  # refused, timed out, or not an address: one answer
            raise JaxrockInputError(f"--scheduler {scheduler}: no Dask scheduler answers there within 10 s "
                                    f"({type(e).__name__}: {e}); expected a running scheduler's address, tcp://HOST:PORT") from None
    from ..analyses.sweep import run_sweep
    from ..interrupt import Interrupted
    from ..io import store as zstore

    ran = 0

    def count(k):  # the scenes this run ran (a resumed store's damaged chunks included)
        nonlocal ran
        ran += sw.chunk_scenes(k)

    t0 = time.perf_counter()
    try:
        ds = run_sweep(sw, store, client=client, devices=devs, progress=not quiet,
                       history=_history(), on_chunk=count)
    except Interrupted:
        kept = len(zstore.flagged(store, sw)) if store.exists() else 0
        typer.echo(f"interrupted: {kept} of {sw.n_chunks} chunks kept in {store}; resume with: {_resume_command()}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    seconds = time.perf_counter() - t0
    dims = " × ".join(f"{len(v)} {k}" for k, v in sw.axes.items())
    where = f"Dask cluster {scheduler}" if scheduler else f"{len(devs)} device(s)"
    before = sw.size - ran
    resumed = f" ({before:,} were in the store already)" if before else ""
    say(f"sweep: {sw.model} model, {dims} = {sw.size:,} scenes in {sw.n_chunks} chunk(s) of ≤ {math.prod(sw.chunk_shape):,}; "
               f"{ran:,} run in {seconds:.1f} s ({ran / seconds:,.0f} scenes/s with compilation) on {where}{resumed}")
    say(f"overturned: {int(ds.overturned.sum()):,} scenes ({100 * float(ds.overturned.mean()):.1f} %); uplifted: "
               f"{int(ds.uplifted.sum()):,}")
    say(uncertain_line(ds.uncertain.values if sensitivity else None, what="scenes"))
    say(f"wrote {store}")
    report("sweep", {"model": sw.model, "axes": {k: np.asarray(v) if k != "record" else list(v) for k, v in sw.axes.items()},
                     "scenes": sw.size, "chunks": sw.n_chunks, "run": ran, "overturned": int(ds.overturned.sum()),
                     "uplifted": int(ds.uplifted.sum()), "uncertain": int(ds.uncertain.sum()) if sensitivity else None,
                     "status": _status_counts(ds.status.values), "seconds": seconds, "files": [store]},
           {"seconds": "s", **{k: u for k, (_, u, _) in sweep_quantities(sw.model if isinstance(sw.model, str) else None).items()
                               if k in sw.axes and u}})
    _exit_if_untrusted(_status_counts(ds.status.values), "scene(s)")


_SCHEDULER = re.compile(r"^(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.-]+):(\d{1,5})$")


def _probe_scheduler(address: str) -> None:
    """`--scheduler`: an address (PROTOCOL://HOST:PORT or HOST:PORT) where something accepts a
    TCP connection within 10 s, checked before a Dask client is made (a client that cannot connect
    hangs in its own cleanup and prints tracebacks after the answer)."""
    import socket

    from .._validate import JaxrockInputError

    m = _SCHEDULER.match(address.strip())
    if m is None or not 0 < int(m.group(3)) < 65536:
        raise JaxrockInputError(f"--scheduler {address!r}: not a scheduler address; expected tcp://HOST:PORT (or HOST:PORT; "
                                "tls://, ws://, ucx:// also), as `dask scheduler` prints it")
    host, port = m.group(2).strip("[]"), int(m.group(3))
    try:
        socket.create_connection((host, port), timeout=10).close()
    except OSError as e:
        raise JaxrockInputError(f"--scheduler {address}: no Dask scheduler answers there within 10 s ({e.strerror or e}); "
                                "expected a running scheduler's address, tcp://HOST:PORT") from None


@app.command()
@_guarded
def suite(
    records: Optional[list[str]] = typer.Argument(None, help="record files, folders of records (.AT2, .txt, .dat, .csv), list files (.list: one per line) and "
                                                  f"packaged records ({builtin_record_names()}) or '{BUILTIN_SUITE}' (all five); default: '{RECORD_ALIASES[1]}'"),
    model: str = typer.Option("rigid,spring,spring-flexible", help=f"model kinds, comma-separated ({', '.join(model_kinds())}): "
                              "each runs the same suite"),
    height: str = typer.Option("1,2,4,8", help=f"full height 2h [m]: {_LIST}"),
    tan_alpha: str = typer.Option("0.2", help=f"slenderness tanα: {_LIST}"),
    scale: str = typer.Option("0.25:4:16", help="record factors of the sweep ('1,2,5' or 'a:b:n'): the fragility's observations, "
                              "and the brackets the least overturning factor is bisected in"),
    refine: int = typer.Option(5, help="bisections of each least overturning factor (resolution: the sweep's step / 2^refine)"),
    im: str = typer.Option("pga", help="intensity measure of the fragility: pga [m/s2], pgv [m/s], pgd [m], arias [m/s], or scale"),
    boot: int = typer.Option(500, help="bootstrap resamplings of the records (the fragility's band)"),
    units: Optional[str] = typer.Option(None, help="acceleration units of two-column record files (default g)"),
    out: Path = typer.Option(Path("out/suite"), help="output folder: suite.zarr, least_scale.csv/.png, fragility.csv/.md/.png, "
                             "and each model's sweep store <model>.zarr (a rerun resumes it)"),
    sensitivity: bool = typer.Option(True, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    ensemble: int = typer.Option(0, help=f"replace each uncertain verdict by the fraction of this many runs at its factor x (1 ± 1e-7) "
                                 f"that overturn, and fit the fragility on those fractions (0 to {MAX_ENSEMBLE}; 0: the verdicts)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a suite estimated beyond 1 h"),
):
    """A record suite: each record's intensity measures, its least overturning scale factor for each
    column (figure 10 for a suite: median and 16-84 % band) and the fragility of each column
    (lognormal by maximum likelihood, bootstrap band), for each model."""
    from .._validate import JaxrockInputError, check_grid, check_writable
    from ..analyses.suite import _check_im, check_motion

    kinds = [k.strip() for k in model.split(",") if k.strip()]
    bad = [k for k in kinds if k not in model_kinds()]
    if not kinds or bad or len(set(kinds)) < len(kinds):
        what = ", ".join(bad) or ("no model" if not kinds else "a model named twice")
        raise JaxrockInputError(f"--model {model!r}: {what}; valid: comma-separated, each once, of {', '.join(model_kinds())}")
    _check_refine(refine)
    _check_count("--boot", boot)
    _check_im(im)
    if not 0 <= ensemble <= MAX_ENSEMBLE:
        raise JaxrockInputError(f"--ensemble = {ensemble}; valid: an integer in [0, {MAX_ENSEMBLE}] (0: the verdicts as they are)")
    if ensemble and not sensitivity:
        raise JaxrockInputError("--ensemble replaces the uncertain verdicts, which only --sensitivity finds: drop --no-sensitivity")
    given = {}
    for name, text in (("height", height), ("tan_alpha", tan_alpha)):
        v = parse_values("--" + name.replace("_", "-"), text)
        given[name] = float(v[0]) if v.size == 1 else v
    sc = parse_values("--scale", scale)
    if sc.size < 2:
        raise JaxrockInputError(f"--scale {scale!r}: one factor; give at least 2 (the sweep whose outcomes are fitted)")
    check_grid("--scale", sc)  # the least overturning factor is the first of them that overturns
    check_writable("--out", out / "fragility.csv")
    _hold(out, "--out")
    from ..io.records import read_records
    from ..analyses.sweep import Sweep

    for src in records or ():
        if Path(src).is_dir() and os.path.realpath(src) == os.path.realpath(out):
            raise JaxrockInputError(f"--out {out}: is the records folder {src}; the suite's CSV outputs would be read as records "
                                    "on a rerun: choose another --out")
    recs = read_records(records or [RECORD_ALIASES[1]], units=units)
    check_motion(recs)
    seconds = max(float(r.t_end - r.t_start) for r in recs)
    runs = cost = 0.0
    for k in kinds:
        sw = Sweep.make(k, records=recs, scale=sc, **given)  # every value checked before anything runs
        n = sw.size + refine * sw.size // sc.size
        runs, cost = runs + n, cost + n * record_run_seconds(k, seconds) * (SENSITIVITY_COST if sensitivity else 1.0)
    _estimate(int(runs), kinds[0], yes, what=f"record runs ({', '.join(kinds)})", per_cell=cost / runs)
    from ..analyses.suite import run_suite
    from ..geometry import G
    from ..interrupt import Interrupted
    from ..io import store as zstore
    from ..reports import suite_files

    t0 = time.perf_counter()
    try:
        ds = run_suite(kinds, recs, scale=sc, refine=refine, im=im, n_boot=boot, store_dir=out, progress=not quiet,
                       history=_history(), sensitivity=sensitivity, ensemble=ensemble, **given)
    except Interrupted:
        kept = ", ".join(f"{out / f'{k}.zarr'} ({zstore.kept_scenes(out / f'{k}.zarr'):,} runs)" for k in kinds if (out / f"{k}.zarr").is_dir())
        typer.echo(f"interrupted: the sweeps kept in {kept or 'no store yet'}; resume with: {_resume_command()}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    secs = time.perf_counter() - t0
    files = suite_files(ds, out, f"{len(recs)} records")
    say(f"suite: {len(recs)} records × {len(kinds)} model(s) × {ds.sizes['scale']} factors"
               + "".join(f" × {len(v)} {k}" for k, v in given.items() if np.ndim(v)) + f" in {secs:.1f} s")
    say(f"{'record':<24}{'PGA [g]':>9}{'PGV [m/s]':>11}{'D5-95 [s]':>11}")
    for r in range(ds.sizes["record"]):
        one = ds.isel(record=r)
        say(f"{str(one.record.values)[:23]:<24}{float(one.pga) / G:9.3f}{float(one.pgv):11.3f}{float(one.d5_95):11.2f}")
    say(Path(files["table"]).read_text(encoding="utf-8").split("\n\n")[1])
    say(uncertain_line(ds.least_scale_uncertain.values if sensitivity else None, ds.uncertain.values, "least factor(s)",
                              ds.least_scale.size))
    say("wrote " + ", ".join(str(p) for p in files.values()))
    import csv

    def number(text):  # a fragility CSV cell: a number, else its text
        try:
            return float(text)
        except ValueError:
            return text

    with open(files["fragility"], encoding="utf-8") as fh:
        fragility = [{k: number(v) for k, v in row.items()} for row in csv.DictReader(fh)]
    report("suite", {"models": kinds, "records": [{"record": str(ds.record.values[r]), "pga": float(ds.pga[r]), "pgv": float(ds.pgv[r]),
                                                    "d5_95": float(ds.d5_95[r])} for r in range(ds.sizes["record"])],
                     "fragility": fragility,
                     "status": _status_counts(ds.worst_status.values), "seconds": secs, "files": list(files.values())},
           {"pga": "m/s2", "pgv": "m/s", "d5_95": "s", "seconds": "s"})
    _exit_if_untrusted(_status_counts(ds.worst_status.values), "column(s) × record(s)")


def _local_devices(n: Optional[int]):
    import jax

    devs = jax.local_devices()
    if n is not None and n > len(devs):
        from .._validate import JaxrockInputError

        raise JaxrockInputError(f"--devices = {n}; valid: 1 to {len(devs)} (this host's devices)")
    return devs if n is None else devs[:n]


# ----------------------------------------------------------------------------------------------
# calibrate
# ----------------------------------------------------------------------------------------------
@app.command()
@_guarded
def calibrate(
    out: Path = typer.Option(Path("out/calibration"), help="output folder (calibration.csv and the figures)"),
    tan_alphas: Optional[str] = typer.Option(None, help="slenderness values to calibrate at ('0.1,0.2,0.3' or 'a:b:n'; default 0.05:0.35:13)"),
    max_iter: int = typer.Option(300, help="optimiser iterations at most"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """Calibrate the spring model's damper c̄ against the rigid model's η⁴ (paper eq. 17, figure 7)."""
    # Thin wrapper over jaxrock.reports.calibration_report.
    from .._validate import JaxrockInputError, check_writable

    _check_count("--max-iter", max_iter)
    check_writable("--out", out / "calibration.csv")
    _hold(out, "--out")
    ta = None
    if tan_alphas is not None:
        ta = parse_values("--tan-alphas", tan_alphas)
        TAN_ALPHA.check(ta, "--tan-alphas")
        if np.unique(ta).size < 3:
            raise JaxrockInputError(f"--tan-alphas = {tan_alphas!r}: {np.unique(ta).size} distinct value(s); "
                                    "the power-law fit c̄ = k (α/0.1)^n needs at least 3")
    from ..reports import calibration_report

    t0 = time.perf_counter()
    rep = calibration_report(out, tan_alphas=ta, progress=not quiet, max_iter=max_iter)
    say(rep.format_table())
    seconds = time.perf_counter() - t0
    say(f"{seconds:.1f} s; wrote " + ", ".join(str(p) for p in rep.files.values()))
    report("calibrate", {"table": rep.table, "seconds": seconds, "files": list(rep.files.values())}, {"seconds": "s"})
    stuck = [f"{r['tan_alpha']:g}" for r in rep.table if not r["converged"]]
    if stuck:
        typer.echo(f"Warning: c̄ did not converge in --max-iter {max_iter} iterations at tanα = {', '.join(stuck)} "
                   f"({len(stuck)} of {len(rep.table)}): raise --max-iter", err=True)
        raise typer.Exit(EXIT_UNTRUSTED)


def _steps() -> tuple[str, ...]:
    from ..paper.reproduce import STEP_NAMES

    return STEP_NAMES


def _in_folder(out: Path, first_file: str, parts: str, kept: str, run):
    """The frame of the commands that fill a folder and resume (reproduce, stability,
    work-precision): `--out` checked writable and held, then `run()`; a signal exits 130 naming
    where the finished `parts` are kept (`out/kept`) and the command that resumes."""
    from .._validate import check_writable
    from ..interrupt import Interrupted

    check_writable("--out", out / first_file)
    _hold(out, "--out")
    try:
        return run()
    except Interrupted:
        typer.echo(f"interrupted: the finished {parts} are kept in {out / kept}; resume with: {_resume_command()}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None


@app.command()
@_guarded
def reproduce(
    quick: bool = typer.Option(False, "--quick", help="coarse grids and fewer variants (about 1.5 against 4 min on 2 cores with a warm compilation cache)"),
    out: Path = typer.Option(Path("out/reproduce"), help="output folder: report.md (verdicts and figures), findings.csv, every "
                             "figure and its data; findings/ keeps each finished step (a rerun resumes)"),
    only: Optional[str] = typer.Option(None, help="comma-separated steps to run (default all): " + ", ".join(_steps())),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """Reproduce the paper: every figure (3-17) into one folder and a report that sets each value the
    paper reports beside jaxrock's, with the difference and a verdict (reproduced / differs,
    explained / not reproduced) and the computed reason where it differs."""
    from .._validate import JaxrockInputError

    names = None
    if only is not None:
        names = [n.strip() for n in only.split(",") if n.strip()]
        bad = [n for n in names if n not in _steps()]
        if not names or bad:
            raise JaxrockInputError(f"--only {only!r}: {', '.join(bad) or 'no step'}; valid: comma-separated {', '.join(_steps())}")
    from ..paper.reproduce import reproduce as run

    rep = _in_folder(out, "report.md", "steps", "findings", lambda: run(out, quick=quick, only=names, progress=not quiet))
    counts = rep.counts()
    say(f"{sum(counts.values())} values of the paper in {sum(rep.seconds.values()):.0f} s of computation: "
               + ", ".join(f"{n} {v}" for v, n in counts.items()))
    say("wrote " + ", ".join(str(p) for p in rep.files.values()))
    report("reproduce", {"verdicts": counts, "seconds": sum(rep.seconds.values()), "files": list(rep.files.values())}, {"seconds": "s"})


@app.command()
@_guarded
def stability(
    quick: bool = typer.Option(False, "--quick", help="the quick matrix: fewer cases, flexible columns of 4 elements (about 1 min)"),
    out: Path = typer.Option(Path("out/stability"), help="output folder: stability.md, stability.csv, stability.png; "
                             "stability_cases/ keeps each finished case (a rerun resumes)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """The defaults of the three models (rigid, quasi-rigid SM, flexible SM) on stiff and extreme
    scenes, each against a refined reference: finite or not, status, error, stated accuracy, run
    time, verdict (holds / flagged / ok but off / not finite). Exit 1 where a status lies (ok but
    off) or a summary is not finite."""
    from ..numerics.stability import HOLDS, NOT_FINITE, OFF, VERDICTS
    from ..numerics.stability import stability as run

    rows = _in_folder(out, "stability.md", "cases", "stability_cases", lambda: run(out, quick=quick, progress=not quiet))
    counts = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
    say(f"{len(rows)} runs: " + ", ".join(f"{n} {v}" for v, n in counts.items()))
    for r in rows:
        if r["verdict"] != HOLDS:
            say(f"  {r['case']} | {r['model']}: {r['verdict']} ({r['status']}, error {r['error']:.1e}, accuracy {r['accuracy']:.0e})")
    say(f"wrote {out / 'stability.md'}, {out / 'stability.csv'}, {out / 'stability.png'}")
    report("stability", {"verdicts": counts, "runs": rows, "files": [out / "stability.md", out / "stability.csv", out / "stability.png"]})
    if counts[OFF] or counts[NOT_FINITE]:
        raise typer.Exit(EXIT_UNTRUSTED)


@app.command("work-precision")
@_guarded
def work_precision(
    quick: bool = typer.Option(False, "--quick", help="fewer settings and smaller grids (about 3 min on 2 cores)"),
    out: Path = typer.Option(Path("out/work-precision"), help="output folder: work_precision.png (the diagrams), .md (tables, the "
                             "defaults against the peers), .csv (every point); work_precision_panels/ keeps each finished panel"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """Error against run time for the RM (diffrax solvers over rtol, float32, the SciPy event loop)
    and the SM (Tsit5 and generalized-α over the tolerance, Checked, the spring's smoothing and
    backbone, the number of elements, OpenSeesPy when the `opensees` extra is installed), per scene
    and per vmapped grid, against converged references, the defaults marked."""
    from ..numerics.work_precision import defaults_table
    from ..numerics.work_precision import work_precision as run

    rows = _in_folder(out, "work_precision.md", "panels", "work_precision_panels", lambda: run(out, quick=quick, progress=not quiet))
    say(f"{len(rows)} points; the defaults against the peers:")
    for line in defaults_table(rows):
        say(line)
    say(f"wrote {out / 'work_precision.png'}, {out / 'work_precision.md'}, {out / 'work_precision.csv'}")
    report("work-precision", {"points": rows, "files": [out / "work_precision.png", out / "work_precision.md", out / "work_precision.csv"]})


def main():  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    app()
