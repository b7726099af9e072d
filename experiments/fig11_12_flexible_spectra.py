"""Figures 11 and 12 and eq. 21: overturning spectra of quasi-rigid and concrete columns of four
heights, tanα = 0.1 and 0.2, symmetric Ricker pulse, and their uplift and overturning lines.

    python experiments/fig11_12_flexible_spectra.py [--n 24] [--heights 10,30,50,100] [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('eq21', 'fig11', doc=__doc__)
