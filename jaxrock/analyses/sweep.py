"""Sweeps: every scene of a product of axes, run chunk by chunk into a labelled store.

A `Sweep` is a value: one model kind, and for each scene quantity either one value or an axis of
values — the spectra's axes a_p/(g tanα′) and ω_p/p′ (Ricker pulses), or records and their scale
factor; the column's size 2h, slenderness tanα and base tanα′; the model parameters η, c̄, E, ρ, ζ
and the spring's smoothing θs/α′. The product of its axes (in the order of `axis_order()`: records
and model axes outside, excitation axes inside) is split into `chunks` of at most `chunk_size`
scenes, each a hyper-rectangle of the grid (every record in its own chunks: records differ in
length). `run_chunk` runs one chunk through the batch engine (`jaxrock.analyses.engine`: the
compaction of the spectra, on the devices it is given) and returns its summary outputs; a chunk reads nothing but the sweep, so chunks run in any order, in
any process, with the same bits.

`run_sweep` runs the chunks not yet in the store (`jaxrock.io.store`: xarray on Zarr, one Zarr
chunk per sweep chunk) in this process, one chunk per local device at a time (`on_devices`; on a CPU,
one device per core with `jaxrock.use_cpu_cores`), or as tasks of a Dask cluster (`client`), with a
progress bar; a rerun after an interruption runs only what is missing.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Callable, Iterable

import numpy as np

from .._validate import JaxrockInputError, check_range
from ..outputs import OUTPUTS
from ..scene import (DEFAULT_PULSE, MODEL_KINDS, PULSES, model_kinds, model_params, pulse_class, pulse_params, pulse_takes, sweep_quantities,
                     takes)
from .engine import batch_limit, make_stepper, on_devices, run_batch

if TYPE_CHECKING:
    from ..model import AbstractModel


def axis_order() -> tuple[str, ...]:
    """A store's dimensions, outermost first (`jaxrock.scene.sweep_quantities`)."""
    return tuple(sweep_quantities())


def model_quantities() -> tuple[str, ...]:
    """The quantities that make a scene's model: the block's geometry (first three), the registered
    kinds' numeric parameters (`jaxrock.scene.model_params`), the spring's smoothing."""
    return ("height", "tan_alpha", "tan_alpha_base", *model_params(), "smoothing")


PULSE_QUANTITIES = ("accel_ratio", "omega_ratio")
DEFAULTS = {"height": 10.0, "tan_alpha": 0.2}  # the rest: the model kind's own defaults


@dataclasses.dataclass(frozen=True, eq=False)
class Sweep:
    """Every scene of a product of axes, run chunk by chunk (module docstring, `jaxrock.analyses.sweep`).

    Build with `Sweep.make`, which checks every value; run with `run_sweep` (or
    `least_overturning_scale` for a record sweep). A frozen dataclass.

    Arguments:
        model (str | AbstractModel): a model kind (`jaxrock.scene.model_kinds()`), or a model value
            (`overturning_spectrum` runs one).
        axes (dict): quantity → values (at least one), in `axis_order()`.
        fixed (dict): quantity → one value.
        pulse (str | Callable | None): the Ricker pulse kind or class (pulse sweeps), or None with
            `records` (record sweeps: `axes["record"]` holds their names).
        records (tuple): the records of a record sweep; default ().
        backbone (str | None): the spring backbone name of a spring kind; default None: the default.
        integrator (AbstractIntegrator | None): default None: the model's default.
        chunk_size (int): the most scenes of one chunk; default 1024.
        sensitivity (bool): every run carries its tangent and reports its `sensitivity` and `uncertain`
            flag (`jaxrock.sensitivity`; forward mode: without `integrator`, the model's forward-mode
            default); default False: those outputs read "not computed".

    Example:
        ```python
        import jaxrock
        sweep = jaxrock.Sweep.make("rigid", height=[5.0, 10.0], tan_alpha=0.2,
                                   accel_ratio=[1.0, 2.0, 4.0], omega_ratio=[2.0, 4.0])
        ds = jaxrock.run_sweep(sweep, "sweep.zarr")
        ```
    """

    model: "str | AbstractModel"
    axes: dict
    fixed: dict
    pulse: "str | Callable | None"
    records: tuple = ()
    backbone: str | None = None
    integrator: object = None
    chunk_size: int = 1024
    sensitivity: bool = False

    @classmethod
    def make(cls, model="rigid", *, pulse=None, records=None, backbone: str | None = None,
             integrator=None, chunk_size: int = 1024, sensitivity: bool = False, **quantities) -> "Sweep":
        """A checked sweep: each keyword of `jaxrock.scene.sweep_quantities()` is one number (fixed) or a sequence (an
        axis). Pulse sweeps take `accel_ratio` and `omega_ratio` (both required; `pulse` a pulse
        kind's name or class); record sweeps take `records` (a `jaxrock.Record` or a sequence of
        them) and `scale` (default 1). `model` is a model kind, or a model (a value: every scene
        runs it, resized to `height` if given, at its own slenderness; no other model quantity may
        be given). Every value is checked here, naming the quantity and its valid range.

        Arguments:
            model (str | AbstractModel): a model kind or a model value; default "rigid".
            pulse (str | type | None): a pulse kind's name or class (pulse sweeps); default None.
            records (Record | Sequence[Record] | None): the records of a record sweep; default None.
            backbone: the spring backbone name of a spring kind; default None: the kind's default.
            integrator (AbstractIntegrator | None): default None: the model's default.
            chunk_size: the most scenes of one chunk; default 1024.
            sensitivity: every run reports its sensitivity and `uncertain` flag; default False.
            **quantities (float | Sequence[float]): each quantity of `jaxrock.scene.sweep_quantities()`,
                one number (fixed) or a sequence (an axis).

        Returns:
            The checked `Sweep`.

        Raises:
            JaxrockInputError: when a value is outside its valid range, a quantity is unknown, or a
                model value is given with model quantities other than `height`.
        """
        from ..model import AbstractModel

        if isinstance(model, AbstractModel):
            varied = sorted(set(quantities) & set(model_quantities()[1:])) + (["backbone"] if backbone is not None else [])
            if varied:
                raise JaxrockInputError(f"{', '.join(varied)}: set by the model given (of which only the height may vary); "
                                        "name a model kind to vary them")
        elif model not in MODEL_KINDS:
            raise JaxrockInputError(f"model = {model!r}; valid: {', '.join(model_kinds())}")
        known = sweep_quantities()
        unknown = sorted(set(quantities) - set(known) - {"record"})
        if unknown or "record" in quantities:
            raise JaxrockInputError(f"{', '.join(unknown) or 'record'}: not a sweep quantity; valid: "
                                    f"{', '.join(q for q in known if q != 'record')} (and records=...)")
        if int(chunk_size) < 1:
            raise JaxrockInputError(f"chunk_size = {chunk_size}; valid: an integer >= 1")
        given = {k: v for k, v in quantities.items() if v is not None}
        for name in given:
            if name in model_quantities()[3:] and isinstance(model, str) and model not in takes(name):
                raise JaxrockInputError(f"{name} applies to model {' / '.join(takes(name))} only, not {model}")
        if backbone is not None and isinstance(model, str) and "backbone" not in MODEL_KINDS[model].parameters:
            raise JaxrockInputError(f"backbone applies to the spring models only, not {model}")
        recs = () if records is None else (tuple(records) if isinstance(records, (list, tuple)) else (records,))
        from ..construct import pulse_params_of

        own_pulse = pulse_params_of(DEFAULT_PULSE if pulse is None else pulse)
        for name in (q for q in given if q in pulse_params()):
            if recs or name not in own_pulse:
                kinds = f"pulse {' / '.join(pulse_takes(name))}"
                raise JaxrockInputError(f"{name} applies to {kinds} only, not {'records' if recs else pulse or DEFAULT_PULSE}")
        if recs:
            if pulse is not None or any(q in given for q in PULSE_QUANTITIES):
                raise JaxrockInputError("a sweep runs records or pulses, not both: drop pulse/accel_ratio/omega_ratio, or records")
            names = [r.name for r in recs]
            if len(set(names)) != len(names):
                raise JaxrockInputError(f"records: two records share a name ({names}); give each its own")
        else:
            if "scale" in given:
                raise JaxrockInputError("scale applies to record sweeps (records=...), not to pulses")
            missing = [q for q in PULSE_QUANTITIES if q not in given]
            if missing:
                raise JaxrockInputError(f"a pulse sweep needs {' and '.join(missing)}")
            pulse = DEFAULT_PULSE if pulse is None else pulse
            if isinstance(pulse, str) and pulse not in PULSES:
                raise JaxrockInputError(f"pulse = {pulse!r}; valid: {', '.join(PULSES)}")
        values = {**(DEFAULTS if isinstance(model, str) else {}), **given}
        axes, fixed = {}, {}
        known = sweep_quantities(model if isinstance(model, str) else None, pulse if isinstance(pulse, str) else None)  # each kind's own
        for name in known:
            if name == "record":
                if recs:
                    axes["record"] = np.asarray([r.name for r in recs])
                continue
            if name not in values:
                continue
            v = np.asarray(values[name], dtype=float)
            if v.ndim > 1 or v.size == 0:
                raise JaxrockInputError(f"{name}: one number or a 1-D sequence of numbers, got shape {v.shape}")
            lo, hi, lo_open, hi_open = known[name][2]
            check_range(name, v, lo, hi, lo_open=lo_open, hi_open=hi_open)
            if name in own_pulse:
                own_pulse[name].check_step(v, name)
            (axes if v.ndim == 1 else fixed)[name] = v if v.ndim == 1 else float(v)
        ta = axes.get("tan_alpha", fixed.get("tan_alpha"))
        tb = axes.get("tan_alpha_base", fixed.get("tan_alpha_base"))
        if tb is not None and np.min(tb) < np.max(ta):
            raise JaxrockInputError(f"tan_alpha_base = {np.min(tb):g} < tan_alpha = {np.max(ta):g}; valid: every tan_alpha_base >= every tan_alpha")
        sweep = cls(model=model, axes=axes, fixed=fixed, pulse=pulse, records=recs, backbone=backbone, integrator=integrator,
                    chunk_size=int(chunk_size), sensitivity=bool(sensitivity))
        sweep._check_models()
        return sweep

    def _check_models(self) -> None:
        """Refuse, in one line, a model quantity outside the model's own limits (`limits()`, e.g.
        E ∈ [1e6, 1e15] Pa): the model of the first scene built with each axis's least and
        greatest value (the limits are intervals)."""
        first = {k: v[:1] for k, v in self.chunk_values(0).items()}
        for name in (q for q in model_quantities() if q in self.axes):
            for value in (np.min(self.axes[name]), np.max(self.axes[name])):
                self._models({**first, name: np.asarray([value])}, batched=False)

    # -- the grid and its chunks ------------------------------------------------------------------
    @property
    def dims(self) -> tuple[str, ...]:
        return tuple(self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.axes.values())

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    @property
    def chunk_shape(self) -> tuple[int, ...]:
        """The chunk: `t` values of one axis and every axis inside it whole, one value of the axes
        outside (records one at a time: an interrupted suite keeps each record's finished chunks),
        at most `chunk_size` scenes. Of these the one that maximises cells²/2^⌈log₂ cells⌉ (the
        batch engine pads a batch to a power-of-two multiple of its smallest size: 2016 cells run
        at 2048, 2304 at 4096)."""
        shape, best, best_score = self.shape, (), -1.0
        for j in range(len(shape)):
            inner = math.prod(shape[j + 1 :])
            if inner > self.chunk_size or (j < len(shape) - 1 and self.dims[j + 1] == "record"):
                continue
            most = 1 if self.dims[j] == "record" else min(shape[j], self.chunk_size // inner)
            for t in range(1, most + 1):
                cells = t * inner
                score = cells * cells / (1 << (cells - 1).bit_length())
                if score > best_score:
                    best, best_score = (1,) * j + (t, *shape[j + 1 :]), score
        return best

    @property
    def chunk_grid(self) -> tuple[int, ...]:
        return tuple(-(-n // c) for n, c in zip(self.shape, self.chunk_shape))

    @property
    def n_chunks(self) -> int:
        return math.prod(self.chunk_grid)

    def chunk_region(self, k: int) -> tuple[slice, ...]:
        """The grid region of chunk `k` (chunks numbered in C order of the chunk grid)."""
        at = np.unravel_index(int(k), self.chunk_grid) if self.dims else ()
        return tuple(slice(i * c, min((i + 1) * c, n)) for i, c, n in zip(at, self.chunk_shape, self.shape))

    def chunk_scenes(self, k: int) -> int:
        return math.prod(s.stop - s.start for s in self.chunk_region(k))

    def chunk_values(self, k: int) -> dict[str, np.ndarray]:
        """Per scene of chunk `k` (C order of its region): the value of every quantity the sweep
        sets (axes and fixed); `record` as an index into `records`."""
        return self.values_at(self.chunk_region(k))

    def values_at(self, region: tuple[slice, ...], dims: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
        """Per scene of the grid region `region` of the axes `dims` (default: all; C order): the
        value of every quantity the sweep sets (axes and fixed; the axes not in `dims` left out);
        `record` as an index into `records`."""
        dims = self.dims if dims is None else dims
        grids = np.meshgrid(*(np.arange(s.start, s.stop) for s in region), indexing="ij")
        n = math.prod(s.stop - s.start for s in region)
        out = {name: np.full(n, v) for name, v in self.fixed.items()}
        for name, idx in zip(dims, grids):
            out[name] = idx.ravel() if name == "record" else self.axes[name][idx.ravel()]
        return out

    # -- what made it -----------------------------------------------------------------------------
    def description(self) -> dict[str, str]:
        """Everything that determines the sweep's numbers and its store's layout
        (`jaxrock.io.provenance`): a store made by another description is refused."""
        from ..io import provenance

        d = provenance.describe(model=self.template_model, excitation=self.excitation, integrator=self.integrator,
                                grid={k: v for k, v in self.axes.items() if k != "record"})
        d.update({"model kind": self.kind, "backbone": str(self.backbone), "chunk_shape": str(self.chunk_shape),
                  "sensitivity": str(self.sensitivity)})
        if "record" in self.axes:
            d["grid record"] = ",".join(self.axes["record"])
        d.update({f"fixed {k}": repr(v) for k, v in self.fixed.items()})
        for r in self.records:
            d[f"record {r.name}"] = provenance.value_text(np.concatenate([np.ravel(r.acc), np.ravel(r.dt)]))
        return d

    def attrs(self) -> dict:
        """The store's attributes: how it was made, readable (every fixed value, the integrator,
        versions) and complete (`made_by`, the `description` as JSON)."""
        from ..io import provenance

        model = self.template_model
        return {
            "title": f"jaxrock sweep: {self.kind} model, {self.excitation}",
            **provenance.file_attrs(model, self.integrator),
            "model_kind": self.kind,
            "backbone": str(self.backbone),
            "excitation": self.excitation,
            **{f"fixed_{k}": v for k, v in self.fixed.items()},
            "made_by": provenance.to_json(self.description()),
        }

    @functools.cached_property
    def batch_limit(self) -> int:
        """Scenes per vmapped batch whose running state fits the batch engine's memory budget
        (`engine.batch_limit`): a chunk larger than it runs in several batches."""
        import equinox as eqx

        from ..sensitivity import forward_integrator

        model = self.template_model
        if self.sensitivity:
            integ = forward_integrator(model, self.integrator)
        else:
            integ = model.default_integrator() if self.integrator is None else self.integrator
        return batch_limit(eqx.filter_eval_shape(make_stepper, model, integ, False, self.sensitivity))

    @property
    def kind(self) -> str:
        """The model kind's name, or the class name of a model given as a value."""
        return self.model if isinstance(self.model, str) else type(self.model).__name__

    @property
    def excitation(self) -> str:
        """The pulse class's name (`RickerPulse`, ...), or "records"."""
        return "records" if self.pulse is None else pulse_class(self.pulse).__name__

    # -- models and excitations -------------------------------------------------------------------
    def _model_kwargs(self, v: dict, i=slice(None)) -> dict:
        from ..construct import kind_values

        kw = {k: x[i] for k, x in kind_values(self.model, v).items()}
        if self.backbone is not None:
            kw["backbone"] = self.backbone
        return kw

    @functools.cached_property
    def template_model(self):
        """The model of the sweep's first scene (unbatched; built once)."""
        return self._models(self.chunk_values(0), batched=False)

    def resized(self, height):
        """The model value at full height `height` and its own slenderness (and base's)."""
        import equinox as eqx

        block = self.model.block
        new = type(block).from_slenderness(height, block.tan_alpha, block.b_base / block.h, exact_inertia=block.exact_inertia)
        return eqx.tree_at(lambda m: m.block, self.model, new)

    def _models(self, v: dict, batched: bool):
        import jax
        import jax.numpy as jnp

        from ..construct import scene_model
        from ..geometry import Block
        if not isinstance(self.model, str):
            if "height" not in v:
                return self.model
            return jax.vmap(self.resized)(jnp.asarray(v["height"])) if batched else self.resized(float(v["height"][0]))
        if not batched:
            block = Block.from_slenderness(float(v["height"][0]), float(v["tan_alpha"][0]),
                                           None if "tan_alpha_base" not in v else float(v["tan_alpha_base"][0]))
            return scene_model(self.model, block, **self._model_kwargs(v, 0))
        tb = v.get("tan_alpha_base", v["tan_alpha"])
        block = jax.vmap(Block.from_slenderness)(jnp.asarray(v["height"]), jnp.asarray(v["tan_alpha"]), jnp.asarray(tb))
        kw = {k: jnp.asarray(x) for k, x in self._model_kwargs(v).items() if k != "backbone"}
        backbone = {} if self.backbone is None else {"backbone": self.backbone}
        return jax.vmap(lambda b, kw: scene_model(self.model, b, **kw, **backbone))(block, kw)

    def _excitations(self, v: dict, model, batched: bool):
        import jax
        import jax.numpy as jnp

        from ..construct import pulse_values, scene_pulse

        if self.pulse is not None:
            values = {k: jnp.asarray(x) for k, x in {**pulse_values(self.pulse, v), "accel_ratio": v["accel_ratio"],
                                                     "omega_ratio": v["omega_ratio"]}.items()}
            if batched:
                return jax.vmap(lambda b, vv: scene_pulse(self.pulse, b, vv))(model.block, values)
            return jax.vmap(lambda vv: scene_pulse(self.pulse, model.block, vv))(values)
        import equinox as eqx

        from ..io.scenes_file import stack

        # every record padded to the sweep's longest, under one name: one compiled program per
        # sweep, and scenes of several records in one batch (a bisection's)
        which = np.asarray(v["record"]).astype(int)
        scale = jnp.asarray(v.get("scale", np.ones(which.size)), dtype=float)
        longest = max(r.n for r in self.records)
        pairs = any(r.vertical is not None for r in self.records)  # one structure for pairs and single records
        padded = {r: self.records[r].padded(longest, "record", vertical=pairs) for r in np.unique(which).tolist()}
        if len(padded) == 1:
            return jax.vmap(padded[int(which[0])].scaled)(scale)
        base = stack([padded[r] for r in which.tolist()])
        return eqx.tree_at(lambda e: e.scale, base, base.scale * scale)


def run_chunk(sweep: Sweep, k: int, devices=None) -> dict[str, np.ndarray]:
    """The summary outputs (and `status`) of chunk `k`, each an array of the chunk's region
    (`run_values`). `devices`: the devices its scenes are sharded over (None: every local one)."""
    shape = tuple(s.stop - s.start for s in sweep.chunk_region(k))
    return {name: a.reshape(shape) for name, a in run_values(sweep, sweep.chunk_values(k), devices).items()}


def run_values(sweep: Sweep, v: dict[str, np.ndarray], devices=None) -> dict[str, np.ndarray]:
    """The summary outputs (and `status`, int32) of the scenes `v` (quantity → one value per scene,
    as `Sweep.values_at` gives them; of one record or several), one array each. One model for all scenes
    when no model quantity varies among them (a spectrum's grid), else one per scene; run in
    batches of at most `sweep.batch_limit` scenes, sharded over `devices` (None: every local one)."""
    import jax

    from ..results import status_codes

    batched = any(np.unique(v[q]).size > 1 for q in model_quantities() if q in v)
    model = sweep._models(v, batched)
    exc = sweep._excitations(v, model, batched)
    n, limit = len(next(iter(v.values()))), sweep.batch_limit
    take = lambda tree, sl: jax.tree_util.tree_map(lambda x: x[sl], tree)
    parts = []
    for lo in range(0, n, limit):
        sl = slice(lo, min(lo + limit, n))
        m = take(model, sl) if batched else model
        sol = run_batch(m, take(exc, sl), sweep.integrator, model_batched=batched, devices=devices, sensitivity=sweep.sensitivity)
        parts.append({name: np.asarray(getattr(sol, name)) for name in OUTPUTS} | {"status": np.asarray(status_codes(sol.status))})
    out = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    out["status"] = out["status"].astype(np.int32)
    return out


def _store_task(path: str, sweep: Sweep, k: int) -> int:
    """A Dask task: chunk `k` run on the worker's devices and written to its own region."""
    from ..io.store import write_chunk

    write_chunk(path, sweep, k, run_chunk(sweep, k))
    return sweep.chunk_scenes(k)


def run_sweep(sweep: Sweep, store=None, *, client=None, devices=None, progress: bool = True, history: str | None = None,
              on_chunk: Callable[[int], None] | None = None):
    """Run `sweep` and return its results as an `xarray.Dataset` (dimensions: its axes).

    SIGINT / SIGTERM (inside `jaxrock.interrupt.deferred_signals`) stop it after the chunk in progress
    with `jaxrock.interrupt.Interrupted`; what finished is in the store.

    Arguments:
        sweep: the sweep (`Sweep.make`).
        store (str | os.PathLike | None): a Zarr store folder (`jaxrock.io.store`): created if missing,
            else checked and only its missing chunks run; default None: nothing is written and every
            chunk runs here.
        client (dask.distributed.Client | None): each missing chunk is a task that writes its own region
            of the store (a lost worker's chunk is run again by Dask); default None: chunks run in this
            process.
        devices (Sequence[jax.Device] | None): the devices chunks are sharded over; default None:
            every local device.
        progress: show a progress bar; default True.
        history: the command, for the attributes of a new store; default None.
        on_chunk: called with each finished chunk's index; default None.

    Returns:
        (xarray.Dataset): the summary outputs and `status` over the sweep's axes.

    Raises:
        JaxrockInputError: when `client` is given without a store, the store was made by another
            sweep or is unreadable, or another run is writing into it (`<store>.lock`).

    Example:
        ```python
        ds = jaxrock.run_sweep(jaxrock.Sweep.make("rigid", accel_ratio=[1, 2, 4], omega_ratio=[2, 4]))
        ds.max_theta.sel(accel_ratio=2.0)
        ```
    """
    from ..io import store as zstore
    from ..io.files import exclusive

    if client is not None and store is None:
        raise JaxrockInputError("a Dask cluster writes into a store: give store=PATH")
    with contextlib.ExitStack() as stack:
        if store is not None:
            stack.enter_context(exclusive(store, "store"))
            zstore.open_for(store, sweep, history)
        return _run(sweep, store, client, devices, progress, on_chunk)


def _run(sweep, store, client, devices, progress, on_chunk):
    """`run_sweep` with its store (if any) made and held."""
    from tqdm.auto import tqdm

    from ..io import store as zstore

    done = set()
    if store is not None:
        done, damaged = zstore.survey(store, sweep)
        if damaged:
            zstore.unflag(store, damaged)  # a rerun cut short leaves them to run again, never as done
            for k, why in damaged.items():
                print(f"store {store}: chunk {k} is damaged ({why}); running it again", file=sys.stderr)
    todo = (k for k in range(sweep.n_chunks) if k not in done)  # lazily: a sweep may have more chunks than memory holds
    held = {}
    bar = tqdm(total=sweep.size, initial=sum(sweep.chunk_scenes(k) for k in done), unit="scene", desc="sweep",
               disable=not progress, smoothing=0.1)

    def finished_chunk(k):
        bar.update(sweep.chunk_scenes(k))
        if on_chunk is not None:
            on_chunk(k)

    try:
        if client is None:
            _run_here(sweep, todo, store, held, devices, finished_chunk)
        else:
            _run_on_cluster(client, os.path.abspath(store), sweep, list(todo), finished_chunk)  # workers may start elsewhere
    finally:
        bar.close()
    if store is None:
        return zstore.in_memory(sweep, held)
    return zstore.load(store)


def _run_here(sweep: Sweep, todo: Iterable[int], store, held: dict, devices, finished_chunk: Callable[[int], None]) -> None:
    """The chunks of `todo` in this process, one per device at a time (`on_devices`), each written
    by one more thread while the next ones run. Every chunk runs as it would alone on one device:
    the same bits. Leaving waits for the writes in progress, so a finished chunk is kept."""
    from ..io import store as zstore

    writes = []

    def done(k, out):
        if store is None:
            held[k] = out
            finished_chunk(k)
        else:
            writes.append(writer.submit(lambda k, out: zstore.write_chunk(store, sweep, k, out) or k, k, out))
        for w in [w for w in writes if w.done()]:
            writes.remove(w)
            finished_chunk(w.result())

    with ThreadPoolExecutor(max_workers=1) as writer:
        try:
            on_devices(lambda k, devs: run_chunk(sweep, k, devs), todo, devices, done)
        finally:
            for w in writes:
                finished_chunk(w.result())


def _run_on_cluster(client, path: str, sweep: Sweep, todo: Iterable[int], finished_chunk: Callable[[int], None]) -> None:
    """Every chunk of `todo` as a Dask task (a task run twice writes the same bytes, so a lost
    worker's chunk run again elsewhere is harmless); `finished_chunk(k)` as each one ends."""
    from distributed import as_completed

    from .. import interrupt

    futures = client.map(_store_task, [path] * len(todo), [sweep] * len(todo), list(todo), pure=False, key=[
        f"jaxrock-chunk-{k}-{time.time_ns()}" for k in todo])
    by_key = {f.key: k for f, k in zip(futures, todo)}
    try:
        for f in as_completed(futures, loop=client.loop):
            f.result()  # a task's error is raised here
            finished_chunk(by_key[f.key])
            interrupt.stop_point()
    finally:
        client.cancel(futures)


__all__ = ["Sweep", "run_chunk", "run_sweep", "run_values", "axis_order", "model_quantities"]
