"""Vertical ground motion (`jaxrock.WithVertical`): closed forms of the rigid model (a constant
vertical acceleration is a change of g; uplift at |üg| > (g + üv) tanα), the exact uplift time of
pulses and record pairs against root finds written here, the RM against the SciPy reference with
the same vertical motion, gradients against central differences, and the one-line refusals."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from helpers import invoke

import jaxrock as jr
from jaxrock.numerics import scipy_rigid

G = 9.81  # m/s², SPEC


class Steady(jr.AbstractExcitation):
    """A constant acceleration `value` on [t0, t1], zero outside (a test's vertical component)."""

    value: jax.Array
    t0: float = eqx.field(static=True)
    t1: float = eqx.field(static=True)

    def __call__(self, t):
        t = jnp.asarray(t, dtype=float)
        return jnp.where((t >= self.t0) & (t <= self.t1), self.value, 0.0)

    @property
    def t_start(self):
        return jnp.asarray(self.t0)

    @property
    def t_end(self):
        return jnp.asarray(self.t1)

    @property
    def max_step(self):
        return jnp.asarray(jnp.inf)

    @property
    def peak(self):
        return jnp.abs(self.value)

    @property
    def step_ts(self):
        return None

    def scaled(self, factor):
        return Steady(self.value * factor, self.t0, self.t1)

    def next_exceedance(self, t, level):
        raise NotImplementedError  # a vertical component is never searched on its own


def _history(model, excitation, ts):
    sol = jr.simulate(model, excitation, save=jr.Save(jnp.asarray(ts), ("theta",)))
    assert sol.status == jr.Status.ok
    return np.asarray(sol.history["theta"]), sol


@pytest.mark.parametrize("c", [-3.0, 2.5])
def test_constant_vertical_is_a_change_of_g(c):
    """θ̈ = −p²[(1 + c/g) sin φ + (üg/g) cos φ] is the equation of a block of size R/(1 + c/g) under
    üg·g/(g + c): the same θ(t), impacts and uplift (|üg| > (g + c) tanα ⟺ |üg g/(g + c)| > g tanα)."""
    block = jr.Block.from_slenderness(6.0, 0.15)
    a_p, omega_p = jr.pulse_of_ratios(block, 1.6, 3.0)
    pulse = jr.RickerPulse(a_p, omega_p)
    t0, t1 = float(pulse.t_start), float(pulse.t_end) + 30.0
    ts = np.linspace(t0, t1 - 1.0, 801)
    theta_v, sol_v = _history(jr.RigidModel(block), jr.WithVertical(pulse, Steady(jnp.asarray(c), t0, t1)), ts)
    k = 1 + c / G
    twin = jr.Block.from_size(6.0 / k, 6.0 * 0.15 / k)  # the same α, p² × (1 + c/g)
    theta_g, sol_g = _history(jr.RigidModel(twin, eta=block.eta), jr.RickerPulse(a_p / k, omega_p), ts)
    assert 0.05 < float(sol_v.max_theta) < 1 and int(sol_v.n_impacts) >= 2  # a rocking scene, not a quiet one
    assert np.max(np.abs(theta_v - theta_g)) / float(block.alpha) < 1e-6
    assert float(sol_v.t_uplift) == pytest.approx(float(sol_g.t_uplift), abs=1e-9)


@pytest.mark.parametrize("c", [-4.0, 0.0, 4.0])
def test_uplift_threshold_with_vertical(c):
    """A body at rest uplifts exactly when max |üg| > (g + üv) tanα (SPEC, with üv)."""
    block = jr.Block.from_slenderness(4.0, 0.25)
    level = (G + c) * 0.25
    for factor, lifts in ((1 - 1e-6, False), (1 + 1e-6, True)):
        pulse = jr.RickerPulse(factor * level, 5.0)
        steady = Steady(jnp.asarray(c), float(pulse.t_start), float(pulse.t_end))
        sol = jr.simulate(jr.RigidModel(block), jr.WithVertical(pulse, steady))
        assert bool(sol.uplifted) is lifts, (c, factor)
        assert (float(sol.max_theta) > 0) is lifts


def _first_root(F, t0, t1, n=200_001):
    """The first t in [t0, t1] with F(t) > 0, by a dense scan and brentq (independent of jaxrock)."""
    grid = np.linspace(t0, t1, n)
    vals = F(grid)
    i = int(np.argmax(vals > 0))
    assert vals[i] > 0
    return brentq(F, grid[i - 1], grid[i], xtol=1e-14) if i else grid[0]


def test_uplift_time_of_a_vertical_pulse():
    """`WithVertical.uplift_time` on two pulses: the first root of |üg| − (g + üv) tanα."""
    tan_a = 0.2
    for a_v, delay in ((-5.0, 0.0), (5.0, 0.15), (8.0, -0.3)):
        ex = jr.WithVertical(jr.RickerPulse(2.6, 4.0), jr.SinePulse(a_v, 9.0, 1.5), delay)
        ug = lambda t: 2.6 * (1 - (4.0 * t) ** 2 / 2) * np.exp(-((4.0 * t) ** 2) / 4)
        uv = lambda t: np.where((t - delay >= 0) & (t - delay <= 3 * np.pi / 9.0), a_v * np.sin(9.0 * (t - delay)), 0.0)
        F = lambda t: np.abs(ug(t)) - G * tan_a * (1 + uv(t) / G)
        t0 = float(ex.t_start)
        expected = _first_root(F, t0, float(ex.t_end))
        got = float(ex.uplift_time(t0, G * tan_a))
        assert got == pytest.approx(expected, abs=1e-9), (a_v, delay)


def test_uplift_time_of_a_record_pair_is_exact():
    """A record pair (`Record(vertical=...)`) is linear on each sample interval: the uplift time is
    the linear root, from any start."""
    rng = np.random.default_rng(7)
    dt, n = 0.01, 600
    h, v = rng.normal(0, 1.5, n), rng.normal(0, 2.0, n)
    ex = jr.Record(h, dt, vertical=v)
    ts = dt * np.arange(n)
    F = lambda t: np.abs(np.interp(t, ts, h)) - G * 0.4 * (1 + np.interp(t, ts, v) / G)
    for t_from in (0.0, 0.731, 2.0):
        expected = _first_root(F, t_from, ts[-1], n=600_001)
        assert float(ex.uplift_time(t_from, G * 0.4)) == pytest.approx(expected, abs=1e-9)


SCENES = [  # (2h [m], tanα, a_p/(g tanα), ω_p/p, a_v [m/s²], ω_v/ω_p, delay·ω_p)
    (10.0, 0.2, 2.0, 3.0, 4.0, 2.0, 0.0),
    (10.0, 0.2, 2.0, 3.0, -4.0, 2.0, 0.5),
    (4.0, 0.15, 3.0, 5.0, 6.0, 1.0, -1.0),
    (20.0, 0.1, 4.0, 6.0, 3.0, 3.0, 0.3),
    (2.0, 0.3, 1.6, 2.0, 7.0, 0.5, 0.0),
    (8.0, 0.25, 2.5, 4.0, -6.0, 2.5, 1.2),
    (6.0, 0.12, 5.0, 8.0, 5.0, 1.5, -0.4),
    (12.0, 0.18, 1.3, 1.5, 8.0, 4.0, 0.0),
]


def _scene(height, tan_a, ap_ratio, wp_ratio, a_v, wv_ratio, phase):
    block = jr.Block.from_slenderness(height, tan_a)
    a_p, omega_p = jr.pulse_of_ratios(block, ap_ratio, wp_ratio)
    return block, jr.WithVertical(jr.RickerPulse(a_p, omega_p), jr.RickerPulse(a_v, wv_ratio * omega_p), phase / omega_p)


@pytest.mark.parametrize("scene", SCENES)
def test_rigid_with_vertical_against_scipy(scene):
    """The RM with a vertical pulse against the SciPy reference given the same üv (its own uplift
    scan, its own events): max θ/α and the uplift time."""
    block, ex = _scene(*scene)
    sol = jr.simulate(jr.RigidModel(block), ex)
    assert sol.status == jr.Status.ok
    h, v = ex.horizontal, ex.vertical
    f, _, _ = scipy_rigid.ricker(float(h.a_p), float(h.omega_p))
    fv, _, _ = scipy_rigid.ricker(float(v.a_p), float(v.omega_p))
    ref = scipy_rigid.solve(block, f, float(ex.t_start), float(ex.t_end), vertical_fn=lambda t: fv(np.asarray(t) - float(ex.delay)))
    assert bool(sol.overturned) == ref.overturned
    assert float(sol.max_theta) == pytest.approx(ref.max_theta, abs=2e-6)
    assert float(sol.t_uplift) == pytest.approx(ref.t_uplift, abs=1e-8)


def test_vertical_changes_the_answer():
    """The vertical component is not ignored: an upward üv at the horizontal peak stabilises, a
    downward one destabilises (gravity's restoring moment grows and shrinks)."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    a_p, omega_p = jr.pulse_of_ratios(block, 2.0, 3.0)
    pulse = jr.RickerPulse(a_p, omega_p)
    plain = float(jr.simulate(jr.RigidModel(block), pulse).max_theta)
    up = float(jr.simulate(jr.RigidModel(block), jr.WithVertical(pulse, jr.RickerPulse(3.0, omega_p))).max_theta)
    down = float(jr.simulate(jr.RigidModel(block), jr.WithVertical(pulse, jr.RickerPulse(-3.0, omega_p))).max_theta)
    assert up < plain < down


@pytest.mark.slow  # 13-15 s warm (8 scenes × grad + 2 central differences; a batch, a history and both modes)
def test_gradients_through_vertical_match_central_differences():
    """d max θ/α against the vertical amplitude a_v and the horizontal a_p, reverse mode, on the
    8 scenes, against central differences of the same runs."""
    checked = 0
    for scene in SCENES:
        block, ex = _scene(*scene)
        model = jr.RigidModel(block)

        def peak(x):
            e = eqx.tree_at(lambda e: (e.horizontal.a_p, e.vertical.a_p), ex, (x[0], x[1]))
            return jr.simulate(model, e).max_theta

        x0 = jnp.asarray([ex.horizontal.a_p, ex.vertical.a_p])
        sol = jr.simulate(model, ex)
        if bool(sol.overturned):  # max θ/α is the threshold, flat: nothing to compare
            continue
        grad = np.asarray(jax.grad(peak)(x0))
        assert np.all(np.isfinite(grad))
        for i in range(2):
            eps = 1e-5 * float(abs(x0[i]))
            e = jnp.zeros(2).at[i].set(eps)
            fd = (float(peak(x0 + e)) - float(peak(x0 - e))) / (2 * eps)
            assert grad[i] == pytest.approx(fd, rel=2e-3, abs=1e-4 / float(abs(x0[i]))), (scene, i)
        checked += 1
    assert checked >= 6


def test_vertical_refusals():
    """One line each, naming the parameter and its range."""
    pulse = jr.RickerPulse(3.0, 4.0)
    with pytest.raises(jr.JaxrockInputError, match=r"peak \|uv\| \(vertical acceleration\).*9.81"):
        jr.WithVertical(pulse, jr.RickerPulse(10.0, 4.0))
    with pytest.raises(jr.JaxrockInputError, match="a record pair is one Record"):
        jr.WithVertical(jr.Record(np.zeros(10), 0.01), pulse)
    with pytest.raises(jr.JaxrockInputError, match="vertical has 9 samples, acc 10"):
        jr.Record(np.zeros(10), 0.01, vertical=np.zeros(9))
    with pytest.raises(jr.JaxrockInputError, match=r"peak \|uv\|"):
        jr.Record(np.zeros(10), 0.01, scale=2.0, vertical=np.full(10, 5.0))
    with pytest.raises(jr.JaxrockInputError, match="one-component"):
        jr.WithVertical(jr.WithVertical(pulse, pulse), pulse)
    assert math.isinf(float(jr.WithVertical(pulse, jr.RickerPulse(1.0, 4.0)).uplift_time(0.0, 100.0)))


# -- the spring model: the same vertical motion through its own pipeline -----------------------------
FIG5 = [(0.1, 2.0), (0.2, 4.0), (0.3, -3.0)]  # (tanα, a_v [m/s²]) on figure 5's pulse, a vertical twice as fast


@pytest.mark.parametrize("tan_a, a_v", FIG5)
def test_quasi_rigid_spring_model_follows_the_rigid_model_with_vertical(tan_a, a_v):
    """Two pipelines of one system (undamped, figure 5's scene): with a vertical pulse the quasi-rigid
    SM stays within the RM tolerance of test_spring's figure 5/8 comparison, and the vertical
    component moves both models the same way by about the same amount."""
    block = jr.Block.from_slenderness(10.0, tan_a)
    pulse = jr.RickerPulse(4 * G * tan_a, 2 * math.pi)
    ex = jr.WithVertical(pulse, jr.RickerPulse(a_v, 4 * math.pi))
    tol = 0.01 + 0.12 * tan_a
    runs = {}
    for name, model in (("rm", jr.RigidModel(block, eta=1.0)), ("sm", jr.SpringModel(block, cbar=0.0))):
        runs[name] = [jr.simulate(model, e) for e in (pulse, ex)]
        assert all(s.status == jr.Status.ok for s in runs[name])
    (rm0, rmv), (sm0, smv) = ([float(s.max_theta) for s in runs[k]] for k in ("rm", "sm"))
    assert abs(smv - rmv) < tol, (smv, rmv)
    assert abs(rmv - rm0) > 0.02  # the vertical component matters on these scenes
    assert np.sign(smv - sm0) == np.sign(rmv - rm0) and abs((smv - sm0) - (rmv - rm0)) < 0.2 * abs(rmv - rm0)


def test_spring_model_energy_balance_with_vertical():
    """kinetic + potential + dissipated = input with a vertical component: its share of the
    weight's forces (column and spring) is a ground load whose work is counted as input."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    ex = jr.WithVertical(jr.RickerPulse(4 * G * 0.2, 2 * math.pi), jr.RickerPulse(5.0, 3 * math.pi), 0.2)
    ts = jnp.linspace(float(ex.t_start), float(ex.t_end) + 3.0, 400)
    fields = ("kinetic", "potential", "dissipated", "input")
    s = jr.simulate(jr.SpringModel(block), ex, save=jr.Save(ts, fields))
    assert s.status == jr.Status.ok
    H = {k: np.asarray(v) for k, v in s.history.items()}
    scale = np.max(np.abs(H["input"]))
    assert scale > 0
    assert np.max(np.abs(H["kinetic"] + H["potential"] + H["dissipated"] - H["input"])) < 1e-4 * scale


def test_flexible_column_follows_the_quasi_rigid_body_with_vertical():
    """The third pipeline: a concrete column of 4 elements (its weight's nodal forces scaled by
    1 + üv/g) against the one-DOF body under the same pair (0.6602 vs 0.6612 without üv, 0.6317 vs
    0.6324 with it when written)."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    pulse = jr.RickerPulse(4 * G * 0.2, 2 * math.pi)
    ex = jr.WithVertical(pulse, jr.RickerPulse(4.0, 4 * math.pi))
    flexible = jr.SpringModel(block, column=jr.Column(E=30e9))
    (f0, fv), (q0, qv) = ([float(jr.simulate(m, e).max_theta) for e in (pulse, ex)] for m in (flexible, jr.SpringModel(block)))
    assert abs(fv - qv) < 5e-3 and abs(f0 - q0) < 5e-3
    assert fv < f0 - 0.02 and abs((fv - f0) - (qv - q0)) < 0.1 * abs(qv - q0)


# -- the pulse kind "vertical": spectra, the command line -----------------------------------------------
def test_vertical_spectrum_uplift_line_is_the_closed_form():
    """With the vertical peak at the horizontal one (φ = 0; r κ² tanα < 1, so t = 0 is where
    |üg| − (g + üv) tanα peaks) uplift needs a_p > (g + r a_p) tanα: a_p/(g tanα) > 1/(1 − r tanα),
    at every ω_p/p. The spectrum's refined uplift line against it."""
    block = jr.Block.from_slenderness(10.0, 0.2)
    r = 0.3
    spec = jr.overturning_spectrum(jr.RigidModel(block), np.array([2.0, 5.0]), np.array([0.9, 1.2, 2.0]), pulse="vertical",
                                   pulse_params={"vertical_ratio": r, "vertical_frequency": 2.0}, refine=30, progress=False)
    np.testing.assert_allclose(np.asarray(spec.uplift_line), 1 / (1 - r * 0.2), rtol=1e-8)


def test_cli_spectrum_with_a_vertical_pulse(tmp_path):
    """`jaxrock spectrum --pulse vertical ...` runs and says so; a V/H ratio out of range is one line, exit 2."""
    out = tmp_path / "v"
    r = invoke("spectrum", "--pulse", "vertical", "--vertical-ratio", "0.3", "--vertical-frequency", "2", "--omega-ratio", "2,6",
               "--accel-ratio", "1.5,3", "--out", out)
    assert r.exit_code == 0, r.output
    assert "vertical pulse" in r.output and (tmp_path / "v.nc").exists()
    r = invoke("spectrum", "--pulse", "vertical", "--vertical-ratio", "7", "--out", out)
    assert r.exit_code == 2 and "vertical-ratio" in r.output.replace("_", "-")


def _pair(seed=11, n=1500, dt=0.01):
    """A synthetic horizontal/vertical pair: band-limited noise under an envelope, peaks 4 and 3 m/s²."""
    rng = np.random.default_rng(seed)
    t = dt * np.arange(n)
    env = (t / 3) ** 2 * np.exp(2 - 2 * t / 3)
    smooth = lambda x: np.convolve(x, np.ones(5) / 5, mode="same")
    h, v = smooth(rng.normal(size=n)) * env, smooth(rng.normal(size=n)) * env
    return 4.0 * h / np.max(np.abs(h)), 3.0 * v / np.max(np.abs(v)), dt


def test_record_pair_paced_summary_against_history_and_scipy():
    """A record pair through the paced summary path (one step attempt at a time), the segment
    loop's history and the SciPy reference: the same max θ/α and uplift time."""
    h, v, dt = _pair()
    block = jr.Block.from_slenderness(3.0, 0.15)
    rec = jr.Record(h, dt, vertical=v)
    model = jr.RigidModel(block)
    summary = jr.simulate(model, rec)
    ts = jnp.linspace(0.0, float(rec.t_end), 3001)
    history = jr.simulate(model, rec, save=jr.Save(ts, ("theta",)))
    ref = scipy_rigid.solve_record(block, h, dt, vertical_fn=lambda t: np.interp(t, dt * np.arange(h.size), v, left=0.0, right=0.0))
    assert summary.status == jr.Status.ok and history.status == jr.Status.ok
    assert float(summary.max_theta) > 0.05 and not ref.overturned
    assert float(summary.max_theta) == pytest.approx(ref.max_theta, abs=2e-6)
    assert float(history.max_theta) == pytest.approx(ref.max_theta, abs=2e-6)
    assert float(summary.t_uplift) == pytest.approx(ref.t_uplift, abs=1e-9)
    plain = jr.simulate(model, jr.Record(h, dt))
    assert abs(float(plain.max_theta) - float(summary.max_theta)) > 1e-3  # the vertical component is felt
    zero = jr.simulate(model, jr.Record(h, dt, vertical=np.zeros_like(v)))
    # two programs (the plain record's leaves the vertical terms out): their rounding differs, 2.2e-12 measured
    assert float(zero.max_theta) == pytest.approx(float(plain.max_theta), abs=1e-10)


def test_read_record_pair(tmp_path):
    """Two files of one event (their own units; the shorter padded with zeros) make one pair."""
    h, v, dt = _pair(n=400)
    (tmp_path / "h.txt").write_text("\n".join(f"{k * dt:.4f} {x / G:.12e}" for k, x in enumerate(h)))
    (tmp_path / "v.txt").write_text("\n".join(f"{k * dt:.4f} {100 * x:.12e}" for k, x in enumerate(v[:300])))
    pair = jr.read_record_pair(tmp_path / "h.txt", tmp_path / "v.txt", units=("g", "cm/s2"))
    assert pair.name == "h" and pair.n == 400
    np.testing.assert_allclose(np.asarray(pair.acc), h, rtol=1e-11)
    np.testing.assert_allclose(np.asarray(pair.vertical[:300]), v[:300], rtol=1e-11)
    assert np.all(np.asarray(pair.vertical[300:]) == 0)
    (tmp_path / "v2.txt").write_text("\n".join(f"{k * 0.02:.4f} {x:.6e}" for k, x in enumerate(v)))
    with pytest.raises(jr.JaxrockInputError, match="one sample step"):
        jr.read_record_pair(tmp_path / "h.txt", tmp_path / "v2.txt")


def test_suite_of_pairs(tmp_path):
    """A suite list names a pair as `H + V`: it runs beside a horizontal-only record (one compiled
    structure: the single record gets a zero vertical), and each run of the pair is `simulate`'s."""
    import xarray as xr

    h, v, dt = _pair(n=800)
    (tmp_path / "h.txt").write_text("\n".join(f"{k * dt:.4f} {x:.12e}" for k, x in enumerate(h)))
    (tmp_path / "v.txt").write_text("\n".join(f"{k * dt:.4f} {x:.12e}" for k, x in enumerate(v)))
    (tmp_path / "suite.list").write_text("h.txt + v.txt   # the pair\nelcentro\n")
    recs = jr.read_records([tmp_path / "suite.list"], units="m/s2")
    assert [r.vertical is not None for r in recs] == [True, False]
    r = invoke("suite", tmp_path / "suite.list", "--units", "m/s2", "--model", "rigid", "--height", "2", "--tan-alpha", "0.15",
               "--scale", "0.5:2:4", "--refine", "2", "--boot", "10", "--no-sensitivity", "--out", tmp_path / "s", "-q")
    assert r.exit_code == 0, r.output
    ds = xr.open_zarr(tmp_path / "s" / "suite.zarr").load()
    got = ds.max_theta.isel(model=0).squeeze().values[0]  # the pair's row, over the scales
    assert got.shape == ds.scale.shape
    block = jr.Block.from_slenderness(2.0, 0.15)
    want = [float(jr.simulate(jr.RigidModel(block), recs[0].scaled(s)).max_theta) for s in ds.scale.values]
    np.testing.assert_allclose(got, want, atol=1e-9)
    (tmp_path / "bad.list").write_text("h.txt + nowhere.txt\n")
    with pytest.raises(jr.JaxrockInputError, match="line 1: .*no such file: nowhere.txt"):
        jr.read_records([tmp_path / "bad.list"])


def test_cli_runs_a_record_pair(tmp_path):
    """`--record 'H + V'` (simulate, record-spectrum): the pair's run is `simulate`'s; a missing
    component is one line, exit 2."""
    h, v, dt = _pair(n=600)
    (tmp_path / "h.txt").write_text("\n".join(f"{k * dt:.4f} {x:.12e}" for k, x in enumerate(h)))
    (tmp_path / "v.txt").write_text("\n".join(f"{k * dt:.4f} {x:.12e}" for k, x in enumerate(v)))
    pair = f"{tmp_path / 'h.txt'} + {tmp_path / 'v.txt'}"
    r = invoke("simulate", "--record", pair, "--units", "m/s2", "--height", "3", "--tan-alpha", "0.15", "--json")
    assert r.exit_code == 0, r.output
    import json

    got = json.loads(r.output)
    want = jr.simulate(jr.RigidModel(jr.Block.from_slenderness(3.0, 0.15)), jr.Record(h, dt, vertical=v))
    assert abs(float(got["max_theta"]) - float(want.max_theta)) < 1e-9, got
    r = invoke("record-spectrum", "--record", pair, "--units", "m/s2", "--height", "2,4", "--scale", "0.5:2:4", "--refine", "1",
               "--no-sensitivity", "--out", tmp_path / "rs")
    assert r.exit_code == 0, r.output
    r = invoke("simulate", "--record", f"{tmp_path / 'h.txt'} + {tmp_path / 'nowhere.txt'}")
    assert r.exit_code == 2 and "nowhere.txt: file not found" in r.output and len(r.output.strip().splitlines()) == 1, r.output
