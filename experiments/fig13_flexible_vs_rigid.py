"""Figure 13: a rigid and a concrete column, 2h = 50 m, 2b = 5 m, under the pulses
(ω_p/p, a_p/(g tanα)) = (3, 2.6) and (6, 5.85), and the overturning boundary along ω_p/p = 6 of
each model and of variants of it (fig13_boundaries.md).

    python experiments/fig13_flexible_vs_rigid.py [--n-elements 10] [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig13', doc=__doc__)
