"""Figures 5 and 8: rocking of 10 m blocks (tanα = 0.1, 0.2, 0.3) under a symmetric Ricker pulse
a_p = 4 g tanα, ω_p = 2π rad/s — RM against the quasi-rigid SM with and without the added
rotational masses; undamped (figure 5: η = 1, c̄ = 0) and damped (figure 8: η of eq. 3, c̄ of eq. 17).

    python experiments/fig05_08_time_histories.py [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_history

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
out = Path(args.out)

print(f"{'fig':>4} {'tanα':>5} {'RM':>8} {'SM':>8} {'SM+ΔI':>8}   (max |θ|/α)")
for fig, damped in ((5, False), (8, True)):
    for tan_a in (0.1, 0.2, 0.3):
        block = jr.Block.from_slenderness(10.0, tan_a)
        pulse = jr.RickerPulse(jr.pulse_of_ratios(block, 4.0, 1.0)[0], 2 * np.pi)
        ts = np.linspace(float(pulse.t_start), float(pulse.t_start) + 10.0, 2001)
        models = {
            "RM": jr.RigidModel(block, eta=None if damped else 1.0),
            "SM": jr.SpringModel(block, added_masses=False, cbar=None if damped else 0.0),
            "SM + added masses": jr.SpringModel(block, added_masses=True, cbar=None if damped else 0.0),
        }
        sols = {k: jr.simulate(m, pulse, save=jr.Save(ts, ("theta",))) for k, m in models.items()}
        plot_history(sols, pulse, model=models["RM"], path=out / f"fig{fig:02d}_tan{tan_a}.png",
                     title=f"figure {fig}: 2h = 10 m, tanα = {tan_a}, {'damped' if damped else 'undamped'}")
        print(f"{fig:>4} {tan_a:>5} " + " ".join(f"{float(s.max_theta):8.4f}" for s in sols.values()))
