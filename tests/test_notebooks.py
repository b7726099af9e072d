"""The research notebooks are stored as CI runs them: without outputs, with a quick mode.

Running them is `pytest --nbmake notebooks/` (the `notebooks` extra; `.ci/run` does it, in quick
mode through notebooks/conftest.py); this file checks only what that run cannot see."""

import json
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.ipynb"))
RESEARCH = [p for p in NOTEBOOKS if p.name[:2].isdigit()]


def test_research_notebooks_exist():
    assert len(RESEARCH) >= 3, [p.name for p in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_stored_without_outputs(path):
    nb = json.loads(path.read_text())
    for cell in nb["cells"]:
        assert "id" in cell
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [] and cell["execution_count"] is None, f"{path.name}: a cell has outputs"


@pytest.mark.parametrize("path", RESEARCH, ids=lambda p: p.name)
def test_quick_mode_and_run_time(path):
    """Each research notebook reads the quick switch in a cell tagged `parameters` and states its
    full-mode run time on a 2-core CPU in its introduction."""
    nb = json.loads(path.read_text())
    params = [c for c in nb["cells"] if "parameters" in c["metadata"].get("tags", [])]
    assert len(params) == 1 and "JAXROCK_NOTEBOOK_QUICK" in "".join(params[0]["source"])
    intro = "".join(nb["cells"][0]["source"])
    assert intro.startswith("# ") and "**Question.**" in intro and "**Run time**" in intro and "2-core CPU" in intro
