"""Planar corotational Euler–Bernoulli beam-column (paper section 4, SPEC "Spring model").

The column of height `2h` stands on the base node 0 at the origin and is cut into `n` equal
elements (`n + 1` nodes at heights `z_i = i·2h/n`). Degrees of freedom (the vector `q`, length
`N = 3n + 1`), all relative to the ground:

    q = [φ₀, u_x1, u_y1, φ₁, …, u_xn, u_yn, φ_n]

`φ₀` is the base rotation θ (the rotational spring's rotation; the base translations are fixed,
so node 0 has no translational DOF). Rotations and the chord angle are measured clockwise from the
vertical, so that a positive θ moves the top towards +x (u_c = 2h sinθ, eq. 5).

Everything is derived from energies with JAX autodiff (jax-md style):

- corotational strain energy (large rotations, small strains): each element's chord of current
  length L and angle β carries the local deformations `(L − L₀, φ_i − β, φ_j − β)`;
  `U_e = EA/(2L₀)(L − L₀)² + EI/L₀ (2θ₁² + 2θ₁θ₂ + 2θ₂²)`. The nonlinear kinematics with the
  gravity potential gives the geometric (P-Δ) negative stiffness;
- gravity potential of the distributed mass: `g Σ m_e y_centroid` (linear along each chord: exact);
- kinetic energy with the *rod-consistent* translational mass (velocity linear along each chord):
  it is rotation invariant and exact for any rigid-body motion, so a rigid rotation of the column
  has exactly `(4/3) m h²` about the base, at any θ. The Hermite-consistent beam mass is not
  rotation invariant in a corotational setting (its rigid-body inertia is wrong by ~(1 − cosθ) or
  needs configuration-dependent mass and gyroscopic terms); the rod mass costs 0.2–0.3 % in the
  first period at 10 elements (measured, `tests/test_spring.py`), see `first_period`;
- rotational inertia at the nodes: the added masses `ΔI/nnod` (paper) or, without them, the
  section's rotary inertia `ρ I L_trib` (Rayleigh beam), which keeps the mass matrix regular;
- Rayleigh stiffness-proportional damping acting on the local deformations only (a dissipation
  function `½ a₁ Σ ḋ_eᵀ K_e ḋ_e`), so rigid-body rotation is never damped.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import _linalg
from ..geometry import G


def n_dof(n: int) -> int:
    return 3 * n + 1


def node_heights(h, n: int) -> Float[Array, " n+1"]:
    return 2 * h * jnp.arange(n + 1) / n


def positions(q, h, n: int):
    """Current nodal positions x, y (n+1 each) and rotations φ (n+1) from q."""
    z = node_heights(h, n)
    rest = q[1:].reshape(n, 3)
    x = jnp.concatenate([jnp.zeros(1, q.dtype), rest[:, 0]])
    y = z + jnp.concatenate([jnp.zeros(1, q.dtype), rest[:, 1]])
    phi = jnp.concatenate([q[:1], rest[:, 2]])
    return x, y, phi


def from_positions(x, y, phi, h, n: int):
    z = node_heights(h, n)
    rest = jnp.stack([x[1:], y[1:] - z[1:], phi[1:]], axis=1).reshape(-1)
    return jnp.concatenate([phi[:1], rest])


def _chords(q, h, n: int):
    """Every element's chord (Δx, Δy) and the node rotations φ (of velocities with h = 0)."""
    x, y, phi = positions(q, h, n)
    return x[1:] - x[:-1], y[1:] - y[:-1], phi


def element_deformations(q, h, n: int):
    """Local deformations of every element: axial extension L − L₀ and end rotations relative to
    the chord, θ₁ = φ_i − β, θ₂ = φ_j − β (β: chord angle clockwise from vertical)."""
    dx, dy, phi = _chords(q, h, n)
    L0 = 2 * h / n
    L = jnp.sqrt(dx**2 + dy**2)
    beta = jnp.arctan2(dx, dy)
    return L - L0, phi[:-1] - beta, phi[1:] - beta


def strain_energy(q, h, n: int, EA, EI):
    """Corotational strain energy Σ U_e (see module docstring)."""
    L0 = 2 * h / n
    e, t1, t2 = element_deformations(q, h, n)
    return jnp.sum(0.5 * EA / L0 * e**2 + EI / L0 * 2 * (t1**2 + t1 * t2 + t2**2))


def local_forces(d, h, n: int, EA, EI):
    """K_e d per element: the axial force and the two end moments (N, M₁, M₂) = ∂U_e/∂d."""
    L0 = 2 * h / n
    e, t1, t2 = d
    return EA / L0 * e, EI / L0 * (4 * t1 + 2 * t2), EI / L0 * (2 * t1 + 4 * t2)


def _element_forces(q, v, h, n: int, EA, EI, a1):
    """Every element's local forces (N, M₁, M₂), each stacked [elastic, Rayleigh], and its chord
    (Δx, Δy, L, L²)."""
    d = element_deformations(q, h, n)
    dx, dy, _ = _chords(q, h, n)  # (L and β: the same expressions as d's, computed once by XLA)
    dvx, dvy, vphi = _chords(v, 0.0 * h, n)  # node velocities (no rest heights)
    L2 = dx**2 + dy**2
    L = jnp.sqrt(L2)
    beta_dot = (dy * dvx - dx * dvy) / L2
    d_dot = ((dx * dvx + dy * dvy) / L, vphi[:-1] - beta_dot, vphi[1:] - beta_dot)
    forces = tuple(jnp.stack([a, a1 * b]) for a, b in zip(local_forces(d, h, n, EA, EI), local_forces(d_dot, h, n, EA, EI)))
    return forces, (dx, dy, L, L2)


def base_section_moment(q, v, h, n: int, EA, EI, a1):
    """The bending moment in the column's lowest section [N·m]: the first element's end moment at its
    lower node, elastic plus Rayleigh (paper figure 17's "bending moment at the base"), with the
    sign of the base's reaction moment (−M₁)."""
    (_, M1, _), _ = _element_forces(q, v, h, n, EA, EI, a1)
    return -(M1[0, 0] + M1[1, 0])


def internal_forces(q, v, h, n: int, EA, EI, a1):
    """(∇U, a₁ Jᵀ K_e J v): the gradient of `strain_energy` and the Rayleigh force on the element
    deformations, in closed form. d = (L − L₀, φ_i − β, φ_j − β) has the Jacobian J with
    ∂L/∂(x_j, y_j) = (Δx, Δy)/L and ∂β/∂(x_j, y_j) = (Δy, −Δx)/L² (β = atan2(Δx, Δy); node i:
    the negatives), so an element's local forces (N, M₁, M₂) act on its nodes as
    ±(N Δx/L − (M₁ + M₂) Δy/L², N Δy/L + (M₁ + M₂) Δx/L²) and M₁, M₂ on φ_i, φ_j. The same as
    `jax.grad(strain_energy)` and the transposed linearisation (tests/test_spring.py), without
    the pads and splits of the autodiff transpose, which cost ~5× more under `vmap` on CPU."""
    (N, M1, M2), (dx, dy, L, L2) = _element_forces(q, v, h, n, EA, EI, a1)
    fx = N * dx / L - (M1 + M2) * dy / L2
    fy = N * dy / L + (M1 + M2) * dx / L2
    f_j = jnp.stack([fx, fy, M2], axis=-1)  # (2, n, 3): on the element's upper node j
    f_i = jnp.stack([-fx, -fy, M1], axis=-1)  # on its lower node i
    zero = jnp.zeros((2, 1, 3), q.dtype)
    nodes = jnp.concatenate([f_i, zero], axis=1) + jnp.concatenate([zero, f_j], axis=1)  # (2, n + 1, 3)
    f = jnp.concatenate([nodes[:, 0, 2:], nodes[:, 1:].reshape(2, -1)], axis=1)
    return f[0], f[1]


def gravity_potential(q, h, n: int, m):
    """g Σ m_e ȳ_e: the column's gravity potential (mass m spread uniformly; exact for straight
    chords). Measured from the ground."""
    _, y, _ = positions(q, h, n)
    return G * (m / n) * jnp.sum(0.5 * (y[1:] + y[:-1]))


def mass_matrix(h, n: int, m, rot_masses) -> Float[Array, "N N"]:
    """Constant mass matrix: rod-consistent translational mass (exact for rigid motion at any
    rotation) and the nodal rotational masses `rot_masses` (n+1 values, node 0 first)."""
    N = n_dof(n)
    me = m / n
    Mt = jnp.zeros((n + 1, n + 1))
    i = jnp.arange(n)
    Mt = Mt.at[i, i].add(me / 3).at[i + 1, i + 1].add(me / 3).at[i, i + 1].add(me / 6).at[i + 1, i].add(me / 6)
    M = jnp.zeros((N, N))
    ix = 1 + 3 * jnp.arange(n)  # u_x of nodes 1..n
    iy = ix + 1
    M = M.at[ix[:, None], ix[None, :]].set(Mt[1:, 1:])
    M = M.at[iy[:, None], iy[None, :]].set(Mt[1:, 1:])
    irot = jnp.concatenate([jnp.zeros(1, int), 3 + 3 * jnp.arange(n)])
    M = M.at[irot, irot].add(rot_masses)
    return M


def mass_times(x, n: int, m, rot_masses):
    """`mass_matrix(h, n, m, rot_masses) @ x` from its structure: the rod mass couples each node's
    u_x (and u_y) with its neighbours' (m_e/3 per element end, m_e/6 across an element; the base
    node does not move), the rotational masses act on the node rotations alone. A few fused
    elementwise operations: under `vmap` on XLA:CPU the dense product is a library call of ~6 µs
    per batch of 16 (31 DOFs), most of a flexible step's cost."""
    me = m / n
    diag = jnp.concatenate([jnp.full(n - 1, 2.0), jnp.ones(1)]) * (me / 3)
    zero = jnp.zeros(1, x.dtype)

    def rod(u):
        return diag * u + (me / 6) * (jnp.concatenate([zero, u[:-1]]) + jnp.concatenate([u[1:], zero]))

    rest = x[1:].reshape(n, 3)
    phi = x[0::3]
    out = jnp.stack([rod(rest[:, 0]), rod(rest[:, 1]), rot_masses[1:] * phi[1:]], axis=1).reshape(-1)
    return jnp.concatenate([rot_masses[:1] * phi[:1], out])


def influence_x(n: int) -> Float[Array, " N"]:
    """Influence vector of a horizontal ground motion: 1 on the u_x DOFs."""
    r = jnp.zeros(n_dof(n))
    return r.at[1 + 3 * jnp.arange(n)].set(1.0)


def ground_load(n: int, m) -> Float[Array, " N"]:
    """Effective load vector `p` of a unit horizontal ground acceleration, f = −üg p.

    In coordinates relative to the ground, the inertia of the whole column (base node included,
    which moves with the ground) gives `p = M[free, all] · r_all`: the u_x rows of M times 1, plus
    the consistent-mass coupling `m_e/6` between the base node and node 1, which `M r` on the
    free DOFs alone misses. Without it the horizontal inertia force is `m − m_e/6` (its lever arm
    ~2 % short at 4 elements, so the flexible model rocked less than the one-DOF model even at
    E = 10¹⁴ Pa). Σ p_x = m: a rigid column feels `−m üg` in total and `−m üg h cosθ` about its base.
    """
    me = m / n
    M_rows = mass_matrix(jnp.asarray(1.0), n, m, jnp.zeros(n + 1)) @ influence_x(n)
    return M_rows.at[1].add(me / 6)


def linear_stiffness(h, n: int, EA, EI):
    """Material stiffness at the undeformed configuration (Hessian of the strain energy)."""
    return jax.hessian(strain_energy)(jnp.zeros(n_dof(n)), h, n, EA, EI)


def first_period(h, n: int, m, EA, EI, rot_masses):
    """First fixed-base period [s] of the discretised column (base rotation DOF removed,
    material stiffness, no gravity): the reference of eq. 21 and of the Rayleigh damping."""
    K = linear_stiffness(h, n, EA, EI)[1:, 1:]
    M = mass_matrix(h, n, m, rot_masses)[1:, 1:]
    Lc = _linalg.cholesky(M)
    Li = _linalg.solve_triangular(Lc, jnp.eye(M.shape[0]))
    A = Li @ K @ Li.T
    w2 = _linalg.eigvalsh(0.5 * (A + A.T))[0]
    return 2 * jnp.pi / jnp.sqrt(w2)


def top_displacement(q, h, n: int):
    """Horizontal displacement of the top node u (relative to the ground)."""
    return q[3 * n - 2]
