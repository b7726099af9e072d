"""Hostile input through the Python API (issue 19): a parameter outside its range is refused at
construction in one line, and under `jax.vmap`/`jax.jit` — where constructors see tracers and
cannot refuse — the run says so with `Status.invalid_input` instead of a plausible `ok`."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock import JaxrockInputError


def test_invalid_parameters_under_vmap_are_flagged_not_answered():
    """NaN a_p, ω_p ≤ 0, tanα outside [1e-3, 1) and a negative height came back `ok` with θ/α of
    0, 3.31 or 1.99; each lane is now `invalid_input` with NaN numbers, and the valid lane in the
    same batch equals its unbatched run."""

    def run(height, tan_alpha, a_p, omega_p):
        block = jr.Block.from_slenderness(height, tan_alpha)
        return jr.simulate(jr.RigidModel(block), jr.RickerPulse(a_p, omega_p))

    lanes = [(10.0, 0.2, 5.0, 6.0), (10.0, 0.2, np.nan, 6.0), (10.0, 0.2, 5.0, -1.0), (10.0, 1.5, 5.0, 6.0),
             (10.0, 1e-8, 5.0, 6.0), (-10.0, 0.2, 5.0, 6.0), (10.0, 0.2, 0.0, 6.0)]
    sol = jax.jit(jax.vmap(run))(*map(jnp.asarray, zip(*lanes)))
    names = list(jr.status_names(sol.status))
    assert names == ["ok"] + ["invalid_input"] * (len(lanes) - 1)
    assert np.all(np.isnan(np.asarray(sol.max_theta)[1:])) and not np.any(np.asarray(sol.overturned)[1:])
    one = jr.simulate(jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2)), jr.RickerPulse(5.0, 6.0))
    assert float(sol.max_theta[0]) == pytest.approx(float(one.max_theta), abs=1e-12)


@pytest.mark.parametrize("kind", ["rigid", "spring"])
def test_run_batch_flags_invalid_lanes_on_either_path(kind):
    """`run_batch` of models stacked under vmap: the rigid model runs in passes with cells gathered,
    the quasi-rigid spring's Tsit5 as one vmapped solve; on both, a lane outside its limits
    (tanα = 1.5, a NaN a_p, ω_p < 0) is `invalid_input` with NaN numbers and the valid lanes equal
    their own `simulate`."""
    heights, tans = jnp.asarray([10.0, 10.0, 10.0, 10.0]), jnp.asarray([0.2, 1.5, 0.2, 0.2])
    a_p, w_p = jnp.asarray([3.0, 3.0, np.nan, 3.0]), jnp.asarray([6.0, 6.0, 6.0, -1.0])
    build = (lambda b: jr.RigidModel(b)) if kind == "rigid" else (lambda b: jr.SpringModel(b))
    models = jax.vmap(lambda h, t: build(jr.Block.from_slenderness(h, t)))(heights, tans)
    sol = jr.run_batch(models, jax.vmap(jr.RickerPulse)(a_p, w_p), model_batched=True)
    assert list(jr.status_names(sol.status)) == ["ok", "invalid_input", "invalid_input", "invalid_input"]
    assert np.all(np.isnan(np.asarray(sol.max_theta)[1:])) and not np.any(np.asarray(sol.overturned)[1:])
    one = jr.simulate(build(jr.Block.from_slenderness(10.0, 0.2)), jr.RickerPulse(3.0, 6.0))
    assert float(sol.max_theta[0]) == pytest.approx(float(one.max_theta), abs=1e-12)


@pytest.mark.parametrize(
    "build, needle",
    [
        (lambda: jr.Block.from_slenderness(10.0, 1e-8), "tan_alpha = 1e-08 is outside the valid range [0.001, 1)"),
        (lambda: jr.Column(1e-3), "E (Young's modulus) [Pa] = 0.001 is outside the valid range [1e+06, 1e+15]"),
        (lambda: jr.Column(30e9, 1e12), "rho (density) [kg/m^3] = 1e+12 is outside the valid range [10, 30000]"),
        (lambda: jr.simulate(jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2)), jr.RickerPulse(5.0, 6.0), t1=-1.0),
         "t1 (end time) applies to a time history"),
    ],
)
def test_out_of_range_or_ignored_parameters_are_refused(build, needle):
    """Each returned a confident answer before: tanα = 1e-8 θ/α = 1.000000 not overturned; E = 1e-3 Pa
    or ρ = 1e12 kg/m³ θ/α = 0, ok; t1 = -1 and t1 = 1e9 the same summary (t1 was ignored)."""
    with pytest.raises(JaxrockInputError, match=re.escape(needle)):
        build()


@pytest.mark.parametrize(
    "build, needle",
    [
        (lambda: jr.RigidModel("block"), "block must be a jaxrock.Block, got str"),
        (lambda: jr.simulate(jr.RigidModel(jr.Block.from_slenderness(10.0, [0.1, 0.2])), jr.RickerPulse(5.0, 6.0)),
         "tan_alpha = b/h has shape (2,); simulate runs one scene"),
        (lambda: jr.simulate(jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2)), jr.RickerPulse([1.0, 2.0], 6.0)),
         "|a_p| (pulse amplitude) [m/s^2] has shape (2,); simulate runs one scene"),
        (lambda: jr.Block.from_size(10.0 + 1j, 2.0), "height (2h) [m] = (10+1j) is complex"),
        (lambda: jr.Block.from_slenderness(None, 0.2), "height (2h) [m] is missing (None)"),
        (lambda: jr.Block.from_slenderness("ten", 0.2), "height (2h) [m] = 'ten' is not a number"),
    ],
)
def test_wrong_kinds_of_value_are_refused_at_construction(build, needle):
    """These failed later inside JAX (an AttributeError, an incompatible-shapes TypeError, a raw
    TypeError) or named the value wrongly ("height = nan" for None)."""
    with pytest.raises(JaxrockInputError, match=re.escape(needle)):
        build()


@pytest.mark.parametrize("value", ["0", "garbage"])
def test_float32_mode_is_gone_and_its_variable_refused(value):
    """JAXROCK_X64=0 ended the default scene in max_steps with θ/α = 0; any value but 1 now stops the import."""
    env = {**os.environ, "JAXROCK_X64": value}
    r = subprocess.run([sys.executable, "-c", "import jaxrock"], env=env, capture_output=True, text=True)
    assert r.returncode != 0 and f"JAXROCK_X64 = '{value}': jaxrock runs in float64 only" in r.stderr


def test_run_batch_with_mismatched_batch_sizes_is_refused():
    """A model batch of 3 with 4 excitations was a raw vmap error ("vmap got inconsistent sizes")."""
    models = jax.vmap(lambda h: jr.RigidModel(jr.Block.from_slenderness(h, 0.2)))(jnp.asarray([5.0, 10.0, 20.0]))
    pulses = jax.vmap(jr.RickerPulse)(jnp.full(4, 5.0), jnp.full(4, 6.0))
    with pytest.raises(JaxrockInputError, match=re.escape("run_batch: the batch sizes differ (excitations: [4]; model: [3])")):
        jr.run_batch(models, pulses, model_batched=True)
    with pytest.raises(JaxrockInputError, match="one is a scalar"):
        jr.run_batch(jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2)), jr.RickerPulse(5.0, 6.0))


def test_forward_mode_through_a_reverse_mode_integrator_says_which_setting_can():
    """Issue 52: `jax.jacfwd` through the rigid model's default (reverse-mode) integrator was a raw
    JAX error ("can't apply forward-mode autodiff (jvp) to a custom_vjp function"). It now names
    the setting that works (that it gives the reverse-mode derivative: test_gradients'
    central-difference test, parametrized over both modes)."""
    block = jr.Block.from_slenderness(10.0, 0.2)

    def rigid(a_p):
        return jr.simulate(jr.RigidModel(block), jr.RickerPulse(a_p, 6.0)).max_theta

    with pytest.raises(JaxrockInputError, match=re.escape("pass integrator=model.default_integrator(autodiff='forward')")):
        jax.jacfwd(rigid)(5.0)


def test_reverse_mode_through_forward_generalized_alpha_says_which_setting_can():
    """Issue 52: `jax.grad` through generalized-α in forward mode was a raw JAX error raised in the
    backward pass ("Reverse-mode differentiation does not work for lax.while_loop"). `simulate` now
    sees the reverse-mode trace and names what works, also under vmap; `jax.jacfwd` still runs.
    (The default integrator under `jax.grad` takes its reverse-mode form: test_backbone's
    test_flexible_reverse_mode_is_forward_mode.)"""
    block = jr.Block.from_slenderness(10.0, 0.2)
    forward = jr.GeneralizedAlpha(1e-5, 1e-5)

    def flexible(cbar):
        return jr.simulate(jr.SpringModel(block, jr.Column(30e9), cbar=cbar, n_elements=2), jr.RickerPulse(5.0, 6.0),
                           integrator=forward).max_theta

    with pytest.raises(JaxrockInputError, match=re.escape("pass integrator=model.default_integrator(autodiff='reverse')")):
        jax.grad(flexible)(0.05)
    with pytest.raises(JaxrockInputError, match="cannot differentiate GeneralizedAlpha with autodiff='forward'"):
        jax.grad(lambda c: jax.vmap(flexible)(c).sum())(jnp.asarray([0.05, 0.06]))
    assert np.isfinite(float(jax.jacfwd(flexible)(0.05)))


@pytest.mark.parametrize(
    "build, needle",
    [
        (lambda: jr.RickerPulse(np.inf, 6.0), "= inf is not a finite number; valid: any finite number"),
        (lambda: jr.Block.from_slenderness(1e300, 0.2), "height (2h) [m] = 1e+300 is outside the valid range [1e-12, 1e+12]"),
        (lambda: jr.Block.from_size(1e-13, 1e-14), "height (2h) [m] = 1e-13 is outside the valid range [1e-12, 1e+12]"),
    ],
)
def test_messages_name_the_value_that_is_wrong(build, needle):
    """Issue 52: "a_p = inf is outside the valid range [-inf, inf]"; `--height 1e300` refused as
    "eta = nan …" (the inertia overflowed before the height was checked). Heights are bounded to
    1e-12–1e12 m, where the dimensionless response was checked to be the same."""
    with pytest.raises(JaxrockInputError, match=re.escape(needle)):
        build()
