"""The `jaxrock` command line (typer): spectra, single scenes, CSV batches, record spectra and the
damper calibration. `jaxrock COMMAND --help` describes each command.

Bad input ends with a one-line `Error: ...` message (the `JaxrockInputError` text, naming the
parameter and its valid range) and exit code 2, never a traceback.
"""

from __future__ import annotations

import contextlib
import functools
import math
import time
from enum import Enum
from pathlib import Path
from typing import Optional

import equinox as eqx
import numpy as np
import typer
import typer.core


class _OneLineErrors(typer.core.TyperGroup):
    """Click's usage errors (an unknown choice, a non-integer count, an unknown option) as one line,
    `Error: … (see 'jaxrock CMD --help')`, exit code 2, like every other bad input; click printed
    four lines (usage, a hint, a blank line, the error)."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        import sys

        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer.Abort:
            typer.echo("interrupted: nothing kept", err=True)
            rv = EXIT_INTERRUPTED
        except typer.TyperException as e:  # click's usage errors and the like
            if not standalone_mode:
                raise
            ctx = getattr(e, "ctx", None)
            if type(e).__name__ == "NoArgsIsHelpError":  # `jaxrock` alone: the help, as asked
                typer.echo(e.format_message(), err=True)
            else:
                hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
                typer.echo(f"Error: {e.format_message()}{hint}", err=True)
            rv = e.exit_code
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)


app = typer.Typer(
    cls=_OneLineErrors,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help texts are shown as written: units "[m]" and ranges "a:b:n" are not markup
    help="Rocking bodies under earthquakes (Vassiliou, Mackie & Stojadinovic 2014), in JAX (float64).",
)

EXIT_INPUT = 2
MAX_LIST = 100_000  # values of a list option ('a:b:n')
# Work estimate before a run (`_estimate`): measured cost per cell on 2 CPU cores, vmapped
# (benchmarks/results: bench_rigid.txt 0.19 ms; bench_spring.txt quasi-rigid Tsit5 1.47 ms,
# generalized-α 1e-6 0.092 ms, flexible 10 elements 4.2 ms), compilation apart (~20 s); a run
# beyond LIMIT_SECONDS or LIMIT_BYTES needs --yes.
CELL_SECONDS = {"rigid": 0.19e-3, "spring": 1.47e-3, "spring-ga": 0.092e-3, "spring-flexible": 4.2e-3}
RECORD_RUN_SECONDS = 0.37  # one rigid run of El Centro (40 s): default record-spectrum, 192 runs in 70.8 s
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
    "invalid_input": "a parameter was outside its valid range: report the command line as a bug (the CLI checks its input)",
}


class ModelKind(str, Enum):
    rigid = "rigid"
    spring = "spring"
    spring_flexible = "spring-flexible"


class BackboneKind(str, Enum):
    tanh = "tanh"
    bilinear = "bilinear"


class PulseKind(str, Enum):
    symmetric = "symmetric"
    antisymmetric = "antisymmetric"


def _fail(msg: str):
    typer.echo(f"Error: {msg}", err=True)
    raise typer.Exit(EXIT_INPUT)


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else (f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h")


def _estimate(n_cells: int, kind: str, yes: bool, what: str = "cells", per_cell: float | None = None) -> None:
    """Refuse (exit 2) a run estimated beyond an hour or 2 GB unless --yes; announce one over a
    minute. `kind` keys CELL_SECONDS; `per_cell` [s] overrides its cost."""
    cost = CELL_SECONDS[kind] if per_cell is None else per_cell
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
    """A stop asked by a signal: remove half-written files, say what is kept and how to resume; exit 130."""
    from .provenance import checkpoint_cells, remove_temporaries

    if ck is not None and ck.is_dir():
        remove_temporaries(ck)
        kept = checkpoint_cells(ck)
        typer.echo(f"interrupted: {kept:,} of {n_cells:,} cells kept in {ck}; resume with: {_resume_command()}", err=True)
    else:
        typer.echo("interrupted: nothing kept (run with --checkpoint to keep finished batches)", err=True)
    raise typer.Exit(EXIT_INTERRUPTED)


def _history() -> str:
    """The command line of this run, for a file's CF `history` attribute."""
    import sys

    from .provenance import command_line

    return command_line(sys.argv[1:])


def _status_counts(status) -> dict[str, int]:
    """Status name → number of runs, from (an array of) status codes."""
    from .results import STATUS_NAMES

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
    from ._files import exclusive

    _held.enter_context(exclusive(path, what))


def _guarded(fn):
    """A command: a `JaxrockInputError` becomes a one-line message and exit code 2; SIGINT and
    SIGTERM stop the run at its next safe point (`jaxrock.interrupt`) and exit 130 — a command
    with work to keep catches `Interrupted` itself and says how to resume."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        global _held
        from ._validate import JaxrockInputError
        from .interrupt import deferred_signals

        try:
            with deferred_signals(), contextlib.ExitStack() as _held:
                return fn(*args, **kwargs)
        except JaxrockInputError as e:
            _fail(str(e))
        except KeyboardInterrupt:
            typer.echo("interrupted: nothing kept", err=True)
            raise typer.Exit(EXIT_INTERRUPTED) from None

    return wrapper


def _check_count(name: str, n: int):
    from ._validate import JaxrockInputError

    if n < 1:
        raise JaxrockInputError(f"{name} = {n}; valid: an integer >= 1")


def _axis(name: str, lo: float, hi: float, n: int) -> np.ndarray:
    from ._validate import JaxrockInputError, check_positive

    _check_count(f"--n-{name}", n)
    check_positive(f"--{name}-min", lo)
    check_positive(f"--{name}-max", hi)
    if n > 1 and not hi > lo:
        raise JaxrockInputError(f"--{name}-max = {hi:g} must be > --{name}-min = {lo:g}")
    return np.linspace(lo, hi, n) if n > 1 else np.asarray([lo], dtype=float)


def parse_values(name: str, text: str) -> np.ndarray:
    """A list option: "1,2,5" (values) or "a:b:n" (n values evenly spaced from a to b)."""
    import re

    from ._validate import JaxrockInputError

    text = text.strip()
    items = re.split(r"\s*,\s*|\s+", text)
    if text and "" in items:
        raise JaxrockInputError(f"{name} = {text!r} has an empty item; expected numbers '1,2,5' or a range 'a:b:n'")
    try:
        if ":" in text:
            a, b, n = text.split(":")
            a, b, n = float(a), float(b), int(n)
        else:
            vals = [float(v) for v in items if v]
    except ValueError:
        raise JaxrockInputError(f"{name} = {text!r}; expected numbers '1,2,5' or a range 'a:b:n'") from None
    if ":" in text:
        _check_count(f"{name} (a:b:n) n", n)
        if n > MAX_LIST:
            raise JaxrockInputError(f"{name} = {text!r}: n = {n} values; valid: at most {MAX_LIST}")
        return np.linspace(a, b, n)
    if not vals:
        raise JaxrockInputError(f"{name} is empty; expected numbers '1,2,5' or a range 'a:b:n'")
    return np.asarray(vals, dtype=float)


def build_model(model: ModelKind | str, height: float, tan_alpha: float, tan_alpha_base=None, *, undamped=False,
                eta=None, cbar=None, E=None, rho=None, zeta=None, backbone=None, smoothing=None):
    """The model of a CLI scene: the flags are checked here, the model is built by
    `batch.scene_model` (the same as a batch row)."""
    from ._validate import JaxrockInputError
    from .batch import scene_model
    from .geometry import Block

    kind = ModelKind(model)
    block = Block.from_slenderness(height, tan_alpha, tan_alpha_base)
    if kind is not ModelKind.spring_flexible:
        for name, v in (("--E", E), ("--rho", rho), ("--zeta", zeta)):
            if v is not None:
                raise JaxrockInputError(f"{name} applies to --model spring-flexible only (the column's material)")
    if kind is ModelKind.rigid:
        for name, v in (("--backbone", backbone), ("--smoothing", smoothing)):
            if v is not None:
                raise JaxrockInputError(f"{name} applies to the spring models only (the base spring)")
        if cbar is not None:
            raise JaxrockInputError("--cbar applies to the spring models only (rigid: --eta or --undamped)")
        if undamped and eta is not None:
            raise JaxrockInputError("give --undamped or --eta, not both")
        return scene_model("rigid", block, eta=1.0 if undamped else eta)
    if eta is not None:
        raise JaxrockInputError("--eta applies to the rigid model only (spring: --cbar or --undamped)")
    if undamped and cbar is not None:
        raise JaxrockInputError("give --undamped or --cbar, not both")
    backbone = None if backbone is None else BackboneKind(backbone).value
    return scene_model(kind.value, block, cbar=0.0 if undamped else cbar, E=E, rho=rho, zeta=zeta, backbone=backbone,
                       smoothing=smoothing)


def _integrator(model: ModelKind, tol: Optional[float]):
    """`--tol`: generalized-α at that local tolerance for the spring models; None: the default."""
    if tol is None:
        return None
    from ._validate import JaxrockInputError
    from .spring import GeneralizedAlpha

    if model == ModelKind.rigid:
        raise JaxrockInputError("--tol selects the spring model's generalized-α integrator; the rigid model takes none")
    return GeneralizedAlpha(rtol=tol, atol=tol)


def even_batch(n: int, limit: int) -> int:
    """A batch size that splits n cells into equal batches of at most `limit`, about four or more
    of them (a progress bar that moves), so that no smaller last batch needs its own compilation.
    Falls back to `min(n, limit)` when n has no suitable divisor."""
    if n <= 256:
        return min(n, limit)
    k0 = max(4, -(-n // limit))
    for k in range(k0, k0 + 64):
        if n % k == 0 and n // k >= 64:
            return n // k
    return min(n, limit)


# ----------------------------------------------------------------------------------------------
# spectrum
# ----------------------------------------------------------------------------------------------
def spectrum_summary(spec, seconds: float) -> str:
    from .results import STATUS_NAMES

    a = spec.attrs
    n_a, n_w = spec.max_theta.shape
    n = n_a * n_w
    tan_col = float(a["width"]) / float(a["height"])
    base = "" if abs(tan_col - float(a["tan_alpha"])) < 1e-12 else f" on a base tanα′ = {float(a['tan_alpha']):.4g}"
    lines = [
        f"spectrum: {a.get('model')}, {a.get('pulse')}, 2h = {float(a['height']):g} m, tanα = {tan_col:.4g}{base} "
        f"(rocking α = {float(a['alpha']):.4g} rad, p = {float(a['p']):.4g} rad/s)",
        f"grid: {n_w} ω_p/p in [{spec.omega_ratio[0]:g}, {spec.omega_ratio[-1]:g}] × {n_a} a_p/(g tanα) in "
        f"[{spec.accel_ratio[0]:g}, {spec.accel_ratio[-1]:g}] = {n} cells in {seconds:.1f} s ({1e3 * seconds / n:.2f} ms/cell)",
        f"overturned: {int(spec.overturned.sum())} cells ({100 * spec.overturned.mean():.1f} %), "
        f"uplifted: {int(spec.uplifted.sum())} ({100 * spec.uplifted.mean():.1f} %)",
        "status: " + ", ".join(f"{STATUS_NAMES[k]} {int(c)}" for k, c in enumerate(np.bincount(spec.status.ravel(), minlength=len(STATUS_NAMES))) if c),
    ]
    for name, b in (("uplift", spec.uplift_boundary), ("overturning", spec.overturn_boundary)):
        fin = np.isfinite(b)
        if fin.any():
            rng = f"{np.min(b[fin]):.3g} … {np.max(b[fin]):.3g}"
            none = "" if fin.all() else f" ({int((~fin).sum())} ω_p/p columns: none in the grid)"
            lines.append(f"least {name} a_p/(g tanα): {rng}{none}")
        else:
            lines.append(f"least {name} a_p/(g tanα): none in the grid")
    return "\n".join(lines)


@app.command()
@_guarded
def spectrum(
    model: ModelKind = typer.Option(ModelKind.rigid, help="rigid (RM), spring (quasi-rigid SM with added masses), spring-flexible (SM, concrete column)"),
    height: float = typer.Option(10.0, help="full height 2h [m]"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα = b/h, in (0, 1)"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h, in [tanα, 1)"),
    pulse: PulseKind = typer.Option(PulseKind.symmetric, help="Ricker pulse shape"),
    omega_min: float = typer.Option(1.0, help="smallest ω_p/p"),
    omega_max: float = typer.Option(15.0, help="largest ω_p/p"),
    n_omega: int = typer.Option(48, help="number of ω_p/p values"),
    accel_min: float = typer.Option(0.5, help="smallest a_p/(g tanα)"),
    accel_max: float = typer.Option(10.0, help="largest a_p/(g tanα)"),
    n_accel: int = typer.Option(48, help="number of a_p/(g tanα) values"),
    out: str = typer.Option("out/spectrum", help="output stem: writes <out>.nc (netCDF) and <out>.png; a folder (or a path "
                            "ending in /) means <out>/spectrum.nc and .png"),
    undamped: bool = typer.Option(False, "--undamped", help="no energy loss: η = 1 (rigid) or c̄ = 0 (spring)"),
    checkpoint: bool = typer.Option(True, "--checkpoint/--no-checkpoint", help="keep finished batches in the folder <out>.checkpoint; a rerun resumes"),
    batch_size: int = typer.Option(4096, help="largest number of cells per vmapped batch (memory bound); the grid is split into equal batches"),
    refine: int = typer.Option(10, min=0, max=40, help="bisections of the uplift and overturning lines between grid rows (0: grid lines)"),
    tol: Optional[float] = typer.Option(
        None, help="spring models: run generalized-α at this local tolerance in (0, 1) (e.g. 1e-6: a quasi-rigid pulse grid ~15x "
        "faster, max error ~1e-2 in θ/α; see README); default: the model's default integrator"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    yes: bool = typer.Option(False, "--yes", help="run a grid estimated beyond 1 h or 2 GB"),
):
    """Overturning spectrum: max θ/α over a grid of (ω_p/p, a_p/(g tanα)) (paper figures 6, 9, 11)."""
    from ._files import output_stem
    from ._validate import check_writable
    from .spectra import overturning_spectrum

    wr = _axis("omega", omega_min, omega_max, n_omega)
    ar = _axis("accel", accel_min, accel_max, n_accel)
    _check_count("--batch-size", batch_size)
    m = build_model(model, height, tan_alpha, tan_alpha_base, undamped=undamped)
    integ = _integrator(model, tol)
    out = output_stem(out, "spectrum")
    for suffix in (".nc", ".png"):
        check_writable("--out", Path(f"{out}{suffix}"))
    _hold(out, "--out")
    kind = "spring-ga" if (model == ModelKind.spring and tol is not None) else model.value
    _estimate(wr.size * ar.size, kind, yes)
    ck = Path(f"{out}.checkpoint") if checkpoint else None
    t0 = time.perf_counter()
    bs = even_batch(wr.size * ar.size, batch_size)
    from .interrupt import Interrupted

    try:
        spec = overturning_spectrum(m, wr, ar, pulse=pulse.value, integrator=integ, batch_size=bs, progress=not quiet,
                                    checkpoint=ck, keep_checkpoint=True, refine=refine)
    except Interrupted:
        _interrupted(ck, wr.size * ar.size)
    seconds = time.perf_counter() - t0
    spec = eqx.tree_at(lambda s: s.attrs, spec, {**spec.attrs, "model_kind": model.value, "undamped": int(undamped),
                                                  "history": _history()})
    nc = spec.save(Path(f"{out}.nc"))
    from .plotting import plot_spectrum

    import matplotlib.pyplot as plt

    title = f"{model.value}{' (undamped)' if undamped else ''}, {pulse.value} pulse, 2h = {height:g} m, tanα = {tan_alpha:g}"
    fig = plot_spectrum(spec, title=title, path=Path(f"{out}.png"))
    plt.close(fig)
    if ck is not None and ck.exists():  # kept until the result files are written
        import shutil

        shutil.rmtree(ck)
    typer.echo(spectrum_summary(spec, seconds))
    typer.echo(f"wrote {nc} and {out}.png")
    _exit_if_untrusted(_status_counts(spec.status), "cell(s)")


# ----------------------------------------------------------------------------------------------
# simulate
# ----------------------------------------------------------------------------------------------
def _excitation(block, pulse: str, record: Optional[str], scale: float, a_p, accel_ratio, omega_p, omega_ratio, units=None):
    from ._validate import JaxrockInputError, check_range
    from .spectra import PULSES

    if record is not None:
        for name, v in (("--a-p", a_p), ("--accel-ratio", accel_ratio), ("--omega-p", omega_p), ("--omega-ratio", omega_ratio)):
            if v is not None:
                raise JaxrockInputError(f"{name} applies to Ricker pulses, not to --record")
        check_range("--scale", scale, 0.0, math.inf, hi_open=True)
        if record.lower() in ("elcentro", "el-centro", "el_centro"):
            from .records import el_centro

            if units is not None:
                raise JaxrockInputError("--units applies to --record files; the packaged El Centro record needs none")
            rec = el_centro()
        else:
            from .records import read_record

            if not Path(record).is_file():
                raise JaxrockInputError(f"--record {record}: file not found")
            rec = read_record(record) if units is None else read_record(record, units=units)
        return rec.scaled(scale), f"{rec.name} × {scale:g}"
    if units is not None:
        raise JaxrockInputError("--units applies to --record files, not to Ricker pulses")
    if a_p is not None and accel_ratio is not None:
        raise JaxrockInputError("give --a-p or --accel-ratio, not both")
    if omega_p is not None and omega_ratio is not None:
        raise JaxrockInputError("give --omega-p or --omega-ratio, not both")
    if a_p is None:
        accel_ratio = 4.0 if accel_ratio is None else accel_ratio
        check_range("--accel-ratio", accel_ratio)
        a_p = accel_ratio * float(block.uplift_acceleration)
    if omega_p is None:
        if omega_ratio is None:
            omega_p = 2 * math.pi
        else:
            check_range("--omega-ratio", omega_ratio, 0.0, math.inf, lo_open=True, hi_open=True)
            omega_p = omega_ratio * float(block.p_r)
    exc = PULSES[pulse](a_p, omega_p)
    desc = (f"{pulse} Ricker pulse a_p = {a_p:.4g} m/s² ({a_p / float(block.uplift_acceleration):.4g} g tanα), "
            f"ω_p = {omega_p:.4g} rad/s ({omega_p / float(block.p_r):.4g} p)")
    return exc, desc


@functools.cache
def _jitted_simulate():
    import equinox as eqx

    from .model import simulate as _simulate

    return eqx.filter_jit(_simulate)


def _simulate(model, excitation, save=None, integrator=None):
    """`jaxrock.simulate`, jitted (one compilation per model/excitation structure per process)."""
    return _jitted_simulate()(model, excitation, save=save, integrator=integrator)


def solution_summary(sol, model) -> str:
    from .results import status_names

    a = float(model.block.alpha_r)
    t_over = float(np.asarray(sol.t_overturn))
    t_up = float(np.asarray(sol.t_uplift))
    lines = [
        f"max θ/α = {float(np.asarray(sol.max_theta)):.6f}",
        f"overturned: {'yes, at t = %.4f s' % t_over if bool(np.asarray(sol.overturned)) else 'no'}",
        f"uplifted: {'yes, at t = %.4f s' % t_up if bool(np.asarray(sol.uplifted)) else 'no'}",
        f"impacts: {int(np.asarray(sol.n_impacts))}",
        f"status: {status_names(sol.status)}",
        f"(α = {a:.5g} rad, p = {float(model.block.p_r):.5g} rad/s)",
    ]
    return "\n".join(lines)


@app.command()
@_guarded
def simulate(
    height: float = typer.Option(10.0, help="full height 2h [m]"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα = b/h, in (0, 1)"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h"),
    model: ModelKind = typer.Option(ModelKind.rigid, help="rigid, spring (quasi-rigid SM), spring-flexible"),
    pulse: PulseKind = typer.Option(PulseKind.symmetric, help="Ricker pulse shape"),
    a_p: Optional[float] = typer.Option(None, "--a-p", help="pulse amplitude [m/s²] (default: --accel-ratio 4)"),
    accel_ratio: Optional[float] = typer.Option(None, help="pulse amplitude as a_p/(g tanα) (default 4)"),
    omega_p: Optional[float] = typer.Option(None, help="pulse frequency [rad/s] (default 2π)"),
    omega_ratio: Optional[float] = typer.Option(None, help="pulse frequency as ω_p/p"),
    record: Optional[str] = typer.Option(None, help="a record file (.AT2 or two-column) or 'elcentro', instead of a pulse"),
    scale: float = typer.Option(1.0, help="factor on the record"),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    undamped: bool = typer.Option(False, "--undamped", help="η = 1 (rigid) or c̄ = 0 (spring)"),
    eta: Optional[float] = typer.Option(None, help="rigid: impact velocity ratio (default 1 − 1.5 sin²α)"),
    cbar: Optional[float] = typer.Option(None, help="spring: damper c̄ (default eq. 17)"),
    E: Optional[float] = typer.Option(None, "--E", help="spring-flexible: Young's modulus [Pa] (default 30e9)"),
    rho: Optional[float] = typer.Option(None, help="spring-flexible: density [kg/m³] (default 2500)"),
    zeta: Optional[float] = typer.Option(None, help="spring-flexible: column damping ratio (default 0.01)"),
    backbone: Optional[BackboneKind] = typer.Option(None, help="spring: base-spring backbone (default tanh; bilinear with "
                                                    "--smoothing 1e-5 is within 1e-3 of the sharp limit, README)"),
    smoothing: Optional[float] = typer.Option(None, help="spring: pre-yield rotation θs/α′ in (0, 1) (default 1e-4)"),
    tol: Optional[float] = typer.Option(None, help="spring models: run generalized-α at this local tolerance in (0, 1); default: the model's default integrator"),
    plot: Optional[Path] = typer.Option(None, help="write a time-history plot (PNG) here"),
    t_free: Optional[float] = typer.Option(None, help="plot: free-rocking time after the excitation [s] (default 2 × 2π/p)"),
    n_points: Optional[int] = typer.Option(None, help="plot: number of saved time points (default 1500)"),
):
    """One scene: prints max θ/α, overturning, uplift, impacts and the run status."""
    from .plotting import plot_history
    from .results import Save

    m = build_model(model, height, tan_alpha, tan_alpha_base, undamped=undamped, eta=eta, cbar=cbar, E=E, rho=rho, zeta=zeta,
                    backbone=backbone, smoothing=smoothing)
    exc, desc = _excitation(m.block, pulse.value, record, scale, a_p, accel_ratio, omega_p, omega_ratio, units)
    integ = _integrator(model, tol)
    if plot is None:
        from ._validate import JaxrockInputError

        for flag, v in (("--t-free", t_free), ("--n-points", n_points)):
            if v is not None:
                raise JaxrockInputError(f"{flag} applies to the time-history plot: give --plot FILE.png as well")
    else:
        from ._validate import check_positive, check_writable

        check_writable("--plot", plot)
        n_points = 1500 if n_points is None else n_points
        _check_count("--n-points", n_points)
        if t_free is not None:
            check_positive("--t-free", t_free)
    t0 = time.perf_counter()
    sol = _simulate(m, exc, integrator=integ)
    seconds = time.perf_counter() - t0
    typer.echo(f"{model.value} model, 2h = {height:g} m, tanα = {tan_alpha:g}; {desc}")
    typer.echo(solution_summary(sol, m))
    typer.echo(f"run time {seconds:.2f} s (with compilation)")
    from .interrupt import stop_point

    stop_point()
    if plot is not None:
        p = float(m.block.p_r)
        tf = 2 * 2 * math.pi / p if t_free is None else t_free
        t_start, t_end = float(exc.t_start), float(exc.t_end)
        if record is None:  # the pulse window is generous (|üg| < 1e-13 a_p): show its core, |ω_p t| <= 8
            w = float(exc.omega_p)
            t_start, t_end = max(t_start, -8.0 / w), min(t_end, 8.0 / w)
        ts = np.linspace(t_start, t_end + tf, n_points)
        hist = _simulate(m, exc, save=Save(ts, ("theta",)), integrator=integ)
        import matplotlib.pyplot as plt

        fig = plot_history(hist, exc, model=m, path=plot, title=f"{model.value}, 2h = {height:g} m, tanα = {tan_alpha:g}\n{desc}")
        plt.close(fig)
        typer.echo(f"wrote {plot}")
    _exit_if_untrusted(_status_counts(sol.status._value), "run")


# ----------------------------------------------------------------------------------------------
# batch
# ----------------------------------------------------------------------------------------------
@app.command()
@_guarded
def batch(
    scenes: Path = typer.Argument(..., help="scenes CSV (one scene per row; see `jaxrock.batch`)"),
    results: str = typer.Argument(..., help="results CSV to write (a folder, or a path ending in /: <folder>/<scenes stem>_results.csv)"),
    resume: bool = typer.Option(False, "--resume", help="skip rows already in the results file"),
    chunk_size: int = typer.Option(256, help="rows per vmapped batch"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
):
    """Run a CSV of scenes (vmapped, grouped by structure) and write a results CSV.

    Columns: height, tan_alpha | width, [tan_alpha_base], [model: rigid | spring | spring-flexible],
    [pulse: symmetric | antisymmetric | elcentro | FILE], a_p | accel_ratio, omega_p | omega_ratio,
    [scale], [eta], [cbar], [E], [rho], [zeta]. Results: the inputs plus max_theta, overturned,
    t_overturn, uplifted, t_uplift, n_impacts, status.
    """
    from ._validate import check_writable
    from .batch import count_results, results_path_for, run_scenes
    from .interrupt import Interrupted

    results = results_path_for(scenes, results)
    check_writable("results", results)
    try:
        rep = run_scenes(scenes, results, resume=resume, chunk_size=chunk_size, progress=not quiet)
    except Interrupted:
        typer.echo(f"interrupted: {count_results(results):,} rows kept in {results}; resume with: {_resume_command('--resume')}",
                   err=True)
        raise typer.Exit(EXIT_INTERRUPTED) from None
    typer.echo(
        f"{rep.n_rows} rows: {rep.n_run} run in {rep.n_groups} group(s), {rep.n_skipped} skipped (already done); "
        f"{rep.seconds:.1f} s"
    )
    typer.echo(f"overturned: {rep.n_overturned}; status: " + ", ".join(f"{k} {v}" for k, v in rep.status_counts.items()))
    typer.echo(f"wrote {rep.path}")
    _exit_if_untrusted(rep.status_counts, "row(s)")


# ----------------------------------------------------------------------------------------------
# record spectrum
# ----------------------------------------------------------------------------------------------
@app.command("record-spectrum")
@_guarded
def record_spectrum(
    record: str = typer.Option("elcentro", help="record file (.AT2 or two-column text), or 'elcentro' (packaged El Centro 1940 NS)"),
    model: ModelKind = typer.Option(ModelKind.rigid, help="rigid, spring, spring-flexible"),
    tan_alpha: float = typer.Option(0.2, help="slenderness tanα"),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′"),
    heights: str = typer.Option("1,2,3,5,7,10,15,20", help="body heights 2h [m]: '1,2,5' or 'a:b:n'"),
    scales: str = typer.Option(
        "0.5:12:16",
        help="record factors of the vmapped sweep ('1,2,5' or 'a:b:n'); the first that overturns is then refined by "
        "bisection. A coarse sweep is cheap (a vmapped record run costs about as much per lane as a bisection step) "
        "but can miss a narrow overturning window between two factors",
    ),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                 "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    refine: int = typer.Option(8, help="bisections refining the least overturning factor (resolution: sweep step / 2^refine)"),
    out: str = typer.Option("out/record_spectrum", help="output stem: <out>.nc, <out>.csv, <out>.png; a folder (or a path "
                            "ending in /) means <out>/record_spectrum.*"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
    yes: bool = typer.Option(False, "--yes", help="run a sweep estimated beyond 1 h"),
):
    """Least scale factor of a record that overturns the body, per height (paper figure 10)."""
    from ._files import output_stem, write_atomically
    from ._validate import JaxrockInputError, check_writable
    from .plotting import plot_record_spectrum
    from .spectra import record_overturning_scale

    hs = parse_values("--heights", heights)
    sc = parse_values("--scales", scales)
    if refine < 0:
        raise JaxrockInputError(f"--refine = {refine}; valid: an integer >= 0")
    m = build_model(model, float(hs[0]), tan_alpha, tan_alpha_base)
    exc, desc = _excitation(m.block, "symmetric", record, 1.0, None, None, None, None, units)
    out = output_stem(out, "record_spectrum")
    for suffix in (".nc", ".csv", ".png"):
        check_writable("--out", Path(f"{out}{suffix}"))
    _hold(out, "--out")
    per_run = RECORD_RUN_SECONDS * CELL_SECONDS[model.value] / CELL_SECONDS["rigid"] * float(exc.t_end - exc.t_start) / 40.0
    _estimate(hs.size * (sc.size + refine), model.value, yes, what="record runs", per_cell=per_run)
    t0 = time.perf_counter()
    rs = record_overturning_scale(m, exc, hs, sc, refine=refine, progress=not quiet)
    seconds = time.perf_counter() - t0
    rs = type(rs)(height=rs.height, scale=rs.scale, bracket_low=rs.bracket_low,
                  attrs={**rs.attrs, "model_kind": model.value, "history": _history()})
    nc = rs.save(Path(f"{out}.nc"))
    csv_path = Path(f"{out}.csv")
    lines = ["height,least_scale,bracket_low"] + [f"{float(h)!r},{float(s)!r},{float(lo)!r}" for h, s, lo in zip(rs.height, rs.scale, rs.bracket_low)]
    write_atomically(csv_path, lambda tmp: tmp.write_text("\n".join(lines) + "\n"))
    import matplotlib.pyplot as plt

    fig = plot_record_spectrum([rs], [f"{model.value}, tanα = {tan_alpha:g}"], path=Path(f"{out}.png"),
                               title=f"least overturning factor of {desc}")
    plt.close(fig)
    typer.echo(f"{desc}; {model.value} model, tanα = {tan_alpha:g}; {len(hs)} heights × {len(sc)} factors in {seconds:.1f} s")
    typer.echo(f"{'2h [m]':>8} {'least factor':>13}")
    for h, s in zip(rs.height, rs.scale):
        typer.echo(f"{h:8.3g} {('> %g' % sc[-1]) if not np.isfinite(s) else ('%.4g' % s):>13}")
    typer.echo(f"wrote {nc}, {csv_path}, {out}.png")


# ----------------------------------------------------------------------------------------------
# calibrate
# ----------------------------------------------------------------------------------------------
@app.command()
@_guarded
def calibrate(
    out: Path = typer.Option(Path("out/calibration"), help="output folder (calibration.csv and the figures)"),
    tan_alphas: Optional[str] = typer.Option(None, help="slenderness values to calibrate at ('0.1,0.2,0.3' or 'a:b:n'; default 0.05:0.35:13)"),
    max_iter: int = typer.Option(300, help="optimiser iterations at most"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress bar"),
):
    """Calibrate the spring model's damper c̄ against the rigid model's η⁴ (paper eq. 17, figure 7)."""
    # Thin wrapper over jaxrock.calibration.calibration_report (owned by the calibration module).
    from ._validate import JaxrockInputError, check_range, check_writable
    from .calibration import calibration_report

    _check_count("--max-iter", max_iter)
    check_writable("--out", out / "calibration.csv")
    ta = None
    if tan_alphas is not None:
        ta = parse_values("--tan-alphas", tan_alphas)
        check_range("--tan-alphas", ta, 0.0, 1.0, lo_open=True, hi_open=True)
        if np.unique(ta).size < 3:
            raise JaxrockInputError(f"--tan-alphas = {tan_alphas!r}: {np.unique(ta).size} distinct value(s); "
                                    "the power-law fit c̄ = k (α/0.1)^n needs at least 3")
    t0 = time.perf_counter()
    rep = calibration_report(out, tan_alphas=ta, progress=not quiet, max_iter=max_iter)
    typer.echo(rep.format_table())
    typer.echo(f"{time.perf_counter() - t0:.1f} s; wrote " + ", ".join(str(p) for p in rep.files.values()))
    stuck = [f"{r['tan_alpha']:g}" for r in rep.table if not r["converged"]]
    if stuck:
        typer.echo(f"Warning: c̄ did not converge in --max-iter {max_iter} iterations at tanα = {', '.join(stuck)} "
                   f"({len(stuck)} of {len(rep.table)}): raise --max-iter", err=True)
        raise typer.Exit(EXIT_UNTRUSTED)


def main():  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    app()
