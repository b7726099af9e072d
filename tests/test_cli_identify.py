"""`jaxrock identify` (issue 62): a synthetic free-rocking test of known η is identified back within
its interval; bad input is refused in one line, exit 2, before JAX is imported; the figure draws
what was fitted. The fits compile the identification's programs (about 1.5 min per loss on 2
cores, cold): they are in the slow set, the refusals and the reader in the default one."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from helpers import fresh_cli, invoke, read_csv, write

ETA = 0.9


def _free_rocking(path, eta=ETA, noise=2e-4, seed=0):
    """A free-rocking test of the 2-m block at tanα = 0.15 released at 0.8 α, with Gaussian noise, as CSV."""
    import jaxrock
    from jaxrock.analyses.identify import history

    block = jaxrock.Block.from_slenderness(2.0, 0.15)
    alpha = float(block.alpha_r)
    t = np.arange(0.0, 4.0, 0.01)
    theta, _ = history(jaxrock.RigidModel(block, eta=eta), jaxrock.StillGround(), t, start=(0.0, 0.8 * alpha, 0.0))
    theta = np.asarray(theta) + np.random.default_rng(seed).normal(0.0, noise, t.size)
    return write(path, "t,theta\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, theta)))


def _rows(path) -> list[dict]:
    """identify.csv's rows, its '# ' footer line left out."""
    return [r for r in read_csv(path) if not r["parameter"].startswith("#")]


def _sine(path, n=40):
    """A small valid measurement (no physics): enough for the refusals that come after reading it."""
    t = np.arange(n) * 0.01
    return write(path, "t,theta\n" + "".join(f"{float(a)!r},{float(1e-3 * np.sin(10 * a))!r}\n" for a in t))


# -- the fit (slow: compiles the identification) --------------------------------------------------
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_free_rocking_eta_is_identified_within_its_interval(tmp_path):
    """η = 0.9 of a noisy free-rocking test (noise 2e-4 rad, 0.2 % of α) is found within 0.005 from a
    start at 0.8, inside the reported 95 % interval; the table and the figure are written."""
    measured = _free_rocking(tmp_path / "test.csv")
    out = tmp_path / "id"
    r = invoke("identify", measured, "--model", "rigid", "--free", "eta", "--eta", 0.8, "--n-boot", 20,
               "--height", 2.0, "--tan-alpha", 0.15, "--out", out)
    assert r.exit_code == 0, r.output
    print(r.stdout)
    assert "eta = " in r.stdout and "95 %" in r.stdout and "NOT IDENTIFIABLE" not in r.stdout
    (row,) = _rows(out / "identify.csv")
    est, lo, hi = float(row["estimate"]), float(row["lower"]), float(row["upper"])
    assert row["parameter"] == "eta" and row["identifiable"] == "True"
    assert abs(est - ETA) < 0.005, row
    assert lo <= ETA <= hi and hi - lo < 0.02, row
    assert np.isfinite(float(row["bootstrap_lower"]))  # 20 resamplings: a bootstrap interval
    png = out / "identify.png"
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_ground_motion_column_is_the_excitation(tmp_path):
    """A block at rest uplifted by a short sine of the ground (ag[g] column, 1.5 g tanα for one cycle
    of 0.5 s) then rocking freely: η is identified from the history under that ground motion."""
    import jaxrock
    from jaxrock.analyses.identify import history

    block = jaxrock.Block.from_slenderness(2.0, 0.15)
    dt = 0.01
    t = np.arange(0.0, 4.0, dt)
    ag_g = np.where(t < 0.5, 1.5 * 0.15 * np.sin(2 * np.pi * t / 0.5), 0.0)
    rec = jaxrock.Record(ag_g * 9.81, dt)
    theta, _ = history(jaxrock.RigidModel(block, eta=ETA), rec, t)
    theta = np.asarray(theta)
    assert np.max(np.abs(theta)) > 0.2 * float(block.alpha_r)  # it rocks
    theta = theta + np.random.default_rng(1).normal(0.0, 1e-4, t.size)
    rows = "".join(f"{float(a)!r},{float(b)!r},{float(c)!r}\n" for a, b, c in zip(t, theta, ag_g))
    measured = write(tmp_path / "shaken.csv", "t,theta,ag[g]\n" + rows)
    out = tmp_path / "id"
    r = invoke("identify", measured, "--free", "eta", "--eta", 0.8, "--loss", "multiple", "--boot", 0,
               "--height", 2.0, "--tan-alpha", 0.15, "--out", out, "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["excitation"].startswith("its ground acceleration")
    (row,) = _rows(out / "identify.csv")
    assert abs(float(row["estimate"]) - ETA) < 0.01 and float(row["lower"]) <= ETA <= float(row["upper"]), row


# -- refusals (default set: nothing is compiled) --------------------------------------------------
@pytest.mark.parametrize("case, args, names", [
    ("unknown --free", ["--free", "bogus"], ["--free bogus", "eta, cbar"]),
    ("--free the model lacks", ["--free", "cbar"], ["--free cbar", "--model rigid", "valid for --model rigid: eta, height"]),
    ("a name twice", ["--free", "eta,eta"], ["--free", "twice"]),
    ("negative --n-boot", ["--free", "eta", "--n-boot", "-1"], ["--boot (--n-boot) = -1", ">= 0"]),
    ("negative --seed", ["--free", "eta", "--seed", "-3"], ["--seed = -3", ">= 0"]),
    ("--smoothing on the rigid model", ["--free", "eta", "--smoothing", "0.1"], ["--smoothing", "spring"]),
    ("--units without --record", ["--free", "eta", "--units", "m/s2"], ["--units", "--record"]),
])
def test_bad_options_are_refused_in_one_line(tmp_path, case, args, names):
    measured = _sine(tmp_path / "m.csv")
    r = invoke("identify", measured, "--height", 2, "--tan-alpha", 0.15, "--out", tmp_path / "o", *args)
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1, (case, r.output)
    for n in names:
        assert n in r.output, (case, r.output)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("case, text, names", [
    ("no theta column", "t,phi\n" + "".join(f"{0.01 * i},{i}\n" for i in range(20)), ["no theta column", "found: t, phi", "theta [rad]"]),
    ("no t column", "time_s,theta\n0,1\n", ["no t column"]),
    ("t not increasing", "t,theta\n" + "".join(f"{0.01 * i},{i}\n" for i in range(10)) + "0.05,1\n", ["line 12", "strictly increasing"]),
    ("a non-number", "t,theta\n" + "".join(f"{0.01 * i},{i}\n" for i in range(10)) + "0.2,abc\n", ["line 12", "'abc'", "nan"]),
    ("too few samples", "t,theta\n0,1\n0.1,2\n", ["2 sample(s)", "at least 8"]),
    ("no finite theta", "t,theta\n" + "".join(f"{0.01 * i},\n" for i in range(10)), ["no finite sample"]),
    ("empty", "", ["empty"]),
])
def test_bad_measurements_are_refused_in_one_line(tmp_path, case, text, names):
    measured = write(tmp_path / "m.csv", text)
    r = invoke("identify", measured, "--free", "eta", "--height", 2, "--tan-alpha", 0.15, "--out", tmp_path / "o")
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1, (case, r.output)
    assert r.output.startswith(f"Error: MEASURED {measured}"), (case, r.output)
    for n in names:
        assert n in r.output, (case, r.output)


def test_a_missing_file_and_an_hdf5_file_are_refused(tmp_path):
    r = invoke("identify", tmp_path / "nope.csv", "--free", "eta", "--height", 2, "--tan-alpha", 0.15)
    assert r.exit_code == 2 and "no such file" in r.output and len(r.output.strip().splitlines()) == 1
    h5 = tmp_path / "m.nc"
    h5.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    r = invoke("identify", h5, "--free", "eta", "--height", 2, "--tan-alpha", 0.15)
    assert r.exit_code == 2 and "netCDF-4 (HDF5)" in r.output and "netCDF-3" in r.output


@pytest.mark.parametrize("args, code", [
    (["identify", "--help"], 0),
    (["identify", "{m}", "--free", "bogus", "--height", "2", "--tan-alpha", "0.15"], 2),
    (["identify", "{m}", "--free", "cbar", "--height", "2", "--tan-alpha", "0.15"], 2),
    (["identify", "{bad}", "--free", "eta", "--height", "2", "--tan-alpha", "0.15"], 2),
    (["identify", "{m}", "--free", "eta", "--n-boot", "-1", "--height", "2", "--tan-alpha", "0.15"], 2),
    (["identify", "{m}", "--free", "eta", "--height", "2", "--tan-alpha", "2"], 2),
])
def test_help_and_refusals_import_no_jax(tmp_path, args, code):
    """`identify --help` and the refusals answer without importing JAX or the other heavy libraries
    (as tests/test_startup.py holds for the other commands), in a fresh interpreter."""
    files = {"m": str(_sine(tmp_path / "m.csv")), "bad": str(write(tmp_path / "bad.csv", "t,phi\n0,1\n"))}
    assert fresh_cli([a.format(**files) for a in args]) == {"code": code, "heavy": []}


# -- the reader and the figure --------------------------------------------------------------------
def test_the_command_line_knows_the_librarys_names():
    """The JAX-free lists of the command line are the library's (`FREE`, `LOSSES`)."""
    from jaxrock.analyses.identify import FREE, LOSSES
    from jaxrock.cli.identify import FREE_NAMES, LOSS_NAMES

    assert FREE_NAMES == tuple(FREE) and LOSS_NAMES == LOSSES


def test_reader_takes_missing_samples_comments_g_and_netcdf(tmp_path):
    """CSV: an empty or nan θ is a missing sample, '#' lines are comments, ag[g] says its unit; a
    netCDF-3 file with `time`, `theta`, `ag` (units g) reads the same."""
    from jaxrock.cli.identify import read_measured

    t = np.arange(10) * 0.01
    text = "# a test\nt, theta ,ag[g]\n" + "".join(f"{a},{'' if i == 3 else ('nan' if i == 4 else i)},{0.1 * i}\n" for i, a in enumerate(t))
    m = read_measured(write(tmp_path / "m.csv", text + "# footer\n"))
    assert np.allclose(m.t, t) and np.isnan(m.theta[3]) and np.isnan(m.theta[4]) and m.theta[5] == 5.0
    assert m.ag_units == "g" and np.allclose(m.ag, 0.1 * np.arange(10))
    import xarray as xr

    ds = xr.Dataset({"theta": ("time", m.theta), "ag": ("time", m.ag, {"units": "g"})}, coords={"time": t})
    ds.to_netcdf(tmp_path / "m.nc", engine="scipy")
    n = read_measured(tmp_path / "m.nc")
    assert np.allclose(n.t, m.t) and np.array_equal(np.isnan(n.theta), np.isnan(m.theta)) and n.ag_units == "g"


def test_reader_takes_a_top_displacement_column(tmp_path):
    """A `top` column (CSV; `u_top` in a netCDF file, as `jaxrock simulate --save` writes it) is the top
    displacement [m], its empty cells missing samples; a top column without a finite sample is refused."""
    from jaxrock.cli.identify import read_measured

    t = np.arange(10) * 0.01
    text = "t,theta,top[m]\n" + "".join(f"{a},{0.01 * i},{'' if i == 2 else 0.04 * i}\n" for i, a in enumerate(t))
    m = read_measured(write(tmp_path / "m.csv", text))
    assert m.ag is None and np.isnan(m.top[2]) and np.allclose(np.delete(m.top, 2), np.delete(0.04 * np.arange(10), 2))
    import xarray as xr

    xr.Dataset({"theta": ("time", m.theta), "u_top": ("time", m.top)}, coords={"time": t}).to_netcdf(tmp_path / "m.nc", engine="scipy")
    n = read_measured(tmp_path / "m.nc")
    assert np.array_equal(np.isnan(n.top), np.isnan(m.top)) and np.allclose(n.top[~np.isnan(n.top)], m.top[~np.isnan(m.top)])
    empty = "t,theta,top\n" + "".join(f"{a},{0.01 * i},nan\n" for i, a in enumerate(t))
    r = invoke("identify", write(tmp_path / "e.csv", empty), "--height", 2, "--tan-alpha", 0.15, "--free", "eta")
    assert r.exit_code == 2 and "top holds no finite sample" in r.output


def test_plot_identification_draws_what_was_fitted(tmp_path):
    """The figure's data are the segments' measured and fitted samples (masked), the peaks, and a
    histogram per parameter where bootstrap estimates exist (here a hand-made result: nothing is fitted)."""
    import matplotlib.pyplot as plt

    import jaxrock
    from jaxrock.analyses.identify import Identification, Segments
    from jaxrock.plotting import plot_identification

    model = jaxrock.RigidModel(jaxrock.Block.from_slenderness(2.0, 0.15), eta=0.9)
    ts = np.array([[0.0, 0.1, 0.2, 0.2], [0.3, 0.4, 0.5, 0.6]])
    mask = np.array([[True, True, True, False], [True, True, True, True]])
    theta = np.where(mask, 0.01 * np.cos(ts), 0.0)
    seg = Segments(np.array([0.0, 0.3]), np.array([0.01, -0.01]), ts, theta, mask, np.array([0.0, 0.3, 0.6]),
                   np.array([0.01, -0.01, 0.008]), 1e-4)
    boot = np.random.default_rng(0).normal([0.9, 2.0], 0.01, (30, 2))
    res = Identification(("eta", "height"), np.array([0.9, 2.0]), np.array([0.8, 2.0]), np.array([0.01, 0.01]),
                         np.array([[0.88, 0.92], [1.98, 2.02]]), np.array([[0.88, 0.92], [1.98, 2.02]]),
                         np.array([[0.88, 0.92], [1.98, 2.02]]), np.eye(2), boot, np.array([True, True]), True, 5, 1e-4, 1e-4,
                         "multiple", 2, 7, model, seg, theta + 1e-4, (1.0, 1.0))
    fig = plot_identification(res, tmp_path / "id.png")
    d = fig.jaxrock_data
    assert d["t"].size == 7 and np.allclose(d["residual"], 1e-4) and np.allclose(d["theta_measured"], theta[mask])
    assert np.array_equal(d["peaks_t"], seg.peaks_t) and d["bootstrap"].shape == (30, 2)
    assert len(fig.axes) == 4  # θ/α′, residuals, one histogram per parameter
    assert (tmp_path / "id.png").is_file()
    plt.close(fig)

    # with a measured top displacement: a panel of the column's deflection u_top − 2h sinθ (θ the fitted one)
    top = np.where(mask, 2.0 * np.sin(theta + 1e-4) + 0.003, 0.0)
    top_mask = mask.copy()
    top_mask[1, 2] = False  # a missing top sample
    seg = seg._replace(top=top, top_mask=top_mask, top_noise=1e-5)
    fitted_top = 2.0 * np.sin(theta + 1e-4) + 0.002
    fig = plot_identification(dataclasses.replace(res, segments=seg, fitted_top=fitted_top))
    w_meas, w_fit = fig.jaxrock_data["deflection"]
    assert len(fig.axes) == 5 and np.allclose(w_fit, 0.002)
    assert np.isnan(w_meas[5]) and np.allclose(np.delete(w_meas, 5), 0.003)
    plt.close(fig)
