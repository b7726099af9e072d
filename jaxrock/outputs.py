"""The summary outputs of a run, declared once: `SUMMARY`, a tuple of `Output`s (re-exported by
`jaxrock.results`, which builds `Solution` from it).

It imports no JAX (the command line's help names the outputs before JAX is loaded). A new summary
output is a line in `SUMMARY` and the code that computes it (`jaxrock.bookkeeping.Watch.solution`,
or an integrator passing it there).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Output(NamedTuple):
    """One summary output of a run, declared once in `SUMMARY`.

    `Solution`'s fields, `Spectrum`'s arrays, the netCDF variables, the batch results file's columns
    and the command line's summaries are generated from these declarations.

    Attributes:
        name: the field of `Solution` and `Spectrum`, the netCDF variable and the CSV column.
        label: how the command line's summaries call it.
        meaning: what it is (the netCDF long_name).
        units: its CF units ("1" for ratios, flags and counts; "s" for times).
        kind: "float", "bool" or "int".
        absent: its value from a model that does not compute it; default None: every model does.
        needs: the output it is computed with; default None: none. Where that one is not computed,
            neither is this one (its `absent` value then means "not computed").

    Example:
        ```python
        {o.name: o.units for o in jaxrock.SUMMARY}  # {'max_theta': '1', 'overturned': '1', ...}
        ```
    """

    name: str
    label: str
    meaning: str
    units: str
    kind: str
    absent: float | bool | int | None = None
    needs: str | None = None

    @property
    def dtype(self) -> type:
        """The NumPy dtype of its values (float64, bool or int64, by `kind`)."""
        return {"float": np.float64, "bool": np.bool_, "int": np.int64}[self.kind]

    @property
    def annotation(self):
        """The `jaxtyping` annotation of its `Solution` field (a scalar array of its `kind`)."""
        from jaxtyping import Array, Bool, Float, Int

        return {"float": Float, "bool": Bool, "int": Int}[self.kind][Array, ""]

    def csv_value(self, x) -> float | int:
        """The value a CSV cell holds (`jaxrock.io.tables.cell` writes it): floats exactly, flags 0/1.

        Arguments:
            x (float | bool | int): one scene's value.
        """
        return float(x) if self.kind == "float" else int(x)

    def line(self, x) -> str:
        """One scene's value as the command line prints it ("max θ/α = 0.663037", "overturned: no").

        Arguments:
            x (float | bool | int): one scene's value.
        """
        if self.kind == "bool":
            return f"{self.label}: {'yes' if bool(x) else 'no'}"
        if self.kind == "int":
            return f"{self.label}: {int(x)}"
        if self.units == "s":
            return f"{self.label}: {f't = {float(x):.4f} s' if np.isfinite(x) else 'never'}"
        if self.absent is not None and np.isnan(self.absent) and np.isnan(x):
            return f"{self.label}: not computed"
        return f"{self.label} = {float(x):.6f}" if abs(float(x)) < 1e4 else f"{self.label} = {float(x):.6g}"

    def invalid(self, x, ok):
        """`x` where `ok`, else what an invalid scene reports (NaN, no, or the absent value).

        Arguments:
            x (Array): the values (traceable).
            ok (Array): whether each scene's parameters are within their limits.

        Returns:
            (Array): the values, with the invalid scenes' replaced.
        """
        import jax.numpy as jnp

        if self.kind == "float":
            return jnp.where(ok, x, jnp.asarray(jnp.nan, dtype=x.dtype))
        if self.kind == "bool":
            return x & ok
        return jnp.where(ok, x, jnp.asarray(0 if self.absent is None else self.absent, dtype=x.dtype))


PERTURBATION = 1e-7  # δ: the relative perturbation of the scale that the `uncertain` flag answers for (jaxrock.sensitivity)
MARGIN_OVERTURNED = 0.1  # an overturned run's margin to the other verdict [α′], chosen by benchmarks/study_uncertain.py

SUMMARY: tuple[Output, ...] = (
    Output("max_theta", "max θ/α", "max |theta|/alpha' over the whole response (alpha' the rocking slenderness: alpha without "
           "a base): the exact peak; the threshold once overturned, never beyond it", "1", "float"),
    Output("overturned", "overturned", "|theta| reached threshold*alpha'", "1", "bool"),
    Output("t_overturn", "overturned at", "time of overturning (+inf: did not overturn)", "s", "float"),
    Output("uplifted", "uplifted", "the body left its rest state (|theta| passed the uplift rotation)", "1", "bool"),
    Output("t_uplift", "uplifted at", "first time |theta| passed the uplift rotation (+inf: never)", "s", "float"),
    Output("n_impacts", "impacts", "impacts at theta = 0 (the rigid model's; 0 for spring models)", "1", "int", absent=0),
    Output("sensitivity", "sensitivity", "max over the run of |d theta/d ln(scale)|/alpha', the tangent of the motion along the "
           "excitation's log-scale (jaxrock.sensitivity; NaN: not asked for)", "1", "float", absent=float("nan")),
    Output("uncertain", "verdict uncertain", f"the overturning verdict could flip under a relative perturbation of {PERTURBATION:g} "
           f"of the scale: {PERTURBATION:g} x sensitivity reaches the margin to overturning (1 - max theta/alpha'; "
           f"{MARGIN_OVERTURNED:g} once overturned) (jaxrock.sensitivity; no where the sensitivity is not computed)", "1", "bool",
           absent=False, needs="sensitivity"),
)
"""The summary outputs of a run, in order: one `Output` each.

`max_theta`, `overturned`, `t_overturn`, `uplifted`, `t_uplift`, `n_impacts`, `sensitivity` and
`uncertain`; `Solution`'s fields, `Spectrum`'s arrays, the netCDF variables and the results
file's columns are generated from it. A new summary output is a line here and the code that
computes it (`jaxrock.bookkeeping.Watch.solution`, or an integrator passing it there).
"""
OUTPUTS = {o.name: o for o in SUMMARY}
RESULT_COLUMNS: tuple[str, ...] = (*OUTPUTS, "status")  # a results row: the summary, then the status name


# the fields a time history can hold (`jaxrock.Save`; each model's `history_fields`): long name, CF units
HISTORY_FIELDS: dict[str, tuple[str, str]] = {
    "theta": ("rotation theta of the body", "rad"),
    "theta_dot": ("angular velocity of the body", "rad s-1"),
    "u_top": ("horizontal displacement of the column's top", "m"),
    "w_top": ("the column's top displacement relative to the rigid rotation", "m"),
    "base_moment": ("moment at the base spring", "N m"),
    "section_moment": ("bending moment of the column's base section", "N m"),
    "kinetic": ("kinetic energy", "J"),
    "potential": ("potential energy (gravity, spring and column strain, from the rest state)", "J"),
    "elastic": ("strain energy of the column", "J"),
    "dissipated": ("energy dissipated (damper + rayleigh)", "J"),
    "damper": ("work of the base damper", "J"),
    "rayleigh": ("work of the column's Rayleigh damping", "J"),
    "input": ("work of the ground on the body", "J"),
}


def computed(o: Output, values: dict) -> bool:
    """Whether the output `o` was computed, given every output's values (`values[name]`): False where
    it `needs` one whose values are all its absent NaN."""
    if o.needs is None:
        return True
    need = np.asarray(values[o.needs], dtype=float)
    return not np.isnan(need).all()


def summary_doc() -> str:
    """The summary outputs as a list (`name` [units]: meaning), for docstrings."""
    return "\n".join(f"- `{o.name}` [{o.units}]: {o.meaning}." for o in SUMMARY)
