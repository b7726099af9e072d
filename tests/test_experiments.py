"""The figure scripts in `experiments/`: each answers `--help` with its usage and an `--out`
option, and does no work (run in an empty folder, which stays empty: fig07 once ran a whole
calibration into a folder named `--help`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCRIPTS = sorted((Path(__file__).resolve().parents[1] / "experiments").glob("fig*.py"))


def test_every_experiment_script_answers_help_without_working(tmp_path):
    assert len(SCRIPTS) >= 8
    procs = {p.name: subprocess.Popen([sys.executable, str(p), "--help"], cwd=tmp_path, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True) for p in SCRIPTS}
    for name, proc in procs.items():
        out, _ = proc.communicate(timeout=240)
        assert proc.returncode == 0, (name, out)
        assert "usage:" in out and "--out" in out, (name, out)
    assert list(tmp_path.iterdir()) == []
