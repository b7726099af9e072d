"""`jaxrock record-spectrum`: a record's least overturning scale factor per body height (figure 10)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from .guards import (report, say, _estimate, _exit_if_untrusted, _guarded, _history, _hold, _status_counts, record_run_seconds,
                     SENSITIVITY_COST)
from ..scene import DEFAULT_MODEL, DEFAULT_PULSE, RECORD_ALIASES, builtin_record_names
from .options import (model_option, ModelKind, _check_refine, _excitation, _integrator, build_model, parse_values, SENSITIVITY_HELP,
                      uncertain_line)
from .app import QUIET_OPTION, TOL_HELP, app, FORCE_OPTION, JSON_OPTION


@app.command("record-spectrum")
@_guarded
def record_spectrum(
    record: str = typer.Option(RECORD_ALIASES[0], help=f"record file (.AT2 or two-column text), a horizontal/vertical pair 'H + V', or a packaged record "
                                                          f"({builtin_record_names()})"),
    model: ModelKind = model_option(DEFAULT_MODEL),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′"),
    height: str = typer.Option("1,2,3,5,7,10,15,20", help="body heights 2h [m]: '1,2,5' or 'a:b:n'"),
    scale: str = typer.Option(
        "0.5:12:16",
        help="record factors of the vmapped sweep ('1,2,5' or 'a:b:n'); the first that overturns is then refined by "
        "bisection. A coarse sweep is cheap (a vmapped record run costs about as much per lane as a bisection step) "
        "but can miss a narrow overturning window between two factors",
    ),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    refine: int = typer.Option(8, help="bisections refining the least overturning factor (resolution: sweep step / 2^refine)"),
    tol: Optional[float] = typer.Option(None, help=TOL_HELP),
    out: str = typer.Option("out/record_spectrum", help="output stem: <out>.nc, <out>.csv, <out>.png; a folder (or a path "
                            "ending in /) means <out>/record_spectrum.*"),
    sensitivity: bool = typer.Option(True, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    yes: bool = typer.Option(False, "--yes", help="run a sweep estimated beyond 1 h"),
):
    """Least scale factor of a record that overturns the body, per height (paper figure 10)."""
    from ..io.files import check_output, output_stem

    hs = parse_values("--height", height)
    sc = parse_values("--scale", scale)
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
