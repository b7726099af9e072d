"""jaxrock: differentiable, vmappable rocking-body simulation (rigid and spring models) in JAX.

Layers, top-down (each imports only from its own layer and those below; docs/development.md, "Layout"):
front ends (`cli`, `reports`, `plotting`) → analyses (`analyses`: the batch engine, spectra,
calibration, scenes files) → input/output (`io`) → models with their integrators (`rigid`,
`spring`) → the protocol (`model`: model → stepper, `simulate`; `bookkeeping`: what a run records)
→ values (`geometry`, `excitation`, `results`, `intensity`) → the vocabulary (`scene`, `outputs`: the words and
defaults of scenes and outputs, without JAX). Everything public is re-exported here.

Importing jaxrock imports none of them, nor JAX: each name below is imported when first used (PEP
562), so that the command line prints its help and refuses bad arguments in a fraction of a second.

Simulations run in float64: once JAX is imported (by jaxrock or by you, before or after jaxrock),
`jax_enable_x64` is set (`jaxrock.runtime`). There is no float32 mode (it ended the default scene
in `max_steps` with θ/α = 0, and 33 of 4096 cells of a spectrum failed); the variable
`JAXROCK_X64` that once chose it is refused unless it is 1. JAX's persistent compilation cache is
turned on at the same moment, in the user's cache folder (`jaxrock.cache`: `JAXROCK_CACHE_DIR`
moves it, `JAXROCK_CACHE_DIR=off` switches it off), unless the process has chosen a cache folder
of its own.
"""

import importlib as _importlib
import importlib.util as _importlib_util
from typing import TYPE_CHECKING as _TYPE_CHECKING

from . import runtime as _runtime

_runtime.install()  # float64 and the compilation cache, when JAX is imported

# public name → the module that defines it (imported on first use)
_EXPORTS = {
    **dict.fromkeys(["G", "Block", "pulse_of_ratios", "ratios_of_pulse"], "geometry"),
    **dict.fromkeys(["AbstractExcitation", "RickerPulse", "AntisymmetricRickerPulse", "SinePulse", "Record", "StillGround", "WithVertical", "ricker_with_vertical"], "excitation"),
    "JaxrockInputError": "_validate",
    **dict.fromkeys(["Save", "Solution", "Status", "status_names", "status_codes"], "results"),
    **dict.fromkeys(["SUMMARY", "Output"], "outputs"),
    **dict.fromkeys(["AbstractIntegrator", "AbstractModel", "AbstractStepper", "AbstractSpringIntegrator", "Schedule", "simulate"],
                    "model"),
    **dict.fromkeys(["ModelKind", "Param", "register_model_kind", "register_pulse_kind", "DEFAULT_SMOOTHING", "DEFAULT_BACKBONE"], "scene"),
    **dict.fromkeys(["scene_of", "scene_model", "scene_pulse"], "construct"),
    **dict.fromkeys(["Sensitivity", "verdict_uncertain"], "sensitivity"),
    **dict.fromkeys(["EventIntegrator", "RigidModel", "RockingFrame"], "rigid"),
    **dict.fromkeys(["SpringModel", "AbstractSpringModel", "QuasiRigidSpringModel", "FlexibleSpringModel", "SpringSystem", "Column",
                     "SpringIntegrator", "GeneralizedAlpha", "Checked", "AbstractBackbone", "Bilinear", "Tanh", "cbar_eq17", "first_period_eq21", "pushover_eq9"], "spring"),
    **dict.fromkeys(["el_centro", "builtin_record", "read_at2", "read_record", "read_record_pair", "read_records", "read_two_column"], "io.records"),
    "read_scenes": "io.scenes_file",
    **dict.fromkeys(["record_measures", "suite_measures", "spectral_acceleration", "intensity_of"], "intensity"),
    **dict.fromkeys(["fit_lognormal", "fit_truncated_ida"], "analyses.fragility"),
    **dict.fromkeys(["HazardCurve", "mean_annual_frequency", "probability_in_years"], "analyses.hazard"),
    "risk_analysis": "analyses.risk",
    **dict.fromkeys(["identify", "Measured", "Identification", "eta_from_peaks"], "analyses.identify"),
    "run_suite": "analyses.suite",
    **dict.fromkeys(["Spectrum", "RecordSpectrum", "overturning_spectrum", "record_overturning_scale", "refine_boundaries", "run_batch",
                     "run_scenes", "energy_ratio", "energy_ratio_grid", "calibrate_cbar", "CalibrationResult", "fit_power_law",
                     "rm_target", "Sweep", "run_sweep", "least_overturning_scale", "overturning_probability", "Boundary", "find_boundary",
                     "boundary_slope"], "analyses"),
    "use_cpu_cores": "runtime",
    "calibration_report": "reports",  # writes figures: matplotlib is imported with it
}
__all__ = list(_EXPORTS)

if _TYPE_CHECKING:  # the same names, explicitly, for static tools (type checkers, IDEs); never run
    from .geometry import G as G, Block as Block, pulse_of_ratios as pulse_of_ratios, ratios_of_pulse as ratios_of_pulse
    from .excitation import (
        AbstractExcitation as AbstractExcitation, RickerPulse as RickerPulse,
        AntisymmetricRickerPulse as AntisymmetricRickerPulse, Record as Record, SinePulse as SinePulse, StillGround as StillGround,
        WithVertical as WithVertical, ricker_with_vertical as ricker_with_vertical,
    )
    from ._validate import JaxrockInputError as JaxrockInputError
    from .results import (
        Save as Save, Solution as Solution, Status as Status, status_names as status_names, status_codes as status_codes,
    )
    from .outputs import SUMMARY as SUMMARY, Output as Output
    from .model import (
        AbstractIntegrator as AbstractIntegrator, AbstractModel as AbstractModel, AbstractStepper as AbstractStepper,
        AbstractSpringIntegrator as AbstractSpringIntegrator, Schedule as Schedule, simulate as simulate,
    )
    from .scene import (
        ModelKind as ModelKind, Param as Param, register_model_kind as register_model_kind,
        register_pulse_kind as register_pulse_kind, DEFAULT_SMOOTHING as DEFAULT_SMOOTHING, DEFAULT_BACKBONE as DEFAULT_BACKBONE,
    )
    from .construct import scene_of as scene_of, scene_model as scene_model, scene_pulse as scene_pulse
    from .sensitivity import Sensitivity as Sensitivity, verdict_uncertain as verdict_uncertain
    from .rigid import EventIntegrator as EventIntegrator, RigidModel as RigidModel, RockingFrame as RockingFrame
    from .spring import (
        SpringModel as SpringModel, AbstractSpringModel as AbstractSpringModel, QuasiRigidSpringModel as QuasiRigidSpringModel,
        FlexibleSpringModel as FlexibleSpringModel, SpringSystem as SpringSystem, Column as Column, SpringIntegrator as SpringIntegrator,
        GeneralizedAlpha as GeneralizedAlpha, Checked as Checked, AbstractBackbone as AbstractBackbone, Bilinear as Bilinear,
        Tanh as Tanh, cbar_eq17 as cbar_eq17, first_period_eq21 as first_period_eq21, pushover_eq9 as pushover_eq9,
    )
    from .io.records import (
        el_centro as el_centro, builtin_record as builtin_record, read_at2 as read_at2, read_record as read_record,
        read_record_pair as read_record_pair, read_records as read_records, read_two_column as read_two_column,
    )
    from .io.scenes_file import read_scenes as read_scenes
    from .intensity import (
        record_measures as record_measures, suite_measures as suite_measures, spectral_acceleration as spectral_acceleration,
        intensity_of as intensity_of,
    )
    from .analyses.fragility import fit_lognormal as fit_lognormal, fit_truncated_ida as fit_truncated_ida
    from .analyses.hazard import (
        HazardCurve as HazardCurve, mean_annual_frequency as mean_annual_frequency, probability_in_years as probability_in_years,
    )
    from .analyses.risk import risk_analysis as risk_analysis
    from .analyses.identify import (
        identify as identify, Measured as Measured, Identification as Identification, eta_from_peaks as eta_from_peaks,
    )
    from .analyses.suite import run_suite as run_suite
    from .analyses import (
        Spectrum as Spectrum, RecordSpectrum as RecordSpectrum, overturning_spectrum as overturning_spectrum,
        record_overturning_scale as record_overturning_scale, refine_boundaries as refine_boundaries, run_batch as run_batch,
        run_scenes as run_scenes, energy_ratio as energy_ratio, energy_ratio_grid as energy_ratio_grid,
        calibrate_cbar as calibrate_cbar, CalibrationResult as CalibrationResult, fit_power_law as fit_power_law,
        rm_target as rm_target, Sweep as Sweep, run_sweep as run_sweep, least_overturning_scale as least_overturning_scale,
        overturning_probability as overturning_probability, Boundary as Boundary, find_boundary as find_boundary,
        boundary_slope as boundary_slope,
    )
    from .runtime import use_cpu_cores as use_cpu_cores
    from .reports import calibration_report as calibration_report


def __getattr__(name):
    if name == "__version__":  # from git tags at install time (`jaxrock.cache.package_version`)
        from .cache import package_version

        return package_version()
    if name in _EXPORTS:
        value = getattr(_importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    elif _importlib_util.find_spec(f"{__name__}.{name}") is not None:  # a submodule: jaxrock.scene, jaxrock.cli, ...
        value = _importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'jaxrock' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *__all__})
