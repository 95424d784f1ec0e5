"""The README's "Your own plant" runs as written: CSV files -> Dataset -> black box -> gray box ->
table, figures and a saved model (issue 25)."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest

import graybox as gb

matplotlib.use("Agg")

README = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")


def _blocks() -> list[str]:
    section = README.split("## Your own plant", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def test_the_section_has_the_file_writer_and_the_pipeline():
    make, pipeline = _blocks()
    assert 'sep=";", decimal=","' in make
    for step in ("load_record_csv", "load_static_csv", "gb.Dataset(", "frols", "pe_pareto", "decide_dsf",
                 "evaluate", "savefig", "gb.save(", "gb.load("):
        assert step in pipeline, step
    assert "load_pumping()" not in make + pipeline.replace("gb.load_pumping() returns", "")


def test_your_own_plant_runs_end_to_end(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    make, pipeline = _blocks()
    exec(compile(make, "README.md (your own plant, files)", "exec"), {})
    assert (tmp_path / "run1.csv").read_text().startswith("time;power;temperature\n0,0;")
    ns: dict = {}
    # the two notes the README says the run prints, and nothing else
    with pytest.warns(gb.StaticRangeWarning, match=r"static points: ū = \[0\.0, 20\.0, 80\.0, 100\.0\]"), \
            pytest.warns(gb.CandidateWarning, match="dropped as linear combinations"):
        exec(compile(pipeline, "README.md (your own plant)", "exec"), ns)
    data, table = ns["data"], ns["table"]
    assert (len(data.ident), len(data.valid), len(data.static)) == (1500, 600, 6)
    assert data.ident.units == ("%", "°C") and data.Ts == 0.5
    # what the text says: the black box misses the steady states, the gray box meets them at a
    # dynamic cost of the same order
    black, gray = table.loc["black box"], table.loc["gray box"]
    assert black["JSF"] > 100 * gray["JSF"] and gray["JSF"] <= 0.05
    assert gray["JS_valid"] < 2 * black["JS_valid"]
    assert (tmp_path / "free_run.png").stat().st_size > 0 and (tmp_path / "static.png").stat().st_size > 0
    again = ns["model"]
    assert np.array_equal(again.theta, ns["gray"].theta) and again.structure == ns["gray"].structure
    assert np.isfinite(ns["y"]).all() and ns["y"].shape == data.valid.y.shape
