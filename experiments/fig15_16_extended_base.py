"""Figures 15 and 16: concrete columns (tanα = 0.1, 0.2) on a rigid base with tanα′ = 0.3 under
symmetric and antisymmetric Ricker pulses, against the RM and the quasi-rigid SM.

    python experiments/fig15_16_extended_base.py [--n 24] [--heights 10,50,100] [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig15', doc=__doc__)
