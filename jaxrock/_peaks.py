"""Peaks and threshold crossings of the base rotation from (t, θ, θ̇) at step ends, shared by the
spring model's integrators (diffrax and generalized-α)."""

from __future__ import annotations

import jax.numpy as jnp


def _hermite(s, a0, a1, w0, w1):
    """The cubic Hermite interpolant at s ∈ [0, 1] of a step from (a0, w0) to (a1, w1), with the
    slopes w already multiplied by the step length."""
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * w0 + (-2 * s3 + 3 * s2) * a1 + (s3 - s2) * w1


def _hermite_slope(a0, a1, w0, w1):
    """(A, B, C) of the interpolant's derivative d/ds = A s² + B s + C."""
    return 6 * a0 + 3 * w0 - 6 * a1 + 3 * w1, -6 * a0 - 4 * w0 + 6 * a1 - 2 * w1, w0


def hermite_peak(ts, th, om):
    """max |θ| over all steps from (t, θ, θ̇) at the step ends, maximising the cubic Hermite
    interpolant of each step in closed form. Unused (non-finite) entries are ignored."""
    t0, t1 = ts[:-1], ts[1:]
    valid = jnp.isfinite(t1) & jnp.isfinite(t0) & (t1 > t0)
    safe = lambda x, fill: jnp.where(valid, x, fill)
    t0s, t1s = safe(t0, 0.0), safe(t1, 1.0)
    a0, a1 = safe(th[:-1], 0.0), safe(th[1:], 0.0)
    w0, w1 = safe(om[:-1], 0.0), safe(om[1:], 0.0)
    dt = t1s - t0s
    A, B, C = _hermite_slope(a0, a1, dt * w0, dt * w1)
    disc = B**2 - 4 * A * C
    sq = jnp.sqrt(jnp.where(disc > 0, disc, 1.0))
    qq = -0.5 * (B + jnp.where(B >= 0, 1.0, -1.0) * sq)
    qok = (jnp.abs(qq) > 0) & (disc > 0)
    qs = jnp.where(qok, qq, 1.0)
    r1 = jnp.where(qok & (jnp.abs(A) > 0), qq / jnp.where(jnp.abs(A) > 0, A, 1.0), -1.0)
    r2 = jnp.where(qok, C / qs, -1.0)
    # degenerate quadratic (A = 0): single root −C/B
    r3 = jnp.where((jnp.abs(A) == 0) & (jnp.abs(B) > 0), -C / jnp.where(jnp.abs(B) > 0, B, 1.0), -1.0)

    best = jnp.maximum(jnp.abs(a0), jnp.abs(a1))
    for r in (r1, r2, r3):
        inside = (r > 0) & (r < 1)
        best = jnp.maximum(best, jnp.where(inside, jnp.abs(_hermite(jnp.where(inside, r, 0.5), a0, a1, dt * w0, dt * w1)), 0.0))
    return jnp.max(jnp.where(valid, best, 0.0))


def hermite_crossing(t0, t1, th0, th1, om0, om1, level, newton: int = 4):
    """Time in [t0, t1] at which |θ| reaches `level` on the step's cubic Hermite interpolant, for a
    step that ends beyond it (|θ₁| ≥ level): the linear estimate refined by Newton on the cubic,
    kept in [0, 1]. Accurate to the interpolant's O(dt⁴), so its derivative with respect to the
    parameters is the crossing's (a linear estimate's derivative is off by O(dt²) and jumps with
    the step sequence)."""
    sgn = jnp.where(th1 >= 0, 1.0, -1.0)
    dt = t1 - t0
    a0, a1, w0, w1 = sgn * th0, sgn * th1, sgn * om0 * dt, sgn * om1 * dt
    rise = jnp.where(a1 > a0, a1 - a0, 1.0)
    s = jnp.clip((level - a0) / rise, 0.0, 1.0)
    A, B, C = _hermite_slope(a0, a1, w0, w1)
    for _ in range(newton):
        f = _hermite(s, a0, a1, w0, w1) - level
        df = (A * s + B) * s + C
        s = jnp.clip(s - f / jnp.where(df > 0, df, 1.0) * (df > 0), 0.0, 1.0)
    return t0 + s * dt


def first_exceedance(ts, th, om, level):
    """First time |θ| exceeds `level` (on the cubic Hermite interpolant of the recorded steps);
    +inf if never."""
    x = jnp.abs(th) - level
    ok = jnp.isfinite(ts) & jnp.isfinite(x)
    x = jnp.where(ok, x, -1.0)
    above = x > 0
    k = jnp.argmax(above)
    km = jnp.maximum(k - 1, 0)
    tk = jnp.where(k > 0, hermite_crossing(ts[km], ts[k], th[km], th[k], om[km], om[k], level), ts[k])
    return jnp.where(jnp.any(above), tk, jnp.inf)
