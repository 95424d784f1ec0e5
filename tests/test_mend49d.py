"""mend49d: results checked on construction, frols's scaling, reports of partial stores, pe_pareto's failed
members, close equilibria, the Dask cell time limit's reason."""

from __future__ import annotations

import dataclasses
import functools
import warnings

import numpy as np
import pytest

import graybox as gb

CAND = gb.Candidates(2, 2, ne=0, degree=2)
TRUE = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])


def plant(seed, n=300, noise=0.02):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + noise * rng.standard_normal(n)
    return gb.Record(u, y, name=f"r{seed}")


@functools.cache
def _selection() -> gb.GrayboxSelection:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(CAND, plant(1), validation=plant(2), test=plant(3), estimator="ls", sizes=[3],
                                 progress=False)


# -- 1. a GrayboxSelection's table is checked on construction -------------------------------------------------------

@pytest.mark.parametrize("column, value", [("JS_test", "abc"), ("JS_test", "0.5"), ("JS_test", "array"),
                                           ("JS_valid", "x"), ("JSF_test", True), ("in_band", "False"),
                                           ("rank", 1.5), ("vs_best", None)])
def test_a_selection_whose_table_holds_text_or_arrays_for_figures_is_refused_naming_the_column(column, value):
    """dataclasses.replace(sel, table=...) with text (or arrays) in JS_test was accepted (the check of negative figures
    coerced text to NaN); regret then failed with NumPy's bare "could not convert string to float"."""
    sel = _selection()
    table = sel.table
    if value == "array":
        table[column] = [np.array([1.0, 2.0])] * len(table)
    elif value is None:
        table[column] = table[column].astype(object)
        table.iloc[0, table.columns.get_loc(column)] = None
    else:
        table[column] = value
    with pytest.raises(TypeError, match=f"GrayboxSelection: the table's column '{column}' must hold"):
        dataclasses.replace(sel, table=table)


def test_a_selection_whose_table_repeats_a_column_is_refused():
    sel = _selection()
    table = sel.table
    table.insert(0, "JS_test", table["JS_test"], allow_duplicates=True)
    with pytest.raises(ValueError, match=r"column\(s\) \['JS_test'\] appear more than once"):
        dataclasses.replace(sel, table=table)


def test_a_selection_rebuilt_from_its_own_table_and_of_object_columns_of_numbers_is_kept():
    sel = _selection()
    again = dataclasses.replace(sel, table=sel.table)
    assert again.regret == sel.regret >= 1
    table = sel.table
    table["JS_test"] = table["JS_test"].astype(object)  # numbers all the same
    assert dataclasses.replace(sel, table=table).regret == sel.regret
