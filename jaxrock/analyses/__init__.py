"""Analyses: many runs of a model, computed and returned as values (no files but checkpoints).

- `engine`: the batch engine — summaries of a batch of scenes through the models' steppers;
- `spectra`: overturning spectra of pulses (`overturning_spectrum`, `refine_boundaries`) and the
  least overturning scale of a record (`record_overturning_scale`);
- `free_rocking`: the spring model's energy ratio per free-rocking cycle (figure 7);
- `calibration`: the damper c̄ calibrated by gradient against the rigid model's energy loss (eq. 17);
- `scenes`: a scenes file run row by row, vmapped by structure (`run_scenes`);
- `sweep`: every scene of a product of axes, chunk by chunk into a Zarr store, on local devices or a
  Dask cluster (`Sweep`, `run_sweep`);
- `boundary`: overturning boundaries by gradient — Newton on the margin (1 − max|θ|/α′)² along a
  parameter (`find_boundary`), and a boundary's implicit derivative (`boundary_slope`);
- `suite`: the least overturning scale of every record of a suite for every column, by vmapped
  bisection (`least_overturning_scale`); an uncertain verdict's probability from an ensemble of
  perturbed runs (`overturning_probability`).
"""

from .boundary import Boundary, boundary_slope, find_boundary, margin
from .calibration import CalibrationResult, calibrate_cbar, fit_power_law
from .free_rocking import energy_ratio, energy_ratio_grid, rm_target
from .engine import run_batch
from .scenes import run_scenes
from .suite import least_overturning_scale, overturning_probability
from .sweep import Sweep, run_sweep
from .spectra import RecordSpectrum, Spectrum, overturning_spectrum, record_overturning_scale, refine_boundaries

__all__ = ["run_batch", "Spectrum", "RecordSpectrum", "overturning_spectrum", "record_overturning_scale", "refine_boundaries",
           "run_scenes", "CalibrationResult", "calibrate_cbar", "energy_ratio", "energy_ratio_grid", "fit_power_law", "rm_target", "Sweep", "run_sweep",
           "least_overturning_scale", "overturning_probability", "Boundary", "find_boundary", "boundary_slope", "margin"]
