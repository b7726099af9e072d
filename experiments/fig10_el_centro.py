"""Figure 10: least scale factor of the El Centro 1940 NS record that overturns a block, against
its height 2h, RM against the quasi-rigid SM, tanα = 0.1, 0.2, 0.3.

    python experiments/fig10_el_centro.py [--heights 1,2,4,8,16] [--refine 8] [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig10', doc=__doc__)
