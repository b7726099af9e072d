"""Sweeps (`jaxrock.analyses.sweep`, `jaxrock sweep`): the same numbers as the spectra and as single
runs, a store that survives real signals and resumes to the same bits, refusals in one line, the
scenes sharded over forced host devices and spread over a real Dask cluster with the same bits."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import xarray as xr
from helpers import Watch, invoke, jaxrock_process

import jaxrock as jr
from jaxrock.analyses.sweep import Sweep, run_sweep
from jaxrock.outputs import OUTPUTS

FIELDS = (*OUTPUTS, "status")


def _same(a: xr.Dataset, b: xr.Dataset):
    """Every output and coordinate of two sweeps equal bit for bit (NaN where NaN)."""
    for name in (*FIELDS, *a.coords):
        x, y = a[name].values, b[name].values
        assert x.dtype == y.dtype and x.shape == y.shape, name
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.int64), y.view(np.int64)), f"{name} differs"
        else:
            assert np.array_equal(x, y), f"{name} differs"


def _short_record(seconds: float, name: str, dt=0.01):
    """A record a rigid block rocks under within its few seconds (one sine cycle of 2 Hz, 0.5 g)."""
    t = np.arange(0.0, seconds, dt)
    acc = np.where(t < 0.5, 0.5 * jr.G * np.sin(4 * np.pi * t), 0.0)
    return jr.Record(acc, dt, name=name)


def test_pulse_sweep_is_the_spectrum(tmp_path):
    """A pulse sweep of one model, in chunks of 8 cells, is `overturning_spectrum` bit for bit; the
    store holds what the in-memory run returns, and says how it was made."""
    wr, ar = np.linspace(1.0, 12.0, 6), np.linspace(0.8, 8.0, 5)
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    spec = jr.overturning_spectrum(model, wr, ar, progress=False)
    sw = Sweep.make("rigid", accel_ratio=ar, omega_ratio=wr, chunk_size=8)
    assert sw.chunk_shape == (1, 6) and sw.n_chunks == 5
    mem = run_sweep(sw, progress=False)
    for name in FIELDS:
        got, want = mem[name].values, getattr(spec, name)
        assert np.array_equal(got, want, equal_nan=got.dtype.kind == "f"), name
    stored = run_sweep(sw, tmp_path / "s.zarr", progress=False)
    _same(stored, mem)
    made = json.loads(stored.attrs["made_by"])
    assert made["model kind"] == "rigid" and made["fixed height"] == "10.0" and made["excitation"] == "RickerPulse"
    assert made["model.eta"] == str(np.asarray(model.eta)) and "12." in made["grid omega_ratio"]
    assert stored.attrs["jax_version"] and stored.chunk_done.values.tolist() == [1] * 5
    assert xr.open_zarr(tmp_path / "s.zarr", chunks=None).max_theta.encoding["chunks"] == (1, 6)  # one Zarr chunk per sweep chunk


def test_a_sweep_with_sensitivity_is_the_spectrum_with_it_and_keeps_its_own_store(tmp_path):
    """`Sweep(..., sensitivity=True)`: the spectrum's sensitivities and uncertain flags, cell for cell
    (the same batches); its store says so, and a store made without them is refused, not resumed."""
    wr, ar = np.linspace(1.0, 12.0, 4), np.linspace(0.8, 8.0, 3)
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    spec = jr.overturning_spectrum(model, wr, ar, progress=False, sensitivity=True)
    sw = Sweep.make("rigid", accel_ratio=ar, omega_ratio=wr, chunk_size=4, sensitivity=True)
    ds = run_sweep(sw, tmp_path / "s.zarr", progress=False)
    np.testing.assert_allclose(ds.sensitivity.values, spec.sensitivity, rtol=1e-9)
    assert np.all(np.isfinite(ds.sensitivity.values)) and np.array_equal(ds.uncertain.values, spec.uncertain)
    assert json.loads(ds.attrs["made_by"])["sensitivity"] == "True"
    plain = Sweep.make("rigid", accel_ratio=ar, omega_ratio=wr, chunk_size=4)
    with pytest.raises(jr.JaxrockInputError):
        run_sweep(plain, tmp_path / "s.zarr", progress=False)


def test_record_sweep_over_sizes_matches_single_runs():
    """Two records of different lengths × 2 sizes × 2 slendernesses × 2 factors, a chunk holding
    several models (vmapped models): each scene as `jaxrock.simulate` gives it (to the event
    integrator's round-off), flags consistent with max θ/α."""
    recs = [_short_record(3.0, "short"), _short_record(4.5, "long")]
    sw = Sweep.make("rigid", records=recs, height=[1.0, 4.0], tan_alpha=[0.1, 0.2], scale=[0.6, 1.4], chunk_size=8)
    assert sw.dims == ("record", "height", "tan_alpha", "scale") and sw.chunk_shape == (1, 2, 2, 2)
    ds = run_sweep(sw, progress=False)
    assert (ds.status.values == 0).all()
    assert ds.overturned.any() and (~ds.overturned).any() and ds.uplifted.any()
    assert np.array_equal(ds.overturned.values, ds.max_theta.values == 1.0)
    for i, rec in enumerate(recs):
        for j, h in enumerate(sw.axes["height"]):
            for k, ta in enumerate(sw.axes["tan_alpha"]):
                for m, s in enumerate(sw.axes["scale"]):
                    sol = jr.simulate(jr.RigidModel(jr.Block.from_slenderness(h, ta)), rec.scaled(s))
                    cell = ds.isel(record=i, height=j, tan_alpha=k, scale=m)
                    assert bool(cell.overturned) == bool(sol.overturned)
                    assert float(cell.max_theta) == pytest.approx(float(sol.max_theta), abs=1e-9)


def test_sweep_refuses_bad_values_in_one_line(tmp_path):
    for args, words in (
        (["--tan-alpha", "0.2,1.5"], "--tan-alpha = 1.5"),
        (["--eta", "0.5"], "--eta applies to --model rigid"),  # fine for rigid: no error expected below
        (["--model", "spring", "--eta", "0.5"], "--eta applies to --model rigid only"),
        (["--scale", "2"], "--scale applies to record sweeps"),
        (["--record", str(tmp_path)], "holds no record file"),
        (["--accel-ratio", "0,1"], "--accel-ratio"),
        (["--height", "5", "--tan-alpha", "0.3", "--tan-alpha-base", "0.2"], "tan_alpha_base"),
        (["--model", "spring-flexible", "--youngs-modulus", "1e3,3e10"], "--youngs-modulus (Young's modulus) [Pa] = 1000 is outside the valid range [1e+06, 1e+15]"),
        (["--scheduler", "-q"], "--scheduler '-q': not a scheduler address"),  # a flag taken for the address
    ):
        if args == ["--eta", "0.5"]:
            continue
        r = invoke("sweep", *args, "--out", str(tmp_path / "x.zarr"))
        assert r.exit_code == 2, (args, r.output)
        assert words in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not (tmp_path / "x.zarr").exists()


def _finish(proc) -> int:
    proc.communicate(timeout=240)
    return proc.returncode


SWEEP = ["sweep", "--accel-ratio", "0.8:8:6", "--omega-ratio", "1:12:6", "--chunk-size", "1", "-q"]
# 144 one-scene chunks: the signal, sent once the progress bar shows 2-19 done, must arrive before
# the last chunk ends (36 chunks once all ended first, in a loaded CI run: kept 36 of 36)
KILL_SWEEP = ["sweep", "--accel-ratio", "0.8:8:12", "--omega-ratio", "1:12:12", "--chunk-size", "1", "-q"]


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_killed_sweep_resumes_to_the_same_bits(tmp_path, sig):
    """A real `jaxrock sweep` process stopped by a real signal after its first chunks (SIGINT: at the
    next chunk, exit 130 and the resume command; SIGKILL: at once), then rerun with the same
    command: the store equals an uninterrupted run's, bit for bit."""
    whole = tmp_path / "whole.zarr"
    rc = _finish(jaxrock_process(*KILL_SWEEP, "--out", whole, cwd=tmp_path))
    assert rc == 0
    cut = tmp_path / "cut.zarr"
    w = Watch(jaxrock_process(*KILL_SWEEP[:-1], "--out", cut, cwd=tmp_path))  # with its progress bar, to see it run
    w.wait_for(r"\b([2-9]|1[0-9])/144")
    w.proc.send_signal(sig)
    rc, out, err = w.finish()
    kept = int(xr.open_zarr(cut, chunks=None).chunk_done.sum())
    assert 0 < kept < 144, f"the stop came too late or too early: {kept} of 144 chunks"
    if sig == signal.SIGINT:
        assert rc == 130 and f"interrupted: {kept} of 144 chunks kept in" in err and "resume with: jaxrock sweep" in err
    else:
        assert rc == -signal.SIGKILL
    rc = _finish(jaxrock_process(*KILL_SWEEP, "--out", cut, cwd=tmp_path))
    assert rc == 0
    a, b = xr.open_zarr(whole, chunks=None), xr.open_zarr(cut, chunks=None)
    _same(a, b)
    assert a.attrs["made_by"] == b.attrs["made_by"]


def test_store_of_another_sweep_or_garbled_is_refused(tmp_path):
    store = tmp_path / "s.zarr"
    r = invoke(*SWEEP, "--out", str(store))
    assert r.exit_code == 0, r.output
    r = invoke(*SWEEP, "--tan-alpha", "0.25", "--out", str(store))
    assert r.exit_code == 2 and "was made by a different run (fixed tan_alpha: 0.2 → 0.25, model.block.b: 1. → 1.25" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
    (store / "zarr.json").write_text("{ not json")
    r = invoke(*SWEEP, "--out", str(store))
    assert r.exit_code == 2 and "is unreadable or not a jaxrock sweep" in r.output and len(r.output.strip().splitlines()) == 1


DAMAGE_SWEEP = ["sweep", "--accel-ratio", "1:8:4", "--omega-ratio", "2:10:4", "--height", "5,10", "--chunk-size", "8", "-q"]


@pytest.mark.parametrize("damage", ["remove max_theta", "remove overturned", "flip a byte of max_theta", "remove a flag"])
def test_a_damaged_store_is_named_and_its_chunk_run_again(tmp_path, damage):
    """Issue 52: with one chunk file of a finished store removed, a resume said "0 run … 32 were in the
    store already" and kept 8 NaN max_theta with status ok (or overturned all False, "6 scenes" for
    10). Now every chunk file has a CRC-32C and a file even when it equals the fill value: the
    damaged chunk is named with its variable and file, run again and counted as run, and the store
    ends equal to the undamaged one bit for bit."""
    store = tmp_path / "s.zarr"
    r = invoke(*DAMAGE_SWEEP, "--out", store)
    assert r.exit_code == 0, r.output
    whole = xr.open_zarr(store, chunks=None).load()
    what = damage.split()[-1]
    chunk_file = sorted((store / ("chunk_done" if what == "flag" else what) / "c").rglob("*"))
    chunk_file = [f for f in chunk_file if f.is_file()][1]
    if damage.startswith("flip"):
        data = bytearray(chunk_file.read_bytes())
        data[len(data) // 2] ^= 0x10
        chunk_file.write_bytes(bytes(data))
    else:
        chunk_file.unlink()
    r = invoke(*DAMAGE_SWEEP, "--out", store)
    assert r.exit_code == 0, r.output
    assert "8 run in" in r.output and "(24 were in the store already)" in r.output, r.output
    if what != "flag":
        key = chunk_file.relative_to(store).as_posix()
        assert f"chunk 1 is damaged ({what}: chunk file {key} is " in r.output, r.output
    _same(xr.open_zarr(store, chunks=None).load(), whole)
    r = invoke(*DAMAGE_SWEEP, "--out", store)
    assert "0 run in" in r.output and "is damaged" not in r.output, r.output


_SHARDED = textwrap.dedent("""
    import jax, numpy as np
    import jaxrock as jr
    from jaxrock.analyses import sweep as sweep_module
    from jaxrock.analyses.engine import run_batch
    from jaxrock.analyses.sweep import Sweep, run_sweep
    assert len(jax.local_devices()) == 4
    used, run_chunk = set(), sweep_module.run_chunk
    sweep_module.run_chunk = lambda sw, k, devices: used.add(devices[0].id) or run_chunk(sw, k, devices)
    same = lambda x, y: np.array_equal(np.asarray(x).view(np.uint8), np.asarray(y).view(np.uint8))
    for sw in (Sweep.make("rigid", height=[2.0, 8.0], accel_ratio=np.linspace(0.8, 8, 5), omega_ratio=np.linspace(1, 12, 6), chunk_size=8),
               Sweep.make("spring", accel_ratio=[1.5, 4.0, 7.0], omega_ratio=np.linspace(2, 10, 5), chunk_size=4)):
        one = run_sweep(sw, devices=jax.local_devices()[:1], progress=False)
        used.clear()
        four = run_sweep(sw, progress=False)
        assert len(used) == 4, used  # a chunk per device at a time
        for name in ("max_theta", "t_uplift", "t_overturn", "overturned", "uplifted", "n_impacts", "status"):
            assert same(one[name].values, four[name].values), (sw.model, name)
        assert (one.status.values == 0).all() and one.overturned.any()
    # a record suite: its sweep's chunks (a record each) over the devices, then its bisection
    sw = Sweep.make("rigid", records=jr.read_records(["builtin"])[:3], height=[1.0, 4.0], tan_alpha=0.2, scale=np.linspace(0.5, 2.5, 5))
    used.clear()
    one, four = (jr.least_overturning_scale(sw, refine=3, progress=False, devices=d) for d in (jax.local_devices()[:1], None))
    assert len(used) == 3 and same(one.least_scale.values, four.least_scale.values) and same(one.max_theta.values, four.max_theta.values)
    # a batch's passes sharded over the four devices (`NamedSharding`, explicit devices): each device
    # runs its block at a quarter of the batch size, so the last bits may move as in another batch
    # (`run_batch`: 1e-10); here one cell by one ulp
    m = jr.RigidModel(jr.Block.from_slenderness(3.0, 0.2))
    pulses = jax.vmap(jr.RickerPulse)(np.linspace(1.0, 6.0, 24), np.linspace(2.0, 12.0, 24))
    a, b = run_batch(m, pulses), run_batch(m, pulses, devices=jax.local_devices())
    assert np.array_equal(a.overturned, b.overturned) and np.max(np.abs(a.max_theta - b.max_theta)) <= 1e-10
    print("SAME BITS")
""")


def test_sharded_over_four_host_devices_is_bit_identical():
    """A sweep over 4 forced host devices runs a chunk per device at a time (each from its own
    thread) and gives one device's bits: the rigid model with a model per scene, the quasi-rigid
    spring model (refilled lanes). A batch's passes sharded over them (a 1-D mesh): one device's
    numbers to the bound of another batch size."""
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=4", "JAX_PLATFORMS": "cpu"}
    r = subprocess.run([sys.executable, "-c", _SHARDED], env=env, capture_output=True, text=True, timeout=280)
    assert r.returncode == 0 and "SAME BITS" in r.stdout, r.stderr[-3000:]


def test_dask_cluster_writes_the_same_store_even_when_a_worker_is_killed(tmp_path):
    """A `LocalCluster` of two worker processes on 127.0.0.1, joined by `jaxrock sweep --scheduler`,
    writes the store one process writes, bit for bit; a worker killed by SIGKILL while chunks are
    in flight has its chunks run again."""
    distributed = pytest.importorskip("distributed")
    sw = Sweep.make("rigid", height=[3.0, 9.0], accel_ratio=np.linspace(0.8, 8, 4), omega_ratio=np.linspace(1, 12, 4), chunk_size=4)
    assert sw.n_chunks == 8
    here = run_sweep(sw, tmp_path / "here.zarr", progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        r = invoke("sweep", "--height", "3,9", "--accel-ratio", "0.8:8:4", "--omega-ratio", "1:12:4", "--chunk-size", "4", "-q",
                   "--out", str(tmp_path / "cluster.zarr"), "--scheduler", cluster.scheduler_address)
        assert r.exit_code == 0 and f"on Dask cluster {cluster.scheduler_address}" in r.output, r.output
        there = xr.open_zarr(tmp_path / "cluster.zarr", chunks=None)
        _same(here, there)
        assert there.attrs["made_by"] == here.attrs["made_by"]
        pids = list(client.run(os.getpid).values())
        assert len(set(pids)) == 2 and os.getpid() not in pids
        seen = []

        def kill_one(k):
            seen.append(k)
            if len(seen) == 1:
                os.kill(pids[0], signal.SIGKILL)

        again = run_sweep(sw, tmp_path / "killed.zarr", client=client, progress=False, on_chunk=kill_one)
        assert len(seen) == 8
        assert len(set(client.run(os.getpid).values()) & set(pids)) == 1  # the killed worker was replaced
    _same(here, again)


@pytest.mark.parametrize("given", ["", ".", ".."])
def test_store_naming_no_folder_of_its_own_is_refused(tmp_path, monkeypatch, given):
    """Issue 52: `--store ""` and `--store .` (now --out) were tracebacks (Path('.').with_name)."""
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", "--accel-ratio", "1:8:2", "--omega-ratio", "2:10:2", "--out", given, "-q")
    assert r.exit_code == 2 and "names the current or a parent folder, not a store" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1 and not list(tmp_path.iterdir())


@pytest.mark.parametrize("address, needle", [("garbage", "not a scheduler address"), ("", "not a scheduler address"),
                                             ("tcp://127.0.0.1:1", "no Dask scheduler answers there")])
def test_scheduler_that_is_no_address_or_answers_nothing_is_one_line(tmp_path, address, needle):
    """Issue 52: `--scheduler garbage` or `""` waited 10 s, printed a clean line, then a
    `Client.__del__` traceback after a 20 s close timeout. The address is now checked and probed
    before any Dask client exists: one line, exit 2, within seconds, no store made."""
    pytest.importorskip("distributed")
    r = invoke("sweep", "--accel-ratio", "1:8:2", "--omega-ratio", "2:10:2", "--out", tmp_path / "s.zarr", "-q", "--scheduler", address)
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not (tmp_path / "s.zarr").exists()


def test_a_sweep_of_a_trillion_chunks_starts_resumes_and_stops_at_once(tmp_path):
    """Issue 52: a sweep of 10¹⁵ scenes (9.8e11 chunks) acknowledged SIGTERM and ran on for minutes
    (its chunk flags were read whole, 1 TB, and its to-do list built in full; once a MemoryError).
    The flags beyond 2^24 chunks are read from the flag files present, the to-do list is lazy, and
    a stop asked before the first chunk ends the run at once with the finished chunks counted."""
    import time

    from jaxrock import interrupt
    from jaxrock.io import store as zstore

    axis = lambda a, b: np.linspace(a, b, 100_000)
    sw = Sweep.make("rigid", accel_ratio=axis(0.5, 10), omega_ratio=axis(1, 15), height=axis(1, 10))
    assert sw.n_chunks > 1e11
    path = tmp_path / "huge.zarr"
    zstore.open_for(path, sw)
    for k in (0, 7):
        zstore.write_chunk(path, sw, k, {name: np.zeros(sw.chunk_shape, dtype=dtype)
                                         for name, (dtype, _, _) in zstore._variables().items()})
    t0 = time.perf_counter()
    assert zstore.survey(path, sw) == ({0, 7}, {})
    with interrupt.deferred_signals():
        interrupt._pending = signal.SIGTERM
        with pytest.raises(interrupt.Interrupted):
            run_sweep(sw, path, progress=False)
    assert zstore.flagged(path, sw) == {0, 7}
    assert time.perf_counter() - t0 < 20


@pytest.mark.parametrize("kind, pulse", [("rigid", "sine"), ("spring", "antisymmetric"), ("spring-flexible", "symmetric")])
def test_scene_of_builds_under_vmap_what_each_route_builds(kind, pulse):
    """`jaxrock.scene_of`, the one constructor of (model, pulse) from flat values, vmapped over
    seeded scenes: each lane is, leaf for leaf, the model and pulse built one at a time from the
    kind's builder and the pulse's class, and a sweep's chunk (which builds with it) holds the
    same scenes; each lane runs to `simulate`'s result on its own scene."""
    import jax
    import jax.numpy as jnp

    rng = np.random.default_rng(5700)
    n = 4
    values = {"height": rng.uniform(2, 30, n), "tan_alpha": rng.uniform(0.1, 0.3, n), "accel_ratio": rng.uniform(1, 5, n),
              "omega_ratio": rng.uniform(1, 8, n)}
    if kind == "rigid":
        values["eta"] = rng.uniform(0.7, 1.0, n)
    else:
        values["cbar"] = rng.uniform(0.0, 0.2, n)
    if pulse == "sine":
        values["n_cycles"] = rng.integers(1, 6, n) / 2
    models, pulses = jax.vmap(lambda v: jr.scene_of(kind, pulse, v))({k: jnp.asarray(v) for k, v in values.items()})
    for i in range(n):
        one = {k: float(v[i]) for k, v in values.items()}
        block = jr.Block.from_slenderness(one["height"], one["tan_alpha"])
        params = {k: one[k] for k in ("eta", "cbar") if k in one}
        model = jr.scene.MODEL_KINDS[kind].model(block, **params)
        a_p, w_p = jr.pulse_of_ratios(block, one["accel_ratio"], one["omega_ratio"])
        exc = jr.scene.pulse_class(pulse)(a_p, w_p, **({"n_cycles": one["n_cycles"]} if pulse == "sine" else {}))
        for got, want in ((models, model), (pulses, exc)):
            lane = jax.tree_util.tree_map(lambda x: x[i], got)
            assert jax.tree_util.tree_structure(lane) == jax.tree_util.tree_structure(want)
            for x, y in zip(jax.tree_util.tree_leaves(lane), jax.tree_util.tree_leaves(want)):
                np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=1e-15, atol=0)
    if kind == "rigid":
        sol = jr.run_batch(models, pulses, model_batched=True)
        for i in range(n):
            lane = jax.tree_util.tree_map(lambda x: x[i], (models, pulses))
            assert abs(float(sol.max_theta[i]) - float(jr.simulate(*lane).max_theta)) <= 1e-9
    sw = Sweep.make(kind, pulse=pulse, height=values["height"][0], tan_alpha=values["tan_alpha"][0],
                    accel_ratio=values["accel_ratio"], omega_ratio=values["omega_ratio"][0],
                    **({"n_cycles": values["n_cycles"][0]} if pulse == "sine" else {}))
    v = sw.chunk_values(0)
    built = sw._excitations(v, sw._models(v, batched=True), batched=True)
    same = jax.vmap(lambda vv: jr.scene_of(kind, pulse, vv)[1])({k: jnp.asarray(x) for k, x in v.items()})
    for x, y in zip(jax.tree_util.tree_leaves(built), jax.tree_util.tree_leaves(same)):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
