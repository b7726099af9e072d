"""The spring model's assembled system: the arrays of one scene and the mechanics written on them
(energies → forces by `jax.grad`, the first-order form for diffrax, the second-order pieces for
generalized-α). Every integrator of the spring model takes one: a `QuasiRigidSystem` or a
`FlexibleSystem` (`AbstractSpringSystem`, also named `SpringSystem`)."""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from .. import _linalg
from ..geometry import G
from . import beam
from .base_spring import AbstractBackbone, damper

HISTORY_FIELDS = (
    "theta",
    "theta_dot",
    "u_top",
    "w_top",
    "base_moment",
    "section_moment",
    "kinetic",
    "potential",
    "elastic",
    "dissipated",
    "damper",
    "rayleigh",
    "input",
)
# the energy terms [J]: kinetic, potential (gravity + spring + column strain, from the rest state),
# elastic (the column's strain energy alone), the work dissipated (damper + rayleigh) and the
# ground's input work; kinetic + potential + dissipated = input (the balance)
ENERGY_FIELDS = ("kinetic", "potential", "elastic", "dissipated", "damper", "rayleigh", "input")
WORK_FIELDS = ("damper", "rayleigh", "input")  # the work integrals tracked beside the state


class AbstractSpringSystem(eqx.Module):
    """The spring model assembled for a run: every array a right-hand side needs, computed once per scene.

    Made by `AbstractSpringModel.system()` (built by `assemble`), never constructed directly; a
    value, vmappable like the model. Two final kinds (issue 57): `QuasiRigidSystem`, the one-DOF
    body, and `FlexibleSystem`, the corotational beam column; what they share is written here on
    what each supplies (its column's potential, forces, mass, rest state and tolerance scales).
    `SpringSystem` is its name before the split: either kind. Its members:

    - sizes: `ndof`;
    - mass: `m`, `Itot` (one-DOF inertia about the base centre), `mass_matrix`, `mass_times`;
    - base: `backbone`, `My`, `theta_s` (spring), `c` (damper, eq. 18), `fixed_base`;
    - energies and forces: `potential`, `kinetic`, `elastic`, `rigid_potential`, `forces`,
      `forces_without_spring`, `base_moment`, the first-order `vector_field`;
    - tangents for implicit steps: `tangents` (K₀, C₀ at rest), `rotate`;
    - scales: `alpha_r`, `p_r`, `R_r`, `atol_scale` (tolerances per component), `deform_scale`;
    - state: `initial_state`, `split`, `history`;
    - the levels a run is watched against: `theta_up` (uplift), `settled` (a summary's stop).

    Attributes:
        fixed_base: (static) base rotation clamped.
        track_energy: (static) the work integrals (damper, Rayleigh, input) integrated alongside the state.
        backbone: (static) the spring's backbone (`AbstractBackbone`).
        h: half-height h [m].
        m: column mass m [kg].
        My: the spring's yield moment My = m g b′ [N·m].
        theta_s: the backbone's pre-yield rotation θs = smoothing · α′ [rad].
        c: the damper coefficient c (eq. 18) [N·m·s].
        alpha_r: the rocking slenderness angle α′ [rad].
        p_r: the rocking frequency parameter p′ [rad/s].
        R_r: the rocking half-diagonal R′ [m].
        Itot: one-DOF inertia about the base centre [kg·m²] (also used for the flexible model's rigid potential).
        deform_scale: with a fixed base, the tolerance scales × (static drift / 2h α′).
        branch: a kinked backbone's branch the run is on (`AbstractBackbone.kinked`; None: the whole backbone).
    """

    fixed_base: eqx.AbstractVar[bool]
    track_energy: eqx.AbstractVar[bool]
    backbone: eqx.AbstractVar[AbstractBackbone]
    h: eqx.AbstractVar[Array]
    m: eqx.AbstractVar[Array]
    My: eqx.AbstractVar[Array]
    theta_s: eqx.AbstractVar[Array]
    c: eqx.AbstractVar[Array]
    alpha_r: eqx.AbstractVar[Array]
    p_r: eqx.AbstractVar[Array]
    R_r: eqx.AbstractVar[Array]
    Itot: eqx.AbstractVar[Array]  # one-DOF inertia (also used for the rigid potential of the flexible model)
    deform_scale: eqx.AbstractVar[Array | float]  # fixed base: tolerance scales × (static drift / 2h α′)
    # a kinked backbone's branch the run is on (`AbstractBackbone.kinked`; None: the whole backbone)
    branch: eqx.AbstractVar[Array | None]

    # -- what each kind supplies ------------------------------------------------------------------
    @property
    @abc.abstractmethod
    def ndof(self) -> int:
        """Degrees of freedom (q[0] = θ, the base rotation)."""

    @property
    @abc.abstractmethod
    def settle_margin(self) -> float:
        """Energy margin of a summary's settled test (`settle_energy`)."""

    @abc.abstractmethod
    def _column_potential(self, q):
        """Gravity (+ strain) potential of the column, spring excluded."""

    @abc.abstractmethod
    def _from_rest(self, V):
        """A potential counted from the (preloaded) rest state."""

    @abc.abstractmethod
    def elastic(self, q):
        """The column's strain energy from its preloaded rest state [J]."""

    @abc.abstractmethod
    def kinetic(self, v):
        """Kinetic energy [J]."""

    @abc.abstractmethod
    def _column_terms(self, q, v, ug):
        """(f_ext, f_col, f_dcol): the ground's load, the column's conservative force and its
        deformation damping at ground acceleration `ug`."""

    @abc.abstractmethod
    def _gravity_force(self, q):
        """−∇ of the column's gravity potential alone: the generalised weight [N, N·m]."""

    @abc.abstractmethod
    def mass_matrix(self):
        """M (N × N)."""

    @abc.abstractmethod
    def mass_times(self, x):
        """`mass_matrix() @ x`, from the matrix's structure."""

    @abc.abstractmethod
    def _accelerate(self, f):
        """M⁻¹ f."""

    @abc.abstractmethod
    def _rest_q(self):
        """q at rest (θ = 0, preloaded)."""

    @abc.abstractmethod
    def _damping_at_rest(self, q0):
        """The column's deformation damping matrix at `q0` (spring damper excluded)."""

    @abc.abstractmethod
    def rotate(self, x, theta):
        """Tangent vectors of the column rotated rigidly by θ about the base (T(θ) x). The strain
        energy is invariant under the rigid rotation, so its Hessian there is T K₀ Tᵀ, and M and
        the deformation damping are invariant: the tangent at a rocked configuration is the rest
        tangent rotated."""

    @abc.abstractmethod
    def _rayleigh_power(self, v, f_damp, damper):
        """The column's Rayleigh power [W] (the rest of v·f_damp beyond the damper's)."""

    @abc.abstractmethod
    def _rotated_rest(self, theta0, theta_dot0):
        """(q, v): the rest state rotated rigidly by θ0 with angular velocity θ̇0."""

    @abc.abstractmethod
    def _q_scale(self):
        """Per-coordinate size of a rocking motion: α′ for rotations, 2h α′ for displacements."""

    @abc.abstractmethod
    def top_displacement(self, q):
        """Horizontal displacement of the column's top [m]."""

    @abc.abstractmethod
    def _section_moment(self, t, q, v, excitation):
        """Bending moment of the column's base section [N·m]."""

    # -- shared mechanics -------------------------------------------------------------------------
    def settle_energy(self, peak):
        """`settle_margin` × the rigid potential at the peak |θ| so far: below this mechanical energy
        |θ| can never reach that peak again (`jaxrock.spring`)."""
        return self.settle_margin * self.rigid_potential(peak)

    def settled(self, energy, peak):
        """A summary's stop: the mechanical energy below `settle_energy(peak)`."""
        return energy < self.settle_energy(peak)

    @property
    def theta_up(self):
        """Uplift rotation: the spring has (all but) yielded beyond it (`AbstractBackbone.band` θs)."""
        return self.backbone.band * self.theta_s

    # -- energies -------------------------------------------------------------------------------
    def spring_potential(self, theta):
        return self.backbone.potential(theta, self.My, self.theta_s)

    def spring_moment(self, theta):
        if self.branch is not None:
            return self.backbone.moment_on_branch(theta, self.My, self.theta_s, self.branch)
        return self.backbone.moment(theta, self.My, self.theta_s)

    # -- a kinked backbone's branches (`AbstractBackbone.kinked`) --------------------------------
    def branch_at(self, theta):
        """The branch of a kinked backbone at θ: 0 pre-yield (|θ| ≤ θs), else sign θ."""
        return jnp.where(jnp.abs(theta) <= self.theta_s, 0.0, jnp.sign(theta))

    def on_branch(self, branch) -> "AbstractSpringSystem":
        """This system with its spring continued from `branch` (`moment_on_branch`)."""
        return eqx.tree_at(lambda s: s.branch, self, jnp.asarray(branch, self.theta_s.dtype), is_leaf=lambda x: x is None)

    def kink_distance(self, theta, branch):
        """How far θ lies inside `branch` (0: |θ| < θs; ±1: ±θ > θs) [rad]: it falls through 0 at the kink."""
        return jnp.where(branch == 0, self.theta_s - jnp.abs(theta), branch * theta - self.theta_s)

    def potential(self, q):
        """Total potential relative to the (preloaded) rest state [J]."""
        V = self._column_potential(q)
        if not self.fixed_base:
            V = V + self.spring_potential(q[0])
        return self._from_rest(V)

    def rigid_potential(self, theta):
        """One-DOF SM potential at zero velocity (exact for the quasi-rigid scene):
        My θs log cosh(θ/θs) − m g h (1 − cosθ) → SPEC's E(θ) = m g R(sinα|θ| − cosα(1 − cosθ))
        as θs → 0 (for a plain block, My = m g R sinα and h = R cosα)."""
        return self.spring_potential(theta) - self.m * G * self.h * (1 - jnp.cos(theta))

    # -- forces -----------------------------------------------------------------------------------
    def forces(self, t, q, v, excitation):
        """(f_total, f_ext, f_damp, f_nospring): generalised forces [N, N·m].

        A vertical ground acceleration üv scales gravity by 1 + üv/g: the weight's forces on the
        column (`_gravity_force`) and the spring's moment, which the weight holds (My = m g b′); that
        share is a ground load, in f_ext (so the input work balances the energy)."""
        f_ext, f_col, f_dcol = self._column_terms(q, v, excitation(t))
        if excitation.has_vertical:
            uv = excitation.vertical_acceleration(t) / G
            f_ext = f_ext + uv * self._gravity_force(q)
            if not self.fixed_base:
                f_ext = f_ext.at[0].add(-uv * self.spring_moment(q[0]))
        f_nospring = f_ext + f_col - f_dcol
        if self.fixed_base:
            f_sp = jnp.zeros_like(q)
        else:
            f_sp = jnp.zeros_like(q).at[0].set(self.spring_moment(q[0]) + self.c * v[0])
        f_damp = f_dcol + jnp.zeros_like(q).at[0].set(0.0 if self.fixed_base else self.c * v[0])
        return f_nospring - f_sp, f_ext, f_damp, f_nospring

    def base_moment(self, t, q, v, excitation):
        """Spring + damper moment (1 + üv/g) M(θ) + c θ̇ [N·m]; for a fixed base the reaction moment."""
        if self.fixed_base:
            return self.forces(t, q, v, excitation)[3][0]
        moment = self.spring_moment(q[0])
        if excitation.has_vertical:
            moment = (1 + excitation.vertical_acceleration(t) / G) * moment
        return moment + self.c * v[0]

    # -- second-order form (generalized-α) -------------------------------------------------------
    def forces_without_spring(self, t, q, v, excitation):
        """(f_rest, f_ext, f_damp) with the total force f_rest − M(θ) e₀: everything but the
        spring's elastic moment M(θ), which the generalized-α step solves for exactly."""
        f_total, f_ext, f_damp, _ = self.forces(t, q, v, excitation)
        if not self.fixed_base:
            f_total = f_total.at[0].add(self.spring_moment(q[0]))
        return f_total, f_ext, f_damp

    def tangents(self):
        """(K₀, C₀): stiffness (Hessian of the column potential, spring excluded) and damping
        (Rayleigh on the deformations + the base damper) at the preloaded rest state."""
        q0 = self._rest_q()
        K0 = jax.hessian(self._column_potential)(q0)
        C0 = self._damping_at_rest(q0)
        if not self.fixed_base:
            C0 = C0.at[0, 0].add(self.c)
        return K0, C0

    # -- first-order form -------------------------------------------------------------------------
    def split(self, y):
        N = self.ndof
        return y[:N], y[N : 2 * N]

    def vector_field(self, t, y, excitation):
        q, v = self.split(y)
        f, f_ext, f_damp, _ = self.forces(t, q, v, excitation)
        a = self._accelerate(f)
        if self.fixed_base:
            a = a.at[0].set(0.0)
        parts = [v, a]
        if self.track_energy:
            parts.append(self.powers(v, f_ext, f_damp))
        return jnp.concatenate(parts)

    def powers(self, v, f_ext, f_damp):
        """The rates of the work integrals `WORK_FIELDS` [W]: the damper's c θ̇², the column's
        Rayleigh v·f_R (the rest of v·f_damp) and the ground's v·f_ext."""
        damper = jnp.zeros(()) if self.fixed_base else self.c * v[0] ** 2
        return jnp.stack([damper, self._rayleigh_power(v, f_damp, damper), v @ f_ext])

    def initial_state(self, theta0=0.0, theta_dot0=0.0):
        """y at rest (gravity-preloaded column) rotated rigidly by θ0 with angular velocity θ̇0."""
        q, v = self._rotated_rest(jnp.asarray(theta0, dtype=float), jnp.asarray(theta_dot0, dtype=float))
        y0 = [q, v]
        if self.track_energy:
            y0.append(jnp.zeros(len(WORK_FIELDS)))
        return jnp.concatenate(y0)

    def atol_scale(self):
        """Per-component scale of the absolute tolerance: α′ for rotations, 2h α′ for
        displacements, × p′ for velocities, m g R′ α′ for the energy integrals — the sizes of a
        rocking motion. A fixed-base column never rocks: all scales shrink by its static drift under
        m g tanα′ over 2h α′ (`deform_scale`; 1/473 for the figure-17 chimney), so that its
        vibration, not a rocking it cannot do, sets the tolerance."""
        sq = self._q_scale()
        parts = [sq, sq * self.p_r]
        if self.track_energy:
            parts.append(jnp.ones(len(WORK_FIELDS)) * self.m * G * self.R_r * self.alpha_r)
        return jnp.concatenate(parts) * self.deform_scale

    def mechanical_energy(self, y):
        q, v = self.split(y)
        return self.kinetic(v) + self.potential(q)

    def history(self, t, y, excitation, fields):
        q, v = self.split(y)
        theta, theta_dot = q[0], v[0]
        work = dict(zip(WORK_FIELDS, y[2 * self.ndof :])) if self.track_energy else {}
        out = {}
        for name in fields:
            if name == "theta":
                out[name] = theta
            elif name == "theta_dot":
                out[name] = theta_dot
            elif name == "u_top":
                out[name] = self.top_displacement(q)
            elif name == "w_top":
                out[name] = self.top_displacement(q) - 2 * self.h * jnp.sin(theta)
            elif name == "base_moment":
                out[name] = self.base_moment(t, q, v, excitation)
            elif name == "section_moment":
                out[name] = self._section_moment(t, q, v, excitation)
            elif name == "kinetic":
                out[name] = self.kinetic(v)
            elif name == "potential":
                out[name] = self.potential(q)
            elif name == "elastic":
                out[name] = self.elastic(q)
            elif name == "dissipated":
                out[name] = work["damper"] + work["rayleigh"]
            elif name in WORK_FIELDS:
                out[name] = work[name]
        return out


SpringSystem = AbstractSpringSystem  # the name before the split (issue 57): either kind


class QuasiRigidSystem(AbstractSpringSystem):
    """The one-DOF quasi-rigid body on its spring: q = [θ]."""

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
    Itot: Array
    deform_scale: Array | float = eqx.field(default=1.0, kw_only=True)
    branch: Array | None = eqx.field(default=None, kw_only=True)

    @property
    def ndof(self) -> int:
        return 1

    @property
    def settle_margin(self) -> float:
        return 1.0  # exact for the one-DOF model

    def _column_potential(self, q):
        return self.m * G * self.h * (jnp.cos(q[0]) - 1.0)

    def _from_rest(self, V):
        return V

    def elastic(self, q):
        return jnp.zeros(())

    def kinetic(self, v):
        return 0.5 * self.Itot * v[0] ** 2

    def _column_terms(self, q, v, ug):
        f_ext = jnp.atleast_1d(-self.m * ug * self.h * jnp.cos(q[0]))  # eq. 10 right-hand side
        return f_ext, self._gravity_force(q), jnp.zeros_like(q)

    def _gravity_force(self, q):
        return -jax.grad(self._column_potential)(q)  # the body's potential is its weight's

    def mass_matrix(self):
        return jnp.reshape(self.Itot, (1, 1))

    def mass_times(self, x):
        return self.Itot * x

    def _accelerate(self, f):
        return f / self.Itot

    def _rest_q(self):
        return jnp.zeros(1)

    def _damping_at_rest(self, q0):
        return jnp.zeros((1, 1))

    def rotate(self, x, theta):
        return x

    def _rayleigh_power(self, v, f_damp, damper):
        return jnp.zeros(())

    def _rotated_rest(self, theta0, theta_dot0):
        return jnp.atleast_1d(theta0), jnp.atleast_1d(theta_dot0)

    def _q_scale(self):
        return jnp.ones(1) * self.alpha_r

    def top_displacement(self, q):
        return 2 * self.h * jnp.sin(q[0])

    def _section_moment(self, t, q, v, excitation):
        return self.base_moment(t, q, v, excitation)  # the one-DOF column transmits the base moment


class FlexibleSystem(AbstractSpringSystem):
    """The corotational Euler–Bernoulli column of `n` elements on its spring (`beam`): q = [θ, then
    (u_x, u_y, φ) per node above the base]."""

    n: int = eqx.field(static=True)
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
    Itot: Array
    EA: Array
    EI: Array
    a1: Array  # Rayleigh, stiffness proportional
    M: Array
    rot_masses: Array  # the nodal rotational masses of M (`beam.mass_times`)
    Minv: Array
    q_eq: Array  # the gravity-preloaded rest state
    V_eq: Array
    r: Array  # ground load vector p (`beam.ground_load`): f_ext = −üg p
    deform_scale: Array | float = eqx.field(default=1.0, kw_only=True)
    branch: Array | None = eqx.field(default=None, kw_only=True)

    @property
    def ndof(self) -> int:
        return beam.n_dof(self.n)

    @property
    def settle_margin(self) -> float:
        return 0.9  # 10 % for the flexural P-Δ softening of a flexible column

    def _column_potential(self, q):
        V = beam.strain_energy(q, self.h, self.n, self.EA, self.EI)
        V = V + beam.gravity_potential(q, self.h, self.n, self.m)
        return V

    def _from_rest(self, V):
        return V - self.V_eq

    def elastic(self, q):
        rest = beam.strain_energy(self.q_eq, self.h, self.n, self.EA, self.EI)
        return beam.strain_energy(q, self.h, self.n, self.EA, self.EI) - rest

    def kinetic(self, v):
        return 0.5 * v @ self.mass_times(v)

    def _column_forces(self, q, v):
        """(−∇V_column, Rayleigh force a₁ Jᵀ K_e J v): the strain energy's gradient and the
        deformation damping in closed form (`beam.internal_forces`); the gravity force is constant
        (the potential is linear in the heights)."""
        g_el, g_d = beam.internal_forces(q, v, self.h, self.n, self.EA, self.EI, self.a1)
        g_grav = jax.grad(beam.gravity_potential)(q, self.h, self.n, self.m)
        return -(g_el + g_grav), g_d

    def _column_terms(self, q, v, ug):
        f_col, f_dcol = self._column_forces(q, v)
        return -ug * self.r, f_col, f_dcol

    def _gravity_force(self, q):
        return -jax.grad(beam.gravity_potential)(q, self.h, self.n, self.m)

    def mass_matrix(self):
        return self.M

    def mass_times(self, x):
        return beam.mass_times(x, self.n, self.m, self.rot_masses)

    def _accelerate(self, f):
        return self.Minv @ f

    def _rest_q(self):
        return self.q_eq

    def _damping_at_rest(self, q0):
        return jax.jacfwd(lambda v: self._column_forces(q0, v)[1])(jnp.zeros(self.ndof))

    def rotate(self, x, theta):
        c, s = jnp.cos(theta), jnp.sin(theta)
        rest = x[1:].reshape(self.n, 3)
        ux, uy = rest[:, 0], rest[:, 1]
        rest = jnp.stack([c * ux + s * uy, -s * ux + c * uy, rest[:, 2]], axis=1)
        return jnp.concatenate([x[:1], rest.reshape(-1)])

    def _rayleigh_power(self, v, f_damp, damper):
        return v @ f_damp - damper

    def _rotated_rest(self, theta0, theta_dot0):
        x, y, phi = beam.positions(self.q_eq, self.h, self.n)
        c, s = jnp.cos(theta0), jnp.sin(theta0)
        # clockwise rigid rotation about the base (top moves to +x for θ0 > 0)
        xr, yr = x * c + y * s, -x * s + y * c
        q = beam.from_positions(xr, yr, phi + theta0, self.h, self.n)
        # rigid angular velocity ω0: ẋ = ω0 y, ẏ = −ω0 x, φ̇ = ω0
        v = beam.from_positions(theta_dot0 * yr, -theta_dot0 * xr + beam.node_heights(self.h, self.n), jnp.full_like(phi, theta_dot0), self.h, self.n)
        return q, v

    def _q_scale(self):
        unit = jnp.tile(jnp.array([2.0, 2.0, 0.0]), self.n)
        sq = jnp.concatenate([jnp.zeros(1), unit])
        return jnp.where(sq > 0, self.h * sq, 1.0) * self.alpha_r

    def top_displacement(self, q):
        return beam.top_displacement(q, self.h, self.n)

    def _section_moment(self, t, q, v, excitation):
        return beam.base_section_moment(q, v, self.h, self.n, self.EA, self.EI, self.a1)


def assemble(model, track_energy: bool = False) -> AbstractSpringSystem:
    """Assemble the system of a `SpringModel` (`QuasiRigidSystem`, `FlexibleSystem`): mass, yield moment and pre-yield rotation,
    damper (eq. 18), inertia; for a flexible column the mass matrix and its inverse, the Rayleigh
    coefficient, the gravity-preloaded rest state (Newton on ∇V = 0) and, for a fixed base, the
    tolerance scale of its static drift."""
    blk = model.block
    m = model.mass()
    My = m * G * blk.b_base  # = m g R′ sinα′
    theta_s = model.smoothing * blk.alpha_r
    c = damper(model.cbar, m, blk.R_r)  # eq. 18
    Itot = model.total_inertia()
    common = dict(
        fixed_base=model.fixed_base,
        track_energy=track_energy,
        backbone=model.backbone,
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
    if not model.flexible:
        return QuasiRigidSystem(**common)
    n = model.n_elements
    A, I = model.column.section(blk)
    EA, EI = model.column.E * A, model.column.E * I
    rot_masses = model.rotational_masses()
    M = beam.mass_matrix(blk.h, n, m, rot_masses)
    Minv = _linalg.inv(M)
    Minv = 0.5 * (Minv + Minv.T)
    _, a1 = model.rayleigh()
    sys_ = FlexibleSystem(n=n, EA=EA, EI=EI, a1=a1, M=M, rot_masses=rot_masses, Minv=Minv, q_eq=jnp.zeros(beam.n_dof(n)), V_eq=jnp.zeros(()),
                          r=beam.ground_load(n, m), **common)
    # gravity preload: static equilibrium at θ = 0 (axial shortening), by Newton on ∇V = 0
    N = beam.n_dof(n)
    grad_v = jax.grad(sys_._column_potential)
    hess_v = jax.hessian(sys_._column_potential)
    q = jnp.zeros(N)
    free = jnp.ones(N).at[0].set(0.0)  # keep θ = 0
    for _ in range(3):
        g_ = grad_v(q) * free
        H = hess_v(q) * free[:, None] * free[None, :] + jnp.diag(1.0 - free)
        q = q - _linalg.solve(H, g_)
    V_eq = sys_._column_potential(q)
    sys_ = eqx.tree_at(lambda s: (s.q_eq, s.V_eq), sys_, (q, V_eq))
    if model.fixed_base:
        # static drift of the clamped column under a lateral m g tanα′ (its mass distribution)
        K = beam.linear_stiffness(blk.h, n, EA, EI)[1:, 1:]
        u = _linalg.solve(K, sys_.r[1:] * G * jnp.tan(blk.alpha_r))
        drift = jnp.abs(beam.top_displacement(jnp.concatenate([jnp.zeros(1), u]), blk.h, n))
        sys_ = eqx.tree_at(lambda s: s.deform_scale, sys_, drift / (2 * blk.h * blk.alpha_r))
    return sys_
