"""hunt47d: structure search and least squares (frols, semp, subset search, stopping rules, ELS)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.core._regressors import regressor_matrix
from conftest import first_order_signals


def _plant(n: int = 200, seed: int = 0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] - 0.2 * u[k - 2] * y[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u=u, y=y)


SPACE = gb.Candidates(ny=2, nu=2, degree=2)


def test_a_semp_result_made_from_an_array_keeps_its_own_read_only_copy():
    res = gb.semp(SPACE, _plant(), n_terms=3)
    theta = np.array(res.theta)
    made = gb.SEMPResult(res.structure, theta, res.score, res.path, res.forward_scores, res.criterion, res.stop,
                         res.n_rows)
    theta[0] = 99.0  # the caller's array changes; the result does not
    assert made.theta[0] == res.theta[0]
    with pytest.raises(ValueError):
        made.theta[0] = 99.0
    assert isinstance(gb.SEMPResult(res.structure, list(res.theta), res.score, res.path, res.forward_scores,
                                    res.criterion, res.stop, res.n_rows).theta, np.ndarray)


def test_an_els_result_made_from_arrays_keeps_its_own_read_only_copies():
    res = gb.els(["y(k-1)", "u(k-1)"], _plant())
    theta_ls, residuals = np.array(res.theta_ls), tuple(np.array(r) for r in res.residuals)
    made = gb.ELSResult(res.model, res.n_iter, res.converged, res.history, residuals, theta_ls)
    theta_ls[0] = 99.0
    residuals[0][5] = 99.0
    assert made.theta_ls[0] == res.theta_ls[0]
    assert made.residuals[0][5] == res.residuals[0][5]
    for a in (made.theta_ls, made.residuals[0]):
        with pytest.raises(ValueError):
            a[0] = 1.0


@pytest.mark.parametrize("search", ["greedy", "swap", "exact"])
def test_a_tolerance_on_a_short_record_looks_at_the_sizes_its_rows_carry(search):
    # 6 regression rows of noise: no model of fewer than 6 terms reaches 1e-12; a tolerance then stops at the
    # largest size the rows carry (rows - 1) with the warning that it was not reached, as semp and a criterion do.
    # It was a ValueError about 6 terms on 6 rows (greedy) or about the criterion AIC nobody asked for (swap, exact)
    rng = np.random.default_rng(1)
    rec = gb.Record(u=rng.standard_normal(8), y=rng.standard_normal(8))
    with pytest.warns(RuntimeWarning, match="tolerance 1e-12 not reached"):
        sel = gb.frols(SPACE, rec, tol=1e-12, search=search)
    assert sel.n_terms <= sel.n_rows - 1 == 5
    with pytest.raises(ValueError, match="max_terms"):
        gb.frols(SPACE, rec, tol=1e-12, search=search, max_terms=6)


def test_the_subset_rss_floor_is_the_one_the_selection_docstring_states():
    # noise-free data: the best subset of 2 terms fits exactly, and its RSS is the round-off floor the
    # docstring names (it said 1e-13 yᵀy, from a Gram matrix; then 1e-20 yᵀy; now an exact fit's measured round-off,
    # 1e4 eps² (yᵀy + N (Σ|θ_s|)²) with θ_s the parameters of the unit-RMS columns)
    u, y = first_order_signals(200, 0, noise=0.0)
    sel = gb.frols(SPACE, gb.Record(u=u, y=y), n_terms=2, search="exact")
    L = SPACE.max_lag
    yy, n = float(y[L:] @ y[L:]), len(y) - L
    psi = regressor_matrix(sel.structure, u, y, start=L)
    rms = np.sqrt(np.mean(psi ** 2, axis=0))
    theta_s = np.linalg.lstsq(psi / rms, y[L:], rcond=None)[0]
    floor = 1e4 * np.finfo(float).eps ** 2 * (yy + n * np.sum(np.abs(theta_s)) ** 2)
    assert sel.subset_rss[0] == pytest.approx(floor, rel=1e-6)
    assert "1e4 eps² (yᵀy + N (Σ|θ_s|)²)" in " ".join(gb.Selection.__doc__.split())


def _short_offset_record(n: int) -> gb.Record:
    rng = np.random.default_rng(2)
    u = rng.standard_normal(n) + 5.0
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] * u[k - 2] + 0.1 * rng.standard_normal()
    return gb.Record(u=u, y=y)


@pytest.mark.parametrize("select", [gb.frols, gb.semp])
def test_a_centred_choice_whose_closure_fills_the_rows_is_refused_in_one_clear_message(select):
    # 8 samples, 6 regression rows: the terms a criterion chooses on the centred signals close under shifts to
    # 6 terms. semp returned that model, interpolating the record (which els then refused as too short); frols
    # said '6 terms need more than their 6 regression rows; lower n_terms', an n_terms nobody gave
    rec = _short_offset_record(8)
    with pytest.warns(RuntimeWarning), pytest.raises(ValueError, match="close under shifts to 6 terms") as info:
        select(SPACE, rec, centre=True, criterion="bic")
    assert "n_terms" not in str(info.value).split(";")[0]
    # a closure the rows carry is fitted as before
    assert len(select(SPACE, _short_offset_record(20), centre=True, n_terms=3).structure) < 18


def _lagged_offset_record() -> gb.Record:
    rng = np.random.default_rng(0)
    u = rng.uniform(-1.0, 1.0, 60) + 3.0
    y = np.zeros(60)
    for k in range(3, 60):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.3 * u[k - 3] * u[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u=u, y=y)


def _rss_from(structure, rec: gb.Record, start: int) -> tuple[np.ndarray, float]:
    X, t = gb.stacked_regressors(structure, rec, start=start)
    theta = np.linalg.lstsq(X, t, rcond=None)[0]
    r = t - X @ theta
    return theta, float(r @ r)


def test_a_centred_frols_fits_and_scores_on_the_rows_the_candidates_give():
    # the candidates' largest lag is 3: the search's rows are samples 3 … 59. The closures were refitted, and
    # the subsets' RSS taken, from each closure's own largest lag: n_rows 59 for a closure of lag 1 (the docstring
    # says the rows start at the candidates' largest lag), and subset_rss of the small subsets on 59 rows, the
    # larger ones on 57, where they are compared size by size
    rec, space = _lagged_offset_record(), gb.Candidates(ny=3, nu=3, degree=2)
    with pytest.warns(RuntimeWarning, match="bic is smallest at the largest size"):
        sel = gb.frols(space, rec, centre=True, search="swap", criterion="bic", max_terms=6)
    assert any(S.max_lag < 3 for S in sel.subsets)
    for S, rss in zip(sel.subsets, sel.subset_rss):
        assert rss == pytest.approx(_rss_from(S, rec, 3)[1], rel=1e-7)  # a closed structure's RSS is the raw one's
    small = gb.frols(space, rec, centre=True, n_terms=2)
    assert small.structure.max_lag < 3 and small.n_rows == 57
    theta, rss = _rss_from(small.structure, rec, 3)
    assert small.rss[-1] == pytest.approx(rss, rel=1e-7)
    np.testing.assert_allclose(small.theta, theta, rtol=1e-7, atol=1e-9)


def test_a_centred_semp_fits_its_closure_on_the_rows_it_scores():
    rec, space = _lagged_offset_record(), gb.Candidates(ny=3, nu=3, degree=2)
    res = gb.semp(space, rec, centre=True, n_terms=2)
    assert res.structure.max_lag < 3
    # as semp fits every structure it scores, on samples 3 … 59 (it fitted the closure on 1 … 59)
    np.testing.assert_allclose(res.theta, _rss_from(res.structure, rec, 3)[0], rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("select", [gb.frols, gb.semp])
def test_a_centred_closure_is_told_apart_on_the_rows_the_search_and_the_fit_use(select):
    # a two-level input but for its first sample: u(k-1)^2 is a combination of u(k-1) and 1 on every row the
    # search (candidates' largest lag 3) and the fit use, and independent of them only at sample 1, which the
    # closure was judged on. semp returned u(k-1)^2 + u(k-1) + 1 with a u² coefficient fitted to that one sample;
    # frols said 'only 2 independent terms ... n_terms = 3 asked' (2 were asked). Both now refuse the included
    # term in the words of a term the closure cannot keep
    rng = np.random.default_rng(0)
    u = np.where(rng.standard_normal(80) > 0, 1.0, -1.0)
    u[0] = 0.5
    y = np.zeros(80)
    for k in range(1, 80):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.05 * rng.standard_normal()
    rec = gb.Record(u=u, y=y + 10.0)
    with pytest.raises(ValueError, match=r"included term u\(k-1\)\^2 cannot stay in a structure closed under shifts"):
        select(gb.Candidates(ny=1, nu=3, degree=2), rec, centre=True, n_terms=2, include=["u(k-1)^2"])


def test_semp_names_an_included_term_whose_column_is_zero_as_frols_does():
    # u held at zero: its terms are zero columns. semp said the one included term was 'collinear'
    rng = np.random.default_rng(0)
    rec = gb.Record(u=np.zeros(50), y=rng.standard_normal(50))
    with pytest.raises(ValueError, match=r"included term u\(k-1\) cannot be used on these data: all-zero column"):
        gb.semp(gb.Candidates(1, 1), rec, n_terms=2, include=["u(k-1)"])


def test_a_centred_semp_scores_a_closure_whose_free_run_diverges_inf_and_says_so():
    # 17 samples of noise, two binary inputs: the 7 terms chosen on the centred signals run (score 0.35), their
    # closure refitted by least squares does not. semp raised the simulator's DivergenceError ('the model is
    # unstable along this input'), naming no structure; a diverging free run scores inf, as semp's module says
    rng = np.random.default_rng(229)
    n = int(rng.integers(3, 30))
    rng.integers(1, 3), rng.integers(0, 4)
    u = np.where(rng.standard_normal((n, 2)) > 0, 1.0, -1.0)
    y = rng.standard_normal(n) * (0 if rng.random() < 0.05 else 1) + (1e4 if rng.random() < 0.2 else 0)
    rec = gb.Record(u=u, y=y, input_names=("u1", "u2"))
    space = gb.Candidates(2, 1, degree=2, input_names=("u1", "u2"))
    with pytest.warns(RuntimeWarning) as heard:
        res = gb.semp(space, rec, centre=True, tol=0.0108)
    assert res.score == np.inf
    assert any("diverges" in str(w.message) and "closure" in str(w.message) for w in heard)


def test_semp_with_n_terms_looks_past_that_size_as_its_docstring_now_says():
    # the docstring said the search stops when the structure holds n_terms terms; it goes on to 2·n_terms + 4
    # (here 10) and returns the best structure of n_terms terms met on the path
    res = gb.semp(SPACE, _plant(), n_terms=3)
    path = res.path
    assert path["n_terms"].max() == 10 and len(res.structure) == 3
    assert res.score == path.loc[path["n_terms"] == 3, "score"].min()
    assert "up to 2·n_terms + 4 terms" in " ".join(gb.semp.__doc__.split())
