"""The spring model: the paper's parameters of one scene (geometry, damper, backbone, smoothing,
added masses; a flexible column's material, damping and mesh) as a value, with its default
integrator, its static pushover and the levels its runs are watched against. Two final kinds of
`AbstractSpringModel`: `QuasiRigidSpringModel` and `FlexibleSpringModel` (with its discretised
column's period and Rayleigh coefficients); `SpringModel(block, column=None, ...)` makes either.
What a run integrates is its assembled system (`jaxrock.spring.system`); the package docstring
(`jaxrock.spring`) describes the model."""

from __future__ import annotations

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import _linalg
from .._validate import JaxrockInputError, Limit, check_limits
from ..bookkeeping import Watch
from ..excitation import AbstractExcitation
from ..geometry import G, Block
from ..model import AbstractModel, AbstractSpringIntegrator, check_autodiff
from ..scene import CONCRETE_E, CONCRETE_RHO, CONCRETE_ZETA
from . import beam
from ..scene import default_spring
from .base_spring import AbstractBackbone, as_backbone
from .column import Column, cbar_eq17, pushover_eq9
from .diffrax_integrator import SpringIntegrator
from .checked import Checked
from .generalized_alpha import GeneralizedAlpha
from .system import ENERGY_FIELDS, HISTORY_FIELDS, QuasiRigidSystem, SpringSystem, assemble



class AbstractSpringModel(AbstractModel):
    """The paper's spring model (SM): a column on a rigid-plastic spring with its damper at the base.

    The damper is eq. 18's. Two final kinds (issue 57): `QuasiRigidSpringModel`, the one-DOF body,
    and `FlexibleSpringModel`, a corotational Euler–Bernoulli column; `SpringModel(block,
    column=None, ...)` makes either. Array fields are vmappable/differentiable leaves; the fields
    marked static are structure.

    What the default backbone and smoothing leave, over `benchmarks/bench_backbone.py`'s scenes: the
    bilinear at 1e-5 within 8.3e-4 of α of the rigid-plastic limit wherever that limit is settled
    (quasi-rigid and flexible); with the flexible default integrator
    `Checked(GeneralizedAlpha(1e-5, 1e-5))` the total error (spring and steps) is 4.9e-5 – 7.0e-5
    median, 6.6e-3 – 2.5e-2 at most (tanh at 1e-4: 5.5e-4 – 7.9e-4, 2.4e-2 – 3.5e-2), the largest,
    in a probe, on runs it flags `inaccurate` (docs/numerics.md); `Checked(GeneralizedAlpha(1e-6,
    1e-6))` came near 1e-3 there at about twice the cost. Derivatives through the kinks are the
    motion's with either integrator (both end their steps on the kinks).

    Attributes:
        block: geometry (`Block`, with `b_base > b` for an extended rigid base, section 5).
        added_masses: (static) whether ΔI = I′o − (4/3) m h² is added (SPEC; paper section 3.3).
        cbar: damper coefficient c̄ [-], ≥ 0 (None at construction: eq. 17 with α′; always an array).
        backbone: (static) the spring's moment–rotation curve, `Bilinear` or `Tanh` (default
            `DEFAULT_BACKBONE`: the bilinear, the paper's rigid-plastic spring, for both models).
        smoothing: θs/α′, the backbone's pre-yield rotation (the bilinear yield rotation θy, or the
            tanh's θs), in (0, 1); default `DEFAULT_SMOOTHING` (1e-5 bilinear, 1e-4 tanh).
        fixed_base: (static) base rotation clamped (section 6).
        threshold: overturned when |θ| ≥ threshold·α′, in (0, 1] (an array).
    """

    block: eqx.AbstractVar[Block]
    cbar: eqx.AbstractVar[Float[Array, ""]]
    smoothing: eqx.AbstractVar[Float[Array, ""]]
    threshold: eqx.AbstractVar[Float[Array, ""]]
    backbone: eqx.AbstractVar[AbstractBackbone]
    added_masses: eqx.AbstractVar[bool]
    fixed_base: eqx.AbstractVar[bool]

    def _set_spring(self, block, flexible: bool, added_masses, cbar, backbone, smoothing, fixed_base, threshold):
        """The shared fields, set by each kind's `__init__`."""
        if not isinstance(block, Block):
            raise JaxrockInputError(f"block must be a jaxrock.Block, got {type(block).__name__}")
        self.block = block
        self.added_masses = bool(added_masses)
        self.cbar = cbar_eq17(block.alpha_r) if cbar is None else jnp.asarray(cbar, dtype=float)
        backbone, smoothing = default_spring(flexible, backbone, smoothing)
        self.backbone = as_backbone(backbone)
        self.smoothing = jnp.asarray(smoothing, dtype=float)
        self.fixed_base = bool(fixed_base)
        self.threshold = jnp.asarray(threshold, dtype=float)

    def _spring_limits(self) -> tuple[Limit, ...]:
        return (Limit("smoothing (theta_s/alpha)", self.smoothing, 0.0, 1.0, lo_open=True, hi_open=True),
                Limit("threshold (overturning |theta|/alpha)", self.threshold, 0.0, 1.0, lo_open=True),
                Limit("cbar (damper coefficient)", self.cbar, 0.0, math.inf, hi_open=True))

    @property
    @abc.abstractmethod
    def flexible(self) -> bool:
        """Whether the column deforms (`FlexibleSpringModel`)."""

    @abc.abstractmethod
    def mass(self):
        """Column mass m [kg] (per unit out-of-plane thickness for the default section)."""

    # -- AbstractModel --------------------------------------------------------------------------
    def default_integrator(self, autodiff: str | None = None) -> "SpringIntegrator | Checked":
        """The integrator a run takes by default: the work–precision choice.

        Chosen by `jaxrock work-precision` and `benchmarks/bench_spring.py`; the measured errors and
        costs, and the alternatives, are in docs/numerics.md:

        - quasi-rigid → explicit Tsit5 at rtol = atol = 1e-10 after the exact pre-yield phase
          (`jaxrock.spring.rest`: until the block first yields, its linear equation is stepped
          exactly on a fixed grid), reverse-mode differentiable (which the calibration of c̄
          needs). Chosen by `python benchmarks/bench_backbone.py --part tolerance` (the default
          bilinear spring, error in max θ/α against Tsit5 1e-12 over the backbone study's scenes;
          results/bench_backbone_tolerance.txt): on 248 pulses it leaves ≤ 4e-8 at 1.7–2.2 ms/scene,
          where Tsit5 through the pre-yield phase left 1.7e-7 at 1e-11 and 5–6 ms (its steps went to
          the stiff pre-yield spring's ringing); 1e-11 leaves ≤ 3e-9 at 1.3x the cost. On 24 El
          Centro scenes 2.2e-5 (median 6.5e-10; 1e-11: 1.6e-6 at 1.3x the cost; pass
          `SpringIntegrator(1e-11, 1e-11, solver="tsit5", max_steps=200_000)` for it).
          `GeneralizedAlpha(1e-6, 1e-6)` is ~1e-3 off in θ/α;
        - flexible → `Checked(GeneralizedAlpha(1e-5, 1e-5))`, ρ∞ = 0.9, accuracy 1e-2 in max θ/α′:
          its status is `inaccurate` where a companion run at 1e-4 differs by more (a stiff spring
          or column, where the local tolerance does not bound the global error: `jaxrock.spring.
          checked`); the companion's looser steps on top of the run's (a batch runs the two apart).

        Arguments:
            autodiff: "reverse" or "forward" (`AbstractModel.default_integrator`); default None:
                reverse for the quasi-rigid spring, forward for the flexible column (`jax.jacfwd`;
                `simulate` under `jax.grad` takes the reverse-mode form, the same values).

        Returns:
            A `SpringIntegrator` (quasi-rigid) or a `Checked` `GeneralizedAlpha` (flexible).

        Raises:
            JaxrockInputError: when `autodiff` is neither None, "reverse" nor "forward".
        """
        if autodiff is not None:
            check_autodiff(autodiff)
        return self._default_integrator(autodiff)

    @abc.abstractmethod
    def _default_integrator(self, autodiff: str | None):
        """`default_integrator` of this kind (`autodiff` checked)."""

    @property
    def history_fields(self) -> tuple[str, ...]:
        return HISTORY_FIELDS

    # -- inertia, pushover -------------------------------------------------------------------------
    def total_inertia(self):
        """Itot about the base centre: (4/3) m h² (eq. 11), or I′o with added masses."""
        m, blk = self.mass(), self.block
        return m * blk.inertia_ratio if self.added_masses else (4.0 / 3.0) * m * blk.h**2

    def pushover(self, theta):
        """The model's own static pushover: the lateral load F/(m g) that holds the column at `theta`.

        The load is applied as a uniform lateral acceleration of the column's mass (for a rigid
        column: F at mid-height, eq. 9's load). Solved by Newton on the static equilibrium
        ∇V(q) = (F/m) r with θ prescribed (r: the ground load vector; gravity P-Δ and, for a flexible
        column, its bending included). Quasi-rigid: (M(θ)/(m g h) − sinθ)/cosθ, which is eq. 9,
        tanα/cosθ − tanθ, once the spring has yielded (|θ| beyond its pre-yield band).

        Arguments:
            theta (float | Array): base rotation θ [rad] (any shape).

        Returns:
            (Array): F/(m g) [-], the shape of `theta`.

        Raises:
            JaxrockInputError: when the model has a fixed base (`fixed_base=True`).
        """
        if self.fixed_base:
            raise JaxrockInputError("pushover: a fixed-base column (fixed_base=True) does not rock")
        return _pushover(self.system(), jnp.asarray(theta, dtype=float))

    def system(self, track_energy: bool = False) -> SpringSystem:
        """The assembled system of this model (`QuasiRigidSystem`, `FlexibleSystem`), its arrays computed once.

        Arguments:
            track_energy: integrate the work integrals (`system.WORK_FIELDS`: damper, Rayleigh, input)
                alongside; default False.

        Returns:
            The `SpringSystem`.
        """
        return assemble(self, track_energy)

    # -- public pieces for calibration / custom solves --------------------------------------------
    def vector_field(self, t, y, excitation: AbstractExcitation):
        """dy/dt of the first-order form y = [q, v] (q[0] = θ).

        Assembles the system on each call; inside loops prefer `self.system().vector_field` or
        `SpringIntegrator.solve`.

        Arguments:
            t (float): time [s].
            y (Array): the state [q, v].
            excitation: the ground motion (`AbstractExcitation`).

        Returns:
            (Array): dy/dt, the shape of `y`.
        """
        return self.system().vector_field(t, y, excitation)

    def initial_state(self, theta0=0.0, theta_dot0=0.0):
        """The state y at rest (gravity-preloaded column) rotated rigidly by θ0 with angular velocity ω0.

        Arguments:
            theta0 (float | Array): initial base rotation θ0 [rad]; default 0.
            theta_dot0 (float | Array): initial angular velocity ω0 [rad/s]; default 0.

        Returns:
            (Array): y = [q, v].
        """
        return self.system().initial_state(theta0, theta_dot0)

    def base_rotation(self, y):
        return y[0]

    def static_potential(self, theta):
        """The one-DOF model's own exact potential energy at zero velocity [J].

        For the tanh backbone My θs log cosh(θ/θs) − m g h (1 − cosθ) (the backbone's potential in
        general; → SPEC's E(θ) = m g R (sinα|θ| − cosα(1 − cosθ)) as θs → 0). For the flexible model
        this is the rigidly rotated column's value (its deformation adds only strain energy).

        Arguments:
            theta (float | Array): base rotation θ [rad].

        Returns:
            (Array): The potential [J].
        """
        return self.system().rigid_potential(theta)

    def mechanical_energy(self, y):
        return self.system().mechanical_energy(y)

    # -- run ------------------------------------------------------------------------------------
    def stepper(self, integrator, save=None, t1=None):
        """The run as an `AbstractStepper` of `integrator`, on the system assembled here once.

        Energy integrals are tracked when `save` asks for energies.

        Arguments:
            integrator (AbstractSpringIntegrator): the spring integrator (`SpringIntegrator`, `GeneralizedAlpha`,
                `Checked`).
            save (Save | None): what a history records (`Save`); default None: a summary run.
            t1 (float | None): end of the run [s]; default None (`run_end`).

        Returns:
            (AbstractStepper): The `AbstractStepper`.

        Raises:
            JaxrockInputError: when `integrator` is not a spring integrator.
        """
        if not isinstance(integrator, AbstractSpringIntegrator):
            raise JaxrockInputError(f"SpringModel needs a SpringIntegrator, GeneralizedAlpha or Checked, got {type(integrator).__name__}")
        fields = () if save is None else save.fields
        system = self.system(track_energy=any(f in ENERGY_FIELDS for f in fields))
        return integrator.stepper(self, system, save, t1)

    @property
    def overturn_rotation(self):
        """|θ| [rad] at which the body has overturned: threshold·α′ (+inf for a fixed base)."""
        return jnp.inf if self.fixed_base else self.threshold * self.block.alpha_r

    def run_end(self, system, excitation, save=None, t1=None):
        """The latest end of a run: `t1` (default the last save time) for a history; for a summary
        `t1`, or 20 rocking periods 2π/p′ after the excitation."""
        if save is not None:
            return save.ts[-1] if t1 is None else t1
        t_end = excitation.t_end
        return t_end + 20 * 2 * jnp.pi / system.p_r if t1 is None else jnp.maximum(t1, t_end)

    def watch(self, system: SpringSystem) -> Watch:
        """The levels a run is watched against (`jaxrock.bookkeeping`): overturning at
        `overturn_rotation`, uplift beyond the spring's pre-yield band (`SpringSystem.theta_up`)."""
        alpha_r = self.block.alpha_r
        return Watch(alpha=alpha_r, threshold=self.threshold,
                     overturn=self.overturn_rotation, uplift=system.theta_up)


class QuasiRigidSpringModel(AbstractSpringModel):
    """The one-DOF quasi-rigid spring model (paper sections 3–4).

    A rigid column of concrete's density on the spring (`AbstractSpringModel`'s fields; no column,
    no column damping). `SpringModel(block)` makes it.

    Arguments:
        block: the column's geometry (`Block`).
        added_masses: whether the added rotational inertia ΔI = I′o − (4/3) m h² is included (SPEC;
            paper section 3.3); default True.
        cbar (float | Array | None): damper coefficient c̄ [-], ≥ 0; default None: eq. 17, 0.02 (α′/0.1)² (`cbar_eq17`).
        backbone: the spring's moment–rotation curve, `Bilinear`, `Tanh` or their names "bilinear",
            "tanh"; default None: `DEFAULT_BACKBONE` (the bilinear).
        smoothing (float | Array | None): θs/α′, the backbone's pre-yield rotation, in (0, 1); default None: `DEFAULT_SMOOTHING`
            for the backbone (1e-5 bilinear, 1e-4 tanh).
        fixed_base: clamp the base rotation (section 6); default False.
        threshold (float | Array): overturned when |θ| ≥ threshold·α′ [-], in (0, 1]; default 1.

    Raises:
        JaxrockInputError: when `block` is not a `Block`, the backbone is unknown, or `cbar`,
            `smoothing` or `threshold` is outside its range.

    Example:
        ```python
        import jaxrock
        model = jaxrock.QuasiRigidSpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), cbar=0.02)
        ```
    """

    block: Block
    cbar: Float[Array, ""]
    smoothing: Float[Array, ""]
    threshold: Float[Array, ""]
    backbone: AbstractBackbone = eqx.field(static=True)
    added_masses: bool = eqx.field(static=True)
    fixed_base: bool = eqx.field(static=True)

    def __init__(self, block: Block, *, added_masses: bool = True, cbar=None, backbone: AbstractBackbone | str | None = None,
                 smoothing=None, fixed_base: bool = False, threshold=1.0):
        self._set_spring(block, False, added_masses, cbar, backbone, smoothing, fixed_base, threshold)
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        return self._spring_limits()

    @property
    def flexible(self) -> bool:
        return False

    def mass(self):
        return CONCRETE_RHO * 2 * self.block.b * 2 * self.block.h

    def first_period(self):
        """Refused: the one-DOF body has no column to vibrate."""
        raise JaxrockInputError("first_period: the quasi-rigid SM (column=None) has no column; give a Column")

    def _default_integrator(self, autodiff):
        # 20,000 steps (the class default) ended the 40-s packaged records B-ELC000 and A-TIN000
        # (dt 0.005 s) in max_steps at every factor, the block at rest on its ringing spring
        return SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5", max_steps=200_000, autodiff=autodiff or "reverse")


class FlexibleSpringModel(AbstractSpringModel):
    """The spring model with a corotational Euler–Bernoulli column (paper sections 5–6).

    Beyond `AbstractSpringModel`'s fields it holds the `column`, its damping ratio `zeta` and its
    mesh `n_elements` (static). The column's damping is stiffness-proportional Rayleigh damping
    (`rayleigh`) set for ζ at the first fixed-base period of the discretised column *with its added
    rotational masses* (`first_period`; they lengthen it a little, `tests/test_spring.py`).
    `SpringModel(block, column)` makes it.

    Arguments:
        block: the column's geometry (`Block`).
        column: the column's material and section (`Column`: E, ρ, optional A, I).
        added_masses: whether the added rotational inertia ΔI = I′o − (4/3) m h² is included (SPEC;
            paper section 3.3); default True.
        cbar (float | Array | None): damper coefficient c̄ [-], ≥ 0; default None: eq. 17, 0.02 (α′/0.1)² (`cbar_eq17`).
        backbone: the spring's moment–rotation curve, `Bilinear`, `Tanh` or their names "bilinear",
            "tanh"; default None: `DEFAULT_BACKBONE` (the bilinear).
        smoothing (float | Array | None): θs/α′, the backbone's pre-yield rotation, in (0, 1); default None: `DEFAULT_SMOOTHING`
            for the backbone (1e-5 bilinear, 1e-4 tanh).
        zeta (float | Array): column damping ratio ζ [-], ≥ 0; default `CONCRETE_ZETA` (0.01).
        n_elements: number of column elements, an integer ≥ 1; default 10.
        fixed_base: clamp the base rotation (section 6); default False.
        threshold (float | Array): overturned when |θ| ≥ threshold·α′ [-], in (0, 1]; default 1.

    Raises:
        JaxrockInputError: when `block` is not a `Block`, `column` is not a `Column`, `n_elements` is
            not an integer ≥ 1, the backbone is unknown, or a value is outside its range.

    Example:
        ```python
        import jaxrock
        block = jaxrock.Block.from_slenderness(50.0, 0.1)
        model = jaxrock.FlexibleSpringModel(block, jaxrock.Column.concrete(), n_elements=8)
        model.first_period()  # T₁ [s] of the discretised column
        ```
    """

    block: Block
    column: Column
    cbar: Float[Array, ""]
    smoothing: Float[Array, ""]
    zeta: Float[Array, ""]
    threshold: Float[Array, ""]
    backbone: AbstractBackbone = eqx.field(static=True)
    added_masses: bool = eqx.field(static=True)
    n_elements: int = eqx.field(static=True)
    fixed_base: bool = eqx.field(static=True)

    def __init__(self, block: Block, column: Column, *, added_masses: bool = True, cbar=None,
                 backbone: AbstractBackbone | str | None = None, smoothing=None, zeta=CONCRETE_ZETA, n_elements: int = 10,
                 fixed_base: bool = False, threshold=1.0):
        if not isinstance(column, Column):
            raise JaxrockInputError(f"column must be a jaxrock Column or None, got {type(column).__name__}")
        if not isinstance(n_elements, int) or isinstance(n_elements, bool) or n_elements < 1:
            raise JaxrockInputError(f"n_elements = {n_elements!r}: must be an integer >= 1")
        self._set_spring(block, True, added_masses, cbar, backbone, smoothing, fixed_base, threshold)
        self.column = column
        self.zeta = jnp.asarray(zeta, dtype=float)
        self.n_elements = n_elements
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        return (*self._spring_limits(), Limit("zeta (column damping ratio)", self.zeta, 0.0, math.inf, hi_open=True),
                *self.column.limits())

    @property
    def flexible(self) -> bool:
        return True

    def mass(self):
        A, _ = self.column.section(self.block)
        return self.column.rho * A * 2 * self.block.h

    def _default_integrator(self, autodiff):
        return Checked(GeneralizedAlpha(rtol=1e-5, atol=1e-5, autodiff=autodiff or "forward"))

    def rotational_masses(self):
        """Rotational inertia at the n + 1 column nodes: ΔI/(n + 1) with the added masses, else the
        section's rotary inertia ρ I L_trib (keeps M regular; Rayleigh beam)."""
        blk, n = self.block, self.n_elements
        if self.added_masses:
            return jnp.full(n + 1, (self.total_inertia() - (4.0 / 3.0) * self.mass() * blk.h**2) / (n + 1))
        _, I = self.column.section(blk)
        le = 2 * blk.h / n
        return self.column.rho * I * le * jnp.concatenate([jnp.full(1, 0.5), jnp.ones(n - 1), jnp.full(1, 0.5)])

    def first_period(self):
        """First fixed-base period T₁ [s] of the discretised column with the model's rotational masses.

        Base rotation clamped, no gravity: the period ζ refers to (eq. 21 is the bare solid column's).
        """
        A, I = self.column.section(self.block)
        E = self.column.E
        return beam.first_period(self.block.h, self.n_elements, self.mass(), E * A, E * I, self.rotational_masses())

    def rayleigh(self):
        """Rayleigh coefficients (a₀, a₁) of the column, C = a₀ M + a₁ K on its deformations:
        stiffness proportional, a₀ = 0 and a₁ = ζ T₁/π (ζ = a₁ ω₁/2 at T₁ = `first_period`)."""
        return jnp.zeros(()), self.zeta * self.first_period() / jnp.pi


def SpringModel(block: Block, column: Column | None = None, *, added_masses: bool = True, cbar=None,
                backbone: AbstractBackbone | str | None = None, smoothing=None, zeta=None, n_elements: int | None = None,
                fixed_base: bool = False, threshold=1.0) -> AbstractSpringModel:
    """The paper's spring model of `block`, quasi-rigid or with a flexible column.

    Quasi-rigid (`QuasiRigidSpringModel`) without a `column`, flexible (`FlexibleSpringModel`)
    with one. `zeta` and `n_elements` belong to a column: without one they act on nothing and are
    not kept (as before the split, so that code written for either kind, e.g.
    `SpringModel(block, column, n_elements=4)` with `column` None, runs unchanged).

    Arguments:
        block: the column's geometry (`Block`).
        column: the flexible column (`Column`); default None: the quasi-rigid model.
        added_masses: whether the added rotational inertia ΔI = I′o − (4/3) m h² is included (SPEC;
            paper section 3.3); default True.
        cbar (float | Array | None): damper coefficient c̄ [-], ≥ 0; default None: eq. 17, 0.02 (α′/0.1)² (`cbar_eq17`).
        backbone: the spring's moment–rotation curve, `Bilinear`, `Tanh` or their names "bilinear",
            "tanh"; default None: `DEFAULT_BACKBONE` (the bilinear).
        smoothing (float | Array | None): θs/α′, the backbone's pre-yield rotation, in (0, 1); default None: `DEFAULT_SMOOTHING`
            for the backbone (1e-5 bilinear, 1e-4 tanh).
        zeta (float | Array | None): column damping ratio ζ [-], ≥ 0; default None: `CONCRETE_ZETA` (0.01). Flexible only.
        n_elements: number of column elements, an integer ≥ 1; default None: 10. Flexible only.
        fixed_base: clamp the base rotation (section 6); default False.
        threshold (float | Array): overturned when |θ| ≥ threshold·α′ [-], in (0, 1]; default 1.

    Returns:
        The model, a `QuasiRigidSpringModel` or a `FlexibleSpringModel`.

    Raises:
        JaxrockInputError: when `block` is not a `Block`, `column` is neither None nor a `Column`,
            `n_elements` is not an integer ≥ 1, the backbone is unknown, or a value is outside its range.

    Example:
        ```python
        import jaxrock
        block = jaxrock.Block.from_slenderness(50.0, 0.1)
        rigid = jaxrock.SpringModel(block)  # quasi-rigid, one DOF
        flexible = jaxrock.SpringModel(block, jaxrock.Column.concrete(), zeta=0.02)
        sol = jaxrock.simulate(rigid, jaxrock.RickerPulse(2.0, 3.0))
        ```
    """
    if column is None:
        return QuasiRigidSpringModel(block, added_masses=added_masses, cbar=cbar, backbone=backbone, smoothing=smoothing,
                                     fixed_base=fixed_base, threshold=threshold)
    return FlexibleSpringModel(block, column, added_masses=added_masses, cbar=cbar, backbone=backbone, smoothing=smoothing,
                               zeta=CONCRETE_ZETA if zeta is None else zeta, n_elements=10 if n_elements is None else n_elements,
                               fixed_base=fixed_base, threshold=threshold)


@eqx.filter_jit
def _pushover(system: SpringSystem, theta):
    """`SpringModel.pushover` on the assembled system (compiled once per column structure)."""
    if isinstance(system, QuasiRigidSystem):
        f = lambda th: jax.grad(system.potential)(jnp.atleast_1d(th))[0] / (system.m * G * system.h * jnp.cos(th))
        return jnp.vectorize(f)(theta)
    r = system.r * G  # generalized force of a unit lateral acceleration ratio (F/(m g) = 1)
    grad_v = jax.grad(system.potential)
    scale = jnp.tile(jnp.array([1.0, 1.0, 0.0]), system.n) * (system.h - 1.0) + 1.0  # h for translations

    def one(th):
        q0 = system.initial_state(th)[: system.ndof]
        lam0 = pushover_eq9(th, system.alpha_r)

        def residual(x):
            return grad_v(q0.at[1:].add(x[:-1] * scale)) - x[-1] * r

        x = jnp.concatenate([jnp.zeros(system.ndof - 1), jnp.atleast_1d(lam0)])
        for _ in range(8):  # Newton: quadratic from the rigidly rotated, preloaded column
            x = x - _linalg.solve(jax.jacfwd(residual)(x), residual(x))
        return x[-1]

    return jnp.vectorize(one)(theta)


def quasi_rigid_scene(block: Block, cbar=None, backbone=None, smoothing=None) -> QuasiRigidSpringModel:
    """A scenes file's quasi-rigid spring model (added masses; default damper, backbone, smoothing):
    the builder of the model kind "spring" (`jaxrock.scene.MODEL_KINDS`)."""
    return QuasiRigidSpringModel(block, cbar=cbar, backbone=backbone, smoothing=smoothing)


def flexible_scene(block: Block, cbar=None, E=None, rho=None, zeta=None, backbone=None, smoothing=None) -> FlexibleSpringModel:
    """A scenes file's flexible spring model, a concrete column unless E, ρ, ζ are given: the
    builder of the model kind "spring-flexible" (`jaxrock.scene.MODEL_KINDS`)."""
    column = Column(CONCRETE_E if E is None else E, CONCRETE_RHO if rho is None else rho)
    return FlexibleSpringModel(block, column, zeta=CONCRETE_ZETA if zeta is None else zeta, cbar=cbar,
                               backbone=backbone, smoothing=smoothing)
