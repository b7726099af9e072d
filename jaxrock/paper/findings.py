"""A finding: one value the paper reports (a row of SPEC's table, or a number printed in the text)
set beside jaxrock's, with the criterion that judges them and the verdict.

Verdicts:
- `REPRODUCED`: jaxrock's value meets the criterion (a stated tolerance, or the paper's claim
  restated as a computed inequality);
- `EXPLAINED`: it does not, and a computation run with the figure says why (its numbers are in
  `reason`);
- `NOT_REPRODUCED`: it does not, and nothing computed explains it (`reason` says what was tried).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

REPRODUCED = "reproduced"
EXPLAINED = "differs, explained"
NOT_REPRODUCED = "not reproduced"
VERDICTS = (REPRODUCED, EXPLAINED, NOT_REPRODUCED)


@dataclass(frozen=True)
class Finding:
    figure: str  # "5, 8", "17", "eq. 21", ...
    quantity: str  # what is compared
    paper: str  # the paper's value or claim, as it reports it
    jaxrock: str  # jaxrock's value (computed in this run)
    difference: str  # jaxrock against the paper ("" where the claim is qualitative)
    criterion: str  # what "reproduced" means for this row
    verdict: str  # one of VERDICTS
    reason: str = ""  # for a verdict other than REPRODUCED: the computed explanation or what was tried

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")
        if self.verdict != REPRODUCED and not self.reason:
            raise ValueError(f"figure {self.figure}, {self.quantity}: a verdict '{self.verdict}' needs its reason")

    def row(self) -> dict:
        return asdict(self)


def judged(ok: bool, explanation: str | None = None) -> str:
    """The verdict of a criterion met (`ok`) or not; not met, `EXPLAINED` where a computed
    `explanation` is given, else `NOT_REPRODUCED`."""
    return REPRODUCED if ok else (EXPLAINED if explanation else NOT_REPRODUCED)


def value_finding(figure: str, quantity: str, paper: float, value: float, *, rtol: float, unit: str = "",
                  digits: int = 4, explanation: str | None = None, tried: str | None = None) -> Finding:
    """A number against the paper's, reproduced within the relative tolerance `rtol` (chosen from
    the digits the paper prints, or stated where it is a model difference). Outside it, the row is
    `EXPLAINED` by `explanation` (a computed reason), else `NOT_REPRODUCED` with `tried`."""
    rel = (value - paper) / abs(paper) if paper != 0 else math.copysign(math.inf, value)
    ok = abs(rel) <= rtol
    u = f" {unit}" if unit else ""
    return Finding(figure, quantity, f"{paper:.{digits}g}{u}", f"{value:.{digits}g}{u}", f"{100 * rel:+.1f} %",
                   f"within {100 * rtol:g} %", judged(ok, explanation),
                   "" if ok else (explanation or tried or "no computed explanation"))
