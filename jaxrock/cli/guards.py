"""The command line's frame: one-line errors and exit codes, the work estimate before a run,
output locks, signals (stop at a safe point, say how to resume) and the status verdict after it."""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import re
from pathlib import Path
from typing import Optional

import numpy as np
import typer
import typer.core


class _OneLineErrors(typer.core.TyperGroup):
    """Click's usage errors (an unknown choice, a non-integer count, an unknown option) as one line,
    `Error: … (see 'jaxrock CMD --help')`, exit code 2, like every other bad input; click printed
    four lines (usage, a hint, a blank line, the error)."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        import sys

        from ..runtime import use_cpu_cores

        use_cpu_cores()  # before JAX starts: a sweep's chunks run one per core
        from . import PLUGIN_ERRORS

        if PLUGIN_ERRORS and standalone_mode:  # a plugin that failed to load: its kinds are missing from every option
            typer.echo(f"Error: {PLUGIN_ERRORS[0]}", err=True)
            sys.exit(EXIT_INPUT)
        try:
            from .._validate import JaxrockInputError
            from .grammar import upgrade

            if not os.environ.get(f"_{(prog_name or 'jaxrock').upper().replace('-', '_')}_COMPLETE"):  # not while completing
                try:
                    args = upgrade(list(sys.argv[1:] if args is None else args))  # the previous release's spellings, with a warning
                except JaxrockInputError as e:
                    typer.echo(f"Error: {e}", err=True)
                    sys.exit(EXIT_INPUT)
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer.Abort:
            typer.echo("interrupted: nothing kept", err=True)
            rv = EXIT_INTERRUPTED
        except typer.TyperException as e:  # click's usage errors and the like
            if not standalone_mode:
                raise
            ctx = getattr(e, "ctx", None)
            if type(e).__name__ == "NoArgsIsHelpError":  # `jaxrock` alone: the help on stdout, exit 0 (nothing went wrong)
                typer.echo(e.format_message())
                rv = 0
            else:
                hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
                typer.echo(f"Error: {e.format_message()}{hint}", err=True)
                rv = e.exit_code
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)



EXIT_INPUT = 2
# Work estimate before a run (`_estimate`): measured cost per cell on 2 CPU cores, vmapped
# (benchmarks/results: bench_rigid.txt 0.19 ms; bench_spring.txt quasi-rigid Tsit5 1.47 ms,
# generalized-α 1e-6 0.092 ms, flexible 10 elements 4.2 ms), compilation apart (~20 s); a run
# beyond LIMIT_SECONDS or LIMIT_BYTES needs --yes.
CELL_SECONDS = {"rigid": 0.19e-3, "spring": 1.47e-3, "spring-ga": 0.092e-3, "spring-flexible": 4.2e-3}
# one run of a 40-s record. Rigid: its runs go sample by sample (issue 53); the default
# record-spectrum (El Centro, 192 runs) takes 21 s cold, nearly all compilation, and
# benchmarks/bench_suite.py's 432 runs of 11 records (2.4 M samples) 3.0-4.7 s warm, 1.2-1.9 µs per
# sample per run; 0.03 s leaves room for small batches (a bisection's few cells). Quasi-rigid SM:
# the same suite 53 s warm, 21 µs per sample per run, 0.17 s for 40 s at dt = 0.005 s. Flexible SM
# (measured when a rigid run cost 0.15 s): the default suite's sweeps (5 records, 320 runs per
# model) ran it 4.3 times as long as the rigid model; the flexible default checked (`Checked`,
# issue 29) costs 1.7 times that (El Centro × 0.5 and × 1 on 4 and 20 m columns, warm: 0.71
# against 0.41 s in all)
RECORD_RUN_SECONDS = {"rigid": 0.03, "spring": 0.17, "spring-flexible": 1.1}
CELL_BYTES = 64  # a_p, ω_p, the grid, the results and the checkpoint's copy, per cell
LIMIT_SECONDS, LIMIT_BYTES = 3600.0, 2e9
EXIT_UNTRUSTED = 1  # the work ran, but some run ended with a status other than ok
EXIT_INTERRUPTED = 130  # SIGINT or SIGTERM: stopped at a safe point, finished work kept

# what to change, per failed status (the line printed beside a non-zero exit)
STATUS_ADVICE = {
    "max_iterations": "the loop bound was hit before the answer was fixed: shorten the free-rocking time or report the scene",
    "max_steps": "the step bound was hit: the scene is stiff (tiny tanα or smoothing) or the tolerance too tight "
    "(loosen --tol, or raise max_steps of the integrator in Python)",
    "solver_failed": "the integrator failed (step underflow, divergence or NaN): loosen --tol or report the scene",
    "missed_impact": "an impact was crossed without its event: report the command line as a bug",
    "inaccurate": "the estimated error exceeds the stated accuracy (a stiff spring or column): tighten --tol, or raise the smoothing",
    "invalid_input": "a parameter was outside its valid range: report the command line as a bug (the CLI checks its input)",
}


def _fail(msg: str):
    typer.echo(f"Error: {msg}", err=True)
    raise typer.Exit(EXIT_INPUT)


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else (f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h")


SENSITIVITY_COST = 2.0  # a run with its tangent against one without (benchmarks/study_uncertain.py: 1.4x records, 2.3x pulses)


def cell_seconds(kind: str) -> float:
    """The estimated cost of one pulse cell of a model of `kind` (`CELL_SECONDS`; a kind registered
    since, unmeasured: the dearest built-in kind's)."""
    return CELL_SECONDS.get(kind, max(CELL_SECONDS.values()))


def record_run_seconds(kind: str, seconds: float) -> float:
    """The estimated cost of one run of a `seconds`-long record with a model of `kind`."""
    return RECORD_RUN_SECONDS.get(kind, RECORD_RUN_SECONDS["spring-flexible"]) * seconds / 40.0  # a registered kind: the dearest


def _estimate(n_cells: int, kind: str, yes: bool, what: str = "cells", per_cell: float | None = None) -> None:
    """Refuse (exit 2) a run estimated beyond an hour or 2 GB unless --yes; announce one over a
    minute. `kind`'s cost per cell is `cell_seconds(kind)`; `per_cell` [s] overrides it."""
    cost = cell_seconds(kind) if per_cell is None else per_cell
    seconds = n_cells * cost
    mem = n_cells * CELL_BYTES
    est = (f"{n_cells:,} {what}: about {_duration(seconds)} and {mem / 1e9:.2g} GB "
           f"(at {1e3 * cost:.3g} ms each, measured on 2 CPU cores)")
    if (seconds > LIMIT_SECONDS or mem > LIMIT_BYTES) and not yes:
        _fail(f"{est}; beyond {LIMIT_SECONDS / 3600:g} h or {LIMIT_BYTES / 1e9:g} GB: pass --yes to run it, or coarsen the grid")
    if seconds > 60:
        typer.echo(f"{est}, plus compilation", err=True)


def _resume_command(extra: str | None = None) -> str:
    import shlex
    import sys

    argv = sys.argv[1:]
    return "jaxrock " + shlex.join(argv + ([extra] if extra and extra not in argv else []))


def _interrupted(ck: Optional[Path], n_cells: int):
    """A stop asked by a signal: say what the checkpoint store keeps and how to resume; exit 130."""
    from ..io.store import kept_scenes

    if ck is not None and ck.is_dir():
        kept = kept_scenes(ck)
        typer.echo(f"interrupted: {kept:,} of {n_cells:,} cells kept in {ck}; resume with: {_resume_command()}", err=True)
    else:
        typer.echo("interrupted: nothing kept (run with --checkpoint to keep finished batches)", err=True)
    raise typer.Exit(EXIT_INTERRUPTED)


def _history() -> str:
    """The command line of this run, for a file's CF `history` attribute."""
    import sys

    from ..io.provenance import command_line

    return command_line(sys.argv[1:])


def _status_counts(status) -> dict[str, int]:
    """Status name → number of runs, from (an array of) status codes."""
    from ..results import STATUS_NAMES

    counts = np.bincount(np.ravel(np.asarray(status)), minlength=len(STATUS_NAMES))
    return {STATUS_NAMES[k]: int(c) for k, c in enumerate(counts) if c}


def _exit_if_untrusted(counts: dict[str, int], what: str):
    """One line per failed status kind on stderr and exit code 1, when any run is not ok (the
    files were written; their status column says which)."""
    bad = {name: c for name, c in counts.items() if name != "ok"}
    for name, c in bad.items():
        typer.echo(f"Warning: {c} {what} ended with status {name}: {STATUS_ADVICE[name]}", err=True)
    if bad:
        raise typer.Exit(EXIT_UNTRUSTED)


_held: contextlib.ExitStack | None = None  # the locks of the running command (`_hold`)


def _hold(path, what: str) -> None:
    """Hold `<path>.lock` until the command ends: a second run writing the same output is refused."""
    from ..io.files import exclusive

    _held.enter_context(exclusive(path, what))


# the file system refused a write: no space, a quota, a file size limit, read-only or not permitted
_NO_ROOM = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EACCES, errno.EPERM}


JSON = False  # `--json`: the summary as one JSON document on stdout instead of text (set per command by `_guarded`)


def say(text: str = "") -> None:
    """A line of a command's text summary on stdout (none under `--json`: `report` prints the document)."""
    if not JSON:
        typer.echo(text)


def plain(x):
    """`x` as JSON can hold it: arrays and tuples as lists, NumPy scalars as numbers, paths as text,
    non-finite numbers as null (a time or factor that never happened, a value not computed)."""
    import math
    from pathlib import PurePath

    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        x = x.tolist()  # a 0-d array: its number
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, PurePath):
        return str(x)
    return x


def report(command: str, data: dict, units: dict | None = None) -> None:
    """Under `--json`: one JSON document on stdout, `{"command", "jaxrock", "units", ...data}`
    (`units`: field → unit of the numbers that have one; `null` means never or not computed)."""
    if JSON:
        import json

        from ..cache import package_version

        doc = {"command": command, "jaxrock": package_version(), "units": units or {}, **data}
        typer.echo(json.dumps(plain(doc), allow_nan=False, ensure_ascii=False, indent=1))


_NAMED = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?: \([^)]*\))?(?: \[[^\]]*\])?) = ")


def command_flags(fn) -> dict[str, str]:
    """A command function's options: Python parameter → its flag ("tan_alpha" → "--tan-alpha";
    "save_path" → "--save", as declared)."""
    import inspect

    flags = {}
    for name, q in inspect.signature(fn).parameters.items():
        decls = [d for d in getattr(q.default, "param_decls", None) or () if d.startswith("--")]
        if type(q.default).__name__ == "OptionInfo":
            flags[name] = decls[0].split("/")[0] if decls else "--" + name.replace("_", "-")
    return flags


def in_flags(message: str, flags: dict[str, str]) -> str:
    """A library's message that starts by naming a Python parameter ("tan_alpha = 2 is outside …",
    "height (2h) [m] = -1 …") as the command's flag for it (`flags`: "--tan-alpha = 2 …")."""
    m = _NAMED.match(message)
    flag = None if m is None else flags.get(m.group(1))
    return message if flag is None else flag + message[len(m.group(1)):]


def _guarded(fn):
    """A command: a `JaxrockInputError` becomes a one-line message and exit code 2; SIGINT and
    SIGTERM stop the run at its next safe point (`jaxrock.interrupt`) and exit 130 — a command
    with work to keep catches `Interrupted` itself and says how to resume."""

    flags = command_flags(fn)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        global _held, JSON
        from .._validate import MADE_FOLDERS, JaxrockInputError, remove_made_folders
        from ..interrupt import deferred_signals

        from ..io import files

        MADE_FOLDERS.clear()
        files.FORCE = bool(kwargs.get("force", False))  # the commands that write files take --force
        JSON = bool(kwargs.get("as_json", False))  # the commands that print a summary take --json
        try:
            with deferred_signals(), contextlib.ExitStack() as _held:
                return fn(*args, **kwargs)
        except JaxrockInputError as e:
            remove_made_folders()
            _fail(in_flags(str(e), flags))
        except OSError as e:
            if e.errno not in _NO_ROOM:
                raise
            remove_made_folders()
            where = f" {e.filename}" if e.filename else " an output"
            _fail(f"cannot write{where}: {e.strerror or e} (finished work kept in a store or checkpoint is resumed by "
                  f"the same command); free space, or choose a writable path")
        except KeyboardInterrupt:
            typer.echo("interrupted: nothing kept", err=True)
            raise typer.Exit(EXIT_INTERRUPTED) from None
        finally:
            files.FORCE = False  # the library, called after, keeps its default
            JSON = False

    return wrapper
