"""Preparation before any physics: reading a scenes CSV and a long record, as whole calls.

    python benchmarks/bench_preparation.py [--rows 100000] [--samples 1000000]

- `jaxrock.io.scenes_file.read_scenes` on `--rows` rows (2h 1–50 m, tanα 0.05–0.35, a third each rigid,
  quasi-rigid and flexible models, symmetric and antisymmetric pulses by ratio, random η / c̄ / E
  cells left empty half the time; seed 0): every row parsed and checked, every group's values
  ready to stack.
- `jaxrock.read_record` on a two-column file of `--samples` lines and on an `.AT2` file of as many
  values (8 per line).

Median of 3 (the CLI once). Written to benchmarks/results/bench_preparation.txt.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.io.scenes_file import read_scenes

HERE = Path(__file__).resolve().parent
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def scenes_csv(path: Path, n: int) -> None:
    rng = np.random.default_rng(0)
    models = np.array(["rigid", "spring", "spring-flexible"])[rng.integers(0, 3, n)]
    pulses = np.array(["symmetric", "antisymmetric"])[rng.integers(0, 2, n)]
    lines = ["id,height,tan_alpha,model,pulse,accel_ratio,omega_ratio,eta,cbar,E"]
    for i in range(n):
        m = models[i]
        eta = f"{rng.uniform(0.8, 1):.4f}" if m == "rigid" and rng.random() < 0.5 else ""
        cbar = f"{rng.uniform(0, 0.1):.4f}" if m != "rigid" and rng.random() < 0.5 else ""
        E = f"{rng.uniform(2e10, 4e10):.4g}" if m == "spring-flexible" and rng.random() < 0.5 else ""
        lines.append(f"s{i},{np.exp(rng.uniform(0, np.log(50))):.4f},{rng.uniform(0.05, 0.35):.4f},{m},{pulses[i]},"
                     f"{rng.uniform(1, 8):.4f},{rng.uniform(1, 15):.4f},{eta},{cbar},{E}")
    path.write_text("\n".join(lines) + "\n")


def median_time(fn, k=3) -> float:
    ts = []
    for _ in range(k):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=100_000)
    ap.add_argument("--samples", type=int, default=1_000_000)
    args = ap.parse_args()
    out(f"# bench_preparation ({platform.processor() or platform.machine()}, {jr.__name__} float64)")
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        csv = d / "scenes.csv"
        scenes_csv(csv, args.rows)
        t = median_time(lambda: read_scenes(csv))
        out(f"read_scenes, {args.rows:,} rows: {t:.2f} s ({1e6 * t / args.rows:.1f} µs/row)")

        dt = 0.005
        acc = 0.3 * np.sin(2 * np.pi * 1.3 * np.arange(args.samples) * dt)
        two = d / "rec.txt"
        two.write_text("\n".join(f"{k * dt:.4f} {a:.7e}" for k, a in enumerate(acc)) + "\n")
        t = median_time(lambda: jr.read_record(two))
        out(f"read_record, two-column, {args.samples:,} lines: {t:.2f} s")
        at2 = d / "rec.AT2"
        body = "\n".join("  ".join(f"{a:.7E}" for a in acc[k : k + 8]) for k in range(0, acc.size, 8))
        at2.write_text(f"PEER\nsynthetic\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= {acc.size}, DT= {dt} SEC\n{body}\n")
        t = median_time(lambda: jr.read_record(at2))
        out(f"read_record, .AT2, {args.samples:,} values: {t:.2f} s")

    res = HERE / "results"
    res.mkdir(exist_ok=True)
    (res / "bench_preparation.txt").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
