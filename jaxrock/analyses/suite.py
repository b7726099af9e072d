"""Record suites: the least overturning scale factor of every record for every column (the paper's
figure 10, for a suite), refined by a vmapped bisection.

`least_overturning_scale` runs a record sweep (`jaxrock.analyses.sweep`: records × the column's
quantities × a `scale` axis, resumable in a store), takes in each cell (record, size, slenderness,
...) the first factor of the sweep that overturns the column, and bisects between it and the factor
before it (0 below the first): each round runs every cell of a record in one vmapped batch (models
per scene), so a suite costs `refine` batches per record after its sweep (records grouped into
batches of at least `BISECTION_CELLS` cells, the groups one per local device at a time, as a
sweep's chunks). The bracket [low, least] is reported with its width.

Overturning is not monotone in the factor (a rocking column that overturns at s may survive a
larger one): the least factor found is the least within its bracket; an overturning window
narrower than the sweep's step below it is missed, and where the bracket holds several windows
the bisection ends at one of their edges. `windows` counts, per cell, the sweep's turns from
overturned back to standing: 0 where the sweep saw a monotone outcome. On records it is seldom 0:
22 of 24 cells (3 records × 4 sizes × 2 slendernesses, RM) turned at least once in a sweep of step
0.025 — the least factor of a record is a property of the sweep's resolution; the fragility
(`jaxrock.analyses.fragility`) uses every outcome of the sweep instead.
"""

from __future__ import annotations

import numpy as np

from .._validate import JaxrockInputError, check_grid
from ..outputs import PERTURBATION
from ..scene import MAX_ENSEMBLE, MAX_REFINE
from .sweep import Sweep, on_devices, run_sweep, run_values

BISECTION_CELLS = 256  # the least batch of a bisection round (records grouped to reach it)


def least_overturning_scale(sweep: Sweep, store=None, *, refine: int = 8, progress: bool = True, devices=None,
                            history: str | None = None):
    """The least overturning factor of each record for each column of the record sweep `sweep`
    (`Sweep.make(..., records=..., scale=[...])`, `scale` an axis), as an `xarray.Dataset`:

    - the sweep's outputs (`overturned`, `max_theta`, ..., `status`) over all its axes;
    - over its axes without `scale`: `least_scale` (+inf where no factor of the sweep overturns),
      `bracket_low` (the largest factor known not to overturn below it; NaN where none
      overturns), `bracket_width` = least_scale − bracket_low (after `refine` bisections: the
      sweep's step / 2^refine), and `worst_status`, the largest status code of the cell's runs
      (sweep and bisection: 0 = every run ok), `windows` (module docstring), and
      `least_scale_uncertain`: whether a run that decided the least factor has an uncertain
      verdict (`jaxrock.sensitivity`; computed by a sweep made with `sensitivity=True`).

    With a store, each record's finished bisection is kept beside it (`<store>.bisection.npz`,
    written atomically, with the store's description and `refine`): an interrupted run resumes both.

    Arguments:
        sweep: a record sweep with a `scale` axis.
        store (str | os.PathLike | None): a Zarr store folder, as `run_sweep`'s; default None.
        refine: bisections of each least factor, an integer in [0, `MAX_REFINE`]; default 8.
        progress: show a progress bar; default True.
        devices (Sequence[jax.Device] | None): as `run_sweep`'s; default None: every local device.
        history: the command, for the attributes of a new store; default None.

    Returns:
        (xarray.Dataset): the sweep's outputs and the least factors described above.

    Raises:
        JaxrockInputError: when `sweep` is not a record sweep with a `scale` axis, `refine` is out of
            range, a record has no ground motion, or the store is another sweep's.

    Example:
        ```python
        import jaxrock
        sweep = jaxrock.Sweep.make("rigid", records=jaxrock.read_records("builtin"), height=[5.0, 10.0],
                                   tan_alpha=0.2, scale=[0.5, 1.0, 2.0, 4.0])
        ds = jaxrock.least_overturning_scale(sweep, refine=8)
        ds.least_scale  # per record and height
        ```
    """
    from tqdm.auto import tqdm

    from .. import interrupt

    if not sweep.records or "scale" not in sweep.axes:
        raise JaxrockInputError("least_overturning_scale needs a record sweep with a scale axis: Sweep.make(..., records=[...], scale=[...])")
    if not 0 <= int(refine) <= MAX_REFINE:
        raise JaxrockInputError(f"refine = {refine}; valid: an integer in [0, {MAX_REFINE}] (each bisection halves the bracket)")
    check_grid("scale (record factors)", sweep.axes["scale"])  # the least factor is the first of them that overturns
    assert sweep.dims[0] == "record" and sweep.dims[-1] == "scale"  # axis_order(): records outermost, scale innermost
    ds = run_sweep(sweep, store, progress=progress, devices=devices, history=history).drop_vars("chunk_done")
    sc = sweep.axes["scale"]
    over, status = ds.overturned.values, ds.status.values  # (record, *cells, scale)
    has = over.any(axis=-1)
    k = np.argmax(over, axis=-1)
    hi = np.where(has, sc[k], np.inf)
    lo = np.where(has, np.where(k > 0, sc[np.maximum(k - 1, 0)], 0.0), np.nan)
    worst = status.max(axis=-1)
    # the least factor is uncertain where a run that decided it is: a factor of the sweep up to it
    # (every factor where none overturns) or a bisection's
    uncertain = (ds.uncertain.values & (sc <= hi[..., None])).any(axis=-1)
    cell_dims = sweep.dims[1:-1]
    cells = sweep.values_at(tuple(slice(0, len(sweep.axes[d])) for d in cell_dims), cell_dims)  # every column, C order
    found = {"hi": hi, "lo": lo, "worst": worst, "uncertain": uncertain}
    kept = _Bisections(store, ds.attrs["made_by"], int(refine), **found)
    groups = _groups([r for r in range(len(sweep.records)) if has[r].any() and not kept.done[r]], has)

    def bisect(group, devs):
        todo = has[group].reshape(len(group), -1)
        h, l, w, u = (a[group].reshape(len(group), -1).copy() for a in found.values())
        v = {name: np.broadcast_to(x.ravel(), todo.shape)[todo] for name, x in cells.items()}
        v["record"] = np.broadcast_to(np.asarray(group)[:, None], todo.shape)[todo]
        for _ in range(int(refine)):
            interrupt.stop_point()
            mid = 0.5 * (l[todo] + h[todo])
            out = run_values(sweep, v | {"scale": mid}, devs)
            yes = out["overturned"].astype(bool)
            h[todo] = np.where(yes, mid, h[todo])
            l[todo] = np.where(yes, l[todo], mid)
            w[todo] = np.maximum(w[todo], out["status"])
            u[todo] = u[todo] | out["uncertain"].astype(bool)
            bar.update()
        return h, l, w, u

    def done(group, results):
        for i, r in enumerate(group):
            for a, x in zip(found.values(), results):
                a[r] = x[i].reshape(a[r].shape)
            kept.finished(r)

    with tqdm(total=len(groups) * int(refine), desc="bisection", unit="batch", disable=not progress) as bar:
        on_devices(bisect, groups, devices, done)
    dims = sweep.dims[:-1]
    ds["least_scale"] = (dims, hi, {"long_name": "least scale factor that overturns (inf: none of the sweep)", "units": "1"})
    ds["bracket_low"] = (dims, lo, {"long_name": "largest scale factor below least_scale known not to overturn", "units": "1"})
    ds["bracket_width"] = (dims, hi - lo, {"long_name": "least_scale - bracket_low", "units": "1"})
    ds["windows"] = (dims, (over[..., :-1] & ~over[..., 1:]).sum(-1).astype(np.int32),
                     {"long_name": "times the sweep's outcome turns from overturned to not as the factor grows (0: monotone)"})
    ds["worst_status"] = (dims, worst.astype(np.int32), {"long_name": "largest jaxrock.Status code of the cell's runs (0: all ok)"})
    ds["least_scale_uncertain"] = (dims, uncertain, {
        "long_name": "a run that decided least_scale (a factor of the sweep up to it, every factor where none overturns, or a "
                     "bisection's) has an uncertain verdict (jaxrock.sensitivity; never where the sweep computes no sensitivity)",
        "units": "1"})
    ds.attrs["refine"] = int(refine)
    return ds


def _groups(records: list[int], has) -> list[list[int]]:
    """The records bisected together (a group's rounds are one batch each), in groups of at least
    BISECTION_CELLS cells: a batch's lanes move in lockstep, and a record's few cells alone would
    leave most of each loop step's work undone."""
    groups, group = [], []
    for r in records:
        group.append(r)
        if len(group) * has[r].size >= BISECTION_CELLS:
            groups, group = groups + [group], []
    return groups + ([group] if group else [])


class _Bisections:
    """The bisections finished so far, kept beside the sweep's store (`<store>.bisection.npz`):
    loaded into `arrays` (name → an array over records, in place) when made by the same sweep and
    `refine`."""

    def __init__(self, store, made_by: str, refine: int, **arrays):
        from pathlib import Path

        self.path = None if store is None else Path(f"{store}.bisection.npz")
        self.key, self.arrays = np.array(f"{made_by}\nrefine={refine}"), arrays
        first = next(iter(arrays.values()))
        self.done = np.zeros(first.shape[0], dtype=bool)
        if self.path is not None and self.path.is_file():
            try:
                with np.load(self.path) as f:
                    if str(f["key"]) == str(self.key) and all(f[k].shape == a.shape for k, a in arrays.items()):
                        done = f["done"].copy()
                        for name, a in arrays.items():
                            a[done] = f[name][done]
                        self.done = done
            except Exception:  # unreadable (a crash while writing cannot leave one: it is renamed whole): run again
                self.done[:] = False

    def finished(self, r: int) -> None:
        self.done[r] = True
        if self.path is not None:
            from ..io.files import write_atomically

            def write(tmp):
                with open(tmp, "wb") as fh:
                    np.savez(fh, key=self.key, done=self.done, **self.arrays)

            write_atomically(self.path, write)


def overturning_probability(sweep: Sweep, ds, n: int, devices=None) -> np.ndarray:
    """The probability that each run of the record sweep `sweep` overturns (over `sweep.dims`):
    its verdict (0 or 1) where certain; where `ds.uncertain` (the sweep's dataset, made with
    `sensitivity=True`), the fraction of an ensemble of `n` runs at the scale × (1 + δ t), t
    equally spaced in [−1, 1] and δ = `PERTURBATION` (the perturbation the flag answers for),
    that overturn: one batch of vmapped lanes for every uncertain run.

    Arguments:
        sweep: the record sweep, made with `sensitivity=True`.
        ds (xarray.Dataset): the sweep's dataset (`run_sweep` or `least_overturning_scale`).
        n: runs in each uncertain run's ensemble; < 1: the verdicts as they are.
        devices (Sequence[jax.Device] | None): default None: every local device.

    Returns:
        The probabilities in [0, 1], an array over `sweep.dims`.

    Example:
        ```python
        p = jaxrock.overturning_probability(sweep, ds, n=16)
        ```
    """
    import dataclasses

    over = ds.overturned.transpose(*sweep.dims).values.astype(float)
    idx = np.flatnonzero(ds.uncertain.transpose(*sweep.dims).values)
    if idx.size == 0 or int(n) < 1:
        return over
    every = sweep.values_at(tuple(slice(0, len(sweep.axes[d])) for d in sweep.dims))
    v = {k: np.repeat(a[idx], int(n)) for k, a in every.items()}
    v["scale"] = v["scale"] * (1.0 + PERTURBATION * np.tile(np.linspace(-1.0, 1.0, int(n)), idx.size))
    out = run_values(dataclasses.replace(sweep, sensitivity=False), v, devices)
    p = over.ravel()
    p[idx] = out["overturned"].reshape(idx.size, int(n)).mean(axis=1)
    return p.reshape(over.shape)


def _check_im(im: str) -> None:
    """`im` is "scale" or a measure `jaxrock.intensity.parse_im` takes that grows with the factor."""
    from ..intensity import parse_im

    if im != "scale" and parse_im(im)[2] == 0:
        raise JaxrockInputError(f"im = {im!r}: does not scale with the record; a fragility needs a measure that grows with the factor")


def suite_fragility(ds, measures, im: str = "pga", *, records=None, n_boot: int | None = None, seed: int = 0):
    """The lognormal fragility (`jaxrock.analyses.fragility.fit_lognormal`) of each column of a
    suite's sweep `ds` (`least_overturning_scale`'s dataset), against the intensity `im`: a
    measure of `jaxrock.intensity.SCALING` ("pga", "pgv", "pgd", "arias", ...; of the scaled record:
    factor^power × the record's measure, from `measures`, `suite_measures`), "scale" (the
    factor itself), or any other measure of `jaxrock.intensity.parse_im` (Sa at a period or at the
    column's T₁, the rocking-specific ratios: computed per record and column from `records`). The observations are every record × factor of the sweep whose run ended ok
    (the others are counted in `n_failed`), each its verdict, or its `p_overturn` where `ds` has
    one (`overturning_probability`: an uncertain verdict's ensemble fraction); the bootstrap
    resamples records. Returns an
    `xarray.Dataset` over the sweep's axes without `record` and `scale`: `median` [the measure's
    units], `beta`, their 5–95 % intervals (`median_ci`, `beta_ci`, dimension `bound`), the
    bootstrap fits (`median_boot`, `beta_boot`, dimension `bootstrap`), `n`, `n_overturned`, `n_failed`."""
    import xarray as xr

    from ..intensity import MEASURES, SCALING
    from .fragility import N_BOOT, fit_lognormal

    _check_im(im)
    n_boot = N_BOOT if n_boot is None else int(n_boot)
    scale = ds.scale.values
    over = (ds.p_overturn if "p_overturn" in ds else ds.overturned).transpose("record", ..., "scale").values
    status = ds.status.transpose("record", ..., "scale").values
    cell_shape = over.shape[1:-1]
    if im == "scale":
        x = np.ones((ds.sizes["record"], *cell_shape, 1)) * scale
        units = "1"
    elif im in SCALING and im in measures:
        x = np.ones((1, *cell_shape, 1)) * measures[im].sel(record=ds.record).values.reshape(-1, *[1] * len(cell_shape), 1) * scale ** SCALING[im]
        units = MEASURES[im][1]
    else:
        if records is None:
            raise JaxrockInputError(f"im = {im!r}: a measure of each record and column; give the suite's records")
        from .risk import _cells, _intensities

        x1, units, power = _intensities(im, records, _cells(ds)[1])
        x = x1[..., None] * scale**power
    group = np.broadcast_to(np.arange(ds.sizes["record"])[:, None], (ds.sizes["record"], scale.size))
    fits = []
    for idx in np.ndindex(*cell_shape):
        x_c = x[(slice(None), *idx)]
        o, st = over[(slice(None), *idx)], status[(slice(None), *idx)]
        ok = st == 0
        if not ok.any():
            fits.append(None)
            continue
        f = fit_lognormal(x_c[ok], o[ok], group[ok], n_boot=n_boot, seed=seed)
        f["n_failed"] = int((~ok).sum())
        fits.append(f)
    blank = {"median": np.nan, "beta": np.nan, "median_ci": np.full(2, np.nan), "beta_ci": np.full(2, np.nan),
             "median_boot": np.full(n_boot, np.nan), "beta_boot": np.full(n_boot, np.nan), "n": 0, "n_overturned": 0}
    fits = [f if f is not None else {**blank, "n_failed": int(over.shape[0] * over.shape[-1])} for f in fits]
    get = lambda key: np.array([f[key] for f in fits]).reshape(tuple(cell_shape) + np.shape(fits[0][key]))
    dims = tuple(d for d in ds.overturned.dims if d not in ("record", "scale"))
    what = "scale factor" if im == "scale" else MEASURES[im][0] if im in MEASURES else im
    out = xr.Dataset(
        {
            "median": (dims, get("median"), {"long_name": f"fragility median: {what} at 50 % probability of overturning", "units": units}),
            "beta": (dims, get("beta"), {"long_name": "fragility dispersion (lognormal standard deviation)", "units": "1"}),
            "median_ci": ((*dims, "bound"), get("median_ci"), {"long_name": "bootstrap 5-95 % interval of median", "units": units}),
            "beta_ci": ((*dims, "bound"), get("beta_ci"), {"long_name": "bootstrap 5-95 % interval of beta", "units": "1"}),
            "median_boot": ((*dims, "bootstrap"), get("median_boot"), {"long_name": "median of each bootstrap fit", "units": units}),
            "beta_boot": ((*dims, "bootstrap"), get("beta_boot"), {"long_name": "beta of each bootstrap fit", "units": "1"}),
            "n": (dims, get("n").astype(np.int32), {"long_name": "observations (record x factor runs ending ok)"}),
            "n_overturned": (dims, get("n_overturned"), {"long_name": "observations that overturned (an uncertain one counts its "
                                                                         "probability where the sweep has p_overturn)"}),
            "n_failed": (dims, get("n_failed").astype(np.int32), {"long_name": "runs left out: status not ok"}),
        },
        coords={**{d: ds[d] for d in dims}, "bound": ("bound", np.array([5.0, 95.0]), {"units": "percent"})},
        attrs={"im": im, "im_units": units, "n_boot": n_boot, "seed": seed,
               "fit": "lognormal CDF by maximum likelihood of the sweep's outcomes (Baker 2015, multiple stripes); bootstrap over records"},
    )
    return out


def check_motion(records) -> None:
    """A suite's records all move: a record whose samples are all 0 has no intensity to fit a
    fragility against (and no significant duration)."""
    still = [r.name for r in records if not np.any(np.asarray(r.acc))]
    if still:
        raise JaxrockInputError(f"records: {', '.join(still)}: every sample is 0 (no ground motion); a suite needs records that move")


def run_suite(models, records, *, scale, refine: int = 6, im: str = "pga", n_boot: int | None = None, store_dir=None,
              progress: bool = True, history: str | None = None, integrator=None, sensitivity: bool = True, ensemble: int = 0,
              **quantities):
    """A record suite for each model kind of `models` (e.g. ("rigid", "spring", "spring-flexible")):
    the record sweep of `records` × `quantities` (the column's axes or fixed values, as `Sweep.make`)
    × `scale`, its least overturning factors (`least_overturning_scale`, `refine` bisections) and
    its fragility against `im` (`suite_fragility`), with the records' measures
    (`jaxrock.intensity.suite_measures`). Returns one `xarray.Dataset` with a `model` dimension.
    `store_dir`: each model's sweep is kept in `<store_dir>/<model>.zarr` (a rerun resumes it).
    `sensitivity` (default on: record runs are where verdicts turn chaotic): every run reports its
    sensitivity and whether its verdict is uncertain, and each column whether its least factor is
    (`least_scale_uncertain`; `jaxrock.sensitivity`). `ensemble` > 0 (with the sensitivity): each
    uncertain run is replaced by the fraction of `ensemble` perturbed runs that overturn
    (`p_overturn`, `overturning_probability`), and the fragility is fitted on those fractions."""
    from pathlib import Path

    import xarray as xr

    from ..intensity import suite_measures

    if isinstance(models, str):
        models = (models,)
    if len(set(models)) < len(models):
        raise JaxrockInputError(f"models {list(models)}: a model kind given twice; name each once")
    check_grid("scale (record factors)", scale)  # the least overturning factor is the first of them that overturns
    _check_im(im)
    check_motion(records)
    if not 0 <= int(ensemble) <= MAX_ENSEMBLE:
        raise JaxrockInputError(f"ensemble = {ensemble}; valid: an integer in [0, {MAX_ENSEMBLE}] (0: the verdicts as they are)")
    if int(ensemble) and not sensitivity:
        raise JaxrockInputError("ensemble: replaces the uncertain verdicts, which only a run with its sensitivity finds; drop "
                                "sensitivity=False (--no-sensitivity)")
    sweeps = [Sweep.make(m, records=records, scale=scale, integrator=integrator, sensitivity=sensitivity, **quantities) for m in models]  # every input checked first
    measures = suite_measures(sweeps[0].records)
    parts = []
    for m, sweep in zip(models, sweeps):
        store = None if store_dir is None else Path(store_dir) / f"{m}.zarr"
        ds = least_overturning_scale(sweep, store, refine=refine, progress=progress, history=history)
        if int(ensemble):
            p = overturning_probability(sweep, ds, int(ensemble))
            ds["p_overturn"] = (sweep.dims, p, {"long_name": f"probability of overturning: the verdict, or where uncertain the fraction "
                                                             f"of {int(ensemble)} runs at the scale x (1 +- {PERTURBATION:g}) that overturn", "units": "1"})
        ds = ds.assign_coords({k: v for k, v in sweep.fixed.items()})  # the column's fixed quantities (a measure's tanα, T₁)
        frag = suite_fragility(ds, measures, im, records=records, n_boot=n_boot)
        parts.append(xr.merge([ds, frag.rename({k: f"fragility_{k}" for k in frag.data_vars})], combine_attrs="override"))
    out = xr.concat(parts, dim=xr.DataArray(np.asarray(list(models), dtype=object), dims="model", name="model"),  # object: a Zarr v3 string
                    combine_attrs="drop_conflicts")
    out = xr.merge([out, measures], combine_attrs="override")
    out = out.assign_coords({k: v for k, v in sweeps[0].fixed.items()})  # the fixed quantities as scalar coordinates
    out.attrs.update({"title": "jaxrock record suite", "im": im, "refine": int(refine)})
    return out


__all__ = ["check_motion", "least_overturning_scale", "overturning_probability", "suite_fragility", "run_suite"]
