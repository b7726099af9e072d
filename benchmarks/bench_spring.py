"""Spring-model (SM) benchmark: jaxrock vs the paper's own SM in OpenSeesPy (jaxrock/numerics/opensees_sm.py).

    python benchmarks/bench_spring.py [--quick] [--grid 32] [--flex-grid 8] [--n-opensees 32] [--n-opensees-flex 16]

Scenes (symmetric Ricker pulse, ω_p/p ∈ [1, 15], a_p/(g tanα) ∈ [0.5, 10], linspace grids):
- quasi-rigid: tanα = 0.2, 2h = 10 m; jaxrock `SpringModel(block)` (one-DOF rigid SM, eq. 10 with
  the damper) vs OpenSees one corotational element with E = 1e14 Pa;
- flexible: concrete (E = 30 GPa, ρ = 2500 kg/m³) 2h = 50 m, 2b = 5 m, 10 elements, ζ = 0.01,
  `SpringModel(block, Column.concrete(), n_elements=10)` vs the same mesh in OpenSees.
Both: added rotational masses, c̄ of eq. 17, the default backbones (quasi-rigid: bilinear at
θy = 1e-5 α; flexible: tanh at θs = 1e-4 α), OpenSees' `ElasticMultiLinear` sampling the same.

- jaxrock: `jaxrock.overturning_spectrum` on the whole grid, for the default integrator and the
  alternatives of the work–precision study (compile = first call − best of the next calls;
  per scene = best call / cells).
- Reference on the whole grid: jaxrock at a tight tolerance (quasi-rigid: Tsit5 1e-12;
  flexible: generalized-α 1e-9), itself checked on a few cells against an independent scheme
  (diffrax Kvaerno5: 1e-11 quasi-rigid, 1e-7 flexible) and against OpenSees at dt/8.
- OpenSees: a random subsample of cells, Newmark trapezoidal, dt = min(T_p, 2π/p)/400; time per
  scene includes building the model (as a user would run it).
- Errors: max/median |Δ max|θ|/α| against the reference (overturned = 1), for jaxrock on the whole
  grid and on the OpenSees subsample, so the two are compared on the same cells.

The printed table is also written to benchmarks/results/bench_spring.txt.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import jaxrock as jr  # noqa: E402
from jaxrock.spring import Checked, Column, GeneralizedAlpha, SpringIntegrator, SpringModel  # noqa: E402

from jaxrock.numerics import opensees_sm as osm  # noqa: E402

G = 9.81
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def jax_grid(model, wr, ar, integrator, repeat=5):
    t = time.perf_counter()
    jr.overturning_spectrum(model, wr, ar, integrator=integrator, progress=False)
    t1 = time.perf_counter() - t
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        spec = jr.overturning_spectrum(model, wr, ar, integrator=integrator, progress=False)
        best = min(best, time.perf_counter() - t)
    return spec, t1 - best, best / spec.max_theta.size


def jax_cells(model, a_p, w_p, integrator):
    f = jax.jit(jax.vmap(lambda a, w: jr.simulate(model, jr.RickerPulse(a, w), integrator=integrator)))
    sol = f(jnp.asarray(a_p), jnp.asarray(w_p))
    return np.asarray(sol.max_theta), np.asarray(jr.status_codes(sol.status))


def label(integ):
    if isinstance(integ, Checked):  # the flexible default
        return "Checked " + label(integ.integrator)
    if isinstance(integ, GeneralizedAlpha):
        return f"generalized-α ρ∞={integ.rho_inf:g} tol {integ.rtol:g}"
    rest = "" if integ.exact_rest else ", solver through pre-yield"
    return f"diffrax {integ.solver} tol {integ.rtol:g}{rest}"


def err(x, y):
    d = np.abs(np.asarray(x) - np.asarray(y))
    return float(np.max(d)), float(np.median(d))


def scene(name, model, sc, wr, ar, n_os, rng, ref_integrator, check_integrator, n_check, alternatives, args):
    blk = model.block
    p, ta = float(blk.p_r), float(jnp.tan(blk.alpha_r))
    out(f"\n## {name}: {len(ar)} x {len(wr)} grid, 2h = {float(blk.height):g} m, tanα = {ta:.3g}, "
        f"p = {p:.4f} rad/s" + (f", E = {sc.E:g} Pa, {sc.n} elements" if model.flexible else ", one-DOF"))
    W, A = np.meshgrid(wr, ar)
    a_all, w_all = (np.asarray(x).ravel() for x in jr.pulse_of_ratios(blk, A, W))
    t = time.perf_counter()
    ref, ref_st = jax_cells(model, a_all, w_all, ref_integrator)
    out(f"reference: jaxrock {label(ref_integrator)} on all {ref.size} cells, {time.perf_counter() - t:.1f} s, "
        f"failed {int(np.sum(ref_st != 0))}")
    idx = rng.choice(W.size, size=min(n_os, W.size), replace=False)
    chk = idx[:n_check]
    t = time.perf_counter()
    ref_chk, chk_st = jax_cells(model, a_all[chk], w_all[chk], check_integrator)
    e = err(ref_chk, ref[chk])
    out(f"reference check: {label(check_integrator)} on {len(chk)} cells ({time.perf_counter() - t:.1f} s, failed "
        f"{int(np.sum(chk_st != 0))}): |Δ| max {e[0]:.2e}, median {e[1]:.2e}")
    # OpenSees on the subsample
    os_th, os_t, os_fail, os_ref = [], [], 0, []
    for a, w in zip(a_all[idx], w_all[idx]):
        r = osm.run_pulse(sc, float(a), float(w), steps_per_period=args.spp)
        os_th.append(r["max_theta"])
        os_t.append(r["time"])
        os_fail += r["failed"]
        if not args.no_os_ref:
            os_ref.append(osm.run_pulse(sc, float(a), float(w), steps_per_period=8 * args.spp)["max_theta"])
    os_th, os_t = np.array(os_th), np.array(os_t)
    t_os = float(np.mean(os_t))
    if os_ref:
        e = err(os_ref, ref[idx])
        out(f"reference vs OpenSees dt/8 on the {len(idx)} subsample cells: |Δ| max {e[0]:.2e}, median {e[1]:.2e}")
    out(f"{'method':44s} {'ms/scene':>9s} {'compile s':>9s} {'err all cells max/med':>22s} {'err subsample max/med':>22s} {'failed':>8s}")
    rows = {}
    for integ in alternatives:
        spec, t_comp, t_jax = jax_grid(model, wr, ar, integ)
        th = spec.max_theta.ravel()
        rows[label(integ)] = (t_jax, th)
        ea, es = err(th, ref), err(th[idx], ref[idx])
        fl = f"{int(np.sum(spec.status != 0))}/{th.size}"
        out(f"{label(integ):44s} {t_jax * 1e3:9.3f} {t_comp:9.1f} {ea[0]:11.2e}/{ea[1]:.2e} {es[0]:11.2e}/{es[1]:.2e} {fl:>8s}")
    es = err(os_th, ref[idx])
    out(f"{'OpenSeesPy Newmark dt=T/' + str(args.spp):44s} {t_os * 1e3:9.3f} {0.0:9.1f} {'':>22s} {es[0]:11.2e}/{es[1]:.2e} "
        f"{f'{os_fail}/{len(idx)}':>8s}")
    t_def, th_def = rows[label(alternatives[0])]
    out("side by side (subsample): ω_p/p  a_p/(g tanα)  jaxrock  OpenSees  |Δ|  reference  OS-dt/8  OS ms")
    for k, i in enumerate(idx):
        o_ref = os_ref[k] if os_ref else math.nan
        out(f"  {W.ravel()[i]:6.2f} {A.ravel()[i]:6.2f}   {th_def[i]:.5f}  {os_th[k]:.5f}  {abs(th_def[i] - os_th[k]):.1e}"
            f"  {ref[i]:.5f}  {o_ref:.5f}  {os_t[k] * 1e3:.1f}")
    return {lab: t_os / tj for lab, (tj, _) in rows.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny grids (smoke run)")
    ap.add_argument("--grid", type=int, default=32, help="quasi-rigid grid per axis")
    ap.add_argument("--flex-grid", type=int, default=8, help="flexible grid per axis")
    ap.add_argument("--n-opensees", type=int, default=32, help="OpenSees subsample of the quasi-rigid grid")
    ap.add_argument("--n-opensees-flex", type=int, default=16, help="OpenSees subsample of the flexible grid")
    ap.add_argument("--spp", type=int, default=400, help="OpenSees steps per pulse period")
    ap.add_argument("--no-os-ref", action="store_true", help="skip the OpenSees dt/8 reference")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.quick:
        args.grid, args.flex_grid, args.n_opensees, args.n_opensees_flex = 4, 2, 3, 2
    rng = np.random.default_rng(args.seed)
    out("# bench_spring: jaxrock SpringModel vs OpenSeesPy SM (jaxrock/numerics/opensees_sm.py)")
    out(f"# machine: {platform.machine()} {jax.device_count()} {jax.devices()[0].platform} device(s), "
        f"{os.cpu_count()} cores, jax {jax.__version__}, python {platform.python_version()}")
    # quasi-rigid
    blk = jr.Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk)
    sc = osm.Scene(10.0, 2.0, E=None, n_elements=1)
    wr, ar = np.linspace(1, 15, args.grid), np.linspace(0.5, 10, args.grid)
    r_q = scene("quasi-rigid", model, sc, wr, ar, args.n_opensees, rng,
                SpringIntegrator(rtol=1e-12, atol=1e-12, solver="tsit5", max_steps=400_000),
                SpringIntegrator(rtol=1e-11, atol=1e-11, solver="kvaerno5", max_steps=200_000), 8,
                [model.default_integrator(), SpringIntegrator(rtol=1e-11, atol=1e-11, solver="tsit5", max_steps=200_000),
                 SpringIntegrator(rtol=1e-9, atol=1e-9, solver="tsit5", max_steps=200_000),
                 SpringIntegrator(rtol=1e-11, atol=1e-11, solver="tsit5", max_steps=200_000, exact_rest=False),
                 GeneralizedAlpha(1e-6, 1e-6), GeneralizedAlpha(1e-7, 1e-7)], args)
    # flexible
    blk = jr.Block.from_size(50.0, 5.0)
    model = SpringModel(blk, Column.concrete(), n_elements=10)
    sc = osm.Scene(50.0, 5.0, E=30e9, n_elements=10)
    wr, ar = np.linspace(1, 15, args.flex_grid), np.linspace(0.5, 10, args.flex_grid)
    r_f = scene("flexible concrete", model, sc, wr, ar, args.n_opensees_flex, rng,
                GeneralizedAlpha(1e-9, 1e-9, levels=24),
                SpringIntegrator(rtol=1e-7, atol=1e-7, solver="kvaerno5", max_steps=200_000), 3 if not args.quick else 1,
                [model.default_integrator(), GeneralizedAlpha(1e-4, 1e-4), GeneralizedAlpha(1e-6, 1e-6)], args)
    out("")
    out("speed-up per scene (OpenSees / jaxrock, compile excluded):")
    for lab, r in r_q.items():
        out(f"  quasi-rigid  {lab:40s} {r:7.1f}x  [target >= 50x at max error <= 1e-6]")
    for lab, r in r_f.items():
        out(f"  flexible     {lab:40s} {r:7.1f}x  [target >= 60x at an error below OpenSees']")
    if not args.quick:  # a smoke run leaves the committed results alone
        res = HERE / "results"
        res.mkdir(exist_ok=True)
        (res / "bench_spring.txt").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
