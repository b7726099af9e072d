"""Block geometry: every derived rocking quantity (R, α, p, η, and the extended-base α′, R′, p′, η′)
is computed here and nowhere else.

Notation (paper section 2, SPEC "Notation"): the column has height `2h` and width `2b`;
`R = sqrt(h² + b²)`, `α = atan(b/h)`, `p = sqrt(3g/(4R))`, `η = 1 − (3/2) sin²α` (eq. 3, r = η²).

Extended rigid base (paper section 5): the column stands on a rigid, massless base of half-width
`b′ ≥ b` and rocks about the base's corners: `α′ = atan(b′/h)`, `R′ = sqrt(h² + b′²)`.
The exact rigid-body inertia about a corner is `I′o = m (R²/3 + R′²)` (parallel axes; SPEC),
`p′² = m g R′ / I′o` (eq. 23) and `η′ = 1 − 2 m b′²/I′o` (angular-momentum balance about the new
corner). With `exact_inertia=False` the paper's printed (first-order) inertia eq. 24,
`I′o = m R²/3 + m R² cosα/cosα′`, is used instead; `p′` then follows eq. 25. Both reduce to the
plain block when `b′ = b`.

The "rocking" quantities (`alpha_r`, `p_r`, `eta_r`, `R_r`) are those that govern the rigid
rocking motion: the plain block's for `b′ = b`, the base's otherwise. Spectra are normalised by them.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import equinox as eqx
from jaxtyping import Array, Float

from ._validate import JaxrockInputError, Limit, check_limits, check_positive, check_range, is_concrete
from .scene import HEIGHT_RANGE, TAN_ALPHA, TAN_ALPHA_BASE, check_slenderness  # the valid geometry, declared once (`jaxrock.scene`)

G = 9.81  # m/s², SPEC
"""Gravitational acceleration g = 9.81 m/s² (SPEC), used by every model, pulse ratio and uplift level."""


class Block(eqx.Module):
    """A rectangular rocking column (half-height `h`, half-width `b`) on a base of half-width `b_base`.

    Build with `Block.from_size(height, width)` or `Block.from_slenderness(height, tan_alpha)`, or
    directly from the fields, `Block(h, b, b_base, exact_inertia=True)`. Fields are JAX arrays
    (vmappable, differentiable); `exact_inertia` is structure (static).
    The rocking quantities (`alpha_r`, `p_r`, `eta_r`, `R_r`) are the plain block's for
    `b_base = b` and the extended base's otherwise (paper section 5, eqs. 23–25).

    Attributes:
        h: half-height h [m]; the full height 2h in [1e-12, 1e12] m.
        b: half-width b [m], > 0; the slenderness tanα = b/h in [1e-3, 1).
        b_base: half-width b′ of the rigid base [m], b′ ≥ b (b′ = b: no base); tanα′ = b′/h in [1e-3, 1).
        exact_inertia: True (default): the exact inertia about a base corner, I′o = m (R²/3 + R′²);
            False: the paper's first-order eq. 24 (p′ by eq. 25). The same for a plain block.

    Raises:
        JaxrockInputError: at construction, when a concrete value is outside its valid range (under
            `jax.vmap`/`jax.jit` the run reports `Status.invalid_input` instead).

    Example:
        ```python
        import jaxrock

        block = jaxrock.Block.from_slenderness(10.0, 0.2)  # 2h = 10 m, tanα = 0.2
        float(block.p)  # 1.2012... rad/s
        float(block.uplift_acceleration)  # g tanα = 1.962 m/s²
        ```
    """

    h: Float[Array, ""]
    b: Float[Array, ""]
    b_base: Float[Array, ""]
    exact_inertia: bool = eqx.field(static=True, default=True)

    def __check_init__(self):
        check_positive("h (half-height) [m]", self.h)
        check_positive("b (half-width) [m]", self.b)
        check_positive("b_base (base half-width) [m]", self.b_base)
        if is_concrete((self.b, self.b_base)) and bool(jnp.any(self.b_base < self.b * (1 - 1e-12))):
            raise JaxrockInputError(
                f"base half-width b_base = {float(jnp.min(self.b_base)):g} m is narrower than the "
                f"column half-width b = {float(jnp.max(self.b)):g} m; valid range: b_base >= b"
            )
        check_limits(self.limits())

    def limits(self) -> tuple[Limit, ...]:
        """The valid geometry: 2h in `HEIGHT_RANGE`, tanα and tanα′ in their declared ranges.

        The ranges are `jaxrock.scene.TAN_ALPHA` and `TAN_ALPHA_BASE` ([1e-3, 1)), and tanα ≤ tanα′.

        Returns:
            (tuple[Limit, ...]): one `jaxrock._validate.Limit` per checked quantity.
        """
        inf = math.inf
        return (
            Limit("h (half-height) [m]", self.h, 0.5 * HEIGHT_RANGE[0], 0.5 * HEIGHT_RANGE[1]),
            Limit("tan_alpha = b/h", self.b / self.h, TAN_ALPHA.lo, TAN_ALPHA.hi, TAN_ALPHA.lo_open, TAN_ALPHA.hi_open),
            Limit("b_base/b (base over column half-width)", self.b_base / self.b, 1 - 1e-12, inf, hi_open=True),
            Limit("tan_alpha_base = b_base/h", self.b_base / self.h, TAN_ALPHA_BASE.lo, TAN_ALPHA_BASE.hi, TAN_ALPHA_BASE.lo_open,
                  TAN_ALPHA_BASE.hi_open),
        )

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def from_size(cls, height, width, base_width=None, *, exact_inertia: bool = True) -> "Block":
        """A column of full height `height` (2h) and width `width` (2b), optionally on a wider base.

        Arguments:
            height (float | Array): full height 2h [m], in [1e-12, 1e12].
            width (float | Array): full width 2b [m], > 0, with width/height in [1e-3, 1).
            base_width (float | Array | None): full width 2b′ of an extended rigid base [m], ≥ width;
                default None: no base (b′ = b).
            exact_inertia: the base corner's inertia, exact (default True) or the paper's eq. 24.

        Returns:
            (Block): the block.

        Raises:
            JaxrockInputError: when a concrete value is outside its valid range.

        Example:
            ```python
            block = jaxrock.Block.from_size(10.0, 2.0, base_width=3.0)  # 2b′ = 3 m
            ```
        """
        check_range("height (2h) [m]", height, *HEIGHT_RANGE)
        check_positive("width (2b) [m]", width)
        h = 0.5 * jnp.asarray(height, dtype=float)
        b = 0.5 * jnp.asarray(width, dtype=float)
        bb = b if base_width is None else 0.5 * jnp.asarray(base_width, dtype=float)
        return cls(h, b, bb, exact_inertia)

    @classmethod
    def from_slenderness(cls, height, tan_alpha, tan_alpha_base=None, *, exact_inertia: bool = True) -> "Block":
        """A column of full height `height` (2h) and slenderness `tan_alpha` = b/h.

        Arguments:
            height (float | Array): full height 2h [m], in [1e-12, 1e12].
            tan_alpha (float | Array): slenderness tanα = b/h [–], in [1e-3, 1).
            tan_alpha_base (float | Array | None): slenderness of an extended rigid base tanα′ = b′/h [–],
                in [1e-3, 1) and ≥ tan_alpha; default None: no base (tanα′ = tanα).
            exact_inertia: the base corner's inertia, exact (default True) or the paper's eq. 24.

        Returns:
            (Block): the block.

        Raises:
            JaxrockInputError: when a concrete value is outside its valid range.

        Example:
            ```python
            block = jaxrock.Block.from_slenderness(10.0, 0.2)
            ```
        """
        check_slenderness(height, tan_alpha, tan_alpha_base)
        h = 0.5 * jnp.asarray(height, dtype=float)
        b = h * jnp.asarray(tan_alpha, dtype=float)
        bb = b if tan_alpha_base is None else h * jnp.asarray(tan_alpha_base, dtype=float)
        return cls(h, b, bb, exact_inertia)

    # -- the column itself --------------------------------------------------------------------
    @property
    def height(self):
        """Full height 2h [m]."""
        return 2 * self.h

    @property
    def width(self):
        """Full width 2b [m]."""
        return 2 * self.b

    @property
    def R(self):
        """Half-diagonal R = sqrt(h² + b²) [m]."""
        return jnp.sqrt(self.h**2 + self.b**2)

    @property
    def alpha(self):
        """Slenderness angle α = atan(b/h) [rad]."""
        return jnp.arctan2(self.b, self.h)

    @property
    def tan_alpha(self):
        """Slenderness tanα = b/h [–]."""
        return self.b / self.h

    @property
    def p(self):
        """Frequency parameter p = sqrt(3g/(4R)) of the column [rad/s]."""
        return jnp.sqrt(3 * G / (4 * self.R))

    @property
    def eta(self):
        """Angular-velocity ratio across an impact of the plain block, η = 1 − (3/2) sin²α (eq. 3)."""
        return 1 - 1.5 * jnp.sin(self.alpha) ** 2

    # -- rocking about the base corners -------------------------------------------------------
    @property
    def alpha_r(self):
        """Rocking slenderness α′ = atan(b′/h) [rad] (α for a plain block)."""
        return jnp.arctan2(self.b_base, self.h)

    @property
    def R_r(self):
        """Rocking half-diagonal R′ = sqrt(h² + b′²) [m] (R for a plain block)."""
        return jnp.sqrt(self.h**2 + self.b_base**2)

    @property
    def inertia_ratio(self):
        """I′o / m about a rocking corner [m²]: exact R²/3 + R′², or the paper's eq. 24."""
        if self.exact_inertia:
            return self.R**2 / 3 + self.R_r**2
        return self.R**2 / 3 + self.R**2 * jnp.cos(self.alpha) / jnp.cos(self.alpha_r)

    @property
    def p_r(self):
        """Rocking frequency parameter p′ = sqrt(m g R′ / I′o) [rad/s] (eq. 23); equals p for a plain block."""
        return jnp.sqrt(G * self.R_r / self.inertia_ratio)

    @property
    def eta_r(self):
        """η′ = 1 − 2 b′²/(I′o/m); equals η = 1 − 1.5 sin²α for a plain block (exact inertia)."""
        return 1 - 2 * self.b_base**2 / self.inertia_ratio

    @property
    def uplift_acceleration(self):
        """Least |üg| that uplifts the rigid block from rest: g tanα′ [m/s²] (eq. 26)."""
        return G * self.b_base / self.h


def pulse_of_ratios(block: Block, accel_ratio, omega_ratio):
    """The pulse amplitude and frequency of the spectra's ratios a_p/(g tanα′) and ω_p/p′.

    The ratios are the spectra's axes (`jaxrock.scene.AXES`), taken with the rocking α′ and p′ of
    `block`; numbers or arrays (broadcast). The inverse of `ratios_of_pulse`.

    Arguments:
        block: the block whose α′ and p′ normalise the pulse.
        accel_ratio (float | Array): a_p/(g tanα′) [–].
        omega_ratio (float | Array): ω_p/p′ [–].

    Returns:
        a_p (Array): pulse amplitude a_p = accel_ratio · g tanα′ [m/s²].
        omega_p (Array): pulse frequency ω_p = omega_ratio · p′ [rad/s].

    Example:
        ```python
        block = jaxrock.Block.from_slenderness(10.0, 0.2)
        a_p, omega_p = jaxrock.pulse_of_ratios(block, 2.0, 3.0)  # 3.924 m/s², 3.6037 rad/s
        ```
    """
    return accel_ratio * G * jnp.tan(block.alpha_r), omega_ratio * block.p_r


def ratios_of_pulse(block: Block, a_p, omega_p):
    """The spectra's ratios a_p/(g tanα′) and ω_p/p′ of a pulse's amplitude and frequency.

    The inverse of `pulse_of_ratios`; numbers or arrays (broadcast).

    Arguments:
        block: the block whose rocking α′ and p′ normalise the pulse.
        a_p (float | Array): pulse amplitude [m/s²].
        omega_p (float | Array): pulse frequency [rad/s].

    Returns:
        accel_ratio (Array): a_p/(g tanα′) [–].
        omega_ratio (Array): ω_p/p′ [–].
    """
    return a_p / (G * jnp.tan(block.alpha_r)), omega_p / block.p_r
