"""The CF conventions (CF-1.8) of the netCDF files jaxrock writes, in one place: a title and the
references (the paper, the software); the scene's numbers (height, width, α, p, tanα, η, c̄, …)
as scalar variables with their units, not unit-less global attributes; "did not happen" (a time
of overturning where the body did not overturn) written as the fill value with its meaning
stated, never +inf beside a NaN fill; inputs as they were given (tanα = 0.2, not
0.19999999999999998). `tests/test_cf.py` runs the IOOS compliance checker on every kind of file.
"""

from __future__ import annotations

import numpy as np

CONVENTIONS = "CF-1.8"
PAPER = ("Vassiliou, M. F., Mackie, K. R. and Stojadinovic, B. (2014): Dynamic response analysis of solitary flexible rocking "
         "bodies: modeling and behavior under pulse-like ground excitation. Earthquake Engineering and Structural Dynamics "
         "43(10), 1463-1481, doi:10.1002/eqe.2406")
NEVER = "fill value: did not happen"  # the comment of a variable whose fill value means "never" (`encode_never`)


def references() -> str:
    """The CF `references` attribute: the paper the models implement and the software."""
    from ..cache import package_version

    return f"{PAPER}; jaxrock {package_version()}, a differentiable simulator of rocking bodies in JAX"


def input_value(x) -> float:
    """An input as the user gave it, from a number derived from it (tan(arctan 0.2) =
    0.19999999999999998, b/h): rounded to 15 significant digits, which every decimal input of up
    to 15 digits survives and no computed round-off does."""
    return float(f"{float(x):.15g}")


def _scalars() -> dict[str, tuple[str, str]]:
    """Global attribute → (long_name, units) of the scene's numbers written as scalar variables:
    the sweepable quantities as declared (`jaxrock.scene.sweep_quantities`: a registered kind's
    parameters included) and the block's derived ones."""
    from ..scene import sweep_quantities

    known = {name: (long_name, units or "1") for name, (long_name, units, _) in sweep_quantities().items() if name != "record"}
    return {**known,
            "width": ("full width 2b", "m"),
            "alpha": ("rocking slenderness angle alpha'", "rad"),
            "p": ("frequency parameter p' of the rocking body", "rad s-1"),
            "threshold": ("overturning threshold on |theta|/alpha'", "1")}


def encode(ds, title: str):
    """`ds` (an xarray Dataset) as CF wants it: `title`, `references`, `Conventions` and a `history`
    (the command line's command, else how it was made); each
    numeric global attribute that names a scene quantity moved into a scalar variable with its
    units; the other attributes as netCDF-3 can hold them (numbers and strings)."""
    import xarray as xr

    scalars = _scalars()
    attrs, moved = {}, {}
    for k, v in ds.attrs.items():
        if k in scalars and isinstance(v, (int, float, np.number)) and not isinstance(v, bool):
            long_name, units = scalars[k]
            moved[k] = xr.Variable((), float(v), {"long_name": long_name, "units": units})
        else:
            attrs[k] = v if isinstance(v, (int, float, str, np.number)) and not isinstance(v, bool) else str(v)
    from ..cache import package_version

    out = ds.assign(moved)
    out.attrs = {"history": f"made by jaxrock {package_version()} through its Python API",  # the command line writes its command
                 **attrs, "Conventions": CONVENTIONS, "title": title, "references": references()}
    return out


def decode_attrs(ds) -> dict:
    """The global attributes `encode` was given, from a file it wrote: its scalar variables back
    among them."""
    return {**ds.attrs, **{k: float(ds[k].values) for k in _scalars() if k in ds.variables and ds[k].ndim == 0}}


def encode_never(values, attrs: dict, also: str = "") -> tuple[np.ndarray, dict]:
    """A float variable whose +inf means "did not happen" (a time of overturning, a least
    overturning factor where none overturns): +inf written as the fill value (NaN), the meaning
    stated in `comment` (`also`: what else the fill value means, e.g. an invalid scene)."""
    v = np.asarray(values, dtype=float)
    return np.where(np.isposinf(v), np.nan, v), {**attrs, "comment": NEVER + (f"; {also}" if also else "")}


def flags(long_name: str, meanings, dtype=np.int8) -> dict:
    """CF flag attributes: `flag_values` beside `flag_meanings` (and units 1)."""
    return {"long_name": long_name, "units": "1", "flag_values": np.arange(len(meanings), dtype=dtype),
            "flag_meanings": " ".join(meanings)}


INVALID = "or the scene is invalid (status invalid_input)"


def output_variable(o, values, dims) -> tuple:
    """A summary output (`jaxrock.outputs.Output`) as a netCDF variable: flags as CF flags (int8,
    "not_overturned overturned"), counts as int32 (netCDF-3 has no int64), a time's "never"
    (+inf) as the fill value (`encode_never`), numbers as they are."""
    values = np.asarray(values)
    if o.kind == "bool":
        return dims, values.astype(np.int8), {**flags(o.name, (f"not_{o.name}", o.name)), "long_name": o.meaning}
    if o.units == "s":
        return (dims, *encode_never(values, {"long_name": o.meaning, "units": o.units}, INVALID))
    data = values.astype(np.int32) if o.kind == "int" else values
    return dims, data, {"long_name": o.meaning, "units": o.units}


def netcdf_encoding(ds) -> dict:
    """`to_netcdf`'s encoding: no fill value on coordinates and on scalar variables that hold a
    value (CF 2.5.1), a NaN fill on the other float variables."""
    def filled(v):
        return v.dtype.kind == "f" and bool(np.isnan(v.values).any())

    return {name: {"_FillValue": None} for name, v in ds.variables.items() if name in ds.coords or (v.ndim == 0 and not filled(v))}


def write_netcdf(ds, path) -> None:
    """`ds` (encoded) as a netCDF-3 file at `path` (SciPy's writer: no HDF5 library needed)."""
    ds.to_netcdf(path, engine="scipy", encoding=netcdf_encoding(ds))
