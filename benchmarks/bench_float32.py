"""float32 against float64: where single precision is safe (issue 25, item 4).

    python benchmarks/bench_float32.py [--grid 32]

jaxrock runs in float64 (`jaxrock.runtime`); float32 is what GPUs run fast. This study runs the same
spectra in a child process with `jax_enable_x64` switched off after import (not a supported mode:
a measurement of what it would give) and compares them with float64 at the same settings and
with a converged float64 reference:

- the rigid model on the bench_rigid scene (tanα = 0.2, 2h = 10 m, symmetric Ricker), a grid of
  ω_p/p ∈ [1, 15] × a_p/(g tanα) ∈ [0.5, 10], Tsit5 at several rtol (atol = rtol/100, root_tol
  raised to what the precision can resolve);
- per setting: failed cells (status not ok) and their statuses, cells whose verdict (uplift,
  overturn) differs from the reference, max |Δθ/α| over the cells both runs finished, and the warm
  time per scene (failed cells included: a cell that ends in max_iterations ran its whole bound).

The printed table is also written to benchmarks/results/bench_float32.txt.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RTOLS = {"float64": (1e-6, 1e-8, 1e-10), "float32": (1e-3, 1e-4, 1e-5, 1e-6)}
ROOT_TOL = {"float64": 1e-13, "float32": 1e-6}
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def child(precision: str, grid: int, dest: str) -> None:
    """Run the spectra of one precision and save them (np.savez) to `dest`."""
    import jax

    import jaxrock as jr

    if precision == "float32":
        jax.config.update("jax_enable_x64", False)
    blk = jr.Block.from_slenderness(10.0, 0.2)
    model = jr.RigidModel(blk, eta=blk.eta_r)
    wr, ar = np.linspace(1.0, 15.0, grid), np.linspace(0.5, 10.0, grid)
    res = {}
    for rtol in RTOLS[precision]:
        integ = jr.EventIntegrator(rtol=rtol, atol=rtol * 1e-2, root_tol=ROOT_TOL[precision])
        run = lambda: jr.overturning_spectrum(model, omega_ratio=wr, accel_ratio=ar, integrator=integ, progress=False)
        t = time.perf_counter()
        run()
        t_first = time.perf_counter() - t
        t = time.perf_counter()
        s = run()
        t_warm = time.perf_counter() - t
        key = f"{rtol:.0e}"
        res[f"{key}/max_theta"] = np.asarray(s.max_theta, dtype=np.float64)
        res[f"{key}/status"] = np.asarray(s.status)
        res[f"{key}/uplifted"] = np.asarray(s.uplifted)
        res[f"{key}/overturned"] = np.asarray(s.overturned)
        res[f"{key}/time"] = np.array([t_warm / s.max_theta.size, t_first - t_warm])
    if precision == "float64":
        import diffrax

        ref = jr.EventIntegrator(solver=diffrax.Dopri8(), rtol=1e-13, atol=1e-15)
        s = jr.overturning_spectrum(model, omega_ratio=wr, accel_ratio=ar, integrator=ref, progress=False)
        res["ref/max_theta"], res["ref/uplifted"], res["ref/overturned"] = (np.asarray(x) for x in (s.max_theta, s.uplifted, s.overturned))
    res["dtype"] = np.array(str(jax.numpy.result_type(float)))
    np.savez(dest, **res)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--grid", type=int, default=32, help="grid size per axis (default 32)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--dest", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child, args.grid, args.dest)
        return

    import jax

    from jaxrock.results import STATUS_NAMES

    runs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for precision in ("float64", "float32"):
            dest = os.path.join(tmp, f"{precision}.npz")
            subprocess.run([sys.executable, __file__, "--child", precision, "--grid", str(args.grid), "--dest", dest], check=True)
            runs[precision] = dict(np.load(dest))
    ref = runs["float64"]
    ref_theta, ref_up, ref_over = ref["ref/max_theta"], ref["ref/uplifted"], ref["ref/overturned"]
    n = ref_theta.size
    out(f"# bench_float32: rigid model, {args.grid}x{args.grid} grid (ω_p/p 1-15, a_p/(g tanα) 0.5-10), tanα = 0.2, 2h = 10 m, symmetric Ricker")
    out(f"# machine: {platform.machine()} {os.cpu_count()} CPUs, jax {jax.__version__} on {jax.devices()[0].platform}")
    out("# reference: float64, Dopri8 rtol 1e-13; each row Tsit5, atol = rtol/100, root_tol as shown; time warm (second call)")
    out("")
    out(f"{'dtype':<8} {'rtol':>7} {'root_tol':>8} {'ms/scene':>9} {'compile s':>9} {'failed':>6} {'verdicts off':>12} {'max err θ/α':>12}  failures")
    for precision, r in runs.items():
        assert str(r["dtype"]) == precision, (precision, r["dtype"])
        for rtol in RTOLS[precision]:
            key = f"{rtol:.0e}"
            ok = r[f"{key}/status"] == 0
            off = int(np.sum((r[f"{key}/uplifted"] != ref_up) | (r[f"{key}/overturned"] != ref_over)))
            err = np.max(np.abs(r[f"{key}/max_theta"] - ref_theta)[ok]) if ok.any() else np.nan
            per, comp = r[f"{key}/time"]
            codes, counts = np.unique(r[f"{key}/status"][~ok], return_counts=True)
            kinds = ", ".join(f"{k} {STATUS_NAMES[c]}" for c, k in zip(codes, counts)) or "-"
            out(f"{precision:<8} {rtol:>7.0e} {ROOT_TOL[precision]:>8.0e} {per * 1e3:>9.3f} {comp:>9.1f} {int((~ok).sum()):>6d}"
                f" {off:>12d} {err:>12.2e}  {kinds}")
    out(f"(of {n} cells)")
    res = HERE / "results"
    res.mkdir(exist_ok=True)
    (res / "bench_float32.txt").write_text("\n".join(LINES) + "\n")
    print(f"\n(written to {res / 'bench_float32.txt'})")


if __name__ == "__main__":
    main()
