"""Gradients of every summary output (max_theta, t_overturn, t_uplift) with respect to every scene
parameter (a_p, ω_p, size 2h, slenderness tanα, base width tanα′/tanα, η), in both modes: reverse
(`jax.jacrev`, the integrators' default `autodiff="reverse"`) and forward (`jax.jacfwd`,
`autodiff="forward"`).

- Finite everywhere: random scenes (both pulses, plain and extended bases, η = 1 and eq. 3), half
  of them bisected onto their overturning boundary and left a random distance (6e-7 … 4e-2 of
  g tanα′) below or above it; zero exactly where the answer is pinned (an overturned run's
  max_theta, a run that never uplifts); the two modes agree.
- Correct: equal to central differences at the default integrator, on both sides of the boundary.
- Next to the boundary they follow the analytic laws: max_theta ≈ 1 − k√(a* − a) below it (the
  last free peak: arccos near 1), t_overturn ≈ −c log(a − a*) above it (the time spent near the
  unstable equilibrium).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.spring import Column, SpringIntegrator, SpringModel, cbar_eq17

PULSES = {"symmetric": jr.RickerPulse, "antisymmetric": jr.AntisymmetricRickerPulse}
INTEGRATORS = {"reverse": jr.EventIntegrator(), "forward": jr.EventIntegrator(autodiff="forward")}
JACOBIANS = {"reverse": jax.jacrev, "forward": jax.jacfwd}
PARAMS = ("a_p", "omega_p", "height", "tan_alpha", "base", "eta")
MAX_THETA, T_OVERTURN, T_UPLIFT = range(3)


def _finite(x):
    return jnp.where(jnp.isfinite(x), x, 0.0)


def rigid_summary(x, pulse: str, autodiff: str = "reverse"):
    """(max_theta, t_overturn or 0, t_uplift or 0) and the Solution, of x = PARAMS."""
    a_p, omega_p, height, tan_a, base, eta = x
    block = jr.Block.from_slenderness(height, tan_a, tan_a * base)
    s = jr.simulate(jr.RigidModel(block, eta=eta), PULSES[pulse](a_p, omega_p), integrator=INTEGRATORS[autodiff])
    return jnp.stack([s.max_theta, _finite(s.t_overturn), _finite(s.t_uplift)]), s


def random_scenes(n: int, seed: int) -> np.ndarray:
    """Rows of PARAMS: tanα 0.05–0.35, 2h 1–50 m (log-uniform), half on an extended base (tanα′
    up to 1.6 tanα), η = 1 or eq. 3, a_p/(g tanα′) 0.5–10, ω_p/p′ 1–15."""
    rng = np.random.default_rng(seed)
    tan_a = rng.uniform(0.05, 0.35, n)
    height = np.exp(rng.uniform(np.log(1.0), np.log(50.0), n))
    base = np.where(rng.random(n) < 0.5, rng.uniform(1.0, 1.6, n), 1.0)
    block = jr.Block.from_slenderness(height, tan_a, tan_a * base)
    eta = np.where(rng.random(n) < 0.5, 1.0, np.asarray(block.eta_r))
    a_p = rng.uniform(0.5, 10.0, n) * np.asarray(block.uplift_acceleration)
    omega_p = rng.uniform(1.0, 15.0, n) * np.asarray(block.p_r)
    return np.stack([a_p, omega_p, height, tan_a, base, eta], axis=1)


@functools.cache
def _overturned(pulse: str):
    return jax.jit(jax.vmap(lambda x: rigid_summary(x, pulse)[1].overturned))


def straddle_boundary(x: np.ndarray, pulse: str, seed: int, overturned=None) -> np.ndarray:
    """Move the odd rows next to their overturning boundary in a_p: bisect between 0.5 and 10
    g tanα′ (vmapped, on the summary flag of `overturned`, by default a program of its own) and
    stop after 8–24 halvings, on the side (below or above) drawn at random. Rows with no boundary
    in that range keep their a_p."""
    rng = np.random.default_rng(seed)
    level = np.asarray(jr.Block.from_slenderness(x[:, 2], x[:, 3], x[:, 3] * x[:, 4]).uplift_acceleration)
    lo, hi = 0.5 * level, 10.0 * level
    f = _overturned(pulse) if overturned is None else overturned
    x_lo, x_hi = x.copy(), x.copy()
    x_lo[:, 0], x_hi[:, 0] = lo, hi
    has = ~np.asarray(f(jnp.asarray(x_lo))) & np.asarray(f(jnp.asarray(x_hi)))
    stop = rng.integers(8, 25, len(x))
    below = rng.random(len(x)) < 0.5
    out = x.copy()
    for k in range(1, 25):
        mid = x.copy()
        mid[:, 0] = 0.5 * (lo + hi)
        over = np.asarray(f(jnp.asarray(mid)))
        lo, hi = np.where(over, lo, mid[:, 0]), np.where(over, mid[:, 0], hi)
        pick = (k == stop) & has & (np.arange(len(x)) % 2 == 1)
        out[pick, 0] = np.where(below, lo, hi)[pick]
    return out


@functools.cache
def _jacobian_program(pulse: str, autodiff: str):
    # has_aux: the flags come from the same (primal) run as the derivatives
    return jax.jit(jax.vmap(JACOBIANS[autodiff](lambda x: rigid_summary(x, pulse, autodiff), has_aux=True)))


def check_gradients(x: np.ndarray, pulse: str, autodiff: str):
    """The property: finite, and exactly zero where the output is pinned."""
    jac, s = _jacobian_program(pulse, autodiff)(jnp.asarray(x))
    jac = np.asarray(jac)  # scene × output × parameter
    over, up = np.asarray(s.overturned), np.asarray(s.uplifted)
    assert np.all(np.asarray(s.status == jr.Status.ok)), set(jr.status_names(s.status))
    bad = ~np.all(np.isfinite(jac), axis=(1, 2))
    assert not bad.any(), f"non-finite {autodiff} gradients at {x[bad][:3]}"
    assert over.any() and (~over & up).any(), "the scenes must straddle the boundary"
    assert np.all(jac[over, MAX_THETA] == 0), "an overturned run's max_theta is the threshold"
    assert np.all(jac[~over, T_OVERTURN] == 0)
    assert np.all(jac[~up] == 0), "a body that never uplifts answers 0 and inf, whatever the parameters"
    assert np.any(jac[over, T_OVERTURN] != 0) and np.any(jac[~over & up, MAX_THETA] != 0)
    return jac


def scenes(n: int, pulse: str, seed: int, autodiff: str = "reverse") -> np.ndarray:
    """Random scenes, half of them next to their boundary. For forward mode the boundary is found
    with its Jacobian program (the primal run's flag): no program is compiled for the search alone,
    6 s less; reverse runs cost more than that compile, so reverse mode searches with its own."""
    over = (lambda y: _jacobian_program(pulse, autodiff)(y)[1].overturned) if autodiff == "forward" else None
    return straddle_boundary(random_scenes(n, seed), pulse, seed, over)


@pytest.mark.parametrize(
    "pulse,autodiff",
    [
        ("symmetric", "reverse"),
        ("antisymmetric", "forward"),
        pytest.param("antisymmetric", "reverse", marks=pytest.mark.slow),
        pytest.param("symmetric", "forward", marks=pytest.mark.slow),
    ],
)
def test_gradients_are_finite_on_random_scenes(pulse, autodiff):
    """32 scenes, 16 of them next to their boundary. Each mode and each pulse in the default run
    (reverse 41 s, of which about 30 s tracing and compiling the reverse program; forward 16 s),
    the other two combinations marked slow."""
    check_gradients(scenes(32, pulse, seed=1, autodiff=autodiff), pulse, autodiff)


@pytest.mark.slow
@pytest.mark.parametrize("pulse", PULSES)
def test_gradients_are_finite_on_many_random_scenes_and_both_modes_agree(pulse):
    """256 scenes per pulse; reverse and forward mode agree to 1e-7 relative (the same discrete
    program differentiated two ways)."""
    x = scenes(256, pulse, seed=2)
    rev, fwd = (check_gradients(x, pulse, mode) for mode in ("reverse", "forward"))
    np.testing.assert_allclose(fwd, rev, rtol=1e-7, atol=1e-9 * np.abs(rev).max())


# --- correct: central differences, and the laws next to the boundary --------------------------------

ROWS = 32  # every program below runs 32 rows, so each is compiled once (shared with the tests above)


def _rows(x: np.ndarray) -> np.ndarray:
    return np.concatenate([x, np.repeat(x[-1:], ROWS - len(x), axis=0)]) if len(x) < ROWS else x


@functools.cache
def _values(pulse: str):
    return jax.jit(jax.vmap(lambda x: rigid_summary(x, pulse)[0]))


def values(x: np.ndarray, pulse: str = "symmetric") -> np.ndarray:
    out = [np.asarray(_values(pulse)(jnp.asarray(_rows(x[k : k + ROWS])))) for k in range(0, len(x), ROWS)]
    return np.concatenate(out)[: len(x)]


def jacobian(x: np.ndarray, pulse: str = "symmetric", autodiff: str = "forward") -> np.ndarray:
    """Forward mode by default: its program compiles in a third of the reverse one's time, and the
    two agree to 1e-7 (test_gradients_are_finite_on_many_random_scenes_and_both_modes_agree)."""
    jac, s = _jacobian_program(pulse, autodiff)(jnp.asarray(_rows(x)))
    assert np.all(np.asarray(s.status == jr.Status.ok))
    return np.asarray(jac)[: len(x)]


def central_differences(x: np.ndarray, rel: float, values_of=None, top: int | None = None, bottom: int | None = None) -> np.ndarray:
    """Central differences of `values_of` (rows of parameters → rows of outputs; default the RM's
    `values`) with a step `rel` × the parameter. At the edge of a parameter's valid range, where a
    step outside would be `invalid_input` (NaN), a one-sided second-order difference: in column
    `top` where the value is at its top (1: η) and in column `bottom` where it is at its bottom
    (1: the base factor b′/b)."""
    values_of = values if values_of is None else values_of
    n, m = x.shape
    steps = rel * np.abs(x)
    def shifted(k: int, sgn: int) -> np.ndarray:
        y = x.copy()
        y[:, k] += sgn * steps[:, k]
        return y

    edges = [(col, sgn) for col, sgn in ((top, -1), (bottom, +1)) if col is not None]
    blocks = [shifted(k, sgn) for k in range(m) for sgn in (+1, -1)] + ([x] if edges else []) + [shifted(c, 2 * sgn) for c, sgn in edges]
    v = values_of(np.concatenate(blocks)).reshape(len(blocks), n, 3)  # one call: one batch shape
    central = v[: 2 * m].reshape(m, 2, n, 3)  # param, shift, scene, output
    h2 = 2 * steps.T[:, :, None]
    fd = (central[:, 0] - central[:, 1]) / h2
    for j, (col, sgn) in enumerate(edges):  # second order, one-sided into the range: (-3 f0 + 4 f1 - f2) / 2h
        near, far = central[col, 0 if sgn > 0 else 1], v[2 * m + 1 + j]
        one_sided = sgn * (-3 * v[2 * m] + 4 * near - far) / h2[col]
        at_edge = x[:, col] >= 1.0 if sgn < 0 else x[:, col] <= 1.0
        fd[col] = np.where(at_edge[:, None], one_sided, fd[col])
    return fd.transpose(1, 2, 0)  # scene, output, param


def relative_error(jac: np.ndarray, fd: np.ndarray) -> np.ndarray:
    """|jac − fd| relative to the largest derivative of each scene's output."""
    scale = np.abs(fd).max(axis=2, keepdims=True)
    return np.abs(jac - fd) / np.where(scale > 0, scale, 1.0)


G_TAN = 9.81 * 0.2  # g tanα of the 10 m, tanα = 0.2 block


def block_10m(a_p, ratio=None, omega_p=None, base=1.0, eta=None):
    blk = jr.Block.from_slenderness(10.0, 0.2, 0.2 * base)
    w = omega_p if omega_p is not None else ratio * float(blk.p_r)
    return [a_p, w, 10.0, 0.2, base, float(blk.eta_r) if eta is None else eta]


@pytest.mark.parametrize("autodiff", ["forward", "reverse"])
def test_rigid_gradients_match_central_differences_at_the_default_integrator(autodiff):
    """Each mode at the default integrator against central differences (step 1e-5 relative:
    truncation ~1e-10, solver noise ~rtol/step = 1e-3 at worst, measured ≤ 3e-7), for all six
    parameters and all three outputs, on rocking scenes (one with an extended base, one undamped)
    and overturning ones (t_overturn). Measured agreement ≤ 2.9e-7 relative at the default rtol 1e-8
    (7.5e-8 at rtol 1e-10)."""
    x = np.array(
        [
            block_10m(3.0, omega_p=2 * np.pi),
            block_10m(2.0 * G_TAN, 5.0),
            block_10m(4.0 * G_TAN, 5.0, base=1.3),
            block_10m(1.5 * G_TAN, 3.0, eta=1.0),
            block_10m(12.0, omega_p=2 * np.pi),  # overturns during the pulse
            block_10m(10.0, omega_p=2 * np.pi),  # overturns in free motion
        ]
    )
    jac = jacobian(x, autodiff=autodiff)
    err = relative_error(jac, central_differences(x, 1e-5, top=PARAMS.index("eta"), bottom=PARAMS.index("base")))
    assert err.max() < 1e-5, np.array2string(err.max(axis=2), precision=1)
    assert np.all(jac[:4, T_OVERTURN] == 0) and np.all(jac[4:, MAX_THETA] == 0)
    assert np.all(np.abs(jac[:4, MAX_THETA]).max(axis=1) > 1e-2) and np.all(np.abs(jac[4:, T_OVERTURN]).max(axis=1) > 1e-2)


def least_overturning(row: list[float], lo: float, hi: float, rounds: int = 6) -> float:
    """The least overturning a_p of a scene, bracketed to (hi − lo)/31⁶ by vmapped bisection."""
    f = _overturned("symmetric")
    for _ in range(rounds):
        grid = np.linspace(lo, hi, ROWS)
        x = np.array([row] * ROWS)
        x[:, 0] = grid
        yes = np.asarray(f(jnp.asarray(x)))
        k = int(np.argmax(yes))
        assert yes[k] and not yes[0] and yes[k:].all()
        lo, hi = grid[k - 1], grid[k]
    return 0.5 * (lo + hi)


def test_gradients_follow_the_laws_next_to_the_boundary():
    """2h = 10 m, tanα = 0.2, ω_p = 2π, a* = 9.2518 m/s² (least overturning a_p).
    Below: the last free peak, cos(α − θ) = cosα + E/p², reaches α when E does, so
    1 − θ/α ≈ k√(a* − a) and d(θ/α)/da ≈ k/(2√(a* − a)): √δ · d(θ/α)/da tends to a constant.
    Above: the block passes the unstable top (θ̈ ≈ p²(θ − α) there) with energy ∝ (a − a*),
    spending a time ≈ −(1/2p) log(a − a*), so δ · dt_overturn/da tends to −1/(2p) exactly
    (measured: −0.41625 against −1/(2p) = −0.41627; below, 0.13448). The derivatives are checked at
    δ = (a* − a)/a* = 1e-3 … 1e-6 for both limits, and against central differences at 1e-4."""
    row = block_10m(9.25, omega_p=2 * np.pi)
    a_star = least_overturning(row, 9.0, 9.6)
    assert abs(a_star - 9.2518) < 1e-3
    deltas = np.array([1e-3, 1e-4, 1e-5, 1e-6])
    x = np.array([row] * 8)
    x[:4, 0] = a_star * (1 - deltas)
    x[4:, 0] = a_star * (1 + deltas)
    jac = jacobian(x)[:, :, 0]
    below = jac[:4, MAX_THETA] * np.sqrt(deltas * a_star)
    above = jac[4:, T_OVERTURN] * deltas * a_star
    assert np.all(np.isfinite(jac)) and np.all(below > 0) and np.all(above < 0)
    # the limits: successive estimates converge (relative changes shrink, the last below 1 %)
    for law in (below, above):
        changes = np.abs(np.diff(law)) / np.abs(law[1:])
        assert changes[-1] < 1e-2, law
        assert changes[-1] < changes[0], law
    p = float(jr.Block.from_slenderness(10.0, 0.2).p_r)
    assert above[-1] == pytest.approx(-0.5 / p, rel=1e-3)
    fd = central_differences(x[[1, 5]], 1e-7, top=PARAMS.index("eta"), bottom=PARAMS.index("base"))[:, :, 0]  # step 1e-7 a*: a tenth of the distance
    np.testing.assert_allclose(jac[[1, 5], [MAX_THETA, T_OVERTURN]], fd[[0, 1], [MAX_THETA, T_OVERTURN]], rtol=1e-3)


# --- the quasi-rigid spring model (reverse mode, its default Tsit5 integrator) ----------------------

SM_PARAMS = ("a_p", "omega_p", "height", "tan_alpha", "base", "cbar")


def spring_summary(x, column: Column | None = None, integrator=None):
    """(max_theta, t_overturn or 0, t_uplift or 0) and the Solution of x = SM_PARAMS: the
    quasi-rigid SM, or a 4-element flexible `column`, at its default integrator or the one given
    (symmetric pulse)."""
    a_p, omega_p, height, tan_a, base, cbar = x
    block = jr.Block.from_slenderness(height, tan_a, tan_a * base)
    s = jr.simulate(SpringModel(block, column, cbar=cbar, n_elements=4), jr.RickerPulse(a_p, omega_p), integrator=integrator)
    return jnp.stack([s.max_theta, _finite(s.t_overturn), _finite(s.t_uplift)]), s


@functools.cache
def _spring_programs():
    """(Jacobian at the default integrator, values of the converged run, Jacobian of the converged run)."""
    jac = jax.jit(jax.vmap(jax.jacrev(spring_summary, has_aux=True)))
    converged = SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=200_000)
    val = jax.jit(jax.vmap(lambda x: spring_summary(x, integrator=converged)[0]))
    jac_converged = jax.jit(jax.vmap(jax.jacrev(lambda x: spring_summary(x, integrator=converged), has_aux=True)))
    return jac, val, jac_converged


def spring_scenes():
    cb = lambda base=1.0: float(cbar_eq17(jr.Block.from_slenderness(10.0, 0.2, 0.2 * base).alpha_r))
    rows = [block_10m(3.0, omega_p=2 * np.pi), block_10m(2.0 * G_TAN, 5.0), block_10m(4.0 * G_TAN, 5.0, base=1.3), block_10m(12.0, omega_p=2 * np.pi)]
    return np.array([r[:5] + [cb(r[4])] for r in rows])


# 236 s alone on 2 cores (reverse mode through the exact pre-yield phase's checkpointed loop and the
# pieces, for the default and the converged run): beyond the 300-s per-test limit beside another worker
@pytest.mark.timeout(900)
def test_spring_gradients_match_central_differences():
    """The quasi-rigid SM, reverse mode at its default integrator (Tsit5 1e-10 after the exact
    pre-yield phase), all six parameters (c̄ in place of η), three rocking scenes (one on an extended
    base) and one that overturns, against central differences (step 1e-4 relative) of converged
    runs (Tsit5 1e-12). Measured (per scene and output, relative to its largest derivative):
    max_theta 1.2e-6, t_overturn 1.9e-7, t_uplift 7.0e-9 (the Tsit5 default at 1e-11 stepping the
    pre-yield phase: 1.1e-7, 2.6e-7, 5.2e-5; at 1e-10: 3.3e-6, 4.9e-6, 2.0e-4 – 5.1e-4).
    Differences of the default integrator itself are noisier — its adaptive step sequence jumps by
    O(rtol) from one parameter value to the next, which the difference divides by the step, while
    the gradient of a run is that run's own derivative — so the reference is the converged run.

    On the default bilinear spring (θy = 1e-5 α) the uplift time is where |θ| first reaches the
    yield rotation: located on the exact pre-yield motion (`jaxrock.spring.rest`), its derivative
    is the motion's to the differences' noise, where the solver's steps through the block's ringing
    on the stiff pre-yield branch left up to 5e-4. The converged run's own gradient is checked too
    (the derivative of the motion). Bounds: 3e-6 for max_theta and t_overturn, 1e-7 for t_uplift."""
    jac_p, val_p, jac_converged = _spring_programs()
    x = spring_scenes()
    jac, s = jac_p(jnp.asarray(x))
    jac = np.asarray(jac)
    assert np.all(np.asarray(s.status == jr.Status.ok)) and np.all(np.isfinite(jac))
    assert list(np.asarray(s.overturned)) == [False, False, False, True]
    fd = central_differences(x, 1e-4, lambda y: np.asarray(val_p(jnp.asarray(y))), bottom=SM_PARAMS.index("base"))
    err = relative_error(jac, fd)
    assert err[:, [MAX_THETA, T_OVERTURN]].max() < 3e-6, np.array2string(err.max(axis=2), precision=1)
    assert err[:, T_UPLIFT].max() < 1e-7, np.array2string(err.max(axis=2), precision=1)
    assert np.all(jac[3, MAX_THETA] == 0) and np.all(jac[:3, T_OVERTURN] == 0)
    jac12, _ = jac_converged(jnp.asarray(x))
    err12 = relative_error(np.asarray(jac12), fd)
    assert err12.max() < 1e-5, np.array2string(err12.max(axis=2), precision=1)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["quasi-rigid", "flexible"])
def test_spring_gradients_are_finite_on_random_scenes(kind):
    """The SM on random scenes (both sides of the boundary, plain and extended bases, c̄ of
    eq. 17): the quasi-rigid SM in reverse mode (its default Tsit5), the flexible column (4
    elements, concrete) in forward mode (its default generalized-α). Finite, and zero where
    pinned."""
    rng = np.random.default_rng(3)
    n = 32 if kind == "quasi-rigid" else 8
    x = random_scenes(n, seed=3)
    x[:, 5] = np.asarray(cbar_eq17(jr.Block.from_slenderness(x[:, 2], x[:, 3], x[:, 3] * x[:, 4]).alpha_r))
    x[:, 2] = np.where(kind == "flexible", rng.uniform(5.0, 30.0, n), x[:, 2])
    column = None if kind == "quasi-rigid" else Column.concrete()
    jacobian_of = jax.jacrev if kind == "quasi-rigid" else jax.jacfwd

    jac, s = jax.jit(jax.vmap(jacobian_of(lambda y: spring_summary(y, column), has_aux=True)))(jnp.asarray(x))
    jac, over = np.asarray(jac), np.asarray(s.overturned)
    assert np.all(np.asarray(s.status == jr.Status.ok))
    assert np.all(np.isfinite(jac))
    assert over.any() and (~over).any()
    assert np.all(jac[over, MAX_THETA] == 0) and np.all(jac[~over, T_OVERTURN] == 0)
