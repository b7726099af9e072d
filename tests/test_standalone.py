"""A clone stands alone: no file names a path outside the repository (its code, tests, notebooks,
benchmarks and docs run with nothing beside it)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEXT = {".py", ".md", ".ipynb", ".toml", ".cfg", ".txt", ".yml", ".yaml", ".json", ".cff", ""}
SKIP = {".git", ".venv", "out", "build", "dist", "__pycache__", ".pytest_cache"}
# a folder beside the clone (../shared, ../data, …) or an absolute path of a machine
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
    assert OUTSIDE.search("see ../shared/SPEC.md") and OUTSIDE.search("/work/main/x") and not OUTSIDE.search("jaxrock/data/records")
