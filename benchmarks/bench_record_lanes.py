"""What a record run costs against the batch it runs in: the rigid model on El Centro (4000
samples), a batch of B runs at factors spread over 1-3 (every run rocks, most overturn), warm, for
B = 8 ... 4096: seconds per batch, ms per run, µs per record sample per run. Under `vmap` the lanes
of a batch step through the samples together: a small batch pays each loop step's fixed cost.

    python benchmarks/bench_record_lanes.py

Written to benchmarks/results/bench_record_lanes.txt.
"""

from __future__ import annotations

import os
import platform
import time
from pathlib import Path

os.environ.setdefault("JAXROCK_CACHE_DIR", "off")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import jaxrock as jr  # noqa: E402
from jaxrock.analyses.engine import run_batch  # noqa: E402

HERE = Path(__file__).resolve().parent


def main():
    rec = jr.el_centro()
    model = jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2))
    lines = [f"# bench_record_lanes: RM, 2h = 1 m, tanα = 0.2, El Centro ({rec.n} samples) × factors 1-3, warm (best of 2)",
             f"# machine: {platform.machine()} {os.cpu_count()} CPUs; jax {jax.__version__}", "",
             f"{'batch':>6}{'s/batch':>10}{'ms/run':>9}{'µs/sample/run':>15}"]
    print("\n".join(lines), flush=True)
    for b in (8, 64, 512, 4096):
        excs = jax.vmap(rec.scaled)(jnp.linspace(1.0, 3.0, b))
        jax.block_until_ready(run_batch(model, excs))
        best = float("inf")
        for _ in range(2):
            t0 = time.perf_counter()
            jax.block_until_ready(run_batch(model, excs))
            best = min(best, time.perf_counter() - t0)
        lines.append(f"{b:6d}{best:10.3f}{1e3 * best / b:9.3f}{1e6 * best / b / rec.n:15.3f}")
        print(lines[-1], flush=True)
    path = HERE / "results" / "bench_record_lanes.txt"
    path.write_text("\n".join(lines) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
