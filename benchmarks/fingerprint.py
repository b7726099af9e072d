"""Bit fingerprint of jaxrock's outputs, for refactors that must not change a number.

    python benchmarks/fingerprint.py OUT.npz                 # record (e.g. on the commit before)
    python benchmarks/fingerprint.py NEW.npz --compare OUT.npz  # record again and compare bit for bit

88 arrays: 6 × 6 pulse spectra of the rigid model, the quasi-rigid spring model (default Tsit5 and
generalized-α 1e-6) and a 4-element flexible column (3 × 3); histories and summaries of one pulse
for each (every history field); reverse- and forward-mode gradients of max θ/α. About 3 minutes on
2 CPU cores. Exit code 1 when any array differs (each is named with its largest difference).
"""

from __future__ import annotations

import argparse
import sys

import jax
import jax.numpy as jnp
import numpy as np

import jaxrock as jr


def fingerprint() -> dict[str, np.ndarray]:
    out = {}
    blk = jr.Block.from_slenderness(height=10.0, tan_alpha=0.2)
    flex = jr.Block.from_slenderness(height=20.0, tan_alpha=0.15)
    ga = jr.GeneralizedAlpha(1e-6, 1e-6)
    grids = {"rm": (jr.RigidModel(blk), None, 6), "sm": (jr.SpringModel(blk), None, 6), "sm_ga": (jr.SpringModel(blk), ga, 6),
             "flex": (jr.SpringModel(flex, jr.Column.concrete(), n_elements=4), None, 3)}
    for name, (model, integ, n) in grids.items():
        s = jr.overturning_spectrum(model, np.linspace(1.5, 8, n), np.linspace(1.2, 5, n), integrator=integ, progress=False)
        for f in ("max_theta", "overturned", "uplifted", "status"):
            out[f"{name}.{f}"] = np.asarray(getattr(s, f))
    exc = jr.RickerPulse(a_p=3.0 * 9.81 * 0.2, omega_p=6.0)
    ts = jnp.linspace(0, 4, 81)
    for name, (model, integ, _) in grids.items():
        sol = jr.simulate(model, exc, integrator=integ, save=jr.Save(ts, model.history_fields))
        out.update({f"h_{name}.{f}": np.asarray(v) for f, v in sol.history.items()})
        summary = jr.simulate(model, exc, integrator=integ)
        for f in ("max_theta", "t_uplift", "t_overturn", "n_impacts"):
            out[f"h_{name}.{f}"] = np.asarray(getattr(sol, f))
            out[f"s_{name}.{f}"] = np.asarray(getattr(summary, f))
        out[f"h_{name}.status"], out[f"s_{name}.status"] = np.asarray(jr.status_codes(sol.status)), np.asarray(jr.status_codes(summary.status))
    pulse = lambda a: jr.RickerPulse(a_p=a, omega_p=6.0)
    out["grad_rm"] = np.asarray(jax.grad(lambda a: jr.simulate(jr.RigidModel(blk), pulse(a)).max_theta)(2.0))
    out["grad_sm"] = np.asarray(jax.grad(lambda a: jr.simulate(jr.SpringModel(blk), pulse(a)).max_theta)(2.0))
    out["grad_ga"] = np.asarray(jax.jacfwd(lambda a: jr.simulate(jr.SpringModel(blk), pulse(a), integrator=ga).max_theta)(2.0))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="where to save this fingerprint (.npz)")
    ap.add_argument("--compare", help="an earlier fingerprint to compare with, bit for bit")
    args = ap.parse_args(argv)
    new = fingerprint()
    np.savez(args.out, **new)
    if args.compare is None:
        print(f"saved {len(new)} arrays to {args.out}")
        return 0
    old = np.load(args.compare)
    differ = [k for k in old.files if k not in new or not np.array_equal(old[k], new[k], equal_nan=True)]
    for k in differ:
        d = np.nanmax(np.abs(old[k].astype(float) - new[k].astype(float))) if k in new and old[k].shape == new[k].shape else "shape"
        print(f"differs: {k} (largest difference {d})")
    print(f"compared {len(old.files)} arrays: {len(differ)} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
