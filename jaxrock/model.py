"""One call shape for every physics pipeline: `simulate(model, excitation, ...)`.

A model is a value (an `eqx.Module` whose array leaves can be vmapped and differentiated) that
knows its geometry (`block`), its overturning threshold and its default integrator. The
integrator settings are a separate value; the output request is a `Save` (or nothing: summary only).
"""

from __future__ import annotations

import abc

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from ._validate import JaxrockInputError, Limit, check_one_scene, check_range, is_concrete, within_limits
from .excitation import AbstractExcitation
from .geometry import Block
from .results import Save, Solution, Status


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
) -> Solution:
    """Simulate one scene. A pure function: `jax.vmap` and `jax.grad` accept it.

    - Without `save`, only the summary is computed and the run stops as soon as the answer is
      fixed (overturned; at rest after the excitation ended; or excitation over, so that the
      remaining free-rocking peaks can only decay).
    - With `save=Save(ts, fields)`, the requested time history is returned and the run goes on to
      `t1` (default: the last save time); `t1` without `save` is refused.
    - A parameter outside its limits (`limits()` of the block, model and excitation) is refused
      at construction; under `jax.vmap`/`jax.jit`, where it cannot be, the run returns
      `Status.invalid_input` with NaN numbers.
    """
    if not isinstance(model, AbstractModel):
        raise JaxrockInputError(f"model must be a jaxrock model (RigidModel, SpringModel), got {type(model).__name__}")
    if not isinstance(excitation, AbstractExcitation):
        raise JaxrockInputError(
            f"excitation must be a jaxrock excitation (RickerPulse, AntisymmetricRickerPulse, Record), got {type(excitation).__name__}"
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
    return _run(model, excitation, integrator, save, t1)


@eqx.filter_jit
def _run(model, excitation, integrator, save, t1):
    # Compiled once per structure (model kind, mesh, save request): repeated calls with new
    # numbers reuse it. Composes with an outer jit, vmap and grad.
    ok = within_limits(scene_limits(model, excitation))
    model, excitation = _neutral(model, ok), _neutral(excitation, ok)
    return flag_invalid(model.run(excitation, integrator, save, t1), ok)


# A valid, quiet scene (2h = 10 m, tanα = 0.2 at rest under 1 m/s², below its uplift at 1.96 m/s²):
# the values an invalid lane runs instead of its own, by leaf name, so that NaN or negative sizes
# never reach a loop (they ran it to its iteration bound).
_NEUTRAL = {"h": 5.0, "b": 1.0, "b_base": 1.0, "eta": 0.9, "threshold": 1.0, "cbar": 0.05, "smoothing": 1e-4,
            "zeta": 0.01, "E": 3e10, "rho": 2500.0, "A": 2.0, "I": 2.0 / 3.0, "a_p": 1.0, "omega_p": 6.0,
            "acc": 0.0, "dt": 0.01, "scale": 0.0}


def _neutral(tree, ok):
    """`tree` where `ok`, else its leaves replaced by the quiet scene's (`_NEUTRAL`)."""

    def swap(path, leaf):
        name = getattr(path[-1], "name", None) if path else None
        if name not in _NEUTRAL or not eqx.is_inexact_array(leaf):
            return leaf
        return jnp.where(ok, leaf, jnp.asarray(_NEUTRAL[name], dtype=leaf.dtype))

    return jax.tree_util.tree_map_with_path(swap, tree)


def flag_invalid(sol: Solution, ok) -> Solution:
    """`Status.invalid_input` and NaN numbers where `ok` is false (a parameter outside its
    limits). Concrete input is refused at construction; under `jax.vmap`/`jax.jit` constructors
    see tracers and cannot, so the run flags it instead (failure as a value)."""
    nan = jnp.asarray(jnp.nan, dtype=sol.max_theta.dtype)
    return eqx.tree_at(
        lambda s: (s.max_theta, s.overturned, s.uplifted, s.t_overturn, s.t_uplift, s.status),
        sol,
        (jnp.where(ok, sol.max_theta, nan), sol.overturned & ok, sol.uplifted & ok, jnp.where(ok, sol.t_overturn, nan),
         jnp.where(ok, sol.t_uplift, nan), Status.where(ok, sol.status, Status.invalid_input)),
    )
