"""Excitations as values (`jaxrock.excitation`): pulses peak at exactly a_p, a record is its samples
linearly interpolated and scales linearly, its next exceedance is the first crossing a dense scan
finds; and a new pulse kind is a class (here a function) and a line in the vocabulary
(`jaxrock.scene.PULSES`), nothing more."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.io.records import el_centro


def test_record_scaled_values():
    rec = el_centro()
    t = jnp.asarray(2.155)
    assert float(rec.scaled(2.5)(t)) == pytest.approx(2.5 * float(rec(t)), rel=1e-14)
    mid = 0.5 * (rec.acc[215] + rec.acc[216])
    assert float(rec(t)) == pytest.approx(float(mid), rel=1e-9)


def _first_dense_exceedance(rec, t0, level, per_step=40):
    """Brute force: dense numpy scan of the piecewise-linear record from t0; first time |üg| ≥ level."""
    ts = np.asarray(rec.times)
    acc = np.asarray(rec.scale * rec.acc)
    dense = np.linspace(t0, ts[-1], int((ts[-1] - t0) / float(rec.dt)) * per_step + 1)
    above = np.abs(np.interp(dense, ts, acc)) >= level
    return (dense[np.argmax(above)] if above.any() else np.inf), dense[1] - dense[0]


def test_next_exceedance_matches_dense_scan():
    rec = el_centro().scaled(1.3)
    pga = float(jnp.max(jnp.abs(rec.scale * rec.acc)))
    starts = np.array([0.0, 0.004, 1.0, 2.0, 2.153, 5.0, 12.345, 30.0])
    fractions = np.array([0.05, 0.3, 0.6, 0.9, 0.999])
    t0, frac = (a.ravel() for a in np.meshgrid(starts, fractions))
    levels = frac * pga
    taus = np.asarray(jax.vmap(rec.next_exceedance)(jnp.asarray(t0), jnp.asarray(levels)))
    for t, level, tau in zip(t0, levels, taus):
        brute, h = _first_dense_exceedance(rec, t, level)
        if not np.isfinite(brute):
            assert np.isinf(tau), (t, level)
            continue
        assert tau >= t
        assert brute - h - 1e-12 <= tau <= brute + 1e-12, (t, level, tau, brute)
        if tau > t:  # a crossing, not "already above": |üg(τ)| is the level itself
            assert abs(float(rec(tau))) == pytest.approx(level, rel=1e-9), (t, level)
        else:
            assert abs(float(rec(t))) >= level
    assert np.isinf(float(rec.next_exceedance(0.0, 1.01 * pga)))
    assert np.isinf(float(rec.next_exceedance(float(rec.t_end) + 0.1, 0.01 * pga)))


@pytest.mark.parametrize("pulse", ["symmetric", "antisymmetric"])
def test_pulse_peak_is_exactly_a_p(pulse):
    """max |üg| = a_p (SPEC; eq. 29's β is the unscaled peak, 1.3801 in the paper rounded): the
    peak is located by a bounded scalar search on the pulse itself, and a dense scan never exceeds it."""
    from scipy.optimize import minimize_scalar

    from jaxrock import AntisymmetricRickerPulse, RickerPulse

    a_p, omega_p = 2.345, 3.7
    exc = (RickerPulse if pulse == "symmetric" else AntisymmetricRickerPulse)(a_p, omega_p)
    f = lambda t: -abs(float(exc(t)))
    bracket = (-0.5 / omega_p, 0.5 / omega_p) if pulse == "symmetric" else (0.5 / omega_p, 2.5 / omega_p)
    peak = -minimize_scalar(f, bounds=bracket, method="bounded", options={"xatol": 1e-12}).fun
    assert abs(peak - a_p) <= 1e-14 * a_p
    ts = jnp.linspace(exc.t_start, exc.t_end, 2_000_001)
    assert float(jnp.max(jnp.abs(exc(ts)))) <= a_p * (1 + 1e-15)
    assert float(exc.peak) == a_p == float(type(exc)(-a_p, omega_p).peak)  # `peak`, any sign


def test_record_peak_is_its_largest_sample_within_its_length_times_its_scale():
    """`Record.peak` (the engine orders a batch's cells by it): max |üg| of the linear interpolant,
    i.e. of its samples, scaled; a padded record's zeros and the samples past `length` are not
    the record."""
    acc = np.array([0.1, -0.7, 0.3, 0.2, 0.0])
    rec = jr.Record(acc, 0.01, 2.0)
    assert float(rec.peak) == 1.4
    assert float(rec.padded(9).peak) == 1.4
    short = jr.Record(np.array([0.1, -0.2, 0.3, -5.0]), 0.01, 1.0, length=3)
    assert float(short.peak) == 0.3 == float(jnp.max(jnp.abs(short(jnp.linspace(0.0, 0.05, 501)))))
    assert float(jr.StillGround().peak) == 0.0


def flipped_ricker(a_p, omega_p):
    """A new pulse kind: the Ricker pulse with the ground moving the other way."""
    return jr.RickerPulse(-a_p, omega_p)


def test_a_new_pulse_kind_needs_only_the_vocabulary(tmp_path, monkeypatch):
    """Added to `PULSES` alone, a pulse kind is read from a scenes file (its ratios converted as
    any pulse's) and runs a spectrum; mirrored ground motion mirrors the response, so its spectrum
    is the symmetric pulse's."""
    monkeypatch.setitem(jr.scene.PULSES, "flipped", flipped_ricker)
    path = tmp_path / "scenes.csv"
    path.write_text("height,tan_alpha,pulse,accel_ratio,omega_ratio\n10,0.2,flipped,3,2\n")
    scenes = jr.read_scenes(path)
    (kind, exc), idx = next(iter(scenes.groups.items()))
    assert (kind, exc) == ("rigid", "flipped")
    pulse = scenes.excitation(exc, idx)
    a_p, w_p = jr.pulse_of_ratios(jr.Block.from_slenderness(10.0, 0.2), 3.0, 2.0)
    np.testing.assert_allclose([float(pulse.a_p[0]), float(pulse.omega_p[0])], [-float(a_p), float(w_p)], rtol=1e-15)
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    grid = dict(omega_ratio=[2.0, 5.0], accel_ratio=[1.5, 4.0], progress=False)
    flipped = jr.overturning_spectrum(model, pulse="flipped", **grid)
    plain = jr.overturning_spectrum(model, pulse="symmetric", **grid)
    assert flipped.attrs["pulse"] == "flipped_ricker"
    np.testing.assert_allclose(flipped.max_theta, plain.max_theta, rtol=1e-9)
    np.testing.assert_array_equal(flipped.overturned, plain.overturned)
