"""The scenes file and the results file of a batch run (`jaxrock batch scenes.csv --out results.csv
[--resume]`, or `run_scenes(scenes, results)`, `jaxrock.analyses.scenes`): reading and checking the
scenes, each row's model and excitation, and the results rows written, read back and resumed.

Scenes file
-----------
A CSV file with a header line. Column names are case-insensitive; empty cells mean "default";
blank lines and lines whose first cell starts with `#` are skipped. Rows are numbered from 1 (the
first scene after the header). Columns:

<the scene's parameters: `jaxrock.scene.parameter_table()`>

Label columns are copied to the results unchanged: `id`, `name`, `label`, `group`, `note`,
`notes`, `comment`, or any name starting with `x_`. Any other column is an error that names the
closest valid one (a misspelt `modle` would otherwise run the default model). A parameter given
for a model or pulse it does not apply to (e.g. `eta` for a spring model, `scale` for a pulse) is
an error. Every row is checked before anything runs, a column at a time (vectorised; docs/guide/batch.md for
its speed); a bad row stops the run with a message naming the file, the row (and its line), the
column and the valid range.

Results file
------------
The column `row` (the scene's row number), the scene's input columns as given, then the summary
outputs (`jaxrock.results.SUMMARY`; floats written exactly, flags as 0/1):

<the summary outputs: `jaxrock.results.summary_doc()`>
- `status`: `ok`, or why the numbers are not to be trusted (see `jaxrock.Status`).

Results are appended after every batch, so an interrupted run
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
import math
from dataclasses import dataclass
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._validate import JaxrockInputError, check_range, in_range, is_number, within_limits
from ..construct import kind_values, pulse_params_of, scene_model, scene_pulse
from ..excitation import Record
from ..geometry import G, Block, pulse_of_ratios
from ..scene import (DEFAULT_MODEL, DEFAULT_PULSE, HEIGHT, MODEL_KINDS, PULSE_PARAMS, PULSES, RECORD_ALIASES, SCALE, TAN_ALPHA, TAN_ALPHA_BASE,
                     TAN_ALPHA_MIN, builtin_record_names,
                     is_builtin_record, model_kinds, model_params, parameter_table, parameters, pulse_params,
                     pulse_takes, takes)
from ..results import RESULT_COLUMNS, summary_doc
from .tables import csv_text

__doc__ = (__doc__.replace("<the scene's parameters: `jaxrock.scene.parameter_table()`>", parameter_table())
           .replace("<the summary outputs: `jaxrock.results.summary_doc()`>", summary_doc()))
def input_columns() -> tuple[str, ...]:
    """The columns a scenes file may have, lower-cased as the header's names are read (a kind
    registered since adds its parameters)."""
    return tuple(p.name.lower() for p in parameters())
# Columns copied to the results unchanged (labels); any other unknown column is an error naming
# the closest known one (a typo such as `modle` ran the rigid model in silence).
PASS_THROUGH = ("id", "name", "label", "group", "note", "notes", "comment")
PASS_THROUGH_PREFIX = "x_"


# ----------------------------------------------------------------------------------------------
# reading and checking
# ----------------------------------------------------------------------------------------------
class _Table:
    """The scenes' cells by column (lower-cased names), checked a column at a time (vectorised: a
    10⁵-row file in about a second); a failed check names the first row where it fails."""

    def __init__(self, source, keys: list[str], cells: list[list[str]], rows: list[int], lines: list[int]):
        self.source, self.n = source, len(cells)
        self.rows, self.lines = np.asarray(rows), np.asarray(lines)
        columns = list(zip(*cells)) if cells else [() for _ in keys]
        self.cells = {k: np.asarray(col, dtype=object) for k, col in zip(keys, columns)}

    def where(self, i: int, col: str | None = None) -> str:
        s = f"{self.source}: row {self.rows[i]} (line {self.lines[i]})"
        return s if col is None else f"{s}, column '{col}'"

    def fail(self, bad, col: str | None, msg):
        """Raise for the first row of the mask `bad` (if any); `msg` is text or a function of the row."""
        if np.any(bad):
            i = int(np.argmax(bad))
            raise JaxrockInputError(f"{self.where(i, col)}: {msg(i) if callable(msg) else msg}")

    def has(self, col: str) -> np.ndarray:
        return self.cells[col] != "" if col in self.cells else np.zeros(self.n, bool)

    def text(self, col: str, default: str) -> np.ndarray:
        return np.where(self.has(col), self.cells.get(col, default), default)

    def param(self, p, rows=None) -> np.ndarray:
        """The column of a declared parameter (`jaxrock.scene.Param`), checked against its range and step."""
        x = self.num(p.name.lower(), p.lo, p.hi, lo_open=p.lo_open, hi_open=p.hi_open, rows=rows)
        self.fail(p.off_step(x), p.name.lower(), lambda i: f"{x[i]:g}; valid: {p.range_text}")
        return x

    def num(self, col: str, lo=-math.inf, hi=math.inf, *, lo_open=False, hi_open=False, nonzero=False, rows=None) -> np.ndarray:
        """The column's numbers (NaN where empty, or outside `rows`), each checked against the range."""
        present = self.has(col) if rows is None else self.has(col) & rows
        v = np.full(self.n, np.nan)
        if not present.any():
            return v
        raw = self.cells[col][present]
        try:
            v[present] = raw.astype(float)
        except ValueError:
            bad = np.zeros(self.n, bool)
            bad[np.flatnonzero(present)[[not is_number(x) for x in raw].index(True)]] = True
            self.fail(bad, col, lambda i: f"{self.cells[col][i]!r} is not a number")
        inside = in_range(v, lo, hi, lo_open=lo_open, hi_open=hi_open)

        def why(i):
            try:
                check_range(col, v[i], lo, hi, lo_open=lo_open, hi_open=hi_open)
            except JaxrockInputError as e:
                return str(e)

        self.fail(present & ~inside, col, why)
        if nonzero:
            self.fail(present & (v == 0), col, f"{col} = 0; valid: any non-zero value")
        return v

    def one_of(self, a: str, b: str, what: str, rows) -> np.ndarray:
        """Rows (of `rows`) that give `a` rather than `b`; giving both or neither is refused."""
        self.fail(rows & self.has(a) & self.has(b), a, f"give either '{a}' or '{b}' ({what}), not both")
        self.fail(rows & ~self.has(a) & ~self.has(b), a, f"missing: give '{a}' or '{b}' ({what})")
        return self.has(a)


def _resolve_record(text: str, base: Path, fail, cache: dict) -> Record:
    from .records import builtin_record, read_record

    candidates = [base / text, Path(text)]
    path = next((p for p in candidates if p.is_file()), None)
    if path is None and is_builtin_record(text):
        key = text.strip().lower()
        key = RECORD_ALIASES[0] if key in RECORD_ALIASES else key
        if key not in cache:
            cache[key] = builtin_record(key)
        return cache[key]
    if path is None:
        fail(
            f"{text!r} is neither a pulse ({', '.join(PULSES)}), a packaged record ({builtin_record_names()}) nor a record file "
            f"(looked in {base} and the working directory)"
        )
    path = path.resolve()
    if path not in cache:
        try:
            cache[path] = read_record(path)
        except JaxrockInputError as e:
            fail(str(e))
    return cache[path]


def _invalid_lanes(stacked) -> np.ndarray:
    """Per lane of a stacked value (a `Block`, a `Column`): whether a parameter is outside its limits."""
    return ~np.asarray(jax.vmap(lambda one: within_limits(one.limits()))(stacked))


def stack(objs):
    """Stack the array leaves of structurally equal pytrees along a new leading axis."""
    dyn = [eqx.partition(o, eqx.is_array)[0] for o in objs]
    static = eqx.partition(objs[0], eqx.is_array)[1]
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.asarray(np.stack([np.asarray(x) for x in xs])), *dyn)
    return eqx.combine(stacked, static)


@dataclass
class Scenes:
    """Every checked row of a scenes file, as arrays (one entry per row) and groups of rows that
    run in one vmapped batch (same model kind and excitation kind; records of any length, padded)."""

    header: list[str]
    rows: np.ndarray  # row numbers (from 1)
    values: list[dict]  # per row: original column name → cell text
    groups: dict  # (model kind, excitation kind) → row indices
    params: dict  # name → array over rows (the model's and excitation's values, defaults filled)
    records: list  # per row: the Record (record rows) or None

    def __len__(self) -> int:
        return len(self.rows)

    def model(self, kind: str, idx) -> object:
        """The stacked models of rows `idx` (all of model kind `kind`)."""
        p = {k: jnp.asarray(v[idx]) for k, v in self.params.items()}
        block = jax.vmap(Block.from_slenderness)(p["height"], p["tan_alpha"], p["tan_alpha_base"])
        return jax.vmap(lambda b, kw: scene_model(kind, b, **kw))(block, kind_values(kind, p))

    def intensity(self, idx) -> np.ndarray:
        """Per row of `idx`: its excitation's peak |üg| over the block's uplift level g tanα′
        (eq. 26), the batch engine's measure of a scene's difficulty: below 1 a rigid body stays
        at rest, near 1 it chatters, far above it it soon overturns."""
        idx = np.asarray(idx, dtype=int)
        peaks: dict[int, float] = {}  # a record's peak |acc|, once per record (rows share them)

        def peak(i):
            rec = self.records[i]
            if rec is None:
                return abs(self.params["a_p"][i])
            if id(rec) not in peaks:
                peaks[id(rec)] = float(np.max(np.abs(np.asarray(rec.acc))))
            return abs(self.params["scale"][i]) * peaks[id(rec)]

        return np.array([peak(i) for i in idx], dtype=float) / (G * self.params["tan_alpha_base"][idx])

    def excitation(self, exc: str, idx) -> object:
        """The stacked excitations of rows `idx` (all of excitation kind `exc`)."""
        if exc in PULSES:
            values = {k: jnp.asarray(self.params[k][idx]) for k in ("a_p", "omega_p", *pulse_params_of(exc))}
            return jax.vmap(lambda v: scene_pulse(exc, None, v))(values)
        n = max(self.records[i].n for i in idx)  # records of distinct lengths, padded to one: one program
        pairs = any(self.records[i].vertical is not None for i in idx)  # one structure for pairs and single records
        return stack([self.records[i].padded(n, "record", vertical=pairs).scaled(self.params["scale"][i]) for i in idx])


def _check_table(t: _Table, base: Path, cache: dict) -> tuple[dict, dict, list]:
    everyone = np.ones(t.n, bool)
    kind = np.char.lower(t.text("model", DEFAULT_MODEL).astype(str))
    t.fail(~np.isin(kind, model_kinds()), "model", lambda i: f"{t.cells['model'][i]!r}; valid: {', '.join(model_kinds())}")
    for name in model_params():
        col, kinds = name.lower(), takes(name)
        t.fail(t.has(col) & ~np.isin(kind, kinds), col, lambda i: f"applies only to model {' / '.join(kinds)}, not {kind[i]}")

    height = t.param(HEIGHT)
    t.fail(np.isnan(height), "height", "missing: the full height 2h [m] (> 0) is required")
    by_tan = t.one_of("tan_alpha", "width", "slenderness tanα = b/h in [1e-3, 1), or full width 2b [m]", everyone)
    tan_a = t.param(TAN_ALPHA)
    width = t.num("width", 0.0, math.inf, lo_open=True, hi_open=True)
    tan_a = np.where(by_tan, tan_a, width / height)
    t.fail(~by_tan & ~(tan_a < 1), "width", lambda i: f"width/height = {tan_a[i]:g}; valid: width < height (tanα < 1)")
    t.fail(~by_tan & ~(tan_a >= TAN_ALPHA_MIN), "width",
           lambda i: f"width/height = {tan_a[i]:g}; valid: tanα >= {TAN_ALPHA_MIN:g}")
    tan_b = t.param(TAN_ALPHA_BASE)
    t.fail(tan_b < tan_a * (1 - 1e-12), "tan_alpha_base",
           lambda i: f"tan_alpha_base = {tan_b[i]:g} < tan_alpha = {tan_a[i]:g}; valid: [tan_alpha, 1)")
    tan_b = np.where(np.isnan(tan_b), tan_a, tan_b)  # no base: b′ = b
    blocks = jax.vmap(Block.from_slenderness)(jnp.asarray(height), jnp.asarray(tan_a), jnp.asarray(tan_b))
    t.fail(_invalid_lanes(blocks), None, lambda i: _refusal(lambda: Block.from_slenderness(height[i], tan_a[i], tan_b[i])))

    from ..spring import Column, cbar_eq17

    params = {"height": height, "tan_alpha": tan_a, "tan_alpha_base": tan_b}
    # the model parameters as each row's kind declares them (`jaxrock.scene.Param`): its range, its
    # default (computed by the model where it declares none: η eq. 5, c̄ eq. 17)
    computed = {"eta": np.asarray(blocks.eta_r), "cbar": np.asarray(cbar_eq17(blocks.alpha_r))}
    for name, shared in model_params().items():
        value = np.full(t.n, np.nan)
        for k in takes(name):
            rows = kind == k
            p = MODEL_KINDS[k].params.get(name, shared)
            x = t.param(p, rows=rows)
            default = p.default if p.default is not None else computed.get(name, np.nan)
            value = np.where(rows, np.where(np.isnan(x), default, x), value)
            t.fail(rows & np.isnan(value), name.lower(), f"missing: {p.meaning} is required for model {k} (no default)")
        params[name] = np.where(np.isnan(value), shared.default if shared.default is not None else 0.0, value)
    flexible = np.isin(kind, takes("E"))  # rows whose column's material is checked
    columns = jax.vmap(Column)(jnp.asarray(params["E"]), jnp.asarray(params["rho"]))
    t.fail(flexible & _invalid_lanes(columns), None, lambda i: _refusal(lambda: Column(params["E"][i], params["rho"][i])))

    pulse = t.text("pulse", DEFAULT_PULSE).astype(str)
    exc = np.char.lower(pulse).astype(object)
    is_pulse = np.isin(exc, list(PULSES))
    t.fail(is_pulse & t.has("scale"), "scale", "applies only to records, not to a Ricker pulse")
    records = [None] * t.n
    for name in np.unique(pulse[~is_pulse]):
        rows = np.flatnonzero(pulse == name)
        rec = _resolve_record(str(name), base, lambda msg: t.fail(pulse == name, "pulse", msg), cache)
        for i in rows:
            records[i] = rec
        exc[rows] = "record"
    by_a = t.one_of("a_p", "accel_ratio", "pulse amplitude a_p [m/s^2], or a_p/(g tan alpha)", is_pulse)
    by_w = t.one_of("omega_p", "omega_ratio", "pulse frequency omega_p [rad/s], or omega_p/p", is_pulse)
    a_p, a_r = t.num("a_p", nonzero=True, rows=is_pulse), t.num("accel_ratio", nonzero=True, rows=is_pulse)
    w_p = t.num("omega_p", 0.0, math.inf, lo_open=True, hi_open=True, rows=is_pulse)
    w_r = t.num("omega_ratio", 0.0, math.inf, lo_open=True, hi_open=True, rows=is_pulse)
    a_of_ratio, w_of_ratio = pulse_of_ratios(blocks, a_r, w_r)
    a_p, w_p = np.where(by_a, a_p, np.asarray(a_of_ratio)), np.where(by_w, w_p, np.asarray(w_of_ratio))
    for col in ("a_p", "accel_ratio", "omega_p", "omega_ratio"):
        t.fail(~is_pulse & t.has(col), col, f"applies only to pulses (pulse = {' / '.join(PULSES)}), not to a record")
    scale = t.param(SCALE, rows=~is_pulse)
    params.update(a_p=a_p, omega_p=w_p, scale=np.where(np.isnan(scale), 1.0, scale))
    for name, shared in pulse_params().items():  # the pulse kinds' own parameters, as each row's kind declares them
        col, kinds = name.lower(), pulse_takes(name)
        t.fail(t.has(col) & ~np.isin(exc, kinds), col, lambda i: f"applies only to pulse {' / '.join(kinds)}, not {exc[i]}")
        value = np.full(t.n, np.nan)
        for k in kinds:
            rows = exc == k
            p = PULSE_PARAMS[k][name]
            x = t.param(p, rows=rows)
            value = np.where(rows, np.where(np.isnan(x), p.default, x), value)
        params[name] = np.where(np.isnan(value), shared.default, value)

    groups: dict = {}
    for i, key in enumerate(zip(kind.tolist(), exc.tolist())):
        groups.setdefault(key, []).append(i)
    return params, {k: np.asarray(v) for k, v in groups.items()}, records


def _refusal(build) -> str:
    """The one-line refusal of a concrete construction (the row's values, one scene)."""
    try:
        build()
    except JaxrockInputError as e:
        return str(e)
    return "a parameter is outside its valid range"  # pragma: no cover - the limits agree with the constructors


def read_scenes(path) -> Scenes:
    """Read and check every row of a scenes CSV file.

    The file (module docstring, `jaxrock.io.scenes_file`): a header line of case-insensitive column
    names (a `height` column at least), one scene per row; empty cells mean "default"; blank lines and
    lines whose first cell starts with `#` are skipped; label columns (`id`, `name`, `label`, `group`,
    `note`, `notes`, `comment`, `x_...`) are carried through. Every row is checked, a column at a time,
    before anything runs; rows of the same structure are grouped for one vmapped batch each.

    Arguments:
        path (str | os.PathLike): the scenes CSV file.

    Returns:
        The checked rows (`Scenes`), as arrays per parameter and groups of rows.

    Raises:
        JaxrockInputError: at a bad row, naming the row, the column and the valid range; or when the
            file is missing, empty, without scenes, or its header repeats a column, names an unknown
            one or lacks `height`.

    Example:
        ```python
        import jaxrock
        scenes = jaxrock.read_scenes("scenes.csv")
        len(scenes)  # the number of rows
        ```
    """
    path = Path(path)
    if not path.exists():
        raise JaxrockInputError(f"{path}: scenes file not found")
    if not path.is_file():
        raise JaxrockInputError(f"{path}: the scenes file is {'a folder' if path.is_dir() else 'not a regular file (a FIFO, a device)'}; "
                                "expected a CSV file")
    with csv_text(path, "scenes") as fh:
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
        columns = input_columns()
        for h, k in zip(header, keys):
            if k not in columns and k not in PASS_THROUGH and not k.startswith(PASS_THROUGH_PREFIX):
                close = difflib.get_close_matches(k, columns + PASS_THROUGH, n=1, cutoff=0.6)
                hint = f"did you mean '{close[0]}'? " if close else ""
                raise JaxrockInputError(
                    f"{path}: line 1: unknown column {h!r}; {hint}valid: {', '.join(columns)}; "
                    f"copied through: {', '.join(PASS_THROUGH)} or any name starting with '{PASS_THROUGH_PREFIX}'")
        if "height" not in keys:
            raise JaxrockInputError(
                f"{path}: line 1: no 'height' column; the header must name the scene columns "
                f"(height, tan_alpha or width, pulse, a_p or accel_ratio, omega_p or omega_ratio, ...)"
            )
        cells, rows, lines = [], [], []
        for raw in reader:
            if not any(c.strip() for c in raw) or raw[0].lstrip().startswith("#"):
                continue
            if len(raw) != len(header):
                raise JaxrockInputError(
                    f"{path}: row {len(rows) + 1} (line {reader.line_num}): {len(raw)} cells, but the header has {len(header)} columns"
                )
            cells.append([c.strip() for c in raw])
            rows.append(len(rows) + 1)
            lines.append(reader.line_num)
    if not cells:
        raise JaxrockInputError(f"{path}: no scenes (only a header)")
    params, groups, records = _check_table(_Table(path, keys, cells, rows, lines), path.resolve().parent, {})
    values = [dict(zip(header, c)) for c in cells]
    return Scenes(header, np.asarray(rows), values, groups, params, records)


__all__ = ["read_scenes", "Scenes", "scene_model", "input_columns", "RESULT_COLUMNS"]
