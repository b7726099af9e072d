"""One constructor of scenes from flat values (issue 57): the model of a registered model kind and
the pulse of a registered pulse kind (`jaxrock.scene`) from named numbers. The command line, the
scenes file, sweeps and the spectra's refinement build their scenes here and nowhere else.

- `scene_model(kind, block, **parameters)`: the model of one scene, by the kind's builder;
- `kind_values(kind, values)`: the kind's own parameters among named values (a scenes file's
  columns, a sweep's quantities, the CLI's flags), the others left out;
- `scene_pulse(pulse, block, values)`: a pulse of kind `pulse` from `a_p` or `accel_ratio`
  (a_p/(g tanα′)), `omega_p` or `omega_ratio` (ω_p/p′) and its own parameters
  (`jaxrock.scene.PULSE_PARAMS`; one not given: the class's default);
- `scene_of(kind, pulse, values)`: both, on the block of `height`, `tan_alpha`, `tan_alpha_base`.

Each is traceable: `jax.vmap` over the values (arrays with a leading batch axis) builds a batch of
scenes, so a batch is one call, not a loop.
"""

from __future__ import annotations

from typing import Mapping

from ._validate import JaxrockInputError
from .geometry import Block, pulse_of_ratios
from .scene import MODEL_KINDS, PULSE_PARAMS, PULSES, model_kinds, pulse_class


def scene_model(kind: str, block: Block, **parameters):
    """The model of one scene of model kind `kind`, built by its registered builder.

    The builder is the kind's `jaxrock.scene.ModelKind.build`; traceable (`jax.vmap` over the
    parameters builds a batch of models).

    Arguments:
        kind: a registered model kind (`jaxrock.scene.model_kinds()`: "rigid", "spring",
            "spring-flexible", and any registered since).
        block: the scene's geometry.
        **parameters (float | Array | str | None): the kind's parameters (e.g. `eta`, `cbar`, `E`,
            `backbone`); None or left out: the builder's default.

    Returns:
        (AbstractModel): the model.

    Raises:
        JaxrockInputError: when `kind` is not registered, a parameter is not one the kind takes, or a
            concrete value is outside the kind's own declaration (`jaxrock.scene.Param`).

    Example:
        ```python
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        model = jaxrock.scene_model("rigid", block, eta=0.9)
        ```
    """
    if kind not in MODEL_KINDS:
        raise JaxrockInputError(f"model = {kind!r}; valid: {', '.join(model_kinds())}")
    entry = MODEL_KINDS[kind]
    given = {k: v for k, v in parameters.items() if v is not None}
    extra = sorted(set(given) - set(entry.parameters))
    if extra:
        raise JaxrockInputError(f"{', '.join(extra)}: not a parameter of model {kind} (it takes {', '.join(entry.parameters) or 'none'})")
    for name, p in entry.params.items():  # against the kind's own declaration (concrete values; a vmapped row is checked before)
        if name in given:
            p.check(given[name])
    return entry.model(block, **given)


def kind_values(kind: str, values: Mapping) -> dict:
    """The values among `values` that are parameters of model kind `kind` (`ModelKind.parameters`)."""
    return {k: values[k] for k in MODEL_KINDS[kind].parameters if k in values}


def pulse_params_of(pulse) -> dict:
    """The declared parameters beyond a_p and ω_p (`jaxrock.scene.PULSE_PARAMS`) of a pulse kind,
    named or given as its class or callable (one registered under no name: none)."""
    if isinstance(pulse, str):
        return PULSE_PARAMS.get(pulse, {})
    return next((PULSE_PARAMS.get(k, {}) for k, v in PULSES.items() if v is pulse or (isinstance(v, str) and pulse_class(k) is pulse)), {})


def pulse_values(pulse, values: Mapping) -> dict:
    """The values among `values` that are parameters of pulse kind `pulse` beyond a_p and ω_p."""
    return {k: values[k] for k in pulse_params_of(pulse) if k in values}


def scene_pulse(pulse, block: Block | None, values: Mapping):
    """A pulse of kind `pulse` from named values: amplitude, frequency and the kind's own parameters.

    Traceable: `jax.vmap` over the values builds a batch of pulses.

    Arguments:
        pulse (str | Callable): a pulse kind (a name of `jaxrock.scene.PULSES`: "symmetric",
            "antisymmetric", "sine", or any registered since), or a class or callable
            `(a_p, omega_p, **parameters)`.
        block: the block whose α′ and p′ the ratios refer to; may be None where both `a_p` and
            `omega_p` are given.
        values: `a_p` [m/s²] or `accel_ratio` (a_p/(g tanα′)), `omega_p` [rad/s] or `omega_ratio`
            (ω_p/p′) (a ratio left out: 1), and the kind's own parameters (e.g. `n_cycles`; left
            out: the class's default). Other keys are ignored.

    Returns:
        (AbstractExcitation): the pulse.

    Raises:
        JaxrockInputError: when `pulse` names no registered kind, or the pulse refuses a value
            (e.g. a_p = 0, ω_p ≤ 0).

    Example:
        ```python
        pulse = jaxrock.scene_pulse("sine", block, {"accel_ratio": 2.0, "omega_ratio": 3.0, "n_cycles": 1.5})
        ```
    """
    if "a_p" in values and "omega_p" in values:
        a_p, omega_p = values["a_p"], values["omega_p"]
    else:
        a_r, w_r = values.get("accel_ratio", 1.0), values.get("omega_ratio", 1.0)
        a_of, w_of = pulse_of_ratios(block, a_r, w_r)
        a_p = values["a_p"] if "a_p" in values else a_of
        omega_p = values["omega_p"] if "omega_p" in values else w_of
    return pulse_class(pulse)(a_p, omega_p, **pulse_values(pulse, values))


def scene_block(values: Mapping) -> Block:
    """The block of `height` (2h [m]), `tan_alpha` and `tan_alpha_base` (absent or None: no base)."""
    return Block.from_slenderness(values["height"], values["tan_alpha"], values.get("tan_alpha_base"))


def scene_of(kind: str, pulse, values: Mapping, **options):
    """The model and pulse of one scene from flat values (a scenes file's row, a sweep's point).

    The block is `Block.from_slenderness(height, tan_alpha, tan_alpha_base)` (`scene_block`), the
    model `scene_model` with the values that are the kind's parameters (`kind_values`), the pulse
    `scene_pulse`. Traceable: `jax.vmap` over the values builds a batch of scenes.

    Arguments:
        kind: a registered model kind ("rigid", "spring", "spring-flexible", ...).
        pulse (str | Callable): a pulse kind or a pulse class or callable (see `scene_pulse`).
        values: `height` (2h [m]) and `tan_alpha` (required), `tan_alpha_base` (absent or None: no
            base), the kind's numeric parameters and the pulse's values (see `scene_pulse`).
        **options (str | float): the kind's non-numeric options (e.g. `backbone`, `smoothing`).

    Returns:
        model (AbstractModel): the scene's model.
        pulse (AbstractExcitation): the scene's pulse.

    Raises:
        JaxrockInputError: when a value is outside its range, or the kind or pulse is not registered.
        KeyError: when `height` or `tan_alpha` is missing.

    Example:
        ```python
        values = {"height": 10.0, "tan_alpha": 0.2, "accel_ratio": 2.0, "omega_ratio": 3.0}
        model, pulse = jaxrock.scene_of("rigid", "symmetric", values)
        sol = jaxrock.simulate(model, pulse)
        ```
    """
    block = scene_block(values)
    return scene_model(kind, block, **kind_values(kind, values), **options), scene_pulse(pulse, block, values)


__all__ = ["scene_model", "kind_values", "pulse_params_of", "pulse_values", "scene_pulse", "scene_block", "scene_of"]
