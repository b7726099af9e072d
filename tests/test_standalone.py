"""A clone stands alone: no file names a path outside the repository (its code, tests, notebooks,
benchmarks and docs run with nothing beside it)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEXT = {".py", ".md", ".ipynb", ".toml", ".cfg", ".txt", ".yml", ".yaml", ".json", ".cff", ""}
SKIP = {".git", ".venv", "out", "build", "dist", "__pycache__", ".pytest_cache", ".cache", "site"}  # .cache: mkdocs-jupyter's
# a folder beside the clone (the reference material, data or tools a developer had there) or an
# absolute path of a machine
OUTSIDE = re.compile(r"\.\./(?:shared|data|\.library)\b|/work/|/home/\w|/root/|/Users/\w|[A-Z]:\\\\Users")


def _files():
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if any(part in SKIP or part.endswith(".egg-info") for part in rel.parts) or not path.is_file():
            continue
        if path.suffix.lower() in TEXT or rel.parts[0] == ".ci":
            yield rel, path


def test_no_file_names_a_path_outside_the_repository():
    hits = []
    for rel, path in _files():
        if path == Path(__file__).resolve():
            continue  # its own patterns
        for lineno, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), start=1):
            if OUTSIDE.search(line):
                hits.append(f"{rel}:{lineno}: {line.strip()[:120]}")
    assert not hits, "\n".join(hits)


def test_the_scan_sees_the_repository():
    """The scan above reads the files it should (a scan of nothing passes trivially)."""
    seen = {str(rel) for rel, _ in _files()}
    assert {"README.md", "pyproject.toml", "jaxrock/__init__.py", "tests/conftest.py", ".ci/run"} <= seen
    assert any(s.startswith("notebooks/") and s.endswith(".ipynb") for s in seen)
    beside = "/".join(["..", "shared", "SPEC.md"])  # spelt in pieces: this file names no such path itself
    assert OUTSIDE.search(f"see {beside}") and OUTSIDE.search("/".join(["", "work", "main", "x"]))
    assert not OUTSIDE.search("jaxrock/data/records")


def test_readme_commands_are_the_ones_ci_runs():
    """The README's first screen gives two commands (install + the main job on its default, install +
    the tests); .ci/run runs exactly those, verbatim, in a copy with nothing beside it, checks the
    first one's files, and then the slow set and the notebooks."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("readme_commands", ROOT / ".ci" / "readme_commands.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    run, test = module.commands(readme)
    assert readme.index("```bash") < 1200, "the commands are on the README's first screen"
    assert "pip install -e ." in run and run.endswith("jaxrock spectrum")
    assert "pip install -e '.[test]'" in test and test.endswith("python -m pytest -q")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    for needle in ('.ci/readme_commands.py', 'bash -c "${CMDS[0]}"', 'bash -c "${CMDS[1]}"', "out/spectrum.nc out/spectrum.png",
                   "-m slow", "--nbmake notebooks/"):
        assert needle in ci, needle
    assert "-m 'not slow and not study'" in (ROOT / "pyproject.toml").read_text(encoding="utf-8")  # the README's command runs the default set
