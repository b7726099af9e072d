"""The scene vocabulary: the words a scene is described in, written once. The command line's
options, the scenes file's columns and the spectra's axes are generated from it.

It imports no JAX (the bottom of the layers): the command line builds its help and refuses bad
arguments from it before JAX is loaded, and the classes it names are imported when first used.

- Model kinds: the registry `MODEL_KINDS` (`model_kinds()`: rigid, spring, spring-flexible, and
  any kind registered since with `register_model_kind`); `DEFAULT_MODEL`; each kind's numeric
  parameters declared as `Param`s (`model_params()`: all of them); `UNDAMPED`, the value of each
  damping parameter that dissipates nothing; `load_plugins`, the kinds of other packages
  (`PLUGIN_GROUP` entry points, the `PLUGIN_ENV` variable).
- Pulse kinds: `PULSES` (name → excitation class of `jaxrock.excitation`, `pulse_class`); a new
  pulse kind is a class there and a line here. `DEFAULT_PULSE`.
- Records: `RECORD_ALIASES`, the names of the packaged El Centro 1940 NS record; `PACKAGED_RECORDS`, the
  other packaged records; `BUILTIN_SUITE`, the name of all of them together.
- Geometry: `TAN_ALPHA_MIN` and `check_slenderness`, the valid height and slenderness of a block.
- Spring backbones: `BACKBONES` (name → class of `jaxrock.spring.base_spring`), `DEFAULT_BACKBONE`
  (by model), `DEFAULT_SMOOTHING` (by backbone), `default_spring`.
- Ratios (SPEC "Spectra"): the spectra's axes a_p/(g tanα′) and ω_p/p′ (`AXES`), converted to and
  from the physical a_p [m/s²] and ω_p [rad/s] by `jaxrock.geometry.pulse_of_ratios` and
  `ratios_of_pulse` only (functions of a `Block`).
- Concrete defaults (paper sections 4–6): `CONCRETE_E`, `CONCRETE_RHO`, `CONCRETE_ZETA`.
- The scene's parameters (`PARAMETERS`): each column of a scenes file with its unit, meaning and
  valid values / default (the scenes file's table, `parameter_table`).
"""

from __future__ import annotations

import importlib
import math
from typing import Callable, NamedTuple

from ._validate import JaxrockInputError, check_range, is_concrete


def _resolve(module: str, name: str):
    """A class or function named in this vocabulary, imported on first use."""
    return getattr(importlib.import_module(module), name)


# -- model parameters ------------------------------------------------------------------------------
class Param(NamedTuple):
    """A numeric model (or pulse) parameter, declared once (issue 57).

    The command line's help, the scenes file's table, the sweep's quantities, `UNDAMPED` and the
    neutral values are generated from it. Give a model kind's parameters to `register_model_kind`,
    a pulse kind's to `register_pulse_kind`.

    Attributes:
        name: a scenes file's column and the model builder's keyword.
        meaning: what it means, for tables and help.
        unit: its unit as people write it ("–" for none).
        lo: lower end of the valid range.
        hi: upper end of the valid range (`math.inf`: none).
        lo_open: whether `lo` itself is refused; default False.
        hi_open: whether `hi` itself is refused; default False.
        default: its default; default None: the model computes it (`default_text` says how).
        default_text: how the model computes the default, for tables; default "".
        undamped: for a damping parameter, the value that dissipates nothing; default None.
        long_name: an ASCII name for stores (netCDF long_name); default "".
        units: its CF units; default "1".
        neutral: the value a run puts in place of an invalid one under `vmap`
            (`jaxrock.model.guard_scene`); default None: `default`.
        step: where given, the values must be whole multiples of it (a sine pulse's half cycles);
            default None.
        option: the command line's flag where the name's own would not be lower case (`E`:
            "--youngs-modulus"); default "".

    Example:
        ```python
        import math

        ZETA = jaxrock.Param("zeta", "column damping ratio", "–", 0.0, math.inf, hi_open=True, default=0.01)
        ```
    """

    name: str
    meaning: str
    unit: str
    lo: float
    hi: float
    lo_open: bool = False
    hi_open: bool = False
    default: float | None = None
    default_text: str = ""
    undamped: float | None = None
    long_name: str = ""
    units: str = "1"
    neutral: float | None = None
    step: float | None = None
    option: str = ""  # the command line's flag where the name's own would not be lower case (`E`: --youngs-modulus)

    @property
    def range_text(self) -> str:
        """The valid range as a table writes it ("[0, 1]", "≥ 0", "> 0"; "multiples of 0.5 in [0.5, 100]")."""
        if math.isinf(self.hi):
            text = f"{'>' if self.lo_open else '≥'} {self.lo:g}"
        else:
            text = f"{'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}{')' if self.hi_open else ']'}"
        return text if self.step is None else f"multiples of {self.step:g} in {text}"

    def check(self, x, name: str | None = None) -> None:
        """Refuse, in one line, a value outside the valid range or off its step.

        Concrete values only; a traced one is checked where it is made.

        Arguments:
            x (float | ArrayLike): the value(s).
            name: the name the message gives; default None: the parameter's.

        Raises:
            JaxrockInputError: when a value is not finite, is outside [lo, hi] or is off `step`.
        """
        check_range(name or self.name, x, self.lo, self.hi, lo_open=self.lo_open, hi_open=self.hi_open)
        if is_concrete(x):
            self.check_step(x, name)

    def off_step(self, x):
        """Where the values `x` are not whole multiples of `step` (nowhere without one).

        Arguments:
            x (ArrayLike): the values.

        Returns:
            (numpy.ndarray): a boolean array of the shape of `x`.
        """
        import numpy as np

        x = np.asarray(x, dtype=float)
        if self.step is None:
            return np.zeros(x.shape, bool)
        return np.isfinite(x) & (x / self.step != np.round(x / self.step))

    def check_step(self, x, name: str | None = None) -> None:
        """Refuse, in one line, a value that is not a whole multiple of `step`.

        Arguments:
            x (ArrayLike): the value(s).
            name: the name the message gives; default None: the parameter's.

        Raises:
            JaxrockInputError: when a value is off `step`.
        """
        import numpy as np

        bad = self.off_step(x)
        if bad.any():
            raise JaxrockInputError(f"{name or self.name} = {np.asarray(x, dtype=float)[bad].flat[0]:g}; valid: {self.range_text}")

    @property
    def range(self) -> tuple[float, float, bool, bool]:
        """(lo, hi, lo_open, hi_open)."""
        return self.lo, self.hi, self.lo_open, self.hi_open

    @property
    def flag(self) -> str:
        """The command line's option ("--tan-alpha" for `tan_alpha`; `option` where given: "--youngs-modulus" for `E`)."""
        return self.option or "--" + self.name.replace("_", "-")


# the built-in models' parameters (paper: η eq. 5, c̄ eq. 17; the concrete column of sections 4–6)
ETA = Param("eta", "rigid impact velocity ratio (1: undamped)", "–", 0.0, 1.0, default_text="1 − 1.5 sin²α′", undamped=1.0,
            long_name="rigid impact velocity ratio", neutral=0.9)
CBAR = Param("cbar", "spring-model damper c̄ (0: undamped)", "–", 0.0, math.inf, hi_open=True, default_text="eq. 17", undamped=0.0,
             long_name="spring-model damper cbar", neutral=0.05)
E_COLUMN = Param("E", "Young's modulus of the column", "Pa", 0.0, math.inf, True, True, default=30e9, units="Pa", option="--youngs-modulus")
RHO_COLUMN = Param("rho", "density of the column", "kg/m³", 0.0, math.inf, True, True, default=2500.0, units="kg m-3")
MASS_RATIO = Param("mass_ratio", "rocking frame: cap beam mass over all the columns' mass, γ = m_b/(N m)", "–", 0.0, math.inf,
                   hi_open=True, default=1.0, long_name="frame cap beam over columns mass ratio")
ZETA_COLUMN = Param("zeta", "column damping ratio, first fixed-base mode", "–", 0.0, math.inf, hi_open=True, default=0.01,
                    long_name="column damping ratio")


# -- model kinds -----------------------------------------------------------------------------------
class ModelKind(NamedTuple):
    """A model kind that scenes files name (`jaxrock.io.scenes_file`'s `model` column, the CLI's `--model`).

    Made by `register_model_kind`. `build(block, **parameters)` makes the model of one scene
    (traceable: batches vmap it), from the scene's `Block` and the values of its `parameters`
    (batch columns, e.g. `eta`, `cbar`, `E`; a parameter left out is not passed, so the builder's
    default applies).

    Attributes:
        name: the kind's name (lower case, no commas).
        build: the builder `(block, **parameters) → model`, or its name "module:function", imported
            when a model is first made (the built-in kinds are).
        parameters: the names of the parameters it takes (numeric ones and options such as
            `backbone`); default ().
        description: one line for help and tables; default "".
        params: the numeric parameters' declarations (`Param`), by name; default {}.
    """

    name: str
    build: Callable | str  # (jaxrock.Block, **parameters) → a jaxrock model
    parameters: tuple[str, ...] = ()
    description: str = ""
    params: dict = {}

    def model(self, block, **parameters):
        """The model of one scene: `build(block, **parameters)`.

        Arguments:
            block (Block): the scene's geometry.
            **parameters (float | Array): the kind's parameters given (the builder's defaults for the others).

        Returns:
            (AbstractModel): the model.
        """
        build = _resolve(*self.build.split(":")) if isinstance(self.build, str) else self.build
        return build(block, **parameters)


MODEL_KINDS: dict[str, ModelKind] = {}


def register_model_kind(name: str, build: Callable | str, parameters: tuple[str | Param, ...] = (), description: str = "") -> ModelKind:
    """Make a model kind nameable in scenes files (`jaxrock.io.scenes_file`) and the command line.

    A kind registered under a name already taken replaces it. Other packages register theirs from
    a module named by an entry point of the group "jaxrock.models" or by the variable
    `JAXROCK_PLUGINS` (`load_plugins`).

    Arguments:
        name: the kind's name, lower case, without commas.
        build: the builder `(block, **parameters) → model` (traceable: batches vmap it), or its name
            "module:function", imported when a model is first made.
        parameters: its numeric parameters as `Param`s (a built-in one, e.g. `ZETA_COLUMN`, or its
            own), its other options (`backbone`, `smoothing`) by name; default ().
        description: one line for help and tables; default "".

    Returns:
        the registered kind.

    Raises:
        JaxrockInputError: when `name` is empty, not lower case or holds a comma.

    Example:
        ```python
        def build(block, eta=None):
            return jaxrock.RigidModel(block, eta=eta, threshold=0.9)

        jaxrock.register_model_kind("rigid-09", build, (jaxrock.scene.ETA,), "rigid, overturned at 0.9 α′")
        ```
    """
    if not name or name != name.lower() or "," in name:
        raise JaxrockInputError(f"model kind {name!r}: a lower-case name without commas")
    params = {p.name: p for p in parameters if isinstance(p, Param)}
    names = tuple(p.name if isinstance(p, Param) else p for p in parameters)
    MODEL_KINDS[name] = kind = ModelKind(name, build, names, description, params)
    return kind


register_model_kind("rigid", "jaxrock.rigid.model:scenes_file_model", (ETA,), "Housner's rigid block (RM)")
register_model_kind("spring", "jaxrock.spring.model:quasi_rigid_scene", (CBAR, "backbone", "smoothing"),
                    "quasi-rigid spring model (SM), added masses")
register_model_kind("spring-flexible", "jaxrock.spring.model:flexible_scene", (CBAR, E_COLUMN, RHO_COLUMN, ZETA_COLUMN, "backbone", "smoothing"),
                    "spring model with an elastic column (concrete by default)")
# the frame's η is its own (`jaxrock.rigid.frame.frame_eta`), not a scene parameter: a scene's default η is Housner's
register_model_kind("frame", "jaxrock.rigid.frame:scenes_file_model", (MASS_RATIO,),
                    "rocking frame: rigid columns capped by a rigid beam (Makris & Vassiliou 2013)")
DEFAULT_MODEL = "rigid"


# Model kinds from other packages: the modules named by the entry points of `PLUGIN_GROUP` (a
# package's `[project.entry-points."jaxrock.models"]`) and by the environment variable `PLUGIN_ENV`
# (module names separated by commas), imported by the command line before it builds its options,
# each registering its kinds with `register_model_kind`.
PLUGIN_GROUP = "jaxrock.models"
PLUGIN_ENV = "JAXROCK_PLUGINS"


def load_plugins() -> list[str]:
    """Import the plugin modules (`PLUGIN_GROUP`, `PLUGIN_ENV`); returns one line per module that
    could not be imported (the command line refuses to start with it)."""
    import os
    from importlib.metadata import entry_points

    errors = []
    named = [(f"entry point {ep.name} ({ep.value})", ep.load) for ep in entry_points(group=PLUGIN_GROUP)]
    named += [(f"{PLUGIN_ENV} module {m.strip()!r}", lambda m=m.strip(): importlib.import_module(m))
              for m in os.environ.get(PLUGIN_ENV, "").split(",") if m.strip()]
    for what, load in named:
        try:
            load()
        except Exception as e:  # any failure of someone else's module: one line, the command refuses to start
            errors.append(f"{what} could not be loaded: {type(e).__name__}: {e}")
    return errors


def model_params() -> dict[str, Param]:
    """Every numeric model parameter of the registered kinds, by name (a name two kinds declare:
    the first kind's declaration)."""
    out: dict[str, Param] = {}
    for kind in MODEL_KINDS.values():
        for p in kind.params.values():
            out.setdefault(p.name, p)
    return out


UNDAMPED = {p.name: p.undamped for p in model_params().values() if p.undamped is not None}  # the value that dissipates nothing


def model_kinds() -> tuple[str, ...]:
    """The model kinds a scene may name (the built-in rigid, spring and spring-flexible, and any
    kind registered with `jaxrock.register_model_kind` since)."""
    return tuple(MODEL_KINDS)


def takes(parameter: str) -> tuple[str, ...]:
    """The model kinds that take a parameter."""
    return tuple(k.name for k in MODEL_KINDS.values() if parameter in k.parameters)


# -- pulse kinds and records -----------------------------------------------------------------------
# name → a class of jaxrock.excitation by name (eq. 28, eq. 29), or any callable (a_p, ω_p, **parameters) → excitation
PULSES: dict[str, str | Callable] = {}
PULSE_PARAMS: dict[str, dict[str, Param]] = {}  # name → its parameters beyond a_p and ω_p (the spectra's axes)


def register_pulse_kind(name: str, cls: str | Callable, parameters: tuple[Param, ...] = ()) -> None:
    """Make a pulse kind nameable: `pulse=` of spectra and sweeps, a scenes file's `pulse`, the CLI's `--pulse`.

    A kind registered under a name already taken replaces it.

    Arguments:
        name: the kind's name, lower case, without commas.
        cls: `cls(a_p, omega_p, **parameters)` makes one pulse (traceable: batches vmap it); a class
            of `jaxrock.excitation` may be named by its name (e.g. "SinePulse").
        parameters: its numeric parameters beyond a_p and ω_p as `Param`s (flags, scenes-file
            columns, sweep quantities); default ().

    Raises:
        JaxrockInputError: when `name` is empty, not lower case or holds a comma.

    Example:
        ```python
        jaxrock.register_pulse_kind("half-sine", lambda a_p, omega_p: jaxrock.SinePulse(a_p, omega_p, n_cycles=0.5))
        ```
    """
    if not name or name != name.lower() or "," in name:
        raise JaxrockInputError(f"pulse kind {name!r}: a lower-case name without commas")
    PULSES[name] = cls
    PULSE_PARAMS[name] = {p.name: p for p in parameters}


def pulse_kind_of(cls_name: str) -> str:
    """The pulse kind whose class is named `cls_name` ("RickerPulse" → "symmetric"); the name itself
    where no kind has that class."""
    for kind, cls in PULSES.items():
        if (cls if isinstance(cls, str) else getattr(cls, "__name__", "")) == cls_name:
            return kind
    return cls_name


N_CYCLES = Param("n_cycles", "cycles N of the sine pulse", "–", 0.5, 100.0, default=1.0, long_name="sine pulse cycles", step=0.5)
register_pulse_kind("symmetric", "RickerPulse")
register_pulse_kind("antisymmetric", "AntisymmetricRickerPulse")
register_pulse_kind("sine", "SinePulse", (N_CYCLES,))
VERTICAL_RATIO = Param("vertical_ratio", "vertical pulse: its peak over a_p (V/H), upwards; r·|a_p| < g", "–", 0.0, 5.0, lo_open=True,
                       default=0.5, long_name="vertical over horizontal peak ratio")
VERTICAL_FREQUENCY = Param("vertical_frequency", "vertical pulse: its frequency over ω_p", "–", 0.0, math.inf, True, True, default=2.0,
                           long_name="vertical over horizontal pulse frequency")
VERTICAL_PHASE = Param("vertical_phase", "vertical pulse: ω_p × its centre's delay", "rad", -math.inf, math.inf, True, True, default=0.0,
                       long_name="vertical pulse phase", units="rad")
register_pulse_kind("vertical", "ricker_with_vertical", (VERTICAL_RATIO, VERTICAL_FREQUENCY, VERTICAL_PHASE))
DEFAULT_PULSE = "symmetric"


def pulse_params() -> dict[str, Param]:
    """Every numeric parameter of the pulse kinds beyond a_p and ω_p, by name."""
    out: dict[str, Param] = {}
    for params in PULSE_PARAMS.values():
        for p in params.values():
            out.setdefault(p.name, p)
    return out


def pulse_takes(parameter: str) -> tuple[str, ...]:
    """The pulse kinds that take a parameter."""
    return tuple(k for k, params in PULSE_PARAMS.items() if parameter in params)
RECORD_ALIASES = ("elcentro", "el-centro", "el_centro")  # the packaged El Centro 1940 NS (`jaxrock.el_centro`)
# the other packaged records (jaxrock/data/records; sources in jaxrock/data/README.md): name → file
PACKAGED_RECORDS = {"elcentro_peknold": "elCentro_peknold.AT2", "arl360": "ARL360.at2", "b-elc000": "B-ELC000.AT2",
                    "a-tin000": "A-TIN000.AT2"}
BUILTIN_SUITE = "builtin"  # a suite of every packaged record (`jaxrock.read_records`)


def pulse_class(pulse) -> type:
    """The pulse class named `pulse` (`PULSES`), or `pulse` itself when it is a class."""
    if isinstance(pulse, str):
        if pulse not in PULSES:
            raise JaxrockInputError(f"pulse = {pulse!r}; valid: {', '.join(PULSES)}")
        cls = PULSES[pulse]
        return _resolve("jaxrock.excitation", cls) if isinstance(cls, str) else cls
    return pulse


def is_builtin_record(name: str) -> bool:
    """Whether `name` names one packaged record (`RECORD_ALIASES`, `PACKAGED_RECORDS`; any case)."""
    key = name.strip().lower()
    return key in RECORD_ALIASES or key in PACKAGED_RECORDS


def builtin_record_names() -> str:
    """The packaged records' names, for messages."""
    return ", ".join([RECORD_ALIASES[0], *PACKAGED_RECORDS])


# -- geometry --------------------------------------------------------------------------------------
# Least slenderness accepted (a 1000:1 column). Below it the rigid model's answers drift (θ/α off by
# 2.6e-4 at tanα = 1e-6 against 1e-4) and at 1e-8 the default scene rocks through 16,667 impacts
# to max_iterations; no rocking body of interest is that slender.
# full height 2h [m]: from 1e-12 to 1e12 m the dimensionless response was checked to be the same
# (issue 52's campaign); beyond, derived quantities (h², the inertia) overflow to NaN
HEIGHT_RANGE = (1e-12, 1e12)
TAN_ALPHA_MIN = 1e-3
MAX_REFINE = 40  # bisections of a boundary or a least scale: the step / 2^40 is below what a verdict resolves
MAX_ENSEMBLE = 1024  # perturbed runs per uncertain verdict (`jaxrock.analyses.suite.overturning_probability`)


# the scene's quantities beyond the model kinds' and pulse kinds' own (sweep axes, scenes-file columns)
HEIGHT = Param("height", "full height 2h of the column", "m", 0.0, math.inf, True, True, long_name="full height 2h", units="m")
TAN_ALPHA = Param("tan_alpha", "slenderness tanα = b/h", "–", TAN_ALPHA_MIN, 1.0, hi_open=True,
                  long_name="slenderness tan(alpha) = b/h")
TAN_ALPHA_BASE = Param("tan_alpha_base", "extended rigid base tanα′ = b′/h (paper section 5)", "–", TAN_ALPHA_MIN, 1.0, hi_open=True,
                       long_name="extended base slenderness tan(alpha') = b'/h")
SMOOTHING = Param("smoothing", "spring pre-yield rotation θs/α′", "–", 0.0, 1.0, True, True,
                  long_name="spring pre-yield rotation theta_s/alpha'")
SCALE = Param("scale", "factor on a record", "–", 0.0, math.inf, hi_open=True, default=1.0, long_name="record scale factor")
ACCEL_RATIO = Param("accel_ratio", "a_p/(g tanα′)", "–", 0.0, math.inf, True, True, long_name="a_p/(g tan alpha')")
OMEGA_RATIO = Param("omega_ratio", "ω_p/p′", "–", 0.0, math.inf, True, True, long_name="omega_p/p'")


def check_slenderness(height, tan_alpha, tan_alpha_base=None) -> None:
    """Refuse, in one line, a block's full height 2h outside `HEIGHT_RANGE` or a slenderness tanα
    (and the base's tanα′) outside [TAN_ALPHA_MIN, 1) (`jaxrock.Block.from_slenderness`'s checks)."""
    check_range("height (2h) [m]", height, *HEIGHT_RANGE)
    TAN_ALPHA.check(tan_alpha)
    if tan_alpha_base is not None:
        TAN_ALPHA_BASE.check(tan_alpha_base)


# -- spring backbones ------------------------------------------------------------------------------
BACKBONES = {"bilinear": "Bilinear", "tanh": "Tanh"}  # name → a class of jaxrock.spring.base_spring (its `name`)
# Backbone and θs/α′: the study of benchmarks/bench_backbone.py (its results file): 192 quasi-rigid
# and 48 flexible (concrete, 10 elements) scenes, tanα 0.05–0.35, 2h 1–50 m, ω_p/p′ 1–15,
# a_p/(g tanα) 1–8, both pulses, and new seeded scenes with records; error of max|θ|/α against the
# sharp limit (bilinear, θy = 1e-6 α). The default for both models, the bilinear backbone at
# θy = 1e-5 α (the paper's rigid-plastic spring as OpenSees' multilinear one), is within 8.3e-4
# wherever the limit is settled; tanh at θs = 1e-4 α, the default before, left up to 4.9e-2
# (quasi-rigid) and 3.9e-2 (flexible). Its kinks are events of the diffrax integrator
# (`SpringIntegrator`) and step ends of generalized-α, so derivatives through it are the motion's
# (`bench_backbone.py --part gradients`).
DEFAULT_BACKBONE = {"quasi-rigid": "bilinear", "flexible": "bilinear"}  # per spring model
"""The base spring's default backbone per spring model ("quasi-rigid", "flexible"): "bilinear" for both.

The bilinear backbone at θy = 1e-5 α′ (the paper's rigid-plastic spring as OpenSees' multilinear one)
is within 8.3e-4 in max |θ|/α of the sharp limit wherever that limit is settled (benchmarks/bench_backbone.py:
192 quasi-rigid and 48 flexible scenes); tanh at θs = 1e-4 α′, the default before, left up to 4.9e-2.
"""
DEFAULT_SMOOTHING = {"bilinear": 1e-5, "tanh": 1e-4}  # θs/α′ per backbone
"""The default pre-yield rotation θs/α′ of the base spring, per backbone: bilinear 1e-5, tanh 1e-4.

A spring model given no `smoothing` takes its backbone's; a backbone without an entry needs one, in (0, 1).
"""


def default_spring(flexible: bool, backbone=None, smoothing=None):
    """(backbone, smoothing) of a spring model, quasi-rigid or `flexible`: the defaults where None
    (`DEFAULT_BACKBONE` by model, `DEFAULT_SMOOTHING` by backbone)."""
    if backbone is None:
        backbone = DEFAULT_BACKBONE["flexible" if flexible else "quasi-rigid"]
    if smoothing is None:
        smoothing = DEFAULT_SMOOTHING.get(backbone if isinstance(backbone, str) else getattr(backbone, "name", None))
        if smoothing is None and (not isinstance(backbone, str) or backbone in BACKBONES):
            raise JaxrockInputError(f"smoothing: no default for the backbone {backbone!r}; give one in (0, 1)")
    return backbone, smoothing


# -- ratios ----------------------------------------------------------------------------------------
# the spectra's axes (rocking α′, p′), converted by `jaxrock.geometry.pulse_of_ratios` / `ratios_of_pulse`
AXES = {"accel_ratio": "a_p/(g tan alpha)", "omega_ratio": "omega_p/p"}


# -- concrete defaults -----------------------------------------------------------------------------
CONCRETE_E = E_COLUMN.default  # Pa
CONCRETE_RHO = RHO_COLUMN.default  # kg/m³
CONCRETE_ZETA = ZETA_COLUMN.default  # column damping ratio at its first fixed-base mode


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
    pulses = " / ".join(f"`{k}`" for k in PULSES)
    return (
        Parameter("height", "m", "full height 2h of the column", "> 0, required"),
        Parameter("tan_alpha", "–", "slenderness tanα = b/h", f"[{TAN_ALPHA_MIN:g}, 1); give it or `width`"),
        Parameter("width", "m", "full width 2b (instead of `tan_alpha`)", "> 0, width/height < 1"),
        Parameter("tan_alpha_base", "–", "extended rigid base tanα′ = b′/h (paper section 5)", "[tanα, 1); default: no base"),
        Parameter("model", "–", ", ".join(f"`{k.name}` ({k.description})" for k in MODEL_KINDS.values()),
                  f"default `{DEFAULT_MODEL}`"),
        Parameter("pulse", "–", f"a pulse kind ({pulses}: the Ricker pulses of eqs. 28 and 29, a sine pulse of `n_cycles`), `{RECORD_ALIASES[0]}` (the packaged El Centro 1940 NS), or a record "
                  "file path (`.AT2` or two-column text; relative to the scenes file, else to the working directory)",
                  f"default `{DEFAULT_PULSE}`"),
        Parameter("a_p", "m/s²", "pulse amplitude (any sign, ≠ 0)", "pulses: give it or `accel_ratio`"),
        Parameter("accel_ratio", "–", AXES["accel_ratio"].replace("alpha", "α′"), "≠ 0"),
        Parameter("omega_p", "rad/s", "pulse frequency", "> 0; pulses: give it or `omega_ratio`"),
        Parameter("omega_ratio", "–", AXES["omega_ratio"].replace("omega", "ω") + "′", "> 0"),
        Parameter("scale", "–", "factor on a record", "≥ 0, default 1 (records only)"),
        *(Parameter(p.name, p.unit, p.meaning, f"{p.range_text}, default {p.default_text or format(p.default, 'g')} "
                    f"(pulse {_kinds(pulse_takes(p.name))})") for p in pulse_params().values()),
        *(Parameter(p.name, p.unit, p.meaning, f"{p.range_text}, default {p.default_text or format(p.default, 'g')} "
                    f"({_kinds(takes(p.name))})") for p in model_params().values()),
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


# -- sweeps ----------------------------------------------------------------------------------------
def sweep_quantities(kind: str | None = None, pulse: str | None = None) -> dict[str, tuple]:
    """What a sweep can vary, in its store's dimension order (outermost first): quantity → (long
    name, units, valid range (lo, hi, lo_open, hi_open); None for the record names). The model
    parameters are the registered kinds' (`model_params`), a kind registered since included; a
    parameter that model kind `kind` (pulse kind `pulse`) declares is its own declaration's (a name
    two kinds share, e.g. `zeta`, has each kind's meaning and range)."""
    own = {**MODEL_KINDS[kind].params} if kind in MODEL_KINDS else {}
    own.update(PULSE_PARAMS.get(pulse, {}) if isinstance(pulse, str) else {})
    params = {**model_params(), **pulse_params()}
    described = {name: (p.long_name or p.meaning, p.units, p.range) for name, p in {**params, **own}.items() if name in params}
    scene = lambda *ps: {p.name: (p.long_name or p.meaning, p.units, p.range) for p in ps}
    return {
        "record": ("ground-motion record", "", None),
        **scene(HEIGHT, TAN_ALPHA, TAN_ALPHA_BASE),
        **{name: described[name] for name in model_params()},
        **scene(SMOOTHING, SCALE),
        **{name: described[name] for name in pulse_params()},
        **scene(ACCEL_RATIO, OMEGA_RATIO),
    }
