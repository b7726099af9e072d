"""Block geometry (`jaxrock.geometry`) against SPEC's closed forms, and the scene vocabulary's
ratios (`jaxrock.scene`): a_p/(g tanα′) and ω_p/p′ to and from the physical pulse."""

import math

import jax
import numpy as np
import pytest

import jaxrock as jr
from helpers import G, spec_extended


@pytest.mark.parametrize("height,tan_a", [(10.0, 0.2), (2.0, 0.05), (50.0, 0.1), (0.5, 0.6)])
def test_plain_block_closed_forms(height, tan_a):
    """R = √(h² + b²), α = atan(b/h), p = √(3g/(4R)), η = 1 − 1.5 sin²α (eq. 3), uplift at g tanα
    (eq. 26); without a base the rocking quantities are the column's."""
    blk = jr.Block.from_slenderness(height, tan_a)
    h, b = height / 2, height / 2 * tan_a
    R, alpha = math.hypot(h, b), math.atan(tan_a)
    np.testing.assert_allclose([float(blk.R), float(blk.alpha), float(blk.p), float(blk.eta)],
                               [R, alpha, math.sqrt(3 * G / (4 * R)), 1 - 1.5 * math.sin(alpha) ** 2], rtol=1e-14)
    np.testing.assert_allclose([float(blk.alpha_r), float(blk.p_r), float(blk.eta_r)], [float(blk.alpha), float(blk.p), float(blk.eta)],
                               rtol=1e-14)
    assert float(blk.uplift_acceleration) == pytest.approx(G * tan_a, rel=1e-14)
    same = jr.Block.from_size(height, 2 * b)
    np.testing.assert_allclose([float(same.p_r), float(same.eta_r)], [float(blk.p_r), float(blk.eta_r)], rtol=1e-14)


def test_extended_base_geometry_follows_spec():
    blk = jr.Block.from_slenderness(20.0, 0.1, 0.3)
    a, p, e = spec_extended(20.0, 0.1, 0.3)
    np.testing.assert_allclose([float(blk.alpha_r), float(blk.p_r), float(blk.eta_r)], [a, p, e], rtol=1e-14)
    # the paper's first-order inertia (eq. 24) gives eq. 25: p′² = p² 4cosα/(3cosα + cosα′)
    paper = jr.Block.from_slenderness(20.0, 0.1, 0.3, exact_inertia=False)
    al, alb = math.atan(0.1), math.atan(0.3)
    p_25 = float(blk.p) * math.sqrt(4 * math.cos(al) / (3 * math.cos(al) + math.cos(alb)))
    np.testing.assert_allclose(float(paper.p_r), p_25, rtol=1e-14)
    assert abs(float(paper.p_r) / float(blk.p_r) - 1) > 1e-3  # the difference is visible at tanα′ = 0.3


def test_rocking_quantities_do_not_depend_on_size():
    """α′ and η′ are functions of the slenderness alone; p′ scales as 1/√(size) (SPEC "Spectra"):
    why a spectrum in (ω_p/p′, a_p/(g tanα′)) depends on α′ only."""
    small, large = jr.Block.from_slenderness(2.0, 0.15, 0.25), jr.Block.from_slenderness(32.0, 0.15, 0.25)
    assert float(small.alpha_r) == pytest.approx(float(large.alpha_r), rel=1e-14)
    assert float(small.eta_r) == pytest.approx(float(large.eta_r), rel=1e-14)
    assert float(small.p_r) / float(large.p_r) == pytest.approx(4.0, rel=1e-14)


def test_ratios_round_trip_and_mean_what_they_say():
    """`pulse_of_ratios` gives a_p = ratio·g·tanα′ and ω_p = ratio·p′; `ratios_of_pulse` inverts it,
    on arrays and under vmap over blocks."""
    blk = jr.Block.from_slenderness(10.0, 0.2, 0.3)
    a_p, w_p = jr.pulse_of_ratios(blk, 4.0, 2.5)
    assert float(a_p) == pytest.approx(4.0 * G * 0.3, rel=1e-14)
    assert float(w_p) == pytest.approx(2.5 * float(blk.p_r), rel=1e-15)
    ar, wr = np.linspace(0.5, 10, 7), np.linspace(1, 15, 7)
    back = jr.ratios_of_pulse(blk, *jr.pulse_of_ratios(blk, ar, wr))
    np.testing.assert_allclose(np.asarray(back[0]), ar, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(back[1]), wr, rtol=1e-15)
    blocks = jax.vmap(jr.Block.from_slenderness)(np.array([5.0, 10.0, 20.0]), np.array([0.1, 0.2, 0.3]))
    a_each, _ = jax.vmap(lambda b: jr.pulse_of_ratios(b, 2.0, 1.0))(blocks)
    np.testing.assert_allclose(np.asarray(a_each), 2.0 * G * np.array([0.1, 0.2, 0.3]), rtol=1e-14)
