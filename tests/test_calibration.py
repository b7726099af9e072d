"""Physics of the c̄ calibration (paper section 3.4, eq. 17, figure 7; SPEC "Energy loss and
calibration of c̄").

Compiled functions are shared: every grid below has the same shapes (one compilation of
`energy_ratio_grid`), and the calibrations use one (3 α × 6 angles) and one (3 α × 1 angle) shape.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock  # noqa: F401  (float64)
from jaxrock.analyses.calibration import CALIBRATION_ANGLES, calibrate_cbar, fit_power_law
from jaxrock.analyses.free_rocking import SpringFamily, energy_ratio, energy_ratio_grid, free_cycle, rm_target
from jaxrock.geometry import Block

TAN = (0.1, 0.2, 0.3)
CBARS = (0.0, 0.02, 0.08, 0.18)
XS = (0.3, 0.5, 0.7, 0.95)


@pytest.fixture(scope="module")
def grid():
    """r_eq² on tanα × c̄ × θ₀/α (quasi-rigid SM with added masses, as in figure 7)."""
    return np.asarray(energy_ratio_grid(TAN, CBARS, XS))


@pytest.fixture(scope="module")
def calibrated():
    """Calibration over the default angles θ₀/α = 0.5 … 0.95 at tanα = 0.1, 0.2, 0.3."""
    return calibrate_cbar(TAN)


def test_rm_targets_are_eta_to_the_fourth():
    """SPEC: tanα = 0.1 → r² = 0.9419; 0.2 → 0.7884; 0.3 → 0.5893 (two impacts, r² = η⁴)."""
    got = [float(rm_target(Block.from_slenderness(10.0, t))) for t in TAN]
    np.testing.assert_allclose(got, [0.9419, 0.7884, 0.5893], atol=5e-5)
    # extended base: the base's η′ governs (SPEC, section 5)
    blk = Block.from_slenderness(10.0, 0.1, tan_alpha_base=0.3)
    assert float(rm_target(blk)) == pytest.approx(float(blk.eta_r) ** 4)


def test_undamped_sm_loses_no_energy(grid):
    """c̄ = 0: the SM is conservative, the next same-side peak is θ₀ again (r_eq² = 1)."""
    np.testing.assert_allclose(grid[:, 0, :], 1.0, atol=1e-6)


def test_peak_is_the_same_side_peak():
    """θ₁ is on the starting side and one full cycle later (not the opposite-side peak); without
    damping θ₁ = θ₀ to the root-finder/solver tolerance."""
    fc = jax.jit(free_cycle)(SpringFamily()(0.2, 0.0), 0.7)
    assert bool(fc.found)
    assert float(fc.theta1) == pytest.approx(float(fc.theta0), rel=1e-7)
    # the period of the rigid model at this amplitude: 4 acosh(1/(1 − 0.7))/p; the SM's is close
    p = float(Block.from_slenderness(10.0, 0.2).p)
    t_rm = 4 * math.acosh(1 / 0.3) / p
    assert 0.9 * t_rm < float(fc.t_peak) < 1.1 * t_rm


def test_energy_ratio_decreases_with_cbar(grid):
    d = np.diff(grid, axis=1)  # along c̄ = 0, 0.02, 0.08, 0.18
    assert np.all(d < -1e-3)


def test_energy_ratio_depends_little_on_alpha(grid):
    """Paper (figure 7, a): for fixed c̄ and θ₀/α > 0.5, r_eq does not depend on α.
    Measured: over tanα = 0.1 … 0.3 r_eq² varies by at most 0.0046 (c̄ = 0.18, θ₀/α = 0.95),
    ≤ 5 % of the energy lost per cycle 1 − r_eq² (largest, 4.8 %, at c̄ = 0.02, θ₀/α = 0.95) — while changing c̄ from 0.08 to 0.18 moves it
    by ~0.16."""
    sel = grid[:, 1:, 1:]  # c̄ > 0, θ₀/α ≥ 0.5
    spread = sel.max(axis=0) - sel.min(axis=0)
    assert spread.max() < 0.006
    assert np.all(spread / (1 - sel.mean(axis=0)) < 0.05)
    # (b): above θ₀/α = 0.5 r_eq² depends on θ₀ only slightly: ≤ 0.07 between 0.5 and 0.95
    assert np.all(np.abs(grid[:, 1:, 1] - grid[:, 1:, 3]) < 0.07)


def test_gradient_matches_finite_differences():
    """d r_eq²/d c̄ and d r_eq²/d tanα by reverse mode through the solver, event and root find,
    against central differences (measured agreement: 3e-5 relative for c̄, 2e-4 for tanα)."""
    fam = SpringFamily()
    f = jax.jit(lambda ta, c: energy_ratio(fam(ta, c), 0.7))
    g = jax.jit(jax.grad(lambda ta, c: energy_ratio(fam(ta, c), 0.7), argnums=(0, 1)))
    ta, c = 0.2, 0.08
    dta, dc = g(ta, c)
    hc, ht = 1e-4, 3e-3  # r_eq² changes little with tanα: a smaller ht drowns in step-sequence noise (~1e-8)
    fd_c = (f(ta, c + hc) - f(ta, c - hc)) / (2 * hc)
    fd_t = (f(ta + ht, c) - f(ta - ht, c)) / (2 * ht)
    assert float(dc) == pytest.approx(float(fd_c), rel=1e-4)
    assert float(dc) < 0
    assert float(dta) == pytest.approx(float(fd_t), rel=2e-3)


def test_single_angle_calibration_reproduces_target():
    """Calibrated at one angle, c̄ reproduces r² = η⁴ there to 1e-4 (here ~1e-6); vmapped over α."""
    for x in (0.5, 0.95):
        res = calibrate_cbar(TAN, theta0_over_alpha=(x,))
        assert bool(jnp.all(res.converged))
        np.testing.assert_allclose(np.asarray(res.r2[:, 0]), np.asarray(res.target), atol=1e-4)


def test_calibration_is_a_least_squares_optimum(calibrated):
    """Over the 6 angles no single c̄ hits η⁴ everywhere (r_eq² varies with θ₀/α): the result is
    the least-squares optimum (Gauss–Newton distance < 1e-5 in log c̄), whose mean residual is
    within 1e-3 of the target, and re-evaluating r_eq² at the returned c̄ gives the stored r2."""
    res = calibrated
    assert bool(jnp.all(res.converged))
    assert np.all(np.asarray(res.step) < 1e-5)
    assert np.all(np.abs(np.asarray(res.bias)) < 1e-3)
    # the residual is the θ₀ spread, not optimisation error: the optimum is bracketed by the angles
    r2 = np.asarray(res.r2)
    tgt = np.asarray(res.target)[:, None]
    assert np.all((r2.min(axis=1) < tgt[:, 0]) & (r2.max(axis=1) > tgt[:, 0]))
    x0 = np.asarray(energy_ratio_grid(TAN[:1], [float(res.cbar[0])] * 4, list(CALIBRATION_ANGLES[:4])))[0, 0]
    np.testing.assert_allclose(x0, r2[0, :4], atol=1e-9)


def test_calibrated_cbar_against_eq17(calibrated):
    """Eq. 17 (0.0199, 0.0779, 0.1699) against the calibration over θ₀/α ∈ [0.5, 0.95].

    The paper's fit was by hand from figure 7, whose curves are drawn at c̄ = 0.02, 0.08, 0.18,
    i.e. at eq. 17 itself (α = 0.1, 0.2, 0.3); how far a hand fit may legitimately be off is set
    by r_eq²'s dependence on θ₀/α: calibrating at single angles θ₀/α = 0.95 … 0.5 gives c̄ in
    [0.0183, 0.0247], [0.0800, 0.1046], [0.1992, 0.2557] (see `test_single_angle_calibration…`).
    Measured: calibrated/eq. 17 = 1.02, 1.13, 1.29. Eq. 17 is inside the θ₀ band at tanα = 0.1,
    2.6 % below it at 0.2 and 15 % below it at 0.3: eq. 17 under-damps squat blocks (with its
    c̄ = 0.17 at tanα = 0.3 the SM keeps r_eq² = 0.64–0.69 instead of 0.589). Neither the
    spring smoothing (θs = 10⁻² α changes c̄ by < 2 %) nor the added masses (< 4 %) explain it;
    the quadratic law is too flat: the fitted exponent is n ≈ 2.2.
    """
    res = calibrated
    ratio = np.asarray(res.cbar) / np.asarray(res.cbar_eq17)
    np.testing.assert_allclose(np.asarray(res.cbar_eq17), [0.0199, 0.0779, 0.1699], atol=6e-5)
    assert abs(ratio[0] - 1) < 0.05  # slender: eq. 17 holds to the reading precision of fig. 7
    assert 1.05 < ratio[1] < 1.20
    assert 1.20 < ratio[2] < 1.40
    fit = fit_power_law(res.alpha, res.cbar)
    assert fit.k == pytest.approx(0.02, rel=0.05)  # the slender end matches eq. 17
    assert 2.1 < fit.n < 2.35 and fit.n_se < 0.05


def test_power_law_fit_recovers_exact_law():
    a = np.linspace(0.05, 0.35, 7)
    fit = fit_power_law(a, 0.02 * (a / 0.1) ** 2)
    assert fit.k == pytest.approx(0.02, rel=1e-12) and fit.n == pytest.approx(2.0, rel=1e-12)
    assert fit.n_se < 1e-10


@pytest.mark.slow
def test_report_writes_files(tmp_path):
    from jaxrock.reports import calibration_report

    rep = calibration_report(tmp_path, tan_alphas=[0.1, 0.2, 0.3], progress=False, fig7_theta0_over_alpha=XS)
    for p in rep.files.values():
        assert p.exists() and p.stat().st_size > 0
    assert len(rep.table) == 3
    assert "eq. 17" in rep.format_table() or "c̄ eq.17" in rep.format_table()


def test_energy_ratio_on_both_backbones_approaches_one_limit():
    """r_eq² of one free cycle (tanα = 0.2, c̄ of eq. 17) with the family's backbone: the bilinear
    spring at θy = 1e-5 α is 1.3e-6 (θ₀ = 0.5 α) and 1.8e-6 (0.9 α) from θy = 1e-6 α, first order;
    tanh at 1e-4 α (the default before) is 3.0e-5 and 2.8e-5 from it (measured). So the calibrated c̄ does
    not hang on the backbone."""
    r = lambda b, s, x: float(energy_ratio(SpringFamily(backbone=b, smoothing=s)(0.2, 0.0779), x))
    for x in (0.5, 0.9):
        sharp = r("bilinear", 1e-6, x)
        assert abs(r("bilinear", 1e-5, x) - sharp) < 1e-5
        assert abs(r("tanh", 1e-4, x) - sharp) < 1e-4
