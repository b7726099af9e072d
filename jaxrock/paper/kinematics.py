"""Figures 3 and 4: the SM's kinematics and pushover against the RM's (paper section 3).

Figure 3: the top displacements of the RM's two top corners (eqs. 4, 6) and of the SM's column top
(eqs. 5, 7), normalised by 2R, against θ/α. The SM's curves are the models' own: the top node of
the column rotated rigidly about its base from its gravity-preloaded rest state
(`SpringSystem.initial_state`), for a quasi-rigid (E = 10¹⁴ Pa) and a concrete beam column, and
`u_top` of the one-DOF quasi-rigid model.

Figure 4: F/(m g) against θ/α, RM eq. 8 (force at the centroid) and SM eq. 9 (force at mid-height),
beside the SM's own static pushover (`SpringModel.pushover`: Newton on the static equilibrium
with θ prescribed) of the quasi-rigid and of a concrete column.
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

from ..geometry import Block
from ..plotting import plot_curves
from ..spring import Column, SpringModel, pushover_eq9
from ..spring import beam
from .findings import Finding, judged

TAN_ALPHAS = (0.1, 0.3)  # the paper's "two different values of slenderness" are not printed
AGREE_WELL = 0.05  # "agree well": within 5 % of the curve's range


def rm_corners(theta, alpha, R):
    """Eqs. 4 and 6: the RM's top corners 1 and 2, (u1, u2, v1, v2) [m]. The extracted eq. 4 prints
    u2 = 2R(sinα − sin(α + θ)) for θ < 0, which moves the corner against the rotation; by the
    block's symmetry u2(θ) = −u1(−θ) = 2R(sin(α + θ) − sinα), used here (the PDF lost the sign)."""
    pos = theta > 0
    u1 = jnp.where(pos, 2 * R * (jnp.sin(alpha) - jnp.sin(alpha - theta)), 2 * R * jnp.cos(alpha) * jnp.sin(theta))
    u2 = jnp.where(pos, 2 * R * jnp.cos(alpha) * jnp.sin(theta), 2 * R * (jnp.sin(alpha + theta) - jnp.sin(alpha)))
    v1 = jnp.where(pos, 2 * R * (jnp.cos(alpha - theta) - jnp.cos(alpha)), -2 * R * jnp.cos(alpha) * (1 - jnp.cos(theta)))
    v2 = jnp.where(pos, -2 * R * jnp.cos(alpha) * (1 - jnp.cos(theta)), 2 * R * (jnp.cos(alpha + theta) - jnp.cos(alpha)))
    return u1, u2, v1, v2


def beam_top(model: SpringModel, theta):
    """The model's column top (u, v) [m] with the column rotated rigidly by θ from its rest state."""
    system = model.system()
    x0, y0, _ = beam.positions(system.q_eq, system.h, system.n)

    def one(th):
        x, y, _ = beam.positions(system.initial_state(th)[: system.ndof], system.h, system.n)
        return x[-1] - x0[-1], y[-1] - y0[-1]

    return tuple(np.asarray(v) for v in jnp.vectorize(one)(theta))


def fig03(out: Path, *, height: float = 10.0, n_elements: int = 4, n_points: int = 201) -> list[Finding]:
    out = Path(out)
    panels, h_dev, v_sign, model_dev = [], [], [], []
    for ta in TAN_ALPHAS:
        block = Block.from_slenderness(height, ta)
        a, R = float(block.alpha), float(block.R)
        th = np.linspace(-1, 1, n_points) * a
        u1, u2, v1, v2 = (np.asarray(v) / (2 * R) for v in rm_corners(jnp.asarray(th), a, R))
        uc, vc = 2 * R * np.cos(a) * np.sin(th) / (2 * R), -2 * R * np.cos(a) * (1 - np.cos(th)) / (2 * R)  # eqs. 5, 7
        one_dof = SpringModel(block)
        sys1 = one_dof.system()
        u_model = np.asarray(jnp.vectorize(lambda t: sys1.history(0.0, sys1.initial_state(t), None, ("u_top",))["u_top"])(th)) / (2 * R)
        tops = {name: beam_top(SpringModel(block, col, n_elements=n_elements), th)
                for name, col in (("quasi-rigid beam", Column.quasi_rigid()), ("concrete beam", Column.concrete()))}
        x = th / a
        panels.append(dict(title=f"horizontal, tanα = {ta}", xlabel="θ/α", ylabel="u / 2R", lines={
            "RM corner 1 (eq. 4)": (x, u1), "RM corner 2 (eq. 4)": (x, u2), "SM one-DOF u_top": (x, u_model),
            **{f"SM {k}": (x, v[0] / (2 * R)) for k, v in tops.items()}, "paper SM eq. 5": (x, uc)}))
        panels.append(dict(title=f"vertical, tanα = {ta}", xlabel="θ/α", ylabel="v / 2R", lines={
            "RM corner 1 (eq. 6)": (x, v1), "RM corner 2 (eq. 6)": (x, v2),
            **{f"SM {k}": (x, v[1] / (2 * R)) for k, v in tops.items()}, "paper SM eq. 7": (x, vc)}))
        # the SM's column top against both of the RM's top corners (one of them is eq. 5 exactly)
        h_dev.append(max(np.max(np.abs(uc - u)) / np.max(np.abs(u)) for u in (u1, u2)))
        v_lift = np.where(th > 0, v1, v2)  # the corner that lifts
        v_sign.append(bool(np.all(v_lift[np.abs(th) > 0.05 * a] > 0) and np.all(vc[np.abs(th) > 0.05 * a] < 0)))
        dev = {k: max(np.max(np.abs(v[0] / (2 * R) - uc)), np.max(np.abs(v[1] / (2 * R) - vc))) for k, v in tops.items()}
        model_dev.append((max(np.max(np.abs(u_model - uc)), dev["quasi-rigid beam"]), dev["concrete beam"]))
    plt.close(plot_curves(panels, ncols=2, path=out / "fig03_kinematics.png", title="figure 3: top displacements, RM and SM"))
    tas = ", ".join(f"{t:g}" for t in TAN_ALPHAS)
    return [
        Finding("3", f"horizontal top displacement, RM against SM (tanα = {tas})", "agree well",
                "max |u_SM − u_RM| / max|u_RM| = " + ", ".join(f"{100 * d:.1f} %" for d in h_dev), "",
                f"≤ {100 * AGREE_WELL:g} % for each tanα", judged(max(h_dev) <= AGREE_WELL),
                "" if max(h_dev) <= AGREE_WELL else "the RM's corner displacement adds 2b(1 − cosθ), which grows as α³"),
        Finding("3", "vertical top displacement, RM against SM", "do not match (the SM's top sinks, the RM's lifting corner rises)",
                "opposite signs for every |θ| > 0.05α" if all(v_sign) else "same sign somewhere", "",
                "the RM's lifting corner rises and the SM's top sinks", judged(all(v_sign)),
                "" if all(v_sign) else "the signs do not oppose"),
        Finding("3 (eqs. 5, 7)", "the quasi-rigid SM models' own column top (one DOF; beam, E = 10¹⁴ Pa) against eqs. 5, 7",
                "eqs. 5, 7", f"max deviation {max(d[0] for d in model_dev):.1e} × 2R (concrete beam: "
                f"{max(d[1] for d in model_dev):.1e} × 2R, its shortening under its own weight)", "", "≤ 1e-9 × 2R",
                judged(max(d[0] for d in model_dev) <= 1e-9),
                "" if max(d[0] for d in model_dev) <= 1e-9 else "the models' kinematics are not eqs. 5, 7"),
    ]


def fig04(out: Path, *, height: float = 10.0, n_elements: int = 4, n_points: int = 101) -> list[Finding]:
    out = Path(out)
    panels, eq_dev, model_dev, flex_drop = [], [], [], []
    for ta in TAN_ALPHAS:
        block = Block.from_slenderness(height, ta)
        a = float(block.alpha)
        th = np.linspace(0.0, 1.0, n_points) * a
        eq8 = np.tan(a - th)
        eq9 = np.asarray(pushover_eq9(th, a))
        yielded = th >= 0.05 * a  # beyond the spring's pre-yield band (θs = 1e-4 α by default)
        quasi = np.asarray(SpringModel(block).pushover(jnp.asarray(th[yielded])))
        flex = np.asarray(SpringModel(block, Column.concrete(), n_elements=n_elements).pushover(jnp.asarray(th[yielded])))
        x = th / a
        panels.append(dict(title=f"tanα = {ta}, 2h = {height:g} m", xlabel="θ/α", ylabel="F/(m g)", lines={
            "SM quasi-rigid (model)": (x[yielded], quasi), f"SM concrete, {n_elements} elements (model)": (x[yielded], flex),
            "paper RM eq. 8": (x, eq8), "paper SM eq. 9": (x, eq9)}))
        eq_dev.append(np.max(np.abs(eq9 - eq8)) / ta)
        model_dev.append(np.max(np.abs(quasi / eq9[yielded] - 1)))
        flex_drop.append(np.max(np.abs(flex - eq9[yielded])) / ta)
    plt.close(plot_curves(panels, path=out / "fig04_pushover.png", title="figure 4: pushover, RM (eq. 8) and SM (eq. 9)"))
    return [
        Finding("4", "pushover, RM eq. 8 against SM eq. 9", "agree well",
                "max |eq. 9 − eq. 8| / tanα = " + ", ".join(f"{100 * d:.1f} %" for d in eq_dev), "",
                f"≤ {100 * AGREE_WELL:g} % of tanα for each tanα", judged(max(eq_dev) <= AGREE_WELL),
                "" if max(eq_dev) <= AGREE_WELL else "eq. 9 exceeds eq. 8 by tanα(1/cosθ − 1) + …, which grows as α²"),
        Finding("4 (eq. 9)", "the quasi-rigid SM's own static pushover against eq. 9 (θ ≥ 0.05α)", "eq. 9",
                f"max relative deviation {max(model_dev):.1e}; concrete column below by ≤ "
                f"{100 * max(flex_drop):.2f} % of tanα (bending P-Δ)", "", "quasi-rigid within 1e-6",
                judged(max(model_dev) <= 1e-6), "" if max(model_dev) <= 1e-6 else "the spring has not yielded"),
    ]
