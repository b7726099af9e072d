"""A new spring integrator, written in this file only: the spring model's contract
(`jaxrock.AbstractSpringIntegrator`: the public `SpringSystem`, `SpringModel.run_end` and
`SpringModel.watch`) is enough to add one without touching the library.

Classical RK4 at a fixed step on the system's first-order form (`SpringSystem.vector_field`), the
run recorded by the shared bookkeeping (`Watch.steps` on each step, `Record.merge`), a summary
stopped by `SpringSystem.settled`. Checked against the default Tsit5 at 1e-10 through `simulate`
and through the batch engine (`overturning_spectrum`); its error falls as h⁴ (RK4's order on
the smooth tanh spring once the step resolves the pre-yield band).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.bookkeeping import Record


class FixedRK4(jr.AbstractSpringIntegrator):
    dt: float = eqx.field(static=True, default=2e-3)
    max_steps: int = eqx.field(static=True, default=200_000)

    def stepper(self, model, system, save=None, t1=None):
        if save is not None:
            raise jr.JaxrockInputError("FixedRK4 gives summaries only")
        return FixedRK4Stepper(self, model, system, t1)


class FixedRK4Stepper(jr.AbstractStepper):
    integrator: FixedRK4
    model: jr.SpringModel
    system: jr.SpringSystem
    t1: object

    @property
    def max_steps(self):
        return self.integrator.max_steps

    @property
    def checkpointed(self):
        return False

    def init(self, exc):
        return dict(t=jnp.asarray(exc.t_start, float), y=self.system.initial_state(), rec=Record.start(),
                    done=jnp.asarray(False), steps=jnp.zeros((), jnp.int32))

    def step(self, exc, c):
        sys_, h = self.system, self.integrator.dt
        f = lambda t, y: sys_.vector_field(t, y, exc)
        t, y = c["t"], c["y"]
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y1, t1 = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + h
        N = sys_.ndof
        watch = self.model.watch(sys_)
        rec = c["rec"].merge(watch.steps(jnp.stack([t, t1]), jnp.stack([y[0], y1[0]]), jnp.stack([y[N], y1[N]])))
        settled = (t1 >= exc.t_end) & sys_.settled(sys_.mechanical_energy(y1), rec.peak)
        done = rec.overturned | settled | (t1 >= self.model.run_end(sys_, exc, None, self.t1))
        return dict(t=t1, y=y1, rec=rec, done=done, steps=c["steps"] + 1)

    def done(self, c):
        return c["done"] | (c["steps"] >= self.max_steps)

    def finish(self, exc, c):
        status = jr.Status.where(c["done"], jr.Status.ok, jr.Status.max_steps)
        return self.model.watch(self.system).solution(c["rec"], status, n_iterations=c["steps"])


BLOCK = jr.Block.from_slenderness(height=10.0, tan_alpha=0.2)
MODEL = jr.SpringModel(BLOCK, smoothing=1e-3)  # a softer spring than the default: RK4 resolves it at these steps
REF = jr.SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5")


def _pulse(accel, omega):
    return jr.RickerPulse(a_p=accel * BLOCK.uplift_acceleration, omega_p=omega * BLOCK.p_r)


@pytest.mark.parametrize("accel,omega", [(2.0, 3.0), (4.0, 6.0), (3.0, 10.0)])
def test_a_newcomer_spring_integrator_agrees_with_the_default(accel, omega):
    ref = jr.simulate(MODEL, _pulse(accel, omega), integrator=REF)
    errs = []
    for dt in (4e-3, 2e-3):
        sol = jr.simulate(MODEL, _pulse(accel, omega), integrator=FixedRK4(dt=dt))
        assert sol.status == jr.Status.ok and bool(sol.overturned) == bool(ref.overturned)
        assert abs(float(sol.t_uplift) - float(ref.t_uplift)) < 1e-3
        errs.append(abs(float(sol.max_theta) - float(ref.max_theta)))
    assert errs[1] < 1e-3, errs
    assert errs[1] < errs[0] / 4 or errs[1] < 1e-7, errs  # converges (h⁴ in the smooth regime)


def test_a_newcomer_spring_integrator_runs_in_the_batch_engine():
    """The batch engine (vmapped, one `solve` per lane: the stepper has no passes) gives what
    `simulate` gives, cell by cell (the first test ties `simulate` to the reference)."""
    wr, ar = np.array([3.0, 10.0]), np.array([2.0, 4.0])
    rk4 = FixedRK4(dt=2e-3)
    spec = jr.overturning_spectrum(MODEL, wr, ar, integrator=rk4, progress=False)
    assert spec.ok
    for i, a in enumerate(ar):
        for j, w in enumerate(wr):
            sol = jr.simulate(MODEL, _pulse(a, w), integrator=rk4)
            assert abs(float(sol.max_theta) - spec.max_theta[i, j]) < 1e-9
            assert bool(sol.overturned) == spec.overturned[i, j] and bool(sol.uplifted) == spec.uplifted[i, j]
