"""`jaxrock simulate`: one scene's summary, its time-history plot and file."""

from __future__ import annotations

import math
import time
from typing import Optional

import numpy as np
import typer

from .guards import report, say, _exit_if_untrusted, _guarded, _history, _status_counts
from ..scene import DEFAULT_MODEL, DEFAULT_PULSE, builtin_record_names
from .options import (model_option, MAX_PLOT_POINTS, BackboneKind, ModelKind, PulseKind, _excitation, _integrator, build_model, figure_path,
                      solution_summary, SENSITIVITY_HELP, split_params, with_params)
from .app import TOL_HELP, app, BACKBONE_DEFAULTS, FORCE_OPTION, JSON_OPTION, SMOOTHING_DEFAULTS, UNDAMPED_HELP


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
    model: ModelKind = model_option(DEFAULT_MODEL),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles"),
    a_p: Optional[float] = typer.Option(None, "--a-p", help="pulse amplitude [m/s²] (default: --accel-ratio 4)"),
    accel_ratio: Optional[float] = typer.Option(None, help="pulse amplitude as a_p/(g tanα) (default 4)"),
    omega_p: Optional[float] = typer.Option(None, help="pulse frequency [rad/s] (default 2π)"),
    omega_ratio: Optional[float] = typer.Option(None, help="pulse frequency as ω_p/p"),
    record: Optional[str] = typer.Option(None, help=f"a record file (.AT2 or two-column), a horizontal/vertical pair 'H + V' of them, or a packaged "
                                                    f"record ({builtin_record_names()}), instead of a pulse"),
    scale: float = typer.Option(1.0, help="factor on the record"),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    undamped: bool = typer.Option(False, "--undamped", help=UNDAMPED_HELP),
    backbone: Optional[BackboneKind] = typer.Option(None, help=f"spring: base-spring backbone (default {BACKBONE_DEFAULTS}; the bilinear "
                                                    "at θy = 1e-5 α′ is within 1e-3 of the sharp limit, docs/numerics.md)"),
    smoothing: Optional[float] = typer.Option(None, help=f"spring: pre-yield rotation θs/α′ in (0, 1) (default {SMOOTHING_DEFAULTS})"),
    tol: Optional[float] = typer.Option(None, help=TOL_HELP),
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
