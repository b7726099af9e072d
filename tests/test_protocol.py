"""The run-loop protocol (`jaxrock.AbstractStepper`), proved by a newcomer's model.

A linear oscillator that "overturns" past an amplitude is written here, in this file only, as a
user would write a new model: an `AbstractModel` whose `stepper` gives init / step / done / finish,
registered as a model kind for scenes files. It then runs through `simulate`,
`overturning_spectrum` (passes with the running cells gathered between them) and `run_scenes`
without any change to those, and every entry point agrees with an independent SciPy solve of the
same equation and with each other.

    θ̈ + 2ζ p θ̇ + p² θ = −p² üg(t)/g     (static response to a steady üg: θ = −üg/g)

integrated by classical RK4 at a fixed step h = (2π/p)/`per_period` (a loop step is `substeps`
RK4 steps); max |θ| is taken at the step points; "overturned" once |θ| ≥ threshold·α′.
"""

from __future__ import annotations

import csv
import re
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jaxrock as jr
from jaxrock.scene import MODEL_KINDS

G = 9.81


class RK4(jr.AbstractIntegrator):
    per_period: int = eqx.field(static=True, default=200)
    substeps: int = eqx.field(static=True, default=8)
    max_steps: int = eqx.field(static=True, default=4096)

    def stepper(self, model, system=None, save=None, t1=None):
        if save is not None:
            raise jr.JaxrockInputError("the oscillator gives summaries only")
        return OscillatorStepper(model, self)


class Oscillator(jr.AbstractModel):
    block: jr.Block
    zeta: jax.Array = 0.05  # (AbstractModel declares block and threshold: fields after them need defaults)
    threshold: float = 1.0

    def default_integrator(self):
        return RK4()

    @property
    def history_fields(self):
        return ()

    def stepper(self, integrator, save=None, t1=None):
        if not isinstance(integrator, RK4):
            raise jr.JaxrockInputError(f"the oscillator needs RK4, got {type(integrator).__name__}")
        return integrator.stepper(self, None, save, t1)

    def rhs(self, t, y, excitation):
        p = self.block.p_r
        return jnp.stack([y[1], -2 * self.zeta * p * y[1] - p**2 * y[0] - p**2 * excitation(t) / G])


class OscillatorStepper(jr.AbstractStepper):
    model: Oscillator
    integrator: RK4

    @property
    def max_steps(self):
        return self.integrator.max_steps

    @property
    def checkpointed(self):
        return True

    @property
    def schedule(self):
        return jr.Schedule(passes=(2, 4), smallest_batch=4)

    def h(self):
        return 2 * jnp.pi / self.model.block.p_r / self.integrator.per_period

    def t_stop(self, excitation):
        return excitation.t_end + 3 * 2 * jnp.pi / self.model.block.p_r  # three free periods

    def init(self, excitation):
        z = jnp.zeros(())
        # the end time rides in the state: `done` sees the state only
        return dict(t=jnp.asarray(excitation.t_start, float), t_stop=self.t_stop(excitation), y=jnp.zeros(2), peak=z,
                    over=jnp.asarray(False),
                    t_over=jnp.asarray(jnp.inf), t_up=jnp.asarray(jnp.inf), n=jnp.zeros((), jnp.int32))

    def step(self, excitation, s):
        h, m = self.h(), self.model
        limit = m.threshold * m.block.alpha_r
        t_stop = s["t_stop"]

        def rk4(_, s):
            t, y = s["t"], s["y"]
            f = lambda tt, yy: m.rhs(tt, yy, excitation)
            k1 = f(t, y)
            k2 = f(t + h / 2, y + h / 2 * k1)
            k3 = f(t + h / 2, y + h / 2 * k2)
            k4 = f(t + h, y + h * k3)
            y1 = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            a1 = jnp.abs(y1[0])
            go = ~s["over"] & (t < t_stop)
            over = a1 >= limit
            new = dict(t=t + h, t_stop=t_stop, y=y1, peak=jnp.maximum(s["peak"], a1), over=over,
                       t_over=jnp.where(over, t + h, s["t_over"]),
                       t_up=jnp.where(jnp.isinf(s["t_up"]) & (a1 > 1e-3 * m.block.alpha_r), t + h, s["t_up"]), n=s["n"])
            return jax.tree_util.tree_map(lambda a, b: jnp.where(go, a, b), new, s)

        s = jax.lax.fori_loop(0, self.integrator.substeps, rk4, s)
        return dict(s, n=s["n"] + 1)

    def done(self, s):
        return s["over"] | (s["t"] >= s["t_stop"]) | (s["n"] >= self.max_steps)

    def finish(self, excitation, s):
        m = self.model
        finished = s["over"] | (s["t"] >= s["t_stop"])
        status = jr.Status.where(finished, jr.Status.ok, jr.Status.max_iterations)
        peak = jnp.where(s["over"], m.threshold, jnp.minimum(s["peak"] / m.block.alpha_r, m.threshold))
        return jr.Solution(max_theta=peak, overturned=s["over"], t_overturn=s["t_over"], uplifted=jnp.isfinite(s["t_up"]),
                           t_uplift=s["t_up"], n_impacts=jnp.zeros((), jnp.int32), sensitivity=jnp.asarray(jnp.nan),
                           uncertain=jnp.asarray(False), status=status,
                           n_iterations=s["n"])


# -- the newcomer's reference: SciPy on the same equation, sampled at the same step points ---------
def reference_peak(model: Oscillator, excitation) -> tuple[float, bool]:
    """max |θ|/α′ at the RK4 step points by DOP853 at rtol 1e-12, and whether it overturned."""
    integ = model.default_integrator()
    p, alpha = float(model.block.p_r), float(model.block.alpha_r)
    zeta = float(model.zeta)
    h = 2 * math.pi / p / integ.per_period
    t0, t_stop = float(excitation.t_start), float(excitation.t_end) + 3 * 2 * math.pi / p
    ug = jax.jit(excitation.__call__)
    ts = t0 + h * np.arange(1, int(math.ceil((t_stop - t0) / h - 1e-9)) + 1)
    sol = solve_ivp(lambda t, y: [y[1], -2 * zeta * p * y[1] - p**2 * y[0] - p**2 * float(ug(t)) / G], (t0, ts[-1]),
                    [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14 * alpha, t_eval=ts)
    a = np.abs(sol.y[0]) / alpha
    over = a >= model.threshold
    return (float(model.threshold) if over.any() else float(a.max())), bool(over.any())


BLOCK = jr.Block.from_slenderness(10.0, 0.2)
OSC = Oscillator(BLOCK, zeta=jnp.asarray(0.05))


@pytest.fixture
def oscillator_kind():
    """The oscillator as a scenes-file model kind, for this test only: `zeta` its one parameter,
    declared with its own meaning, range and default (not the concrete column's)."""
    build = lambda block, zeta=0.05: Oscillator(block, zeta=jnp.asarray(zeta, dtype=float))
    zeta = jr.Param("zeta", "oscillator damping ratio", "–", 0.0, 2.0, default=0.05)
    yield jr.register_model_kind("oscillator", build, (zeta,), "a linear oscillator (test)")
    MODEL_KINDS.pop("oscillator")


@pytest.mark.parametrize("accel_ratio, omega_ratio", [(0.5, 1.0), (0.9, 3.0), (2.0, 1.0)])
def test_simulate_runs_the_newcomer_and_matches_scipy(accel_ratio, omega_ratio):
    exc = jr.RickerPulse(accel_ratio * float(BLOCK.uplift_acceleration), omega_ratio * float(BLOCK.p_r))
    sol = jr.simulate(OSC, exc)
    ref, over = reference_peak(OSC, exc)
    assert sol.ok and bool(sol.overturned) == over
    assert abs(float(sol.max_theta) - ref) < 1e-7 * max(ref, 1e-3)
    # a result never contradicts its flags
    assert bool(sol.uplifted) or not bool(sol.overturned)
    assert (float(sol.max_theta) == OSC.threshold) == bool(sol.overturned)


def test_gradient_through_the_newcomer_is_finite_and_right():
    """Reverse mode through `simulate`'s checkpointed loop: d max θ / d a_p against central differences."""
    w = 3.0 * float(BLOCK.p_r)
    f = lambda a: jr.simulate(OSC, jr.RickerPulse(a, w)).max_theta
    a0, da = 0.6 * float(BLOCK.uplift_acceleration), 1e-5
    g = float(jax.grad(f)(a0))
    fd = (float(f(a0 + da)) - float(f(a0 - da))) / (2 * da)
    assert np.isfinite(g) and abs(g - fd) < 1e-6 * abs(fd)


def test_spectrum_of_the_newcomer_equals_simulate_cell_by_cell():
    """`overturning_spectrum` drives the oscillator in passes of 2, then 4 steps, gathering the
    running cells between passes: every cell equals its own `simulate`."""
    wr, ar = np.array([0.5, 1.0, 3.0]), np.array([0.2, 0.8, 1.5, 3.0])
    spec = jr.overturning_spectrum(OSC, wr, ar, batch_size=8, progress=False)
    assert spec.ok and not spec.contradictions().any()
    assert spec.overturned.any() and not spec.overturned.all()
    for i, a in enumerate(ar):
        for j, w in enumerate(wr):
            sol = jr.simulate(OSC, jr.RickerPulse(a * float(BLOCK.uplift_acceleration), w * float(BLOCK.p_r)))
            assert abs(spec.max_theta[i, j] - float(sol.max_theta)) <= 1e-12
            assert spec.overturned[i, j] == bool(sol.overturned)


def test_run_scenes_runs_the_registered_newcomer(tmp_path, oscillator_kind):
    """A scenes file names the registered kind; its `zeta` column reaches the model (an empty cell:
    the oscillator's own default, 0.05; before the parameters were declared per kind, the concrete
    column's 0.01), checked against the oscillator's own range ([0, 2]: 3 is refused, though the
    column's zeta takes it); a rigid-only column on an oscillator row is refused in one line."""
    scenes = tmp_path / "scenes.csv"
    rows = [(10.0, 0.2, 0.5, 1.0, ""), (10.0, 0.2, 2.0, 1.0, "0.2"), (5.0, 0.15, 0.9, 3.0, "")]
    scenes.write_text("height,tan_alpha,model,accel_ratio,omega_ratio,zeta\n"
                      + "".join(f"{h},{t},oscillator,{a},{w},{z}\n" for h, t, a, w, z in rows))
    report = jr.run_scenes(scenes, tmp_path / "out.csv", progress=False)
    assert report.status_counts == {"ok": 3}
    got = list(csv.DictReader(open(tmp_path / "out.csv")))
    for (h, t, a, w, z), rec in zip(rows, got):
        blk = jr.Block.from_slenderness(h, t)
        model = Oscillator(blk, zeta=jnp.asarray(float(z) if z else 0.05))
        sol = jr.simulate(model, jr.RickerPulse(a * float(blk.uplift_acceleration), w * float(blk.p_r)))
        assert abs(float(rec["max_theta"]) - float(sol.max_theta)) <= 1e-12
        assert rec["overturned"] == str(int(bool(sol.overturned)))
    bad = tmp_path / "bad.csv"
    bad.write_text("height,tan_alpha,model,accel_ratio,omega_ratio,eta\n10,0.2,oscillator,1,1,0.9\n")
    with pytest.raises(jr.JaxrockInputError, match="eta.*applies only to model rigid"):
        jr.run_scenes(bad, tmp_path / "bad_out.csv", progress=False)
    bad.write_text("height,tan_alpha,model,accel_ratio,omega_ratio,zeta\n10,0.2,oscillator,1,1,3\n")
    with pytest.raises(jr.JaxrockInputError, match=r"zeta.*valid range \[0, 2\]"):
        jr.run_scenes(bad, tmp_path / "bad_out.csv", progress=False)


@pytest.mark.parametrize("model, integrator, needs", [
    (jr.RigidModel(BLOCK), jr.GeneralizedAlpha(), "RigidModel needs an EventIntegrator"),
    (jr.SpringModel(BLOCK), jr.EventIntegrator(), "SpringModel needs a SpringIntegrator, GeneralizedAlpha or Checked"),
    (OSC, jr.EventIntegrator(), "the oscillator needs RK4"),
])
def test_a_model_refuses_an_integrator_it_cannot_run(model, integrator, needs):
    """While tracing, before any compilation: one line naming what the model needs."""
    with pytest.raises(jr.JaxrockInputError, match=needs):
        jr.simulate(model, jr.RickerPulse(3.0, 6.0), integrator=integrator)


def test_a_sweep_varies_the_newcomers_own_parameter(oscillator_kind):
    """The oscillator's own `zeta` (declared with `jaxrock.Param`: range [0, 2], default 0.05) is a
    sweep quantity: a sweep over it runs each scene as `simulate` does with that damping (more
    damping, less rotation), 3 is refused against the oscillator's own range, and a value the
    column's zeta would take but the rigid model does not is refused for `rigid`."""
    from jaxrock.analyses.sweep import Sweep, run_chunk

    zetas = np.array([0.02, 0.3])
    sw = Sweep.make("oscillator", height=10.0, tan_alpha=0.2, zeta=zetas, accel_ratio=0.6, omega_ratio=1.0)
    assert sw.axes["zeta"].tolist() == zetas.tolist()
    got = run_chunk(sw, 0)["max_theta"].ravel()
    for z, value in zip(zetas, got):
        sol = jr.simulate(Oscillator(BLOCK, zeta=jnp.asarray(z)), jr.RickerPulse(0.6 * float(BLOCK.uplift_acceleration), float(BLOCK.p_r)))
        assert abs(value - float(sol.max_theta)) <= 1e-12
    assert got[1] < got[0]
    from jaxrock.io.store import _coordinates

    assert _coordinates(sw)["zeta"][2]["long_name"] == "oscillator damping ratio"  # its store names its own zeta
    with pytest.raises(jr.JaxrockInputError, match=r"zeta.*\[0, 2\]"):
        Sweep.make("oscillator", zeta=[0.1, 3.0], accel_ratio=0.6, omega_ratio=1.0)
    with pytest.raises(jr.JaxrockInputError, match="zeta applies to model spring-flexible / oscillator only, not rigid"):
        Sweep.make("rigid", zeta=[0.1], accel_ratio=0.6, omega_ratio=1.0)


# -- the newcomer as another package's plugin: registered in its own module, reaching the command line --
PLUGIN = '''
import jax.numpy as jnp
import jaxrock as jr
from test_protocol import Oscillator


def build(block, zeta=0.05, threshold=1.0):
    return Oscillator(block, zeta=jnp.asarray(zeta, dtype=float), threshold=jnp.asarray(threshold, dtype=float))


jr.register_model_kind("oscillator", build, (
    jr.Param("zeta", "oscillator damping ratio", "–", 0.0, 2.0, default=0.05),
    jr.Param("threshold", "amplitude θ/α′ counted as overturning", "–", 0.0, 10.0, lo_open=True, default=1.0),
), "a linear oscillator (test)")
'''


def _jaxrock(tmp_path, *args, plugins="oscillator_plugin"):
    import os
    import subprocess
    import sys
    from pathlib import Path

    env = {**os.environ, "JAXROCK_PLUGINS": plugins,
           "PYTHONPATH": os.pathsep.join([str(tmp_path), str(Path(__file__).parent), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", "jaxrock.cli", *args], capture_output=True, text=True, env=env, cwd=tmp_path,
                          timeout=600)


@pytest.fixture
def oscillator_plugin(tmp_path, monkeypatch):
    """The oscillator registered by a module of its own (`JAXROCK_PLUGINS` names it; a package
    would name it by an entry point), with a parameter no built-in kind has, `threshold`."""
    import importlib
    import sys

    (tmp_path / "oscillator_plugin.py").write_text(PLUGIN)
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.import_module("oscillator_plugin")
    yield tmp_path
    MODEL_KINDS.pop("oscillator")
    sys.modules.pop("oscillator_plugin")


def test_a_plugin_kind_and_its_own_parameter_reach_every_entry_point(oscillator_plugin):
    """No file of jaxrock edited: the plugin's `threshold` is a flag of `jaxrock simulate`, `sweep`
    and `spectrum` (help and all), a scenes-file column and a sweep quantity, each run equal to
    `simulate` of the model the plugin builds; it is refused for the rigid model, and a plugin that
    cannot be imported stops the command line in one line, exit 2."""
    tmp = oscillator_plugin
    osc = lambda zeta=0.05, threshold=1.0: Oscillator(BLOCK, zeta=jnp.asarray(zeta), threshold=jnp.asarray(threshold))
    pulse = lambda a, w: jr.RickerPulse(a * float(BLOCK.uplift_acceleration), w * float(BLOCK.p_r))
    # jaxrock simulate: its flag, its own default (zeta 0.05) when not given, overturning at its own threshold
    for args, model, exc in ((("--threshold", "0.5", "--accel-ratio", "0.4", "--omega-ratio", "1"), osc(threshold=0.5), pulse(0.4, 1)),
                             (("--zeta", "0.3", "--accel-ratio", "0.6", "--omega-ratio", "1"), osc(zeta=0.3), pulse(0.6, 1))):
        r = _jaxrock(tmp, "simulate", "--model", "oscillator", *args)
        assert r.returncode == 0, r.stderr
        sol = jr.simulate(model, exc)
        printed = float(next(line for line in r.stdout.splitlines() if line.startswith("max θ/α")).split("=")[1])
        assert abs(printed - float(sol.max_theta)) <= 1e-5 * float(sol.max_theta)
        assert f"overturned: {'yes' if bool(sol.overturned) else 'no'}" in r.stdout
    assert bool(jr.simulate(osc(threshold=0.5), pulse(0.4, 1)).overturned) and not bool(jr.simulate(osc(), pulse(0.4, 1)).overturned)
    # jaxrock sweep over the plugin's parameter: a store whose every scene is simulate's
    r = _jaxrock(tmp, "sweep", "--model", "oscillator", "--threshold", "0.2,0.5", "--accel-ratio", "0.1,0.4", "--omega-ratio", "1",
                 "--out", "s.zarr", "-q")
    assert r.returncode == 0, r.stderr
    import xarray as xr

    ds = xr.open_zarr(tmp / "s.zarr")
    assert ds.threshold.attrs["long_name"] == "amplitude θ/α′ counted as overturning"
    for th in (0.2, 0.5):
        for a in (0.1, 0.4):
            got = float(ds.max_theta.sel(threshold=th, accel_ratio=a).squeeze())
            assert abs(got - float(jr.simulate(osc(threshold=th), pulse(a, 1)).max_theta)) <= 1e-12
    # jaxrock spectrum: a grid of cells, each simulate's
    r = _jaxrock(tmp, "spectrum", "--model", "oscillator", "--threshold", "0.5", "--omega-ratio", "1:3:2", "--accel-ratio",
                 "0.5:2:2", "--refine", "0", "--out", "sp", "-q")
    assert r.returncode == 0, r.stderr
    sp = xr.open_dataset(tmp / "sp.nc")
    for a in sp.accel_ratio.values:
        for w in sp.omega_ratio.values:
            got = float(sp.max_theta.sel(accel_ratio=a, omega_ratio=w))
            assert abs(got - float(jr.simulate(osc(threshold=0.5), pulse(a, w)).max_theta)) <= 1e-12
    # a scenes file names it and its columns (empty: its own defaults)
    scenes = tmp / "scenes.csv"
    scenes.write_text("height,tan_alpha,model,accel_ratio,omega_ratio,threshold,zeta\n10,0.2,oscillator,0.4,1,0.5,\n10,0.2,oscillator,0.4,1,,0.3\n")
    jr.run_scenes(scenes, tmp / "out.csv", progress=False)
    got = [float(rec["max_theta"]) for rec in csv.DictReader(open(tmp / "out.csv"))]
    want = [float(jr.simulate(m, pulse(0.4, 1)).max_theta) for m in (osc(threshold=0.5), osc(zeta=0.3))]
    assert want[0] == 0.5 and np.allclose(got, want, rtol=0, atol=1e-12)  # vmapped rows: round-off apart
    # refused in one line, exit 2: its flag on another kind, its own range, a plugin that is not there
    for args, plugins, says in ((("simulate", "--threshold", "0.5"), "oscillator_plugin", "--threshold applies to --model oscillator only, not rigid"),
                                (("simulate", "--model", "oscillator", "--threshold", "0"), "oscillator_plugin", r"threshold = 0 .*\(0, 10\]"),
                                (("sweep", "--model", "oscillator", "--zeta", "3", "--accel-ratio", "1", "--omega-ratio", "1", "--out", "z.zarr"),
                                 "oscillator_plugin", r"zeta = 3 .*\[0, 2\]"),
                                (("simulate", "--help"), "no_such_plugin", "JAXROCK_PLUGINS module 'no_such_plugin' could not be loaded")):
        r = _jaxrock(tmp, *args, plugins=plugins)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and re.search(says, r.stderr), r.stderr
    assert "--threshold" in _jaxrock(tmp, "sweep", "--help").stdout
