"""The spring's backbone and its pre-yield rotation θs, chosen by a study over many scenes (issues 20, 56).

    python benchmarks/bench_backbone.py [--quick] [--n-rigid 192] [--n-flex 48] [--seed 0]
    python benchmarks/bench_backbone.py --part gradients


Scenes (seeded uniform sample, both pulse kinds in equal numbers): tanα ∈ [0.05, 0.35],
2h ∈ [1, 50] m (log-uniform), ω_p/p′ ∈ [1, 15] (log-uniform), a_p/(g tanα) ∈ [1, 8]; the
quasi-rigid one-DOF SM, and flexible concrete columns (E = 30 GPa, 10 elements, ζ = 0.01); added
masses, c̄ of eq. 17. Then new scenes from seed + 1: pulses as above and El Centro 1940 NS scaled
to PGA/(g tanα) ∈ [1, 4] (56 + 24 quasi-rigid, 16 + 8 flexible).

For each backbone (bilinear, tanh) and θs/α ∈ {1e-3 … 3e-6}:
- error: |max|θ|/α − the sharp limit| (overturned = 1), the sharp limit being the bilinear backbone
  at θy = 1e-6 α (its own distance to the limit estimated by first-order extrapolation,
  |f(1e-6) − f(2e-6)|, and printed); runs at tight tolerances so that the backbone error is what
  is measured (quasi-rigid: Tsit5 1e-10, the default, ~1e-8, stopping on the bilinear kinks;
  flexible: generalized-α 1e-7);
- verdict changes: scenes that overturn in one and not in the other (their error is the jump to
  1, listed apart, with the scene);
- cost: ms per scene of the model's default integrator on the whole vmapped batch (compaction as
  in the spectra), best of two warm calls; for flexible columns also the default integrator's
  total error (backbone + time steps).

`--part gradients`: the defaults' derivatives. On 16 seeded scenes per model (a_p/(g tanα) 1.2–6,
2h 5–30 m, tanα 0.12–0.3, ω_p/p 2–8), d max|θ|/α, d t_uplift and d t_overturn / d ln a_p in both
autodiff modes against central differences (h = 1e-4 in ln a_p): quasi-rigid with Tsit5 1e-10 (the
default) and generalized-α 1e-6, flexible with generalized-α 1e-6 on its default (the
bilinear backbone at θy = 1e-5 α, generalized-α ending its steps on the kinks) and on tanh at
θs = 1e-4 α (the default before); and
calibration's reverse-mode ∂r_eq²/∂c̄ (Tsit5 1e-10 and 1e-12; tanα = 0.2, c̄ = 0.08, θ₀ = 0.7 α)
for tanh at θs = 1e-4 α and the bilinear backbone at θy = 1e-5 α.

`--part sawtooth`: whether generalized-α's derivatives through the bilinear's kinks are the motion's:
d max θ/d ln a_p by `jacfwd` at tolerance 1e-8 against central differences at h = 1e-2 … 1e-7 and the
motion's (a sawtooth while its steps stepped over the kinks on a grid fixed in time).

`--part transit`: whether generalized-α's derivative leaves the motion's: the history θ(t) of the first
6 gradient scenes (quasi-rigid, generalized-α 1e-8) differentiated along ln a_p by `jacfwd`, against
the motion's (Tsit5 1e-11, forward mode, stopping on the kinks) and generalized-α's own central
difference (h = 1e-4), before and after the first band transit (the first impact), on both backbones.

`--part tolerance`: the quasi-rigid default's tolerance by convergence over the study's scenes (Tsit5
1e-9 … 1e-11 against 1e-12), with the exact pre-yield phase and without.

`--part rest`: the exact pre-yield phase's grid (`jaxrock.spring.rest`): first yields against a finer
grid on the study's pulses, and on El Centro against the same record sampled finer.

`--part cost`: where the sharp spring's cost comes from: steps and warm ms per scene of the
quasi-rigid SM on 64 seeded pulses, tanh and bilinear at θs = 1e-4 and 1e-5 α (Tsit5, the default),
and Kvaerno5 on the bilinear.

The printed tables are also written to benchmarks/results/bench_backbone.txt (and
bench_backbone_gradients.txt, bench_backbone_sawtooth.txt, bench_backbone_transit.txt, bench_backbone_cost.txt).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxrock as jr
from jaxrock import AntisymmetricRickerPulse, Block, Column, GeneralizedAlpha, RickerPulse, SpringIntegrator, SpringModel
from jaxrock.spring.base_spring import as_backbone

HERE = Path(__file__).resolve().parent
LINES: list[str] = []
SMOOTHINGS = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6)
SHARP = (1e-6, 2e-6)  # bilinear reference and its extrapolation partner
OWN_TOL = 1e-4  # the reference's own error estimate above which a scene counts as unsettled
TSIT5 = SpringIntegrator(rtol=1e-10, atol=1e-10, solver="tsit5")
GA7 = GeneralizedAlpha(rtol=1e-7, atol=1e-7)
GRADIENT_BACKBONES = tuple((b, float(s)) for b, s in (x.split(":") for x in os.environ.get("GRADIENT_BACKBONES", "tanh:1e-4,bilinear:1e-5").split(",")))


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def sample(n, rng, n_records=0):
    """(2h, tanα, ω_p/p, a_p/(g tanα), kind) for n pulse scenes, symmetric and antisymmetric in
    turn, then `n_records` El Centro scenes (the record scaled to PGA/(g tanα) = `ar` ∈ [1, 4])."""
    m = n + n_records
    scenes = dict(
        height=np.exp(rng.uniform(math.log(1.0), math.log(50.0), m)),
        tan_alpha=rng.uniform(0.05, 0.35, m),
        wr=np.exp(rng.uniform(0.0, math.log(15.0), m)),
        ar=rng.uniform(1.0, 8.0, m),
        kind=np.where(np.arange(m) % 2 == 1, "anti", "sym").astype(object),
    )
    scenes["kind"][n:] = "record"
    scenes["ar"][n:] = rng.uniform(1.0, 4.0, n_records)
    return scenes


def excitations(kind, blk, ar, wr):
    """The stacked excitations of one kind of scene (`blk`: the stacked blocks)."""
    if kind == "record":
        rec = jr.el_centro()
        return jax.vmap(rec.scaled)(ar * jr.G * blk.tan_alpha / float(jnp.max(jnp.abs(rec.acc))))
    a_p, w_p = jax.vmap(jr.pulse_of_ratios)(blk, ar, wr)
    return (AntisymmetricRickerPulse if kind == "anti" else RickerPulse)(a_p, w_p)


def batch(scenes, idx, flexible, backbone, smoothing, kind):
    """Stacked models and excitations of the scenes `idx` (all of one `kind`)."""
    def one(h2, ta):
        blk = Block.from_slenderness(h2, ta)
        col = Column.concrete() if flexible else None
        return SpringModel(blk, col, backbone=backbone, smoothing=smoothing)

    arr = lambda k: jnp.asarray(scenes[k][idx])
    models = jax.vmap(one)(arr("height"), arr("tan_alpha"))
    return models, excitations(kind, models.block, arr("ar"), arr("wr"))


def run(scenes, flexible, backbone, smoothing, integrator, timed=False):
    """max θ/α and status of every scene (and seconds per scene, best of two warm calls)."""
    theta = np.full(scenes["ar"].size, np.nan)
    status = np.zeros(scenes["ar"].size, int)
    per_scene = 0.0
    for kind in ("sym", "anti", "record"):
        idx = np.flatnonzero(scenes["kind"] == kind)
        if idx.size == 0:
            continue
        models, exc = batch(scenes, idx, flexible, backbone, smoothing, kind)
        go = lambda: jax.block_until_ready(jr.run_batch(models, exc, integrator, model_batched=True))
        sol = go()
        if timed:
            best = math.inf
            for _ in range(2):
                t = time.perf_counter()
                go()
                best = min(best, time.perf_counter() - t)
            per_scene += best
        theta[idx] = np.asarray(sol.max_theta)
        status[idx] = np.asarray(jr.status_codes(sol.status))
    return theta, status, per_scene / scenes["ar"].size


def describe(scenes, i):
    if scenes["kind"][i] == "record":
        return f"2h {scenes['height'][i]:.1f} m, tanα {scenes['tan_alpha'][i]:.3f}, El Centro at PGA/(g tanα) {scenes['ar'][i]:.2f}"
    return (f"2h {scenes['height'][i]:.1f} m, tanα {scenes['tan_alpha'][i]:.3f}, ω_p/p {scenes['wr'][i]:.2f}, "
            f"a_p/(g tanα) {scenes['ar'][i]:.2f}, {scenes['kind'][i]}")


def study(name, scenes, flexible, error_integrator, default_integrator):
    n = scenes["ar"].size
    out(f"\n## {name}: {n} scenes ({int(np.sum(scenes['kind'] == 'anti'))} antisymmetric pulses, "
        f"{int(np.sum(scenes['kind'] == 'record'))} records)")
    t = time.perf_counter()
    ref, ref_st, _ = run(scenes, flexible, "bilinear", SHARP[0], error_integrator)
    ref2, _, _ = run(scenes, flexible, "bilinear", SHARP[1], error_integrator)
    own = np.abs(ref - ref2)
    out(f"sharp limit: bilinear θy = {SHARP[0]:g} α ({time.perf_counter() - t:.0f} s, failed {int(np.sum(ref_st != 0))}); "
        f"its own error |f(1e-6) − f(2e-6)|: max {own.max():.1e}, median {np.median(own):.1e}; "
        f"{int(np.sum(ref >= 1))} scenes overturn")
    settled = own < OWN_TOL
    out(f"{int(np.sum(~settled))} scenes where the sharp limit is itself unsettled (own error ≥ {OWN_TOL:g}: a response "
        f"that hangs on a near-tie, e.g. whether a late impact re-lifts the block); 'max settled' leaves them out")
    head = f"{'backbone':9s} {'θs/α':>7s} {'max err':>9s} {'max settled':>11s} {'p99':>9s} {'median':>9s} {'verdicts':>8s} {'failed':>6s} {'ms/scene':>9s}"
    if flexible:
        head += f" {'default-integrator err max/median':>34s}"
    out(head)
    rows = []
    for backbone in ("bilinear", "tanh"):
        for s in SMOOTHINGS:
            th, st, _ = run(scenes, flexible, backbone, s, error_integrator)
            th_d, st_d, cost = run(scenes, flexible, backbone, s, default_integrator, timed=True)
            flip = (th >= 1) != (ref >= 1)
            err = np.abs(th - ref)
            e = err[~flip]
            i_max = np.flatnonzero(~flip)[np.argmax(e)]
            e_set = err[~flip & settled]
            line = (f"{backbone:9s} {s:7.0e} {e.max():9.2e} {e_set.max():11.2e} {np.quantile(e, 0.99):9.2e} {np.median(e):9.2e} "
                    f"{int(flip.sum()):8d} {int(np.sum(st != 0)) + int(np.sum(st_d != 0)):6d} {cost * 1e3:9.2f}")
            if flexible:
                ed = np.abs(th_d - ref)[~flip]
                line += f" {ed.max():16.2e}/{np.median(ed):.2e}"
            out(line)
            rows.append((backbone, s, e.max(), i_max, np.flatnonzero(flip), th))
    out("unsettled scenes (own error of the sharp limit): " + "; ".join(f"{own[i]:.1e} at {describe(scenes, i)}" for i in np.flatnonzero(~settled)))
    out("largest error (same verdict) per setting, and the scenes whose verdict changes:")
    for backbone, s, emax, i_max, flips, th in rows:
        out(f"  {backbone:8s} {s:7.0e}: {emax:.2e} at {describe(scenes, i_max)}")
        for i in flips:
            out(f"      verdict changes: {th[i]:.4f} vs sharp {ref[i]:.4f} at {describe(scenes, i)}")
    return rows


def _relative(d, fd, floor):
    """|d − fd| / max(|fd|, floor) where both are finite."""
    ok = np.isfinite(d) & np.isfinite(fd)
    return np.where(ok, np.abs(d - fd) / np.maximum(np.abs(fd), floor), np.nan), ok


def gradient_scenes(n=16):
    """(a_p/(g tanα), 2h, tanα, ω_p/p) of the derivative parts' seeded scenes: rocking, a third or so
    overturning."""
    rng = np.random.default_rng(11)
    return tuple(jnp.asarray(x) for x in (rng.uniform(1.2, 6.0, n), rng.uniform(5, 30, n), rng.uniform(0.12, 0.3, n),
                                          rng.uniform(2, 8, n)))


def pulse_summary(integrator, column=None, **spring):
    """(ln a_p/(g tanα), 2h, tanα, ω_p/p) → [max θ/α, t_uplift, t_overturn] of the SM under a Ricker pulse."""
    def run(log_ar, h2, ta, wr):
        blk = Block.from_slenderness(h2, ta)
        ex = RickerPulse(*jr.pulse_of_ratios(blk, jnp.exp(log_ar), wr))
        s = jr.simulate(SpringModel(blk, column, **spring), ex, integrator=integrator)
        return jnp.stack([s.max_theta, s.t_uplift, s.t_overturn])

    return run


def gradients() -> None:
    """Derivatives of the defaults against central differences (issue 56, item 3)."""
    from jaxrock.analyses.free_rocking import SpringFamily, energy_ratio

    out("# bench_backbone --part gradients: derivatives against central differences (h = 1e-4 in ln a_p)")
    out(f"# defaults: backbone {jr.DEFAULT_BACKBONE} (by model), θs/α {jr.DEFAULT_SMOOTHING} (by backbone)")
    scenes = gradient_scenes()
    h = 1e-4
    outputs = ("max_theta", "t_uplift", "t_overturn")
    floors = {"max_theta": 0.05, "t_uplift": 0.01, "t_overturn": 0.01}  # the scale below which an error is absolute
    out(f"{'model, backbone':27s} {'integrator':>24s} {'mode':>8s}  " + "  ".join(f"{o + ' median/max (n)':>28s}" for o in outputs) + "  s")
    # (model, column, backbone (None: the model's default), integrator name, integrator by mode).
    # Reverse mode through generalized-α is its `autodiff="reverse"` (the flexible column under
    # Kvaerno5, the reverse-mode route before it, is left out: 8 scenes at 1e-9 in forward mode had
    # not finished in 35 min on 2 cores, 2026-11-29)
    ga = lambda a: GeneralizedAlpha(1e-6, 1e-6, autodiff=a)
    rows = (
        ("quasi-rigid", None, None, "Tsit5 1e-10 (default)", lambda a: SpringIntegrator(1e-10, 1e-10, "tsit5", max_steps=200_000, autodiff=a)),
        ("quasi-rigid", None, None, "generalized-α 1e-6", ga),
        ("flexible", Column.concrete(), None, "generalized-α 1e-6", ga),
        ("flexible", Column.concrete(), ("tanh", 1e-4), "generalized-α 1e-6", ga),  # the flexible default before issue 56
    )
    for name, column, backbone, iname, make in rows:
        spring = {} if backbone is None else dict(backbone=backbone[0], smoothing=backbone[1])
        name_b = f"{name} {spring['backbone']} {spring['smoothing']:g}" if spring else f"{name} (default)"
        for mode in ("forward", "reverse"):
            t = time.perf_counter()
            run = pulse_summary(make(mode), column, **spring)
            x = jnp.log(scenes[0])
            f = jax.jit(jax.vmap(run))
            derivative = jax.jacfwd(run) if mode == "forward" else jax.jacrev(run)
            d = np.asarray(jax.jit(jax.vmap(derivative))(x, *scenes[1:]))
            fd = (np.asarray(f(x + h, *scenes[1:])) - np.asarray(f(x - h, *scenes[1:]))) / (2 * h)
            cells = []
            for k, o in enumerate(outputs):
                err, ok = _relative(d[:, k], fd[:, k], floors[o])
                cells.append(f"{np.nanmedian(err):.1e}/{np.nanmax(err):.1e} ({int(ok.sum())})" if ok.any() else "—")
            out(f"{name_b:27s} {iname:>24s} {mode:>8s}  " + "  ".join(f"{c:>28s}" for c in cells) + f"  {time.perf_counter() - t:.0f}")
    out(f"\n{'backbone':9s} {'θs/α':>6s} {'integrator':>18s}  ∂r_eq²/∂c̄ reverse mode, central differences (h = 1e-4): tanα 0.2, c̄ 0.08, θ₀ = 0.7 α")
    for backbone, s in GRADIENT_BACKBONES:
        for tol in (1e-10, 1e-12):
            integ = SpringIntegrator(rtol=tol, atol=tol, solver="tsit5", max_steps=200_000)
            fam = SpringFamily(backbone=backbone, smoothing=s)
            r2 = lambda c: energy_ratio(fam(0.2, c), 0.7, integrator=integ)
            g = float(jax.jit(jax.grad(r2))(0.08))
            fd = float((jax.jit(r2)(0.08 + 1e-4) - jax.jit(r2)(0.08 - 1e-4)) / 2e-4)
            out(f"{backbone:9s} {s:6.0e} {'Tsit5 ' + format(tol, 'g'):>18s}  {g:.8f}  {fd:.8f}  relative {abs(g - fd) / abs(fd):.1e}")


def sawtooth() -> None:
    """Whether generalized-α's derivatives through the bilinear's kinks are the motion's (issue 56, item 1): on
    the first 6 of `gradients`' scenes (quasi-rigid, generalized-α at 1e-8), d max θ/d ln a_p by
    `jacfwd` against central differences at h = 1e-2 … 1e-7 and the motion's derivative (Tsit5 1e-11,
    forward mode, stopping on the kinks). A smooth discrete map gives one value in every column;
    a sawtooth gives the motion's at large h and its teeth's slope (`jacfwd`'s) at small h."""
    out("# bench_backbone --part sawtooth: quasi-rigid, generalized-α 1e-8, d max θ/d ln a_p")
    sc = gradient_scenes()
    hs = (1e-2, 1e-3, 1e-5, 1e-7)
    out(f"{'backbone':9s} {'θs/α':>6s} {'scene':>5s} {'max θ/α':>8s} {'motion':>9s} {'jacfwd':>9s}  " + " ".join(f"{'cd h=' + format(h, 'g'):>10s}" for h in hs))
    for backbone, smoothing in (("bilinear", 1e-5), ("tanh", 1e-4)):
        def max_theta(integrator):
            run = pulse_summary(integrator, backbone=backbone, smoothing=smoothing)
            return lambda *a: run(*a)[0]

        ga = max_theta(GeneralizedAlpha(1e-8, 1e-8))
        ref = max_theta(SpringIntegrator(1e-11, 1e-11, "tsit5", max_steps=400_000, autodiff="forward"))
        f, d_ga, d_ref = jax.jit(ga), jax.jit(jax.jacfwd(ga)), jax.jit(jax.jacfwd(ref))
        for i in range(6):
            a = (jnp.log(sc[0][i]), sc[1][i], sc[2][i], sc[3][i])
            cds = [(float(f(a[0] + h, *a[1:])) - float(f(a[0] - h, *a[1:]))) / (2 * h) for h in hs]
            out(f"{backbone:9s} {smoothing:6.0e} {i:5d} {float(f(*a)):8.5f} {float(d_ref(*a)):9.5f} {float(d_ga(*a)):9.5f}  "
                + " ".join(f"{c:10.5f}" for c in cds))


def transit() -> None:
    """Whether generalized-α's derivative leaves the motion's (issue 56, item 1): d θ(t)/d ln a_p on
    the history, before and after the first crossing of the pre-yield band (the first impact).
    Errors are relative to the largest |d θ/d ln a_p| of the motion in the same window."""
    out("# bench_backbone --part transit: quasi-rigid, generalized-α 1e-8, d θ(t)/d ln a_p against the motion's (Tsit5 1e-11)")
    out("# window: from the start to the first band transit, and from there to the pulse's end + 3 s; error relative to the")
    out("# motion's largest |derivative| in the window; cd: generalized-α's own central difference (h = 1e-4)")
    out(f"{'backbone':9s} {'θs/α':>6s} {'scene':>5s} {'transit s':>9s}  {'jacfwd before':>13s} {'jacfwd after':>12s}  "
        f"{'cd before':>9s} {'cd after':>9s}")
    sc = gradient_scenes()
    h = 1e-4
    for backbone, smoothing in (("bilinear", 1e-5), ("tanh", 1e-4)):
        for i in range(6):
            h2, ta, wr = sc[1][i], sc[2][i], sc[3][i]
            blk = Block.from_slenderness(h2, ta)
            ex0 = RickerPulse(*jr.pulse_of_ratios(blk, sc[0][i], wr))
            ts = jnp.linspace(float(ex0.t_start), float(ex0.t_end) + 3.0, 400)

            def history(integrator):
                def run(log_ar):
                    ex = RickerPulse(*jr.pulse_of_ratios(blk, jnp.exp(log_ar), wr))
                    s = jr.simulate(SpringModel(blk, None, backbone=backbone, smoothing=smoothing), ex,
                                    integrator=integrator, save=jr.Save(ts))
                    return s.history["theta"] / blk.alpha
                return run

            ga = history(GeneralizedAlpha(1e-8, 1e-8))
            ref = history(SpringIntegrator(1e-11, 1e-11, "tsit5", max_steps=400_000, autodiff="forward"))
            x = jnp.log(sc[0][i])
            th = np.asarray(jax.jit(ref)(x))
            d_ga, d_ref = np.asarray(jax.jit(jax.jacfwd(ga))(x)), np.asarray(jax.jit(jax.jacfwd(ref))(x))
            f = jax.jit(ga)
            cd = (np.asarray(f(x + h)) - np.asarray(f(x - h))) / (2 * h)
            band = as_backbone(backbone).band * smoothing  # the pre-yield band, in θ/α (≈ θ/α′)
            up = np.flatnonzero(np.abs(th) > 2 * band)
            sign = np.sign(th)
            cross = [k for k in up if sign[k] != sign[up[0]] and sign[k] != 0]
            if not cross:
                out(f"{backbone:9s} {smoothing:6.0e} {i:5d} {'—':>9s}  (no band transit: overturns or stays)")
                continue
            k = cross[0]
            cells = []
            for d in (d_ga, cd):
                for lo, hi in ((0, k), (k, len(ts))):
                    both = np.isfinite(d[lo:hi]) & np.isfinite(d_ref[lo:hi])  # an overturned run's history ends
                    scale = max(np.max(np.abs(d_ref[lo:hi][both])), 1e-12)
                    cells.append(np.max(np.abs(d[lo:hi] - d_ref[lo:hi])[both]) / scale)
            out(f"{backbone:9s} {smoothing:6.0e} {i:5d} {float(ts[k]):9.3f}  {cells[0]:13.1e} {cells[1]:12.1e}  "
                f"{cells[2]:9.1e} {cells[3]:9.1e}")


def cost() -> None:
    """Where the sharp spring's cost comes from: steps and warm time per scene of the quasi-rigid SM
    on 64 seeded pulses (seed 5, batches of 32 by pulse shape) for each backbone at θs = 1e-4 and
    1e-5 α under the default integrator, and an L-stable solver on the bilinear (issue 56, item 2)."""
    out("# bench_backbone --part cost: quasi-rigid SM, 64 seeded pulses (seed 5), warm ms and steps per scene")
    scenes = sample(64, np.random.default_rng(5))
    settings = [(b, th, "Tsit5 1e-10 (default)", None) for b in ("tanh", "bilinear") for th in (1e-4, 1e-5)]
    settings.append(("bilinear", 1e-5, "Kvaerno5 1e-8", SpringIntegrator(rtol=1e-8, atol=1e-8, solver="kvaerno5")))
    out(f"{'backbone':9s} {'θs/α':>6s} {'integrator':>22s} {'ms/scene':>9s} {'steps/scene':>12s}")
    for backbone, th, name, integrator in settings:
        seconds, steps = 0.0, 0
        for kind in ("sym", "anti"):
            models, exc = batch(scenes, np.flatnonzero(scenes["kind"] == kind), False, backbone, th, kind)
            go = lambda: jax.block_until_ready(jr.run_batch(models, exc, integrator, model_batched=True))
            go()
            t = time.perf_counter()
            sol = go()
            seconds += time.perf_counter() - t
            steps += int(np.asarray(sol.n_iterations).sum())
        out(f"{backbone:9s} {th:6.0e} {name:>22s} {1e3 * seconds / 64:9.2f} {steps / 64:12.0f}")


def tolerance() -> None:
    """The quasi-rigid default's tolerance, chosen by convergence over the study's scenes (issue 56,
    item 3): the default model (bilinear, θy = 1e-5 α) under Tsit5 at 1e-9 … 1e-11, with its exact
    pre-yield phase (`jaxrock.spring.rest`, the default) and without, against Tsit5 at 1e-12 with it
    (whose own error is estimated by |1e-12 − 1e-13|, and its distance to the run without the exact
    phase printed), on the study's 192 pulse scenes (seed 0) and its new ones (seed 1: 56 pulses, 24
    El Centro records, apart): max, p99 and median |Δ max θ/α| (verdict changes apart), failures,
    warm ms per scene."""
    out("# bench_backbone --part tolerance: the quasi-rigid default (bilinear 1e-5) under Tsit5, error against Tsit5 1e-12")
    rng, rng_new = np.random.default_rng(0), np.random.default_rng(1)
    new = sample(56, rng_new, 24)
    part = lambda idx: {k: v[idx] for k, v in new.items()}
    records = new["kind"] == "record"
    sets = (("192 pulses (seed 0)", sample(192, rng)), ("56 new pulses (seed 1)", part(~records)),
            ("24 El Centro 1940 NS scaled to PGA/(g tanα) ∈ [1, 4] (seed 1)", part(records)))
    tsit5 = lambda tol, rest=True: SpringIntegrator(rtol=tol, atol=tol, solver="tsit5", max_steps=400_000, exact_rest=rest)
    for title, scenes in sets:
        out(f"\n## {title}")
        t = time.perf_counter()
        ref, ref_st, ref_cost = run(scenes, False, "bilinear", 1e-5, tsit5(1e-12), timed=True)
        ref13, _, _ = run(scenes, False, "bilinear", 1e-5, tsit5(1e-13))
        ref_solver, _, _ = run(scenes, False, "bilinear", 1e-5, tsit5(1e-12, rest=False))
        own, other = np.abs(ref - ref13), np.abs(ref - ref_solver)
        out(f"reference Tsit5 1e-12 with the exact pre-yield phase ({time.perf_counter() - t:.0f} s, failed {int(np.sum(ref_st != 0))}, "
            f"{ref_cost * 1e3:.2f} ms/scene); its own error |1e-12 − 1e-13|: max {own.max():.1e}, median {np.median(own):.1e}; "
            f"|Δ| to Tsit5 1e-12 stepping the pre-yield phase too: max {other.max():.1e}, median {np.median(other):.1e}")
        out(f"{'Tsit5 tol':>9s} {'pre-yield':>9s} {'max err':>9s} {'p99':>9s} {'median':>9s} {'verdicts':>8s} {'failed':>6s} {'ms/scene':>9s}  largest at")
        for tol in (1e-9, 1e-10, 1e-11):
            for rest in (False, True):
                th, st, cost = run(scenes, False, "bilinear", 1e-5, tsit5(tol, rest), timed=True)
                flip = (th >= 1) != (ref >= 1)
                err = np.abs(th - ref)[~flip]
                i_max = np.flatnonzero(~flip)[np.argmax(err)]
                out(f"{tol:9.0e} {'exact' if rest else 'Tsit5':>9s} {err.max():9.2e} {np.quantile(err, 0.99):9.2e} {np.median(err):9.2e} "
                    f"{int(flip.sum()):8d} {int(np.sum(st != 0)):6d} {cost * 1e3:9.2f}  {describe(scenes, i_max)}")


def rest() -> None:
    """The exact pre-yield phase's grid (`jaxrock.spring.rest`): on the study's 192 pulses (seed 0)
    the first yield's time and velocity with `REST_STEPS` = 256 … 2048 steps over the pulse window
    against 8192, and the phase's warm ms per scene; on 24 El Centro scenes (seed 1) the record's
    own grid (one step per sample) against the same motion sampled 4 and 16 times finer."""
    from jaxrock.spring import rest as R

    out("# bench_backbone --part rest: the exact pre-yield phase of the quasi-rigid default (bilinear 1e-5)")
    scenes = sample(192, np.random.default_rng(0))

    def first_yields(models, exc):
        f = jax.jit(jax.vmap(lambda m, e: R.rest_phase(m.system(), e, jnp.inf, False)))
        end = jax.block_until_ready(f(models, exc))
        t = time.perf_counter()
        end = jax.block_until_ready(f(models, exc))
        return end, time.perf_counter() - t

    default = R.REST_STEPS
    runs = {}
    for steps in (256, 512, 1024, 2048, 8192):
        R.REST_STEPS = steps
        ts, vs, secs, n = [], [], 0.0, []
        for kind in ("sym", "anti"):
            models, exc = batch(scenes, np.flatnonzero(scenes["kind"] == kind), False, "bilinear", 1e-5, kind)
            end, sec = first_yields(models, exc)
            system = jax.vmap(lambda m: m.system())(models)
            ts.append(np.asarray(end.t * system.p_r))
            vs.append(np.asarray(end.y[:, 1] / (system.p_r * system.alpha_r)))
            secs += sec
            n.append(np.asarray(end.n_steps))
        runs[steps] = (np.concatenate(ts), np.concatenate(vs), secs / 192, np.concatenate(n))
    R.REST_STEPS = default
    t_ref, v_ref = runs[8192][:2]
    out("## 192 pulses (seed 0): first yield against 8192 steps over the window (time × p, velocity / (p α))")
    out(f"{'steps':>6s} {'max |Δt| p':>11s} {'max |Δv|':>9s} {'ms/scene':>9s} {'steps to yield':>15s}")
    for steps in (256, 512, 1024, 2048):
        t, v, sec, n = runs[steps]
        out(f"{steps:6d} {np.max(np.abs(t - t_ref)):11.1e} {np.max(np.abs(v - v_ref)):9.1e} {sec * 1e3:9.3f} {np.mean(n):15.0f}")
    new = sample(0, np.random.default_rng(1), 24)
    rec = jr.el_centro()
    acc, dt = np.asarray(rec.acc), float(rec.dt)

    def finer(k):
        tu = np.arange((acc.size - 1) * k + 1) * dt / k
        return jr.Record(np.interp(tu, np.arange(acc.size) * dt, acc), dt / k)

    blocks = jax.vmap(Block.from_slenderness)(jnp.asarray(new["height"]), jnp.asarray(new["tan_alpha"]))
    models = jax.vmap(lambda b: SpringModel(b, backbone="bilinear", smoothing=1e-5))(blocks)
    scale = jnp.asarray(new["ar"]) * jr.G * blocks.tan_alpha / float(np.max(np.abs(acc)))
    system = jax.vmap(lambda m: m.system())(models)
    ends = {k: first_yields(models, jax.vmap((rec if k == 1 else finer(k)).scaled)(scale)) for k in (1, 4, 16)}
    out("\n## 24 El Centro scenes (seed 1): one step per sample against the record sampled k times finer (the same motion)")
    out(f"{'k':>3s} {'max |Δt| p':>11s} {'max |Δv|':>9s} {'ms/scene (k)':>13s}")
    t1 = np.asarray(ends[1][0].t * system.p_r)
    v1 = np.asarray(ends[1][0].y[:, 1] / (system.p_r * system.alpha_r))
    out(f"{1:3d} {'':>11s} {'':>9s} {ends[1][1] / 24 * 1e3:13.3f}")
    for k in (4, 16):
        e, sec = ends[k]
        out(f"{k:3d} {np.max(np.abs(np.asarray(e.t * system.p_r) - t1)):11.1e} "
            f"{np.max(np.abs(np.asarray(e.y[:, 1] / (system.p_r * system.alpha_r)) - v1)):9.1e} {sec / 24 * 1e3:13.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", choices=("study", "gradients", "sawtooth", "transit", "cost", "tolerance", "rest"), default="study")
    ap.add_argument("--quick", action="store_true", help="a few scenes (smoke run)")
    ap.add_argument("--n-rigid", type=int, default=192, help="quasi-rigid scenes")
    ap.add_argument("--n-flex", type=int, default=48, help="flexible scenes")
    ap.add_argument("--n-rigid-new", type=int, default=56, help="new quasi-rigid pulse scenes (seed + 1)")
    ap.add_argument("--n-records", type=int, default=24, help="new quasi-rigid El Centro scenes")
    ap.add_argument("--n-flex-new", type=int, default=16, help="new flexible pulse scenes")
    ap.add_argument("--n-records-flex", type=int, default=8, help="new flexible El Centro scenes")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.part != "study":
        {"gradients": gradients, "sawtooth": sawtooth, "transit": transit, "cost": cost, "tolerance": tolerance, "rest": rest}[args.part]()
        (HERE / "results" / f"bench_backbone_{args.part}.txt").write_text("\n".join(LINES) + "\n")
        return
    if args.quick:
        args.n_rigid, args.n_flex, args.n_rigid_new, args.n_records, args.n_flex_new, args.n_records_flex = 8, 4, 4, 2, 2, 2
    rng = np.random.default_rng(args.seed)
    t0 = time.perf_counter()
    out("# bench_backbone: error of the spring backbone against the sharp (rigid-plastic) limit, and cost")
    out(f"# machine: {platform.machine()} {jax.device_count()} {jax.devices()[0].platform} device(s), "
        f"{os.cpu_count()} cores, jax {jax.__version__}; seed {args.seed}")
    rigid = sample(args.n_rigid, rng)
    flex = sample(args.n_flex, rng)
    # new seeded scenes (issue 56): pulses and El Centro records
    rng_new = np.random.default_rng(args.seed + 1)
    rigid_new = sample(args.n_rigid_new, rng_new, args.n_records)
    flex_new = sample(args.n_flex_new, rng_new, args.n_records_flex)
    qr = SpringModel(Block.from_slenderness(10.0, 0.2))
    fl = SpringModel(Block.from_slenderness(10.0, 0.2), Column.concrete())
    study("quasi-rigid one-DOF SM (errors and cost: Tsit5 1e-10, the default)", rigid, False, TSIT5, qr.default_integrator())
    flex_title = "flexible concrete column, 10 elements (errors: generalized-α 1e-7; cost: the default Checked generalized-α 1e-5)"
    study("quasi-rigid one-DOF SM, new scenes (seed + 1) with El Centro records", rigid_new, False, TSIT5, qr.default_integrator())
    study(flex_title, flex, True, GA7, fl.default_integrator())
    study(flex_title.replace(" (", ", new scenes (seed + 1) with El Centro records (", 1), flex_new, True, GA7, fl.default_integrator())
    out(f"\ntotal {time.perf_counter() - t0:.0f} s")
    if not args.quick:
        res = HERE / "results"
        res.mkdir(exist_ok=True)
        (res / "bench_backbone.txt").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
