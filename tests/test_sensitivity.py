"""A run's sensitivity, max |∂θ/∂ln(scale)|/α′ along the run (`jaxrock.sensitivity`, issue 55 item 1)."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.io.records import el_centro
from jaxrock.spring import Column, GeneralizedAlpha, SpringModel

G = 9.81
BLOCK = jr.Block.from_slenderness(3.0, 0.2)
RM = jr.RigidModel(BLOCK)


def pulse(ar, wr, block=BLOCK, kind=jr.RickerPulse):
    return kind(ar * G * float(block.tan_alpha), wr * float(block.p_r))


def same_summary(a, b):
    """The run with its tangent gives the plain run's summary: the same verdicts and statuses, the
    same numbers to their last bits but for the rounding of another compiled program (the primal
    under `jvp`: 1e-14 relative on the flexible column on the tanh spring; 1.6e-12 on its default
    bilinear spring, whose steps end on the kinks by regula falsi on distances of ~θy = 1e-5 α, which
    amplifies the rounding: bound 1e-11)."""
    for name in ("overturned", "uplifted", "n_impacts"):
        np.testing.assert_array_equal(np.asarray(getattr(a, name)), np.asarray(getattr(b, name)), err_msg=name)
    for name in ("max_theta", "t_overturn", "t_uplift"):
        np.testing.assert_allclose(np.asarray(getattr(a, name)), np.asarray(getattr(b, name)), rtol=1e-11, err_msg=name)
    assert np.array_equal(jr.status_codes(a.status), jr.status_codes(b.status))


@pytest.mark.parametrize("ar, wr, kind", [(2.0, 3.0, jr.RickerPulse), (3.0, 5.0, jr.AntisymmetricRickerPulse)])
def test_the_sensitivity_is_the_slope_of_the_motion_in_the_scale(ar, wr, kind):
    """A history run to four rocking periods after the pulse, against central differences of its
    history in the pulse's amplitude (ln scale ± 1e-6): the largest |Δθ|/(2δ α′) over a fine time
    grid bounds the tangent sampled at the loop steps' ends from above (to the differences' error)
    and is reached within 15 %. The summary run (which stops once its answer is fixed) reports the
    plain run's summary."""
    ex = pulse(ar, wr, kind=kind)
    same_summary(jr.simulate(RM, ex, sensitivity=True), jr.simulate(RM, ex))
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end) + 4 * 2 * math.pi / float(BLOCK.p_r), 4000)
    save = jr.Save(ts, ("theta",))
    s = jr.simulate(RM, ex, save=save, sensitivity=True)
    d = 1e-6
    th = [jr.simulate(RM, ex.scaled(math.exp(k * d)), save=save).history["theta"] for k in (1, -1)]
    slope = np.max(np.abs(np.asarray(th[0]) - np.asarray(th[1]))) / (2 * d) / float(BLOCK.alpha_r)
    assert 0.0 < float(s.sensitivity) <= slope * 1.01, (float(s.sensitivity), slope)
    assert float(s.sensitivity) >= 0.85 * slope, (float(s.sensitivity), slope)


def test_a_chaotic_record_run_is_sensitive_and_uncertain_and_a_short_pulse_is_not():
    """El Centro on a 3 m block (tanα 0.2) at 2.5× its uplift factor rocks to 0.886 α without
    overturning, its tangent grown to ~5e8; a Ricker pulse's stays O(1), its verdict certain.
    Either way the summary is the plain run's, bit for bit. On a 1.5 m block at 1.95× the record
    overturns, and the verdict is rounding's: relative perturbations of 1e-9 of the scale give
    both verdicts, and the run is flagged `uncertain`."""
    rec = el_centro()
    uplift = G * 0.2 / float(jnp.max(jnp.abs(rec.acc)))
    run = rec.scaled(2.5 * uplift)
    s = jr.simulate(RM, run, sensitivity=True)
    same_summary(s, jr.simulate(RM, run))
    assert not bool(s.overturned) and float(s.sensitivity) > 1e7, float(s.sensitivity)
    small = jr.RigidModel(jr.Block.from_slenderness(1.5, 0.2))
    flips = jr.run_batch(small, jax.vmap(rec.scaled)(1.95 * uplift * (1 + 1e-9 * jnp.arange(-8.0, 9.0))))
    assert np.any(np.asarray(flips.overturned)) and not np.all(np.asarray(flips.overturned))
    assert bool(jr.simulate(small, rec.scaled(1.95 * uplift), sensitivity=True).uncertain)
    short = jr.simulate(RM, pulse(2.0, 3.0), sensitivity=True)
    assert float(short.sensitivity) < 10.0 and not bool(short.uncertain)
    assert not bool(jr.simulate(RM, pulse(2.0, 3.0)).uncertain)  # not computed: never flagged


def test_the_uncertain_flag_is_the_perturbation_against_the_margin():
    """`verdict_uncertain`: a standing run is uncertain once δ × sensitivity reaches 1 − max θ/α′,
    an overturned one once it reaches `MARGIN_OVERTURNED`; a NaN sensitivity (not computed) never.
    And every run of a batch reports the flag its own numbers give."""
    from jaxrock.outputs import MARGIN_OVERTURNED, PERTURBATION

    margin = np.array([0.1, 0.1, MARGIN_OVERTURNED, MARGIN_OVERTURNED, 0.1])
    s = margin / PERTURBATION * np.array([0.999, 1.001, 0.999, 1.001, np.nan])
    over = np.array([False, False, True, True, False])
    got = jr.verdict_uncertain(s, np.where(over, 1.0, 1.0 - margin), over)
    np.testing.assert_array_equal(got, [False, True, False, True, False])
    assert bool(jr.verdict_uncertain(1.0, 1.0 - 1e-3, False, perturbation=2e-3))
    rec = el_centro()
    k = G * 0.2 / float(jnp.max(jnp.abs(rec.acc))) * jnp.linspace(1.0, 4.5, 8)  # 2.5x among them
    sol = jr.run_batch(RM, jax.vmap(rec.scaled)(k), sensitivity=True)
    np.testing.assert_array_equal(np.asarray(sol.uncertain),
                                  jr.verdict_uncertain(np.asarray(sol.sensitivity), np.asarray(sol.max_theta), np.asarray(sol.overturned)))
    assert np.any(np.asarray(sol.uncertain)) and not np.all(np.asarray(sol.uncertain))
    np.testing.assert_array_equal(np.asarray(sol.sensitivity) > 0, np.asarray(sol.uplifted))


def test_a_batch_reports_each_runs_sensitivity_as_simulate_does():
    """`run_batch(sensitivity=True)` (its passes gather the running cells: the tangent travels with
    the state) gives every cell `simulate`'s summary and sensitivity; a block at rest has 0."""
    ex = jr.RickerPulse(jnp.linspace(0.5, 4.0, 12) * G * 0.2, jnp.linspace(2.0, 8.0, 12) * float(BLOCK.p_r))
    batch = jr.run_batch(RM, ex, sensitivity=True)
    alone = jax.vmap(lambda e: jr.simulate(RM, e, sensitivity=True))(ex)
    np.testing.assert_allclose(np.asarray(batch.sensitivity), np.asarray(alone.sensitivity), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(batch.max_theta), np.asarray(alone.max_theta), rtol=1e-10, atol=1e-12)
    at_rest = ~np.asarray(batch.uplifted)
    assert at_rest.any() and np.all(np.asarray(batch.sensitivity)[at_rest] == 0.0)
    assert np.all(np.asarray(batch.sensitivity)[~at_rest] > 0.0)


@pytest.mark.parametrize("model, integrator", [
    (SpringModel(BLOCK), None),  # the forward-mode Tsit5 default
    # generalized-α on the default bilinear spring: its steps end on the kinks (stepping over them
    # its tangent was off: 1.4 against the rigid model's 3.8 here)
    (SpringModel(BLOCK), GeneralizedAlpha(1e-6, 1e-6)),
    (SpringModel(jr.Block.from_size(50.0, 5.0), Column.concrete(), n_elements=4), None),  # Checked generalized-α
])
def test_the_spring_models_report_it_too(model, integrator):
    """The quasi-rigid and flexible spring models: an uplifting pulse's sensitivity is finite and
    positive, near the rigid model's on the same block (the quasi-rigid body rocks as the rigid
    one), and the summary is the plain run's."""
    ex = pulse(2.0, 3.0, model.block)
    s = jr.simulate(model, ex, integrator=integrator, sensitivity=True)
    same_summary(s, jr.simulate(model, ex, integrator=integrator))
    assert 0.0 < float(s.sensitivity) < 1e3
    if not model.flexible:
        rigid = jr.simulate(jr.RigidModel(model.block), ex, sensitivity=True)
        assert abs(float(s.sensitivity) / float(rigid.sensitivity) - 1) < 0.2, (float(s.sensitivity), float(rigid.sensitivity))


def test_it_is_asked_for_and_needs_forward_mode():
    """Not asked: NaN (not computed). A reverse-mode integrator is refused with one clear line."""
    assert math.isnan(float(jr.simulate(RM, pulse(2.0, 3.0)).sensitivity))
    with pytest.raises(jr.JaxrockInputError, match="forward-mode"):
        jr.simulate(RM, pulse(2.0, 3.0), integrator=jr.EventIntegrator(), sensitivity=True)
    with pytest.raises(jr.JaxrockInputError, match="forward-mode"):
        jr.run_batch(RM, jr.RickerPulse(jnp.ones(2), jnp.ones(2) * 6.0), jr.EventIntegrator(), sensitivity=True)


@pytest.mark.slow
def test_a_checked_batch_follows_its_runs_tangent():
    """A flexible column's `Checked` default in a batch: the run (the first of its `parts`) carries
    the tangent, the companion judges it; every cell's sensitivity, status and summary are those of
    `simulate` (one loop of both): the summaries to 1e-10, the sensitivities to 1e-7 (the runs'
    round-off differs with the batch's shape, and a sensitivity of 37 amplifies it: measured 1.3e-8
    relative since generalized-α's tangent is applied from its modes, two products where one was)."""
    model = SpringModel(jr.Block.from_size(50.0, 5.0), Column.concrete(), n_elements=4)
    ex = jr.RickerPulse(jnp.array([2.0, 3.0, 4.0, 2.5]) * G * float(model.block.tan_alpha),
                        jnp.array([2.0, 3.0, 5.0, 4.0]) * float(model.block.p_r))
    batch = jr.run_batch(model, ex, sensitivity=True)
    alone = jax.vmap(lambda e: jr.simulate(model, e, sensitivity=True))(ex)
    np.testing.assert_allclose(np.asarray(batch.sensitivity), np.asarray(alone.sensitivity), rtol=1e-7)
    np.testing.assert_allclose(np.asarray(batch.max_theta), np.asarray(alone.max_theta), rtol=1e-10, atol=1e-12)
    assert np.array_equal(jr.status_codes(batch.status), jr.status_codes(alone.status))
    assert np.all(np.asarray(batch.sensitivity) > 0)


@pytest.mark.slow
def test_the_quasi_rigid_tangent_stays_finite_through_thousands_of_kinks():
    """El Centro on a 4 m quasi-rigid block (tanα 0.3) at factor 1: after its rocking the block rings
    about its spring's yield rotation, ~4000 kinks, many of them near grazing (θ̇ ≈ 0 at |θ| = θy),
    each with an event time whose derivative is ~1/θ̇. The next solve starts at the kink's time with
    the state's fixed-time derivative (`equal_time`: the spring's moment is continuous there), so
    the tangent stays finite (carried from kink to kink, the time's derivative overflowed and the
    next root find raised: the failure of `jaxrock reproduce`'s figure 10). The sensitivity is
    finite, the flag the one its numbers give, and the summary is the plain run's."""
    model = SpringModel(jr.Block.from_slenderness(4.0, 0.3))
    ex = jax.vmap(el_centro().scaled)(jnp.array([1.0, 1.5]))
    s = jr.run_batch(model, ex, sensitivity=True)
    plain = jr.run_batch(model, ex)
    same_summary(s, plain)
    sens = np.asarray(s.sensitivity)
    assert np.all(np.isfinite(sens)) and np.all(sens > 0), sens
    np.testing.assert_array_equal(np.asarray(s.uncertain),
                                  jr.verdict_uncertain(sens, np.asarray(s.max_theta), np.asarray(s.overturned)))
