"""Figures 3 and 4: the SM's kinematics and pushover against the RM's (eqs. 4-9), with the SM
models' own top displacements and static pushover (quasi-rigid and concrete columns).

    python experiments/fig03_04_kinematics.py [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig03', 'fig04', doc=__doc__)
