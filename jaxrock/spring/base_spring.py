"""The base spring and its damper (paper section 3, Figure 2 right; eqs. 17–18).

The damper in parallel with the spring: ``c = c̄ m g^0.5 R′^1.5`` (eq. 18, `damper`), c̄ by default
from eq. 17 (`jaxrock.spring.column.cbar_eq17`). The spring's moment–rotation curve M(θ), its backbone:

The paper's spring is nonlinear *elastic* and rigid-plastic: M = My sign θ once the column
rocks, unloading along the loading path. A computable spring needs a finite pre-yield stiffness;
each backbone here has one parameter, the pre-yield rotation ``θs = smoothing · α′``
(`SpringModel.smoothing`), and tends to the rigid-plastic envelope as θs → 0:

- `Bilinear` (the paper's OpenSees spring, as ``ElasticMultiLinear``; both spring models'
  default at θy = 1e-5 α′): linear up to the yield rotation θy = θs, then flat at My. Its error
  against the rigid-plastic limit is of first order in θy: at 1e-5 α′ at most 7.6e-4 in
  max|θ|/α over the 192 quasi-rigid scenes of `benchmarks/bench_backbone.py` whose limit is
  settled, 8.3e-4 over its 48 flexible ones (2.2e-2 at θy = 1e-4 α′). Its kinks are `kinked`:
  the diffrax integrator stops on them and restarts on the other branch (`moment_on_branch`),
  so derivatives through it are the motion's; generalized-α ends its steps on them likewise;
- `Tanh` (the flexible SM's default at θs = 1e-4 α′ until issue 56): ``M = My tanh(θ/θs)``, smooth everywhere,
  so derivatives through any integrator are good; it reaches 99.5 % of My only at 3 θs and its
  error at equal θs is 9–30× the bilinear's (same study: 4.9e-2 quasi-rigid, 3.9e-2 flexible at
  θs = 1e-4 α′).

A backbone is a small, leafless value: structure, not data (its θs is the model's array leaf).
Each gives the moment, its potential (the forces are its gradient) and the exact solution of the
scalar spring equation of an implicit step, ``u + k m(u) = r`` in ``u = θ/θs`` with
``m = M/My`` and ``k ≥ 0`` (`jaxrock.spring.generalized_alpha`): closed form for the bilinear backbone,
so its kink never enters a Newton iteration; a fixed number of Newton steps for tanh.
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from ..geometry import G
from .._validate import JaxrockInputError
from ..scene import BACKBONES, DEFAULT_BACKBONE, DEFAULT_SMOOTHING  # the names and defaults (`jaxrock.scene`)


def damper(cbar, m, R):
    """Eq. 18: the damper coefficient c = c̄ m g^0.5 R^1.5 [N·m·s] (R: the rocking R′)."""
    return cbar * m * math.sqrt(G) * R**1.5


_TANH_NEWTON = 10  # tanh's scalar solve: Newton steps (round-off for k, r in [1e-4, 1e10], tests/test_backbone.py)


class AbstractBackbone(eqx.Module):
    """The base spring's backbone: its moment–rotation curve M(θ).

    M(θ) = My m(θ/θs) with an odd, increasing unit curve m(u) → sign u as |u| → ∞, the pre-yield
    rotation θs = smoothing · α′ given by the model (`AbstractSpringModel.smoothing`). A backbone is
    a small, leafless value (structure, not data); a subclass sets the class variables `name`,
    `band` (the pre-yield band, in θs, beyond which the spring has yielded) and `kinked`, and
    implements `unit_moment`, `unit_potential` and `solve` (and, when kinked, `moment_on_branch`
    and `solve_on_branch`). It takes no arguments.
    """

    name: ClassVar[str]
    # the spring has (all but) yielded once |θ| > band·θs: the uplift rotation and the pre-yield
    # band whose crossing generalized-α resolves
    band: ClassVar[float]
    # a kink (a jump of the stiffness) at |θ| = θs: the diffrax integrator then steps onto it
    # (an event, the run restarted on the next branch, `moment_on_branch`), never over it
    kinked: ClassVar[bool] = False

    def unit_moment(self, u):
        """The unit moment m(u) = M/My.

        Arguments:
            u (Array): the rotation over the pre-yield rotation, θ/θs [-] (any shape).

        Returns:
            (Array): m(u) [-], the shape of `u`.
        """
        raise NotImplementedError

    def unit_potential(self, u):
        """The unit potential ∫₀ᵘ m: the spring's potential is My θs times it.

        Arguments:
            u (Array): the rotation over the pre-yield rotation, θ/θs [-] (any shape).

        Returns:
            (Array): ∫₀ᵘ m [-], the shape of `u`.
        """
        raise NotImplementedError

    def solve(self, r, k):
        """The exact solution of the scalar spring equation of an implicit step.

        Arguments:
            r (Array): right-hand side r [-].
            k (Array): coefficient k ≥ 0 [-].

        Returns:
            (Array): u with u + k m(u) = r, exact to round-off.
        """
        raise NotImplementedError

    def moment(self, theta, My, theta_s):
        return My * self.unit_moment(theta / theta_s)

    def moment_on_branch(self, theta, My, theta_s, branch):
        """A kinked backbone's moment continued smoothly from one branch (0: pre-yield, ±1: yielded
        to ±My): the moment of a run between two kinks (`kinked`)."""
        raise NotImplementedError

    def solve_on_branch(self, r, k, branch):
        """`solve` with the unit moment continued from `branch` (`moment_on_branch`)."""
        raise NotImplementedError

    def potential(self, theta, My, theta_s):
        return My * theta_s * self.unit_potential(theta / theta_s)


class Bilinear(AbstractBackbone):
    """The bilinear backbone, the paper's spring and both spring models' default.

    Linear to the yield rotation θy = θs, flat at My beyond: m(u) = clip(u, −1, 1). Its kinks at
    |θ| = θs are stepped onto by the integrators (`kinked`), so derivatives through it are the
    motion's. Default smoothing θy/α′ = 1e-5 (`DEFAULT_SMOOTHING`). It takes no arguments.

    Example:
        ```python
        import jaxrock
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), backbone=jaxrock.Bilinear())
        ```
    """

    name: ClassVar[str] = "bilinear"
    band: ClassVar[float] = 1.0
    kinked: ClassVar[bool] = True

    def moment_on_branch(self, theta, My, theta_s, branch):
        return My * jnp.where(branch == 0, theta / theta_s, branch)

    def solve_on_branch(self, r, k, branch):
        return jnp.where(branch == 0, r / (1.0 + k), r - k * branch)

    def unit_moment(self, u):
        return jnp.clip(u, -1.0, 1.0)

    def unit_potential(self, u):
        a = jnp.abs(u)
        return jnp.where(a <= 1.0, 0.5 * u * u, a - 0.5)

    def solve(self, r, k):
        # pre-yield: u (1 + k) = r while |u| ≤ 1, i.e. |r| ≤ 1 + k; yielded: u + k sign u = r
        return jnp.where(jnp.abs(r) <= 1.0 + k, r / (1.0 + k), r - k * jnp.sign(r))


class Tanh(AbstractBackbone):
    """The smooth tanh backbone: m(u) = tanh u, potential log cosh u.

    Smooth everywhere (99.5 % of My only at 3 θs); its error at equal θs is 9–30× the bilinear's.
    Default smoothing θs/α′ = 1e-4 (`DEFAULT_SMOOTHING`). It takes no arguments.

    Example:
        ```python
        import jaxrock
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), backbone="tanh")
        ```
    """

    name: ClassVar[str] = "tanh"
    band: ClassVar[float] = 3.0

    def unit_moment(self, u):
        return jnp.tanh(u)

    def unit_potential(self, u):
        a = jnp.abs(u)
        return a + jnp.log1p(jnp.exp(-2 * a)) - math.log(2.0)

    def solve(self, r, k):
        """f(u) = u + k tanh u − |r| is increasing and concave for u ≥ 0 (odd: solved for |r|),
        and its root lies in [0, |r|]. Newton from any point of [0, |r|] reaches it: from the
        right its first step lands left of the root (the tangent lies above a concave f), and from
        the left it climbs monotonically. The start is the best of three lower estimates: the
        pre-yield |r|/(1 + k), the yielded |r| − k and, for |r| near k (the tail, where Newton
        from those climbs by only ~½ per step), ½ log(1 + 2k/(||r| − k| + 1)) from
        k (1 − tanh u) ≈ 2k e^(−2u). A fixed number of steps, `_TANH_NEWTON`, then leaves a
        residual at round-off for k and |r| over fourteen decades: no loop, so that under `vmap`
        it fuses into the step's arithmetic."""
        ra = jnp.abs(r)
        s = ra - k
        u = jnp.maximum(jnp.maximum(ra / (1 + k), s), jnp.minimum(0.5 * jnp.log1p(2 * k / (jnp.abs(s) + 1)), ra))
        for _ in range(_TANH_NEWTON):
            th = jnp.tanh(u)
            u = jnp.maximum(u + (ra - u - k * th) / (1 + k * (1 - th * th)), 0.0)
        return jnp.sign(r) * u


def as_backbone(backbone: "AbstractBackbone | str") -> AbstractBackbone:
    """A backbone value from itself or its name."""
    if isinstance(backbone, AbstractBackbone):
        return backbone
    if isinstance(backbone, str) and backbone in BACKBONES:
        return globals()[BACKBONES[backbone]]()
    raise JaxrockInputError(f"backbone = {backbone!r}; valid: {tuple(BACKBONES)} or a jaxrock backbone value")


__all__ = ["AbstractBackbone", "Bilinear", "Tanh", "DEFAULT_BACKBONE", "DEFAULT_SMOOTHING", "as_backbone"]
