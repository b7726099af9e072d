"""`jaxrock identify`: a model's parameters fitted to a measured rotation history, with their
uncertainty (`jaxrock.identify`, issue 62).

The measurement is read here, without JAX (`read_measured`: CSV, or netCDF-3 through xarray's
scipy engine), so that a bad file, a bad `--free` name or a parameter the model lacks is refused in
one line before anything is imported or compiled."""

from __future__ import annotations

import math
import time
from enum import Enum
from pathlib import Path
from typing import NamedTuple, Optional

import numpy as np
import typer

from .guards import EXIT_UNTRUSTED, report, say, _guarded, _hold
from ..scene import DEFAULT_MODEL, DEFAULT_PULSE, builtin_record_names, takes
from .options import model_option, ModelKind, build_model, split_params, with_params
from .app import app, FORCE_OPTION, JSON_OPTION, SMOOTHING_DEFAULTS

# `jaxrock.analyses.identify.FREE`'s names and its `LOSSES`, here without importing JAX (tests/test_cli_identify.py
# holds them equal)
FREE_NAMES = ("eta", "cbar", "smoothing", "zeta", "E", "height")
LOSS_NAMES = ("auto", "multiple", "single")
LossKind = Enum("LossKind", {k: k for k in LOSS_NAMES}, type=str)
SPRING_BACKBONE = "tanh"  # identify refuses a kinked backbone: its spring models are built with this smooth one

# a measurement's columns (CSV header, netCDF variable): spelling → (quantity, unit)
COLUMNS = {"t": ("t", "s"), "time": ("t", "s"), "t[s]": ("t", "s"), "time[s]": ("t", "s"),
           "theta": ("theta", "rad"), "theta[rad]": ("theta", "rad"),
           "top": ("top", "m"), "top[m]": ("top", "m"), "u_top": ("top", "m"), "u_top[m]": ("top", "m"),
           "ag": ("ag", "m/s2"), "ag[m/s2]": ("ag", "m/s2"), "ground_acceleration": ("ag", "m/s2"), "ag[g]": ("ag", "g")}
EXPECTED = "columns t [s] and theta [rad], optionally top [m] (the top displacement) and ag [m/s²] or ag[g] [g]"
MISSING = ("", "nan", "na", "n/a", "-")  # a theta or top cell that is a missing sample (read as NaN)


class Measurement(NamedTuple):
    """A measured history as read: times [s], θ [rad] (NaN: missing), the ground acceleration in
    `ag_units` (None: not measured), the line (CSV) or sample (netCDF) of each time, and the top
    displacement [m] (NaN: missing; None: not measured)."""

    t: np.ndarray
    theta: np.ndarray
    ag: np.ndarray | None
    ag_units: str
    lines: list[int]
    top: np.ndarray | None = None


def _column_key(name: str) -> str:
    return name.strip().lower().replace(" ", "")


def _columns(path: Path, names) -> dict[str, tuple[str, str]]:
    """Which of `names` (a header, variables) are which quantity: one each, t and theta present."""
    from .._validate import JaxrockInputError

    found: dict[str, tuple[str, str]] = {}
    for name in names:
        q = COLUMNS.get(_column_key(str(name)))
        if q is None:
            continue
        if any(v[0] == q[0] for v in found.values()):
            raise JaxrockInputError(f"MEASURED {path}: two {q[0]} columns ({', '.join(k for k, v in found.items() if v[0] == q[0])}, "
                                    f"{name}); expected {EXPECTED}, each once")
        found[str(name)] = q
    for need in ("t", "theta"):
        if not any(v[0] == need for v in found.values()):
            have = ", ".join(str(n) for n in names) or "none"
            raise JaxrockInputError(f"MEASURED {path}: no {need} column (found: {have}); expected {EXPECTED}")
    return found


def _check(path: Path, m: Measurement, where: str) -> Measurement:
    """The checks `jaxrock.Measured` makes, here before JAX: ≥ 8 samples, t finite and strictly
    increasing, a finite θ, ag finite."""
    from .._validate import JaxrockInputError

    if m.t.size < 8:
        raise JaxrockInputError(f"MEASURED {path}: {m.t.size} sample(s); identification needs at least 8")
    bad = np.flatnonzero(~np.isfinite(m.t))
    if bad.size:
        raise JaxrockInputError(f"MEASURED {path}: {where} {m.lines[bad[0]]}: t = {m.t[bad[0]]}; every time must be a finite number [s]")
    steps = np.diff(m.t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise JaxrockInputError(f"MEASURED {path}: {where} {m.lines[k + 1]}: t = {m.t[k + 1]:g} s does not exceed the previous "
                                f"{m.t[k]:g} s; t must be strictly increasing")
    if not np.any(np.isfinite(m.theta)):
        raise JaxrockInputError(f"MEASURED {path}: theta holds no finite sample")
    if m.top is not None and not np.any(np.isfinite(m.top)):
        raise JaxrockInputError(f"MEASURED {path}: top holds no finite sample")
    if m.ag is not None and not np.all(np.isfinite(m.ag)):
        k = int(np.flatnonzero(~np.isfinite(m.ag))[0])
        raise JaxrockInputError(f"MEASURED {path}: {where} {m.lines[k]}: ag = {m.ag[k]}; a measured ground acceleration must be "
                                "finite at every sample (a missing θ may be left empty, not a missing ag)")
    return m


def _read_csv(path: Path) -> Measurement:
    import csv

    from .._validate import JaxrockInputError
    from ..io.tables import csv_text

    rows = [(n, r) for n, r in enumerate(csv.reader(csv_text(path, "measured")), start=1)
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]  # blank lines, comments (a jaxrock footer)
    if not rows:
        raise JaxrockInputError(f"MEASURED {path}: the file is empty; expected a CSV with {EXPECTED}")
    header = [c.strip() for c in rows[0][1]]
    found = _columns(path, header)
    index = {q: header.index(name) for name, (q, _) in found.items()}
    lines, values = [], {q: [] for q in index}
    for n, r in rows[1:]:
        if len(r) != len(header):
            raise JaxrockInputError(f"MEASURED {path}: line {n}: {len(r)} value(s) for {len(header)} columns ({', '.join(header)})")
        for q, i in index.items():
            cell = r[i].strip()
            if q in ("theta", "top") and cell.lower() in MISSING:
                values[q].append(math.nan)
                continue
            try:
                values[q].append(float(cell))
            except ValueError:
                raise JaxrockInputError(f"MEASURED {path}: line {n}: {header[i]} = {cell!r} is not a number"
                                        + ("; a missing sample is an empty cell or nan" if q in ("theta", "top") else "")) from None
        lines.append(n)
    ag_units = next((u for q, u in found.values() if q == "ag"), "m/s2")
    return _check(path, Measurement(np.asarray(values["t"]), np.asarray(values["theta"]),
                                    np.asarray(values["ag"]) if "ag" in values else None, ag_units, lines,
                                    np.asarray(values["top"]) if "top" in values else None), "line")


def _read_netcdf(path: Path) -> Measurement:
    from .._validate import JaxrockInputError

    with open(path, "rb") as fh:
        magic = fh.read(8)
    if magic.startswith(b"\x89HDF"):
        raise JaxrockInputError(f"MEASURED {path}: a netCDF-4 (HDF5) file; jaxrock reads netCDF-3 (classic or 64-bit offset, what it "
                                "writes itself) or CSV: convert it, e.g. xarray's to_netcdf(..., format='NETCDF3_64BIT')")
    if not magic.startswith(b"CDF"):
        raise JaxrockInputError(f"MEASURED {path}: not a netCDF file (no 'CDF' signature); expected netCDF-3 or a CSV with {EXPECTED}")
    import xarray as xr

    try:
        ds = xr.open_dataset(path, engine="scipy").load()
    except Exception as e:  # a truncated or malformed file: its reader's reason, in one line
        raise JaxrockInputError(f"MEASURED {path}: cannot be read as netCDF ({type(e).__name__}: {e})") from None
    names = list(ds.variables)
    found = _columns(path, names)
    arrays = {}
    for name, (q, unit) in found.items():
        v = ds[name]
        if v.ndim != 1:
            raise JaxrockInputError(f"MEASURED {path}: {name} has {v.ndim} dimensions {v.dims}; expected one (time)")
        arrays[q] = np.asarray(v.values, dtype=float)
        if q == "ag" and str(v.attrs.get("units", "")).strip().lower() == "g":
            unit = "g"
        found[name] = (q, unit)
    sizes = {q: a.size for q, a in arrays.items()}
    if len(set(sizes.values())) > 1:
        raise JaxrockInputError(f"MEASURED {path}: the variables have different lengths ({sizes}); expected one time axis")
    ag_units = next((u for q, u in found.values() if q == "ag"), "m/s2")
    return _check(path, Measurement(arrays["t"], arrays["theta"], arrays.get("ag"), ag_units, list(range(1, arrays["t"].size + 1)),
                                    arrays.get("top")), "sample")


def read_measured(path) -> Measurement:
    """A measured history from a CSV file (a header `t,theta[,top][,ag | ag[g]]`; `#` lines are comments;
    an empty or `nan` θ or top is a missing sample) or a netCDF-3 file (`.nc`: variables `t` or `time`,
    `theta`, optional `top` or `u_top` [m], optional `ag` in m/s², or in g where its `units` say so), checked.
    `jaxrock simulate --save` files read as they are (`ground_acceleration`, `u_top`). Imports no JAX."""
    from .._validate import JaxrockInputError

    path = Path(path)
    if not path.exists():
        raise JaxrockInputError(f"MEASURED {path}: no such file; expected a CSV or netCDF file with {EXPECTED}")
    if not path.is_file():
        raise JaxrockInputError(f"MEASURED {path}: is not a regular file (a folder, FIFO or device); expected a CSV or netCDF file")
    return _read_netcdf(path) if path.suffix.lower() in (".nc", ".nc3", ".cdf") else _read_csv(path)


def free_names(text: str, kind: str) -> tuple[str, ...]:
    """`--free`: names separated by commas, each once, each one the model kind has (`jaxrock.scene.takes`;
    the height every kind has)."""
    from .._validate import JaxrockInputError
    from .grammar import flag_of

    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise JaxrockInputError(f"--free {text!r}: names no parameter; valid: comma-separated, of {', '.join(FREE_NAMES)}")
    has = [n for n in FREE_NAMES if n == "height" or kind in takes(n)]
    for n in names:
        if n not in FREE_NAMES:
            raise JaxrockInputError(f"--free {n}: not a parameter identify fits; valid: {', '.join(FREE_NAMES)} "
                                    f"(--model {kind}: {', '.join(has)})")
        if n not in has:
            raise JaxrockInputError(f"--free {n}: --model {kind} has no {n} ({flag_of(n)} belongs to --model {' / '.join(takes(n))}); "
                                    f"valid for --model {kind}: {', '.join(has)}")
    if len(set(names)) < len(names):
        raise JaxrockInputError(f"--free {text!r}: names a parameter twice; valid: each of {', '.join(has)} once")
    return tuple(names)


def _excitation_of(path: Path, m: Measurement, record: Optional[str], units: Optional[str]):
    """The measurement's ground motion: its ag column as a `Record` from t = 0, the `--record`, or still ground."""
    from .._validate import JaxrockInputError

    if m.ag is not None:
        if record is not None:
            raise JaxrockInputError(f"--record {record}: MEASURED {path} has its own ground acceleration column; give one of them")
        if units is not None:
            raise JaxrockInputError(f"--units applies to --record files; the ag column of MEASURED {path} names its unit (ag: m/s², ag[g]: g)")
        from ..excitation import Record
        from ..io.records import _uniform_step, unit_factor

        dt = _uniform_step(m.t, m.lines, f"MEASURED {path}")  # a record's samples are uniform
        lead = m.t[0] / dt
        if m.t[0] < 0 or abs(lead - round(lead)) > 1e-6 * max(1.0, lead):
            raise JaxrockInputError(f"MEASURED {path}: with a ground acceleration column, t starts at 0 or a later multiple of its step "
                                    f"{dt:g} s (the record's origin is t = 0); it starts at {m.t[0]:g} s")
        acc = np.concatenate([np.zeros(int(round(lead))), m.ag * unit_factor(m.ag_units, f"MEASURED {path}")])
        return Record(acc, dt, name=path.stem), f"its ground acceleration ({m.ag.size} samples at {dt:g} s)"
    if record is not None:
        from .options import _excitation

        return _excitation(None, DEFAULT_PULSE, record, 1.0, None, None, None, None, units)
    if units is not None:
        raise JaxrockInputError("--units applies to --record files; without --record the test is free rocking")
    from ..excitation import StillGround

    return StillGround(), "free rocking (still ground)"


@app.command()
@_guarded
@with_params(pulses=False)
def identify(
    measured: Path = typer.Argument(..., show_default=False,
                                    help=f"the measured history: a CSV with {EXPECTED} at the same times ('#' lines are comments; an "
                                    "empty or nan θ is a missing sample, skipped), or a netCDF-3 file (.nc: variables t or time, theta, "
                                    "optional top or u_top [m] and ag; netCDF-4/HDF5 files are not read: jaxrock's dependencies read netCDF-3 only). "
                                    "Without ag nor --record the test is free rocking"),
    free: str = typer.Option(..., help=f"the parameters to fit, comma-separated: {', '.join(FREE_NAMES)} (eta: rigid; cbar, smoothing: "
                             "spring models; zeta, E: spring-flexible; height: 2h at fixed slenderness, any model); they start from "
                             "the model's values (the flags below, else the defaults)", show_default=False),
    height: float = typer.Option(..., help="full height 2h [m] of the measured body", show_default=False),
    tan_alpha: float = typer.Option(..., help="slenderness tanα = b/h of the measured body, in (0, 1)", show_default=False),
    tan_alpha_base: Optional[float] = typer.Option(None, help="extended rigid base tanα′ = b′/h"),
    model: ModelKind = model_option(DEFAULT_MODEL),
    smoothing: Optional[float] = typer.Option(None, help=f"spring: pre-yield rotation θs/α′ in (0, 1) (default "
                                              f"{SMOOTHING_DEFAULTS.split(', ')[-1]}). The spring models are built with the smooth "
                                              f"{SPRING_BACKBONE} backbone: identification refuses the kinked bilinear one"),
    record: Optional[str] = typer.Option(None, help=f"the ground motion of the test when MEASURED has no ag column: a record file (.AT2 "
                                         f"or two-column), a pair 'H + V', or a packaged record ({builtin_record_names()}); its t = 0 is "
                                         "MEASURED's t = 0"),
    units: Optional[str] = typer.Option(None, help="acceleration units of the --record file: a two-column file is read in g unless this "
                                        "says otherwise (m/s2, cm/s2, mm/s2, in/s2, ft/s2); an .AT2 file states its own"),
    loss: LossKind = typer.Option(LossKind.auto, help="auto: the whole history, and where it leaves more than the noise, multiple "
                                  "shooting from the measured peaks and the whole history again from its estimate; single: the whole "
                                  "history from its first state; multiple: the segments between the measured peaks"),
    boot: int = typer.Option(50, "--boot", "--n-boot", help="bootstrap resamplings (of the segments between peaks, or of the residuals "
                             "of a whole-history fit), >= 0; 0: the Laplace interval only"),
    seed: int = typer.Option(0, help="the bootstrap's random seed, >= 0"),
    out: Path = typer.Option(Path("out/identify"), help="output folder: identify.csv (one row per parameter) and identify.png "
                             "(measured and fitted θ/α′, residuals, bootstrap histograms)"),
    as_json: bool = JSON_OPTION,
    force: bool = FORCE_OPTION,
    **params: Optional[float],
):
    """Fit a model's parameters (η, c̄, θs, ζ, E, 2h) to a measured rotation history θ(t), with their
    uncertainty: prints the estimates ± standard error, 95 % intervals, correlations and a flag for
    any parameter the measurement does not determine; exit code 1 when the fit did not converge or
    a parameter is not identifiable (the files are written)."""
    from .._validate import JaxrockInputError
    from ..io.files import check_output

    kind = ModelKind(model).value
    names = free_names(free, kind)
    if boot < 0:
        raise JaxrockInputError(f"--boot (--n-boot) = {boot}; valid: an integer >= 0 (0: the Laplace interval only)")
    if seed < 0:
        raise JaxrockInputError(f"--seed = {seed}; valid: an integer >= 0")
    data = read_measured(measured)
    csv_path, png = out / "identify.csv", out / "identify.png"
    for path in (csv_path, png):
        check_output("--out", path)
    model_kw, _ = split_params(params)
    spring = kind in takes("backbone")
    m = build_model(model, height, tan_alpha, tan_alpha_base, smoothing=smoothing,
                    backbone=SPRING_BACKBONE if spring else None, **model_kw)  # JAX from here on
    exc, desc = _excitation_of(measured, data, record, units)
    _hold(out, "--out")
    from ..analyses.identify import Measured, identify as fit
    from ..io.tables import write_table

    t0 = time.perf_counter()
    res = fit(Measured(data.t, data.theta, exc, top=data.top), m, names, loss=loss.value, n_boot=boot, seed=seed, warn=False)
    seconds = time.perf_counter() - t0
    base = "" if tan_alpha_base is None else f", tanα′ = {tan_alpha_base:g}"
    what = (f"{kind} model{f' ({SPRING_BACKBONE} backbone)' if spring else ''}, 2h = {height:g} m, tanα = {tan_alpha:g}{base}; "
            f"{measured.name}: {desc}")
    say(what)
    say(str(res))
    footer = (f"jaxrock identify: {what}; {res.loss} shooting, {res.n_segments} segment(s), {res.n_samples} samples, RMS residual "
              f"{res.rms:.6g} rad, noise {res.noise:.6g} rad, {'converged' if res.converged else 'NOT converged'}, {boot} bootstrap "
              f"resamplings (seed {seed})")
    written = [write_table(csv_path, res.table(), footer=footer)]
    import matplotlib.pyplot as plt

    from ..plotting import plot_identification

    plt.close(plot_identification(res, png, title=what.replace("; ", "\n")))
    written.append(png)
    say(f"{seconds:.1f} s (fit {res.seconds[0]:.1f} s, bootstrap {res.seconds[1]:.1f} s); wrote {', '.join(str(w) for w in written)}")
    report("identify", {"measured": measured, "model": kind, "height": height, "tan_alpha": tan_alpha, "tan_alpha_base": tan_alpha_base,
                        "excitation": desc, "loss": res.loss, "parameters": res.table(), "correlation": res.correlation,
                        "converged": res.converged, "iterations": res.iterations, "rms": res.rms, "noise": res.noise,
                        "n_segments": res.n_segments, "n_samples": res.n_samples, "n_boot": boot, "seed": seed, "seconds": seconds,
                        "files": written},
           {"height": "m", "rms": "rad", "noise": "rad", "seconds": "s",
            "parameters": "each parameter's own: E Pa, height m, the others 1"})
    bad = [n for n, ok in zip(res.free, res.identifiable) if not ok]
    if bad:
        typer.echo(f"Warning: the measurement does not determine {', '.join(bad)} (a singular or flat loss): its interval is its whole "
                   "range; free fewer parameters, or measure a test that excites them (impacts for eta, a flexible response for E)",
                   err=True)
    if not res.converged:
        typer.echo("Warning: the fit did not converge (or a run failed): check the residuals in identify.png, start nearer "
                   "(the parameters' flags), or free fewer parameters", err=True)
    if bad or not res.converged:
        raise typer.Exit(EXIT_UNTRUSTED)
