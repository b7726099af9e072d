"""Summary runs on sampled records go sample by sample (`RigidStepper._attempt`, issue 53). Checked
against the generic event loop (the same record behind an excitation that is not a `Record`, which
`simulate` runs through diffrax's `diffeqsolve` with events) and the SciPy event loop, on synthetic
records that no benchmark uses; gradients in both modes against central differences; a record
padded to a longer array (a suite's longest) runs as itself."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrock as jr
from jaxrock.analyses import kernels
from jaxrock.analyses.engine import run_batch
from jaxrock.geometry import G
from jaxrock.numerics import scipy_rigid as sr
from jaxrock.rigid.event_integrator import RECORD_TOLERANCES


class Unpaced(jr.AbstractExcitation):
    """A record seen through the generic excitation interface: runs take the diffrax event loop."""

    rec: jr.Record

    def __call__(self, t):
        return self.rec(t)

    @property
    def t_start(self):
        return self.rec.t_start

    @property
    def t_end(self):
        return self.rec.t_end

    @property
    def max_step(self):
        return self.rec.max_step

    @property
    def step_ts(self):
        return self.rec.step_ts

    def next_exceedance(self, t, level):
        return self.rec.next_exceedance(t, level)


def synthetic(seed: int, seconds: float, dt: float) -> jr.Record:
    """Low-passed white noise under a rise-and-decay envelope, peak 1 m/s² (a record no benchmark uses)."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds / dt)) + 1
    t = dt * np.arange(n)
    width = max(1, int(round(0.05 / dt)))
    noise = np.convolve(rng.standard_normal(n + width), np.ones(width) / width, mode="same")[:n]
    acc = noise * (t / 2.0) ** 2 * np.exp(-t / 2.0)
    return jr.Record(acc / np.max(np.abs(acc)), dt, name=f"synthetic{seed}")


RECORDS = [synthetic(1, 12.0, 0.01), synthetic(2, 8.0, 0.005)]
FACTORS = [1.3, 1.8, 2.5, 3.5, 5.0, 8.0]  # peak |üg| / (g tanα′)


def _scenes(rec, height):
    m = jr.RigidModel(jr.Block.from_slenderness(height, 0.2))
    scales = np.asarray(FACTORS) * float(m.block.uplift_acceleration)
    return m, scales, jax.vmap(rec.scaled)(jnp.asarray(scales))


@pytest.mark.parametrize("rec", RECORDS, ids=lambda r: r.name)
def test_paced_runs_agree_with_the_event_loop_and_scipy(rec):
    """Paced runs at their defaults (the record tolerances, rtol 1e-12) against the event loop at
    the same tolerances: within 1e-6 of α′, the same verdicts. Both against SciPy: every cell whose
    answer is determined (SciPy at rtol 1e-10 and 1e-12 within 1e-8 of α′ and 1e-8 s) within 1e-6
    of it, the same verdict. (At the pulse default, rtol 1e-8, one cell here, 2h = 3 m at 2.5 × the
    uplift level, ends 1.75e-5 off in both loops: one impact fewer is resolved before the peak.)"""
    determined, rocking, overturned = 0, 0, 0
    same = jr.EventIntegrator(rtol=RECORD_TOLERANCES[0], atol=RECORD_TOLERANCES[1])
    for height in (1.0, 3.0):
        m, scales, excs = _scenes(rec, height)
        paced, generic = run_batch(m, excs), run_batch(m, jax.vmap(Unpaced)(excs), same)
        assert np.all(np.asarray(jr.status_codes(paced.status)) == 0)
        assert np.array_equal(np.asarray(paced.overturned), np.asarray(generic.overturned))
        assert np.max(np.abs(np.asarray(paced.max_theta) - np.asarray(generic.max_theta))) <= 1e-6
        for i, s in enumerate(scales):
            refs = [sr.solve_record(m.block, np.asarray(rec.acc), float(rec.dt), s, rtol=r, atol=r * 1e-2) for r in (1e-10, 1e-12)]
            if (abs(refs[0].max_theta - refs[1].max_theta) > 1e-8 or refs[0].overturned != refs[1].overturned
                    or abs(refs[0].t_overturn - refs[1].t_overturn) > 1e-8):
                continue
            determined += 1
            ref = refs[1]
            for sol in (paced, generic):
                assert bool(sol.overturned[i]) == ref.overturned, (rec.name, height, s)
                assert abs(float(sol.max_theta[i]) - ref.max_theta) <= 1e-6, (rec.name, height, s, float(sol.max_theta[i]), ref.max_theta)
                if ref.overturned and ref.n_rest == 0:  # (after a Zeno closure to rest, the two loops'
                    # closures differ: 2.7e-4 s at rtol 1e-13 on one cell here, the same in both of jaxrock's loops)
                    assert abs(float(sol.t_overturn[i]) - ref.t_overturn) <= 1e-6
            rocking += ref.n_impacts > 0
            overturned += ref.overturned
    assert determined >= 9 and rocking >= 4 and overturned >= 1, (determined, rocking, overturned)


@pytest.mark.parametrize("autodiff", ["reverse", "forward"])
def test_paced_gradients_match_central_differences(autodiff):
    """d(max|θ|/α′)/d(scale) through impacts, apexes and the closing free flight."""
    rec = RECORDS[0]
    m = jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2))
    integ = m.default_integrator(autodiff=autodiff)
    f = jax.jit(lambda s: jr.simulate(m, rec.scaled(s), integrator=integ).max_theta)
    s0 = 1.8 * float(m.block.uplift_acceleration)
    assert 0.05 < float(f(s0)) < 0.9  # rocking, several impacts, no overturning
    grad = jax.grad(f)(s0) if autodiff == "reverse" else jax.jvp(f, (s0,), (1.0,))[1]
    h = 1e-5 * s0
    fd = (f(s0 + h) - f(s0 - h)) / (2 * h)
    fd2 = (f(s0 + 2 * h) - f(s0 - 2 * h)) / (4 * h)
    assert abs(float(fd) - float(fd2)) < 1e-4 * abs(float(fd))  # smooth here: the differences agree
    assert np.isfinite(float(grad)) and abs(float(grad) - float(fd)) < 1e-4 * abs(float(fd)), (float(grad), float(fd))


def test_a_padded_record_runs_as_itself():
    """Zeros appended to the array (`Record.padded`) change neither the end nor any output."""
    rec = RECORDS[1]
    padded = rec.padded(rec.n + 777)
    assert padded.n == rec.n + 777 and float(padded.t_end) == float(rec.t_end)
    m, scales, excs = _scenes(rec, 1.0)
    a = run_batch(m, excs)
    b = run_batch(m, jax.vmap(padded.scaled)(jnp.asarray(scales)))
    for name in ("max_theta", "t_overturn", "t_uplift"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert np.allclose(x, y, rtol=0, atol=1e-12, equal_nan=True), name
    assert np.array_equal(np.asarray(a.n_impacts), np.asarray(b.n_impacts))
    with pytest.raises(jr.JaxrockInputError, match="cannot pad"):
        rec.padded(rec.n - 1)


def test_a_record_that_never_reaches_the_level_ends_at_once():
    """Below the uplift level the run is decided by the one search at its start: no steps."""
    rec = RECORDS[0]
    m = jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2))
    sol = jr.simulate(m, rec.scaled(0.99 * float(m.block.uplift_acceleration)))
    assert float(sol.max_theta) == 0.0 and not bool(sol.overturned) and int(sol.n_iterations) == 0
    assert float(m.block.uplift_acceleration) == pytest.approx(G * float(jnp.tan(m.block.alpha_r)))
    assert eqx.is_array(rec.length) and int(rec.length) == rec.n


def _programs(fn) -> int:
    """How many run-loop programs (`kernels.advance`'s, keyed by shapes and structure) `fn()` adds."""
    before = set(kernels._KERNELS)
    fn()
    return len(set(kernels._KERNELS) - before)


@pytest.mark.parametrize("via", ["sweep", "scenes file"])
def test_a_suite_of_distinct_lengths_compiles_what_one_record_does(via, tmp_path):
    """Records padded to the suite's longest under one name (`Sweep`, scenes files): three records
    of three lengths (none used elsewhere) compile no more programs than one record alone."""
    d = 0.0 if via == "sweep" else 0.3  # lengths of their own for each case: no program shared with the other
    one = [synthetic(21, 9.99 + d, 0.01)]
    three = [synthetic(22, 10.49 + d, 0.01), synthetic(23, 5.19 + d, 0.005), synthetic(24, 21.07 + d, 0.02)]
    assert len({r.n for r in three} | {one[0].n}) == 4

    def run(records):
        if via == "sweep":
            sweep = jr.Sweep.make("rigid", records=records, height=[1.0, 3.0], tan_alpha=0.2, scale=[0.5, 2.0, 4.0])
            return lambda: jr.run_sweep(sweep, progress=False)
        rows = ["model,height,tan_alpha,pulse,scale"]
        for r in records:
            path = tmp_path / f"{r.name}.txt"
            np.savetxt(path, np.column_stack([np.asarray(r.times), np.asarray(r.acc)]))
            rows += [f"rigid,{h},0.2,{path.name},{s}" for h in (1.0, 3.0) for s in (0.5, 2.0, 4.0)]
        scenes = tmp_path / f"scenes{len(records)}.csv"
        scenes.write_text("\n".join(rows) + "\n")
        return lambda: jr.run_scenes(scenes, tmp_path / f"results{len(records)}.csv", progress=False)

    alone, suite = _programs(run(one)), _programs(run(three))
    assert 0 < suite <= alone, (alone, suite)


def test_a_paced_summary_agrees_with_its_history_run():
    """The summary of a paced run against the history run of the same scene (the event loop with
    dense output, `Save`): the same uplift time and verdict, and the history's largest |θ| on a
    1 ms grid just below the summary's peak, which the events locate between grid points."""
    rec = RECORDS[0]
    m = jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2))
    ts = jnp.arange(0.0, float(rec.t_end) + 2.0, 1e-3)
    for factor in (1.3, 1.8):
        exc = rec.scaled(factor * float(m.block.uplift_acceleration))
        summary = jr.simulate(m, exc)
        hist = jr.simulate(m, exc, save=jr.Save(ts=ts))
        assert bool(summary.overturned) == bool(hist.overturned) is False
        assert float(summary.t_uplift) == pytest.approx(float(hist.t_uplift), abs=1e-9)
        peak = float(np.max(np.abs(np.asarray(hist.history["theta"])))) / float(m.block.alpha_r)
        assert 0.0 <= float(summary.max_theta) - peak < 2e-5, (float(summary.max_theta), peak)


def test_spring_pieces_step_on_the_same_samples_as_one_whole_grid():
    """The quasi-rigid SM's pieces carry only the record's samples that they can reach
    (`Record.step_ts_from`), not the whole grid: the steps, hence the outputs, are the same bits as
    with the whole grid (an excitation without the window), for the record and for the record
    padded to a suite's longest. (The solver steps the pre-yield phase in both: the exact phase
    runs on a sampled record's grid, which the unpaced wrapper hides.)"""
    rec = RECORDS[1]
    m = jr.SpringModel(jr.Block.from_slenderness(1.0, 0.2))
    integ = jr.SpringIntegrator(1e-10, 1e-10, solver="tsit5", max_steps=200_000, exact_rest=False)
    scales = jnp.asarray(FACTORS[:4]) * float(m.block.uplift_acceleration)
    whole = run_batch(m, jax.vmap(lambda s: Unpaced(rec.scaled(s)))(scales), integ)
    assert np.all(np.asarray(whole.uplifted)) and not np.all(np.asarray(whole.overturned))
    for r in (rec, rec.padded(3 * rec.n)):
        windowed = run_batch(m, jax.vmap(r.scaled)(scales), integ)
        for name in ("max_theta", "t_overturn", "t_uplift"):
            assert np.array_equal(np.asarray(getattr(windowed, name)), np.asarray(getattr(whole, name))), name
