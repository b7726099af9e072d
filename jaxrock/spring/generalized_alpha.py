"""Generalized-α time stepping of the spring model (Chung & Hulbert 1993), adaptive, in JAX.

The structural-dynamics scheme the issue asks to weigh against diffrax's ESDIRK solvers (chosen
by the work–precision study in `benchmarks/bench_spring.py`). For ``M q̈ = f(t, q, q̇)`` with the
spring's elastic moment ``M(θ)`` (`jaxrock.spring.base_spring`) on the base rotation θ = q₀:

    (1 − αm) M a₁ + αm M a₀ = (1 − αf) f(t₁, q₁, v₁) + αf f(t₀, q₀, v₀),
    q₁ = q₀ + dt v₀ + dt² ((½ − β) a₀ + β a₁),   v₁ = v₀ + dt ((1 − γ) a₀ + γ a₁),

αm = (2ρ∞ − 1)/(ρ∞ + 1), αf = ρ∞/(ρ∞ + 1), γ = ½ − αm + αf, β = ¼ (1 − αm + αf)²: second order,
unconditionally stable, high-frequency dissipation set by ρ∞ (1: the trapezoidal rule).

Newton on q₁ with three structural shortcuts, each exact or converging to the exact step:

- the spring is solved exactly: with the rest of the system linearised, the step reduces to one
  scalar, monotone equation in θ₁, ``θ₁ + z₀ M(θ₁) = r`` (z₀ > 0), solved in closed form for the
  bilinear backbone and for tanh by Newton from a point where it converges monotonically
  (`AbstractBackbone.solve`) — so the pre-yield branch (stiffness My/θs, up to 10⁶ × the
  rocking stiffness) never makes the iteration diverge, however large the step;
- the rest of the tangent is the rest state's (``K(dt) = (1−αm)/(β dt²) M + (1−αf)(K₀ + γ/(β dt) C₀)``),
  rotated rigidly to the current base rotation (``T(θ) K T(θ)ᵀ``, `SpringSystem.rotate`: exact for
  a rigidly rotated column, as the strain energy is rotation invariant): a quasi-Newton iteration
  on the exact residual, which converges to the exact implicit step;
- K(dt) is inverted for any dt from the modes of (K₀, M), computed once per run (C₀ is Rayleigh's
  a₁ K₀ up to the preload's geometric stiffness, plus the base damper's rank one, Sherman–Morrison),
  so a step of any size costs a few matrix–vector products. Step sizes come from a ladder
  dt_k = dt_top / 2^k (k < `levels`) on a grid; steps double only on their own grid, so records'
  sample times are hit.

Steps through the tanh spring's pre-yield band (|θ| < 3 θs, where the moment turns from −My to My and
the acceleration jumps by ~2 My/I) move θ by at most `crossing` θs. The displacement error estimate
below allows a step of ~(tol/Δa)^½ there, which jumps the band in one or two steps; the impact's
velocity change then depends on where the band falls on the step grid, which slides as the
parameters move. The values carry a fast wiggle and `jacfwd`, the exact derivative of the discrete
map, is its slope: on 64 random one-DOF scenes at 1e-6 its median error against Tsit5's reverse
gradient was 250 % without the limit and 0.5 % with `crossing` = 1 (`benchmarks/bench_gradients.py
--part bias`; choice of the value there).

A kinked backbone (the bilinear) is stepped branch by branch, as the diffrax integrator does with
events: each step runs on one branch (its moment continued past the kinks, `moment_on_branch`); a
step whose end leaves the branch is rejected and replaced by one that ends on the kink (its size by
regula falsi on the end's distance to the kink, within the Newton iteration's accuracy in θ); the
run goes on from there on the next branch, and the step grid restarts at the kink. No step straddles
a kink and the steps after one move with it as the parameters move it: the discrete map is smooth,
and `jacfwd` is the motion's derivative (a grid fixed in time made each step's error, and so the
derivative, depend on where the kink fell on it: d max θ/d ln a_p tens of % off,
`benchmarks/bench_backbone.py --part sawtooth`).

The local error is Zienkiewicz & Xie's estimate ``dt² (β − 1/6)(a₁ − a₀)`` in a max norm,
componentwise against ``atol·scale + rtol·|q|`` (scale: α′ for rotations, 2h α′ for displacements).
Differentiable in one mode, chosen by `autodiff`: "forward" (`jax.jvp`, `jax.jacfwd`; the loops are
`lax.while_loop`s) or "reverse" (`jax.grad`, `jax.vjp`; the run's loop is equinox's checkpointed
while loop, the Newton iteration's a bounded one: the same iterations, the same values up to the
order in which XLA sums, ~1e-13).
Both differentiate the same discrete map, so the two modes' derivatives agree to round-off.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp

from jaxtyping import Array

from .. import _linalg
from .._validate import JaxrockInputError
from ..bookkeeping import Record
from ..model import AbstractModel, AbstractSpringIntegrator, AbstractStepper, Schedule, check_autodiff
from ..results import Save, Solution, Status
from .system import FlexibleSystem, SpringSystem


# Attempted steps per loop step (`GeneralizedAlphaStepper.step`): a run's record of its step ends
# (`Watch.steps`) and a summary's settled test (the column's strain energy) are made once a block,
# not once a step; under `vmap` every lane pays for both at each (in a probe of 32 lanes of the
# 10-element column: 2.2 µs a lane-step one at a time, 1.9 with blocks of 4 or 8, 3.0 with 16; 256
# random scenes, 2 cores, the `Checked` default: 3.2 ms a scene one at a time, 2.7 in blocks of 8).
BLOCK = 8
# A landing on a kink (`GeneralizedAlphaStepper`): the most regula falsi attempts before the step
# is taken where the last one ended
MAX_LANDING = 8
LANDING_BAND = 0.05  # the landing tolerance at most this fraction of θs


class GeneralizedAlpha(AbstractSpringIntegrator):
    """Adaptive generalized-α for `SpringModel` (quasi-rigid or flexible).

    The flexible spring model's default integrator, inside `Checked` (module docstring,
    `jaxrock.spring.generalized_alpha`). Constructed from its fields, in this order; all are static.

    Attributes:
        rtol: local relative error tolerance, in (0, 1); default 1e-5.
        atol: local absolute error tolerance, scaled per component (module docstring), in (0, 1);
            default 1e-5.
        rho_inf: spectral radius at infinite frequency, in [0, 1] (1: trapezoidal, no dissipation);
            default 0.9.
        levels: step-size ladder length (dt_top / 2^k, k < levels), in [4, 40]; default 16.
        max_steps: bound on attempted steps (then `Status.max_steps`), ≥ 16; default 100 000.
        max_newton: Newton iterations per step before the step is retried at half the size, ≥ 2;
            default 8.
        newton_tol: Newton stops when its increment, or the error its contraction leaves, is below
            `newton_tol` × the error tolerance; in (0, 1]; default 1e-2.
        crossing: the largest |Δθ| of a step through a smooth spring's pre-yield band, in θs, in
            (0, 100] or None (only the error estimate limits such steps); default 1. A kinked
            spring's steps end on its kinks instead.
        autodiff: "forward" (`jax.jacfwd`, `jax.jvp`) or "reverse" (`jax.grad`, `jax.vjp`): the mode
            its loops differentiate in (module docstring); the values are the same. Default "forward".

    Raises:
        JaxrockInputError: when a field is outside its range or `autodiff` is neither mode.

    Example:
        ```python
        import jaxrock
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), jaxrock.Column.concrete())
        integrator = jaxrock.GeneralizedAlpha(rtol=1e-6, atol=1e-6, rho_inf=0.8)
        sol = jaxrock.simulate(model, jaxrock.RickerPulse(2.0, 3.0), integrator=integrator)
        ```
    """

    rtol: float = eqx.field(static=True, default=1e-5)
    atol: float = eqx.field(static=True, default=1e-5)
    rho_inf: float = eqx.field(static=True, default=0.9)
    levels: int = eqx.field(static=True, default=16)
    max_steps: int = eqx.field(static=True, default=100_000)
    max_newton: int = eqx.field(static=True, default=8)
    newton_tol: float = eqx.field(static=True, default=1e-2)
    crossing: float | None = eqx.field(static=True, default=1.0)
    autodiff: str = eqx.field(static=True, default="forward")

    def __check_init__(self):
        check_autodiff(self.autodiff)
        if not (0 < self.rtol < 1) or not (0 < self.atol < 1):
            raise JaxrockInputError(f"rtol = {self.rtol:g}, atol = {self.atol:g}: both must be in (0, 1)")
        if not (0.0 <= self.rho_inf <= 1.0):
            raise JaxrockInputError(f"rho_inf = {self.rho_inf:g}: must be in [0, 1]")
        if not (4 <= self.levels <= 40):
            raise JaxrockInputError(f"levels = {self.levels}: must be in [4, 40]")
        if self.max_steps < 16 or self.max_newton < 2:
            raise JaxrockInputError(f"max_steps = {self.max_steps} (>= 16), max_newton = {self.max_newton} (>= 2)")
        if not (0 < self.newton_tol <= 1):
            raise JaxrockInputError(f"newton_tol = {self.newton_tol:g}: must be in (0, 1]")
        if self.crossing is not None and not (0 < self.crossing <= 100):
            raise JaxrockInputError(f"crossing = {self.crossing:g}: must be in (0, 100] (θs per step), or None")

    @property
    def coefficients(self):
        r = self.rho_inf
        am = (2 * r - 1) / (r + 1)
        af = r / (r + 1)
        gamma = 0.5 - am + af
        beta = 0.25 * (1 - am + af) ** 2
        return am, af, gamma, beta

    def stepper(self, model, system, save=None, t1=None) -> "GeneralizedAlphaStepper":
        """`AbstractSpringIntegrator.stepper`: one loop step is `BLOCK` attempted steps."""
        return GeneralizedAlphaStepper(self, model, system, save, t1)


class GAState(eqx.Module):
    """The state of a generalized-α run (one scene), carried from attempt to attempt."""

    n: Array  # the step grid: the step ends are tg + n dt_min (restarted at a kink, a record's sample)
    tg: Array
    k: Array  # the level of the next step (dt_top / 2^k)
    t: Array
    q: Array  # displacements, velocities, accelerations, the total force at t
    v: Array
    a: Array
    f: Array
    ew: Array  # the work integrals (`WORK_FIELDS`) when tracked, else empty
    fd: Array  # the damping and ground forces at t (the work integrals' integrands)
    fe: Array
    rec: Record
    done: Array
    failed: Array
    rho: Array  # Newton's contraction, as last measured (unknown: 1)
    steps: Array  # attempts so far
    hist: dict | None  # a history's saved values (None: a summary) and the next save time's index
    ptr: Array
    branch: Array  # the spring's branch (a kinked backbone: 0 pre-yield, ±1 yielded)
    # a landing on a kink in progress: the bracket (dt, kink distance) on either side of it, the
    # kink (σ of σ θs), the side last moved (Illinois), the attempts so far
    land: Array
    bracket: Array
    kink: Array
    side: Array
    n_land: Array
    modes: tuple | None  # the tangent's modes (Φ, λ), constant over the run (`initial`)


class GeneralizedAlphaStepper(AbstractStepper):
    """A spring-model run by generalized-α (`AbstractStepper`): one step is `BLOCK` attempted steps
    of the adaptive scheme (module docstring); `n_iterations` counts the attempts. The state is a
    `GAState`; the tangent's modes, computed once per scene in `init`, ride in it unchanged.

    Runs from the excitation's start to `SpringModel.run_end` or earlier: overturned at
    |θ| ≥ threshold·α′; or, for a summary, settled after the excitation (mechanical energy below
    `SpringSystem.settled`, tested at the end of each block: a settled run never again reaches its
    peak, so the steps a block adds change no summary). Each accepted step is recorded from its ends
    (`jaxrock.bookkeeping.Watch.steps`: the peak and the crossings on its cubic Hermite
    interpolant), a block's steps at once."""

    integrator: GeneralizedAlpha
    model: AbstractModel  # the SpringModel
    system: SpringSystem
    save: Save | None
    t1: Array | None

    @property
    def max_steps(self) -> int:
        return self.integrator.max_steps

    @property
    def checkpointed(self) -> bool:
        return self.integrator.autodiff == "reverse"

    @property
    def schedule(self) -> Schedule:
        # a quasi-rigid step is cheap and its batch overhead large (below 64 cells gathering stops
        # paying; 32×32 grid: 0.09 ms/scene vs 0.15 with 8). A flexible step is dear (~2.2 µs a
        # cell from 16 cells on, 2 cores) and its cells' lengths differ tenfold (90–1250 steps on
        # the benchmark's grid): lanes refilled every 256 attempts, 32 blocks (three concrete-column grids,
        # 8×8 to 16×16, one core: 16 lanes 1.6–2.1 ms/scene against 2.1–3.8 gathering every running
        # cell; 16 lanes every 128 steps 2.4–2.5, 32 every 256 1.7–2.2). 32 lanes since a batch is
        # dealt over a CPU's cores and a `Checked` run's companion runs apart (two sets of 256
        # random 10-element scenes, 2 cores: 2.8–3.1 ms/scene against 3.1–3.5 on 16 lanes, 8 lanes
        # 5.3, 64 lanes 2.9). The last cells too on these lanes: one compiled size. A cell keeps
        # the modes of its tangent ((N + 1) N floats).
        N = self.system.ndof
        if N == 1:
            return Schedule(passes=(128 // BLOCK, 256 // BLOCK, 512 // BLOCK, 1024 // BLOCK), smallest_batch=64)
        return Schedule(passes=(256 // BLOCK,), smallest_batch=16, lanes=32, bytes_per_scene=(N + 1) * N * 8)

    def init(self, exc):
        return self._loop(exc)[0]()

    def step(self, exc, c):
        return self._loop(exc)[1](c)

    def done(self, c):
        return c.done | (c.steps >= self.max_steps)

    def motion(self, c):
        a = self.system.alpha_r
        return c.t, c.q[0] / a, c.v[0] / a

    def finish(self, exc, c) -> Solution:
        out = self._loop(exc)[2](c)
        return self.model.watch(self.system).solution(out["record"], out["status"], ts=None if self.save is None else self.save.ts,
                                                      history=out["history"], n_iterations=out["steps"])

    def _loop(self, excitation):
        """(initial, body, result) of the step loop on `excitation`: closures over the scene's
        constants (cheap: the tangent's modes are computed in `initial` only)."""
        ig, mech, model = self.integrator, self.system, self.model
        watch = model.watch(mech)
        t_stop = model.run_end(mech, excitation, self.save, self.t1)
        summary = self.save is None
        save_ts = None if self.save is None else self.save.ts
        fields = () if self.save is None else self.save.fields
        n_ts = 0 if save_ts is None else save_ts.shape[0]

        am, af, gamma, beta = ig.coefficients
        n_levels = ig.levels
        N = mech.ndof
        dtype = jnp.result_type(float)
        M = mech.mass_matrix()
        e0 = jnp.zeros(N).at[0].set(1.0)
        clamp = mech.fixed_base
        free = jnp.ones(N).at[0].set(0.0) if clamp else jnp.ones(N)

        # step-size ladder: dt_top = (excitation step) · 2^j ≈ a sixteenth of the rocking period
        t0 = jnp.asarray(excitation.t_start, dtype)
        t_end = jnp.asarray(excitation.t_end, dtype)
        t_free = 2 * jnp.pi / mech.p_r / 16
        dt_exc = jnp.where(jnp.isfinite(excitation.max_step), excitation.max_step, t_free)
        sampled = excitation.step_ts is not None  # a record: its steps end on the samples
        j_exc = jnp.clip(jnp.floor(jnp.log2(t_free / dt_exc)), 0, n_levels // 2).astype(jnp.int32)
        dt_top = dt_exc * 2.0**j_exc
        # level k steps stride[k] grid intervals of dt_min = dt_top / 2^(levels − 1)
        stride = (2 ** (n_levels - 1 - jnp.arange(n_levels))).astype(jnp.int64 if dtype == jnp.float64 else jnp.int32)
        dt_min = dt_top * 2.0 ** (1 - n_levels)

        scale = mech.atol_scale()[:N]
        My, theta_s = mech.My, mech.theta_s
        theta_band = mech.theta_up  # the pre-yield band (tanh: |θ| < 3 θs, 99.5 % of My; bilinear: θy)
        # a kinked backbone: each step runs on one branch (the moment continued from it), and a step
        # that leaves it is replaced by one that ends on the kink (`attempt`): no step straddles it
        kinked = mech.backbone.kinked and not clamp
        c_base = jnp.zeros((), dtype) if clamp else mech.c  # the base damper in the tangent
        a1_ray = mech.a1 if isinstance(mech, FlexibleSystem) else jnp.zeros((), dtype)

        def tol_of(q_a, q_b):
            return ig.atol * scale + ig.rtol * jnp.maximum(jnp.abs(q_a), jnp.abs(q_b))

        def spring_on(branch):
            """(M(θ), the θ with θ + z₀ M(θ) = rhs): the spring's moment and its exact scalar solve
            (`AbstractBackbone.solve`; in u = θ/θs: u + k m(u) = r, k = z₀ My/θs ≥ 0), on `branch`
            for a kinked backbone (`moment_on_branch`)."""
            bb = mech.backbone
            if clamp:
                return (lambda th: jnp.zeros_like(th)), None
            if kinked:
                return (mech.on_branch(branch).spring_moment,
                        lambda rhs, z0: bb.solve_on_branch(rhs / theta_s, z0 * My / theta_s, branch) * theta_s)
            return (mech.spring_moment, lambda rhs, z0: bb.solve(rhs / theta_s, z0 * My / theta_s) * theta_s)

        track = mech.track_energy

        def initial():
            """The state at the excitation's start, with the modes of the tangent (computed once).

            The step's tangent K(dt) = A M + (1 − αf) K₀ + B C₀ (A = (1 − αm)/(β dt²),
            B = (1 − αf) γ/(β dt); K₀, C₀ at rest) is inverted for any dt from the modes of the
            pencil (K₀, M), K₀ Φ = M Φ Λ, Φᵀ M Φ = I: with C₀ = a₁ K₀ + c e₀e₀ᵀ (Rayleigh on the
            deformations, the base damper; up to the gravity preload's geometric stiffness, a
            quasi-Newton tangent), K⁻¹ = Φ diag(1/(A + (1 − αf + B a₁) Λ)) Φᵀ corrected for the
            damper's rank one (Sherman–Morrison): steps of any size, such as those ending on a
            kink, cost a few matrix–vector products more than one of a fixed size."""
            K0 = mech.tangents()[0]
            ff = free[:, None] * free[None, :]
            L = _linalg.cholesky(jax.lax.stop_gradient(M * ff + jnp.diag(1.0 - free)))
            Li = _linalg.solve_triangular(L, jnp.eye(N, dtype=dtype))
            S = Li @ jax.lax.stop_gradient(K0 * ff) @ Li.T
            lam, V = _linalg.eigh_primal(0.5 * (S + S.T))
            y_init = mech.initial_state()  # [q, v] (+ the work integrals `WORK_FIELDS` when tracked)
            q0, v0 = y_init[:N], y_init[N : 2 * N]
            branch0 = mech.branch_at(q0[0]) if kinked else jnp.zeros((), dtype)
            f0_rest, f0_ext, f0_damp = mech.forces_without_spring(t0, q0, v0, excitation)
            f0_tot = f0_rest - spring_on(branch0)[0](q0[0]) * e0
            a0 = _linalg.solve(M * free[:, None] * free[None, :] + jnp.diag(1.0 - free), f0_tot * free)

            # carry
            hist0 = None
            if save_ts is not None:
                vals0 = mech.history(t0, y_init, excitation, fields)
                at0 = save_ts <= t0
                hist0 = {f: jnp.where(at0, vals0[f], jnp.nan) for f in fields}
            k_start = jnp.minimum(j_exc + 1, n_levels - 1)
            carry = GAState(
                n=jnp.zeros((), stride.dtype), tg=t0,
                k=k_start, t=t0, q=q0, v=v0, a=a0, f=f0_tot,
                ew=y_init[2 * N :] if track else jnp.zeros(0, dtype),  # the work integrals (`WORK_FIELDS`)
                fd=f0_damp, fe=f0_ext,
                rec=Record.start(q0[0]), done=jnp.asarray(False), failed=jnp.asarray(False),
                rho=jnp.asarray(1.0, dtype),
                steps=jnp.zeros((), jnp.int32), hist=hist0, ptr=jnp.sum(save_ts <= t0) if save_ts is not None else jnp.zeros((), jnp.int32),
                branch=branch0,
                land=jnp.asarray(False), bracket=jnp.zeros(4, dtype), kink=jnp.zeros((), dtype), side=jnp.zeros((), jnp.int32),
                n_land=jnp.zeros((), jnp.int32),
                modes=(Li.T @ V, lam),
            )
            return carry

        def step(c, dt, t1):
            """One attempted step of size dt from the carry's state to t1."""
            t, q, v, a, f_tot = c.t, c.q, c.v, c.a, c.f
            Phi, lam = c.modes
            A = (1 - am) / (beta * dt**2)
            B = (1 - af) * gamma / (beta * dt)
            d = 1.0 / (A + ((1 - af) + B * a1_ray) * lam)
            k_base = lambda r: Phi @ (d * (Phi.T @ r))  # the tangent without the damper, inverted
            u = k_base(e0)
            bc = B * c_base
            k_e0 = u / (1 + bc * u[0])  # K⁻¹ e₀

            def k_inv(r):
                w = k_base(r)
                return w - bc * w[0] * k_e0

            th_rot = q[0]
            apply = lambda r: mech.rotate(k_inv(mech.rotate(r, -th_rot)), th_rot)
            z = (1 - af) * mech.rotate(k_e0, th_rot) * free  # apply(e₀): the rotation keeps e₀
            z0 = z[0]
            spring, solve_theta = spring_on(c.branch)
            acc_of = lambda q1: (q1 - q - dt * v - dt**2 * (0.5 - beta) * a) / (beta * dt**2)
            vel_of = lambda a1: v + dt * ((1 - gamma) * a + gamma * a1)

            def residual(q1):
                a1 = acc_of(q1)
                fr, _, _ = mech.forces_without_spring(t1, q1, vel_of(a1), excitation)
                return (mech.mass_times((1 - am) * a1 + am * a) - (1 - af) * fr - af * f_tot) * free

            def ncond(nc):
                return (~nc[1]) & (nc[2] < ig.max_newton)

            def nbody(nc):
                q1, _, i, r_prev, rho = nc
                x = apply(residual(q1)) * free
                th_new = solve_theta(q1[0] - x[0], z0) if not clamp else q1[0]
                dq = -x - spring(th_new) * z
                dq = dq.at[0].set(th_new - q1[0])
                r = jnp.max(jnp.abs(dq) / tol_of(q, q1))
                # converged: increment below newton_tol of the error tolerance; or, from the second
                # iteration on, what the contraction ρ = r/r_prev leaves, ρ/(1 − ρ) r, below it
                # (Hairer & Wanner IV.8: typically ρ ~ 1e-4 here, so the third iteration a batch
                # would wait for is not needed); or stalled (at the round-off floor of a stiff
                # column's forces) while already below the tolerance
                rho = jnp.where(jnp.isfinite(r_prev), r / r_prev, rho)  # first iteration: the last step's
                contracted = (rho < 0.5) & (rho / (1 - rho) * r <= ig.newton_tol)
                conv = (r <= ig.newton_tol) | contracted | ((r <= 1.0) & (r >= 0.5 * r_prev))
                conv = conv & jnp.isfinite(r)
                return q1 + dq, conv, i + 1, r, rho

            qp = q + dt * v + 0.5 * dt**2 * a
            # a finished cell of a batch (its result frozen) does not iterate: under vmap the
            # batch's iterations are its slowest cell's, and a finished (overturned) cell's state
            # was the one that needed a third iteration
            init = (qp, c.done, 0, jnp.asarray(jnp.inf, dtype), c.rho)
            q1, conv, _, _, rho = _while(ncond, nbody, init, ig.max_newton, ig.autodiff)
            # The last increment is applied: an increment δ left out is a velocity error γδ/(β dt),
            # which grows as the steps shrink. a₁, v₁ are linear in q₁; the total force is the one
            # the step equation implies at q₁ (exact to O(δ²)), so no force evaluation is repeated,
            # except the ground and damping forces of the energy integrals when they are tracked.
            a1 = acc_of(q1)
            v1 = vel_of(a1)
            if track:
                _, fe1, fd1 = mech.forces_without_spring(t1, q1, v1, excitation)
            else:
                fe1 = fd1 = jnp.zeros_like(q1)
            f1_tot = (mech.mass_times((1 - am) * a1 + am * a) - af * f_tot) / (1 - af)
            err = jnp.max(jnp.abs(dt**2 * (beta - 1.0 / 6.0) * (a1 - a)) / tol_of(q, q1))
            if ig.crossing is not None and not clamp and not kinked:
                # a step through the pre-yield band moves θ by at most `crossing` θs; the excess
                # enters as an error of order 3, so the controller drops ~log2(excess) levels; at
                # the ladder's bottom it no longer rejects (the band is resolved as far as it goes)
                th0, th1 = q[0], q1[0]
                through = (th0 * th1 <= 0) | (jnp.minimum(jnp.abs(th0), jnp.abs(th1)) < theta_band)
                through = through & (c.k < n_levels - 1)
                excess = jnp.where(through, jnp.abs(th1 - th0) / (ig.crossing * theta_s), 0.0)
                err = jnp.maximum(err, excess**3)
            err = jnp.where(conv & jnp.isfinite(err), err, jnp.inf)
            # a kinked backbone: the landing tolerance, the Newton iteration's own accuracy in θ, at
            # most a twentieth of the pre-yield band (at a loose tolerance the accuracy can exceed
            # the band: every θ in it would count as on a kink)
            eps = jnp.minimum(ig.newton_tol * tol_of(q, q1)[0], LANDING_BAND * theta_s)
            return dict(t1=t1, q1=q1, v1=v1, a1=a1 * free, f1=f1_tot, fe1=fe1, fd1=fd1, err=err, dt=dt, rho=rho,
                        eps=eps)

        def attempt(c, buf):
            """One attempted step of a cell still running (else nothing): the state after it, and
            `buf` (the block's accepted step ends, `body`) with its end where accepted.

            A step ends on the grid of its level (from a point off the grid, on the next point of
            it), or, on a kinked backbone, on the kink its branch's step crossed: the crossing step
            is rejected and the step's size that ends on the kink is found by regula falsi (Illinois)
            on the kink distance of the step's end, within the Newton iteration's accuracy in θ
            (each try an attempt, so that under `vmap` no lane waits for another's landing); the
            run then continues on the next branch."""
            active = ~c.done & (c.steps < ig.max_steps)
            k = c.k
            n1 = (c.n // stride[k] + 1) * stride[k]
            t_grid = c.tg + n1.astype(dtype) * dt_min
            # a record: a step from off its sample grid (after a kink) ends on the next sample at
            # the latest, where the grid restarts on the samples
            clip = jnp.zeros((), bool)
            if sampled:
                i_next = jnp.floor((c.t - t0) / dt_exc + 1e-9) + 1
                t_sample = t0 + i_next * dt_exc
                clip = (t_sample < t_grid) & (c.t < t_end)
                t_grid = jnp.where(clip, t_sample, t_grid)
            dt_grid = t_grid - c.t
            lo_dt, lo_g, hi_dt, hi_g = c.bracket
            landing = c.land
            span = jnp.where(landing, hi_g - lo_g, -1.0)  # no bracket: a stand-in (0/0 would reach reverse mode's cotangents)
            dt_land = lo_dt - lo_g * (hi_dt - lo_dt) / span
            dt = jnp.where(landing, dt_land, dt_grid)
            t1 = jnp.where(landing, c.t + dt_land, t_grid)
            s = step(c, dt, t1)
            ok = s["err"] <= 1.0
            # a kinked backbone: the kink σ θs a step leaves its branch b through (b = 0: σ = sign θ₁;
            # b = ±1: σ = b), and how far θ lies inside the branch from that kink (< 0: past it)
            b, th0, th1, eps = c.branch, c.q[0], s["q1"][0], s["eps"]
            sigma = jnp.where(landing, c.kink, jnp.where(b == 0, jnp.sign(th1), b))
            inside = lambda th: jnp.where(b == 0, theta_s - sigma * th, b * th - theta_s)
            g0, g1 = inside(th0), inside(th1)
            crossed = kinked & (g1 < -eps)
            # leaving the kink it stands on, backwards: the run continues on the other branch
            at_kink = g0 <= eps
            landed = landing & ((~crossed & (g1 <= eps)) | (c.n_land >= MAX_LANDING))
            accept = ok & jnp.where(landing, landed, ~crossed)
            # level after this attempt: double (one level up) when the error allows twice the step
            # (0.9 err^(-1/3) ≥ 2), the step grid allows it and, during the excitation, dt stays
            # within its step; on rejection drop as many levels as the error asks (≥ 1)
            grow = ok & ~landing & (s["err"] < 0.125 / 1.5) & (k > 0)
            aligned = (n1 % stride[jnp.maximum(k - 1, 0)]) == 0
            k_floor = jnp.where(t1 < t_end, j_exc, 0)
            k_up = jnp.where(grow & aligned & (k - 1 >= k_floor), k - 1, k)
            shrink = jnp.ceil(jnp.log2(jnp.maximum(s["err"], 1.0)) / 3.0 + 0.2).astype(jnp.int32)
            k_dn = jnp.minimum(k + jnp.where(jnp.isfinite(s["err"]), jnp.maximum(shrink, 1), 2), n_levels - 1)
            # the kink's bookkeeping: the branch beyond it, the bracket of a landing. A step that
            # crosses a kink only brackets it, whatever its error (past the kink its branch's
            # continuation, e.g. the stiff pre-yield spring, is not the motion)
            beyond = jnp.where(b == 0, sigma, 0.0)
            solved = jnp.isfinite(s["err"])
            start = solved & crossed & ~landing & ~at_kink
            flip = solved & crossed & ~landing & at_kink
            move_hi = solved & crossed & landing & ~landed
            move_lo = ok & landing & ~crossed & ~landed
            bracketing = start | flip | move_hi | move_lo
            failed = (~ok) & (k == n_levels - 1) & ~bracketing
            illinois = jnp.where(move_hi & (c.side == 1), 0.5, 1.0)  # the end kept twice: its distance halved
            illinois_hi = jnp.where(move_lo & (c.side == -1), 0.5, 1.0)
            bracket = jnp.where(start, jnp.stack([jnp.zeros((), dtype), g0, dt, g1]),
                      jnp.where(move_hi, jnp.stack([lo_dt, lo_g * illinois, dt, g1]),
                      jnp.where(move_lo, jnp.stack([dt, g1, hi_dt, hi_g * illinois_hi]), c.bracket)))
            side = jnp.where(start, 0, jnp.where(move_hi, 1, jnp.where(move_lo, -1, c.side)))
            land_next = (landing & (move_hi | move_lo)) | start
            # an accepted end off the grid (on a kink, on a record's sample) restarts the grid there:
            # the steps that follow move with the kink as the parameters move it (a grid fixed in
            # time would make each one's error, and the derivatives, depend on the kink's phase)
            restart = landing | clip
            n_new = jnp.where(restart, 0, n1)
            tg_new = jnp.where(restart, t1, c.tg)

            # accepted-step bookkeeping (the step's record from `buf`, at the block's end)
            dt = s["dt"]
            ew = c.ew
            if track:
                ew = ew + 0.5 * dt * (mech.powers(c.v, c.fe, c.fd) + mech.powers(s["v1"], s["fe1"], s["fd1"]))
            # done at an end beyond the overturning rotation or the run's end; an interpolant that
            # reaches it between two ends below, and a settled summary, at the block's end
            finished = (jnp.abs(s["q1"][0]) >= watch.overturn) | (t1 >= t_stop)
            new = dataclasses.replace(
                c, n=n_new, tg=tg_new, k=jnp.where(landing, k, k_up), t=t1, q=s["q1"], v=s["v1"], a=s["a1"], f=s["f1"], ew=ew,
                fd=s["fd1"], fe=s["fe1"], rec=c.rec, done=finished,
                failed=jnp.asarray(False), steps=c.steps + 1, hist=c.hist, ptr=c.ptr, rho=s["rho"],
                branch=jnp.where(landed, beyond, c.branch), land=jnp.asarray(False), bracket=c.bracket, kink=c.kink,
                side=c.side, n_land=jnp.zeros((), jnp.int32), modes=None,
            )
            if save_ts is not None:
                hist, ptr = _fill_history(mech, excitation, fields, save_ts, n_ts, c, s, new, track, ig.autodiff)
                new = dataclasses.replace(new, hist=hist, ptr=ptr)
            rejected = dataclasses.replace(c, modes=None, k=jnp.where(active & ~ok & ~bracketing, k_dn, k), steps=c.steps + active, done=c.done | (active & failed),
                            failed=c.failed | (active & failed), rho=jnp.where(active, s["rho"], c.rho),
                            branch=jnp.where(active & flip, beyond, c.branch), land=jnp.where(active, land_next, landing),
                            bracket=jnp.where(active, bracket, c.bracket), kink=jnp.where(active & start, sigma, c.kink), side=jnp.where(active, side, c.side),
                            n_land=jnp.where(active & land_next, c.n_land + 1, jnp.where(active, 0, c.n_land)))
            # the modes (constant) are left out of the select and put back
            take = accept & active
            out = jax.tree_util.tree_map(lambda x_ok, x_no: jnp.where(take, x_ok, x_no), new, rejected)
            ts, th, om, i = buf
            i = i + take
            buf = (ts.at[i].set(jnp.where(take, t1, ts[i])), th.at[i].set(jnp.where(take, s["q1"][0], th[i])),
                   om.at[i].set(jnp.where(take, s["v1"][0], om[i])), i)
            return dataclasses.replace(out, modes=c.modes), buf

        def body(c):
            """`BLOCK` attempts (`attempt`), then the record of their accepted steps (`Watch.steps`
            on the step ends, the block's start first) and, for a summary, whether the run has
            settled: once a block, not once a step (`BLOCK`)."""
            nan = jnp.full(BLOCK + 1, jnp.nan, dtype)
            buf = (nan.at[0].set(c.t), nan.at[0].set(c.q[0]), nan.at[0].set(c.v[0]), jnp.zeros((), jnp.int32))
            c, (ts, th, om, _) = jax.lax.fori_loop(0, BLOCK, lambda _, cb: attempt(*cb), (c, buf))
            rec = c.rec.merge(watch.steps(ts, th, om))
            finished = c.done | rec.overturned
            if summary:
                energy = mech.kinetic(c.v) + mech.potential(c.q)
                finished = finished | ((c.t >= t_end) & mech.settled(energy, rec.peak))
            return dataclasses.replace(c, rec=rec, done=finished)

        def result(c):
            status = Status.where(
                c.failed | ~jnp.isfinite(c.rec.peak),
                Status.solver_failed,
                Status.where(c.done, Status.ok, Status.max_steps),
            )
            return dict(record=c.rec, status=status, steps=c.steps, history=c.hist)

        return initial, body, result


def _while(cond, body, init, max_steps: int, autodiff: str):
    """`lax.while_loop` (forward mode), or for reverse mode equinox's bounded loop of at most
    `max_steps` iterations (`cond` must bound it; nested in the run's checkpointed loop, a
    checkpointed one failed under `vmap`, "Nonconstant batch"): the same iterations either way
    (under `vmap` a bounded loop computes all `max_steps` and keeps the ones `cond` allows)."""
    if autodiff == "reverse":
        return eqxi.while_loop(cond, body, init, max_steps=max_steps, kind="bounded")
    return jax.lax.while_loop(cond, body, init)


def _fill_history(mech, excitation, fields, save_ts, n_ts, c, s, new, track, autodiff):
    """Write the save times in (t, t₁] from the cubic Hermite interpolant of the accepted step
    (q from q, v; v from v, a; the work integrals linearly)."""
    t, t1 = c.t, s["t1"]
    dt = t1 - t

    def cond(st):
        hist, ptr = st
        return (ptr < n_ts) & (save_ts[jnp.minimum(ptr, n_ts - 1)] <= t1)

    def body(st):
        hist, ptr = st
        ts = save_ts[ptr]
        u = (ts - t) / dt
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        q = h00 * c.q + h10 * dt * c.v + h01 * s["q1"] + h11 * dt * s["v1"]
        v = h00 * c.v + h10 * dt * c.a + h01 * s["v1"] + h11 * dt * s["a1"]
        y = jnp.concatenate([q, v])
        if track:
            y = jnp.concatenate([y, (1 - u) * c.ew + u * new.ew])
        vals = mech.history(ts, y, excitation, fields)
        hist = {f: hist[f].at[ptr].set(vals[f]) for f in fields}
        return hist, ptr + 1

    return _while(cond, body, (c.hist, c.ptr), n_ts, autodiff)
