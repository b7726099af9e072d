"""Hostile input, third pass (issue 52): the files a command writes. No write through a symbolic
link into a file the command did not make, no unrelated file overwritten without `--force`, one
lock per file whatever its name, outputs with the user's umask, devices refused as outputs."""

from __future__ import annotations

import errno
import os
import stat
import subprocess
import sys

import pytest
from helpers import invoke, write

from jaxrock import JaxrockInputError
from jaxrock.io.files import exclusive, write_atomically

SCENES = "height,tan_alpha,accel_ratio,omega_ratio\n10,0.2,3,6\n"


def test_batch_does_not_write_through_a_symlink(tmp_path):
    """`ln -s target.csv link.csv; jaxrock batch b.csv link.csv` overwrote target.csv and replaced
    the link by a 0600 file."""
    scenes = write(tmp_path / "b.csv", SCENES)
    target = write(tmp_path / "target.csv", "precious\n")
    (tmp_path / "link.csv").symlink_to(target)
    r = invoke("batch", scenes, "--out", tmp_path / "link.csv", "--quiet")
    assert r.exit_code == 2 and "is a symbolic link" in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert target.read_text() == "precious\n" and (tmp_path / "link.csv").is_symlink()


def test_batch_does_not_overwrite_an_unrelated_file_without_force(tmp_path):
    """`jaxrock batch b.csv precious.csv` overwrote an existing file silently; its own results file
    (with its description beside it) is still rewritten by a rerun, and --force overwrites."""
    scenes = write(tmp_path / "b.csv", SCENES)
    precious = write(tmp_path / "precious.csv", "keep me\n")
    r = invoke("batch", scenes, "--out", precious, "--quiet")
    assert r.exit_code == 2 and "exists and is not the results of a batch run" in r.output and "--force" in r.output, r.output
    assert precious.read_text() == "keep me\n"
    r = invoke("batch", scenes, "--out", precious, "--quiet", "--force")
    assert r.exit_code == 0, r.output
    assert precious.read_text().startswith("row,height")
    r = invoke("batch", scenes, "--out", precious, "--quiet")  # now a results file of batch: a rerun rewrites it
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("device", ["/dev/null", "/dev/full"])
def test_batch_refuses_a_device_as_its_results(tmp_path, device):
    """`batch b.csv /dev/full` was a traceback (ENOSPC), `/dev/null` created /dev/null.made_by.json."""
    scenes = write(tmp_path / "b.csv", SCENES)
    existed = os.path.exists(device + ".made_by.json")
    r = invoke("batch", scenes, "--out", device, "--quiet")
    assert r.exit_code == 2 and "is not a regular file" in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert os.path.exists(device + ".made_by.json") == existed


def test_one_lock_per_file_whatever_its_name(tmp_path):
    """Two runs into one file through a symlinked name both took "the" lock."""
    real = tmp_path / "store.zarr"
    real.mkdir()
    (tmp_path / "alias.zarr").symlink_to(real)
    with exclusive(real, "store"):
        with pytest.raises(JaxrockInputError, match="another run"):
            with exclusive(tmp_path / "alias.zarr", "store"):
                pass


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o077])
def test_outputs_keep_the_users_umask(tmp_path, umask):
    """Every CSV, netCDF and Markdown output was written 0600 (mkstemp's mode) whatever the umask."""
    old = os.umask(umask)
    try:
        path = write_atomically(tmp_path / "out.csv", lambda tmp: tmp.write_text("x\n"))
        opened = tmp_path / "opened.csv"
        opened.write_text("x\n")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == stat.S_IMODE(opened.stat().st_mode) == 0o666 & ~umask


def test_calibrate_refuses_a_slenderness_refused_everywhere_else(tmp_path):
    """`calibrate --tan-alpha 0.0005,0.1,0.2` was accepted (and printed as 0.001)."""
    r = invoke("calibrate", "--tan-alpha", "0.0005,0.1,0.2", "--out", tmp_path)
    assert r.exit_code == 2 and "--tan-alpha" in r.output and "0.001" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1


def test_calibration_table_says_when_the_papers_range_has_no_fit():
    """With no three tanα in [0.1, 0.3] the report printed the full fit as "fit over tanα ∈ [0.1, 0.3]"."""
    from jaxrock.analyses.calibration import fit_power_law
    from jaxrock.reports import CalibrationReport

    row = dict(tan_alpha=0.5, alpha=0.46, target_r2=0.5, cbar_calibrated=0.4, cbar_eq17=0.4, residual_rms=0.0, iterations=3)
    table = [row, {**row, "tan_alpha": 0.9, "alpha": 0.73}, {**row, "tan_alpha": 0.99, "alpha": 0.78}]
    fit = fit_power_law([0.46, 0.73, 0.78], [0.4, 0.9, 1.0])
    text = CalibrationReport(None, fit, None, table, None, None).format_table()
    assert "fit over tanα ∈ [0.5, 0.99]:" in text and "fit over tanα ∈ [0.1, 0.3]: none (fewer than 3" in text


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--scale", "3,1,2"], "--scale grid must be strictly increasing"),
        (["--model", "rigid,rigid"], "a model named twice"),
        (["--refine", "100"], "--refine = 100; valid: an integer in [0, 40]"),
    ],
)
def test_suite_refuses_what_would_give_a_wrong_least_scale(tmp_path, args, needle):
    """`suite elcentro --scale 3,1,2 --refine 2` gave least scale 2.25 where factor 2 overturns (the
    factors were taken in the order given); `--model rigid,rigid` was a traceback; `--refine 100`
    bisected to 2e-16 in 105 s."""
    base = {"--model": "rigid", "--height": "2", "--scale": "1,2,3", "--refine": "2"}
    base.update(dict(zip(args[::2], args[1::2])))
    r = invoke("suite", "elcentro", *[x for kv in base.items() for x in kv], "--out", tmp_path / "s", "-q", "--yes")
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not (tmp_path / "s" / "rigid.zarr").exists()


@pytest.mark.parametrize(
    "given, needle",
    [("/dev/full", "is not a regular file"), ("nowhere/", "names a folder"), (".", "names a folder"),
     ("theta.xyz", "matplotlib cannot write '.xyz' files")],
)
def test_simulate_plot_path_is_refused_before_the_run(tmp_path, monkeypatch, given, needle):
    """`--plot /dev/full` wrote /dev/full.png and exited 0; `--plot dir_that_does_not_exist/` wrote
    ./dir_that_does_not_exist.png."""
    monkeypatch.chdir(tmp_path)
    r = invoke("simulate", "--plot", given)
    assert r.exit_code == 2 and needle in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not os.path.exists(given.rstrip("/") + ".png") and not list(tmp_path.iterdir())


def test_simulate_plot_without_suffix_says_the_file_it_wrote(tmp_path):
    """`--plot noext` wrote noext.png but printed "wrote noext"."""
    r = invoke("simulate", "--plot", tmp_path / "noext", "--n-points", 50)
    assert r.exit_code == 0, r.output
    assert f"wrote {tmp_path / 'noext.png'}" in r.output and (tmp_path / "noext.png").is_file()
    r = invoke("simulate", "--plot", tmp_path / "p.png", "--n-points", 100_000_000)
    assert r.exit_code == 2 and "--n-points = 100000000; valid: an integer in [2, 1,000,000]" in r.output, r.output


def test_simulate_run_time_waits_for_the_result(monkeypatch):
    """A 154 s record run printed "run time 4.26 s": the timer stopped before JAX's asynchronous
    result was ready. The printed time now covers `block_until_ready`."""
    import jax

    calls = []
    real = jax.block_until_ready
    monkeypatch.setattr(jax, "block_until_ready", lambda x: calls.append(1) or real(x))
    r = invoke("simulate", "--accel-ratio", 3)
    assert r.exit_code == 0 and "run time" in r.output and calls, r.output


def _no_room(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


@pytest.mark.parametrize("where", ["batch results", "spectrum netCDF", "sweep store"])
def test_a_full_disk_is_one_line_and_leaves_no_temporary(tmp_path, monkeypatch, where):
    """ENOSPC (or a read-only disk, a quota, a file size limit) while writing batch results, a
    spectrum or a store was a traceback, and a spectrum left `tmp_<pid>_…` behind. Now one line,
    exit 2, and no temporary is left (finished work stays in its store or checkpoint)."""
    import xarray as xr

    from jaxrock.analyses import scenes
    from jaxrock.io import store

    monkeypatch.chdir(tmp_path)
    if where == "batch results":
        monkeypatch.setattr(scenes, "append_results", _no_room)
        r = invoke("batch", write(tmp_path / "b.csv", SCENES), "--out", tmp_path / "r.csv", "-q")
    elif where == "spectrum netCDF":
        def partial(self, path, **kw):
            open(path, "wb").write(b"CDF\x01")
            _no_room()
        monkeypatch.setattr(xr.Dataset, "to_netcdf", partial)
        r = invoke("spectrum", "--omega-ratio", "1:15:2", "--accel-ratio", "0.5:10:2", "--refine", 0, "--out", tmp_path / "spec", "-q")
    else:
        def half(tmp, sweep, history):
            tmp.mkdir()
            _no_room()
        monkeypatch.setattr(store, "_make", half)
        r = invoke("sweep", "--accel-ratio", "1:8:2", "--omega-ratio", "2:10:2", "--out", tmp_path / "s.zarr", "-q")
    assert r.exit_code == 2 and "cannot write" in r.output and "No space left on device" in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1, r.output
    assert not [p.name for p in tmp_path.rglob("tmp_*")]


@pytest.mark.parametrize("damage", ['{"key": {"mode": "quick"}, "rows": [{"a": 1', '{"rows": []}', '[1, 2]',
                                    '{"key": {"mode": "quick"}, "rows": [{"b": 2}]}', '{"key": {"mode": "quick"}, "rows": 3}'])
def test_a_damaged_kept_part_is_run_again(tmp_path, damage):
    """Issue 52: kept-step JSON files of `stability`/`work-precision` that were truncated or lacked
    keys were tracebacks (JSONDecodeError, KeyError); each such part now runs again, and a part
    kept whole is still read back, not run."""
    from jaxrock.numerics.kept import run_parts

    ran = []

    def run(part):
        ran.append(part)
        return [{"a": part, "b": 2 * part}]

    key = {"mode": "quick"}
    args = dict(name=str, desc="t", progress=False, columns=("a", "b"))
    assert run_parts([1, 2], run, tmp_path, key, **args) == [{"a": 1, "b": 2}, {"a": 2, "b": 4}]
    (tmp_path / "1.json").write_text(damage)
    ran.clear()
    assert run_parts([1, 2], run, tmp_path, key, **args) == [{"a": 1, "b": 2}, {"a": 2, "b": 4}]
    assert ran == [1]


@pytest.mark.parametrize("damage", ['{"mode": "quick", "version"', '{"mode": "quick"}', '{"mode": "quick", "version": "V", "findings": [{"x": 1}], "seconds": 1}'])
def test_a_damaged_kept_step_of_reproduce_is_run_again(tmp_path, monkeypatch, damage):
    """The same for `reproduce`'s kept steps (a truncated file or missing keys gave a KeyError)."""
    from jaxrock.paper import reproduce

    monkeypatch.setattr(reproduce, "_version", lambda: "V")
    path = tmp_path / "step.json"
    path.write_text(damage)
    assert reproduce._kept(path, "quick") is None


def test_work_precision_leaves_out_an_openseespy_that_cannot_load(tmp_path):
    """Issue 52: with OpenSeesPy installed but unable to load (its library missing a BLAS:
    "Failed to import openseespy on Linux"), `jaxrock work-precision` crashed. The OpenSees panels
    are now left out with one line saying why."""
    fake = tmp_path / "openseespy"
    fake.mkdir()
    (fake / "__init__.py").write_text("")
    (fake / "opensees.py").write_text("raise RuntimeError('Failed to import openseespy on Linux.')\n")
    code = "from jaxrock.numerics.work_precision import Settings; print(Settings.make(quick=True).opensees)"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "False", r.stderr
    assert "the OpenSees panels are left out: openseespy is installed but cannot load (RuntimeError: Failed to import" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_a_refused_run_leaves_no_empty_output_folder(tmp_path):
    """Issue 52: a run refused after its --out was checked left the empty folder it had made."""
    r = invoke("suite", tmp_path / "nosuch.AT2", "--model", "rigid", "--scale", "1,2", "--out", tmp_path / "new" / "deep", "-q")
    assert r.exit_code == 2 and "no such file or folder" in r.output, r.output
    assert not (tmp_path / "new").exists()


def test_suite_refuses_to_write_into_its_records_folder(tmp_path):
    """Issue 52: with --out the records folder, a rerun read the suite's own CSV outputs as records."""
    recs = tmp_path / "recs"
    recs.mkdir()
    (recs / "r.txt").write_text("".join(f"{i * 0.01:.2f} {0.3 * (i % 7 - 3)}\n" for i in range(300)))
    r = invoke("suite", recs, "--model", "rigid", "--scale", "1,2", "--out", recs, "-q", "--yes")
    assert r.exit_code == 2 and "is the records folder" in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert sorted(p.name for p in recs.iterdir()) == ["r.txt"]


def test_outputs_replace_only_files_jaxrock_wrote(tmp_path):
    """Issue 52's rule for every command: an output replaces a file jaxrock wrote (a netCDF or a
    figure names jaxrock in its first bytes; a CSV or a report starts as the new one will), never
    an unrelated file without --force, never through a symbolic link."""
    notes = write(tmp_path / "spec.nc", "my notes\n")
    args = ["spectrum", "--omega-ratio", "1:15:2", "--accel-ratio", "0.5:10:2", "--refine", 0, "--out", tmp_path / "spec", "-q"]
    r = invoke(*args)
    assert r.exit_code == 2 and "spec.nc: exists and was not written by jaxrock; pass --force" in r.output, r.output
    assert notes.read_text() == "my notes\n" and not (tmp_path / "spec.checkpoint").exists()
    assert invoke(*args, "--force").exit_code == 0
    r = invoke(*args)  # its own outputs: replaced without --force
    assert r.exit_code == 0, r.output
    assert b"jaxrock" in (tmp_path / "spec.png").read_bytes()[:65536]

    photo = write(tmp_path / "photo.png", "not a plot\n")
    r = invoke("simulate", "--plot", photo, "--n-points", 20)
    assert r.exit_code == 2 and "photo.png: exists and was not written by jaxrock" in r.output, r.output
    (tmp_path / "link.pdf").symlink_to(photo)
    r = invoke("simulate", "--plot", tmp_path / "link.pdf", "--n-points", 20, "--force")
    assert r.exit_code == 2 and "is a symbolic link" in r.output and photo.read_text() == "not a plot\n", r.output


def test_a_table_replaces_its_own_csv_only(tmp_path):
    from jaxrock.io.tables import write_table

    rows = [{"a": 1.0, "b": 2}]
    write_table(tmp_path / "t.csv", rows)
    write_table(tmp_path / "t.csv", rows)  # its own: the same header
    write(tmp_path / "other.csv", "x,y\n1,2\n")
    with pytest.raises(JaxrockInputError, match="other.csv: exists and was not written by jaxrock"):
        write_table(tmp_path / "other.csv", rows)
    assert (tmp_path / "other.csv").read_text() == "x,y\n1,2\n"
