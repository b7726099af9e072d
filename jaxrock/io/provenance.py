"""How a result was made: a description of everything that determines its numbers (package
version, model and every parameter, excitation kind, grid, integrator settings), written into
stores and result files, and compared before a store or a results file is resumed.

A description is a flat dict of strings: ``{"jaxrock": "0.1.0", "model": "RigidModel",
"model.block.height": "10.0", …}``. Array leaves of up to 8 numbers are written out; larger ones
(a column's matrices, a grid) by their size and a SHA-256 digest of their bytes.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import jax
import numpy as np

from .._validate import JaxrockInputError
from ..cache import package_version
from .files import write_atomically


def value_text(x) -> str:
    a = np.asarray(x)
    if a.size <= 8:
        return np.array2string(a.ravel() if a.ndim else a, precision=17, separator=",")
    return f"{a.dtype}{list(a.shape)} sha256:{hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()[:16]}"


def _leaves(prefix: str, tree) -> dict[str, str]:
    """Every array leaf of a pytree (an equinox Module) by its path, and its structure (static
    fields such as a column's element count) as one entry."""
    out = {prefix: type(tree).__name__}
    leaves, treedef = jax.tree_util.tree_flatten_with_path(tree)
    out[f"{prefix} structure"] = hashlib.sha256(str(treedef).encode()).hexdigest()[:16]
    for path, leaf in leaves:
        out[prefix + jax.tree_util.keystr(path)] = value_text(leaf)
    return out


def describe(*, model, excitation: str, integrator=None, grid: dict | None = None) -> dict[str, str]:
    """The description of a run: `excitation` names the excitation kind (and a record's content
    digest); `grid` maps axis names to their values."""
    d = {"jaxrock": package_version(), "excitation": excitation}
    d.update(_leaves("model", model))
    d["integrator"] = "the model's default" if integrator is None else repr(integrator)
    for name, values in (grid or {}).items():
        d[f"grid {name}"] = value_text(values)
    return d


def file_attrs(model, integrator=None) -> dict:
    """Attributes that say how a result file was made: CF's conventions and references, package and JAX versions, the integrator
    and its settings, the model's energy loss (η of the rigid model or c̄ of the spring model) and
    the full description (`describe`, as JSON in `made_by`)."""
    from .cf import CONVENTIONS, references

    attrs = {
        "Conventions": CONVENTIONS,
        "references": references(),
        "source": f"jaxrock {package_version()} (jax {jax.__version__})",
        "jaxrock_version": package_version(),
        "jax_version": jax.__version__,
        "integrator": repr(model.default_integrator() if integrator is None else integrator),
    }
    if hasattr(model, "eta"):
        attrs["eta"] = float(np.asarray(model.eta))
    if hasattr(model, "cbar"):
        attrs["cbar"] = float(np.asarray(model.cbar))
    return attrs


def command_line(argv: list[str]) -> str:
    """A CF `history` entry: UTC time and the command, quoted so that it can be pasted back."""
    import shlex
    from datetime import datetime, timezone

    return f"{datetime.now(timezone.utc):%Y-%m-%dT%H:%M:%SZ} jaxrock " + " ".join(shlex.quote(a) for a in argv)


def refuse_if_different(made: dict[str, str], wanted: dict[str, str], what: str, fresh: str) -> None:
    """One line naming up to three differences between how `what` was made and this run."""
    diff = differences(made, wanted)
    if diff:
        shown = ", ".join(f"{k}: {made.get(k, '—')} → {wanted.get(k, '—')}" for k in diff[:3])
        more = f" and {len(diff) - 3} more" if len(diff) > 3 else ""
        raise JaxrockInputError(f"{what} was made by a different run ({shown}{more}); {fresh}")


def differences(made: dict[str, str], wanted: dict[str, str]) -> list[str]:
    """Names of the entries that differ (or exist on one side only), in a stable order."""
    keys = sorted(set(made) | set(wanted))
    return [k for k in keys if made.get(k) != wanted.get(k)]


def to_json(d: dict[str, str]) -> str:
    return json.dumps(d, sort_keys=True, ensure_ascii=False)


def write_description(file: Path, d: dict[str, str]) -> None:
    """Write a description (JSON) under a temporary name and rename it: never half-written."""
    write_atomically(file, lambda tmp: tmp.write_text(to_json(d), encoding="utf-8"))


def check_description(file: Path, wanted: dict[str, str], what: str, fresh: str) -> None:
    """Refuse, in one line, `what` unless its description `file` is readable and equals `wanted`."""
    try:
        made = json.loads(Path(file).read_text(encoding="utf-8"))
        if not isinstance(made, dict):
            raise ValueError("not a description")
    except Exception as e:  # missing, not a folder, garbled: all one answer
        raise JaxrockInputError(f"{what}: no readable description {Path(file).name} ({type(e).__name__}: {e}); {fresh}") from None
    refuse_if_different(made, wanted, what, fresh)


__all__ = ["check_description", "command_line", "describe", "differences", "file_attrs", "package_version", "refuse_if_different",
           "to_json", "value_text", "write_description"]
