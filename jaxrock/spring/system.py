"""The spring model's assembled system: the arrays of one scene and the mechanics written on them
(energies → forces by `jax.grad`, the first-order form for diffrax, the second-order pieces for
generalized-α). Every integrator of the spring model takes a `SpringSystem`."""

from __future__ import annotations

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


class SpringSystem(eqx.Module):
    """The spring model assembled for a run (`SpringModel.system()`, built by `assemble`): every
    array a right-hand side needs, computed once per scene — a value, vmappable like the model.

    - sizes: `n` elements (None: the one-DOF quasi-rigid body), `ndof`;
    - mass: `m`, `Itot` (one-DOF inertia about the base centre), `M`, `rot_masses`, `Minv`
      (flexible), `mass_times` (M x from its structure);
    - base: `backbone`, `My`, `theta_s` (spring), `c` (damper, eq. 18), `fixed_base`;
    - column: `EA`, `EI`, `a1` (Rayleigh), `q_eq`, `V_eq` (the gravity-preloaded rest state), `r`
      (ground load vector);
    - energies and forces: `potential`, `kinetic`, `rigid_potential`, `forces`,
      `forces_without_spring`, `base_moment`, the first-order `vector_field`;
    - tangents for implicit steps: `mass_matrix`, `tangents` (K₀, C₀ at rest), `rotate`;
    - scales: `alpha_r`, `p_r`, `R_r`, `atol_scale` (tolerances per component), `deform_scale`;
    - state: `initial_state`, `split`, `history`;
    - the levels a run is watched against: `theta_up` (uplift), `settled` (a summary's stop)."""

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
    rot_masses: Array | None  # the nodal rotational masses of M (`beam.mass_times`)
    Minv: Array | None
    q_eq: Array | None
    V_eq: Array | None
    r: Array | None  # ground load vector p (`beam.ground_load`): f_ext = −üg p
    deform_scale: Array | float = 1.0  # fixed base: tolerance scales × (static drift / 2h α′)
    # a kinked backbone's branch the run is on (`AbstractBackbone.kinked`; None: the whole backbone)
    branch: Array | None = None

    @property
    def ndof(self) -> int:
        return 1 if self.n is None else beam.n_dof(self.n)

    @property
    def settle_margin(self):
        """Energy margin of a summary's settled test: exact for the one-DOF model; 10 % for the
        flexural P-Δ softening of a flexible column."""
        return 1.0 if self.n is None else 0.9

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

    def on_branch(self, branch) -> "SpringSystem":
        """This system with its spring continued from `branch` (`moment_on_branch`)."""
        return eqx.tree_at(lambda s: s.branch, self, jnp.asarray(branch, self.theta_s.dtype), is_leaf=lambda x: x is None)

    def kink_distance(self, theta, branch):
        """How far θ lies inside `branch` (0: |θ| < θs; ±1: ±θ > θs) [rad]: it falls through 0 at the kink."""
        return jnp.where(branch == 0, self.theta_s - jnp.abs(theta), branch * theta - self.theta_s)

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

    def elastic(self, q):
        """The column's strain energy from its preloaded rest state [J] (0 for the one-DOF body)."""
        if self.n is None:
            return jnp.zeros(())
        rest = beam.strain_energy(self.q_eq, self.h, self.n, self.EA, self.EI)
        return beam.strain_energy(q, self.h, self.n, self.EA, self.EI) - rest

    def kinetic(self, v):
        if self.n is None:
            return 0.5 * self.Itot * v[0] ** 2
        return 0.5 * v @ self.mass_times(v)

    # -- forces -----------------------------------------------------------------------------------
    def _column_damping(self, q, v):
        """Rayleigh force a₁ Jᵀ K_e J v on the local deformations (never on rigid motion)."""
        return self._column_forces(q, v)[1]

    def _column_forces(self, q, v):
        """(−∇V_column, Rayleigh force a₁ Jᵀ K_e J v): the strain energy's gradient and the
        deformation damping in closed form (`beam.internal_forces`); the gravity force is constant
        (the potential is linear in the heights)."""
        g_el, g_d = beam.internal_forces(q, v, self.h, self.n, self.EA, self.EI, self.a1)
        g_grav = jax.grad(beam.gravity_potential)(q, self.h, self.n, self.m)
        return -(g_el + g_grav), g_d

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

    def mass_times(self, x):
        """`mass_matrix() @ x`, from the matrix's structure (`beam.mass_times`)."""
        return self.Itot * x if self.n is None else beam.mass_times(x, self.n, self.m, self.rot_masses)

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
            parts.append(self.powers(v, f_ext, f_damp))
        return jnp.concatenate(parts)

    def powers(self, v, f_ext, f_damp):
        """The rates of the work integrals `WORK_FIELDS` [W]: the damper's c θ̇², the column's
        Rayleigh v·f_R (the rest of v·f_damp) and the ground's v·f_ext."""
        damper = jnp.zeros(()) if self.fixed_base else self.c * v[0] ** 2
        rayleigh = jnp.zeros(()) if self.n is None else v @ f_damp - damper
        return jnp.stack([damper, rayleigh, v @ f_ext])

    def initial_state(self, theta0=0.0, theta_dot0=0.0):
        theta0 = jnp.asarray(theta0, dtype=float)
        theta_dot0 = jnp.asarray(theta_dot0, dtype=float)
        if self.n is None:
            q = jnp.atleast_1d(theta0)
            v = jnp.atleast_1d(theta_dot0)
        else:
            x, y, phi = beam.positions(self.q_eq, self.h, self.n)
            c, s = jnp.cos(theta0), jnp.sin(theta0)
            # clockwise rigid rotation about the base (top moves to +x for θ0 > 0)
            xr, yr = x * c + y * s, -x * s + y * c
            q = beam.from_positions(xr, yr, phi + theta0, self.h, self.n)
            # rigid angular velocity ω0: ẋ = ω0 y, ẏ = −ω0 x, φ̇ = ω0
            v = beam.from_positions(theta_dot0 * yr, -theta_dot0 * xr + beam.node_heights(self.h, self.n), jnp.full_like(phi, theta_dot0), self.h, self.n)
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
        if self.n is None:
            sq = jnp.ones(1) * self.alpha_r
        else:
            unit = jnp.tile(jnp.array([2.0, 2.0, 0.0]), self.n)
            sq = jnp.concatenate([jnp.zeros(1), unit])
            sq = jnp.where(sq > 0, self.h * sq, 1.0) * self.alpha_r
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
                out[name] = 2 * self.h * jnp.sin(theta) if self.n is None else beam.top_displacement(q, self.h, self.n)
            elif name == "w_top":
                u = 2 * self.h * jnp.sin(theta) if self.n is None else beam.top_displacement(q, self.h, self.n)
                out[name] = u - 2 * self.h * jnp.sin(theta)
            elif name == "base_moment":
                out[name] = self.base_moment(t, q, v, excitation)
            elif name == "section_moment":  # the one-DOF column transmits the base moment
                out[name] = (self.base_moment(t, q, v, excitation) if self.n is None
                             else beam.base_section_moment(q, v, self.h, self.n, self.EA, self.EI, self.a1))
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



def assemble(model, track_energy: bool = False) -> SpringSystem:
    """Assemble the `SpringSystem` of a `SpringModel`: mass, yield moment and pre-yield rotation,
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
    if model.column is None:
        return SpringSystem(n=None, EA=None, EI=None, a1=None, M=None, rot_masses=None, Minv=None, q_eq=None, V_eq=None, r=None, **common)
    n = model.n_elements
    A, I = model.column.section(blk)
    EA, EI = model.column.E * A, model.column.E * I
    rot_masses = model.rotational_masses()
    M = beam.mass_matrix(blk.h, n, m, rot_masses)
    Minv = _linalg.inv(M)
    Minv = 0.5 * (Minv + Minv.T)
    _, a1 = model.rayleigh()
    sys_ = SpringSystem(n=n, EA=EA, EI=EI, a1=a1, M=M, rot_masses=rot_masses, Minv=Minv, q_eq=jnp.zeros(beam.n_dof(n)), V_eq=jnp.zeros(()), r=beam.ground_load(n, m), **common)
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
