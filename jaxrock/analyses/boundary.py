"""Overturning boundaries by gradient: where a family of scenes turns from surviving to overturning,
and how that place moves with a parameter.

A boundary itself (the `overturned` flag) has no derivative, but the run's peak does. Approaching an
overturning boundary from the surviving side, the margin m = 1 − max|θ|/α′ (`margin`) falls to 0 like
a power of the distance d to it, m ≈ C d^γ:

- γ = 1/2 for the rigid model: its overturning angle α′ is the unstable equilibrium, where the
  potential has a smooth maximum, so the motion ends ever closer to it and m ~ √(energy deficit);
- for the spring models the same, except very near the boundary: their smoothed spring moves the
  potential's maximum a little beyond α′ (to sin θ = tanα′), so m turns linear (γ = 1) within
  ~4e-4 of a_p/(g tanα′) of it (quasi-rigid SM, 10 m, tanα 0.2, ω_p/p 3).

So m² is close to linear in any parameter near a boundary:

- `find_boundary`: Newton's method on m² along one scalar parameter x (the step −m/(2m′)), m′ from
  one forward-mode pass (`jax.jvp`), safeguarded by the bracket [overturns, survives]: a step that
  leaves the bracket, or an overturned iterate (m = 0, no slope), bisects instead; a step shorter
  than half the tolerance steps just past the predicted boundary instead, which closes the bracket
  (Newton from the surviving side never crosses on its own). Measured to a 1e-6 bracket from
  [2, 4]: the rigid model 10 runs, the quasi-rigid SM 16 (where it is linear, Newton on m² halves
  the distance per step), bisection 21. A bracket with several boundaries (overturning is not
  monotone in a_p, nor in a record's scale) ends at one of them, as bisection would.
- `boundary_slope`: the implicit derivative of a boundary x*(p) in parameters p, −(∂m/∂p)/(∂m/∂x),
  both partials from one `jax.jacfwd` pass at a point just inside the surviving side (x* less a small
  step: the ratio, not either partial, has a limit on the boundary, whatever γ). It is traceable:
  `jax.vmap` it over boundary points (`notebooks/03_gradients.ipynb`, all ω_p/p of a spectrum's line
  in one batch).

The runs must be forward-mode differentiable in x and p: a model's
`default_integrator(autodiff="forward")` is its default's settings in forward mode (a bare
`SpringIntegrator(autodiff="forward")` has the class's looser defaults: another integrator, whose
boundary lies 3e-5 away on the quasi-rigid SM).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._validate import JaxrockInputError
from ..results import STATUS_NAMES, Solution, status_codes


def margin(solution: Solution):
    """m = 1 − max|θ|/α′: 0 when the run overturns, a power of the distance to an overturning
    boundary near it (module docstring)."""
    return 1.0 - solution.max_theta


class Boundary(eqx.Module):
    """The result of `find_boundary`: an overturning boundary along one parameter, bracketed.

    Attributes:
        value: the surviving end of the final bracket, the boundary to within `width` (in x's unit).
        overturning: the bracket's other end (the run there overturns).
        width: |value − overturning|.
        n_runs: simulations taken.
        iterates: the x of each simulation, in order.
        converged: the bracket is within `tol`.
        status: "ok", or the name of the first other status a run ended with (`STATUS_NAMES`; the
            search stops there, `converged` False).
    """

    value: float
    overturning: float
    width: float
    n_runs: int
    iterates: tuple[float, ...]
    converged: bool
    status: str


def find_boundary(run, overturns_at, survives_at, *, tol: float = 1e-4, max_runs: int = 60) -> Boundary:
    """The overturning boundary along the scalar parameter of `run`, by safeguarded Newton.

    Newton on a power of the margin m = 1 − max|θ|/α′ (`margin`), kept inside the bracket between
    `overturns_at` and `survives_at` (module docstring, `jaxrock.analyses.boundary`); either order
    of the two ends along x is fine. A run on a host loop: one simulation per iteration, not vmappable.

    Arguments:
        run (Callable[[float], Solution]): x ↦ the `Solution` of the scene at parameter x.
        overturns_at (float): a finite x at which the run overturns.
        survives_at (float): a finite x, other than `overturns_at`, at which the run survives.
        tol: the bracket width at which the search stops (absolute, in x), > 0; default 1e-4.
        max_runs: the most simulations; default 60.

    Returns:
        The bracketed boundary (`Boundary`).

    Raises:
        JaxrockInputError: when the ends are not two different finite values, `tol` ≤ 0, or
            `run(overturns_at)` does not overturn or `run(survives_at)` does not survive.

    Example:
        ```python
        import jaxrock
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        model = jaxrock.RigidModel(block)
        run = lambda a: jaxrock.simulate(model, jaxrock.RickerPulse(a * 9.81 * 0.2, 2 * float(block.p)))
        b = jaxrock.find_boundary(run, overturns_at=8.0, survives_at=1.0)
        b.value  # the boundary in a_p/(g tanα), to within b.width
        ```
    """
    if not (np.isfinite(overturns_at) and np.isfinite(survives_at)) or overturns_at == survives_at:
        raise JaxrockInputError(f"find_boundary: overturns_at = {overturns_at}, survives_at = {survives_at}; "
                                "valid: two different finite values")
    if not tol > 0:
        raise JaxrockInputError(f"find_boundary: tol = {tol}; valid: > 0")

    def margin_and_flags(x):
        sol = run(x)
        return margin(sol), (sol.overturned, status_codes(sol.status))

    # one simulation per iterate: m, m′ (forward mode) and the run's flags
    evaluate = jax.jit(lambda x: jax.jvp(margin_and_flags, (x,), (jnp.ones_like(x),), has_aux=True))
    _, _, (over, code) = evaluate(jnp.asarray(float(overturns_at)))
    if int(code) != 0 or not bool(over):
        raise JaxrockInputError(f"find_boundary: overturns_at = {overturns_at} does not overturn "
                                f"(status {STATUS_NAMES[int(code)]}); valid: a value whose run overturns")
    lo, hi = float(overturns_at), float(survives_at)  # lo: overturns, hi: survives (either order in x)
    x, iterates = hi, []
    while len(iterates) < max_runs:
        m, slope, (over, code) = evaluate(jnp.asarray(x))
        m, slope = float(m), float(slope)
        iterates.append(x)
        if int(code) != 0:
            return Boundary(hi, lo, abs(hi - lo), len(iterates), tuple(iterates), False, STATUS_NAMES[int(code)])
        if len(iterates) == 1 and bool(over):
            raise JaxrockInputError(f"find_boundary: survives_at = {survives_at} overturns; valid: a value whose run survives")
        if bool(over) or m <= 0.0:
            lo = x
        else:
            hi = x
        if abs(hi - lo) <= tol:
            break
        nxt = np.nan
        if m > 0.0 and slope != 0.0:
            nxt = x - 0.5 * m / slope  # Newton on m²: x − m/(2 m′)
            if abs(nxt - x) < 0.5 * tol:  # within reach: step just past the boundary to close the bracket
                nxt = x + np.sign(lo - hi) * 0.9 * tol
        inside = np.isfinite(nxt) and min(lo, hi) < nxt < max(lo, hi)
        x = nxt if inside else 0.5 * (lo + hi)
    return Boundary(hi, lo, abs(hi - lo), len(iterates), tuple(iterates), abs(hi - lo) <= tol, "ok")


def boundary_slope(run, x_star, params, step) -> tuple[Array, Array]:
    """The implicit derivative dx*/dp of an overturning boundary x*(p) in the parameters p.

    From the partials of `margin` at x* − `step`. The returned peak should be close to 1: where it is
    not, the boundary is a jump of the outcome (not a limit of surviving runs) and the slope means
    nothing. Traceable (`jax.vmap`).

    Arguments:
        run (Callable[[Array, Array], Solution]): (x, p) ↦ the `Solution` of the scene.
        x_star (float | Array): the boundary x* (e.g. `Boundary.value`).
        params (float | Array): the parameters p (a scalar or an array).
        step (float | Array): signed, so that x* − step survives (e.g. a bisection's last bracket:
            x* = `Boundary.overturning`, step = `Boundary.overturning − Boundary.value`).

    Returns:
        (dx*/dp, max|θ|/α′ at x* − step): the slope, shaped like `params`, and the peak.

    Example:
        ```python
        b = jaxrock.find_boundary(lambda a: run(a, p0), 8.0, 1.0)
        slope, peak = jaxrock.boundary_slope(run, b.overturning, p0, b.overturning - b.value)
        ```
    """
    x = jnp.asarray(x_star, dtype=float) - step

    def margin_and_peak(y, q):
        sol = run(y, q)
        return margin(sol), sol.max_theta

    (d_x, d_p), peak = jax.jacfwd(margin_and_peak, argnums=(0, 1), has_aux=True)(x, jnp.asarray(params, dtype=float))
    return -d_p / d_x, peak
