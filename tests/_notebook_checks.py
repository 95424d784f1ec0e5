"""The checks of the notebooks' quick runs, made inside the documentation build's notebook kernels.

The suite executes each notebook once, as the documentation site shows it: tests/conftest.py starts the Sphinx build
with ``GRAYBOX_NOTEBOOK_CHECKS`` naming a folder, docs/conf.py then gives each notebook's copy two hidden cells (tag
``remove-cell``): a first that records every warning (:func:`start`), a last that runs the notebook's checks on its
namespace (:func:`finish`) and writes the verdict, ``<folder>/<notebook>.json``, which tests/test_notebooks.py reads.
A check that fails is written down, not raised: the page still builds and the test names what failed.
"""

from __future__ import annotations

import json
import traceback
import warnings
from pathlib import Path

import numpy as np

#: The notes each notebook's quick run gives a reader (a warning's class name and a regular expression its message
#: matches), asserted by tests/test_notebooks.py: a missing one or a new one fails.
EXPECTED_WARNINGS: dict[str, list[tuple[str, str]]] = {
    "01_black_box.ipynb": [("CandidateWarning", r"u\(k-4\)u\(k-5\)\^2")],
    "02_gray_box_convex.ipynb": [],
    "03_simulation_error.ipynb": [],
    "04_buck_converter.ipynb": [("StaticRangeWarning", r"ū = \[1\.0, 4\.0\]"),
                                ("StaticRangeWarning", r"ū = \[1\.5, 1\.75, 2\.0, 2\.75")],
    "05_constraint_variants.ipynb": [],
    "06_miso.ipynb": [],
    "07_control.ipynb": [],
}

_CAUGHT: list[tuple[str, str]] = []

#: The number words the notebooks' text counts with.
_WORDS = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six", 7: "seven", 8: "eight", 9: "nine", 10: "ten"}


def _said(name: str) -> str:
    """The markdown of notebook ``name`` as committed (one string, lines joined by spaces): what its reader is told."""
    path = Path(__file__).resolve().parents[1] / "notebooks" / name
    nb = json.loads(path.read_text(encoding="utf-8"))
    return " ".join("".join(c["source"]).replace("\n", " ") for c in nb["cells"] if c["cell_type"] == "markdown")


def start() -> None:
    """Record every warning the notebook gives from here on (each shown as well, as the kernel would)."""
    show = warnings.showwarning

    def record(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001, ANN202
        _CAUGHT.append((category.__name__, str(message)))
        show(message, category, filename, lineno, file, line)

    warnings.simplefilter("always")  # each one, not its first at a place only: a repeated note is a new one
    warnings.showwarning = record


def _pumping_notebook(ns: dict) -> None:
    assert ns["QUICK"] is True


def _black_box(ns: dict) -> None:
    assert ns["QUICK"] is True
    # the text: each test's limit is set on 199 shuffles of the residuals, its own, beyond the pointwise band (a
    # limit for all its lags)
    t = ns["tests"]
    assert all(c.permutations == 199 and c.limit > c.band for c in t.tests.values())
    assert len({c.limit for c in t.tests.values()}) == len(t.tests)
    assert "shuffled in time 199 times" in _said("01_black_box.ipynb")
    # "no model passes them all: ... residual correlation at long lags ... and u² terms"
    assert len(ns["all_tests"]) == 3
    for name, r in ns["all_tests"].items():
        assert not r.tests["xi_xi"].passed and not r.tests["u2_xi"].passed, name
        xi = r.tests["xi_xi"]
        assert np.max(np.abs(xi.lags[np.abs(xi.phi) > xi.limit])) > 6, name  # beyond the six lags of the models
    # the ℓ = 3 model: the text said "cubic y terms give the steady-state equation several roots"; FROLS picked terms
    # in y² and none in y³, two roots at each speed shown
    els3 = ns["els3"]
    assert max(t.power_of("y") for t in els3.structure) == 2
    assert all(len(els3.equilibria(ub)) == 2 for ub in ns["data"].static.ubar[[0, len(ns["data"].static) // 2, -1]])
    assert "terms in y² but none in y³" in _said("01_black_box.ipynb")


def _buck(ns: dict) -> None:
    assert ns["QUICK"] is True
    # "graybox uses it and says so once": one StaticRangeWarning for the theoretical curve's [1, 4], one for the
    # PE set's points, not one per model of the Σ*_y sweep
    ranges = [m for c, m in _CAUGHT if c == "StaticRangeWarning"]
    assert len(ranges) == 2, ranges
    # the paper's Σ*_y: the least-squares model's is above 1 (refused), the ELS model's just below it, accepted and
    # a near-integrator that misses the validation record (the text said both were "at or above 1" and refused)
    assert ns["ls"].clusters()["Σy"] > 1 > ns["els"].clusters()["Σy"] > 0.999
    table = ns["sigma_table"]
    assert table.loc["CLS (22), Σ*y from ELS", "JS_valid"] > 5 * table.loc["CLS (22), Σy estimated", "JS_valid"]
    assert table.loc["CLS (22), Σ*y from ELS", "fit_valid"] < 0
    said = _said("04_buck_converter.ipynb")
    assert "least-squares model's Σ_y is above 1" in said and "negative fit" in said


def _simulation_error(ns: dict) -> None:
    assert ns["QUICK"] is True
    # the gradient sweep's first member runs slow, so the whole sweep is fitted inside the margin (margin="auto"),
    # with the checkpoint of that sweep
    assert sorted(p.name for p in Path("checkpoints").iterdir()) == ["se_ga_quick.npz", "se_gradient_quick.margin.npz"]


def _grid(ns: dict) -> None:
    assert ns["QUICK"] is True
    stores = sorted(p.name for p in Path("grid_results").iterdir())
    assert any(n.startswith("pumping-quick") for n in stores), stores
    assert (ns["pumping"]["status"] == "ok").sum() >= 4 * 6  # at least 4 structures × 6 variants that ran
    assert "pumping" in ns["summary"].columns and "buck" in ns["summary"].columns
    said = _said("05_constraint_variants.ipynb")
    grid = ns["pumping_grid"]
    assert f"{len(grid.structures)} structures × {len(grid.variants)} variants" in said
    assert f"{_WORDS[len(grid.variants)].capitalize()} variants" in said
    # "The black-box LS models never qualify: their static curves miss the points by more than 1 mlc"
    ls = ns["pumping"][ns["pumping"]["variant"] == "LS"]
    assert (ls["static_miss"] > 1.0).all() and "by more than 1 mlc" in said


def _miso(ns: dict) -> None:
    assert ns["QUICK"] is True
    # the CLS model meets the fitted surface (eq. (22) on two inputs)
    ub = ns["data"].static.ubar
    assert abs(ns["cls"].static_curve(ub) - ns["surface"](ub)).max() < 1e-8
    assert (ns["results"].status == "ok").sum() >= 6
    # the grid ran in a fresh store, every cell now (a fixed file's cells were reused after a change of the code)
    assert ns["run"].reused == 0 and ns["run"].store == str(ns["store"]) and not Path("miso_grid.sqlite").exists()
    said = _said("06_miso.ipynb")
    assert f"The static surfaces of the {_WORDS[len(ns['models'])]} models" in said
    grid = ns["grid"]
    assert f"{_WORDS[len(grid.structures)]} structures × {_WORDS[len(grid.variants)]} variants" in said
    # D_SF's choices lie in the band, the direct solution on its edge (J_SF = B)
    table, band = ns["table"], ns["BAND"]
    assert table.loc["PE D_SF", "JSF"] <= band and table.loc["SE D_SF", "JSF"] <= band
    assert table.loc["D_SF direct", "JSF"] > 0.99 * band
    assert table.loc["D_SF direct", "JS_valid"] < table.loc["SE D_SF", "JS_valid"] < table.loc["PE D_SF", "JS_valid"]
    # the quick run's: "with J_SF a quarter and a tenth of the band"
    assert 0.15 < table.loc["PE D_SF", "JSF"] / band < 0.4 and table.loc["SE D_SF", "JSF"] / band < 0.15
    # the ELS model's Σy is above 1, its y·u clusters keeping its denominator positive (the text said they brought it
    # "back down", where the code's comment said "back up")
    c = ns["els"].clusters()
    assert c["Σy"] > 1 > ns["sigma_y"] and "keep its denominator 1 − Σy − Σyu1 ū1 − Σyu2 ū2 positive" in said


def _control(ns: dict) -> None:
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


CHECKS = {
    "01_black_box.ipynb": _black_box,
    "02_gray_box_convex.ipynb": _pumping_notebook,
    "03_simulation_error.ipynb": _simulation_error,
    "04_buck_converter.ipynb": _buck,  # the measurements ship with graybox: never skipped
    "05_constraint_variants.ipynb": _grid,
    "06_miso.ipynb": _miso,
    "07_control.ipynb": _control,
}


def finish(name: str, ns: dict, folder: str) -> None:
    """Run notebook ``name``'s checks on its namespace; write the verdict to ``folder``/``name``.json."""
    try:
        CHECKS[name](ns)
        error = None
    except Exception:  # noqa: BLE001 - written down for the test to report
        error = traceback.format_exc()
    verdict = {"error": error, "warnings": _CAUGHT}
    (Path(folder) / f"{name}.json").write_text(json.dumps(verdict, ensure_ascii=False), encoding="utf-8")
