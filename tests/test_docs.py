"""The README and the getting-started page are one screen and a first hour: every code block in them
runs (Python blocks in a fresh interpreter, `jaxrock` lines as commands, in a scratch folder), the
README stays about one screen, and the documentation site builds with warnings as errors (a broken
reference, an undocumented or mistyped parameter in a docstring, a missing page)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
GETTING_STARTED = ROOT / "docs" / "getting-started.md"


def blocks(path: Path, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", path.read_text(encoding="utf-8"), flags=re.S | re.M)


def commands(path: Path) -> list[str]:
    """The `jaxrock ...` lines of a page's bash blocks (install lines are CI's: .ci/run runs them)."""
    return [line.split("  #")[0].strip() for block in blocks(path, "bash") for line in block.splitlines()
            if line.strip().startswith("jaxrock ")]


def _run_cli(line: str, cwd: Path):
    """One documented command line, verbatim, as `python -m jaxrock ...` (the interpreter under test)."""
    r = subprocess.run([sys.executable, "-m", "jaxrock", *shlex.split(line)[1:]], cwd=cwd, capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, (line, r.stdout[-2000:], r.stderr[-2000:])


def test_readme_is_one_screen_and_says_the_essentials():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150
    for must in ("## In Python", "## On the command line", "## How to cite", "mkdocs serve", "docs/getting-started.md"):
        assert must in text, must
    for link in re.findall(r"\]\(([^)#]+)\)", text):  # every relative link points at a file of the repository
        if not link.startswith("http"):
            assert (ROOT / link).exists(), link
    assert len(blocks(README, "python")) == 1 and len(commands(README)) >= 6


# getting-started: 55 s cold in the default run (a spectrum, then the Python blocks), the slow set; README's (29 s) stays
@pytest.mark.parametrize("page", [README, pytest.param(GETTING_STARTED, marks=pytest.mark.slow)], ids=["README", "getting-started"])
def test_python_blocks_run(page, tmp_path):
    """Each page's Python blocks, in order, in one fresh interpreter (a later block may use an
    earlier one's file: getting-started loads the spectrum its first command wrote)."""
    if page == GETTING_STARTED:  # its first command writes the file its first Python block reads
        for line in commands(page):
            if line.startswith("jaxrock spectrum"):
                _run_cli(line, tmp_path)
    code = "\n\n".join(blocks(page, "python"))
    assert code.strip()
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "nan" not in r.stdout.lower(), r.stdout


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("page", [README, GETTING_STARTED], ids=["README", "getting-started"])
def test_cli_lines_run(page, tmp_path):
    """Every `jaxrock` line of the page's bash blocks exits 0 from a scratch folder."""
    lines = commands(page)
    assert lines
    for line in lines:
        _run_cli(line, tmp_path)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_docs_site_builds_strict(tmp_path):
    """`mkdocs build --strict` (mkdocs.yml says strict too): API pages from the docstrings, the CLI
    reference from the commands, the notebooks as tutorials; any warning fails."""
    mkdocs = shutil.which("mkdocs", path=str(Path(sys.executable).parent)) or shutil.which("mkdocs")
    if mkdocs is None:
        pytest.skip("mkdocs is not installed (pip install -e '.[docs]')")
    r = subprocess.run([mkdocs, "build", "--strict", "--site-dir", str(tmp_path / "site")], cwd=ROOT, capture_output=True,
                       text=True, timeout=800, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert r.returncode == 0, r.stderr[-4000:]
    assert (tmp_path / "site" / "api" / "models" / "index.html").exists()
    cli = (tmp_path / "site" / "cli" / "index.html").read_text(encoding="utf-8")
    assert "jaxrock record-spectrum" in cli and "--accel-ratio" in cli
