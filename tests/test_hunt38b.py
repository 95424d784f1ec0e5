"""Hunt 38b: finding and fitting models (frols and its searches, semp, the estimators, D_SF, Pareto
sets) used as a user would: inputs in other units or far from zero, several records, short records,
noise-free data and bad input. Each test names what was wrong before its fix."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb


def _two_level(n: int = 600, seed: int = 0) -> gb.Record:
    """A binary input between 1 and 2 V (a PRBS with an offset): u² = 3u − 2 on every sample, so u(k-1)²
    is a linear combination of 1 and u(k-1), not proportional to either."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.integers(1, 3, n // 5 + 1), 5)[:n].astype(float)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.4 * u[k - 1] - 0.1 * u[k - 1] ** 2 + 0.02 * rng.standard_normal()
    return gb.Record(u, y)


# frols(search="swap" or "exact") with a criterion or a tolerance looks at every size up to max_terms;
# when the candidates held a linear dependence (here u² = 3u − 2) the largest sizes had no independent
# subset and the whole call failed with "no subset of 14 independent terms on these data", though nobody
# asked for 14 terms and greedy search, on the same call, stopped at the sizes the data carry.
@pytest.mark.parametrize("search", ["swap", "exact"])
@pytest.mark.parametrize("rule", [{"criterion": "bic"}, {"tol": 1e-9}])
def test_a_search_by_criterion_or_tolerance_stops_at_the_sizes_the_data_carry(search, rule):
    rec = _two_level()
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        warnings.simplefilter("ignore", RuntimeWarning)  # the tolerance is not reached
        greedy = gb.frols(cand, rec, **rule)
        sel = gb.frols(cand, rec, search=search, **rule)
    sizes = [len(s) for s in sel.subsets]
    assert sizes == list(range(1, len(sizes) + 1))
    assert max(sizes) == len(greedy.evaluated)  # the independent terms there are, as greedy finds them
    # the best subset of each size is at least as good as greedy's nested model of that size
    assert np.all(sel.subset_rss <= greedy.rss[: len(sizes)] * (1 + 1e-9))
    if "criterion" in rule:
        assert sel.n_terms == 3 and {"y(k-1)", "u(k-1)"} <= {str(t) for t in sel.structure}


def test_a_criterion_search_cut_by_a_dependence_does_not_ask_for_a_larger_max_terms():
    """The sizes ended because no larger subset is independent: "raise max_terms" would be no help (greedy
    search, on the same data, does not say it)."""
    rng = np.random.default_rng(0)
    n = 600
    u = np.repeat(rng.integers(1, 3, n // 5 + 1), 5)[:n].astype(float)
    y = np.zeros(n)
    for k in range(2, n):  # every independent candidate counts: the criterion is smallest at the last size
        a, b, c, d = y[k - 1], y[k - 2], u[k - 1], u[k - 2]
        y[k] = (0.5 + 0.3 * a + 0.2 * b + 0.3 * c + 0.2 * d - 0.01 * a * a + 0.01 * a * b - 0.01 * b * b + 0.02 * a * c
                - 0.02 * a * d + 0.02 * b * c - 0.02 * b * d + 0.1 * c * d + 1e-5 * rng.standard_normal())
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        warnings.simplefilter("error", RuntimeWarning)
        greedy = gb.frols(cand, gb.Record(u, y), criterion="aic")
        sel = gb.frols(cand, gb.Record(u, y), criterion="aic", search="swap")
    assert sel.n_terms == greedy.n_terms == len(sel.subsets[-1])
