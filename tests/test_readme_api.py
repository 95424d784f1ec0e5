"""The README's "trust and keep a model" example runs as written and names only what exists."""

import re
import warnings
from pathlib import Path

import matplotlib

import graybox as gb

matplotlib.use("Agg")

README = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
SECTION = README.split("## API: trust and keep a model", 1)[1]


def test_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    block = re.findall(r"```python\n(.*?)```", SECTION, re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md (API)", "exec"), ns)
    assert isinstance(ns["tests"], gb.ResidualTests) and isinstance(ns["boot"], gb.DecisionBootstrap)
    assert gb.load("els.json", expect=gb.ELSResult).model.n_params == 17


def test_every_name_in_the_table_exists():
    table = SECTION.split("```python")[0]
    for name in re.findall(r"^\| `([A-Za-z_.]+)", table, re.M):
        obj = gb
        for part in name.split("."):
            obj = getattr(obj, part)
    for name in ("plot_residual_tests", "plot_static_band", "plot_decision_bootstrap"):
        assert hasattr(gb.plots, name)


def test_selection_example_runs():
    section = README.split("## API: structure selection for gray-box use", 1)[1]
    block = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md (selection)", "exec"), ns)
    assert len(ns["path"].structure) == 17
    assert ns["chosen"].decision.JSF <= 0.031 and len(ns["chosen"].table) > 5
    table = section.split("```python")[0]
    for name in re.findall(r"^\| `([A-Za-z_.]+)", table, re.M):
        obj = gb
        for part in name.split("."):
            obj = getattr(obj, part)


def test_long_records_example_runs():
    section = README.split("## API: long records", 1)[1]
    block = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md (long records)", "exec"), ns)
    assert isinstance(ns["big"], gb.DaskRecord) and len(ns["sel"].structure) == 17
    table = section.split("```python")[0]
    for name in re.findall(r"^\| `([A-Za-z_.]+)", table, re.M):
        assert hasattr(gb, name), name
