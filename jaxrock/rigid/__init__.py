"""The rigid rocking model (RM): Housner's block (eq. 2) or a rigid column on an extended base
(eq. 22), impacts by eq. 3, run by events located on diffrax's dense output.

- `model`: `RigidModel` (the value: geometry, η, threshold; the closed-form free peak);
- `frame`: `RockingFrame` (columns capped by a rigid beam, Makris & Vassiliou 2013: an equivalent block);
- `event_integrator`: `EventIntegrator` and its `RigidStepper` (rest, rocking segments, impacts,
  Zeno closure, the summary's early stop).
"""

from .event_integrator import EventIntegrator, RigidStepper
from .frame import RockingFrame
from .model import RigidModel

__all__ = ["RigidModel", "RockingFrame", "EventIntegrator", "RigidStepper"]
