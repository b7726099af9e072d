"""Figure 17: the Christchurch Airport chimney (paper section 6) under El Centro 1940 NS, rocking on
its 7.5 m foundation (tanα′ = 7.5/32.65 = 0.23) and on a foundation too wide to uplift (fixed
base). Concrete, ζ = 0.01, constant section A = 1.74 m², I = 2.99 m⁴. The paper reports a maximum
base moment of 7327 kNm rocking against 33200 kNm fixed, and a maximum rotation of 0.027 α′.

The column's width for the block geometry (its rotary inertia and the SM's R) is the solid
rectangle with the same radius of gyration, 2b = sqrt(12 I/A) = 4.54 m.

Beside the figure, a study of what moves the moments (`VARIANTS`): the moment measured in the
column's lowest section instead of the spring's, the record's processing (the PEER record against
the older "Peknold" version), the damping ratio, the mass, a cracked stiffness, the added
rotational masses and the mesh. Each variant runs the rocking and the fixed-base chimney.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..excitation import Record
from ..geometry import Block
from ..io.records import builtin_record, el_centro
from ..model import simulate
from ..plotting import plot_history
from ..results import Save, status_names
from ..rigid import RigidModel
from ..spring import Column, SpringModel
from .findings import Finding, judged, value_finding

HEIGHT, BASE, A, I = 32.65, 7.5, 1.74, 2.99
PAPER = {"rocking": 7327.0, "fixed": 33200.0, "rotation": 0.027}


def peknold() -> Record:
    """El Centro 1940 NS, the older "Peknold version" (1559 points at 0.02 s, PGA 0.3188 g), from
    the OpenSees repository (`EXAMPLES/ExampleScripts/elCentro.AT2`), shipped as
    `jaxrock/data/records/elCentro_peknold.AT2`."""
    return builtin_record("elcentro_peknold", label="El Centro 1940 NS (Peknold)")


def chimney(*, rho_factor=1.0, E_factor=1.0, zeta=0.01, n_elements=10, added_masses=True, fixed_base=False) -> SpringModel:
    block = Block.from_size(HEIGHT, math.sqrt(12 * I / A), base_width=BASE)
    column = Column(Column.concrete().E * E_factor, Column.concrete().rho * rho_factor, A=A, I=I)
    return SpringModel(block, column, zeta=zeta, n_elements=n_elements, added_masses=added_masses, fixed_base=fixed_base)


def run(record, fields=("theta", "w_top", "base_moment", "section_moment"), **kw):
    """Rocking and fixed-base runs of one variant: their solutions (histories at 0.01 s)."""
    ts = np.arange(0.0, float(record.t_end) + 5.0, 0.01)
    return {name: simulate(chimney(fixed_base=fixed, **kw), record, save=Save(ts, fields))
            for name, fixed in (("rocking", False), ("fixed", True))}


def peaks(sols, moment="base_moment", **kw) -> dict:
    """The peak moments [kNm] of a variant's runs, their ratio, the rotation and T₁ [s]."""
    m = {k: float(np.max(np.abs(np.asarray(s.history[moment])))) / 1e3 for k, s in sols.items()}
    return {**m, "T1": float(chimney(fixed_base=True, **kw).first_period()), "ratio": m["rocking"] / m["fixed"],
            "rotation": float(sols["rocking"].max_theta), "ok": all(status_names(s.status) == "ok" for s in sols.values())}


VARIANTS = {  # name → (record, model options, moment measured)
    "as in the paper's text (baseline)": ("peer", {}, "base_moment"),
    "moment in the column's lowest section": ("peer", {}, "section_moment"),
    "record: Peknold version": ("peknold", {}, "base_moment"),
    "ζ = 0.005": ("peer", {"zeta": 0.005}, "base_moment"),
    "ζ = 0.02": ("peer", {"zeta": 0.02}, "base_moment"),
    "mass × 1.25": ("peer", {"rho_factor": 1.25}, "base_moment"),
    "mass × 1.5": ("peer", {"rho_factor": 1.5}, "base_moment"),
    "E × 0.7 (cracked)": ("peer", {"E_factor": 0.7}, "base_moment"),
    "no added rotational masses": ("peer", {"added_masses": False}, "base_moment"),
    "20 elements": ("peer", {"n_elements": 20}, "base_moment"),
    "Peknold, section moment, mass × 1.5": ("peknold", {"rho_factor": 1.5}, "section_moment"),
}
STIFFNESS_SCAN = (1.3, 1.15, 0.85, 0.7, 0.55)
QUICK_VARIANTS = tuple(k for k in VARIANTS if k != "20 elements")


def fig17(out: Path, *, n_elements: int = 10, quick: bool = False) -> list[Finding]:
    out = Path(out)
    records = {"peer": el_centro(), "peknold": peknold()}
    sols = run(records["peer"], n_elements=n_elements)
    plt.close(plot_history({"rocking": sols["rocking"], "fixed base": sols["fixed"]}, records["peer"],
                           fields=("theta", "w_top", "base_moment"), model=RigidModel(chimney().block),
                           path=out / "fig17_chimney.png", title="figure 17: Christchurch chimney, El Centro 1940 NS"))
    base = peaks(sols, n_elements=n_elements)
    # the rocking moment is about m g b′ (the spring's yield): the mass that gives the paper's
    mass_match = PAPER["rocking"] / base["rocking"]
    # and with it, stiffness factors that move T₁ along the record's spectrum (the fixed-base moment)
    variants = {**{k: VARIANTS[k] for k in (QUICK_VARIANTS if quick else VARIANTS)},
                f"mass × {mass_match:.3f} (the paper's rocking moment over the baseline's)": ("peer", {"rho_factor": mass_match}, "base_moment"),
                **{f"mass × {mass_match:.3f}, E × {e:g}": ("peer", {"rho_factor": mass_match, "E_factor": e}, "base_moment")
                   for e in STIFFNESS_SCAN}}
    table = {}
    for name, (rec, opts, moment) in variants.items():
        table[name] = base if (rec, opts, moment) == ("peer", {}, "base_moment") else \
            peaks(run(records[rec], **{"n_elements": n_elements, **opts}), moment, **{"n_elements": n_elements, **opts})
    lines = ["# Christchurch chimney: what moves the maximum base moments", "",
             f"Paper: {PAPER['rocking']:.0f} kNm rocking, {PAPER['fixed']:.0f} kNm fixed, ratio "
             f"{PAPER['rocking'] / PAPER['fixed']:.3f}, rotation {PAPER['rotation']} α′.", "",
             "| variant | rocking [kNm] | fixed [kNm] | ratio | max θ/α′ | T₁ fixed [s] | all ok |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    lines += [f"| {k} | {v['rocking']:.0f} ({100 * (v['rocking'] / PAPER['rocking'] - 1):+.0f} %) | {v['fixed']:.0f} "
              f"({100 * (v['fixed'] / PAPER['fixed'] - 1):+.0f} %) | {v['ratio']:.3f} | {v['rotation']:.4f} | {v['T1']:.3f} | {v['ok']} |"
              for k, v in table.items()]
    (out / "fig17_variants.md").write_text("\n".join(lines) + "\n")

    def err(v):
        return max(abs(math.log(v["rocking"] / PAPER["rocking"])), abs(math.log(v["fixed"] / PAPER["fixed"])))

    best = min(table, key=lambda k: err(table[k]))
    b = table[best]
    scan = [v for k, v in table.items() if k.startswith(f"mass × {mass_match:.3f}")]
    lo, hi = min(scan, key=lambda v: v["fixed"]), max(scan, key=lambda v: v["fixed"])
    ratios = [v["ratio"] for v in table.values()]
    within = err(b) <= math.log(1.1)
    explanation = (
        f"The rocking moment is the spring's yield m g b′ = {chimney().mass() * 9.81 * BASE / 2 / 1e3:.0f} kNm plus the damper's "
        f"moment: {PAPER['rocking']:.0f} kNm needs {mass_match:.2f}× the mass ρ A 2h (or a base moment {100 * (mass_match - 1):.0f} % "
        "above the uplift moment). The fixed-base moment follows the 1 %-damped spectrum of the record at T₁, which is spiky: "
        f"with that mass it ranges {lo['fixed']:.0f}–{hi['fixed']:.0f} kNm for T₁ = {min(v['T1'] for v in scan):.2f}–"
        f"{max(v['T1'] for v in scan):.2f} s. Of {len(table)} variants (fig17_variants.md) the closest to both is '{best}': "
        f"{b['rocking']:.0f} and {b['fixed']:.0f} kNm ({100 * (b['rocking'] / PAPER['rocking'] - 1):+.0f} %, "
        f"{100 * (b['fixed'] / PAPER['fixed'] - 1):+.0f} %), ratio {b['ratio']:.3f}: two factors fitted to two numbers, "
        "which shows the paper's magnitudes are within the model's reach, not what the paper used. The ratio rocking/fixed "
        f"ranges {min(ratios):.2f}–{max(ratios):.2f} over the variants (paper {PAPER['rocking'] / PAPER['fixed']:.2f}): "
        "rocking always cuts the moment, by how much depends on T₁")
    found = explanation if within else None
    tried = explanation + "; no variant comes within 10 % of both"
    return [
        value_finding("17", "maximum base moment, rocking", PAPER["rocking"], base["rocking"], rtol=0.10, unit="kNm",
                      explanation=found, tried=tried),
        value_finding("17", "maximum base moment, fixed base", PAPER["fixed"], base["fixed"], rtol=0.10, unit="kNm",
                      explanation=found, tried=tried),
        Finding("17", "rocking cuts the base moment (rocking / fixed)", "< 1/4 (7327/33200 = 0.221)",
                f"{base['ratio']:.3f} (variants {min(ratios):.2f}–{max(ratios):.2f})", f"{100 * (base['ratio'] / 0.2207 - 1):+.0f} %",
                "ratio < 0.25", judged(base["ratio"] < 0.25, found),
                "" if base["ratio"] < 0.25 else f"rocking cuts the moment to {base['ratio']:.2f} of the fixed base's, not below "
                f"a quarter. {explanation if within else tried}"),
        value_finding("17", "maximum rotation of the rocking chimney", PAPER["rotation"], base["rotation"], rtol=0.10, unit="α′",
                      digits=3),
    ]

