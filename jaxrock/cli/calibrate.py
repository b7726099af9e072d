"""`jaxrock calibrate`: the damper c̄ against the rigid model's η⁴ (eq. 17, figure 7)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from .guards import report, say, EXIT_UNTRUSTED, _guarded, _hold
from ..scene import TAN_ALPHA
from .options import _check_count, parse_values
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION


@app.command()
@_guarded
def calibrate(
    out: Path = typer.Option(Path("out/calibration"), help="output folder (calibration.csv and the figures)"),
    tan_alpha: Optional[str] = typer.Option(None, help="slenderness values to calibrate at ('0.1,0.2,0.3' or 'a:b:n'; default 0.05:0.35:13)"),
    max_iter: int = typer.Option(300, help="optimiser iterations at most"),
    quiet: bool = QUIET_OPTION,
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
    if tan_alpha is not None:
        ta = parse_values("--tan-alpha", tan_alpha)
        TAN_ALPHA.check(ta, "--tan-alpha")
        if np.unique(ta).size < 3:
            raise JaxrockInputError(f"--tan-alpha = {tan_alpha!r}: {np.unique(ta).size} distinct value(s); "
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
