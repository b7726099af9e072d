"""Free rocking of the spring model: the energy ratio per cycle r_eq² the damper c̄ is calibrated on
(paper section 3.4, figure 7).

The SM loses energy continuously through its rotational damper ``c = c̄ m g^0.5 R′^1.5``; the RM
loses it at impacts, ``E/E₀ = r² = η′⁴`` per full free-rocking cycle (two impacts; SPEC, the
paper's missing eq. 13, `rm_target`).

- `energy_ratio(model, θ₀/α)`: the SM's per-cycle ratio ``r_eq² = E(θ₁)/E(θ₀)`` of free rocking
  (θ̇(0) = 0, still ground) from θ₀ to the next peak θ₁ *on the same side* (θ₀ → opposite peak →
  θ₁). ``E`` is the model's own potential at zero velocity, `SpringModel.static_potential`
  (the spring's potential − m g h (1 − cosθ), e.g. ``My θs log cosh(θ/θs)`` for tanh, → SPEC's
  ``m g R (sinα|θ| − cosα(1 − cosθ))`` as θs → 0; at θs ≤ 10⁻⁴α′ the two ratios differ by
  < 5·10⁻⁴, and only the model's own energy gives exactly r_eq² = 1 without damping). On the
  bilinear backbone (the quasi-rigid default) the solve stops on its kinks
  (`SpringIntegrator.solve_through`), so ∂r_eq²/∂c̄ is the motion's.
  The peak is located exactly: a `diffrax.Event` on the base velocity, ``s θ̇`` crossing zero
  downwards (s = sign θ₀), gated to the same side (``s θ > 0``) and to times after half the rigid
  model's quarter period (so that the start, where θ̇ = 0, and the column's vibration there cannot
  trigger it; the opposite-side peak is an *upward* crossing of s θ̇ and is skipped), with a
  Newton root find on the solver's dense output. Since θ̇ = 0 at the peak, θ₁ is stationary in
  the event time and its derivative w.r.t. c̄ and α is that of the trajectory: reverse-mode
  `jax.grad` works, and everything `jax.vmap`s (over θ₀/α, c̄, α, columns).
- `SpringFamily`: spring models that differ only in slenderness and damper; `energy_ratio_grid`
  over (tanα, c̄, θ₀/α) in one vmapped, compiled call.
"""

from __future__ import annotations

import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array, Bool, Float

from .._validate import JaxrockInputError, check_range
from ..excitation import StillGround
from ..geometry import Block
from ..spring import AbstractSpringModel, Column, SpringIntegrator, SpringModel


#: Tolerances of the free-rocking solves: r_eq² to ~1e-8, so that finite differences and the
#: 1e-4 calibration target are far above the integration error. Quasi-rigid SM: explicit Tsit5;
#: flexible columns: the spring model's own L-stable solver (`default_integrator`).
# explicit Tsit5 for the one-DOF model: its only stiff part, the spring's pre-yield branch
# (θs = 10⁻⁴ α: a short pre-yield period near θ = 0), is mild; measured 0.1 s vs 0.66 s per calibration
# iteration of 13 α × 6 angles on 2 CPU cores against the L-stable Kvaerno5.
CALIBRATION_INTEGRATOR = SpringIntegrator(rtol=1e-9, atol=1e-9, solver="tsit5")
# flexible: Kvaerno5 + Newton at 1e-7 (below ~1e-7 the stage round-off of a stiff column's
# accelerations exceeds the scaled velocity tolerance and the step control stalls, see SpringIntegrator)
FLEXIBLE_CALIBRATION_INTEGRATOR = SpringIntegrator(rtol=1e-7, atol=1e-7, solver="kvaerno5", max_steps=100_000)


def default_integrator(model_or_family):
    """The free-rocking solves' integrator: explicit Tsit5 for the quasi-rigid SM, the ESDIRK `SpringIntegrator` for columns.

    Arguments:
        model_or_family (AbstractSpringModel | SpringFamily): a spring model, or a family of them (flexible when its
            `column` is not None).

    Returns:
        (SpringIntegrator): `CALIBRATION_INTEGRATOR` (Tsit5, rtol = atol = 1e-9) for the quasi-rigid SM;
            `FLEXIBLE_CALIBRATION_INTEGRATOR` (Kvaerno5, rtol = atol = 1e-7) for a flexible column.
    """
    flexible = model_or_family.column is not None if isinstance(model_or_family, SpringFamily) else model_or_family.flexible
    return FLEXIBLE_CALIBRATION_INTEGRATOR if flexible else CALIBRATION_INTEGRATOR


#: Figure 7 of the paper.
FIG7_TAN_ALPHAS: tuple[float, ...] = (0.1, 0.2, 0.3)
FIG7_CBARS: tuple[float, ...] = (0.02, 0.08, 0.18)


_STILL = StillGround()


# ----------------------------------------------------------------------------------------------
# one free-rocking cycle
# ----------------------------------------------------------------------------------------------
class FreeCycle(eqx.Module):
    """One free-rocking cycle of a spring model from θ₀ (θ̇₀ = 0): the result of `free_cycle`.

    Attributes:
        theta0: the starting angle θ₀ [rad].
        theta1: the next peak on the same side θ₁ [rad] (exact: event + root find).
        t_peak: the time of θ₁ [s] (≈ the free-rocking period at this amplitude).
        r2: r_eq² = E(θ₁)/E(θ₀) [–] (NaN if the peak was not found).
        found: whether the same-side peak was reached before the time bound and the solve succeeded.
    """

    theta0: Float[Array, ""]
    theta1: Float[Array, ""]
    t_peak: Float[Array, ""]
    r2: Float[Array, ""]
    found: Bool[Array, ""]


def _quarter_time(x, p):
    """Rigid model's time from rest at θ₀ = xα to θ = 0: acosh(1/(1 − x))/p (small-α solution)."""
    x = jnp.clip(jnp.abs(x), 1e-6, 1 - 1e-9)
    return jnp.arccosh(1.0 / (1.0 - x)) / p


def free_cycle(
    model: SpringModel,
    theta0_over_alpha,
    *,
    integrator: SpringIntegrator | None = None,
    max_periods: float = 3.0,
) -> FreeCycle:
    """Free rocking of `model` from θ₀ = (θ₀/α′)·α′, θ̇ = 0, no excitation, to the next peak on the same side.

    A pure function of array leaves: `jax.vmap`/`jax.grad` accept it (w.r.t. c̄, α, …). The peak is
    located exactly: a `diffrax.Event` on the base velocity (s θ̇ crossing zero downwards, s = sign θ₀,
    gated to the same side and to times after half the rigid model's quarter period) with a Newton
    root find on the solver's dense output. Since θ̇ = 0 at the peak, θ₁ is stationary in the event
    time and its derivative w.r.t. c̄ and α is that of the trajectory.

    Arguments:
        model: the spring model (`QuasiRigidSpringModel` or `FlexibleSpringModel`, e.g. from `SpringModel`).
        theta0_over_alpha (float | ArrayLike): the initial angle θ₀/α′ [–], in (0, 1).
        integrator: the integrator; default None: `default_integrator(model)` (explicit Tsit5 for the
            quasi-rigid model, the ESDIRK `SpringIntegrator` for flexible columns).
        max_periods: the time bound, in rigid-model free-rocking periods at the same amplitude
            (4 × the quarter time acosh(1/(1 − θ₀/α))/p′, + 4/p′), > 0; default 3.0. `found` is False
            if the peak was not reached by then (e.g. a heavily over-damped body that creeps to rest).

    Returns:
        (FreeCycle): θ₀, θ₁, the time of θ₁, r_eq² = E(θ₁)/E(θ₀) and whether the peak was found.

    Raises:
        JaxrockInputError: when `model` is not a spring model or θ₀/α′ is outside (0, 1).

    Example:
        ```python
        import jaxrock
        from jaxrock.analyses.free_rocking import free_cycle
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(10.0, 0.2), cbar=0.08)
        cycle = free_cycle(model, 0.8)
        cycle.found, cycle.t_peak, cycle.r2  # True, ≈ 5.7 s, ≈ 0.797
        ```
    """
    if not isinstance(model, AbstractSpringModel):
        raise JaxrockInputError(f"model must be a SpringModel, got {type(model).__name__}")
    if integrator is None:
        integrator = default_integrator(model)
    check_range("theta0_over_alpha", theta0_over_alpha, 0.0, 1.0, lo_open=True, hi_open=True)
    mech = model.system()
    alpha = model.block.alpha_r
    x = jnp.asarray(theta0_over_alpha, dtype=float)
    theta0 = x * alpha
    y0 = mech.initial_state(theta0, 0.0)
    N = mech.ndof
    p = jax.lax.stop_gradient(mech.p_r)
    xq = jax.lax.stop_gradient(x)
    t_gate = 0.5 * _quarter_time(xq, p)
    t1 = max_periods * 4 * _quarter_time(xq, p) + 4.0 / p

    def same_side_peak(t, y, args, **kwargs):
        # s θ̇ crossing 0 downwards on the starting side, after the start (sign(0) at t = 0 and −1
        # outside the gate: no trigger); the opposite-side peak is an upward crossing.
        th, om = y[0], y[N]
        live = (th > 0) & (t > t_gate)
        return jnp.where(live, om, -1.0)

    root = optx.Newton(rtol=1e-12, atol=1e-12 / p)
    event = diffrax.Event(same_side_peak, root_finder=root, direction=False)
    t_peak, y1, result, event_mask = integrator.solve_through(mech, _STILL, y0, 0.0, t1, event, dtmax=jnp.inf)
    theta1 = y1[0]
    found = (result == diffrax.RESULTS.event_occurred) & jnp.all(jnp.stack(event_mask))  # one condition
    e0 = mech.rigid_potential(theta0)
    e1 = mech.rigid_potential(theta1)
    r2 = jnp.where(found, e1 / e0, jnp.nan)
    return FreeCycle(theta0=theta0, theta1=theta1, t_peak=t_peak, r2=r2, found=found)


def energy_ratio(model: SpringModel, theta0_over_alpha, *, integrator: SpringIntegrator | None = None):
    """Energy ratio r_eq² = E(θ₁)/E(θ₀) of one free-rocking cycle of a spring model (paper section 3.4, figure 7).

    Free rocking from θ₀/α′ (θ̇₀ = 0, still ground) to the next peak θ₁ on the same side
    (θ₀ → opposite peak → θ₁). E is the model's own potential at zero velocity
    (`SpringModel.static_potential`: the spring's potential − m g h (1 − cosθ), → the rigid model's
    m g R (sinα|θ| − cosα(1 − cosθ)) as θs → 0), so r_eq² = 1 exactly without damping. The damper c̄
    is calibrated so that r_eq² matches the rigid model's r² = η′⁴ (`rm_target`, SPEC's stand-in
    for the paper's missing eq. 13; the paper's fit is eq. 17).

    Differentiable w.r.t. the model's leaves (c̄, block geometry, column; reverse-mode `jax.grad`
    works), vmappable over θ₀/α and over batches of models; NaN when the same-side peak is not
    reached (see `free_cycle`). For a grid over (α, c̄, θ₀/α) use `energy_ratio_grid`.

    Arguments:
        model: the spring model (`QuasiRigidSpringModel` or `FlexibleSpringModel`, e.g. from `SpringModel`).
        theta0_over_alpha (float | ArrayLike): the initial angle θ₀/α′ [–], in (0, 1).
        integrator: the integrator; default None: `default_integrator(model)` (explicit Tsit5 at
            rtol = atol = 1e-9 for the quasi-rigid model, the ESDIRK `SpringIntegrator` for flexible columns).

    Returns:
        (Array): r_eq² [–], a scalar (NaN when the same-side peak is not reached).

    Raises:
        JaxrockInputError: when `model` is not a spring model or θ₀/α′ is outside (0, 1).

    Example:
        ```python
        import jax
        import jaxrock
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        model = jaxrock.SpringModel(block, cbar=0.08)
        jaxrock.energy_ratio(model, 0.8), jaxrock.rm_target(block)  # ≈ 0.797 vs η′⁴ ≈ 0.788
        jax.grad(lambda c: jaxrock.energy_ratio(jaxrock.SpringModel(block, cbar=c), 0.8))(0.08)  # ∂r_eq²/∂c̄ ≈ −2.05
        ```
    """
    return free_cycle(model, theta0_over_alpha, integrator=integrator).r2


def rm_target(block: Block):
    """The rigid model's energy ratio per full free-rocking cycle: r² = η′⁴, the target of the damper calibration.

    Two impacts per cycle, each keeping η′² of the energy (SPEC; the paper's missing eq. 13).
    η′ = η = 1 − 1.5 sin²α for a plain block, the base's η′ for an extended base (`Block.eta_r`).

    Arguments:
        block: the block (`Block`).

    Returns:
        (Array): r² = η′⁴ [–], a scalar.

    Example:
        ```python
        import jaxrock
        jaxrock.rm_target(jaxrock.Block.from_slenderness(10.0, 0.2))  # ≈ 0.788
        ```
    """
    return block.eta_r**4


# ----------------------------------------------------------------------------------------------
# families of spring models indexed by (tanα, c̄)
# ----------------------------------------------------------------------------------------------
class SpringFamily(eqx.Module):
    """Spring models that differ only in slenderness and damper: `family(tan_alpha, cbar)` is the model at (tanα, c̄).

    Everything else is fixed. Hashable by value, so compiled calibrations are reused.

    Attributes:
        height: the full height 2h [m]; default 10.0 (r_eq² of the quasi-rigid SM is size independent).
        added_masses: whether the added rotational inertia ΔI = I′o − (4/3) m h² is included (`SpringModel`); default True.
        tan_alpha_base: None (default): a plain block; else a fixed extended base tanα′, whose η′ is then the target.
        column: None (default): the quasi-rigid one-DOF SM; or a `Column` (flexible model).
        backbone: the spring's backbone (`jaxrock.spring.base_spring`); default None: the model's default (`SpringModel`).
        smoothing: θs/α′ of the backbone; default None: the backbone's default.
        zeta: the column's damping ratio ζ [–], ≥ 0 (flexible models only); default 0.01.
        n_elements: the number of column elements, an integer ≥ 1 (flexible models only); default 10.

    Example:
        ```python
        from jaxrock.analyses.free_rocking import SpringFamily
        family = SpringFamily()
        model = family(0.2, 0.08)  # the quasi-rigid SM of tanα = 0.2, c̄ = 0.08
        family.energy_ratio(0.2, 0.08, 0.8)  # ≈ 0.797
        ```
    """

    height: float = 10.0
    added_masses: bool = eqx.field(static=True, default=True)
    tan_alpha_base: float | None = None
    column: Column | None = None
    backbone: str | None = eqx.field(static=True, default=None)
    smoothing: float | None = None
    zeta: float = 0.01
    n_elements: int = eqx.field(static=True, default=10)

    def block(self, tan_alpha) -> Block:
        """The family's block at slenderness tanα.

        Arguments:
            tan_alpha (float | Array): the slenderness tanα [–], in [1e-3, 1).

        Returns:
            (Block): the block of height `height`, with the family's base (`tan_alpha_base`).
        """
        return Block.from_slenderness(self.height, tan_alpha, self.tan_alpha_base)

    def __call__(self, tan_alpha, cbar) -> AbstractSpringModel:
        column = {} if self.column is None else dict(zeta=self.zeta, n_elements=self.n_elements)
        return SpringModel(self.block(tan_alpha), self.column, added_masses=self.added_masses, cbar=cbar, backbone=self.backbone,
                           smoothing=self.smoothing, **column)

    def energy_ratio(self, tan_alpha, cbar, theta0_over_alpha, integrator: SpringIntegrator | None = None):
        """`energy_ratio` of the family's model at (tanα, c̄).

        Arguments:
            tan_alpha (float | Array): the slenderness tanα [–], in (0, 1).
            cbar (float | Array): the damper coefficient c̄ [–], ≥ 0.
            theta0_over_alpha (float | Array): the initial angle θ₀/α′ [–], in (0, 1).
            integrator: the integrator; default None: `default_integrator` of the model.

        Returns:
            (Array): r_eq² [–], a scalar (NaN when the same-side peak is not reached).
        """
        return energy_ratio(self(tan_alpha, cbar), theta0_over_alpha, integrator=integrator)


@eqx.filter_jit
def _grid(family, tan_alphas, cbars, xs, integrator):
    f = lambda ta, c, x: family.energy_ratio(ta, c, x, integrator)
    f = jax.vmap(f, in_axes=(None, None, 0))
    f = jax.vmap(f, in_axes=(None, 0, None))
    f = jax.vmap(f, in_axes=(0, None, None))
    return f(tan_alphas, cbars, xs)


def energy_ratio_grid(
    tan_alphas,
    cbars,
    theta0_over_alpha,
    *,
    family: SpringFamily | None = None,
    integrator: SpringIntegrator | None = None,
):
    """Energy ratio r_eq² of free rocking on the grid tanα × c̄ × θ₀/α, in one vmapped, compiled call (figure 7).

    Each point is `energy_ratio` of `family(tanα, c̄)` from θ₀/α′; the call is compiled once per
    family, integrator and grid shape. Figure 7 of the paper is the grid `FIG7_TAN_ALPHAS` ×
    `FIG7_CBARS` × θ₀/α.

    Arguments:
        tan_alphas (float | ArrayLike): the slendernesses tanα [–], each in (0, 1).
        cbars (float | ArrayLike): the damper coefficients c̄ [–], each ≥ 0.
        theta0_over_alpha (float | ArrayLike): the initial angles θ₀/α′ [–], each in (0, 1).
        family: the spring models (`SpringFamily`: height, base, column, backbone, ...);
            default None: `SpringFamily()`, the quasi-rigid one-DOF model of height 10 m.
        integrator: the integrator; default None: `default_integrator(family)` (explicit Tsit5 for the
            quasi-rigid model, the ESDIRK `SpringIntegrator` for flexible columns).

    Returns:
        (Array): r_eq² [–], shape (n_α, n_c̄, n_θ) (NaN where the same-side peak is not reached).

    Raises:
        JaxrockInputError: when a tanα or θ₀/α′ is outside (0, 1) or a c̄ is negative.

    Example:
        ```python
        import jaxrock
        from jaxrock.analyses.free_rocking import FIG7_CBARS, FIG7_TAN_ALPHAS
        r2 = jaxrock.energy_ratio_grid(FIG7_TAN_ALPHAS, FIG7_CBARS, [0.5, 0.7, 0.9])
        r2.shape  # (3, 3, 3)
        ```
    """
    family = SpringFamily() if family is None else family
    integrator = default_integrator(family) if integrator is None else integrator
    ta = jnp.atleast_1d(jnp.asarray(tan_alphas, dtype=float))
    cb = jnp.atleast_1d(jnp.asarray(cbars, dtype=float))
    xs = jnp.atleast_1d(jnp.asarray(theta0_over_alpha, dtype=float))
    check_range("tan_alpha", ta, 0.0, 1.0, lo_open=True, hi_open=True)
    check_range("cbar", cb, 0.0, math.inf, hi_open=True)
    check_range("theta0_over_alpha", xs, 0.0, 1.0, lo_open=True, hi_open=True)
    return _grid(family, ta, cb, xs, integrator)


__all__ = ["CALIBRATION_INTEGRATOR", "FIG7_TAN_ALPHAS", "FIG7_CBARS", "FreeCycle", "free_cycle", "energy_ratio", "energy_ratio_grid", "rm_target", "SpringFamily", "default_integrator"]
