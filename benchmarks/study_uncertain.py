"""Brute force against the `uncertain` flag (issue 55): does the flag catch the runs whose verdict
rounding can flip, and leave the others alone?

    python benchmarks/study_uncertain.py [--records-per 100] [--pulses 240] [--quick] [--out FILE]

Scenes (seeded, RM, one block per scene):
- record runs: the five packaged records and bench_suite's six synthetic ones (12–90 s), 100 runs
  each (`--records-per`): 2h ∈ [1, 6] m (log-uniform), tanα ∈ [0.1, 0.3], the record scaled to
  1–5× its uplift factor (g tanα / PGA);
- pulse cells: `--pulses` random scenes of bench_throughput's mixed blocks (2h ∈ [2, 50] m,
  tanα ∈ [0.1, 0.35], both Ricker shapes, a_p/(g tanα) ∈ [0.5, 10], ω_p/p ∈ [1, 15]).

Each scene runs once as a user runs it (the default tolerance, with its sensitivity and its
`uncertain` flag) and then by brute force at 3 tolerances (records: rtol 1e-12 (the default),
1e-11, 1e-10; pulses: 1e-8 (the default), 1e-10, 1e-12; atol = rtol/100) × 5 scale factors
(1 and ×(1 ± 1e-9), ×(1 ± 1e-7)): 15 runs. A scene's verdict *changes* where the 15 overturning
verdicts are not all its own. The flag must catch ≥ 95 % of the scenes whose verdict changes and
flag ≤ 10 % of those whose verdict never changes.

Also printed: the rates of other thresholds of the same rule (what chose the defaults of
`jaxrock.uncertainty`), and the cost of the sensitivity (warm time with it / without it).
Written to benchmarks/results/study_uncertain.txt (`--quick`: a few scenes, printed only).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("JAXROCK_CACHE_DIR", "off")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import jaxrock as jr  # noqa: E402
from bench_suite import SYNTHETIC, synthetic  # noqa: E402
from jaxrock.analyses.engine import run_batch  # noqa: E402

G = 9.81
LINES: list[str] = []
FACTORS = (1.0, 1 + 1e-9, 1 - 1e-9, 1 + 1e-7, 1 - 1e-7)
RTOLS = {"record": (1e-12, 1e-11, 1e-10), "pulse": (1e-8, 1e-10, 1e-12)}


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def record_scenes(rng, per: int, quick: bool):
    """[("records", models, excitations)]: `per` seeded runs of each record (one block per run),
    every record padded to the longest and stacked: one batch, one compiled program."""
    from jaxrock.io.scenes_file import stack

    records = [jr.builtin_record(n) for n in ("elcentro", "elcentro_peknold", "arl360", "b-elc000", "a-tin000")]
    records += [synthetic(*s) for s in SYNTHETIC]
    if quick:
        records = records[:2]
    longest = max(r.n for r in records)
    h, tan, runs = [], [], []
    for rec in records:
        h.append(np.exp(rng.uniform(np.log(1.0), np.log(6.0), per)))
        tan.append(rng.uniform(0.1, 0.3, per))
        pga = float(np.max(np.abs(np.asarray(rec.acc))))
        k = rng.uniform(1.0, 5.0, per) * G * tan[-1] / pga
        padded = rec.padded(longest, "record")
        runs += [padded.scaled(jnp.asarray(x)) for x in k]
    return [(f"{len(records)} records x {per}", models(np.concatenate(h), np.concatenate(tan)), stack(runs))]


def models(h, tan):
    """One rigid model per scene (a leading batch axis on every leaf)."""
    return jax.vmap(lambda h, t: jr.RigidModel(jr.Block.from_slenderness(h, t)))(jnp.asarray(h), jnp.asarray(tan))


def pulse_scenes(rng, n: int):
    h, tan = rng.uniform(2.0, 50.0, n), rng.uniform(0.1, 0.35, n)
    p = np.asarray(jr.Block.from_slenderness(jnp.asarray(h), jnp.asarray(tan)).p_r)
    a = rng.uniform(0.5, 10.0, n) * G * tan
    w = rng.uniform(1.0, 15.0, n) * p
    half = n // 2
    return [(kind.__name__, models(h[sl], tan[sl]), kind(jnp.asarray(a[sl]), jnp.asarray(w[sl])))
            for kind, sl in ((jr.RickerPulse, slice(0, half)), (jr.AntisymmetricRickerPulse, slice(half, n)))]


def brute_force(model, exc, rtols):
    """(n, 15) overturning verdicts: each scene at every tolerance × scale factor."""
    cols = []
    for rtol in rtols:
        integ = jr.EventIntegrator(rtol=rtol)
        for f in FACTORS:
            cols.append(np.asarray(run_batch(model, jax.vmap(lambda e: e.scaled(f))(exc), integ, model_batched=True).overturned))
    return np.stack(cols, axis=1)


def rates(flag, changed) -> tuple[float, float]:
    catch = flag[changed].mean() if changed.any() else float("nan")
    false = flag[~changed].mean() if (~changed).any() else float("nan")
    return 100 * catch, 100 * false


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--records-per", type=int, default=100)
    ap.add_argument("--pulses", type=int, default=240)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    if args.quick:
        args.records_per, args.pulses = 4, 16
    jr.use_cpu_cores()
    rng = np.random.default_rng(55)
    out("# study_uncertain: the `uncertain` flag against brute force (issue 55)")
    out(f"# machine: {platform.machine()}, {jax.device_count()} {jax.default_backend()} device(s), jax {jax.__version__}")
    rows = {"record": [], "pulse": []}
    cost = {"record": [0.0, 0.0], "pulse": [0.0, 0.0]}
    for kind, groups in (("record", record_scenes(rng, args.records_per, args.quick)), ("pulse", pulse_scenes(rng, args.pulses))):
        for name, model, exc in groups:
            for _ in range(2):  # the second call is warm
                t = time.perf_counter()
                plain = jax.block_until_ready(run_batch(model, exc, model_batched=True))
                t_plain = time.perf_counter() - t
                t = time.perf_counter()
                sol = jax.block_until_ready(run_batch(model, exc, model_batched=True, sensitivity=True))
                t_sens = time.perf_counter() - t
            cost[kind][0] += t_plain
            cost[kind][1] += t_sens
            assert np.array_equal(np.asarray(plain.overturned), np.asarray(sol.overturned))
            verdicts = brute_force(model, exc, RTOLS[kind])
            base = np.asarray(sol.overturned)
            flips = verdicts != base[:, None]
            changed = np.any(flips, axis=1)
            small = np.any(flips.reshape(base.size, len(RTOLS[kind]), len(FACTORS))[:, :, :3], axis=(1, 2))
            rows[kind].append(dict(name=name, changed=changed, small=small, over=base, max_theta=np.asarray(sol.max_theta),
                                   sens=np.asarray(sol.sensitivity), flag=np.asarray(sol.uncertain)))
            out(f"{kind:7s} {name:28s} {base.size:4d} scenes: {changed.sum():3d} change, {np.asarray(sol.uncertain).sum():3d} flagged")
    out()
    cat = {k: {f: np.concatenate([r[f] for r in v]) for f in v[0] if f != "name"} for k, v in rows.items() if v}
    allk = {f: np.concatenate([cat[k][f] for k in cat]) for f in ("changed", "small", "over", "max_theta", "sens", "flag")}
    out(f"the flag (δ = {jr.outputs.PERTURBATION:g}, overturned margin {jr.outputs.MARGIN_OVERTURNED:g}): 'change' = the verdict "
        "changes at some tolerance × scale factor; 'change ≤1e-9' = at a factor 1 or 1 ± 1e-9")
    out(f"{'scenes':24s}{'n':>6s}{'change':>8s}{'flagged':>9s}{'catch %':>9s}{'false %':>9s}{'change ≤1e-9':>14s}{'catch %':>9s}")
    for label, c in (("record runs", cat["record"]), ("pulse cells", cat["pulse"]), ("all", allk)):
        catch, false = rates(c["flag"], c["changed"])
        catch9, _ = rates(c["flag"], c["small"])
        out(f"{label:24s}{c['changed'].size:6d}{c['changed'].sum():8d}{c['flag'].sum():9d}{catch:9.1f}{false:9.1f}"
            f"{c['small'].sum():14d}{catch9:9.1f}")
    out()
    out("the rule at other thresholds (all scenes): uncertain where δ·S ≥ margin, margin = 1 − max θ/α′ standing, "
        "`m_over` overturned; rates against 'change' and against 'change ≤1e-9'")
    out(f"{'δ':>8s}{'m_over':>8s}{'catch %':>9s}{'false %':>9s}{'catch ≤1e-9 %':>15s}{'false %':>9s}")
    for delta in (1e-10, 1e-9, 1e-8, 1e-7, 1e-6):
        for m_over in (1e-3, 1e-2, 1e-1):
            margin = np.where(allk["over"], m_over, 1.0 - allk["max_theta"])
            flag = delta * allk["sens"] >= margin
            catch, false = rates(flag, allk["changed"])
            catch9, false9 = rates(flag, allk["small"])
            out(f"{delta:8.0e}{m_over:8.0e}{catch:9.1f}{false:9.1f}{catch9:15.1f}{false9:9.1f}")
    out()
    ch = allk["changed"]
    margin = np.where(allk["over"], jr.outputs.MARGIN_OVERTURNED, 1.0 - allk["max_theta"])
    out("the scenes whose verdict changes: overturned, max θ/α′, sensitivity S, S·1e-9/margin, flagged")
    for i in np.flatnonzero(ch):
        out(f"  {'yes' if allk['over'][i] else 'no ':4s}{allk['max_theta'][i]:9.4f}{allk['sens'][i]:12.3g}"
            f"{1e-9 * allk['sens'][i] / margin[i]:12.3g}  {'flagged' if allk['flag'][i] else '-'}")
    out()
    for kind in cost:
        out(f"cost of the sensitivity, {kind} scenes (warm, in batches as above): {cost[kind][1]:.2f} s with / "
            f"{cost[kind][0]:.2f} s without = {cost[kind][1] / cost[kind][0]:.2f}x")
    if not args.quick:
        path = Path(args.out) if args.out else HERE / "results" / "study_uncertain.txt"
        path.write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
