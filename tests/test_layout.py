"""The package's import graph reads top-down (docs/development.md, "Layout"): a module imports only from its own
layer or the layers below it — front ends → analyses → input/output → models → protocol → values →
vocabulary → internals — so that, e.g., a model never reaches for an analysis and the I/O never for a figure."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "jaxrock"

# layer of each module (dotted name below jaxrock), highest first; a package's modules share its layer
LAYERS = [
    ("front ends", ("cli", "paper", "numerics", "reports", "plotting", "__main__")),
    ("analyses", ("analyses",)),
    ("input/output", ("io",)),
    ("models", ("rigid", "spring", "construct")),
    ("protocol", ("model", "bookkeeping", "sensitivity")),
    ("values", ("geometry", "excitation", "results", "intensity")),
    ("vocabulary", ("scene", "outputs")),  # words and defaults, without JAX
    # _version: written by setuptools-scm at install time
    ("internals", ("_validate", "_linalg", "_rootfind", "interrupt", "cache", "runtime", "__init__", "_version")),
]
RANK = {name: rank for rank, (_, names) in enumerate(LAYERS) for name in names}


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        yield path, parts


def _imports(path: Path, parts: tuple[str, ...]):
    """The jaxrock modules a file imports (the first name below jaxrock), relative or absolute."""
    package = parts[:-1] if parts[-1] != "__init__" else parts[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
                target = (*base, *(node.module.split(".") if node.module else ()))
                names = [target] if node.module else [(*base, a.name) for a in node.names]
            elif node.module and node.module.split(".")[0] == "jaxrock":
                names = [tuple(node.module.split(".")[1:])]
            else:
                continue
            for t in names:
                if t:
                    yield t[0], node.lineno


@pytest.mark.parametrize("path,parts", list(_modules()), ids=lambda x: "/".join(x) if isinstance(x, tuple) else "")
def test_imports_go_down_the_layers(path, parts):
    if parts == ("__init__",):
        return  # the public API re-exports every layer
    own = RANK[parts[0]]
    up = [(top, line) for top, line in _imports(path, parts) if RANK.get(top, own) < own]
    assert not up, f"{'/'.join(parts)} imports upward: " + ", ".join(f"{t} (line {n})" for t, n in up)


def test_static_tools_see_the_public_api():
    """`jaxrock/__init__.py` loads its names lazily (`_EXPORTS`, PEP 562), which static tools cannot
    follow; its `if _TYPE_CHECKING:` block imports the same names explicitly (`X as X`, a re-export
    to type checkers). The two lists are one: every exported name from its module, nothing else."""
    tree = ast.parse((ROOT / "__init__.py").read_text())
    value = next(n.value for n in tree.body if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", None) == "_EXPORTS")
    exports = eval(compile(ast.Expression(value), "_EXPORTS", "eval"), {"__builtins__": {}, "dict": dict})  # literals and dict.fromkeys
    block = next(n for n in tree.body if isinstance(n, ast.If) and getattr(n.test, "id", None) == "_TYPE_CHECKING")
    typed = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom) and node.level == 1, ast.dump(node)
        for alias in node.names:
            assert alias.asname == alias.name, f"{alias.name} must be re-exported as itself (`{alias.name} as {alias.name}`)"
            typed[alias.name] = node.module
    assert typed == exports
