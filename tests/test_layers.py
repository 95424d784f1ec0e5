"""Arrows point down: no module imports one above it, not even inside a function.

The order is the README's layout table, bottom first: a module imports only modules listed
before it (a subpackage counts as one unit).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).parents[1] / "graybox"

#: Bottom first; a module may import only modules that come earlier in this list.
ORDER = [
    "_validation", "_progress", "_terms", "_latex", "_records",
    "_regressors", "_kernels", "_static_kernels", "_simulation", "_static", "_static_surface", "_gram",
    "_model", "_evaluate", "_ls", "_curves", "_surfaces", "_pareto", "_constraints", "_static_form",
    "_selection", "_semp", "_els", "_neural", "_convex", "_se", "_se_dsf", "_decide",
    "_residuals", "_uncertainty", "_bootstrap", "_io",
    "reference", "datasets", "_api",
    "plots", "experiments", "reproduce", "_cli", "__init__",
]


def _unit(path: Path) -> str:
    """The ORDER entry a file belongs to (a subpackage counts as one unit)."""
    rel = path.relative_to(PKG).with_suffix("").parts
    return rel[0]


def _imports(path: Path) -> set[str]:
    """ORDER units that a file imports, anywhere in it (module level or inside functions)."""
    rel = path.relative_to(PKG).with_suffix("").parts
    pkg = ["graybox", *rel[:-1]]  # the package the file is in
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names: list[list[str]] = []
        if isinstance(node, ast.ImportFrom):
            base = pkg[: len(pkg) - (node.level - 1)] if node.level else []
            target = base + (node.module.split(".") if node.module else [])
            if target == ["graybox"] and node.level:
                names = [["graybox", a.name] for a in node.names]
            else:
                names = [target]
        elif isinstance(node, ast.Import):
            names = [a.name.split(".") for a in node.names]
        for t in names:
            if t and t[0] == "graybox":
                out.add(t[1] if len(t) > 1 else "__init__")
    return out


FILES = sorted(p for p in PKG.rglob("*.py"))


def test_every_module_has_a_layer():
    units = {_unit(p) for p in FILES}
    assert units <= set(ORDER), f"modules without a layer: {sorted(units - set(ORDER))}"


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(PKG)))
def test_imports_point_down(path):
    me = _unit(path)
    rank = ORDER.index(me)
    up = [u for u in _imports(path) if u != me and u in ORDER and ORDER.index(u) > rank]
    assert not up, f"{path.relative_to(PKG)} ({me}) imports {sorted(up)}, which sit above it"
