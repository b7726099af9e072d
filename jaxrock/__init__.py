"""jaxrock: differentiable, vmappable rocking-body simulation (rigid and spring models) in JAX.

Layers, top-down (each imports only from its own layer and those below; README "Layout"):
front ends (`cli`, `reports`, `plotting`) → analyses (`analyses`: the batch engine, spectra,
calibration, scenes files) → input/output (`io`) → models with their integrators (`rigid`,
`spring`) → the protocol (`model`: model → stepper, `simulate`; `bookkeeping`: what a run records)
→ values (`geometry`, `excitation`, `results`). Everything public is re-exported here.

Simulations run in float64: importing jaxrock sets `jax_enable_x64`. There is no float32 mode
(it ended the default scene in `max_steps` with θ/α = 0, and 33 of 4096 cells of a spectrum
failed); the variable `JAXROCK_X64` that once chose it is refused unless it is 1.

Importing jaxrock also turns on JAX's persistent compilation cache in the user's cache folder
(`jaxrock.cache`: `JAXROCK_CACHE_DIR` moves it, `JAXROCK_CACHE_DIR=off` switches it off), unless
the process has chosen a cache folder of its own.
"""

import os as _os

import jax as _jax

if _os.environ.get("JAXROCK_X64", "1") != "1":
    raise ImportError(f"JAXROCK_X64 = {_os.environ['JAXROCK_X64']!r}: jaxrock runs in float64 only (its float32 mode gave wrong "
                      "answers and was removed); unset the variable")
_jax.config.update("jax_enable_x64", True)

from .cache import enable_compilation_cache as _enable_compilation_cache

_enable_compilation_cache()  # JAX's persistent compilation cache, unless switched off or chosen by the process (jaxrock.cache)

from ._validate import JaxrockInputError
from .geometry import G, Block
from .excitation import AbstractExcitation, AntisymmetricRickerPulse, Record, RickerPulse, StillGround

__all__ = [
    "G",
    "Block",
    "AbstractExcitation",
    "RickerPulse",
    "AntisymmetricRickerPulse",
    "Record",
    "StillGround",
    "JaxrockInputError",
]

from .results import SUMMARY, Output, Save, Solution, Status, status_codes, status_names
from .model import (AbstractIntegrator, AbstractModel, AbstractSpringIntegrator, AbstractStepper, ModelKind, Schedule,
                    register_model_kind, simulate)
from .rigid import EventIntegrator, RigidModel

__all__ += [
    "Save",
    "Solution",
    "Status",
    "status_names",
    "status_codes",
    "SUMMARY",
    "Output",
    "AbstractIntegrator",
    "AbstractModel",
    "AbstractStepper",
    "AbstractSpringIntegrator",
    "Schedule",
    "ModelKind",
    "register_model_kind",
    "simulate",
    "EventIntegrator",
    "RigidModel",
]

from .spring import (DEFAULT_BACKBONE, DEFAULT_SMOOTHING, AbstractBackbone, Bilinear, Column, GeneralizedAlpha, SpringIntegrator,
                     SpringModel, SpringSystem, Tanh, cbar_eq17, first_period_eq21, pushover_eq9)
from .scene import pulse_of_ratios, ratios_of_pulse
from .io import el_centro, read_at2, read_record, read_scenes, read_two_column

__all__ += ["pulse_of_ratios", "ratios_of_pulse", "el_centro", "read_at2", "read_record", "read_two_column", "read_scenes"]

from .analyses import (CalibrationResult, RecordSpectrum, Spectrum, calibrate_cbar, energy_ratio, energy_ratio_grid, fit_power_law,
                       overturning_spectrum, record_overturning_scale, refine_boundaries, rm_target, run_batch, run_scenes)

__all__ += ["Spectrum", "RecordSpectrum", "overturning_spectrum", "record_overturning_scale", "refine_boundaries", "run_batch",
            "run_scenes"]

__all__ += [
    "SpringModel",
    "SpringSystem",
    "Column",
    "SpringIntegrator",
    "GeneralizedAlpha",
    "DEFAULT_SMOOTHING",
    "DEFAULT_BACKBONE",
    "AbstractBackbone",
    "Bilinear",
    "Tanh",
    "cbar_eq17",
    "first_period_eq21",
    "pushover_eq9",
    "energy_ratio",
    "energy_ratio_grid",
    "calibrate_cbar",
    "CalibrationResult",
    "fit_power_law",
    "calibration_report",
    "rm_target",
]


def __getattr__(name):
    # The report writes figures: matplotlib is imported when it is first asked for, not with jaxrock.
    if name == "calibration_report":
        from .reports import calibration_report

        return calibration_report
    raise AttributeError(f"module 'jaxrock' has no attribute {name!r}")
