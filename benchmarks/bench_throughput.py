"""Throughput on the workloads users run: ordered grids against random scene sets, batch sizes
from 4096 to 65536 (and up to 2^20 where a GPU is lent), mixed sizes and slendernesses.

    python benchmarks/bench_throughput.py [--sizes 4096,16384,65536] [--spring-sizes 1024,256] [--repeat 3] [--quick] [--out FILE]

JAX gets one CPU device per core (`jaxrock.use_cpu_cores`, as the command line; `--cores 1`: one),
so `run_batch` deals a batch's cells over them. Rows (warm µs per scene = the best of `--repeat` more calls / scenes; first call = compilation included;
stored kernels off, `JAXROCK_CACHE_DIR=off`):
- RM, 2h = 10 m, tanα = 0.2, symmetric Ricker pulse, a_p/(g tanα) ∈ [0.5, 10], ω_p/p ∈ [1, 15]:
  `overturning_spectrum` on the 64 × 64 grid; `run_batch` on the same 4096 grid cells; `run_batch` on
  uniform random sets of each `--sizes`; a random set (the least of `--sizes`, at most 4096) of mixed blocks (2h ∈ [2, 50] m, tanα ∈
  [0.1, 0.35], both pulse shapes, one model per scene).
- Quasi-rigid SM (the same block, default integrator): 1024 random scenes; flexible SM (concrete,
  2h = 50 m, 2b = 5 m, 10 elements): 256 random scenes (`--spring-sizes`), with its default
  (`Checked`: the run and a companion) and the run alone.
- Rows "with sensitivity": the same scenes with each run's tangent (`sensitivity=True`, issue 55;
  the command line's spectrum and suite default), against the row before it.
- Each row also counts the scenes that did not end `ok` (a valid random scene must).

The same command runs on a lent GPU (`device`): the table names the device, and its rows are
comparable only with rows of the same device. Results go to benchmarks/results/bench_throughput.txt
(benchmarks/results/bench_throughput_<platform>.txt off the CPU) unless `--out` says otherwise.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("JAXROCK_CACHE_DIR", "off")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrock as jr  # noqa: E402
from jaxrock.spring import Column, SpringModel  # noqa: E402

HERE = Path(__file__).resolve().parent
G = 9.81
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def timed(fn, repeat: int = 3):
    """(first call [s], best of `repeat` more calls [s], the result): times on a 2-core machine
    wander by 10-30 % between calls."""
    t = time.perf_counter()
    jax.block_until_ready(fn())
    first, best = time.perf_counter() - t, float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        res = jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t)
    return first, best, res


def not_ok(sol) -> int:
    return int(np.sum(np.asarray(jr.status_codes(sol.status)) != 0))


def row(name: str, n: int, first: float, warm: float, bad: int, ref_us: float | None = None) -> float:
    us = 1e6 * warm / n
    ratio = "" if ref_us is None else f"{us / ref_us:8.2f}x"
    out(f"{name:58s} {n:8d} {first:9.1f} {warm:9.2f} {us:10.1f} {ratio:>9s} {bad:6d}")
    return us


def random_pulses(rng, n, block):
    a = rng.uniform(0.5, 10.0, n) * G * float(block.tan_alpha)
    w = rng.uniform(1.0, 15.0, n) * float(block.p_r)
    return jr.RickerPulse(jnp.asarray(a), jnp.asarray(w))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="4096,16384,65536", help="random RM set sizes (comma-separated)")
    ap.add_argument("--spring-sizes", default="1024,256", help="quasi-rigid and flexible SM random set sizes (default 1024,256; larger on a GPU)")
    ap.add_argument("--models", default="rigid,spring", help="which rows: rigid, spring or both (default)")
    ap.add_argument("--quick", action="store_true", help="small sizes: a smoke run of every row")
    ap.add_argument("--repeat", type=int, default=3, help="warm calls per row, the best counts (default 3)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cores", type=int, default=None, help="CPU devices (default: every usable core, as the command line runs)")
    ap.add_argument("--out", type=Path, default=None, help="results file (default: benchmarks/results/bench_throughput[_<platform>].txt)")
    args = ap.parse_args()
    jr.use_cpu_cores(args.cores)  # as the command line does (before JAX's first computation): a batch dealt over the cores
    sizes = [256, 1024] if args.quick else [int(s) for s in args.sizes.split(",")]
    grid = 16 if args.quick else 64
    n_q, n_f = (64, 16) if args.quick else (int(s) for s in args.spring_sizes.split(","))
    rng = np.random.default_rng(args.seed)
    dev = jax.devices()[0]
    out(f"# bench_throughput: µs per scene by workload and batch size (warm = best of {args.repeat} calls after the first; first = with compilation)")
    out(f"# engine: MAX_PASS {jr.analyses.engine.MAX_PASS}, lane scale {jr.analyses.engine.LANE_SCALE.get(dev.platform, jr.analyses.engine.ACCELERATOR_LANE_SCALE)} on {dev.platform}")
    out(f"# machine: {platform.machine()}, {jax.device_count()} {dev.platform} device(s) ({dev.device_kind}), "
        f"{os.cpu_count()} cores, jax {jax.__version__}, python {platform.python_version()}")
    out(f"{'workload':58s} {'scenes':>8s} {'first s':>9s} {'warm s':>9s} {'µs/scene':>10s} {'vs grid':>9s} {'not ok':>6s}")

    block = jr.Block.from_slenderness(10.0, 0.2)
    if "rigid" in args.models.split(","):
        rigid_rows(args, rng, block, sizes, grid)
    if "spring" in args.models.split(","):
        spring_rows(rng, block, n_q, n_f, args.repeat)

    path = args.out or HERE / "results" / ("bench_throughput.txt" if dev.platform == "cpu" else f"bench_throughput_{dev.platform}.txt")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(LINES) + "\n")
    print(f"written to {path}")


def rigid_rows(args, rng, block, sizes, grid) -> None:
    model = jr.RigidModel(block)
    wr, ar = np.linspace(1.0, 15.0, grid), np.linspace(0.5, 10.0, grid)
    spec_us = None
    for sens in (False, True):
        first, warm, spec = timed(lambda: jr.overturning_spectrum(model, omega_ratio=wr, accel_ratio=ar, progress=False, sensitivity=sens),
                                  args.repeat)
        us = row(f"RM overturning_spectrum {grid}x{grid} grid" + (", with sensitivity (vs without)" if sens else ""), grid * grid,
                 first, warm, int(np.sum(np.asarray(spec.status) != 0)), spec_us)
        spec_us = us
    W, A = np.meshgrid(wr, ar)
    cells = jr.RickerPulse(jnp.asarray(A.ravel() * G * 0.2), jnp.asarray(W.ravel() * float(block.p_r)))
    first, warm, sol = timed(lambda: jr.run_batch(model, cells), args.repeat)
    grid_us = row(f"RM run_batch, the {grid * grid} grid cells", grid * grid, first, warm, not_ok(sol))
    for n in sizes:
        exc = random_pulses(rng, n, block)
        first, warm, sol = timed(lambda: jr.run_batch(model, exc), args.repeat)
        plain_us = row(f"RM run_batch, {n} random scenes", n, first, warm, not_ok(sol), grid_us)
        if n == min(sizes):
            first, warm, sol = timed(lambda: jr.run_batch(model, exc, sensitivity=True), args.repeat)
            row(f"RM run_batch, {n} random scenes, with sensitivity (vs without)", n, first, warm, not_ok(sol), plain_us)

    # mixed blocks and pulse shapes, one model per scene
    n = min(min(sizes), 4096)
    heights, tans = rng.uniform(2.0, 50.0, n), rng.uniform(0.1, 0.35, n)
    models = jax.vmap(lambda h, t: jr.RigidModel(jr.Block.from_slenderness(h, t)))(jnp.asarray(heights), jnp.asarray(tans))
    p = np.asarray(models.block.p_r)
    a, w = rng.uniform(0.5, 10.0, n) * G * tans, rng.uniform(1.0, 15.0, n) * p
    for cls in (jr.RickerPulse, jr.AntisymmetricRickerPulse):
        exc = cls(jnp.asarray(a), jnp.asarray(w))
        first, warm, sol = timed(lambda: jr.run_batch(models, exc, model_batched=True), args.repeat)
        row(f"RM run_batch, {n} random blocks, {cls.__name__}", n, first, warm, not_ok(sol), grid_us)


def spring_rows(rng, block, n_q, n_f, repeat) -> None:
    quasi = SpringModel(block)
    flexible = SpringModel(jr.Block.from_size(50.0, 5.0), Column.concrete(), n_elements=10)
    exc_q, exc_f = random_pulses(rng, n_q, quasi.block), random_pulses(rng, n_f, flexible.block)
    # the flexible default is `Checked`: its run and a companion at 10x its tolerances; the run
    # alone is the integrator's own cost on the same scenes
    for name, sm, exc, integ in (("quasi-rigid SM", quasi, exc_q, None),
                                 ("flexible SM (10 elements)", flexible, exc_f, None),
                                 ("flexible SM, its run alone (no companion)", flexible, exc_f, flexible.default_integrator().integrator)):
        n = exc.a_p.shape[0]
        first, warm, sol = timed(lambda: jr.run_batch(sm, exc, integ), repeat)
        plain_us = row(f"{name}, {n} random scenes", n, first, warm, not_ok(sol))
        if integ is None:  # the default, with its tangent (forward mode: the model's forward-mode default)
            first, warm, sol = timed(lambda: jr.run_batch(sm, exc, sensitivity=True), repeat)
            row(f"{name.split(' (')[0]}, {n} random, with sensitivity (vs without)", n, first, warm, not_ok(sol), plain_us)


if __name__ == "__main__":
    main()
