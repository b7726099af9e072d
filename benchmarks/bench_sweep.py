"""Sweeps from a laptop to a cluster (issue 26): scenes per second against local devices, Dask
workers and chunk size, with the memory per scene.

    python benchmarks/bench_sweep.py [--quick]

The scene set: a rigid-model pulse sweep (symmetric Ricker) over 2h ∈ {2, 5, 10, 20} m ×
a_p/(g tanα) ∈ [0.5, 10] × ω_p/p ∈ [1, 15] (48 × 48 each: 9216 scenes), tanα = 0.2, a model per
scene within a chunk (2h varies in it). Every row runs in its own process (forced host devices are
set before JAX starts) with the compilation cache of this run: the first run compiles and warms
it, then the best of three warm runs is timed, each into a fresh store where a store is written
(times on this machine wander 10-20 % over minutes).

- devices: 1, 2, 4 forced host devices (`XLA_FLAGS=--xla_force_host_platform_device_count=N`),
  a chunk per device at a time (`sweep.on_devices`), in memory;
- workers: a Dask `LocalCluster` of 1 or 2 worker processes (1 thread each) writing one Zarr store,
  against the same sweep in one process writing its store;
- chunk size: 256, 1024, 4096 scenes per chunk, one process, one device, writing the store; the
  process's peak resident memory and the store's bytes on disk per scene;
- the whole command `jaxrock sweep` cold (compilation cache off) and warm.

The printed table is also written to benchmarks/results/bench_sweep.txt.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
LINES: list[str] = []

CHILD = r"""
import json, os, resource, sys, time
import numpy as np
args = json.loads(sys.argv[1])
import jax
import jaxrock as jr
from jaxrock.analyses.sweep import Sweep, run_sweep
n = args["n"]
sw = Sweep.make("rigid", height=[2.0, 5.0, 10.0, 20.0], accel_ratio=np.linspace(0.5, 10, n), omega_ratio=np.linspace(1, 15, n),
                chunk_size=args["chunk"])
client = cluster = None
if args.get("workers"):
    import distributed
    cluster = distributed.LocalCluster(n_workers=args["workers"], threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=None)
    client = distributed.Client(cluster)
store = args.get("store")
def run(tag):
    path = None if store is None else f"{store}-{tag}.zarr"
    t = time.perf_counter()
    ds = run_sweep(sw, path, client=client, progress=False)
    return time.perf_counter() - t, ds, path
cold, ds, _ = run("cold")
warm, ds, path = min((run(f"warm{i}") for i in range(3)), key=lambda r: r[0])
disk = None if path is None else sum(f.stat().st_size for f in __import__("pathlib").Path(path).rglob("*") if f.is_file())
print("RESULT " + json.dumps({"scenes": sw.size, "chunks": sw.n_chunks, "chunk": int(np.prod(sw.chunk_shape)), "cold": cold, "warm": warm,
      "devices": len(jax.local_devices()), "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
      "disk_per_scene": None if disk is None else disk / sw.size, "overturned": int(ds.overturned.sum()),
      "ok": bool((ds.status.values == 0).all())}))
if client is not None:
    client.close(); cluster.close()
"""


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def child(env_extra: dict, **args) -> dict:
    env = {**os.environ, "JAX_PLATFORMS": "cpu", **env_extra}
    r = subprocess.run([sys.executable, "-c", CHILD, json.dumps(args)], env=env, capture_output=True, text=True, timeout=1800)
    line = next((x for x in r.stdout.splitlines() if x.startswith("RESULT ")), None)
    if r.returncode != 0 or line is None:
        raise RuntimeError(f"child {args} failed:\n{r.stderr[-3000:]}")
    return json.loads(line[7:])


def command(args: list[str], env_extra: dict, cwd: str) -> float:
    t = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "jaxrock.cli", *args], env={**os.environ, "JAX_PLATFORMS": "cpu", **env_extra}, cwd=cwd,
                       capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        raise RuntimeError(r.stderr[-2000:])
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="12 × 12 per size instead of 48 × 48 (a smoke run, not for the results file)")
    opts = ap.parse_args()
    n = 12 if opts.quick else 48
    tmp = tempfile.mkdtemp(prefix="bench_sweep_")
    cache = {"JAXROCK_CACHE_DIR": os.path.join(tmp, "cache")}
    out(f"# bench_sweep: rigid pulse sweep, 4 sizes × {n} × {n} = {4 * n * n} scenes; {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} CPU cores, python {platform.python_version()}")
    out("# scenes/s: best of 3 warm runs (the first run in the same process compiled; Dask workers compile once each)")
    out()
    out("| setting | chunks × scenes | scenes/s (warm) | speed-up | first run [s] | peak RSS [MB] | store [B/scene] |")
    out("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    base = None
    for d in (1, 2, 4):
        r = child({**cache, "XLA_FLAGS": f"--xla_force_host_platform_device_count={d}"}, n=n, chunk=1024)
        rate = r["scenes"] / r["warm"]
        base = base or rate
        out(f"| {d} forced host device(s), in memory | {r['chunks']} × {r['chunk']} | {rate:,.0f} | {rate / base:.2f} | {r['cold']:.1f} | "
            f"{r['rss_mb']:.0f} | – |")
    one = child(cache, n=n, chunk=1024, store=os.path.join(tmp, "one"))
    rate1 = one["scenes"] / one["warm"]
    out(f"| 1 process, store | {one['chunks']} × {one['chunk']} | {rate1:,.0f} | 1.00 | {one['cold']:.1f} | {one['rss_mb']:.0f} | "
        f"{one['disk_per_scene']:.1f} |")
    for w in (1, 2):
        r = child(cache, n=n, chunk=1024, store=os.path.join(tmp, f"dask{w}"), workers=w)
        rate = r["scenes"] / r["warm"]
        out(f"| Dask LocalCluster, {w} worker process(es), store | {r['chunks']} × {r['chunk']} | {rate:,.0f} | {rate / rate1:.2f} | "
            f"{r['cold']:.1f} | (client) {r['rss_mb']:.0f} | {r['disk_per_scene']:.1f} |")
    for c in (256, 1024, 4096):
        r = child(cache, n=n, chunk=c, store=os.path.join(tmp, f"chunk{c}"))
        rate = r["scenes"] / r["warm"]
        out(f"| chunk size {c}, 1 process, store | {r['chunks']} × {r['chunk']} | {rate:,.0f} | {rate / rate1:.2f} | {r['cold']:.1f} | "
            f"{r['rss_mb']:.0f} | {r['disk_per_scene']:.1f} |")
    out()
    args = ["sweep", "--height", "2,5,10,20", "--accel-ratio", f"0.5:10:{n}", "--omega-ratio", f"1:15:{n}", "-q"]
    cold = command([*args, "--out", os.path.join(tmp, "cli-cold.zarr")], {"JAXROCK_CACHE_DIR": "off"}, tmp)
    command([*args, "--out", os.path.join(tmp, "cli-warmup.zarr")], cache, tmp)
    warm = command([*args, "--out", os.path.join(tmp, "cli-warm.zarr")], cache, tmp)
    out(f"whole command `jaxrock {' '.join(args)}`: cold (cache off) {cold:.1f} s, warm (cache filled) {warm:.1f} s")
    shutil.rmtree(tmp, ignore_errors=True)
    if not opts.quick:
        (HERE / "results" / "bench_sweep.txt").write_text("\n".join(LINES) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
