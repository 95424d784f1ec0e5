"""hunt50k: select_graybox and the structure searches on small problems of one's own."""

import numpy as np
import pytest

import graybox as gb
from conftest import first_order_signals


def _binary_records():
    # a two-level input: u(k-1)^2 is u(k-1), so Candidates(1, 1, degree=2) holds 5 independent terms of 6
    rng = np.random.default_rng(0)
    n = 300
    u = np.repeat(rng.choice([0.0, 1.0], n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + u[k - 1] + 0.01 * rng.standard_normal()
    return gb.Record(u[:150], y[:150], name="a"), gb.Record(u[150:], y[150:], name="b")


@pytest.mark.parametrize("source", ["swap", "exact"])
def test_unreached_size_names_the_sizes_a_subset_search_reaches(source):
    # the message said "reached: {'exact': []}": the search seemed to reach no size at all, where it reaches 1..5
    a, b = _binary_records()
    with pytest.raises(ValueError, match=r"no search reached any of the sizes \[6\]") as info:
        gb.select_graybox(gb.Candidates(1, 1, degree=2), gb.Dataset(a, b), estimator="ls", sizes=[6],
                          sources=[source])
    assert f"'{source}': []" not in str(info.value)
    assert f"'{source}': [1, 2, 3, 4, 5]" in str(info.value)


def test_tolerance_not_reached_with_every_candidate_does_not_advise_raising_max_terms():
    # with every candidate looked at, a larger max_terms looks at nothing more: the warning said to raise it
    rng = np.random.default_rng(1)
    u = rng.uniform(0, 2, 300)
    y = np.zeros(300)
    for k in range(1, 300):
        y[k] = 0.7 * y[k - 1] + 0.5 * u[k - 1] + 0.01 * rng.standard_normal()
    cand = gb.Candidates(2, 2, degree=2)
    with pytest.warns(RuntimeWarning, match="tolerance 1e-15 not reached") as rec:
        sel = gb.frols(cand, gb.Record(u, y), tol=1e-15)
    assert len(sel.structure) == len(cand.process)
    said = " ".join(str(w.message) for w in rec)
    assert "raise max_terms" not in said and "raise tol" in said


def test_sizes_named_twice_are_refused_as_sources_are():
    # sizes=[3, 3] ran and dropped the repeat without a word, where sources and estimator named twice are refused
    data = gb.load_pumping()
    with pytest.raises(ValueError, match=r"sizes must be distinct numbers of terms, got \[3, 3\]"):
        gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2), data, estimator="ls", sizes=[3, 3], progress=False)


def test_frols_refuses_max_terms_above_the_candidates_as_semp_does():
    # frols(max_terms=16) of 15 candidates looked at the 15 without a word, where semp refuses it and frols refuses
    # n_terms = 16: one agreement for the option
    rec = gb.Record(*first_order_signals())
    cand = gb.Candidates(1, 1, degree=1)
    n = len(cand.process)
    for search in (gb.frols, gb.semp):
        with pytest.raises(ValueError, match=rf"max_terms must be an integer <= {n}, got {n + 1}"):
            search(cand, rec, criterion="bic", max_terms=n + 1)
    with pytest.raises(ValueError, match=rf"max_terms must be an integer <= {n}"):
        gb.frols(cand, rec, criterion="bic", max_terms=n + 1, centre=True)
    assert len(gb.frols(cand, rec, criterion="bic", max_terms=n).structure) <= n
