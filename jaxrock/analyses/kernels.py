"""The batch engine's loop pass, traced once for every batch size and kept between processes.

Tracing a stepper's `advance` under `vmap` is most of a short run's cost (the rigid stepper: ~2 s
on a 2-core CPU, diffrax's solve with its events and root finds), and `jit` traces again for every
new batch size: the compacted passes of one spectrum use three sizes and its refinement a fourth.
Here the pass is exported (`jax.export`) with a symbolic batch size, so one trace serves every
size in the process, and its serialized form is kept in the cache folder (`jaxrock.cache`,
`kernels/`), so that a later process does not trace it at all. XLA's compilation for each size is
then JAX's persistent compilation cache's. The numbers are the jitted pass's, bit for bit.

An entry is keyed by the pass's structure (the stepper's and the excitation's types and static
values, every array's dtype and shape but the batch axis) under a folder named by a digest of
jaxrock's source and the versions of the libraries that trace it: a change to any is a new entry,
never a stale one. A structure whose static values have no stable text (an object printed with its
address) is traced once per process and not stored.
"""

from __future__ import annotations

import functools
import hashlib
from importlib import metadata
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import export

from .. import cache
from ..io.files import write_atomically

_TRACED_BY = ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax", "jaxtyping")


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
    digest.update(f"x64={jax.config.jax_enable_x64}".encode())
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


def advance(stepper, excitations, state, n, batched: bool):
    """(state, done) after at most `n` more loop steps of every cell: `engine`'s pass, through a
    kernel traced once for all batch sizes (see the module docstring)."""
    dyn_s, static_s = eqx.partition(stepper, eqx.is_array)
    dyn_e, static_e = eqx.partition(excitations, eqx.is_array)
    leaves_s, tree_s = jax.tree_util.tree_flatten(dyn_s)
    leaves_e, tree_e = jax.tree_util.tree_flatten(dyn_e)
    leaves_c, tree_c = jax.tree_util.tree_flatten(state)
    n = jnp.asarray(n)
    shapes = lambda xs, b: tuple((x.shape[1:] if b else x.shape, str(x.dtype)) for x in xs)
    static = lambda t: (lambda leaves, tree: (tuple(leaves), tree))(*jax.tree_util.tree_flatten(t))
    structure = (batched, tree_s, tree_e, tree_c, static(static_s), static(static_e),
                 shapes(leaves_s, batched), shapes(leaves_e, True), shapes(leaves_c, True), str(n.dtype))
    kernel = _KERNELS.get(structure)
    if kernel is None:
        kernel = _KERNELS[structure] = _kernel(structure, (leaves_s, leaves_e, leaves_c, n), (static_s, static_e))
    leaves, done = kernel(leaves_s, leaves_e, leaves_c, n)
    return jax.tree_util.tree_unflatten(tree_c, leaves), done


def _kernel(structure, args, statics):
    """The jitted call of the stored pass of this structure, exported (and stored) if not there."""
    batched, tree_s, tree_e, tree_c = structure[:4]
    text = repr(structure)
    path = None
    if _store() is not None and " at 0x" not in text:
        path = _store() / f"advance-{hashlib.sha256(text.encode()).hexdigest()[:32]}.jax"
    if path is not None and path.exists():
        exported = export.deserialize(bytearray(path.read_bytes()))
    else:
        (b,) = export.symbolic_shape("b")
        spec = lambda x, lead: jax.ShapeDtypeStruct((b, *x.shape[1:]) if lead else x.shape, x.dtype)
        leaves_s, leaves_e, leaves_c, n = args
        fn = functools.partial(_pass, trees=(tree_s, tree_e, tree_c), statics=statics, batched=batched)
        exported = export.export(jax.jit(fn))([spec(x, batched) for x in leaves_s], [spec(x, True) for x in leaves_e],
                                              [spec(x, True) for x in leaves_c], jax.ShapeDtypeStruct((), n.dtype))
        if path is not None:
            blob = bytes(exported.serialize())
            path.parent.mkdir(parents=True, exist_ok=True)
            write_atomically(path, lambda tmp: tmp.write_bytes(blob))
    return jax.jit(exported.call)


__all__ = ["advance", "vmap_scenes"]
