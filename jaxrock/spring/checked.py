"""A spring-model integrator whose status states its global error: `Checked`.

A step-size controller holds a *local* error tolerance; the error of the summary (max |θ|/α′) is
global, and on a stiff spring it need not follow the tolerance. On the quasi-rigid column
E = 10¹⁴ Pa with θs = 10⁻⁶ α′ (2h = 10 m, tanα = 0.2, a_p = 4 g tanα, ω_p = 2π, 4 elements)
generalized-α at rtol 1e-5 ends 3.3e-3 off (0.6579 against 0.6612), at 1e-6 2.9e-3 off, at 1e-4
0.12 off, each step within its tolerance.

`Checked(integrator, accuracy, factor)` runs a *companion*: the same integrator at `factor` × its
tolerances (`simulate`: one loop, two states; a batch: each apart, `CheckedStepper.parts`). Its estimate of the run's error is

    ε = |max θ/α′ − max θ/α′ (companion)|   (overturned counts as 1, so a verdict that differs
                                             is an error of 1 − the other peak),

which, where the error scales with the tolerance (err(factor·tol) ≈ factor·err(tol)), is
(factor − 1) × the run's own error: a conservative estimate. The run keeps its own summary and
its status becomes `Status.inaccurate` where ε > `accuracy`, or where the companion failed (no
estimate). On the stiff scene above the flexible default, `Checked(GeneralizedAlpha(1e-5,
1e-5))`, estimates 0.12 and reports `inaccurate`. Cost: the companion's steps (fewer: looser,
and on a flexible column generalized-α's companion without the run's `crossing` limit); a batch runs the two apart (in
one loop, `vmap`'s lockstep would make every loop step cost both runs' steps, the finished
companion's too), the companion from the run's start (`CheckedStepper.shared_start`).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp

from .._validate import JaxrockInputError
from ..model import AbstractSpringIntegrator, AbstractStepper, Schedule
from ..results import Solution, Status
from .generalized_alpha import GeneralizedAlpha
from .system import FlexibleSystem


class Checked(AbstractSpringIntegrator):
    """A spring integrator whose runs check their own global error.

    The global error of `integrator` is estimated by a companion run at `factor` × its tolerances
    (module docstring, `jaxrock.spring.checked`): the status is `Status.ok` only where the estimate
    is ≤ `accuracy` (in max |θ|/α′), else `Status.inaccurate`. The flexible spring model's default
    is `Checked(GeneralizedAlpha(1e-5, 1e-5))`. Constructed from its fields, in this order.

    Attributes:
        integrator: a `GeneralizedAlpha` or a `SpringIntegrator` (not a `Checked`).
        accuracy: the stated global accuracy of max |θ|/α′ [-], in (0, 1); default 1e-2.
        factor: the companion's tolerance over the run's [-], in [2, 1000]; default 10 (looser:
            cheaper, and the estimate conservative where the error follows the tolerance). `factor`
            times the integrator's `rtol` and `atol` must stay below 1.

    Raises:
        JaxrockInputError: when `integrator` is not a spring integrator or is a `Checked`, or
            `accuracy` or `factor` is outside its range.

    Example:
        ```python
        import jaxrock
        block = jaxrock.Block.from_slenderness(50.0, 0.1)
        model = jaxrock.SpringModel(block, jaxrock.Column.concrete())
        integrator = jaxrock.Checked(jaxrock.GeneralizedAlpha(1e-6, 1e-6), accuracy=1e-3)
        sol = jaxrock.simulate(model, jaxrock.RickerPulse(2.0, 3.0), integrator=integrator)
        ```
    """

    integrator: AbstractSpringIntegrator
    accuracy: float = eqx.field(static=True, default=1e-2)
    factor: float = eqx.field(static=True, default=10.0)

    def __check_init__(self):
        if not isinstance(self.integrator, AbstractSpringIntegrator) or isinstance(self.integrator, Checked):
            raise JaxrockInputError(f"Checked needs a SpringIntegrator or GeneralizedAlpha, got {type(self.integrator).__name__}")
        if not (0 < self.accuracy < 1):
            raise JaxrockInputError(f"accuracy = {self.accuracy:g}: must be in (0, 1) (max |θ|/α′)")
        if not (2 <= self.factor <= 1000):
            raise JaxrockInputError(f"factor = {self.factor:g}: must be in [2, 1000]")
        if max(self.integrator.rtol, self.integrator.atol) * self.factor >= 1:
            raise JaxrockInputError(f"factor = {self.factor:g} × the tolerance ({self.integrator.rtol:g}, {self.integrator.atol:g}) "
                                    "must stay below 1: tighten the integrator or lower factor")

    @property
    def rtol(self) -> float:
        return self.integrator.rtol

    @property
    def atol(self) -> float:
        return self.integrator.atol

    @property
    def companion(self) -> AbstractSpringIntegrator:
        """The same integrator at `factor` × its tolerances."""
        return dataclasses.replace(self.integrator, rtol=self.integrator.rtol * self.factor, atol=self.integrator.atol * self.factor)

    def companion_for(self, system) -> AbstractSpringIntegrator:
        """The companion a run of `system` gets: `companion`; on a flexible column, generalized-α's
        without its `crossing` limit. The limit serves the run's forward derivatives
        (`jaxrock.spring.generalized_alpha`; the companion's value is never differentiated); on a
        flexible column the estimate is then cheaper and no less honest
        (`benchmarks/bench_checked.py`, 128 random flexible scenes against 1e-8, the 59 that rock
        without overturning: the companion costs 0.71 of the run's time against 0.83; it
        under-states the run's error in 6 scenes against 8, none beyond the accuracy; 5 needless
        flags against 4, no false `ok`). The one-DOF body keeps it: there the band's crossing is
        most of the error (10 m block, tanα 0.2, 6 pulse cells against 1e-9: at 1e-5 1.3e-2 off
        without the limit, 6.4e-4 with it; the command line's `--tol 1e-6` grid flagged a cell
        needlessly)."""
        companion = self.companion
        if isinstance(companion, GeneralizedAlpha) and isinstance(system, FlexibleSystem):
            companion = dataclasses.replace(companion, crossing=None)
        return companion

    def stepper(self, model, system, save=None, t1=None) -> "CheckedStepper":
        # generalized-α's start (`init`: the state at rest and the ladder of tangent inverses) reads
        # none of what the companion changes (tolerances, `crossing`): the two start alike
        return CheckedStepper(self.integrator.stepper(model, system, save, t1), self.companion_for(system).stepper(model, system, save, t1),
                              self.accuracy, isinstance(self.integrator, GeneralizedAlpha))


class CheckedStepper(AbstractStepper):
    """The run and its companion in one loop (`AbstractStepper`): a step advances each that is
    not done; the run is done when both are; `finish` is the run's `Solution` with its status
    judged by the estimate (`Checked`, `join`). A batch runs the two apart (`parts`) and joins
    their solutions (`bench_throughput.py --models spring`, 256 random 10-element scenes, 2 cores:
    3.39 ms/scene apart on 16 lanes each against 3.95 in one loop on 32)."""

    run: AbstractStepper
    companion: AbstractStepper
    accuracy: float = eqx.field(static=True)
    same_start: bool = eqx.field(static=True, default=False)  # `shared_start`

    @property
    def max_steps(self) -> int:
        return max(self.run.max_steps, self.companion.max_steps)

    @property
    def checkpointed(self) -> bool:
        return self.run.checkpointed and self.companion.checkpointed

    @property
    def shared_start(self) -> bool:
        """The run and the companion start alike (generalized-α: `Checked.stepper`), so that a
        batch prepares their start once (`AbstractStepper.shared_start`; 256 random 10-element
        scenes, 2 cores: the preparation was a fifth of a `Checked` batch's time, half of it the
        companion's)."""
        return self.same_start

    @property
    def schedule(self) -> Schedule:
        # the batch engine runs the run and the companion apart (`parts`), each in its own passes;
        # a shared start is kept while the run goes (twice the memory a scene holds)
        s = self.run.schedule
        per_scene = max(s.bytes_per_scene, self.companion.schedule.bytes_per_scene)
        return s._replace(bytes_per_scene=per_scene * (2 if self.same_start else 1))

    def init(self, excitation):
        return self.run.init(excitation), self.companion.init(excitation)

    def step(self, excitation, state):
        def advance(stepper, s):
            return jax.lax.cond(stepper.done(s), lambda x: x, lambda x: stepper.step(excitation, x), s)

        return advance(self.run, state[0]), advance(self.companion, state[1])

    def done(self, state):
        return self.run.done(state[0]) & self.companion.done(state[1])

    def motion(self, state):
        return self.run.motion(state[0])

    def finish(self, excitation, state) -> Solution:
        return self.join(excitation, (self.run.finish(excitation, state[0]), self.companion.finish(excitation, state[1])))

    @property
    def parts(self) -> tuple[AbstractStepper, AbstractStepper]:
        return self.run, self.companion

    def join(self, excitation, solutions) -> Solution:
        sol, ref = solutions
        estimate = jnp.abs(sol.max_theta - ref.max_theta)
        trusted = (ref.status == Status.ok) & (estimate <= self.accuracy)
        status = Status.where(sol.status == Status.ok, Status.where(trusted, Status.ok, Status.inaccurate), sol.status)
        return eqx.tree_at(lambda s: (s.status, s.n_iterations), sol, (status, sol.n_iterations + ref.n_iterations))
