"""Spring-model (SM) benchmark: jaxrock vs the paper's own SM in OpenSeesPy (benchmarks/opensees_sm.py).

    python benchmarks/bench_spring.py [--quick] [--n-opensees 16] [--n-opensees-flex 6] [--grid 32] [--flex-grid 4]

Scenes (symmetric Ricker pulse, ω_p/p ∈ [1, 15], a_p/(g tanα) ∈ [0.5, 10], linspace grids):
- quasi-rigid: tanα = 0.2, 2h = 10 m; jaxrock `SpringModel(block)` (one-DOF rigid SM, eq. 10 with
  the damper) vs OpenSees one corotational element with E = 1e14 Pa;
- flexible: concrete (E = 30 GPa, ρ = 2500 kg/m³) 2h = 50 m, 2b = 5 m, 10 elements, ζ = 0.01,
  `SpringModel(block, Column.concrete(), n_elements=10)` vs the same mesh in OpenSees.
Both: added rotational masses, c̄ of eq. 17, tanh backbone θs = 1e-4 α.

- jaxrock: `jaxrock.overturning_spectrum` on the whole grid (compile = first call − second call;
  per-scene = second call / cells), default integrators.
- OpenSees: a random subsample of `--n-opensees` quasi-rigid cells (default 16) and
  `--n-opensees-flex` flexible cells (default 6), Newmark trapezoidal,
  dt = min(T_p, 2π/p)/400; time per scene includes building the model (as a user would run it).
- References on the subsample: jaxrock at tight tolerance (quasi-rigid: Kvaerno5 rtol = atol =
  1e-11; flexible: Kvaerno5 1e-7) and OpenSees at dt/8 (3200 steps per period). Errors are
  max/median |Δ max|θ|/α| over the subsample; overturned cells count as 1.

The printed table is also written to benchmarks/results/bench_spring.txt.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import jaxrock as jr  # noqa: E402
from jaxrock.spring import Column, SpringIntegrator, SpringModel  # noqa: E402

import opensees_sm as osm  # noqa: E402

G = 9.81
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def jax_grid(model, wr, ar):
    t = time.perf_counter()
    jr.overturning_spectrum(model, wr, ar, progress=False)
    t1 = time.perf_counter() - t
    t = time.perf_counter()
    spec = jr.overturning_spectrum(model, wr, ar, progress=False)
    t2 = time.perf_counter() - t
    return spec, t1 - t2, t2 / spec.max_theta.size


def jax_cells(model, a_p, w_p, integrator):
    f = jax.jit(jax.vmap(lambda a, w: jr.simulate(model, jr.RickerPulse(a, w), integrator=integrator)))
    sol = f(jnp.asarray(a_p), jnp.asarray(w_p))
    return np.asarray(sol.max_theta), np.asarray(sol.status._value)


def scene(name, model, sc, wr, ar, n_os, rng, ref_integrator, args):
    blk = model.block
    p, ta = float(blk.p_r), float(jnp.tan(blk.alpha_r))
    out(f"\n## {name}: {len(ar)} x {len(wr)} grid, 2h = {float(blk.height):g} m, tanα = {ta:.3g}, "
        f"p = {p:.4f} rad/s" + (f", E = {sc.E:g} Pa, {sc.n} elements" if model.column is not None else ", one-DOF"))
    spec, t_comp, t_jax = jax_grid(model, wr, ar)
    n_fail = int(np.sum(spec.status != 0))
    # subsample
    W, A = np.meshgrid(wr, ar)
    idx = rng.choice(W.size, size=min(n_os, W.size), replace=False)
    wr_s, ar_s = W.ravel()[idx], A.ravel()[idx]
    a_p, w_p = ar_s * G * ta, wr_s * p
    jax_sub = spec.max_theta.ravel()[idx]
    t = time.perf_counter()
    ref_j, ref_st = jax_cells(model, a_p, w_p, ref_integrator)
    t_ref = time.perf_counter() - t
    os_th, os_t, os_fail, os_ref = [], [], 0, []
    for a, w in zip(a_p, w_p):
        r = osm.run_pulse(sc, float(a), float(w), steps_per_period=args.spp)
        os_th.append(r["max_theta"])
        os_t.append(r["time"])
        os_fail += r["failed"]
        if not args.no_os_ref:
            os_ref.append(osm.run_pulse(sc, float(a), float(w), steps_per_period=8 * args.spp)["max_theta"])
    os_th, os_t = np.array(os_th), np.array(os_t)
    t_os = float(np.mean(os_t))
    err = lambda x, y: (float(np.max(np.abs(x - y))), float(np.median(np.abs(x - y))))
    out(f"jaxrock reference ({ref_integrator.solver} rtol {ref_integrator.rtol:g}) on {len(idx)} cells: {t_ref:.1f} s, "
        f"failed {int(np.sum(ref_st != 0))}")
    rows = [("jaxrock overturning_spectrum (default)", t_jax, t_comp, jax_sub, f"{n_fail}/{spec.max_theta.size}")]
    rows.append((f"OpenSeesPy Newmark dt=T/{args.spp} ({len(idx)} cells)", t_os, 0.0, os_th, f"{os_fail}/{len(idx)}"))
    out(f"{'method':48s} {'ms/scene':>9s} {'compile s':>9s} {'err vs jax-ref max/med':>24s} {'err vs OS-ref max/med':>23s} {'failed':>8s}")
    for label, tt, tc, th, fl in rows:
        e1 = err(th, ref_j)
        e2 = err(th, np.array(os_ref)) if os_ref else (math.nan, math.nan)
        out(f"{label:48s} {tt*1e3:9.2f} {tc:9.1f} {e1[0]:11.2e}/{e1[1]:.2e} {e2[0]:11.2e}/{e2[1]:.2e} {fl:>8s}")
    if os_ref:
        e = err(np.array(os_ref), ref_j)
        out(f"references: |OpenSees(dt/8) − jaxrock(tight)| max {e[0]:.2e}, median {e[1]:.2e}")
    out("per cell (subsample): ω_p/p  a_p/(g tanα)  jaxrock  jax-ref  OpenSees  OS-ref  OS s")
    for k in range(len(idx)):
        o_ref = os_ref[k] if os_ref else math.nan
        out(f"  {wr_s[k]:6.2f} {ar_s[k]:6.2f}   {jax_sub[k]:.5f}  {ref_j[k]:.5f}  {os_th[k]:.5f}  {o_ref:.5f}  {os_t[k]:.3f}")
    ratio = t_os / t_jax
    return ratio


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny grids (smoke run)")
    ap.add_argument("--n-opensees", type=int, default=16, help="OpenSees subsample size per grid")
    ap.add_argument("--grid", type=int, default=32, help="quasi-rigid grid per axis")
    ap.add_argument("--flex-grid", type=int, default=4,
                    help="flexible grid per axis (default 4: 8 x 8 takes ~6 min of jaxrock on 2 CPUs)")
    ap.add_argument("--n-opensees-flex", type=int, default=6, help="OpenSees subsample of the flexible grid")
    ap.add_argument("--spp", type=int, default=400, help="OpenSees steps per pulse period")
    ap.add_argument("--no-os-ref", action="store_true", help="skip the OpenSees dt/8 reference")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.quick:
        args.grid, args.flex_grid, args.n_opensees, args.n_opensees_flex = 4, 2, min(args.n_opensees, 3), 2
    rng = np.random.default_rng(args.seed)
    out(f"# bench_spring: jaxrock SpringModel vs OpenSeesPy SM (benchmarks/opensees_sm.py)")
    out(f"# machine: {platform.machine()} {jax.device_count()} {jax.devices()[0].platform} device(s), "
        f"jax {jax.__version__}, python {platform.python_version()}")
    # quasi-rigid
    blk = jr.Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk)
    sc = osm.Scene(10.0, 2.0, E=None, n_elements=1)
    wr, ar = np.linspace(1, 15, args.grid), np.linspace(0.5, 10, args.grid)
    r_q = scene("quasi-rigid", model, sc, wr, ar, args.n_opensees, rng,
                SpringIntegrator(rtol=1e-11, atol=1e-11, solver="kvaerno5", max_steps=200_000), args)
    # flexible
    blk = jr.Block.from_size(50.0, 5.0)
    model = SpringModel(blk, Column.concrete(), n_elements=10)
    sc = osm.Scene(50.0, 5.0, E=30e9, n_elements=10)
    wr, ar = np.linspace(1, 15, args.flex_grid), np.linspace(0.5, 10, args.flex_grid)
    r_f = scene("flexible concrete", model, sc, wr, ar, args.n_opensees_flex, rng,
                SpringIntegrator(rtol=1e-7, atol=1e-7, solver="kvaerno5", max_steps=200_000), args)
    out("")
    out(f"speed-up per scene (OpenSees / jaxrock, compile excluded): quasi-rigid {r_q:.1f}x [target >= 100x], "
        f"flexible {r_f:.1f}x [target >= 20x]")
    res = HERE / "results"
    res.mkdir(exist_ok=True)
    (res / "bench_spring.txt").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
