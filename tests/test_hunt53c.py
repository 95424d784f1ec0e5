"""hunt53c: the honest-selection surfaces (select_graybox, output error, the best-subset searches)."""

import warnings

import numpy as np
import pytest

import graybox as gb


def _first_order(seed, n=200):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), name=f"first order {seed}")


@pytest.fixture(scope="module")
def small():
    return gb.Dataset(_first_order(1), _first_order(2))


@pytest.mark.parametrize("sources", [["swap"], ["exact"], ["frols", "swap"]])
def test_a_size_below_the_included_terms_is_left_out_by_every_source(small, sources):
    # sizes=[1, 2, 3] with two included terms: the semp and frols sources leave size 1 out with a SelectionWarning,
    # but a swap or exact source ended the whole call with frols's "n_terms = 1 is fewer than the 2 included terms"
    with pytest.warns(gb.SelectionWarning, match=r"sizes no search reached are left out: .*(swap|exact): \[1\]"):
        s = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=1), small, estimator="ls", include=["1", "y(k-1)"],
                              sizes=[1, 2, 3], sources=sources)
    assert set(s.table["size"]) == {2, 3}


def _two_levels_late(first=1.0, second=2.0):
    # a first-order plant whose input takes two levels in these 12 samples: u(k-1)^2 is a combination of u(k-1) and 1
    u = np.array([first] * 5 + [second] * 7)
    y = np.zeros(12)
    for k in range(1, 12):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2
    return gb.Record(u, y, name=f"levels {first:g}, {second:g}")


@pytest.mark.filterwarnings("ignore:the validation record's 11 error samples:graybox.SelectionWarning")
@pytest.mark.parametrize("search", ["swap", "exact"])
def test_a_subset_search_that_cannot_reach_the_size_says_how_many_it_can(search):
    # greedy frols said "only 2 independent terms could be selected" (FewerTermsError.reached = 2); the swap and exact
    # searches said "no subset of 3 independent terms" with reached None, so select_graybox reported them as reaching
    # no size at all: "no search reached any of the sizes [3] (reached: {'frols': [1, 2], 'swap': [], 'exact': []})"
    from graybox.selection._stopping import FewerTermsError

    cand = gb.Candidates(ny=0, nu=1, degree=2)
    with pytest.raises(FewerTermsError) as info:
        gb.frols(cand, _two_levels_late(), n_terms=3, search=search)
    assert info.value.reached == 2
    with pytest.raises(ValueError, match=rf"'{search}': \[1, 2\]"):
        gb.select_graybox(cand, _two_levels_late(), validation=_two_levels_late(2.0, 1.0),
                          estimator="ls", sources=["frols", search], sizes=[3])


def _levels(levels, name):
    u = np.repeat(np.asarray(levels, float), 10)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2
    return gb.Record(u, y + 0.001 * np.sin(np.arange(u.size)), name=name)


def test_default_sizes_none_of_which_the_records_reach_take_the_sizes_they_do():
    # three candidates (1, u(k-1), u(k-1)^2) and a two-level input: the default sizes were [3] alone, which no search
    # reaches there, and the call failed ("no search reached any of the sizes [3] (reached: {'semp': [1, 2], ...})"),
    # though the docstring leaves default sizes a search does not reach out without a word
    data = gb.Dataset(_levels([1, 2, 1, 1, 2, 2, 1, 2, 1, 2], "i"), _levels([2, 1, 2, 2, 1, 1, 2, 2, 1, 1], "v"))
    s = gb.select_graybox(gb.Candidates(ny=0, nu=1, degree=2), data, estimator="ls")
    assert set(s.table["size"]) == {2} and len(s.structure) == 2


@pytest.mark.filterwarnings("ignore::graybox.SelectionWarning", "ignore::graybox.StaticRangeWarning")
def test_a_shortlist_out_of_the_band_goes_by_js_not_by_the_rows_names():
    # the docstring: the slow estimators fit the structures the fast ones rank best, "in band first, then by J_S on
    # the choosing data". Rows out of the band were all ranked inf, so with no PE row in the band the shortlist took
    # the rows by name: frols-2 got the SE fit though semp-2 had the smaller J_S
    ub = np.linspace(0.5, 2.0, 6)
    points = gb.StaticPoints(ub, (0.2 * ub + 0.05 * ub**2) / 0.3 + 0.05 * np.sin(5 * ub))
    data = gb.Dataset(_first_order(1, 120), _first_order(2, 120), points)
    s = gb.select_graybox(gb.Candidates(ny=2, nu=2, degree=2), data, band=1e-6, sizes=[2, 4], shortlist=1,
                          estimator=["pe", "se-gradient"], lambdas=[1.0], fallback="min_jsf")
    pe = s.table[s.table["estimator"] == "pe"]
    assert not pe["in_band"].any() and pe["JS_valid"].nunique() == len(pe)
    assert list(s.table.index[s.table["estimator"] == "se-gradient"]) == [pe["JS_valid"].idxmin()]


def test_rule_min_takes_the_fewest_terms_among_rows_tied_on_the_best_js():
    """Rows tied on J_S (exact structures on noise-free data) went to the first in table order under rule="min",
    where one-se takes the fewest terms among the rows it cannot tell apart."""
    import pandas as pd

    from graybox.experiments._select import _choose

    table = pd.DataFrame({"in_band": [True, True, True], "JS_valid": [1e-6, 1e-6, 2e-6], "n_terms": [6, 4, 3]},
                         index=["six", "four", "three"])
    scores = [np.array([1e-6]), np.array([1e-6]), np.array([2e-6])]
    pos, rule = _choose(table, scores, np.ones(1), "min")
    assert (table.index[pos], rule) == ("four", "min")
    assert list(table["eligible"]) == [True, True, False]
