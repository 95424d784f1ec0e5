"""The notebooks in notebooks/ run end to end.

Each notebook's code cells are joined and executed in a fresh namespace, with QUICK forced to
True (its first code cell), matplotlib's Agg backend, and a temporary folder as the working
directory (notebook 3 writes its SE checkpoints there). No Jupyter is needed: the notebooks are
plain Python apart from one guarded ``get_ipython()`` call.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from graybox import CandidateWarning, StaticRangeWarning


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


def notebook_code(name: str) -> str:
    """The notebook's code cells joined into one script, with the first cell replaced by ``QUICK = True``."""
    nb = json.loads((NOTEBOOKS / name).read_text(encoding="utf-8"))
    assert nb["nbformat"] == 4
    cells = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert cells, f"{name} has no code cells"
    for c in cells:  # committed with outputs cleared
        assert c["outputs"] == [] and c["execution_count"] is None, f"{name}: a code cell has outputs"
    sources = ["".join(c["source"]) for c in cells]
    assert sources[0].strip().startswith("QUICK ="), f"{name}: the first code cell must set QUICK"
    sources[0] = "QUICK = True"
    return "\n\n".join(sources)


#: The notes each notebook's quick run gives a reader, asserted: a missing one or a new one fails.
EXPECTED_WARNINGS: dict[str, list[tuple[type[Warning], str]]] = {
    "01_black_box.ipynb": [(CandidateWarning, r"u\(k-4\)u\(k-5\)\^2")],
    "02_gray_box_convex.ipynb": [],
    "03_simulation_error.ipynb": [],
    "04_buck_converter.ipynb": [(StaticRangeWarning, r"ū = \[1\.0, 4\.0\]"),
                                (StaticRangeWarning, r"ū = \[1\.5, 1\.75, 2\.0, 2\.75")],
    "05_constraint_variants.ipynb": [],
    "06_miso.ipynb": [],
    "07_control.ipynb": [],
}


def run_notebook(name: str) -> dict:
    namespace = {"__name__": "__notebook__"}
    with contextlib.ExitStack() as notes:
        for category, match in EXPECTED_WARNINGS[name]:
            notes.enter_context(pytest.warns(category, match=match))
        exec(compile(notebook_code(name), str(NOTEBOOKS / name), "exec"), namespace)
    return namespace


@pytest.fixture
def sandbox(tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_every_notebook_is_tested():
    assert sorted(p.name for p in NOTEBOOKS.glob("*.ipynb")) == NAMES == sorted(EXPECTED_WARNINGS)


@pytest.mark.parametrize("name", NAMES[:3])
def test_pumping_notebook_runs(name, sandbox):
    ns = run_notebook(name)
    assert ns["QUICK"] is True
    if name.startswith("03"):
        # the gradient sweep's first member runs slow, so the whole sweep is fitted inside the margin
        # (margin="auto"), with the checkpoint of that sweep
        assert sorted(p.name for p in (sandbox / "checkpoints").iterdir()) == [
            "se_ga_quick.npz", "se_gradient_quick.margin.npz"]


def test_buck_notebook_runs(sandbox):
    ns = run_notebook("04_buck_converter.ipynb")  # the measurements ship with graybox: never skipped
    assert ns["QUICK"] is True


def test_grid_notebook_runs(sandbox):
    ns = run_notebook("05_constraint_variants.ipynb")
    assert ns["QUICK"] is True
    stores = sorted(p.name for p in (sandbox / "grid_results").iterdir())
    assert any(n.startswith("pumping-quick") for n in stores)
    assert (ns["pumping"]["status"] == "ok").sum() >= 4 * 6  # at least 4 structures × 6 variants that ran
    assert "pumping" in ns["summary"].columns
    assert "buck" in ns["summary"].columns


def test_miso_notebook_runs(sandbox):
    ns = run_notebook("06_miso.ipynb")
    assert ns["QUICK"] is True
    # the CLS model meets the fitted surface (eq. (22) on two inputs)
    ub = ns["data"].static.ubar
    assert abs(ns["cls"].static_curve(ub) - ns["surface"](ub)).max() < 1e-8
    assert (ns["results"].status == "ok").sum() >= 6


def test_control_notebook_runs(sandbox):
    pytest.importorskip("control")
    ns = run_notebook("07_control.ipynb")
    assert ns["QUICK"] is True
    # the gray-box model's local gain is the plant's static slope (the static curve is imposed) ...
    np.testing.assert_allclose(ns["table"]["gain CLS"], ns["table"]["gain plant"], rtol=0.02)
    # ... its time constant falls with the speed, as the plant's does
    assert np.all(np.diff(ns["oc"].time_constant) < 0) and np.all(np.diff(ns["tau_plant"]) < 0)
    # the loops designed on the model behave alike on the model and on the plant, at every operating point
    s = ns["summary"]
    assert np.all(s["max |model − plant| (mlc)"] < 0.15 * ns["STEP"])  # the text: "less than 0.15 mlc"
    assert np.all(np.abs(s["rise model (s)"] - s["rise plant (s)"]) <= 0.2)
    # local PIs rise alike across the range; the one PI of 1200 rpm does not
    spread = s["rise plant (s)"].groupby(level="controller").agg(lambda r: r.max() - r.min())
    assert spread["local PI"] < 0.5 * spread["PI of 1200 rpm"]
