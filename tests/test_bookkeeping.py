"""The run bookkeeping every integrator shares (`jaxrock.bookkeeping`): peak, uplift and overturn
located on the steps' cubic Hermite interpolants, a run's record as the merge of its pieces' records,
and the `Solution` it gives (clamped to the threshold, never NaN with status ok)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrock import Status
from jaxrock.bookkeeping import Record, Watch

A, W = 0.3, 2.0  # θ(t) = A sin(W t): a free swing with a known peak and known crossing times


def _swing(n):
    ts = jnp.linspace(0.0, 1.2, n)  # past the peak at t = π/(2W) ≈ 0.785
    return ts, A * jnp.sin(W * ts), A * W * jnp.cos(W * ts)


def _watch(uplift=0.1, overturn=0.25):
    return Watch(alpha=jnp.asarray(0.2), threshold=jnp.asarray(overturn / 0.2), overturn=jnp.asarray(overturn), uplift=jnp.asarray(uplift))


@pytest.mark.parametrize("n", [7, 13, 25])
def test_crossings_and_peak_converge_at_fourth_order(n):
    """Coarse steps: the Hermite peak and crossing times converge to the closed forms as dt⁴."""
    ts, th, om = _swing(n)
    steps = eqx.filter_jit(lambda w, *a: w.steps(*a))
    rec = steps(_watch(overturn=0.35), ts, th, om)  # never reaches 0.35
    dt = float(ts[1] - ts[0])
    assert abs(float(rec.peak) - A) < 0.05 * dt**4 * A * W**4
    assert abs(float(rec.t_uplift) - np.arcsin(0.1 / A) / W) < 0.05 * dt**4 * W**3
    assert not bool(rec.overturned) and np.isinf(float(rec.t_overturn))
    rec = steps(_watch(overturn=0.25), ts, th, om)
    assert bool(rec.overturned)
    assert abs(float(rec.t_overturn) - np.arcsin(0.25 / A) / W) < 0.05 * dt**4 * W**3


def test_a_run_is_the_merge_of_its_pieces():
    """Generalized-α records step by step, diffrax by phase: both must equal the whole run's record."""
    ts, th, om = _swing(40)
    watch = _watch()
    whole = watch.steps(ts, th, om)

    def piece(rec, k):
        take = lambda x: jax.lax.dynamic_slice(x, (k,), (2,))
        return rec.merge(watch.steps(take(ts), take(th), take(om))), None

    rec, _ = jax.lax.scan(piece, Record.start(th[0]), jnp.arange(len(ts) - 1))
    for a, b in zip((whole.peak, whole.t_uplift, whole.overturned, whole.t_overturn), (rec.peak, rec.t_uplift, rec.overturned, rec.t_overturn)):
        assert float(a) == float(b)


def test_solution_never_contradicts_its_flags():
    watch = _watch()
    ts, th, om = _swing(25)
    sol = watch.solution(watch.steps(ts, th, om), Status.ok)
    assert bool(sol.overturned) and float(sol.max_theta) == float(watch.threshold)  # threshold once overturned
    assert bool(sol.uplifted) and float(sol.t_uplift) < float(sol.t_overturn)
    bad = Record.start().saw_peak(True, jnp.nan)
    sol = watch.solution(bad, Status.ok)
    assert sol.status == Status.solver_failed and np.isnan(float(sol.max_theta))
