"""Figures 15 and 16: concrete columns (tanα = 0.1, 0.2) on a rigid base with tanα′ = 0.3, several
heights, symmetric (figures 15, 16 top) and antisymmetric (figure 16 bottom, eq. 29) Ricker
pulses; spectra are normalised by the base's α′ and p′. Figure 16 overlays the boundary lines.

    python experiments/fig15_16_extended_base.py [--n 12] [--heights 10,50,100] [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_boundaries, plot_spectra_grid

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--n", type=int, default=24, help="grid points per axis")
ap.add_argument("--heights", default="10,50,100")
ap.add_argument("--n-elements", type=int, default=10)
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
out = Path(args.out)
w, a = np.linspace(1, 15, args.n), np.linspace(0.5, 10, args.n)
heights = [float(h) for h in args.heights.split(",")]

for pulse in ("symmetric", "antisymmetric"):
    for tan_a in (0.1, 0.2):
        spectra, titles = [], []
        rm = jr.overturning_spectrum(jr.RigidModel(jr.Block.from_slenderness(heights[0], tan_a, 0.3)), w, a, pulse=pulse)
        spectra.append(rm)
        titles.append("RM (rigid column + base)")
        for h in heights:
            m = jr.SpringModel(jr.Block.from_slenderness(h, tan_a, 0.3), jr.Column.concrete(), n_elements=args.n_elements)
            s = jr.overturning_spectrum(m, w, a, pulse=pulse, checkpoint=out / f"fig15_{pulse}_{h:g}m_tan{tan_a}.checkpoint")
            s.save(out / f"fig15_{pulse}_{h:g}m_tan{tan_a}.nc")
            spectra.append(s)
            titles.append(f"concrete 2h = {h:g} m")
            print(f"{pulse} tanα={tan_a} 2h={h:g}: overturned {int(s.overturned.sum())} vs RM {int(rm.overturned.sum())}, all ok {s.ok}")
        if pulse == "symmetric":
            plot_spectra_grid(spectra, titles, ncols=len(spectra), path=out / f"fig15_tan{tan_a}.png",
                              suptitle=f"figure 15: columns with tanα = {tan_a} on a base with tanα′ = 0.3")
        plot_boundaries(spectra, titles, path=out / f"fig16_{pulse}_tan{tan_a}.png",
                        title=f"figure 16 ({pulse}): tanα = {tan_a}, tanα′ = 0.3")
