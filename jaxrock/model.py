"""One call shape for every physics pipeline: `simulate(model, excitation, ...)`.

A model is a value (an `eqx.Module` whose array leaves can be vmapped and differentiated) that
knows its geometry (`block`), its overturning threshold and its default integrator. The
integrator settings are a separate value; the output request is a `Save` (or nothing: summary only).
"""

from __future__ import annotations

import abc

import diffrax
import equinox as eqx
import jax.numpy as jnp

from ._validate import JaxrockInputError, check_range, is_concrete
from .excitation import AbstractExcitation
from .geometry import Block
from .results import Save, Solution


AUTODIFF_MODES = ("reverse", "forward")


class AbstractIntegrator(eqx.Module):
    """Numerical settings of a model's time integration (tolerances, bounds)."""


def check_autodiff(autodiff: str):
    if autodiff not in AUTODIFF_MODES:
        raise JaxrockInputError(f"autodiff = {autodiff!r}; valid: {AUTODIFF_MODES}")


def diffrax_adjoint(autodiff: str, checkpoints: int | None = None) -> diffrax.AbstractAdjoint:
    """diffrax's adjoint for an integrator's `autodiff` mode: `"reverse"` (`jax.grad`, `jax.vjp`,
    `jax.jacrev`; recursive checkpointing, `checkpoints` as diffrax's) or `"forward"` (`jax.jvp`,
    `jax.jacfwd`; plain loops, no stored trajectory). JAX cannot run forward mode through a
    reverse-mode loop (a `custom_vjp`), nor the reverse, so the mode is chosen with the integrator."""
    return diffrax.ForwardMode() if autodiff == "forward" else diffrax.RecursiveCheckpointAdjoint(checkpoints)


class AbstractModel(eqx.Module):
    """A rocking body model: rigid (`RigidModel`) or spring (`SpringModel`)."""

    block: eqx.AbstractVar[Block]
    threshold: eqx.AbstractVar[float]

    @abc.abstractmethod
    def default_integrator(self) -> AbstractIntegrator:
        """The integrator used when `simulate` is given none."""

    @abc.abstractmethod
    def run(self, excitation: AbstractExcitation, integrator: AbstractIntegrator, save: Save | None, t1) -> Solution:
        """Integrate from the excitation's start; see `simulate`."""

    @property
    @abc.abstractmethod
    def history_fields(self) -> tuple[str, ...]:
        """Names this model can save in a time history."""


def simulate(
    model: AbstractModel,
    excitation: AbstractExcitation,
    *,
    integrator: AbstractIntegrator | None = None,
    save: Save | None = None,
    t1=None,
) -> Solution:
    """Simulate one scene. A pure function: `jax.vmap` and `jax.grad` accept it.

    - Without `save`, only the summary is computed and the run stops as soon as the answer is
      fixed (overturned; at rest after the excitation ended; or excitation over, so that the
      remaining free-rocking peaks can only decay).
    - With `save=Save(ts, fields)`, the requested time history is returned and the run goes on to
      `t1` (default: the last save time).
    """
    if not isinstance(model, AbstractModel):
        raise JaxrockInputError(f"model must be a jaxrock model (RigidModel, SpringModel), got {type(model).__name__}")
    if not isinstance(excitation, AbstractExcitation):
        raise JaxrockInputError(
            f"excitation must be a jaxrock excitation (RickerPulse, AntisymmetricRickerPulse, Record), got {type(excitation).__name__}"
        )
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
    return _run(model, excitation, integrator, save, t1)


@eqx.filter_jit
def _run(model, excitation, integrator, save, t1):
    # Compiled once per structure (model kind, mesh, save request): repeated calls with new
    # numbers reuse it. Composes with an outer jit, vmap and grad.
    return model.run(excitation, integrator, save, t1)
