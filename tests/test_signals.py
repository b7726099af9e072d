"""Real signals sent to real `jaxrock` processes: a stop keeps every finished batch, never
crashes, exits 130 with the command that resumes, and the resumed run ends with the result of an
uninterrupted one."""

from __future__ import annotations

import re
import signal
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from helpers import Watch as _Watch
from helpers import jaxrock_process as _jaxrock


def _spectrum_args(out):
    return ["spectrum", "--omega-ratio", "1:15:4", "--accel-ratio", "0.5:10:4", "--batch-size", 4, "--refine", 3, "--out", out]


def _interrupt(args, cwd, pattern, sig=signal.SIGINT):
    w = _Watch(_jaxrock(*args, cwd=cwd))
    w.wait_for(pattern)
    w.proc.send_signal(sig)
    return w.finish()


def test_sigint_during_refinement_keeps_the_grid_and_resumes_without_recomputing_it(tmp_path):
    """The grid is done (16/16) and the refinement compiles and runs: SIGINT there kept nothing
    and crashed (exit 139) before; now it exits 130, keeps all 16 cells, and the rerun only
    refines, its grid the kept cells bit for bit."""
    out = tmp_path / "sp"
    rc, _, err = _interrupt(_spectrum_args(out), tmp_path, r"16/16")
    assert rc == 130, err[-2000:]
    assert "interrupted: 16 of 16 cells kept" in err and "resume with: jaxrock spectrum" in err
    assert not Path(f"{out}.nc").exists() and Path(f"{out}.checkpoint").is_dir()
    with xr.open_zarr(f"{out}.checkpoint", chunks=None) as ck:
        kept = ck["max_theta"].values.ravel()
    rc, stdout, err = _Watch(_jaxrock(*_spectrum_args(out), cwd=tmp_path)).finish()
    assert rc == 0, err[-2000:]
    assert not re.search(r"\b[0-9]/16\b", err), "the resumed run recomputed grid cells"
    assert not Path(f"{out}.checkpoint").exists()
    with xr.open_dataset(f"{out}.nc", engine="scipy") as a:
        grid = a["max_theta"].values.ravel()
    np.testing.assert_array_equal(kept, grid)


@pytest.mark.slow
@pytest.mark.parametrize("moment, sig", [(r"0/16", signal.SIGINT), (r"[48]/16", signal.SIGTERM)])
def test_signal_during_compile_or_mid_grid_exits_130_and_resumes_to_the_uninterrupted_spectrum(tmp_path, moment, sig):
    """Stopped while compiling or between batches, resumed, the spectrum equals an uninterrupted
    run's bit for bit (the grid and the refined lines)."""
    out, ref = tmp_path / "sp", tmp_path / "ref"
    uninterrupted = _Watch(_jaxrock(*_spectrum_args(ref), "--no-checkpoint", cwd=tmp_path))
    rc, _, err = _interrupt(_spectrum_args(out), tmp_path, moment, sig)
    assert rc == 130, err[-2000:]
    kept = int(re.search(r"interrupted: (\d+) of 16 cells kept", err).group(1))
    assert kept % 4 == 0 and kept >= 4  # the batch in progress finishes first
    rc, _, err = _Watch(_jaxrock(*_spectrum_args(out), cwd=tmp_path)).finish()
    assert rc == 0 and f"{kept}/16" in err
    assert uninterrupted.finish()[0] == 0
    with xr.open_dataset(f"{out}.nc", engine="scipy") as a, xr.open_dataset(f"{ref}.nc", engine="scipy") as b:
        for k in ("max_theta", "overturned", "uplifted", "status", "uplift_boundary", "overturn_boundary"):
            np.testing.assert_array_equal(a[k].values, b[k].values, err_msg=k)


def test_sigterm_mid_batch_keeps_finished_rows_and_resume_completes_them(tmp_path):
    """A batch stopped by SIGTERM (a scheduler's stop) after its first chunk keeps the rows it
    wrote, names the command with --resume, and the resumed run writes every row once, in order."""
    rows = ["height,tan_alpha,accel_ratio,omega_ratio"] + [f"{2 + i % 5},0.2,{1.5 + 0.1 * i},{2 + i % 7}" for i in range(48)]
    (tmp_path / "scenes.csv").write_text("\n".join(rows) + "\n")
    args = ["batch", "scenes.csv", "--out", "results.csv", "--chunk-size", 8]
    rc, _, err = _interrupt(args, tmp_path, r"8/48", signal.SIGTERM)
    assert rc == 130, err[-2000:]
    kept = int(re.search(r"interrupted: (\d+) rows kept in results.csv", err).group(1))
    assert 8 <= kept < 48 and kept % 8 == 0
    assert "resume with: jaxrock batch scenes.csv --out results.csv --chunk-size 8 --resume" in err
    rc, stdout, err = _Watch(_jaxrock(*args, "--resume", cwd=tmp_path)).finish()
    assert rc == 0, err[-2000:]
    assert f"{48 - kept} run in 1 group(s), {kept} skipped" in stdout
    lines = (tmp_path / "results.csv").read_text().splitlines()
    assert [int(line.split(",")[0]) for line in lines[1:]] == list(range(1, 49))
