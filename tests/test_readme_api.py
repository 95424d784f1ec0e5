"""The README's API examples run as written and their tables name only what exists."""

import re
import warnings
from pathlib import Path

import matplotlib
from _once import reuse_selections

import graybox as gb

matplotlib.use("Agg")

README = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")


def _section(title: str) -> str:
    return README.split(f"## {title}", 1)[1]


def _run_example(title: str) -> dict:
    """Execute the first python block of a README section; its namespace."""
    block = re.findall(r"```python\n(.*?)```", _section(title), re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, f"README.md ({title})", "exec"), ns)
    return ns


def _check_table_names(title: str) -> None:
    """Every `name` opening a row of the section's table (before its example) is a graybox attribute."""
    table = _section(title).split("```python")[0]
    for name in re.findall(r"^\| `([A-Za-z_.]+)", table, re.M):
        obj = gb
        for part in name.split("."):
            obj = getattr(obj, part)


def test_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ns = _run_example("API: trust and keep a model")
    assert isinstance(ns["tests"], gb.ResidualTests) and isinstance(ns["boot"], gb.DecisionBootstrap)
    assert gb.load("els.json", expect=gb.ELSResult).model.n_params == 17


def test_every_name_in_the_table_exists():
    _check_table_names("API: trust and keep a model")
    for name in ("plot_residual_tests", "plot_static_band", "plot_decision_bootstrap"):
        assert hasattr(gb.plots, name)


def test_selection_example_runs(monkeypatch):
    reuse_selections(monkeypatch)  # its two selections are selection.md's first two, run by test_guide_code before it
    ns = _run_example("API: structure selection for gray-box use")
    assert len(ns["path"].structure) == 17
    assert ns["chosen"].decision.JSF <= 0.031 and len(ns["chosen"].table) > 5
    _check_table_names("API: structure selection for gray-box use")


def test_long_records_example_runs():
    ns = _run_example("API: long records")
    assert isinstance(ns["big"], gb.DaskRecord) and len(ns["sel"].structure) == 17
    _check_table_names("API: long records")


def test_control_example_runs():
    import pytest

    pytest.importorskip("control")
    ns = _run_example("API: from model to controller")
    lm = ns["lm"]
    assert lm.reached and abs(lm.dc_gain[0] - ns["gray"].static_gain([1200.0])[0]) < 1e-12
    assert ns["oc"].has_band
    assert abs(ns["step"].outputs[0][-1] - (lm.ybar + 1.0)) < 1e-3  # the PI brings the model to the setpoint
    _check_table_names("API: from model to controller")

def test_output_error_example_runs():
    ns = _run_example("API: output error, and fits that hold on new data")
    assert isinstance(ns["oe"], gb.OEResult) and ns["oe"].radius <= 0.95 + 1e-9
    assert ns["early"].chosen_on == data_valid_name() and ns["pick"].chosen_on == data_valid_name()
    _check_table_names("API: output error, and fits that hold on new data")


def data_valid_name() -> str:
    return gb.load_pumping().valid.name


def test_a_kept_selection_is_found_by_its_arguments_content():
    # tests/_once keyed a Dataset's extra (a FrozenMap, no dict) by its id: the README's freshly loaded data never
    # met the guide's kept selection (each test made its two 12 s calls), or met another's where an id was reused
    import _once

    a, b = gb.load_pumping(), gb.load_pumping()
    assert a.extra is not b.extra
    cand = gb.Candidates(ny=6, nu=6, degree=2)
    assert _once._key((cand, a), {}) == _once._key((gb.Candidates(ny=6, nu=6, degree=2), b), {})
    other = gb.Dataset(a.ident, a.valid, a.static, extra={"static_curve": None})
    assert _once._key((cand, a), {}) != _once._key((cand, other), {})
