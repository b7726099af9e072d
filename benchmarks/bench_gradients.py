"""Cost of a gradient relative to a forward (summary) run, per model and autodiff mode.

    python benchmarks/bench_gradients.py [--n 64]

Scenes: `--n` random cells of the (ω_p/p, a_p/(g tanα)) plane (1–15 × 0.5–10, symmetric pulse,
seed 0) on the 2h = 10 m, tanα = 0.2 block, all vmapped in one call. Rows:

- forward run: `jax.vmap(simulate)` (the summary, max_theta), at the model's default integrator;
- reverse: `jax.vmap(jax.grad)` of max_theta with respect to (a_p, ω_p) (one backward pass);
- forward mode: `jax.vmap(jax.jacfwd)` with respect to (a_p, ω_p) (two tangents), with
  `autodiff="forward"` (RM, quasi-rigid SM) or the default generalized-α (flexible SM, whose
  reverse mode is the same settings with `autodiff="reverse"`).

Warm times (median of 3) per scene, the ratio to the forward run, and compile time apart (first
call minus warm).

Smoothness of the flexible SM (10-element concrete column, 2h = 10 m, tanα = 0.2, a_p = 2 g tanα,
ω_p = 3p): max_theta over a_p swept ±1 % in 2000 intervals, at generalized-α 1e-5 (default) and
1e-7, each with and without the crossing limit; a jump is an interval whose increment departs
from the `jacfwd` slope by more than 10× the median departure; central differences at steps
1e-6 … 1e-3 beside `jacfwd`.

Accuracy of generalized-α's forward-mode derivative (`--part bias`), with and without its limit
on steps through the spring's pre-yield band (`GeneralizedAlpha.crossing`), on random scenes
(2h 5–30 m, tanα 0.12–0.3, a_p 1.2–3 g tanα, ω_p 2–8 p, seed 5): for 64 one-DOF quasi-rigid
scenes, `jacfwd` of max_theta in a_p against Tsit5's reverse-mode gradient at 1e-11, and the
values against Tsit5 at 1e-11; for the first 8 as flexible 4-element concrete columns (no
explicit solver can run them), against the slope of the values (a quadratic fitted to 21 runs of
generalized-α 1e-7 over a_p ± 0.1 %), and diffrax's Kvaerno5 1e-6 in reverse mode beside them.

Written to benchmarks/results/bench_gradients.txt (`--part bias` / `smooth`: bench_gradients_bias.txt /
_smooth.txt).
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
    yield "flexible SM (4 el.)", flex, {"run": None, "reverse": flex.default_integrator("reverse"), "forward": None}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=64, help="number of random scenes (vmapped)")
    ap.add_argument("--part", choices=("all", "bias", "smooth"), default="all",
                    help="bias: only the generalized-α accuracy tables; smooth: only the flexible smoothness sweep")
    args = ap.parse_args()
    if args.part != "all":
        bias() if args.part == "bias" else smoothness()
        (HERE / "results").mkdir(exist_ok=True)
        (HERE / "results" / f"bench_gradients_{args.part}.txt").write_text("\n".join(LINES) + "\n")
        return
    rng = np.random.default_rng(0)
    wr, ar = rng.uniform(1, 15, args.n), rng.uniform(0.5, 10, args.n)
    out(f"# gradient cost vs forward run — {args.n} random pulse scenes vmapped, 2h = 10 m, tanα = 0.2")
    out(f"# {platform.node()} · {platform.processor() or platform.machine()} · jax {jax.__version__} · {jax.devices()[0].platform}")
    out(f"{'model':22s} {'run':34s} {'ms/scene':>9s} {'× forward':>9s} {'compile s':>9s}")
    for name, model, integs in cases():
        blk = model.block
        a, w = (jnp.asarray(x) for x in jr.pulse_of_ratios(blk, ar, wr))

        def peak(a_p, omega_p, integ):
            return jr.simulate(model, jr.RickerPulse(a_p, omega_p), integrator=integ).max_theta

        default = integs["run"] if "run" in integs else integs.get("reverse", integs.get("forward"))
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
    a0, w = (float(x) for x in jr.pulse_of_ratios(blk, 2.0, 3.0))
    out()
    out(f"# flexible SM smoothness: a_p = {a0:.4f} m/s² ± 1 % in {n - 1} intervals, ω_p = 3p")
    out(f"{'tol':>6s} {'crossing':>8s} {'jacfwd':>9s} {'jumps':>6s} {'median jump':>12s} {'max jump':>9s}   central differences at 1e-6, 1e-5, 1e-4, 1e-3")
    for tol, crossing in ((1e-5, None), (1e-5, 1.0), (1e-7, None), (1e-7, 1.0)):
        integ = GeneralizedAlpha(tol, tol, crossing=crossing)
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
        out(f"{tol:6.0e} {str(crossing):>8s} {g:9.4f} {int(jumps.sum()):6d} {med:12.2e} {dev.max():9.2e}   " + ", ".join(f"{x:.4f}" for x in fd))


def bias(n_one: int = 64, n_flex: int = 8, points: int = 21, span: float = 1e-3):
    """Generalized-α's `jacfwd` against a trusted derivative, with and without the crossing limit."""
    rng = np.random.default_rng(5)
    n = max(n_one, n_flex)
    H, TA, AR, WR = rng.uniform(5, 30, n), rng.uniform(0.12, 0.3, n), rng.uniform(1.2, 3.0, n), rng.uniform(2, 8, n)

    def peak_of(column, integ):
        def peak(a_r, h, ta, wr):
            blk = jr.Block.from_slenderness(h, ta)
            model = SpringModel(blk, column, n_elements=4)
            return jr.simulate(model, jr.RickerPulse(*jr.pulse_of_ratios(blk, a_r, wr)), integrator=integ).max_theta

        return peak

    def jac_of(peak, scenes, mode="jacfwd"):
        f = jax.jit(jax.vmap(jax.jacfwd(peak) if mode == "jacfwd" else jax.grad(peak)))
        jax.block_until_ready(f(*scenes))
        t0 = time.perf_counter()
        d = np.asarray(f(*scenes))
        return d * np.asarray(scenes[0]), 1e3 * (time.perf_counter() - t0) / len(d)

    def row(label, d, ref, ms, v=None, vref=None):
        err = np.abs(d - ref) / np.maximum(np.abs(ref), 0.05)  # relative, absolute below |d/dln a_p| = 0.05
        verr = f"{np.median(np.abs(v / vref - 1)):10.1e}" if v is not None else f"{'':10s}"
        out(f"{label:34s} {np.median(err):8.1e} {np.quantile(err, 0.9):8.1e} {err.max():8.1e} {verr} {ms:9.2f}")

    head = f"{'integrator':34s} {'median':>8s} {'p90':>8s} {'max':>8s} {'value err':>10s} {'ms/scene':>9s}"
    # one-DOF quasi-rigid SM: the truth is Tsit5's reverse-mode gradient at 1e-11
    one = tuple(jnp.asarray(x[:n_one]) for x in (AR, H, TA, WR))
    tsit = SpringIntegrator(rtol=1e-11, atol=1e-11, solver="tsit5", max_steps=200_000)
    ref, _ = jac_of(peak_of(None, tsit), one, "grad")
    vref = np.asarray(jax.jit(jax.vmap(peak_of(None, tsit)))(*one))
    out(f"# one-DOF SM, {n_one} random scenes (2h 5–30 m, tanα 0.12–0.3, a_p 1.2–3 g tanα, ω_p 2–8 p, seed 5):")
    out("# d max_theta / d ln a_p by jacfwd against Tsit5 1e-11 reverse mode; value error against Tsit5 1e-11")
    out(head)
    for tol in (1e-5, 1e-6, 1e-7, 1e-8):
        for crossing in (None, 2.0, 1.0, 0.5) if tol == 1e-5 else (None, 1.0):
            peak = peak_of(None, GeneralizedAlpha(tol, tol, crossing=crossing))
            d, ms = jac_of(peak, one)
            v = np.asarray(jax.jit(jax.vmap(peak))(*one))
            row(f"generalized-α {tol:.0e}, crossing {crossing}", d, ref, ms, v, vref)
    d, ms = jac_of(peak_of(None, SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5")), one, "grad")
    row("Tsit5 1e-10 (default), grad", d, ref, ms)

    # flexible SM: the truth is the slope of generalized-α's values (1e-7, crossing 1: the smoothest)
    # over a_p ± span, a quadratic fitted to `points` runs
    flex = tuple(jnp.asarray(x[:n_flex]) for x in (AR, H, TA, WR))
    r = np.linspace(-span, span, points)
    rep = lambda x: jnp.asarray(np.repeat(x[:n_flex], points))
    grid = (jnp.asarray((AR[:n_flex, None] * (1 + r)[None]).ravel()), rep(H), rep(TA), rep(WR))
    column = Column.concrete()
    v = np.asarray(jax.jit(jax.vmap(peak_of(column, GeneralizedAlpha(1e-7, 1e-7, crossing=1.0))))(*grid)).reshape(n_flex, points)
    fits = [np.polyfit(r, v[i], 2) for i in range(n_flex)]
    slope = np.array([c[1] for c in fits])
    resid = np.array([np.std(v[i] - np.polyval(fits[i], r)) for i in range(n_flex)])
    out()
    out(f"# flexible SM (4-element concrete columns), the first {n_flex} scenes: jacfwd against the slope of the values")
    out(f"# (generalized-α 1e-7, crossing 1; quadratic over a_p ± {span:g}, {points} runs; fit residual {np.median(resid):.1e} median)")
    out(head)
    per_scene = []
    for tol in (1e-5, 1e-7):
        for crossing in (None, 1.0):
            d, ms = jac_of(peak_of(column, GeneralizedAlpha(tol, tol, crossing=crossing)), flex)
            row(f"generalized-α {tol:.0e}, crossing {crossing}", d, slope, ms)
            per_scene.append((f"GA {tol:.0e}, crossing {crossing}", d))
    d, ms = jac_of(peak_of(column, SpringIntegrator(rtol=1e-6, atol=1e-6)), flex, "grad")
    row("Kvaerno5 1e-6, grad", d, slope, ms)
    per_scene.append(("Kvaerno5 1e-6, grad", d))
    out("# per scene, d max_theta / d ln a_p")
    out(f"{'slope of the values':28s} " + " ".join(f"{x:8.4f}" for x in slope))
    for name, d in per_scene:
        out(f"{name:28s} " + " ".join(f"{x:8.4f}" for x in d))


if __name__ == "__main__":
    main()
