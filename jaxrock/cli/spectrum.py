"""`jaxrock spectrum`: an overturning spectrum over (ω_p/p, a_p/(g tanα)) → netCDF and figure."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional

import typer

from .guards import (report, say, _estimate, _exit_if_untrusted, _guarded, _history, _hold, _interrupted, _status_counts,
                     SENSITIVITY_COST, cell_seconds)
from ..scene import DEFAULT_MODEL, DEFAULT_PULSE, MAX_REFINE
from .options import (model_option, parse_values, ModelKind, PulseKind, _check_count, _integrator, build_model, spectrum_summary, SENSITIVITY_HELP,
                      check_pulse_params, split_params, with_params)
from .grammar import DEFAULT_GRID
from .app import QUIET_OPTION, TOL_HELP, app, FORCE_OPTION, JSON_OPTION, RATIO_UNITS, UNDAMPED_HELP


@app.command()
@_guarded
@with_params()
def spectrum(
    model: ModelKind = model_option(DEFAULT_MODEL),
    height: float = typer.Option(10.0, help="full height 2h [m]"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα = b/h, in (0, 1)"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h, in [tanα, 1)"),
    pulse: PulseKind = typer.Option(PulseKind(DEFAULT_PULSE), help="pulse kind: the Ricker pulses of eqs. 28 (symmetric) and 29 (antisymmetric), a sine pulse of --n-cycles"),
    omega_ratio: str = typer.Option(DEFAULT_GRID["spectrum"]["--omega-ratio"], help="ω_p/p′ axis: 'a:b:n' or values '1,2,5' (increasing)"),
    accel_ratio: str = typer.Option(DEFAULT_GRID["spectrum"]["--accel-ratio"], help="a_p/(g tanα′) axis: 'a:b:n' or values '1,2,5' (increasing)"),
    out: str = typer.Option("out/spectrum", help="output stem: writes <out>.nc (netCDF) and <out>.png; a folder (or a path "
                            "ending in /) means <out>/spectrum.nc and .png"),
    undamped: bool = typer.Option(False, "--undamped", help=UNDAMPED_HELP),
    checkpoint: bool = typer.Option(True, "--checkpoint/--no-checkpoint", help="keep finished batches in the folder <out>.checkpoint; a rerun resumes"),
    batch_size: int = typer.Option(4096, help="largest number of cells per vmapped batch (memory bound); the grid is split into batches "
                                   "of sizes the compiled passes share"),
    refine: int = typer.Option(10, min=0, max=MAX_REFINE, help="bisections of the uplift and overturning lines between grid rows (0: grid lines)"),
    tol: Optional[float] = typer.Option(None, help=TOL_HELP),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP + "; off by default on pulses "
                                     "(none of 240 seeded pulse cells changed verdict, benchmarks/study_uncertain.py)"),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a grid estimated beyond 1 h or 2 GB"),
    **params: Optional[float],
):
    """Overturning spectrum: max θ/α over a grid of (ω_p/p, a_p/(g tanα)) (paper figures 6, 9, 11)."""
    from ..io.files import check_output, output_stem

    from .._validate import check_grid

    wr = check_grid("--omega-ratio", parse_values("--omega-ratio", omega_ratio))
    ar = check_grid("--accel-ratio", parse_values("--accel-ratio", accel_ratio))
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
