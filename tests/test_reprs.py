"""Every value type prints short: one line or a few, whatever it holds (issue 25)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.core._reprs import short_repr, summary

MAX_CHARS = 360  # a Dataset's three lines (its points with their ±δ); everything else is one line well under it


def _short(obj: object, lines: int = 1) -> str:
    text = repr(obj)
    assert text.count("\n") < lines, text
    assert len(text) <= MAX_CHARS, (len(text), text)
    assert "array(" not in text, text  # arrays appear by their shape, never element by element
    return text


def test_a_candidate_set_prints_its_size_lags_degree_and_inputs():
    cand = gb.Candidates(ny=6, nu=6, ne=2, degree=3)
    text = _short(cand)
    assert text.startswith(f"Structure({len(cand)} terms, degree 3, lags y 1..6, u 1..6, e 1..2: ['1', ")
    two = gb.Candidates(2, {"n1": 2, "n2": 3}, delay={"n2": 2}, degree=2)
    assert "lags y 1..2, n1 1..2, n2 2..3" in _short(two)
    small = gb.Structure(["1", "y(k-1)", "u(k-1)"])
    assert repr(small) == "Structure(['1', 'y(k-1)', 'u(k-1)'])"  # a model's few terms: all of them


def test_data_values_are_short():
    data = gb.load_pumping()
    _short(data.ident)
    _short(data.static)
    text = _short(data, lines=3)
    assert text.startswith("Dataset(ident=Record('pumping ident': 3200 samples")
    _short(gb.Dataset(data.ident, data.valid), lines=3)


def test_results_and_their_parts_are_short():
    data = gb.load_pumping()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fit's notes (static range, ELS cap) are not under test
        sel = gb.frols(gb.Candidates(ny=2, nu=2, degree=2, max_y_power=1), data, n_terms=6, include=["1"])
        fit = gb.els(sel, data)
        pe = gb.pe_pareto(fit.model.structure, data, lambdas=np.logspace(-6, 0, 5))
    curve = gb.StaticCurve.fit(data.static, degree=2)
    surface = gb.StaticSurface.fit(gb.load_pumping_miso().static, 2)
    for obj in (sel, fit, fit.model, pe, gb.decide_dsf(pe, band=1.0, fallback="min_jsf"), curve, surface,
                gb.StaticBand(0.1), gb.GainBounds(lower=0.0), gb.GAOptions(), fit.model.equilibria(1000.0)[0],
                gb.ls_uncertainty(fit.model, data), gb.residual_tests(fit.model, data.valid)):
        _short(obj)


def test_runs_specs_and_grids_are_short():
    from graybox.datasets import PumpingPlant
    from graybox.experiments import EXAMPLE_SPEC, Grid

    plant = PumpingPlant()
    run = plant.simulate(np.full(400, 1000.0), seed=0)
    _short(run)
    grid = Grid.from_toml_text(EXAMPLE_SPEC)
    _short(grid)
    _short(grid.cells()[0])
    _short(grid.data[0])


@dataclasses.dataclass(frozen=True)
class _Value:
    n: int
    x: float
    name: str
    samples: np.ndarray
    few: np.ndarray
    history: tuple
    table: dict

    __repr__ = short_repr


def test_short_repr_summarises_what_is_long_and_keeps_what_is_short():
    v = _Value(3, 0.1 + 0.2, "short", np.zeros((1000, 2)), np.array([1.0, 2.5]), tuple(range(500)),
               {f"k{i}": i for i in range(100)})
    assert repr(v) == ("_Value(n=3, x=0.3, name='short', samples=<array 1000×2 float64>, few=[1. , 2.5], "
                       "history=<tuple of 500>, table=<dict of 100 keys>)")
    assert summary("x" * 100).endswith("…'") and len(summary("x" * 100)) < 60


@pytest.mark.parametrize("value", [1, -2.5, "a", (1, 2), None, True])
def test_short_values_print_as_themselves(value):
    assert summary(value) == (f"{value:.6g}" if isinstance(value, float) else repr(value))


def test_a_squared_error_that_is_no_number_says_no_unit():
    # was: a black box's decision without static points said "J_SF=nan mlc²"
    m = gb.Model(gb.parse_structure(["y(k-1)", "1"]), [0.5, 1.0], units=("rpm", "mlc"))
    text = repr(gb.Decision(m, 0, float("nan"), 1.2, float("nan"), "min J_S", True, 1.2))
    assert "J_S=1.2 mlc²" in text and "J_SF=nan," in text


def test_static_points_print_the_range_of_their_uncertainty_not_its_largest_alone():
    # was: δ = (2, 3) rpm from a file's uncertainty column printed "±3 rpm", as if every point carried ±3 (and the
    # column had been read as one number); a newcomer checking the load could not see the per-point δ
    varied = gb.StaticPoints([10.0, 50.0], [632.0, 2980.0], uncertainty=[2.0, 3.0], units=("%", "rpm"))
    assert _short(varied).endswith("±2–3 rpm)")
    same = gb.StaticPoints([10.0, 50.0], [632.0, 2980.0], uncertainty=3.0, units=("%", "rpm"))
    assert _short(same).endswith("±3 rpm)")
