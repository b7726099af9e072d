"""The quasi-rigid SM's exact pre-yield phase (`jaxrock.spring.rest`): the closed-form uplift
threshold, the solver's motion to its tolerance, the grid's convergence, a record's grid being the
record itself, and derivatives through the first yield."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock
from jaxrock.excitation import AntisymmetricRickerPulse, RickerPulse
from jaxrock.geometry import G, Block
from jaxrock.model import simulate
from jaxrock.spring import SpringIntegrator, SpringModel
from jaxrock.spring import rest as R

_first_yield = jax.jit(lambda m, ex: R.rest_phase(m.system(), ex, jnp.inf, False))
_sim = jax.jit(lambda m, ex, integ: simulate(m, ex, integrator=integ), static_argnums=2)
# the same run, its pre-yield phase stepped by the solver (the reference of these tests)
_SOLVER = SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=1_000_000, exact_rest=False)
_EXACT = SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=1_000_000)

# seeded scenes: (2h, tanα, ω_p/p, a_p/(g tanα), antisymmetric)
_SCENES = [(5.9, 0.176, 3.9, 3.7, True), (12.8, 0.072, 4.0, 3.77, True), (2.0, 0.3, 1.3, 1.6, False),
           (30.0, 0.12, 9.0, 5.5, False), (1.2, 0.25, 2.2, 2.5, True)]


def _scene(h2, ta, wr, ar, anti):
    blk = Block.from_slenderness(h2, ta)
    return SpringModel(blk), (AntisymmetricRickerPulse if anti else RickerPulse)(*jaxrock.pulse_of_ratios(blk, ar, wr))


def test_a_slow_pulse_yields_at_the_static_threshold():
    """Quasi-static uplift (eq. 10 pre-yield with θ̈, θ̇ → 0): My θ/θy − m g h θ = m h |üg| reaches
    θy where |üg| = g (b − h θy)/h, i.e. at g tanα (1 − θy/tanα); on a pulse 200 times slower than
    the block (ω_p/p = 0.005) the first yield comes at that level's first exceedance within 1e-4 of
    the pulse period, and never on a pulse below it."""
    blk = Block.from_slenderness(10.0, 0.2)
    m = SpringModel(blk)
    theta_y = float(m.system().theta_s)
    level = G * blk.tan_alpha * (1 - theta_y / blk.tan_alpha)
    for ar in (1.05, 1.5, 3.0):
        ex = RickerPulse(*jaxrock.pulse_of_ratios(blk, ar, 0.005))
        end = _first_yield(m, ex)
        t_static = float(ex.next_exceedance(ex.t_start, level))
        assert bool(end.yielded)
        assert abs(float(end.t) - t_static) * float(ex.omega_p) / (2 * math.pi) < 1e-4, (ar, float(end.t), t_static)
        assert abs(float(end.y[0])) == pytest.approx(theta_y, rel=1e-12)
    below = _first_yield(m, RickerPulse(*jaxrock.pulse_of_ratios(blk, 0.95, 0.005)))
    assert not bool(below.yielded) and float(below.peak) < theta_y


@pytest.mark.slow  # two compiles of Tsit5 1e-12 runs; the default run keeps test_spring's tolerance test (the same comparison on two scenes)
def test_exact_phase_agrees_with_the_solver_through_it():
    """The summary with the exact pre-yield phase (the default) against the same run whose solver
    steps the phase too, both at Tsit5 1e-12: max θ/α and the uplift time agree to the solver's own
    error (measured: ≤ 3e-9 and 2e-7/p; the study's 192 + 56 pulses: `bench_backbone.py --part
    tolerance`)."""
    for sc in _SCENES:
        m, ex = _scene(*sc)
        a, b = _sim(m, ex, _EXACT), _sim(m, ex, _SOLVER)
        p = float(m.system().p_r)
        assert bool(a.overturned) == bool(b.overturned)
        assert abs(float(a.max_theta) - float(b.max_theta)) < 1e-7, sc
        assert abs(float(a.t_uplift) - float(b.t_uplift)) * p < 2e-6, sc


@pytest.mark.slow  # three grids, a compile each; the default run keeps the static threshold and the derivatives
def test_pulse_grid_converges(monkeypatch):
    """The grid over the pulse window (`REST_STEPS`) converges at the h⁴ of the interpolated pulse:
    the first yield's time and velocity at the default against 4 times finer, within 1e-6/p and
    1e-9 p α′ (`bench_backbone.py --part rest`: ≤ 9.3e-8 and 1.1e-10 on 192 pulses), and 4 times
    coarser farther off than the default."""
    def first(steps):
        monkeypatch.setattr(R, "REST_STEPS", steps)
        out = []
        for sc in _SCENES:
            m, ex = _scene(*sc)
            end = jax.jit(lambda m, ex: R.rest_phase(m.system(), ex, jnp.inf, False))(m, ex)
            s = m.system()
            out.append((float(end.t * s.p_r), float(end.y[1] / (s.p_r * s.alpha_r))))
        return np.array(out)

    default = R.REST_STEPS
    d, fine, coarse = first(default), first(4 * default), first(default // 4)
    assert np.max(np.abs(d[:, 0] - fine[:, 0])) < 1e-6 and np.max(np.abs(d[:, 1] - fine[:, 1])) < 1e-9
    assert np.max(np.abs(coarse - fine)) > np.max(np.abs(d - fine))


@pytest.mark.slow  # a 40-s record at two samplings; the default run keeps the pulses' exact phase
def test_a_records_grid_is_the_record():
    """On a record the ground acceleration is linear between samples, so one step per sample is
    exact: the same record sampled 4 times finer (the same motion) gives the same first yield to
    round-off, including yields between two samples, which only the sub-steps' interpolants see
    (seeded El Centro scenes where the step ends alone came 0.3–0.7/p late)."""
    rec = jaxrock.el_centro()
    acc, dt = np.asarray(rec.acc), float(rec.dt)
    tu = np.arange((acc.size - 1) * 4 + 1) * dt / 4
    finer = jaxrock.Record(np.interp(tu, np.arange(acc.size) * dt, acc), dt / 4)
    rng = np.random.default_rng(3)
    for _ in range(6):
        blk = Block.from_slenderness(float(np.exp(rng.uniform(0, math.log(50)))), float(rng.uniform(0.05, 0.35)))
        m = SpringModel(blk)
        scale = rng.uniform(1, 4) * G * blk.tan_alpha / float(np.max(np.abs(acc)))
        a, b = _first_yield(m, rec.scaled(scale)), _first_yield(m, finer.scaled(scale))
        p = float(m.system().p_r)
        assert bool(a.yielded) and bool(b.yielded)
        assert abs(float(a.t) - float(b.t)) * p < 1e-10
        assert abs(float(a.y[1]) - float(b.y[1])) / (p * float(blk.alpha)) < 1e-10


@pytest.mark.parametrize("mode", ["forward", "reverse"])
def test_uplift_time_derivative_is_the_motions(mode):
    """d t_uplift / d ln a_p through the exact phase (the located first yield) against central
    differences (h = 1e-5), and against the quasi-static closed form d t/d ln a_p = −üg/(d üg/dt) at
    the threshold on a slow pulse (its dynamic part ~(ω_p/ω_s)² below)."""
    blk = Block.from_slenderness(10.0, 0.2)
    m = SpringModel(blk)
    a_p, w_p = jaxrock.pulse_of_ratios(blk, 2.0, 0.05)

    def t_up(log_a):  # reverse mode: the phase's checkpointed loop
        return R.rest_phase(m.system(), RickerPulse(jnp.exp(log_a), w_p), jnp.inf, mode == "reverse").t

    x = jnp.log(a_p)
    d = jax.jacfwd(t_up)(x) if mode == "forward" else jax.grad(t_up)(x)
    h = 1e-5
    fd = (t_up(x + h) - t_up(x - h)) / (2 * h)
    assert np.isfinite(float(d))
    assert abs(float(d) - float(fd)) <= 1e-5 * abs(float(fd)), (float(d), float(fd))
    t = t_up(x)
    ex = RickerPulse(a_p, w_p)
    slope = jax.grad(ex)(t)
    assert float(d) == pytest.approx(-float(ex(t)) / float(slope), rel=1e-3)
