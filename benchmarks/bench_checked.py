"""Is `Checked`'s estimate honest, and what does its companion cost? (issue 54: the flexible default's cost)

    python benchmarks/bench_checked.py [--n 128] [--seed 1] [--quick]

The flexible default is `Checked(GeneralizedAlpha(1e-5, 1e-5))`: the run, and a companion at
`factor` × its tolerances whose distance to the run, ε = |max θ/α − max θ/α (companion)|, is the
run's stated error (`Status.inaccurate` where ε > 1e-2). The companion is half the default's cost.
This study measures, on seeded random scenes of `bench_backbone.sample` (flexible concrete
columns, 2h 1–50 m, tanα 0.05–0.35, both pulse kinds, the model's default spring), against a
reference run at 1e-8:

- the run's true error e = |max θ/α − reference| on the scenes that rock without overturning (an
  overturned scene is 1 in both: no error to estimate);
- for each companion variant: the estimate ε, how often it under-states the error (ε < e), the
  cells it lets through wrongly (e > 1e-2 with ε ≤ 1e-2: a false `ok`) and flags needlessly
  (ε > 1e-2 with e ≤ 1e-2), ε/e, and its ms per scene (run alone, best of two warm calls).

The variants: the companion at factor 10 with the run's `crossing` limit (the limit serves the
run's forward derivatives, `jaxrock.spring.generalized_alpha`; the companion's value is never
differentiated), without it, and at factors 20 and 30 without it.

The printed table is also written to benchmarks/results/bench_checked.txt.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import sys
from pathlib import Path

import jax
import numpy as np

import jaxrock as jr
from jaxrock import GeneralizedAlpha
from jaxrock.scene import default_spring

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_backbone import describe, sample  # noqa: E402  (the scene set of the backbone study)
from bench_backbone import run as backbone_run  # noqa: E402

HERE = Path(__file__).resolve().parent
LINES: list[str] = []
ACCURACY = 1e-2


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def run(scenes, integrator, timed=False):
    """max θ/α, status and seconds per scene of every scene with the default spring (`bench_backbone.run`)."""
    return backbone_run(scenes, True, *default_spring(flexible=True), integrator, timed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=128, help="scenes (default 128)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="16 scenes: a smoke run")
    args = ap.parse_args()
    jr.use_cpu_cores(None)
    n = 16 if args.quick else args.n
    scenes = sample(n, np.random.default_rng(args.seed))
    default = jr.SpringModel(jr.Block.from_slenderness(10.0, 0.2), jr.Column.concrete()).default_integrator()
    run_ig = default.integrator
    out(f"# bench_checked: {n} seeded scenes (seed {args.seed}), flexible concrete columns, default spring; "
        f"the run {type(run_ig).__name__}({run_ig.rtol:g}, {run_ig.atol:g}), accuracy {ACCURACY:g}")
    out(f"# machine: {platform.machine()}, {jax.device_count()} {jax.devices()[0].platform} device(s), jax {jax.__version__}")
    ref, ref_st, _ = run(scenes, GeneralizedAlpha(1e-8, 1e-8, max_steps=1_000_000))
    th, st, t_run = run(scenes, run_ig, timed=True)
    # the statistics are over the scenes that rock without overturning in the reference and the
    # run (an overturned scene's max θ/α is 1 in both: an error of 0 that says nothing)
    rocking = (ref < 1) & (th < 1)
    good = (ref_st == 0) & (st == 0) & rocking
    err = np.abs(th - ref)
    out(f"{int(np.sum(ref >= 1))} scenes overturn in the reference, {int(np.sum((ref >= 1) != (th >= 1)))} verdicts differ; "
        f"the rest ({int(good.sum())} rocking scenes) below")
    out(f"reference GeneralizedAlpha(1e-8): failed {int(np.sum(ref_st != 0))}; the run: failed {int(np.sum(st != 0))}, "
        f"{1e3 * t_run:.2f} ms/scene; its true error: median {np.median(err[good]):.1e}, p90 {np.percentile(err[good], 90):.1e}, "
        f"max {err[good].max():.1e} ({describe(scenes, np.flatnonzero(good)[np.argmax(err[good])])}); "
        f"{int(np.sum(err[good] > ACCURACY))} scenes beyond {ACCURACY:g}")
    out(f"{'companion':34s} {'ms/scene':>8s} {'vs run':>7s} {'ε median':>9s} {'ε p90':>9s} {'ε<e':>5s} "
        f"{'false ok':>8s} {'flagged':>7s} {'needless':>8s} {'ε/e median':>10s} {'failed':>6s}")
    for factor, crossing in ((10.0, run_ig.crossing), (10.0, None), (20.0, None), (30.0, None)):
        comp = dataclasses.replace(run_ig, rtol=run_ig.rtol * factor, atol=run_ig.atol * factor, crossing=crossing)
        c, c_st, t_c = run(scenes, comp, timed=True)
        ok = good & (c_st == 0)
        est = np.abs(th - c)[ok]
        e = err[ok]
        flagged = est > ACCURACY
        ratio = est[e > 0] / e[e > 0]
        name = f"factor {factor:g}, crossing {crossing}"
        out(f"{name:34s} {1e3 * t_c:8.2f} {t_c / t_run:7.2f} {np.median(est):9.1e} {np.percentile(est, 90):9.1e} "
            f"{int(np.sum(est < e)):5d} {int(np.sum((e > ACCURACY) & ~flagged)):8d} {int(flagged.sum()):7d} "
            f"{int(np.sum(flagged & (e <= ACCURACY))):8d} {np.median(ratio):10.1f} {int(np.sum(c_st != 0)):6d}")
    path = HERE / "results" / "bench_checked.txt"
    if not args.quick:
        path.write_text("\n".join(LINES) + "\n")
        print(f"written to {path}")


if __name__ == "__main__":
    main()
