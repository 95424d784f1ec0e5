"""Hunt 30b: structure and model selection (frols, semp, the subset searches, select_graybox) used as
a control engineer would on their own data: engineering units, inputs not named "u", short records,
step tests at a few levels, black and gray boxes, and bad input that must be a clear error or an
explicit, reported fallback."""

import warnings

import numpy as np
import pytest

import graybox as gb

CAND = gb.Candidates(ny=2, nu=2, degree=2, input_names=("n",))


def step_test(levels, hold, seed=4, noise=0.01, su=1.0, sy=1.0):
    """A first-order plant y = 0.7 y + 0.2 n + 0.05 n² + 0.1 driven by a staircase of ``levels``,
    each held ``hold`` samples (a step test at a few operating points); input named "n"."""
    rng = np.random.default_rng(seed)
    u = np.repeat(np.asarray(levels, float), hold)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2 + 0.1
    y += noise * rng.standard_normal(u.size)
    return gb.Record(u * su, y * sy, name="step test", input_names=("n",))


@pytest.fixture
def structures_of_all_data_per_fold(monkeypatch):
    """Folds fitted on the structures searched on all the identification data (what select_graybox falls back to
    when the structures searched per fold never run on their held-out folds): the fits a fold cannot make."""
    from graybox.experiments import _select

    monkeypatch.setattr(_select, "_fold_structures",
                        lambda rows, candidates, plan, *a: [tuple(r["terms"] for _ in plan.splits) for r in rows])


@pytest.mark.parametrize("estimator", ["ls", "pe"])
def test_a_fit_a_fold_cannot_identify_fails_its_row_not_the_search(estimator, structures_of_all_data_per_fold):
    # was: a step test at three levels passed alone (folds) aborted the whole search with
    # "least squares: regressor matrix has rank 3 < 4 columns ... from these data": one fold's
    # identification part holds two levels only, on which n(k-1), n(k-1)² and the constant are
    # collinear; the error named neither the structure nor the fold. A failed fit is now a failed
    # member (its row's reason says which fit and why) and the search chooses among the others.
    rec = step_test([0.8, 1.9, 1.3], 100)
    static = None
    kw = {}
    if estimator == "pe":
        ub = np.linspace(0.8, 1.9, 5)
        static = gb.StaticPoints(ub, (0.2 * ub + 0.05 * ub ** 2 + 0.1) / 0.3, input_names=("n",))
        kw = dict(band=1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        res = gb.select_graybox(CAND, rec, static, sizes=[3, 4, 6], folds=3, estimator=estimator, **kw)
    if estimator == "pe":
        # the static points at five levels, weighted (λ1 < 1), identify θ on a fold's two levels (hunt36b), except
        # where a structure holds the terms n(k-1) and n(k-2), which are one cluster (the static points cannot tell
        # them apart) and one column in each of the middle fold's two segments, each at one input level (a fold is
        # fitted on its segments as separate records: no regressor reaches across the cut, where the joined
        # segments made an input step that never happened): those rows fail, saying why; every other row fits
        both = res.table["terms"].map(lambda t: {"n(k-1)", "n(k-2)"} <= set(t.split(" + ")))
        assert both.any() and (res.table.loc[both, "reason"].str.contains("fold 2 ident.*not identifiable")).all()
        assert (res.table.loc[~both, "reason"] == "").all() and np.isfinite(res.table.loc[~both, "JS_valid"]).all()
        assert res.decision.lambda1 < 1.0
        return
    failed = res.table[res.table["reason"].str.contains("fold", na=False)]
    assert len(failed) >= 1
    assert failed["reason"].str.contains("not identifiable").all()
    assert np.isinf(failed["JS_valid"]).all() and not failed["in_band"].any()
    assert np.isfinite(res.chosen["JS_valid"]) and res.chosen["reason"] == ""
    assert np.all(np.isfinite(res.model.theta))


def short_record(n, seed=0):
    """n samples of the first-order plant under a random input in rpm, output in Pa."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(800.0, 1900.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 200.0 * (u[k - 1] / 1000) + 50.0 * (u[k - 1] / 1000) ** 2 + 2e5 * 0.3
    return gb.Record(u, y, name="short", input_names=("n",))


def test_semp_gives_a_size_a_short_record_can_carry():
    # was: semp(n_terms=4) on 12 rows after the largest lag raised "12 samples after the largest
    # lag are too few for 12 terms": 12 is the look-ahead of its search (2·n_terms + 4), not the
    # size asked for; the look-ahead is now cut to what the rows carry, and only a size the rows
    # cannot carry is refused
    rec = short_record(14)
    res = gb.semp(CAND, rec, n_terms=4)
    assert len(res.structure) == 4 and res.path["n_terms"].max() <= 11
    with pytest.raises(ValueError, match="12 samples after the largest lag are too few for 12 terms"):
        gb.semp(CAND, rec, n_terms=12)


def test_select_graybox_sizes_are_checked_against_the_record_and_the_included_terms():
    # was: on a 14-sample identification record the default sizes (up to 15) failed inside SEMP with
    # "12 samples after the largest lag are too few for 15 terms", and sizes below the included
    # terms' count with "2 included terms exceed the 1 terms asked for" (or FROLS's "n_terms = 1"):
    # arguments the caller never gave. The default sizes now stop below the record's rows; sizes it
    # cannot carry, or that cannot hold the included terms, are refused naming sizes.
    valid = short_record(100, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(CAND, gb.Dataset(short_record(14), valid), estimator="ls")
    assert res.table["size"].max() <= 11
    with pytest.raises(ValueError, match=r"sizes \[12\] need more than the identification record's 12 samples"):
        gb.select_graybox(CAND, gb.Dataset(short_record(14), valid), sizes=[4, 12])
    with pytest.raises(ValueError, match=r"sizes \[1\] are fewer than the 2 included terms"):
        gb.select_graybox(CAND, gb.Dataset(short_record(300), valid), sizes=[1], include=("1", "y(k-1)"))


def test_semp_refuses_an_output_that_is_identically_zero_as_frols_does():
    # was: semp on an all-zero output (a sensor not connected) emitted numpy's "divide by zero
    # encountered in log" once per step (its criterion is N ln 0) and returned the structure "1"
    # with θ = 0 and a criterion of -inf; frols refuses the same data in words
    rec = short_record(200)
    zero = gb.Record(rec.u, np.zeros(200), input_names=("n",))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="the output is identically zero"):
            gb.semp(CAND, zero, max_terms=6)


def test_select_graybox_on_dask_workers_leaves_nothing_in_the_temporary_folder(tmp_path, monkeypatch):
    # was: the LocalCluster graybox starts made Dask's "dask-scratch-space" folder in the temporary
    # folder and left it there after the call ("Nothing is written to disk", says select_graybox)
    import tempfile

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    data = gb.Dataset(short_record(200), short_record(100, seed=1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(CAND, data, sizes=[3], sources="frols", estimator="ls", workers=1)
    assert np.all(np.isfinite(res.model.theta))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("search", ["swap", "exact"])
def test_subset_searches_keep_to_independent_columns_on_noise_free_data(search):
    # was: on a noise-free record of the first-order plant, y(k-1), y(k-2), n(k-2), n(k-2)² and the
    # constant are exactly dependent (y(k-1) is the plant's own equation one step back); every
    # subset holding the true terms ties at the round-off floor, and the swap and exact searches
    # returned one holding all five, so frols(n_terms=10..13, search=...) failed with "included
    # term n(k-2)^2 cannot be used on these data" though nothing was included, where greedy search
    # gives 10..13 independent terms. Of candidates tied at the floor the search now adds the one
    # most independent of its subset, and one its Gram form finds dependent never; a subset whose
    # dependence only the QR of the final fit sees is refused naming the search, not an included term
    rec = short_record(200, seed=3)
    for n in (10, 12):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.CandidateWarning)
            sel = gb.frols(CAND, rec, n_terms=n, search=search)
        assert len(sel.structure) == n and np.all(np.isfinite(sel.theta))
        psi = gb.regressor_matrix(sel.structure, rec.u, rec.y, start=2, input_names=rec.input_names)
        assert np.linalg.matrix_rank(psi / np.sqrt(np.mean(psi ** 2, axis=0))) == n
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        # 13 terms: the Gram form the searches ran on could not tell a dependent subset from the
        # greedy one and the call was refused ("the best subset of 13 terms the search found holds");
        # on the triangular factor (hunt43b) they find the 13 independent terms greedy finds
        sel = gb.frols(CAND, rec, n_terms=13, search=search)
        greedy = gb.frols(CAND, rec, n_terms=13)
        assert set(sel.structure) == set(greedy.structure) and np.all(np.isfinite(sel.theta))
        psi = gb.regressor_matrix(sel.structure, rec.u, rec.y, start=2, input_names=rec.input_names)
        assert np.linalg.matrix_rank(psi / np.sqrt(np.mean(psi ** 2, axis=0))) == 13
        # more than the data's independent terms: said as greedy search says it
        with pytest.raises(ValueError, match="independent terms"):
            gb.frols(CAND, rec, n_terms=14, search=search)


@pytest.mark.parametrize("search", ["greedy", "swap", "exact"])
def test_frols_says_too_many_terms_for_the_rows_in_the_same_words_for_every_search(search):
    # was: with search="swap" or "exact", n_terms = 12 on 12 regression rows failed with "criterion
    # aic needs fewer terms (12) than rows (12)": a criterion the caller did not ask for
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        # (it read "more terms (12) than regression rows (12)" when they are as many: hunt37c)
        with pytest.raises(ValueError, match=r"12 terms need more than their 12 regression rows \(no error left"):
            gb.frols(CAND, short_record(14, seed=3), n_terms=12, search=search)


@pytest.mark.parametrize("rss, n_rows, error, match", [
    ([0.0], 10, ValueError, "rss must be > 0"),
    ([-1.0], 10, ValueError, "rss must be > 0"),
    ([np.nan], 10, ValueError, "rss has 1 non-finite"),
    ([[1.0, 2.0]], 10, ValueError, "rss must be 1-D"),
    ([1.0], 2.5, TypeError, "n_rows must be an integer"),
    ([1.0], True, TypeError, "n_rows must be an integer"),
    ([1.0], 0, ValueError, "n_rows must be an integer >= 1"),
])
def test_information_criterion_refuses_what_it_cannot_score(rss, n_rows, error, match):
    # was: an RSS of 0 gave -inf and a negative one NaN (with numpy's "divide by zero" / "invalid
    # value encountered in log"), 2.5 rows a number, a 2-D rss a 2-D curve, n_rows=True one row
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(error, match=match):
            gb.information_criterion("aic", rss, n_rows)


@pytest.mark.parametrize("search", ["greedy", "swap", "exact"])
def test_included_terms_dependent_on_these_data_are_named_by_every_search(search):
    # (kept while subset searches learnt to refuse dependent columns: the searches then found "no
    # subset of 7 independent terms" where greedy search names the included term that cannot be used)
    include = ["y(k-1)", "y(k-2)", "n(k-2)", "n(k-2)^2", "1"]  # the noise-free plant one step back
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        with pytest.raises(ValueError, match="included term 1 cannot be used on these data: linear combination"):
            gb.frols(CAND, short_record(200, seed=3), n_terms=7, include=include, search=search)


def test_frols_on_the_gram_form_refuses_a_selected_term_its_qr_factor_finds_dependent():
    # was: frols(method="gram", n_terms=10) on the noise-free plant returned 10 terms of rank 9 (the
    # Gram form cannot see the dependence y(k-1) = F(y(k-2), n(k-2), 1)), with θ of the constant
    # off by 13 % in a cancelling null-space direction; its accurate (TSQR) factor sees it: refused
    rec = short_record(200, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        sel = gb.frols(CAND, rec, n_terms=6, method="gram")
        assert len(sel.structure) == 6
        with pytest.raises(ValueError, match=r"only 6 independent terms could be selected on these data: selected "
                                             r"term .* is a linear combination of the terms selected before it.*"
                                             r"method='mgs'"):
            gb.frols(CAND, rec, n_terms=10, method="gram")


def test_select_graybox_names_an_included_term_given_twice_as_the_searches_do():
    # (kept while sizes learnt to be checked against the included terms: that check first said
    # "duplicated term 1 in structure", where the searches say which argument holds it)
    data = gb.Dataset(short_record(200), short_record(100, seed=1))
    with pytest.raises(ValueError, match="included term 1 is given twice"):
        gb.select_graybox(CAND, data, sizes=[3], include=("1", "y(k-1)", "1"))


def test_semp_tolerance_on_a_constant_output_does_not_depend_on_the_units():
    # was: with var(y) = 0 (a constant output) semp divided the free-run MSE by 1 output unit², so
    # the same record in two units gave ratios 1e12 apart (4e-10 and 4e+02, the tolerance reached in
    # one and not in the other): it is now read on the mean square output there
    rec = short_record(200)
    stops = []
    for scale in (1.0, 1e6):
        flat = gb.Record(rec.u, np.full(200, 2e5 * scale), input_names=("n",))
        stops.append(gb.semp(CAND, flat, tol=1e-3, max_terms=4).stop)
    assert stops[0] == stops[1]


def test_a_black_box_row_without_a_model_has_no_static_error_either(structures_of_all_data_per_fold):
    # was: a black-box row whose fits failed (or diverged) had JSF = inf and JSF_test = inf, where
    # the table's promise is NaN without static points (there is no static error to be infinite)
    rec = step_test([0.8, 1.9, 1.3], 100)
    test = step_test([1.1, 1.6, 0.9], 60, seed=9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        res = gb.select_graybox(CAND, rec, sizes=[3, 4, 6], folds=3, estimator="ls", test=test)
    assert np.isinf(res.table["JS_valid"]).any()  # some rows have no model
    assert res.table["JSF"].isna().all() and res.table["JSF_test"].isna().all()


@pytest.mark.parametrize("search", ["greedy", "swap", "exact"])
def test_frols_keeps_every_included_term_whatever_rule_stops_it(search):
    # was: greedy frols(tol=0.5, include=[six terms]) returned "y(k-1)" alone (the tolerance was
    # met after the first included term and the others were dropped, where swap and exact keep all
    # six); a criterion minimum below their count dropped them likewise; and max_terms below their
    # count returned the first max_terms of them (greedy) or failed with numpy's "zero-size array
    # to reduction operation maximum" (swap, exact)
    r0 = short_record(300, seed=3)
    rec = gb.Record(r0.u, r0.y + np.random.default_rng(1).normal(0, 1.0, 300), input_names=("n",))
    include = ["y(k-1)", "n(k-1)", "n(k-1)^2", "1", "y(k-2)^2", "n(k-2)y(k-1)"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a tolerance or criterion cut short: not the point
        for kw in (dict(tol=0.5), dict(criterion="bic", max_terms=8)):
            sel = gb.frols(CAND, rec, include=include, search=search, **kw)
            assert [str(t) for t in sel.structure][:6] == include
        with pytest.raises(ValueError, match="6 included terms exceed the 5 terms max_terms allows"):
            gb.frols(CAND, rec, include=include, search=search, max_terms=5)


def test_select_graybox_says_when_it_falls_back_to_the_smallest_static_error():
    # was: with fallback="min_jsf" and a band no structure reaches, the call chose the smallest J_SF
    # without a word (se_dsf warns in the same case; the docstring says the fallback "says so")
    rec1, rec2 = step_test([0.8, 1.9, 1.3, 1.6], 50, seed=1), step_test([1.0, 1.7, 0.9, 1.4], 50, seed=2)
    ub = np.linspace(0.8, 1.9, 5)
    far = gb.StaticPoints(ub, (0.2 * ub + 0.05 * ub ** 2 + 0.1) / 0.3 + np.array([0.5, -0.5, 0.5, -0.5, 0.5]),
                          input_names=("n",))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        warnings.filterwarnings("error", "no structure meets the band", gb.SelectionWarning)
        with pytest.raises(gb.SelectionWarning, match=r"no structure meets the band B = 1e-06.*smallest J_SF"):
            gb.select_graybox(CAND, gb.Dataset(rec1, rec2, far), band=1e-6, estimator="pe", sizes=[3],
                              fallback="min_jsf")
