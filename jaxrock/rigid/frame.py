"""The rocking frame (Makris & Vassiliou 2013, EESD 42:431–449, doi:10.1002/eqe.2222): N identical
free-standing rigid columns capped by a freely supported rigid beam, the beam translating on the
columns' top corners, as a value (`RockingFrame`) run by the rigid model's event integrator.

With γ = m_b/(N m) (the beam's mass over all the columns') and each column a block of α, R,
p² = 3g/(4R) (I₀ = 4/3 m R²), the beam rides on the top corner diagonal to each column's pivot:
its velocity is 2R θ̇ and its height 2R cos(α − |θ|) + const, wherever its centre of mass is.
Lagrange's equation of the one-DOF system (the paper's "Equation of motion of the rocking frame"):

    θ̈ = −p̂² [(1 + üv/g) sin(α sgnθ − θ) + (üg/g) cos(α sgnθ − θ)],  p̂² = p² (1 + 2γ)/(1 + 3γ),

the equation of a solitary block of the same α and the larger size R̂ = R (1 + 3γ)/(1 + 2γ): the
heavier the beam, the smaller p̂, the more stable the frame. Uplift at |üg| > (g + üv) tanα, the
column's own level, whatever γ ("Minimum acceleration needed to initiate uplift"). At an impact
the pivots move to the other corners and the beam to the other top corners; angular momentum
about each new pivot, the beam's share of the impulse acting at the new top corner, gives
("Maximum coefficient of restitution")

    η = θ̇₂/θ̇₁ = [1 − (3/2) sin²α + 3γ cos 2α] / (1 + 3γ),

Housner's η at γ = 0. So the frame runs as the equivalent block (`RockingFrame.equivalent`) with
this η: the same stepper, the same cost per scene as a solitary block. The paper's equation
numbers could not be looked up here; the derivation above is checked in tests/test_frame.py
against a Lagrangian written from the masses and a momentum balance written from the geometry.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._validate import JaxrockInputError, Limit, check_limits
from ..bookkeeping import Watch
from ..geometry import Block
from ..model import AbstractIntegrator, AbstractModel
from ..results import Save
from .event_integrator import EventIntegrator, RigidStepper
from .model import RigidModel


def frame_size_factor(mass_ratio):
    """R̂/R = (1 + 3γ)/(1 + 2γ): the equivalent block's size over the column's (p̂² = p² (1 + 2γ)/(1 + 3γ)).

    Arguments:
        mass_ratio (float | Array): γ = m_b/(N m) [–], ≥ 0.
    """
    return (1 + 3 * mass_ratio) / (1 + 2 * mass_ratio)


def frame_eta(alpha, mass_ratio):
    """The frame's impact velocity ratio η = [1 − (3/2) sin²α + 3γ cos 2α] / (1 + 3γ) (module docstring).

    Arguments:
        alpha (float | Array): the columns' slenderness angle α [rad].
        mass_ratio (float | Array): γ = m_b/(N m) [–], ≥ 0.
    """
    return (1 - 1.5 * jnp.sin(alpha) ** 2 + 3 * mass_ratio * jnp.cos(2 * alpha)) / (1 + 3 * mass_ratio)


class RockingFrame(AbstractModel):
    """A rocking frame: N identical rigid columns (`block`) capped by a freely supported rigid beam.

    Makris & Vassiliou (2013): it rocks as a solitary block of the same slenderness and the larger
    size R (1 + 3γ)/(1 + 2γ), with its own η (`jaxrock.rigid.frame`). Run by the rigid model's
    `EventIntegrator`; spectra are normalised by the columns' α and p, as the paper's. The model
    kind "frame" (`--model frame --mass-ratio γ`).

    Arguments:
        block: one column (a plain block: no extended base).
        mass_ratio (float | Array): γ = m_b/(N m), the cap beam's mass over all the columns' [–],
            ≥ 0; 0: no beam (the solitary column); the model kind's default is 1. The number of columns enters only through γ
            (`from_beam`).
        eta (float | Array | None): the angular-velocity ratio across an impact [–], in [0, 1];
            default None: the frame's (`frame_eta`).
        threshold (float | Array): overturned when |θ| ≥ threshold·α [–], in (0, 1]; default 1.

    Raises:
        JaxrockInputError: when `block` is not a `Block`, or a concrete parameter is outside its range
            (a block on an extended base included).

    Example:
        ```python
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        frame = jaxrock.RockingFrame(block, mass_ratio=1.0)  # the beam weighs as much as the columns
        float(frame.equivalent.block.p / block.p)  # sqrt(3/4) = 0.866
        ```
    """

    block: Block
    mass_ratio: Float[Array, ""]
    eta: Float[Array, ""]
    threshold: Float[Array, ""]

    def __init__(self, block: Block, mass_ratio, eta=None, threshold=1.0):
        if not isinstance(block, Block):
            raise JaxrockInputError(f"block must be a jaxrock.Block, got {type(block).__name__}")
        self.block = block
        self.mass_ratio = jnp.asarray(mass_ratio, dtype=float)
        self.eta = frame_eta(block.alpha, self.mass_ratio) if eta is None else jnp.asarray(eta, dtype=float)
        self.threshold = jnp.asarray(threshold, dtype=float)
        check_limits(self.limits())

    @classmethod
    def from_beam(cls, block: Block, beam_over_column, n_columns: int, **kw: float) -> "RockingFrame":
        """A frame of `n_columns` columns whose beam weighs `beam_over_column` × one column: γ = ratio/N.

        Arguments:
            block: one column.
            beam_over_column (float | Array): m_b/m [–], ≥ 0.
            n_columns: N, ≥ 1.
            **kw (float | Array): `eta`, `threshold`.
        """
        if int(n_columns) < 1:
            raise JaxrockInputError(f"n_columns = {n_columns}; valid: ≥ 1")
        return cls(block, jnp.asarray(beam_over_column, dtype=float) / int(n_columns), **kw)

    def limits(self) -> tuple[Limit, ...]:
        return (Limit("mass_ratio (cap beam over all columns' mass)", self.mass_ratio, 0.0, float("inf"), hi_open=True),
                Limit("eta (impact velocity ratio)", self.eta, 0.0, 1.0),
                Limit("threshold (overturning |theta|/alpha)", self.threshold, 0.0, 1.0, lo_open=True),
                Limit("b_base/b (a frame's columns stand on no extended base)", self.block.b_base / self.block.b, 1 - 1e-12, 1 + 1e-12))

    @property
    def equivalent(self) -> RigidModel:
        """The solitary block the frame rocks as: the same α, the size R (1 + 3γ)/(1 + 2γ), the frame's η."""
        k = frame_size_factor(self.mass_ratio)
        blk = self.block
        twin = Block(blk.h * k, blk.b * k, blk.b * k, blk.exact_inertia)
        return RigidModel(twin, eta=self.eta, threshold=self.threshold)

    @property
    def history_fields(self):
        """The fields a time history can hold: "theta" [rad] and "theta_dot" [rad/s] of the columns."""
        return ("theta", "theta_dot")

    def default_integrator(self, autodiff: str | None = None) -> EventIntegrator:
        """`EventIntegrator()` with its default settings (the rigid model's).

        Arguments:
            autodiff: "reverse" or "forward"; default None: "reverse".
        """
        return EventIntegrator(autodiff=autodiff or "reverse")

    def watch(self, system=None) -> Watch:
        """The levels a run is watched against: the equivalent block's (the same α)."""
        return self.equivalent.watch(system)

    def stepper(self, integrator: AbstractIntegrator, save: Save | None = None, t1=None) -> RigidStepper:
        """The run of the equivalent block (`AbstractModel.stepper`).

        Arguments:
            integrator: an `EventIntegrator`.
            save: the output request; default None: a summary.
            t1 (float | Array | None): end time [s] of a time history.
        """
        return self.equivalent.stepper(integrator, save, t1)


def scenes_file_model(block: Block, mass_ratio=1.0) -> RockingFrame:
    """A scenes file's rocking frame, with its own η: the builder of the model kind "frame" (`jaxrock.scene.MODEL_KINDS`)."""
    return RockingFrame(block, mass_ratio=mass_ratio)
