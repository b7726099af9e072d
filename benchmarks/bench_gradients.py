"""Cost of a gradient relative to a forward (summary) run, per model and autodiff mode.

    python benchmarks/bench_gradients.py [--n 64]

Scenes: `--n` random cells of the (ω_p/p, a_p/(g tanα)) plane (1–15 × 0.5–10, symmetric pulse,
seed 0) on the 2h = 10 m, tanα = 0.2 block, all vmapped in one call. Rows:

- forward run: `jax.vmap(simulate)` (the summary, max_theta), at the model's default integrator;
- reverse: `jax.vmap(jax.grad)` of max_theta with respect to (a_p, ω_p) (one backward pass);
- forward mode: `jax.vmap(jax.jacfwd)` with respect to (a_p, ω_p) (two tangents), with
  `autodiff="forward"` (RM, quasi-rigid SM) or the default generalized-α (flexible SM).

Warm times (median of 3) per scene, the ratio to the forward run, and compile time apart (first
call minus warm).

Smoothness of the flexible SM (10-element concrete column, 2h = 10 m, tanα = 0.2, a_p = 2 g tanα,
ω_p = 3p): max_theta over a_p swept ±1 % in 2000 intervals, at generalized-α 1e-5 (default) and
1e-7; a jump is an interval whose increment departs from the `jacfwd` slope by more than 10× the
median departure; central differences at steps 1e-6 … 1e-3 beside `jacfwd`.

Bias of generalized-α's forward-mode derivative (`--part bias`): on 8 random flexible scenes
(4-element concrete columns, 2h 5–30 m, tanα 0.12–0.3, a_p 1.2–3 g tanα, ω_p 2–8 p, seed 5) and
the same scenes' one-DOF quasi-rigid SM, `jacfwd` of max_theta in a_p against the slope of the
values themselves (a quadratic fitted to 41 runs over a_p ± 0.1 %, which averages the step
ladder's jumps out), at tolerances 1e-5 … 1e-9; and diffrax's Kvaerno5 at 1e-6 in reverse mode
(`jax.grad`; for the one-DOF SM its default Tsit5 1e-10) against the slope of generalized-α at
1e-9; per-scene values at the end.

Written to benchmarks/results/bench_gradients.txt (`--part bias`: bench_gradients_bias.txt).
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxrock as jr
from jaxrock.spring import Column, GeneralizedAlpha, SpringIntegrator, SpringModel

HERE = Path(__file__).resolve().parent
LINES: list[str] = []


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def timed(f, *args):
    t0 = time.perf_counter()
    jax.block_until_ready(f(*args))
    first = time.perf_counter() - t0
    warm = []
    for _ in range(3):
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        warm.append(time.perf_counter() - t0)
    w = float(np.median(warm))
    return w, first - w


def cases():
    blk = jr.Block.from_slenderness(10.0, 0.2)
    yield "RM", jr.RigidModel(blk), {"reverse": jr.EventIntegrator(), "forward": jr.EventIntegrator(autodiff="forward")}
    yield "quasi-rigid SM", SpringModel(blk), {
        "reverse": SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5"),
        "forward": SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5", autodiff="forward"),
    }
    flex = SpringModel(jr.Block.from_slenderness(10.0, 0.2), Column.concrete(), n_elements=4)
    yield "flexible SM (4 el.)", flex, {"forward": None}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=64, help="number of random scenes (vmapped)")
    ap.add_argument("--part", choices=("all", "bias"), default="all", help="bias: only the generalized-α bias table")
    args = ap.parse_args()
    if args.part == "bias":
        bias()
        (HERE / "results").mkdir(exist_ok=True)
        (HERE / "results" / "bench_gradients_bias.txt").write_text("\n".join(LINES) + "\n")
        return
    rng = np.random.default_rng(0)
    wr, ar = rng.uniform(1, 15, args.n), rng.uniform(0.5, 10, args.n)
    out(f"# gradient cost vs forward run — {args.n} random pulse scenes vmapped, 2h = 10 m, tanα = 0.2")
    out(f"# {platform.node()} · {platform.processor() or platform.machine()} · jax {jax.__version__} · {jax.devices()[0].platform}")
    out(f"{'model':22s} {'run':34s} {'ms/scene':>9s} {'× forward':>9s} {'compile s':>9s}")
    for name, model, integs in cases():
        blk = model.block
        a = jnp.asarray(ar * float(blk.uplift_acceleration))
        w = jnp.asarray(wr * float(blk.p_r))

        def peak(a_p, omega_p, integ):
            return jr.simulate(model, jr.RickerPulse(a_p, omega_p), integrator=integ).max_theta

        default = integs.get("reverse", integs.get("forward"))
        t_fwd, c_fwd = timed(jax.jit(jax.vmap(lambda a_p, w_p: peak(a_p, w_p, default))), a, w)
        out(f"{name:22s} {'forward run (summary)':34s} {1e3 * t_fwd / args.n:9.3f} {1.0:9.2f} {c_fwd:9.1f}")
        if "reverse" in integs:
            g = jax.jit(jax.vmap(jax.grad(lambda a_p, w_p: peak(a_p, w_p, integs["reverse"]), argnums=(0, 1))))
            t, c = timed(g, a, w)
            out(f"{name:22s} {'reverse: grad wrt (a_p, ω_p)':34s} {1e3 * t / args.n:9.3f} {t / t_fwd:9.2f} {c:9.1f}")
        jf = jax.jit(jax.vmap(jax.jacfwd(lambda a_p, w_p: peak(a_p, w_p, integs["forward"]), argnums=(0, 1))))
        t, c = timed(jf, a, w)
        out(f"{name:22s} {'forward mode: jacfwd wrt (a_p, ω_p)':34s} {1e3 * t / args.n:9.3f} {t / t_fwd:9.2f} {c:9.1f}")
    smoothness()
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "bench_gradients.txt").write_text("\n".join(LINES) + "\n")


def smoothness(n: int = 2001):
    blk = jr.Block.from_slenderness(10.0, 0.2)
    model = SpringModel(blk, Column.concrete())
    a0, w = 2 * jr.G * 0.2, 3 * float(blk.p_r)
    out()
    out(f"# flexible SM smoothness: a_p = {a0:.4f} m/s² ± 1 % in {n - 1} intervals, ω_p = 3p")
    out(f"{'tol':>6s} {'jacfwd':>9s} {'jumps':>6s} {'median jump':>12s} {'max jump':>9s}   central differences at 1e-6, 1e-5, 1e-4, 1e-3")
    for tol in (1e-5, 1e-7):
        integ = GeneralizedAlpha(tol, tol)
        peak = lambda a: jr.simulate(model, jr.RickerPulse(a, w), integrator=integ).max_theta
        f = jax.jit(jax.vmap(peak))
        rel = np.linspace(-1e-2, 1e-2, n)
        v = np.asarray(f(jnp.asarray(a0 * (1 + rel))))
        g = float(jax.jit(jax.jacfwd(peak))(a0))
        dev = np.abs(np.diff(v) - g * a0 * (rel[1] - rel[0]))
        jumps = dev > 10 * np.median(dev) + 1e-12
        hs = np.array([1e-6, 1e-5, 1e-4, 1e-3])
        probe = np.concatenate([a0 * (1 + hs), a0 * (1 - hs), np.full(n - 8, a0)])
        vp = np.asarray(f(jnp.asarray(probe)))
        fd = (vp[:4] - vp[4:8]) / (2 * hs * a0)
        med = float(np.median(dev[jumps])) if jumps.any() else 0.0
        out(f"{tol:6.0e} {g:9.4f} {int(jumps.sum()):6d} {med:12.2e} {dev.max():9.2e}   " + ", ".join(f"{x:.4f}" for x in fd))


def bias(n: int = 8, points: int = 41, span: float = 1e-3):
    rng = np.random.default_rng(5)
    H, TA, AR, WR = rng.uniform(5, 30, n), rng.uniform(0.12, 0.3, n), rng.uniform(1.2, 3.0, n), rng.uniform(2, 8, n)
    r = np.linspace(-span, span, points)
    rep = lambda x: jnp.asarray(np.repeat(x, points))
    grid = (jnp.asarray((AR[:, None] * (1 + r)[None]).ravel()), rep(H), rep(TA), rep(WR))
    centre = tuple(jnp.asarray(x) for x in (AR, H, TA, WR))

    def peak_of(column, integ):
        def peak(a_r, h, ta, wr):
            blk = jr.Block.from_slenderness(h, ta)
            model = SpringModel(blk, column, n_elements=4)
            return jr.simulate(model, jr.RickerPulse(a_r * blk.uplift_acceleration, wr * blk.p_r), integrator=integ).max_theta

        return peak

    out(f"# generalized-α: jacfwd of max_theta in a_p vs the slope of the values (quadratic fit over a_p ± {span:g}), {n} scenes")
    out(f"{'column':10s} {'integrator':22s} {'ms/scene':>9s} {'median |d/slope − 1|':>21s} {'max':>8s}")
    per_scene = []
    for name, column in (("flexible", Column.concrete()), ("one-DOF", None)):
        for tol in ((1e-5, 1e-7, 1e-9) if column is not None else (1e-7, 1e-9)):
            peak = peak_of(column, GeneralizedAlpha(tol, tol))
            f = jax.jit(jax.vmap(peak))
            jax.block_until_ready(f(*grid))
            t0 = time.perf_counter()
            v = np.asarray(f(*grid)).reshape(n, points)
            ms = 1e3 * (time.perf_counter() - t0) / (n * points)
            slope = np.array([np.polyfit(r, v[i], 2)[1] for i in range(n)])  # d/d(relative a_p) at the centre
            jac = np.asarray(jax.jit(jax.vmap(jax.jacfwd(peak)))(*centre)) * AR
            dev = np.abs(jac / slope - 1)
            out(f"{name:10s} {f'generalized-α {tol:.0e}':22s} {ms:9.1f} {np.median(dev):21.1e} {dev.max():8.1e}")
            if tol == 1e-9:
                per_scene.append((name, jac, slope))
        # the reverse-mode diffrax choice of each model, against the slope of generalized-α at 1e-9
        label, integ = ("Kvaerno5 1e-6", SpringIntegrator(rtol=1e-6, atol=1e-6)) if column is not None else ("Tsit5 1e-10", SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5"))
        g = np.asarray(jax.jit(jax.vmap(jax.grad(peak_of(column, integ))))(*centre)) * AR
        slope = per_scene[-1][2]
        dev = np.abs(g / slope - 1)
        out(f"{name:10s} {label + ', grad':22s} {'':>9s} {np.median(dev):21.1e} {dev.max():8.1e}")
        per_scene.append((f"{name}, {label} grad", g, slope))
    out("# per scene (d max_theta / d relative a_p), generalized-α 1e-9 unless named")
    for name, jac, slope in per_scene:
        out(f"{name:24s} derivative " + " ".join(f"{x:8.4f}" for x in jac))
        out(f"{'':24s} slope      " + " ".join(f"{x:8.4f}" for x in slope))


if __name__ == "__main__":
    main()
