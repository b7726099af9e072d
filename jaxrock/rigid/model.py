"""The rigid rocking model (RM): Housner's equation with impacts, eqs. 1–3 and 22–27, as a value
(`RigidModel`), with its closed-form free-rocking peak and the levels its runs are watched against.
It runs by events (`jaxrock.rigid.event_integrator`)."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._validate import JaxrockInputError, Limit, check_limits
from ..bookkeeping import Watch
from ..excitation import AbstractExcitation
from ..geometry import G, Block
from ..model import AbstractIntegrator, AbstractModel
from ..results import Save
from .event_integrator import EventIntegrator, RigidStepper


class RigidModel(AbstractModel):
    """Housner's rigid rocking block (eq. 2), or a rigid column on an extended rigid base (eq. 22).

    Impacts by eq. 3; run by events (`EventIntegrator`, its default integrator). The block's
    parameters resolved here (η′) depend on its slenderness only: a model whose block is replaced
    by one of another size (`record_overturning_scale`) stays correct. The model kind "rigid".

    Arguments:
        block: the geometry; the rocking quantities α′, p′, η′ are taken from it.
        eta (float | Array | None): the angular-velocity ratio η across an impact (r = η², eq. 3) [–],
            in [0, 1]; 1: undamped; default None: the block's η′ (eq. 3, resolved here: the field is
            always an array).
        threshold (float | Array): overturned when |θ| ≥ threshold·α′ [–], in (0, 1]; default 1.

    Raises:
        JaxrockInputError: when `block` is not a `Block`, or a concrete `eta` or `threshold` is
            outside its range.

    Example:
        ```python
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        model = jaxrock.RigidModel(block)  # η = η′ = 1 − 1.5 sin²α = 0.942
        sol = jaxrock.simulate(model, jaxrock.RickerPulse(3.924, 3.604))
        ```
    """

    block: Block
    eta: Float[Array, ""]
    threshold: Float[Array, ""]

    def __init__(self, block: Block, eta=None, threshold=1.0):
        if not isinstance(block, Block):
            raise JaxrockInputError(f"block must be a jaxrock.Block, got {type(block).__name__}")
        self.block = block
        self.eta = block.eta_r if eta is None else jnp.asarray(eta, dtype=float)
        self.threshold = jnp.asarray(threshold, dtype=float)
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        return (Limit("eta (impact velocity ratio)", self.eta, 0.0, 1.0),
                Limit("threshold (overturning |theta|/alpha)", self.threshold, 0.0, 1.0, lo_open=True))

    @property
    def history_fields(self):
        """The fields a time history can hold: "theta" [rad] and "theta_dot" [rad/s]."""
        return ("theta", "theta_dot")

    def default_integrator(self, autodiff: str | None = None) -> EventIntegrator:
        """`EventIntegrator()` with its default settings.

        Arguments:
            autodiff: "reverse" or "forward"; default None: "reverse".
        """
        return EventIntegrator(autodiff=autodiff or "reverse")

    def acceleration(self, t, theta, side, excitation: AbstractExcitation):
        """θ̈ about the corner on `side`, eq. 2 / eq. 22 [rad/s²]; a vertical ground acceleration üv
        scales gravity: θ̈ = −p′²[(1 + üv/g) sin(α′ sgnθ − θ) + (üg/g) cos(α′ sgnθ − θ)].

        Arguments:
            t (float | Array): time [s].
            theta (float | Array): rotation θ [rad].
            side (float | Array): the rocking corner, ±1.
            excitation: the ground motion.
        """
        a, p = self.block.alpha_r, self.block.p_r
        phi = side * a - theta
        weight = jnp.sin(phi)
        if excitation.has_vertical:
            weight = (1 + excitation.vertical_acceleration(t) / G) * weight
        return -(p**2) * (weight + excitation(t) / G * jnp.cos(phi))

    def _free(self, theta, theta_dot, side):
        """(overturns, next peak |θ| [rad]) of free rocking from (θ, θ̇) on `side` (`jaxrock.rigid.event_integrator`)."""
        a, p, eta = self.block.alpha_r, self.block.p_r, self.eta
        energy = 0.5 * theta_dot**2 + p**2 * (jnp.cos(a - jnp.abs(theta)) - jnp.cos(a))
        energy = jnp.where(side * theta_dot < 0, eta**2 * energy, energy)
        c = jnp.cos(a) + energy / p**2
        over = c >= jnp.cos((1 - self.threshold) * a)
        # double where: the masked branch must not see c ≥ 1, where arccos′ = −∞ and its zero
        # cotangent would become 0·∞ = NaN under `grad`; cos α is a safe stand-in (peak 0)
        return over, a - jnp.arccos(jnp.where(over, jnp.cos(a), jnp.maximum(c, -1.0)))

    def free_peak(self, theta, theta_dot, side):
        """Closed-form next peak |θ|/α′ of free rocking from (θ, θ̇) on `side`: the threshold if it overturns.

        Energy is conserved between impacts and multiplied by η² at each (`jaxrock.rigid.event_integrator`).

        Arguments:
            theta (float | Array): rotation θ [rad].
            theta_dot (float | Array): angular velocity θ̇ [rad/s].
            side (float | Array): the rocking corner, ±1.

        Returns:
            (Array): the next peak |θ|/α′ [–].
        """
        over, peak = self._free(theta, theta_dot, side)
        return jnp.where(over, self.threshold, peak / self.block.alpha_r)

    def free_rotation(self, theta, theta_dot, side):
        """The same next peak as `free_peak`, as a rotation |θ| [rad] (threshold·α′ if it overturns).

        Arguments:
            theta (float | Array): rotation θ [rad].
            theta_dot (float | Array): angular velocity θ̇ [rad/s].
            side (float | Array): the rocking corner, ±1.

        Returns:
            (Array): the next peak |θ| [rad].
        """
        over, peak = self._free(theta, theta_dot, side)
        return jnp.where(over, self.threshold * self.block.alpha_r, peak)

    def watch(self, system=None) -> Watch:
        """The levels a run is watched against (`jaxrock.bookkeeping`).

        Overturning at threshold·α′; uplift as soon as |θ| > 0 (the block leaves rest when |üg| > g tanα′).

        Arguments:
            system (None): unused (the rigid model prepares nothing).
        """
        alpha = self.block.alpha_r
        return Watch(alpha=alpha, threshold=self.threshold, overturn=self.threshold * alpha, uplift=jnp.zeros_like(alpha))

    def stepper(self, integrator: AbstractIntegrator, save: Save | None = None, t1=None) -> "RigidStepper":
        """The run of a scene of this model (`AbstractModel.stepper`).

        Arguments:
            integrator: an `EventIntegrator`.
            save: the output request; default None: a summary.
            t1 (float | Array | None): end time [s] of a time history.

        Raises:
            JaxrockInputError: when `integrator` is not an `EventIntegrator`.
        """
        if not isinstance(integrator, EventIntegrator):
            raise JaxrockInputError(f"RigidModel needs an EventIntegrator, got {type(integrator).__name__}")
        return integrator.stepper(self, None, save, t1)  # the rigid model prepares nothing


def scenes_file_model(block: Block, eta=None) -> RigidModel:
    """A scenes file's rigid model (the block's η′ by default): the builder of the model kind
    "rigid" (`jaxrock.scene.MODEL_KINDS`)."""
    return RigidModel(block, eta=eta)
