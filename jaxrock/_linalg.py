"""Dense linear algebra that cannot deadlock under `vmap` on XLA:CPU.

jaxlib 0.10.2 (the only release installable here) splits a *batched* LAPACK call (`getrf`,
`trsm`, `potrf`, `syevd`, … of at least ~2·10⁵ flops) into chunks queued on XLA:CPU's intra-op
thread pool, and the calling worker waits for them without running any. When the thunk executor
runs as many such kernels at once as the pool has threads, every worker waits: the process hangs
for ever (eight independent `jnp.linalg.inv` of 12 × 33 × 33 batches in one jitted function hang
every time on 2 cores; the flexible spring model vmapped over 12–16 scenes hung in 3 of 24 fresh
processes). Upstream removed that path in jax 0.11.1.

Every routine here therefore calls LAPACK on one matrix at a time on the CPU backend: batches,
whether they come from leading dimensions or from `vmap`, run as a sequential loop
(`jax.custom_batching.sequential_vmap`). On other backends (a GPU's cuSOLVER/cuBLAS), where there
is no such deadlock and a loop of single small solves would serialise the device, the batched call
is kept (chosen when traced, by `jax.default_backend()`; the kept kernels are keyed by platform).
That alone breaks reverse mode (a `custom_vmap` cannot be linearised), so each routine is a
`jax.custom_jvp` whose tangent is written with matrix products of primal-only factors
(d(A⁻¹) = −A⁻¹ dA A⁻¹, and likewise for solves and factorisations): `grad`, `jvp`, `vmap` and
Hessian–vector products all work. The matrices of jaxrock are small (3(n+1) ≤ ~150 DOFs), so a
loop over single LAPACK calls costs the same as the batched call (measured: the flexible model's
speed is unchanged).

Route every linear-algebra call that can run under `vmap` through this module; implicit diffrax
solvers take `SequentialLU` as the linear solver of their Newton iterations.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import lineax as lx
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, Float

__all__ = ["inv", "solve", "cholesky", "solve_triangular", "eigvalsh", "eigh_primal", "expm", "SequentialLU"]

# `expm`: the Taylor degree at a scaled norm ≤ 1/4 (remainder 0.25¹³/13! ~ 2e-18) and the most
# squarings (norms to 0.25·2¹⁶ ≈ 1.6e4)
_EXPM_DEGREE = 12
_EXPM_SQUARINGS = 16


def _one_at_a_time(fn, core_ndims: tuple[int, ...]):
    """`fn` on single core arrays; leading dimensions and `vmap` become a sequential loop on the
    CPU backend, a batched call elsewhere (module doc)."""
    seq = jax.custom_batching.sequential_vmap(fn)

    def apply(*args):
        lead = args[0].shape[: args[0].ndim - core_ndims[0]]
        f = seq if jax.default_backend() == "cpu" else fn
        for _ in lead:
            f = jax.vmap(f)
        return f(*args)

    return apply


_inv = _one_at_a_time(lambda a: jnp.linalg.inv(a), (2,))
_solve_vec = _one_at_a_time(lambda a, b: jnp.linalg.solve(a, b), (2, 1))
_cholesky = _one_at_a_time(lambda a: jnp.linalg.cholesky(a), (2,))
_eigh = _one_at_a_time(lambda a: tuple(jnp.linalg.eigh(a)), (2,))


def _t(x):
    return jnp.swapaxes(x, -1, -2)


@jax.custom_jvp
def inv(a: Float[Array, "*batch n n"]) -> Float[Array, "*batch n n"]:
    """A⁻¹, over any leading batch dimensions."""
    return _inv(a)


@inv.defjvp
def _inv_jvp(primals, tangents):
    (a,), (da,) = primals, tangents
    ai = inv(a)
    return ai, -ai @ da @ ai


@jax.custom_jvp
def solve(a: Float[Array, "n n"], b: Float[Array, "n *k"]) -> Float[Array, "n *k"]:
    """x with A x = b, for one matrix A and a vector or matrix b (vmap for batches)."""
    if b.ndim == 1:
        return _solve_vec(a, b)
    return jax.vmap(_solve_vec, in_axes=(None, 1), out_axes=1)(a, b)


@solve.defjvp
def _solve_jvp(primals, tangents):
    (a, b), (da, db) = primals, tangents
    x = solve(a, b)
    return x, inv(a) @ (db - da @ x)  # dx = A⁻¹ (db − dA x)


@jax.custom_jvp
def cholesky(a: Float[Array, "n n"]) -> Float[Array, "n n"]:
    """Lower Cholesky factor L of a symmetric positive definite A = L Lᵀ."""
    return _cholesky(a)


@cholesky.defjvp
def _cholesky_jvp(primals, tangents):
    (a,), (da,) = primals, tangents
    l = cholesky(a)
    li = solve_triangular(l, jnp.eye(a.shape[-1], dtype=a.dtype))
    x = li @ da @ _t(li)
    phi = jnp.tril(x) - 0.5 * jnp.diag(jnp.diagonal(x))  # dL = L Φ(L⁻¹ dA L⁻ᵀ)
    return l, l @ phi


def _trsm(l, b, lower):
    return jax.scipy.linalg.solve_triangular(l, b, lower=lower)


@functools.partial(jax.custom_jvp, nondiff_argnums=(2,))
def solve_triangular(l: Float[Array, "n n"], b: Float[Array, "n *k"], lower: bool = True) -> Float[Array, "n *k"]:
    """x with L x = b for a triangular L (lower by default)."""
    f = _one_at_a_time(functools.partial(_trsm, lower=lower), (2, b.ndim))
    return f(l, b)


@solve_triangular.defjvp
def _solve_triangular_jvp(lower, primals, tangents):
    (l, b), (dl, db) = primals, tangents
    x = solve_triangular(l, b, lower)
    li = solve_triangular(l, jnp.eye(l.shape[-1], dtype=l.dtype), lower)
    dl = jnp.tril(dl) if lower else jnp.triu(dl)
    return x, li @ (db - dl @ x)


@jax.custom_jvp
def eigvalsh(a: Float[Array, "n n"]) -> Float[Array, " n"]:
    """Eigenvalues (ascending) of a symmetric A."""
    return _eigh(a)[0]


@eigvalsh.defjvp
def _eigvalsh_jvp(primals, tangents):
    (a,), (da,) = primals, tangents
    w, v = _eigh(a)
    return w, jnp.einsum("ji,jk,ki->i", v, da, v)  # dλᵢ = vᵢᵀ dA vᵢ (distinct eigenvalues)


def eigh_primal(a: Float[Array, "n n"]) -> tuple[Float[Array, " n"], Float[Array, "n n"]]:
    """(eigenvalues ascending, orthonormal eigenvectors) of a symmetric A, without derivatives (A
    enters through `stop_gradient`): for the factors of a quasi-Newton tangent, whose converged
    iterate does not depend on them (and whose eigenvalues may be degenerate, where the eigenvectors'
    derivative is not defined)."""
    return _eigh(jax.lax.stop_gradient(a))


_lu_factor = _one_at_a_time(lambda a: tuple(jax.scipy.linalg.lu_factor(a)), (2,))


def _lu_solve(lu, piv, b, trans):
    f = _one_at_a_time(lambda lu_, piv_, b_: jax.scipy.linalg.lu_solve((lu_, piv_), b_, trans=trans), (2, 1, 1))
    return f(lu, piv, b)


class SequentialLU(lx.AbstractLinearSolver):
    """lineax's dense LU solve with the factorisation and the triangular solves done one matrix at a
    time (see module doc). For square operators whose input and output have the same structure
    (the stage equations of diffrax's implicit solvers); lineax differentiates the solve itself."""

    def init(self, operator, options):
        del options
        if operator.in_size() != operator.out_size():
            raise ValueError("SequentialLU needs a square operator")
        lu, piv = _lu_factor(operator.as_matrix())
        return lu, piv, False

    def compute(self, state, vector, options):
        del options
        lu, piv, transposed = state
        flat, unravel = ravel_pytree(vector)
        return unravel(_lu_solve(lu, piv, flat, 1 if transposed else 0)), lx.RESULTS.successful, {}

    def transpose(self, state, options):
        lu, piv, transposed = state
        return (lu, piv, not transposed), {}

    def conj(self, state, options):
        lu, piv, transposed = state
        return (lu.conj(), piv, transposed), {}

    def assume_full_rank(self):
        return True


def expm(a: Float[Array, "n n"]) -> Float[Array, "n n"]:
    """exp(a) of a small matrix by scaling and squaring its Taylor series: matrix products only
    (`jax.scipy.linalg.expm` solves its Padé quotient with LAPACK, batched under `vmap`), so
    differentiable by plain autodiff; the squarings past the norm's need are skipped by `where`."""
    norm = jnp.max(jnp.sum(jnp.abs(a), axis=-1))
    s = jnp.clip(jnp.ceil(jnp.log2(jnp.maximum(norm, 1e-300) / 0.25)), 0, _EXPM_SQUARINGS)
    x = a / 2.0**s
    eye = jnp.eye(a.shape[-1], dtype=a.dtype)
    out, term = eye, eye
    for k in range(1, _EXPM_DEGREE + 1):
        term = term @ x / k
        out = out + term
    for i in range(_EXPM_SQUARINGS):
        out = jnp.where(i < s, out @ out, out)
    return out
