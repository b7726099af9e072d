"""Figure 7 and the c̄ calibration: the SM's free-rocking energy ratio r_eq² and c̄ calibrated by
gradient against the RM's η⁴, beside eq. 17 (writes fig07_energy_ratio.png, calibration_cbar.png,
calibration.csv).

    python experiments/fig07_energy_ratio.py [--out out/figures]
"""

from jaxrock.paper.reproduce import script

script('fig07', doc=__doc__)
