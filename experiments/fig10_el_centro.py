"""Figure 10: least scale factor of the El Centro 1940 NS record that overturns a block, against
its height 2h, RM against the quasi-rigid SM (with added masses), tanα = 0.1, 0.2, 0.3.

    python experiments/fig10_el_centro.py [--heights 1,2,4,8,16] [--scales 0.5:10:20] [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_record_spectrum

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--heights", default="1,2,4,8,16")
ap.add_argument("--scales", default="0.5:10:20", help="start:stop:count of the factor sweep")
ap.add_argument("--refine", type=int, default=8)
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
heights = [float(h) for h in args.heights.split(",")]
lo, hi, n = args.scales.split(":")
scales = np.linspace(float(lo), float(hi), int(n))
record = jr.el_centro()

results, labels = [], []
for tan_a in (0.1, 0.2, 0.3):
    block = jr.Block.from_slenderness(heights[0], tan_a)
    for name, m in (("RM", jr.RigidModel(block)), ("SM", jr.SpringModel(block))):
        r = jr.record_overturning_scale(m, record, heights, scales, refine=args.refine)
        r.save(Path(args.out) / f"fig10_{name}_tan{tan_a}.nc")
        results.append(r)
        labels.append(f"{name}, tanα = {tan_a}")
        print(f"{name} tanα={tan_a}: " + ", ".join(f"2h={h:g}: {s:.3f}" for h, s in zip(r.height, r.scale)))
plot_record_spectrum(results, labels, path=Path(args.out) / "fig10_el_centro.png",
                     title="figure 10: El Centro 1940 NS, least overturning scale factor")
