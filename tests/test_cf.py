"""The files jaxrock writes follow CF-1.8 (issue 58): the IOOS compliance checker finds nothing to
correct in a spectrum file and a record spectrum file; the attributes a reader needs are there
(title, references, the scene's numbers as scalar variables with units, inputs as given); a
time's "never" is the fill value with its meaning stated, and a file reads back bit for bit."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import xarray as xr

import jaxrock as jr
from jaxrock.analyses.spectra import Spectrum
from jaxrock.outputs import OUTPUTS

WORDS = re.compile(r"^[A-Za-z0-9_.+\-@]+( [A-Za-z0-9_.+\-@]+)*$")  # CF 3.5: blank-separated words of these characters


@pytest.fixture(scope="module")
def spectrum_file(tmp_path_factory):
    """A 4 x 3 rigid spectrum of tanα = 0.2 whose grid holds cells that neither uplift nor
    overturn (their times are "never"), saved."""
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    spec = jr.overturning_spectrum(model, np.array([1.5, 4.0, 9.0]), np.array([0.5, 2.0, 5.0, 9.0]), refine=0, progress=False)
    path = tmp_path_factory.mktemp("cf") / "spec.nc"
    spec.save(path)
    return spec, path


def _checker(path, tmp_path) -> dict[str, list[str]]:
    """The IOOS compliance checker's messages, CF 1.8, by section (empty: nothing to correct)."""
    runner = pytest.importorskip("compliance_checker.runner")
    runner.CheckSuite.load_all_available_checkers()
    report = tmp_path / "cc.json"
    runner.ComplianceChecker.run_checker(str(path), ["cf:1.8"], 0, "normal", output_filename=str(report), output_format="json")
    res = json.loads(report.read_text())["cf:1.8"]
    return {r["name"]: r["msgs"] for level in ("high_priorities", "medium_priorities", "low_priorities")
            for r in res.get(level, []) if r["msgs"]}


def _check_flags_and_fill(ds):
    for name, v in ds.variables.items():
        if "flag_meanings" in v.attrs:
            words = v.attrs["flag_meanings"].split(" ")
            assert WORDS.match(v.attrs["flag_meanings"]) and len(set(words)) == len(words) == len(v.attrs["flag_values"]), name
        if v.dtype.kind == "f":
            assert not np.isinf(v.values).any(), f"{name}: +inf beside a NaN fill value"


def test_spectrum_file_passes_the_cf_checker(spectrum_file, tmp_path):
    _, path = spectrum_file
    assert _checker(path, tmp_path) == {}


def test_spectrum_file_attributes(spectrum_file):
    """title and references (the paper's DOI); geometry as scalar variables with units, the input
    tanα written as given (was 0.19999999999999998, a global attribute without units); flags whose
    meanings are CF words (was 'no overturned'); "never" as the fill value (was +inf)."""
    spec, path = spectrum_file
    with xr.open_dataset(path, engine="scipy", mask_and_scale=False) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["title"].startswith("jaxrock overturning spectrum")
        assert "doi:10.1002/eqe.2406" in ds.attrs["references"] and "jaxrock" in ds.attrs["references"]
        for name, units in (("height", "m"), ("width", "m"), ("alpha", "rad"), ("p", "rad s-1"), ("tan_alpha", "1"), ("eta", "1")):
            assert ds[name].ndim == 0 and ds[name].attrs["units"] == units and name not in ds.attrs, name
        assert float(ds.tan_alpha) == 0.2 and float(ds.height) == 10.0
        assert ds.overturned.attrs["flag_meanings"] == "not_overturned overturned"
        _check_flags_and_fill(ds)
        never = ~spec.overturned & (spec.status == 0)
        assert never.any() and np.isnan(ds.t_overturn.values[never]).all()
        assert "did not happen" in ds.t_overturn.attrs["comment"]
        assert "_FillValue" not in ds.accel_ratio.attrs  # CF 2.5.1: coordinates have none


def test_spectrum_file_reads_back_bit_for_bit(spectrum_file):
    """`Spectrum.load` restores "never" as +inf (only where the scene is valid) and the scalar
    variables as attributes: every output equal, bit for bit."""
    spec, path = spectrum_file
    back = Spectrum.load(path)
    for name in (*OUTPUTS, "status", "omega_ratio", "accel_ratio"):
        np.testing.assert_array_equal(getattr(back, name), getattr(spec, name), err_msg=name)
    assert np.isinf(back.t_overturn).any()
    for k in ("height", "width", "alpha", "p", "eta", "threshold"):
        assert back.attrs[k] == spec.attrs[k], k
    assert back.attrs["tan_alpha"] == 0.2


def test_record_spectrum_file_passes_the_cf_checker(tmp_path):
    """A record spectrum whose tallest body no factor overturns ("never": the fill value). The
    checker's one message is its guess that a coordinate named `height` is a vertical axis (it
    asks for standard_name 'height', the height above the surface): here it is the body's size,
    for which CF has no standard name, so the guess is set aside by name and nothing else may be
    reported."""
    model = jr.RigidModel(jr.Block.from_slenderness(2.0, 0.2))
    rs = jr.record_overturning_scale(model, jr.el_centro(), [1.0, 20.0], [0.5, 1.0], refine=1, progress=False)
    assert np.isinf(rs.scale[-1]) and rs.attrs["tan_alpha"] == 0.2
    path = rs.save(tmp_path / "rs.nc")
    msgs = _checker(path, tmp_path)
    height_guess = "Coordinate variable 'height' should have standard_name='height', found: 'None'"
    assert {k: [m for m in v if m != height_guess] for k, v in msgs.items()} in ({}, {"§5.1 Independent Latitude, Longitude, "
                                                                                      "Vertical, and Time Axes": []})
    with xr.open_dataset(path, engine="scipy", mask_and_scale=False) as ds:
        _check_flags_and_fill(ds)
        assert "doi:10.1002/eqe.2406" in ds.attrs["references"] and ds.attrs["title"].startswith("jaxrock least overturning")
        assert np.isnan(ds.scale.values[-1]) and "did not happen" in ds.scale.attrs["comment"]
        assert float(ds.tan_alpha) == 0.2 and ds.tan_alpha.attrs["units"] == "1"


def test_sweep_store_attributes(tmp_path):
    """A sweep's Zarr store: Conventions, title and references; flag meanings that are CF words."""
    sw = jr.Sweep.make("rigid", accel_ratio=[1.0, 5.0], omega_ratio=[2.0, 6.0], height=4.0)
    jr.run_sweep(sw, tmp_path / "s.zarr", progress=False)
    with xr.open_zarr(tmp_path / "s.zarr") as ds:
        assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["title"].startswith("jaxrock sweep")
        assert "doi:10.1002/eqe.2406" in ds.attrs["references"]
        for name, v in ds.variables.items():
            if "flag_meanings" in v.attrs:
                assert WORDS.match(v.attrs["flag_meanings"]), name
