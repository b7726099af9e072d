"""The command line's options: list and axis values, the model, integrator and excitation of a scene
from its flags (checked here, built as a scenes-file row is), and the printed summaries."""

from __future__ import annotations

import math
from enum import Enum
from pathlib import Path
from typing import Optional

import numpy as np

from ..scene import BACKBONES, PULSES, model_kinds

MAX_LIST = 100_000  # values of a list option ('a:b:n')


# the vocabulary's kinds (`jaxrock.scene`) and the backbones as command-line choices; a member's
# name is its value with '-' as '_' (ModelKind.spring_flexible)
ModelKind = Enum("ModelKind", {k.replace("-", "_"): k for k in model_kinds()}, type=str)
PulseKind = Enum("PulseKind", {k: k for k in PULSES}, type=str)


BackboneKind = Enum("BackboneKind", {k: k for k in BACKBONES}, type=str)
LIST_HELP = "one value, or several ('1,2,5' or 'a:b:n'): an axis of the sweep"


def with_params(lists: bool = False, pulses: bool = True):
    """A command taking one option per declared parameter of the model kinds and pulse kinds
    (`jaxrock.scene.model_params`, `pulse_params`: the built-in kinds' and any registered before
    the command line was built, a plugin's included), its flag (`Param.flag`) and help generated
    from the declaration; the command receives them as keywords (None: not given; split them with
    `split_params`). `lists`: each takes a sweep axis ('1,2,5', 'a:b:n') as text; `pulses`: the
    pulse kinds' parameters too (False: a command without pulses, the model kinds' only)."""
    import inspect

    import typer

    from ..scene import model_params, parameter_help, pulse_params

    def decorate(command):
        sig = inspect.signature(command)
        own = [q for q in sig.parameters.values() if q.kind is not q.VAR_KEYWORD]
        declared = {**model_params(), **(pulse_params() if pulses else {})}
        added = [inspect.Parameter(p.name, inspect.Parameter.KEYWORD_ONLY, annotation=Optional[str] if lists else Optional[float],
                                   default=typer.Option(None, p.flag, help=parameter_help(p.name) + (f": {LIST_HELP}" if lists else "")))
                 for p in declared.values() if p.name not in sig.parameters]
        command.__signature__ = sig.replace(parameters=own + added)
        return command

    return decorate


def split_params(params: dict) -> tuple[dict, dict]:
    """The keywords of `with_params` as (model parameters, pulse parameters), those given only."""
    from ..scene import pulse_params

    given = {k: v for k, v in params.items() if v is not None}
    return {k: v for k, v in given.items() if k not in pulse_params()}, {k: v for k, v in given.items() if k in pulse_params()}


def _check_count(name: str, n: int):
    from .._validate import JaxrockInputError

    if n < 1:
        raise JaxrockInputError(f"{name} = {n}; valid: an integer >= 1")


def figure_path(flag: str, text: str) -> Path:
    """A figure file the user names: not a folder (an existing one, or a name ending in a
    separator), not a device or FIFO; without a suffix it gets ".png" (what matplotlib writes, now
    also what is said); a suffix matplotlib cannot write is refused."""
    import os

    from matplotlib.backend_bases import FigureCanvasBase

    from .._validate import JaxrockInputError, check_file_kind
    from ..io.files import check_output

    if not text or text.endswith((os.sep, "/")) or Path(text).is_dir():
        raise JaxrockInputError(f"{flag} {text!r}: names a folder; expected a figure file, e.g. {flag} theta.png")
    path = Path(text)
    check_file_kind(flag, path)  # before a suffix is added: /dev/full is not /dev/full.png
    formats = FigureCanvasBase.get_supported_filetypes()
    if not path.suffix:
        path = path.with_name(path.name + ".png")
    elif path.suffix[1:].lower() not in formats:
        raise JaxrockInputError(f"{flag} {path}: matplotlib cannot write {path.suffix!r} files; valid: {', '.join(sorted(formats))}")
    check_output(flag, path)
    return path


MAX_PLOT_POINTS = 1_000_000  # simulate --plot: saved time points


def _check_refine(refine: int):
    from .._validate import JaxrockInputError
    from ..scene import MAX_REFINE

    if not 0 <= refine <= MAX_REFINE:
        raise JaxrockInputError(f"--refine = {refine}; valid: an integer in [0, {MAX_REFINE}] (each bisection halves the bracket)")


def parse_values(name: str, text: str) -> np.ndarray:
    """A list option: "1,2,5" (values) or "a:b:n" (n values evenly spaced from a to b)."""
    import re

    from .._validate import JaxrockInputError

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


def model_option(default: str, many: bool = False):
    """`--model`, one grammar in every command: kinds separated by commas ("rigid,spring"), parsed
    into a `ModelKind` (a list of them where the command runs several, `many`); an unknown kind, a
    kind named twice, or several where the command runs one, is refused in one line."""
    import typer

    def parse(text):
        if isinstance(text, (ModelKind, list)):
            return text
        kinds = [k.strip() for k in str(text).split(",") if k.strip()]
        bad = [k for k in kinds if k not in model_kinds()]
        if not kinds or bad or len(set(kinds)) < len(kinds):
            what = f"not a model kind: {', '.join(bad)}" if bad else ("no model" if not kinds else "a model named twice")
            raise typer.BadParameter(f"{what}; valid: {'comma-separated, each once, of ' if many else ''}{', '.join(model_kinds())}")
        if not many and len(kinds) > 1:
            raise typer.BadParameter(f"{text!r} names {len(kinds)}; this command runs one model kind, one of {', '.join(model_kinds())}")
        return [ModelKind(k) for k in kinds] if many else ModelKind(kinds[0])

    from ..scene import parameter_help

    what = (f"model kinds, comma-separated, each running the same work ({' | '.join(model_kinds())})" if many
            else parameter_help("model", valid=False))
    return typer.Option(default, parser=parse, metavar="KIND[,KIND...]" if many else "KIND", help=what)


def build_model(model: ModelKind | str, height: float, tan_alpha: float, tan_alpha_base=None, *, undamped=False, **parameters):
    """The model of a CLI scene: every parameter flag given (None: not given) must be one the model
    kind takes (the registry says which, `jaxrock.scene.takes`); `undamped` sets each damping
    parameter of the kind to its undamped value (`jaxrock.scene.UNDAMPED`). Built by
    `scene_model`, as a scenes-file row is."""
    from .._validate import JaxrockInputError
    from ..scene import UNDAMPED, check_slenderness, takes
    from .grammar import flag_of

    kind = ModelKind(model).value
    check_slenderness(height, tan_alpha, tan_alpha_base)  # refused before JAX is imported
    given = {k: v for k, v in parameters.items() if v is not None}
    for name in given:
        if kind not in takes(name):
            raise JaxrockInputError(f"{flag_of(name)} applies to --model {' / '.join(takes(name))} only, not {kind}")
    if undamped:
        if not any(kind in takes(k) for k in UNDAMPED):
            raise JaxrockInputError(f"--undamped: --model {kind} has no damping parameter to switch off "
                                    f"({', '.join(flag_of(k) for k in UNDAMPED)} belong to other kinds)")
        for name in (k for k in UNDAMPED if kind in takes(k)):
            if name in given:
                raise JaxrockInputError(f"give --undamped or {flag_of(name)}, not both")
            given[name] = UNDAMPED[name]
    if "backbone" in given:
        given["backbone"] = BackboneKind(given["backbone"]).value
    from ..construct import scene_model
    from ..geometry import Block

    return scene_model(kind, Block.from_slenderness(height, tan_alpha, tan_alpha_base), **given)


def _integrator(model: ModelKind, tol: Optional[float]):
    """`--tol`: generalized-α at that local tolerance for the spring models, its global error
    checked (`Checked`: status `inaccurate` beyond 1e-2 in max θ/α); None: the default."""
    if tol is None:
        return None
    from .._validate import JaxrockInputError, check_range
    from ..spring import Checked, GeneralizedAlpha

    if model == ModelKind.rigid:
        raise JaxrockInputError("--tol selects the spring model's generalized-α integrator; the rigid model takes none")
    check_range("--tol", tol, 0.0, 0.1, lo_open=True, hi_open=True)  # the companion run at 10x the tolerance stays below 1
    return Checked(GeneralizedAlpha(rtol=tol, atol=tol))


SENSITIVITY_HELP = ("carry each run's tangent along its scale: report its sensitivity and count the verdicts a relative perturbation "
                    "of 1e-7 could flip (uncertain; jaxrock.sensitivity); costs about 1.4x a record run, 2x a pulse cell")


def uncertain_line(flags, runs=None, what: str = "cells", n: int | None = None) -> str:
    """How many of `flags` (None: not computed) are uncertain verdicts; `runs`: the flags of the
    runs behind them (a suite's sweep), counted too."""
    from ..outputs import PERTURBATION

    if flags is None:
        return "verdict uncertain: not computed (--sensitivity judges each verdict)"
    flags = np.asarray(flags, dtype=bool)
    n = flags.size if n is None else n
    behind = "" if runs is None else f"; {int(np.sum(runs))} of the sweep's {np.size(runs):,} runs"
    return (f"verdict uncertain: {int(flags.sum())} of {n:,} {what}{behind} (a relative perturbation of {PERTURBATION:g} of the scale "
            "could flip them: jaxrock.sensitivity)")


def _grid_line(o, values) -> str:
    """A summary output over a spectrum's cells: a flag's count and share, else its range."""
    if o.kind == "bool":
        return f"{o.label}: {int(values.sum())} cells ({100 * values.mean():.1f} %)"
    fin = values[np.isfinite(values)]
    unit = "" if o.units == "1" else f" {o.units}"
    if not fin.size and o.absent is not None and np.isnan(o.absent) and np.isnan(values).all():
        return f"{o.label}: not computed"
    return f"{o.label}: " + (f"{fin.min():.4g} … {fin.max():.4g}{unit}" if fin.size else "none")


def spectrum_summary(spec, seconds: float) -> str:
    """The summary `jaxrock spectrum` prints, in the command line's words (`--model`'s and `--pulse`'s kinds)."""
    from ..outputs import OUTPUTS, computed
    from ..scene import pulse_kind_of
    from ..results import STATUS_NAMES, SUMMARY

    a = spec.attrs
    n_a, n_w = spec.max_theta.shape
    n = n_a * n_w
    tan_col = float(a["width"]) / float(a["height"])
    base = "" if abs(tan_col - float(a["tan_alpha"])) < 1e-12 else f" on a base tanα′ = {float(a['tan_alpha']):.4g}"
    lines = [
        f"spectrum: {a.get('model_kind', a.get('model'))} model, {pulse_kind_of(str(a.get('pulse')))} pulse, 2h = {float(a['height']):g} m, tanα = {tan_col:.4g}{base} "
        f"(rocking α = {float(a['alpha']):.4g} rad, p = {float(a['p']):.4g} rad/s)",
        f"grid: {n_w} ω_p/p in [{spec.omega_ratio[0]:g}, {spec.omega_ratio[-1]:g}] × {n_a} a_p/(g tanα) in "
        f"[{spec.accel_ratio[0]:g}, {spec.accel_ratio[-1]:g}] = {n} cells in {seconds:.1f} s ({1e3 * seconds / n:.2f} ms/cell)",
        *(_grid_line(o, getattr(spec, o.name)) for o in SUMMARY if o.name != "uncertain"),
        uncertain_line(spec.uncertain if computed(OUTPUTS["uncertain"], {"sensitivity": spec.sensitivity}) else None),
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


def check_pulse_params(pulse: str, given: dict, record: bool = False) -> None:
    """Refuse, in one line, a pulse parameter flag the pulse kind does not take (or any, with a record)."""
    from .._validate import JaxrockInputError
    from ..scene import PULSE_PARAMS, pulse_params, pulse_takes

    for name in given:
        if record or name not in PULSE_PARAMS.get(pulse, {}):
            raise JaxrockInputError(f"{pulse_params()[name].flag} applies to --pulse {' / '.join(pulse_takes(name))} only, "
                                    f"not {'--record' if record else pulse}")


def _excitation(block, pulse: str, record: Optional[str], scale: float, a_p, accel_ratio, omega_p, omega_ratio, units=None,
                pulse_params: dict | None = None):
    from .._validate import JaxrockInputError, check_range
    from ..construct import scene_pulse
    from ..geometry import pulse_of_ratios, ratios_of_pulse
    from ..scene import is_builtin_record

    pulse_params = pulse_params or {}
    check_pulse_params(pulse, pulse_params, record is not None)
    if record is not None:
        for name, v in (("--a-p", a_p), ("--accel-ratio", accel_ratio), ("--omega-p", omega_p), ("--omega-ratio", omega_ratio)):
            if v is not None:
                raise JaxrockInputError(f"{name} applies to pulses, not to --record")
        check_range("--scale", scale, 0.0, math.inf, hi_open=True)
        if is_builtin_record(record) and not Path(record).exists():
            from ..io.records import builtin_record

            if units is not None:
                raise JaxrockInputError(f"--units applies to --record files; the packaged record {record} needs none")
            rec = builtin_record(record)
        else:
            from ..io.records import read_record
            from ..scene import builtin_record_names

            parts = [p.strip() for p in record.split(" + ")] if " + " in record and not Path(record).exists() else [record]
            for part in parts:
                if len(parts) > 2 or not Path(part).exists():
                    raise JaxrockInputError(f"--record {record}: {'a pair is two files, HORIZONTAL + VERTICAL' if len(parts) > 2 else f'{part}: file not found'}"
                                            f"{'' if len(parts) > 1 else f', nor a packaged record ({builtin_record_names()})'}")
            if len(parts) == 2:
                from ..io.records import read_record_pair

                rec = read_record_pair(*parts, units=units)
            else:
                rec = read_record(record) if units is None else read_record(record, units=units)
        return rec.scaled(scale), f"{rec.name} × {scale:g}"
    if units is not None:
        raise JaxrockInputError("--units applies to --record files, not to pulses")
    if a_p is not None and accel_ratio is not None:
        raise JaxrockInputError("give --a-p or --accel-ratio, not both")
    if omega_p is not None and omega_ratio is not None:
        raise JaxrockInputError("give --omega-p or --omega-ratio, not both")
    if a_p is None:
        accel_ratio = 4.0 if accel_ratio is None else accel_ratio
        check_range("--accel-ratio", accel_ratio)
        a_p = float(pulse_of_ratios(block, accel_ratio, 1.0)[0])
    if omega_p is None:
        if omega_ratio is None:
            omega_p = 2 * math.pi
        else:
            check_range("--omega-ratio", omega_ratio, 0.0, math.inf, lo_open=True, hi_open=True)
            omega_p = float(pulse_of_ratios(block, 1.0, omega_ratio)[1])
    exc = scene_pulse(pulse, block, {"a_p": a_p, "omega_p": omega_p, **pulse_params})
    a_r, w_r = (float(x) for x in ratios_of_pulse(block, a_p, omega_p))
    extra = "".join(f", {k} = {v:g}" for k, v in pulse_params.items())
    desc = f"{pulse} pulse a_p = {a_p:.4g} m/s² ({a_r:.4g} g tanα), ω_p = {omega_p:.4g} rad/s ({w_r:.4g} p){extra}"
    return exc, desc


def solution_summary(sol, model) -> str:
    """One scene's summary outputs (`jaxrock.results.SUMMARY`), one per line, and its status."""
    from ..results import SUMMARY, status_names

    from ..outputs import computed

    values = {o.name: np.asarray(getattr(sol, o.name)) for o in SUMMARY}
    lines = [o.line(values[o.name]) if computed(o, values) else f"{o.label}: not computed" for o in SUMMARY]
    lines += [f"status: {status_names(sol.status)}",
              f"(α = {float(model.block.alpha_r):.5g} rad, p = {float(model.block.p_r):.5g} rad/s)"]
    return "\n".join(lines)
