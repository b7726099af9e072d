"""`Checked`: a status that states the global error (issue 29, item 3).

The stiff scenes where generalized-α's local tolerance does not bound its global error, and the
default's `inaccurate` there, are asserted in `test_generalized_alpha.py::test_flexible_extremes`.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.spring import Checked, Column, GeneralizedAlpha, SpringIntegrator, SpringModel

G = 9.81
BLOCK = jr.Block.from_slenderness(50.0, 0.1)
MODEL = SpringModel(BLOCK, Column.concrete(), n_elements=4)
GA5 = GeneralizedAlpha(1e-5, 1e-5)


def grid(n=4):
    w, a = np.meshgrid(np.linspace(1.0, 15.0, n), np.linspace(0.5, 10.0, n))
    return jr.RickerPulse(jnp.asarray(a.ravel() * G * 0.1), jnp.asarray(w.ravel() * float(BLOCK.p)))


def run(integrator, ex):
    return jax.vmap(lambda e: jr.simulate(MODEL, e, integrator=integrator))(ex)


def test_checked_keeps_the_run_and_is_honest_on_a_grid():
    """On a 4 × 4 pulse grid of the 50 m concrete column: the checked run's summary is the
    unchecked run's, bit for bit (the companion only judges it); every `ok` cell is within the
    stated accuracy of GA 1e-8 (measured: all ok, errors ≤ 3e-4, estimates ≤ 2e-3 on the 8 × 8
    grid with 10 elements); and a tight accuracy (1e-5, below the estimates) flags cells."""
    ex = grid()
    plain, checked = run(GA5, ex), run(Checked(GA5), ex)
    ref = run(GeneralizedAlpha(1e-8, 1e-8, levels=24, max_steps=400_000), ex)  # 16 levels: one cell solver_failed at the bottom
    np.testing.assert_array_equal(np.asarray(checked.max_theta), np.asarray(plain.max_theta))
    np.testing.assert_array_equal(np.asarray(checked.t_uplift), np.asarray(plain.t_uplift))
    assert np.all(np.asarray(ref.status._value) == 0)
    ok = np.asarray(checked.status._value) == 0
    err = np.abs(np.asarray(checked.max_theta) - np.asarray(ref.max_theta))
    assert ok.all(), jr.status_names(checked.status)
    assert np.all(err[ok] <= 1e-2)
    strict = run(Checked(GA5, accuracy=1e-5), ex)
    names = set(jr.status_names(strict.status).tolist())
    assert "inaccurate" in names and names <= {"ok", "inaccurate"}, names


def test_checked_judges_a_diffrax_run_both_ways():
    """`Checked` wraps the diffrax integrator too: quasi-rigid Tsit5 at 1e-7 on a pulse near
    overturning (2h = 10 m, tanα = 0.2, a_p = 4 g tanα, ω_p = 2π) is 7.6e-4 off Tsit5 1e-11
    (0.66227 vs 0.66304). Its companion at 1e-6 puts the estimate between 1e-4 and 1e-3: ok at
    accuracy 1e-3 (true), inaccurate at 1e-4 (true); the summary is the plain run's either way.
    On the tanh spring at θs = 1e-4 α, which makes the 1e-7 run's error fall between the two
    accuracies (on the default bilinear at 1e-5 it is 1.2e-5: 0.661138 vs 0.661150)."""
    model = SpringModel(jr.Block.from_slenderness(10.0, 0.2), backbone="tanh", smoothing=1e-4)
    ex = jr.RickerPulse(4.0 * G * 0.2, 2 * math.pi)
    tsit = SpringIntegrator(rtol=1e-7, atol=1e-7, solver="tsit5", max_steps=200_000)
    ref = jr.simulate(model, ex, integrator=SpringIntegrator(rtol=1e-11, atol=1e-11, solver="tsit5", max_steps=200_000))
    plain = jr.simulate(model, ex, integrator=tsit)
    err = abs(float(plain.max_theta) - float(ref.max_theta))
    assert 1e-4 < err <= 1e-3, err
    for accuracy, verdict in ((1e-3, "ok"), (1e-4, "inaccurate")):
        s = jr.simulate(model, ex, integrator=Checked(tsit, accuracy=accuracy))
        assert str(jr.status_names(s.status)) == verdict
        assert float(s.max_theta) == float(plain.max_theta)


def test_a_checked_batch_runs_its_run_and_companion_apart_with_each_cells_verdict(monkeypatch):
    """`run_batch` runs a checked batch's run and companion apart (`CheckedStepper.parts`, each in
    its own passes: in one loop every step would cost both, the finished companion's too), the
    companion from the run's start (computed once), and joins them: every cell's summary, step count and verdict are those of its `simulate` (one
    loop, both states), with a strict accuracy that flags some cells."""
    from jaxrock.analyses import kernels
    from jaxrock.spring.checked import CheckedStepper

    from jaxrock.analyses import engine

    kinds, started = set(), []
    advance, init = kernels.advance, engine._init
    monkeypatch.setattr(kernels, "advance", lambda st, *a: kinds.add(type(st).__name__) or advance(st, *a))
    monkeypatch.setattr(engine, "_init", lambda st, *a: started.append(st.integrator.rtol) or init(st, *a))
    ex, strict = grid(), Checked(GA5, accuracy=1e-5)
    batch, alone = jr.run_batch(MODEL, ex, strict), run(strict, ex)
    assert kinds == {"GeneralizedAlphaStepper"}  # no pass of the two in one loop
    assert started and set(started) == {GA5.rtol}  # the companion starts from the run's start (`shared_start`)
    assert isinstance(MODEL.stepper(strict), CheckedStepper)
    names = jr.status_names(batch.status)
    assert np.array_equal(names, jr.status_names(alone.status)) and set(names.tolist()) == {"ok", "inaccurate"}, names
    np.testing.assert_array_equal(np.asarray(batch.n_iterations), np.asarray(alone.n_iterations))
    # the rounding of the two programs differs; the bilinear spring's landings (regula falsi on
    # kink distances of ~θy) amplify it: measured 4.1e-10 relative (on tanh it met 1e-10)
    np.testing.assert_allclose(np.asarray(batch.max_theta), np.asarray(alone.max_theta), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("kw, match", [
    (dict(accuracy=0.0), "accuracy"),
    (dict(accuracy=1.5), "accuracy"),
    (dict(factor=1.0), "factor"),
    (dict(integrator=GeneralizedAlpha(0.2, 0.2)), "below 1"),
])
def test_checked_refuses_bad_settings(kw, match):
    with pytest.raises(jr.JaxrockInputError, match=match):
        Checked(**{"integrator": GA5, **kw})


def test_checked_refuses_to_nest_and_the_rigid_model_refuses_it():
    with pytest.raises(jr.JaxrockInputError, match="Checked needs"):
        Checked(Checked(GA5))
    with pytest.raises(jr.JaxrockInputError, match="RigidModel needs"):
        jr.simulate(jr.RigidModel(BLOCK), jr.RickerPulse(1.0, 3.0), integrator=Checked(GA5))


def test_the_companion_starts_as_the_run_does_and_leaves_out_only_the_crossing_limit():
    """What a batch's shared start rests on: generalized-α's companion (factor × the tolerances; on
    a flexible column no `crossing` limit, which serves the run's derivatives; the one-DOF body
    keeps it) starts from the run's state bit for bit (its ladder of tangent inverses included); a
    diffrax run's start is not claimed."""
    checked = Checked(GA5)
    assert checked.companion == GeneralizedAlpha(1e-4, 1e-4)
    assert checked.companion_for(MODEL.system()) == GeneralizedAlpha(1e-4, 1e-4, crossing=None)
    assert checked.companion_for(SpringModel(BLOCK).system()) == GeneralizedAlpha(1e-4, 1e-4)
    stepper = MODEL.stepper(checked)
    assert stepper.shared_start
    ex = grid(2)
    run0, comp0 = jax.vmap(stepper.run.init)(ex), jax.vmap(stepper.companion.init)(ex)
    for a, b in zip(jax.tree_util.tree_leaves(run0), jax.tree_util.tree_leaves(comp0), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert not MODEL.stepper(Checked(SpringIntegrator())).shared_start
