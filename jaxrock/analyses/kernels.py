"""Kernels traced once and kept between processes: the batch engine's loop pass (for every batch
size) and one scene's run (`simulate`, as the command line calls it).

Tracing a stepper's `advance` under `vmap` is most of a short run's cost (the rigid stepper: ~2 s
on a 2-core CPU, diffrax's solve with its events and root finds), and `jit` traces again for every
new batch size: the compacted passes of one spectrum use three sizes and its refinement a fourth.
Here the pass is exported (`jax.export`) with a symbolic batch size, so one trace serves every
size in the process, and its serialized form is kept in the cache folder (`jaxrock.cache`,
`kernels/`), so that a later process does not trace it at all. XLA's compilation for each size is
then JAX's persistent compilation cache's. `simulate` here is `jaxrock.simulate` kept the same way
(its trace is ~1 s of a second `jaxrock simulate`); its output's structure, which a flat exported
kernel does not carry, is kept beside it (a pickled template: the cache folder is read as the
user's own files are). The numbers are the jitted functions', bit for bit.

An entry is keyed by the pass's structure (the stepper's and the excitation's types and static
values, every array's dtype and shape but the batch axis) under a folder named by a digest of
jaxrock's source, the versions of the libraries that trace it and the platform it is exported for
(`cpu`, `cuda`, ...: one cache folder serves a GPU run and a `JAX_PLATFORMS=cpu` run alike): a change
to any is a new entry, never a stale one; a kept kernel whose platforms lack this process's (a
file copied between folders) is exported again and replaced, never called. A structure whose static values have no stable text (an object printed with its
address) is traced once per process and not stored.
"""

from __future__ import annotations

import functools
import hashlib
import pickle
import threading
from importlib import metadata
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import export

from .. import cache
from ..io.files import write_atomically
from ..model import run_scene, scene_arguments

_TRACED_BY = ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax", "jaxtyping")
# A kernel is only read back by the same versions of these (its folder's digest), so the custom
# calls JAX guarantees no compatibility for across versions (LAPACK's QR in lineax's solves) are kept.
_EXPORT = functools.partial(export.export, disabled_checks=[export.DisabledSafetyCheck.custom_call("ALL")])


@functools.cache
def _store() -> Path | None:
    """The folder of stored passes for this jaxrock source and these libraries (None: cache off)."""
    root = cache.cache_root()
    if root is None:
        return None
    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    for name in _TRACED_BY:
        digest.update(f"{name}={metadata.version(name)}\0".encode())
    digest.update(f"x64={jax.config.jax_enable_x64}\0platform={export.default_export_platform()}".encode())
    return root / "kernels" / digest.hexdigest()[:24]


def vmap_scenes(fn, batched: bool):
    """vmap over (stepper, excitation, *rest): the stepper too when it carries a batch axis."""
    return eqx.filter_vmap(fn, in_axes=(eqx.if_array(0) if batched else None, eqx.if_array(0)))


def _pass(leaves_s, leaves_e, leaves_c, n, *, trees, statics, batched):
    """The engine's pass on flat leaves: every running cell at most `n` more loop steps."""
    tree_s, tree_e, tree_c = trees
    stepper = eqx.combine(jax.tree_util.tree_unflatten(tree_s, leaves_s), statics[0])
    exc = eqx.combine(jax.tree_util.tree_unflatten(tree_e, leaves_e), statics[1])
    state = jax.tree_util.tree_unflatten(tree_c, leaves_c)

    def one(s, es):
        c = s.advance(es[0], es[1], n)
        return c, s.done(c)

    c, done = vmap_scenes(one, batched)(stepper, (exc, state))
    return jax.tree_util.tree_leaves(c), done


_KERNELS: dict = {}
_MAKING = threading.Lock()


def _shapes(leaves, batched: bool) -> tuple:
    return tuple((x.shape[1:] if batched else x.shape, str(x.dtype)) for x in leaves)


def _static(tree) -> tuple:
    """A static part (of `eqx.partition`) as its leaves and structure: part of a kernel's key."""
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    return tuple(leaves), treedef


def _path(kind: str, structure) -> Path | None:
    """Where the kernel of this structure is kept (None: the cache is off, or the structure has no
    stable text: an object printed with its address)."""
    text = repr(structure)
    if _store() is None or " at 0x" in text:
        return None
    return _store() / f"{kind}-{hashlib.sha256(text.encode()).hexdigest()[:32]}.jax"


def _load_or_export(path: Path | None, export_now, with_template: bool = False):
    """(exported kernel, its template or None) from `path` (the template from the file beside it),
    else from `export_now()` (also where the kept one was exported for other platforms), then
    stored there for the next process."""
    template_path = None if path is None else path.with_suffix(".pkl")
    if path is not None and path.exists() and (not with_template or template_path.exists()):
        exported = export.deserialize(bytearray(path.read_bytes()))
        if export.default_export_platform() in exported.platforms:
            return exported, (pickle.loads(template_path.read_bytes()) if with_template else None)
    exported, template = export_now()
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        if with_template:  # written first: a kernel file is only ever found with its template
            blob_template = pickle.dumps(template)
            write_atomically(template_path, lambda tmp: tmp.write_bytes(blob_template))
        blob = bytes(exported.serialize())
        write_atomically(path, lambda tmp: tmp.write_bytes(blob))
    return exported, template


def advance(stepper, excitations, state, n, batched: bool, mesh=None):
    """(state, done) after at most `n` more loop steps of every cell: `engine`'s pass, through a
    kernel traced once for all batch sizes (see the module docstring). With a `mesh` (a 1-D
    `jax.sharding.Mesh`, axis "scenes") the cells are sharded over its devices
    (`NamedSharding`), each device running the one-device kernel on its own block: the code of
    a batch of the block's size, so the bits of that batch (a `shard_map` of it compiles an SPMD
    program whose code moved the last bit of 1 cell in 60); no device waits on another within the
    pass. The batch size must be a multiple of the mesh's size."""
    dyn_s, static_s = eqx.partition(stepper, eqx.is_array)
    dyn_e, static_e = eqx.partition(excitations, eqx.is_array)
    leaves_s, tree_s = jax.tree_util.tree_flatten(dyn_s)
    leaves_e, tree_e = jax.tree_util.tree_flatten(dyn_e)
    leaves_c, tree_c = jax.tree_util.tree_flatten(state)
    n = jnp.asarray(n)
    structure = (batched, tree_s, tree_e, tree_c, _static(static_s), _static(static_e),
                 _shapes(leaves_s, batched), _shapes(leaves_e, True), _shapes(leaves_c, True), str(n.dtype))
    with _MAKING:  # chunks and shares run from several threads (`engine.on_devices`): one trace per structure
        kernel = _KERNELS.get((structure, mesh))
        if kernel is None:
            try:
                call = _advance_kernel(structure, (leaves_s, leaves_e, leaves_c, n), (static_s, static_e)).call
            except NotImplementedError as e:  # a pass with a host callback cannot be exported: compiled for this process
                if "host_callback" not in str(e):  # (equinox's runtime checks in optimistix's implicit derivative of an
                    raise  # event's root find, under a sensitivity's `jvp`: `jaxrock.sensitivity`)
                call = functools.partial(_pass, trees=structure[1:4], statics=(static_s, static_e), batched=batched)
            kernel = _KERNELS[(structure, mesh)] = jax.jit(call) if mesh is None else _sharded(call, mesh, batched, leaves_s, leaves_e, leaves_c)
    if mesh is not None:
        cells = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("scenes"))
        leaves_s = jax.device_put(leaves_s, cells) if batched else leaves_s
        leaves_e, leaves_c = jax.device_put((leaves_e, leaves_c), cells)
    leaves, done = kernel(leaves_s, leaves_e, leaves_c, n)
    return jax.tree_util.tree_unflatten(tree_c, leaves), done


def _sharded(call, mesh, batched, leaves_s, leaves_e, leaves_c):
    """The pass `call` (an exported kernel's) over `mesh`: each device runs the one-device kernel on its block of cells
    (the blocks of the inputs' `NamedSharding`), dispatched to all devices before any is awaited;
    the outputs are assembled into arrays of the same sharding."""
    call = jax.jit(call)
    cells = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("scenes"))

    def run(ls, le, lc, n):
        blocks = [([x.addressable_shards[d].data for x in ls] if batched else [jax.device_put(x, dev) for x in ls],
                   [x.addressable_shards[d].data for x in le], [x.addressable_shards[d].data for x in lc], jax.device_put(n, dev))
                  for d, dev in enumerate(x.device for x in le[0].addressable_shards)]
        outs = [call(*b) for b in blocks]  # asynchronous: every device is busy before the first result is read
        size = le[0].shape[0]
        glue = lambda parts: jax.make_array_from_single_device_arrays((size, *parts[0].shape[1:]), cells, parts)
        return [glue([o[0][i] for o in outs]) for i in range(len(lc))], glue([o[1] for o in outs])

    return run


def _advance_kernel(structure, args, statics):
    """The stored pass of this structure (`jax.export.Exported`), exported (and stored) if not there."""
    batched, tree_s, tree_e, tree_c = structure[:4]

    def export_now():
        (b,) = export.symbolic_shape("b")
        spec = lambda x, lead: jax.ShapeDtypeStruct((b, *x.shape[1:]) if lead else x.shape, x.dtype)
        leaves_s, leaves_e, leaves_c, n = args
        fn = functools.partial(_pass, trees=(tree_s, tree_e, tree_c), statics=statics, batched=batched)
        return _EXPORT(jax.jit(fn))([spec(x, batched) for x in leaves_s], [spec(x, True) for x in leaves_e],
                                    [spec(x, True) for x in leaves_c], jax.ShapeDtypeStruct((), n.dtype)), None

    exported, _ = _load_or_export(_path("advance", structure), export_now)
    return exported


def simulate(model, excitation, *, integrator=None, save=None, t1=None):
    """`jaxrock.simulate` (the same checks, the same numbers), through a kernel traced once per
    structure and kept between processes. Not for use under `jit`, `vmap` or `grad`: call
    `jaxrock.simulate` there."""
    args = scene_arguments(model, excitation, integrator=integrator, save=save, t1=t1)
    dyn, static = eqx.partition(args, eqx.is_array)
    leaves, tree = jax.tree_util.tree_flatten(dyn)
    structure = ("simulate", tree, _static(static), _shapes(leaves, False))
    kernel = _KERNELS.get(structure)
    if kernel is None:
        kernel = _KERNELS[structure] = _simulate_kernel(structure, leaves, tree, static)
    return kernel(leaves)


def _simulate_kernel(structure, leaves, tree, static):
    """The call of the stored `run_scene` of this structure: flat leaves in, the `Solution` out
    (its array leaves from the kernel; its structure and static part from the kept template)."""

    def export_now():
        out = {}

        def flat(xs):
            dyn_out, out["static"] = eqx.partition(run_scene(*eqx.combine(jax.tree_util.tree_unflatten(tree, xs), static)),
                                                   eqx.is_array)
            ys, out["tree"] = jax.tree_util.tree_flatten(dyn_out)
            return ys

        exported = _EXPORT(jax.jit(flat))([jax.ShapeDtypeStruct(x.shape, x.dtype) for x in leaves])
        template = jax.tree_util.tree_unflatten(out["tree"], [np.zeros((), a.dtype) for a in exported.out_avals])
        return exported, (template, out["static"])

    try:
        exported, (template, static_out) = _load_or_export(_path("simulate", structure), export_now, with_template=True)
    except NotImplementedError:  # JAX exports no host callback: a quasi-rigid history by diffrax keeps one (test_cache)
        return lambda xs: run_scene(*eqx.combine(jax.tree_util.tree_unflatten(tree, xs), static))
    call, tree_out = jax.jit(exported.call), jax.tree_util.tree_structure(template)
    return lambda xs: eqx.combine(jax.tree_util.tree_unflatten(tree_out, call(xs)), static_out)


__all__ = ["advance", "simulate", "vmap_scenes"]
