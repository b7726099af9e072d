"""Calibration of the spring model's damper, c̄ (paper section 3.4, eq. 17; figure 7), by gradient
descent through the simulator.

The SM loses energy continuously through its rotational damper ``c = c̄ m g^0.5 R′^1.5``; the RM
loses it at impacts, ``E/E₀ = r² = η′⁴`` per full free-rocking cycle (two impacts; SPEC, the
paper's missing eq. 13). The paper fitted c̄ by hand ("based on the data in Figure 7") as
``c̄ = 0.02 (α/0.1)²``. Here:

- `jaxrock.analyses.free_rocking`: the SM's per-cycle ratio ``r_eq² = E(θ₁)/E(θ₀)`` of free
  rocking (`energy_ratio`) and families of models over (tanα, c̄) (`SpringFamily`).
- `calibrate_cbar(tan_alphas)`: one optax Adam optimisation of a batch of independent log c̄
  (one per α; log keeps c̄ > 0) minimising, for each α, the mean over a fixed set of angles
  θ₀/α ∈ [0.5, 0.95] of ``(r_eq²(θ₀/α; α, c̄) − η′⁴)²``. See its docstring for the stopping rule.
- `fit_power_law`: least squares of ``log c̄ = log k + n log(α/0.1)`` with standard errors.
- `jaxrock.reports.calibration_report(out_dir)` runs these and writes the table (CSV), figure 7
  and the calibration plot (PNG); what the CLI command ``jaxrock calibrate`` prints.

r_eq² depends on θ₀/α, so no single c̄ matches the target at every angle; the residual reported
is the RMS over the angles. What the calibration finds against eq. 17 is in docs/guide/spectra.md
("Reproducing the paper"), as `jaxrock calibrate` measures it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
from jaxtyping import Array, Bool, Float, Int

from .. import interrupt
from .._validate import JaxrockInputError, check_range
from ..spring import SpringIntegrator, cbar_eq17
from .free_rocking import SpringFamily, default_integrator, rm_target

#: θ₀/α of the calibration (the paper: "for θ₀/α > 0.5"); 6 angles in [0.5, 0.95].
CALIBRATION_ANGLES: tuple[float, ...] = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95)


# ----------------------------------------------------------------------------------------------
# calibration by gradient descent (optax)
# ----------------------------------------------------------------------------------------------
@eqx.filter_jit
def _values_and_slopes(family, tan_alphas, log_c, xs, integrator):
    """r_eq² and ∂r_eq²/∂log c̄ for every (α, θ₀/α): shape (n_α, n_θ) each (reverse mode, vmapped)."""
    f = lambda ta, lc, x: family.energy_ratio(ta, jnp.exp(lc), x, integrator)
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
    """Calibrated dampers for a batch of slendernesses: the result of `calibrate_cbar`.

    Arrays over α (n_α) unless stated.

    Attributes:
        tan_alpha: the slendernesses tanα [–].
        alpha: the rocking α′ [rad] (α′ of the base for an extended base).
        cbar: the calibrated c̄ [–].
        cbar_eq17: eq. 17 at the same α′ [–].
        target: the RM's r² = η′⁴ [–].
        theta0_over_alpha: the calibration angles θ₀/α [–] (n_θ).
        r2: r_eq² at the calibration angles at `cbar` [–] (n_α, n_θ).
        residual: RMS over the angles of r_eq² − target (what no single c̄ can remove: r_eq² varies
            with θ₀/α).
        bias: the mean over the angles of r_eq² − target.
        step: the Gauss–Newton estimate of the remaining distance to the least-squares optimum,
            |Δ log c̄| (the stopping measure).
        iterations: Adam iterations until this α met the stopping rule (or `max_iter`).
        converged: whether this α met the stopping rule.
        loss_history: the mean squared residual per iteration (n_iter, n_α).
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

    Arguments:
        tan_alphas (float | ArrayLike): the slendernesses tanα [–], each in (0, 1).
        theta0_over_alpha (Sequence[float] | ArrayLike): the initial angles θ₀/α [–], each in (0, 1);
            default `CALIBRATION_ANGLES` (0.5, 0.6, 0.7, 0.8, 0.9, 0.95).
        family: the spring models calibrated (`SpringFamily`: height, base, column, backbone, ...);
            default None: `SpringFamily()`, the quasi-rigid one-DOF model.
        integrator: the integrator; default None: the calibration's (explicit Tsit5 for the
            quasi-rigid model, the ESDIRK `SpringIntegrator` for flexible columns).
        cbar0: the starting c̄ for every α, > 0; default 0.05.
        learning_rate: Adam's initial learning rate; default 0.1.
        decay: the learning rate's decay per iteration; default 0.97.
        max_iter: the most iterations, ≥ 1; default 300.
        xtol: the stopping rule's Gauss–Newton distance |Δ log c̄|; default 1e-5.
        progress: show a progress bar; default False.

    Returns:
        The calibrated c̄ per α, with its residuals and convergence (`CalibrationResult`).

    Raises:
        JaxrockInputError: when a tanα or θ₀/α is outside (0, 1), `cbar0` ≤ 0, or `max_iter` < 1.

    Example:
        ```python
        import jaxrock
        res = jaxrock.calibrate_cbar([0.1, 0.2, 0.3])
        res.cbar, res.cbar_eq17  # calibrated against the paper's eq. 17
        fit = jaxrock.fit_power_law(res.alpha, res.cbar)
        ```
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
    """Fit the power law c̄ = k (α/α_ref)^n to calibrated dampers by least squares in log space.

    log c̄ = log k + n log(α/α_ref); points with a non-finite or non-positive α or c̄ are left out.
    The paper's eq. 17 is k = 0.02, n = 2.

    Arguments:
        alpha (ArrayLike): the slenderness angles α [rad] (e.g. `CalibrationResult.alpha`).
        cbar (ArrayLike): the damper coefficients c̄ [–], one per α.
        alpha_ref: the reference angle α_ref [rad]; default 0.1.

    Returns:
        The fit (`PowerLawFit`: `k`, `n`, their standard errors `k_se`, `n_se`, the covariance `cov`
            of (log k, n), the RMS residual `rms_log` in log c̄; callable as α ↦ c̄).

    Raises:
        JaxrockInputError: when fewer than 3 valid points remain.

    Example:
        ```python
        fit = jaxrock.fit_power_law([0.1, 0.2, 0.3], [0.02, 0.08, 0.18])
        print(fit)  # c̄ = (0.0200 ± ...) (α/0.1)^(2.000 ± ...)
        ```
    """
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


__all__ = ["CALIBRATION_ANGLES", "CalibrationResult", "calibrate_cbar", "PowerLawFit", "fit_power_law", "rm_targets", "warm_up"]
