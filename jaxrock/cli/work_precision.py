"""`jaxrock work-precision`: error against run time, jaxrock and its peers."""

from __future__ import annotations

from pathlib import Path

import typer

from .guards import report, say, _guarded
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION, in_folder


@app.command("work-precision")
@_guarded
def work_precision(
    quick: bool = typer.Option(False, "--quick", help="fewer settings and smaller grids (about 3 min on 2 cores)"),
    out: Path = typer.Option(Path("out/work-precision"), help="output folder: work_precision.png (the diagrams), .md (tables, the "
                             "defaults against the peers), .csv (every point); work_precision_panels/ keeps each finished panel"),
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
):
    """Error against run time for the RM (diffrax solvers over rtol, float32, the SciPy event loop)
    and the SM (Tsit5 and generalized-α over the tolerance, Checked, the spring's smoothing and
    backbone, the number of elements, OpenSeesPy when the `opensees` extra is installed), per scene
    and per vmapped grid, against converged references, the defaults marked."""
    from ..numerics.work_precision import defaults_table
    from ..numerics.work_precision import work_precision as run

    rows = in_folder(out, "work_precision.md", "panels", "work_precision_panels", lambda: run(out, quick=quick, progress=not quiet))
    say(f"{len(rows)} points; the defaults against the peers:")
    for line in defaults_table(rows):
        say(line)
    say(f"wrote {out / 'work_precision.png'}, {out / 'work_precision.md'}, {out / 'work_precision.csv'}")
    report("work-precision", {"points": rows, "files": [out / "work_precision.png", out / "work_precision.md", out / "work_precision.csv"]})
