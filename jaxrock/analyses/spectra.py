"""Overturning spectra: max |θ|/α′ over a grid of (ω_p/p′, a_p/(g tanα′)), by `vmap`.

In these coordinates the rigid spectrum depends on α′ only (SPEC "Spectra"). The grid is a sweep
(`jaxrock.analyses.sweep`) of one model over a_p/(g tanα′) × ω_p/p′, run in batches of `batch_size`
cells (memory stays bounded) by the batch engine (`jaxrock.analyses.engine`: the model's stepper,
the running cells gathered between passes). A `checkpoint` store keeps finished batches: an
interrupted run resumes where it stopped.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import interrupt
from .._validate import JaxrockInputError, check_grid
from ..excitation import Record
from ..io import cf, provenance
from ..io.files import write_output
from ..model import AbstractIntegrator, AbstractModel
from ..results import OUTPUTS, STATUS_NAMES, SUMMARY, schema_module
from ..construct import scene_pulse
from ..scene import AXES, DEFAULT_PULSE, pulse_class
from ..sensitivity import forward_integrator
from .engine import batch_limit, even_batches, make_stepper, run_batch
from .suite import least_overturning_scale
from .sweep import Sweep, run_sweep


class _AbstractSpectrum(eqx.Module):
    """`Spectrum`'s methods (its fields come from `jaxrock.results.SUMMARY`)."""

    @property
    def ok(self) -> bool:
        return bool(np.all(self.status == 0))

    def _least(self, mask: np.ndarray) -> np.ndarray:
        has = mask.any(axis=0)
        first = np.argmax(mask, axis=0)
        return np.where(has, self.accel_ratio[first], np.nan)

    def contradictions(self) -> np.ndarray:
        """Cells whose result contradicts its own flags (none, in a correct run): max_theta at the
        threshold without overturning, overturned with another max_theta, or overturned without
        uplifting. Failed cells (status ≠ ok) are not judged."""
        threshold = float(self.attrs.get("threshold", 1.0))
        over = self.overturned
        bad = ((self.max_theta >= threshold) & ~over) | (over & (self.max_theta != threshold)) | (over & ~self.uplifted)
        return bad & (self.status == 0)

    @property
    def uplift_boundary(self) -> np.ndarray:
        """Least a_p/(g tanα′) that uplifts, per ω_p/p′ column: refined if `uplift_line` is there,
        else the least grid row (NaN: none in the grid)."""
        return self._least(self.uplifted) if self.uplift_line is None else self.uplift_line

    @property
    def overturn_boundary(self) -> np.ndarray:
        """Least a_p/(g tanα′) that overturns, per ω_p/p′ column: refined if `overturn_line` is
        there, else the least grid row (NaN: none in the grid)."""
        return self._least(self.overturned) if self.overturn_line is None else self.overturn_line

    def to_xarray(self):
        import xarray as xr

        dims = ("accel_ratio", "omega_ratio")
        ds = xr.Dataset(
            {
                **{o.name: cf.output_variable(o, getattr(self, o.name), dims) for o in SUMMARY},
                "status": (dims, self.status.astype(np.int32), cf.flags("jaxrock.Status code", STATUS_NAMES, np.int32)),
                "uplift_boundary": (("omega_ratio",), self.uplift_boundary, {"long_name": "least a_p/(g tan alpha) that uplifts", "units": "1"}),
                "overturn_boundary": (("omega_ratio",), self.overturn_boundary, {"long_name": "least a_p/(g tan alpha) that overturns", "units": "1"}),
            },
            coords={
                **{k: (k, getattr(self, k), {"long_name": AXES[k], "units": "1"}) for k in ("omega_ratio", "accel_ratio")},
            },
            attrs={**self.attrs, "refined": int(self.uplift_line is not None)},
        )
        return cf.encode(ds, self.attrs.get("title") or f"jaxrock overturning spectrum: {self.attrs.get('model', 'model')}, "
                         f"{self.attrs.get('pulse', 'pulse')}")

    def save(self, path) -> Path:
        """Write the spectrum to a netCDF file (readable by xarray, netCDF tools and `Spectrum.load`).

        Arguments:
            path (str | os.PathLike): the file; its folder is made if missing.

        Returns:
            The path written.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        ds = self.to_xarray()
        return write_output(path, lambda tmp: cf.write_netcdf(ds, tmp))

    @classmethod
    def load(cls, path) -> "Spectrum":
        """Read a spectrum written by `save`.

        Arguments:
            path (str | os.PathLike): the netCDF file.

        Returns:
            The `Spectrum`.

        Raises:
            JaxrockInputError: when the file lacks one of today's summary outputs or `status`
                (written by an older jaxrock), naming what it lacks.
        """
        import xarray as xr

        with xr.open_dataset(path, engine="scipy") as ds:
            missing = [name for name in (*OUTPUTS, "status") if name not in ds]
            if missing:
                raise JaxrockInputError(f"{path}: no variable(s) {', '.join(missing)} (written by jaxrock "
                                        f"{ds.attrs.get('jaxrock_version', 'of another version')}); rerun the spectrum")
            refined = bool(ds.attrs.get("refined"))
            status = ds["status"].values.astype(np.int32)
            valid = status != STATUS_NAMES.index("invalid_input")

            def values(name, o):  # a time's fill value: never, where the scene is valid (`jaxrock.io.cf.output_variable`)
                v = ds[name].values.astype(o.dtype)
                return np.where(np.isnan(v) & valid, np.inf, v) if o.units == "s" else v

            return cls(
                omega_ratio=ds["omega_ratio"].values.copy(),
                accel_ratio=ds["accel_ratio"].values.copy(),
                **{name: values(name, o) for name, o in OUTPUTS.items()},
                status=status,
                attrs={k: v for k, v in cf.decode_attrs(ds).items() if k not in ("refined", "references")},
                uplift_line=ds["uplift_boundary"].values.copy() if refined else None,
                overturn_line=ds["overturn_boundary"].values.copy() if refined else None,
            )


Spectrum = schema_module(
    "Spectrum", _AbstractSpectrum,
    """A labelled overturning spectrum.

    `max_theta[i, j]` is max |θ|/α′ at `accel_ratio[i]` = a_p/(g tanα′) and `omega_ratio[j]` =
    ω_p/p′ (the threshold value, 1 by default, where the body overturns); every summary output
    (`jaxrock.results.SUMMARY`) is an array of the grid's shape, and `status` holds the cells'
    status codes (`jaxrock.results.STATUS_NAMES`). `attrs` describes the scene (model, α′, p′,
    pulse, ...). `uplift_line` and `overturn_line`, when present, are the boundaries refined by
    bisection between grid rows (`refine_boundaries`).
    """,
    {"omega_ratio": np.ndarray, "accel_ratio": np.ndarray, **{name: np.ndarray for name in OUTPUTS}, "status": np.ndarray,
     "attrs": dict, "uplift_line": np.ndarray | None, "overturn_line": np.ndarray | None},
    {"uplift_line": None, "overturn_line": None},
    __name__,
)
"""A labelled overturning spectrum: every summary output over a grid of pulse ratios.

An `eqx.Module` whose output fields are generated from the summary outputs
(`jaxrock.results.SUMMARY`), each an array of the grid's shape (len(accel_ratio), len(omega_ratio)).
`max_theta[i, j]` is max |θ|/α′ at `accel_ratio[i]` = a_p/(g tanα′) and `omega_ratio[j]` = ω_p/p′ (the
threshold value, 1 by default, where the body overturns). Made by `overturning_spectrum`, written by
`Spectrum.save` and read back by `Spectrum.load`; `spec.ok` says whether every cell's status is ok,
`uplift_boundary` and `overturn_boundary` give the least a_p/(g tanα′) that uplifts (overturns) per
ω_p/p′ column, `contradictions()` the cells whose result contradicts its own flags, `to_xarray()`
the spectrum as an `xarray.Dataset`.

Attributes:
    omega_ratio: the grid's ω_p/p′ values [–], 1-D.
    accel_ratio: the grid's a_p/(g tanα′) values [–], 1-D.
    max_theta: max |θ|/α′ per cell [–] (the threshold where the body overturns).
    overturned: whether the cell's body overturned.
    t_overturn: time of overturning [s] (+inf: did not overturn).
    uplifted: whether the cell's body left its rest state.
    t_uplift: first time |θ| passed the uplift rotation [s] (+inf: never).
    n_impacts: impacts at θ = 0 (the rigid model's; 0 for spring models).
    sensitivity: max |∂θ/∂ln(scale)|/α′ [–] (`jaxrock.sensitivity`; NaN: not computed).
    uncertain: whether the cell's overturning verdict is uncertain (False where not computed).
    status: the cells' status codes (`jaxrock.results.STATUS_NAMES`; 0: ok).
    attrs: what describes the scene (model, α′, p′, pulse, ...), written into the file.
    uplift_line: the uplift boundary refined by bisection between grid rows (`refine_boundaries`),
        per ω_p/p′ column; None: not refined.
    overturn_line: the overturning boundary refined likewise; None: not refined.

Example:
    ```python
    import numpy as np, jaxrock
    model = jaxrock.RigidModel(jaxrock.Block.from_slenderness(10.0, 0.2))
    spec = jaxrock.overturning_spectrum(model, np.linspace(1, 10, 32), np.linspace(1, 8, 32))
    spec.save("spectrum.nc")
    again = jaxrock.Spectrum.load("spectrum.nc")
    ```
"""


def overturning_spectrum(
    model: AbstractModel,
    omega_ratio,
    accel_ratio,
    *,
    pulse=DEFAULT_PULSE,
    pulse_params: dict | None = None,
    integrator: AbstractIntegrator | None = None,
    batch_size: int = 4096,
    progress: bool = True,
    checkpoint: str | os.PathLike | None = None,
    keep_checkpoint: bool = False,
    refine: int = 0,
    sensitivity: bool = False,
) -> Spectrum:
    """The overturning spectrum of `model`: max |θ|/α′ over a grid of pulse ratios.

    The grid is `accel_ratio` (a_p/(g tanα′)) × `omega_ratio` (ω_p/p′), in which the rigid spectrum
    depends on α′ only (SPEC "Spectra"). It is run as a sweep (`jaxrock.analyses.sweep`) in batches
    of about the size the batch engine's passes share (`engine.even_batches`), whole rows of
    ω_p/p′. A `checkpoint` store records what made it (`jaxrock.io.provenance`).

    Arguments:
        model: the model (its `block` sets α′, p′).
        omega_ratio (ArrayLike): ω_p/p′ values [–], non-empty, > 0, strictly increasing.
        accel_ratio (ArrayLike): a_p/(g tanα′) values [–], non-empty, > 0, strictly increasing.
        pulse (str | type): a pulse kind's name (`jaxrock.scene.PULSES`: "symmetric" Ricker,
            "antisymmetric" eq. 29, "sine" of N cycles) or a pulse class; default `DEFAULT_PULSE`
            ("symmetric").
        pulse_params: the pulse's parameters beyond a_p and ω_p (`jaxrock.scene.PULSE_PARAMS`, e.g.
            {"n_cycles": 2}); default None: their defaults.
        integrator: the integrator; default None: the model's `default_integrator()`.
        batch_size: the most cells run together in one vmapped batch (memory bound), ≥ 1; default 4096.
        progress: show a progress bar; default True.
        checkpoint: the sweep's Zarr store (`jaxrock.io.store`); each finished batch is written into it
            as its own chunk, and rerunning the same call after an interruption resumes from it.
            Default None: no checkpoint.
        keep_checkpoint: keep the checkpoint once the spectrum (with its refinement) is complete;
            default False: it is removed (the caller that keeps it removes it once the result is
            saved: the CLI does).
        refine: bisections of the uplift and overturning lines between grid rows (`refine_boundaries`);
            default 0: grid lines.
        sensitivity: every cell carries its tangent and reports its `sensitivity` and whether its
            verdict is `uncertain` (`jaxrock.sensitivity`); default False: those read "not computed" / no.

    Returns:
        The `Spectrum`.

    Raises:
        JaxrockInputError: when a grid is empty, not > 0 or not strictly increasing, `batch_size` < 1,
            the pulse is unknown, or the checkpoint is of another run (model, parameters, pulse, grid,
            integrator, version), unreadable, or being written by another run (`<checkpoint>.lock`).

    Example:
        ```python
        import numpy as np, jaxrock
        model = jaxrock.RigidModel(jaxrock.Block.from_slenderness(10.0, 0.2))
        spec = jaxrock.overturning_spectrum(model, np.linspace(1, 10, 64), np.linspace(1, 8, 64),
                                            pulse="antisymmetric", refine=8, checkpoint="spec.zarr")
        spec.overturn_boundary  # least a_p/(g tanα′) that overturns, per ω_p/p′
        ```
    """
    wr = check_grid("omega_ratio (omega_p/p)", omega_ratio)
    ar = check_grid("accel_ratio (a_p/(g tan alpha))", accel_ratio)
    if int(batch_size) < 1:
        raise JaxrockInputError(f"batch_size = {batch_size}; valid: an integer >= 1")
    cls = pulse_class(pulse)
    ck = Path(checkpoint) if checkpoint is not None else None
    n = wr.size * ar.size
    if sensitivity:
        integ = forward_integrator(model, integrator)
    else:
        integ = model.default_integrator() if integrator is None else integrator
    stepper = make_stepper(model, integ, False, sensitivity)  # compiled once, reused by run_batch (the same call)
    chunk = even_batches(n, min(int(batch_size), batch_limit(stepper)), stepper.schedule.batch_unit)
    pp = dict(pulse_params or {})
    sweep = Sweep.make(model, pulse=cls, accel_ratio=ar, omega_ratio=wr, integrator=integrator, chunk_size=chunk,
                       sensitivity=sensitivity, **pp)
    ds = run_sweep(sweep, ck, progress=progress)
    block = model.block
    attrs = {
        "model": type(model).__name__,
        "pulse": cls.__name__,
        **{k: float(v) for k, v in sweep.fixed.items() if k in pp},
        "threshold": float(model.threshold),
        "tan_alpha": cf.input_value(jnp.tan(block.alpha_r)),
        "alpha": float(block.alpha_r),
        "p": float(block.p_r),
        "height": cf.input_value(block.height),
        "width": cf.input_value(block.width),
        **provenance.file_attrs(model, integrator),
        "made_by": ds.attrs["made_by"],
    }
    spec = Spectrum(omega_ratio=wr, accel_ratio=ar, **{k: ds[k].values for k in (*OUTPUTS, "status")}, attrs=attrs)
    if int(refine) > 0:
        spec = refine_boundaries(model, spec, pulse=pulse, pulse_params=pp, iterations=int(refine), integrator=integrator)
    if ck is not None and ck.exists() and not keep_checkpoint:
        shutil.rmtree(ck)
    return spec


def refine_boundaries(
    model: AbstractModel,
    spectrum: Spectrum,
    *,
    pulse=DEFAULT_PULSE,
    pulse_params: dict | None = None,
    iterations: int = 12,
    integrator: AbstractIntegrator | None = None,
) -> Spectrum:
    """The spectrum with its uplift and overturning lines refined by bisection.

    In each ω_p/p′ column the bracket is the first grid row that uplifts (overturns) and the row
    below it; `iterations` bisections of a_p, all columns in one vmapped batch per step, shrink
    it by 2^-iterations. A column whose first grid row already uplifts (overturns) keeps the grid
    value; one with none stays NaN. Overturning is not monotone in a_p: the line found is the
    least a_p within the bracket, not below it.

    Arguments:
        model: the model the spectrum was run with.
        spectrum (Spectrum): the spectrum (`overturning_spectrum`).
        pulse (str | type): the pulse kind's name or class, as `overturning_spectrum`'s; default
            `DEFAULT_PULSE` ("symmetric").
        pulse_params: the pulse's parameters beyond a_p and ω_p; default None: their defaults.
        iterations: bisections per line; default 12.
        integrator: the integrator; default None: the model's `default_integrator()`.

    Returns:
        The spectrum with `uplift_line` and `overturn_line` set.

    Example:
        ```python
        spec = jaxrock.refine_boundaries(model, spec, iterations=10)
        ```
    """
    cls = pulse_class(pulse)
    pp = dict(pulse_params or {})
    ar, wr = spectrum.accel_ratio, spectrum.omega_ratio
    lines = []
    for mask, flag in ((spectrum.uplifted, "uplifted"), (spectrum.overturned, "overturned")):
        first = np.argmax(mask, axis=0)
        has = mask.any(axis=0)
        line = np.where(has, ar[first], np.nan)
        todo = has & (first > 0)
        lo = np.where(todo, ar[np.maximum(first - 1, 0)], 0.0)
        hi = line.copy()
        if todo.any():
            for _ in range(int(iterations)):
                interrupt.stop_point()
                mid = np.where(todo, 0.5 * (lo + hi), ar[0])
                exc = jax.vmap(lambda a, w: scene_pulse(cls, model.block, {"accel_ratio": a, "omega_ratio": w, **pp}))(
                    jnp.asarray(mid), jnp.asarray(wr))
                yes = np.asarray(getattr(run_batch(model, exc, integrator), flag))
                hi = np.where(todo & yes, mid, hi)
                lo = np.where(todo & ~yes, mid, lo)
            line = np.where(todo, hi, line)
        lines.append(line)
    return eqx.tree_at(lambda s: (s.uplift_line, s.overturn_line), spectrum, tuple(lines), is_leaf=lambda x: x is None)


# -- record spectra (paper figure 10) ---------------------------------------------------------------
class RecordSpectrum(eqx.Module):
    """Least scale factor of a record that overturns a body, per body height (paper figure 10).

    Made by `record_overturning_scale`; `save` writes it to a netCDF file.

    Attributes:
        height: the bodies' full heights 2h [m], 1-D.
        scale: the least factor of the sweep (refined by bisection) that overturns the body of height
            `height[i]` [–]; +inf where no factor of the sweep overturns it.
        bracket_low: the largest factor below it that does not overturn [–].
        attrs: what describes the run (model, record, tanα, tanα′, integrator, ...).
        uncertain: per height, whether a run that decided it has an uncertain verdict
            (`jaxrock.sensitivity`); default None: not computed.
        worst_status: per height, the largest `jaxrock.Status` code of its runs (0: all ok); default
            None: not known.
    """

    height: np.ndarray
    scale: np.ndarray
    bracket_low: np.ndarray
    attrs: dict
    uncertain: np.ndarray | None = None
    worst_status: np.ndarray | None = None

    def save(self, path) -> Path:
        """Write the record spectrum to a netCDF file (readable by xarray and netCDF tools).

        Arguments:
            path (str | os.PathLike): the file; its folder is made if missing.

        Returns:
            The path written.
        """
        import xarray as xr

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        ds = xr.Dataset(
            {
                "scale": (("height",), *cf.encode_never(self.scale, {"long_name": "least overturning scale factor", "units": "1"},
                                                       "no factor of the sweep overturns")),
                "bracket_low": (("height",), self.bracket_low, {"long_name": "largest scale below it that does not overturn", "units": "1"}),
                **({} if self.uncertain is None else {"uncertain": (("height",), np.asarray(self.uncertain, np.int8), cf.flags(
                    "a run that decided the least scale has an uncertain verdict (jaxrock.sensitivity)", ("certain", "uncertain")))}),
                **({} if self.worst_status is None else {"worst_status": (("height",), np.asarray(self.worst_status, np.int32), {
                    "long_name": "largest jaxrock.Status code of the height's runs (0: all ok)"})}),
            },
            coords={"height": ("height", self.height, {"long_name": "2h", "units": "m"})},
            attrs=self.attrs,
        )
        ds = cf.encode(ds, self.attrs.get("title") or f"jaxrock least overturning scale factor: {self.attrs.get('record', 'record')}, "
                       f"{self.attrs.get('model', 'model')}")
        return write_output(path, lambda tmp: cf.write_netcdf(ds, tmp))


def record_overturning_scale(
    model: AbstractModel,
    record: Record,
    heights,
    scales,
    *,
    refine: int = 12,
    integrator: AbstractIntegrator | None = None,
    progress: bool = True,
    sensitivity: bool = False,
) -> RecordSpectrum:
    """Least factor of `record` that overturns `model`'s body, for each height in `heights`.

    The body keeps the template's slenderness (and base slenderness); only its size changes.
    A suite of one record (`jaxrock.analyses.suite.least_overturning_scale`): the factor sweep
    `scales` run vmapped for each height, the first overturning factor then refined by `refine`
    bisections (all heights in one vmapped batch) against the factor before it.
    Overturning is not monotone in the factor: an overturning window narrower than the sweep's
    step, below the first overturning factor found, is missed — refine the sweep to rule it out.

    Arguments:
        model: the template model (its slenderness and base slenderness are kept).
        record: the ground-motion record (`Record`).
        heights (ArrayLike): full heights 2h [m], non-empty, > 0, strictly increasing.
        scales (ArrayLike): the factor sweep [–], non-empty, > 0, strictly increasing.
        refine: bisections of the first overturning factor; default 12.
        integrator: the integrator; default None: the model's `default_integrator()`.
        progress: show a progress bar; default True.
        sensitivity: every run judges its verdict, and `uncertain` says which least factors an
            uncertain run decided (`jaxrock.sensitivity`); default False.

    Returns:
        The least factor per height (`RecordSpectrum`).

    Raises:
        JaxrockInputError: when a grid is empty, not > 0 or not strictly increasing, or `record` is
            not a `Record`.

    Example:
        ```python
        import numpy as np, jaxrock
        model = jaxrock.RigidModel(jaxrock.Block.from_slenderness(10.0, 0.2))
        rs = jaxrock.record_overturning_scale(model, jaxrock.el_centro(), [5.0, 10.0, 20.0], np.linspace(0.5, 8, 16))
        rs.scale  # least overturning factor per height
        ```
    """
    hs = check_grid("heights (2h) [m]", heights)
    sc = check_grid("scales (record factors)", scales)
    if not isinstance(record, Record):
        raise JaxrockInputError(f"record must be a jaxrock.Record, got {type(record).__name__}")
    block = model.block
    tan_a, tan_b = block.tan_alpha, block.b_base / block.h
    # a suite of one record: the model resized to each height, one chunk (one vmapped batch) per height
    sweep = Sweep.make(model, records=[record], height=hs, scale=sc, integrator=integrator, chunk_size=sc.size, sensitivity=sensitivity)
    ds = least_overturning_scale(sweep, refine=refine, progress=progress)
    least, low = ds.least_scale.values[0], ds.bracket_low.values[0]
    attrs = {"model": type(model).__name__, "record": record.name, "tan_alpha": cf.input_value(tan_a), "tan_alpha_base": cf.input_value(tan_b),
             **provenance.file_attrs(model, integrator)}
    return RecordSpectrum(height=hs, scale=least, bracket_low=low, attrs=attrs,
                          uncertain=ds.least_scale_uncertain.values[0] if sensitivity else None,
                          worst_status=ds.worst_status.values[0])
