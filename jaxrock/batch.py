"""Batch runs from a CSV file of scenes: one scene per row → vmapped runs → a results CSV.

`jaxrock batch scenes.csv results.csv [--resume]`, or `run_scenes(scenes, results)` from Python.

Scenes file
-----------
A CSV file with a header line. Column names are case-insensitive; empty cells mean "default";
blank lines and lines whose first cell starts with `#` are skipped. Rows are numbered from 1 (the
first scene after the header). Columns:

| column | unit | meaning | valid values / default |
| --- | --- | --- | --- |
| `height` | m | full height 2h of the column | > 0, required |
| `tan_alpha` | – | slenderness tanα = b/h | (0, 1); give it or `width` |
| `width` | m | full width 2b (instead of `tan_alpha`) | > 0, width/height < 1 |
| `tan_alpha_base` | – | extended rigid base tanα′ = b′/h (paper section 5) | [tanα, 1); default: no base |
| `model` | – | `rigid` (RM), `spring` (quasi-rigid SM with added masses), `spring-flexible` (SM, elastic column) | default `rigid` |
| `pulse` | – | `symmetric` / `antisymmetric` Ricker pulse, `elcentro` (the packaged El Centro 1940 NS), or a record file path (`.AT2` or two-column text; relative to the scenes file, else to the working directory) | default `symmetric` |
| `a_p` | m/s² | pulse amplitude (any sign, ≠ 0) | pulses: give it or `accel_ratio` |
| `accel_ratio` | – | a_p/(g tanα′) | ≠ 0 |
| `omega_p` | rad/s | pulse frequency | > 0; pulses: give it or `omega_ratio` |
| `omega_ratio` | – | ω_p/p′ | > 0 |
| `scale` | – | factor on a record | ≥ 0, default 1 (records only) |
| `eta` | – | rigid impact velocity ratio (1: undamped) | [0, 1], default 1 − 1.5 sin²α′ (rigid only) |
| `cbar` | – | spring-model damper c̄ (0: undamped) | ≥ 0, default eq. 17 (spring models only) |
| `E` | Pa | Young's modulus of the column | > 0, default 30e9 (`spring-flexible` only) |
| `rho` | kg/m³ | density of the column | > 0, default 2500 (`spring-flexible` only) |
| `zeta` | – | column damping ratio, first fixed-base mode | ≥ 0, default 0.01 (`spring-flexible` only) |

Label columns are copied to the results unchanged: `id`, `name`, `label`, `group`, `note`,
`notes`, `comment`, or any name starting with `x_`. Any other column is an error that names the
closest valid one (a misspelt `modle` would otherwise run the default model). A parameter given
for a model or pulse it does not apply to (e.g. `eta` for a spring model, `scale` for a pulse) is
an error. Every row is checked before anything runs; the first bad row stops the run with a
message naming the file, the row (and its line), the column and the valid range.

Results file
------------
The column `row` (the scene's row number), the scene's input columns as given, then:
`max_theta` (max |θ|/α′; 1 = threshold when it overturned), `overturned` (0/1), `t_overturn` [s]
(`inf` when it did not overturn), `uplifted` (0/1), `t_uplift` [s] (`inf` if never),
`n_impacts` (rigid model; 0 for spring models), `status` (`ok`, or why the numbers are not to be
trusted: see `jaxrock.Status`). Results are appended after every batch, so an interrupted run
keeps its finished rows; `resume=True` (`--resume`) skips the rows already in the results file
(their inputs must be unchanged). When all rows are done the file is rewritten in row order.

How rows are batched
--------------------
Rows whose models and excitations have the same structure (model kind; pulse kind, or the
record) form one group; the group's models *and* excitations are stacked and run with one `vmap`,
in chunks of `chunk_size` rows padded to a power of two ≥ 8 (so few shapes are compiled).
Geometry, pulse parameters, scale factors, damping and material values all vary freely within a
group. Rigid groups and flexible spring groups (generalized-α) are advanced in passes with the
cells still running gathered between passes (as in `overturning_spectrum`). Results equal those
of `simulate` row by row to the solver tolerance (rigid: ~1e-12; spring: its rtol), not bitwise:
the batch a row lands in can change the last digits.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from tqdm.auto import tqdm

from . import interrupt, provenance
from ._files import exclusive, output_stem, same_file, write_atomically
from ._validate import JaxrockInputError, check_range
from .excitation import Record
from .geometry import Block
from .spectra import PULSES, run_batch
from .results import STATUS_NAMES
from .rigid import RigidModel

MODELS = ("rigid", "spring", "spring-flexible")
BUILTIN_RECORDS = ("elcentro",)
INPUT_COLUMNS = (
    "height",
    "tan_alpha",
    "width",
    "tan_alpha_base",
    "model",
    "pulse",
    "a_p",
    "accel_ratio",
    "omega_p",
    "omega_ratio",
    "scale",
    "eta",
    "cbar",
    "e",
    "rho",
    "zeta",
)
# Columns copied to the results unchanged (labels); any other unknown column is an error naming
# the closest known one (a typo such as `modle` ran the rigid model in silence).
PASS_THROUGH = ("id", "name", "label", "group", "note", "notes", "comment")
PASS_THROUGH_PREFIX = "x_"
RESULT_COLUMNS = ("max_theta", "overturned", "t_overturn", "uplifted", "t_uplift", "n_impacts", "status")
_ONLY = {
    "eta": ("rigid",),
    "cbar": ("spring", "spring-flexible"),
    "e": ("spring-flexible",),
    "rho": ("spring-flexible",),
    "zeta": ("spring-flexible",),
}


# ----------------------------------------------------------------------------------------------
# reading and checking
# ----------------------------------------------------------------------------------------------
@dataclass
class Scene:
    """One checked row: the model and excitation values to run, and the row as read."""

    row: int
    line: int
    values: dict  # original column name → cell text
    model: object
    excitation: object
    kind: str


class _Row:
    def __init__(self, source, row: int, line: int, cells: dict):
        self.source, self.row, self.line, self.cells = source, row, line, cells

    def where(self, col: str | None = None) -> str:
        s = f"{self.source}: row {self.row} (line {self.line})"
        return s if col is None else f"{s}, column '{col}'"

    def fail(self, col: str | None, msg: str):
        raise JaxrockInputError(f"{self.where(col)}: {msg}")

    def has(self, col: str) -> bool:
        return self.cells.get(col, "") != ""

    def text(self, col: str, default: str | None = None) -> str | None:
        return self.cells[col] if self.has(col) else default

    def num(self, col: str, lo=-math.inf, hi=math.inf, *, lo_open=False, hi_open=False, default=None, nonzero=False):
        if not self.has(col):
            return default
        raw = self.cells[col]
        try:
            v = float(raw)
        except ValueError:
            self.fail(col, f"{raw!r} is not a number")
        try:
            check_range(col, v, lo, hi, lo_open=lo_open, hi_open=hi_open)
        except JaxrockInputError as e:
            self.fail(col, str(e))
        if nonzero and v == 0:
            self.fail(col, f"{col} = 0; valid: any non-zero value")
        return v

    def one_of(self, a: str, b: str, what: str):
        if self.has(a) and self.has(b):
            self.fail(a, f"give either '{a}' or '{b}' ({what}), not both")
        if not (self.has(a) or self.has(b)):
            self.fail(a, f"missing: give '{a}' or '{b}' ({what})")
        return a if self.has(a) else b


def _resolve_record(text: str, base: Path, row: _Row, cache: dict) -> Record:
    from .records import el_centro, read_record

    key = text.lower()
    if key in ("elcentro", "el-centro", "el_centro"):
        if "elcentro" not in cache:
            cache["elcentro"] = el_centro()
        return cache["elcentro"]
    candidates = [base / text, Path(text)]
    path = next((p for p in candidates if p.is_file()), None)
    if path is None:
        row.fail(
            "pulse",
            f"{text!r} is neither 'symmetric', 'antisymmetric', 'elcentro' nor a record file "
            f"(looked in {base} and the working directory)",
        )
    path = path.resolve()
    if path not in cache:
        try:
            cache[path] = read_record(path)
        except JaxrockInputError as e:
            row.fail("pulse", str(e))
    return cache[path]


def scene_model(kind: str, block: Block, *, eta=None, cbar=None, E=None, rho=None, zeta=None):
    """The model of one scene (`kind` in `MODELS`; None means the default): shared by the batch
    rows and the CLI. A rigid model always carries its η as an array (the block's η′ by default),
    so that rows with and without `eta` share one batch."""
    if kind == "rigid":
        return RigidModel(block, eta=block.eta_r if eta is None else jnp.asarray(eta, dtype=float))
    from .spring import Column, SpringModel

    if kind == "spring":
        return SpringModel(block, None, cbar=cbar)
    column = Column(30e9 if E is None else E, 2500.0 if rho is None else rho)  # concrete (sections 4–6)
    return SpringModel(block, column, cbar=cbar, zeta=0.01 if zeta is None else zeta)


def _check_row(row: _Row, base: Path, cache: dict) -> tuple[object, object, str]:
    kind = (row.text("model", "rigid")).lower()
    if kind not in MODELS:
        row.fail("model", f"{row.cells['model']!r}; valid: {', '.join(MODELS)}")
    for col, models in _ONLY.items():
        if row.has(col) and kind not in models:
            row.fail(col, f"applies only to model {' / '.join(models)}, not {kind}")

    height = row.num("height", 0.0, math.inf, lo_open=True, hi_open=True)
    if height is None:
        row.fail("height", "missing: the full height 2h [m] (> 0) is required")
    geo = row.one_of("tan_alpha", "width", "slenderness tanα = b/h in (0, 1), or full width 2b [m]")
    if geo == "tan_alpha":
        tan_a = row.num("tan_alpha", 0.0, 1.0, lo_open=True, hi_open=True)
    else:
        width = row.num("width", 0.0, math.inf, lo_open=True, hi_open=True)
        tan_a = width / height
        if not tan_a < 1:
            row.fail("width", f"width/height = {tan_a:g}; valid: width < height (tanα < 1)")
    tan_b = row.num("tan_alpha_base", 0.0, 1.0, lo_open=True, hi_open=True)
    if tan_b is not None and tan_b < tan_a * (1 - 1e-12):
        row.fail("tan_alpha_base", f"tan_alpha_base = {tan_b:g} < tan_alpha = {tan_a:g}; valid: [tan_alpha, 1)")
    try:
        block = Block.from_slenderness(height, tan_a, tan_b)
    except JaxrockInputError as e:
        row.fail(None, str(e))

    try:
        model = scene_model(
            kind,
            block,
            eta=row.num("eta", 0.0, 1.0),
            cbar=row.num("cbar", 0.0, math.inf, hi_open=True),
            E=row.num("e", 0.0, math.inf, lo_open=True, hi_open=True),
            rho=row.num("rho", 0.0, math.inf, lo_open=True, hi_open=True),
            zeta=row.num("zeta", 0.0, math.inf, hi_open=True),
        )
    except JaxrockInputError as e:
        row.fail(None, str(e))

    pulse = row.text("pulse", "symmetric")
    if pulse.lower() in PULSES:
        if row.has("scale"):
            row.fail("scale", "applies only to records, not to a Ricker pulse")
        cls = PULSES[pulse.lower()]
        a_col = row.one_of("a_p", "accel_ratio", "pulse amplitude a_p [m/s^2], or a_p/(g tan alpha)")
        w_col = row.one_of("omega_p", "omega_ratio", "pulse frequency omega_p [rad/s], or omega_p/p")
        a = row.num(a_col, nonzero=True)
        w = row.num(w_col, 0.0, math.inf, lo_open=True, hi_open=True)
        a_p = a if a_col == "a_p" else a * float(block.uplift_acceleration)
        omega_p = w if w_col == "omega_p" else w * float(block.p_r)
        try:
            exc = cls(a_p, omega_p)
        except JaxrockInputError as e:
            row.fail(a_col, str(e))
        exc_kind = pulse.lower()
    else:
        rec = _resolve_record(pulse, base, row, cache)
        for col in ("a_p", "accel_ratio", "omega_p", "omega_ratio"):
            if row.has(col):
                row.fail(col, "applies only to Ricker pulses (pulse = symmetric / antisymmetric), not to a record")
        scale = row.num("scale", 0.0, math.inf, hi_open=True, default=1.0)
        exc = rec.scaled(scale)
        exc_kind = f"record:{rec.n}"
    return model, exc, f"{kind}/{exc_kind}"


def _text(path: Path, what: str) -> io.StringIO:
    """A CSV file's text, for `csv` (newline=""): a file that is not UTF-8 text is refused in one line."""
    try:
        text = Path(path).read_bytes().decode("utf-8-sig")  # a spreadsheet's byte-order mark is not part of the header
    except UnicodeDecodeError as e:
        raise JaxrockInputError(f"{path}: the {what} file is not UTF-8 text (byte {e.start}: {e.reason}); expected a CSV") from None
    if "\x00" in text:
        raise JaxrockInputError(f"{path}: the {what} file is binary (NUL bytes); expected a CSV")
    return io.StringIO(text, newline="")


def read_scenes(path) -> tuple[list[Scene], list[str]]:
    """Read and check every row of a scenes CSV (see the module docstring).

    Returns the scenes and the header (original column names). Raises `JaxrockInputError` at the
    first bad row, naming the row, the column and the valid range.
    """
    path = Path(path)
    if not path.is_file():
        raise JaxrockInputError(f"{path}: scenes file not found")
    with _text(path, "scenes") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise JaxrockInputError(f"{path}: the file is empty; expected a CSV header line (height, tan_alpha, ...)") from None
        header = [h.strip() for h in header]
        keys = [h.lower() for h in header]
        dup = sorted({k for k in keys if keys.count(k) > 1 and k})
        if dup:
            raise JaxrockInputError(f"{path}: line 1: column(s) {dup} appear more than once")
        for h, k in zip(header, keys):
            if k not in INPUT_COLUMNS and k not in PASS_THROUGH and not k.startswith(PASS_THROUGH_PREFIX):
                close = difflib.get_close_matches(k, INPUT_COLUMNS + PASS_THROUGH, n=1, cutoff=0.6)
                hint = f"did you mean '{close[0]}'? " if close else ""
                raise JaxrockInputError(
                    f"{path}: line 1: unknown column {h!r}; {hint}valid: {', '.join(INPUT_COLUMNS)}; "
                    f"copied through: {', '.join(PASS_THROUGH)} or any name starting with '{PASS_THROUGH_PREFIX}'")
        if "height" not in keys:
            raise JaxrockInputError(
                f"{path}: line 1: no 'height' column; the header must name the scene columns "
                f"(height, tan_alpha or width, pulse, a_p or accel_ratio, omega_p or omega_ratio, ...)"
            )
        base = path.resolve().parent
        cache: dict = {}
        scenes = []
        n = 0
        for cells in reader:
            line = reader.line_num
            if not any(c.strip() for c in cells) or cells[0].lstrip().startswith("#"):
                continue
            n += 1
            if len(cells) != len(header):
                raise JaxrockInputError(
                    f"{path}: row {n} (line {line}): {len(cells)} cells, but the header has {len(header)} columns"
                )
            values = dict(zip(header, (c.strip() for c in cells)))
            row = _Row(path, n, line, dict(zip(keys, (c.strip() for c in cells))))
            model, exc, kind = _check_row(row, base, cache)
            scenes.append(Scene(n, line, values, model, exc, kind))
    if not scenes:
        raise JaxrockInputError(f"{path}: no scenes (only a header)")
    return scenes, header


# ----------------------------------------------------------------------------------------------
# running
# ----------------------------------------------------------------------------------------------
def _structure(x):
    dyn, static = eqx.partition(x, eqx.is_array)
    return (jax.tree_util.tree_structure(dyn), tuple(jax.tree_util.tree_leaves(static)))


def group_key(scene: Scene):
    """Scenes with equal keys are stacked into one vmapped batch."""
    return (scene.kind, _structure(scene.model), _structure(scene.excitation))


def _stack(objs):
    """Stack the array leaves of structurally equal pytrees along a new leading axis."""
    dyn = [eqx.partition(o, eqx.is_array)[0] for o in objs]
    static = eqx.partition(objs[0], eqx.is_array)[1]
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.asarray(np.stack([np.asarray(x) for x in xs])), *dyn)
    return eqx.combine(stacked, static)


def run_stacked(model, exc):
    """Summaries of a stacked batch (every array leaf of `model` and `exc` has the batch axis)."""
    return run_batch(model, exc, model_batched=True)


def _fmt(x) -> str:
    x = float(x)
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return repr(x)


def _result_rows(sol, k: int) -> list[dict]:
    out = []
    status = np.asarray(sol.status._value)
    for i in range(k):
        out.append(
            {
                "max_theta": _fmt(np.asarray(sol.max_theta)[i]),
                "overturned": str(int(np.asarray(sol.overturned)[i])),
                "t_overturn": _fmt(np.asarray(sol.t_overturn)[i]),
                "uplifted": str(int(np.asarray(sol.uplifted)[i])),
                "t_uplift": _fmt(np.asarray(sol.t_uplift)[i]),
                "n_impacts": str(int(np.asarray(sol.n_impacts)[i])),
                "status": STATUS_NAMES[int(status[i])],
            }
        )
    return out


@dataclass
class BatchReport:
    """What `run_scenes` did."""

    n_rows: int
    n_run: int
    n_skipped: int
    n_groups: int
    seconds: float
    status_counts: dict = field(default_factory=dict)
    n_overturned: int = 0
    path: Path | None = None


def _read_done(results: Path, header: list[str], scenes: list[Scene]) -> dict[int, dict]:
    """Finished rows of an earlier run (row number → result row), checked against the scenes."""
    done: dict[int, dict] = {}
    if not results.exists():
        return done
    with _text(results, "results") as fh:
        reader = csv.DictReader(fh)
        expected = ["row", *header, *RESULT_COLUMNS]
        if reader.fieldnames is None:
            return done
        if list(reader.fieldnames) != expected:
            raise JaxrockInputError(
                f"{results}: its columns {reader.fieldnames} do not match this scenes file "
                f"(expected {expected}); use another results file or run without --resume"
            )
        by_row = {s.row: s for s in scenes}
        for rec in reader:
            try:
                r = int(rec["row"])
            except (TypeError, ValueError):
                continue  # a partly written last line of an interrupted run
            if r not in by_row or any(rec.get(c) in (None, "") for c in ("status", "max_theta")):
                continue
            if any(rec[h] != by_row[r].values[h] for h in header):
                raise JaxrockInputError(
                    f"{results}: row {r} was computed for other inputs than row {r} of the scenes file; "
                    f"use another results file or run without --resume"
                )
            done[r] = rec
    return done


def count_results(results) -> int:
    """Finished rows in a results file (0 when it is missing or unreadable)."""
    try:
        with _text(Path(results), "results") as fh:
            return sum(1 for rec in csv.DictReader(fh) if rec.get("status") in STATUS_NAMES)
    except (OSError, JaxrockInputError):
        return 0


def _chunks(idx: list[int], size: int):
    for lo in range(0, len(idx), size):
        yield idx[lo : lo + size]


_MIN_PAD = 8


def _pad_size(k: int, chunk: int) -> int:
    """Batch shapes: powers of two from 8 up to the chunk size (few compilations)."""
    return min(chunk, max(_MIN_PAD, 1 << max(0, (k - 1).bit_length())))


def _description(scenes: list[Scene]) -> dict[str, str]:
    """What determines a batch's numbers beyond each row's own inputs (which the results file
    holds): the package version, the integrators (each model's default) and every record's content."""
    d = {"jaxrock": provenance.package_version(), "integrator": "each model's default"}
    for s in scenes:
        if isinstance(s.excitation, Record):
            name = f"record {s.values.get('pulse', '')}"
            if name not in d:
                d[name] = provenance.value_text(np.concatenate([np.ravel(s.excitation.acc), np.ravel(s.excitation.dt)]))
    return d


def run_scenes(scenes_path, results_path, *, resume: bool = False, chunk_size: int = 256, progress: bool = True) -> BatchReport:
    """Run every scene of `scenes_path` and write `results_path` (see the module docstring).

    All rows are checked first (a `JaxrockInputError` names the first bad row and column).
    Results are appended per chunk; with `resume`, rows already in `results_path` are skipped,
    once `<results>.made_by.json` shows they were made by this package version from the same
    record contents (else a `JaxrockInputError` names the difference).
    """
    if int(chunk_size) < 1:
        raise JaxrockInputError(f"chunk_size = {chunk_size}; valid: an integer >= 1")
    chunk_size = int(chunk_size)
    t0 = time.perf_counter()
    results = results_path_for(scenes_path, results_path)
    if same_file(results, scenes_path):
        raise JaxrockInputError(f"{results}: the results file is the scenes file (the same file by another name); name another")
    scenes, header = read_scenes(scenes_path)
    clash = [h for h in header if h.lower() in ("row", *RESULT_COLUMNS)]
    if clash:
        raise JaxrockInputError(f"{scenes_path}: line 1: column(s) {clash} are names of result columns; rename them")
    with exclusive(results, "results file"):
        return _run(scenes, header, results, resume, chunk_size, progress, t0)


def results_path_for(scenes_path, results_path) -> Path:
    """The results file: `results_path`, or inside it when it is a folder (or ends with a
    separator) as `<scenes stem>_results.csv`."""
    return output_stem(results_path, f"{Path(scenes_path).stem}_results.csv")


def _run(scenes, header, results: Path, resume, chunk_size, progress, t0) -> BatchReport:
    """`run_scenes` on checked scenes, the results file held."""
    made_by = _description(scenes)
    sidecar = results.with_name(results.name + ".made_by.json")
    done = _read_done(results, header, scenes) if resume else {}
    if done:
        fresh = "run without --resume to start afresh, or write another results file"
        provenance.check_description(sidecar, made_by, f"{results}", fresh)
    fields = ["row", *header, *RESULT_COLUMNS]

    todo = [s for s in scenes if s.row not in done]
    groups: dict = {}
    for s in todo:
        groups.setdefault(group_key(s), []).append(s)

    results.parent.mkdir(parents=True, exist_ok=True)
    if not (resume and results.exists() and done):
        with open(results, "w", newline="", encoding="utf-8") as fh:
            csv.DictWriter(fh, fieldnames=fields).writeheader()
        provenance.write_description(sidecar, made_by)
    bar = tqdm(total=len(scenes), initial=len(scenes) - len(todo), unit="scene", desc="batch", disable=not progress)
    new: dict[int, dict] = {}
    for members in groups.values():
        models = [s.model for s in members]
        excs = [s.excitation for s in members]
        for part in _chunks(list(range(len(members))), chunk_size):
            interrupt.stop_point()
            size = _pad_size(len(part), chunk_size)
            index = part + [part[0]] * (size - len(part))
            sol = run_stacked(_stack([models[i] for i in index]), _stack([excs[i] for i in index]))
            rows = _result_rows(sol, len(part))
            with open(results, "a", newline="", encoding="utf-8") as fh:
                w = csv.DictWriter(fh, fieldnames=fields)
                for i, res in zip(part, rows):
                    s = members[i]
                    rec = {"row": str(s.row), **s.values, **res}
                    w.writerow(rec)
                    new[s.row] = rec
                fh.flush()
                os.fsync(fh.fileno())
            bar.update(len(part))
    bar.close()

    # all done: rewrite in row order (atomically)
    allrows = {**done, **new}

    def write(tmp):
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=fields)
            w.writeheader()
            for r in sorted(allrows):
                w.writerow({k: allrows[r][k] for k in fields})

    write_atomically(results, write)

    statuses = [allrows[r]["status"] for r in allrows]
    counts = {name: statuses.count(name) for name in STATUS_NAMES if statuses.count(name)}
    return BatchReport(
        n_rows=len(scenes),
        n_run=len(todo),
        n_skipped=len(scenes) - len(todo),
        n_groups=len(groups),
        seconds=time.perf_counter() - t0,
        status_counts=counts,
        n_overturned=sum(int(allrows[r]["overturned"]) for r in allrows),
        path=results,
    )


__all__ = ["read_scenes", "run_scenes", "run_stacked", "count_results", "Scene", "BatchReport", "MODELS", "INPUT_COLUMNS", "RESULT_COLUMNS"]
