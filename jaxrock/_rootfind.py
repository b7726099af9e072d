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
        g = jnp.where(state.flip, -f, f)  # oriented: g < 0 below the root
        lower = jnp.where(g < 0, y, state.lower)
        upper = jnp.where(g < 0, state.upper, y)
        newton = y - f / jnp.where(df == 0, 1.0, df)
        ok = (df != 0) & (newton > lower) & (newton < upper)
        # A Newton step below the tolerance has converged, even where it rounds onto the end of the
        # bracket that y has just become (|f/df| below half an ulp of y): bisecting there instead
        # restarted the search from the bracket's middle, ~40 halvings to reach the same root.
        converged = (df != 0) & (jnp.abs(newton - y) < self.atol + self.rtol * jnp.abs(y))
        new_y = jnp.where(ok, newton, jnp.where(converged, jnp.clip(newton, lower, upper), 0.5 * (lower + upper)))
        new_y = jnp.where(state.done | (f == 0), y, new_y)
        return new_y, _State(lower, upper, state.flip, f, jnp.abs(new_y - y), state.done | (f == 0)), aux

    def terminate(self, fn, y, args, options, state: _State, tags):
        scale = self.atol + self.rtol * jnp.abs(y)
        small = (state.step < scale) | (state.upper - state.lower < scale)
        return state.done | small, optx.RESULTS.successful

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}
