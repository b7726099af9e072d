"""The command line: outputs equal the library's results on the same inputs; bad input exits 2.

Grids are tiny (3×3) and scenes few: the cost is compilation, shared within the process (the CLI
runs in-process under CliRunner, so its jitted functions are reused by the direct calls).
"""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path
import time

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
import typer
from typer.testing import CliRunner

import jaxrock as jr
from jaxrock.cli import app, even_batch, parse_values
from jaxrock.spectra import Spectrum, overturning_spectrum

runner = CliRunner()
# jaxrock.simulate, jitted: the same compiled function as the CLI's (shared cache per function)
_jit_sim = eqx.filter_jit(jr.simulate)


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


# -- spectrum --------------------------------------------------------------------------------------
def test_spectrum_writes_nc_equal_to_library_and_png(tmp_path):
    out = tmp_path / "spec"
    r = invoke("spectrum", "--n-omega", 3, "--n-accel", 3, "--omega-min", 1.5, "--omega-max", 6,
               "--accel-min", 0.8, "--accel-max", 6, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "spec.png").stat().st_size > 1000
    assert not (tmp_path / "spec.checkpoint").exists()  # removed once complete
    spec = Spectrum.load(tmp_path / "spec.nc")
    model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    ref = overturning_spectrum(model, np.linspace(1.5, 6, 3), np.linspace(0.8, 6, 3), batch_size=9, progress=False)
    np.testing.assert_array_equal(spec.omega_ratio, ref.omega_ratio)
    np.testing.assert_array_equal(spec.accel_ratio, ref.accel_ratio)
    np.testing.assert_allclose(spec.max_theta, ref.max_theta, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(spec.overturned, ref.overturned)
    np.testing.assert_array_equal(spec.uplifted, ref.uplifted)
    np.testing.assert_array_equal(spec.status, ref.status)
    assert "9 cells" in r.output and "overturned:" in r.output and "status: ok" in r.output
    assert f"overturned: {int(ref.overturned.sum())} cells" in r.output


def test_spectrum_tol_runs_generalized_alpha(tmp_path):
    """`--tol` runs the spring model with generalized-α: the file equals the library's spectrum
    with that integrator, cell for cell."""
    out = tmp_path / "spec"
    r = invoke("spectrum", "--model", "spring", "--n-omega", 2, "--n-accel", 3, "--omega-min", 2, "--omega-max", 6,
               "--accel-min", 0.8, "--accel-max", 6, "--tol", 1e-6, "--refine", 0, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    spec = Spectrum.load(tmp_path / "spec.nc")
    model = jr.SpringModel(jr.Block.from_slenderness(10.0, 0.2))
    ref = overturning_spectrum(model, np.linspace(2, 6, 2), np.linspace(0.8, 6, 3), integrator=jr.GeneralizedAlpha(1e-6, 1e-6),
                               progress=False)
    np.testing.assert_allclose(spec.max_theta, ref.max_theta, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(spec.overturned, ref.overturned)


@pytest.mark.parametrize(
    "args, name",
    [
        (["--tan-alpha", 1.5], "tan_alpha"),
        (["--height", -1], "height"),
        (["--n-omega", 0], "--n-omega"),
        (["--accel-min", 2, "--accel-max", 1], "--accel-max"),
        (["--tan-alpha-base", 0.1], "b_base"),
        (["--tol", 1e-6], "--tol"),
        (["--model", "spring", "--tol", 2.0], "rtol"),
    ],
)
def test_spectrum_bad_input_exits_2_naming_the_parameter(tmp_path, args, name):
    r = invoke("spectrum", *args, "--out", tmp_path / "s", "--quiet")
    assert r.exit_code == 2
    assert name in r.output
    assert "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "s.nc").exists()


def test_typer_type_errors_exit_2():
    r = invoke("spectrum", "--n-omega", "abc")
    assert r.exit_code == 2


def test_every_command_has_help():
    for cmd in ("spectrum", "simulate", "batch", "record-spectrum", "calibrate"):
        r = invoke(cmd, "--help")
        assert r.exit_code == 0, (cmd, r.output)
        assert "Usage" in r.output


@pytest.mark.parametrize(
    "cmd, text",
    [
        ("spectrum", "full height 2h [m]"),
        ("simulate", "pulse amplitude [m/s²]"),
        ("simulate", "pulse frequency [rad/s]"),
        ("batch", "[pulse: symmetric | antisymmetric | elcentro | FILE]"),
        ("record-spectrum", "body heights 2h [m]: '1,2,5' or 'a:b:n'"),
        ("calibrate", "('0.1,0.2,0.3' or 'a:b:n'"),
    ],
)
def test_help_shows_units_and_ranges_as_written(cmd, text):
    """Help texts are not rich markup: '[m]' and the optional batch columns survive, and 'a:b:n'
    is not turned into an emoji (it was, with typer's default rich_markup_mode)."""
    r = invoke(cmd, "--help")
    assert r.exit_code == 0, r.output
    assert text in " ".join(r.output.split()), r.output


def test_helpers():
    assert even_batch(2304, 4096) == 576
    assert 2304 % even_batch(2304, 500) == 0 and even_batch(2304, 500) <= 500
    assert even_batch(9, 4096) == 9
    np.testing.assert_allclose(parse_values("--x", "1:3:3"), [1, 2, 3])
    np.testing.assert_allclose(parse_values("--x", "1, 2,5"), [1, 2, 5])
    with pytest.raises(jr.JaxrockInputError, match="--x"):
        parse_values("--x", "a,b")


# -- simulate --------------------------------------------------------------------------------------
def _printed_max(output: str) -> float:
    return float(re.search(r"max θ/α = ([0-9.eE+-]+)", output).group(1))


def test_simulate_prints_max_theta_of_simulate(tmp_path):
    png = tmp_path / "h.png"
    r = invoke("simulate", "--height", 10, "--tan-alpha", 0.2, "--accel-ratio", 4, "--omega-p", 2 * math.pi, "--plot", png,
               "--n-points", 200)
    assert r.exit_code == 0, r.output
    block = jr.Block.from_slenderness(10.0, 0.2)
    sol = _jit_sim(jr.RigidModel(block), jr.RickerPulse(4 * float(block.uplift_acceleration), 2 * math.pi))
    assert _printed_max(r.output) == pytest.approx(float(sol.max_theta), abs=2e-6)
    assert ("overturned: no" in r.output) == (not bool(sol.overturned))
    assert "status: ok" in r.output
    assert png.stat().st_size > 1000


@pytest.mark.parametrize(
    "args, name",
    [
        (["--tan-alpha", 1.5], "tan_alpha"),
        (["--height", -2], "height"),
        (["--a-p", 1, "--accel-ratio", 2], "--a-p"),
        (["--omega-p", -1], "omega_p"),
        (["--record", "no/such/file.AT2"], "--record"),
        (["--eta", 0.5, "--model", "spring"], "--eta"),
    ],
)
def test_simulate_bad_input_exits_2(args, name):
    r = invoke("simulate", *args)
    assert r.exit_code == 2, r.output
    assert name in r.output and "Traceback" not in r.output


# -- batch -----------------------------------------------------------------------------------------
SCENES = """id,height,tan_alpha,width,pulse,accel_ratio,a_p,omega_ratio,omega_p,eta
a,10,0.2,,symmetric,4,,,6.283185307179586,
b,5,0.15,,symmetric,3,,2,,0.9
# a comment line
c,20,,2,symmetric,,5,3,,1
"""


def _write(path, text):
    path.write_text(text)
    return path


def _read(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _direct(row):
    """The scene of one row, built by hand, run by `simulate`."""
    h = float(row["height"])
    ta = float(row["tan_alpha"]) if row["tan_alpha"] else float(row["width"]) / h
    block = jr.Block.from_slenderness(h, ta)
    a_p = float(row["a_p"]) if row["a_p"] else float(row["accel_ratio"]) * 9.81 * ta
    w = float(row["omega_p"]) if row["omega_p"] else float(row["omega_ratio"]) * float(block.p)
    eta = float(row["eta"]) if row["eta"] else float(block.eta)
    model = jr.RigidModel(block, eta=jnp.asarray(eta))
    return _jit_sim(model, jr.RickerPulse(a_p, w))


def test_batch_round_trip_and_resume(tmp_path):
    scenes = _write(tmp_path / "scenes.csv", SCENES)
    res = tmp_path / "out" / "results.csv"
    r = invoke("batch", scenes, res, "--quiet")
    assert r.exit_code == 0, r.output
    rows = _read(res)
    assert [x["row"] for x in rows] == ["1", "2", "3"]
    assert [x["id"] for x in rows] == ["a", "b", "c"]
    for x in rows:
        sol = _direct(x)
        assert float(x["max_theta"]) == pytest.approx(float(sol.max_theta), abs=1e-9)
        assert int(x["overturned"]) == int(sol.overturned)
        assert float(x["t_overturn"]) == pytest.approx(float(sol.t_overturn), abs=1e-9) if sol.overturned else x["t_overturn"] == "inf"
        assert int(x["uplifted"]) == int(sol.uplifted)
        assert int(x["n_impacts"]) == int(sol.n_impacts)
        assert x["status"] == "ok"

    # an interrupted run: only row 2 finished (its result marked to show it is kept, not rerun)
    with open(res) as fh:
        lines = fh.read().splitlines()
    kept = lines[2].split(",")
    kept[-7] = "0.123456"  # max_theta
    _write(res, lines[0] + "\n" + ",".join(kept) + "\n" + "1,a,10")  # + a partly written line
    r = invoke("batch", scenes, res, "--resume", "--quiet")
    assert r.exit_code == 0, r.output
    assert "1 skipped" in r.output and "2 run" in r.output
    again = _read(res)
    assert [x["row"] for x in again] == ["1", "2", "3"]
    assert again[1]["max_theta"] == "0.123456"
    for a, b in ((again[0], rows[0]), (again[2], rows[2])):
        # rerun in other batches: equal to the root-finding tolerance, not bitwise
        assert {k: v for k, v in a.items() if k not in ("max_theta", "t_overturn", "t_uplift")} == {
            k: v for k, v in b.items() if k not in ("max_theta", "t_overturn", "t_uplift")
        }
        for k in ("max_theta", "t_overturn", "t_uplift"):
            assert float(a[k]) == pytest.approx(float(b[k]), abs=1e-9)

    # resuming against changed inputs is refused
    _write(scenes, SCENES.replace("b,5,0.15", "b,6,0.15"))
    r = invoke("batch", scenes, res, "--resume", "--quiet")
    assert r.exit_code == 2 and "row 2" in r.output


@pytest.mark.parametrize(
    "bad, where",
    [
        ("b,5,1.5,,symmetric,3,,2,,", ["row 2", "line 3", "'tan_alpha'", "(0, 1)"]),
        ("b,-5,0.1,,symmetric,3,,2,,", ["row 2", "'height'", "(0, inf)"]),
        ("b,5,0.1,,symmetric,3,,abc,,", ["row 2", "'omega_ratio'", "not a number"]),
        ("b,5,0.1,,triangle,3,,2,,", ["row 2", "'pulse'", "symmetric"]),
        ("b,5,0.1,,symmetric,,,2,,", ["row 2", "'a_p'", "accel_ratio"]),
        ("b,5,0.1,0.5,symmetric,3,,2,,", ["row 2", "'tan_alpha'", "width"]),
        ("b,5,0.1,,symmetric,3,,2,,1.5", ["row 2", "'eta'", "[0, 1]"]),
    ],
)
def test_batch_malformed_row_fails_before_running(tmp_path, bad, where):
    lines = SCENES.splitlines()
    lines[2] = bad
    scenes = _write(tmp_path / "scenes.csv", "\n".join(lines) + "\n")
    res = tmp_path / "results.csv"
    r = invoke("batch", scenes, res, "--quiet")
    assert r.exit_code == 2, r.output
    for w in where:
        assert w in r.output, (w, r.output)
    assert "Traceback" not in r.output
    assert not res.exists()  # nothing ran


def test_batch_parameter_for_wrong_model(tmp_path):
    scenes = _write(tmp_path / "s.csv", "height,tan_alpha,model,accel_ratio,omega_ratio,eta\n10,0.2,spring,3,2,0.5\n")
    r = invoke("batch", scenes, tmp_path / "r.csv")
    assert r.exit_code == 2 and "'eta'" in r.output and "rigid" in r.output


# -- record spectrum, calibrate ------------------------------------------------------------------
def test_record_spectrum_equals_library(tmp_path):
    from jaxrock.spectra import record_overturning_scale

    t = np.arange(0, 2.0, 0.02)
    acc = 0.4 * np.sin(2 * np.pi * 1.0 * t) * np.exp(-t)  # [g]
    rec_file = tmp_path / "pulse.txt"
    rec_file.write_text("\n".join(f"{a:.4f} {b:.8f}" for a, b in zip(t, acc)) + "\n")
    out = tmp_path / "rs"
    r = invoke("record-spectrum", "--record", rec_file, "--heights", "1,4", "--scales", "0.5:8:4", "--refine", 3,
               "--tan-alpha", 0.2, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    rows = _read(tmp_path / "rs.csv")
    ref = record_overturning_scale(jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2)), jr.read_record(rec_file),
                                   [1.0, 4.0], np.linspace(0.5, 8, 4), refine=3, progress=False)
    np.testing.assert_allclose([float(x["least_scale"]) for x in rows], ref.scale)
    assert (tmp_path / "rs.png").exists() and (tmp_path / "rs.nc").exists()


def test_calibrate_bad_input_exits_2(tmp_path):
    r = invoke("calibrate", "--tan-alphas", "0.1,1.5", "--out", tmp_path)
    assert r.exit_code == 2 and "--tan-alphas" in r.output
    r = invoke("record-spectrum", "--heights", "5,2", "--out", tmp_path / "x")
    assert r.exit_code == 2 and "heights" in r.output


# -- honest exits: a run that is not ok exits 1 with a line saying what to change -----------------
def test_simulate_failed_status_exits_1_with_advice():
    """Generalized-α at 1e-14 cannot meet its tolerance on the step ladder: status solver_failed
    (as in test_generalized_alpha's unreachable-tolerance test). The summary is printed, then one
    line on what to change, and the exit code is 1 (was 0)."""
    r = invoke("simulate", "--model", "spring", "--tol", 1e-14, "--accel-ratio", 3)
    assert r.exit_code == 1, r.output
    assert "status: solver_failed" in r.output
    assert "1 run ended with status solver_failed" in r.output and "loosen --tol" in r.output
    r = invoke("simulate", "--model", "spring", "--tol", 1e-6, "--accel-ratio", 3)
    assert r.exit_code == 0, r.output
    assert "Warning" not in r.output


def test_spectrum_failed_cells_exit_1_after_writing(tmp_path):
    out = tmp_path / "spec"
    r = invoke("spectrum", "--model", "spring", "--tol", 1e-14, "--n-omega", 1, "--n-accel", 1, "--accel-min", 3,
               "--omega-min", 2, "--refine", 0, "--out", out, "--quiet")
    assert r.exit_code == 1, r.output
    assert "1 cell(s) ended with status solver_failed" in r.output
    assert Spectrum.load(tmp_path / "spec.nc").status.ravel().tolist() == [jr.Status.solver_failed._value.item()]


@pytest.mark.slow
def test_calibrate_not_converged_exits_1(tmp_path):
    """Two optimiser iterations cannot meet the calibration's stopping test: every slenderness is
    named on one line and the exit code is 1 (was 0, with converged=False only in the CSV).
    A real calibration (21–30 s): slow; the default run checks the decision on a given report."""
    r = invoke("calibrate", "--tan-alphas", "0.1,0.2,0.3", "--max-iter", 2, "--out", tmp_path, "--quiet")
    assert r.exit_code == 1, r.output
    assert "did not converge in --max-iter 2 iterations at tanα = 0.1, 0.2, 0.3 (3 of 3)" in r.output


def test_spectrum_refuses_a_checkpoint_of_another_pulse(tmp_path):
    """The checkpoint of an interrupted symmetric run, rerun as antisymmetric with the same --out:
    exit 2 and one line naming the difference, before any cell runs (it resumed the symmetric
    cells and labelled them antisymmetric)."""
    from jaxrock import provenance
    from jaxrock.cli import build_model

    out = tmp_path / "spec"
    wr, ar = np.linspace(1.5, 6, 3), np.linspace(0.8, 6, 3)
    model = build_model("rigid", 10.0, 0.2)
    made = provenance.describe(model=model, excitation="RickerPulse", grid={"omega_ratio": wr, "accel_ratio": ar})
    z = np.zeros(9)
    provenance.append_checkpoint(Path(f"{out}.checkpoint"), made, slice(0, 9), dict(
        max_theta=z, overturned=z.astype(bool), uplifted=z.astype(bool), status=z.astype(np.int32)))
    r = invoke("spectrum", "--n-omega", 3, "--n-accel", 3, "--omega-min", 1.5, "--omega-max", 6,
               "--accel-min", 0.8, "--accel-max", 6, "--out", out, "--quiet", "--pulse", "antisymmetric")
    assert r.exit_code == 2, r.output
    assert "excitation: RickerPulse → AntisymmetricRickerPulse" in r.output and "delete" in r.output
    assert len(r.output.strip().splitlines()) == 1
    r = invoke("spectrum", "--n-omega", 3, "--n-accel", 3, "--omega-min", 1.5, "--omega-max", 6,
               "--accel-min", 0.8, "--accel-max", 6, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output  # the run that made it resumes it (all cells done: max_theta 0)
    assert "uplifted: 0" in r.output


def test_calibrate_names_the_slendernesses_that_did_not_converge(tmp_path, monkeypatch):
    """The CLI's decision on a calibration report (the real run is the slow test above): exit 1
    and one line naming the unconverged slendernesses; a fully converged report exits 0."""
    import jaxrock.calibration as cal

    class Report:
        files: dict = {}

        def __init__(self, converged):
            self.table = [dict(tan_alpha=t, converged=c) for t, c in zip((0.1, 0.2, 0.3), converged)]

        def format_table(self):
            return "table"

    for converged, code in (((True, False, False), 1), ((True, True, True), 0)):
        monkeypatch.setattr(cal, "calibration_report", lambda *a, _c=converged, **k: Report(_c))
        r = invoke("calibrate", "--tan-alphas", "0.1,0.2,0.3", "--max-iter", 5, "--out", tmp_path, "--quiet")
        assert r.exit_code == code, r.output
        assert ("did not converge in --max-iter 5 iterations at tanα = 0.2, 0.3 (2 of 3)" in r.output) == (code == 1)


# -- everything checked before the work ------------------------------------------------------------
@pytest.mark.parametrize(
    "args, name",
    [
        (["spectrum", "--out", "{blocked}/spec"], "--out"),
        (["simulate", "--plot", "{blocked}/x.png"], "--plot"),
        (["batch", "{scenes}", "{blocked}/r.csv"], "results"),
        (["record-spectrum", "--out", "{blocked}/rs"], "--out"),
        (["calibrate", "--out", "{blocked}"], "--out"),
    ],
)
def test_unwritable_output_fails_before_the_work(tmp_path, monkeypatch, args, name):
    """An output path under a file cannot be written: one line naming the option and the blocking
    file, exit 2, and no model was ever run (it failed after 17.7 s of computing)."""
    blocked = tmp_path / "a_file"
    blocked.write_text("x")
    scenes = tmp_path / "scenes.csv"
    scenes.write_text("height,tan_alpha,accel_ratio,omega_ratio\n10,0.2,3,4\n")
    runs = []
    monkeypatch.setattr(jr.model, "simulate", lambda *a, **k: runs.append(1))
    monkeypatch.setattr("jaxrock.cli._simulate", lambda *a, **k: runs.append(1))
    r = invoke(*[a.format(blocked=blocked, scenes=scenes) for a in args])
    assert r.exit_code == 2, r.output
    assert f"{name} " in r.output and "a_file is a file, not a folder" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not runs


@pytest.mark.parametrize("content, needle", [(b"\x00\x01\xff\xfe", "not UTF-8 text"), (b"height,tan_alpha\x00\n", "binary (NUL bytes)")])
def test_batch_binary_csv_is_one_line(tmp_path, content, needle):
    scenes = tmp_path / "scenes.csv"
    scenes.write_bytes(content)
    r = invoke("batch", scenes, tmp_path / "r.csv")
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output


def test_calibrate_needs_three_slendernesses_before_computing(tmp_path):
    """Two values computed for 23 s, then failed in the power-law fit; now refused at once."""
    t0 = time.perf_counter()
    r = invoke("calibrate", "--tan-alphas", "0.15,0.25", "--out", tmp_path)
    assert r.exit_code == 2 and "needs at least 3" in r.output, r.output
    assert time.perf_counter() - t0 < 2.0


def test_record_units_option(tmp_path):
    """A two-column file is read in g unless --units says otherwise: the same motion written in
    m/s² and in cm/s² gives the same answer; --units on a pulse is refused."""
    t = np.arange(200) * 0.01
    acc = 3.0 * np.sin(2 * np.pi * t) * np.exp(-t)  # m/s²
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("".join(f"{x:.17g} {y:.17g}\n" for x, y in zip(t, acc)))
    b.write_text("".join(f"{x:.17g} {100 * y:.17g}\n" for x, y in zip(t, acc)))
    ra = invoke("simulate", "--record", a, "--units", "m/s2")
    rb = invoke("simulate", "--record", b, "--units", "cm/s/s")
    assert ra.exit_code == 0 and rb.exit_code == 0, (ra.output, rb.output)
    peak = lambda out: float(re.search(r"max θ/α = ([0-9.]+)", out).group(1))
    assert peak(ra.output) > 1e-3 and peak(ra.output) == pytest.approx(peak(rb.output), rel=1e-5)
    r = invoke("simulate", "--units", "g")
    assert r.exit_code == 2 and "--units applies to --record files" in r.output
    r = invoke("simulate", "--record", a, "--units", "furlongs")
    assert r.exit_code == 2 and "valid units are g, m/s2, cm/s2" in r.output


def test_spectrum_file_says_how_it_was_made(tmp_path):
    """Units on every variable and coordinate, CF flag_values beside flag_meanings, c̄ (or η),
    the integrator, the versions and the command line."""
    import xarray as xr

    out = tmp_path / "spec"
    r = invoke("spectrum", "--model", "spring", "--n-omega", 2, "--n-accel", 3, "--omega-min", 2, "--omega-max", 6,
               "--accel-min", 0.8, "--accel-max", 6, "--tol", 1e-6, "--refine", 0, "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    with xr.open_dataset(tmp_path / "spec.nc", engine="scipy") as ds:
        for name in [*ds.data_vars, *ds.coords]:
            assert ds[name].attrs.get("units") == "1", name
        for name in ("overturned", "uplifted", "status"):
            values, meanings = ds[name].attrs["flag_values"], ds[name].attrs["flag_meanings"].split()
            assert len(np.atleast_1d(values)) == len(meanings) and list(np.atleast_1d(values)) == list(range(len(meanings)))
        assert ds["status"].attrs["flag_meanings"].split()[0] == "ok"
        a = ds.attrs
        assert a["Conventions"].startswith("CF-") and a["jaxrock_version"] and a["jax_version"]
        assert "GeneralizedAlpha(" in a["integrator"] and "rtol=1e-06" in a["integrator"]
        model = jr.SpringModel(jr.Block.from_slenderness(10.0, 0.2))
        assert a["cbar"] == pytest.approx(float(model.cbar), rel=1e-15)
        assert re.match(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ jaxrock ", a["history"])
    # the model, grid and batch of test_spectrum_writes_nc_equal_to_library_and_png: its program is reused
    rigid_model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    rigid = overturning_spectrum(rigid_model, np.linspace(1.5, 6, 3), np.linspace(0.8, 6, 3), batch_size=9, progress=False)
    assert rigid.attrs["eta"] == pytest.approx(float(rigid_model.restitution), rel=1e-15)
    assert "EventIntegrator(" in rigid.attrs["integrator"]


# -- huge work is estimated, and refused without --yes ---------------------------------------------
def test_huge_grid_is_refused_with_an_estimate_unless_yes():
    """10⁴ × 10⁴ cells showed an ETA of 41–124 h and took 5 GB: now one line with the estimate
    (from the measured cost per cell) and exit 2, before anything is allocated or compiled."""
    t0 = time.perf_counter()
    r = invoke("spectrum", "--n-omega", 10_000, "--n-accel", 10_000)
    assert r.exit_code == 2, r.output
    assert "100,000,000 cells: about 5.3 h and 6.4 GB (at 0.19 ms each" in r.output and "--yes" in r.output
    assert len(r.output.strip().splitlines()) == 1 and time.perf_counter() - t0 < 2.0
    # the gate itself: --yes lets the same work through; a flexible grid is dearer per cell
    from jaxrock.cli import _estimate

    _estimate(10**8, "rigid", yes=True)
    _estimate(800_000, "spring-flexible", yes=True)  # 56 min: announced, allowed
    with pytest.raises(typer.Exit):
        _estimate(900_000, "spring-flexible", yes=False)  # 63 min
    _estimate(900_000, "rigid", yes=False)  # 2.9 min


def test_huge_list_option_is_refused():
    r = invoke("record-spectrum", "--heights", "1:2:100000000")
    assert r.exit_code == 2 and "n = 100000000 values; valid: at most 100000" in r.output, r.output


def test_huge_record_sweep_is_refused_with_an_estimate():
    r = invoke("record-spectrum", "--heights", "1:20:10000")
    assert r.exit_code == 2 and "240,000 record runs: about" in r.output and "--yes" in r.output, r.output


def test_interrupted_spectrum_keeps_its_batches_and_says_how_to_resume(tmp_path, monkeypatch):
    """Ctrl-C in the second of three batches: exit 130, the first batch kept in the checkpoint
    folder (its own file; no temporary left), one line with the command that resumes; the rerun
    computes the two other batches only and equals the library's spectrum."""
    from jaxrock import spectra

    out = tmp_path / "spec"
    args = ["spectrum", "--n-omega", 3, "--n-accel", 3, "--omega-min", 1.5, "--omega-max", 6, "--accel-min", 0.8,
            "--accel-max", 6, "--out", out, "--quiet", "--batch-size", 3, "--refine", 0]
    real, calls = spectra.run_batch, []

    def interrupted_in_second_batch(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(spectra, "run_batch", interrupted_in_second_batch)
    r = invoke(*args)
    assert r.exit_code == 130, r.output
    assert "interrupted: 3 of 9 cells kept in" in r.output and "resume with: jaxrock" in r.output
    ck = Path(f"{out}.checkpoint")
    assert sorted(f.name for f in ck.iterdir()) == ["batch_000000000000.npz", "made_by.json"]
    monkeypatch.setattr(spectra, "run_batch", real)
    calls.clear()
    monkeypatch.setattr(spectra, "run_batch", lambda *a, **k: (calls.append(1), real(*a, **k))[1])
    r = invoke(*args)
    assert r.exit_code == 0, r.output
    assert len(calls) == 2 and not ck.exists()
    ref = overturning_spectrum(jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2)), np.linspace(1.5, 6, 3),
                               np.linspace(0.8, 6, 3), progress=False)
    np.testing.assert_allclose(Spectrum.load(tmp_path / "spec.nc").max_theta, ref.max_theta, rtol=0, atol=1e-12)


def test_batch_resume_refuses_results_of_another_record_or_version(tmp_path, monkeypatch):
    """A results file carries how it was made (<results>.made_by.json): resuming after the record
    file's content changed (same name, same row inputs), or under another package version, is
    refused with one line naming it; a results file with no description is refused too."""
    from jaxrock import provenance

    rec = tmp_path / "rec.txt"
    t = np.arange(100) * 0.02
    rec.write_text("".join(f"{x:.17g} {0.3 * np.sin(3 * x):.17g}\n" for x in t))
    scenes = _write(tmp_path / "scenes.csv", "height,tan_alpha,pulse,scale\n10,0.2,rec.txt,1\n5,0.2,rec.txt,2\n")
    res = tmp_path / "results.csv"
    r = invoke("batch", scenes, res, "--quiet")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "results.csv.made_by.json").is_file()
    assert invoke("batch", scenes, res, "--resume", "--quiet").exit_code == 0  # same run: resumes
    rec.write_text("".join(f"{x:.17g} {0.4 * np.sin(3 * x):.17g}\n" for x in t))
    r = invoke("batch", scenes, res, "--resume", "--quiet")
    assert r.exit_code == 2 and "made by a different run (record rec.txt:" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
    rec.write_text("".join(f"{x:.17g} {0.3 * np.sin(3 * x):.17g}\n" for x in t))
    version = provenance.package_version()
    monkeypatch.setattr(provenance, "package_version", lambda: "9.9.9")
    r = invoke("batch", scenes, res, "--resume", "--quiet")
    assert r.exit_code == 2 and f"jaxrock: {version} → 9.9.9" in r.output, r.output
    (tmp_path / "results.csv.made_by.json").unlink()
    r = invoke("batch", scenes, res, "--resume", "--quiet")
    assert r.exit_code == 2 and "no readable description results.csv.made_by.json" in r.output, r.output
