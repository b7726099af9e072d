"""What a release carries: a version from git tags that names the commit (`jaxrock --version`,
`jaxrock.__version__`, the provenance of every file), the license pyproject declares, a citation of
the software and the paper, and the entry points (`jaxrock`, `python -m jaxrock`)."""

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PEP440 = re.compile(r"^\d+(\.\d+)*((a|b|rc)\d+)?(\.post\d+)?(\.dev\d+)?(\+[a-z0-9.]+)?$")


def _run(*args, cwd=ROOT):
    return subprocess.run(args, capture_output=True, text=True, cwd=cwd, timeout=120)


def test_version_is_the_same_everywhere():
    import jaxrock
    from jaxrock.cache import package_version

    version = package_version()
    assert PEP440.match(version), version
    assert jaxrock.__version__ == version
    r = _run(sys.executable, "-m", "jaxrock", "--version")
    assert r.returncode == 0 and r.stdout.strip() == f"jaxrock {version}", r


@pytest.mark.skipif(not (ROOT / ".git").exists() or shutil.which("git") is None, reason="a source tree without git history")
def test_each_commit_after_a_tag_has_its_own_version(tmp_path):
    """setuptools-scm's version of the checkout, of a commit after it, and of a tag: three versions,
    the tag's plain. (The installed `jaxrock --version` is this version at install time.)"""
    setuptools_scm = pytest.importorskip("setuptools_scm")
    clone = tmp_path / "clone"
    assert _run("git", "clone", "-q", "--no-checkout", str(ROOT), str(clone)).returncode == 0
    env = ["-c", "user.name=t", "-c", "user.email=t@example.org"]
    first = setuptools_scm.get_version(root=str(clone))
    assert _run("git", *env, "commit", "-q", "--allow-empty", "-m", "next", cwd=clone).returncode == 0
    second = setuptools_scm.get_version(root=str(clone))
    assert _run("git", *env, "tag", "-a", "v9.8.7", "-m", "a release", cwd=clone).returncode == 0
    tagged = setuptools_scm.get_version(root=str(clone))
    assert first != second and PEP440.match(first) and PEP440.match(second), (first, second)
    assert tagged == "9.8.7"


def test_plain_jaxrock_prints_help_and_exits_0():
    r = _run(sys.executable, "-m", "jaxrock")
    assert r.returncode == 0, r
    assert r.stdout.startswith("Usage: ") and "spectrum" in r.stdout and "--version" in r.stdout


def test_license_citation_and_metadata_agree():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert meta["license"] == "MIT" and (ROOT / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    assert (ROOT / "jaxrock" / "py.typed").exists() and "Typing :: Typed" in meta["classifiers"]
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert "license: MIT" in cff and "doi: 10.1002/eqe.2406" in cff  # the software, and the paper it implements
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert "## [Unreleased]" in changelog
    released = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", changelog, flags=re.M)
    assert released and re.search(rf"^version: {re.escape(released[0])}$", cff, flags=re.M), "CITATION.cff cites the latest release"


def test_declared_floors_are_the_checked_minimums():
    """Each dependency's floor in pyproject.toml is its pin in .ci/minimums.txt, the set CI installs
    and runs the smoke tests on (.ci/minimums): a floor raised or lowered without that check fails."""
    from packaging.requirements import Requirement
    from packaging.version import Version

    deps = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    floors = {}
    for dep in deps:
        req = Requirement(dep)
        (spec,) = [s for s in req.specifier if s.operator == ">="]
        floors[req.name.lower()] = Version(spec.version)
    pins = {}
    for line in (ROOT / ".ci" / "minimums.txt").read_text(encoding="utf-8").splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            pins[name.strip().lower()] = Version(version)
    assert pins.pop("jaxlib") == pins["jax"]  # jaxlib moves with jax
    assert pins == floors
    smoke = [line for line in (ROOT / ".ci" / "smoke_tests.txt").read_text(encoding="utf-8").splitlines()
             if line.strip() and not line.startswith("#")]
    assert smoke and all((ROOT / path).is_file() for path in smoke)


def test_an_editable_install_names_the_commit_that_runs(tmp_path, monkeypatch):
    """After a commit or a pull, an editable install's version (fixed at install) gains
    `.head.<commit>`: a store or checkpoint made before is not resumed as if it matched. The
    checkout's HEAD is read from `.git` for a branch, a packed ref and a detached HEAD."""
    from jaxrock import cache
    from jaxrock._version import commit_id, version

    git = tmp_path / ".git"
    (git / "refs" / "heads").mkdir(parents=True)
    (git / "HEAD").write_text("ref: refs/heads/main\n")
    (git / "refs" / "heads" / "main").write_text("a" * 40 + "\n")
    assert cache._checkout_head(git) == "a" * 40
    (git / "refs" / "heads" / "main").unlink()
    (git / "packed-refs").write_text("# pack-refs with: peeled\n" + "b" * 40 + " refs/heads/main\n")
    assert cache._checkout_head(git) == "b" * 40
    (git / "HEAD").write_text("c" * 40 + "\n")
    assert cache._checkout_head(git) == "c" * 40
    assert cache._checkout_head(tmp_path / "nothing") is None

    monkeypatch.setattr(cache, "_checkout_head", lambda: "d" * 40)
    moved = cache.package_version()
    assert moved.startswith(version) and moved.endswith(".head." + "d" * 9) and PEP440.match(moved), moved
    if commit_id:
        monkeypatch.setattr(cache, "_checkout_head", lambda: commit_id.removeprefix("g") + "0" * 20)
        assert cache.package_version() == version  # the installed commit: the installed version
    monkeypatch.setattr(cache, "_checkout_head", lambda: None)
    assert cache.package_version() == version  # an installed wheel
