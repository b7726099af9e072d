"""Figure 13: a rigid and a flexible (concrete) column, 2h = 50 m, 2b = 5 m, under two symmetric
Ricker pulses: (ω_p/p, a_p/(g tanα)) = (3, 2.6), where the paper finds that the flexible column
overturns and the rigid one keeps rocking, and (6, 5.85), where it finds the opposite. Rows: θ/α,
top displacement u, bending deformation w = u − 2h sinθ, ground acceleration.

    python experiments/fig13_flexible_vs_rigid.py [--out out/figures]
"""

import argparse
from pathlib import Path

import numpy as np

import jaxrock as jr
from jaxrock.plotting import plot_history

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--n-elements", type=int, default=10)
ap.add_argument("--out", default="out/figures")
args = ap.parse_args()
block = jr.Block.from_size(50.0, 5.0)
models = {
    "RM": jr.RigidModel(block),
    "quasi-rigid SM": jr.SpringModel(block),
    "flexible SM": jr.SpringModel(block, jr.Column.concrete(), n_elements=args.n_elements),
}
for w_ratio, a_ratio in ((3.0, 2.6), (6.0, 5.85)):
    pulse = jr.RickerPulse(*jr.pulse_of_ratios(block, a_ratio, w_ratio))
    ts = np.linspace(float(pulse.t_start), float(pulse.t_end) + 10.0, 3001)
    sols = {}
    for name, m in models.items():
        fields = ("theta",) if name == "RM" else ("theta", "u_top", "w_top")
        sols[name] = jr.simulate(m, pulse, save=jr.Save(ts, fields))
        print(f"(ω_p/p, a_p/(g tanα)) = ({w_ratio}, {a_ratio}) {name:15s}: max θ/α = {float(sols[name].max_theta):.3f}, "
              f"overturned {bool(sols[name].overturned)}, status {jr.status_names(sols[name].status)}")
    plot_history({k: v for k, v in sols.items() if k != "RM"}, pulse, fields=("theta", "u_top", "w_top"),
                  model=models["RM"], path=Path(args.out) / f"fig13_w{w_ratio:g}_a{a_ratio:g}.png",
                  title=f"figure 13: 2h = 50 m, 2b = 5 m, ω_p/p = {w_ratio}, a_p/(g tanα) = {a_ratio}")
