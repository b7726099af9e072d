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
    """How a run ended (failure as a value). Anything but `ok` means the numbers are not to be trusted.

    An `equinox` enumeration: compare with `==` (`sol.status == jaxrock.Status.ok`, traceable),
    convert a batch with `status_names` or `status_codes`. Each item's value is its meaning.

    Attributes:
        ok: finished within the integrator's tolerance (with `Checked`, the flexible SM's default, its
            estimated global error of max |θ|/α′ is within the stated accuracy).
        max_iterations: the bound on loop iterations (segments and step chunks) was hit before the answer was fixed.
        max_steps: an integration segment hit its step bound (stiff, or too tight a tolerance).
        solver_failed: the integrator or a root find failed (step size underflow, divergence, NaN).
        missed_impact: an impact surface was crossed without its event firing (report this as a bug).
        invalid_input: a parameter is outside its valid range (given under `jax.vmap`/`jax.jit`, where
            constructors cannot refuse it); the numbers are NaN.
        inaccurate: finished, but the global error estimate (`Checked`: a companion run at a looser
            tolerance) exceeds the stated accuracy, or the companion failed.

    Example:
        ```python
        sol = jaxrock.simulate(model, pulse)
        if sol.status != jaxrock.Status.ok:
            print(jaxrock.status_names(sol.status))
        ```
    """

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
    """The integer codes of (a batch of) status values: the index into `STATUS_NAMES`, 0 = ok.

    Arguments:
        status: one `Status` value or a batch of them (e.g. `Solution.status` of a vmapped run).

    Returns:
        (Array): the integer codes, the shape of the batch (traced under `jit`/`vmap`).
    """
    return status._value


def status_names(status: Status) -> np.ndarray:
    """The names of (a batch of) status values, e.g. for a CSV column.

    Arguments:
        status: one `Status` value or a batch of them (concrete: not under `jit`/`vmap`).

    Returns:
        an object array of names ("ok", "max_steps", …), the shape of the batch.

    Example:
        ```python
        jaxrock.status_names(sol.status)  # array('ok', dtype=object)
        ```
    """
    return np.asarray(STATUS_NAMES, dtype=object)[np.asarray(status_codes(status))]


def schema_module(name: str, base: type, doc: str, fields: dict, defaults: dict, module: str) -> type:
    """A module class `name` (subclass of `base`) with the annotated `fields` (name → annotation,
    in order) and `defaults`: how `Solution` and `Spectrum` take their fields from `SUMMARY`."""
    namespace = {"__annotations__": fields, "__doc__": doc, "__module__": module, "__qualname__": name, **defaults}
    return types.new_class(name, (base,), {}, lambda ns: ns.update(namespace))


class Save(eqx.Module):
    """An output request: save a time history at times `ts` [s] (absolute time).

    Given to `simulate(..., save=Save(ts, fields))`, the run returns `Solution.ts` and
    `Solution.history` (field name → array over ts) and goes on to `t1` (default: the last save time).
    Each model lists the fields it can give (`history_fields`; rigid: "theta", "theta_dot";
    spring models more, see `jaxrock.spring`); `simulate` refuses the others.

    Arguments:
        ts (ArrayLike): save times [s], a non-empty, finite, strictly increasing 1-D array.
        fields (tuple[str, ...]): the fields to save (static); default ("theta",).

    Raises:
        JaxrockInputError: when `ts` is not a non-empty, finite, strictly increasing 1-D array.

    Example:
        ```python
        import numpy as np

        save = jaxrock.Save(np.linspace(-3.0, 10.0, 1301), fields=("theta", "theta_dot"))
        sol = jaxrock.simulate(model, pulse, save=save)
        sol.history["theta"]  # θ [rad] at save.ts
        ```
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
"""The result of one scene (or, under vmap, of a batch: every leaf gains leading axes).

An `eqx.Module` whose fields are generated from the summary outputs (`jaxrock.results.SUMMARY`),
then `status`, `ts`, `history` and `n_iterations`; `sol.ok` is `sol.status == Status.ok`.

Attributes:
    max_theta: max |θ|/α′ over the whole response [–] (α′ the rocking slenderness: α without a base): the
        exact peak; the threshold once overturned, never beyond it.
    overturned: whether |θ| reached threshold·α′.
    t_overturn: time of overturning [s] (+inf: did not overturn).
    uplifted: whether the body left its rest state (|θ| passed the uplift rotation).
    t_uplift: first time |θ| passed the uplift rotation [s] (+inf: never).
    n_impacts: impacts at θ = 0 (the rigid model's; 0 for spring models).
    sensitivity: max over the run of |∂θ/∂ln(scale)|/α′ [–], the tangent of the motion along the
        excitation's log-scale (`jaxrock.sensitivity`; NaN: not asked for).
    uncertain: whether the overturning verdict could flip under a relative perturbation 1e-7 of the
        scale (`verdict_uncertain`; False where the sensitivity is not computed).
    status: a `Status` value; check `sol.status == jaxrock.Status.ok`.
    ts: the save times [s], only when a `Save` was given (else None).
    history: dict field name → array over `ts`, only when a `Save` was given (else None).
    n_iterations: loop iterations the run took (cost diagnostics).

Example:
    ```python
    sol = jaxrock.simulate(jaxrock.RigidModel(block), pulse)
    float(sol.max_theta), bool(sol.overturned), bool(sol.ok)
    ```
"""


__all__ = ["Status", "STATUS_NAMES", "status_codes", "status_names", "Output", "SUMMARY", "OUTPUTS", "RESULT_COLUMNS", "summary_doc",
           "schema_module", "Save", "Solution"]
