"""`jaxrock._linalg`: dense linear algebra that cannot deadlock under `vmap` on XLA:CPU.

jaxlib 0.10.2 splits a batched LAPACK call into chunks on the intra-op pool and the calling worker
waits on them; with as many such kernels in flight as pool threads, the process hangs for ever
(measured on 2 cores: eight `jnp.linalg.inv` of 12 × 33 × 33 in one jitted function, 3 hangs in
3 processes). The hang tests run in a subprocess under a timeout, so a regression fails instead of
blocking the suite. The derivative tests check the hand-written tangents (the routines are
`custom_jvp`s) against central differences, through `grad`, `jvp`, `vmap` and a Hessian–vector
product, and the values against `jnp.linalg`.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrock import _linalg

HANG_TIMEOUT = 240  # s; the non-hanging runs take 10–40 s on 2 cores


def _run_or_hang(code: str):
    try:
        out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=HANG_TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f"hung for {HANG_TIMEOUT} s (XLA:CPU intra-op deadlock of batched LAPACK calls?)")
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_eight_batched_inverses_do_not_hang():
    """The minimal deadlock: eight independent batched inverses in one program (the raw
    `jnp.linalg.inv` version hangs every time on 2 cores)."""
    out = _run_or_hang(
        """
        import jax, jax.numpy as jnp
        from jaxrock import _linalg
        @jax.jit
        def f(a):
            return sum(_linalg.inv(a + i * jnp.eye(33)).sum() for i in range(8))
        a = jax.random.normal(jax.random.PRNGKey(0), (12, 33, 33)) + 10 * jnp.eye(33)
        for _ in range(10):
            r = f(a).block_until_ready()
        ref = sum(jnp.linalg.inv(a[k] + i * jnp.eye(33)).sum() for i in range(8) for k in range(12))
        print(float(abs(r - ref) / abs(ref)))
        """
    )
    assert float(out.split()[-1]) < 1e-12


@pytest.mark.parametrize("integrator", ["ga", pytest.param("kvaerno5", marks=pytest.mark.slow)])  # kvaerno5: 70 s
def test_vmapped_flexible_runs_do_not_hang(integrator):
    """`jit(vmap(simulate))` of the flexible spring model over 16 varied scenes: mass inverse,
    preload solves, first period, generalized-α's tangent ladder (default) or the ESDIRK stage
    solves (Kvaerno5), all under vmap; repeated executions in one fresh process."""
    integ = "None" if integrator == "ga" else "SpringIntegrator(rtol=1e-5, atol=1e-5, solver='kvaerno5')"
    out = _run_or_hang(
        f"""
        import numpy as np, jax, jax.numpy as jnp
        import jaxrock as jr
        from jaxrock.spring import Column, SpringModel, SpringIntegrator
        blk = jr.Block.from_size(50.0, 5.0)
        model = SpringModel(blk, Column.concrete(), n_elements=4)
        rng = np.random.default_rng(0)
        wr, ar = rng.uniform(1, 10, 16), rng.uniform(0.5, 5, 16)
        f = jax.jit(jax.vmap(lambda w, a: jr.simulate(
            model, jr.RickerPulse(a * jr.G * blk.tan_alpha, w * blk.p), integrator={integ}).max_theta))
        for i in range(5):
            r = f(jnp.asarray(wr) * (1 + 1e-3 * i), jnp.asarray(ar)).block_until_ready()
        print(bool(np.all(np.isfinite(np.asarray(r)))))
        """
    )
    assert out.split()[-1] == "True"


# ----------------------------------------------------------------------------------------------
# values and derivatives
# ----------------------------------------------------------------------------------------------
N = 6
_A = jax.random.normal(jax.random.PRNGKey(1), (N, N))
SPD = _A @ _A.T + N * jnp.eye(N)
B = jnp.linspace(-1.0, 2.0, N)
L_SPD = jnp.linalg.cholesky(SPD)
sym = lambda a: 0.5 * (a + a.T)

CASES = {
    "inv": (lambda a: _linalg.inv(a), SPD, lambda a: jnp.linalg.inv(a)),
    "solve_matrix": (lambda a: _linalg.solve(a, B), SPD, lambda a: jnp.linalg.solve(a, B)),
    "solve_rhs": (lambda b: _linalg.solve(SPD, b), B, lambda b: jnp.linalg.solve(SPD, b)),
    "solve_many": (lambda a: _linalg.solve(a, jnp.stack([B, B**2], 1)), SPD, lambda a: jnp.linalg.solve(a, jnp.stack([B, B**2], 1))),
    "cholesky": (lambda a: _linalg.cholesky(sym(a)), SPD, lambda a: jnp.linalg.cholesky(sym(a))),
    "solve_triangular": (
        lambda l: _linalg.solve_triangular(jnp.tril(l), jnp.eye(N)),
        L_SPD,
        lambda l: jax.scipy.linalg.solve_triangular(jnp.tril(l), jnp.eye(N), lower=True),
    ),
    "eigvalsh": (lambda a: _linalg.eigvalsh(sym(a)), SPD, lambda a: jnp.linalg.eigvalsh(sym(a))),
}


@pytest.mark.parametrize("name", CASES)
def test_values_match_jnp(name):
    f, x, ref = CASES[name]
    np.testing.assert_allclose(f(x), ref(x), rtol=1e-12, atol=1e-13)
    xs = jnp.stack([x, 1.5 * x, 2 * x])  # under vmap: the sequential path
    np.testing.assert_allclose(jax.vmap(f)(xs), jax.vmap(ref)(xs), rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("name", CASES)
def test_derivatives_match_finite_differences(name):
    f, x, _ = CASES[name]
    loss = lambda x: jnp.sum(jnp.sin(f(x)))
    e = jax.random.normal(jax.random.PRNGKey(2), x.shape)
    h = 1e-5
    fd = (loss(x + h * e) - loss(x - h * e)) / (2 * h)
    g = jax.grad(loss)(x)
    _, jv = jax.jvp(loss, (x,), (e,))
    np.testing.assert_allclose(jnp.vdot(g, e), fd, rtol=1e-7)
    np.testing.assert_allclose(jv, fd, rtol=1e-7)
    # vmap of grad (sequential primal under vmap, matrix-product tangents)
    gs = jax.jit(jax.vmap(jax.grad(loss)))(jnp.stack([x, x]))
    np.testing.assert_allclose(gs[1], g, rtol=1e-12, atol=1e-14)
    # Hessian–vector product: forward over reverse, against differences of gradients
    hv = jax.jvp(jax.grad(loss), (x,), (e,))[1]
    hv_fd = (jax.grad(loss)(x + h * e) - jax.grad(loss)(x - h * e)) / (2 * h)
    np.testing.assert_allclose(hv, hv_fd, rtol=1e-5, atol=1e-8)


def test_batched_inverse_over_leading_dims():
    """`inv` over leading dimensions (generalized-α's step ladder) equals the per-matrix inverse."""
    a = jnp.stack([SPD, 2 * SPD + jnp.eye(N), SPD.T @ SPD])
    np.testing.assert_allclose(_linalg.inv(a), jnp.stack([jnp.linalg.inv(m) for m in a]), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(jnp.einsum("kij,kjl->kil", _linalg.inv(a), a), jnp.broadcast_to(jnp.eye(N), a.shape), atol=1e-12)


def _primitives(jaxpr) -> set[str]:
    names = set()
    for eqn in jaxpr.eqns:
        names.add(eqn.primitive.name)
        for param in eqn.params.values():
            for sub in param if isinstance(param, (list, tuple)) else (param,):
                inner = getattr(sub, "jaxpr", sub)
                if hasattr(inner, "eqns"):
                    names |= _primitives(inner)
    return names


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_the_sequential_loop_only_on_the_cpu_backend(monkeypatch, name, backend):
    """The loop of single LAPACK calls is XLA:CPU's deadlock workaround: traced for another backend
    (here `jax.default_backend` says so; the small batch runs on this CPU either way) a batch is one
    batched call, with the same values and derivatives."""
    f, x, ref = CASES[name]
    monkeypatch.setattr(jax, "default_backend", lambda: backend)
    xs = jnp.stack([x, 1.5 * x, 2 * x])
    prims = _primitives(jax.make_jaxpr(jax.vmap(f))(xs).jaxpr)
    assert ("scan" in prims) == (backend == "cpu"), prims  # the loop over the batch
    np.testing.assert_allclose(jax.vmap(f)(xs), jax.vmap(ref)(xs), rtol=1e-12, atol=1e-13)
    loss = lambda x: jnp.sum(jnp.sin(f(x)))
    np.testing.assert_allclose(jax.vmap(jax.grad(loss))(xs)[0], jax.grad(loss)(x), rtol=1e-12, atol=1e-14)
