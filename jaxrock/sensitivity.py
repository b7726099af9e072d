"""A run's sensitivity: how fast its motion forgets where it started (issue 55).

Rocking under a long record is chaotic in places: two runs that differ in the last bits of the
excitation's scale, or of the solver's steps, rock alike for a while and then diverge
exponentially, and the verdict (overturned or not) may be decided by rounding. The tangent of the
motion says so cheaply. `Sensitivity(stepper)` runs any stepper with the tangent of its state with
respect to the logarithm of the excitation's scale, s = ln(scale) (forward mode, `jax.jvp` of each
loop step: one pass, the tangent carried beside the state), and reports

    sensitivity = max over the run of |∂θ/∂ln(scale)| / α′,

sampled at the ends of the stepper's loop steps (a rigid segment or window of `chunk_steps` steps, a
generalized-α block). Its size says what a relative perturbation δ of the scale (or an error of the
same size anywhere in the run, which the motion amplifies alike) can do: the rotation moves by
about δ × sensitivity of α′. A short pulse gives O(1) values (the response is smooth in the scale);
a chaotic record run grows like exp(λt), λ the finite-time Lyapunov exponent, to 10⁸ and beyond in
40 s.

The verdict of a run is *uncertain* (`Solution.uncertain`, `verdict_uncertain`) where such a
perturbation, δ = `PERTURBATION` (1e-7) unless stated, can reach the margin to overturning:

    δ × sensitivity ≥ 1 − max|θ|/α′        (a run that stands),
    δ × sensitivity ≥ `MARGIN_OVERTURNED`   (a run that overturned: the perturbed run may stand).

`benchmarks/study_uncertain.py` holds the flag against brute force (each scene at 3 tolerances ×
5 scale factors, ×(1 ± 1e-9) and ×(1 ± 1e-7) among them; results/study_uncertain.txt), which chose
δ = 1e-7, the largest perturbation it makes: on 1,100 record runs the flag catches 35 of the 36
whose verdict changes and flags 9.5 % of the others; at δ = 1e-9 it catches 24 (every one that
flips at 1e-9: the tangent answers for the perturbation it is asked about).

The stepper must be forward-mode differentiable (`AbstractStepper.checkpointed` False, or a diffrax
integrator with `autodiff="forward"`); `simulate(..., sensitivity=True)` and `run_batch(...,
sensitivity=True)` take the model's forward-mode default where no integrator is given.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ._validate import JaxrockInputError
from .model import AbstractIntegrator, AbstractModel, AbstractStepper, Schedule
from .outputs import MARGIN_OVERTURNED, PERTURBATION  # declared with the output they define
from .results import Solution


def verdict_uncertain(sensitivity, max_theta, overturned, perturbation: float = PERTURBATION):
    """Whether a relative perturbation of the excitation's scale can flip the overturning verdict.

    The verdict is uncertain where `perturbation × sensitivity` reaches the margin to overturning
    (or an error of that size anywhere in the run, which the motion amplifies alike):
    1 − max|θ|/α′ for a run that stands, `MARGIN_OVERTURNED` (0.1) for one that overturned (the
    perturbed run may stand). δ = 1e-7 was chosen by `benchmarks/study_uncertain.py`: on 1,100
    record runs the flag catches 35 of the 36 whose verdict changes and flags 9.5 % of the others.

    Arguments:
        sensitivity (float | ArrayLike): max |∂θ/∂ln(scale)|/α′ of each run (`Solution.sensitivity`);
            NaN (not computed) gives False.
        max_theta (float | ArrayLike): max |θ|/α′ of each run (`Solution.max_theta`).
        overturned (bool | ArrayLike): whether each run overturned (`Solution.overturned`).
        perturbation: the relative perturbation δ of the scale; default `PERTURBATION` = 1e-7.

    Returns:
        (Array | numpy.ndarray): a boolean per run, the broadcast shape of the inputs (JAX arrays in,
            a JAX array out; else NumPy).

    Example:
        ```python
        sol = jaxrock.simulate(model, record, sensitivity=True)
        jaxrock.verdict_uncertain(sol.sensitivity, sol.max_theta, sol.overturned, perturbation=1e-9)
        ```
    """
    import numpy as np

    xp = jnp if any(isinstance(x, jax.Array) for x in (sensitivity, max_theta, overturned)) else np
    margin = xp.where(overturned, MARGIN_OVERTURNED, 1.0 - max_theta)
    return perturbation * sensitivity >= margin


def forward_integrator(model: AbstractModel, integrator: AbstractIntegrator | None) -> AbstractIntegrator:
    """The integrator of a run with its sensitivity: `integrator` where it differentiates in
    forward mode (its own `autodiff`, or the wrapped one's for `Checked`; generalized-α always
    does), the model's forward-mode default where None; a reverse-mode one is refused."""
    if integrator is None:
        return model.default_integrator(autodiff="forward")
    inner = getattr(integrator, "integrator", integrator)  # `Checked` wraps one
    if getattr(inner, "autodiff", "forward") != "forward":
        raise JaxrockInputError(f"sensitivity needs a forward-mode integrator: {type(inner).__name__}(autodiff='forward'), "
                                "or leave the integrator out (the model's forward-mode default)")
    return integrator


def _tangent(fn, *primals):
    """`fn(1, *primals)` and its tangent along the first argument (the scale factor, at 1) and the
    tangents `primals`' second halves: `primals` are (value, tangent) pairs."""
    one = jnp.ones(())
    values, tangents = zip(*primals) if primals else ((), ())
    return jax.jvp(fn, (one, *values), (one, *tangents))


class Sensitivity(AbstractStepper):
    """A stepper run with the tangent of its state along s = ln(scale) of the excitation (forward mode).

    Its `Solution` is the stepper's with `sensitivity` = max over the run of |∂θ/∂ln(scale)|/α′
    (sampled at the ends of the loop steps) and the `uncertain` flag it implies (`verdict_uncertain`).
    The state is (the stepper's state, its tangent, the largest |∂θ/∂ln scale|/α′ so far). A
    stepper with `parts` (`Checked`) follows its first part's tangent (the run; the companion only
    judges it). `simulate(..., sensitivity=True)` and `run_batch(..., sensitivity=True)` wrap their
    stepper in it.

    Attributes:
        stepper: the run to follow; it must be forward-mode differentiable (`checkpointed` False, or
            a diffrax integrator with `autodiff="forward"`) and expose its `motion`.

    Example:
        ```python
        stepper = model.stepper(model.default_integrator(autodiff="forward"))
        sol = jaxrock.Sensitivity(stepper).solve(pulse)
        ```
    """

    stepper: AbstractStepper

    @property
    def max_steps(self) -> int:
        return self.stepper.max_steps

    @property
    def checkpointed(self) -> bool:
        return False  # forward mode through the loop

    @property
    def schedule(self) -> Schedule:
        s = self.stepper.schedule
        return s._replace(bytes_per_scene=2 * s.bytes_per_scene)  # the tangent beside the state

    def _slope(self, state, tangent):
        """|∂θ/∂ln scale|/α′ at the state's time: the state's own tangent less the part that its
        time's carries (a loop step ending on an event, an impact, ends when the event does: at
        t + δt, where the rotation is off by θ̇ δt)."""
        _, _, omega = self.stepper.motion(state)
        dt, dtheta, _ = self.stepper.motion(tangent)
        return jnp.abs(dtheta - omega * dt)

    def init(self, excitation):
        state, tangent = _tangent(lambda k: self.stepper.init(excitation.scaled(k)))
        return state, tangent, self._slope(state, tangent)

    def step(self, excitation, state):
        state, tangent, most = state
        state, tangent = _tangent(lambda k, s: self.stepper.step(excitation.scaled(k), s), (state, tangent))
        return state, tangent, jnp.maximum(most, self._slope(state, tangent))

    def done(self, state):
        return self.stepper.done(state[0])

    def motion(self, state):
        return self.stepper.motion(state[0])

    def finish(self, excitation, state) -> Solution:
        return _judged(self.stepper.finish(excitation, state[0]), state[2])

    @property
    def parts(self) -> tuple[AbstractStepper, ...]:
        parts = self.stepper.parts
        return (Sensitivity(parts[0]), *parts[1:]) if parts else ()

    def join(self, excitation, solutions) -> Solution:
        return _judged(self.stepper.join(excitation, solutions), solutions[0].sensitivity)


def _judged(sol: Solution, sensitivity) -> Solution:
    """`sol` with its `sensitivity` and the `uncertain` flag it implies (δ = `PERTURBATION`)."""
    s = jnp.asarray(sensitivity).astype(sol.max_theta.dtype)
    flag = verdict_uncertain(s, sol.max_theta, sol.overturned)
    return eqx.tree_at(lambda x: (x.sensitivity, x.uncertain), sol, (s, flag))
