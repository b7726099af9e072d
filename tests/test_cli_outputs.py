"""Machine-readable results (issue 58, item 2): `--json` documents that agree with the files the
same run wrote, `simulate --save` histories whose physics holds (the sampled peak never exceeds the
exact one; the spring model's energy balance), `-h` and shell completion."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from jaxrock.analyses.spectra import Spectrum
from jaxrock.outputs import HISTORY_FIELDS
from helpers import invoke, read_csv


def _doc(r) -> dict:
    """The JSON document a command printed on stdout (nothing else is on stdout)."""
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_spectrum_json_agrees_with_its_netcdf(tmp_path):
    """`spectrum --json`: one JSON document (strict: no NaN or Infinity) whose counts, boundaries
    and grid are the netCDF file's; null where a boundary is not in the grid; the files are 0644 under
    umask 022."""
    old = os.umask(0o022)
    try:
        r = invoke("spectrum", "--omega-ratio", "1.5:9:4", "--accel-ratio", "0.5:8:5",
                   "--refine", 3, "--out", tmp_path / "s", "--quiet", "--json")
    finally:
        os.umask(old)
    doc = _doc(r)
    for f in ("s.nc", "s.png"):  # written under umask 022: readable by others (was 0600 before the atomic write's chmod)
        assert stat.S_IMODE((tmp_path / f).stat().st_mode) == 0o644, f
    assert doc["command"] == "spectrum" and doc["units"]["height"] == "m" and doc["units"]["p"] == "rad/s"
    spec = Spectrum.load(tmp_path / "s.nc")
    assert doc["cells"] == 20 and doc["overturned"] == int(spec.overturned.sum()) and doc["uplifted"] == int(spec.uplifted.sum())
    np.testing.assert_array_equal(doc["omega_ratio"], spec.omega_ratio)
    for name, line in (("uplift_boundary", spec.uplift_boundary), ("overturn_boundary", spec.overturn_boundary)):
        got = np.array([np.nan if v is None else v for v in doc[name]])
        np.testing.assert_array_equal(got, line, err_msg=name)
    assert doc["status"] == {"ok": 20} and doc["alpha"] == spec.attrs["alpha"]
    assert [os.path.basename(f) for f in doc["files"]] == ["s.nc", "s.png"]


def test_simulate_save_netcdf_round_trips_and_its_peak_is_the_summarys(tmp_path):
    """`simulate --save h.nc --json`: the history's θ at 4000 points never exceeds the summary's
    exact peak and comes within the sampling's reach of it (|θ̇| Δt); the file's impacts are the
    sampled θ's sign changes; the ground acceleration is the pulse's (peak a_p)."""
    r = invoke("simulate", "--accel-ratio", 3, "--omega-ratio", 4, "--save", tmp_path / "h.nc", "--n-points", 4000, "--json")
    doc = _doc(r)
    with xr.open_dataset(tmp_path / "h.nc", engine="scipy") as ds:
        alpha = float(ds.alpha) if "alpha" in ds else doc["alpha"]
        peak = np.abs(ds.theta.values).max() / alpha
        dt = float(ds.t[1] - ds.t[0])
        assert peak <= doc["max_theta"] * (1 + 1e-12)
        assert doc["max_theta"] - peak <= np.abs(ds.theta_dot.values).max() * dt / alpha
        assert float(ds.max_theta) == doc["max_theta"]
        # the file's summary is the history run's, to the window's end: every impact is a sign change of the sampled θ;
        # the printed summary's run stopped once its answer was fixed, so it counts no more of them
        th = ds.theta.values[ds.theta.values != 0]
        assert int(ds.n_impacts) == int((np.sign(th[1:]) != np.sign(th[:-1])).sum()) >= doc["n_impacts"] > 0
        assert doc["t_overturn"] is None and np.isnan(float(ds.t_overturn)) and "did not happen" in ds.t_overturn.attrs["comment"]
        a_p = 3 * 9.81 * float(ds.tan_alpha)
        assert abs(np.abs(ds.ground_acceleration.values).max() - a_p) < 1e-3 * a_p
        assert ds.theta.attrs["units"] == "rad" and ds.t.attrs["units"] == "s"


def test_simulate_save_csv_holds_every_field_and_the_energy_balances(tmp_path):
    """The quasi-rigid spring model's history as CSV: every field the model gives, and
    kinetic + potential + dissipated = input (the balance the model integrates) to 1e-6 of the input."""
    r = invoke("simulate", "--model", "spring", "--accel-ratio", 3, "--save", tmp_path / "h.csv", "--n-points", 300)
    assert r.exit_code == 0, r.output
    rows = read_csv(tmp_path / "h.csv")
    rows = [row for row in rows if not row["t"].startswith("#")]
    cols = {k: np.array([float(row[k]) for row in rows]) for k in rows[0]}
    assert set(HISTORY_FIELDS) <= set(cols) and {"t", "ground_acceleration"} <= set(cols)
    balance = cols["kinetic"] + cols["potential"] + cols["dissipated"] - cols["input"]
    assert np.abs(balance).max() <= 1e-6 * np.abs(cols["input"]).max()
    assert "max_theta = " in (tmp_path / "h.csv").read_text().splitlines()[-1]


def test_simulate_save_refuses_an_unknown_suffix(tmp_path):
    r = invoke("simulate", "--save", tmp_path / "h.txt")
    assert r.exit_code == 2 and "--save" in r.output and ".nc" in r.output and ".csv" in r.output


@pytest.mark.parametrize("args", [("record-spectrum", "--height", "2,4", "--scale", "0.5,1", "--refine", 1, "--no-sensitivity"),
                                  ("batch",)])
def test_json_documents_of_other_commands(tmp_path, args):
    """record-spectrum and batch: strict JSON with their results (a least factor per height; the
    rows run and their status counts)."""
    if args[0] == "batch":
        (tmp_path / "scenes.csv").write_text("height,tan_alpha,accel_ratio,omega_ratio\n4,0.2,3,4\n10,0.15,6,2\n")
        r = invoke("batch", tmp_path / "scenes.csv", "--out", tmp_path / "res.csv", "--quiet", "--json")
        doc = _doc(r)
        assert doc["rows"] == doc["run"] == 2 and sum(doc["status"].values()) == 2
        return
    r = invoke(*args, "--out", tmp_path / "rs", "--quiet", "--json")
    doc = _doc(r)
    rows = read_csv(tmp_path / "rs.csv")
    assert doc["height"] == [float(x["height"]) for x in rows]
    assert [float("inf") if v is None else v for v in doc["least_scale"]] == [float(x["least_scale"]) for x in rows]
    assert doc["worst_status"] == ["ok", "ok"]


def test_help_short_option_and_shell_completion():
    """`-h` is `--help` for the program and every command; completion answers a partial command."""
    assert invoke("-h").exit_code == 0 and "Commands" in invoke("-h").output
    assert "--save" in invoke("simulate", "-h").output
    env = {**os.environ, "_JAXROCK_COMPLETE": "complete_bash", "COMP_WORDS": "jaxrock reco", "COMP_CWORD": "1", "JAX_PLATFORMS": "cpu"}
    out = subprocess.run([sys.executable, "-c", "from jaxrock.cli import app; app(prog_name='jaxrock')"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["record-spectrum"], out.stderr
