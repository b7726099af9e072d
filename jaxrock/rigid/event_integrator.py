"""The rigid model's event-driven integration (`EventIntegrator`, `RigidStepper`): the motion as a
sequence of segments, run by a bounded loop (static bound, reported as `Status.max_iterations` if
hit):

- **rest** — the block stays at θ = 0 while |üg| < (g + üv) tanα′ (üv = 0 without a vertical
  component); the uplift time is found by `excitation.uplift_time` (exact on pulses and records)
  and the block uplifts on side s = −sign(üg) (SPEC);
- **rocking** — eq. 2 (eq. 22 for an extended base) about the corner on side s, integrated by a
  diffrax solver until one of three `diffrax.Event`s, each located by a Newton root find on the
  dense output:
    * impact: sθ crosses 0 downwards → θ set exactly to 0, θ̇ ← η θ̇, side flips (eq. 3, r = η²);
    * apex: sθ̇ crosses 0 downwards → the exact peak |θ| is recorded (θ̇ set exactly to 0);
    * overturn: sθ reaches threshold·α′ → overturned, with its time.

Zeno sequences: after an impact with |üg| < g tanα′, the remaining flights form a geometric
series (velocity ×η per impact, frozen üg, small angles) whose total duration is
`T_Z = 2v/(1−η²) (1/A_s + η/A_−s)`, `A_s = p² cosα ((1 + üv/g) tanα + s üg/g)`. When `T_Z ≤ zeno_time/p`,
or when the post-impact velocity is below `zeno_velocity·p·α` (a floor for slender blocks, η → 1,
whose flights near the uplift threshold are long even at round-off velocities), the block is put
to rest (its rest is memoryless: the next uplift only depends on the excitation, searched from the
impact time), instead of computing the remaining infinitely many impacts.

Stopping when the answer is fixed (no history asked): after the excitation has ended the motion is
free; energy `E = ½θ̇² + p²(cos(α−|θ|) − cosα)` is conserved between impacts and multiplied by η²
at each, so the remaining peaks can only decay and the next one is known in closed form:
`cos(α − θ_peak) = cosα + E/p²` (after one more impact, E → η²E, if the block is moving inwards).
The run stops there, unless that peak overturns the block, in which case it goes on to find the
overturning time.

Summaries on a sampled record (`jaxrock.Record`) go sample by sample instead (`RigidStepper._attempt`,
issue 53): each attempt is one error-controlled step of the solver (diffrax's step and dense
output, its PID controller's integral rule), to the next sample at most, on which üg is one linear
piece; the first event of a step (the same three, in the same priority, plus the uplift of a block
at rest, searched on the piece) is located on the step's dense output by a plain bracketed Newton
loop (`jaxrock._rootfind.bracketed_root`) and differentiated implicitly. The rest, impact, Zeno
and free-motion rules are the segment loop's. Under `vmap` the lanes of a batch then advance in
lockstep through the samples, where the segment loop's lanes desynchronised at every impact.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._rootfind import SafeNewton, bracketed_root
from ..bookkeeping import Record
from ..excitation import AbstractExcitation
from ..excitation import Record as SampledRecord
from ..excitation import crossing
from ..geometry import G
from ..model import AbstractIntegrator, AbstractStepper, FirstStepController, Schedule, check_autodiff, diffrax_adjoint, diffrax_status
from ..results import Save, Solution, Status

if TYPE_CHECKING:
    from .model import RigidModel

_REST, _ROCKING, _OVERTURNED = 0, 1, 2

PULSE_TOLERANCES = (1e-8, 1e-10)  # (rtol, atol) of `EventIntegrator` on analytic excitations
RECORD_TOLERANCES = (1e-12, 1e-14)  # and on sampled records (its docstring)


class EventIntegrator(AbstractIntegrator):
    """Settings of the rigid model's event-driven integration (`RigidModel`'s default integrator).

    The motion is a sequence of rest and rocking segments, each rocking one integrated by a diffrax
    solver until an impact, apex or overturning event, with Zeno sequences closed in closed form
    (`jaxrock.rigid.event_integrator`)..

    Default tolerances, analytic pulses: 1e-8, 1e-10 (`PULSE_TOLERANCES`): max |Δ max θ/α′| ≤ 1.4e-7
    against a converged reference on the benchmark's 64 × 64 pulse grid and three more families of
    32 × 32 (other slenderness, size and pulse shape; benchmarks/bench_rigid.py), the error falling
    with rtol (8e-10 at 1e-10, 3e-11 at 1e-12). Sampled records: 1e-12, 1e-14 (`RECORD_TOLERANCES`):
    on the record suite of benchmarks/bench_suite.py (11 records, 59 cells against SciPy at rtol
    1e-12; results/bench_suite_rtol.txt) max |Δθ|/α′ falls from 2.4e-5 at 1e-8 to 6.9e-7 at 1e-11 and
    3.6e-7 at 1e-12, for 16 % more time than at 1e-8: a record's steps are capped by its samples, so
    a tighter tolerance costs little there, where on a pulse every step is the tolerance's.

    Attributes:
        solver: an explicit diffrax solver; default `Tsit5()`: on the benchmark grid it reaches a
            given error in θ/α at about half the cost of `Dopri8`, whose 13 stages do not pay back at
            the step sizes the excitation and the events impose (benchmarks/bench_rigid.py).
        rtol: relative step-size tolerance (on θ [rad] and θ̇ [rad/s]), > 0; default None: by the
            excitation (`tolerances`: 1e-8 on pulses, 1e-12 on records).
        atol: absolute step-size tolerance, > 0; default None: by the excitation (1e-10 on pulses,
            1e-14 on records), or rtol/100 where `rtol` is given.
        root_tol: tolerance of the root finds that locate the events [s]; default 1e-13.
        zeno_time: Zeno closure threshold on the remaining flights' duration, in units of 1/p′;
            default 1e-4.
        zeno_velocity: Zeno closure threshold on the post-impact velocity, in units of p′α′; default 1e-9.
        chunk_steps: length of one loop iteration, in nominal steps (step attempts in a paced record
            run); default 16. Under `vmap` all lanes move in lock-step, one loop iteration at a time;
            cutting segments into time windows of about this many steps keeps a lane that chatters
            through many short segments from making every other lane wait a whole long segment per
            impact (benchmarks/bench_rigid.py). Windows are cut in time, not by diffrax's `max_steps`:
            under `vmap`, diffrax 0.7 returns the state of the last *attempted* step for a lane
            stopped by `max_steps` while another lane had an event, which may be a rejected step.
        max_steps: bound on steps per window (static); default 4096; hitting it is reported as
            `Status.max_steps`.
        max_iterations: bound on loop iterations (segments + windows) per run (static); default
            100_000; hitting it is reported as `Status.max_iterations`.
        autodiff: "reverse" (default: `jax.grad`, `jax.jacrev`) or "forward" (`jax.jvp`,
            `jax.jacfwd`) (static); see `jaxrock.model.diffrax_adjoint`.
        on_samples: whether the event loop's steps land on a record's samples, its üg's kinks
            (diffrax's `step_ts`; static); default True. False: steps only capped by the record's
            step. The placement is the more accurate (an overturning 5.085 s into a 200 Hz record
            moves 5e-6 s without it), but diffrax's clipping corrupts the derivatives of the motion
            after an apex, in both modes (dθ/dt₀ 0.42 against 0.148 by central differences; 5e-9
            apart without it): `jaxrock.identify` differentiates histories on records with False.
            Summaries on records go sample by sample on their own and are unaffected.

    Raises:
        JaxrockInputError: when `autodiff` is neither "reverse" nor "forward".

    Example:
        ```python
        integrator = jaxrock.EventIntegrator(rtol=1e-10, autodiff="forward")
        sol = jaxrock.simulate(model, pulse, integrator=integrator)
        ```
    """

    solver: diffrax.AbstractSolver = diffrax.Tsit5()
    rtol: float | None = None
    atol: float | None = None
    root_tol: float = 1e-13
    zeno_time: float = 1e-4
    zeno_velocity: float = 1e-9
    chunk_steps: int = 16
    max_steps: int = eqx.field(static=True, default=4096)
    max_iterations: int = eqx.field(static=True, default=100_000)
    autodiff: str = eqx.field(static=True, default="reverse")
    on_samples: bool = eqx.field(static=True, default=True)

    def __check_init__(self):
        check_autodiff(self.autodiff)

    def tolerances(self, exc: AbstractExcitation) -> tuple[float, float]:
        """The step-size tolerances on `exc`.

        The fields where given, else `RECORD_TOLERANCES` on a sampled record (or a pair) and `PULSE_TOLERANCES`
        on anything else; atol = rtol/100 where only rtol is given.

        Arguments:
            exc: the excitation of the run.

        Returns:
            rtol (float): the relative tolerance.
            atol (float): the absolute tolerance.
        """
        rtol0, atol0 = RECORD_TOLERANCES if exc.sampled else PULSE_TOLERANCES
        rtol = rtol0 if self.rtol is None else self.rtol
        atol = (atol0 if self.rtol is None else 1e-2 * rtol) if self.atol is None else self.atol
        return rtol, atol

    def stepper(self, model: "RigidModel", system=None, save: Save | None = None, t1=None) -> "RigidStepper":
        """`AbstractIntegrator.stepper`: the segment loop, one segment or window per step.

        Arguments:
            model: the rigid model of the scene.
            system (None): unused (the rigid model prepares nothing).
            save: the output request; default None: a summary.
            t1 (float | Array | None): end time [s] of a time history.
        """
        return RigidStepper(model, self, save, t1)


class _Carry(eqx.Module):
    t: Array
    theta: Array
    theta_dot: Array
    side: Array
    mode: Array
    rec: Record  # peak, uplift, overturn so far
    n_impacts: Array
    n_segments: Array
    dt_next: Array  # > 0: continue the current segment with this step (chunked); 0: fresh segment
    status: Status
    finished: Array
    hist: dict | None


class _Paced(eqx.Module):
    """The state of a summary run on a sampled record, advanced one step attempt at a time
    (`RigidStepper._attempt`); the fields `_solution` reads are `_Carry`'s."""

    t: Array
    theta: Array
    theta_dot: Array
    side: Array
    mode: Array
    rec: Record
    n_impacts: Array
    n_segments: Array
    k: Array  # the sample interval [t_k, t_k+1) that holds t; the record's last sample index after its end
    h: Array  # the next step the error control proposes
    cap: Array  # the largest step of the current flight (`_flight_steps`)
    status: Status
    finished: Array
    hist: None = None


class _Scene(NamedTuple):
    """The per-scene constants of a run (cheap scalars, recomputed where needed)."""

    alpha: Array
    p: Array
    eta: Array
    level: Array  # uplift acceleration g tanα′
    threshold: Array  # overturning |θ|/α′
    t_end: Array  # excitation end
    t_stop: Array  # run end: excitation end (summary) or t1 (history)
    h_nom: Array  # nominal step
    eps: Array
    tiny: Array


class RigidStepper(AbstractStepper):
    """The rigid model's segment loop (module docstring) as an `AbstractStepper`: one step is one
    segment or one time window of a segment (`EventIntegrator.chunk_steps`); the state is `_Carry`."""

    model: RigidModel
    integrator: EventIntegrator
    save: Save | None
    t1: Array | None
    # (t0, θ0, θ̇0): a history run from this state at t0 instead of rest at the excitation's start
    # (`jaxrock.analyses.identify`: free rocking from a release, a segment from a measured peak)
    start: tuple[Array, Array, Array] | None = None

    @property
    def max_steps(self) -> int:
        return self.integrator.max_iterations

    @property
    def checkpointed(self) -> bool:
        return self.integrator.autodiff == "reverse"

    @property
    def schedule(self) -> Schedule:
        # short first passes (most cells finish within a few segments), then longer ones; below 64
        # cells a smaller batch stops paying (a segment is cheap, a batch's overhead is not)
        return Schedule(passes=(4, 8, 16, 32), smallest_batch=64, bytes_per_scene=0)

    @property
    def summary_only(self) -> bool:
        return self.save is None

    def motion(self, state):
        a = self.model.block.alpha_r
        return state.t, state.theta / a, state.theta_dot / a

    def _scene(self, exc: AbstractExcitation) -> _Scene:
        model, block = self.model, self.model.block
        p = block.p_r
        dtype = jnp.result_type(float)
        t_end = exc.t_end
        return _Scene(
            alpha=block.alpha_r,
            p=p,
            eta=model.eta,
            level=block.uplift_acceleration,
            threshold=jnp.asarray(model.threshold, dtype=float),
            t_end=t_end,
            t_stop=t_end if self.summary_only else jnp.asarray(self.t1, dtype=float),
            h_nom=jnp.minimum(exc.max_step, 0.05 / p),
            eps=jnp.finfo(dtype).eps,
            tiny=jnp.finfo(dtype).tiny,
        )

    def _paced(self, exc: AbstractExcitation) -> bool:
        """Whether a run goes sample by sample (module docstring): summaries on a sampled record."""
        return self.summary_only and isinstance(exc, SampledRecord) and self.start is None

    def init(self, exc: AbstractExcitation) -> _Carry | _Paced:
        c = self._init(exc)
        if not self._paced(exc):
            return c
        # the quiet start of the record in one search (a block that never uplifts is done here)
        sc = self._scene(exc)
        c = self._rest_step(sc, exc, c)
        h, cap = self._flight_steps(sc, exc, c.t, c.theta, c.theta_dot, c.side)
        return _Paced(t=c.t, theta=c.theta, theta_dot=c.theta_dot, side=c.side, mode=c.mode, rec=c.rec,
                      n_impacts=c.n_impacts, n_segments=c.n_segments, k=_interval(exc, c.t), h=h, cap=cap,
                      status=c.status, finished=c.finished)

    def _init(self, exc: AbstractExcitation) -> _Carry:
        dtype = jnp.result_type(float)
        zero = jnp.zeros((), dtype)
        save = self.save
        hist0 = None if save is None else {k: jnp.zeros_like(save.ts) for k in save.fields}
        t0, theta0, theta_dot0 = (exc.t_start, zero, zero) if self.start is None else self.start
        t0, theta0, theta_dot0 = (jnp.asarray(v, dtype) for v in (t0, theta0, theta_dot0))
        moving = (theta0 != 0) | (theta_dot0 != 0)
        return _Carry(
            t=t0,
            theta=theta0,
            theta_dot=theta_dot0,
            side=jnp.where(theta0 != 0, jnp.sign(theta0), jnp.where(theta_dot0 < 0, -1.0, 1.0)).astype(dtype),
            mode=jnp.where(moving, jnp.asarray(_ROCKING), jnp.asarray(_REST)),
            rec=Record.start().saw_uplift(moving, t0),
            n_impacts=jnp.zeros((), jnp.int32),
            n_segments=jnp.zeros((), jnp.int32),
            dt_next=zero,
            status=Status.ok,
            finished=jnp.asarray(False),
            hist=hist0,
        )

    def done(self, c: _Carry):
        return c.finished | (c.n_segments >= self.max_steps)

    def finish(self, exc: AbstractExcitation, c: _Carry) -> Solution:
        status = Status.where(~c.finished & (c.status == Status.ok), Status.max_iterations, c.status)
        return _solution(self.model, c, status, self.summary_only, self.save)

    def step(self, exc: AbstractExcitation, c: _Carry | _Paced) -> _Carry | _Paced:
        sc = self._scene(exc)
        is_rest = c.mode == _REST
        c = eqx.tree_at(lambda x: x.n_segments, c, c.n_segments + 1)
        if isinstance(c, _Paced):
            return jax.lax.fori_loop(0, self.integrator.chunk_steps, lambda _, c: self._attempt(sc, exc, c), c)
        c_rest = self._rest_step(sc, exc, c)
        # a block that uplifts in this iteration rocks in the same iteration
        c = jax.tree_util.tree_map(lambda a, b: jnp.where(is_rest, a, b), c_rest, c)
        return self._rock_step(sc, exc, c, (c.mode == _ROCKING) & ~c.finished)

    def _will_overturn(self, sc: _Scene, c: _Carry):
        return self.model.free_peak(c.theta, c.theta_dot, c.side) >= sc.threshold

    def _segment_end(self, sc: _Scene, c: _Carry):
        # Summary runs stop at the end of the excitation unless the free motion overturns.
        go_on = self.summary_only & (c.t >= sc.t_end) & self._will_overturn(sc, c)
        end = jnp.where(go_on, c.t + 1e4 / sc.p, sc.t_stop)
        return jnp.maximum(end, c.t)

    @staticmethod
    def _min_step(sc: _Scene, t):
        """Smallest step: 1e-8/p, but resolvable at time t in this precision."""
        return jnp.maximum(1e-8 / sc.p, 64 * sc.eps * (jnp.abs(t) + 1 / sc.p))

    def _rest_step(self, sc: _Scene, exc: AbstractExcitation, c: _Carry) -> _Carry:
        save, t_stop = self.save, sc.t_stop
        t_up = exc.uplift_time(c.t, sc.level)
        starts = t_up < t_stop
        t_new = jnp.where(starts, t_up, c.t)
        side = -jnp.sign(exc(t_new))
        hist = c.hist
        if hist is not None:
            upto = jnp.where(starts, t_up, t_stop)
            inwin = (save.ts >= c.t) & (save.ts < upto)
            hist = {k: jnp.where(inwin, 0.0, v) for k, v in hist.items()}
        return eqx.tree_at(
            lambda x: (x.t, x.side, x.mode, x.rec, x.finished, x.hist),
            c,
            (
                t_new,
                jnp.where(starts, side, c.side),
                jnp.where(starts, _ROCKING, _REST),
                c.rec.saw_uplift(starts, t_up),
                ~starts,
                hist,
            ),
            is_leaf=lambda x: x is None,
        )

    def _rock_step(self, sc: _Scene, exc: AbstractExcitation, c: _Carry, is_rocking) -> _Carry:
        model, integ, save, summary_only = self.model, self.integrator, self.save, self.summary_only
        alpha, p, eta, threshold, t_end, h_nom, tiny = sc.alpha, sc.p, sc.eta, sc.threshold, sc.t_end, sc.h_nom, sc.tiny
        t_seg = jnp.where(is_rocking, self._segment_end(sc, c), c.t)
        dt_min = self._min_step(sc, c.t)
        h0, cap = self._flight_steps(sc, exc, c.t, c.theta, c.theta_dot, c.side)
        fresh_flight = c.dt_next == 0
        term, event, controller = self._diffrax_parts(sc, exc, jnp.where(fresh_flight, cap, exc.max_step))
        # A flight's first window spans at most 4·chunk_steps of its cap, i.e. 16 of its estimated
        # durations: where the ground turns a hop into a rocking motion (|üg| rising through
        # g tanα′ during a chatter), the hop's cap would hold every step of a window of
        # chunk_steps·h_nom, thousands of steps (`max_steps`); the next window steps freely.
        t_win = jnp.minimum(t_seg, c.t + integ.chunk_steps * jnp.where(fresh_flight, jnp.minimum(h_nom, 4 * cap), h_nom))
        dt0 = jnp.where(c.dt_next > 0, c.dt_next, h0)
        dt0 = jax.lax.stop_gradient(jnp.minimum(dt0, jnp.maximum(t_win - c.t, tiny)))
        saveat = diffrax.SaveAt(t1=True, dense=not summary_only)
        sol = diffrax.diffeqsolve(
            term,
            integ.solver,
            c.t,
            t_win,  # ≥ c.t: the segment's end is never before it (`_segment_end`)
            None,  # the first step (> 0) travels with the controller: no host callback (FirstStepController)
            (c.theta, c.theta_dot),
            args=c.side,
            saveat=saveat,
            stepsize_controller=FirstStepController(controller, dt0),
            event=event,
            max_steps=integ.max_steps,
            # every step of a window checkpointed: a window's solve that recomputes steps inside
            # the segment loop's own checkpointed backward pass returned wrong cotangents
            # (d max_theta/d a_p 1e-4 off at rtol 1e-12, where a window takes > 90 steps, the
            # default number of checkpoints for max_steps = 4096; forward mode, and either loop
            # storing every step, agree with central differences to 1e-9). Costs memory in
            # reverse mode only: max_steps states per window being differentiated.
            adjoint=diffrax_adjoint(integ.autodiff, checkpoints=integ.max_steps),
            throw=False,
        )
        tf = sol.ts[-1]
        thf, theta_dot_f = sol.ys[0][-1], sol.ys[1][-1]
        hit_over, hit_apex, hit_impact = sol.event_mask
        hit_impact, hit_apex, hit_over = (hit_impact & is_rocking, hit_apex & is_rocking, hit_over & is_rocking)
        # A grazing uplift: |üg| a hair above g tanα′ while the rounded moment about the corner
        # turns the fresh block (θ = θ̇ = 0) into the ground; the impact event cannot see a
        # crossing from exactly 0. It counts as an uplift (|üg| exceeded the level) that returns to
        # rest at once, and the next exceedance is searched a resolvable instant later (the
        # window may hold a real uplift): never a failure.
        fresh = (c.theta == 0) & (c.theta_dot == 0)
        back_to_rest = is_rocking & fresh & ~hit_impact & ~hit_over & (c.side * thf <= 0)
        chunked = is_rocking & ~(hit_impact | hit_apex | hit_over) & (tf < t_seg)
        n_acc = jnp.maximum(sol.stats["num_accepted_steps"], 1)
        dt_next = jnp.where(chunked & ~back_to_rest, jnp.maximum((tf - c.t) / n_acc, dt_min), 0.0)
        status = diffrax_status(sol.result)
        missed = is_rocking & ~hit_impact & ~back_to_rest & (c.side * thf < -1e-6 * alpha)
        status = Status.where(missed, Status.missed_impact, status)
        status = Status.where(is_rocking, status, Status.ok)

        hist = c.hist
        if hist is not None:
            inwin = is_rocking & (save.ts >= c.t) & (save.ts <= tf)
            ys = jax.vmap(sol.evaluate)(jnp.clip(save.ts, c.t, tf))
            new = {"theta": jnp.where(back_to_rest, 0.0, ys[0]), "theta_dot": jnp.where(back_to_rest, 0.0, ys[1])}
            hist = {k: jnp.where(inwin, new[k], v) for k, v in hist.items()}
            # after overturning, hold the overturning state (the fall itself is not modelled)
            after = hit_over & (save.ts > tf)
            hold = {"theta": c.side * threshold * alpha, "theta_dot": theta_dot_f}
            hist = {k: jnp.where(after, hold[k], v) for k, v in hist.items()}

        theta_dot_impact, side_imp, zeno = self._impact(sc, exc, tf, theta_dot_f, c.side)
        zeno = hit_impact & zeno

        rec = c.rec.saw_peak(is_rocking & (hit_apex | (not summary_only)) & ~back_to_rest, thf).saw_overturn(hit_over, tf)
        theta_new = jnp.where(hit_impact | back_to_rest, 0.0, thf)
        theta_dot_new = jnp.where(hit_impact, jnp.where(zeno, 0.0, theta_dot_impact), jnp.where(hit_apex | back_to_rest, 0.0, theta_dot_f))
        side_new = jnp.where(hit_impact, side_imp, c.side)
        mode = jnp.where(hit_over, _OVERTURNED, jnp.where(zeno | back_to_rest, _REST, c.mode))
        t_new = jnp.where(back_to_rest, c.t + self._min_step(sc, c.t), tf)
        no_event = ~(hit_impact | hit_apex | hit_over)
        bad = status != Status.ok
        seg_done = is_rocking & no_event & ~chunked & (tf >= t_seg)
        # A summary segment that reaches the end of the excitation goes on exactly when its free
        # motion overturns (the same test `segment_end` makes at the start of the next segment).
        free_overturns = summary_only & (c.t < t_end) & (tf >= t_end) & (model.free_peak(thf, theta_dot_f, c.side) >= threshold)
        finished = c.finished | hit_over | bad | (seg_done & ~free_overturns & ~back_to_rest)
        out = eqx.tree_at(
            lambda x: (x.t, x.theta, x.theta_dot, x.side, x.mode, x.rec, x.n_impacts, x.dt_next, x.status, x.finished, x.hist),
            c,
            (
                jnp.where(is_rocking, t_new, c.t),
                jnp.where(is_rocking, theta_new, c.theta),
                jnp.where(is_rocking, theta_dot_new, c.theta_dot),
                jnp.where(is_rocking, side_new, c.side),
                jnp.where(is_rocking, mode, c.mode),
                rec,
                c.n_impacts + hit_impact.astype(c.n_impacts.dtype),
                jnp.where(is_rocking, dt_next, c.dt_next),
                Status.where(is_rocking, status, c.status),
                jnp.where(is_rocking, finished, c.finished),
                hist,
            ),
            is_leaf=lambda x: x is None,
        )
        return out

    def _attempt(self, sc: _Scene, exc: SampledRecord, c: _Paced) -> _Paced:
        """One step attempt of a paced run: a block at rest looks for |üg| > (g + üv) tanα′ on the current
        sample interval; a rocking block takes one error-controlled step of the solver, to the next
        sample at most, and locates the first event (overturn, apex, impact: as the diffrax
        events) on the step's dense output."""
        model, integ = self.model, self.integrator
        solver = _stage_loop(integ)
        alpha, p = sc.alpha, sc.p
        active = ~c.finished
        in_record = c.k < exc.length - 1
        # the next sample, or after the record the end of a free motion that overturns
        t_b = jnp.where(in_record, exc.dt * (c.k + 1).astype(c.t.dtype), c.t + 1e4 / p)

        # everything this attempt evaluates lies on the current sample interval, where üg is one
        # linear piece (zero after the record): read from the record once
        record, exc = exc, _Piece.of(exc, c.k, in_record)

        # at rest: uplift on this interval, else on to its end
        rest = active & (c.mode == _REST)
        v = (exc.vertical_acceleration(c.t), exc.vertical_acceleration(t_b)) if exc.has_vertical else (None, None)
        t_up = crossing(c.t, t_b, exc(c.t), exc(t_b), sc.level, *v)
        up = rest & in_record & (t_up <= t_b)
        t_rest = jnp.where(up, t_up, t_b)
        side_up = -jnp.sign(exc(t_rest))

        # rocking: one step of at most the flight's cap, ending on the next sample at the latest
        rock = active & (c.mode == _ROCKING)
        s, thr = c.side, sc.threshold * alpha
        # (a step that would leave less than 1 % of itself before the sample goes to the sample: the
        # interval t_k+1 − t_k rounds an ulp above the step cap dt, and the remnant would be an ulp)
        h = jnp.minimum(c.h, c.cap)
        t1 = jnp.where(c.t + 1.01 * h >= t_b, t_b, c.t + h)

        def vf(t, y, side):
            return y[1], model.acceleration(t, y[0], side, exc)

        term = diffrax.ODETerm(vf)
        y0 = (c.theta, c.theta_dot)
        state0 = solver.init(term, c.t, t1, y0, s)
        y1, y_err, dense, _, _ = solver.step(term, c.t, t1, y0, s, state0, made_jump=False)
        # error control as diffrax's PIDController (its defaults: an integral controller)
        rtol, atol = integ.tolerances(record)
        scale = [atol + rtol * jnp.maximum(jnp.abs(a), jnp.abs(b)) for a, b in zip(y0, y1)]
        err = jnp.sqrt(0.5 * sum((e / sc_) ** 2 for e, sc_ in zip(y_err, scale)))
        finite = jnp.isfinite(y1[0]) & jnp.isfinite(y1[1]) & jnp.isfinite(err)
        ok = finite & (err <= 1)
        factor = jnp.where(err == 0, 10.0, 0.9 * jnp.where(finite & (err > 0), err, 1.0) ** (-1.0 / solver.order(term)))
        h_next = jax.lax.stop_gradient(jnp.where(finite, jnp.clip(factor, 0.2, 10.0), 0.2) * (t1 - c.t))

        # the events, in diffrax's priority (`_diffrax_parts`)
        g0, g1 = (s * c.theta, s * c.theta_dot), (s * y1[0], s * y1[1])
        over = (g0[0] - thr <= 0) & (g1[0] - thr > 0)
        apex = ~over & (g0[1] > 0) & (g1[1] <= 0)
        impact = ~over & ~apex & (g0[0] > 0) & (g1[0] <= 0)
        event = rock & ok & (over | apex | impact)
        interp = solver.interpolation_cls(t0=c.t, t1=t1, **dense)

        def condition(t, args):
            interp, s, thr = args
            th, th_dot = interp.evaluate(t)
            return jnp.where(apex, s * th_dot, s * th - jnp.where(over, thr, 0.0))

        te = jnp.where(event, bracketed_root(condition, (interp, s, thr), jnp.where(event, c.t, t1), t1, integ.root_tol), t1)
        ye = interp.evaluate(te)
        thf, theta_dot_f = jnp.where(event, ye[0], y1[0]), jnp.where(event, ye[1], y1[1])
        hit_over, hit_apex, hit_impact = event & over, event & apex, event & impact
        fresh = (c.theta == 0) & (c.theta_dot == 0)
        back_to_rest = rock & ok & fresh & ~hit_impact & ~hit_over & (s * y1[0] <= 0)
        missed = rock & ok & ~hit_impact & ~back_to_rest & (s * thf < -1e-6 * alpha)

        theta_dot_impact, side_imp, zeno = self._impact(sc, exc, te, theta_dot_f, s)
        zeno = hit_impact & zeno
        theta_r = jnp.where(hit_impact | back_to_rest, 0.0, thf)
        theta_dot_r = jnp.where(hit_impact, jnp.where(zeno, 0.0, theta_dot_impact), jnp.where(hit_apex | back_to_rest, 0.0, theta_dot_f))
        side_r = jnp.where(hit_impact, side_imp, s)
        mode_r = jnp.where(hit_over, _OVERTURNED, jnp.where(zeno | back_to_rest, _REST, _ROCKING))
        t_r = jnp.where(back_to_rest, c.t + self._min_step(sc, c.t), te)
        at_b = ok & ~event & ~back_to_rest & (t1 == t_b)
        # on reaching the record's end, the run goes on exactly when the free motion overturns
        end_free = at_b & in_record & (c.k + 2 == record.length) & (model.free_peak(thf, theta_dot_f, s) < sc.threshold)
        finished_r = hit_over | missed | end_free | (at_b & ~in_record)

        # merge: rest lanes, rocking lanes, finished lanes unchanged
        sel = lambda a_rest, a_rock, a: jnp.where(rest, a_rest, jnp.where(rock & ok, a_rock, a))  # a rejected step changes only h
        t_new = sel(t_rest, t_r, c.t)
        theta_new = sel(c.theta, theta_r, c.theta)
        theta_dot_new = sel(c.theta_dot, theta_dot_r, c.theta_dot)
        side_new = sel(jnp.where(up, side_up, c.side), side_r, c.side)
        new_flight = (up & rest) | (rock & (hit_apex | hit_impact))
        h_f, cap_f = self._flight_steps(sc, exc, t_new, theta_new, theta_dot_new, side_new)
        k_new = jnp.where(in_record & (t_new >= t_b), c.k + 1, c.k)
        return _Paced(
            t=t_new,
            theta=theta_new,
            theta_dot=theta_dot_new,
            side=side_new,
            mode=sel(jnp.where(up, _ROCKING, _REST), mode_r, c.mode),
            rec=c.rec.saw_uplift(up, t_up).saw_peak(rock & hit_apex, thf).saw_overturn(rock & hit_over, te),
            n_impacts=c.n_impacts + (rock & hit_impact).astype(c.n_impacts.dtype),
            n_segments=c.n_segments,
            k=k_new,
            h=jnp.where(new_flight, h_f, jnp.where(rock, h_next, c.h)),
            cap=jnp.where(new_flight, cap_f, c.cap),
            status=Status.where(rock & missed, Status.missed_impact, c.status),
            finished=c.finished | (rest & ~in_record) | (rock & finished_r),
        )

    def _flight_steps(self, sc: _Scene, exc: AbstractExcitation, t, theta, theta_dot, side):
        """(first step, largest step) of a flight (a segment) from (θ, θ̇) at time t on `side`.

        The flight's time scale: from θ = 0 its duration 2|θ̇|/|θ̈|, from an apex its fall
        √(2|θ|/|θ̈|). A flight's first step off θ = 0 is a fortieth of it, and its steps stay below
        a quarter of it, so that no step holds a crossing of θ = 0 and the return from it (the
        impact event sees sθ of one sign at both ends: a 42 ms step over an 8 ms dip after a tiny
        apex lost two impacts). A block uplifting from rest (θ = θ̇ = 0) starts at the least step.
        A step size carries no derivative (as diffrax's own controller): the flight estimate's
        |θ̇|/|θ̈| has an infinite derivative where θ̈ underflows (an overturned lane after the
        pulse, still evaluated under vmap), and 0·∞ = NaN reached every lane's gradient."""
        acc_abs = jnp.maximum(jnp.abs(self.model.acceleration(t, theta, side, exc)), sc.tiny)
        dt_min = self._min_step(sc, t)
        at_zero = theta == 0
        t_flight = jnp.where(at_zero, 2 * jnp.abs(theta_dot) / acc_abs, jnp.sqrt(2 * jnp.abs(theta) / acc_abs))
        moving = (theta != 0) | (theta_dot != 0)
        cap = jnp.where(moving, jnp.clip(0.25 * t_flight, dt_min, exc.max_step), exc.max_step)
        h0 = jnp.where(at_zero, jnp.clip(0.05 * jnp.abs(theta_dot) / acc_abs, dt_min, sc.h_nom), sc.h_nom)
        return jax.lax.stop_gradient(h0), jax.lax.stop_gradient(cap)

    def _impact(self, sc: _Scene, exc: AbstractExcitation, tf, theta_dot_f, side):
        """The impact at time `tf` on `side` (eq. 3): (θ̇ after it, the new side, whether the Zeno
        closure puts the block to rest: module docstring)."""
        alpha, p, eta, integ = sc.alpha, sc.p, sc.eta, self.integrator
        theta_dot_impact = eta * theta_dot_f
        side_imp = -side
        s_ug, tan_a = side_imp * exc(tf) / G, jnp.tan(alpha)
        if exc.has_vertical:
            tan_a = (1 + exc.vertical_acceleration(tf) / G) * tan_a
        a_s = p**2 * jnp.cos(alpha) * (tan_a + s_ug)
        a_o = p**2 * jnp.cos(alpha) * (tan_a - s_ug)
        v = jnp.abs(theta_dot_impact)
        both = (a_s > 0) & (a_o > 0)
        t_zeno = 2 * v / (1 - eta**2 + sc.tiny) * (1 / jnp.where(both, a_s, 1.0) + eta / jnp.where(both, a_o, 1.0))
        zeno = both & ((t_zeno * p <= integ.zeno_time) | (v <= integ.zeno_velocity * p * alpha))
        return theta_dot_impact, side_imp, zeno

    def _diffrax_parts(self, sc: _Scene, exc: AbstractExcitation, dtmax):
        """The rocking equation's term, its three events and the step-size controller (steps of at
        most `dtmax`)."""
        model, integ, threshold, alpha = self.model, self.integrator, sc.threshold, sc.alpha

        def vf(t, y, args):
            theta, theta_dot = y
            return theta_dot, model.acceleration(t, theta, args, exc)

        term = diffrax.ODETerm(vf)
        cond_impact = lambda t, y, args, **kw: args * y[0]
        cond_apex = lambda t, y, args, **kw: args * y[1]
        cond_over = lambda t, y, args, **kw: args * y[0] - threshold * alpha
        event = diffrax.Event(
            # diffrax gives priority by list position when several events fire in one step. Order
            # them as they can occur in time within one flight: crossing the overturning angle comes
            # before any apex beyond it, and an apex before the impact that ends its flight.
            [cond_over, cond_apex, cond_impact],
            # Safeguarded Newton on the step's dense output: plain Newton stalls at apexes where θ̈ ≈ 0.
            root_finder=SafeNewton(rtol=integ.root_tol, atol=integ.root_tol),
            direction=[True, False, False],
        )
        rtol, atol = integ.tolerances(exc)
        # steps on the record's samples (its kinks) unless `on_samples` is off (its docstring: the
        # derivatives after an apex)
        controller = diffrax.PIDController(rtol=rtol, atol=atol, dtmax=dtmax, step_ts=exc.step_ts if integ.on_samples else None)
        return term, event, controller


class _Piece(eqx.Module):
    """üg (and üv of a pair) on one sample interval of a record: linear from `a0` (`v0`) at `t0`
    (what `RigidStepper._attempt` evaluates, seven times per step, without reading the record again)."""

    t0: Array
    a0: Array
    slope: Array
    max_step: Array
    v0: Array | None = None  # a pair's üv (None: no vertical component)
    v_slope: Array | None = None

    @classmethod
    def of(cls, exc: SampledRecord, k, in_record) -> "_Piece":
        """Sample interval k of `exc` (zero after the record's end: `in_record` false)."""
        dt = exc.dt

        def linear(samples):
            x0, x1 = (exc.scale * samples[jnp.minimum(i, exc.n - 1)] for i in (k, k + 1))
            return jnp.where(in_record, x0, 0.0), jnp.where(in_record, (x1 - x0) / dt, 0.0)

        v = linear(exc.vertical) if exc.has_vertical else (None, None)
        return cls(dt * k.astype(dt.dtype), *linear(exc.acc), dt, *v)

    @property
    def has_vertical(self) -> bool:
        return self.v0 is not None

    def __call__(self, t):
        return self.a0 + (t - self.t0) * self.slope

    def vertical_acceleration(self, t):
        return self.v0 + (t - self.t0) * self.v_slope


def _interval(exc: SampledRecord, t):
    """The sample interval k with t_k ≤ t < t_k+1 (the record's last sample index from its end on)."""
    t = jnp.where(jnp.isfinite(t), t, 0.0)
    k = jnp.floor(t / exc.dt).astype(jnp.int32)
    k = jnp.where(exc.dt * (k + 1).astype(t.dtype) <= t, k + 1, k)
    k = jnp.where(exc.dt * k.astype(t.dtype) > t, k - 1, k)
    return jnp.clip(k, 0, exc.length - 1)


def _solution(model: RigidModel, c: _Carry, status: Status, summary_only: bool, save: Save | None) -> Solution:
    rec = c.rec
    if summary_only:
        # Free motion after the excitation: the next peak is the last one that matters.
        still = (c.mode == _ROCKING) & (status == Status.ok)
        rec = rec.saw_peak(still, model.free_rotation(c.theta, c.theta_dot, c.side))
    return model.watch().solution(rec, status, n_impacts=c.n_impacts, ts=None if summary_only else save.ts,
                                  history=c.hist, n_iterations=c.n_segments)


def _stage_loop(integ: EventIntegrator):
    """The integrator's solver with the loop over its stages that `autodiff` can differentiate:
    forward mode needs a plain loop (as diffrax's `ForwardMode` sets), reverse mode a checkpointed one."""
    solver = integ.solver
    if integ.autodiff == "forward" and hasattr(solver, "scan_kind"):
        return eqx.tree_at(lambda s: s.scan_kind, solver, "lax", is_leaf=lambda x: x is None)
    return solver
