"""Figures 5–10: rigid blocks by the RM and the quasi-rigid SM (paper section 4).

- 5, 8: 2h = 10 m, tanα = 0.1, 0.2, 0.3 under a symmetric Ricker pulse a_p = 4 g tanα,
  ω_p = 2π rad/s; RM against the SM without and with the added rotational masses; undamped
  (figure 5: η = 1, c̄ = 0) and damped (figure 8: η of eq. 3, c̄ of eq. 17).
- 6, 9: their overturning spectra.
- 7: the SM's free-rocking energy ratio r_eq² and the calibrated c̄ against eq. 17.
- 10: the least El Centro factor that overturns a block, against 2h, RM against the SM.
Also the check value of SPEC's notation: p of the Temple of Apollo's column.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..excitation import RickerPulse
from ..geometry import Block, pulse_of_ratios
from ..io.records import el_centro
from ..model import simulate
from ..plotting import plot_history, plot_record_spectrum, plot_spectra_grid
from ..reports import calibration_report
from ..analyses.calibration import calibrate_cbar
from ..analyses.free_rocking import SpringFamily
from ..results import Save
from ..rigid import RigidModel
from ..spring import SpringModel
from ..analyses.spectra import overturning_spectrum, record_overturning_scale
from .findings import Finding, judged, value_finding

TAN_ALPHAS = (0.1, 0.2, 0.3)
FOLLOWS = 0.05  # "follows the RM": peak θ/α within 5 % of the RM's
AGREE_CELLS = 0.05  # "the spectra agree": at most 5 % of the cells with another overturning verdict


def _models(block, damped):
    return {
        "RM": RigidModel(block, eta=None if damped else 1.0),
        "SM": SpringModel(block, added_masses=False, cbar=None if damped else 0.0),
        "SM + ΔI": SpringModel(block, added_masses=True, cbar=None if damped else 0.0),
    }


def temple_of_apollo() -> list[Finding]:
    p = float(Block.from_size(7.5, 1.8).p)
    return [value_finding("2 (p)", "frequency parameter p of the Temple of Apollo's column (7.5 m × 1.8 m)", 1.4, p,
                          rtol=0.05, unit="rad/s", digits=3)]


def fig05_08(out: Path) -> list[Finding]:
    """Time histories; the RMS of (θ_SM − θ_RM)/α over 10 s and the peaks."""
    out = Path(out)
    rms, peak = {}, {}
    for fig, damped in ((5, False), (8, True)):
        for ta in TAN_ALPHAS:
            block = Block.from_slenderness(10.0, ta)
            pulse = RickerPulse(pulse_of_ratios(block, 4.0, 1.0)[0], 2 * np.pi)
            ts = np.linspace(float(pulse.t_start), float(pulse.t_start) + 10.0, 2001)
            models = _models(block, damped)
            sols = {k: simulate(m, pulse, save=Save(ts, ("theta",))) for k, m in models.items()}
            plt.close(plot_history(sols, pulse, model=models["RM"], path=out / f"fig{fig:02d}_tan{ta}.png",
                                   title=f"figure {fig}: 2h = 10 m, tanα = {ta}, {'damped' if damped else 'undamped'}"))
            th = {k: np.asarray(s.history["theta"]) / float(block.alpha) for k, s in sols.items()}
            for k in ("SM", "SM + ΔI"):
                rms[fig, ta, k] = float(np.sqrt(np.mean((th[k] - th["RM"]) ** 2)))
                peak[fig, ta, k] = float(sols[k].max_theta) / float(sols["RM"].max_theta) - 1
    findings = []
    for fig in (5, 8):
        kind = "damped" if fig == 8 else "undamped"
        follows = all(abs(peak[fig, ta, "SM + ΔI"]) <= FOLLOWS for ta in TAN_ALPHAS)
        best = min(TAN_ALPHAS, key=lambda ta: rms[fig, ta, "SM"])
        masses_help = all(rms[fig, ta, "SM + ΔI"] < rms[fig, ta, "SM"] for ta in TAN_ALPHAS if ta > 0.1)
        text = "; ".join(f"tanα {ta}: RMS {rms[fig, ta, 'SM + ΔI']:.3f} (without ΔI {rms[fig, ta, 'SM']:.3f}), "
                         f"peak {100 * peak[fig, ta, 'SM + ΔI']:+.1f} %" for ta in TAN_ALPHAS)
        ok = follows and best == 0.1 and masses_help
        findings.append(Finding(
            f"{fig}", f"θ/α history of the SM against the RM ({kind})",
            "SM with added masses follows the RM; the SM matches best for tanα = 0.1; the masses help squat blocks",
            text, "", f"peaks within {100 * FOLLOWS:g} %; the SM without ΔI has its least RMS of (θ_SM − θ_RM)/α at "
            "tanα = 0.1; ΔI lowers the RMS for tanα = 0.2, 0.3", judged(ok),
            "" if ok else f"least RMS without ΔI at tanα = {best}; masses help: {masses_help}; peaks within "
            f"{100 * FOLLOWS:g} %: {follows}"))
        worse = rms[fig, 0.1, "SM + ΔI"] > rms[fig, 0.1, "SM"]
        findings.append(Finding(
            f"{fig}", f"tanα = 0.1: the added masses against none ({kind})", "slightly worse with the added masses",
            f"RMS {rms[fig, 0.1, 'SM + ΔI']:.3f} with, {rms[fig, 0.1, 'SM']:.3f} without", "", "RMS with ΔI larger",
            judged(worse), "" if worse else
            "jaxrock's SM with ΔI has the RM's inertia exactly (I_tot = I_o) and differs from eq. 2 only by eq. 10's "
            "nonlinear terms; the paper puts its worse match down to other sources of error, which are not identified"))
    return findings


def fig06_09(out: Path, *, n: int = 32) -> list[Finding]:
    out = Path(out)
    w, a = np.linspace(1, 15, n), np.linspace(0.5, 10, n)
    disagree, doubt = {}, {6: 0, 9: 0}
    for fig, damped in ((6, False), (9, True)):
        spectra, titles = [], []
        for ta in TAN_ALPHAS:
            rm = None
            for name, m in _models(Block.from_slenderness(10.0, ta), damped).items():
                s = overturning_spectrum(m, w, a, progress=False, sensitivity=True)
                doubt[fig] += int(np.sum(s.uncertain))
                s.save(out / f"fig{fig:02d}_{name.replace(' + ', '_').replace('ΔI', 'dI')}_tan{ta}.nc")
                rm = s if rm is None else rm
                spectra.append(s)
                titles.append(f"{name}, tanα = {ta}")
                if name != "RM":  # a failed cell (either model) counts as a disagreement
                    failed = (s.status != 0) | (rm.status != 0)
                    disagree[fig, ta, name] = (float(np.mean((s.overturned != rm.overturned) | failed)),
                                               float(np.median(np.abs(s.max_theta - rm.max_theta))), int(failed.sum()))
        plt.close(plot_spectra_grid(spectra, titles, ncols=3, path=out / f"fig{fig:02d}_spectra.png",
                                    suptitle=f"figure {fig}: {'damped' if damped else 'undamped'} rigid blocks, symmetric Ricker pulse"))
    findings = []
    for fig in (6, 9):
        worst = max(v[0] for k, v in disagree.items() if k[0] == fig)
        ok = worst <= AGREE_CELLS
        text = "; ".join(f"{name} tanα {ta}: {100 * disagree[fig, ta, name][0]:.1f} % cells, median |Δθ/α| "
                         f"{disagree[fig, ta, name][1]:.3f}" + (f", {disagree[fig, ta, name][2]} failed" if disagree[fig, ta, name][2] else "")
                         for ta in TAN_ALPHAS for name in ("SM", "SM + ΔI"))
        text += f"; verdicts rounding could flip (jaxrock.sensitivity): {doubt[fig]} of {3 * len(TAN_ALPHAS) * n * n} cells"
        findings.append(Finding(
            f"{fig}", f"spectra ({'damped' if fig == 9 else 'undamped'}, {n}×{n}): RM, SM without and with added masses",
            "the three agree", text, "", f"each SM spectrum gives another overturning verdict than the RM's in ≤ "
            f"{100 * AGREE_CELLS:g} % of the cells (a failed cell counts as another verdict)", judged(ok),
            "" if ok else f"up to {100 * worst:.1f} % of the cells differ"))
    return findings


def fig07(out: Path, *, quick: bool = False) -> list[Finding]:
    rep = calibration_report(out, tan_alphas=TAN_ALPHAS if quick else None, progress=False,
                             fig7_theta0_over_alpha=np.linspace(0.05, 0.98, 12 if quick else 32))
    xs, r2 = rep.fig7_theta0_over_alpha, rep.fig7_r2  # (tanα, c̄, θ₀)
    upper = xs >= 0.5
    along_theta = float(np.max(np.ptp(r2[:, :, upper], axis=-1)))
    across_alpha = float(np.max(np.ptp(r2[:, :, upper], axis=0)))
    findings = [Finding(
        "7", "r_eq² against θ₀/α (tanα = 0.1, 0.2, 0.3; c̄ = 0.02, 0.08, 0.18)",
        "r_eq depends little on α and, above θ₀/α = 0.5, on θ₀",
        f"spread over θ₀/α ∈ [0.5, 1): ≤ {along_theta:.3f}; over tanα at one c̄: ≤ {across_alpha:.3f}", "",
        "both spreads ≤ 0.1 (in r_eq²)", judged(max(along_theta, across_alpha) <= 0.1),
        "" if max(along_theta, across_alpha) <= 0.1 else "r_eq² varies more than 0.1")]
    by_ta = {round(r["tan_alpha"], 6): r for r in rep.table}
    variants = {"without added masses": SpringFamily(added_masses=False), "with the bilinear backbone": SpringFamily(backbone="bilinear")}
    other = {k: float(calibrate_cbar([0.3], family=fam, progress=False).cbar[0]) for k, fam in variants.items()}
    tried = (f"the calibration's fit over tanα ∈ [0.1, 0.3] is c̄ = {rep.fit_paper_range.k:.4f} (α/0.1)^{rep.fit_paper_range.n:.2f}: "
             "k is the paper's 0.02, the exponent is not its 2. Tried at tanα = 0.3 (eq. 17: 0.170): the SM "
             + ", ".join(f"{k} (c̄ = {v:.3f})" for k, v in other.items()) + "; neither closes the gap. The paper's OpenSees "
             "integrator and spring discretisation are not known")
    for ta in TAN_ALPHAS:
        r = by_ta[ta]
        findings.append(value_finding("7 (eq. 17)", f"calibrated c̄ at tanα = {ta} (RM target r² = η⁴ = {r['target_r2']:.4f})",
                                      r["cbar_eq17"], r["cbar_calibrated"], rtol=0.10, digits=3, tried=tried))
    return findings


def fig10(out: Path, *, heights=(1, 2, 4, 8, 16), scales=np.linspace(0.5, 10, 20), refine: int = 8) -> list[Finding]:
    out = Path(out)
    record = el_centro()
    results, labels, least, doubt = [], [], {}, 0
    for ta in TAN_ALPHAS:
        block = Block.from_slenderness(heights[0], ta)
        for name, m in (("RM", RigidModel(block)), ("SM", SpringModel(block))):
            r = record_overturning_scale(m, record, heights, scales, refine=refine, progress=False, sensitivity=True)
            doubt += int(np.sum(r.uncertain))
            r.save(out / f"fig10_{name}_tan{ta}.nc")
            results.append(r)
            labels.append(f"{name}, tanα = {ta}")
            least[name, ta] = np.asarray(r.scale)
    plt.close(plot_record_spectrum(results, labels, path=out / "fig10_el_centro.png",
                                   title="figure 10: El Centro 1940 NS, least overturning scale factor"))
    # a height that neither model overturns at any factor of the sweep agrees (inf/inf: 0, not NaN)
    standing = {ta: np.isinf(least["SM", ta]) & np.isinf(least["RM", ta]) for ta in TAN_ALPHAS}
    rel = {ta: np.where(standing[ta], 0.0, np.abs(least["SM", ta] / least["RM", ta] - 1)) for ta in TAN_ALPHAS}
    med = {ta: float(np.median(rel[ta])) for ta in TAN_ALPHAS}
    ok = all(med[ta] <= 0.10 for ta in TAN_ALPHAS if ta < 0.3)
    text = "; ".join(f"tanα {ta}: median |SM/RM − 1| {100 * med[ta]:.1f} % (max {100 * np.max(rel[ta]):.0f} %"
                     + (f", both standing to factor {np.asarray(scales)[-1]:g} at {int(standing[ta].sum())} height(s))" if standing[ta].any() else ")")
                     for ta in TAN_ALPHAS)
    text += (f"; least factors an uncertain run decided (a verdict rounding could flip, jaxrock.sensitivity): {doubt} of "
             f"{2 * len(TAN_ALPHAS) * len(heights)}")
    return [Finding("10", f"least overturning El Centro factor, RM against SM (2h = {', '.join(f'{h:g}' for h in heights)} m)",
                    "agree for α < 0.3", text, "", "median relative difference over the heights ≤ 10 % for tanα = 0.1, 0.2",
                    judged(ok), "" if ok else "the factors differ by more than 10 %")]
