"""What starting jaxrock costs a process (`jaxrock/__init__`, `jaxrock.runtime`): importing jaxrock
and its command line imports no JAX, so that `--help` and refused arguments answer at once; JAX,
whenever it is imported, runs in float64 with the compilation cache; every public name resolves.
Each check runs in a fresh interpreter (this process has long imported JAX)."""

from __future__ import annotations

import os

import pytest

from helpers import fresh_cli, fresh_python


@pytest.mark.parametrize("args, code", [
    (["--help"], 0),
    (["spectrum", "--help"], 0),
    (["simulate", "--tan-alpha", "2"], 2),  # jaxrock's own range check
    (["simulate", "--height", "-1"], 2),
    (["spectrum", "--omega-ratio", "1:15:0"], 2),
    (["simulate", "--model", "concrete"], 2),  # click's choice check
    (["spectrum", "--accel-ratio", "abc"], 2),  # not a number
])
def test_help_and_refused_arguments_import_no_jax(args, code):
    """`--help` and a refused argument end (exit 0 / 2) without importing JAX or the other heavy
    libraries: the help and the checks come from JAX-free modules (`jaxrock.scene`,
    `jaxrock.outputs`, `jaxrock._validate`)."""
    out = fresh_cli(args)
    assert out == {"code": code, "heavy": []}


def test_a_run_still_imports_what_it_needs():
    """The check above can fail: a command that runs a scene does import JAX (and answers)."""
    out = fresh_cli(["simulate", "--accel-ratio", "3", "--omega-ratio", "4"])
    assert out["code"] in (0, None) and {"jax", "equinox", "diffrax"} <= set(out["heavy"])


@pytest.mark.parametrize("order", ["jaxrock first, then jax by the user", "jax first", "jaxrock's names first"])
def test_jax_runs_in_float64_with_the_cache_whoever_imports_it(order, tmp_path):
    """float64 and the cache folder are set the moment JAX is imported, before any array exists,
    whatever the order; nothing is written to the environment (child processes keep theirs)."""
    first = {"jaxrock first, then jax by the user": "import jaxrock\nimport jax",
             "jax first": "import jax\nimport jaxrock",
             "jaxrock's names first": "import jaxrock as jr\njr.Block\nimport jax"}[order]
    out = fresh_python(first + """
import json, os
import jax.numpy as jnp
print(json.dumps({"dtype": str(jnp.asarray(1.0).dtype), "cache": jax.config.jax_compilation_cache_dir,
                  "env": sorted(k for k in os.environ if k.startswith("JAX_"))}))
""", env={"JAXROCK_CACHE_DIR": str(tmp_path)})
    import jax

    assert out["dtype"] == "float64"
    assert out["cache"] == str(tmp_path / "xla" / f"jaxrock-{_version()}-jax-{jax.__version__}")
    assert out["env"] == sorted(k for k in os.environ if k.startswith("JAX_"))


def _version() -> str:
    """The cache folder's version: the release part of jaxrock's (builds between two releases share it)."""
    from jaxrock.cache import _release

    return _release()


def test_every_public_name_resolves():
    """`__all__` (imported on first use) names real objects, `from jaxrock import *` takes them
    all, submodules resolve as attributes, and a wrong name is an AttributeError."""
    out = fresh_python("""
        import json
        import jaxrock as jr
        names = {n: type(getattr(jr, n)).__name__ for n in jr.__all__}
        ns = {}
        exec("from jaxrock import *", ns)
        try:
            jr.no_such_name
            missing = "resolved"
        except AttributeError as e:
            missing = str(e)
        print(json.dumps({"names": names, "star": sorted(set(jr.__all__) - set(ns)), "scene": jr.scene.__name__,
                          "missing": missing, "dir": sorted(set(jr.__all__) - set(dir(jr)))}))
    """)
    assert out["star"] == [] and out["dir"] == []
    assert out["scene"] == "jaxrock.scene"
    assert out["missing"] == "module 'jaxrock' has no attribute 'no_such_name'"
    assert out["names"]["simulate"] == "function" and out["names"]["RigidModel"] in ("type", "_ModuleMeta")
    assert len(out["names"]) > 50
