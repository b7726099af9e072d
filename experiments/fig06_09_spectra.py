"""Figures 6 and 9: overturning spectra of rigid blocks (tanα = 0.1, 0.2, 0.3; symmetric Ricker
pulse) by the RM and the quasi-rigid SM without and with the added rotational masses; undamped
(figure 6) and damped (figure 9).

    python experiments/fig06_09_spectra.py [--n 32] [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig06', doc=__doc__)
