"""The quasi-rigid SM on its pre-yield spring until it first yields, stepped exactly (`rest_phase`).

Before its first uplift the one-DOF body sits on the linear branch of its kinked spring
(|θ| < θy = θs, `jaxrock.spring.base_spring.Bilinear`), where eq. 10 with the spring's moment
My θ/θy and the damper of eq. 18 reads

    I θ̈ + c θ̇ + (My/θy − m g h) θ = −m h üg(t)                                  (eq. 10, pre-yield)

up to cos θ = 1 − O(θy²) and sin θ = θ + O(θy³) (relative 1e-12 of the terms at θy = 1e-5 α′).
An explicit solver's steps there follow the stiff spring's ringing, not the tolerance: on the
backbone study's pulses 60–80 % of Tsit5's steps came before the first uplift.

Here the equation is stepped exactly on a fixed grid: on each step of length h the ground
acceleration is its cubic Hermite interpolant (values and slopes at both ends; on a sampled record
its samples' linear interpolant, the record itself) and the state is propagated by the exponential
of the 6×6 augmented matrix (Van Loan 1978), computed once per scene. The first yield is the
first sub-step (`SUB_PULSE`, `SUB_RECORD` per step) whose cubic Hermite interpolant reaches θy; it
is located on that sub-step's exact solution by Newton from the interpolant's crossing, so that the
uplift time and state are smooth functions of the parameters (their derivatives the motion's). The diffrax integrator takes over there, on the
yielded branch (`jaxrock.spring.diffrax_integrator`).

On a pulse the grid has `REST_STEPS` steps over the pulse window (the error of the interpolated
pulse, ∝ h⁴, then below the explicit solver's tolerance: `benchmarks/bench_backbone.py --part
rest`); on a record, one step per sample.
"""

from __future__ import annotations

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..excitation import AbstractExcitation, AbstractRicker, Record as SampledRecord
from .. import _linalg
from ..bookkeeping import hermite_crossing, step_peaks
from ..geometry import G

# Steps of the exact grid over a pulse's window (`rest_grid`; choice: module docstring).
REST_STEPS = 1024
# Sub-steps per step on which the exact solution's Hermite interpolant is checked for a yield: on a
# record the spring's ringing (ω h up to ~25 on a sample step) is resolved by 32, so that a yield
# between two samples is seen (16 records' first yields, the grid refined 4 and 16 times: the same
# to 1e-12 s; with the step ends and midpoints alone, 2 of 8 came 0.3–0.7/p late). On a pulse the
# ringing is 1e-4 of θy at most and 2 sub-steps give the 32's first yields (192 pulses, 1e-13 s).
SUB_RECORD = 32
SUB_PULSE = 4
BLOCK = 32  # steps per loop iteration (`rest_phase`)
_NEWTON = 2  # Newton iterations (from the Hermite estimate) that locate the first yield on its sub-step


def rest_grid(excitation: AbstractExcitation) -> tuple[Float[Array, ""], int, int] | None:
    """(h, n, sub-steps): the exact grid's step, its number of steps over the excitation's window
    and the sub-steps checked for a yield (n and sub-steps static); None for an excitation without
    one (the run then starts on the diffrax path)."""
    if isinstance(excitation, SampledRecord):  # a pair's üv makes the equation parametric: no exact phase
        return None if excitation.vertical is not None else (excitation.dt, excitation.n - 1, SUB_RECORD)
    if isinstance(excitation, AbstractRicker):
        return (excitation.t_end - excitation.t_start) / REST_STEPS, REST_STEPS, SUB_PULSE
    return None


class PreYield(eqx.Module):
    """The pre-yield equation of a scene as y′ = A y + b üg(t), y = (θ, θ̇), and its propagator
    over one grid step of length `h`: exp(Z h) of the augmented matrix (module docstring)."""

    A: Float[Array, "2 2"]
    b: Float[Array, " 2"]
    h: Float[Array, ""]
    P_sub: Float[Array, "n_sub+1 2 6"]  # exp(j Z / n_sub)[:2], j = 0 … n_sub: the step's points

    def __init__(self, system, h, n_sub: int):
        k = system.My / system.theta_s - system.m * G * system.h  # pre-yield stiffness less gravity's
        self.A = jnp.array([[0.0, 1.0], [-k / system.Itot, -system.c / system.Itot]])
        self.b = jnp.array([0.0, -system.m * system.h / system.Itot])
        self.h = jnp.asarray(h, dtype=float)
        E = _linalg.expm(self.augmented() / n_sub)
        powers = [jnp.eye(6)]
        for _ in range(n_sub):
            powers.append(E @ powers[-1])
        self.P_sub = jnp.stack(powers)[:, :2, :]

    def augmented(self):
        """Z: d/dσ (y, w) = Z (y, w) on σ = (t − t₀)/h ∈ [0, 1], with w the forcing's Taylor
        coefficients, w₀(σ) = üg(t₀ + σ h) a cubic (w = (d₀, d₁, 2 d₂, 6 d₃))."""
        Z = jnp.zeros((6, 6))
        Z = Z.at[:2, :2].set(self.A * self.h).at[:2, 2].set(self.b * self.h)
        return Z.at[2, 3].set(1.0).at[3, 4].set(1.0).at[4, 5].set(1.0)

    @staticmethod
    def forcing(f0, f1, s0, s1):
        """w of the cubic Hermite interpolant from values f and slopes s (× h) at both ends."""
        d2 = 3.0 * (f1 - f0) - 2.0 * s0 - s1
        d3 = 2.0 * (f0 - f1) + s0 + s1
        return jnp.stack([f0, s0, 2.0 * d2, 6.0 * d3])

    def block(self):
        """(Y, T) with the states after each of `BLOCK` steps from y with forcings w (BLOCK, 4):
        Y @ y + T @ w.ravel() (rows: the steps' (θ, θ̇)): Y[i] = Eⁱ⁺¹, T[i, l] = Eⁱ⁻ˡ G (l ≤ i)."""
        E, G_ = self.P_sub[-1, :, :2], self.P_sub[-1, :, 2:]
        powers = [jnp.eye(2)]
        for _ in range(BLOCK):
            powers.append(E @ powers[-1])
        powers = jnp.stack(powers)  # E⁰ … E^BLOCK
        i, l = jnp.arange(BLOCK)[:, None], jnp.arange(BLOCK)[None, :]
        T = jnp.where((l <= i)[..., None, None], powers[jnp.clip(i - l, 0, BLOCK)] @ G_, 0.0)  # (BLOCK, BLOCK, 2, 4)
        return powers[1:].reshape(BLOCK * 2, 2), T.transpose(0, 2, 1, 3).reshape(BLOCK * 2, BLOCK * 4)

    def points(self, y, w):
        """The exact states (n_sub+1, 2) at σ = j/n_sub of a step from y with forcing w."""
        return self.P_sub @ jnp.concatenate([y, w])

    def at(self, sigma, y, w):
        """The exact state at σ ∈ [0, 1] of a step from y with forcing w."""
        return (_linalg.expm(sigma * self.augmented()) @ jnp.concatenate([y, w]))[:2]


def _forcing(excitation, h, t0, n: int):
    """The Taylor vectors w (n, 4) of the ground acceleration on the grid's n steps from t0
    (`PreYield.forcing`): values and slopes at the grid points, a record's slopes its secants."""
    ts = t0 + h * jnp.arange(n + 1)
    f = jax.vmap(excitation)(ts)
    if isinstance(excitation, SampledRecord):
        s0 = s1 = f[1:] - f[:-1]
    else:
        s = jax.vmap(lambda t: jax.jvp(excitation, (t,), (jnp.ones_like(t),))[1])(ts) * h
        s0, s1 = s[:-1], s[1:]
    return jax.vmap(PreYield.forcing)(f[:-1], f[1:], s0, s1)


class RestEnd(eqx.Module):
    """Where the exact phase ends: at the first yield (`yielded`, the state on the kink), or at the
    window's end without one."""

    t: Float[Array, ""]
    y: Float[Array, " 2"]
    yielded: Array
    peak: Float[Array, ""]  # max |θ| on the way (the sub-steps' interpolants); θy once yielded
    n_steps: Array


def rest_phase(system, excitation: AbstractExcitation, t_stop, reverse: bool) -> RestEnd:
    """The exact pre-yield phase from rest at the excitation's start (module docstring) to the first
    yield, or to the window's end or `t_stop`, whichever comes first: `BLOCK` steps at a time, each
    block's states one product with the scene's block propagator. `reverse`: in a loop that reverse
    mode differentiates (equinox's checkpointed loop), else a plain loop."""
    h, n, n_sub = rest_grid(excitation)
    pre = PreYield(system, h, n_sub)
    theta_y = system.theta_s
    t0 = jnp.asarray(excitation.t_start, dtype=float)
    t_last = jnp.minimum(excitation.t_end, t_stop)
    sigmas = jnp.arange(n_sub + 1) / n_sub
    n_blocks = -(-n // BLOCK)
    Y_of, T = pre.block()

    def cond(c):
        b, found = c[0], c[3]
        return (~found) & (b < n_blocks) & (t0 + b * BLOCK * h < t_last)

    def body(c):
        b, y, peak, _, _, _ = c
        w = _forcing(excitation, h, t0 + b * BLOCK * h, BLOCK)
        Y = (Y_of @ y + T @ w.reshape(-1)).reshape(BLOCK, 2)  # the states after each step of the block
        starts = jnp.concatenate([y[None], Y[:-1]])
        pts = jnp.einsum("jab,kb->kja", pre.P_sub, jnp.concatenate([starts, w], axis=1))  # (BLOCK, n_sub+1, 2)
        ts = h * (b * BLOCK + jnp.arange(BLOCK)[:, None] + sigmas[None, :])
        peaks = step_peaks(ts.reshape(-1), pts[..., 0].reshape(-1), pts[..., 1].reshape(-1))
        peaks = jnp.append(peaks, 0.0).reshape(BLOCK, n_sub + 1)[:, :n_sub]  # sub-step j of step i, on its interpolant
        live = (t0 + ts[:, :1] < t_last) & (b * BLOCK + jnp.arange(BLOCK)[:, None] < n)
        above = (peaks >= theta_y) & live
        found = jnp.any(above)
        first = jnp.argmax(above.reshape(-1))
        i, j = first // n_sub, first % n_sub
        n_live = jnp.sum(live)
        # where it yields: the step's index and start; else the block's last live step's end
        k = (b * BLOCK + jnp.where(found, i, n_live)).astype(jnp.int32)
        y_next = jnp.where(found, starts[i], jnp.where(n_live > 0, Y[jnp.maximum(n_live - 1, 0)], y))
        return b + 1, y_next, jnp.maximum(peak, jnp.max(jnp.where(live, peaks, 0.0))), found, k, j.astype(jnp.int32)

    zero = jnp.zeros((), jnp.int32)
    start = (zero, jnp.zeros(2), jnp.zeros(()), jnp.asarray(False), zero, zero)
    _, y, peak, found, k, j = eqxi.while_loop(cond, body, start, max_steps=n_blocks, kind="checkpointed" if reverse else "lax")
    w = _forcing(excitation, h, t0 + k * h, 1)[0]

    # the first yield on sub-step j of the step found: |θ(σ)| = θy by Newton on the exact solution,
    # from the crossing of the sub-step's Hermite interpolant (then one Newton step more, unclipped,
    # so that σ's derivatives are the root's)
    pts = pre.points(y, w)
    lo, hi = sigmas[j], sigmas[j + 1]
    a, b = pts[j], pts[j + 1]
    sign = jnp.where(a[0] + b[0] >= 0, 1.0, -1.0)
    t_guess = hermite_crossing(lo, hi, sign * a[0], jnp.maximum(sign * b[0], theta_y), sign * a[1] * h, sign * b[1] * h, theta_y)

    def newton(sig):
        z = pre.at(sig, y, w)
        return sig - (sign * z[0] - theta_y) / (sign * z[1] * h)

    sig = jax.lax.fori_loop(0, _NEWTON, lambda _, s: jnp.clip(newton(s), lo, hi), t_guess)
    sig = jnp.where(found, newton(sig), 0.0)
    y_kink = pre.at(sig, y, w).at[0].set(sign * theta_y)
    return RestEnd(t=t0 + (k + sig) * h, y=jnp.where(found, y_kink, y), yielded=found,
                   peak=jnp.where(found, theta_y, peak), n_steps=k + found)


def rest_states(system, excitation: AbstractExcitation, ts) -> Float[Array, "n_ts 2"]:
    """(θ, θ̇) of the exact pre-yield motion at the times `ts` (a history's save times; the start's
    rest before the excitation's start; meaningful up to the phase's end, `rest_phase`): the grid's
    states by one associative scan of the steps' affine maps, each time's on its step exactly."""
    h, n, n_sub = rest_grid(excitation)
    pre = PreYield(system, h, n_sub)
    t0 = jnp.asarray(excitation.t_start, dtype=float)
    W = _forcing(excitation, h, t0, n)
    E, G_ = pre.P_sub[-1, :, :2], pre.P_sub[-1, :, 2:]
    combine = lambda a, b: (b[0] @ a[0], (b[0] @ a[1][..., None])[..., 0] + b[1])
    Y = jnp.concatenate([jnp.zeros((1, 2)), jax.lax.associative_scan(combine, (jnp.broadcast_to(E, (n, 2, 2)), W @ G_.T))[1]])
    x = jnp.clip((jnp.asarray(ts, dtype=float) - t0) / h, 0.0, n)
    k = jnp.minimum(jnp.floor(x).astype(jnp.int32), n - 1)
    return jax.vmap(lambda k, sig: pre.at(sig, Y[k], W[k]))(k, x - k)
