"""Record suite, rigid model: jaxrock's least overturning factors (a vmapped sweep, then vmapped
bisection) against the same search with the SciPy event loop (`jaxrock/numerics/scipy_rigid.py`: DOP853 with
impact, apex and overturning events, stepping on every record sample), run by run as its users
would script it.

    python benchmarks/bench_suite.py [--refine 5]

Suite: the packaged El Centro 1940 NS, ARL360 (Northridge) and elCentro_peknold; 2h = 1, 4 m; tanα = 0.2; factors 0.25:4:16. Both peers run the same sweep and
the same bisection (the first overturning factor of the sweep, bisected `refine` times against
the one before it). jaxrock: the first call (with compilation, cache off) and the best of 2 warm
calls; SciPy at its tuned setting of bench_rigid (DOP853 rtol 1e-6, max error in θ/α ≤ 1e-6 on
pulses). Written to benchmarks/results/bench_suite.txt.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("JAXROCK_CACHE_DIR", "off")  # the first call's compilation is part of what is measured

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent

import jaxrock as jr  # noqa: E402
from jaxrock.numerics import scipy_rigid as sr  # noqa: E402

LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def scipy_least(block, rec, scales, refine, rtol):
    """The sweep, then the bisection, one SciPy run at a time: (least, low, runs)."""
    acc, dt = np.asarray(rec.acc), float(rec.dt)
    over = lambda s: sr.solve_record(block, acc, dt, s, rtol=rtol, atol=rtol * 1e-2).overturned
    flags = [over(s) for s in scales]
    runs = len(scales)
    if not any(flags):
        return np.inf, np.nan, runs
    k = flags.index(True)
    lo, hi = (scales[k - 1] if k else 0.0), scales[k]
    for _ in range(refine):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if over(mid) else (mid, hi)
        runs += 1
    return hi, lo, runs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--refine", type=int, default=5)
    args = ap.parse_args()
    records = jr.read_records(["arl360", "elcentro_peknold", "elcentro"])
    heights, tan_a, scales = [1.0, 4.0], 0.2, np.linspace(0.25, 4.0, 16)
    out(f"# bench_suite: {len(records)} records × {len(heights)} sizes, tanα = {tan_a}, factors 0.25:4:16, refine {args.refine}, RM")
    out(f"# machine: {platform.machine()} {os.cpu_count()} CPUs; jaxrock compilation cache off")
    sweep = jr.Sweep.make("rigid", records=records, height=heights, tan_alpha=tan_a, scale=scales)
    t0 = time.perf_counter()
    ds = jr.least_overturning_scale(sweep, refine=args.refine, progress=False)
    first = time.perf_counter() - t0
    warm = []
    for _ in range(2):
        t0 = time.perf_counter()
        jr.least_overturning_scale(sweep, refine=args.refine, progress=False)
        warm.append(time.perf_counter() - t0)
    runs_jr = sweep.size + args.refine * int(np.isfinite(ds.least_scale.values).sum())
    out()
    out(f"{'record':<20}{'2h':>5}{'jaxrock least':>15}{'SciPy least':>13}{'same bracket':>14}")
    t0 = time.perf_counter()
    runs_sp, same = 0, 0
    for r, rec in enumerate(records):
        for i, h in enumerate(heights):
            block = jr.Block.from_slenderness(h, tan_a)
            least, low, n = scipy_least(block, rec, scales, args.refine, 1e-6)
            runs_sp += n
            mine = float(ds.least_scale[r, i])
            agree = (mine == least) or (np.isinf(mine) and np.isinf(least))
            same += agree
            out(f"{rec.name[:19]:<20}{h:5g}{mine:15.6g}{least:13.6g}{'yes' if agree else 'no':>14}")
    scipy_s = time.perf_counter() - t0
    cells = len(records) * len(heights)
    out()
    out(f"same least factor (bit for bit: the same brackets): {same} of {cells} cells")
    out(f"jaxrock: {runs_jr} record runs; first call {first:.1f} s (with compilation), warm {min(warm):.2f} s "
        f"({1e3 * min(warm) / runs_jr:.1f} ms/run)")
    out(f"SciPy DOP853 rtol 1e-6: {runs_sp} record runs in {scipy_s:.1f} s ({1e3 * scipy_s / runs_sp:.0f} ms/run)")
    out(f"speed-up, warm: {scipy_s / min(warm):.0f}x; with jaxrock's compilation: {scipy_s / first:.1f}x")
    path = HERE / "results" / "bench_suite.txt"
    path.write_text("\n".join(LINES) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
