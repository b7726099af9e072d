"""`jaxrock batch`: a CSV of scenes, vmapped in groups, into a results CSV."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .guards import report, say, EXIT_INTERRUPTED, _exit_if_untrusted, _guarded, _resume_command
from ..outputs import OUTPUTS, RESULT_COLUMNS
from ..scene import PULSES, RECORD_ALIASES, model_kinds, model_params, pulse_params
from .options import SENSITIVITY_HELP
from .app import QUIET_OPTION, app, FORCE_OPTION, JSON_OPTION


@app.command(help=(
    "Run a CSV of scenes (vmapped, grouped by structure) and write a results CSV.\n\n"
    f"Columns: height, tan_alpha | width, [tan_alpha_base], [model: {' | '.join(model_kinds())}], "
    f"[pulse: {' | '.join(PULSES)} | {RECORD_ALIASES[0]} | FILE], a_p | accel_ratio, omega_p | omega_ratio, [scale], "
    f"{', '.join(f'[{k}]' for k in (*model_params(), *pulse_params()))}. Results: the inputs plus {', '.join(RESULT_COLUMNS)}."))
@_guarded
def batch(
    scenes: Path = typer.Argument(..., help="scenes CSV (one scene per row; see `jaxrock.io.scenes_file`)"),
    results: Optional[str] = typer.Argument(None, help="deprecated: give --out", show_default=False, hidden=True),
    out: Optional[str] = typer.Option(None, help="results CSV to write (a folder, or a path ending in /: <folder>/<scenes stem>_results.csv; "
                                      "default out/<scenes stem>_results.csv)"),
    resume: bool = typer.Option(False, "--resume", help="skip rows already in the results file"),
    chunk_size: int = typer.Option(256, help="rows per vmapped batch"),
    sensitivity: bool = typer.Option(False, "--sensitivity/--no-sensitivity", help=SENSITIVITY_HELP),
    force: bool = FORCE_OPTION,
    quiet: bool = QUIET_OPTION,
    as_json: bool = JSON_OPTION,
):
    from .._validate import JaxrockInputError, check_writable
    from ..io.results_file import count_results, results_path_for

    if results is not None:
        if out is not None:
            raise JaxrockInputError("give the results file as --out, not also as a second argument")
        typer.echo("Warning: the results file as a second argument is deprecated; use --out (the old form is removed in the next "
                   "release)", err=True)
    results = results_path_for(scenes, out or results or "out/")
    check_writable("--out", results)
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
