"""The column: its material and section (`Column`) and the paper's closed forms of it — eq. 9 (the
rigid column's pushover), eq. 17 (the calibrated damper coefficient c̄) and eq. 21 (the first
fixed-base period of a solid column). The discretised column itself is `jaxrock.spring.beam`."""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._validate import JaxrockInputError, Limit, check_limits
from ..geometry import Block
from ..scene import CONCRETE_E, CONCRETE_RHO


def cbar_eq17(alpha):
    """The paper's calibrated damper coefficient c̄ (eq. 17).

    c̄ = c/(m g^0.5 R^1.5) = 0.02 (α/0.1)². The spring models use it with the rocking α′ when no
    `cbar` is given.

    Arguments:
        alpha (float | Array): slenderness angle α [rad] (a scalar or an array of any shape).

    Returns:
        (Array): c̄ [-], an array of the shape of `alpha`.

    Example:
        ```python
        import jaxrock
        jaxrock.cbar_eq17(0.1)  # 0.02
        ```
    """
    return 0.02 * (jnp.asarray(alpha, dtype=float) / 0.1) ** 2


def first_period_eq21(height, tan_alpha, E, rho):
    """First fixed-base period of a solid rectangular column (eq. 21).

    T₁ = 12.38 sqrt(ρ/E) h/tanα [s], with `height` = 2h as every constructor takes it (2h = 50 m,
    tanα = 0.1, concrete: 0.893 s). The discretised column's own value, with its added masses, is
    `FlexibleSpringModel.first_period`.

    Arguments:
        height (float | Array): full column height 2h [m].
        tan_alpha (float | Array): slenderness tanα = b/h [-].
        E (float | Array): Young's modulus [Pa].
        rho (float | Array): density ρ [kg/m³].

    Returns:
        (Array): T₁ [s] (broadcast over array arguments).

    Example:
        ```python
        import jaxrock
        jaxrock.first_period_eq21(50.0, 0.1, 30e9, 2500.0)  # ≈ 0.893 s
        ```
    """
    return 12.38 * jnp.sqrt(jnp.asarray(rho, dtype=float) / E) * (0.5 * jnp.asarray(height, dtype=float)) / tan_alpha


def pushover_eq9(theta, alpha):
    """The rigid spring model's static pushover curve (eq. 9).

    F/(m g) = tanα/cosθ − tanθ, the lateral force applied at the column's mid-height that holds it
    at base rotation θ once the spring has yielded. The model's own curve, pre-yield branch and
    flexible column included, is `AbstractSpringModel.pushover`.

    Arguments:
        theta (float | Array): base rotation θ [rad] (any shape).
        alpha (float | Array): slenderness angle α [rad].

    Returns:
        (Array): F/(m g) [-], broadcast over the arguments.
    """
    return jnp.tan(alpha) / jnp.cos(theta) - jnp.tan(theta)



class Column(eqx.Module):
    """A linear elastic column: its material and, optionally, its section.

    Without A, I the section is the block's solid rectangle 2b × 1 m: A = 2b, I = (2b)³/12 (per the
    model's out-of-plane thickness). A flexible spring model takes it (`SpringModel(block, column)`).

    Arguments:
        E (float | Array): Young's modulus [Pa], in [1e6, 1e15] (1e14 stands for a rigid column).
        rho (float | Array): density ρ [kg/m³], in [10, 3e4]; default concrete's `CONCRETE_RHO` (2500).
        A (float | Array | None): section area [m²], > 0; default None (the block's solid section).
        I (float | Array | None): section second moment [m⁴], > 0; default None (the block's solid section).

    Raises:
        JaxrockInputError: when only one of `A`, `I` is given, or a value is outside its range.

    Example:
        ```python
        import jaxrock
        column = jaxrock.Column(30e9, 2500.0)  # concrete, the block's solid section
        model = jaxrock.SpringModel(jaxrock.Block.from_slenderness(50.0, 0.1), column)
        ```
    """

    E: Float[Array, ""]
    rho: Float[Array, ""]
    A: Float[Array, ""] | None = None
    I: Float[Array, ""] | None = None

    def __init__(self, E, rho=CONCRETE_RHO, A=None, I=None):
        if (A is None) != (I is None):
            raise JaxrockInputError("give both the section area A and its second moment I, or neither")
        self.E = jnp.asarray(E, dtype=float)
        self.rho = jnp.asarray(rho, dtype=float)
        self.A = None if A is None else jnp.asarray(A, dtype=float)
        self.I = None if I is None else jnp.asarray(I, dtype=float)
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        """E from soft rubber to beyond diamond (10⁶–10¹⁵ Pa; 10¹⁴ stands for a rigid column), ρ
        from foams to beyond osmium (10–3·10⁴ kg/m³): outside these the column is no solid."""
        section = () if self.A is None else (Limit("A (section area) [m^2]", self.A, 0.0, math.inf, lo_open=True, hi_open=True),
                                             Limit("I (section second moment) [m^4]", self.I, 0.0, math.inf, lo_open=True, hi_open=True))
        return (Limit("E (Young's modulus) [Pa]", self.E, 1e6, 1e15), Limit("rho (density) [kg/m^3]", self.rho, 10.0, 3e4), *section)

    @classmethod
    def concrete(cls, A=None, I=None) -> "Column":
        """A concrete column: `jaxrock.scene.CONCRETE_E` and `CONCRETE_RHO` (paper sections 4–6).

        Arguments:
            A (float | Array | None): section area [m²], > 0; default None (the block's solid section).
            I (float | Array | None): section second moment [m⁴], > 0; default None (the block's solid section).

        Returns:
            The `Column`.
        """
        return cls(CONCRETE_E, CONCRETE_RHO, A, I)

    @classmethod
    def quasi_rigid(cls, rho=CONCRETE_RHO) -> "Column":
        """A quasi-rigid column: E = 10¹⁴ Pa (paper section 3: the 'quasi-rigid' FE column).

        Arguments:
            rho (float | Array): density ρ [kg/m³], in [10, 3e4]; default `CONCRETE_RHO` (2500).

        Returns:
            The `Column`.
        """
        return cls(1e14, rho)

    def section(self, block: Block):
        if self.A is None:
            w = 2 * block.b
            return w, w**3 / 12
        return self.A, self.I

