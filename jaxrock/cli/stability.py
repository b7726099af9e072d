"""`jaxrock stability`: the three models' defaults on stiff and extreme scenes."""

from __future__ import annotations

from pathlib import Path

import typer

from .guards import report, say, EXIT_UNTRUSTED, _guarded
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION, in_folder


@app.command()
@_guarded
def stability(
    quick: bool = typer.Option(False, "--quick", help="the quick matrix: fewer cases, flexible columns of 4 elements (about 1 min)"),
    out: Path = typer.Option(Path("out/stability"), help="output folder: stability.md, stability.csv, stability.png; "
                             "stability_cases/ keeps each finished case (a rerun resumes)"),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """The defaults of the three models (rigid, quasi-rigid SM, flexible SM) on stiff and extreme
    scenes, each against a refined reference: finite or not, status, error, stated accuracy, run
    time, verdict (holds / flagged / ok but off / not finite). Exit 1 where a status lies (ok but
    off) or a summary is not finite."""
    from ..numerics.stability import HOLDS, NOT_FINITE, OFF, VERDICTS
    from ..numerics.stability import stability as run

    rows = in_folder(out, "stability.md", "cases", "stability_cases", lambda: run(out, quick=quick, progress=not quiet))
    counts = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
    say(f"{len(rows)} runs: " + ", ".join(f"{n} {v}" for v, n in counts.items()))
    for r in rows:
        if r["verdict"] != HOLDS:
            say(f"  {r['case']} | {r['model']}: {r['verdict']} ({r['status']}, error {r['error']:.1e}, accuracy {r['accuracy']:.0e})")
    say(f"wrote {out / 'stability.md'}, {out / 'stability.csv'}, {out / 'stability.png'}")
    report("stability", {"verdicts": counts, "runs": rows, "files": [out / "stability.md", out / "stability.csv", out / "stability.png"]})
    if counts[OFF] or counts[NOT_FINITE]:
        raise typer.Exit(EXIT_UNTRUSTED)
