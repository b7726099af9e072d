"""Identification from a measured motion (`jaxrock.identify`, `jaxrock.analyses.identify`): the forward
model against `simulate`, the free-rocking peaks against the closed form of eq. 3, recovery of known
parameters from synthetic noisy histories with the truth inside the reported interval, a parameter
the measurement cannot determine reported as such, and bad input refused."""

import warnings

import numpy as np
import pytest

import jaxrock as jr
from jaxrock.analyses.identify import find_peaks, history, noise_level, segments

BLOCK = jr.Block.from_slenderness(2.0, 0.15)
ALPHA = float(BLOCK.alpha_r)
T = np.arange(0.0, 5.0, 0.005)
PULSE = jr.RickerPulse(*jr.pulse_of_ratios(BLOCK, 2.5, 4.0))


def _free_rocking(model, t=T, x0=0.8):
    theta, status = history(model, jr.StillGround(), t, start=(0.0, x0 * ALPHA, 0.0))
    assert status == jr.Status.ok
    return np.asarray(theta)


def _noisy(theta, sigma, seed):
    return theta + np.random.default_rng(seed).normal(0.0, sigma, theta.size)


@pytest.mark.slow
def test_history_from_rest_is_simulate():
    """The forward model from rest is `simulate`'s history, for the rigid and the spring model."""
    ts = np.linspace(PULSE.t_start, PULSE.t_end + 2.0, 300)
    for model in (jr.RigidModel(BLOCK), jr.SpringModel(BLOCK, cbar=0.03, backbone="tanh")):
        theta, status = history(model, PULSE, ts, integrator=None if isinstance(model, jr.RigidModel) else
                                jr.SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5", autodiff="forward"))
        ref = jr.simulate(model, PULSE, save=jr.Save(ts), integrator=None if isinstance(model, jr.RigidModel) else
                          jr.SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5")).history["theta"]
        assert status == jr.Status.ok
        assert np.max(np.abs(np.asarray(theta) - np.asarray(ref))) / ALPHA < 1e-6, type(model).__name__


def test_free_rocking_peaks_follow_eq3():
    """Free rocking from a release: every impact keeps η² of the energy (eq. 3), so the closed-form
    peak-ratio estimate on the measured peaks (parabola-refined) returns η."""
    theta = _free_rocking(jr.RigidModel(BLOCK, eta=0.9))
    t_pk, th_pk, release = find_peaks(T, theta, float(BLOCK.p_r), noise=0.0)
    assert release and t_pk[0] == 0.0 and abs(th_pk[0] / ALPHA - 0.8) < 1e-6
    assert np.all(np.sign(th_pk[1:]) == -np.sign(th_pk[:-1]))  # one impact between two peaks
    eta, ratios = jr.eta_from_peaks(th_pk, ALPHA)
    assert abs(eta - 0.9) < 2e-4 and np.all(np.abs(ratios - 0.9) < 1e-3)


# slow: a fit compiles for 60–200 s on 2 cores (identify's kernels miss the persistent cache), and the
# default run grew to 12.5 min in CI with it
@pytest.mark.slow
@pytest.mark.parametrize("sigma", [2e-4])
def test_identify_eta_free_rocking(sigma):
    """η from a noisy free-rocking test: within the noise's reach of the truth, the truth inside the
    interval, and in agreement with the closed-form peak-ratio estimate within its own scatter."""
    theta = _free_rocking(jr.RigidModel(BLOCK, eta=0.9))
    noisy = _noisy(theta, sigma, seed=3)
    assert abs(noise_level(noisy) / sigma - 1) < 0.15
    fit = jr.identify(jr.Measured(T, noisy), jr.RigidModel(BLOCK, eta=0.8), ["eta"], n_boot=20)
    lo, hi = fit.interval[0]
    assert fit.converged and fit.identifiable.all()
    assert lo <= 0.9 <= hi and hi - lo < 40 * sigma
    assert abs(fit.estimate[0] - 0.9) < 4 * fit.se[0] + 1e-6
    assert abs(fit.rms / sigma - 1) < 0.15  # the fit leaves the noise
    eta_pk, ratios = jr.eta_from_peaks(fit.segments.peaks_theta, ALPHA)
    assert abs(eta_pk - fit.estimate[0]) < 3 * np.std(ratios) / np.sqrt(ratios.size) + 4 * fit.se[0]
    assert fit.bootstrap.shape[0] >= 10 and np.all(np.isfinite(fit.bootstrap_interval))


@pytest.mark.slow
def test_multiple_shooting_segments_start_at_peaks():
    """The multiple-shooting segments start at the measured peaks (θ̇ = 0), each holding one impact,
    and the fit from them alone recovers η (the robust first stage of the default loss)."""
    theta = _free_rocking(jr.RigidModel(BLOCK, eta=0.9))
    seg = segments(jr.Measured(T, theta), float(BLOCK.p_r), "multiple")
    real = seg.mask.any(axis=1)
    assert np.allclose(seg.t0[real], seg.peaks_t[:-1]) and np.allclose(seg.theta0[real], seg.peaks_theta[:-1])
    for k in np.flatnonzero(real):
        s = np.sign(seg.theta[k][seg.mask[k]])
        assert np.count_nonzero(np.diff(s)) == 1, k  # exactly one zero crossing: one impact
    fit = jr.identify(jr.Measured(T, _noisy(theta, 2e-4, 5)), jr.RigidModel(BLOCK, eta=0.7), ["eta"], loss="multiple", n_boot=0)
    assert fit.loss == "multiple" and abs(fit.estimate[0] - 0.9) < 4 * fit.se[0] and fit.interval[0, 0] <= 0.9 <= fit.interval[0, 1]


@pytest.mark.slow
def test_identify_cbar_of_the_spring_model():
    """c̄ of the quasi-rigid spring model (smooth backbone) from its free rocking."""
    truth = jr.SpringModel(BLOCK, cbar=0.03, backbone="tanh")
    noisy = _noisy(_free_rocking(truth), 2e-4, 2)
    fit = jr.identify(jr.Measured(T, noisy), jr.SpringModel(BLOCK, cbar=0.06, backbone="tanh"), ["cbar"], n_boot=0)
    assert fit.interval[0, 0] <= 0.03 <= fit.interval[0, 1] and abs(fit.estimate[0] - 0.03) < 4 * fit.se[0]


@pytest.mark.slow
def test_a_parameter_the_motion_does_not_determine():
    """The spring's smoothing θs/α′ (its pre-yield rotation, 10⁻⁴-scale) leaves no trace in a rotation
    measured to 10⁻³ rad beside c̄: the fit warns and reports θs/α′'s whole range, never a confident
    number, while c̄ stays determined."""
    truth = jr.SpringModel(BLOCK, cbar=0.03, backbone="tanh")
    noisy = _noisy(_free_rocking(truth), 1e-3, 0)
    with pytest.warns(UserWarning, match="does not determine smoothing"):
        fit = jr.identify(jr.Measured(T, noisy), jr.SpringModel(BLOCK, cbar=0.06, backbone="tanh"), ["cbar", "smoothing"], n_boot=0)
    assert list(fit.identifiable) == [True, False] and tuple(fit.interval[1]) == (0.0, 1.0)
    assert fit.interval[0, 0] <= 0.03 <= fit.interval[0, 1]


@pytest.mark.parametrize("kwargs, match", [
    (dict(free=["omega"]), "free: 'omega' is not a parameter"),
    (dict(free=["cbar"]), "has no 'cbar'"),
    (dict(free=["eta", "eta"]), "names a parameter twice"),
    (dict(loss="least"), "loss = 'least'"),
    (dict(n_boot=-1), "n_boot = -1"),
])
def test_bad_input(kwargs, match):
    theta = np.sin(T)
    with pytest.raises(jr.JaxrockInputError, match=match):
        jr.identify(jr.Measured(T, theta), jr.RigidModel(BLOCK, eta=0.9), **{"free": ["eta"], **kwargs})


def test_bad_measurements_and_models():
    with pytest.raises(jr.JaxrockInputError, match="strictly increasing"):
        jr.Measured(T[::-1], np.zeros(T.size))
    with pytest.raises(jr.JaxrockInputError, match="one length"):
        jr.Measured(T, np.zeros(3))
    with pytest.raises(jr.JaxrockInputError, match="backbone has kinks"):
        jr.identify(jr.Measured(T, np.sin(T)), jr.SpringModel(BLOCK, cbar=0.03), ["cbar"])
    with pytest.raises(jr.JaxrockInputError, match="eta = 1 to start from"):
        jr.identify(jr.Measured(T, np.sin(T)), jr.RigidModel(BLOCK, eta=1.0), ["eta"])
    with pytest.raises(jr.JaxrockInputError, match="at least two"):
        jr.identify(jr.Measured(T, 1e-3 * ALPHA * np.exp(-T)), jr.RigidModel(BLOCK, eta=0.9), ["eta"])


# ----------------------------------------------------------------------------------------------
# coverage: the truth inside the reported 95 % interval in ≥ 90 % of 50 seeded trials
# ----------------------------------------------------------------------------------------------
def _coverage(truth_model, start_model, name, value, sigma, excitation=None, t=T, trials=50):
    if excitation is None:
        clean = _free_rocking(truth_model, t)
    else:
        clean = np.asarray(history(truth_model, excitation, t)[0])
    inside, errors = 0, []
    for seed in range(trials):
        fit = jr.identify(jr.Measured(t, _noisy(clean, sigma, 100 + seed), excitation), start_model, [name], n_boot=0, warn=False)
        inside += fit.interval[0, 0] <= value <= fit.interval[0, 1]
        errors.append(fit.estimate[0] - value)
    return inside, np.asarray(errors)


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("sigma", [2e-3])  # 2e-4 passed too (356 s); one level kept for CI's time
def test_coverage_eta_free_rocking(sigma):
    inside, errors = _coverage(jr.RigidModel(BLOCK, eta=0.9), jr.RigidModel(BLOCK, eta=0.8), "eta", 0.9, sigma)
    assert inside >= 45, (inside, errors)
    assert abs(np.mean(errors)) < 3 * np.std(errors) / np.sqrt(errors.size) + 1e-6  # no bias beyond the scatter


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_coverage_eta_pulse():
    t = np.arange(PULSE.t_start, PULSE.t_end + 4.0, 0.005)
    inside, errors = _coverage(jr.RigidModel(BLOCK, eta=0.88), jr.RigidModel(BLOCK, eta=0.95), "eta", 0.88, 5e-4, PULSE, t)
    assert inside >= 45, (inside, errors)


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("sigma", [1e-3])
def test_coverage_cbar(sigma):
    inside, errors = _coverage(jr.SpringModel(BLOCK, cbar=0.03, backbone="tanh"), jr.SpringModel(BLOCK, cbar=0.06, backbone="tanh"),
                               "cbar", 0.03, sigma)
    assert inside >= 45, (inside, errors)
