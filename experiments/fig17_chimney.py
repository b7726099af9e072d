"""Figure 17: the Christchurch Airport chimney under El Centro 1940 NS, rocking and fixed base, and
what moves its base moments (fig17_variants.md).

    python experiments/fig17_chimney.py [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig17', doc=__doc__)
