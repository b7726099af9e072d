"""Figures 5 and 8: rocking of 10 m blocks (tanα = 0.1, 0.2, 0.3) under a symmetric Ricker pulse
a_p = 4 g tanα, ω_p = 2π rad/s: the RM against the quasi-rigid SM with and without the added
rotational masses; undamped (figure 5: η = 1, c̄ = 0) and damped (figure 8).

    python experiments/fig05_08_time_histories.py [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig05', doc=__doc__)
