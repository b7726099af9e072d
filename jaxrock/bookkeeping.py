"""What a run records about its base rotation θ, written once for every integrator of every model.

- `Record`: the running summary — the peak max |θ|, the uplift time (first |θ| beyond the uplift
  rotation), overturned and its time. Event-driven integrators write what their events locate
  (`saw_peak`, `saw_uplift`, `saw_overturn`); step-sampled ones hand over (t, θ, θ̇) at step ends
  (`Watch.steps`); records of consecutive pieces of a run `merge`.
- `Watch`: the levels a run is watched against (the uplift rotation, the overturning rotation
  threshold·α′, +inf for a column that cannot overturn) and the conversion of a `Record` into the
  run's `Solution` (max |θ|/α′ clamped to the threshold, a non-finite peak reported as
  `Status.solver_failed`, never silently NaN with status ok).
- From step ends, the peak and the crossings come from each step's cubic Hermite interpolant (θ,
  θ̇ at both ends, fourth-order accurate), maximised and solved in closed form / by Newton: exact
  to the integrator's tolerance, cheaper than events on θ̇ = 0, and differentiable.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from .results import OUTPUTS, SUMMARY, Solution, Status


def hermite(s, a0, a1, w0, w1):
    """The cubic Hermite interpolant at s ∈ [0, 1] of a step from (a0, w0) to (a1, w1), with the
    slopes w already multiplied by the step length."""
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * w0 + (-2 * s3 + 3 * s2) * a1 + (s3 - s2) * w1


def hermite_slope(a0, a1, w0, w1):
    """(A, B, C) of the interpolant's derivative d/ds = A s² + B s + C."""
    return 6 * a0 + 3 * w0 - 6 * a1 + 3 * w1, -6 * a0 - 4 * w0 + 6 * a1 - 2 * w1, w0


def hermite_turns(a0, a1, w0, w1):
    """The interpolant's turning points: the roots s of its derivative A s² + B s + C, three
    candidates (the stable pair of a quadratic, the one root of a degenerate A = 0), −1 where none."""
    A, B, C = hermite_slope(a0, a1, w0, w1)
    disc = B**2 - 4 * A * C
    sq = jnp.sqrt(jnp.where(disc > 0, disc, 1.0))
    qq = -0.5 * (B + jnp.where(B >= 0, 1.0, -1.0) * sq)
    qok = (jnp.abs(qq) > 0) & (disc > 0)
    qs = jnp.where(qok, qq, 1.0)
    r1 = jnp.where(qok & (jnp.abs(A) > 0), qq / jnp.where(jnp.abs(A) > 0, A, 1.0), -1.0)
    r2 = jnp.where(qok, C / qs, -1.0)
    # degenerate quadratic (A = 0): single root −C/B
    r3 = jnp.where((jnp.abs(A) == 0) & (jnp.abs(B) > 0), -C / jnp.where(jnp.abs(B) > 0, B, 1.0), -1.0)
    return r1, r2, r3


def step_peaks(ts, th, om):
    """max |θ| on each step from (t, θ, θ̇) at the step ends (length n − 1), maximising the cubic
    Hermite interpolant of each step in closed form. Unused (non-finite) steps give 0."""
    t0, t1 = ts[:-1], ts[1:]
    valid = jnp.isfinite(t1) & jnp.isfinite(t0) & (t1 > t0)
    safe = lambda x, fill: jnp.where(valid, x, fill)
    t0s, t1s = safe(t0, 0.0), safe(t1, 1.0)
    a0, a1 = safe(th[:-1], 0.0), safe(th[1:], 0.0)
    w0, w1 = safe(om[:-1], 0.0), safe(om[1:], 0.0)
    dt = t1s - t0s
    best = jnp.maximum(jnp.abs(a0), jnp.abs(a1))
    for r in hermite_turns(a0, a1, dt * w0, dt * w1):
        inside = (r > 0) & (r < 1)
        best = jnp.maximum(best, jnp.where(inside, jnp.abs(hermite(jnp.where(inside, r, 0.5), a0, a1, dt * w0, dt * w1)), 0.0))
    return jnp.where(valid, best, 0.0)


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
    A, B, C = hermite_slope(a0, a1, w0, w1)
    for _ in range(newton):
        f = hermite(s, a0, a1, w0, w1) - level
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


class Record(eqx.Module):
    """The running summary of a run's base rotation (module docstring)."""

    peak: Float[Array, ""]  # max |θ| so far [rad]
    t_uplift: Float[Array, ""]  # first time |θ| passed the uplift rotation (+inf: not yet)
    overturned: Bool[Array, ""]
    t_overturn: Float[Array, ""]  # +inf: not overturned

    @classmethod
    def start(cls, theta0=0.0) -> "Record":
        """Nothing seen yet, from a start at rotation θ₀."""
        dtype = jnp.result_type(float)
        inf = jnp.asarray(jnp.inf, dtype)
        return cls(jnp.abs(jnp.asarray(theta0, dtype)), inf, jnp.asarray(False), inf)

    def saw_peak(self, seen, theta) -> "Record":
        """|θ| = `theta` reached where `seen`."""
        return eqx.tree_at(lambda r: r.peak, self, jnp.where(seen, jnp.maximum(self.peak, jnp.abs(theta)), self.peak))

    def saw_uplift(self, seen, t) -> "Record":
        """Uplifted at time `t` where `seen` (the first uplift stays)."""
        return eqx.tree_at(lambda r: r.t_uplift, self, jnp.where(seen, jnp.minimum(self.t_uplift, t), self.t_uplift))

    def saw_overturn(self, seen, t) -> "Record":
        """Overturned at time `t` where `seen`."""
        return eqx.tree_at(lambda r: (r.overturned, r.t_overturn), self,
                           (self.overturned | seen, jnp.where(seen, t, self.t_overturn)))

    def overturn_located(self, hit, t) -> "Record":
        """The overturning as an integrator's event located it (`hit`, at time `t`): its time
        replaces the estimate from the step interpolants (`Watch.steps`). A crossing the
        interpolants saw and no event located still counts (a peak grazing just past the threshold
        within one step, both step ends below it: the event sees no sign change): the peak reached
        the threshold, and a result never contradicts its own flags (max_theta at the threshold is
        overturned). Its time, from the interpolants, carries no derivative: where no step
        crosses, the interpolants' crossing time has NaN partials, which reverse mode would carry
        into every gradient through the masked branch (0·NaN)."""
        return eqx.tree_at(lambda r: (r.overturned, r.t_overturn), self,
                           (hit | self.overturned, jnp.where(hit, t, jax.lax.stop_gradient(self.t_overturn))))

    def merge(self, later: "Record") -> "Record":
        """This record followed by the record of the run's next piece."""
        return Record(
            peak=jnp.maximum(self.peak, later.peak),
            t_uplift=jnp.where(jnp.isfinite(self.t_uplift), self.t_uplift, later.t_uplift),
            overturned=self.overturned | later.overturned,
            t_overturn=jnp.where(self.overturned, self.t_overturn, later.t_overturn),
        )


class Watch(eqx.Module):
    """The levels a run's base rotation is watched against, and its `Solution`.

    - `alpha`: α′ [rad], the unit of `Solution.max_theta`;
    - `threshold`: overturned at |θ| ≥ threshold·α′; max_theta is clamped to it;
    - `overturn`: the overturning rotation [rad] (threshold·α′; +inf where the body cannot
      overturn, e.g. a fixed-base column);
    - `uplift`: the uplift rotation [rad]: beyond it the body has left its rest state (the spring
      model: its spring has all but yielded, `AbstractBackbone.band` θs).
    """

    alpha: Float[Array, ""]
    threshold: Float[Array, ""]
    overturn: Float[Array, ""]
    uplift: Float[Array, ""]

    def steps(self, ts, th, om) -> Record:
        """The record of a piece of a run from (t, θ, θ̇) at its step ends (non-finite entries
        unused): the peak on the steps' interpolants; the uplift at the first step end beyond the
        uplift rotation, located on its step; overturned when a step's interpolant reaches the
        overturning rotation, located on the first such step."""
        peaks = step_peaks(ts, th, om)
        over = jnp.max(peaks) >= self.overturn
        k = jnp.argmax(peaks >= self.overturn)
        # not overturned: a valid stand-in step (an unused entry's NaN would reach reverse mode's
        # cotangents through the discarded crossing, as 0 · NaN)
        pick = lambda x, k, fill: jnp.where(over, x[k], fill)
        t_over = hermite_crossing(pick(ts, k, 0.0), pick(ts, k + 1, 1.0), pick(th, k, 0.0), pick(th, k + 1, self.overturn),
                                  pick(om, k, 0.0), pick(om, k + 1, 0.0), self.overturn)
        return Record(
            peak=jnp.max(peaks),
            t_uplift=first_exceedance(ts, th, om, self.uplift),
            overturned=over,
            t_overturn=jnp.where(over, t_over, jnp.inf),
        )

    def solution(self, record: Record, status: Status, *, ts=None, history=None, n_iterations=0, **outputs) -> Solution:
        """The run's `Solution`: the summary outputs (`jaxrock.results.SUMMARY`) from the record —
        max |θ|/α′ (the threshold once overturned, never beyond it; a non-finite peak is
        `Status.solver_failed` with NaN), overturned and uplifted with their times — and the
        `outputs` an integrator computes itself (the rigid model's `n_impacts`); an output nobody
        computes takes its `absent` value."""
        max_theta = jnp.where(record.overturned, self.threshold,
                              jnp.minimum(record.peak, self.threshold * self.alpha) / self.alpha)
        bad = ~jnp.isfinite(max_theta)
        status = Status.where(bad & (status == Status.ok), Status.solver_failed, status)
        values = {
            "max_theta": jnp.where(bad, jnp.nan, max_theta),
            "overturned": record.overturned,
            "t_overturn": record.t_overturn,
            "uplifted": jnp.isfinite(record.t_uplift),
            "t_uplift": record.t_uplift,
            **outputs,
        }
        unknown = sorted(set(values) - set(OUTPUTS))
        if unknown:
            raise TypeError(f"{unknown}: not summary outputs (jaxrock.results.SUMMARY: {', '.join(OUTPUTS)})")
        for o in SUMMARY:
            if o.name not in values:
                if o.absent is None:
                    raise TypeError(f"the summary output {o.name!r} has no value and no absent value")
                values[o.name] = jnp.asarray(o.absent, dtype=o.dtype)
        return Solution(**values, status=status, ts=ts, history=history, n_iterations=n_iterations)
