"""What a run returns, declared once: the status enumeration (failure as a value), the summary
outputs (`SUMMARY`) and the `Solution` pytree built from them.

Every summary output is one `Output` of `SUMMARY` (declared in `jaxrock.outputs`, which imports no
JAX, and re-exported here): its name, a short label, its meaning, its units and its kind.
`Solution`'s fields, `Spectrum`'s arrays, the netCDF variables (long_name, units), the batch
results file's columns (`RESULT_COLUMNS`) and the command line's summaries are generated from it; a
new output is a line there and the code that computes it (`jaxrock.bookkeeping.Watch.solution`, or
an integrator passing it there).
"""

from __future__ import annotations

import types

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .outputs import OUTPUTS, RESULT_COLUMNS, SUMMARY, Output, summary_doc  # the summary outputs (`jaxrock.outputs`)


class Status(eqx.Enumeration):
    """How a run ended. Anything but `ok` means the numbers are not to be trusted."""

    ok = ("the run finished within its integrator's tolerance: with `Checked` (the flexible SM's default), its estimated global "
          "error of max |theta|/alpha' is within the stated accuracy; otherwise every step met the local tolerance")
    max_iterations = "the bound on loop iterations (segments and step chunks) was hit before the answer was fixed"
    max_steps = "an integration segment hit its step bound (stiff, or too tight a tolerance)"
    solver_failed = "the integrator or a root find failed (step size underflow, divergence, NaN)"
    missed_impact = "an impact surface was crossed without its event firing (report this as a bug)"
    invalid_input = "a parameter is outside its valid range (given under jax.vmap/jit, where constructors cannot refuse it); the numbers are NaN"
    inaccurate = "the run finished, but its global error estimate (`Checked`: a companion run at a looser tolerance) exceeds the stated accuracy, or the companion failed"


STATUS_NAMES: tuple[str, ...] = tuple(Status._name_to_item)  # index = the item's integer value


def status_codes(status: Status):
    """The integer codes (index into `STATUS_NAMES`; 0 = ok) of (a batch of) status values: an
    array (traced under `jit`/`vmap`)."""
    return status._value


def status_names(status: Status) -> np.ndarray:
    """Names of (a batch of) status values, e.g. for a CSV column."""
    return np.asarray(STATUS_NAMES, dtype=object)[np.asarray(status_codes(status))]


def schema_module(name: str, base: type, doc: str, fields: dict, defaults: dict, module: str) -> type:
    """A module class `name` (subclass of `base`) with the annotated `fields` (name → annotation,
    in order) and `defaults`: how `Solution` and `Spectrum` take their fields from `SUMMARY`."""
    namespace = {"__annotations__": fields, "__doc__": doc, "__module__": module, "__qualname__": name, **defaults}
    return types.new_class(name, (base,), {}, lambda ns: ns.update(namespace))


class Save(eqx.Module):
    """An output request: save a time history at times `ts` [s] (absolute time).

    `fields` names what to save; each model lists the fields it can give
    (rigid: "theta", "theta_dot"; spring models more, see `jaxrock.spring`).
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


class _AbstractSolution(eqx.Module):
    """`Solution`'s methods (its fields come from `SUMMARY`)."""

    @property
    def ok(self):
        return self.status == Status.ok


Solution = schema_module(
    "Solution", _AbstractSolution,
    "The result of one scene (or, under vmap, of a batch: every leaf gains leading axes).\n\n"
    "The summary (`jaxrock.results.SUMMARY`):\n" + summary_doc() + "\n"
    "- `status`: a `Status` value; check `sol.status == jaxrock.Status.ok`.\n"
    "- `ts`, `history`: only when a `Save` was given (dict field name → array over ts).\n"
    "- `n_iterations`: loop iterations the run took (cost diagnostics).\n",
    {**{o.name: o.annotation for o in SUMMARY}, "status": Status, "ts": Float[Array, " n"] | None, "history": dict | None,
     "n_iterations": Int[Array, ""] | int},
    {"ts": None, "history": None, "n_iterations": 0},
    __name__,
)


__all__ = ["Status", "STATUS_NAMES", "status_codes", "status_names", "Output", "SUMMARY", "OUTPUTS", "RESULT_COLUMNS", "summary_doc",
           "schema_module", "Save", "Solution"]
