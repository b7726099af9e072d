"""Calibration of the spring model's damper, c̄ (paper section 3.4, eq. 17; figure 7), by gradient
descent through the simulator.

The SM loses energy continuously through its rotational damper ``c = c̄ m g^0.5 R′^1.5``; the RM
loses it at impacts, ``E/E₀ = r² = η′⁴`` per full free-rocking cycle (two impacts; SPEC, the
paper's missing eq. 13). The paper fitted c̄ by hand ("based on the data in Figure 7") as
``c̄ = 0.02 (α/0.1)²``. Here:

- `energy_ratio(model, θ₀/α)`: the SM's per-cycle ratio ``r_eq² = E(θ₁)/E(θ₀)`` of free rocking
  (θ̇(0) = 0, still ground) from θ₀ to the next peak θ₁ *on the same side* (θ₀ → opposite peak →
  θ₁). ``E`` is the model's own potential at zero velocity, `SpringModel.static_potential`
  (``My θs log cosh(θ/θs) − m g h (1 − cosθ)``, → SPEC's ``m g R (sinα|θ| − cosα(1 − cosθ))`` as
  θs → 0; at the default θs = 10⁻⁴α′ (`DEFAULT_SMOOTHING`) the two ratios differ by < 5·10⁻⁴, and only the model's own
  energy gives exactly r_eq² = 1 without damping).
  The peak is located exactly: a `diffrax.Event` on the base velocity, ``s θ̇`` crossing zero
  downwards (s = sign θ₀), gated to the same side (``s θ > 0``) and to times after half the rigid
  model's quarter period (so that the start, where θ̇ = 0, and the column's vibration there cannot
  trigger it; the opposite-side peak is an *upward* crossing of s θ̇ and is skipped), with a
  Newton root find on the solver's dense output. Since θ̇ = 0 at the peak, θ₁ is stationary in
  the event time and its derivative w.r.t. c̄ and α is that of the trajectory: reverse-mode
  `jax.grad` works, and everything `jax.vmap`s (over θ₀/α, c̄, α, columns).
- `calibrate_cbar(tan_alphas)`: one optax Adam optimisation of a batch of independent log c̄
  (one per α; log keeps c̄ > 0) minimising, for each α, the mean over a fixed set of angles
  θ₀/α ∈ [0.5, 0.95] of ``(r_eq²(θ₀/α; α, c̄) − η′⁴)²``. See its docstring for the stopping rule.
- `fit_power_law`: least squares of ``log c̄ = log k + n log(α/0.1)`` with standard errors.
- `jaxrock.reports.calibration_report(out_dir)` runs these and writes the table (CSV), figure 7
  and the calibration plot (PNG); what the CLI command ``jaxrock calibrate`` prints.

Findings (default quasi-rigid SM with added masses, θs = 10⁻⁴ α, angles 0.5, 0.6, …, 0.9, 0.95):
the calibrated c̄ is 0.0203, 0.0881, 0.2192 at tanα = 0.1, 0.2, 0.3 against eq. 17's 0.0199,
0.0779, 0.1699 (+2 %, +13 %, +29 %); the power-law fit over tanα ∈ [0.05, 0.35] gives
k = 0.0208 ± 0.0004, n = 2.18 ± 0.02 rather than 0.02, 2. r_eq² depends on θ₀/α
(by 0.016 at tanα = 0.1 up to 0.06 at tanα = 0.3 between θ₀/α = 0.5 and 0.95), so no single c̄ matches the
target at every angle; the residual reported is the RMS over the angles. See `jaxrock.reports.calibration_report`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
import optimistix as optx
from jaxtyping import Array, Bool, Float, Int

from .. import interrupt
from .._validate import JaxrockInputError, check_range
from ..excitation import StillGround
from ..geometry import Block
from ..spring import DEFAULT_BACKBONE, DEFAULT_SMOOTHING, Column, SpringIntegrator, SpringModel, cbar_eq17

#: θ₀/α of the calibration (the paper: "for θ₀/α > 0.5"); 6 angles in [0.5, 0.95].
CALIBRATION_ANGLES: tuple[float, ...] = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95)


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
    """Explicit Tsit5 for the quasi-rigid SM, the ESDIRK `SpringIntegrator` for flexible columns."""
    return CALIBRATION_INTEGRATOR if model_or_family.column is None else FLEXIBLE_CALIBRATION_INTEGRATOR
#: Figure 7 of the paper.
FIG7_TAN_ALPHAS: tuple[float, ...] = (0.1, 0.2, 0.3)
FIG7_CBARS: tuple[float, ...] = (0.02, 0.08, 0.18)


_STILL = StillGround()


# ----------------------------------------------------------------------------------------------
# one free-rocking cycle
# ----------------------------------------------------------------------------------------------
class FreeCycle(eqx.Module):
    """One free-rocking cycle of a spring model from θ₀ (θ̇₀ = 0).

    - `theta0`, `theta1`: the start and the next same-side peak [rad] (θ₁ exact: event + root find);
    - `t_peak`: time of θ₁ [s] (≈ the free-rocking period at this amplitude);
    - `r2`: r_eq² = E(θ₁)/E(θ₀) (NaN if the peak was not found);
    - `found`: the same-side peak was reached before the time bound and the solve succeeded.
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
    """Free rocking of `model` from θ₀ = (θ₀/α′)·α′, θ̇ = 0, no excitation, to the next peak on the
    same side. A pure function of array leaves: `jax.vmap`/`jax.grad` accept it (w.r.t. c̄, α, …).

    `max_periods`: the solve stops at this many rigid-model free-rocking periods at the same
    amplitude (4 × the quarter time acosh(1/(1 − θ₀/α))/p′, + 4/p′); `found` is False if the peak
    was not reached by then (e.g. a heavily over-damped body that creeps to rest).
    """
    if not isinstance(model, SpringModel):
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
    sol = integrator.solve(
        mech,
        _STILL,
        y0,
        0.0,
        t1,
        event=event,
        saveat=diffrax.SaveAt(t1=True),
        dtmax=jnp.inf,
    )
    y1 = sol.ys[-1]
    theta1 = y1[0]
    t_peak = sol.ts[-1]
    found = (sol.result == diffrax.RESULTS.event_occurred) & jnp.all(sol.event_mask)
    e0 = mech.rigid_potential(theta0)
    e1 = mech.rigid_potential(theta1)
    r2 = jnp.where(found, e1 / e0, jnp.nan)
    return FreeCycle(theta0=theta0, theta1=theta1, t_peak=t_peak, r2=r2, found=found)


def energy_ratio(model: SpringModel, theta0_over_alpha, *, integrator: SpringIntegrator | None = None):
    """r_eq² = E(θ₁)/E(θ₀) of one free-rocking cycle of `model` from θ₀/α′ (θ̇₀ = 0, still ground).

    Differentiable w.r.t. the model's leaves (c̄, block geometry, column), vmappable over
    θ₀/α and over batches of models; NaN when the same-side peak is not reached (see `free_cycle`).
    For a grid over (α, c̄, θ₀/α) use `energy_ratio_grid`.
    """
    return free_cycle(model, theta0_over_alpha, integrator=integrator).r2


def rm_target(block: Block):
    """The rigid model's energy ratio per full free-rocking cycle: r² = η′⁴ (SPEC; η′ = η for a
    plain block, the base's η′ for an extended base)."""
    return block.eta_r**4


# ----------------------------------------------------------------------------------------------
# families of spring models indexed by (tanα, c̄)
# ----------------------------------------------------------------------------------------------
class SpringFamily(eqx.Module):
    """Spring models that differ only in slenderness and damper: `family(tan_alpha, cbar)`.

    Everything else is fixed: `height` (2h [m]; r_eq² of the quasi-rigid SM is size independent),
    `added_masses`, `tan_alpha_base` (None: plain block; else a fixed extended base tanα′, whose
    η′ is then the target), `column` (None: quasi-rigid one-DOF SM; or a `Column`), `backbone`
    (the spring's, `jaxrock.spring.base_spring`; the smooth tanh by default: gradients through the bilinear
    kink are not reliable, see `jaxrock.spring.DEFAULT_SMOOTHING`), `smoothing` (θs/α′), `zeta`,
    `n_elements`. Hashable by value, so compiled calibrations are reused.
    """

    height: float = 10.0
    added_masses: bool = eqx.field(static=True, default=True)
    tan_alpha_base: float | None = None
    column: Column | None = None
    backbone: str = eqx.field(static=True, default=DEFAULT_BACKBONE)
    smoothing: float = DEFAULT_SMOOTHING
    zeta: float = 0.01
    n_elements: int = eqx.field(static=True, default=10)

    def block(self, tan_alpha) -> Block:
        return Block.from_slenderness(self.height, tan_alpha, self.tan_alpha_base)

    def __call__(self, tan_alpha, cbar) -> SpringModel:
        return SpringModel(
            self.block(tan_alpha),
            self.column,
            added_masses=self.added_masses,
            cbar=cbar,
            backbone=self.backbone,
            smoothing=self.smoothing,
            zeta=self.zeta,
            n_elements=self.n_elements,
        )


def _r2(family, tan_alpha, cbar, x, integrator):
    return energy_ratio(family(tan_alpha, cbar), x, integrator=integrator)


@eqx.filter_jit
def _grid(family, tan_alphas, cbars, xs, integrator):
    f = lambda ta, c, x: _r2(family, ta, c, x, integrator)
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
    """r_eq² on the grid tanα × c̄ × θ₀/α, shape (n_α, n_c̄, n_θ) (one vmapped, compiled call)."""
    family = SpringFamily() if family is None else family
    integrator = default_integrator(family) if integrator is None else integrator
    ta = jnp.atleast_1d(jnp.asarray(tan_alphas, dtype=float))
    cb = jnp.atleast_1d(jnp.asarray(cbars, dtype=float))
    xs = jnp.atleast_1d(jnp.asarray(theta0_over_alpha, dtype=float))
    check_range("tan_alpha", ta, 0.0, 1.0, lo_open=True, hi_open=True)
    check_range("cbar", cb, 0.0, math.inf, hi_open=True)
    check_range("theta0_over_alpha", xs, 0.0, 1.0, lo_open=True, hi_open=True)
    return _grid(family, ta, cb, xs, integrator)


# ----------------------------------------------------------------------------------------------
# calibration by gradient descent (optax)
# ----------------------------------------------------------------------------------------------
@eqx.filter_jit
def _values_and_slopes(family, tan_alphas, log_c, xs, integrator):
    """r_eq² and ∂r_eq²/∂log c̄ for every (α, θ₀/α): shape (n_α, n_θ) each (reverse mode, vmapped)."""
    f = lambda ta, lc, x: _r2(family, ta, jnp.exp(lc), x, integrator)
    vg = jax.value_and_grad(f, argnums=1)
    vg = jax.vmap(vg, in_axes=(None, None, 0))
    vg = jax.vmap(vg, in_axes=(0, 0, None))
    return vg(tan_alphas, log_c, xs)


def rm_targets(family, tan_alphas):
    """The RM's per-cycle energy ratio η′⁴ at each tanα (`rm_target`) for the family's geometry."""
    return _targets(family, jnp.asarray(tan_alphas, dtype=float))


def warm_up(tan_alphas, theta0_over_alpha=CALIBRATION_ANGLES, family: "SpringFamily | None" = None):
    """Compile (and run once) `calibrate_cbar`'s per-iteration pass, to time compilation apart."""
    family = SpringFamily() if family is None else family
    ta = jnp.asarray(tan_alphas, dtype=float)
    jax.block_until_ready(_values_and_slopes(family, ta, jnp.zeros(ta.shape) + math.log(0.05),
                                             jnp.asarray(theta0_over_alpha, dtype=float), default_integrator(family)))


@eqx.filter_jit
def _targets(family, tan_alphas):
    return jax.vmap(lambda ta: rm_target(family.block(ta)))(tan_alphas)


class CalibrationResult(eqx.Module):
    """Calibrated dampers for a batch of slendernesses (arrays over α unless stated).

    - `tan_alpha`, `alpha` [rad] (α′ of the base for an extended base: `alpha` is the rocking α′);
    - `cbar`: calibrated c̄; `cbar_eq17`: eq. 17 at the same α′;
    - `target`: the RM's r² = η′⁴;
    - `theta0_over_alpha` (n_θ): the calibration angles; `r2` (n_α, n_θ): r_eq² there at `cbar`;
    - `residual`: RMS over the angles of r_eq² − target (what no single c̄ can remove: r_eq² varies
      with θ₀/α); `bias`: their mean;
    - `step`: the Gauss–Newton estimate of the remaining distance to the least-squares optimum,
      |Δ log c̄| (the stopping measure);
    - `iterations`: Adam iterations until this α met the stopping rule (or `max_iter`);
      `converged`: it met it; `loss_history` (n_iter, n_α).
    """

    tan_alpha: Float[Array, " a"]
    alpha: Float[Array, " a"]
    cbar: Float[Array, " a"]
    cbar_eq17: Float[Array, " a"]
    target: Float[Array, " a"]
    theta0_over_alpha: Float[Array, " k"]
    r2: Float[Array, "a k"]
    residual: Float[Array, " a"]
    bias: Float[Array, " a"]
    step: Float[Array, " a"]
    iterations: Int[Array, " a"]
    converged: Bool[Array, " a"]
    loss_history: Float[Array, "i a"]


def calibrate_cbar(
    tan_alphas,
    *,
    theta0_over_alpha=CALIBRATION_ANGLES,
    family: SpringFamily | None = None,
    integrator: SpringIntegrator | None = None,
    cbar0: float = 0.05,
    learning_rate: float = 0.1,
    decay: float = 0.97,
    max_iter: int = 300,
    xtol: float = 1e-5,
    progress: bool = False,
) -> CalibrationResult:
    """Calibrate c̄ for each tanα so that the SM's free-rocking r_eq² matches the RM's r² = η′⁴.

    Objective, for each α independently (a batch of independent scalars optimised at once):
    ``L(log c̄) = mean_k (r_eq²(θ₀ₖ/α; α, c̄) − η′⁴)²`` over the fixed angles `theta0_over_alpha`.
    Each iteration evaluates r_eq² and ∂r_eq²/∂log c̄ for all (α, θ₀ₖ) in one vmapped reverse-mode
    pass through the simulator (`_values_and_slopes`).

    Optimiser: `optax.adam` on log c̄ (b1 = 0.8, b2 = 0.9, learning rate `learning_rate`·`decay`^i).
    Start: c̄₀ = `cbar0` for every α, then one Gauss–Newton step computed from the same residuals
    and slopes (so that Adam starts at the right order of magnitude for every α; clipped to ±2 in
    log c̄).

    Stopping rule, per α: stop updating it once the Gauss–Newton distance to the least-squares
    optimum, ``|Σₖ eₖ gₖ / Σₖ gₖ²|`` (eₖ residuals, gₖ = ∂r_eq²/∂log c̄), is below `xtol`
    (default 1e-5: c̄ within 0.001 % of its optimum, i.e. r_eq² within ~1e-6); the run ends
    when every α has stopped, or after `max_iter` iterations (`converged` False for those that
    had not). Residual thresholds on r_eq² − η′⁴ itself cannot be used: r_eq² depends on θ₀/α,
    so the optimum residual is not zero (`residual` reports it).
    """
    family = SpringFamily() if family is None else family
    integrator = default_integrator(family) if integrator is None else integrator
    ta = jnp.atleast_1d(jnp.asarray(tan_alphas, dtype=float))
    check_range("tan_alpha", ta, 0.0, 1.0, lo_open=True, hi_open=True)
    xs = jnp.atleast_1d(jnp.asarray(theta0_over_alpha, dtype=float))
    check_range("theta0_over_alpha", xs, 0.0, 1.0, lo_open=True, hi_open=True)
    check_range("cbar0", cbar0, 0.0, math.inf, lo_open=True, hi_open=True)
    if max_iter < 1:
        raise JaxrockInputError(f"max_iter = {max_iter}: must be >= 1")

    target = _targets(family, ta)
    n_a = ta.shape[0]
    log_lo, log_hi = math.log(1e-5), math.log(5.0)
    log_c = jnp.asarray(np.full(n_a, math.log(cbar0)))  # strongly typed: one compilation
    opt = optax.adam(optax.exponential_decay(learning_rate, 1, decay), b1=0.8, b2=0.9)
    state = opt.init(log_c)
    done = np.zeros(n_a, bool)
    iters = np.full(n_a, max_iter, int)
    losses = []

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=max_iter, desc="calibrating c̄", unit="it")
    try:
        for it in range(max_iter + 1):
            interrupt.stop_point()
            r2, slope = _values_and_slopes(family, ta, log_c, xs, integrator)
            e = r2 - target[:, None]
            ok = jnp.all(jnp.isfinite(e), axis=1) & jnp.all(jnp.isfinite(slope), axis=1)
            e_ = jnp.where(jnp.isfinite(e), e, 0.0)
            s_ = jnp.where(jnp.isfinite(slope), slope, 0.0)
            step = jnp.sum(e_ * s_, axis=1) / jnp.maximum(jnp.sum(s_ * s_, axis=1), 1e-300)
            step = jnp.where(ok, step, jnp.inf)
            losses.append(np.asarray(jnp.mean(e**2, axis=1)))
            newly = (~done) & (np.abs(np.asarray(step)) < xtol)
            iters[newly] = it
            done |= newly
            if bar is not None:
                bar.set_postfix(step=f"{float(jnp.max(jnp.where(done, 0.0, jnp.abs(step)))):.1e}", left=int((~done).sum()))
            if done.all() or it == max_iter:
                break
            if it == 0:
                # Gauss–Newton start (see docstring); a NaN lane (peak not found) is pulled down.
                upd = jnp.where(ok, -jnp.clip(step, -2.0, 2.0), -1.0)
            else:
                grad = jnp.where(ok, jnp.mean(2 * e_ * s_, axis=1), -1.0)
                upd, state = opt.update(grad, state, log_c)
            upd = jnp.where(jnp.asarray(done), 0.0, upd)
            log_c = jnp.asarray(np.clip(np.asarray(log_c + upd), log_lo, log_hi))
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()

    blocks_alpha = jax.vmap(lambda t: family.block(t).alpha_r)(ta)
    return CalibrationResult(
        tan_alpha=ta,
        alpha=blocks_alpha,
        cbar=jnp.exp(log_c),
        cbar_eq17=cbar_eq17(blocks_alpha),
        target=target,
        theta0_over_alpha=xs,
        r2=r2,
        residual=jnp.sqrt(jnp.mean(e**2, axis=1)),
        bias=jnp.mean(e, axis=1),
        step=jnp.abs(step),
        iterations=jnp.asarray(iters),
        converged=jnp.asarray(done),
        loss_history=jnp.asarray(np.stack(losses)),
    )


# ----------------------------------------------------------------------------------------------
# power-law fit
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PowerLawFit:
    """c̄ = k (α/α_ref)^n fitted by least squares in log space.

    `k_se`, `n_se`: standard errors from the covariance s²(XᵀX)⁻¹ (s² = SSR/(N − 2)); `k_se` by the
    delta method (k·se(log k)). The calibrated points carry no noise: the errors measure how far
    the points are from a power law (lack of fit), not scatter. `rms_log` is the RMS residual in
    log c̄. The paper: k = 0.02, n = 2 (eq. 17).
    """

    k: float
    n: float
    k_se: float
    n_se: float
    cov: np.ndarray  # of (log k, n)
    rms_log: float
    alpha_ref: float = 0.1

    def __call__(self, alpha):
        return self.k * (np.asarray(alpha) / self.alpha_ref) ** self.n

    def __str__(self):
        return f"c̄ = ({self.k:.4f} ± {self.k_se:.4f}) (α/{self.alpha_ref:g})^({self.n:.3f} ± {self.n_se:.3f})"


def fit_power_law(alpha, cbar, alpha_ref: float = 0.1) -> PowerLawFit:
    """Least-squares fit of log c̄ = log k + n log(α/α_ref)."""
    a = np.asarray(alpha, dtype=float).ravel()
    c = np.asarray(cbar, dtype=float).ravel()
    keep = np.isfinite(a) & np.isfinite(c) & (a > 0) & (c > 0)
    a, c = a[keep], c[keep]
    if a.size < 3:
        raise JaxrockInputError(f"fit_power_law needs at least 3 valid points, got {a.size}")
    X = np.stack([np.ones_like(a), np.log(a / alpha_ref)], axis=1)
    yv = np.log(c)
    beta, *_ = np.linalg.lstsq(X, yv, rcond=None)
    res = yv - X @ beta
    dof = a.size - 2
    s2 = float(res @ res) / dof
    cov = s2 * np.linalg.inv(X.T @ X)
    k = float(np.exp(beta[0]))
    return PowerLawFit(
        k=k,
        n=float(beta[1]),
        k_se=k * math.sqrt(cov[0, 0]),
        n_se=math.sqrt(cov[1, 1]),
        cov=cov,
        rms_log=float(np.sqrt(np.mean(res**2))),
        alpha_ref=alpha_ref,
    )


__all__ = [
    "CALIBRATION_ANGLES",
    "CALIBRATION_INTEGRATOR",
    "FreeCycle",
    "free_cycle",
    "energy_ratio",
    "energy_ratio_grid",
    "rm_target",
    "SpringFamily",
    "CalibrationResult",
    "calibrate_cbar",
    "PowerLawFit",
    "fit_power_law",
    "rm_targets",
    "warm_up",
]
