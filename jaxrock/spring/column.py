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
    """Eq. 17: c̄ = c/(m g^0.5 R^1.5) = 0.02 (α/0.1)² (α in rad)."""
    return 0.02 * (jnp.asarray(alpha, dtype=float) / 0.1) ** 2


def first_period_eq21(height, tan_alpha, E, rho):
    """Eq. 21: first fixed-base period of a solid rectangular column, T₁ = 12.38 sqrt(ρ/E) h/tanα [s],
    with `height` = 2h [m] as every constructor takes it (2h = 50 m, tanα = 0.1 concrete: 0.893 s).
    The discretised column's own value, with its added masses, is `SpringModel.first_period`."""
    return 12.38 * jnp.sqrt(jnp.asarray(rho, dtype=float) / E) * (0.5 * jnp.asarray(height, dtype=float)) / tan_alpha


def pushover_eq9(theta, alpha):
    """Eq. 9: SM pushover F/(m g) = tanα/cosθ − tanθ (force at the column's mid-height)."""
    return jnp.tan(alpha) / jnp.cos(theta) - jnp.tan(theta)



class Column(eqx.Module):
    """Linear elastic column: Young's modulus E [Pa], density ρ [kg/m³], and optionally the
    section area A [m²] and second moment I [m⁴] (per the model's out-of-plane thickness).
    Without A, I the section is the block's solid rectangle 2b × 1 m: A = 2b, I = (2b)³/12."""

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
        """Concrete: `jaxrock.scene.CONCRETE_E` and `CONCRETE_RHO` (paper sections 4–6)."""
        return cls(CONCRETE_E, CONCRETE_RHO, A, I)

    @classmethod
    def quasi_rigid(cls, rho=CONCRETE_RHO) -> "Column":
        """E = 10¹⁴ Pa (paper section 3: 'quasi-rigid' FE column)."""
        return cls(1e14, rho)

    def section(self, block: Block):
        if self.A is None:
            w = 2 * block.b
            return w, w**3 / 12
        return self.A, self.I

