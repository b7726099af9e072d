"""One call shape for every physics pipeline: `simulate(model, excitation, ...)`.

A model is a value (an `eqx.Module` whose array leaves can be vmapped and differentiated) that
knows its geometry (`block`), its overturning threshold and its default integrator. The
integrator settings are a separate value; the output request is a `Save` (or nothing: summary only).

Every entry point drives a model the same way: the model pairs itself with an integrator into an
`AbstractStepper` (init, step, done, finish; its `Schedule` says how batches advance it), and
`simulate`, the spectra (`jaxrock.analyses.engine.run_batch`) and the scenes files (`jaxrock.io.scenes_file`) only
call those methods. A model kind that scenes files name is registered with `register_model_kind`
(`jaxrock.scene`).
"""

from __future__ import annotations

import abc
import inspect
from typing import NamedTuple

import diffrax
import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, PyTree

from ._validate import JaxrockInputError, Limit, check_one_scene, check_range, is_concrete, within_limits
from .excitation import AbstractExcitation
from .geometry import Block
from .results import OUTPUTS, Save, Solution, Status
from .scene import model_params


AUTODIFF_MODES = ("reverse", "forward")


class AbstractIntegrator(eqx.Module):
    """Numerical settings of a model's time integration (tolerances, bounds): the base of every integrator.

    The one thing an integrator does is turn a run of a model into an `AbstractStepper` (`stepper`),
    whose `Schedule` states how batches advance it and what memory a scene holds. A model calls it
    from its own `AbstractModel.stepper`, after refusing integrators it cannot run and preparing
    what it computes once (its `system`). Built-in: `EventIntegrator` (rigid), `SpringIntegrator`,
    `GeneralizedAlpha` and `Checked` (spring).
    """

    @abc.abstractmethod
    def stepper(self, model: "AbstractModel", system, save: Save | None = None, t1=None) -> "AbstractStepper":
        """The run of `model` with these settings, as an `AbstractStepper`.

        Arguments:
            model: the model of the scene.
            system (object): what the model prepared once (model-specific; None where it prepares nothing).
            save: the output request; None: a summary that stops when the answer is fixed.
            t1 (float | Array | None): end time [s] of a history run (`simulate` defaults it to the last save time).

        Returns:
            the stepper of one scene.
        """


class AbstractSpringIntegrator(AbstractIntegrator):
    """An integrator of the spring model (`jaxrock.spring`): `SpringIntegrator` (diffrax) or `GeneralizedAlpha`.

    Its `stepper` is given

    - `model`: the `SpringModel` — `run_end(system, excitation, save, t1)` (when the run stops at
      the latest) and `watch(system)` (`jaxrock.bookkeeping.Watch`: the levels a run is watched
      against — overturning, uplift — and its `Solution` from the run's `Record`);
    - `system`: the model's assembled `SpringSystem` (`SpringModel.system()`), built once per
      model: mass matrix, forces (`forces`, `forces_without_spring`), tangents at rest, the
      backbone's exact scalar solve, tolerance scales, the initial state, energies, history fields
      and the summary's stop (`settled`);
    - `save`, `t1`: the output request (None: a summary that stops when the answer is fixed).
    """


class Schedule(NamedTuple):
    """How a batch of scenes is advanced (`jaxrock.analyses.engine.run_batch`).

    A stepper states it in `AbstractStepper.schedule`; the default, `Schedule()`, runs each batch as
    one vmapped `solve`.

    Attributes:
        passes: loop steps per pass, in order (the last repeats): between passes the scenes still
            running are gathered into a smaller batch, so that finished ones stop costing. Default
            (): the batch runs as one vmapped `AbstractStepper.solve` (a stepper whose loop is its
            integrator's).
        smallest_batch: the batch size below which gathering stops paying (a cheap step's batch
            overhead is large); default 64.
        bytes_per_scene: memory [bytes] a running scene holds beyond its inputs (sizes the batches); default 0.
        lanes: default 0: every running cell in every pass; else at most this many cells per pass,
            those already started first, so that a finished cell's place goes to the next one (for
            dear steps whose cells differ widely in length: a batch does not wait for its slowest
            cell); a spectrum's batches then hold at least 4 × `lanes` cells (`batch_unit`).

    Example:
        ```python
        jaxrock.Schedule(passes=(4, 8, 16, 32), smallest_batch=64)  # the rigid model's
        ```
    """

    passes: tuple[int, ...] = ()
    smallest_batch: int = 64
    bytes_per_scene: int = 0
    lanes: int = 0

    @property
    def batch_unit(self) -> int:
        """The least batch a spectrum splits its grid into (`jaxrock.analyses.engine.even_batches`)."""
        return max(self.smallest_batch, 4 * self.lanes)


class AbstractStepper(eqx.Module):
    """One scene's run as a loop, the protocol every model and integrator is driven through.

    A stepper is a value made by `AbstractModel.stepper(integrator, save, t1)`: whatever can be
    computed once per model (mass matrices, tangents, preloads) is computed there and carried as
    data, so that a batch builds it once and vmaps it like the model. The state is a pytree of
    arrays of fixed structure. Every method is pure and traceable (`vmap`, `jit`):

    - `init(excitation)` → the state at the excitation's start;
    - `step(excitation, state)` → the state after one loop step (a segment, a chunk of steps, an
      attempted step: the model's unit of work);
    - `done(state)` → whether the answer is fixed *or* the run can go no further (its bound of
      `max_steps` steps included), so that `while not done: step` always ends;
    - `finish(excitation, state)` → the `Solution` (a run cut off by its bound reports it in
      `status`).

    `simulate` is `solve` (init, step until done, finish); the spectra and batches advance many
    scenes `n` steps at a time with `advance` (`schedule`). A stepper whose integrator has a loop of
    its own (a whole `diffrax.diffeqsolve`) runs in `init` and declares `max_steps = 0`.
    `checkpointed`: the loop of `solve` is reverse-mode differentiable (equinox's checkpointed
    while loop; else a `lax.while_loop`: forward mode only).
    """

    @property
    @abc.abstractmethod
    def max_steps(self) -> int:
        """Bound on loop steps (static); 0: the whole run is done in `init`."""

    @property
    @abc.abstractmethod
    def checkpointed(self) -> bool:
        """Whether `solve`'s loop is reverse-mode differentiable (static)."""

    @abc.abstractmethod
    def init(self, excitation: AbstractExcitation) -> PyTree:
        """The state at the excitation's start.

        Arguments:
            excitation: the ground motion of the scene.
        """

    @abc.abstractmethod
    def step(self, excitation: AbstractExcitation, state: PyTree) -> PyTree:
        """One loop step; called only on a state that is not done.

        Under `vmap`, a done lane's result is discarded by the loop.

        Arguments:
            excitation: the ground motion of the scene.
            state: the state before the step.

        Returns:
            the state after the step.
        """

    @abc.abstractmethod
    def done(self, state: PyTree) -> Bool[Array, ""]:
        """Whether the answer is fixed, or no further step is allowed.

        Arguments:
            state: the current state.
        """

    @abc.abstractmethod
    def finish(self, excitation: AbstractExcitation, state: PyTree) -> Solution:
        """The run's `Solution` from its last state.

        Arguments:
            excitation: the ground motion of the scene.
            state: the last state.
        """

    @property
    def schedule(self) -> Schedule:
        """How a batch of these scenes is advanced (default: one vmapped `solve` per batch)."""
        return Schedule()

    @property
    def parts(self) -> tuple["AbstractStepper", ...]:
        """Independent runs this stepper's loop advances together, whose `Solution`s `join` makes
        its own (`jaxrock.spring.CheckedStepper`: the run and its companion); () for one run. The
        batch engine runs each part apart, in its own passes: under `vmap` a loop step of the whole
        costs every part's step, the finished ones' too."""
        return ()

    def motion(self, state: PyTree) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
        """The time and base rotation of a state; a run's sensitivity follows their tangents (`jaxrock.sensitivity`).

        Arguments:
            state: a state of this stepper.

        Returns:
            t (Array): the time [s].
            theta (Array): θ/α′ [–].
            theta_dot (Array): θ̇/α′ [1/s].

        Raises:
            NotImplementedError: where the stepper does not expose its motion (the default).
        """
        raise NotImplementedError(f"{type(self).__name__} does not expose its motion (AbstractStepper.motion)")

    @property
    def shared_start(self) -> bool:
        """Whether every one of the `parts` starts from the same state (`init`, bit for bit): the
        batch engine then computes it once (a flexible generalized-α start holds its ladder of
        tangent inverses, the dearest of its preparation)."""
        return False

    def join(self, excitation: AbstractExcitation, solutions: tuple[Solution, ...]) -> Solution:
        """The `Solution` of the whole from its `parts`' (only where there are parts).

        Arguments:
            excitation: the ground motion of the scene.
            solutions: the parts' solutions, in the order of `parts`.

        Raises:
            NotImplementedError: where the stepper has no parts (the default).
        """
        raise NotImplementedError(f"{type(self).__name__} has no parts to join")

    def advance(self, excitation: AbstractExcitation, state: PyTree, n) -> PyTree:
        """At most `n` more steps (a forward-mode loop), stopping early when done.

        Arguments:
            excitation: the ground motion of the scene.
            state: the state to go on from.
            n (int | Array): the most steps to take (may be traced).

        Returns:
            the state after them.
        """
        state, _ = jax.lax.while_loop(lambda sk: ~self.done(sk[0]) & (sk[1] < n),
                                      lambda sk: (self.step(excitation, sk[0]), sk[1] + 1), (state, 0))
        return state

    def solve(self, excitation: AbstractExcitation) -> Solution:
        """The whole run: `init`, `step` until `done`, `finish`.

        Arguments:
            excitation: the ground motion of the scene.
        """
        state = self.init(excitation)
        if self.max_steps > 0:
            body = lambda s: self.step(excitation, s)
            cond = lambda s: ~self.done(s)
            if self.checkpointed:
                state = eqxi.while_loop(cond, body, state, max_steps=self.max_steps, kind="checkpointed")
            else:
                state = jax.lax.while_loop(cond, body, state)
        return self.finish(excitation, state)


def check_autodiff(autodiff: str):
    if autodiff not in AUTODIFF_MODES:
        raise JaxrockInputError(f"autodiff = {autodiff!r}; valid: {AUTODIFF_MODES}")


def diffrax_status(result) -> Status:
    """A diffrax solve's `RESULTS` as a `Status` (an event that ended the solve is success)."""
    ok = (result == diffrax.RESULTS.successful) | (result == diffrax.RESULTS.event_occurred)
    steps = result == diffrax.RESULTS.max_steps_reached
    return Status.where(ok, Status.ok, Status.where(steps, Status.max_steps, Status.solver_failed))


def diffrax_adjoint(autodiff: str, checkpoints: int | None = None) -> diffrax.AbstractAdjoint:
    """diffrax's adjoint for an integrator's `autodiff` mode: `"reverse"` (`jax.grad`, `jax.vjp`,
    `jax.jacrev`; recursive checkpointing, `checkpoints` as diffrax's) or `"forward"` (`jax.jvp`,
    `jax.jacfwd`; plain loops, no stored trajectory). JAX cannot run forward mode through a
    reverse-mode loop (a `custom_vjp`), nor the reverse, so the mode is chosen with the integrator."""
    return diffrax.ForwardMode() if autodiff == "forward" else diffrax.RecursiveCheckpointAdjoint(checkpoints)


class WrappedController(diffrax.AbstractAdaptiveStepSizeController):
    """An adaptive step-size controller around another (`controller`), whose tolerances and norm
    are the wrapped one's: `FirstStepController`, `jaxrock.spring.diffrax_integrator.KinkGuard`."""

    controller: eqx.AbstractVar[diffrax.AbstractAdaptiveStepSizeController]

    @property
    def rtol(self):
        return self.controller.rtol

    @property
    def atol(self):
        return self.controller.atol

    @property
    def norm(self):  # pyright: ignore[reportIncompatibleMethodOverride]
        return self.controller.norm


class FirstStepController(WrappedController):
    """An adaptive step-size controller that carries the solve's first step: pass it to
    `diffrax.diffeqsolve` with `dt0=None`.

    Given as `dt0`, a traced first step makes diffrax compile its sign check `(t1 - t0)·dt0 ≥ 0`
    (an `equinox.error_if`) into a host callback in the middle of the loop, and JAX keeps no kernel
    with a host callback in its persistent compilation cache (`jaxrock.cache`). jaxrock's solves
    run forward by construction (t1 ≥ t0, dt0 > 0), so the check never fired; this controller
    hands the same first step to the wrapped controller's `init` (the same numbers, bit for bit)
    and leaves the check out.

    Its state carries the end of the step the wrapped controller proposes next (`next_time`): a
    solve cut off after some steps (`max_steps`) goes on where it stopped when the next solve starts
    from its last state with `t_next` that end (`SaveAt(controller_state=True)`); exactly that
    time, not t0 + (t_next − t0), which can round an ulp below a step the controller clipped to a
    sample of a record (and the next step would then be an ulp long)."""

    controller: diffrax.AbstractAdaptiveStepSizeController
    dt0: Float[Array, ""]
    t_next: Float[Array, ""] | None = None  # the first step's end for a solve that goes on (+inf: start afresh from dt0)

    def wrap(self, direction):
        return FirstStepController(self.controller.wrap(direction), self.dt0 * direction, self.t_next)

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        del dt0  # None: diffeqsolve was given no first step
        tnext, state = self.controller.init(terms, t0, t1, y0, self.dt0, args, func, error_order)
        if self.t_next is not None:
            tnext = jnp.where(jnp.isfinite(self.t_next), self.t_next, tnext)
        return tnext, (state, tnext)

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state):
        keep, next_t0, next_t1, jump, state, result = self.controller.adapt_step_size(
            t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state[0])
        return keep, next_t0, next_t1, jump, (state, next_t1), result

    @staticmethod
    def next_time(controller_state):
        """The end of the step proposed after a solve's last step, from its saved controller state."""
        return controller_state[1]


class AbstractModel(eqx.Module):
    """A rocking body model: rigid (`RigidModel`) or spring (`SpringModel`); the base of every model.

    A model is a value (an `eqx.Module` whose array leaves can be vmapped and differentiated) that
    knows its geometry (`block`), its overturning threshold (overturned at |θ| ≥ threshold·α′) and
    its default integrator, and pairs itself with an integrator into an `AbstractStepper`. A model
    kind that scenes files name is registered with `register_model_kind`.
    """

    block: eqx.AbstractVar[Block]
    threshold: eqx.AbstractVar[Float[Array, ""]]  # overturned at |θ| ≥ threshold·α′

    @abc.abstractmethod
    def default_integrator(self, autodiff: str | None = None) -> AbstractIntegrator:
        """The integrator used when `simulate` is given none (under `jax.grad`: its reverse-mode form).

        Arguments:
            autodiff: "forward" or "reverse": the same settings differentiated in that mode (forward:
                `jax.jvp`, `jax.jacfwd`, one pass per input, the cheaper choice for one or a few
                parameters, e.g. `find_boundary`); default None: the model's own choice.

        Returns:
            the integrator.
        """

    @abc.abstractmethod
    def stepper(self, integrator: AbstractIntegrator, save: Save | None = None, t1=None) -> AbstractStepper:
        """The run of a scene of this model with `integrator` as an `AbstractStepper`.

        Arguments:
            integrator: the integration settings.
            save: the output request; default None: a summary, stopping when the answer is fixed.
            t1 (float | Array | None): end time [s] of a time history at `save.ts` (see `simulate`).

        Returns:
            the stepper of one scene.

        Raises:
            JaxrockInputError: when the model cannot run `integrator`.
        """

    @property
    @abc.abstractmethod
    def history_fields(self) -> tuple[str, ...]:
        """Names this model can save in a time history."""

    def limits(self) -> tuple[Limit, ...]:
        """Valid ranges of the model's parameters beyond its block's (`jaxrock._validate.Limit`)."""
        return ()


def scene_limits(model: AbstractModel, excitation: AbstractExcitation) -> tuple[Limit, ...]:
    """Every parameter limit of a scene: the block's, the model's and the excitation's."""
    return model.block.limits() + model.limits() + excitation.limits()


def simulate(
    model: AbstractModel,
    excitation: AbstractExcitation,
    *,
    integrator: AbstractIntegrator | None = None,
    save: Save | None = None,
    t1=None,
    sensitivity: bool = False,
) -> Solution:
    """Simulate one scene. A pure function: `jax.vmap` and `jax.grad` accept it.

    - Without `save`, only the summary is computed and the run stops as soon as the answer is
      fixed (overturned; at rest after the excitation ended; or excitation over, so that the
      remaining free-rocking peaks can only decay).
    - With `save=Save(ts, fields)`, the requested time history is returned and the run goes on to
      `t1` (default: the last save time).
    - A parameter outside its limits (`limits()` of the block, model and excitation) is refused
      at construction; under `jax.vmap`/`jax.jit`, where it cannot be, the run returns
      `Status.invalid_input` with NaN numbers.

    The run is compiled once per structure (model kind, mesh, save request): repeated calls with
    new numbers reuse it.

    Arguments:
        model: the model of the scene (`RigidModel`, a spring model), one scene's values.
        excitation: the ground motion (a pulse, a `Record`, `StillGround`).
        integrator: the integration settings; default None: `model.default_integrator()` (under
            `jax.grad`, its reverse-mode form).
        save: a time history request `Save(ts, fields)`; default None: the summary only.
        t1 (float | Array | None): end time [s] of a history, > the excitation's `t_start`; only with
            `save`; default None: the last save time.
        sensitivity: carry the tangent of the motion along the excitation's log-scale and report
            `Solution.sensitivity` and `Solution.uncertain` (`jaxrock.sensitivity`; forward mode:
            without `integrator`, the model's forward-mode default); default False.

    Returns:
        the summary (and history) of the run; check `status`.

    Raises:
        JaxrockInputError: when `model` or `excitation` is not a jaxrock one; a parameter holds many
            values (one scene: vmap `simulate` or use `run_batch`); `t1` is given without `save` or is
            not after the excitation's start; a save field is not one the model gives; a save time is
            beyond `t1`; the integrator cannot be differentiated in the mode asked (`jax.grad` through a
            forward-mode loop, `jax.jvp` through a reverse-mode one, or `sensitivity` with a
            reverse-mode integrator).

    Example:
        ```python
        import jaxrock

        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        pulse = jaxrock.RickerPulse(*jaxrock.pulse_of_ratios(block, 2.0, 3.0))
        sol = jaxrock.simulate(jaxrock.RigidModel(block), pulse)
        float(sol.max_theta)  # 0.446...
        ```
    """
    if sensitivity:
        from .sensitivity import forward_integrator

        integrator = forward_integrator(model, integrator)
    args = scene_arguments(model, excitation, integrator=integrator, save=save, t1=t1)
    if sensitivity:
        return run_scene(*args, sensitivity=True)
    if _in_reverse_mode() and not _checkpointed(*args):  # JAX would fail later, in its backward pass, in its own words
        raise JaxrockInputError(_autodiff_advice("Reverse-mode differentiation does not work for lax.while_loop", model, args[2]))
    try:
        return run_scene(*args)
    except (TypeError, ValueError) as e:  # JAX's words for a derivative the integrator's loops cannot take
        advice = _autodiff_advice(str(e), args[0], args[2])
        if advice is None:
            raise
        raise JaxrockInputError(advice) from None


def _in_reverse_mode() -> bool:
    """Whether this call is being traced for reverse mode (`jax.grad`, `jax.vjp`, `jax.jacrev`):
    one of the traces around it linearizes. JAX has no public query for it: read from its trace
    stack where it is there (jax >= 0.4.36), else unknown (False)."""
    try:
        from jax._src import core
        from jax._src.interpreters import ad

        trace = core.trace_ctx.trace
        while trace is not None:
            if isinstance(trace, ad.LinearizeTrace):
                return True
            trace = getattr(trace, "parent_trace", None)
    except (ImportError, AttributeError):
        pass
    return False


def _checkpointed(model, excitation, integrator, save, t1) -> bool:
    """Whether the run's loop is reverse-mode differentiable (`AbstractStepper.checkpointed`),
    found by tracing its stepper abstractly."""
    found = {}

    def build():
        found["checkpointed"] = model.stepper(integrator, save, t1).checkpointed
        return jnp.zeros(())

    jax.eval_shape(build)
    return found["checkpointed"]


def _autodiff_advice(error: str, model, integrator) -> str | None:
    """What to change where JAX refuses to differentiate a run: forward mode (`jax.jvp`,
    `jax.jacfwd`) through a reverse-mode integrator, or reverse mode (`jax.grad`, `jax.vjp`,
    `jax.jacrev`) through a loop that only forward mode can enter (generalized-α)."""
    name = type(integrator).__name__
    if "forward-mode autodiff (jvp) to a custom_vjp" in error:
        return (f"jax.jvp/jax.jacfwd cannot differentiate {name} in reverse mode (autodiff='reverse'); pass "
                f"integrator=model.default_integrator(autodiff='forward') (the same settings, forward mode), or use jax.grad")
    if "Reverse-mode differentiation does not work for lax.while_loop" in error:
        return (f"jax.grad/jax.vjp/jax.jacrev cannot differentiate {name} with autodiff='forward'; pass "
                f"integrator=model.default_integrator(autodiff='reverse') (the same settings, reverse mode), or leave the "
                f"integrator out, or use jax.jacfwd or jax.jvp (one pass per parameter)")
    return None


def scene_arguments(model: AbstractModel, excitation: AbstractExcitation, *, integrator: AbstractIntegrator | None = None,
                    save: Save | None = None, t1=None) -> tuple:
    """`simulate`'s checks and defaults: the arguments (model, excitation, integrator, save, t1) of
    its compiled run, `run_scene`."""
    if not isinstance(model, AbstractModel):
        raise JaxrockInputError(f"model must be a jaxrock model (RigidModel, SpringModel), got {type(model).__name__}")
    if not isinstance(excitation, AbstractExcitation):
        raise JaxrockInputError(
            f"excitation must be a jaxrock excitation (a pulse, a Record: jaxrock.AbstractExcitation), got {type(excitation).__name__}"
        )
    check_one_scene(scene_limits(model, excitation))
    if save is None and t1 is not None:
        raise JaxrockInputError("t1 (end time) applies to a time history (save=Save(ts, fields)); a summary runs until "
                                "its answer is fixed (overturned, at rest, or only decaying peaks left): leave t1 out")
    if save is not None:
        unknown = set(save.fields) - set(model.history_fields)
        if unknown:
            raise JaxrockInputError(
                f"Save fields {sorted(unknown)} are not available for {type(model).__name__}; valid: {model.history_fields}"
            )
        if t1 is None:
            t1 = save.ts[-1]
        if is_concrete((save.ts, t1, excitation)) and float(jnp.max(save.ts)) > float(t1) + 1e-12:
            raise JaxrockInputError(f"save times reach {float(jnp.max(save.ts)):g} s, beyond t1 = {float(t1):g} s")
    if t1 is not None and is_concrete((t1, excitation)):
        check_range("t1 (end time) [s]", t1, float(excitation.t_start), float("inf"), lo_open=True, hi_open=True)
    if integrator is None:
        integrator = model.default_integrator()
        # under jax.grad a forward-mode default (the flexible column's) gives way to its reverse-mode
        # form, the same settings and values, where the model offers one (`autodiff`)
        if (_in_reverse_mode() and "autodiff" in inspect.signature(model.default_integrator).parameters
                and not _checkpointed(model, excitation, integrator, save, t1)):
            integrator = model.default_integrator(autodiff="reverse")
    return model, excitation, integrator, save, t1


@eqx.filter_jit
def run_scene(model, excitation, integrator, save, t1, sensitivity: bool = False) -> Solution:
    """One scene's run on checked arguments (`scene_arguments`), with its sensitivity where asked
    (`jaxrock.sensitivity`). Compiled once per structure (model kind, mesh, save request): repeated
    calls with new numbers reuse it. Composes with an outer jit, vmap and grad."""
    model, excitation, ok = guard_scene(model, excitation)
    stepper = model.stepper(integrator, save, t1)
    if sensitivity:
        from .sensitivity import Sensitivity

        stepper = Sensitivity(stepper)
    return flag_invalid(stepper.solve(excitation), ok)


def guard_scene(model: AbstractModel, excitation: AbstractExcitation):
    """(model, excitation, ok): `ok` whether every parameter is within its limits; where not, the
    quiet scene's values in their place (`flag_invalid` then marks the result)."""
    ok = within_limits(scene_limits(model, excitation))
    return _neutral(model, ok), _neutral(excitation, ok), ok


# A valid, quiet scene (2h = 10 m, tanα = 0.2 at rest under 1 m/s², below its uplift at 1.96 m/s²):
# the values an invalid lane runs instead of its own, by leaf name, so that NaN or negative sizes
# never reach a loop (they ran it to its iteration bound). The model parameters' come from their
# declarations (`jaxrock.scene.Param.neutral`, a registered kind's too); these are the rest.
_NEUTRAL = {"h": 5.0, "b": 1.0, "b_base": 1.0, "threshold": 1.0, "smoothing": 1e-4, "A": 2.0, "I": 2.0 / 3.0, "a_p": 1.0,
            "omega_p": 6.0, "acc": 0.0, "dt": 0.01, "scale": 0.0}


def neutral_values() -> dict[str, float]:
    """The quiet scene's value of each leaf name (`_NEUTRAL` and the registered model parameters')."""
    params = {p.name: p.default if p.neutral is None else p.neutral for p in model_params().values()}
    return {**{k: v for k, v in params.items() if v is not None}, **_NEUTRAL}


def _neutral(tree, ok):
    """`tree` where `ok`, else its leaves replaced by the quiet scene's (`neutral_values`)."""
    values = neutral_values()

    def swap(path, leaf):
        name = getattr(path[-1], "name", None) if path else None
        if name not in values or not eqx.is_inexact_array(leaf):
            return leaf
        return jnp.where(ok, leaf, jnp.asarray(values[name], dtype=leaf.dtype))

    return jax.tree_util.tree_map_with_path(swap, tree)


def flag_invalid(sol: Solution, ok) -> Solution:
    """`Status.invalid_input` and NaN numbers where `ok` is false (a parameter outside its
    limits; each summary output's `Output.invalid`). Concrete input is refused at construction;
    under `jax.vmap`/`jax.jit` constructors see tracers and cannot, so the run flags it instead
    (failure as a value)."""
    return eqx.tree_at(
        lambda s: (*(getattr(s, name) for name in OUTPUTS), s.status),
        sol,
        (*(o.invalid(getattr(sol, name), ok) for name, o in OUTPUTS.items()), Status.where(ok, sol.status, Status.invalid_input)),
    )
