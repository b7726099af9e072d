"""Figures 6 and 9: overturning spectra of rigid blocks (tanα = 0.1, 0.2, 0.3; symmetric Ricker
pulse) by the RM, the quasi-rigid SM without and with the added rotational masses; undamped
(figure 6) and damped (figure 9). In these coordinates the rigid spectrum depends on α only.

    python experiments/fig06_09_spectra.py [--n 32] [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_spectra_grid

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--n", type=int, default=32, help="grid points per axis")
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
out = Path(args.out)
w, a = np.linspace(1, 15, args.n), np.linspace(0.5, 10, args.n)

for fig, damped in ((6, False), (9, True)):
    spectra, titles = [], []
    for tan_a in (0.1, 0.2, 0.3):
        block = jr.Block.from_slenderness(10.0, tan_a)
        models = {
            "RM": jr.RigidModel(block, eta=None if damped else 1.0),
            "SM": jr.SpringModel(block, added_masses=False, cbar=None if damped else 0.0),
            "SM + ΔI": jr.SpringModel(block, added_masses=True, cbar=None if damped else 0.0),
        }
        rm = None
        for name, m in models.items():
            s = jr.overturning_spectrum(m, w, a)
            s.save(out / f"fig{fig:02d}_{name.replace(' + ', '_').replace('ΔI', 'dI')}_tan{tan_a}.nc")
            rm = s if rm is None else rm
            spectra.append(s)
            titles.append(f"{name}, tanα = {tan_a}")
            diff = np.abs(s.max_theta - rm.max_theta)
            print(f"fig {fig} tanα={tan_a} {name:8s}: overturned {int(s.overturned.sum())}/{s.overturned.size}, "
                  f"all ok {s.ok}, |θ/α − RM|: median {np.median(diff):.3f}, cells differing > 0.1: {int((diff > 0.1).sum())}")
    plot_spectra_grid(spectra, titles, ncols=3, path=out / f"fig{fig:02d}_spectra.png",
                      suptitle=f"figure {fig}: {'damped' if damped else 'undamped'} rigid blocks, symmetric Ricker pulse")
