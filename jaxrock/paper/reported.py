"""What the paper reports: one row per figure or equation whose values `reproduce` sets beside
jaxrock's (Vassiliou, Mackie, Stojadinović 2014, EESD; the scenes as the paper states them).

`reproduce` prints each step's rows above its findings, and `tests/test_paper.py` checks that the
quick run gives every row findings with verdicts. The numbers themselves are compared where they
are computed (`value_finding` in the step modules), each beside its equation or figure.
"""

from __future__ import annotations

from typing import NamedTuple


class Reported(NamedTuple):
    figures: str  # the figures or equations, comma-separated, as the findings name them
    step: str  # the `reproduce` step that computes them (`jaxrock.paper.reproduce.STEPS`)
    scene: str
    reported: str


REPORTED: tuple[Reported, ...] = (
    Reported("2", "fig02", "the 7.5 m × 1.8 m column of the Temple of Apollo", "p ≈ 1.4 rad/s"),
    Reported("3", "fig03", "top displacements of the RM (eqs. 4, 6) and the SM (eqs. 5, 7)",
             "horizontal displacements agree; vertical displacements do not"),
    Reported("4", "fig04", "pushover of the RM (eq. 8) and the SM (eq. 9)", "the two agree well"),
    Reported("5, 8", "fig05", "2h = 10 m, tanα = 0.1, 0.2, 0.3, symmetric Ricker a_p = 4 g tanα, ω_p = 2π rad/s; "
             "undamped (5) and damped (8)", "SM with added masses follows RM; best for tanα = 0.1"),
    Reported("6, 9", "fig06", "spectra, tanα = 0.1, 0.2, 0.3; RM, SM without and with added masses", "the three agree"),
    Reported("7", "fig07", "r_eq² vs θ₀/α, tanα = 0.1/0.2/0.3, c̄ = 0.02/0.08/0.18",
             "r_eq depends little on α and, above θ₀/α = 0.5, on θ₀"),
    Reported("eq. 17", "fig07", "c̄ calibrated so that the SM's r_eq² equals the RM's η⁴, tanα = 0.1, 0.2, 0.3",
             "c̄ = 0.02 (α/0.1)²: 0.0199, 0.0779, 0.1699"),
    Reported("10", "fig10", "El Centro, least overturning scale factor, RM vs SM", "agree for α < 0.3"),
    Reported("eq. 21", "eq21", "fixed-base first period of a solid 2h = 50 m, 2b = 5 m concrete column", "T₁ = 0.893 s"),
    Reported("11, 12", "fig11", "quasi-rigid and concrete columns of four heights, tanα = 0.1, 0.2, ζ = 0.01",
             "flexibility immaterial for tanα > 0.2; for tanα = 0.1, flexible uplifts below g tanα; less stable than rigid "
             "for ω_p/p < 4.5, more stable above"),
    Reported("13", "fig13", "2h = 50 m, 2b = 5 m; (ω_p/p, a_p/(g tanα)) = (3, 2.6) and (6, 5.85)",
             "(3, 2.6): flexible overturns, rigid keeps rocking; (6, 5.85): flexible survives, rigid overturns"),
    Reported("15, 16", "fig15", "columns on a rigid base tanα′ = 0.3; symmetric and antisymmetric pulses",
             "flexibility negligible for tanα > 0.2; for tanα = 0.1 only above 50 m and ω_p/p < 4"),
    Reported("17", "fig17", "Christchurch chimney: 2h = 32.65 m, base 7.5 m (tanα′ = 0.23), I = 2.99 m⁴, A = 1.74 m², "
             "concrete, ζ = 0.01, El Centro NS", "max base moment 7327 kNm rocking vs 33200 kNm fixed base; max rotation 0.027 α′"),
)
