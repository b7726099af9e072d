"""Beyond the paper: the rocking frame's overturning spectra (Makris & Vassiliou 2013), an extra
section of `reproduce` with no row in the paper's table.

Columns of 2h = 10 m, tanα = 0.2 capped by rigid beams of mass ratio γ = m_b/(N m) = 0 (the
solitary column), 1 and 3 under the symmetric Ricker pulse, on the columns' axes ω_p/p and
a_p/(g tanα) as the paper draws them: the heavier the beam, the smaller the frame's frequency
parameter p̂ = p √((1 + 2γ)/(1 + 3γ)) and the higher the overturning boundary
(`jaxrock.rigid.frame`).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..analyses.spectra import overturning_spectrum
from ..geometry import Block
from ..numerics.kept import write_text
from ..plotting import plot_spectra_grid
from ..rigid import RockingFrame
from .findings import Finding

MASS_RATIOS = (0.0, 1.0, 3.0)


def frame_spectra(out: Path, *, n: int = 32, mass_ratios=MASS_RATIOS, refine: int = 8) -> list[Finding]:
    """The frame's spectra (figure `frame_spectra.png`) and the least overturning a_p/(g tanα) per
    ω_p/p and γ (`frame_boundaries.md`). No finding: nothing of the paper is judged here."""
    out = Path(out)
    w, a = np.linspace(1, 15, n), np.linspace(0.5, 10, n)
    block = Block.from_slenderness(10.0, 0.2)
    spectra = []
    for gamma in mass_ratios:
        s = overturning_spectrum(RockingFrame(block, gamma), w, a, refine=refine, progress=False)
        s.save(out / f"frame_gamma{gamma:g}.nc")
        spectra.append(s)
    titles = [f"γ = {g:g}" + (" (the solitary column)" if g == 0 else f", p̂/p = {np.sqrt((1 + 2 * g) / (1 + 3 * g)):.3f}")
              for g in mass_ratios]
    plt.close(plot_spectra_grid(spectra, titles, ncols=len(spectra), path=out / "frame_spectra.png",
                                suptitle="rocking frame (Makris & Vassiliou 2013): columns 2h = 10 m, tanα = 0.2, the frame's η, "
                                         "symmetric Ricker pulse"))
    picks = [k for k in np.unique(np.linspace(0, n - 1, 6).round().astype(int))]
    rows = ["# Rocking frame: least overturning a_p/(g tanα)", "",
            "| ω_p/p | " + " | ".join(f"γ = {g:g}" for g in mass_ratios) + " |",
            "| --- |" + " --- |" * len(mass_ratios)]
    for k in picks:
        cells = [spectra[j].overturn_boundary[k] for j in range(len(mass_ratios))]
        rows.append(f"| {w[k]:.2f} | " + " | ".join("none" if not np.isfinite(c) else f"{c:.3f}" for c in cells) + " |")
    write_text(out / "frame_boundaries.md", "\n".join(rows) + "\n")
    return []
