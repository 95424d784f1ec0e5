"""The notebooks in notebooks/ run end to end, in their quick mode, and say what their text claims.

The suite executes each notebook once, as the documentation site shows it: the Sphinx build the suite starts
(tests/conftest.py) runs every notebook in its own kernel with ``QUICK = True``, and two hidden cells make the checks
of tests/_notebook_checks.py on the notebook's namespace there and write their verdict, which the tests below read
(a notebook's warnings too). No second execution: the build alone ran each notebook for a minute of CPU, the
suite's in-process runs of them another half (BENCHMARKS.md).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from _notebook_checks import CHECKS, EXPECTED_WARNINGS
from conftest import finish_site_build, site_build


NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
NAMES = [
    "01_black_box.ipynb",
    "02_gray_box_convex.ipynb",
    "03_simulation_error.ipynb",
    "04_buck_converter.ipynb",
    "05_constraint_variants.ipynb",
    "06_miso.ipynb",
    "07_control.ipynb",
]


def check_committed(name: str) -> None:
    """Notebook ``name`` is committed with its outputs cleared, its first code cell setting ``QUICK``."""
    nb = json.loads((NOTEBOOKS / name).read_text(encoding="utf-8"))
    assert nb["nbformat"] == 4
    cells = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert cells, f"{name} has no code cells"
    for c in cells:
        assert c["outputs"] == [] and c["execution_count"] is None, f"{name}: a code cell has outputs"
    assert "".join(cells[0]["source"]).strip().startswith("QUICK ="), f"{name}: the first code cell must set QUICK"
    # nbformat 4.5 requires a unique id per cell: 06 and 07 had none, 05 four cells without one, which nbformat (and
    # so jupyter nbconvert --execute, nbclient) warned of as "will become a hard error" on reading them
    ids = [c.get("id") for c in nb["cells"]]
    assert None not in ids and len(set(ids)) == len(ids), f"{name}: cells without an id, or ids repeated: {ids}"
    import nbformat

    nbformat.validate(nbformat.from_dict(nb))  # the schema, with warnings as errors


def verdict(config, name: str) -> dict:
    """The verdict of notebook ``name``'s checks in the site build (waiting for the build)."""
    build = site_build(config)
    rc, stderr, _ = finish_site_build(build)
    path = build["tmp"] / "notebook-checks" / f"{name}.json"
    assert path.exists(), f"{name} did not reach its last cell in the site build (exit {rc}):\n{stderr[-3000:]}"
    return json.loads(path.read_text(encoding="utf-8"))


def test_every_notebook_is_tested():
    assert sorted(p.name for p in NOTEBOOKS.glob("*.ipynb")) == NAMES == sorted(EXPECTED_WARNINGS) == sorted(CHECKS)


@pytest.mark.parametrize("name", NAMES)
def test_every_notebook_is_committed_cleared_with_its_quick_switch_first(name):
    check_committed(name)


@pytest.mark.parametrize("name", NAMES)
def test_every_notebook_runs_its_quick_mode_and_says_what_its_text_claims(name, request):
    seen = verdict(request.config, name)
    assert seen["error"] is None, f"{name}: a check failed in the notebook's kernel:\n{seen['error']}"
    said = [tuple(w) for w in seen["warnings"]]
    for category, match in EXPECTED_WARNINGS[name]:
        assert any(c == category and re.search(match, m) for c, m in said), f"{name}: no {category} matching {match}"
    unexpected = [(c, m) for c, m in said
                  if not any(c == category and re.search(match, m) for category, match in EXPECTED_WARNINGS[name])]
    assert not unexpected, f"{name}: warnings the notebook's run is not expected to give: {unexpected[:5]}"


def test_the_miso_notebooks_grid_runs_in_a_fresh_store():
    # 06 ran its grid in a fixed miso_grid.sqlite: a rerun after a change of graybox's code reused every cell (the
    # store keys cells by package version, unchanged by a code change) and showed the old code's numbers
    nb = json.loads((NOTEBOOKS / "06_miso.ipynb").read_text(encoding="utf-8"))
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    calls = re.findall(r"(?:run_grid|load_results)\(([^)]*)\)", code)
    assert calls and all(".sqlite" not in c for c in calls), calls  # no file named in the call: the store variable
    assert re.search(r"^scratch = tempfile\.TemporaryDirectory\(.*\nstore = Path\(scratch\.name\) / ", code, re.M), \
        "the store is not in a fresh directory"
