"""`jaxrock reproduce`: every figure of the paper and a report of its values beside jaxrock's."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .guards import report, say, _guarded
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION, in_folder


def _steps() -> tuple[str, ...]:
    from ..paper.reproduce import STEP_NAMES

    return STEP_NAMES


@app.command()
@_guarded
def reproduce(
    quick: bool = typer.Option(False, "--quick", help="coarse grids and fewer variants (about 1.5 against 4 min on 2 cores with a warm compilation cache)"),
    out: Path = typer.Option(Path("out/reproduce"), help="output folder: report.md (verdicts and figures), findings.csv, every "
                             "figure and its data; findings/ keeps each finished step (a rerun resumes)"),
    only: Optional[str] = typer.Option(None, help="comma-separated steps to run (default all): " + ", ".join(_steps())),
    quiet: bool = QUIET_OPTION,
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

    rep = in_folder(out, "report.md", "steps", "findings", lambda: run(out, quick=quick, only=names, progress=not quiet))
    counts = rep.counts()
    say(f"{sum(counts.values())} values of the paper in {sum(rep.seconds.values()):.0f} s of computation: "
               + ", ".join(f"{n} {v}" for v, n in counts.items()))
    say("wrote " + ", ".join(str(p) for p in rep.files.values()))
    report("reproduce", {"verdicts": counts, "seconds": sum(rep.seconds.values()), "files": list(rep.files.values())}, {"seconds": "s"})
