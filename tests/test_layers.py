"""Arrows point down: no module imports one above it, not even inside a function.

The order is :data:`graybox._layers.LAYERS`, bottom first, the one place it is written; the
README's layout table is checked against it here too.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from graybox._layers import LAYERS

PKG = Path(__file__).parents[1] / "graybox"
README = Path(__file__).parents[1] / "README.md"
UNITS = [u for u, _, _ in LAYERS]
MODULES = {u: list(mods) for u, mods, _ in LAYERS}


def _place(parts: list[str]) -> tuple[int, int] | None:
    """(unit rank, module rank inside the unit) of a dotted path below graybox, or None if outside."""
    if not parts or parts[0] not in UNITS:
        return None
    unit = parts[0]
    mods = MODULES[unit]
    if len(parts) == 1 or parts[1] == "__init__":
        return UNITS.index(unit), len(mods)  # a subpackage's __init__ sits on top of its modules
    return UNITS.index(unit), mods.index(parts[1]) if parts[1] in mods else -1


def _rel(path: Path) -> list[str]:
    return list(path.relative_to(PKG).with_suffix("").parts)


def _imports(path: Path) -> set[tuple[str, ...]]:
    """Dotted targets below graybox that a file imports, anywhere in it."""
    rel = _rel(path)
    pkg = ["graybox", *rel[:-1]]
    out: set[tuple[str, ...]] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets: list[list[str]] = []
        if isinstance(node, ast.ImportFrom):
            base = pkg[: len(pkg) - (node.level - 1)] if node.level else []
            target = base + (node.module.split(".") if node.module else [])
            targets = [target + [a.name] for a in node.names]  # a name may be a module of that package
        elif isinstance(node, ast.Import):
            targets = [a.name.split(".") for a in node.names]
        for t in targets:
            if t and t[0] == "graybox":
                out.add(tuple(t[1:]) if len(t) > 1 else ("__init__",))
    return out


def _resolve(target: tuple[str, ...]) -> list[str]:
    """The unit (and module) an import reaches: `from graybox.core._terms import X` → [core, _terms];
    `from graybox import frols` reaches the package's __init__."""
    t = list(target)
    if t[0] not in UNITS:
        return ["__init__"]
    if len(t) >= 2 and t[1] in MODULES[t[0]]:
        return t[:2]
    return t[:1]


FILES = sorted(PKG.rglob("*.py"))


def test_every_module_has_a_layer():
    missing = []
    for p in FILES:
        rel = _rel(p)
        if rel[0] not in UNITS:
            missing.append("/".join(rel))
        elif len(rel) > 1 and rel[-1] != "__init__" and rel[1] not in MODULES[rel[0]]:
            missing.append("/".join(rel))
    assert not missing, f"modules without a layer in graybox/_layers.py: {missing}"


def test_every_layer_exists():
    for unit, mods, _ in LAYERS:
        assert (PKG / f"{unit}.py").exists() or (PKG / unit / "__init__.py").exists(), unit
        for m in mods:
            assert (PKG / unit / f"{m}.py").exists(), f"{unit}.{m}"


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(PKG)))
def test_imports_point_down(path):
    me = _place(_rel(path))
    assert me is not None
    up = []
    for target in _imports(path):
        there = _place(_resolve(target))
        if there is None:
            continue
        if there[0] > me[0] or (there[0] == me[0] and there[1] >= me[1] and _resolve(target) != _rel(path)):
            # the same unit: only modules listed before this one (its __init__ is on top)
            if there[0] == me[0] and _rel(path)[-1] == "__init__":
                continue
            up.append(".".join(_resolve(target)))
    assert not up, f"{path.relative_to(PKG)} imports {sorted(up)}, which sit above it in graybox/_layers.py"


def test_readme_layout_table_is_the_layer_order():
    """The README's layout table lists the units in the layer order, each with what it owns."""
    text = README.read_text(encoding="utf-8")
    rows = re.findall(r"^\| `graybox\.?([\w.]*)` \| (.*) \|$", text, re.M)
    documented = [(name or "__init__", owns) for name, owns in rows]
    expected = [(u, owns) for u, _, owns in LAYERS if not u.startswith("_") or u == "__init__"]
    assert [d[0] for d in documented] == [e[0] for e in reversed(expected)], \
        "README's layout table differs from graybox/_layers.py (write it with tests/test_layers.py's layout_table())"
    assert documented == list(reversed(expected))


def layout_table() -> str:
    """The README's layout table, top first, as written from graybox/_layers.py."""
    rows = [(u, owns) for u, _, owns in reversed(LAYERS) if not u.startswith("_") or u == "__init__"]
    lines = ["| package | owns |", "| --- | --- |"]
    lines += [f"| `graybox{'' if u == '__init__' else '.' + u}` | {owns} |" for u, owns in rows]
    return "\n".join(lines)


def test_import_graybox_loads_no_heavy_dependency():
    """`import graybox` is lazy: numba, cvxpy, pandas, matplotlib and scipy load on first use of a name."""
    import subprocess
    import sys

    code = ("import sys, graybox; heavy = [m for m in ('numba', 'cvxpy', 'pandas', 'matplotlib', 'scipy', 'dask', "
            "'distributed', 'control') if m in sys.modules]; print(','.join(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"import graybox loaded {out}"


#: Slow to import and wanted by few calls (scipy.signal alone about half a second, pandas about 0.4 s): below the
#: figures and the experiments they are imported inside the function that uses them, so that a name such as
#: ``gb.save``, ``gb.frols`` or ``gb.local_model`` (whose module imports the saved types and the layers under it)
#: does not load them all. pandas makes the result tables (``to_frame``, ``evaluate``), not the fits.
WHERE_USED = ("scipy.signal", "scipy.stats", "scipy.optimize", "control", "cvxpy", "matplotlib", "dask",
              "distributed", "pandas")
LAYERS_BELOW_FIGURES = UNITS[:UNITS.index("plots")]
#: Modules below the figures that import a dependency of WHERE_USED at module level, and why: each call of theirs
#: makes a table, and their results' fields are annotated ``pd.DataFrame`` (``typing.get_type_hints`` resolves
#: the annotation in the module's namespace).
IMPORTED_AT_TOP = {"estimation/_output_error.py": ("pandas",), "selection/_simulation_error_pruning.py": ("pandas",)}


@pytest.mark.parametrize("path", [p for p in sorted(PKG.rglob("*.py")) if _rel(p)[0] in LAYERS_BELOW_FIGURES],
                         ids=lambda p: str(p.relative_to(PKG)))
def test_slow_dependencies_load_where_used(path):
    """No module below the figures imports a slow, rarely needed dependency when it is itself imported."""
    top = []
    for node in ast.parse(path.read_text(encoding="utf-8")).body:  # module level only, not inside a function
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            top += [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
        elif isinstance(node, ast.Import):
            top += [a.name for a in node.names]
    allowed = IMPORTED_AT_TOP.get(str(path.relative_to(PKG)), ())
    bad = sorted({m for m in top for h in WHERE_USED if (m == h or m.startswith(h + ".")) and h not in allowed})
    assert not bad, f"{path.relative_to(PKG)} imports {bad} at module level"


def test_every_public_name_resolves():
    import graybox as gb

    for name in gb.__all__:
        assert getattr(gb, name) is not None, name
    # dir() (tab completion) lists every public name, __version__ included (it was in __all__ only)
    assert set(gb.__all__) <= set(dir(gb)), set(gb.__all__) - set(dir(gb))
    with pytest.raises(AttributeError, match="module 'graybox' has no attribute 'nope'"):
        gb.nope  # noqa: B018
