"""A sweep's store: xarray on Zarr (format 3), one Zarr chunk per sweep chunk
(`jaxrock.analyses.sweep`).

Layout (open it with `xarray.open_zarr(path)`, or `load`):
- the sweep's axes as coordinates (records by name), in the sweep's order;
- each summary output (`jaxrock.outputs.OUTPUTS`) and `status` (`jaxrock.results.STATUS_NAMES`;
  -1: not run yet) over the axes, chunked as the sweep is;
- `chunk_done` (dimension `chunk`): 1 once a chunk's outputs are all written. Zarr writes each chunk
  file atomically (a temporary renamed), and a chunk counts as finished only once its flag is
  written after its outputs: a run killed at any moment leaves finished chunks and chunks that a
  rerun runs again whole, never half a chunk;
- every chunk file carries a CRC-32C of its bytes, and a finished chunk has a file for every
  output (even one equal to the fill value): on resume a flagged chunk whose file is missing or
  fails its checksum is damaged, said so by name, and run again (`survey`), never kept as done;
- attributes: how the store was made (`Sweep.attrs`: every fixed value, the integrator, the versions;
  `made_by`, the full description; `history`, the command). A run into a store made by another
  description (or an unreadable store) is refused with one line.

Workers of a Dask cluster write their own chunks' files only (no shared metadata is rewritten),
so that any number write at once.
"""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._validate import JaxrockInputError
from ..outputs import OUTPUTS
from ..results import STATUS_NAMES
from .provenance import refuse_if_different

NOT_RUN = -1  # `status` of a scene whose chunk has not run


def _variables() -> dict[str, tuple[np.dtype, object, dict]]:
    """Each stored output: (dtype, fill value, attributes)."""
    out = {}
    for name, o in OUTPUTS.items():
        dtype = np.dtype(o.dtype)
        fill = {"float": np.nan, "bool": False, "int": 0}[o.kind]
        out[name] = (dtype, fill, {"long_name": o.meaning, "units": o.units})
    out["status"] = (np.dtype(np.int32), NOT_RUN, {"long_name": "jaxrock.Status code (-1: not run yet)",
                                                    "flag_values": list(range(-1, len(STATUS_NAMES))),
                                                    "flag_meanings": " ".join(("not_run", *STATUS_NAMES))})
    return out


def _coordinates(sweep) -> dict:
    from ..scene import sweep_quantities

    known = sweep_quantities(sweep.model if isinstance(sweep.model, str) else None, sweep.pulse if isinstance(sweep.pulse, str) else None)
    coords = {}
    for name, values in sweep.axes.items():
        long_name, units, _ = known[name]
        data = np.asarray(values, dtype=object) if name == "record" else np.asarray(values, dtype=float)  # object: a Zarr v3 string
        coords[name] = (name, data, {"long_name": long_name, **({"units": units} if units else {})})
    return coords


def _fresh(path: Path) -> str:
    return f"delete {path} to start afresh, or write another store"


def open_for(path, sweep, history: str | None = None) -> None:
    """Create the store of `sweep` at `path` (written beside and renamed: never half made), or
    check that the one there was made by the same description. `history`: the command that made
    it (a CF `history` attribute). The caller holds the store (`jaxrock.io.files.exclusive`)."""
    path = Path(path)
    if path.exists():
        made = _made_by(path)
        refuse_if_different(made, sweep.description(), f"store {path}", _fresh(path))
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"tmp_{os.getpid()}_{path.name}")
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        _make(tmp, sweep, history)
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)  # a full disk, an interruption: no half-made store left behind
        raise


def _make(tmp: Path, sweep, history: str | None) -> None:
    """The empty store of `sweep`, at `tmp`."""
    import xarray as xr
    import zarr
    from zarr.codecs import Crc32cCodec, ZstdCodec

    attrs = {**sweep.attrs(), **({"history": history} if history else {})}
    xr.Dataset(coords=_coordinates(sweep), attrs=attrs).to_zarr(tmp, mode="w", zarr_format=3, consolidated=False)
    group = zarr.open_group(tmp, mode="r+")
    for name, (dtype, fill, var_attrs) in _variables().items():
        a = group.create_array(name, shape=sweep.shape, chunks=sweep.chunk_shape, dtype=dtype, fill_value=fill,
                               dimension_names=sweep.dims, compressors=(ZstdCodec(), Crc32cCodec()))
        a.attrs.update(var_attrs)
    done = group.create_array("chunk_done", shape=(sweep.n_chunks,), chunks=(1,), dtype=np.int8, fill_value=0,
                              dimension_names=("chunk",))
    done.attrs.update({"long_name": "1: the chunk's outputs are all written", "units": "1"})
    with warnings.catch_warnings():  # "not part of the format 3 specification": xarray reads it, and warns without it
        warnings.simplefilter("ignore")
        zarr.consolidate_metadata(tmp, zarr_format=3)  # the metadata never changes after: chunk writes only


def _made_by(path: Path) -> dict:
    import zarr

    try:
        group = zarr.open_group(path, mode="r")
        made = json.loads(group.attrs["made_by"])
        missing = [name for name in (*_variables(), "chunk_done") if name not in group or not (path / name / "zarr.json").is_file()]
        if not isinstance(made, dict) or missing:
            raise ValueError(f"no {', '.join(missing) or 'description'}")
    except Exception as e:  # missing metadata, garbled JSON, another kind of folder: one answer
        raise JaxrockInputError(f"store {path} is unreadable or not a jaxrock sweep ({type(e).__name__}: {e}); {_fresh(path)}") from None
    return made


class Survey(NamedTuple):
    """What a store holds: the chunks finished and intact, and the chunks flagged finished whose
    files are not (chunk → what is wrong with it)."""

    done: set[int]
    damaged: dict[int, str]


def survey(path, sweep) -> Survey:
    """Each chunk flagged finished is checked: every output's chunk file is there and reads back
    (its CRC-32C matches). An unreadable flag counts as not finished."""
    import zarr

    path = Path(path)
    group = zarr.open_group(path, mode="r")
    flagged = _flagged(path, sweep, group["chunk_done"])
    arrays = {name: group[name] for name in _variables()}
    done, damaged = set(), {}
    for k in sorted(flagged):
        region = sweep.chunk_region(k)
        at = tuple(s.start // c for s, c in zip(region, sweep.chunk_shape))
        for name, a in arrays.items():
            key = a.metadata.encode_chunk_key(at)
            if not (path / name / key).is_file():
                damaged[k] = f"{name}: chunk file {name}/{key} is missing"
                break
            try:
                a[region]
            except Exception as e:
                damaged[k] = f"{name}: chunk file {name}/{key} is unreadable ({type(e).__name__}: {e})"
                break
        else:
            done.add(k)
    return Survey(done, damaged)


_ONE_READ = 1 << 24  # flags read in one go up to this many chunks (16 MB); beyond, only the flag files there are read


def _flagged(path: Path, sweep, flags) -> set[int]:
    """The chunks flagged finished. Up to `_ONE_READ` chunks in one read; beyond it (a sweep of
    10¹² chunks has flags no memory holds), or where a damaged flag file fails that read, each
    flag file present (one per chunk ever flagged) is read alone, a damaged one as not finished."""
    if sweep.n_chunks <= _ONE_READ:
        try:
            return {int(k) for k in np.flatnonzero(flags[...] == 1)}
        except Exception:
            pass
    folder = path / "chunk_done" / "c"
    listed = sorted(int(n) for n in (os.listdir(folder) if folder.is_dir() else ()) if n.isdigit() and int(n) < sweep.n_chunks)
    out = set()
    for k in listed:
        try:
            if flags[k] == 1:
                out.add(k)
        except Exception:
            pass
    return out


def flagged(path, sweep) -> set[int]:
    """The chunks flagged finished, without reading their outputs back (`survey` checks them)."""
    import zarr

    return _flagged(Path(path), sweep, zarr.open_array(Path(path) / "chunk_done", mode="r"))


def finished(path, sweep) -> set[int]:
    """The chunks whose outputs are all in the store, intact (`survey`)."""
    return survey(path, sweep).done


def unflag(path, chunks) -> None:
    """Mark `chunks` as not finished."""
    import zarr

    flags = zarr.open_array(Path(path) / "chunk_done", mode="r+")
    for k in chunks:
        flags[k] = 0


def write_chunk(path, sweep, k: int, outputs: dict[str, np.ndarray]) -> None:
    """Write chunk `k`'s outputs into its region, then its flag."""
    import zarr

    group = zarr.open_group(path, mode="r+")
    region = sweep.chunk_region(k)
    every = {"write_empty_chunks": True}  # a file even for a chunk equal to the fill: a missing file is damage
    for name in _variables():
        group[name].with_config(every)[region] = outputs[name]
    group["chunk_done"][k] = 1


def load(path):
    """The store as an in-memory `xarray.Dataset`. A damaged chunk file, or a chunk flagged
    finished whose scenes read as not run (a file removed), is refused in one line."""
    import xarray as xr

    try:
        with xr.open_zarr(path, chunks=None) as ds:
            ds = ds.load()
    except Exception as e:
        raise JaxrockInputError(f"store {path} is unreadable ({type(e).__name__}: {e}); {_fresh(Path(path))}") from None
    lost = int(((ds.status == NOT_RUN).sum()) if bool(ds.chunk_done.all()) else 0)
    if lost:
        raise JaxrockInputError(f"store {path} is unreadable (every chunk is flagged finished, but {lost} scenes read as not run: "
                                f"a chunk file was removed?); {_fresh(Path(path))}")
    return ds


def kept_scenes(path) -> int:
    """Scenes of the finished chunks in a store (0 when it is missing or unreadable)."""
    import zarr

    try:
        return int((zarr.open_array(Path(path) / "status", mode="r")[...] != NOT_RUN).sum())
    except Exception:
        return 0


def in_memory(sweep, chunks: dict[int, dict]):
    """The `xarray.Dataset` a store of `sweep` would hold, from chunk outputs kept in memory."""
    import xarray as xr

    data = {}
    for name, (dtype, fill, var_attrs) in _variables().items():
        a = np.full(sweep.shape, fill, dtype=dtype)
        for k, out in chunks.items():
            a[sweep.chunk_region(k)] = out[name]
        data[name] = (sweep.dims, a, var_attrs)
    flags = np.zeros(sweep.n_chunks, dtype=np.int8)
    flags[list(chunks)] = 1
    data["chunk_done"] = (("chunk",), flags, {"long_name": "1: the chunk's outputs are all written", "units": "1"})
    return xr.Dataset(data, coords=_coordinates(sweep), attrs=sweep.attrs())


__all__ = ["NOT_RUN", "Survey", "finished", "survey", "unflag", "flagged", "in_memory", "kept_scenes", "load", "open_for", "write_chunk"]
