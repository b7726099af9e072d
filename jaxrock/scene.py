"""The scene vocabulary: the words a scene is described in, written once. The command line's
options, the scenes file's columns and the spectra's axes are generated from it.

- Model kinds: the registry `jaxrock.model.MODEL_KINDS` (`model_kinds()`: rigid, spring,
  spring-flexible, and any kind registered since); `DEFAULT_MODEL`; `UNDAMPED`, the value of each
  damping parameter that dissipates nothing.
- Pulse kinds: `PULSES` (name → excitation class of `jaxrock.excitation`); a new pulse kind is a
  class there and a line here. `DEFAULT_PULSE`.
- Records: `RECORD_ALIASES`, the names of the packaged El Centro 1940 NS record.
- Ratios (SPEC "Spectra"): the spectra's axes a_p/(g tanα′) and ω_p/p′ (`AXES`), converted to and
  from the physical a_p [m/s²] and ω_p [rad/s] by `pulse_of_ratios` and `ratios_of_pulse` only.
- Concrete defaults (paper sections 4–6): `CONCRETE_E`, `CONCRETE_RHO`, `CONCRETE_ZETA`.
- The scene's parameters (`PARAMETERS`): each column of a scenes file with its unit, meaning and
  valid values / default (the scenes file's table, `parameter_table`).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from ._validate import JaxrockInputError
from .excitation import AntisymmetricRickerPulse, RickerPulse
from .geometry import G, TAN_ALPHA_MIN, Block

# -- model kinds -----------------------------------------------------------------------------------
DEFAULT_MODEL = "rigid"
UNDAMPED = {"eta": 1.0, "cbar": 0.0}  # a damping parameter's value that dissipates nothing


def model_kinds() -> tuple[str, ...]:
    """The model kinds a scene may name (the built-in rigid, spring and spring-flexible, and any
    kind registered with `jaxrock.register_model_kind` since)."""
    from .model import MODEL_KINDS  # the protocol's registry reads this module's defaults

    return tuple(MODEL_KINDS)


def takes(parameter: str) -> tuple[str, ...]:
    """The model kinds that take a parameter."""
    from .model import MODEL_KINDS

    return tuple(k.name for k in MODEL_KINDS.values() if parameter in k.parameters)


# -- pulse kinds and records -----------------------------------------------------------------------
PULSES = {"symmetric": RickerPulse, "antisymmetric": AntisymmetricRickerPulse}  # eq. 28, eq. 29
DEFAULT_PULSE = "symmetric"
RECORD_ALIASES = ("elcentro", "el-centro", "el_centro")  # the packaged El Centro 1940 NS (`jaxrock.el_centro`)


def pulse_class(pulse) -> type:
    """The pulse class named `pulse` (`PULSES`), or `pulse` itself when it is a class."""
    if isinstance(pulse, str):
        if pulse not in PULSES:
            raise JaxrockInputError(f"pulse = {pulse!r}; valid: {', '.join(PULSES)}")
        return PULSES[pulse]
    return pulse


def is_builtin_record(name: str) -> bool:
    return name.strip().lower() in RECORD_ALIASES


# -- ratios ----------------------------------------------------------------------------------------
AXES = {"accel_ratio": "a_p/(g tan alpha)", "omega_ratio": "omega_p/p"}  # the spectra's axes (rocking α′, p′)


def pulse_of_ratios(block: Block, accel_ratio, omega_ratio):
    """(a_p [m/s²], ω_p [rad/s]) of the ratios a_p/(g tanα′) and ω_p/p′ (numbers or arrays)."""
    return accel_ratio * G * jnp.tan(block.alpha_r), omega_ratio * block.p_r


def ratios_of_pulse(block: Block, a_p, omega_p):
    """(a_p/(g tanα′), ω_p/p′) of a pulse's a_p [m/s²] and ω_p [rad/s]."""
    return a_p / (G * jnp.tan(block.alpha_r)), omega_p / block.p_r


# -- concrete defaults -----------------------------------------------------------------------------
CONCRETE_E = 30e9  # Pa
CONCRETE_RHO = 2500.0  # kg/m³
CONCRETE_ZETA = 0.01  # column damping ratio at its first fixed-base mode


# -- the scene's parameters ------------------------------------------------------------------------
class Parameter(NamedTuple):
    """A parameter of a scene: its name (a scenes file's column), unit, meaning and valid values
    (with its default)."""

    name: str
    unit: str
    meaning: str
    valid: str


def _kinds(names) -> str:
    return " / ".join(f"`{k}`" for k in names)


def parameters() -> tuple[Parameter, ...]:
    """Every parameter of a scene, in a scenes file's column order (the model kinds that take each
    model parameter read from the registry, so that a registered kind shows)."""
    from .model import MODEL_KINDS

    pulses = " / ".join(f"`{k}`" for k in PULSES)
    return (
        Parameter("height", "m", "full height 2h of the column", "> 0, required"),
        Parameter("tan_alpha", "–", "slenderness tanα = b/h", f"[{TAN_ALPHA_MIN:g}, 1); give it or `width`"),
        Parameter("width", "m", "full width 2b (instead of `tan_alpha`)", "> 0, width/height < 1"),
        Parameter("tan_alpha_base", "–", "extended rigid base tanα′ = b′/h (paper section 5)", "[tanα, 1); default: no base"),
        Parameter("model", "–", ", ".join(f"`{k.name}` ({k.description})" for k in MODEL_KINDS.values()),
                  f"default `{DEFAULT_MODEL}`"),
        Parameter("pulse", "–", f"{pulses} Ricker pulse, `{RECORD_ALIASES[0]}` (the packaged El Centro 1940 NS), or a record "
                  "file path (`.AT2` or two-column text; relative to the scenes file, else to the working directory)",
                  f"default `{DEFAULT_PULSE}`"),
        Parameter("a_p", "m/s²", "pulse amplitude (any sign, ≠ 0)", "pulses: give it or `accel_ratio`"),
        Parameter("accel_ratio", "–", AXES["accel_ratio"].replace("alpha", "α′"), "≠ 0"),
        Parameter("omega_p", "rad/s", "pulse frequency", "> 0; pulses: give it or `omega_ratio`"),
        Parameter("omega_ratio", "–", AXES["omega_ratio"].replace("omega", "ω") + "′", "> 0"),
        Parameter("scale", "–", "factor on a record", "≥ 0, default 1 (records only)"),
        Parameter("eta", "–", "rigid impact velocity ratio (1: undamped)", f"[0, 1], default 1 − 1.5 sin²α′ ({_kinds(takes('eta'))})"),
        Parameter("cbar", "–", "spring-model damper c̄ (0: undamped)", f"≥ 0, default eq. 17 ({_kinds(takes('cbar'))})"),
        Parameter("E", "Pa", "Young's modulus of the column", f"> 0, default {CONCRETE_E:g} ({_kinds(takes('E'))})"),
        Parameter("rho", "kg/m³", "density of the column", f"> 0, default {CONCRETE_RHO:g} ({_kinds(takes('rho'))})"),
        Parameter("zeta", "–", "column damping ratio, first fixed-base mode", f"≥ 0, default {CONCRETE_ZETA:g} ({_kinds(takes('zeta'))})"),
    )


def parameter_table() -> str:
    """The scene's parameters as a Markdown table (the scenes file's columns)."""
    rows = ["| column | unit | meaning | valid values / default |", "| --- | --- | --- | --- |"]
    rows += [f"| `{p.name}` | {p.unit} | {p.meaning} | {p.valid} |" for p in parameters()]
    return "\n".join(rows)


def parameter_help(name: str, valid: bool = True) -> str:
    """A command-line help text for a scene parameter: its meaning, unit and (`valid`) its valid
    values / default."""
    p = next(q for q in parameters() if q.name == name)
    unit = "" if p.unit == "–" else f" [{p.unit}]"
    return (f"{p.meaning}{unit}" + (f"; {p.valid}" if valid else "")).replace("`", "")
