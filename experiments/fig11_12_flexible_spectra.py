"""Figures 11 and 12: overturning spectra of quasi-rigid and concrete (E = 30 GPa, ρ = 2500 kg/m³,
ζ = 0.01) columns of four heights, tanα = 0.1 and 0.2, symmetric Ricker pulse; figure 12 overlays
their least uplift and overturning lines. The flexible column uplifts below g tanα (tanα = 0.1).

    python experiments/fig11_12_flexible_spectra.py [--n 12] [--heights 10,30,50,100] [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_boundaries, plot_spectra_grid

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--n", type=int, default=24, help="grid points per axis")
ap.add_argument("--heights", default="10,30,50,100")
ap.add_argument("--n-elements", type=int, default=10)
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
out = Path(args.out)
w, a = np.linspace(1, 15, args.n), np.linspace(0.5, 10, args.n)
heights = [float(h) for h in args.heights.split(",")]

for tan_a in (0.1, 0.2):
    spectra, titles = [], []
    rigid = jr.overturning_spectrum(jr.SpringModel(jr.Block.from_slenderness(heights[0], tan_a)), w, a)
    spectra.append(rigid)
    titles.append(f"quasi-rigid SM, tanα = {tan_a}")
    for h in heights:
        m = jr.SpringModel(jr.Block.from_slenderness(h, tan_a), jr.Column.concrete(), n_elements=args.n_elements)
        s = jr.overturning_spectrum(m, w, a, checkpoint=out / f"fig11_{h:g}m_tan{tan_a}.checkpoint")
        s.save(out / f"fig11_{h:g}m_tan{tan_a}.nc")
        spectra.append(s)
        titles.append(f"concrete 2h = {h:g} m, tanα = {tan_a}")
        print(f"tanα={tan_a} 2h={h:g} m: least uplift a_p/(g tanα) min {np.nanmin(s.uplift_boundary):.2f}, "
              f"overturned {int(s.overturned.sum())} vs quasi-rigid {int(rigid.overturned.sum())}, all ok {s.ok}")
    plot_spectra_grid(spectra, titles, ncols=len(spectra), path=out / f"fig11_tan{tan_a}.png",
                      suptitle=f"figure 11: quasi-rigid and concrete columns, tanα = {tan_a}")
    plot_boundaries(spectra, titles, path=out / f"fig12_tan{tan_a}.png",
                    title=f"figure 12: uplift and overturning lines, tanα = {tan_a}")
