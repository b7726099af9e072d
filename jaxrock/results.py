"""What a run returns: a status enumeration (failure as a value) and the `Solution` pytree.

A `Solution` always carries the summary of a scene (max |θ|/α, overturned flag and time, uplift,
impacts, status); a time history only when one was asked for with `Save`.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int


class Status(eqx.Enumeration):
    """How a run ended. Anything but `ok` means the numbers are not to be trusted."""

    ok = "the run finished; the summary is exact to the solver tolerance"
    max_iterations = "the bound on loop iterations (segments and step chunks) was hit before the answer was fixed"
    max_steps = "an integration segment hit its step bound (stiff, or too tight a tolerance)"
    solver_failed = "the integrator or a root find failed (step size underflow, divergence, NaN)"
    missed_impact = "an impact surface was crossed without its event firing (report this as a bug)"
    invalid_input = "a parameter is outside its valid range (given under jax.vmap/jit, where constructors cannot refuse it); the numbers are NaN"


STATUS_NAMES: tuple[str, ...] = tuple(Status._name_to_item)  # index = the item's integer value


def status_names(status: Status) -> np.ndarray:
    """Names of (a batch of) status values, e.g. for a CSV column."""
    return np.asarray(STATUS_NAMES, dtype=object)[np.asarray(status._value)]


class Save(eqx.Module):
    """An output request: save a time history at times `ts` [s] (absolute time).

    `fields` names what to save; each model lists the fields it can give
    (rigid: "theta", "omega"; spring models more, see `jaxrock.spring`).
    """

    ts: Float[Array, " n"]
    fields: tuple[str, ...] = eqx.field(static=True, default=("theta",))

    def __init__(self, ts, fields=("theta",)):
        t = np.asarray(ts, dtype=float)
        from ._validate import JaxrockInputError

        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or (t.size > 1 and np.any(np.diff(t) <= 0)):
            raise JaxrockInputError("Save ts must be a non-empty, finite, strictly increasing 1-D array of times [s]")
        self.ts = jnp.asarray(t)
        self.fields = tuple(fields)


class Solution(eqx.Module):
    """The result of one scene (or, under vmap, of a batch: every leaf gains leading axes).

    - `max_theta`: max |θ|/α_r over the whole response (exact peak; = threshold if it overturned).
    - `overturned`, `t_overturn` (+inf when it did not overturn).
    - `uplifted`, `t_uplift` (+inf when it never uplifted).
    - `n_impacts`: impacts at θ = 0 (rigid model; 0 for spring models).
    - `status`: a `Status` value; check `sol.status == jaxrock.Status.ok`.
    - `ts`, `history`: only when a `Save` was given (dict field name → array over ts).
    - `n_iterations`: loop iterations the run took (cost diagnostics).
    """

    max_theta: Float[Array, ""]
    overturned: Bool[Array, ""]
    t_overturn: Float[Array, ""]
    uplifted: Bool[Array, ""]
    t_uplift: Float[Array, ""]
    n_impacts: Int[Array, ""]
    status: Status
    ts: Float[Array, " n"] | None = None
    history: dict | None = None
    n_iterations: Int[Array, ""] | int = 0

    @property
    def ok(self):
        return self.status == Status.ok
