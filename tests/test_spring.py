"""Physics tests of the spring model (SM), paper sections 3–6 and SPEC "Spring model"."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jaxrock
from jaxrock.spring import beam
from jaxrock._validate import JaxrockInputError
from jaxrock.excitation import RickerPulse
from jaxrock.geometry import G, Block
from jaxrock.model import simulate
from jaxrock.results import Save, Status
from jaxrock.spring import Column, GeneralizedAlpha, SpringIntegrator, SpringModel, cbar_eq17, first_period_eq21, pushover_eq9

_sim = jax.jit(lambda m, ex: simulate(m, ex))
_period = jax.jit(beam.first_period, static_argnums=1)
_max = jax.jit(lambda m, ex: simulate(m, ex).max_theta)


# ----------------------------------------------------------------------------------------------
# reference: Housner's rigid rocking model (eq. 2 with the impact rule eq. 3), SciPy
# ----------------------------------------------------------------------------------------------
def rm_max_theta(height, tan_alpha, a_p, omega_p, eta=None, t_free=None):
    h = height / 2
    b = h * tan_alpha
    R = math.hypot(h, b)
    al = math.atan(tan_alpha)
    p = math.sqrt(3 * G / (4 * R))
    eta = 1 - 1.5 * math.sin(al) ** 2 if eta is None else eta
    ug = lambda t: a_p * (1 - omega_p**2 * t**2 / 2) * math.exp(-(omega_p**2) * t**2 / 4)
    t_end = 12 / omega_p
    t1 = t_end + (t_free if t_free is not None else 20 * 2 * math.pi / p)
    grid = np.linspace(-t_end, t_end, 100001)
    u = np.array([ug(t) for t in grid])
    idx = np.flatnonzero(np.abs(u) > G * tan_alpha)
    if idx.size == 0:
        return 0.0
    t, th, om, s = grid[idx[0]], 0.0, 0.0, -np.sign(u[idx[0]])
    mx = 0.0
    while t < t1:
        f = lambda t, y: [y[1], -(p**2) * (math.sin(al * s - y[0]) + ug(t) / G * math.cos(al * s - y[0]))]
        ev_imp = lambda t, y: y[0]
        ev_imp.terminal, ev_imp.direction = True, -s
        ev_ov = lambda t, y: abs(y[0]) - al
        ev_ov.terminal = True
        sol = solve_ivp(f, (t, t1), [th, om], method="DOP853", rtol=1e-11, atol=1e-13, events=[ev_imp, ev_ov], dense_output=True, max_step=0.05 / omega_p)
        tt = np.linspace(sol.t[0], sol.t[-1], 20001)
        mx = max(mx, float(np.max(np.abs(sol.sol(tt)[0]))))
        if sol.t_events[1].size:
            return 1.0
        if sol.t_events[0].size == 0:
            break
        t, th, om = sol.t_events[0][0], 0.0, sol.y_events[0][0][1] * eta
        if abs(om) < 1e-10:  # at rest: wait for the next uplift
            grid = np.linspace(t, t_end, 20001)
            u = np.array([ug(x) for x in grid])
            idx = np.flatnonzero(np.abs(u) > G * tan_alpha)
            if idx.size == 0:
                break
            t, s, om = grid[idx[0]], -np.sign(u[idx[0]]), 0.0
            continue
        s = np.sign(om)
    return mx / al


# ----------------------------------------------------------------------------------------------
# closed forms
# ----------------------------------------------------------------------------------------------
def test_first_period_eq21_and_convergence():
    blk = Block.from_size(50.0, 5.0)
    col = Column.concrete()
    T21 = float(first_period_eq21(blk.height, blk.tan_alpha, 30e9, 2500.0))
    assert abs(T21 - 0.893) < 1e-3  # SPEC check value
    A, I = col.section(blk)
    m = 2500.0 * A * 2 * blk.h
    errs = []
    for n in (4, 8, 10, 16, 32):
        le = 2 * blk.h / n
        rot = 2500.0 * I * le * jnp.concatenate([jnp.full(1, 0.5), jnp.ones(n - 1), jnp.full(1, 0.5)])
        T = float(_period(blk.h, n, m, 30e9 * A, 30e9 * I, rot))
        errs.append(abs(T / T21 - 1))
    assert errs[2] < 5e-3, errs  # default mesh (10 elements)
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:])), errs  # converges monotonically
    # without rotary inertia (pure Euler–Bernoulli, as eq. 21 assumes) it converges to eq. 21
    n = 32
    T = float(_period(blk.h, n, m, 30e9 * A, 30e9 * I, jnp.full(n + 1, 1e-9 * m)))
    assert abs(T / T21 - 1) < 2e-4


def test_cbar_eq17_spec_values():
    for ta, c in [(0.1, 0.0199), (0.2, 0.0779), (0.3, 0.1699)]:
        assert abs(float(cbar_eq17(math.atan(ta))) - c) < 1e-4


@pytest.mark.parametrize("backbone", ["bilinear", "tanh"])
def test_pushover_eq9_quasi_rigid(backbone):
    """The model's own static pushover (`SpringModel.pushover`, F at mid-height: F h cosθ = dV/dθ) is
    eq. 9 once the spring has yielded; on the bilinear pre-yield branch it is the closed form
    (θ/θy · tanα − sinθ)/cosθ; the potential's rigid-plastic limit is SPEC's E(θ)."""
    for ta in (0.1, 0.3):
        blk = Block.from_slenderness(10.0, ta)
        model = SpringModel(blk, added_masses=False, backbone=backbone)
        m = model.mass()
        th = jnp.linspace(0.05, 1.5, 7) * blk.alpha
        np.testing.assert_allclose(model.pushover(th), pushover_eq9(th, blk.alpha), rtol=1e-9, atol=1e-12)
        if backbone == "bilinear":
            th_y = float(model.smoothing) * blk.alpha
            th = jnp.array([0.25, 0.5, 1.0]) * th_y
            np.testing.assert_allclose(model.pushover(th), (th / th_y * blk.tan_alpha - jnp.sin(th)) / jnp.cos(th), rtol=1e-9)
        th = 0.5 * blk.alpha
        E = m * G * blk.R * (jnp.sin(blk.alpha) * th - jnp.cos(blk.alpha) * (1 - jnp.cos(th)))
        V = model.static_potential(th)
        assert abs(float(V / E) - 1) < 2 * float(model.smoothing) * math.log(2) / 0.5


def test_pushover_of_a_flexible_column_loses_its_bending_p_delta():
    """The flexible column's static pushover (Newton on the equilibrium with θ prescribed, uniform
    lateral acceleration): at E = 10¹⁴ Pa it is eq. 9 (measured −1.5e-7); softer columns bend under
    the load and gravity acting through the bending lowers it, in proportion to 1/E (measured
    −4.9e-4 at 30 GPa and −5.0e-3 at 3 GPa, 2h = 50 m, 2b = 5 m: ratio 10.1)."""
    blk = Block.from_size(50.0, 5.0)
    th = jnp.array([0.01, 0.5, 1.0, 1.2]) * blk.alpha
    eq9 = pushover_eq9(th, blk.alpha)
    d = {E: np.asarray(SpringModel(blk, Column(E), n_elements=4).pushover(th) - eq9) for E in (1e14, 30e9, 3e9)}
    assert np.max(np.abs(d[1e14])) < 1e-6, d[1e14]
    assert np.all(d[30e9] < 0) and np.all(d[3e9] < 0)
    np.testing.assert_allclose(d[3e9] / d[30e9], 10.0, rtol=0.05)


def test_first_period_and_rayleigh_coefficients():
    """Eq. 21 takes 2h as every constructor does (SPEC: 2h = 50 m, 2b = 5 m concrete: 0.893 s); the
    model's own T₁ (10 elements) is eq. 21 within 0.5 % for the bare column (measured 0.896 s) and
    longer with the added masses (0.901 s); the Rayleigh coefficients are (0, ζ T₁/π), the damping
    ratio ζ at that T₁."""
    blk = Block.from_size(50.0, 5.0)
    T21 = float(first_period_eq21(blk.height, blk.tan_alpha, 30e9, 2500.0))
    assert T21 == pytest.approx(0.893, abs=1e-3)
    bare = SpringModel(blk, Column.concrete(), added_masses=False)
    added = SpringModel(blk, Column.concrete(), zeta=0.02)
    assert float(bare.first_period()) == pytest.approx(T21, rel=5e-3)
    T1 = float(added.first_period())
    assert T1 > float(bare.first_period())
    a0, a1 = added.rayleigh()
    assert float(a0) == 0.0 and float(a1) == pytest.approx(0.02 * T1 / math.pi, rel=1e-12)
    # the damping ratio of the first fixed-base mode of C = a₁ K is a₁ ω₁/2 = ζ
    assert float(a1) * (2 * math.pi / T1) / 2 == pytest.approx(0.02, rel=1e-12)
    with pytest.raises(JaxrockInputError, match="no column"):
        SpringModel(blk).first_period()
    assert jaxrock.energy_ratio_grid is jaxrock.analyses.free_rocking.energy_ratio_grid


def test_kinematics_eq5_eq7_flexible_rigid_rotation():
    """Top displacements of the (gravity-preloaded, E = 1e14) FE column under a rigid rotation."""
    blk = Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk, Column(1e14, 2500.0))
    init = eqx.filter_jit(model.initial_state)
    for th in (-0.15, 0.07, 0.19):
        y = init(th)
        x, yy, phi = beam.positions(y[: beam.n_dof(10)], blk.h, 10)
        uc = 2 * blk.R * jnp.cos(blk.alpha) * jnp.sin(th)  # eq. 5
        vc = -2 * blk.R * jnp.cos(blk.alpha) * (1 - jnp.cos(th))  # eq. 7
        assert abs(float(x[-1] - uc)) < 1e-8
        assert abs(float(yy[-1] - 2 * blk.h - vc)) < 1e-7  # + gravity shortening ~1e-8 m
        assert float(model.base_rotation(y)) == pytest.approx(th)


def test_closed_form_forces_are_the_energy_gradient_and_rayleigh_transpose():
    """`beam.internal_forces` (closed form) against autodiff of its definitions: ∇ of the
    corotational strain energy, and a₁ Jᵀ K_e J v with J the Jacobian of the element deformations,
    on large rotations (0.3 rad rigid + random deformations) and random velocities."""
    n, h, EA, EI, a1 = 6, 25.0, 1.5e11, 3.1e11, 2.9e-3
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = jnp.asarray(rng.normal(size=beam.n_dof(n)) * 1e-2)
        q = q.at[0].add(0.3).at[3::3].add(0.3)  # node rotations follow a rocked column
        v = jnp.asarray(rng.normal(size=beam.n_dof(n)))
        g_el, g_d = beam.internal_forces(q, v, h, n, EA, EI, a1)
        ref_el = jax.grad(beam.strain_energy)(q, h, n, EA, EI)
        _, jvp_fn = jax.linearize(lambda qq: beam.element_deformations(qq, h, n), q)
        (ref_d,) = jax.linear_transpose(jvp_fn, q)(tuple(a1 * x for x in beam.local_forces(jvp_fn(v), h, n, EA, EI)))
        np.testing.assert_allclose(g_el, ref_el, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(ref_el))))
        np.testing.assert_allclose(g_d, ref_d, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(ref_d))))


@pytest.mark.parametrize("n", [1, 2, 10])
def test_structured_mass_product_is_the_mass_matrix(n):
    """`beam.mass_times` (the rod mass's tridiagonal coupling and the rotational masses, written
    out) is `beam.mass_matrix(...) @ x`, for one element, two, and ten."""
    rng = np.random.default_rng(n)
    rot, m = jnp.asarray(rng.uniform(1.0, 2.0, n + 1) * 1e5), 6.25e5
    M = beam.mass_matrix(25.0, n, m, rot)
    for _ in range(3):
        x = jnp.asarray(rng.normal(size=beam.n_dof(n)))
        ref = M @ x
        np.testing.assert_allclose(beam.mass_times(x, n, m, rot), ref, rtol=0, atol=1e-14 * float(jnp.max(jnp.abs(ref))))


def test_preload_is_static_equilibrium():
    blk = Block.from_size(50.0, 5.0)
    model = SpringModel(blk, Column.concrete())
    mech = eqx.filter_jit(model.system)()
    y0 = eqx.filter_jit(mech.initial_state)()
    dy = eqx.filter_jit(mech.vector_field)(-100.0, y0, RickerPulse(1.0, 1.0))
    assert float(jnp.max(jnp.abs(dy))) < 1e-6  # m/s², i.e. < 1e-7 g
    # axial shortening of the top under its own weight: ρ g (2h)² / (2E)
    top = mech.q_eq[3 * 10 - 1]
    assert float(top) == pytest.approx(-2500 * G * 50.0**2 / (2 * 30e9), rel=1e-3)


# ----------------------------------------------------------------------------------------------
# dynamics
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("tan_alpha", [0.1, 0.2, 0.3])
def test_quasi_rigid_sm_follows_rm_figures_5_8(tan_alpha):
    """Fig. 5/8 scenes: 2h = 10 m, a_p = 4 g tanα, ω_p = 2π. SM with added masses vs Housner's RM.

    Tolerance: the two models differ in their nonlinear terms (eq. 10 vs eq. 2) and the damper only
    matches the impact loss per cycle on average (eq. 17 is a fit), so agreement is to a few % of α,
    degrading with α as the paper shows (figure 8): |Δ(θ/α)| ≤ 0.01 + 0.12 tanα.
    """
    blk = Block.from_slenderness(10.0, tan_alpha)
    ex = RickerPulse(4 * G * tan_alpha, 2 * math.pi)
    tol = 0.01 + 0.12 * tan_alpha
    # damped (figure 8): c̄ from eq. 17, RM with η
    sm = float(_max(SpringModel(blk), ex))
    rm = rm_max_theta(10.0, tan_alpha, 4 * G * tan_alpha, 2 * math.pi)
    assert abs(sm - rm) < tol, (sm, rm)
    # undamped (figure 5): c̄ = 0, η = 1 (bounded free-rocking time)
    sm0 = float(_max(SpringModel(blk, cbar=0.0), ex))
    rm0 = rm_max_theta(10.0, tan_alpha, 4 * G * tan_alpha, 2 * math.pi, eta=1.0)
    assert abs(sm0 - rm0) < tol, (sm0, rm0)


def test_added_masses_improve_squat_block():
    """Paper section 3.3: for tanα = 0.3 the added rotational masses bring the SM closer to the RM."""
    blk = Block.from_slenderness(10.0, 0.3)
    ex = RickerPulse(4 * G * 0.3, 2 * math.pi)
    rm = rm_max_theta(10.0, 0.3, 4 * G * 0.3, 2 * math.pi, eta=1.0)
    with_m = float(_max(SpringModel(blk, cbar=0.0), ex))
    without = float(_max(SpringModel(blk, cbar=0.0, added_masses=False), ex))
    assert abs(with_m - rm) < abs(without - rm)


def test_exact_peak_not_sample():
    """The reported peak equals a dense history's peak to the solver tolerance; a history's times
    before the excitation starts hold the initial state."""
    blk = Block.from_slenderness(10.0, 0.2)
    ex = RickerPulse(4 * G * 0.2, 2 * math.pi)
    model = SpringModel(blk)
    s = _sim(model, ex)
    # two save times before the excitation starts: the body is still in its initial state there
    ts = jnp.concatenate([float(ex.t_start) - jnp.array([2.0, 1.0]), jnp.linspace(float(ex.t_start), float(ex.t_end) + 10.0, 40001)])
    h = simulate(model, ex, save=Save(ts, ("theta",)))
    assert h.status == Status.ok and bool(jnp.all(h.ts == ts))
    assert bool(jnp.all(h.history["theta"][:2] == h.history["theta"][2]))
    dense = float(jnp.max(jnp.abs(h.history["theta"]))) / float(blk.alpha)
    assert float(s.max_theta) == pytest.approx(dense, abs=2e-5)
    assert float(h.max_theta) == pytest.approx(dense, abs=2e-5)
    assert bool(s.uplifted) and float(s.t_uplift) < 0


@pytest.mark.slow  # 40 s; the default run checks d/dc̄ in test_gradients' spring central differences (all six parameters)
def test_grad_wrt_cbar_matches_finite_differences():
    blk = Block.from_slenderness(10.0, 0.2)
    ex = RickerPulse(4 * G * 0.2, 2 * math.pi)
    integ = SpringIntegrator(rtol=1e-9, atol=1e-9, solver="kvaerno5")

    def f(cbar):
        return simulate(SpringModel(blk, cbar=cbar), ex, integrator=integ).max_theta

    c0, dc = 0.08, 1e-4
    g = float(jax.jit(jax.grad(f))(c0))
    fj = jax.jit(f)
    fd = float((fj(c0 + dc) - fj(c0 - dc)) / (2 * dc))
    assert g < 0  # more damping, less rotation
    assert g == pytest.approx(fd, rel=1e-3)


def test_vmap_grid_quasi_rigid():
    blk = Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk)
    aps = jnp.array([0.5, 3.0, 6.0]) * G * 0.2
    wps = jnp.array([2.0, 6.0])
    A, W = jnp.meshgrid(aps, wps)
    out = jax.jit(jax.vmap(lambda a, w: simulate(model, RickerPulse(a, w))))(A.ravel(), W.ravel())
    assert bool(jnp.all(out.status == Status.ok))
    mt = np.asarray(out.max_theta)
    assert np.all(np.isfinite(mt)) and np.all(mt >= 0) and np.all(mt <= 1)
    assert not bool(out.uplifted[0]) and mt[0] < 1e-2  # a_p < g tanα: no uplift
    # the vmapped entries equal the single runs
    one = float(_max(model, RickerPulse(A.ravel()[4], W.ravel()[4])))
    assert mt[4] == pytest.approx(one, abs=1e-12)


def test_overturning_event():
    blk = Block.from_slenderness(10.0, 0.2)
    s = _sim(SpringModel(blk), RickerPulse(8 * G * 0.2, 2.0))
    assert bool(s.overturned) and float(s.max_theta) == 1.0 and np.isfinite(float(s.t_overturn))
    assert s.status == Status.ok


def test_grazing_overturn_is_flagged():
    """A peak that grazes just past α′ inside one step (both step ends below it, so the overturning
    event sees no sign change) is an overturning: max_theta at the threshold with overturned False
    was a contradiction of the run's own flags (quasi-rigid SM, a_p/(g tanα) 2.711408-2.711411 at
    ω_p/p = 3 on the tanh backbone, found by `find_boundary`; on the default bilinear backbone the
    boundary is at 2.72815475, by bisection); 1e-6 below it the peak is under α′ (0.99999) and
    nothing is flagged, 1e-6 above the run overturns with its time."""
    blk = Block.from_slenderness(10.0, 0.2)
    for ratio, over in ((2.7281537, False), (2.7281557, True)):
        s = _sim(SpringModel(blk), RickerPulse(*jaxrock.pulse_of_ratios(blk, ratio, 3.0)))
        assert s.status == Status.ok and bool(s.overturned) == over and (float(s.max_theta) == 1.0) == over, (ratio, s.max_theta)
        assert np.isfinite(float(s.t_overturn)) == over


def _max_at(model, ex, tol, exact_rest=True):
    """max θ/α′ under Tsit5 at rtol = atol = `tol` (`exact_rest`: the pre-yield phase stepped exactly)."""
    return float(_max_with(model, ex, SpringIntegrator(tol, tol, solver="tsit5", max_steps=400_000, exact_rest=exact_rest)))


_max_with = jax.jit(lambda m, ex, integ: simulate(m, ex, integrator=integ).max_theta, static_argnums=2)


def test_the_quasi_rigid_default_tolerance_converges():
    """The quasi-rigid default (`benchmarks/bench_backbone.py --part tolerance`): Tsit5 at 1e-10
    after the exact pre-yield phase. On the study's two worst pulses for Tsit5 1e-10 stepping the
    pre-yield phase too (seed 1 no. 15, and a seed-0 scene rounded) the default lies within 1e-7 of
    α′ of Tsit5 at 1e-13 (measured 3.8e-8 and 1.0e-8), where the solver's steps left 4.6e-6 and
    3.0e-6; the two references (with and without the exact phase) agree within 1e-8 (2.2e-9, 1.7e-9)."""
    for h2, ta, wr, ar in ((5.894938943278639, 0.17635664426868658, 3.9130756678287484, 3.699604912602856),
                           (12.8, 0.072, 4.0, 3.77)):
        blk = Block.from_slenderness(h2, ta)
        m, ex = SpringModel(blk), jaxrock.AntisymmetricRickerPulse(*jaxrock.pulse_of_ratios(blk, ar, wr))
        ref, default = _max_at(m, ex, 1e-13), float(_max(m, ex))
        assert abs(default - ref) <= 1e-7, (h2, default, ref)
        assert abs(_max_at(m, ex, 1e-13, exact_rest=False) - ref) <= 1e-8
        assert abs(_max_at(m, ex, 1e-10, exact_rest=False) - ref) > 2e-6  # the solver through the pre-yield phase


def test_a_step_that_brushes_the_kink_is_not_kept():
    """A Ricker pulse whose small rocking brushes the yield rotation (a_p/(g tanα) 2.34, ω_p/p 7.77,
    tanα 0.2: the one outlier of `benchmarks/bench_spring.py`'s 1024 cells): a Tsit5 step whose ends
    lay on the pre-yield branch while its motion crossed the kink in between was kept, integrated on
    the continued branch, and the default came out 1.1e-4 of α′ from Tsit5 at 1e-12 (1e-9 the same).
    With such steps rejected (`KinkGuard`) every tolerance from 1e-9 converges to it."""
    blk = Block.from_slenderness(10.0, 0.2)
    m = SpringModel(blk)
    ex = jaxrock.RickerPulse(*jaxrock.pulse_of_ratios(blk, 2.338709677419355, 7.774193548387097))
    ref, default = _max_at(m, ex, 1e-12), float(_max(m, ex))
    assert abs(default - ref) <= 1e-7, (default, ref)
    assert abs(_max_at(m, ex, 1e-9) - ref) <= 1e-6


@pytest.mark.slow  # ~35 s cold (three compiles of a 40-s record run), 8 s warm
def test_the_quasi_rigid_default_tolerance_on_a_record():
    """The other half of the test above: on El Centro the default lies within 1e-5 of α′ of Tsit5 at
    1e-12 (measured 2.8e-6; the study's 24 records: ≤ 2.2e-5, median 6.5e-10), where Tsit5 1e-10
    stepping the pre-yield phase too left 2.6e-5."""
    blk = Block.from_slenderness(2.32, 0.1385)
    rec = jaxrock.el_centro()
    m, ex = SpringModel(blk), rec.scaled(1.815 * G * blk.tan_alpha / float(jnp.max(jnp.abs(rec.acc))))
    ref = _max_at(m, ex, 1e-12)
    assert abs(float(_max(m, ex)) - ref) <= 1e-5
    assert abs(_max_at(m, ex, 1e-10, exact_rest=False) - ref) > 1e-5


def test_energy_balance_flexible():
    blk = Block.from_size(20.0, 2.0)
    model = SpringModel(blk, Column.concrete(), n_elements=6)
    ex = RickerPulse(3 * G * 0.1, 2 * math.pi)
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end) + 2.0, 400)
    f = ("kinetic", "potential", "dissipated", "input", "theta", "u_top", "w_top", "base_moment")
    s = simulate(model, ex, save=Save(ts, f), integrator=SpringIntegrator(rtol=1e-6, atol=1e-6))
    H = s.history
    stored = H["kinetic"] + H["potential"]
    balance = H["input"] - H["dissipated"]
    scale = float(jnp.max(jnp.abs(H["input"])))
    assert float(jnp.max(jnp.abs(stored - balance))) < 1e-5 * scale
    assert float(H["dissipated"][-1]) > 0
    assert np.all(np.isfinite(np.asarray(H["w_top"])))
    np.testing.assert_allclose(H["w_top"], H["u_top"] - 2 * blk.h * jnp.sin(H["theta"]), atol=1e-12)


def quad_damper(ts, H, model):
    """∫ c θ̇² dt of a saved θ̇, by the trapezoid rule."""
    p = float(model.system().c) * H["theta_dot"] ** 2
    return np.concatenate([[0.0], np.cumsum(0.5 * np.diff(np.asarray(ts)) * (p[1:] + p[:-1]))])


@pytest.mark.parametrize("zeta, cbar", [(0.02, None), (0.0, None), (0.02, 0.0)])
def test_energy_terms_flexible(zeta, cbar):
    """The dissipated work split into its sources: damper + rayleigh = dissipated, each
    non-negative and non-decreasing, each zero when its damping is switched off; the damper's work
    is ∫ c θ̇² dt of the saved θ̇ (trapezoid on 4001 points: an independent quadrature); the
    column's strain energy is ≥ 0, and the balance kinetic + potential + damper + rayleigh = input
    holds to generalized-α's trapezoidal work sums (1e-7; Tsit5 cannot take ζ = 0's ringing).
    Measured / max input: balance 5.0e-5, 4.7e-5, 5.0e-5; damper against the quadrature 2.9e-6,
    1.4e-5, 0."""
    blk = Block.from_size(20.0, 2.0)
    kw = {} if cbar is None else dict(cbar=cbar)
    model = SpringModel(blk, Column.concrete(), n_elements=4, zeta=zeta, **kw)
    ex = RickerPulse(3 * G * 0.1, 2 * math.pi)
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end) + 2.0, 4001)
    f = ("kinetic", "potential", "elastic", "dissipated", "damper", "rayleigh", "input", "theta_dot")
    s = simulate(model, ex, save=Save(ts, f), integrator=GeneralizedAlpha(1e-7, 1e-7))
    assert s.status == Status.ok
    H = {k: np.asarray(v) for k, v in s.history.items()}
    scale = np.max(np.abs(H["input"]))
    np.testing.assert_allclose(H["damper"] + H["rayleigh"], H["dissipated"], rtol=0, atol=1e-12 * scale)
    assert np.max(np.abs(H["kinetic"] + H["potential"] + H["dissipated"] - H["input"])) < 1e-4 * scale
    for k in ("damper", "rayleigh"):
        assert np.all(np.diff(H[k]) >= -1e-12 * scale) and H[k][0] == 0.0
    assert (H["rayleigh"][-1] > 1e-3 * scale) == (zeta > 0)
    assert (H["damper"][-1] > 1e-3 * scale) == (cbar != 0.0)
    assert np.max(np.abs(quad_damper(ts, H, model) - H["damper"])) < 1e-4 * scale
    assert np.min(H["elastic"]) > -1e-9 * scale and np.max(H["elastic"]) > 0


def test_energy_terms_quasi_rigid():
    """The one-DOF body has no column: no strain energy, no Rayleigh work; all dissipation is the
    damper's."""
    blk = Block.from_slenderness(10.0, 0.2)
    ex = RickerPulse(4 * G * 0.2, 2 * math.pi)
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end) + 3.0, 500)
    s = simulate(SpringModel(blk), ex, save=Save(ts, ("elastic", "damper", "rayleigh", "dissipated", "input")))
    H = {k: np.asarray(v) for k, v in s.history.items()}
    assert np.all(H["elastic"] == 0.0) and np.all(H["rayleigh"] == 0.0)
    np.testing.assert_array_equal(H["damper"], H["dissipated"])
    assert H["damper"][-1] > 0.1 * np.max(H["input"])


@pytest.mark.parametrize(
    "integrator, tol",
    [
        # the ESDIRK run this equivalence was established with (docstring numbers)
        pytest.param(SpringIntegrator(rtol=1e-6, atol=1e-6, solver="kvaerno5"), 1e-4, marks=pytest.mark.slow),  # 27 s; generalized-α runs by default
        # generalized-α, 2nd order: its global error is ~ (steps × tolerance), measured on this
        # scene 2.2e-3 at the default 1e-5, 4.5e-4 at 1e-6, 1.2e-5 at 1e-7, 2.1e-5 at 1e-8 —
        # 1e-7 with 1e-4 keeps the test about the model (the FE column's compliance), not the solver
        (GeneralizedAlpha(rtol=1e-7, atol=1e-7), 1e-4),
    ],
    ids=["kvaerno5", "generalized_alpha"],
)
def test_flexible_E1e14_converges_to_quasi_rigid(integrator, tol):
    """Paper section 3: the FE column with E = 10¹⁴ Pa is the quasi-rigid SM.

    Measured (tanα = 0.2, 2h = 10 m, a_p = 4 g tanα, ω_p = 2π, 4 elements, Kvaerno5 + Newton, the
    default bilinear backbone at θy = 1e-5 α, whose kinks both diffrax runs stop on): one-DOF
    0.66115020 (Tsit5 1e-10), 5.1e-5 from the sharp limit (θy = 1e-6 α: 0.66109905); FE 0.66115015
    at 1e-5, 0.66115012 at 1e-6; generalized-α 1e-7 0.661234 (tanh at θs = 1e-4: one-DOF 0.663037;
    FE 0.663801 at 1e-5, 0.663042 at 1e-6). Two bugs
    were behind the former 0.637 and the stall: the ground load missed the base-node coupling of
    the consistent mass (`beam.ground_load`: −m_e/6 üg at node 1, 2 % of the overturning moment),
    and Newton's residual test could not pass the round-off of the stiff column's accelerations.
    Tolerance 1e-4: the FE column has a bending/axial compliance ~1e-10 of the spring's, so what
    remains is the solver tolerance. The one-DOF default is within 1e-3 of the sharp limit.
    """
    blk = Block.from_slenderness(10.0, 0.2)
    ex = RickerPulse(4 * G * 0.2, 2 * math.pi)
    qr = float(_max(SpringModel(blk), ex))
    assert qr == pytest.approx(float(_max(SpringModel(blk, backbone="bilinear", smoothing=1e-6), ex)), abs=1e-3)
    s = simulate(SpringModel(blk, Column(1e14, 2500.0), n_elements=4, backbone="bilinear"), ex, integrator=integrator)
    assert s.status == Status.ok
    assert float(s.max_theta) == pytest.approx(qr, abs=tol)


def test_stiff_column_too_tight_tolerance_reports_max_steps():
    """Below the round-off floor (E = 10¹⁴ Pa at 1e-8) the run stops with a status that says why,
    not with NaN or a silently wrong peak."""
    blk = Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk, Column(1e14, 2500.0), n_elements=4)
    integ = SpringIntegrator(rtol=1e-8, atol=1e-8, solver="kvaerno5", max_steps=2000)
    s = simulate(model, RickerPulse(4 * G * 0.2, 2 * math.pi), integrator=integ)
    assert s.status in (Status.ok, Status.max_steps)
    if s.status == Status.ok:
        assert float(s.max_theta) == pytest.approx(0.663037, abs=1e-4)


def test_figure13_flexibility_reversal():
    """2h = 50 m, 2b = 5 m concrete column (ζ = 0.01, 10 elements), paper figure 13, against the
    quasi-rigid SM and Housner's RM (`jaxrock.RigidModel`).

    (ω_p/p, a_p/(g tanα)) = (3, 2.6): reproduced — the flexible column overturns, the rigid ones
    keep rocking (measured: quasi-rigid SM 0.7503 on the default bilinear spring, 0.774 on the
    former tanh default; RM 0.753).
    (6, 5.85): the flexible column survives (0.768) and is clearly more stable than the rigid ones,
    as in the paper. The quasi-rigid SM overturns, as in the paper, on the default bilinear spring
    (on tanh at θs = 1e-4 α: 0.972), Housner's RM does not (0.929). The scene lies just below the
    rigid overturning boundary, where max θ/α jumps from ~0.95 to 1 under a few % change of a_p;
    the paper's figure-13 rigid overturning is within that margin (pulse normalisation, η, plotting
    resolution of its spectra), so we assert the reversal's robust part: flexible < 0.8, rigid > 0.9.
    """
    blk = Block.from_size(50.0, 5.0)
    p, ta = float(blk.p), float(blk.tan_alpha)
    res = {}
    for wr, ar in [(3, 2.6), (6, 5.85)]:
        ex = RickerPulse(ar * G * ta, wr * p)
        flex = _sim(SpringModel(blk, Column.concrete()), ex)
        assert flex.status == Status.ok
        res[wr] = (flex, _sim(SpringModel(blk), ex), _sim(jaxrock.RigidModel(blk), ex))
    flex, qr, rm = res[3]
    assert bool(flex.overturned) and float(flex.max_theta) == 1.0
    assert not bool(qr.overturned) and float(qr.max_theta) == pytest.approx(0.750, abs=0.01)
    assert not bool(rm.overturned) and float(rm.max_theta) == pytest.approx(0.753, abs=0.01)
    flex, qr, rm = res[6]
    assert not bool(flex.overturned) and float(flex.max_theta) < 0.8
    assert float(qr.max_theta) > 0.9 and float(rm.max_theta) > 0.9


@pytest.mark.parametrize(
    "kw",
    [
        dict(height=10.0, ta=0.2, smoothing=1e-6, ar=4.0),
        dict(height=10.0, ta=0.02, smoothing=1e-3, ar=4.0),
        dict(height=10.0, ta=0.5, smoothing=1e-3, ar=4.0),
        dict(height=200.0, ta=0.1, smoothing=1e-3, ar=4.0),
        dict(height=10.0, ta=0.2, smoothing=1e-3, ar=50.0),
    ],
)
def test_extreme_quasi_rigid(kw):
    blk = Block.from_slenderness(kw["height"], kw["ta"])
    s = _sim(SpringModel(blk, smoothing=kw["smoothing"]), RickerPulse(kw["ar"] * G * kw["ta"], 2 * math.pi))
    assert np.isfinite(float(s.max_theta))
    assert s.status in (Status.ok, Status.max_steps)
    if s.status == Status.ok:
        assert 0 <= float(s.max_theta) <= 1


@pytest.mark.slow
def test_extreme_flexible():
    blk = Block.from_slenderness(200.0, 0.1)
    s = _sim(SpringModel(blk, Column(1e14, 2500.0), n_elements=4), RickerPulse(50 * G * 0.1, 2.0))
    assert np.isfinite(float(s.max_theta)) or s.status != Status.ok


def test_fixed_base_never_rotates():
    blk = Block.from_size(20.0, 2.0)
    model = SpringModel(blk, Column.concrete(), n_elements=4, fixed_base=True)
    ex = RickerPulse(G * 0.3, 2 * math.pi)
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end), 200)
    s = simulate(model, ex, save=Save(ts, ("theta", "base_moment", "w_top")))
    assert float(jnp.max(jnp.abs(s.history["theta"]))) < 1e-15
    assert float(jnp.max(jnp.abs(s.history["base_moment"]))) > 0
    assert not bool(s.overturned)


def test_chimney_rocking_cuts_base_moment():
    """Paper section 6 (figure 17): the Christchurch chimney under El Centro 1940 NS (40 s), rocking
    on its 7.5 m foundation vs fixed. The paper: max θ = 0.027 α′, base moment 7327 kNm rocking vs
    33200 kNm fixed (ratio 0.22). Measured here (generalized-α 1e-7; Kvaerno5 1e-6 agrees to
    0.1 %): 0.0281 α′ (4 % from the paper), 5398 vs 19491 kNm (ratio 0.28). Our fixed-base
    moment is 41 % below the paper's (its damping and section data are not all given, see the
    closing note of issue 3), so the test asserts what section 6 is about — rocking cuts the base
    moment to well under half — and the rotation within 10 % of the paper's."""
    A, I = 1.74, 2.99
    blk = Block.from_size(32.65, math.sqrt(12 * I / A), base_width=7.5)
    col = Column.concrete(A=A, I=I)
    rec = jaxrock.el_centro()
    ts = jnp.arange(0.0, float(rec.t_end) + 5.0, 0.01)
    integ = GeneralizedAlpha(rtol=1e-7, atol=1e-7)
    out = {}
    for fixed in (False, True):
        s = simulate(SpringModel(blk, col, fixed_base=fixed), rec, integrator=integ, save=Save(ts, ("base_moment",)))
        assert s.status == Status.ok
        out[fixed] = (float(s.max_theta), float(jnp.max(jnp.abs(s.history["base_moment"]))))
    assert out[False][0] == pytest.approx(0.027, rel=0.1)
    assert out[True][0] == 0.0
    assert out[False][1] < 0.35 * out[True][1]
    assert 15e6 < out[True][1] < 25e6  # 19.5 MNm: the fixed column's own response, 40 s of record


# ----------------------------------------------------------------------------------------------
# bad input
# ----------------------------------------------------------------------------------------------
def test_bad_inputs():
    blk = Block.from_slenderness(10.0, 0.2)
    with pytest.raises(JaxrockInputError, match="E"):
        Column(0.0, 2500.0)
    with pytest.raises(JaxrockInputError, match="rho"):
        Column(30e9, -1.0)
    with pytest.raises(JaxrockInputError, match="zeta"):
        SpringModel(blk, Column.concrete(), zeta=-0.01)
    with pytest.raises(JaxrockInputError, match="n_elements"):
        SpringModel(blk, Column.concrete(), n_elements=0)
    with pytest.raises(JaxrockInputError, match="smoothing"):
        SpringModel(blk, smoothing=0.0)
    with pytest.raises(JaxrockInputError, match="cbar"):
        SpringModel(blk, cbar=-0.1)
    with pytest.raises(JaxrockInputError, match="narrower"):
        Block(jnp.asarray(5.0), jnp.asarray(1.0), jnp.asarray(0.5))
    with pytest.raises(JaxrockInputError, match="solver"):
        SpringIntegrator(solver="euler")
    with pytest.raises(JaxrockInputError, match="Save fields"):
        simulate(SpringModel(blk), RickerPulse(1.0, 1.0), save=Save([0.0, 1.0], ("nope",)))


def test_overturning_event_located_where_newton_stalled():
    """Issue 28's failed cell of figure 6 (undamped SM + ΔI, 2h = 10 m, tanα = 0.1, a_p/(g tanα) =
    8.16, ω_p/p = 2.81): Tsit5 1e-10 ended `solver_failed` with max θ/α = 1 and not overturned,
    optimistix's Newton stalling on the overturning event. With the safeguarded Newton–bisection of
    the RM (`jaxrock._rootfind.SafeNewton`) it overturns, status ok, at the time Tsit5 1e-12 finds
    (measured −0.1169026452 against −0.1169026641 s); the RM (η = 1) overturns too."""
    import jaxrock as jr
    from jaxrock.spring import SpringIntegrator, SpringModel

    blk = jr.Block.from_slenderness(10.0, 0.1)
    model = SpringModel(blk, added_masses=True, cbar=0.0)
    ex = jr.RickerPulse(8.161290322580644 * 9.81 * 0.1, 2.806451612903226 * float(blk.p))
    s = jr.simulate(model, ex)
    ref = jr.simulate(model, ex, integrator=SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=2_000_000))
    assert str(jr.status_names(s.status)) == "ok" and str(jr.status_names(ref.status)) == "ok"
    assert bool(s.overturned) and bool(ref.overturned) and float(s.max_theta) == 1.0
    assert float(s.t_overturn) == pytest.approx(float(ref.t_overturn), abs=1e-6)
    assert bool(jr.simulate(jr.RigidModel(blk, eta=1.0), ex).overturned)
