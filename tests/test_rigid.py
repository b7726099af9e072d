"""Physics of the rigid rocking model (RM): uplift, impact, free rocking, symmetry, Zeno, extended
base, vmap, gradients, and agreement with an independent SciPy event loop (jaxrock/numerics/scipy_rigid.py).

Compiling `simulate` takes seconds, so every compiled function is built once per module (fixtures)
and reused across scenes; the integrator is passed as an argument (its tolerances are traced).
"""

from __future__ import annotations

import itertools
import math

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq

import jaxrock as jr
from helpers import spec_extended
from jaxrock import JaxrockInputError

from jaxrock.numerics import scipy_rigid as sr

G = 9.81
DEFAULT = jr.EventIntegrator()
N_HIST = 4001  # every history has this many samples: one compilation per excitation type
TIGHT = jr.EventIntegrator(rtol=1e-12, atol=1e-14)


def model(height, tan_a, eta=None, tan_base=None):
    """A rigid model whose pytree structure does not depend on `eta` (always an array)."""
    block = jr.Block.from_slenderness(height, tan_a, tan_base)
    e = block.eta_r if eta is None else jnp.asarray(eta, dtype=float)
    return jr.RigidModel(block, eta=e)


def energy(theta, omega, alpha, p):
    """Free-rocking energy per unit I_o: ½θ̇² + p²(cos(α − |θ|) − cosα)."""
    return 0.5 * omega**2 + p**2 * (np.cos(alpha - np.abs(theta)) - np.cos(alpha))


def exact_quarter_period(theta0, alpha, p):
    """Time from rest at θ0 to θ = 0 under eq. 2 without excitation: ∫ dθ/|θ̇|, θ̇ from energy.

    θ = θ0(1 − s²) removes the 1/sqrt singularity at the apex.
    """

    def integrand(s):
        th = theta0 * (1 - s * s)
        d = np.cos(alpha - theta0) - np.cos(alpha - th)
        return 2 * theta0 * s / (p * math.sqrt(2 * d))

    val, err = quad(integrand, 0.0, 1.0, epsabs=0, epsrel=1e-12, limit=200)
    return val


def housner_quarter_period(theta0, alpha, p):
    """Linearised eq. 2 (θ̈ = p²(θ − α) for θ > 0): θ − α = (θ0 − α) cosh(pt) → 0 at T/4."""
    return math.acosh(1 / (1 - theta0 / alpha)) / p


# --- compiled functions (module scope) ------------------------------------------------------------


@pytest.fixture(scope="module")
def run1():
    return jax.jit(lambda m, e, i: jr.simulate(m, e, integrator=i))


@pytest.fixture(scope="module")
def run_hist():
    return jax.jit(lambda m, e, save, t1, i: jr.simulate(m, e, save=save, t1=t1, integrator=i))


@pytest.fixture(scope="module")
def run_batch():
    # the same function as run1, vmapped (the integrator is an argument in both)
    return jax.jit(jax.vmap(lambda m, e, i: jr.simulate(m, e, integrator=i), in_axes=(0, 0, None)))


def history(run_hist, m, exc, ts, integ=DEFAULT):
    sol = run_hist(m, exc, jr.Save(ts, ("theta", "theta_dot")), float(ts[-1]), integ)
    assert int(jr.status_codes(sol.status)) == 0, jr.status_names(sol.status)
    return sol, np.asarray(sol.history["theta"]), np.asarray(sol.history["theta_dot"])


def stack(trees):
    return jax.tree_util.tree_map(lambda *x: jnp.stack(x), *trees)


# --- uplift ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_no_uplift_a_hair_below_g_tan_alpha(run_hist, sign):
    m = model(10.0, 0.2)
    exc = jr.RickerPulse(sign * G * 0.2 * (1 - 1e-6), 2 * np.pi)
    ts = np.linspace(float(exc.t_start), 3.0, N_HIST)
    sol, th, om = history(run_hist, m, exc, ts)
    assert not bool(sol.uplifted) and not bool(sol.overturned)
    assert float(sol.max_theta) == 0.0 and int(sol.n_impacts) == 0
    assert np.all(th == 0.0) and np.all(om == 0.0)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_uplift_a_hair_above_g_tan_alpha_at_the_exact_time(run_hist, sign):
    m = model(10.0, 0.2)
    wp = 2 * np.pi
    exc = jr.RickerPulse(sign * G * 0.2 * (1 + 1e-6), wp)
    ts = np.linspace(float(exc.t_start), 3.0, N_HIST)
    sol, th, _ = history(run_hist, m, exc, ts)
    assert bool(sol.uplifted)
    # |üg| first reaches g tanα where (1 − x²/2) e^{−x²/4} = 1/(1 + 1e-6), x = ω_p t < 0
    x = brentq(lambda x: (1 - x * x / 2) * math.exp(-x * x / 4) - 1 / (1 + 1e-6), -0.1, 0.0, xtol=1e-16)
    assert abs(float(sol.t_uplift) - x / wp) < 1e-9
    # the exceedance lasts ~4e-4 s: the block barely moves and never overturns
    assert np.max(np.abs(th)) < 1e-12 and float(sol.max_theta) < 1e-10


@pytest.mark.parametrize("pulse", [jr.RickerPulse, jr.AntisymmetricRickerPulse])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_uplift_side_is_minus_sign_of_ground_acceleration(run_hist, pulse, sign):
    m = model(10.0, 0.2)
    exc = pulse(sign * 1.5 * G * 0.2, 2 * np.pi)
    ts = np.linspace(float(exc.t_start), 3.0, N_HIST)
    sol, th, _ = history(run_hist, m, exc, ts)
    t_up = float(sol.t_uplift)
    ug_up = float(exc(t_up))
    assert abs(abs(ug_up) - G * 0.2) < 1e-9 * G  # uplift exactly at |üg| = g tanα
    first = th[np.flatnonzero(th)[0]]
    assert np.sign(first) == -np.sign(ug_up)  # üg > 0 → θ < 0


# --- impacts and energy ---------------------------------------------------------------------------


def _flights_after(ts, th, om, t_from, alpha, p):
    """Energy of each free flight (samples between sign changes of θ) after t_from."""
    keep = (ts > t_from) & (th != 0)
    ts, th, om = ts[keep], th[keep], om[keep]
    e = energy(th, om, alpha, p)
    cut = np.flatnonzero(np.sign(th[1:]) != np.sign(th[:-1])) + 1
    flights = [f for f in np.split(np.arange(ts.size), cut)][1:-1]  # whole flights only
    return [(e[f].mean(), e[f].std(), f) for f in flights if f.size > 3]


@pytest.mark.parametrize("eta", [None, 0.8, 1.0])
def test_energy_ratio_across_an_impact_is_eta_squared(run_hist, eta):
    """Free rocking after the pulse: E = ½θ̇² + p²(cos(α−|θ|) − cosα) is constant on each flight and
    ×η² across each impact (at θ = 0, E = ½θ̇², so the velocity ratio is η)."""
    m = model(10.0, 0.2, eta)
    blk = m.block
    alpha, p, eta_v = float(blk.alpha_r), float(blk.p_r), float(m.eta)
    exc = jr.RickerPulse(6 * G * 0.2, 10 * p)
    ts = np.linspace(float(exc.t_start), 10.0, N_HIST)
    sol, th, om = history(run_hist, m, exc, ts)
    assert not bool(sol.overturned)
    flights = _flights_after(ts, th, om, float(exc.t_end), alpha, p)
    assert len(flights) >= 3
    for mean, std, _ in flights:
        assert std <= 1e-8 * mean
    ratios = np.array([b[0] / a[0] for a, b in zip(flights[:-1], flights[1:])])
    np.testing.assert_allclose(np.sqrt(ratios), eta_v, rtol=1e-8)


def test_undamped_energy_is_conserved_after_the_excitation(run_hist):
    m = model(2.0, 0.3, 1.0)
    alpha, p = float(m.block.alpha_r), float(m.block.p_r)
    exc = jr.AntisymmetricRickerPulse(3 * G * 0.3, 5 * p)
    ts = np.linspace(float(exc.t_end), 20.0, N_HIST)
    sol, th, om = history(run_hist, m, exc, ts)
    assert not bool(sol.overturned) and int(sol.n_impacts) >= 10
    e = energy(th, om, alpha, p)
    assert np.ptp(e) <= 1e-8 * e.mean()


# --- free-rocking period --------------------------------------------------------------------------


def _free_taylor(t, th, om, alpha, p):
    """Taylor polynomials (in τ) of θ and θ̇ of free rocking from one saved state (θ, θ̇) on the
    side of θ: θ̈ = −p² sin(sα − θ) and its derivatives (eq. 2 without excitation)."""
    s = np.sign(th)
    phi = s * alpha - th
    a = -(p**2) * math.sin(phi)
    j = p**2 * math.cos(phi) * om
    q = p**2 * (math.sin(phi) * om**2 + math.cos(phi) * a)
    theta = np.polynomial.Polynomial([th, om, a / 2, j / 6, q / 24])
    return theta, theta.deriv()


def _events_from_history(ts, th, om, alpha, p):
    """Impact (θ = 0) and apex (θ̇ = 0) times, and apex |θ|, located between saved samples by the
    local Taylor expansion from the sample before (error ~ (Δt)⁵ p⁵ θ / 120 < 1e-13 here)."""
    impacts, apexes, amps = [], [], []
    for k in range(ts.size - 1):
        dt = ts[k + 1] - ts[k]
        if th[k] == 0:
            continue
        pth, pom = _free_taylor(ts[k], th[k], om[k], alpha, p)
        if np.sign(th[k + 1]) != np.sign(th[k]):
            impacts.append(ts[k] + brentq(pth, 0.0, dt, xtol=1e-15))
        elif np.sign(om[k + 1]) != np.sign(om[k]) and np.sign(om[k]) == np.sign(th[k]):
            tau = brentq(pom, 0.0, dt, xtol=1e-15)
            apexes.append(ts[k] + tau)
            amps.append(abs(pth(tau)))
    return np.array(impacts), np.array(apexes), np.array(amps)


def test_free_rocking_apex_to_impact_time_is_the_exact_quarter_period(run_hist):
    """η = 1 after the pulse: the time from each apex to the next impact (and from each impact to
    the next apex) equals the exact quarter period ∫dθ/θ̇ of eq. 2 at that amplitude."""
    m = model(10.0, 0.2, 1.0)
    alpha, p = float(m.block.alpha_r), float(m.block.p_r)
    exc = jr.RickerPulse(4 * G * 0.2, 8 * p)
    ts = np.linspace(float(exc.t_end), float(exc.t_end) + 12.0, N_HIST)
    sol, th, om = history(run_hist, m, exc, ts)
    e = energy(th, om, alpha, p).mean()
    theta0 = alpha - math.acos(math.cos(alpha) + e / p**2)  # amplitude from the (conserved) energy
    assert 0.1 < theta0 / alpha < 0.9
    t_imp, t_apx, amps = _events_from_history(ts, th, om, alpha, p)
    events = sorted([(t, "impact") for t in t_imp] + [(t, "apex") for t in t_apx])
    gaps = [b[0] - a[0] for a, b in zip(events[:-1], events[1:])]
    assert len(gaps) >= 8 and all(a[1] != b[1] for a, b in zip(events[:-1], events[1:]))  # alternate
    quarter = exact_quarter_period(theta0, alpha, p)
    np.testing.assert_allclose(gaps, quarter, rtol=1e-8)
    np.testing.assert_allclose(amps, theta0, rtol=1e-8)  # the apexes agree with the energy
    # Housner's linearised quarter period is close for this slender block, off by O(α²)
    housner = housner_quarter_period(theta0, alpha, p)
    assert abs(housner / quarter - 1) < alpha**2


def test_housner_formula_solves_the_linearised_equation_and_is_the_small_alpha_limit():
    p = 1.3
    for alpha, r in [(0.2, 0.3), (0.1, 0.6), (0.05, 0.9)]:
        theta0 = r * alpha
        hit = lambda t, y: y[0]
        hit.terminal, hit.direction = True, -1
        lin = solve_ivp(lambda t, y: [y[1], p * p * (y[0] - alpha)], (0, 100 / p), [theta0, 0.0],
                        method="DOP853", rtol=1e-13, atol=1e-15, events=hit)
        assert abs(lin.t_events[0][0] - housner_quarter_period(theta0, alpha, p)) < 1e-10 / p
    # exact → Housner as α → 0 at fixed θ0/α, error ∝ α²
    errs = [abs(housner_quarter_period(0.5 * a, a, p) / exact_quarter_period(0.5 * a, a, p) - 1) for a in (0.2, 0.1, 0.05)]
    assert errs[0] > errs[1] > errs[2]
    np.testing.assert_allclose(errs[0] / errs[1], 4, rtol=0.05)
    np.testing.assert_allclose(errs[1] / errs[2], 4, rtol=0.05)


# --- symmetry -------------------------------------------------------------------------------------


@pytest.mark.parametrize("pulse", [jr.RickerPulse, jr.AntisymmetricRickerPulse])
@pytest.mark.parametrize("eta,accel", [(None, 3.0), (1.0, 1.5), (None, 8.0)])
def test_reversing_the_ground_motion_mirrors_the_response(run_hist, pulse, eta, accel):
    m = model(10.0, 0.2, eta)
    p = float(m.block.p_r)
    ea, eb = pulse(accel * G * 0.2, 4 * p), pulse(-accel * G * 0.2, 4 * p)
    ts = np.linspace(float(ea.t_start), 8.0, N_HIST)
    sa, tha, oma = history(run_hist, m, ea, ts)
    sb, thb, omb = history(run_hist, m, eb, ts)
    assert float(sa.max_theta) == float(sb.max_theta)
    assert bool(sa.overturned) == bool(sb.overturned) and float(sa.t_overturn) == float(sb.t_overturn)
    assert int(sa.n_impacts) == int(sb.n_impacts)
    np.testing.assert_array_equal(tha, -thb)
    np.testing.assert_array_equal(oma, -omb)


# --- Zeno and re-uplift ---------------------------------------------------------------------------


def _two_pulses(t1, a1, t2, a2, wp, dt, t_total):
    ts = np.arange(0.0, t_total, dt)
    x1, x2 = wp * (ts - t1), wp * (ts - t2)
    acc = a1 * (1 - x1**2 / 2) * np.exp(-(x1**2) / 4) + a2 * (1 - x2**2 / 2) * np.exp(-(x2**2) / 4)
    return acc


def test_damped_block_comes_to_rest_and_a_second_pulse_uplifts_it_again(run_hist, run1):
    """Zeno: infinitely many impacts in finite time. The solver must reach rest (θ ≡ 0) after the
    first pulse and uplift again during the second."""
    m = model(2.0, 0.3)  # η = 0.876
    alpha, p = float(m.block.alpha_r), float(m.block.p_r)
    lvl = G * 0.3
    wp, dt, t1, t2 = 5 * p, 0.002, 2.0, 12.0
    acc = _two_pulses(t1, 1.5 * lvl, t2, 2.5 * lvl, wp, dt, 20.0)
    exc = jr.Record(acc, dt)
    ts = np.linspace(0.0, 20.0, N_HIST)
    sol, th, om = history(run_hist, m, exc, ts)
    assert not bool(sol.overturned)
    assert 10 < int(sol.n_impacts) < 2000
    # after the first pulse, the block is exactly at rest before the second pulse uplifts it
    # (the first lobe of the second pulse, −0.446 × 2.5 g tanα, already uplifts it)
    t_up2 = sr.next_exceedance(sr.record(acc, dt)[0], t1 + 3.0, 20.0, lvl, dt)
    assert t2 - 4 / wp < t_up2 < t2
    quiet = (ts > t1 + 4.0) & (ts < t_up2 - 0.05)
    assert np.any(th[ts < t1 + 3.0] != 0)
    assert np.all(th[quiet] == 0) and np.all(om[quiet] == 0)
    assert abs(float(sol.t_uplift) - ts[np.flatnonzero(th)[0] - 1]) < ts[1]  # first uplift, pulse 1
    moving2 = (ts > t_up2) & (ts < t2 + 2.0)
    assert np.max(np.abs(th[moving2])) > 0.05 * alpha
    # summary run: same peak as the SciPy reference (which also closes Zeno sequences)
    s = run1(m, exc, DEFAULT)
    assert int(jr.status_codes(s.status)) == 0 and int(s.n_impacts) < 2000
    ref = sr.solve_record((alpha, p, float(m.eta)), acc, dt)
    assert ref.n_rest >= 1
    assert abs(float(s.max_theta) - ref.max_theta) < 1e-6
    assert float(s.max_theta) > np.max(np.abs(th[ts < t_up2])) / alpha  # the peak is the second pulse's


# --- extended base ---------------------------------------------------------------------------------


def test_extended_base_equal_to_the_column_is_the_plain_block(run1):
    for pulse, accel, ratio in [(jr.RickerPulse, 3.0, 5.0), (jr.AntisymmetricRickerPulse, 2.0, 3.0), (jr.RickerPulse, 6.0, 2.0)]:
        plain = model(10.0, 0.2)
        based = model(10.0, 0.2, tan_base=0.2)
        sized = jr.RigidModel(jr.Block.from_size(10.0, 2.0, base_width=2.0), eta=plain.block.eta_r)
        exc = pulse(accel * G * 0.2, ratio * float(plain.block.p))
        ref = run1(plain, exc, DEFAULT)
        for other in (based, sized):
            s = run1(other, exc, DEFAULT)
            assert abs(float(s.max_theta) - float(ref.max_theta)) <= 1e-12
            assert bool(s.overturned) == bool(ref.overturned)
            if bool(ref.overturned):
                assert abs(float(s.t_overturn) - float(ref.t_overturn)) <= 1e-12


@pytest.mark.parametrize("pulse", ["sym", "anti"])
@pytest.mark.parametrize("accel,ratio", [(1.5, 3.0), (3.0, 5.0), (6.0, 10.0), (3.0, 2.0)])
def test_extended_base_matches_scipy_with_alpha_p_eta_primed(run1, pulse, accel, ratio):
    m = model(20.0, 0.1, tan_base=0.3)
    a, p, e = spec_extended(20.0, 0.1, 0.3)
    cls = jr.RickerPulse if pulse == "sym" else jr.AntisymmetricRickerPulse
    a_p, w_p = accel * G * 0.3, ratio * p
    s = run1(m, cls(a_p, w_p), DEFAULT)
    ref = sr.solve_pulse((a, p, e), a_p, w_p, antisymmetric=pulse == "anti")
    _assert_agree(s, ref, f"extended base {pulse} a={accel} w={ratio}")


# --- agreement with SciPy --------------------------------------------------------------------------


def _assert_agree(s, ref, label):
    assert int(jr.status_codes(s.status)) == 0, (label, jr.status_names(s.status))
    assert bool(s.overturned) == ref.overturned, (label, float(s.max_theta), ref.max_theta)
    if ref.overturned:
        assert abs(float(s.t_overturn) - ref.t_overturn) < 1e-6, (label, float(s.t_overturn), ref.t_overturn)
    else:
        assert abs(float(s.max_theta) - ref.max_theta) < 1e-6, (label, float(s.max_theta), ref.max_theta)


SCENES = [
    dict(pulse=pulse, eta=eta, tan_a=tan_a, height=height, accel=accel, ratio=ratio)
    for pulse in ("sym", "anti")
    for eta in (None, 1.0)
    for tan_a, height in itertools.product((0.1, 0.2, 0.3), (2.0, 10.0, 50.0))
    for accel in (1.5, 3.0, 6.0)
    for ratio in (2.0, 5.0, 10.0)
]


def _scene_inputs(sc):
    m = model(sc["height"], sc["tan_a"], sc["eta"])
    blk = m.block
    cls = jr.RickerPulse if sc["pulse"] == "sym" else jr.AntisymmetricRickerPulse
    a_p = sc["accel"] * G * float(blk.tan_alpha)
    w_p = sc["ratio"] * float(blk.p_r)
    return m, cls(a_p, w_p), a_p, w_p


@pytest.fixture(scope="module")
def batch_results(run_batch):
    """jaxrock (vmapped, default integrator) on every scene, one batch per pulse shape."""
    out = {}
    for pulse in ("sym", "anti"):
        idx = [i for i, sc in enumerate(SCENES) if sc["pulse"] == pulse]
        ms, es = zip(*[_scene_inputs(SCENES[i])[:2] for i in idx])
        sol = jax.device_get(run_batch(stack(ms), stack(es), DEFAULT))
        for k, i in enumerate(idx):
            out[i] = jax.tree_util.tree_map(lambda x: x[k], sol)
    return out


def test_agrees_with_scipy_reference_on_pulse_scenes(batch_results):
    bad = []
    for i, sc in enumerate(SCENES):
        m, _, a_p, w_p = _scene_inputs(sc)
        ref = sr.solve_pulse(m.block, a_p, w_p, antisymmetric=sc["pulse"] == "anti", eta=sc["eta"])
        try:
            _assert_agree(batch_results[i], ref, sc)
        except AssertionError as err:
            bad.append(str(err))
    assert not bad, f"{len(bad)} of {len(SCENES)} scenes disagree:\n" + "\n".join(bad[:10])
    n_over = sum(bool(batch_results[i].overturned) for i in range(len(SCENES)))
    assert 0 < n_over < len(SCENES)  # both regimes are covered


@pytest.fixture(scope="module")
def loop_results(run1):
    """The same scenes one at a time (every 7th scene), with the same compiled function unbatched."""
    return {i: jax.device_get(run1(*_scene_inputs(SCENES[i])[:2], DEFAULT)) for i in range(0, len(SCENES), 7)}


def test_vmap_equals_loop_to_solver_tolerance(batch_results, loop_results):
    for i, s in loop_results.items():
        b = batch_results[i]
        assert int(jr.status_codes(s.status)) == int(jr.status_codes(b.status)) == 0
        assert bool(s.overturned) == bool(b.overturned) and bool(s.uplifted) == bool(b.uplifted)
        assert abs(float(s.max_theta) - float(b.max_theta)) < 1e-8, SCENES[i]
        if bool(s.overturned):
            assert abs(float(s.t_overturn) - float(b.t_overturn)) < 1e-8, SCENES[i]


def test_same_batch_gives_the_same_bits_twice(run_batch):
    """Determinism: the same input on the same machine gives the same bits.

    (A scene run alone and inside a batch agree to the solver tolerance, not bitwise: XLA's
    vectorised transcendental functions differ from the scalar ones by an ulp, which moves the
    adaptive step decisions; see test_vmap_equals_loop_to_solver_tolerance.)
    """
    idx = [i for i, sc in enumerate(SCENES) if sc["pulse"] == "sym"][:16]
    ms, es = zip(*[_scene_inputs(SCENES[i])[:2] for i in idx])
    first = jax.device_get(run_batch(stack(ms), stack(es), DEFAULT))
    second = jax.device_get(run_batch(stack(ms), stack(es), DEFAULT))
    for a, b in zip(jax.tree_util.tree_leaves(first), jax.tree_util.tree_leaves(second)):
        assert np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)  # NaN: an output not asked for


# Cells of the benchmark's 64 × 64 spectrum (tanα = 0.2, 2h = 10 m, damped, symmetric pulse) that
# once went wrong: accel row 12 (a_p/(g tanα) = 2.3095, whose side lobes, 0.446 a_p, hardly exceed
# g tanα) ended in Status.solver_failed (Newton root find stalled at an apex with θ̈ ≈ 0); (2.1587,
# 1.8889) returned max_theta = 1.0055 > 1 without overturning (an apex past the overturning angle
# in the same step took priority over the overturn event). Both are fixed (SafeNewton, event order).
_AR, _WR = np.linspace(0.5, 10.0, 64), np.linspace(1.0, 15.0, 64)
SPECTRUM_CELLS = [(_AR[12], _WR[0]), (_AR[12], _WR[13]), (_AR[12], _WR[20]), (_AR[11], _WR[4]), (_AR[4], _WR[9])]


@pytest.mark.parametrize("accel,ratio", SPECTRUM_CELLS)
def test_agrees_with_scipy_on_hard_spectrum_cells(run1, accel, ratio):
    m = model(10.0, 0.2)
    a_p, w_p = accel * G * 0.2, ratio * float(m.block.p_r)
    ref = sr.solve_pulse(m.block, a_p, w_p)
    s = run1(m, jr.RickerPulse(a_p, w_p), DEFAULT)
    assert int(jr.status_codes(s.status)) == 0 and bool(s.overturned) == ref.overturned
    assert float(s.max_theta) <= 1.0 or bool(s.overturned), "max_theta above the threshold without overturning"
    # Cell (2.3095, 1.0) grazes θ = 0 at t ≈ -0.774 s (|θ| turns back at ~1e-9 rad while |üg| >
    # g tanα): whether it touches (two extra impacts) depends on the 11th digit, and the overturning
    # time 1.2 s later moves by 0.01 s. The 1e-6 agreement is therefore checked at the reference's
    # own tolerance, rtol 1e-12, where it holds for every cell; the default is checked above.
    _assert_agree(run1(m, jr.RickerPulse(a_p, w_p), TIGHT), ref, f"spectrum cell a={accel:.4f} w={ratio:.4f}")


@pytest.mark.parametrize("solver", [diffrax.Tsit5, diffrax.Dopri8])
def test_a_dip_across_zero_after_a_tiny_apex_is_not_stepped_over(run1, solver):
    """Benchmark cell a_p/(g tanα) = 2.3095, ω_p/p = 7.2222: after an apex at θ = −8e-6 α the body
    crosses θ = 0 and lands again 8 ms later (two impacts). A fresh segment's first step of h_nom
    (42 ms) held the whole dip, so the impact event saw sθ > 0 at both ends: Dopri8 at rtol 1e-8
    lost both impacts with status ok and max θ/α 9.3e-4 off. A fresh segment's steps now stay below
    a quarter of its flight's time scale."""
    m = model(10.0, 0.2)
    a_p, w_p = 2.3095238095238093 * G * 0.2, 7.222222222222221 * float(m.block.p_r)
    ref = sr.solve_pulse(m.block, a_p, w_p)
    s = run1(m, jr.RickerPulse(a_p, w_p), jr.EventIntegrator(solver=solver(), rtol=1e-8, atol=1e-10))
    assert int(s.n_impacts) == ref.n_impacts
    _assert_agree(s, ref, f"{solver.__name__} rtol 1e-8")


# El Centro (4000 samples, 0.01 s): (2h, tanα, scale). The (10, 0.15, 1.0) scene once failed
# (Status.solver_failed: a Newton event root find at t ≈ 2.46 s did not converge).
EL_CENTRO = [(10.0, 0.2, 1.0), (4.0, 0.15, 1.5), (10.0, 0.25, 1.5), (10.0, 0.15, 1.0)]


@pytest.mark.slow
@pytest.mark.parametrize("height,tan_a,scale", EL_CENTRO)
def test_agrees_with_scipy_reference_on_el_centro(run1, height, tan_a, scale):
    ec = jr.el_centro()
    m = model(height, tan_a)
    s = run1(m, ec.scaled(scale), DEFAULT)
    ref = sr.solve_record(m.block, np.asarray(ec.acc) * float(ec.scale), float(ec.dt), scale)
    assert ref.n_impacts > 0
    _assert_agree(s, ref, f"El Centro x{scale}, 2h={height}, tanα={tan_a}")


# --- gradients --------------------------------------------------------------------------------------


def peak_tight(a_p, eta, w_p):
    # the integrator is closed over: under jax.jit its tolerances are constants, not tracers
    m = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2), eta=eta)
    return jr.simulate(m, jr.RickerPulse(a_p, w_p), integrator=TIGHT).max_theta


@pytest.mark.slow
def test_gradients_match_central_differences():
    """d(max|θ|/α)/d a_p and /d η where the peak is a smooth function (rocking after one impact,
    no overturning). Central differences on runs at rtol 1e-12 with step 1e-5 (relative):
    truncation ~1e-10, noise ~1e-12/1e-5 = 1e-7 relative; the tolerance 1e-5 covers both and the
    O(rtol) difference between the discrete and the exact derivative."""
    grad = jax.jit(jax.grad(peak_tight, argnums=(0, 1)))
    value = jax.jit(peak_tight)
    blk = jr.Block.from_slenderness(10.0, 0.2)
    p, eta0 = float(blk.p), float(blk.eta)
    # the last scene is a_p = 3 m/s², ω_p = 2π: its windows take > 90 steps at rtol 1e-12, where the
    # reverse pass used to be 1e-4 off (a window's solve recomputing steps inside the segment
    # loop's checkpointed backward pass); now 1.4e-9
    for accel, ratio in [(2.0, 5.0), (4.0, 5.0), (1.5, 3.0), (3.0 / (G * 0.2), 2 * np.pi / p)]:
        a_p, w_p = accel * G * 0.2, ratio * p
        v = float(value(a_p, eta0, w_p))
        assert 0.05 < v < 0.9
        ga, ge = (float(g) for g in grad(a_p, eta0, w_p))
        assert np.isfinite(ga) and np.isfinite(ge)
        h = 1e-5 * a_p
        fd_a = (float(value(a_p + h, eta0, w_p)) - float(value(a_p - h, eta0, w_p))) / (2 * h)
        h = 1e-5
        fd_e = (float(value(a_p, eta0 + h, w_p)) - float(value(a_p, eta0 - h, w_p))) / (2 * h)
        assert abs(ga - fd_a) <= 1e-5 * abs(fd_a), (accel, ratio, ga, fd_a)
        assert abs(ge - fd_e) <= 1e-5 * abs(fd_e) + 1e-9, (accel, ratio, ge, fd_e)
        assert abs(fd_e) > 1e-3  # the peak comes after an impact: η matters


# --- bad input --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "make,needle",
    [
        (lambda: jr.Block.from_size(-10.0, 1.0), "height"),
        (lambda: jr.Block.from_size(10.0, -1.0), "width"),
        (lambda: jr.Block.from_slenderness(-10.0, 0.2), "height"),
        (lambda: jr.Block.from_slenderness(10.0, 0.0), "tan_alpha"),
        (lambda: jr.Block.from_slenderness(10.0, 1.0), "tan_alpha"),
        (lambda: jr.Block.from_slenderness(10.0, -0.2), "tan_alpha"),
        (lambda: jr.Block.from_slenderness(10.0, 1.5), "tan_alpha"),
        (lambda: jr.Block.from_slenderness(10.0, float("nan")), "tan_alpha"),
        (lambda: jr.RickerPulse(1.0, 0.0), "omega_p"),
        (lambda: jr.RickerPulse(1.0, -2.0), "omega_p"),
        (lambda: jr.AntisymmetricRickerPulse(1.0, 0.0), "omega_p"),
        (lambda: jr.RickerPulse(0.0, 2.0), "a_p"),
        (lambda: jr.RickerPulse(float("nan"), 2.0), "a_p"),
        (lambda: jr.AntisymmetricRickerPulse(float("nan"), 2.0), "a_p"),
        (lambda: jr.RickerPulse(float("inf"), 2.0), "a_p"),
    ],
)
def test_bad_input_raises_naming_the_parameter(make, needle):
    with pytest.raises(JaxrockInputError, match=needle) as info:
        make()
    msg = str(info.value)
    assert any(w in msg for w in ("range", "must", "valid", "non-zero")), msg


# --- summary runs decide overturning like history runs ----------------------------------------------


@pytest.mark.parametrize(
    "height,tan_a,eta,a_p,omega_p",
    [
        (10.0, 0.15, 1.0, 5.2 * G * 0.15, None),  # ω_p/p = 5.6667: overturns at 1.840 s, after the pulse
        (10.0, 0.2, None, 9.30, 2 * np.pi),  # between the old (9.4884) and the true (9.2518) boundary
    ],
)
def test_summary_run_that_overturns_in_free_motion_overturns(run1, run_hist, height, tan_a, eta, a_p, omega_p):
    """A segment that reaches the end of the excitation with no event still overturns when its
    free motion does (it used to be marked finished, reporting max_theta = 1, overturned = False)."""
    m = model(height, tan_a, eta)
    exc = jr.RickerPulse(a_p, 5.6667 * float(m.block.p_r) if omega_p is None else omega_p)
    s = run1(m, exc, DEFAULT)
    ts = np.linspace(float(exc.t_start), 30.0, N_HIST)
    h, _, _ = history(run_hist, m, exc, ts)
    assert bool(h.overturned) and float(h.t_overturn) > float(exc.t_end)  # in free motion
    assert bool(s.overturned) and float(s.max_theta) == 1.0
    assert abs(float(s.t_overturn) - float(h.t_overturn)) < 1e-8


def test_least_overturning_amplitude_in_free_motion():
    """2h = 10 m, tanα = 0.2, ω_p = 2π: the least overturning a_p, bisected on the summary flag,
    is the one history runs give (9.2518 m/s²; the summary path used to report 9.4884)."""
    m = model(10.0, 0.2)
    run = jax.jit(jax.vmap(lambda a: jr.simulate(m, jr.RickerPulse(a, 2 * np.pi)).overturned))
    save = jr.Save(np.linspace(-2.0, 30.0, 8))
    runh = jax.jit(jax.vmap(lambda a: jr.simulate(m, jr.RickerPulse(a, 2 * np.pi), save=save, t1=30.0).overturned))

    def least(f, lo=9.0, hi=9.6, n=4):
        for _ in range(n):  # 4 rounds of 7 interior points: bracket 0.6 / 8⁴ ≈ 1.5e-4
            grid = np.linspace(lo, hi, 9)
            yes = np.asarray(f(jnp.asarray(grid)))
            k = int(np.argmax(yes))
            assert yes[k] and not yes[0]
            lo, hi = grid[k - 1], grid[k]
        return hi

    a_sum, a_hist = least(run), least(runh)
    assert abs(a_sum - a_hist) < 2e-4
    assert abs(a_hist - 9.2518) < 1e-3


# --- grazing uplift: the body stays at rest while |üg| ≤ g tanα′ (SPEC) ------------------------------

GRAZE = [1 - 1e-12, 1.0, 1 + 1e-12]


def _grazing_excitation(kind, level, factor):
    if kind == "record":
        rec = jr.el_centro()
        pga = float(jnp.max(jnp.abs(rec.acc)))
        return rec.scaled(level * factor / pga)  # the peak sample at the level, to round-off
    cls = jr.RickerPulse if kind == "symmetric" else jr.AntisymmetricRickerPulse
    return cls(level * factor, 2 * np.pi)


@pytest.mark.parametrize("factor", GRAZE)
@pytest.mark.parametrize(
    "kind,tan_base,literal",
    [
        ("symmetric", None, False),
        ("symmetric", None, True),  # a_p = 9.81 × 0.2 as typed, 1 ulp off the block's G b/h
        ("antisymmetric", None, False),
        ("antisymmetric", None, True),
        ("symmetric", 0.3, False),  # extended base: the level is g tanα′
        ("record", None, False),
    ],
)
def test_grazing_uplift_is_rest_or_a_clean_uplift(run1, run_hist, kind, tan_base, literal, factor):
    m = model(10.0, 0.2, tan_base=tan_base)
    level = G * (tan_base or 0.2) if literal else float(m.block.uplift_acceleration)
    exc = _grazing_excitation(kind, level, factor)
    s = run1(m, exc, DEFAULT)
    t1 = float(exc.t_end) + 2.0
    ts = np.linspace(float(exc.t_start), t1, N_HIST)
    h = run_hist(m, exc, jr.Save(ts, ("theta", "theta_dot")), t1, DEFAULT)
    for sol in (s, h):
        assert str(jr.status_names(sol.status)) == "ok"
        assert not bool(sol.overturned)
        assert float(sol.max_theta) < 1e-10  # a nanosecond-long exceedance moves nothing
    if factor < 1.0 or (factor == 1.0 and kind != "record"):
        # at or below the level: no uplift at all (|üg| ≤ g tanα′; a record's scale is rounded)
        assert not bool(s.uplifted) and not bool(h.uplifted)
        assert np.all(np.asarray(h.history["theta"]) == 0.0)
    if factor > 1.0:
        assert bool(s.uplifted) and bool(h.uplifted)
        assert abs(float(s.t_uplift) - float(h.t_uplift)) < 1e-8
        assert abs(float(exc(s.t_uplift))) >= level * (1 - 1e-14)


def test_uplift_by_a_few_ulps_returns_to_rest_never_fails():
    """a_p 1, 2 or 4 ulps above g tanα′: |üg| exceeds the level only where the pulse's shape is
    exactly 1, for nanoseconds, and for ~1 % of slendernesses the rounded moment about the corner
    then turns the fresh block (θ = θ̇ = 0) into the ground, where the impact event sees no crossing
    from exactly 0 (these ended in `missed_impact`: 49, 19 and 60 of 4000 slendernesses at 1, 2,
    4 ulps). Each is an uplift that returns to rest at once: status ok, no motion."""
    known = [0.25528141, 0.23900392, 0.06609551, 0.26780968, 0.20872426, 0.2677314, 0.25632572, 0.27618291]
    tans = np.concatenate([known, np.random.default_rng(7).uniform(0.05, 0.4, 120)])
    T, K = (a.ravel() for a in np.meshgrid(tans, [1.0, 2.0, 4.0]))

    def run(tan_a, k):
        m = jr.RigidModel(jr.Block.from_slenderness(10.0, tan_a))
        level = m.block.uplift_acceleration
        exc = jr.RickerPulse(level * (1 + k * 2.0**-52), 2 * np.pi)
        sol = jr.simulate(m, exc)
        return jr.status_codes(sol.status), sol.uplifted, sol.overturned, sol.max_theta, jnp.isfinite(exc.next_exceedance(-2.0, level))

    status, up, over, mt, exceeds = (np.asarray(x) for x in jax.jit(jax.vmap(run))(jnp.asarray(T), jnp.asarray(K)))
    assert np.all(status == 0), T[status != 0]
    assert not over.any() and np.all(mt < 1e-10)
    np.testing.assert_array_equal(up, exceeds)  # uplifted exactly when |üg| exceeded the level


# A barely uplifting block chatters (hundreds of impacts at ~1e-9 rad) while |üg| < g tanα′, then the
# pulse's main lobe turns its last hop into a rocking motion: a flight's first window held the
# hop's step cap for chunk_steps·h_nom (thousands of steps: Status.max_steps in run_batch, and the
# lane held its whole batch). Issue 54's scene and the 8 of a seeded search of 16384 symmetric pulses
# near the side lobes' uplift threshold (4 blocks) that failed so; none fails now.
CHATTER_TO_ROCKING = [  # (2h, tanα, a_p/(g tanα), ω_p/p)
    (10.0, 0.2, 2.2850743338967, 4.58971935468193),
    (10.0, 0.2, 2.284736052231864, 1.2341004201419665),
    (10.0, 0.2, 2.2864410523789367, 10.66900415789653),
    (10.0, 0.2, 2.2855959881860204, 6.555744329752079),
    (3.0, 0.15, 2.2687106240414523, 8.533413512996358),
    (3.0, 0.15, 2.2686976126547314, 12.111843073283111),
    (3.0, 0.15, 2.2688012743387467, 12.067367900861944),
    (20.0, 0.25, 2.3034816581113065, 11.691967909423196),
    (6.0, 0.1, 2.25508505453352, 12.68051112037684),
]


def test_chatter_that_turns_into_rocking_ends_ok_and_agrees_with_scipy():
    models, pulses, refs = [], [], []
    for height, tan_a, accel, ratio in CHATTER_TO_ROCKING:
        m = model(height, tan_a)
        a_p, w_p = accel * G * tan_a, ratio * float(m.block.p_r)
        models.append(m)
        pulses.append(jr.RickerPulse(a_p, w_p))
        refs.append(sr.solve_pulse(m.block, a_p, w_p))
    sols = jr.run_batch(stack(models), stack(pulses), model_batched=True)
    for i, ref in enumerate(refs):
        s = jax.tree_util.tree_map(lambda x: x[i], sols)
        label = f"chatter scene {CHATTER_TO_ROCKING[i]}"
        assert ref.n_impacts > 50, label  # the chatter is there
        assert int(jr.status_codes(s.status)) == 0, (label, jr.status_names(s.status))
        assert bool(s.overturned) == ref.overturned, label
        # 1e-5, not _assert_agree's 1e-6: the chatter's last hop grazes θ = 0 (in two scenes
        # jaxrock sees it land, 2 more impacts of ~1e-11 rad; the two codes' impact times differ
        # by ~1e-7 s by then), which moves the later peak by up to 1.4e-6 of α′
        if ref.overturned:
            assert abs(float(s.t_overturn) - ref.t_overturn) < 1e-5, label
        else:
            assert abs(float(s.max_theta) - ref.max_theta) < 1e-5, (label, float(s.max_theta), ref.max_theta)
