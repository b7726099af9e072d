"""Overturning boundaries by gradient (`jaxrock.analyses.boundary`) against bisection and central
differences: the RM of a 10 m block, tanα = 0.2, under symmetric Ricker pulses."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr

BLOCK = jr.Block.from_slenderness(10.0, 0.2)
FORWARD = jr.RigidModel(BLOCK).default_integrator(autodiff="forward")
A_GRID = np.arange(1.0, 8.0 + 1e-9, 0.5)
BISECTIONS = 20


def rigid(a_ratio, w_ratio, eta=None, tan_alpha_base=None):
    block = BLOCK if tan_alpha_base is None else jr.Block.from_slenderness(10.0, 0.2, tan_alpha_base)
    a_p, omega_p = jr.pulse_of_ratios(BLOCK, a_ratio, w_ratio)  # the pulse in the plain block's units
    return jr.simulate(jr.RigidModel(block, eta=eta), jr.RickerPulse(a_p, omega_p), integrator=FORWARD)


def bisected_line(w_ratios, eta=None):
    """The overturning line, bisected `BISECTIONS` times from the grid `A_GRID`."""
    s = jr.overturning_spectrum(jr.RigidModel(BLOCK, eta=eta), w_ratios, A_GRID, refine=BISECTIONS, progress=False)
    assert s.ok
    return s.overturn_line


def test_find_boundary_agrees_with_bisection():
    """Newton on the margin along a_p/(g tanα) at ω_p/p = 3 ends within its tolerance of the bisected
    line, on its surviving side, in fewer runs than bisection takes to the same width (measured: 11
    runs against bisection's 21; the line 2.695641, Newton's bracket [2.6956403, 2.6956412])."""
    line = float(bisected_line([3.0])[0])
    tol = 1e-6
    b = jr.find_boundary(lambda x: rigid(x, 3.0), overturns_at=4.0, survives_at=2.0, tol=tol)
    assert b.converged and b.status == "ok" and b.width <= tol
    assert b.value < line <= b.overturning + 0.5 * 2.0**-BISECTIONS, (b.value, line)
    assert not bool(rigid(b.value, 3.0).overturned) and bool(rigid(b.overturning, 3.0).overturned)
    assert b.n_runs <= 12 < np.log2(2.0 / tol), (b.n_runs, b.iterates)


def test_find_boundary_quasi_rigid_spring_model():
    """The same search on the quasi-rigid SM (its default's settings in forward mode): Newton's
    bracket holds the bisected line (measured 8e-7 from its surviving end), in 16 runs where
    bisection takes 21. (Before grazing overturns were flagged, runs with max_theta = 1 and not
    overturned put the bisected line 4e-6 away from the margin's zero.)"""
    model = jr.SpringModel(BLOCK)
    forward = model.default_integrator(autodiff="forward")

    def run(x):
        return jr.simulate(model, jr.RickerPulse(*jr.pulse_of_ratios(BLOCK, x, 3.0)), integrator=forward)

    line = float(jr.overturning_spectrum(model, [3.0], A_GRID, refine=BISECTIONS, progress=False).overturn_line[0])
    b = jr.find_boundary(run, overturns_at=4.0, survives_at=2.0, tol=1e-6)
    assert b.converged and b.value < line <= b.overturning + 0.5 * 2.0**-BISECTIONS and b.n_runs <= 18, (b.value, line, b.n_runs)


def test_find_boundary_least_base_width():
    """The least extended base (tanα′ = b′/h) that survives a pulse, the other way along x (survives
    above): Newton agrees with a plain bisection of the same run to its tolerance (measured: 0.294016
    in 6 runs, where bisection takes 15 to 1e-5)."""
    run = lambda tb: rigid(4.0, 3.0, tan_alpha_base=tb)
    b = jr.find_boundary(run, overturns_at=0.2, survives_at=0.4, tol=1e-5)
    f = jax.jit(lambda tb: run(tb).overturned)
    lo, hi = 0.2, 0.4
    for _ in range(20):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if bool(f(mid)) else (lo, mid)
    assert b.converged and abs(b.value - hi) <= 1e-5 + (0.4 - 0.2) * 2.0**-20, (b.value, hi)
    assert b.value > 0.2 and b.n_runs <= 9, b.n_runs


def test_boundary_slope_against_central_differences():
    """dа*/dη of the overturning line by implicit differentiation through the simulation, against
    central differences (η ± 0.002) of the bisected line: measured relative differences 7e-5
    (ω_p/p = 2) and 7e-5 (4.5); the peak just inside the line is within 1e-3 of 1."""
    w = np.array([2.0, 4.5])
    eta0 = float(BLOCK.eta)
    line = bisected_line(w)
    step = (A_GRID[1] - A_GRID[0]) * 2.0**-BISECTIONS
    slope, peak = jax.vmap(lambda a, w_: jr.boundary_slope(lambda x, e: rigid(x, w_, eta=e), a, eta0, step))(
        jnp.asarray(line), jnp.asarray(w))
    fd = (bisected_line(w, eta0 + 0.002) - bisected_line(w, eta0 - 0.002)) / 0.004
    assert np.all(np.asarray(peak) > 0.999), peak
    np.testing.assert_allclose(np.asarray(slope), fd, rtol=1e-3)
    assert np.all(np.asarray(slope) < 0)  # less impact loss (η up): overturns at a smaller a_p


def test_find_boundary_refuses_a_bad_bracket():
    run = lambda x: rigid(x, 3.0)
    with pytest.raises(jr.JaxrockInputError, match="overturns_at = 2.0 does not overturn"):
        jr.find_boundary(run, overturns_at=2.0, survives_at=1.5)
    with pytest.raises(jr.JaxrockInputError, match="survives_at = 5.0 overturns"):
        jr.find_boundary(run, overturns_at=4.0, survives_at=5.0)
    with pytest.raises(jr.JaxrockInputError, match="two different finite values"):
        jr.find_boundary(run, overturns_at=4.0, survives_at=4.0)
