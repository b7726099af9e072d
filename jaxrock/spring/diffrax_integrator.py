"""The spring model integrated by diffrax (`SpringIntegrator`): an L-stable ESDIRK solver with full
Newton, or an explicit Runge–Kutta solver for the one-DOF quasi-rigid model; integral step-size
control with a component-scaled absolute tolerance (`SpringSystem.atol_scale`); overturning
``|θ| ≥ threshold·α′`` is an event. The peak and the uplift come from the accepted steps
(`jaxrock.bookkeeping.Watch.steps`).

A summary runs in two phases: the excitation window, then free motion until the answer is fixed —
the mechanical energy below the potential at the largest rotation seen so far
(`SpringSystem.settled`, an event), overturned, or the run's end (`SpringModel.run_end`); in a batch,
each phase in pieces of a bounded number of steps (`DiffraxSpringStepper`).

A kinked backbone (the bilinear, `AbstractBackbone.kinked`) is integrated branch by branch: a solve
ends where |θ| crosses the yield rotation (`kink_event`) and the next starts there on the other
branch (`SpringSystem.on_branch`), so that no step straddles the kink and the derivatives of the
discrete run are those of the motion (`benchmarks/bench_backbone.py --part gradients`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import diffrax
import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
import optimistix as optx
from diffrax import with_stepsize_controller_tols
from jaxtyping import Array

from .. import _linalg
from .._validate import JaxrockInputError
from ..bookkeeping import Record, hermite, hermite_turns
from ..excitation import AbstractExcitation
from .._rootfind import SafeNewton
from ..model import AbstractSpringIntegrator, AbstractStepper, FirstStepController, WrappedController, Schedule, check_autodiff, diffrax_adjoint, diffrax_status
from ..results import Save, Solution, Status
from .rest import rest_grid, rest_phase, rest_states
from .system import QuasiRigidSystem, SpringSystem

if TYPE_CHECKING:
    from .model import AbstractSpringModel

_IMPLICIT = {"kvaerno3": diffrax.Kvaerno3, "kvaerno4": diffrax.Kvaerno4, "kvaerno5": diffrax.Kvaerno5}
_EXPLICIT = {"tsit5": diffrax.Tsit5, "dopri5": diffrax.Dopri5, "dopri8": diffrax.Dopri8}
_SOLVERS = {**_IMPLICIT, **_EXPLICIT}


class SpringIntegrator(AbstractSpringIntegrator):
    """The diffrax integrator of the spring model.

    An L-stable ESDIRK solver (kvaerno3/4/5, stage equations by full Newton) or an explicit
    Runge–Kutta solver (tsit5, dopri5, dopri8: for the one-DOF quasi-rigid SM only, whose one stiff
    part, the spring's pre-yield branch, is mild), with an integral step-size controller. Defaults
    from the work–precision study in `benchmarks/bench_spring.py` and
    `AbstractSpringModel.default_integrator` (the quasi-rigid model's default is
    `SpringIntegrator(1e-10, 1e-10, solver="tsit5", max_steps=200_000)`). Constructed from its
    fields, in this order; all are static.

    Attributes:
        rtol: relative tolerance, in (0, 1); default 1e-6.
        atol: absolute tolerance, multiplying a per-component scale (α′, 2hα′, ×p′), in (0, 1);
            default 1e-6.
        solver: "kvaerno3", "kvaerno4", "kvaerno5", "tsit5", "dopri5" or "dopri8"; default "kvaerno5".
        max_steps: bound on the steps of one solve, ≥ 16; default 20 000.
        exact_rest: step the quasi-rigid model's pre-yield phase exactly until it first yields
            (`jaxrock.spring.rest`) on a kinked spring; False: the solver's steps there too. Default True.
        chunk_steps: a summary's steps per piece in a batch (`DiffraxSpringStepper`), ≥ 16; default 128.
        root_finder: the ESDIRK stage solver, "newton" (full Newton) or "chord" (diffrax's VeryChord);
            default "newton".
        autodiff: "reverse" or "forward": the differentiation mode of its adjoint; default "reverse".

    Raises:
        JaxrockInputError: when `solver`, `root_finder` or `autodiff` is not one of its values, or a
            number is outside its range.

    Example:
        ```python
        import jaxrock
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), jaxrock.Column.concrete())
        integrator = jaxrock.SpringIntegrator(solver="kvaerno5")  # reverse-mode differentiable
        sol = jaxrock.simulate(model, jaxrock.RickerPulse(2.0, 3.0), integrator=integrator)
        ```
    """

    rtol: float = eqx.field(static=True, default=1e-6)
    atol: float = eqx.field(static=True, default=1e-6)
    solver: str = eqx.field(static=True, default="kvaerno5")
    max_steps: int = eqx.field(static=True, default=20_000)
    # a run (summary or history) of the quasi-rigid SM on a kinked spring steps its pre-yield phase
    # exactly until it first yields (`jaxrock.spring.rest`); False: the solver's steps there too
    exact_rest: bool = eqx.field(static=True, default=True)
    chunk_steps: int = eqx.field(static=True, default=128)  # a summary's steps per piece in a batch (`DiffraxSpringStepper`)
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
        if self.chunk_steps < 16:
            raise JaxrockInputError(f"chunk_steps = {self.chunk_steps}: must be >= 16")

    def stepper(self, model, system, save=None, t1=None) -> DiffraxSpringStepper:
        """`AbstractSpringIntegrator.stepper`: a summary in pieces of diffrax solves, a history in one."""
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

    def controller(self, system: SpringSystem, excitation: AbstractExcitation, dtmax=None, t0=0.0, max_steps=None):
        """The step-size controller of a solve from `t0` of at most `max_steps` steps (None: the
        integrator's): PID at (rtol, atol), clipped to the excitation's `step_ts` that the solve
        can reach."""
        pid = diffrax.PIDController(
            rtol=self.rtol,
            atol=self.atol * system.atol_scale(),
            pcoeff=0.0,
            icoeff=1.0,
            dtmax=dtmax,
        )
        if system.backbone.kinked:
            pid = KinkGuard(pid)
        if excitation.step_ts is not None:
            window = excitation.step_ts_from(t0, self.max_steps if max_steps is None else max_steps)
            return diffrax.ClipStepSizeController(pid, step_ts=window)
        return pid

    def solve(
        self,
        model: "AbstractSpringModel | SpringSystem",
        excitation: AbstractExcitation,
        y0,
        t0,
        t1,
        event: diffrax.Event | None = None,
        saveat: diffrax.SaveAt | None = None,
        *,
        dtmax=None,
        t_next=None,
        max_steps: int | None = None,
        throw: bool = False,
        checkpoints: int | None = None,
    ) -> diffrax.Solution:
        """One `diffrax.diffeqsolve` of the model's first-order equations from (t0, y0) to t1.

        `model` may be a `SpringModel` (its system is assembled here) or an assembled
        `SpringSystem` (`SpringModel.system()`), reused across calls. `dtmax` defaults to the excitation's
        `max_step` while t < t_end; `max_steps` to the integrator's; the first step is `first_step`.
        A solve that goes on from an earlier one's last state takes as `t_next` the end
        of the step it proposed next, `FirstStepController.next_time` of its `controller_state`
        (asked with `SaveAt(controller_state=True)`). Never throws by default (`throw=False`):
        inspect `result`.
        """
        system = model if isinstance(model, SpringSystem) else model.system()
        if saveat is None:
            saveat = diffrax.SaveAt(t1=True)
        if dtmax is None:
            dtmax = excitation.max_step
        max_steps = self.max_steps if max_steps is None else max_steps
        term = diffrax.ODETerm(lambda t, y, args: args[0].vector_field(t, y, args[1]))
        t0 = jnp.asarray(t0, dtype=float)
        dt0 = jnp.asarray(first_step(system, dtmax), dtype=float)
        sol = diffrax.diffeqsolve(
            term,
            self.diffrax_solver(),
            t0,
            t1,
            None,  # the first step travels with the controller: no host callback (FirstStepController)
            y0,
            args=(system, excitation),
            saveat=saveat,
            stepsize_controller=FirstStepController(self.controller(system, excitation, dtmax, t0, max_steps), dt0, t_next),
            event=event,
            max_steps=max_steps,
            adjoint=diffrax_adjoint(self.autodiff, checkpoints),
            throw=throw,
        )
        # An interval that runs backwards (a history asked to end before the excitation starts; the
        # phases of a summary run forward by construction) is a failure, as diffrax's sign check
        # of (t1 - t0)·dt0 reported it before the first step travelled with the controller.
        return eqx.tree_at(lambda s: s.result, sol, diffrax.RESULTS.where(t1 < t0, diffrax.RESULTS.internal_error, sol.result))

    def solve_through(self, system: SpringSystem, excitation: AbstractExcitation, y0, t0, t1, event: diffrax.Event,
                      *, dtmax=None, max_pieces: int = 256):
        """From (t0, y0) to `event` (or t1): (t, y, result, event_mask) at the end, as the last
        `solve`'s `ts[-1]`, `ys[-1]`, `result` and `event_mask` (a tuple, one per condition). A kinked backbone
        (`AbstractBackbone.kinked`) is run branch by branch: a solve ends on the kink (`kink_event`)
        and the next starts there on the other branch, at most `max_pieces` solves (then
        `max_steps_reached`) in a loop that reverse mode differentiates (equinox's checkpointed loop)."""
        if not system.backbone.kinked:
            sol = self.solve(system, excitation, y0, t0, t1, event=event, dtmax=dtmax)
            return sol.ts[-1], sol.ys[-1], sol.result, tuple(jax.tree_util.tree_leaves(sol.event_mask))
        fns, dirs = (event.cond_fn, event.direction) if isinstance(event.cond_fn, tuple) else ((event.cond_fn,), (event.direction,))
        n_user = len(fns)
        zero = jnp.zeros((), bool)

        def body(c):
            t, y, branch, _, _, mask = c
            on = system.on_branch(branch)
            sol = self.solve(on, excitation, y, t, t1,
                             event=diffrax.Event((*fns, kink_event(branch)), event.root_finder, direction=(*dirs, False)),
                             dtmax=dtmax, checkpoints=self.max_steps)
            hit = sol.result == diffrax.RESULTS.event_occurred
            kink = hit & sol.event_mask[-1]
            t1_, y1 = equal_time(on, excitation, sol.ts[-1], sol.ys[-1], kink)
            done = ~kink
            result = diffrax.RESULTS.where(kink, diffrax.RESULTS.successful, sol.result)
            mask = tuple(hit & m for m in sol.event_mask[:n_user])
            return t1_, y1, flip(branch, y1[0], kink), done, result, mask

        start = (jnp.asarray(t0, dtype=float), y0, system.branch_at(y0[0]), zero, diffrax.RESULTS.successful,
                 (zero,) * n_user)
        cond = lambda c: ~c[3]
        t, y, _, done, result, mask = eqxi.while_loop(cond, body, start, max_steps=max_pieces,
                                                      kind="checkpointed" if self.autodiff == "reverse" else "lax")
        result = diffrax.RESULTS.where(done, result, diffrax.RESULTS.max_steps_reached)
        return t, y, result, mask


# The kink event fires KINK_HYSTERESIS·θs inside the next branch: a run restarted on the kink starts
# that far from the next one (on whichever side round-off puts it), so it never fires again at once;
# the branches meet continuously, so continuing one 1e-6 θs past the kink changes nothing measurable.
KINK_HYSTERESIS = 1e-6


def kink_event(branch):
    """The condition of a kinked backbone's event (`diffrax.Event`, direction False): how far the
    base rotation lies inside `branch`, plus the hysteresis; it falls through 0 past the kink."""

    def cond(t, y, args, **kw):
        return kink_condition(args[0], y[0], branch)

    return cond


def kink_condition(system: SpringSystem, theta, branch):
    """How far θ lies inside `branch`, plus the hysteresis (`kink_event`): < 0 past the kink."""
    return system.kink_distance(theta, branch) + KINK_HYSTERESIS * system.theta_s


class KinkGuard(WrappedController):
    """A step-size controller that rejects a step which leaves its branch and comes back within it.

    A kinked backbone's solve runs on one branch (`SpringSystem.on_branch`: the moment continued
    smoothly past the kink) and stops where the kink event's condition changes sign between two step
    ends. A step whose ends both lie on the branch while its motion, the cubic Hermite interpolant of
    θ and θ̇ at the ends (`_excursion`), crosses the kink in between was kept, the excursion integrated
    with the continued moment: the wrong one. Seen at Tsit5 1e-10 on the quasi-rigid SM (a Ricker
    pulse at a_p/(g tanα) 2.34, ω_p/p 7.77, tanα 0.2): the small rocking brushed the yield rotation
    and max θ/α came out 1.1e-4 from the converged value (`tests/test_spring.py`). Such a step is
    rejected and retried up to the excursion's deepest point, where the next step ends past the kink
    and the event finds it. The wrapped controller decides everything else."""

    controller: diffrax.AbstractAdaptiveStepSizeController

    def wrap(self, direction):
        return KinkGuard(self.controller.wrap(direction))

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        return self.controller.init(terms, t0, t1, y0, dt0, args, func, error_order)

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state):
        keep, next_t0, next_t1, jump, state, result = self.controller.adapt_step_size(
            t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state)
        system = args[0]
        if system.branch is None:  # the whole backbone (no branch to leave)
            return keep, next_t0, next_t1, jump, state, result
        s_x, d_x = _excursion(system, t1 - t0, y0, y1_candidate)
        away = keep & (d_x < 0) & (kink_condition(system, y1_candidate[0], system.branch) >= 0)
        retry = jax.lax.stop_gradient(t0 + s_x * (t1 - t0))
        return (keep & ~away, jnp.where(away, t0, next_t0), jnp.where(away, retry, next_t1), jump & ~away, state, result)


def _excursion(system: SpringSystem, dt, y0, y1):
    """(s, d): the deepest point s ∈ [0, 1] of a step (as a fraction of it) on the cubic Hermite
    interpolant of θ through its ends' θ and θ̇ (its turning points, `bookkeeping.hermite_turns`;
    none: the start), and the kink event's condition there (`kink_event`; < 0: past the kink)."""
    n = system.ndof
    a0, a1, w0, w1 = y0[0], y1[0], dt * y0[n], dt * y1[n]
    ss = jnp.clip(jnp.stack(hermite_turns(a0, a1, w0, w1)), 0.0, 1.0)
    d = kink_condition(system, hermite(ss, a0, a1, w0, w1), system.branch)
    i = jnp.argmin(d)
    return ss[i], d[i]


def equal_time(system: SpringSystem, excitation: AbstractExcitation, t, y, restart):
    """(t, y) where a solve ends, as the next one starts from it where `restart` (a kink, or a
    piece's own step bound): the time without a derivative and y's derivative at that fixed time,
    y's less f(t, y) times the time's (values unchanged). The spring's moment is continuous across
    a kink, so the motion goes on through it unchanged and the fixed-time derivative is the one the
    next solve needs. Carried from solve to solve instead, the time's derivative accumulated every
    near-grazing kink's 1/θ̇ (forward mode, El Centro on the quasi-rigid SM ringing on its pre-yield
    branch after rocking: 1e295 and then NaN after ~3900 pieces, while θ's own stayed bounded), and
    the next event's root find refused the non-finite input."""
    lag = t - jax.lax.stop_gradient(t)  # zero, with the time's derivative
    y_fixed = y - system.vector_field(t, y, excitation) * lag
    return jnp.where(restart, jax.lax.stop_gradient(t), t), jnp.where(restart, y_fixed, y)


def flip(branch, theta, kink):
    """The branch after a kink event at θ (pre-yield ↔ yielded to sign θ); unchanged without one."""
    return jnp.where(kink, jnp.where(branch == 0, jnp.sign(theta), 0.0), branch)


def first_step(system: SpringSystem, dtmax=None):
    """A solve's first step: a thousandth of the rocking time scale 1/p′, and at most half of `dtmax`."""
    return 1e-3 / system.p_r if dtmax is None else jnp.minimum(1e-3 / system.p_r, 0.5 * dtmax)


_WINDOW, _FREE, _FINISHED = 0, 1, 2  # a summary's phases


class _Carry(eqx.Module):
    """A summary run between its pieces (`DiffraxSpringStepper`)."""

    phase: Array  # _WINDOW: the excitation window; _FREE: free motion until the answer is fixed; _FINISHED
    t: Array
    y: Array
    t_next: Array  # the end of the next piece's first step: the controller's proposal (+inf: a fresh start)
    steps: Array  # steps taken in this phase (its bound: the integrator's max_steps)
    n_steps: Array  # steps taken in all
    rec: Record
    status: Status
    e_settle: Array  # free motion stops below this mechanical energy (`SpringSystem.settle_energy`)
    branch: Array  # a kinked backbone's branch (`SpringSystem.branch_at`; 0 for a smooth one)
    hist: dict | None  # a kinked history's values at the save times so far (NaN: not yet)


class DiffraxSpringStepper(AbstractStepper):
    """A spring-model run by `SpringIntegrator`.

    A summary runs in two phases (module docstring), each as `diffrax.diffeqsolve`s of at most
    `SpringIntegrator.chunk_steps` steps (`step`): a piece cut off by its bound goes on from its
    last state with the step its controller proposed next, so that the pieces take the steps one
    solve would. The batch engine advances a batch a few pieces at a time and gathers the cells still
    running between passes (`schedule`): a cell whose spring rings for a long pulse no longer holds
    the whole batch. `solve` (`simulate`, and derivatives through it) runs each phase as one piece.
    A history is one solve with the peak from the steps' Hermite interpolants."""

    integrator: "SpringIntegrator"
    model: "AbstractSpringModel"
    system: SpringSystem
    save: Save | None
    t1: Array | None

    @property
    def kinked(self) -> bool:
        return self.system.backbone.kinked

    @property
    def max_steps(self) -> int:
        # pieces: both phases' step bounds in pieces, and the phase switch; a kinked backbone's
        # pieces that end on a kink besides (each takes a step at least: the phases' step bound)
        pieces = 2 * (-(-self.integrator.max_steps // self.integrator.chunk_steps)) + 2
        return pieces + (2 * self.integrator.max_steps if self.kinked else 0)

    @property
    def checkpointed(self) -> bool:
        # a kinked backbone's pieces run in `solve`'s loop: checkpointed for reverse mode, a plain
        # loop for forward mode (JAX runs neither mode through the other's loop)
        return self.integrator.autodiff == "reverse" or not self.kinked

    @property
    def schedule(self) -> Schedule:
        # a summary: 64 lanes refilled every 4 pieces (48 for a kinked backbone, whose pieces end
        # on every kink: 96 quasi-rigid study scenes, θy = 1e-5 α, 2.5 ms/scene against 3.8 with 4
        # and 2.8 with 16), one compiled size (quasi-rigid Tsit5
        # default, 32×32 and 24×24 grids: 0.23 ms/scene on both, cold compile 3.9 s, against
        # 0.26 and 0.41 ms, 6.2 s gathering every running cell in passes of 4, 4, 8 pieces;
        # 128 lanes the same, 256 lanes 0.28/0.35, passes of 8 pieces 0.28/0.36)
        if self.save is not None:
            return Schedule()
        return Schedule(passes=(48,) if self.kinked else (4,), smallest_batch=64, lanes=64)

    @property
    def rests(self) -> bool:
        """A run of the quasi-rigid SM on a kinked spring (a summary or a history) starts with its
        exact pre-yield phase (`jaxrock.spring.rest`) on an excitation with an exact grid
        (`rest_grid`)."""
        s = self.system
        return self.integrator.exact_rest and self.kinked and isinstance(s, QuasiRigidSystem) and not s.fixed_base and not s.track_energy

    def init(self, excitation) -> _Carry:
        system = self.system
        y0 = system.initial_state()
        zero = jnp.zeros((), jnp.int32)
        c = _Carry(phase=zero + _WINDOW, t=jnp.asarray(excitation.t_start, dtype=y0.dtype), y=y0,
                   t_next=jnp.asarray(jnp.inf, dtype=y0.dtype), steps=zero, n_steps=zero,
                   rec=Record.start(), status=Status.ok,
                   e_settle=jnp.zeros((), y0.dtype), branch=system.branch_at(y0[0]) if self.kinked else jnp.zeros((), y0.dtype),
                   hist=None if self.save is None or not self.kinked else
                   {f: jnp.full(self.save.ts.shape, jnp.nan, y0.dtype) for f in self.save.fields})
        if self.rests and rest_grid(excitation) is not None:
            c = self._rest(excitation, c)
        return c

    def _rest(self, excitation, c: _Carry) -> _Carry:
        """The run after its exact pre-yield phase (`rest_phase`): on the kink of its first yield,
        in the window (or the free motion, if it yields as the window ends), or at the window's end
        without one, in the free motion on the pre-yield branch."""
        system = self.system
        t_stop = self.model.run_end(system, excitation, self.save, self.t1)
        end = rest_phase(system, excitation, t_stop, reverse=self.integrator.autodiff == "reverse")
        inf = jnp.asarray(jnp.inf, c.t.dtype)
        rec = Record(peak=end.peak, t_uplift=jnp.where(end.yielded, end.t, inf), overturned=jnp.asarray(False), t_overturn=inf)
        window = end.yielded & (end.t < excitation.t_end)
        hist = c.hist
        if hist is not None:  # the save times the phase reached, on its exact motion
            ts = self.save.ts
            states = rest_states(system, excitation, ts)
            vals = jax.vmap(lambda t, y: system.history(t, y, excitation, self.save.fields))(ts, states)
            hist = {f: jnp.where(ts <= end.t, vals[f], hist[f]) for f in hist}
        return eqx.tree_at(lambda x: (x.phase, x.t, x.y, x.n_steps, x.rec, x.e_settle, x.branch, x.hist), c,
                           (jnp.where(window, _WINDOW, _FREE), end.t, end.y, end.n_steps, rec,
                            jnp.where(window, c.e_settle, system.settle_energy(rec.peak)), jnp.where(end.yielded, jnp.sign(end.y[0]), 0.0), hist),
                           is_leaf=lambda x: x is None)

    def step(self, excitation, c: _Carry) -> _Carry:
        return self._piece(excitation, c, self.integrator.chunk_steps)

    def done(self, c: _Carry):
        return c.phase == _FINISHED

    def motion(self, c: _Carry):
        a = self.system.alpha_r
        return c.t, c.y[0] / a, c.y[self.system.ndof] / a

    def finish(self, excitation, c: _Carry) -> Solution:
        status = Status.where(c.phase == _FINISHED, c.status, Status.max_iterations)
        ts = None if self.save is None else self.save.ts
        return self.model.watch(self.system).solution(c.rec, status, n_iterations=c.n_steps, ts=ts, history=c.hist)

    def solve(self, excitation) -> Solution:
        if self.kinked:  # pieces between kinks, in equinox's checkpointed loop
            return super().solve(excitation)
        if self.save is not None:
            return self._history(excitation)
        c = self.init(excitation)
        for _ in (_WINDOW, _FREE):  # each phase in one piece: no loop around diffrax's own
            c = self._piece(excitation, c, self.integrator.max_steps)
        return self.finish(excitation, c)

    def _piece(self, excitation, c: _Carry, max_steps: int) -> _Carry:
        """At most `max_steps` more steps of the phase `c` is in; on to the next phase where it ends."""
        model, system, integ = self.model, self.system, self.integrator
        watch = model.watch(system)
        N = system.ndof
        free, running = c.phase == _FREE, c.phase != _FINISHED
        summary = self.save is None
        t_stop = model.run_end(system, excitation, self.save, self.t1)
        t_end = jnp.where(free, t_stop, excitation.t_end)
        # a finished run still traces its piece (under vmap every lane does), over a vanishing interval
        t_end = jnp.where(running, jnp.maximum(t_end, c.t), c.t + 1e-9)
        e_settle = c.e_settle
        dtmax = jnp.where(free, jnp.inf, excitation.max_step)

        def settled(t, y, args, **kw):
            return free & summary & (args[0].mechanical_energy(y) < e_settle)

        conditions, directions = (settled,), (None,)
        if self.kinked:
            conditions, directions = (settled, kink_event(c.branch)), (None, False)
        steps_saved = diffrax.SubSaveAt(steps=True, t0=True)
        if c.hist is None:
            saveat = diffrax.SaveAt(subs=[steps_saved], controller_state=True)
        else:
            # the save times this piece reaches (those before the start clipped to it: the first
            # piece's start is the run's initial state)
            fields = self.save.fields
            saved = diffrax.SubSaveAt(ts=jnp.clip(self.save.ts, c.t, t_end), fn=lambda t, y, args: args[0].history(t, y, args[1], fields))
            saveat = diffrax.SaveAt(subs=[steps_saved, saved], controller_state=True)
        piece_system = system.on_branch(c.branch) if self.kinked else system
        sol = integ.solve(
            piece_system, excitation, c.y, c.t, t_end,
            event=self._events(watch, conditions, directions),
            saveat=saveat,
            dtmax=dtmax,
            t_next=c.t_next,
            max_steps=max_steps,
            # a piece inside the checkpointed loop of `solve` stores every step in reverse mode (as
            # the RM's windows: a solve recomputed inside the loop's own backward pass otherwise
            # returned wrong cotangents)
            checkpoints=max_steps if self.kinked else None,
        )
        sol_ts, sol_ys = sol.ts[0], sol.ys[0]
        # The piece's last state is its last accepted step, or the event it ended on (`num_accepted_steps`
        # entries after the start). diffrax appends its final value to the saved steps, and under vmap,
        # where another lane's event makes every lane locate one, a lane without an event gets the
        # end of its last *attempted* step there: a rejected one's, for a lane cut off by max_steps.
        n_acc = sol.stats["num_accepted_steps"]
        valid = jnp.arange(sol_ts.shape[0]) <= n_acc
        ts = jnp.where(valid, sol_ts, jnp.inf)
        t_last, y_last = sol_ts[n_acc], sol_ys[n_acc]
        th, om = jnp.where(valid, sol_ys[:, 0], jnp.inf), jnp.where(valid, sol_ys[:, N], jnp.inf)
        event = sol.result == diffrax.RESULTS.event_occurred
        kink = (event & sol.event_mask[-1]) if self.kinked else jnp.zeros((), bool)
        event = event & ~kink  # an event that ends the phase
        cut = sol.result == diffrax.RESULTS.max_steps_reached
        steps = c.steps + sol.stats["num_steps"]
        # an event that ended the piece located the overturning (or the rest); its time is the last step end
        over = event & sol.event_mask[0]
        rec = c.rec.merge(watch.steps(ts, th, om).overturn_located(over, t_last))
        status = diffrax_status(sol.result)
        # a piece cut off by its own bound, not the phase's, or ended on a kink
        go_on = (cut | kink) & (steps < integ.max_steps)
        status = Status.where(go_on, Status.ok, Status.where(kink, Status.max_steps, status))
        ended = event | (status != Status.ok) | free  # the window ends in the free motion's phase
        phase = jnp.where(go_on, c.phase, jnp.where(ended, _FINISHED, _FREE))
        switch = (phase == _FREE) & ~free
        phase = jnp.where(running, phase, c.phase)
        t_last, y_last = equal_time(piece_system, excitation, t_last, y_last, go_on)
        keep = lambda new, old: jnp.where(running, new, old)
        y = jnp.where(jnp.all(jnp.isfinite(y_last)), y_last, c.y)
        # after a kink a fresh first step: the other branch's time scale is not this one's
        t_next = jnp.where(switch | kink, jnp.inf, FirstStepController.next_time(sol.controller_state))
        branch = flip(c.branch, y[0], kink)
        hist = c.hist
        if hist is not None:
            first = (c.n_steps == 0) & (c.phase == _WINDOW)
            take = running & (self.save.ts <= t_last) & ((self.save.ts > c.t) | first)
            hist = {f: jnp.where(take, sol.ys[1][f], hist[f]) for f in hist}
        return _Carry(
            phase=phase,
            t=keep(t_last, c.t),
            y=keep(y, c.y),
            t_next=keep(t_next, c.t_next),
            steps=keep(jnp.where(switch, 0, steps), c.steps),
            n_steps=keep(c.n_steps + sol.stats["num_steps"], c.n_steps),
            rec=jax.tree_util.tree_map(keep, rec, c.rec),
            status=Status.where(running, status, c.status),
            # the peak of the window is the free motion's: computed once
            e_settle=jnp.where(switch, system.settle_energy(rec.peak), c.e_settle),
            branch=keep(branch, c.branch),
            hist=hist,
        )

    def _events(self, watch, more=(), directions=()) -> diffrax.Event:
        """Overturning, |θ| reaching `watch.overturn` (never for a fixed base), first, then `more`
        (with their `directions`); located by Newton on the step's interpolant."""

        def over_fn(t, y, args, **kw):
            return watch.overturn - jnp.abs(y[0])

        return diffrax.Event((over_fn, *more), root_finder=SafeNewton(rtol=1e-10, atol=1e-12 * self.model.block.alpha_r),
                             direction=(None, *directions) if more else None)

    def _history(self, excitation) -> Solution:
        """A history: one solve to the run's end, saved at `save.ts`."""
        model, system, save, t1 = self.model, self.system, self.save, self.t1
        watch = model.watch(system)
        N = system.ndof
        t_final = model.run_end(system, excitation, save, t1)
        # Save times before the excitation starts hold the initial state (the ground is still):
        # diffrax saves only within [t0, t1] (`simulate` refuses times beyond t1; earlier ones are clipped)
        ts = jnp.clip(save.ts, excitation.t_start, t_final)
        sub_hist = diffrax.SubSaveAt(ts=ts, fn=lambda t, y, args: system.history(t, y, args[1], save.fields))
        sub_steps = diffrax.SubSaveAt(steps=True, t0=True, fn=lambda t, y, args: (y[0], y[N]))
        sol = self.integrator.solve(
            system, excitation, system.initial_state(), excitation.t_start, t_final,
            event=self._events(watch),
            saveat=diffrax.SaveAt(subs=[sub_hist, sub_steps]),
        )
        hist, (th, om) = sol.ys
        rec = watch.steps(sol.ts[1], th, om)
        located = (sol.result == diffrax.RESULTS.event_occurred) & (rec.peak >= watch.overturn * (1 - 1e-6))
        last = jnp.max(jnp.where(jnp.isfinite(sol.ts[1]), sol.ts[1], -jnp.inf))
        rec = rec.overturn_located(located, last)
        return watch.solution(rec, diffrax_status(sol.result), ts=save.ts, history=hist)
