"""The command line: outputs equal the library's results on the same inputs; bad input exits 2.

Grids are tiny (3×3) and scenes few: the cost is compilation, shared within the process (the CLI
runs in-process under CliRunner, so its jitted functions are reused by the direct calls).
"""

from __future__ import annotations

import math
import re

import equinox as eqx
import numpy as np
import pytest
import jaxrock as jr
from helpers import invoke, read_csv
from jaxrock.cli import parse_values
from jaxrock.analyses.spectra import Spectrum, overturning_spectrum

# jaxrock.simulate, jitted: the same compiled function as the CLI's (shared cache per function)
_jit_sim = eqx.filter_jit(jr.simulate)


# -- spectrum --------------------------------------------------------------------------------------
def test_spectrum_writes_nc_equal_to_library_and_png(tmp_path):
    """`--out sp/` (a trailing separator) writes inside the folder sp (it wrote sp.nc beside it)."""
    r = invoke("spectrum", "--omega-ratio", "1.5:6:3", "--accel-ratio", "0.8:6:3",
               "--out", f"{tmp_path}/sp/", "--quiet", "--sensitivity")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "sp" / "spectrum.png").stat().st_size > 1000
    assert sorted(f.name for f in (tmp_path / "sp").iterdir()) == ["spectrum.nc", "spectrum.png"]  # no checkpoint, lock or temporary left
    spec = Spectrum.load(tmp_path / "sp" / "spectrum.nc")
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
    # every cell's verdict judged (--sensitivity; the library's spectrum without it): the flag of its own numbers
    assert np.all(np.isfinite(spec.sensitivity)) and np.all(np.isnan(ref.sensitivity)) and not ref.uncertain.any()
    np.testing.assert_array_equal(spec.uncertain, jr.verdict_uncertain(spec.sensitivity, spec.max_theta, spec.overturned))
    assert f"verdict uncertain: {int(spec.uncertain.sum())} of 9 cells" in r.output, r.output


def test_spectrum_tol_runs_generalized_alpha(tmp_path):
    """`--tol` runs the spring model with generalized-α: the file equals the library's spectrum
    with that integrator, cell for cell."""
    out = tmp_path / "spec"
    r = invoke("spectrum", "--model", "spring", "--omega-ratio", "2:6:2", "--accel-ratio", "0.8:6:3",
               "--tol", 1e-6, "--refine", 0, "--out", out, "--quiet", "--no-sensitivity")
    assert r.exit_code == 0, r.output
    assert "verdict uncertain: not computed" in r.output and "sensitivity: not computed" in r.output, r.output
    spec = Spectrum.load(tmp_path / "spec.nc")
    model = jr.SpringModel(jr.Block.from_slenderness(10.0, 0.2))
    ref = overturning_spectrum(model, np.linspace(2, 6, 2), np.linspace(0.8, 6, 3), integrator=jr.GeneralizedAlpha(1e-6, 1e-6),
                               progress=False)
    np.testing.assert_allclose(spec.max_theta, ref.max_theta, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(spec.overturned, ref.overturned)


@pytest.mark.parametrize(
    "args, name",
    [
        (["--tan-alpha", 1.5], "--tan-alpha"),
        (["--height", -1], "height"),
        (["--omega-ratio", "1:15:0"], "--omega-ratio"),
        (["--accel-ratio", "2:1:5"], "--accel-ratio"),
        (["--tan-alpha-base", 0.1], "b_base"),
        (["--tol", 1e-6], "--tol"),
        (["--model", "spring", "--tol", 2.0], "--tol"),
    ],
)
def test_spectrum_bad_input_exits_2_naming_the_parameter(tmp_path, args, name):
    r = invoke("spectrum", *args, "--out", tmp_path / "s", "--quiet")
    assert r.exit_code == 2
    assert name in r.output
    assert "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "s.nc").exists()


@pytest.mark.parametrize("args, needle", [(["spectrum", "--batch-size", "4.5"], "'--batch-size'"), (["spectrum", "--model", "RIGID"], "not a model kind: RIGID"),
                                          (["spectrum", "--bogus"], "--bogus"), (["bogus"], "'bogus'")])
def test_usage_errors_are_one_line_exit_2(args, needle):
    """Click printed a usage line, a hint and a blank line before the error; now one line like every other refusal."""
    r = invoke(*args)
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1, r.output
    assert r.output.startswith("Error: ") and needle in r.output and "--help" in r.output


def test_every_command_has_help():
    for cmd in ("spectrum", "simulate", "batch", "record-spectrum", "sweep", "suite", "calibrate"):
        r = invoke(cmd, "--help")
        assert r.exit_code == 0, (cmd, r.output)
        assert "Usage" in r.output


@pytest.mark.parametrize(
    "cmd, text",
    [
        ("spectrum", "full height 2h [m]"),
        ("simulate", "pulse amplitude [m/s²]"),
        ("simulate", "pulse frequency [rad/s]"),
        ("batch", "[pulse: symmetric | antisymmetric | sine | vertical | elcentro | FILE]"),
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
    assert "sensitivity: not computed" in r.output and "verdict uncertain: not computed" in r.output


def test_simulate_sensitivity_reports_the_tangent_and_the_verdicts_doubt():
    """`--sensitivity`: the run's sensitivity as `simulate(..., sensitivity=True)` gives it, and
    its uncertain flag (El Centro, 1.5 m block at 1.95× its uplift factor: rounding decides)."""
    r = invoke("simulate", "--height", 1.5, "--record", "elcentro", "--scale", 1.95 * 0.2 / 0.3129, "--sensitivity")
    assert r.exit_code == 0, r.output
    block = jr.Block.from_slenderness(1.5, 0.2)
    rec = jr.builtin_record("elcentro")
    sol = jr.simulate(jr.RigidModel(block), rec.scaled(1.95 * 0.2 / 0.3129), sensitivity=True)
    printed = float(re.search(r"sensitivity = (\S+)", r.output).group(1))
    assert printed == pytest.approx(float(sol.sensitivity), rel=1e-5)
    assert f"verdict uncertain: {'yes' if bool(sol.uncertain) else 'no'}" in r.output


def test_simulate_spring_backbone_options_are_the_models():
    """--backbone/--smoothing build the same SpringModel as Python (the bilinear spring at θy = 1e-5 α,
    the README's choice for values)."""
    r = invoke("simulate", "--model", "spring", "--height", 10, "--tan-alpha", 0.2, "--accel-ratio", 4,
               "--omega-p", 2 * math.pi, "--backbone", "bilinear", "--smoothing", 1e-5)
    assert r.exit_code == 0, r.output
    block = jr.Block.from_slenderness(10.0, 0.2)
    model = jr.SpringModel(block, backbone="bilinear", smoothing=1e-5)
    sol = _jit_sim(model, jr.RickerPulse(4 * float(block.uplift_acceleration), 2 * math.pi))
    assert _printed_max(r.output) == pytest.approx(float(sol.max_theta), abs=2e-6)


@pytest.mark.parametrize(
    "args, name",
    [
        (["--tan-alpha", 1.5], "--tan-alpha"),
        (["--height", -2], "height"),
        (["--a-p", 1, "--accel-ratio", 2], "--a-p"),
        (["--omega-p", -1], "--omega-p"),
        (["--record", "no/such/file.AT2"], "--record"),
        (["--eta", 0.5, "--model", "spring"], "--eta"),
        (["--backbone", "bilinear"], "--backbone"),
        (["--model", "spring", "--smoothing", 0], "smoothing"),
        (["--model", "spring", "--backbone", "multilinear"], "backbone"),
    ],
)
def test_simulate_bad_input_exits_2(args, name):
    r = invoke("simulate", *args)
    assert r.exit_code == 2, r.output
    assert name in r.output and "Traceback" not in r.output


# -- record spectrum, calibrate ------------------------------------------------------------------
def test_record_spectrum_equals_library(tmp_path):
    from jaxrock.analyses.spectra import record_overturning_scale

    t = np.arange(0, 2.0, 0.02)
    acc = 0.4 * np.sin(2 * np.pi * 1.0 * t) * np.exp(-t)  # [g]
    rec_file = tmp_path / "pulse.txt"
    rec_file.write_text("\n".join(f"{a:.4f} {b:.8f}" for a, b in zip(t, acc)) + "\n")
    (tmp_path / "rs").mkdir()  # an existing folder: the files go inside it
    r = invoke("record-spectrum", "--record", rec_file, "--height", "1,4", "--scale", "0.5:8:4", "--refine", 3,
               "--tan-alpha", 0.2, "--out", tmp_path / "rs", "--quiet")
    assert r.exit_code == 0, r.output
    rows = read_csv(tmp_path / "rs" / "record_spectrum.csv")
    ref = record_overturning_scale(jr.RigidModel(jr.Block.from_slenderness(1.0, 0.2)), jr.read_record(rec_file),
                                   [1.0, 4.0], np.linspace(0.5, 8, 4), refine=3, progress=False, sensitivity=True)
    np.testing.assert_allclose([float(x["least_scale"]) for x in rows], ref.scale)
    assert [int(x["uncertain"]) for x in rows] == [int(u) for u in ref.uncertain]  # every verdict judged (the default)
    assert f"verdict uncertain: {int(np.sum(ref.uncertain))} of 2 least factor(s)" in r.output, r.output
    assert sorted(f.name for f in (tmp_path / "rs").iterdir()) == [f"record_spectrum.{x}" for x in ("csv", "nc", "png")]


def test_calibrate_bad_input_exits_2(tmp_path):
    r = invoke("calibrate", "--tan-alpha", "0.1,1.5", "--out", tmp_path)
    assert r.exit_code == 2 and "--tan-alpha" in r.output
    r = invoke("record-spectrum", "--height", "5,2", "--out", tmp_path / "x")
    assert r.exit_code == 2 and "heights" in r.output


def test_spectrum_file_says_how_it_was_made(tmp_path):
    """Units on every variable and coordinate, CF flag_values beside flag_meanings, c̄ (or η),
    the integrator, the versions and the command line."""
    import xarray as xr

    out = tmp_path / "spec"
    r = invoke("spectrum", "--model", "spring", "--omega-ratio", "2:6:2", "--accel-ratio", "0.8:6:3",
               "--tol", 1e-6, "--refine", 0, "--out", out, "--quiet", "--no-sensitivity")
    assert r.exit_code == 0, r.output
    assert "verdict uncertain: not computed" in r.output and "sensitivity: not computed" in r.output, r.output
    with xr.open_dataset(tmp_path / "spec.nc", engine="scipy") as ds:
        from jaxrock.io.cf import _scalars

        # times in s; ratios, flags, counts and codes 1; the scene's numbers in their own (height m, alpha rad, p rad s-1)
        units = {**{k: u for k, (_, u) in _scalars().items()}, **{o.name: o.units for o in jr.SUMMARY}}
        for name in [*ds.data_vars, *ds.coords]:
            assert ds[name].attrs.get("units") == units.get(name, "1"), name
        assert ds["alpha"].attrs["units"] == "rad" and ds["height"].attrs["units"] == "m"
        for name in ("overturned", "uplifted", "status"):
            values, meanings = ds[name].attrs["flag_values"], ds[name].attrs["flag_meanings"].split()
            assert len(np.atleast_1d(values)) == len(meanings) and list(np.atleast_1d(values)) == list(range(len(meanings)))
        assert ds["status"].attrs["flag_meanings"].split()[0] == "ok"
        a = ds.attrs
        assert a["Conventions"].startswith("CF-") and a["jaxrock_version"] and a["jax_version"]
        assert "GeneralizedAlpha(" in a["integrator"] and "rtol=1e-06" in a["integrator"]
        model = jr.SpringModel(jr.Block.from_slenderness(10.0, 0.2))
        assert float(ds["cbar"]) == pytest.approx(float(model.cbar), rel=1e-15)  # a scalar variable (issue 58), was an attribute
        assert re.match(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ jaxrock ", a["history"])
    # the model, grid and batch of test_spectrum_writes_nc_equal_to_library_and_png: its program is reused
    rigid_model = jr.RigidModel(jr.Block.from_slenderness(10.0, 0.2))
    rigid = overturning_spectrum(rigid_model, np.linspace(1.5, 6, 3), np.linspace(0.8, 6, 3), batch_size=9, progress=False)
    assert rigid.attrs["eta"] == pytest.approx(float(rigid_model.eta), rel=1e-15)
    assert "EventIntegrator(" in rigid.attrs["integrator"]
