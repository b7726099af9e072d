"""The nonlinear-elastic, viscously damped spring model (SM) of the paper (sections 3–6).

Two final model kinds (`AbstractSpringModel`), each with its own system (`jaxrock.spring.system`);
`SpringModel(block, column=None, ...)` makes either:

- quasi-rigid (`QuasiRigidSpringModel`, ``column=None``): the one-DOF rigid SM, eq. 10 with the damper (SPEC)
  ``Itot θ̈ + c θ̇ + M(θ) − m g h sinθ = −m üg h cosθ``, ``h = R cosα``; no mesh is built.
- flexible (`FlexibleSpringModel`, ``column=Column(...)``): a corotational Euler–Bernoulli column of ``n_elements``
  elements (`jaxrock.spring.beam`) on the rotational spring, gravity preloaded, stiffness-proportional
  Rayleigh damping on the column's deformation (section 4).

Base spring (section 3, Figure 2 right): nonlinear elastic (it unloads along its loading path),
rigid-plastic in the limit, yield moment ``My = m g R′ sinα′ = m g b′`` (b′ = b for a plain
block), with a finite pre-yield rotation ``θs = smoothing · α′`` (stiffness ``My/θs``): the
bilinear backbone, linear to θy = θs then flat at My (the paper's), or ``M = My tanh(θ/θs)``
(`jaxrock.spring.base_spring`; the potential is the backbone's integral). Damper in parallel:
``c = c̄ m g^0.5 R′^1.5`` (eqs. 17–18), by default with ``c̄ = 0.02 (α′/0.1)²`` (eq. 17). For an
extended base the rocking quantities α′, R′ are used in eq. 17/18, because the damper stands for the impact losses at the base's corners, which are
governed by α′ (the paper: "computed using Equation (17)"); give ``cbar`` to override.

Inertia: without added masses ``Itot = (4/3) m h²`` (the column about its base centre, eq. 11);
with added masses ``Itot = I′o = m·Block.inertia_ratio`` (exact parallel-axis value, = (4/3) m R²
for a plain block), i.e. ``ΔI = I′o − (4/3) m h²`` spread evenly over the ``n + 1`` column nodes.

Forces are gradients of energies (`jax.grad`), so the energy balance holds by construction.

Time integration, chosen by work–precision (`SpringModel.default_integrator`,
`benchmarks/bench_spring.py`): flexible columns: adaptive generalized-α (`GeneralizedAlpha`,
`jaxrock.spring.generalized_alpha`: the spring solved exactly as a scalar equation in each Newton
iteration, the rest-state tangent rotated to the rocked configuration and inverted for any step
from its modes, steps that end on the bilinear spring's kinks; forward-mode differentiable); the
one-DOF quasi-rigid model:
its linear pre-yield phase stepped exactly to the first yield (`rest`), then explicit Tsit5 (its
pre-yield branch is only mildly stiff; reverse-mode differentiable). Either
model takes either integrator; diffrax's ESDIRK (`SpringIntegrator(solver="kvaerno5")`, full
Newton stopped on its increment) is the reverse-mode-differentiable choice for flexible columns.
diffrax runs: integral step-size control with a component-scaled absolute tolerance; overturning
``|θ| ≥ threshold·α′`` is an event. The peak ``max |θ|`` is exact to the solver tolerance: the
base rotation and velocity at every accepted step give a cubic Hermite interpolant (θ, θ̇ at
both ends, fourth-order accurate), maximised in closed form on each step (`jaxrock.bookkeeping`) —
cheaper than an event on θ̇ = 0 with restarts, and differentiable.

Summary runs stop when the answer is fixed: phase 1 runs over the excitation window; phase 2 runs
free motion until the mechanical energy falls below the potential at the largest rotation seen so
far — after which |θ| can never reach that rotation again (exact for the one-DOF model, whose
potential is monotone in |θ| below the barrier; for the flexible model the rigid-rotation
potential is used with a 10 % margin for the flexural P-Δ softening) — or it overturns, or
`t1` (default: excitation end + 20 rocking periods 2π/p′) is reached.

The package, one module per concept:

- `column`: the column's material and section (`Column`) and its closed forms (eqs. 9, 17, 21);
- `beam`: the corotational Euler–Bernoulli elements of a flexible column;
- `base_spring`: the base spring's backbones (`Bilinear`, `Tanh`) and the damper (eq. 18);
- `system`: the assembled system of one scene (`QuasiRigidSystem` or `FlexibleSystem`, both an
  `AbstractSpringSystem`, also named `SpringSystem`; `assemble`);
- `model`: the model value (`SpringModel`) and its scenes-file kinds;
- `rest`: the quasi-rigid model's linear pre-yield phase stepped exactly to its first yield (the
  diffrax integrator's start on a kinked spring);
- `diffrax_integrator`, `generalized_alpha`: the integrators, and `checked` (`Checked`: a
  companion run estimates the global error, and the status says whether it is within accuracy), each a `SpringSystem` → an
  `AbstractStepper` (`jaxrock.model`), the run recorded by `jaxrock.bookkeeping`.
"""

from .base_spring import DEFAULT_BACKBONE, DEFAULT_SMOOTHING, AbstractBackbone, Bilinear, Tanh, as_backbone, damper
from .column import Column, cbar_eq17, first_period_eq21, pushover_eq9
from .checked import Checked, CheckedStepper
from .diffrax_integrator import DiffraxSpringStepper, SpringIntegrator
from .generalized_alpha import GeneralizedAlpha, GeneralizedAlphaStepper
from .model import AbstractSpringModel, FlexibleSpringModel, QuasiRigidSpringModel, SpringModel
from .system import HISTORY_FIELDS, AbstractSpringSystem, FlexibleSystem, QuasiRigidSystem, SpringSystem, assemble

__all__ = [
    "SpringModel",
    "AbstractSpringModel",
    "QuasiRigidSpringModel",
    "FlexibleSpringModel",
    "SpringSystem",
    "AbstractSpringSystem",
    "QuasiRigidSystem",
    "FlexibleSystem",
    "SpringIntegrator",
    "GeneralizedAlpha",
    "Checked",
    "CheckedStepper",
    "DiffraxSpringStepper",
    "GeneralizedAlphaStepper",
    "Column",
    "AbstractBackbone",
    "Bilinear",
    "Tanh",
    "as_backbone",
    "damper",
    "assemble",
    "cbar_eq17",
    "first_period_eq21",
    "pushover_eq9",
    "HISTORY_FIELDS",
    "DEFAULT_SMOOTHING",
    "DEFAULT_BACKBONE",
]
