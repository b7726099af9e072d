"""Record suite: jaxrock's least overturning factors (a vmapped sweep, then vmapped bisection)
against its peers run by run as their users would script them, and the error of each against a
tight reference. Rigid model (RM): the same search with the SciPy event loop
(`jaxrock/numerics/scipy_rigid.py`: DOP853 with impact, apex and overturning events, stepping on
every record sample). Quasi-rigid spring model (SM): the same suite in jaxrock, against OpenSeesPy
(`jaxrock/numerics/opensees_sm.py`, `run_record`) on a seeded subsample of its runs.

    python benchmarks/bench_suite.py [--refine 5] [--quick] [--models rigid,spring] [--n-opensees 12] [--rtols ...]

Suite: the five packaged records and six synthetic ones (seeded, 10–90 s, dt 0.005–0.02 s:
low-passed noise under a rise-and-decay envelope, peak 0.35 g), eleven distinct lengths; 2h = 1,
4 m; tanα = 0.2; factors 0.25:4:16. Both peers run the same sweep and the same bisection (the first
overturning factor of the sweep, bisected `refine` times against the one before it).

- jaxrock: the first call (with compilation, cache off, the number of XLA compilations counted)
  and the best of 2 warm calls; µs per record sample per run. On every usable core, as the command
  line runs (`jaxrock.use_cpu_cores`: one device per core, a sweep's chunks one per device;
  `--cores=1`: one); the peers' loops run in one process (a pool of processes would at best divide
  their times by the cores: that ratio is printed too).
- SciPy at its tuned setting of bench_rigid (DOP853 rtol 1e-6: max error in θ/α ≤ 1e-6 on pulses).
- Error: max |θ|/α′ of jaxrock's default and of the SciPy loop at rtol 1e-6 against SciPy at
  rtol 1e-12, on the cells the reference determines (SciPy at 1e-10 and 1e-12 within 1e-8), three
  factors per record and size (below, near and above the least factor).

SM (quasi-rigid, `jr.Sweep.make("spring", ...)`, the default integrator: Tsit5 at 1e-10):
- jaxrock: the same suite and search, first call and one warm call; µs per sample per run.
- OpenSeesPy on `--n-opensees` runs drawn from the suite's sweep (seeded): Newmark trapezoidal at
  the record's step (what its users run) and at a 32nd of it (the step at which its error in
  max θ/α′ falls to ~1e-3 on El Centro: it converges to a floor of ~2e-4, the sampled tanh
  backbone's); µs per sample per run and the error of both and of jaxrock's default against
  jaxrock at Tsit5 rtol = atol = 1e-12 on the runs that it determines (1e-11 and 1e-12 within
  1e-6; OpenSees at a 128th of the step is within 1.6e-4 of it on El Centro ×1 and ×1.5 at
  2h = 4 m).

`--rtols 1e-8,...,1e-12`: instead, the RM's record runs over the step tolerance: the same suite at
each rtol, warm time against the error on the cells above (what chose `RECORD_TOLERANCES`),
written to benchmarks/results/bench_suite_rtol.txt.

Written to benchmarks/results/bench_suite.txt (`--quick`: 3 records, printed only).
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("JAXROCK_CACHE_DIR", "off")  # the first call's compilation is part of what is measured

import jax  # noqa: E402
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent

import jaxrock as jr  # noqa: E402
from jaxrock.analyses.engine import run_batch  # noqa: E402
from jaxrock.numerics import scipy_rigid as sr  # noqa: E402

LINES: list[str] = []
COMPILATIONS = [0]


def _count(event: str, *_args, **_kw) -> None:
    if event == "/jax/core/compile/backend_compile_duration":
        COMPILATIONS[0] += 1


jax.monitoring.register_event_duration_secs_listener(_count)


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def synthetic(seed: int, seconds: float, dt: float) -> jr.Record:
    """Low-passed white noise under a rise-and-decay envelope, peak 0.35 g."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds / dt)) + 1
    t = dt * np.arange(n)
    width = max(1, int(round(0.05 / dt)))
    noise = np.convolve(rng.standard_normal(n + width), np.ones(width) / width, mode="same")[:n]
    rise = seconds / 8
    acc = noise * (t / rise) ** 2 * np.exp(2 - 2 * t / rise)
    return jr.Record(0.35 * 9.81 * acc / np.max(np.abs(acc)), dt, name=f"synthetic {seconds:g} s")


SYNTHETIC = [(11, 12.0, 0.005), (12, 20.0, 0.01), (13, 30.0, 0.02), (14, 45.0, 0.005), (15, 60.0, 0.01), (16, 90.0, 0.005)]


def scipy_over(block, rec, scale, rtol):
    return sr.solve_record(block, np.asarray(rec.acc), float(rec.dt), scale, rtol=rtol, atol=rtol * 1e-2)


def scipy_least(block, rec, scales, refine, rtol):
    """The sweep, then the bisection, one SciPy run at a time: (least, low, runs)."""
    over = lambda s: scipy_over(block, rec, s, rtol).overturned
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


def reference_cells(records, heights, tan_a, ds, scales):
    """The cells of the error check: three factors per record and size (below, near and above the
    least factor of `ds`), each with SciPy at rtol 1e-12 where it determines max |θ|/α′ (SciPy at
    1e-10 and 1e-12 within 1e-8, the same verdict), None where it does not."""
    cells = []
    for r, rec in enumerate(records):
        for i, h in enumerate(heights):
            block = jr.Block.from_slenderness(h, tan_a)
            least = float(ds.least_scale[r, i])
            picks = sorted({0.5 * least, 0.98 * least, 1.5 * least} if np.isfinite(least) else {scales[len(scales) // 2], scales[-1]})
            refs = []
            for s in picks:
                ref = [scipy_over(block, rec, s, rt) for rt in (1e-10, 1e-12)]
                known = abs(ref[0].max_theta - ref[1].max_theta) <= 1e-8 and ref[0].overturned == ref[1].overturned
                refs.append(ref[1].max_theta if known else None)
            cells.append((rec, block, picks, refs))
    return cells


def max_error(cells, run):
    """The largest |run(rec, block, factors) − reference| over the determined cells, and their number."""
    worst, determined = 0.0, 0
    for rec, block, picks, refs in cells:
        got = run(rec, block, picks)
        for g, ref in zip(got, refs):
            if ref is not None:
                determined += 1
                worst = max(worst, abs(float(g) - ref))
    return worst, determined


def jaxrock_runs(integrator=None):
    return lambda rec, block, picks: run_batch(jr.RigidModel(block), jax.vmap(rec.scaled)(np.asarray(picks)), integrator).max_theta


def suite_time(sweep, refine, warm_calls):
    """(the result, the first call's seconds, its XLA compilations, the best warm call's seconds)."""
    COMPILATIONS[0] = 0
    t0 = time.perf_counter()
    ds = jr.least_overturning_scale(sweep, refine=refine, progress=False)
    first, compiled = time.perf_counter() - t0, COMPILATIONS[0]
    warm = []
    for _ in range(warm_calls):
        t0 = time.perf_counter()
        jr.least_overturning_scale(sweep, refine=refine, progress=False)
        warm.append(time.perf_counter() - t0)
    return ds, first, compiled, min(warm)


def runs_and_samples(ds, records, n_sizes, n_scales, refine):
    found = np.isfinite(ds.least_scale.values)
    per_record = n_sizes * n_scales + refine * found.sum(axis=1)
    return int(per_record.sum()), int(sum(n * rec.n for n, rec in zip(per_record, records)))


def jaxrock_suite(kind, records, heights, tan_a, scales, refine, warm_calls, integrator=None):
    """jaxrock's suite of model `kind`: (the result, runs, µs per sample per run warm, warm seconds,
    first call's seconds, the line that reports it)."""
    sweep = jr.Sweep.make(kind, records=records, height=heights, tan_alpha=tan_a, scale=scales, integrator=integrator)
    ds, first, compiled, warm = suite_time(sweep, refine, warm_calls)
    runs, samples = runs_and_samples(ds, records, len(heights), len(scales), refine)
    line = (f"jaxrock: {runs} record runs, {samples} record samples in all; first call {first:.1f} s "
            f"({compiled} XLA compilations), warm {warm:.2f} s ({1e3 * warm / runs:.2f} ms/run, "
            f"{1e6 * warm / samples:.2f} µs per sample per run)")
    return ds, runs, 1e6 * warm / samples, warm, first, line


def spring_section(records, heights, tan_a, scales, args):
    """The quasi-rigid SM: jaxrock's suite against OpenSeesPy on a seeded subsample of its runs."""
    from jaxrock.numerics import opensees_sm as osm

    out()
    out("## quasi-rigid SM (the default: Tsit5 rtol = atol = 1e-10) against OpenSeesPy")
    ds, _, us_jr, _, _, line = jaxrock_suite("spring", records, heights, tan_a, scales, args.refine, 1)
    out(line)
    rng = np.random.default_rng(0)
    picks = [(int(rng.integers(len(records))), int(rng.integers(len(heights))), float(rng.choice(scales))) for _ in range(args.n_opensees)]
    tight = {tol: jr.SpringIntegrator(rtol=tol, atol=tol, solver="tsit5", max_steps=4_000_000) for tol in (1e-11, 1e-12)}
    peers = {"OpenSees dt = record dt": 1, "OpenSees dt = record dt/32": 32}
    err = {k: 0.0 for k in ("jaxrock default", *peers)}
    secs = {k: 0.0 for k in peers}
    verdicts = {k: 0 for k in ("jaxrock default", *peers)}
    peer_samples, determined = 0, 0
    out(f"side by side, {len(picks)} runs drawn from the sweep (seed 0): max θ/α′")
    out(f"{'record':<20}{'2h':>4}{'scale':>7}{'reference':>12}{'jaxrock':>12}" + "".join(f"{'OS dt/' + str(k):>12}" for k in peers.values()))
    for r, i, s in picks:
        rec, h = records[r], heights[i]
        model = jr.SpringModel(jr.Block.from_slenderness(h, tan_a))
        ref11, ref = (jr.simulate(model, rec.scaled(s), integrator=tight[tol]) for tol in (1e-11, 1e-12))
        mine = jr.simulate(model, rec.scaled(s))
        # determined: the reference at 1e-11 and 1e-12 within 1e-6, the same verdict
        known = abs(float(ref11.max_theta) - float(ref.max_theta)) <= 1e-6 and bool(ref11.overturned) == bool(ref.overturned)
        determined += known
        sc = osm.Scene(h, h * tan_a, E=None, n_elements=1)
        row = {"jaxrock default": (float(mine.max_theta), bool(mine.overturned))}
        for name, k in peers.items():
            o = osm.run_record(sc, np.asarray(rec.acc), float(rec.dt), s, substeps=k)
            secs[name] += o["time"]
            row[name] = (o["max_theta"], o["overturned"])
        peer_samples += rec.n
        for name, (m, over) in row.items():
            if known:
                err[name] = max(err[name], abs(m - float(ref.max_theta)))
                verdicts[name] += over == bool(ref.overturned)
        out(f"{rec.name[:19]:<20}{h:4g}{s:7.3g}{float(ref.max_theta):12.6f}{'' if known else '?':1}" + "".join(f"{row[n][0]:12.6f}" for n in row))
    out(f"(?: not determined, the reference at Tsit5 1e-11 and 1e-12 more than 1e-6 apart; errors and verdicts on the {determined} others)")
    out(f"{'':<44}{'µs/sample/run':>14}{'vs jaxrock':>11}{'max |Δ| vs reference':>22}{'same verdict':>14}")
    out(f"{'jaxrock default (the whole suite, warm)':<44}{us_jr:14.2f}{'1':>11}{err['jaxrock default']:22.1e}{verdicts['jaxrock default']:>9d} of {determined}")
    for name in peers:
        us = 1e6 * secs[name] / peer_samples
        out(f"{name + ' (build included)':<44}{us:14.2f}{us / us_jr:10.1f}x{err[name]:22.1e}{verdicts[name]:>9d} of {determined}")
    n_dev = len(jax.local_devices())
    if n_dev > 1:
        out(f"(jaxrock on {n_dev} devices, one per core; OpenSees in {n_dev} processes would at best divide its times by {n_dev})")


def rigid_section(records, heights, tan_a, scales, args):
    """The RM: jaxrock's suite against the SciPy loop's same search, and both against a tight reference."""
    out()
    out("## RM against the SciPy event loop")
    ds, runs_jr, _, warm, first, line = jaxrock_suite("rigid", records, heights, tan_a, scales, args.refine, 2)
    if args.jaxrock_only:
        out(line)
        return
    out(f"{'record':<20}{'samples':>8}{'2h':>5}{'jaxrock least':>15}{'SciPy least':>13}{'same bracket':>14}")
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
            out(f"{rec.name[:19]:<20}{rec.n:8d}{h:5g}{mine:15.6g}{least:13.6g}{'yes' if agree else 'no':>14}")
    scipy_s = time.perf_counter() - t0
    cells = len(records) * len(heights)
    ref_cells = reference_cells(records, heights, tan_a, ds, scales)
    tried = sum(len(c[2]) for c in ref_cells)
    err_jr, determined = max_error(ref_cells, jaxrock_runs())
    err_sp, _ = max_error(ref_cells, lambda rec, block, picks: [scipy_over(block, rec, s, 1e-6).max_theta for s in picks])
    out()
    out(f"same least factor (bit for bit: the same brackets): {same} of {cells} cells")
    out(line)
    out(f"SciPy DOP853 rtol 1e-6: {runs_sp} record runs in {scipy_s:.1f} s ({1e3 * scipy_s / runs_sp:.0f} ms/run)")
    n_dev = len(jax.local_devices())
    out(f"speed-up per run, warm: {(scipy_s / runs_sp) / (warm / runs_jr):.0f}x; "
        f"whole suite with jaxrock's compilation: {scipy_s / first:.1f}x"
        + (f"; against SciPy in {n_dev} processes at best (its time / {n_dev}): {(scipy_s / n_dev / runs_sp) / (warm / runs_jr):.0f}x warm, "
           f"{scipy_s / n_dev / first:.1f}x cold" if n_dev > 1 else ""))
    out(f"max |θ|/α′ error against SciPy rtol 1e-12, {determined} determined cells of {tried}: "
        f"jaxrock default {err_jr:.1e}, SciPy rtol 1e-6 {err_sp:.1e}")


def rtol_study(records, heights, tan_a, scales, args):
    """The RM's record runs over the step tolerance: the same suite and search at each rtol (atol =
    rtol/100), warm time against the error on the reference cells (picked from the first rtol's
    least factors) and the least factors against the first rtol's."""
    out()
    out("## RM on records: error against run time over the step tolerance (atol = rtol/100)")
    out(f"{'rtol':>8}{'first s':>9}{'warm s':>8}{'µs/sample/run':>15}{'max |Δθ|/α′':>13}{'determined':>12}{'same least':>12}")
    cells = base = None
    for rtol in args.rtols:
        integ = jr.EventIntegrator(rtol=rtol, atol=rtol * 1e-2)
        ds, _, us, warm, first, _ = jaxrock_suite("rigid", records, heights, tan_a, scales, args.refine, 2, integ)
        if cells is None:
            cells, base = reference_cells(records, heights, tan_a, ds, scales), ds.least_scale.values
        err, determined = max_error(cells, jaxrock_runs(integ))
        same = int(np.sum(ds.least_scale.values == base))
        out(f"{rtol:8.0e}{first:9.1f}{warm:8.2f}{us:15.2f}{err:13.1e}{determined:12d}{same:>7d} of {base.size}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--refine", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="3 records, printed only")
    ap.add_argument("--jaxrock-only", action="store_true", help="no peer, no errors, printed only (to time an older jaxrock)")
    ap.add_argument("--models", default="rigid,spring", help="comma-separated: rigid (vs SciPy), spring (quasi-rigid SM vs OpenSeesPy)")
    ap.add_argument("--n-opensees", type=int, default=12, help="SM runs drawn from the sweep for OpenSeesPy")
    ap.add_argument("--cores", type=int, default=None, help="CPU devices (default: every usable core, as the "
                    "command line); 1: one device, one core's worth")
    ap.add_argument("--rtols", type=lambda v: [float(x) for x in v.split(",")], default=None,
                    help="comma-separated: only the RM's tolerance study at these rtols (the first picks the error cells), "
                         "written to bench_suite_rtol.txt")
    args = ap.parse_args()
    jr.use_cpu_cores(args.cores)  # as the command line does (before JAX's first computation): a sweep's chunks one per core
    models = ["rigid"] if args.rtols else args.models.split(",")
    records = jr.read_records(["builtin"]) + [synthetic(*s) for s in SYNTHETIC]
    if args.quick:
        records = records[:3]
    heights, tan_a, scales = [1.0, 4.0], 0.2, np.linspace(0.25, 4.0, 16)
    samples = {rec.name: rec.n for rec in records}
    out(f"# bench_suite: {len(records)} records of {len(set(samples.values()))} distinct lengths "
        f"({min(samples.values())}–{max(samples.values())} samples) × {len(heights)} sizes, tanα = {tan_a}, factors 0.25:4:16, "
        f"refine {args.refine}; {', '.join(models)}")
    out(f"# machine: {platform.machine()} {os.cpu_count()} CPUs; jax {jax.__version__}; jaxrock compilation cache off; "
        f"{len(jax.local_devices())} {jax.local_devices()[0].platform} device(s) (`jaxrock.use_cpu_cores`); the peers run one process")
    if args.rtols:
        rtol_study(records, heights, tan_a, scales, args)
        if not args.quick:
            path = HERE / "results" / "bench_suite_rtol.txt"
            path.write_text("\n".join(LINES) + "\n")
            print(f"wrote {path}")
        return
    if "rigid" in models:
        rigid_section(records, heights, tan_a, scales, args)
    if "spring" in models and not args.jaxrock_only:
        spring_section(records, heights, tan_a, scales, args)
    if not args.quick and not args.jaxrock_only and models == ["rigid", "spring"]:
        path = HERE / "results" / "bench_suite.txt"
        path.write_text("\n".join(LINES) + "\n")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
