"""The nonlinear-elastic, viscously damped spring model (SM) of the paper (sections 3–6).

Two scenes share one model value, `SpringModel`:

- quasi-rigid (``column=None``): the one-DOF rigid SM, eq. 10 with the damper (SPEC)
  ``Itot θ̈ + c θ̇ + M(θ) − m g h sinθ = −m üg h cosθ``, ``h = R cosα``; no mesh is built.
- flexible (``column=Column(...)``): a corotational Euler–Bernoulli column of ``n_elements``
  elements (`jaxrock.beam`) on the rotational spring, gravity preloaded, stiffness-proportional
  Rayleigh damping on the column's deformation (section 4).

Base spring (section 3, Figure 2 right): nonlinear elastic (it unloads along its loading path),
rigid-plastic in the limit, yield moment ``My = m g R′ sinα′ = m g b′`` (b′ = b for a plain
block), with a finite pre-yield rotation ``θs = smoothing · α′`` (stiffness ``My/θs``): the
bilinear backbone, linear to θy = θs then flat at My (the paper's), or ``M = My tanh(θ/θs)``
(`jaxrock.backbone`; the potential is the backbone's integral). Damper in parallel:
``c = c̄ m g^0.5 R′^1.5`` (eqs. 17–18), by default with ``c̄ = 0.02 (α′/0.1)²`` (eq. 17). For an
extended base the rocking quantities α′, R′ are used in eq. 17/18, because the damper stands for the impact losses at the base's corners, which are
governed by α′ (the paper: "computed using Equation (17)"); give ``cbar`` to override.

Inertia: without added masses ``Itot = (4/3) m h²`` (the column about its base centre, eq. 11);
with added masses ``Itot = I′o = m·Block.inertia_ratio`` (exact parallel-axis value, = (4/3) m R²
for a plain block), i.e. ``ΔI = I′o − (4/3) m h²`` spread evenly over the ``n + 1`` column nodes.

Forces are gradients of energies (`jax.grad`), so the energy balance holds by construction.

Time integration, chosen by work–precision (`SpringModel.default_integrator`,
`benchmarks/bench_spring.py`): flexible columns: adaptive generalized-α (`GeneralizedAlpha`,
`jaxrock.generalized_alpha`: the spring solved exactly as a scalar equation in each Newton
iteration, the rest-state tangent rotated to the rocked configuration, step-size ladder with
precomputed tangent inverses; forward-mode differentiable); the one-DOF quasi-rigid model:
explicit Tsit5 (its pre-yield branch is only mildly stiff; reverse-mode differentiable). Either
model takes either integrator; diffrax's ESDIRK (`SpringIntegrator(solver="kvaerno5")`, full
Newton stopped on its increment) is the reverse-mode-differentiable choice for flexible columns.
diffrax runs: integral step-size control with a component-scaled absolute tolerance; overturning
``|θ| ≥ threshold·α′`` is an event. The peak ``max |θ|`` is exact to the solver tolerance: the
base rotation and velocity at every accepted step give a cubic Hermite interpolant (θ, θ̇ at
both ends, fourth-order accurate), maximised in closed form on each step (`jaxrock._peaks`) —
cheaper than an event on θ̇ = 0 with restarts, and differentiable.

Summary runs stop when the answer is fixed: phase 1 runs over the excitation window; phase 2 runs
free motion until the mechanical energy falls below the potential at the largest rotation seen so
far — after which |θ| can never reach that rotation again (exact for the one-DOF model, whose
potential is monotone in |θ| below the barrier; for the flexible model the rigid-rotation
potential is used with a 10 % margin for the flexural P-Δ softening) — or it overturns, or
`t1` (default: excitation end + 20 rocking periods 2π/p′) is reached.
"""

from __future__ import annotations

import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from diffrax import with_stepsize_controller_tols
from jaxtyping import Array, Float

from . import _linalg, beam
from ._validate import JaxrockInputError, Limit, check_limits
from .backbone import AbstractBackbone, as_backbone
from ._peaks import first_exceedance as _first_exceedance
from ._peaks import hermite_peak as _hermite_peak
from .excitation import AbstractExcitation
from .generalized_alpha import GeneralizedAlpha
from .geometry import G, Block
from .model import AbstractModel, AbstractSpringIntegrator, AbstractStepper, check_autodiff, diffrax_adjoint, register_model_kind
from .results import Save, Solution, Status

# Backbone and θs/α′: the study of benchmarks/bench_backbone.py (its results file): 192 quasi-rigid
# and 48 flexible (concrete, 10 elements) scenes, tanα 0.05–0.35, 2h 1–50 m, ω_p/p′ 1–15,
# a_p/(g tanα) 1–8, both pulses; error of max|θ|/α against the sharp limit (bilinear, θy = 1e-6 α).
# This default, tanh at θs = 1e-4 α, leaves up to 4.9e-2 (quasi-rigid) and 3.9e-2 (flexible), median
# 1.7e-4 and 7.6e-4, the largest on antisymmetric pulses near a_p/(g tanα) ≈ 4, ω_p/p′ ≈ 4. The
# bilinear backbone at θy = 1e-5 α (`backbone="bilinear", smoothing=1e-5`) is within 8.3e-4
# wherever the limit is settled, for 15 % more cost: use it for values. It stays off by default
# because its kink breaks derivatives through the adaptive steps (`bench_backbone.py --part
# gradients`): calibration's reverse ∂r_eq²/∂c̄ (Tsit5 1e-10) came out −3.43 against finite
# differences' −1.988, and d max θ / d ln a_p was 33 % (median) from central differences with
# generalized-α's jacfwd, 2.7 % with Tsit5's forward mode (tanh: 0.13 % and 3e-6).
DEFAULT_SMOOTHING = 1e-4
DEFAULT_BACKBONE = "tanh"
DEFAULT_E, DEFAULT_RHO, DEFAULT_ZETA = 30e9, 2500.0, 0.01  # a scenes file's column: concrete (paper sections 4–6)
QUASI_RIGID_RHO = 2500.0  # kg/m³: mass of the quasi-rigid scene (results do not depend on it)

HISTORY_FIELDS = (
    "theta",
    "omega",
    "u_top",
    "w_top",
    "base_moment",
    "kinetic",
    "potential",
    "dissipated",
    "input",
)
_ENERGY_FIELDS = ("kinetic", "potential", "dissipated", "input")


# ----------------------------------------------------------------------------------------------
# closed-form helpers
# ----------------------------------------------------------------------------------------------
def cbar_eq17(alpha):
    """Eq. 17: c̄ = c/(m g^0.5 R^1.5) = 0.02 (α/0.1)² (α in rad)."""
    return 0.02 * (jnp.asarray(alpha, dtype=float) / 0.1) ** 2


def first_period_eq21(height, tan_alpha, E, rho):
    """Eq. 21: first fixed-base period of a solid rectangular column, T₁ = 12.38 sqrt(ρ/E) h/tanα [s],
    with `height` = 2h [m] as every constructor takes it (2h = 50 m, tanα = 0.1 concrete: 0.893 s).
    The discretised column's own value, with its added masses, is `SpringModel.first_period`."""
    return 12.38 * jnp.sqrt(jnp.asarray(rho, dtype=float) / E) * (0.5 * jnp.asarray(height, dtype=float)) / tan_alpha


def pushover_eq9(theta, alpha):
    """Eq. 9: SM pushover F/(m g) = tanα/cosθ − tanθ (force at the column's mid-height)."""
    return jnp.tan(alpha) / jnp.cos(theta) - jnp.tan(theta)


# ----------------------------------------------------------------------------------------------
# column values
# ----------------------------------------------------------------------------------------------
class Column(eqx.Module):
    """Linear elastic column: Young's modulus E [Pa], density ρ [kg/m³], and optionally the
    section area A [m²] and second moment I [m⁴] (per the model's out-of-plane thickness).
    Without A, I the section is the block's solid rectangle 2b × 1 m: A = 2b, I = (2b)³/12."""

    E: Float[Array, ""]
    rho: Float[Array, ""]
    A: Float[Array, ""] | None = None
    I: Float[Array, ""] | None = None

    def __init__(self, E, rho=2500.0, A=None, I=None):
        if (A is None) != (I is None):
            raise JaxrockInputError("give both the section area A and its second moment I, or neither")
        self.E = jnp.asarray(E, dtype=float)
        self.rho = jnp.asarray(rho, dtype=float)
        self.A = None if A is None else jnp.asarray(A, dtype=float)
        self.I = None if I is None else jnp.asarray(I, dtype=float)
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        """E from soft rubber to beyond diamond (10⁶–10¹⁵ Pa; 10¹⁴ stands for a rigid column), ρ
        from foams to beyond osmium (10–3·10⁴ kg/m³): outside these the column is no solid."""
        section = () if self.A is None else (Limit("A (section area) [m^2]", self.A, 0.0, math.inf, lo_open=True, hi_open=True),
                                             Limit("I (section second moment) [m^4]", self.I, 0.0, math.inf, lo_open=True, hi_open=True))
        return (Limit("E (Young's modulus) [Pa]", self.E, 1e6, 1e15), Limit("rho (density) [kg/m^3]", self.rho, 10.0, 3e4), *section)

    @classmethod
    def concrete(cls, A=None, I=None) -> "Column":
        """E = 30 GPa, ρ = 2500 kg/m³ (paper sections 4–6)."""
        return cls(30e9, 2500.0, A, I)

    @classmethod
    def quasi_rigid(cls, rho=2500.0) -> "Column":
        """E = 10¹⁴ Pa (paper section 3: 'quasi-rigid' FE column)."""
        return cls(1e14, rho)

    def section(self, block: Block):
        if self.A is None:
            w = 2 * block.b
            return w, w**3 / 12
        return self.A, self.I


# ----------------------------------------------------------------------------------------------
# the prepared mechanics (arrays computed once per run)
# ----------------------------------------------------------------------------------------------
class _Mechanics(eqx.Module):
    """Everything a right-hand side needs, computed once (mass matrix inverse, preload, Rayleigh
    coefficient). Built by `SpringModel.mechanics()`."""

    n: int | None = eqx.field(static=True)  # None: one-DOF quasi-rigid
    fixed_base: bool = eqx.field(static=True)
    track_energy: bool = eqx.field(static=True)
    backbone: AbstractBackbone = eqx.field(static=True)
    h: Array
    m: Array
    My: Array
    theta_s: Array
    c: Array
    alpha_r: Array
    p_r: Array
    R_r: Array
    Itot: Array  # one-DOF inertia (also used for the rigid potential of the flexible model)
    EA: Array | None
    EI: Array | None
    a1: Array | None
    M: Array | None
    Minv: Array | None
    q_eq: Array | None
    V_eq: Array | None
    r: Array | None  # ground load vector p (`beam.ground_load`): f_ext = −üg p
    deform_scale: Array | float = 1.0  # fixed base: tolerance scales × (static drift / 2h α′)

    @property
    def ndof(self) -> int:
        return 1 if self.n is None else beam.n_dof(self.n)

    @property
    def settle_margin(self):
        """Energy margin of a summary's settled test: exact for the one-DOF model; 10 % for the
        flexural P-Δ softening of a flexible column."""
        return 1.0 if self.n is None else 0.9

    @property
    def theta_up(self):
        """Uplift rotation: the spring has (all but) yielded beyond it (`AbstractBackbone.band` θs)."""
        return self.backbone.band * self.theta_s

    # -- energies -------------------------------------------------------------------------------
    def spring_potential(self, theta):
        return self.backbone.potential(theta, self.My, self.theta_s)

    def spring_moment(self, theta):
        return self.backbone.moment(theta, self.My, self.theta_s)

    def _column_potential(self, q):
        """Gravity (+ strain) potential of the column, spring excluded."""
        if self.n is None:
            return self.m * G * self.h * (jnp.cos(q[0]) - 1.0)
        V = beam.strain_energy(q, self.h, self.n, self.EA, self.EI)
        V = V + beam.gravity_potential(q, self.h, self.n, self.m)
        return V

    def potential(self, q):
        """Total potential relative to the (preloaded) rest state [J]."""
        V = self._column_potential(q)
        if not self.fixed_base:
            V = V + self.spring_potential(q[0])
        if self.n is not None:
            V = V - self.V_eq
        return V

    def rigid_potential(self, theta):
        """One-DOF SM potential at zero velocity (exact for the quasi-rigid scene):
        My θs log cosh(θ/θs) − m g h (1 − cosθ) → SPEC's E(θ) = m g R(sinα|θ| − cosα(1 − cosθ))
        as θs → 0 (for a plain block, My = m g R sinα and h = R cosα)."""
        return self.spring_potential(theta) - self.m * G * self.h * (1 - jnp.cos(theta))

    def kinetic(self, v):
        if self.n is None:
            return 0.5 * self.Itot * v[0] ** 2
        return 0.5 * v @ (self.M @ v)

    # -- forces -----------------------------------------------------------------------------------
    def _column_damping(self, q, v):
        """Rayleigh force a₁ Jᵀ K_e J v on the local deformations (never on rigid motion)."""
        return self._column_forces(q, v)[1]

    def _column_forces(self, q, v):
        """(−∇V_column, Rayleigh force) from one linearisation d(q) ≈ d + J δq of the element
        deformations: the strain energy is ½ Σ dᵀ K_e d, so ∇U = Jᵀ K_e d, and the damping force
        is a₁ Jᵀ K_e J v; the gravity force is constant (the potential is linear in the heights)."""
        f = lambda qq: beam.element_deformations(qq, self.h, self.n)
        d, jvp_fn = jax.linearize(f, q)
        transpose = jax.linear_transpose(jvp_fn, q)
        K_e = lambda x: beam.deformation_energy_rate_matrix(x, self.h, self.n, self.EA, self.EI)
        (g_el,) = transpose(K_e(d))
        (g_d,) = transpose(K_e(jvp_fn(v)))
        g_grav = jax.grad(beam.gravity_potential)(q, self.h, self.n, self.m)
        return -(g_el + g_grav), self.a1 * g_d

    def forces(self, t, q, v, excitation):
        """(f_total, f_ext, f_damp, f_nospring): generalised forces [N, N·m]."""
        ug = excitation(t)
        if self.n is None:
            f_ext = jnp.atleast_1d(-self.m * ug * self.h * jnp.cos(q[0]))  # eq. 10 right-hand side
            f_col = -jax.grad(self._column_potential)(q)
            f_dcol = jnp.zeros_like(q)
        else:
            f_ext = -ug * self.r
            f_col, f_dcol = self._column_forces(q, v)
        f_nospring = f_ext + f_col - f_dcol
        if self.fixed_base:
            f_sp = jnp.zeros_like(q)
        else:
            f_sp = jnp.zeros_like(q).at[0].set(self.spring_moment(q[0]) + self.c * v[0])
        f_damp = f_dcol + jnp.zeros_like(q).at[0].set(0.0 if self.fixed_base else self.c * v[0])
        return f_nospring - f_sp, f_ext, f_damp, f_nospring

    def base_moment(self, t, q, v, excitation):
        """Spring + damper moment M(θ) + c θ̇ [N·m]; for a fixed base the reaction moment."""
        if self.fixed_base:
            return self.forces(t, q, v, excitation)[3][0]
        return self.spring_moment(q[0]) + self.c * v[0]

    # -- second-order form (generalized-α) -------------------------------------------------------
    def forces_without_spring(self, t, q, v, excitation):
        """(f_rest, f_ext, f_damp) with the total force f_rest − M(θ) e₀: everything but the
        spring's elastic moment M(θ), which the generalized-α step solves for exactly."""
        f_total, f_ext, f_damp, _ = self.forces(t, q, v, excitation)
        if not self.fixed_base:
            f_total = f_total.at[0].add(self.spring_moment(q[0]))
        return f_total, f_ext, f_damp

    def mass_matrix(self):
        return jnp.reshape(self.Itot, (1, 1)) if self.n is None else self.M

    def tangents(self):
        """(K₀, C₀): stiffness (Hessian of the column potential, spring excluded) and damping
        (Rayleigh on the deformations + the base damper) at the preloaded rest state."""
        N = self.ndof
        q0 = jnp.zeros(N) if self.n is None else self.q_eq
        K0 = jax.hessian(self._column_potential)(q0)
        if self.n is None:
            C0 = jnp.zeros((1, 1))
        else:
            C0 = jax.jacfwd(lambda v: self._column_damping(q0, v))(jnp.zeros(N))
        if not self.fixed_base:
            C0 = C0.at[0, 0].add(self.c)
        return K0, C0

    def rotate(self, x, theta):
        """Tangent vectors of the column rotated rigidly by θ about the base (T(θ) x: each node's
        (u_x, u_y) turned by θ; rotations unchanged). The strain energy is invariant under the
        rigid rotation, so its Hessian there is T K₀ Tᵀ, and M and the deformation damping are
        invariant: the tangent at a rocked configuration is the rest tangent rotated."""
        if self.n is None:
            return x
        c, s = jnp.cos(theta), jnp.sin(theta)
        rest = x[1:].reshape(self.n, 3)
        ux, uy = rest[:, 0], rest[:, 1]
        rest = jnp.stack([c * ux + s * uy, -s * ux + c * uy, rest[:, 2]], axis=1)
        return jnp.concatenate([x[:1], rest.reshape(-1)])

    # -- first-order form -------------------------------------------------------------------------
    def split(self, y):
        N = self.ndof
        return y[:N], y[N : 2 * N]

    def vector_field(self, t, y, excitation):
        q, v = self.split(y)
        f, f_ext, f_damp, _ = self.forces(t, q, v, excitation)
        if self.n is None:
            a = f / self.Itot
        else:
            a = self.Minv @ f
        if self.fixed_base:
            a = a.at[0].set(0.0)
        parts = [v, a]
        if self.track_energy:
            parts.append(jnp.stack([v @ f_damp, v @ f_ext]))
        return jnp.concatenate(parts)

    def initial_state(self, theta0=0.0, omega0=0.0):
        theta0 = jnp.asarray(theta0, dtype=float)
        omega0 = jnp.asarray(omega0, dtype=float)
        if self.n is None:
            q = jnp.atleast_1d(theta0)
            v = jnp.atleast_1d(omega0)
        else:
            x, y, phi = beam.positions(self.q_eq, self.h, self.n)
            c, s = jnp.cos(theta0), jnp.sin(theta0)
            # clockwise rigid rotation about the base (top moves to +x for θ0 > 0)
            xr, yr = x * c + y * s, -x * s + y * c
            q = beam.from_positions(xr, yr, phi + theta0, self.h, self.n)
            # rigid angular velocity ω0: ẋ = ω0 y, ẏ = −ω0 x, φ̇ = ω0
            v = beam.from_positions(omega0 * yr, -omega0 * xr + beam.node_heights(self.h, self.n), jnp.full_like(phi, omega0), self.h, self.n)
        y0 = [q, v]
        if self.track_energy:
            y0.append(jnp.zeros(2))
        return jnp.concatenate(y0)

    def atol_scale(self):
        """Per-component scale of the absolute tolerance: α′ for rotations, 2h α′ for
        displacements, × p′ for velocities, m g R′ α′ for the energy integrals — the sizes of a
        rocking motion. A fixed-base column never rocks: all scales shrink by its static drift under
        m g tanα′ over 2h α′ (`deform_scale`; 1/473 for the figure-17 chimney), so that its
        vibration, not a rocking it cannot do, sets the tolerance."""
        if self.n is None:
            sq = jnp.ones(1) * self.alpha_r
        else:
            unit = jnp.tile(jnp.array([2.0, 2.0, 0.0]), self.n)
            sq = jnp.concatenate([jnp.zeros(1), unit])
            sq = jnp.where(sq > 0, self.h * sq, 1.0) * self.alpha_r
        parts = [sq, sq * self.p_r]
        if self.track_energy:
            parts.append(jnp.ones(2) * self.m * G * self.R_r * self.alpha_r)
        return jnp.concatenate(parts) * self.deform_scale

    def mechanical_energy(self, y):
        q, v = self.split(y)
        return self.kinetic(v) + self.potential(q)

    def history(self, t, y, excitation, fields):
        q, v = self.split(y)
        theta, omega = q[0], v[0]
        out = {}
        for name in fields:
            if name == "theta":
                out[name] = theta
            elif name == "omega":
                out[name] = omega
            elif name == "u_top":
                out[name] = 2 * self.h * jnp.sin(theta) if self.n is None else beam.top_displacement(q, self.h, self.n)
            elif name == "w_top":
                u = 2 * self.h * jnp.sin(theta) if self.n is None else beam.top_displacement(q, self.h, self.n)
                out[name] = u - 2 * self.h * jnp.sin(theta)
            elif name == "base_moment":
                out[name] = self.base_moment(t, q, v, excitation)
            elif name == "kinetic":
                out[name] = self.kinetic(v)
            elif name == "potential":
                out[name] = self.potential(q)
            elif name == "dissipated":
                out[name] = y[-2]
            elif name == "input":
                out[name] = y[-1]
        return out


# ----------------------------------------------------------------------------------------------
# integrator
# ----------------------------------------------------------------------------------------------
_IMPLICIT = {"kvaerno3": diffrax.Kvaerno3, "kvaerno4": diffrax.Kvaerno4, "kvaerno5": diffrax.Kvaerno5}
_EXPLICIT = {"tsit5": diffrax.Tsit5, "dopri5": diffrax.Dopri5, "dopri8": diffrax.Dopri8}
_SOLVERS = {**_IMPLICIT, **_EXPLICIT}


class SpringIntegrator(AbstractSpringIntegrator):
    """diffrax settings of the spring model: an L-stable ESDIRK solver (`solver` ∈ kvaerno3/4/5,
    stage equations by full Newton) or an explicit Runge–Kutta solver (tsit5, dopri5, dopri8: for
    the one-DOF quasi-rigid SM only, whose one stiff part, the spring's pre-yield branch, is mild),
    with an integral step-size controller; `atol` multiplies a per-component scale (α′, 2hα′, ×p′).
    Defaults from the work–precision study in `benchmarks/bench_spring.py` and
    `SpringModel.default_integrator`."""

    rtol: float = eqx.field(static=True, default=1e-6)
    atol: float = eqx.field(static=True, default=1e-6)
    solver: str = eqx.field(static=True, default="kvaerno5")
    max_steps: int = eqx.field(static=True, default=20_000)
    root_finder: str = eqx.field(static=True, default="newton")
    autodiff: str = eqx.field(static=True, default="reverse")  # or "forward": see model.diffrax_adjoint

    def __check_init__(self):
        check_autodiff(self.autodiff)
        if self.solver not in _SOLVERS:
            raise JaxrockInputError(f"solver = {self.solver!r}; valid: {tuple(_SOLVERS)}")
        if not (0 < self.rtol < 1) or not (0 < self.atol < 1):
            raise JaxrockInputError(f"rtol = {self.rtol:g}, atol = {self.atol:g}: both must be in (0, 1)")
        if self.root_finder not in ("newton", "chord"):
            raise JaxrockInputError(f"root_finder = {self.root_finder!r}; valid: ('newton', 'chord')")
        if self.max_steps < 16:
            raise JaxrockInputError(f"max_steps = {self.max_steps}: must be >= 16")

    def stepper(self, model, system, save=None, t1=None) -> DiffraxSpringStepper:
        """`AbstractSpringIntegrator.stepper`: the whole run in diffrax's loop."""
        return DiffraxSpringStepper(self, model, system, save, t1)

    @property
    def explicit(self) -> bool:
        return self.solver in _EXPLICIT

    def diffrax_solver(self):
        """The solver. ESDIRK stage equations are solved by full Newton (Jacobian refreshed every
        iteration: the tanh spring's stiffness jumps by ~α/θs across |θ| ≈ θs, where the
        frozen-Jacobian chord iteration diverges and steps get rejected) or by diffrax's VeryChord.

        Newton stops on the size of its own increment (relative to atol + rtol |k|, k the stage
        derivative), not on the stage residual (`cauchy_termination=False`). The residual is an
        acceleration whose round-off in a stiff column is EA·eps / m_node ~ 1e-5 m/s² at
        E = 10¹⁴ Pa (axial force of a 2.5 m element computed from 10 m coordinates): with the
        Cauchy test (residual < atol) Newton could never converge at atol ≤ 1e-5, every step was
        rejected, the step size collapsed and the run ended at max_steps with max|θ| ≈ 0. The
        increment (I − γ dt J)⁻¹ r damps that round-off by the stiffness itself."""
        if self.explicit:
            return _EXPLICIT[self.solver]()
        if self.root_finder == "newton":
            rf = optx.Newton(rtol=self.rtol, atol=self.atol, cauchy_termination=False, linear_solver=_linalg.SequentialLU())
        else:
            rf = with_stepsize_controller_tols(diffrax.VeryChord)(linear_solver=_linalg.SequentialLU())
        return _IMPLICIT[self.solver](root_finder=rf)

    def controller(self, mech: _Mechanics, excitation: AbstractExcitation, dtmax=None):
        pid = diffrax.PIDController(
            rtol=self.rtol,
            atol=self.atol * mech.atol_scale(),
            pcoeff=0.0,
            icoeff=1.0,
            dtmax=dtmax,
        )
        if excitation.step_ts is not None:
            return diffrax.ClipStepSizeController(pid, step_ts=excitation.step_ts)
        return pid

    def solve(
        self,
        model: "SpringModel | _Mechanics",
        excitation: AbstractExcitation,
        y0,
        t0,
        t1,
        event: diffrax.Event | None = None,
        saveat: diffrax.SaveAt | None = None,
        *,
        dtmax=None,
        throw: bool = False,
    ) -> diffrax.Solution:
        """One `diffrax.diffeqsolve` of the model's first-order equations from (t0, y0) to t1.

        `model` may be a `SpringModel` (its mechanics are prepared here) or prepared mechanics
        (`SpringModel.mechanics()`), reused across calls. `dtmax` defaults to the excitation's
        `max_step` while t < t_end. Never throws by default (`throw=False`): inspect `result`.
        """
        mech = model.mechanics() if isinstance(model, SpringModel) else model
        if saveat is None:
            saveat = diffrax.SaveAt(t1=True)
        if dtmax is None:
            dtmax = excitation.max_step
        term = diffrax.ODETerm(lambda t, y, args: args[0].vector_field(t, y, args[1]))
        t0 = jnp.asarray(t0, dtype=float)
        return diffrax.diffeqsolve(
            term,
            self.diffrax_solver(),
            t0,
            t1,
            jnp.minimum(1e-3 / mech.p_r, 0.5 * dtmax) if dtmax is not None else 1e-3 / mech.p_r,
            y0,
            args=(mech, excitation),
            saveat=saveat,
            stepsize_controller=self.controller(mech, excitation, dtmax),
            event=event,
            max_steps=self.max_steps,
            adjoint=diffrax_adjoint(self.autodiff),
            throw=throw,
        )


class DiffraxSpringStepper(AbstractStepper):
    """A spring-model run by `SpringIntegrator`: diffrax's `diffeqsolve` runs its own loop, so the
    whole run is done in `init` (`max_steps = 0`; the state is the `Solution`). A summary runs in two
    solves: the excitation window, then free motion until the answer is fixed (module docstring);
    a history is one solve with the peak from the steps' Hermite interpolants."""

    integrator: "SpringIntegrator"
    model: "SpringModel"
    system: _Mechanics
    save: Save | None
    t1: Array | None
    @property
    def max_steps(self) -> int:
        return 0

    @property
    def checkpointed(self) -> bool:
        return True

    def step(self, excitation, state):
        return state

    def done(self, state):
        return jnp.asarray(True)

    def finish(self, excitation, state) -> Solution:
        return state

    def init(self, excitation) -> Solution:
        model, mech, save, t1 = self.model, self.system, self.save, self.t1
        alpha_r = model.block.alpha_r
        thr = model.threshold * alpha_r
        y0 = mech.initial_state()
        t_start = excitation.t_start
        t_end = excitation.t_end
        N = mech.ndof
        step_fn = lambda t, y, args: (y[0], y[N])
        root = optx.Newton(rtol=1e-10, atol=1e-12 * alpha_r)
        if model.fixed_base:
            over_fn = lambda t, y, args, **kw: jnp.asarray(1.0)  # never overturns
        else:
            over_fn = lambda t, y, args, **kw: thr - jnp.abs(y[0])
        theta_up = mech.theta_up

        if save is not None:
            t_final = model.run_end(mech, excitation, save, t1)
            sub_hist = diffrax.SubSaveAt(ts=save.ts, fn=lambda t, y, args: mech.history(t, y, args[1], save.fields))
            sub_steps = diffrax.SubSaveAt(steps=True, t0=True, fn=step_fn)
            sol = self.integrator.solve(
                mech, excitation, y0, t_start, t_final,
                event=diffrax.Event(over_fn, root_finder=root),
                saveat=diffrax.SaveAt(subs=[sub_hist, sub_steps]),
            )
            hist, (th, om) = sol.ys
            ts_steps = sol.ts[1]
            peak = _hermite_peak(ts_steps, th, om)
            status = _status_of(sol.result)
            t_last = jnp.max(jnp.where(jnp.isfinite(ts_steps), ts_steps, -jnp.inf))
            over = (sol.result == diffrax.RESULTS.event_occurred) & (peak >= thr * (1 - 1e-6))
            t_over = jnp.where(over, t_last, jnp.inf)
            return model.solution(peak, over, t_over, _first_exceedance(ts_steps, th, om, theta_up), status, sol.ts[0], hist)

        # phase 1: the excitation window
        sub = diffrax.SubSaveAt(steps=True, t0=True, fn=step_fn)
        sol1 = self.integrator.solve(
            mech, excitation, y0, t_start, t_end,
            event=diffrax.Event(over_fn, root_finder=root),
            saveat=diffrax.SaveAt(subs=[sub, diffrax.SubSaveAt(t1=True)]),
        )
        (th1, om1), y_end = sol1.ys
        ts1 = sol1.ts[0]
        y_end = y_end[-1]
        peak1 = _hermite_peak(ts1, th1, om1)
        st1 = _status_of(sol1.result)
        over1 = (sol1.result == diffrax.RESULTS.event_occurred) & (st1 == Status.ok)
        # phase 2: free motion until the answer is fixed
        t_stop = model.run_end(mech, excitation, None, t1)
        margin = mech.settle_margin
        v_ref = margin * mech.rigid_potential(peak1)

        def settled(t, y, args, **kw):
            return args[0].mechanical_energy(y) < v_ref

        y_end = jnp.where(jnp.all(jnp.isfinite(y_end)), y_end, y0)
        t_start2 = sol1.ts[1][-1]
        t_start2 = jnp.where(jnp.isfinite(t_start2), t_start2, t_end)
        # an overturned (or failed) phase 1 still runs phase 2 formally, over a vanishing interval
        done = over1 | (st1 != Status.ok)
        t_stop = jnp.where(done, t_start2 + 1e-9, t_stop)
        sol2 = self.integrator.solve(
            mech, excitation, y_end, t_start2, t_stop,
            event=diffrax.Event((over_fn, settled), root_finder=root),
            saveat=diffrax.SaveAt(steps=True, fn=step_fn),
            dtmax=jnp.inf,
        )
        th2, om2 = sol2.ys
        ts2 = sol2.ts
        # join: the last phase-1 point starts phase 2
        ts2 = jnp.concatenate([jnp.atleast_1d(t_start2), ts2])
        th2 = jnp.concatenate([jnp.atleast_1d(y_end[0]), th2])
        om2 = jnp.concatenate([jnp.atleast_1d(y_end[N]), om2])
        peak2 = jnp.where(done, 0.0, _hermite_peak(ts2, th2, om2))
        status = _worse(st1, Status.where(done, Status.ok, _status_of(sol2.result)))
        peak = jnp.maximum(peak1, peak2)
        over2 = (~done) & (sol2.result == diffrax.RESULTS.event_occurred) & sol2.event_mask[0]
        ts_all = jnp.concatenate([ts1, ts2])
        th_all = jnp.concatenate([th1, th2])
        om_all = jnp.concatenate([om1, om2])
        t_last2 = jnp.max(jnp.where(jnp.isfinite(ts2), ts2, -jnp.inf))
        t_over = jnp.where(over1, t_start2, jnp.where(over2, t_last2, jnp.inf))
        return model.solution(peak, over1 | over2, t_over, _first_exceedance(ts_all, th_all, om_all, theta_up), status)


def _status_of(result) -> Status:
    ok = (result == diffrax.RESULTS.successful) | (result == diffrax.RESULTS.event_occurred)
    steps = result == diffrax.RESULTS.max_steps_reached
    return Status.where(ok, Status.ok, Status.where(steps, Status.max_steps, Status.solver_failed))


def _worse(s1: Status, s2: Status) -> Status:
    return Status.where(s1 == Status.ok, s2, s1)


# ----------------------------------------------------------------------------------------------
# the model
# ----------------------------------------------------------------------------------------------
class SpringModel(AbstractModel):
    """The paper's spring model (SM), quasi-rigid (``column=None``) or flexible.

    Fields (arrays are vmappable/differentiable leaves):
    - `block`: geometry (`Block`, with `b_base > b` for an extended rigid base, section 5);
    - `column`: `Column` (E, ρ, optional A, I) or None for the one-DOF quasi-rigid SM;
    - `added_masses` (static): add ΔI = I′o − (4/3) m h² (SPEC; paper section 3.3);
    - `cbar`: damper coefficient c̄ (default eq. 17 with α′);
    - `backbone` (static): the spring's moment–rotation curve, `jaxrock.backbone.Bilinear` or
      `Tanh` (or their names; default `DEFAULT_BACKBONE`);
    - `smoothing`: θs/α′, the backbone's pre-yield rotation (the bilinear yield rotation θy, or
      the tanh's θs; default `DEFAULT_SMOOTHING`);
    - `zeta`: column damping ratio ζ, stiffness-proportional Rayleigh damping (`rayleigh`) set for ζ
      at the first fixed-base period of the discretised column *with its added rotational masses*
      (`first_period`; they lengthen it: 2h = 50 m, 2b = 5 m concrete, 10 elements: T₁ = 0.901 s,
      0.896 s without them, eq. 21 0.893 s);
    - `n_elements` (static), `fixed_base` (static: base rotation clamped, section 6);
    - `threshold`: overturned when |θ| ≥ threshold·α′.
    """

    block: Block
    column: Column | None
    cbar: Float[Array, ""]
    smoothing: Float[Array, ""]
    zeta: Float[Array, ""]
    threshold: float
    backbone: AbstractBackbone = eqx.field(static=True)
    added_masses: bool = eqx.field(static=True)
    n_elements: int = eqx.field(static=True)
    fixed_base: bool = eqx.field(static=True)

    def __init__(
        self,
        block: Block,
        column: Column | None = None,
        *,
        added_masses: bool = True,
        cbar=None,
        backbone: AbstractBackbone | str = DEFAULT_BACKBONE,
        smoothing=DEFAULT_SMOOTHING,
        zeta=0.01,
        n_elements: int = 10,
        fixed_base: bool = False,
        threshold=1.0,
    ):
        if not isinstance(block, Block):
            raise JaxrockInputError(f"block must be a jaxrock.Block, got {type(block).__name__}")
        if column is not None and not isinstance(column, Column):
            raise JaxrockInputError(f"column must be a jaxrock Column or None, got {type(column).__name__}")
        if not isinstance(n_elements, int) or isinstance(n_elements, bool) or n_elements < 1:
            raise JaxrockInputError(f"n_elements = {n_elements!r}: must be an integer >= 1")
        self.block = block
        self.column = column
        self.added_masses = bool(added_masses)
        self.cbar = cbar_eq17(block.alpha_r) if cbar is None else jnp.asarray(cbar, dtype=float)
        self.backbone = as_backbone(backbone)
        self.smoothing = jnp.asarray(smoothing, dtype=float)
        self.zeta = jnp.asarray(zeta, dtype=float)
        self.n_elements = n_elements
        self.fixed_base = bool(fixed_base)
        self.threshold = threshold
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        column = () if self.column is None else self.column.limits()
        return (Limit("smoothing (theta_s/alpha)", self.smoothing, 0.0, 1.0, lo_open=True, hi_open=True),
                Limit("zeta (column damping ratio)", self.zeta, 0.0, math.inf, hi_open=True),
                Limit("threshold (overturning |theta|/alpha)", self.threshold, 0.0, 1.0, lo_open=True),
                Limit("cbar (damper coefficient)", self.cbar, 0.0, math.inf, hi_open=True), *column)

    # -- AbstractModel --------------------------------------------------------------------------
    def default_integrator(self) -> "SpringIntegrator | GeneralizedAlpha":
        """Work–precision choice (measured on 2 CPU cores, vmapped grids, `benchmarks/bench_spring.py`,
        with the default tanh backbone at θs = 1e-4 α; with the bilinear θy = 1e-5 α, over the 240
        scenes of `benchmarks/bench_backbone.py`: quasi-rigid Tsit5 5.2 ms/scene; flexible
        generalized-α 1e-5 10 ms/scene, its total error against the sharp limit 3.1e-3 max, 4e-5
        median).

        Quasi-rigid → explicit Tsit5 at rtol = atol = 1e-10 (32×32 pulse grid, tanα = 0.2: max error
        of max|θ|/α 2.4e-8 against Tsit5 at 1e-11, ~1.5–1.9 ms/scene; reverse-mode differentiable,
        which the calibration of c̄ needs). `GeneralizedAlpha(1e-6, 1e-6)` runs the same grid at
        0.092 ms/scene with max error 8e-3 (median 1e-4; OpenSeesPy: 19 ms, 1.4e-2): pass it for
        pulse spectra where that suffices — not for records, whose response hangs on resolving the
        block's ringing on the stiff pre-yield spring before uplift (README).

        Flexible → `GeneralizedAlpha(1e-5, 1e-5)`, ρ∞ = 0.9 (8×8 grid of 2h = 50 m concrete
        columns, 10 elements, error against generalized-α at 1e-9, itself 4e-7 from Kvaerno5 at
        1e-7): 4.2 ms/scene, max error 2.9e-4 (median 4e-5); at 1e-4: 2.8 ms, 2.1e-3; at 1e-6:
        7.8 ms, 1.5e-4 (OpenSeesPy at T/400: 157 ms, 6.9e-3). ρ∞ = 1 (the trapezoidal rule)
        leaves the spring's impacts ringing in the stiff axial modes: 30–100× more steps; ρ∞ =
        0.8, 0.7, 0.5 cost 5–30 % more than 0.9 at equal error. diffrax's Kvaerno5 + Newton at 1e-6
        (`SpringIntegrator()`) costs ~1.6 s/scene: use it for reverse-mode gradients of a
        flexible column."""
        if self.column is None:
            return SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5")
        return GeneralizedAlpha(rtol=1e-5, atol=1e-5)

    @property
    def history_fields(self) -> tuple[str, ...]:
        return HISTORY_FIELDS

    @property
    def flexible(self) -> bool:
        return self.column is not None

    # -- mechanics ------------------------------------------------------------------------------
    def mass(self):
        """Column mass m [kg] (per unit out-of-plane thickness for the default section)."""
        if self.column is None:
            return QUASI_RIGID_RHO * 2 * self.block.b * 2 * self.block.h
        A, _ = self.column.section(self.block)
        return self.column.rho * A * 2 * self.block.h

    def total_inertia(self):
        """Itot about the base centre: (4/3) m h² (eq. 11), or I′o with added masses."""
        m, blk = self.mass(), self.block
        return m * blk.inertia_ratio if self.added_masses else (4.0 / 3.0) * m * blk.h**2

    def _rotational_masses(self):
        """Rotational inertia at the n + 1 column nodes: ΔI/(n + 1) with the added masses, else the
        section's rotary inertia ρ I L_trib (keeps M regular; Rayleigh beam)."""
        blk, n = self.block, self.n_elements
        if self.added_masses:
            return jnp.full(n + 1, (self.total_inertia() - (4.0 / 3.0) * self.mass() * blk.h**2) / (n + 1))
        _, I = self.column.section(blk)
        le = 2 * blk.h / n
        return self.column.rho * I * le * jnp.concatenate([jnp.full(1, 0.5), jnp.ones(n - 1), jnp.full(1, 0.5)])

    def _require_column(self, what: str):
        if self.column is None:
            raise JaxrockInputError(f"{what}: the quasi-rigid SM (column=None) has no column; give a Column")

    def first_period(self):
        """First fixed-base period T₁ [s] of the discretised column with the model's rotational masses
        (base rotation clamped, no gravity): the period ζ refers to (eq. 21 is the bare solid column's)."""
        self._require_column("first_period")
        A, I = self.column.section(self.block)
        E = self.column.E
        return beam.first_period(self.block.h, self.n_elements, self.mass(), E * A, E * I, self._rotational_masses())

    def rayleigh(self):
        """Rayleigh coefficients (a₀, a₁) of the column, C = a₀ M + a₁ K on its deformations:
        stiffness proportional, a₀ = 0 and a₁ = ζ T₁/π (ζ = a₁ ω₁/2 at T₁ = `first_period`)."""
        return jnp.zeros(()), self.zeta * self.first_period() / jnp.pi

    def pushover(self, theta):
        """The model's own static pushover: the lateral load F/(m g) that holds the column at base
        rotation `theta` [rad] (any shape), applied as a uniform lateral acceleration of its mass (for
        a rigid column: F at mid-height, eq. 9's load). Solved by Newton on the static equilibrium
        ∇V(q) = (F/m) r with θ prescribed (r: the ground load vector; gravity P-Δ and, for a flexible
        column, its bending included). Quasi-rigid: (M(θ)/(m g h) − sinθ)/cosθ, which is eq. 9,
        tanα/cosθ − tanθ, once the spring has yielded (|θ| beyond its pre-yield band)."""
        if self.fixed_base:
            raise JaxrockInputError("pushover: a fixed-base column (fixed_base=True) does not rock")
        theta = jnp.asarray(theta, dtype=float)
        mech = self.mechanics()
        if mech.n is None:
            f = lambda th: jax.grad(mech.potential)(jnp.atleast_1d(th))[0] / (mech.m * G * mech.h * jnp.cos(th))
            return jnp.vectorize(f)(theta)
        r = mech.r * G  # generalized force of a unit lateral acceleration ratio (F/(m g) = 1)
        grad_v = jax.grad(mech.potential)
        scale = jnp.tile(jnp.array([1.0, 1.0, 0.0]), mech.n) * (mech.h - 1.0) + 1.0  # h for translations

        def one(th):
            q0 = mech.initial_state(th)[: mech.ndof]
            lam0 = pushover_eq9(th, mech.alpha_r)

            def residual(x):
                return grad_v(q0.at[1:].add(x[:-1] * scale)) - x[-1] * r

            x = jnp.concatenate([jnp.zeros(mech.ndof - 1), jnp.atleast_1d(lam0)])
            for _ in range(8):  # Newton: quadratic from the rigidly rotated, preloaded column
                x = x - _linalg.solve(jax.jacfwd(residual)(x), residual(x))
            return x[-1]

        return jnp.vectorize(one)(theta)

    def mechanics(self, track_energy: bool = False) -> _Mechanics:
        blk = self.block
        m = self.mass()
        My = m * G * blk.b_base  # = m g R′ sinα′
        theta_s = self.smoothing * blk.alpha_r
        c = self.cbar * m * math.sqrt(G) * blk.R_r**1.5  # eq. 18
        Itot = self.total_inertia()
        common = dict(
            fixed_base=self.fixed_base,
            track_energy=track_energy,
            backbone=self.backbone,
            h=blk.h,
            m=m,
            My=My,
            theta_s=theta_s,
            c=c,
            alpha_r=blk.alpha_r,
            p_r=blk.p_r,
            R_r=blk.R_r,
            Itot=Itot,
        )
        if self.column is None:
            return _Mechanics(n=None, EA=None, EI=None, a1=None, M=None, Minv=None, q_eq=None, V_eq=None, r=None, **common)
        n = self.n_elements
        A, I = self.column.section(blk)
        EA, EI = self.column.E * A, self.column.E * I
        M = beam.mass_matrix(blk.h, n, m, self._rotational_masses())
        Minv = _linalg.inv(M)
        Minv = 0.5 * (Minv + Minv.T)
        _, a1 = self.rayleigh()
        mech = _Mechanics(n=n, EA=EA, EI=EI, a1=a1, M=M, Minv=Minv, q_eq=jnp.zeros(beam.n_dof(n)), V_eq=jnp.zeros(()), r=beam.ground_load(n, m), **common)
        # gravity preload: static equilibrium at θ = 0 (axial shortening), by Newton on ∇V = 0
        N = beam.n_dof(n)
        grad_v = jax.grad(mech._column_potential)
        hess_v = jax.hessian(mech._column_potential)
        q = jnp.zeros(N)
        free = jnp.ones(N).at[0].set(0.0)  # keep θ = 0
        for _ in range(3):
            g_ = grad_v(q) * free
            H = hess_v(q) * free[:, None] * free[None, :] + jnp.diag(1.0 - free)
            q = q - _linalg.solve(H, g_)
        V_eq = mech._column_potential(q)
        mech = eqx.tree_at(lambda mm: (mm.q_eq, mm.V_eq), mech, (q, V_eq))
        if self.fixed_base:
            # static drift of the clamped column under a lateral m g tanα′ (its mass distribution)
            K = beam.linear_stiffness(blk.h, n, EA, EI)[1:, 1:]
            u = _linalg.solve(K, mech.r[1:] * G * jnp.tan(blk.alpha_r))
            drift = jnp.abs(beam.top_displacement(jnp.concatenate([jnp.zeros(1), u]), blk.h, n))
            mech = eqx.tree_at(lambda mm: mm.deform_scale, mech, drift / (2 * blk.h * blk.alpha_r))
        return mech

    # -- public pieces for calibration / custom solves --------------------------------------------
    def vector_field(self, t, y, excitation: AbstractExcitation):
        """dy/dt of the first-order form y = [q, v] (q[0] = θ). Prepares the mechanics on each call;
        inside loops prefer `self.mechanics().vector_field` or `SpringIntegrator.solve`."""
        return self.mechanics().vector_field(t, y, excitation)

    def initial_state(self, theta0=0.0, omega0=0.0):
        """y at rest (gravity-preloaded column) rotated rigidly by θ0 with angular velocity ω0."""
        return self.mechanics().initial_state(theta0, omega0)

    def base_rotation(self, y):
        return y[0]

    def base_velocity(self, y):
        N = 1 if self.column is None else beam.n_dof(self.n_elements)
        return y[N]

    def static_potential(self, theta):
        """The one-DOF SM's own exact potential at zero velocity, My θs log cosh(θ/θs) − m g h (1 − cosθ)
        [J] (→ SPEC's E(θ) = m g R (sinα|θ| − cosα(1 − cosθ)) as θs → 0). For the flexible model
        this is the rigidly rotated column's value (its deformation adds only strain energy)."""
        return self.mechanics().rigid_potential(theta)

    def mechanical_energy(self, y):
        return self.mechanics().mechanical_energy(y)

    # -- run ------------------------------------------------------------------------------------
    def stepper(self, integrator, save=None, t1=None):
        """The run as an `AbstractStepper` of `integrator` (an `AbstractSpringIntegrator`), on the
        mechanics prepared here once (energy integrals tracked when `save` asks for energies)."""
        if not isinstance(integrator, AbstractSpringIntegrator):
            raise JaxrockInputError(f"SpringModel needs a SpringIntegrator or GeneralizedAlpha, got {type(integrator).__name__}")
        fields = () if save is None else save.fields
        mech = self.mechanics(track_energy=any(f in _ENERGY_FIELDS for f in fields))
        return integrator.stepper(self, mech, save, t1)

    @property
    def overturn_rotation(self):
        """|θ| [rad] at which the body has overturned: threshold·α′ (+inf for a fixed base)."""
        return jnp.inf if self.fixed_base else self.threshold * self.block.alpha_r

    def run_end(self, mech, excitation, save=None, t1=None):
        """The latest end of a run: `t1` (default the last save time) for a history; for a summary
        `t1`, or 20 rocking periods 2π/p′ after the excitation."""
        if save is not None:
            return save.ts[-1] if t1 is None else t1
        t_end = excitation.t_end
        return t_end + 20 * 2 * jnp.pi / mech.p_r if t1 is None else jnp.maximum(t1, t_end)

    def solution(self, peak, over, t_over, t_up, status, ts_hist=None, hist=None, n_iterations=0) -> Solution:
        """The `Solution` of a run from its raw summary: peak max |θ| [rad] (clamped to the
        threshold; the threshold itself once overturned), overturned and its time, the uplift time
        (+inf: never), the status (a non-finite peak is `solver_failed`), the history."""
        alpha_r = self.block.alpha_r
        thr = self.threshold * alpha_r
        max_theta = jnp.where(over, self.threshold, jnp.minimum(peak, thr) / alpha_r)
        bad = ~jnp.isfinite(max_theta)
        status = Status.where(bad & (status == Status.ok), Status.solver_failed, status)
        max_theta = jnp.where(bad, jnp.nan, max_theta)
        return Solution(
            max_theta=max_theta,
            overturned=over,
            t_overturn=t_over,
            uplifted=jnp.isfinite(t_up),
            t_uplift=t_up,
            n_impacts=jnp.zeros((), int),
            status=status,
            ts=ts_hist,
            history=hist,
            n_iterations=n_iterations,
        )


def _quasi_rigid_scene(block: Block, cbar=None, backbone=None, smoothing=None) -> SpringModel:
    """A scenes file's quasi-rigid spring model (added masses; default damper, backbone, smoothing)."""
    return SpringModel(block, None, cbar=cbar, backbone=DEFAULT_BACKBONE if backbone is None else backbone,
                       smoothing=DEFAULT_SMOOTHING if smoothing is None else smoothing)


def _flexible_scene(block: Block, cbar=None, E=None, rho=None, zeta=None, backbone=None, smoothing=None) -> SpringModel:
    """A scenes file's flexible spring model: a concrete column unless E, ρ, ζ are given."""
    column = Column(DEFAULT_E if E is None else E, DEFAULT_RHO if rho is None else rho)
    return SpringModel(block, column, zeta=DEFAULT_ZETA if zeta is None else zeta, cbar=cbar,
                       backbone=DEFAULT_BACKBONE if backbone is None else backbone,
                       smoothing=DEFAULT_SMOOTHING if smoothing is None else smoothing)


register_model_kind("spring", _quasi_rigid_scene, ("cbar", "backbone", "smoothing"), "quasi-rigid spring model (SM), added masses")
register_model_kind("spring-flexible", _flexible_scene, ("cbar", "E", "rho", "zeta", "backbone", "smoothing"),
                    "spring model with an elastic column (concrete by default)")


__all__ = [
    "SpringModel",
    "SpringIntegrator",
    "GeneralizedAlpha",
    "Column",
    "cbar_eq17",
    "first_period_eq21",
    "pushover_eq9",
    "DEFAULT_SMOOTHING",
    "DEFAULT_BACKBONE",
]
