"""Identification: a model's parameters (η, c̄, θs, the column's E and ζ, the block's size) fitted to a
measured rotation history θ(t) by gradient, with their uncertainty (issue 62).

A rocking history is a hard loss: after a few impacts a small change of η shifts every later
impact, and the least squares of θ(t) over a whole test has a minimum per phase alignment. Two
losses, and the default ("auto") uses both:

- **the whole history** (`loss="single"`): the model run once from the measurement's first state
  (a release at rest at the first sample, or rest under the ground motion) over every sample up to
  the last peak;
- **multiple shooting from the measured peaks** (`loss="multiple"`): the measurement cut at its
  peaks (the extremes of |θ| between two zero crossings, each refined by a parabola through its
  neighbours), where θ̇ = 0, so that the state there is the measured angle alone; each segment runs
  the model from one peak over the samples to the next, through one impact. No error builds up
  beyond one segment: its loss keeps one basin over a wide range of starting values.

In both, each start (angle and time) that comes from the measurement is fitted beside the
parameters (a noisy start angle otherwise biases η by several standard errors; a release time off
by a sample shifts the whole history). "auto" fits the whole history first and keeps it where it
leaves no more than the noise (1.5 × the level estimated from the samples' second differences);
else it fits the segments, then the whole history from their estimate, kept where it leaves no more
than the noise; else the segments' fit is the answer. `benchmarks/study_identify.py` measured the choice (docs/guide/identify.md).

The fit is optimistix's Levenberg–Marquardt on the parameters mapped to an unbounded space (log
for positive parameters, logit for those in an interval), the Jacobian in forward mode through the
simulator (`jax.jacfwd`: a few parameters). Spring models need a smooth backbone (`tanh`): across
a kink of the bilinear one the derivative of a history is not the motion's.

Uncertainty, both reported:

- **Laplace** (Gauss–Newton): cov = s² (JᵀJ)⁻¹ at the estimate, J = ∂r/∂(x, starts) in natural
  units, s² = SSR/(n − P), the starts marginalised. It assumes independent noise.
- **Bootstrap** (`n_boot` refits from the estimate): over the segments, resampled with replacement;
  with one segment (the whole history), over the residuals, resampled around the fit.

The reported 95 % `interval` is the hull of the two. A parameter the measurement does not
determine (a direction of JᵀJ below 10⁻¹² of its largest, or a standard error larger than half its
value: the spring's θs beside c̄, a stiff column's ζ) is flagged (`identifiable` False), warned
about, and gets its whole admissible range as interval; the others keep theirs.

`history(model, excitation, ts, start=...)` is the forward model: θ at the times `ts` from rest, or
from a state (t₀, θ₀, θ̇₀), for the rigid model (`RigidStepper` with a start) and the spring models
(one diffrax solve from the state).
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from typing import Callable, NamedTuple, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .. import interrupt
from .._validate import JaxrockInputError
from ..excitation import AbstractExcitation, StillGround
from ..model import AbstractModel, diffrax_status
from ..results import Save, Status
from ..rigid import RigidModel
from ..spring import AbstractSpringModel, SpringIntegrator

#: the losses `identify` offers (module docstring)
LOSSES = ("auto", "multiple", "single")


# ----------------------------------------------------------------------------------------------
# the parameters that can be freed
# ----------------------------------------------------------------------------------------------
class Free(NamedTuple):
    """A parameter `identify` can fit: how to read it from a model and write it back, and its range."""

    get: Callable[[AbstractModel], Array]
    set: Callable[[AbstractModel, Array], AbstractModel]
    lo: float
    hi: float
    label: str


def _field(where, lo, hi, label) -> Free:
    return Free(where, lambda m, v: eqx.tree_at(where, m, jnp.asarray(v, dtype=float)), lo, hi, label)


def _set_height(model, v):
    block = model.block
    k = v / (2 * block.h)
    return eqx.tree_at(lambda m: (m.block.h, m.block.b, m.block.b_base), model, (block.h * k, block.b * k, block.b_base * k))


#: name → `Free`: η (rigid), c̄ and θs/α′ (spring), ζ and E (flexible column), height 2h (every model; slenderness kept)
FREE: dict[str, Free] = {
    "eta": _field(lambda m: m.eta, 0.0, 1.0, "impact velocity ratio η [–]"),
    "cbar": _field(lambda m: m.cbar, 0.0, math.inf, "damper c̄ [–]"),
    "smoothing": _field(lambda m: m.smoothing, 0.0, 1.0, "spring θs/α′ [–]"),
    "zeta": _field(lambda m: m.zeta, 0.0, 1.0, "column damping ratio ζ [–]"),
    "E": _field(lambda m: m.column.E, 0.0, math.inf, "column Young's modulus E [Pa]"),
    "height": Free(lambda m: 2 * m.block.h, _set_height, 0.0, math.inf, "full height 2h [m]"),
}


def check_free(model: AbstractModel, free: Sequence[str]) -> tuple[str, ...]:
    """The names in `free`, checked against the model (each once, each a parameter the model has)."""
    free = tuple(free)
    if not free:
        raise JaxrockInputError(f"free: name at least one parameter to fit, one of {', '.join(FREE)}")
    for name in free:
        if name not in FREE:
            raise JaxrockInputError(f"free: {name!r} is not a parameter identify can fit; valid: {', '.join(FREE)}")
        try:
            value = FREE[name].get(model)
        except AttributeError:
            raise JaxrockInputError(f"free: the {type(model).__name__} has no {name!r} ({FREE[name].label})") from None
        if value is None:
            raise JaxrockInputError(f"free: the {type(model).__name__} has no {name!r} ({FREE[name].label})")
    if len(set(free)) != len(free):
        raise JaxrockInputError(f"free: {free} names a parameter twice")
    return free


def values_of(model: AbstractModel, free: Sequence[str]) -> Array:
    """The free parameters' values in `model`, in the order of `free`."""
    return jnp.stack([jnp.asarray(FREE[n].get(model), dtype=float) for n in free])


def with_values(model: AbstractModel, free: Sequence[str], x) -> AbstractModel:
    """`model` with the free parameters set to `x` (in the order of `free`)."""
    for i, n in enumerate(free):
        model = FREE[n].set(model, x[i])
    return model


def _to_open(x, lo, hi):
    """Natural value → unbounded (logit in an interval, log above 0)."""
    if math.isinf(hi):
        return jnp.log(x - lo)
    f = (x - lo) / (hi - lo)
    return jnp.log(f) - jnp.log1p(-f)


def _from_open(u, lo, hi):
    if math.isinf(hi):
        return lo + jnp.exp(u)
    return lo + (hi - lo) * jax.nn.sigmoid(u)


# ----------------------------------------------------------------------------------------------
# the forward model: θ(ts) from rest or from a state
# ----------------------------------------------------------------------------------------------
def _save(ts, fields=("theta",)) -> Save:
    """A `Save` at traced times (its constructor checks concrete ones)."""
    return eqx.tree_at(lambda s: s.ts, Save(np.arange(1.0, ts.shape[0] + 1.0), fields), ts)


def default_integrator(model: AbstractModel):
    """The forward-mode integrator of identification runs: the rigid model's `EventIntegrator`, or
    for spring models the free-rocking calibration's solver (Tsit5 at 1e-9 for the quasi-rigid,
    Kvaerno5 at 1e-7 for a column: `jaxrock.analyses.free_rocking.default_integrator`). The rigid
    one's steps are not placed on a record's samples (`on_samples=False`): diffrax's placement
    corrupts the derivatives after an apex, and the fits stopped where the wrong gradient vanished."""
    if isinstance(model, RigidModel):
        return dataclasses.replace(model.default_integrator(autodiff="forward"), on_samples=False)
    from .free_rocking import default_integrator as spring_default

    return dataclasses.replace(spring_default(model), autodiff="forward")


def history(model: AbstractModel, excitation: AbstractExcitation, ts, *, start=None, integrator=None, top: bool = False):
    """θ [rad] of `model` at the times `ts`, from rest at the excitation's start or from a state; with
    `top`, also the column top's horizontal displacement relative to the ground [m].

    A pure function: `jax.vmap` and forward-mode `jax.jacfwd` (w.r.t. the model's leaves and the
    start) accept it.

    Arguments:
        model: a `RigidModel` or a spring model.
        excitation: the ground motion (`StillGround()` for free rocking).
        ts (ArrayLike): the times [s], non-decreasing; before a `start` θ holds its θ₀ (a block held before its release).
        start (tuple | None): (t₀ [s], θ₀ [rad], θ̇₀ [rad/s]); default None: rest at the excitation's
            start. (t₀, 0, 0) is rest at t₀.
        integrator (object): default None: `default_integrator(model)` (forward mode).
        top: also return the top displacement u_top [m] at `ts`: 2h sinθ for the rigid and quasi-rigid
            bodies, the rotated and bent column's for a flexible one; default False.

    Returns:
        (Array, Status) or (Array, Array, Status): θ at `ts` [rad] (and u_top [m] with `top`), and the run's status.

    Example:
        ```python
        import numpy as np, jaxrock
        from jaxrock.analyses.identify import history
        block = jaxrock.Block.from_slenderness(2.0, 0.15)
        theta, status = history(jaxrock.RigidModel(block, eta=0.9), jaxrock.StillGround(), np.linspace(0, 4, 401),
                                start=(0.0, 0.8 * float(block.alpha), 0.0))
        ```
    """
    ts = jnp.asarray(ts, dtype=float)
    integrator = default_integrator(model) if integrator is None else integrator
    if isinstance(model, RigidModel):
        from ..rigid.event_integrator import RigidStepper

        start = None if start is None else tuple(jnp.asarray(v, dtype=float) for v in start)
        sol = RigidStepper(model, integrator, _save(ts), ts[-1], start).solve(excitation)
        theta = sol.history["theta"] if start is None else jnp.where(ts < start[0], start[1], sol.history["theta"])
        return (theta, 2 * model.block.h * jnp.sin(theta), sol.status) if top else (theta, sol.status)
    if not isinstance(model, AbstractSpringModel) or not isinstance(integrator, SpringIntegrator):
        raise JaxrockInputError(f"history: a RigidModel or a spring model with a SpringIntegrator, got {type(model).__name__}")
    import diffrax

    system = model.system()
    t0, theta0, theta_dot0 = (excitation.t_start, 0.0, 0.0) if start is None else start
    t0 = jnp.asarray(t0, dtype=float)
    save = (lambda t, y, args: jnp.stack([y[0], system.top_displacement(system.split(y)[0])])) if top else \
        (lambda t, y, args: y[0])
    # a sample before the start is saved at the start: the body held in its initial state
    sol = integrator.solve(system, excitation, system.initial_state(theta0, theta_dot0), t0, ts[-1],
                           saveat=diffrax.SaveAt(ts=jnp.maximum(ts, t0), fn=save))
    status = diffrax_status(sol.result)
    return (sol.ys[:, 0], sol.ys[:, 1], status) if top else (sol.ys, status)


# ----------------------------------------------------------------------------------------------
# the measurement and its segments
# ----------------------------------------------------------------------------------------------
class Measured(eqx.Module):
    """A measured rotation history, optionally the top displacement, and the ground motion they were measured under.

    Attributes:
        t: the sample times [s], strictly increasing.
        theta: the base rotation θ [rad] at `t` (NaN: a missing sample, left out).
        excitation: the ground motion (`StillGround()` for a free-rocking test; a `Record` or pulse).
        top: the column top's horizontal displacement relative to the ground u_top [m] at `t` (NaN: a
            missing sample), or None (default). A flexible column's bending (its E, its damping ζ) shows
            in it far more than in θ: 2h sinθ plus the column's deflection.
    """

    t: Float[Array, " n"]
    theta: Float[Array, " n"]
    excitation: AbstractExcitation
    top: Float[Array, " n"] | None

    def __init__(self, t, theta, excitation: AbstractExcitation | None = None, top=None):
        t = np.asarray(t, dtype=float)
        theta = np.asarray(theta, dtype=float)
        if t.ndim != 1 or t.shape != theta.shape or t.size < 8:
            raise JaxrockInputError(f"measured: t and theta must be 1-D of one length ≥ 8, got {t.shape} and {theta.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise JaxrockInputError("measured: t must be finite and strictly increasing [s]")
        if not np.any(np.isfinite(theta)):
            raise JaxrockInputError("measured: theta holds no finite sample")
        if top is not None:
            top = np.asarray(top, dtype=float)
            if top.shape != t.shape or not np.any(np.isfinite(top)):
                raise JaxrockInputError(f"measured: top must be 1-D of the length of t ({t.size}) with a finite sample, "
                                        f"got shape {top.shape}")
        self.t = jnp.asarray(t)
        self.theta = jnp.asarray(theta)
        self.excitation = StillGround() if excitation is None else excitation
        self.top = None if top is None else jnp.asarray(top)


class Segments(NamedTuple):
    """The measurement cut for multiple shooting (padded to a common length L).

    Attributes:
        t0, theta0: each segment's start (a measured peak, θ̇ = 0; θ₀ = 0: rest at t₀) [s], [rad] (K,).
        ts, theta: the samples each segment is compared with (K, L); padding repeats the last sample.
        mask: which of them are real (K, L).
        peaks_t, peaks_theta: every peak found (time [s], θ [rad]), in order.
        noise: the noise level estimated from the samples' second differences [rad].
        top, top_mask: the measured top displacement [m] on the samples, and which are real (K, L); None without one.
        top_noise: its noise level [m] (NaN without one).
    """

    t0: np.ndarray
    theta0: np.ndarray
    ts: np.ndarray
    theta: np.ndarray
    mask: np.ndarray
    peaks_t: np.ndarray
    peaks_theta: np.ndarray
    noise: float
    top: np.ndarray | None = None
    top_mask: np.ndarray | None = None
    top_noise: float = math.nan


def noise_level(theta, order: int = 2) -> float:
    """The standard deviation of white noise on a smooth signal, from its differences of `order` (MAD;
    the variance of white noise's k-th differences is C(2k, k) σ²). θ's second differences suffice; a top
    displacement's metres of motion against micrometres of noise need the fourth (a signal of ω dt ≪ 1
    shrinks by (ω dt)^k)."""
    d = np.diff(np.asarray(theta, dtype=float), order)
    d = d[np.isfinite(d)]
    return float(np.median(np.abs(d - np.median(d))) / 0.6745 / math.sqrt(math.comb(2 * order, order))) if d.size else 0.0


def find_peaks(t, theta, p: float, noise: float | None = None):
    """The rocking peaks of a measured θ(t): per lobe (a run of one sign beyond the noise), the extreme of
    |θ|, refined by a least-squares parabola through the samples within 0.15/p of it.

    Arguments:
        t, theta (ArrayLike): the samples.
        p: the block's frequency parameter p′ [1/s] (sets the parabola's width).
        noise: the noise level [rad]; default None: `noise_level(theta)`.

    Returns:
        (times, angles, first_is_start): the peaks [s], [rad]; whether the first peak is the
            measurement's first sample (a release).
    """
    t = np.asarray(t, dtype=float)
    th = np.asarray(theta, dtype=float)
    noise = noise_level(th) if noise is None else noise
    amp = np.nanmax(np.abs(th))
    thr = max(4.0 * noise, 0.01 * amp)
    sign = np.where(th > thr, 1, np.where(th < -thr, -1, 0))
    dt = float(np.median(np.diff(t)))
    w = max(2, int(round(0.15 / (p * dt))))
    times, angles, first_is_start = [], [], False
    i, n = 0, t.size
    while i < n:
        if sign[i] == 0:
            i += 1
            continue
        j = i
        while j < n and sign[j] != -sign[i]:
            j += 1
        lobe = np.arange(i, j)
        lobe = lobe[np.isfinite(th[lobe])]
        k = lobe[np.argmax(np.abs(th[lobe]))]
        cut = k >= n - 1 - w and j >= n  # the measurement ends before this lobe's peak is seen
        if np.abs(th[k]) >= max(10.0 * noise, 0.02 * amp) and not cut:
            if i == 0 and k <= w:  # the measurement starts at its peak: a release, θ̇ = 0 at t[0]
                near = lobe[lobe <= w]
                ok = np.isfinite(th[near])
                X = np.stack([np.ones(ok.sum()), (t[near][ok] - t[0]) ** 2], axis=1)
                times.append(t[0])
                angles.append(np.linalg.lstsq(X, th[near][ok], rcond=None)[0][0] if ok.sum() >= 3 else th[0])
                first_is_start = True
            else:
                near = lobe[np.abs(lobe - k) <= w]
                tc = t[near] - t[k]
                ok = np.isfinite(th[near])
                c2, c1, c0 = np.polyfit(tc[ok], th[near][ok], 2) if ok.sum() >= 3 and near.size >= 3 else (0.0, 0.0, th[k])
                tv = -c1 / (2 * c2) if c2 != 0 else 0.0
                if abs(tv) > w * dt:  # the parabola's vertex outside its samples: keep the sample
                    tv, c0, c1, c2 = 0.0, th[k], 0.0, 0.0
                times.append(t[k] + tv)
                angles.append(c0 + c1 * tv + c2 * tv * tv)
        # the next lobe starts where the sign turns
        while j < n and sign[j] == 0:
            j += 1
        i = j
    return np.asarray(times), np.asarray(angles), first_is_start


def segments(measured: Measured, p: float, loss: str = "multiple") -> Segments:
    """The measurement cut at its peaks (`loss="multiple"`) or in one piece (`"single"`)."""
    t = np.asarray(measured.t)
    th = np.asarray(measured.theta)
    noise = noise_level(th)
    pk_t, pk_th, first_is_start = find_peaks(t, th, p, noise)
    if pk_t.size < 2:
        raise JaxrockInputError(f"measured: {pk_t.size} rocking peak(s) above the noise ({noise:.2g} rad): "
                                "identification needs at least two (one impact)")
    amp = np.nanmax(np.abs(th))
    at_rest = abs(th[0]) < max(4.0 * noise, 0.01 * amp) and not first_is_start
    t_exc = float(measured.excitation.t_start)
    starts = []  # (t0, θ0, first sample index, end sample index)
    if at_rest:  # from rest at the excitation's start (or the first sample) to the first peak
        starts.append((min(t_exc, t[0]), 0.0, 0, int(np.searchsorted(t, pk_t[0]))))
    for k in range(pk_t.size - 1):
        i0 = int(np.searchsorted(t, pk_t[k], side="right" if not (k == 0 and first_is_start) else "left"))
        starts.append((pk_t[k], pk_th[k], i0, int(np.searchsorted(t, pk_t[k + 1]))))
    if loss == "single":
        t0, th0, i0 = starts[0][:3]
        starts = [(t0, th0, i0, starts[-1][3])]
    starts = [s for s in starts if s[3] > s[2]]
    # shapes padded (K segments to a multiple of 4, L samples of 64) so that measurements of similar sizes share one
    # compilation; a padding segment repeats the first one's start and holds no sample (the whole history: one, unpadded)
    L = -(-max(s[3] - s[2] for s in starts) // 64) * 64
    K = -(-len(starts) // 4) * 4 if loss != "single" else 1
    starts += [starts[0][:2] + (0, 0)] * (K - len(starts))
    ts = np.zeros((K, L))
    for k, (t0, th0, i0, i1) in enumerate(starts):
        ts[k, : i1 - i0] = t[i0:i1]
        ts[k, i1 - i0:] = t[i1 - 1] if i1 > i0 else t0

    def cut(x):  # a channel's samples on the segments (0 where missing or padding), and which are real
        out, real = np.zeros((K, L)), np.zeros((K, L), bool)
        for k, (_, _, i0, i1) in enumerate(starts):
            out[k, : i1 - i0], real[k, : i1 - i0] = x[i0:i1], np.isfinite(x[i0:i1])
        return np.where(real, out, 0.0), real

    thm, mask = cut(th)
    top, top_mask = (None, None) if measured.top is None else cut(np.asarray(measured.top))
    return Segments(np.asarray([s[0] for s in starts]), np.asarray([s[1] for s in starts]), ts, thm, mask, pk_t, pk_th, noise,
                    top, top_mask, math.nan if top is None else noise_level(measured.top, order=4))


# ----------------------------------------------------------------------------------------------
# the fit
# ----------------------------------------------------------------------------------------------
class _Problem(eqx.Module):
    """The residuals of a model with free parameters against the segments (one static structure)."""

    model: AbstractModel
    excitation: AbstractExcitation
    integrator: object
    free: tuple[str, ...] = eqx.field(static=True)
    lo: tuple[float, ...] = eqx.field(static=True)
    hi: tuple[float, ...] = eqx.field(static=True)
    t0: Array
    theta0: Array
    ts: Array
    theta: Array
    mask: Array
    at_peak: Array  # (K,) whether a segment starts at a measured peak (its start angle is fitted too)
    unit: Array  # the start angles' correction unit [rad] (α′)
    time_unit: Array  # the start times' correction unit [s] (1/p′)
    top: Array | None = None  # the measured top displacement (K, L) [m], or None
    top_mask: Array | None = None
    top_weight: Array | float = 1.0  # its residuals' weight: σ_θ/σ_u, so that both channels' residuals are in radians of θ noise

    def natural(self, u):
        """The free parameters (natural units) and the start angles' corrections (× `unit`) from the unbounded vector."""
        P = len(self.free)
        x = jnp.stack([_from_open(u[i], self.lo[i], self.hi[i]) for i in range(P)])
        return jnp.concatenate([x, u[P:]])

    def predict(self, z):
        """θ of the model with parameters z = (x, start-angle corrections [α′], start-time corrections [1/p′])
        over every segment (K, L), its top displacement (K, L; None where none is measured), and whether
        every run succeeded; a sample before its segment's start holds the start (a block held before its release)."""
        P, K = len(self.free), self.t0.shape[0]
        x, d_theta, d_t = z[:P], z[P:P + K], z[P + K:]
        model = with_values(self.model, self.free, x)
        theta0 = self.theta0 + jnp.where(self.at_peak, d_theta * self.unit, 0.0)
        t0 = self.t0 + jnp.where(self.at_peak, d_t * self.time_unit, 0.0)

        def one(t0, th0, ts):
            out = history(model, self.excitation, ts, start=(t0, th0, 0.0), integrator=self.integrator,
                          top=self.top is not None)
            return out[:-1], out[-1] == Status.ok

        run, ok = jax.vmap(one)(t0, theta0, self.ts)
        return run[0], (run[1] if self.top is not None else None), ok

    def residuals(self, z, weights):
        """The weighted residuals (K, L), or (K, 2L) with a top displacement, of the parameters z (`predict`)."""
        return self.residuals_of(*self.predict(z)[:2], weights)

    def residuals_of(self, theta, top, weights):
        """The weighted residuals of a predicted θ and top displacement (K, L each): zero at the padding;
        θ's (K, L), then the top's in θ's noise units beside them (K, 2L)."""
        r = jnp.where(self.mask, theta - self.theta, 0.0)
        if self.top is not None:
            r = jnp.concatenate([r, jnp.where(self.top_mask, top - self.top, 0.0) * self.top_weight], axis=1)
        return r * jnp.sqrt(weights)[:, None]


@eqx.filter_jit
def _solve(problem: _Problem, u0, weights, rtol, max_steps):
    """Levenberg–Marquardt from u0, then at the solution the residuals, their Jacobian in the natural
    parameters and the fitted θ (one compilation per structure and shape: the bootstrap's refits reuse it)."""
    fn = lambda u, w: problem.residuals(problem.natural(u), w)
    sol = optx.least_squares(fn, optx.LevenbergMarquardt(rtol=rtol, atol=rtol), u0, args=weights,
                             max_steps=max_steps, throw=False, options={"jac": "fwd"})

    def residuals_and_run(z):  # one forward pass gives the Jacobian, the residuals and the fitted θ (and top)
        theta, top, ok = problem.predict(z)
        r = problem.residuals_of(theta, top, weights)
        return r, (r, theta, top, ok)

    J, (r, theta, top, ok) = jax.jacfwd(residuals_and_run, has_aux=True)(problem.natural(sol.value))
    return sol.value, sol.result == optx.RESULTS.successful, sol.stats["num_steps"], r, J, theta, top, ok


@dataclasses.dataclass(frozen=True)
class Identification:
    """The result of `identify`: estimates, their uncertainty, the fitted model and what was fitted.

    Arrays over the free parameters (P) unless stated.

    Attributes:
        free: the parameters' names.
        estimate: the estimates (natural units).
        start: the values the fit started from.
        se: the Laplace (Gauss–Newton) standard errors.
        laplace_interval: estimate ± 1.96 se (P, 2).
        bootstrap_interval: the 2.5 and 97.5 % quantiles of the bootstrap estimates (P, 2); NaN without bootstrap.
        interval: the reported 95 % interval, the hull of the two (the parameter's range where not identifiable) (P, 2).
        correlation: the Laplace correlation matrix (P, P).
        bootstrap: the bootstrap estimates (B, P).
        identifiable: whether the measurement determines each parameter (module docstring).
        converged: whether the fit met its tolerance.
        iterations: the Levenberg–Marquardt steps.
        rms: the RMS residual [rad]; noise: the noise estimated from the samples [rad].
        loss: "multiple" or "single" (the one "auto" kept); n_segments, n_samples: what was fitted (θ and top samples).
        model: the model at the estimates.
        segments: the measurement's segments (`Segments`); fitted: θ of the fitted model on them (K, L).
        seconds: the wall time of the fit and of the bootstrap [s].
        fitted_top: the fitted model's top displacement on the segments (K, L) [m]; None where none was measured.
    """

    free: tuple[str, ...]
    estimate: np.ndarray
    start: np.ndarray
    se: np.ndarray
    laplace_interval: np.ndarray
    bootstrap_interval: np.ndarray
    interval: np.ndarray
    correlation: np.ndarray
    bootstrap: np.ndarray
    identifiable: np.ndarray
    converged: bool
    iterations: int
    rms: float
    noise: float
    loss: str
    n_segments: int
    n_samples: int
    model: AbstractModel
    segments: Segments
    fitted: np.ndarray
    seconds: tuple[float, float]
    fitted_top: np.ndarray | None = None

    def table(self) -> list[dict]:
        """One row per parameter: name, estimate, se, the intervals, identifiable."""
        return [dict(parameter=n, estimate=float(self.estimate[i]), se=float(self.se[i]),
                     lower=float(self.interval[i, 0]), upper=float(self.interval[i, 1]),
                     laplace_lower=float(self.laplace_interval[i, 0]), laplace_upper=float(self.laplace_interval[i, 1]),
                     bootstrap_lower=float(self.bootstrap_interval[i, 0]), bootstrap_upper=float(self.bootstrap_interval[i, 1]),
                     identifiable=bool(self.identifiable[i]))
                for i, n in enumerate(self.free)]

    def __str__(self):
        lines = [f"identification ({self.loss} shooting, {self.n_segments} segment(s), {self.n_samples} samples; "
                 f"RMS residual {self.rms:.3g} rad, noise {self.noise:.3g} rad; "
                 f"{'converged' if self.converged else 'NOT converged'} in {self.iterations} steps)"]
        for row in self.table():
            flag = "" if row["identifiable"] else "   NOT IDENTIFIABLE: the interval is its whole range"
            lines.append(f"  {row['parameter']:>9} = {row['estimate']:.6g} ± {row['se']:.2g}   "
                         f"95 % [{row['lower']:.6g}, {row['upper']:.6g}]{flag}")
        if len(self.free) > 1:
            lines.append("  correlation: " + "; ".join(f"{self.free[i]}–{self.free[j]} {self.correlation[i, j]:+.2f}"
                                                      for i in range(len(self.free)) for j in range(i + 1, len(self.free))))
        return "\n".join(lines)


def identify(
    measured: Measured,
    model: AbstractModel,
    free: Sequence[str] = ("eta",),
    *,
    loss: str = "auto",
    n_boot: int = 50,
    seed: int = 0,
    integrator=None,
    rtol: float = 1e-8,
    max_steps: int = 100,
    warn: bool = True,
) -> Identification:
    """Fit the parameters `free` of `model` to a measured rotation history (module docstring).

    Arguments:
        measured: the measurement (`Measured`: times, θ, the ground motion).
        model: the model, its free parameters at the fit's starting values and every other one known
            (`RigidModel`, `SpringModel`).
        free: the names to fit, from `FREE`: "eta" (rigid), "cbar", "smoothing" (spring), "zeta", "E"
            (flexible column), "height" (2h at fixed slenderness); default ("eta",).
        loss: "auto" (default: the whole history; where it leaves more than the noise, multiple shooting from
            the measured peaks and the whole history again from its estimate), "single" (the whole history from
            its first state) or "multiple" (the segments between the measured peaks).
        n_boot: bootstrap resamplings, ≥ 0 (0: the Laplace interval only); default 50.
        seed: the bootstrap's random seed; default 0.
        integrator (object): default None: `default_integrator(model)` (forward mode).
        rtol: Levenberg–Marquardt's tolerance on the parameters (relative, in the unbounded space);
            default 1e-8.
        max_steps: the most Levenberg–Marquardt steps; default 100.
        warn: warn when a parameter is not identifiable; default True.

    Returns:
        (Identification): the estimates with their intervals, the fitted model and history.

    Raises:
        JaxrockInputError: an unknown or absent parameter, a starting value outside its range, an
            unknown loss, or a measurement with fewer than two peaks.

    Example:
        ```python
        import numpy as np, jaxrock
        block = jaxrock.Block.from_slenderness(2.0, 0.15)
        t = np.arange(0.0, 5.0, 0.005)
        theta, _ = jaxrock.analyses.identify.history(jaxrock.RigidModel(block, eta=0.9), jaxrock.StillGround(), t,
                                                    start=(0.0, 0.8 * float(block.alpha), 0.0))
        noisy = np.asarray(theta) + np.random.default_rng(0).normal(0.0, 2e-4, t.size)
        fit = jaxrock.identify(jaxrock.Measured(t, noisy), jaxrock.RigidModel(block, eta=0.8), free=["eta"])
        print(fit)
        ```
    """
    if not isinstance(measured, Measured):
        raise JaxrockInputError(f"measured must be a jaxrock.Measured, got {type(measured).__name__}")
    if not isinstance(model, (RigidModel, AbstractSpringModel)):
        raise JaxrockInputError(f"model must be a RigidModel or a spring model, got {type(model).__name__}")
    if loss not in LOSSES:
        raise JaxrockInputError(f"loss = {loss!r}; valid: {', '.join(LOSSES)}")
    if n_boot < 0:
        raise JaxrockInputError(f"n_boot = {n_boot}: must be >= 0")
    if isinstance(model, AbstractSpringModel) and model.backbone.kinked:
        raise JaxrockInputError(f"model: the {type(model.backbone).__name__.lower()} backbone has kinks, across which a history's "
                                "derivative is not the motion's; identify a spring model with a smooth one: backbone='tanh'")
    free = check_free(model, free)
    lo = tuple(FREE[n].lo for n in free)
    hi = tuple(FREE[n].hi for n in free)
    x0 = np.asarray(values_of(model, free))
    for i, n in enumerate(free):
        if not lo[i] < x0[i] < hi[i]:
            raise JaxrockInputError(f"{n} = {x0[i]:g} to start from: must be in ({lo[i]:g}, {hi[i]:g})")
    integrator = default_integrator(model) if integrator is None else integrator
    fit = lambda loss, x, n: _fit(measured, model, free, loss, x, integrator, n, seed, rtol, max_steps)
    if loss != "auto":
        result = fit(loss, x0, n_boot)
    else:
        # the whole history first; where it ends in another minimum (it leaves more than the noise), the segments
        # from the measured peaks find the basin and the whole history is fitted again from their estimate
        result = fit("single", x0, n_boot)
        if not _fits(result):
            polished = fit("single", fit("multiple", x0, 0).estimate, n_boot)
            result = polished if _fits(polished) else fit("multiple", x0, n_boot)
    if warn and not result.identifiable.all():
        names = ", ".join(f for f, i in zip(free, result.identifiable) if not i)
        warnings.warn(f"identify: the measurement does not determine {names} (singular or flat loss): its interval is "
                      f"its whole range", stacklevel=2)
    return result


def _fits(result: "Identification") -> bool:
    """Whether a fit converged and leaves no more than the noise (`identify`'s "auto")."""
    return result.converged and result.rms <= 1.5 * result.noise


def _fit(measured, model, free, loss, x0, integrator, n_boot, seed, rtol, max_steps) -> Identification:
    """One fit with one loss, and its uncertainty (`identify`)."""
    lo = tuple(FREE[n].lo for n in free)
    hi = tuple(FREE[n].hi for n in free)
    seg = segments(measured, float(model.block.p_r), loss)
    real = seg.mask.any(axis=1)
    at_peak = (seg.theta0 != 0) & real
    with_top = seg.top is not None
    # the top's residuals weighted by σ_θ/σ_u (noise-free samples: 1/2h, the top's size per radian)
    top_weight = seg.noise / seg.top_noise if with_top and seg.noise > 0 and seg.top_noise > 0 else 0.5 / float(model.block.h)
    problem = _Problem(model, measured.excitation, integrator, free, lo, hi, jnp.asarray(seg.t0), jnp.asarray(seg.theta0),
                       jnp.asarray(seg.ts), jnp.asarray(seg.theta), jnp.asarray(seg.mask), jnp.asarray(at_peak),
                       jnp.asarray(model.block.alpha_r, dtype=float), 1.0 / jnp.asarray(model.block.p_r, dtype=float),
                       jnp.asarray(seg.top) if with_top else None, jnp.asarray(seg.top_mask) if with_top else None,
                       jnp.asarray(top_weight))
    mask = np.concatenate([seg.mask, seg.top_mask], axis=1) if with_top else seg.mask  # the residuals' (K, L or 2L)
    K = seg.t0.size
    P = len(free)
    x0 = np.clip(np.asarray(x0, dtype=float), np.asarray(lo) + 1e-9, np.asarray(hi) - 1e-9)
    u0 = jnp.concatenate([jnp.stack([_to_open(jnp.asarray(x0[i]), lo[i], hi[i]) for i in range(P)]), jnp.zeros(2 * K)])
    tic = time.perf_counter()
    u_hat, converged, steps, r, J, fitted, fitted_top, ok = _solve(problem, u0, jnp.ones(K), rtol, max_steps)
    x_hat = problem.natural(u_hat)[:P]
    r, J = np.asarray(r).reshape(-1), np.asarray(J).reshape(r.size, -1)
    J = J[:, np.r_[np.arange(P), P + np.flatnonzero(at_peak), P + K + np.flatnonzero(at_peak)]]  # a start from rest has none
    seconds_fit = time.perf_counter() - tic

    n = int(mask.sum())
    ssr = float(r @ r)
    s2 = ssr / max(n - J.shape[1], 1)
    x = np.asarray(x_hat)
    scale = np.r_[np.where(np.abs(x) > 0, np.abs(x), 1.0), np.ones(J.shape[1] - P)]
    Js = (J.T @ J) * np.outer(scale, scale)  # in relative units: comparable across parameters
    finite = bool(np.all(np.isfinite(Js)))
    eig = np.linalg.eigvalsh(Js) if finite else np.zeros(1)
    # the free parameters' block of the inverse: their covariance with the start angles marginalised; a direction
    # the data do not see (eigenvalue ≤ 1e-12 of the largest) is regularised at that level, so that the parameters
    # in it get a huge variance (flagged below) and the others keep theirs
    ridge = 1e-12 * max(eig.max(), 1e-300) * np.eye(Js.shape[0])
    cov = s2 * (np.linalg.inv(Js + ridge) * np.outer(scale, scale))[:P, :P] if finite else np.full((P, P), np.inf)
    se = np.sqrt(np.abs(np.diag(cov)))
    scale = scale[:P]
    identifiable = np.isfinite(se) & (se / scale < 0.5)
    singular = not identifiable.all()
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    laplace = np.stack([x - 1.96 * se, x + 1.96 * se], axis=1)

    tic = time.perf_counter()
    boot = np.full((0, P), np.nan)
    boot_int = np.full((P, 2), np.nan)
    if n_boot > 0 and not singular:
        rng = np.random.default_rng(seed)
        idx = np.flatnonzero(real)
        L = seg.mask.shape[1]
        res = np.asarray(r).reshape(K, -1)[:, :L][seg.mask]
        res_top = np.asarray(r).reshape(K, -1)[:, L:][seg.top_mask] / top_weight if with_top else None
        u_b, ok_b = [], []
        for _ in range(n_boot):  # each refit reuses the fit's compilation
            interrupt.stop_point()
            w, data = np.zeros(K), problem
            if idx.size > 1:  # segments resampled with replacement: integer weights
                w[idx] = np.bincount(rng.integers(0, idx.size, idx.size), minlength=idx.size)
            else:  # one segment: its residuals resampled around the fit (a noise bootstrap)
                w[idx] = 1.0
                noise = rng.choice(res, size=seg.mask.shape)
                data = eqx.tree_at(lambda p: p.theta, problem, jnp.where(problem.mask, jnp.asarray(fitted) - noise, 0.0))
                if with_top:
                    noise = rng.choice(res_top, size=seg.mask.shape)
                    data = eqx.tree_at(lambda p: p.top, data, jnp.where(problem.top_mask, jnp.asarray(fitted_top) - noise, 0.0))
            out = _solve(data, u_hat, jnp.asarray(w), rtol, max_steps)
            u_b.append(out[0])
            ok_b.append(bool(out[1]))
        u_b, ok_b = jnp.stack(u_b), np.asarray(ok_b)
        xb = np.asarray(jax.vmap(problem.natural)(u_b))[:, :P]
        boot = xb[np.asarray(ok_b)]
        if boot.shape[0] >= 10:
            boot_int = np.quantile(boot, [0.025, 0.975], axis=0).T
    seconds_boot = time.perf_counter() - tic

    interval = np.stack([np.fmin(laplace[:, 0], boot_int[:, 0]), np.fmax(laplace[:, 1], boot_int[:, 1])], axis=1)
    interval = np.clip(interval, np.asarray(lo), np.asarray(hi))
    interval = np.where(identifiable[:, None], interval, np.stack([np.asarray(lo), np.asarray(hi)], axis=1))
    return Identification(
        free=free, estimate=x, start=np.asarray(x0), se=se, laplace_interval=laplace, bootstrap_interval=boot_int,
        interval=interval, correlation=corr, bootstrap=boot, identifiable=identifiable,
        converged=bool(converged) and bool(np.all(np.asarray(ok)[real])), iterations=int(steps),
        rms=math.sqrt(ssr / max(n, 1)), noise=seg.noise, loss=loss, n_segments=int(real.sum()), n_samples=n,
        model=with_values(model, free, x_hat), segments=seg, fitted=np.asarray(fitted),
        fitted_top=np.asarray(fitted_top) if with_top else None, seconds=(seconds_fit, seconds_boot))


def eta_from_peaks(peaks, alpha) -> tuple[float, np.ndarray]:
    """The closed-form estimate of η from successive free-rocking peaks (one impact between two).

    Each impact keeps η² of the energy (eq. 3); between impacts the rigid block's energy at a peak
    (θ̇ = 0) is its potential, E(θ) = m g R (cos(α − |θ|) − cos α), so η_k = √(E(θ_{k+1})/E(θ_k)).
    The estimate is their geometric mean.

    Arguments:
        peaks (ArrayLike): successive peak angles θ_k [rad] (alternating sides), at least two.
        alpha (float): the block's α′ [rad].

    Returns:
        (float, numpy.ndarray): η, and the ratio of each impact.
    """
    th = np.abs(np.asarray(peaks, dtype=float))
    if th.size < 2:
        raise JaxrockInputError(f"eta_from_peaks: at least two peaks, got {th.size}")
    energy = np.cos(alpha - th) - np.cos(alpha)
    ratios = np.sqrt(energy[1:] / energy[:-1])
    return float(np.exp(np.mean(np.log(ratios)))), ratios


__all__ = ["FREE", "LOSSES", "Free", "Measured", "Segments", "Identification", "identify", "history", "segments", "find_peaks",
           "noise_level", "eta_from_peaks", "default_integrator"]
