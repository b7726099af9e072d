"""The command line's guards: failed runs exit 1 with advice, bad input and other runs' files are
refused before the work, huge work is estimated first, interruptions keep their work and say how
to resume, record units, readable help (issue 18). Split from test_cli.py so that the two files
run on separate workers."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import typer

import jaxrock as jr
from jaxrock import JaxrockInputError
from jaxrock.analyses.spectra import Spectrum
from helpers import invoke, write

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
    r = invoke("spectrum", "--model", "spring", "--tol", 1e-14, "--omega-ratio", 2, "--accel-ratio", 3,
               "--refine", 0, "--out", out, "--quiet")
    assert r.exit_code == 1, r.output
    assert "1 cell(s) ended with status solver_failed" in r.output
    assert Spectrum.load(tmp_path / "spec.nc").status.ravel().tolist() == [int(jr.status_codes(jr.Status.solver_failed))]


def test_record_spectrum_failed_runs_exit_1_files_with_the_users_umask(tmp_path):
    """Generalized-α at 1e-14 on El Centro hits its step bound: the table says which heights, the
    CSV and netCDF carry the worst status, and the exit code is 1 (was 0: record-spectrum never
    checked its runs' status). Written under umask 022, every output is 0644 (was 0600)."""
    import stat

    import xarray as xr

    old = os.umask(0o022)
    try:
        r = invoke("record-spectrum", "--model", "spring", "--tol", 1e-14, "--height", "2,4", "--scale", "0.5,1",
                   "--refine", 1, "--out", tmp_path / "rs", "--quiet", "--no-sensitivity")
    finally:
        os.umask(old)
    assert r.exit_code == 1, r.output
    assert "2 height(s) ended with status max_steps" in r.output and "(a run max_steps)" in r.output
    assert "worst_status" in (tmp_path / "rs.csv").read_text().splitlines()[0]
    with xr.open_dataset(tmp_path / "rs.nc", engine="scipy") as ds:
        assert (ds.worst_status.values > 0).all()
    for suffix in (".nc", ".csv", ".png"):
        assert stat.S_IMODE((tmp_path / f"rs{suffix}").stat().st_mode) == 0o644, suffix


@pytest.mark.slow
def test_calibrate_not_converged_exits_1(tmp_path):
    """Two optimiser iterations cannot meet the calibration's stopping test: every slenderness is
    named on one line and the exit code is 1 (was 0, with converged=False only in the CSV).
    A real calibration (21–30 s): slow; the default run checks the decision on a given report."""
    r = invoke("calibrate", "--tan-alpha", "0.1,0.2,0.3", "--max-iter", 2, "--out", tmp_path, "--quiet")
    assert r.exit_code == 1, r.output
    assert "did not converge in --max-iter 2 iterations at tanα = 0.1, 0.2, 0.3 (3 of 3)" in r.output


def test_spectrum_refuses_a_checkpoint_of_another_pulse(tmp_path):
    """The checkpoint of an interrupted symmetric run, rerun as antisymmetric with the same --out:
    exit 2 and one line naming the difference, before any cell runs (it resumed the symmetric
    cells and labelled them antisymmetric)."""
    from jaxrock.cli import build_model

    out = tmp_path / "spec"
    wr, ar = np.linspace(1.5, 6, 3), np.linspace(0.8, 6, 3)
    model = build_model("rigid", 10.0, 0.2)
    jr.overturning_spectrum(model, wr, ar, checkpoint=Path(f"{out}.checkpoint"), keep_checkpoint=True, progress=False)
    r = invoke("spectrum", "--omega-ratio", "1.5:6:3", "--accel-ratio", "0.8:6:3",
               "--out", out, "--quiet", "--pulse", "antisymmetric")
    assert r.exit_code == 2, r.output
    assert "excitation: RickerPulse → AntisymmetricRickerPulse" in r.output and "delete" in r.output
    assert len(r.output.strip().splitlines()) == 1
    r = invoke("spectrum", "--omega-ratio", "1.5:6:3", "--accel-ratio", "0.8:6:3",
               "--out", out, "--quiet")
    assert r.exit_code == 0, r.output  # the run that made it resumes it
    assert not Path(f"{out}.checkpoint").exists() and Path(f"{out}.nc").exists()


def test_calibrate_names_the_slendernesses_that_did_not_converge(tmp_path, monkeypatch):
    """The CLI's decision on a calibration report (the real run is the slow test above): exit 1
    and one line naming the unconverged slendernesses; a fully converged report exits 0."""
    import jaxrock.reports as cal

    class Report:
        files: dict = {}

        def __init__(self, converged):
            self.table = [dict(tan_alpha=t, converged=c) for t, c in zip((0.1, 0.2, 0.3), converged)]

        def format_table(self):
            return "table"

    for converged, code in (((True, False, False), 1), ((True, True, True), 0)):
        monkeypatch.setattr(cal, "calibration_report", lambda *a, _c=converged, **k: Report(_c))
        r = invoke("calibrate", "--tan-alpha", "0.1,0.2,0.3", "--max-iter", 5, "--out", tmp_path, "--quiet")
        assert r.exit_code == code, r.output
        assert ("did not converge in --max-iter 5 iterations at tanα = 0.2, 0.3 (2 of 3)" in r.output) == (code == 1)


# -- everything checked before the work ------------------------------------------------------------
@pytest.mark.parametrize(
    "args, name",
    [
        (["spectrum", "--out", "{blocked}/spec"], "--out"),
        (["simulate", "--plot", "{blocked}/x.png"], "--plot"),
        (["batch", "{scenes}", "--out", "{blocked}/r.csv"], "--out"),
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
    monkeypatch.setattr("jaxrock.cli.simulate._simulate", lambda *a, **k: runs.append(1))
    r = invoke(*[a.format(blocked=blocked, scenes=scenes) for a in args])
    assert r.exit_code == 2, r.output
    assert f"{name} " in r.output and "a_file is a file, not a folder" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not runs


@pytest.mark.parametrize("content, needle", [(b"\x00\x01\xff\xfe", "not UTF-8 text"), (b"height,tan_alpha\x00\n", "binary (NUL bytes)")])
def test_batch_binary_csv_is_one_line(tmp_path, content, needle):
    scenes = tmp_path / "scenes.csv"
    scenes.write_bytes(content)
    r = invoke("batch", scenes, "--out", tmp_path / "r.csv")
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output


def test_calibrate_needs_three_slendernesses_before_computing(tmp_path):
    """Two values computed for 23 s, then failed in the power-law fit; now refused at once."""
    t0 = time.perf_counter()
    r = invoke("calibrate", "--tan-alpha", "0.15,0.25", "--out", tmp_path)
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


# -- huge work is estimated, and refused without --yes ---------------------------------------------
def test_huge_grid_is_refused_with_an_estimate_unless_yes():
    """10⁴ × 10⁴ cells showed an ETA of 41–124 h and took 5 GB: now one line with the estimate
    (from the measured cost per cell) and exit 2, before anything is allocated or compiled."""
    t0 = time.perf_counter()
    r = invoke("spectrum", "--omega-ratio", "1:15:10000", "--accel-ratio", "0.5:10:10000")
    assert r.exit_code == 2, r.output
    assert "100,000,000 cells: about 5.3 h and 6.4 GB (at 0.19 ms each" in r.output and "--yes" in r.output
    assert len(r.output.strip().splitlines()) == 1 and time.perf_counter() - t0 < 2.0
    r = invoke("spectrum", "--omega-ratio", "1:15:10000", "--accel-ratio", "0.5:10:10000", "--sensitivity")  # each run with its tangent: dearer
    assert r.exit_code == 2 and "100,000,000 cells: about 10.6 h and 6.4 GB (at 0.38 ms each" in r.output, r.output
    # the gate itself: --yes lets the same work through; a flexible grid is dearer per cell
    from jaxrock.cli.guards import _estimate

    _estimate(10**8, "rigid", yes=True)
    _estimate(800_000, "spring-flexible", yes=True)  # 56 min: announced, allowed
    with pytest.raises(typer.Exit):
        _estimate(900_000, "spring-flexible", yes=False)  # 63 min
    _estimate(900_000, "rigid", yes=False)  # 2.9 min


def test_huge_list_option_is_refused():
    r = invoke("record-spectrum", "--height", "1:2:100000000")
    assert r.exit_code == 2 and "n = 100000000 values; valid: at most 100000" in r.output, r.output


def test_huge_record_sweep_is_refused_with_an_estimate():
    r = invoke("record-spectrum", "--height", "1:20:10000")
    assert r.exit_code == 2 and "240,000 record runs: about" in r.output and "--yes" in r.output, r.output


def test_batch_resume_refuses_results_of_another_record_or_version(tmp_path, monkeypatch):
    """A results file carries how it was made (<results>.made_by.json): resuming after the record
    file's content changed (same name, same row inputs), or under another package version, is
    refused with one line naming it; a results file with no description is refused too."""
    from jaxrock.io import provenance

    rec = tmp_path / "rec.txt"
    t = np.arange(100) * 0.02
    rec.write_text("".join(f"{x:.17g} {0.3 * np.sin(3 * x):.17g}\n" for x in t))
    scenes = write(tmp_path / "scenes.csv", "height,tan_alpha,pulse,scale\n10,0.2,rec.txt,1\n5,0.2,rec.txt,2\n")
    res = tmp_path / "results.csv"
    r = invoke("batch", scenes, "--out", res, "--quiet")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "results.csv.made_by.json").is_file()
    assert invoke("batch", scenes, "--out", res, "--resume", "--quiet").exit_code == 0  # same run: resumes
    rec.write_text("".join(f"{x:.17g} {0.4 * np.sin(3 * x):.17g}\n" for x in t))
    r = invoke("batch", scenes, "--out", res, "--resume", "--quiet")
    assert r.exit_code == 2 and "made by a different run (record rec.txt:" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
    rec.write_text("".join(f"{x:.17g} {0.3 * np.sin(3 * x):.17g}\n" for x in t))
    version = provenance.package_version()
    monkeypatch.setattr(provenance, "package_version", lambda: "9.9.9")
    r = invoke("batch", scenes, "--out", res, "--resume", "--quiet")
    assert r.exit_code == 2 and f"jaxrock: {version} → 9.9.9" in r.output, r.output
    (tmp_path / "results.csv.made_by.json").unlink()
    r = invoke("batch", scenes, "--out", res, "--resume", "--quiet")
    assert r.exit_code == 2 and "is not the results of a batch run (no results.csv.made_by.json beside it)" in r.output, r.output


# -- files the user names -----------------------------------------------------------------------
def test_results_file_that_is_a_hard_link_to_the_scenes_is_refused(tmp_path):
    """A hard link is the same file under another name: it was overwritten (symbolic links were caught)."""
    scenes = write(tmp_path / "scenes.csv", "height,tan_alpha,accel_ratio,omega_ratio\n5,0.2,2,3\n")
    os.link(scenes, tmp_path / "results.csv")
    before = scenes.read_bytes()
    r = invoke("batch", scenes, "--out", tmp_path / "results.csv")
    assert r.exit_code == 2 and "the results file is the scenes file" in r.output and len(r.output.splitlines()) == 1, r.output
    assert scenes.read_bytes() == before


@pytest.mark.parametrize("cmd", [["spectrum"], ["record-spectrum"]])
def test_output_another_live_run_is_writing_is_refused_before_the_work(tmp_path, cmd):
    """Two runs into one --out shared temporaries and one died with a FileNotFoundError
    traceback; the second is now refused in one line naming the other process."""
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / "sp.lock").write_text(f"{socket.gethostname()} {other.pid}")
        r = invoke(*cmd, "--out", tmp_path / "sp")
        assert r.exit_code == 2 and f"another run (process {other.pid}" in r.output, r.output
    finally:
        other.kill()
        other.wait()


def test_lock_of_a_dead_run_is_taken_over_and_released(tmp_path):
    from jaxrock.io.files import exclusive

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    lock = tmp_path / "sp.lock"
    lock.write_text(f"{socket.gethostname()} {gone.pid}")
    with exclusive(tmp_path / "sp", "--out"):
        assert lock.read_text() == f"{socket.gethostname()} {os.getpid()}"
        with pytest.raises(JaxrockInputError, match=f"another run \\(process {os.getpid()}"):
            with exclusive(tmp_path / "sp", "--out"):
                pass
    assert not lock.exists()


# -- typos and late errors -----------------------------------------------------------------------
@pytest.mark.parametrize(
    "args, needle",
    [
        (["record-spectrum", "--height", "1,,3"], "--height = '1,,3' has an empty item"),
        (["simulate", "--t-free", "-1"], "--t-free applies to the time history"),
        (["simulate", "--plot", "h.png", "--n-points", "0"], "--n-points = 0; valid: an integer in [2, 1,000,000]"),
        (["simulate", "--plot", "h.png", "--t-free", "-1"], "--t-free = -1 is outside the valid range"),
        (["simulate", "--tan-alpha", "1e-8"], "--tan-alpha = 1e-08 is outside the valid range [0.001, 1)"),
        (["simulate", "--model", "spring-flexible", "--youngs-modulus", "1e-3"], "--youngs-modulus (Young's modulus) [Pa] = 0.001 is outside"),
        (["simulate", "--model", "spring-flexible", "--rho", "1e12"], "--rho (density) [kg/m^3] = 1e+12 is outside"),
    ],
)
def test_typos_and_out_of_range_values_are_refused_before_the_work(tmp_path, monkeypatch, args, needle):
    """Each was accepted in silence (an empty list item dropped; --t-free without --plot ignored)
    or failed only after the simulation, or gave a confident wrong answer (tanα = 1e-8; E = 1e-3 Pa)."""
    monkeypatch.chdir(tmp_path)
    t0 = time.perf_counter()
    r = invoke(*args)
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert time.perf_counter() - t0 < 2.0  # before any compilation
    assert not (tmp_path / "h.png").exists()


def test_misspelt_batch_column_is_refused_naming_the_close_match(tmp_path):
    """`modle=spring` was copied through and the row ran the rigid model."""
    scenes = write(tmp_path / "scenes.csv", "id,height,tan_alpha,modle,accel_ratio,omega_ratio\na,10,0.2,spring,3,2\n")
    r = invoke("batch", scenes, "--out", tmp_path / "res.csv")
    assert r.exit_code == 2 and "unknown column 'modle'; did you mean 'model'?" in r.output, r.output
    assert not (tmp_path / "res.csv").exists()


def test_byte_order_marks_are_accepted_in_scenes_and_records(tmp_path):
    """A spreadsheet's UTF-8 byte-order mark made the scenes file report "no 'height' column" and
    a two-column record refuse its first line."""
    from jaxrock.io.scenes_file import read_scenes

    (tmp_path / "rec.txt").write_text("0 0.1\n0.01 0.2\n0.02 -0.1\n", encoding="utf-8-sig")
    assert jr.read_record(tmp_path / "rec.txt").n == 3
    scenes = tmp_path / "scenes.csv"
    scenes.write_text("height,tan_alpha,pulse\n10,0.2,rec.txt\n", encoding="utf-8-sig")
    s = read_scenes(scenes)
    assert s.header == ["height", "tan_alpha", "pulse"] and s.records[0].n == 3


def test_compressed_record_is_refused_without_printing_its_bytes(tmp_path):
    import gzip

    at2 = Path(jr.__file__).parent / "data" / "IELC180.AT2"
    (tmp_path / "x.AT2").write_bytes(gzip.compress(at2.read_bytes()))
    r = invoke("simulate", "--record", tmp_path / "x.AT2")
    assert r.exit_code == 2 and "gzip-compressed; decompress it first" in r.output and len(r.output) < 300, r.output


def test_a_registered_kind_gets_the_dearest_estimate():
    """A model kind registered after the built-in ones has no measured cost (`CELL_SECONDS` raised
    KeyError for it): its runs are estimated at the dearest built-in kind's cost, so a grid too big
    for an hour is still refused without --yes (exit 2) and a small one is not."""
    import typer

    from jaxrock.cli import guards

    assert guards.cell_seconds("newcomer") == max(guards.CELL_SECONDS.values()) == guards.CELL_SECONDS["spring-flexible"]
    assert guards.cell_seconds("rigid") == guards.CELL_SECONDS["rigid"]
    n_hour = int(guards.LIMIT_SECONDS / guards.cell_seconds("newcomer"))
    with pytest.raises(typer.Exit) as e:
        guards._estimate(2 * n_hour, "newcomer", yes=False)
    assert e.value.exit_code == 2
    guards._estimate(n_hour // 100, "newcomer", yes=False)  # under a minute: no refusal, no announcement
