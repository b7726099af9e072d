"""The spring model integrated by diffrax (`SpringIntegrator`): an L-stable ESDIRK solver with full
Newton, or an explicit Runge–Kutta solver for the one-DOF quasi-rigid model; integral step-size
control with a component-scaled absolute tolerance (`SpringSystem.atol_scale`); overturning
``|θ| ≥ threshold·α′`` is an event. The peak and the uplift come from the accepted steps
(`jaxrock.bookkeeping.Watch.steps`).

A summary runs in two solves: the excitation window, then free motion until the answer is fixed —
the mechanical energy below the potential at the largest rotation seen so far
(`SpringSystem.settled`, an event), overturned, or the run's end (`SpringModel.run_end`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from diffrax import with_stepsize_controller_tols
from jaxtyping import Array

from .. import _linalg
from .._validate import JaxrockInputError
from ..bookkeeping import Record
from ..excitation import AbstractExcitation
from ..model import AbstractSpringIntegrator, AbstractStepper, FirstStepController, check_autodiff, diffrax_adjoint, diffrax_status
from ..results import Save, Solution, Status
from .system import SpringSystem

if TYPE_CHECKING:
    from .model import SpringModel

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

    def controller(self, system: SpringSystem, excitation: AbstractExcitation, dtmax=None):
        pid = diffrax.PIDController(
            rtol=self.rtol,
            atol=self.atol * system.atol_scale(),
            pcoeff=0.0,
            icoeff=1.0,
            dtmax=dtmax,
        )
        if excitation.step_ts is not None:
            return diffrax.ClipStepSizeController(pid, step_ts=excitation.step_ts)
        return pid

    def solve(
        self,
        model: "SpringModel | SpringSystem",
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

        `model` may be a `SpringModel` (its system is assembled here) or an assembled
        `SpringSystem` (`SpringModel.system()`), reused across calls. `dtmax` defaults to the excitation's
        `max_step` while t < t_end. Never throws by default (`throw=False`): inspect `result`.
        """
        system = model if isinstance(model, SpringSystem) else model.system()
        if saveat is None:
            saveat = diffrax.SaveAt(t1=True)
        if dtmax is None:
            dtmax = excitation.max_step
        term = diffrax.ODETerm(lambda t, y, args: args[0].vector_field(t, y, args[1]))
        t0 = jnp.asarray(t0, dtype=float)
        dt0 = jnp.minimum(1e-3 / system.p_r, 0.5 * dtmax) if dtmax is not None else 1e-3 / system.p_r
        dt0 = jnp.asarray(dt0, dtype=float)
        sol = diffrax.diffeqsolve(
            term,
            self.diffrax_solver(),
            t0,
            t1,
            None,  # the first step travels with the controller: no host callback (FirstStepController)
            y0,
            args=(system, excitation),
            saveat=saveat,
            stepsize_controller=FirstStepController(self.controller(system, excitation, dtmax), dt0),
            event=event,
            max_steps=self.max_steps,
            adjoint=diffrax_adjoint(self.autodiff),
            throw=throw,
        )
        # An interval that runs backwards (a history asked to end before the excitation starts; the
        # phases of a summary run forward by construction) is a failure, as diffrax's sign check
        # of (t1 - t0)·dt0 reported it before the first step travelled with the controller.
        return eqx.tree_at(lambda s: s.result, sol, diffrax.RESULTS.where(t1 < t0, diffrax.RESULTS.internal_error, sol.result))


class DiffraxSpringStepper(AbstractStepper):
    """A spring-model run by `SpringIntegrator`: diffrax's `diffeqsolve` runs its own loop, so the
    whole run is done in `init` (`max_steps = 0`; the state is the `Solution`). A summary runs in two
    solves: the excitation window, then free motion until the answer is fixed (module docstring);
    a history is one solve with the peak from the steps' Hermite interpolants."""

    integrator: "SpringIntegrator"
    model: "SpringModel"
    system: SpringSystem
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
        model, system, save, t1 = self.model, self.system, self.save, self.t1
        watch = model.watch(system)
        y0 = system.initial_state()
        t_start = excitation.t_start
        t_end = excitation.t_end
        N = system.ndof
        step_fn = lambda t, y, args: (y[0], y[N])
        root = optx.Newton(rtol=1e-10, atol=1e-12 * model.block.alpha_r)
        over_fn = lambda t, y, args, **kw: watch.overturn - jnp.abs(y[0])  # never for a fixed base
        # an event that ended a solve located the overturning (its peak reached the level, to the
        # root finder's tolerance); the last step end is the event's time
        last = lambda ts: jnp.max(jnp.where(jnp.isfinite(ts), ts, -jnp.inf))
        located = lambda sol, rec: (sol.result == diffrax.RESULTS.event_occurred) & (rec.peak >= watch.overturn * (1 - 1e-6))

        if save is not None:
            t_final = model.run_end(system, excitation, save, t1)
            # Save times before the excitation starts hold the initial state (the ground is still):
            # diffrax saves only within [t0, t1] (`simulate` refuses times beyond t1; earlier ones are clipped)
            ts = jnp.clip(save.ts, t_start, t_final)
            sub_hist = diffrax.SubSaveAt(ts=ts, fn=lambda t, y, args: system.history(t, y, args[1], save.fields))
            sub_steps = diffrax.SubSaveAt(steps=True, t0=True, fn=step_fn)
            sol = self.integrator.solve(
                system, excitation, y0, t_start, t_final,
                event=diffrax.Event(over_fn, root_finder=root),
                saveat=diffrax.SaveAt(subs=[sub_hist, sub_steps]),
            )
            hist, (th, om) = sol.ys
            rec = watch.steps(sol.ts[1], th, om)
            rec = rec.overturn_located(located(sol, rec), last(sol.ts[1]))
            return watch.solution(rec, diffrax_status(sol.result), ts=save.ts, history=hist)

        # phase 1: the excitation window
        sub = diffrax.SubSaveAt(steps=True, t0=True, fn=step_fn)
        sol1 = self.integrator.solve(
            system, excitation, y0, t_start, t_end,
            event=diffrax.Event(over_fn, root_finder=root),
            saveat=diffrax.SaveAt(subs=[sub, diffrax.SubSaveAt(t1=True)]),
        )
        (th1, om1), y_end = sol1.ys
        y_end = y_end[-1]
        rec1 = watch.steps(sol1.ts[0], th1, om1)
        st1 = diffrax_status(sol1.result)
        over1 = (sol1.result == diffrax.RESULTS.event_occurred) & (st1 == Status.ok)
        t_start2 = sol1.ts[1][-1]
        t_start2 = jnp.where(jnp.isfinite(t_start2), t_start2, t_end)
        rec1 = rec1.overturn_located(over1, t_start2)
        # phase 2: free motion until the answer is fixed
        t_stop = model.run_end(system, excitation, None, t1)
        e_settle = system.settle_energy(rec1.peak)  # the peak is fixed during phase 2: computed once

        def settled(t, y, args, **kw):
            return args[0].mechanical_energy(y) < e_settle

        y_end = jnp.where(jnp.all(jnp.isfinite(y_end)), y_end, y0)
        # an overturned (or failed) phase 1 still runs phase 2 formally, over a vanishing interval
        done = over1 | (st1 != Status.ok)
        t_stop = jnp.where(done, t_start2 + 1e-9, t_stop)
        sol2 = self.integrator.solve(
            system, excitation, y_end, t_start2, t_stop,
            event=diffrax.Event((over_fn, settled), root_finder=root),
            saveat=diffrax.SaveAt(steps=True, fn=step_fn),
            dtmax=jnp.inf,
        )
        th2, om2 = sol2.ys
        # join: the last phase-1 point starts phase 2
        ts2 = jnp.concatenate([jnp.atleast_1d(t_start2), sol2.ts])
        th2 = jnp.concatenate([jnp.atleast_1d(y_end[0]), th2])
        om2 = jnp.concatenate([jnp.atleast_1d(y_end[N]), om2])
        over2 = (~done) & (sol2.result == diffrax.RESULTS.event_occurred) & sol2.event_mask[0]
        rec2 = watch.steps(ts2, th2, om2).overturn_located(over2, last(ts2))
        rec = rec1.merge(jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), Record.start(), rec2))
        status = _worse(st1, Status.where(done, Status.ok, diffrax_status(sol2.result)))
        return watch.solution(rec, status)


def _worse(s1: Status, s2: Status) -> Status:
    return Status.where(s1 == Status.ok, s2, s1)
