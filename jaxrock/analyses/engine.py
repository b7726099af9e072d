"""The batch engine: summaries of many scenes at once, each driven through its model's
`AbstractStepper` (`jaxrock.model`). Where the stepper's `Schedule` has passes (the rigid model,
spring-model summaries) a batch is advanced a few loop steps at a time and the cells still
running are gathered into a smaller batch between passes, so that a few long cells (chattering
near the uplift line, rocking near the overturning line) do not make the whole batch wait; with
`Schedule.lanes` (the spring model's dearer steps) a pass holds at most that many cells and a
finished cell's place goes to the next one; a stepper made of independent runs (`parts`: a
`Checked` run and its companion) runs each apart. Else it is one vmapped solve. Lanes of a pass move in
lockstep, each loop step costing the pass its slowest lane's work, so the cells run in the order of
their intensity (`cell_order`: peak |üg| over g tanα′), and on a CPU a pass holds at most
`MAX_PASS` cells: cells that rock alike share a pass, and a pass's state stays in the caches.
Every scene is guarded as `simulate` guards it. Used by the spectra, the
scenes files and any sweep. With several local devices each pass is sharded over them
(`kernels.advance`: a `NamedSharding` of the cells over a 1-D mesh, each device running the
one-device kernel on its block: the last bits of a smaller batch). A CPU's devices (one per core,
`jaxrock.use_cpu_cores`) run a batch's cells dealt in shares, one per device from a thread each
(`_dealt`), and a sweep's chunks one per device (`on_devices`).

Three calls, three sizes: `simulate` runs one scene; `run_batch` a batch in memory (one model for
every excitation, or one per scene with `model_batched`); `run_scenes`
(`jaxrock.analyses.scenes`) a scenes file, grouped into such batches."""

from __future__ import annotations

import functools
from concurrent.futures import ALL_COMPLETED, FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import Callable, Iterable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._validate import JaxrockInputError
from ..excitation import AbstractExcitation
from ..model import AbstractIntegrator, AbstractModel, AbstractStepper, flag_invalid, guard_scene
from ..sensitivity import Sensitivity, forward_integrator
from ..results import Solution
from . import kernels
from .kernels import vmap_scenes as _vmap


def batch_limit(stepper: AbstractStepper, budget_bytes: int = 2**29) -> int:
    """Cells per batch whose running state fits `budget_bytes` (`Schedule.bytes_per_scene`; at
    least 64), e.g. a flexible generalized-α cell's ladder of tangent inverses."""
    per = stepper.schedule.bytes_per_scene
    return 2**62 if per <= 0 else max(64, budget_bytes // per)


def ladder(n: int, smallest: int) -> int:
    """The size a batch of `n` cells is padded to: the least smallest·2^k ≥ n. Every batch and every
    gathered pass of it runs at a size of this ladder, so that a few compiled kernels serve every
    call (a spectrum's grid, its gathered passes and its refinement share them; padding costs at
    most the first pass's cells twice over)."""
    size = smallest
    while size < n:
        size *= 2
    return size


def even_batches(n: int, limit: int, smallest: int) -> int:
    """A batch size for `n` cells, at most `limit`: the largest smallest·4^k that splits them into
    at least four batches (a progress bar that moves); a batch and the passes gathered from it
    (a quarter, a sixteenth) are then sizes of the `ladder`, unpadded. A grid of fewer cells runs
    as one batch."""
    size = smallest
    while size * 4 <= limit and -(-n // (size * 4)) >= 4:
        size *= 4
    return min(size if n > 4 * smallest else n, limit)


# The most cells one pass runs at once on a CPU device (more are run as several passes of this
# size, one after another): the fewer a pass's lanes, the less its lockstep waits on its slowest,
# until each pass's fixed cost tells (a probe of 256/512/1024/4096 on rigid pulse batches of 4096
# grid cells and 4096 and 32768 random scenes, 2 cores: 512 and 256 best, 4096 worst by a third;
# benchmarks/bench_throughput.py). Accelerators take the whole batch at once (2^20 rigid cells in one
# batch: 4.9 s on an H100).
MAX_PASS = {"cpu": 512}

# A stepper's `Schedule.lanes` (a dear step's cells per pass, tuned on CPU cores) is multiplied by
# this on each platform: an accelerator's loop step costs about the same for many more lanes (its
# cost is kernel launches, not arithmetic). On an H100 the spring models ran 10-17x slower per scene
# than 2 CPU cores at the CPU's lanes; at 128x them, 4.9x (quasi-rigid, 65536 random scenes) and
# 29x (flexible, 8192) faster than 2 cores (benchmarks/results/bench_throughput_gpu_spring.txt,
# bench_throughput_spring_large.txt); 16x was slower, 1024x no faster.
LANE_SCALE = {"cpu": 1}
ACCELERATOR_LANE_SCALE = 128


def _bucket(n: int, batch: int, smallest: int) -> int:
    """The size a pass of `n` running cells is padded to: the batch's ladder size, a quarter of it,
    a sixteenth, ..., down to a single cell. On a CPU every padded lane costs a cell's work: the
    last long cell of a record suite (625 impacts over 40 s) took 40 s padded to 64 lanes, against
    0.7 s alone; the few extra kernel sizes (16, 4, 1 below 64) compile once."""
    size = ladder(batch, smallest)
    while size // 4 >= max(n, 1):
        size //= 4
    return size


# How much padding a pass piece may carry on each platform (`_pieces`): a piece is the least size
# of `_bucket`'s ladder that holds the cells left when it pads them by at most this factor, else the
# next size down. An accelerator pads freely (one piece: a padded lane costs it next to nothing, a
# launch does).
PIECE_SLACK = {"cpu": 1.25}


def _pieces(n: int, batch: int, smallest: int, slack: float = PIECE_SLACK["cpu"]) -> list[int]:
    """The padded sizes, in turn, that a pass of `n` running cells is run in: each the least
    `_bucket` size that holds the cells left when that pads them by at most `slack`, else the next
    size down (full); sizes up to `smallest` pad freely. On a CPU a padded lane costs a cell's work
    and a lane of a larger piece waits on more neighbours: 200 cells run as 128 + 32 + 32 + 8 rather
    than padded to 512 (`benchmarks/bench_throughput.py`, 2 cores: 4096 random rigid pulse scenes
    65.9 → 54.8 µs a scene, 1.59 → 1.22× the ordered grid's; 65536, 40.9 → 32.2)."""
    sizes = []
    while n > 0:
        size = _bucket(n, batch, smallest)
        if size > slack * n and size > smallest:
            size //= 4
        sizes.append(size)
        n -= size
    return sizes


def _check_batch_sizes(model, exc, batched) -> None:
    """Every array leaf of `exc` (and of `model`, when batched) has one leading batch size."""
    sizes = {}
    for what, tree in (("excitations", exc), *((("model", model),) if batched else ())):
        for leaf in jax.tree_util.tree_leaves(eqx.filter(tree, eqx.is_array)):
            if np.ndim(leaf) == 0:
                raise JaxrockInputError(f"run_batch: every array of the {what} needs a leading batch axis; one is a scalar "
                                        f"(build them under jax.vmap, or pass model_batched=False for one model)")
            sizes.setdefault(what, set()).add(int(np.shape(leaf)[0]))
    every = set().union(*sizes.values()) if sizes else set()
    if len(every) > 1:
        raise JaxrockInputError("run_batch: the batch sizes differ (" + "; ".join(f"{w}: {sorted(v)}" for w, v in sizes.items())
                                + "); every scene needs its model and its excitation")


@eqx.filter_jit
def _guard(model, exc, batched):
    """Per scene: its values where within their limits, else the quiet scene's, and whether they
    were (as `simulate`: a batch built under vmap cannot be refused at construction). A model
    without a batch axis was checked when it was built and is returned as it is."""

    def one(m, e):
        m, e, ok = guard_scene(m, e)
        return (m if batched else None), e, ok

    m, e, ok = _vmap(one, batched)(model, exc)
    return (m if batched else model), e, ok


_flag = eqx.filter_jit(eqx.filter_vmap(flag_invalid))  # `flag_invalid`, scene by scene


@eqx.filter_jit
def make_stepper(model: AbstractModel, integrator: AbstractIntegrator, model_batched: bool, sensitivity: bool = False) -> AbstractStepper:
    """The summary stepper of `model` (of each model, vmapped, when `model_batched`), with its
    sensitivity where asked (`jaxrock.sensitivity.Sensitivity`): what a model prepares once (mass
    matrices, tangents, preloads) is computed once for the whole batch."""
    make = (lambda m: Sensitivity(m.stepper(integrator))) if sensitivity else (lambda m: m.stepper(integrator))
    if model_batched:
        return eqx.filter_vmap(make)(model)
    return make(model)


# `_init` and `kernels.advance` return the states with their done flags: the host loop reads the flags
# without sending the states back (a flexible cell's state holds its ladder of tangent inverses).
@eqx.filter_jit
def _init(stepper, exc, batched):
    return _vmap(lambda s, e: (lambda c: (c, s.done(c)))(s.init(e)), batched)(stepper, exc)


@eqx.filter_jit
def _finish(stepper, exc, state, batched):
    return _vmap(lambda s, es: s.finish(es[0], es[1]), batched)(stepper, (exc, state))


@eqx.filter_jit
def _join(stepper, exc, sols, batched):
    return _vmap(lambda s, es: s.join(es[0], es[1]), batched)(stepper, (exc, sols))


@eqx.filter_jit
def _solve(stepper, exc, batched):
    return _vmap(lambda s, e: s.solve(e), batched)(stepper, exc)


def mesh_of(devices=None):
    """A 1-D mesh (axis "scenes") of `devices` (None: every local accelerator, or the first CPU
    device: passes in lockstep over host devices cost more than on one, a record batch of 64 rigid
    cells 0.58 s on two against 0.49 s on one on 2 cores; a CPU's cores serve a sweep's chunks,
    one each, `jaxrock.analyses.sweep`); None for one device."""
    if devices is None:
        devices = jax.local_devices()
        devices = devices[:1] if devices[0].platform == "cpu" else devices
    devices = list(devices)
    return jax.sharding.Mesh(np.asarray(devices), ("scenes",)) if len(devices) > 1 else None


# Whether a platform's passes gather and scatter their cells on the device (the default) or on
# the host (a CPU: the host is the device, and numpy's gathers of any size compile nothing).
GATHER_ON_DEVICE = {"cpu": False}

_take = jax.jit(lambda tree, i: jax.tree_util.tree_map(lambda x: x[i], tree))
_put = jax.jit(lambda tree, sub, i: jax.tree_util.tree_map(lambda x, y: x.at[i].set(y), tree, sub), donate_argnums=0)


def _put_host(x, idx, y):
    x[idx] = y[: idx.size]
    return x


@eqx.filter_jit
def _intensity(model, exc, batched):
    """Each cell's peak ground acceleration over its body's uplift acceleration (g tanα′)."""
    return _vmap(lambda m, e: None if e.peak is None else e.peak / m.block.uplift_acceleration, batched)(model, exc)


def cell_order(model: AbstractModel, excitations, batched: bool) -> np.ndarray:
    """The order a batch's cells run in: by intensity (`_intensity`), so that cells that rock alike
    (at rest, chattering near the uplift line, rocking, overturning at once) share the lockstep
    passes, where a random set mixed them: on 16384 random rigid pulse scenes, a third less time
    in a probe. The given order where an excitation does not know its peak (`peak` None) or a
    model has no `block`."""
    n = jax.tree_util.tree_leaves(excitations)[0].shape[0]
    key = _intensity(model, excitations, batched) if hasattr(model, "block") else None
    if key is None:
        return np.arange(n)
    key = np.asarray(key)
    return np.argsort(np.where(np.isfinite(key), key, np.inf), kind="stable")


def _start(stepper: AbstractStepper, excitations, batched: bool, starts: dict | None, key, on_device: bool):
    """`_init`'s (states, done flags); where a stepper's `parts` share their start (`starts`, a
    dict), the first part's, kept under `key` (the share of cells) for the next (on an accelerator
    a copy: the passes donate their states)."""
    if starts is not None and key in starts:
        kept = starts[key]
        return jax.tree_util.tree_map(jnp.copy, kept) if on_device else kept
    start = _init(stepper, excitations, batched)
    if starts is not None:
        starts[key] = jax.tree_util.tree_map(jnp.copy, start) if on_device else start
    return start


def _compacted(stepper: AbstractStepper, excitations, batched: bool, mesh, order: np.ndarray, starts: dict | None = None,
               key=0) -> Solution:
    """Run a batch in passes (`Schedule.passes`), gathering the cells still running between
    passes (with `Schedule.lanes`, at most that many, the started ones first, so that a finished
    cell's place goes to the next): the same results as `simulate`, cell by cell. The running cells
    are taken in `order` (`cell_order`), in passes of at most `MAX_PASS` cells on a CPU. With a `mesh`
    each pass is sharded over its devices: passes are padded to a multiple of their number, and
    `lanes` is per device. `starts`, `key`: a start shared with other parts (`_start`)."""
    passes, smallest, lanes = stepper.schedule.passes, stepper.schedule.smallest_batch, stepper.schedule.lanes
    n_dev = 1 if mesh is None else mesh.size
    platform = (jax.devices()[0] if mesh is None else mesh.devices.flat[0]).platform
    lanes *= n_dev * LANE_SCALE.get(platform, ACCELERATOR_LANE_SCALE)
    most = MAX_PASS.get(platform, 2**62) * n_dev
    n = jax.tree_util.tree_leaves(excitations)[0].shape[0]
    # On a CPU the state (and the batched inputs) live on the host between passes: gathers and
    # scatters of changing sizes in numpy cost nothing. On an accelerator they stay on the device
    # (`GATHER_ON_DEVICE`), gathered and scattered there by the padded index (the ladder's sizes:
    # a few small programs), so that only the done flags and the indices cross to the host.
    on_device = mesh is None and GATHER_ON_DEVICE.get(platform, True)  # a mesh's shards: gathered on the host
    keep = (lambda t: t) if on_device else (lambda t: jax.tree_util.tree_map(np.array, t))
    dyn_e, static_e = eqx.partition(excitations, eqx.is_array)
    dyn_s, static_s = eqx.partition(stepper, eqx.is_array)
    dyn_e, dyn_s = keep(dyn_e), keep(dyn_s)
    state, done = _start(stepper, excitations, batched, starts, key, on_device)
    state, done = keep(state), np.array(done)
    started = np.zeros(n, dtype=bool)
    used, k = 0, 0
    while lanes or used < stepper.max_steps:  # with lanes, each cell's own bound ends it (`done`)
        todo = order[~done[order]]
        if todo.size == 0:
            break
        if lanes:
            todo = np.concatenate([todo[started[todo]], todo[~started[todo]]])[:lanes]
            started[todo] = True
            n_pass, sizes = passes[k], [_bucket(todo.size, lanes, smallest)]
        else:
            n_pass = min(passes[k], stepper.max_steps - used)
            sizes = _pieces(todo.size, min(n, most), smallest, PIECE_SLACK.get(platform, float("inf")))
        lo = 0
        for size in sizes:
            size = -(-size // n_dev) * n_dev
            idx, lo = todo[lo : lo + size], lo + size
            if idx.size == 0:
                break
            padded = np.concatenate([idx, np.full(size - idx.size, idx[0])])
            take = (lambda t: _take(t, padded)) if on_device else (lambda t: jax.tree_util.tree_map(lambda x: x[padded], t))
            sub_s = eqx.combine(take(dyn_s), static_s) if batched else stepper
            sub_e = eqx.combine(take(dyn_e), static_e)
            sub_c, sub_done = kernels.advance(sub_s, sub_e, take(state), n_pass, batched, mesh)
            if on_device:  # the padding repeats idx[0], whose lanes computed the same values
                state = _put(state, sub_c, padded)
            else:
                state = jax.tree_util.tree_map(lambda x, y: _put_host(x, idx, y), state, keep(sub_c))
            done[idx] = np.asarray(sub_done)[: idx.size]
        used += n_pass
        k = min(k + 1, len(passes) - 1)
    return _finish(stepper, excitations, state, batched)


def on_devices(fn: Callable, items: Iterable, devices, done: Callable) -> None:
    """`fn(item, [device])` for each of `items`, one item per local device at a time (`devices`;
    None: every local one), each from a thread of its own: host devices dispatched from one thread
    run one after the other, so a CPU's cores (one device each, `jaxrock.use_cpu_cores`) are used
    by running an item on each. `done(item, result)` runs in the calling thread as each finishes.
    `interrupt.stop_point()` is checked before each item starts; leaving (an interruption, an
    error) waits for the items in flight and hands the finished ones to `done` first."""
    from .. import interrupt

    free = list(jax.local_devices() if devices is None else devices)[::-1]
    if len(free) == 1:  # one device: in this thread
        for item in items:
            interrupt.stop_point()
            done(item, fn(item, free))
        return
    in_flight = {}  # future → (position, item, device)

    def collect(block: bool):
        finished, _ = wait(in_flight, return_when=FIRST_COMPLETED if block else ALL_COMPLETED)
        failed = None
        for fut in sorted(finished, key=lambda f: in_flight[f][0]):
            _, item, dev = in_flight.pop(fut)
            free.append(dev)
            if fut.exception() is not None:  # the others are kept before it is raised
                failed = failed or fut.exception()
            else:
                done(item, fut.result())
        if failed is not None:
            raise failed

    with ThreadPoolExecutor(max_workers=len(free)) as pool:
        try:
            for i, item in enumerate(items):
                interrupt.stop_point()
                if not free:
                    collect(block=True)
                dev = free.pop()
                in_flight[pool.submit(fn, item, [dev])] = (i, item, dev)
        finally:
            if in_flight:
                collect(block=False)


def _host_devices(devices, n: int, smallest: int) -> list:
    """The CPU devices a batch of `n` cells is dealt over (`_dealt`): with `devices` None, every
    local one where JAX has several (one per core, `jaxrock.use_cpu_cores`), as many as hold at
    least `smallest` cells each; else none (an accelerator's passes take the whole batch, and given
    `devices` are a mesh's, `mesh_of`)."""
    local = jax.local_devices() if devices is None else []
    if len(local) < 2 or local[0].platform != "cpu":
        return []
    return local[: min(len(local), n // smallest)]


def _dealt(stepper: AbstractStepper, excitations, batched: bool, order: np.ndarray, devices: list, starts: dict | None = None) -> Solution:
    """A batch over a CPU's devices: its cells, in `order`, dealt to the devices in turn (so that
    each share spans every intensity and costs about the same), each share run by `_compacted` on
    its device from a thread of its own (`on_devices`): a CPU device's computations run on the
    thread that asks for them, so one thread uses one core (2 cores: 1.8-2.2x one thread on rigid
    and spring batches, benchmarks/bench_throughput.py). The shares are fixed by `order`, so the
    bits do not depend on the threads' timing; a cell's last bits are those of its share's batch
    (`run_batch`: 1e-10). `starts`: the parts' shared starts (`_start`), one per share."""
    k, n = len(devices), order.size
    shares = [order[g::k] for g in range(k)]
    dyn_e, static_e = eqx.partition(excitations, eqx.is_array)
    dyn_s, static_s = eqx.partition(stepper, eqx.is_array)
    host = lambda t, idx: jax.tree_util.tree_map(lambda x: np.asarray(x)[idx], t)
    shared = None if batched else eqx.combine(host(dyn_s, ...), static_s)  # one model: on the host, for every share

    def run(g: int, device):
        idx = shares[g]
        with jax.default_device(device[0]):
            sub_s = eqx.combine(host(dyn_s, idx), static_s) if batched else shared
            return _compacted(sub_s, eqx.combine(host(dyn_e, idx), static_e), batched, None, np.arange(idx.size), starts, (g, k))

    parts: dict[int, Solution] = {}
    on_devices(run, range(k), devices, parts.__setitem__)

    def merged(*leaves):
        out = np.empty((n, *np.shape(leaves[0])[1:]), np.asarray(leaves[0]).dtype)
        for idx, leaf in zip(shares, leaves):
            out[idx] = np.asarray(leaf)
        return out

    return jax.tree_util.tree_map(merged, *(parts[g] for g in range(k)))


def run_batch(
    model: AbstractModel,
    excitations: AbstractExcitation,
    integrator: AbstractIntegrator | None = None,
    *,
    model_batched: bool = False,
    devices=None,
    sensitivity: bool = False,
) -> Solution:
    """Summaries of a batch of scenes, one per excitation (and model).

    Driven through the model's `AbstractStepper`: in passes with the running cells gathered between
    them when its `schedule` has passes, else as one vmapped `solve`. A scene with a parameter
    outside its limits comes back `Status.invalid_input` with NaN numbers, as from `simulate`.
    The passes are sharded over `devices` (None: `mesh_of`'s; one device: no sharding), each
    device running its block of cells as a batch of that size (the last bits as below).

    The same scenes in the same batch give the same bits on the same machine. A scene run in
    another batch (another size or other neighbours) or alone through `simulate` may differ in its
    last bits: XLA compiles each batch shape to its own fused kernels, whose floating-point
    rounding differs, and the impact times are root finds that stop anywhere inside their
    tolerance (`root_tol`, 1e-13 s). Issue 52's hostile-input campaign saw 2.4e-12 at most in θ/α
    and in t_overturn [s]; `tests/test_batch.py` holds them to 1e-10.

    Arguments:
        model: the model, one for all scenes, or with a leading batch axis on every array leaf when
            `model_batched`.
        excitations: the excitations, with a leading batch axis on every array leaf (e.g. a
            `jax.vmap`ped constructor).
        integrator: the integrator; default None: the model's `default_integrator()`.
        model_batched: `model` holds one model per scene; default False.
        devices (Sequence[jax.Device] | None): the devices the passes are sharded over; default None:
            `mesh_of`'s (every local accelerator, or the first CPU device).
        sensitivity: each run carries the tangent of its motion along the excitation's log-scale and
            reports `Solution.sensitivity` (`jaxrock.sensitivity`; forward mode: without `integrator`,
            the model's forward-mode default); default False.

    Returns:
        The summaries (`Solution`), each field with the leading batch axis.

    Raises:
        JaxrockInputError: when an array leaf lacks the leading batch axis, the batch sizes differ, or
            `sensitivity` is asked of a reverse-mode integrator.

    Example:
        ```python
        import jax, jax.numpy as jnp, jaxrock
        model = jaxrock.RigidModel(jaxrock.Block.from_slenderness(10.0, 0.2))
        pulses = jax.vmap(jaxrock.RickerPulse)(jnp.linspace(1.0, 5.0, 64), jnp.full(64, 3.0))
        sol = jaxrock.run_batch(model, pulses)
        sol.overturned  # one flag per pulse
        ```
    """
    integ = forward_integrator(model, integrator) if sensitivity else model.default_integrator() if integrator is None else integrator
    _check_batch_sizes(model, excitations, model_batched)
    model, excitations, ok = _guard(model, excitations, model_batched)
    stepper = make_stepper(model, integ, model_batched, sensitivity)
    order = functools.cache(lambda: cell_order(model, excitations, model_batched))  # once, for every part
    sol = _execute(stepper, excitations, model_batched, order, devices)
    return _flag(sol, ok)


def _execute(stepper: AbstractStepper, excitations, batched: bool, order, devices, starts: dict | None = None) -> Solution:
    """A batch's `Solution`s through `stepper`: each of its `parts` apart (from one start computed
    once where they share it, `AbstractStepper.shared_start`), joined; else in passes
    (`Schedule.passes`: dealt over a CPU's devices or compacted on one device or mesh), else as one
    vmapped solve. `order()`: the cells' order (`cell_order`)."""
    if stepper.parts:
        starts = {} if stepper.shared_start else None
        sols = tuple(_execute(part, excitations, batched, order, devices, starts) for part in stepper.parts)
        return _join(stepper, excitations, sols, batched)
    if not stepper.schedule.passes:
        return _solve(stepper, excitations, batched)
    order = order()
    cores = _host_devices(devices, order.size, stepper.schedule.smallest_batch)
    if len(cores) > 1:
        return _dealt(stepper, excitations, batched, order, cores, starts)
    return _compacted(stepper, excitations, batched, mesh_of(devices), order, starts)
