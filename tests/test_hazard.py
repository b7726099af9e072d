"""Hazard integration (`jaxrock.analyses.hazard`): closed forms, the definition by scipy's quad,
the bootstrap broadcast, the deaggregation, the Poisson probability and the CSV reader."""

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ndtr

from jaxrock._validate import JaxrockInputError
from jaxrock.analyses.hazard import (
    HazardCurve,
    deaggregation,
    mean_annual_frequency,
    probability_in_years,
)
from jaxrock.geometry import G

K0 = 2e-3


def closed_form(theta, beta, k, k0=K0):
    return k0 * theta ** -k * np.exp(0.5 * k * k * beta * beta)


@pytest.mark.parametrize("k", [1.0, 1.7, 2.5, 3.2, 4.0])
def test_power_law_closed_form(k):
    theta, beta = np.meshgrid(np.geomspace(0.1, 30.0, 6), np.linspace(0.1, 1.0, 7))
    num = mean_annual_frequency(theta, beta, HazardCurve.power_law(K0, k))
    assert num.shape == theta.shape
    np.testing.assert_allclose(num, closed_form(theta, beta, k), rtol=1e-8, atol=0)


def test_points_of_a_power_law_reproduce_the_closed_form():
    im = np.geomspace(0.5, 20.0, 9)
    h = HazardCurve.from_points(im, K0 * im ** -2.3)
    np.testing.assert_allclose(h.rate([0.1, 1.0, 7.0, 100.0]), K0 * np.array([0.1, 1.0, 7.0, 100.0]) ** -2.3, rtol=1e-12)
    theta, beta = np.meshgrid([0.3, 2.0, 15.0], [0.1, 0.5, 1.0])
    np.testing.assert_allclose(mean_annual_frequency(theta, beta, h), closed_form(theta, beta, 2.3), rtol=1e-8)


def test_piecewise_curve_against_quad_of_the_definition():
    im = np.array([0.5, 1.0, 1.5, 2.5, 4.0, 6.0, 8.0, 10.0, 14.0, 20.0])
    h = HazardCurve.from_points(im, 0.1 * im ** -2.0 * np.exp(-0.08 * im))
    # λ_DS = ∫ P(DS|x) |dλ/dx| dx, |dλ/dx| by a central difference of the log-log interpolation
    dlam = lambda x: (h.rate(x * (1 - 1e-6)) - h.rate(x * (1 + 1e-6))) / (2e-6 * x)
    for theta, beta in [(0.4, 0.3), (2.0, 0.6), (5.0, 0.05), (12.0, 1.0)]:
        f = lambda x, theta=theta, beta=beta: ndtr(math.log(x / theta) / beta) * dlam(x)
        edges = [0.0, *im, np.inf]  # the kinks as interval ends
        ref = sum(quad(f, a, c, epsabs=0, epsrel=1e-12, limit=200)[0] for a, c in itertools.pairwise(edges))
        assert mean_annual_frequency(theta, beta, h) == pytest.approx(ref, rel=1e-6)


def test_bootstrap_broadcast_equals_the_loop_and_nan_passes():
    rng = np.random.default_rng(0)
    median, beta = rng.lognormal(1.0, 0.3, 500), rng.uniform(0.1, 1.0, 500)
    median[7] = np.nan
    h = HazardCurve.from_points([0.5, 1.0, 3.0, 9.0], [1e-2, 3e-3, 2e-4, 1e-5])
    all_at_once = mean_annual_frequency(median, beta, h)
    loop = np.array([mean_annual_frequency(m, b, h) for m, b in zip(median, beta)])
    np.testing.assert_allclose(all_at_once, loop, rtol=1e-14)
    assert np.isnan(all_at_once[7]) and np.isfinite(np.delete(all_at_once, 7)).all()


def test_deaggregation_integrates_to_the_maf():
    h = HazardCurve.from_points([0.5, 1.0, 3.0, 9.0], [1e-2, 3e-3, 2e-4, 1e-5])
    u = np.linspace(np.log(3.0) - 12.0, np.log(3.0) + 8.0, 200001)  # ln x
    x = np.exp(u)
    maf = mean_annual_frequency(3.0, 0.5, h)
    assert np.trapezoid(deaggregation(x, 3.0, 0.5, h) * x, u) == pytest.approx(maf, rel=1e-6)  # over x
    assert np.trapezoid(deaggregation(x, 3.0, 0.5, h, normalise=True), u) == pytest.approx(1.0, rel=1e-6)  # over ln x
    d = deaggregation(x[:, None], np.array([2.0, 3.0]), 0.5, h)
    assert d.shape == (x.size, 2) and (d >= 0).all()


def test_poisson_probability():
    assert probability_in_years(1 / 475, 50) == pytest.approx(1 - math.exp(-50 / 475), rel=1e-14)
    assert probability_in_years(1 / 475, 50) == pytest.approx(0.0999, abs=1e-4)
    assert np.isnan(probability_in_years(np.nan, 50))
    with pytest.raises(JaxrockInputError, match="years"):
        probability_in_years(1e-3, 0)


def test_small_beta_tends_to_the_rate_at_the_median():
    h = HazardCurve.from_points([0.5, 1.0, 3.0, 9.0], [1e-2, 3e-3, 2e-4, 1e-5])
    for theta in [0.7, 2.0, 5.0]:
        assert mean_annual_frequency(theta, 1e-3, h) == pytest.approx(float(h.rate(theta)), rel=1e-4)


def test_slope_density_is_minus_the_derivative():
    h = HazardCurve.from_points([0.5, 1.0, 3.0, 9.0], [1e-2, 3e-3, 2e-4, 1e-5])
    x = np.array([0.2, 0.7, 2.0, 5.0, 20.0])
    fd = (h.rate(x * (1 - 1e-7)) - h.rate(x * (1 + 1e-7))) / (2e-7 * x)
    np.testing.assert_allclose(h.slope_density(x), fd, rtol=1e-6)


def test_read_csv(tmp_path):
    p = tmp_path / "hazard.csv"
    p.write_text("# site A, PSHA 2024\nPGA [g], rate [1/yr]\n0.1, 1e-2\n\n0.2,2e-3  # a comment\n0.4 3e-4\n")
    h = HazardCurve.read(p)
    np.testing.assert_allclose(h.im, np.array([0.1, 0.2, 0.4]) * G, rtol=1e-14)
    np.testing.assert_allclose(h.rates, [1e-2, 2e-3, 3e-4], rtol=1e-14)
    p.write_text("im,rate\n1.0,1e-2\n2.0,1e-3\n")  # no unit: as given
    np.testing.assert_allclose(HazardCurve.parse(str(p)).im, [1.0, 2.0], rtol=1e-14)
    p.write_text("1.0,1e-2\n2.0,1e-3\n")  # no header
    np.testing.assert_allclose(HazardCurve.read(p).rates, [1e-2, 1e-3], rtol=1e-14)


def test_read_csv_refusals(tmp_path):
    p = tmp_path / "hazard.csv"
    p.write_text("im,rate\n1.0,1e-2\n2.0,abc\n")
    with pytest.raises(JaxrockInputError, match=r"hazard\.csv: line 3"):
        HazardCurve.read(p)
    p.write_text("# no header\n1.0,abc\n2.0,1e-3\n")  # a first line with a number is data, not a header
    with pytest.raises(JaxrockInputError, match="line 2"):
        HazardCurve.read(p)
    p.write_text("1.0,1e-2\n2.0,1e-3,5\n")
    with pytest.raises(JaxrockInputError, match="line 2"):
        HazardCurve.read(p)
    p.write_text("1.0,1e-2\n3.0,1e-3\n2.0,1e-4\n")
    with pytest.raises(JaxrockInputError, match="strictly increasing"):
        HazardCurve.read(p)
    p.write_text("1.0,1e-3\n2.0,1e-2\n")
    with pytest.raises(JaxrockInputError, match="strictly decreasing"):
        HazardCurve.read(p)
    with pytest.raises(JaxrockInputError, match="cannot be read"):
        HazardCurve.read(tmp_path / "missing.csv")


def test_parse_and_input_refusals():
    h = HazardCurve.parse("power:1e-3,2.5")
    assert float(h.rate(2.0)) == pytest.approx(1e-3 * 2.0 ** -2.5, rel=1e-14)
    for bad in ["power:1e-3", "power:a,b"]:
        with pytest.raises(JaxrockInputError, match="power:k0,k"):
            HazardCurve.parse(bad)
    with pytest.raises(JaxrockInputError, match="k ="):
        HazardCurve.power_law(1e-3, -1.0)
    with pytest.raises(JaxrockInputError, match="at least 2"):
        HazardCurve.from_points([1.0], [1e-3])
    with pytest.raises(JaxrockInputError, match="beta"):
        mean_annual_frequency(1.0, 0.0, h)
    with pytest.raises(JaxrockInputError, match="median"):
        mean_annual_frequency(-1.0, 0.3, h)
    with pytest.raises(JaxrockInputError, match="HazardCurve"):
        mean_annual_frequency(1.0, 0.3, "power:1e-3,2.5")
    with pytest.raises(JaxrockInputError, match="x ="):
        h.rate(0.0)
