"""Invariants over random scenes, vmapped: a summary run (what spectra and batch use) and a history
run of the same scene agree on `overturned`, `t_overturn` and `max_theta`, and no `Solution` ever
contradicts its own flags.

Scenes span tanα 0.05–0.35, 2h 1–50 m (log-uniform), a_p/(g tanα′) 0.5–10, ω_p/p′ 1–15, both
pulses, plain and extended bases (tanα′ up to 1.6 tanα), and for the RM η = 1 and eq. 3. The
default run holds 320 rigid and 64 quasi-rigid SM scenes (one compile per model kind, pulse and
run kind); the slow run 4160 and 960 more (5120). The history runs last long enough (t_end + 20/p′, or past the summary's
overturning time) to reach every event the summary predicts.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.spring import SpringModel

PULSES = {"symmetric": jr.RickerPulse, "antisymmetric": jr.AntisymmetricRickerPulse}
N_SAVE = 4  # history samples: only the summaries of the history runs are compared


def random_scenes(n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    tan_a = rng.uniform(0.05, 0.35, n)
    extended = rng.random(n) < 0.5
    return {
        "height": np.exp(rng.uniform(np.log(1.0), np.log(50.0), n)),
        "tan_a": tan_a,
        "tan_base": np.where(extended, tan_a * rng.uniform(1.0, 1.6, n), tan_a),
        "undamped": rng.random(n) < 0.5,
        "accel": rng.uniform(0.5, 10.0, n),
        "omega": rng.uniform(1.0, 15.0, n),
    }


def rigid_model(sc):
    block = jr.Block.from_slenderness(sc["height"], sc["tan_a"], sc["tan_base"])
    return jr.RigidModel(block, eta=jnp.where(sc["undamped"], 1.0, block.eta_r))


def spring_model(sc):
    return SpringModel(jr.Block.from_slenderness(sc["height"], sc["tan_a"], sc["tan_base"]))


# both runs at the model's default integrator (the quasi-rigid one: the exact pre-yield phase, then
# Tsit5 at 1e-10 with 200 000 steps, room for history runs, whose steps stay within the excitation's max_step to the
# end: 1 of 32 slow-run scenes needs more than the class default 20 000)
HISTORY_INTEGRATOR = {rigid_model: None, spring_model: None}


def excitation(model, pulse, sc):
    blk = model.block
    return PULSES[pulse](sc["accel"] * blk.uplift_acceleration, sc["omega"] * blk.p_r)


def history_end(m, exc, t_over):
    """20/p′ past the excitation (past the next free peak, even within e^-20 of the threshold) or
    past the summary's overturning time, whichever is later."""
    p = m.block.p_r
    return jnp.maximum(exc.t_end + 20.0 / p, jnp.where(jnp.isfinite(t_over), t_over + 1.0 / p, -jnp.inf))


@functools.cache
def _programs(make_model, pulse: str):
    """The vmapped summary, window and history programs of one model kind and pulse (compiled once)."""

    def summary(sc):
        m = make_model(sc)
        return jr.simulate(m, excitation(m, pulse, sc))

    def window(sc, t_over):
        m = make_model(sc)
        exc = excitation(m, pulse, sc)
        return exc.t_start, history_end(m, exc, t_over)

    def history(sc, save, t1):
        m = make_model(sc)
        return jr.simulate(m, excitation(m, pulse, sc), save=save, t1=t1, integrator=HISTORY_INTEGRATOR[make_model])

    return jax.jit(jax.vmap(summary)), jax.jit(jax.vmap(window)), jax.jit(jax.vmap(history))


def run_both(make_model, pulse: str, scenes: dict) -> tuple[jr.Solution, jr.Solution]:
    """Summary and history runs of every scene."""
    summary, window, history = _programs(make_model, pulse)
    sc = {k: jnp.asarray(v) for k, v in scenes.items()}
    s = summary(sc)
    t0, t1 = (np.asarray(x) for x in window(sc, s.t_overturn))
    # inside the run's window by a margin: the two programs may round t_start differently
    saves = [jr.Save(np.linspace(a + 1e-9 * abs(a), b - 1e-9 * abs(b), N_SAVE)) for a, b in zip(t0, t1)]
    save = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *saves)
    return s, history(sc, save, jnp.asarray(t1))


def assert_self_consistent(sol: jr.Solution, threshold: float = 1.0):
    """A result never contradicts its own flags."""
    mt, over = np.asarray(sol.max_theta), np.asarray(sol.overturned)
    t_over, up = np.asarray(sol.t_overturn), np.asarray(sol.uplifted)
    ok = np.asarray(jr.status_codes(sol.status)) == 0
    assert ok.all(), f"{(~ok).sum()} scenes failed: {set(jr.status_names(sol.status)[~ok])}"
    assert np.all(np.isfinite(mt))
    assert not np.any((mt >= threshold) & ~over), "max_theta at the threshold without overturning"
    assert not np.any(np.isfinite(t_over) & ~over), "a finite t_overturn without overturning"
    assert np.all(np.isfinite(t_over[over])) and np.all(mt[over] == threshold)
    assert np.all(up[over]), "overturned without uplifting"


def assert_summary_matches_history(s: jr.Solution, h: jr.Solution, theta_tol: float, t_tol: float):
    assert_self_consistent(s)
    assert_self_consistent(h)
    s_over, h_over = np.asarray(s.overturned), np.asarray(h.overturned)
    bad = np.flatnonzero(s_over != h_over)
    assert bad.size == 0, f"overturned differs in {bad.size} scenes, e.g. {bad[:5]}"
    dt = np.abs(np.asarray(s.t_overturn)[s_over] - np.asarray(h.t_overturn)[s_over])
    assert np.all(dt < t_tol), f"t_overturn differs by up to {dt.max():.3g} s"
    dth = np.abs(np.asarray(s.max_theta) - np.asarray(h.max_theta))
    assert np.all(dth <= theta_tol), f"max_theta differs by up to {dth.max():.3g} (scene {np.argmax(dth)})"


# rigid: both runs take the same steps until the end of the excitation; after it the summary uses
# the closed-form next peak, the history the located apex (1e-9 of α′) on a trajectory that differs
# by the step control: over the 4320 random scenes of both tests up to 4.5e-9 of α′ (1e-9 held on
# the default run's 160 but failed 7 of the 26 slow batches, 1.1e-9 to 4.5e-9), so 1e-8, the
# default rtol. t_overturn: root finds (1e-13 s) on trajectories that differ by the step control
# (~1e-10 rad).
RIGID_TOL = dict(theta_tol=1e-8, t_tol=1e-7)
# quasi-rigid SM: the summary restarts its steps at the end of the excitation; both runs start with
# the same exact pre-yield phase
SPRING_TOL = dict(theta_tol=1e-7, t_tol=1e-6)


# model kind -> (model, tolerances, scenes per vmapped batch)
KINDS = {"rigid": (rigid_model, RIGID_TOL, 160), "quasi_rigid_sm": (spring_model, SPRING_TOL, 32)}


def check_random_scenes(kind: str, pulse: str, seed: int):
    make_model, tol, n = KINDS[kind]
    s, h = run_both(make_model, pulse, random_scenes(n, seed=seed))
    assert_summary_matches_history(s, h, **tol)


# the antisymmetric pulse is slow (rigid 61 s, quasi-rigid 32 s): the invariant is the same code path
@pytest.mark.parametrize("pulse", [p if p == "symmetric" else pytest.param(p, marks=pytest.mark.slow) for p in PULSES])
@pytest.mark.parametrize("kind", KINDS)
def test_summary_agrees_with_history(kind, pulse):
    check_random_scenes(kind, pulse, seed=10 * list(KINDS).index(kind) + list(PULSES).index(pulse))


# more random scenes, in batches of the default sizes (one compiled program per kind and pulse; each
# batch is one test, well inside the per-test limit): the first 4 batches of each kind (640 rigid and
# 128 quasi-rigid SM scenes per pulse, 85 s) in the slow set, the other 2880 and 704 a study
# (`pytest -m study`, 591 s of CI's slow set on 2 cores: one rigid batch took 268 s)
CI_BATCHES = 4
SLOW_BATCHES = [pytest.param(kind, k, marks=pytest.mark.slow if k < CI_BATCHES else pytest.mark.study)
                for kind, n in (("rigid", 13), ("quasi_rigid_sm", 15)) for k in range(n)]


@pytest.mark.parametrize("pulse", PULSES)
@pytest.mark.parametrize("kind,batch", SLOW_BATCHES)
def test_summary_agrees_with_history_many(kind, batch, pulse):
    check_random_scenes(kind, pulse, seed=1000 + 100 * list(KINDS).index(kind) + 2 * batch + list(PULSES).index(pulse))
