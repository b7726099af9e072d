"""A safeguarded Newton–bisection root finder for diffrax's event location.

diffrax locates an event by a root find in time on the step's dense output, over the pytree of
all event conditions (the ones that did not fire are zeroed, so their sum is the firing one).
`optx.Newton` stalls at near-double roots (an apex where θ̈ ≈ 0) and `optx.Bisection` accepts
scalar outputs only; this solver keeps the bracket [lower, upper] that diffrax passes, takes the
Newton step when it stays inside the bracket and bisects otherwise (Numerical Recipes' rtsafe).
It converges for any continuous condition with a sign change in the bracket, quadratically near
simple roots. The time found is then differentiated implicitly by optimistix, as for any solver.
"""

from __future__ import annotations

from typing import Any, Callable, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array, Bool, Float


def _scalar(fn, y, args):
    f, aux = fn(y, args)
    return sum(jnp.asarray(leaf, dtype=jnp.result_type(y)) for leaf in jax.tree_util.tree_leaves(f)), aux


class _State(eqx.Module):
    lower: Float[Array, ""]  # f(lower) <= 0 (after orientation)
    upper: Float[Array, ""]  # f(upper) >= 0
    flip: Bool[Array, ""]
    f: Float[Array, ""]
    step: Float[Array, ""]
    done: Bool[Array, ""]


def _rtsafe_step(y, f, df, lower, upper, flip, tol):
    """One step from y (f = g(y), df = g′(y)) inside the bracket [lower, upper] (`flip`: g falls
    across it): (the next y, the bracket narrowed to y's side)."""
    o = jnp.where(flip, -f, f)  # oriented: o < 0 below the root
    lower, upper = jnp.where(o < 0, y, lower), jnp.where(o < 0, upper, y)
    newton = y - f / jnp.where(df == 0, 1.0, df)
    ok = (df != 0) & (newton > lower) & (newton < upper)
    # A Newton step below the tolerance has converged, even where it rounds onto the end of the
    # bracket that y has just become (|f/df| below half an ulp of y): bisecting there instead
    # restarted the search from the bracket's middle, ~40 halvings to reach the same root.
    converged = (df != 0) & (jnp.abs(newton - y) < tol)
    new_y = jnp.where(ok, newton, jnp.where(converged, jnp.clip(newton, lower, upper), 0.5 * (lower + upper)))
    return jnp.where(f == 0, y, new_y), lower, upper


class SafeNewton(optx.AbstractRootFinder):
    """Newton steps kept inside a shrinking sign-change bracket; bisection when they leave it."""

    rtol: float
    atol: float
    norm: ClassVar[Callable] = jnp.abs

    def init(self, fn, y, args, options: dict[str, Any], f_struct, aux_struct, tags) -> _State:
        lo = jnp.asarray(options["lower"], jnp.result_type(y))
        hi = jnp.asarray(options["upper"], jnp.result_type(y))
        f_lo, _ = _scalar(fn, lo, args)
        f_hi, _ = _scalar(fn, hi, args)
        flip = f_lo > f_hi
        # an endpoint that is already a root ends the search at once (diffrax's "no event" case)
        done = (f_lo == 0) | (f_hi == 0) | (jnp.sign(f_lo) == jnp.sign(f_hi))
        return _State(lo, hi, flip, jnp.asarray(jnp.inf, lo.dtype), hi - lo, done)

    def step(self, fn, y, args, options, state: _State, tags):
        y = jnp.clip(y, state.lower, state.upper)
        f, df, aux = jax.jvp(lambda t: _scalar(fn, t, args), (y,), (jnp.ones_like(y),), has_aux=True)
        new_y, lower, upper = _rtsafe_step(y, f, df, state.lower, state.upper, state.flip, self.atol + self.rtol * jnp.abs(y))
        new_y = jnp.where(state.done, y, new_y)
        return new_y, _State(lower, upper, state.flip, f, jnp.abs(new_y - y), state.done | (f == 0)), aux

    def terminate(self, fn, y, args, options, state: _State, tags):
        scale = self.atol + self.rtol * jnp.abs(y)
        small = (state.step < scale) | (state.upper - state.lower < scale)
        return state.done | small, optx.RESULTS.successful

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}


def bracketed_root(g: Callable, params, lower, upper, tol, max_steps: int = 200):
    """The root of a scalar `g(t, params)` with a sign change on [lower, upper] (lower = upper:
    that point), by the same safeguarded Newton as `SafeNewton`, in a plain loop (cheap under
    `vmap`: a lane without a bracket is done at once, and the loop carries no derivatives); its
    derivatives by the implicit function theorem, as optimistix gives them: the stopped root t*
    plus −(g(t*) − g(t*)|stopped)/g′(t*), whose value is 0 and whose derivative is −∂g/g′."""
    frozen_params = jax.lax.stop_gradient(params)
    frozen = lambda t: g(t, frozen_params)
    lower, upper = jax.lax.stop_gradient(lower), jax.lax.stop_gradient(upper)
    f_lo, f_hi = frozen(lower), frozen(upper)
    flip = f_lo > f_hi
    # first guess: where the chord crosses zero
    chord = jnp.where(f_hi != f_lo, lower - f_lo * (upper - lower) / jnp.where(f_hi != f_lo, f_hi - f_lo, 1.0), upper)
    t0 = jnp.where((f_lo == 0) | (upper == lower), lower, jnp.where(f_hi == 0, upper, jnp.clip(chord, lower, upper)))
    done0 = (f_lo == 0) | (f_hi == 0) | (upper == lower)

    def body(s):
        t, lo, hi, _, k, done = s
        f, df = jax.jvp(frozen, (t,), (jnp.ones_like(t),))
        new, lo, hi = _rtsafe_step(t, f, df, lo, hi, flip, tol * (1 + jnp.abs(t)))
        return new, lo, hi, jnp.abs(new - t), k + 1, done | (f == 0)

    def cond(s):
        t, lo, hi, step, k, done = s
        small = (step < tol * (1 + jnp.abs(t))) | (hi - lo < tol * (1 + jnp.abs(t)))
        return ~done & ~small & (k < max_steps)

    init = (t0, lower, upper, jnp.full_like(t0, jnp.inf), 0, done0)
    root = jax.lax.stop_gradient(jax.lax.while_loop(cond, body, init)[0])
    f, df = jax.jvp(lambda t: g(t, params), (root,), (jnp.ones_like(root),))
    df = jax.lax.stop_gradient(df)
    # (a point given as its own bracket carries no derivative: the caller's where picks its own)
    ok = (upper > lower) & (df != 0)
    return root - jnp.where(ok, (f - jax.lax.stop_gradient(f)) / jnp.where(ok, df, 1.0), 0.0)
