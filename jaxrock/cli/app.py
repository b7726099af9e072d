"""The `jaxrock` program (typer): the app, with its one-line errors (`guards._OneLineErrors`), and
what its commands share: the options every command spells alike and the frame of the commands that
fill a resumable folder. Each command is a module of this package (`spectrum`, `simulate`, ...)."""

from __future__ import annotations

from pathlib import Path

import typer

from .guards import EXIT_INTERRUPTED, _hold, _OneLineErrors, _resume_command
from ..scene import DEFAULT_BACKBONE, DEFAULT_SMOOTHING, UNDAMPED

JSON_OPTION = typer.Option(False, "--json", help="print the summary as one JSON document on stdout instead of text (units in its "
                           "'units'; null: never, or not computed); warnings stay on stderr")
QUIET_OPTION = typer.Option(False, "--quiet", "-q", help="no progress bar")
FORCE_OPTION = typer.Option(False, "--force", help="let outputs replace existing files that jaxrock did not write "
                            "(without it such a file is refused; symbolic links always are)")
BACKBONE_DEFAULTS = ", ".join(f"{v} {k}" for k, v in DEFAULT_BACKBONE.items())
SMOOTHING_DEFAULTS = ", ".join(f"{v:g} {k}" for k, v in DEFAULT_SMOOTHING.items())
UNDAMPED_HELP = "no energy loss: " + ", ".join(f"{k} = {v:g}" for k, v in UNDAMPED.items()) + " (whichever the model takes)"

TOL_HELP = ("spring models: run generalized-α at this local tolerance, in (0, 0.1), its global error checked by a companion run at "
            "10x the tolerance (status inaccurate beyond 1e-2 in max θ/α); default: the model's default integrator")
RATIO_UNITS = {"omega_ratio": "1 (omega_p/p')", "accel_ratio": "1 (a_p/(g tan alpha'))"}  # --json: the grid's axes

app = typer.Typer(
    cls=_OneLineErrors,
    add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
    context_settings={"help_option_names": ["-h", "--help"]},
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help texts are shown as written: units "[m]" and ranges "a:b:n" are not markup
)


def _print_version(value: bool):
    if value:
        from ..cache import package_version

        typer.echo(f"jaxrock {package_version()}")
        raise typer.Exit()


@app.callback()
def _root(version: bool = typer.Option(False, "--version", callback=_print_version, is_eager=True,
                                       help="print jaxrock's version (from git tags: it names the commit) and exit")):
    """Rocking bodies under earthquakes (Vassiliou, Mackie & Stojadinovic 2014), in JAX (float64)."""  # the program's help


def in_folder(out: Path, first_file: str, parts: str, kept: str, run):
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


def main():  # pragma: no cover
    app()
