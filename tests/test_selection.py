"""FROLS / ERR structure selection (graybox.selection)."""

import dataclasses
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox import Candidates, Model, Record, Structure, stacked_regressors
from graybox.core._records import Dataset
from graybox.selection._forward_regression import CandidateWarning, frols, information_criterion
from graybox.selection._stopping import FewerTermsError

# A polynomial NARX with a constant, output and input lags, a cross term and a square.
TRUE_TERMS = ["1", "y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-1)^2"]
TRUE_THETA = np.array([0.3, 0.7, -0.3, 0.6, 0.2, -0.25])
TRUE = Structure(TRUE_TERMS)


def narx_record(seed: int, n: int = 1500, noise: float = 0.0) -> Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = Model(TRUE, TRUE_THETA).simulate(u, np.zeros(2))
    if noise:
        y = y + noise * np.std(y) * rng.standard_normal(n)
    return Record(u, y, name=f"narx{seed}")


# ---------------------------------------------------------------- correctness


@pytest.mark.parametrize("seed", range(5))
def test_recovers_exact_structure_noise_free(seed):
    sel = frols(Candidates(3, 3, ne=0, degree=2), narx_record(seed), n_terms=len(TRUE))
    assert set(sel.structure) == set(TRUE)
    order = [sel.structure.index(t) for t in TRUE]
    np.testing.assert_allclose(sel.theta[order], TRUE_THETA, atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_recovers_structure_with_output_noise_given_n_terms(seed):
    sel = frols(Candidates(3, 3, ne=0, degree=2), narx_record(seed, noise=0.05), n_terms=len(TRUE))
    assert set(sel.structure) == set(TRUE)


@pytest.mark.parametrize("criterion", ["aic", "bic", "fpe"])
def test_criterion_minimum_is_the_true_size_noise_free(criterion):
    with warnings.catch_warnings():
        # noise-free data: after the true terms, lagged copies of the model are exact
        # combinations of candidates and are (rightly) dropped with a warning
        warnings.simplefilter("ignore", CandidateWarning)
        sel = frols(Candidates(3, 3, ne=0, degree=2), narx_record(1), criterion=criterion)
    assert set(sel.structure) == set(TRUE)
    assert sel.criterion == criterion
    assert int(np.argmin(sel.criterion_curve)) + 1 == len(TRUE)
    assert len(sel.evaluated) > len(sel.structure)  # the curve looked past the minimum


def test_default_rule_is_bic():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        sel = frols(Candidates(3, 3, ne=0, degree=2), narx_record(2))
    assert sel.criterion == "bic" and "bic minimum" in sel.stop
    assert set(sel.structure) == set(TRUE)


def test_tol_stops_at_first_size_below_tolerance():
    rec = narx_record(3, noise=0.01)
    tol = 1e-3
    sel = frols(Candidates(3, 3, ne=0, degree=2), rec, tol=tol)
    unexplained = 1.0 - np.cumsum(sel.err)
    assert unexplained[-1] <= tol
    assert np.all(unexplained[:-1] > tol)


def test_err_matches_least_squares_residual_and_theta(rng):
    rec = narx_record(4, noise=0.05)
    cand = Candidates(3, 3, ne=0, degree=2)
    sel = frols(cand, rec, n_terms=9)
    psi, y = stacked_regressors(sel.structure, rec, start=cand.max_lag)
    theta, *_ = np.linalg.lstsq(psi, y, rcond=None)
    resid = y - psi @ theta
    np.testing.assert_allclose(1.0 - sel.err.sum(), resid @ resid / (y @ y), rtol=1e-9)
    np.testing.assert_allclose(sel.rss[-1], resid @ resid, rtol=1e-9)
    np.testing.assert_allclose(sel.theta, theta, rtol=1e-7, atol=1e-12)
    # the first ERR is the best single-term fit: no candidate explains more on its own
    P, _ = stacked_regressors(cand, rec, start=cand.max_lag)
    single = (P.T @ y) ** 2 / (np.einsum("ij,ij->j", P, P) * (y @ y))
    np.testing.assert_allclose(sel.err[0], single.max(), rtol=1e-12)


def test_several_records_never_straddle(rng):
    r1, r2 = narx_record(5, n=700, noise=0.02), narx_record(6, n=500, noise=0.02)
    cand = Candidates(3, 3, ne=0, degree=2)
    sel = frols(cand, [r1, r2], n_terms=8)
    assert sel.n_rows == (700 - 3) + (500 - 3)
    psi, y = stacked_regressors(sel.structure, [r1, r2], start=3)
    theta, *_ = np.linalg.lstsq(psi, y, rcond=None)
    np.testing.assert_allclose(sel.theta, theta, rtol=1e-7, atol=1e-12)
    # glueing the records into one would create rows across the seam: a different problem
    glued = Record(np.r_[r1.u, r2.u], np.r_[r1.y, r2.y])
    assert frols(cand, glued, n_terms=8).n_rows == sel.n_rows + 3


# ---------------------------------------------------------------- engineering units


def rpm_record(seed: int, n: int = 1500) -> Record:
    """A degree-3 NARX in x = (u − 1200)/450, written out in rpm: u ≈ 1e3, u³ ≈ 1e9."""
    a, b = 450.0, 1200.0 / 450.0
    terms = ["1", "y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-1)^2", "u(k-1)", "u(k-1)^3"]
    theta = [
        10 + 0.3 - 0.6 * b - 0.25 * b * b - 0.1 * b**3,
        0.7 - 0.2 * b,
        -0.3,
        0.6 / a,
        0.2 / a,
        -0.25 / a**2 + 0.3 * b / a**2,
        0.5 * b / a - 0.3 * b * b / a,
        0.1 / a**3,
    ]
    rng = np.random.default_rng(seed)
    u = rng.uniform(750.0, 1650.0, n)
    m = Model(Structure(terms), np.array(theta))
    y = m.simulate(u, np.full(2, 15.0)) + 0.01 * rng.standard_normal(n)
    return Record(u, y)


@pytest.mark.parametrize("seed", [0, 1])
def test_degree3_engineering_units_same_selection_as_unit_variance(seed):
    rec = rpm_record(seed)
    su, sy = rec.u.std(), rec.y.std()
    cand = Candidates(4, 4, ne=0, degree=3)
    eng = frols(cand, rec, n_terms=12)
    unit = frols(cand, Record(rec.u / su, rec.y / sy), n_terms=12)
    assert eng.structure == unit.structure
    np.testing.assert_allclose(eng.err, unit.err, rtol=1e-9, atol=1e-15)
    # θ in rpm units is θ on unit-variance data mapped back: θ = θ' · s_y / (s_u^p s_y^q)
    back = np.array(
        [th * sy / (su ** t.power_of("u") * sy ** t.power_of("y")) for th, t in zip(unit.theta, unit.structure)]
    )
    np.testing.assert_allclose(eng.theta, back, rtol=1e-6)
    assert 0.99 < eng.err_total <= 1.0


# ---------------------------------------------------------------- laws


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(40, 200),
    log_su=st.floats(-3, 4),
    log_sy=st.floats(-3, 4),
    offset=st.floats(-2, 2),
    degree=st.integers(1, 2),
    n_terms=st.integers(1, 12),
)
def test_err_in_unit_interval_and_sum_at_most_one(seed, n, log_su, log_sy, offset, degree, n_terms):
    rng = np.random.default_rng(seed)
    u = 10**log_su * (offset + rng.standard_normal(n))
    y = 10**log_sy * (offset + rng.standard_normal(n))
    cand = Candidates(2, 2, ne=0, degree=degree)
    sel = frols(cand, Record(u, y), n_terms=min(n_terms, len(cand)))
    assert np.all(sel.err >= 0.0) and np.all(sel.err <= 1.0)
    assert sel.err.sum() <= 1.0 + 1e-12
    assert np.all(np.diff(sel.rss) <= 1e-12 * sel.rss[0])  # adding a term never increases RSS
    assert len(set(sel.structure)) == len(sel.structure)


def test_information_criteria_definitions():
    rss = np.array([4.0, 2.0, 1.9])
    N = 100
    base = N * np.log(rss / N)
    k = np.arange(1, 4)
    np.testing.assert_allclose(information_criterion("aic", rss, N), base + 2 * k)
    np.testing.assert_allclose(information_criterion("bic", rss, N), base + k * np.log(N))
    np.testing.assert_allclose(information_criterion("fpe", rss, N), base + N * np.log((N + k) / (N - k)))
    with pytest.raises(ValueError, match="criterion"):
        information_criterion("hqc", rss, N)


# ---------------------------------------------------------------- noise terms


def test_noise_terms_are_carried_not_selected():
    rec = narx_record(7, noise=0.05)
    with_noise = frols(Candidates(3, 3, ne=2, degree=2), rec, n_terms=6)
    without = frols(Candidates(3, 3, ne=0, degree=2), rec, n_terms=6)
    assert with_noise.structure == without.structure
    assert not any(t.is_noise for t in with_noise.structure)
    assert [str(t) for t in with_noise.noise] == ["e(k-1)", "e(k-2)"]
    assert with_noise.n_candidates == len(Candidates(3, 3, ne=0, degree=2))
    assert len(without.noise) == 0


# ---------------------------------------------------------------- result value


def test_selection_is_an_immutable_value_that_prints_as_a_table():
    sel = frols(Candidates(3, 3, ne=2, degree=2), narx_record(8, noise=0.02), n_terms=6)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sel.err = np.zeros(6)
    with pytest.raises(ValueError):
        sel.err[0] = 0.5
    text = str(sel)
    assert "ERR" in text and "e(k-1)" in text
    for t in sel.structure:
        assert str(t) in text
    df = sel.to_frame()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == ["term", "ERR", "cumulative ERR", "aic", "selected", "theta"]
    assert list(df["term"]) == [str(t) for t in sel.structure]
    np.testing.assert_allclose(df["cumulative ERR"].iloc[-1], sel.err_total)
    m = sel.model
    assert m.structure == sel.structure and len(m.noise_structure) == 0
    assert "Selection(" in repr(sel)


def test_frame_marks_terms_evaluated_for_the_curve_only():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        sel = frols(Candidates(3, 3, ne=0, degree=2), narx_record(1), criterion="bic", max_terms=10)
    df = sel.to_frame()
    assert len(df) == 10 and df["selected"].sum() == len(sel.structure) == 6
    assert df["theta"].isna().sum() == 4
    assert "not selected" in str(sel)


# ---------------------------------------------------------------- bad input


def test_more_terms_than_candidates():
    cand = Candidates(2, 2, ne=0, degree=1)  # 5 terms
    with pytest.raises(ValueError, match="more than the 5 process candidates"):
        frols(cand, narx_record(0, n=100), n_terms=6)


@pytest.mark.parametrize("tol", [0.0, 1.0, -0.1, 1.5, float("nan")])
def test_tol_outside_open_unit_interval(tol):
    with pytest.raises(ValueError, match="tol"):
        frols(Candidates(2, 2, ne=0, degree=1), narx_record(0, n=100), tol=tol)


def test_constant_input_duplicates_are_skipped_with_a_warning():
    rng = np.random.default_rng(0)
    n = 400
    u = np.full(n, 1000.0)
    y = np.zeros(n)
    e = rng.standard_normal(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 2.0 + e[k]
    cand = Candidates(2, 2, ne=0, degree=2)
    with pytest.warns(CandidateWarning, match="proportional to 1"):
        sel = frols(cand, Record(u, y), n_terms=3)
    skipped = {str(t) for t, _ in sel.skipped}
    u_terms = {str(t) for t in cand if t.power_of("u") and not t.power_of("y")}
    assert u_terms <= skipped  # every pure input term duplicates the constant
    assert not ({str(t) for t in sel.structure} & u_terms)
    # the skip never produces a model with two copies of one column
    psi, _ = stacked_regressors(sel.structure, Record(u, y), start=2)
    assert np.linalg.matrix_rank(psi) == len(sel.structure)
    # asking for more terms than remain usable is an error, not a silent model
    with pytest.raises(ValueError, match="usable"), pytest.warns(CandidateWarning):
        frols(cand, Record(u, y), n_terms=len(cand) - len(u_terms) + 1)


def test_all_zero_candidate_columns_are_skipped_with_a_warning():
    rng = np.random.default_rng(1)
    n = 300
    y = np.cumsum(rng.standard_normal(n)) * 0.1 + 1.0
    with pytest.warns(CandidateWarning, match="all-zero"):
        sel = frols(Candidates(2, 2, ne=0, degree=2), Record(np.zeros(n), y), n_terms=2)
    assert all(t.power_of("u") == 0 for t in sel.structure)
    assert sum(why == "all-zero column" for _, why in sel.skipped) == 2 + 3 + 4  # u, u², u·y terms


BIN_TERMS = ["1", "y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)"]


def test_binary_input_square_duplicates_constant():
    rng = np.random.default_rng(2)
    n = 800
    u = rng.choice([-1.0, 1.0], n)
    y = Model(Structure(BIN_TERMS), [0.3, 0.7, -0.3, 0.6, 0.2]).simulate(
        u, np.zeros(2)
    )
    with pytest.warns(CandidateWarning, match=r"u\(k-1\)\^2 \(proportional to 1\)"):
        sel = frols(Candidates(2, 2, ne=0, degree=2), Record(u, y), n_terms=5)
    assert set(map(str, sel.structure)) == set(BIN_TERMS)


def test_dependent_candidates_end_selection_with_a_clear_error():
    # noise-free data of a lag-2 model: with lag-3 candidates, y(k-1) is an exact combination
    # of other candidates, so the candidate matrix is rank deficient
    cand = Candidates(3, 3, ne=0, degree=2)
    with pytest.raises(ValueError, match="independent terms.*linear combinations"):
        frols(cand, narx_record(0), n_terms=len(cand))


def test_argument_checks():
    rec = narx_record(0, n=100)
    cand = Candidates(2, 2, ne=0, degree=1)
    with pytest.raises(ValueError, match="either n_terms or tol"):
        frols(cand, rec, n_terms=2, tol=0.1)
    with pytest.raises(ValueError, match="n_terms must be an integer >= 1"):
        frols(cand, rec, n_terms=0)
    with pytest.raises(ValueError, match="criterion"):
        frols(cand, rec, criterion="hqc")
    # one spelling, as semp has it: the criteria are lower case
    with pytest.raises(ValueError, match="criterion must be one of 'aic', 'bic', 'fpe'"):
        frols(cand, rec, criterion="BIC")
    with pytest.raises(TypeError, match="tol must be a real number"):
        frols(cand, rec, tol="0.1")
    with pytest.raises(ValueError, match="max_terms"):
        frols(cand, rec, n_terms=2, max_terms=3)
    # a candidate set is taken as every structure argument is (a list of terms too); what carries none is refused
    assert frols([str(t) for t in cand], rec, n_terms=2).structure == frols(cand, rec, n_terms=2).structure
    with pytest.raises(TypeError, match="Structure"):
        frols(3.0, rec, n_terms=1)
    with pytest.raises(ValueError, match="no process terms"):
        frols(Structure(["e(k-1)"]), rec, n_terms=1)
    # a Dataset stands for its identification record, as for every estimator
    assert frols(cand, Dataset(rec, rec), n_terms=2).structure == frols(cand, rec, n_terms=2).structure
    with pytest.raises(ValueError, match="identically zero"):
        frols(cand, Record(rec.u, np.zeros(100)), n_terms=1)
    with pytest.raises(ValueError, match="fewer than max lag"):
        frols(cand, Record([1.0, 2.0], [1.0, 2.0]), n_terms=1)


def test_edge_warnings():
    rec = narx_record(1, noise=0.01)
    with pytest.warns(RuntimeWarning, match="not reached"):
        sel = frols(Candidates(3, 3, ne=0, degree=2), rec, tol=1e-9, max_terms=3)
    assert len(sel.structure) == 3 and "not reached" in sel.stop
    with pytest.warns(RuntimeWarning, match="still be"):
        frols(Candidates(3, 3, ne=0, degree=2), rec, criterion="aic", max_terms=3)


def test_included_terms_come_first():
    from graybox import Candidates, Record, frols

    rng = np.random.default_rng(2)
    u = rng.uniform(-1, 1, 400)
    y = np.zeros(400)
    for k in range(2, 400):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.3 * u[k - 2] * u[k - 1]
    rec = Record(u, y)
    sel = frols(Candidates(2, 2, ne=0, degree=2), rec, n_terms=4, include=["1", "y(k-2)"])
    assert [str(t) for t in sel.structure][:2] == ["1", "y(k-2)"]
    assert len(sel.structure) == 4 and len(sel.err) == 4
    with pytest.raises(ValueError, match="not among the process candidates"):
        frols(Candidates(2, 2, ne=0, degree=2), rec, n_terms=3, include=["y(k-5)"])
    with pytest.raises(ValueError, match="fewer than the 2 included"):
        frols(Candidates(2, 2, ne=0, degree=2), rec, n_terms=1, include=["1", "y(k-1)"])


def _offset_narx(N=300, seed=0):
    """A stable 2nd-order polynomial NARX of order 1, u uniform in [0, 1]."""
    rng = np.random.default_rng(seed)
    u, y = rng.uniform(0, 1, N), np.zeros(N)
    for k in range(1, N):
        y[k] = 0.5 * y[k - 1] + 0.8 * u[k - 1] + 0.2 * u[k - 1] ** 2 + 0.1 * y[k - 1] * u[k - 1]
    return u, y


@pytest.mark.parametrize("method, du, dy", [("gram", 1e3, -1e4), ("mgs", 1e4, -1e5)])
def test_frols_fewer_terms_on_offset_signals_names_the_offsets(method, du, dy):
    # raw monomials of signals far from zero are nearly collinear with the constant: the search runs out of
    # independent terms, which the error says is the offsets' doing (centre=True selects all 6 on the same data)
    u, y = _offset_narx()
    rec = Record(u + du, y + dy)
    cands = Candidates(2, 2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        with pytest.raises(FewerTermsError) as err:
            frols(cands, rec, n_terms=6, method=method)
        assert err.value.reached == 5
        assert "far from zero" in str(err.value) and "centre=True" in str(err.value)
        assert len(frols(cands, rec, n_terms=6, method=method, centre=True).structure) >= 6


def test_frols_fewer_terms_near_zero_does_not_blame_offsets():
    # the same error on signals about zero (u(k-1) given twice over: a duplicate column) says nothing of offsets
    u, y = _offset_narx()
    rec = Record(np.column_stack([u - 0.5, 2 * (u - 0.5)]), y - y.mean(), input_names=("a", "b"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        with pytest.raises(FewerTermsError) as err:
            frols(Structure(["a(k-1)", "b(k-1)", "y(k-1)"]), rec, n_terms=3, method="mgs")
    assert "far from zero" not in str(err.value)


def test_semp_short_of_its_size_on_offset_signals_names_the_offsets():
    # semp on u + 1e4, y − 1e5 said only "the search never reached 6 terms (… collinear …)"; centre=True reaches them
    from graybox import semp
    u, y = _offset_narx()
    rec = Record(u + 1e4, y - 1e5)
    with pytest.raises(ValueError, match=r"never reached 6 terms.*far from zero.*centre=True"):
        semp(Candidates(2, 2, degree=2), rec, n_terms=6)


def test_frols_fewer_terms_that_centring_does_not_mend_does_not_blame_offsets():
    # a two-level input far from zero: u(k-1)² is affine in u(k-1) whatever the offset, so centre=True runs out at
    # the same 3 terms; the note said the offsets were the cause and pointed to centre=True all the same
    rng = np.random.default_rng(0)
    u = np.where(rng.random(300) < 0.5, -1.0, 1.0)
    y = np.zeros(300)
    for k in range(1, 300):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.01 * rng.standard_normal()
    cands = Structure(["1", "u(k-1)", "u(k-1)^2", "y(k-1)"])
    rec = Record(u + 1e4, y - 1e5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        for centre in (True, False):
            with pytest.raises(FewerTermsError) as err:
                frols(cands, rec, n_terms=4, centre=centre)
            assert err.value.reached == 3 and "far from zero" not in str(err.value), str(err.value)


def test_frols_fewer_terms_with_a_held_input_does_not_blame_offsets():
    # an input held at 5 has no spread: centred it is zero, so centre=True is no way out and the note would mislead
    u, y = _offset_narx()
    rec = Record(np.column_stack([u, np.full(u.size, 5.0)]), y, input_names=("a", "b"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        with pytest.raises(FewerTermsError) as err:
            frols(Structure(["a(k-1)", "b(k-1)", "y(k-1)", "1"]), rec, n_terms=4)
    assert err.value.reached == 3 and "far from zero" not in str(err.value)


@pytest.mark.parametrize("how", [dict(), dict(search="exact"), dict(semp=True)])
def test_tolerance_cut_short_by_the_rows_says_so_not_that_every_candidate_was_looked_at(how):
    # 6 samples of a lag-2 record: 4 rows, so at most 3 terms of the 15 candidates; the tolerance unmet there was
    # said as "every candidate was looked at: raise tol, or add candidates", where a longer record is what is needed
    rng = np.random.default_rng(3)
    rec = Record(rng.uniform(-1.0, 1.0, 6), rng.uniform(-1.0, 1.0, 6))
    cand = Candidates(2, 2, degree=2)
    kw = {k: v for k, v in how.items() if k != "semp"}
    select = gb.semp if how.get("semp") else frols
    with pytest.warns(RuntimeWarning, match="tolerance 1e-30 not reached") as said:
        sel = select(cand, rec, tol=1e-30, **kw)
    assert len(sel.structure) == 3
    text = " ".join(str(w.message) for w in said)
    assert "every candidate was looked at" not in text and "4 regression rows" in text and "longer record" in text


@pytest.mark.parametrize("search", ["greedy", "swap", "exact", "semp"])
def test_a_tolerance_below_round_off_is_met_by_an_exact_fit(search):
    # noise-free data, tol = 1e-30: the true 6 terms fit to round-off (the unexplained fraction's floor, 1e-20), which
    # no tolerance can ask more of; greedy stopped there but warned "not reached ... raise max_terms or tol", swap,
    # exact and semp went on to 27 terms fitted to round-off (semp over 350 steps) and warned
    rec = narx_record(0, n=200)
    cand = Candidates(3, 3, ne=0, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        sel = gb.semp(cand, rec, tol=1e-30) if search == "semp" else frols(cand, rec, tol=1e-30, search=search)
    assert set(sel.structure) == set(TRUE)
    assert "not reached" not in sel.stop


# ---------------------------------------------------------------- round-off of the residual sums (hunt62f)


def offset_record(c: float, n: int = 200, scale: float = 1.0) -> Record:
    """Noise-free y(k) − c = 0.5 (y(k-1) − c) + u(k-1) + 0.1 u(k-1)² at y ≈ c (each sample ±2 about it), times
    ``scale``: the true raw structure is 1, y(k-1), u(k-1), u(k-1)^2."""
    u = np.random.default_rng(1).uniform(-1.0, 1.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.1 * u[k - 1] ** 2
    return Record(u, (y + c) * scale)


@pytest.mark.parametrize("method", ["mgs", "gram"])
def test_the_rss_curve_is_each_prefix_s_own_least_squares_residual_at_an_output_offset(method):
    # was: RSS = yᵀy − Σg², a difference that cancels to eps·yᵀy (7e-6 at y ≈ 1e4 here): greedy's path
    # 1, u(k-1)y(k-1), y(k-1), u(k-1)^2 fits to RSS 4.1e-7 and was stored as 3.0e-10 (the 1e-20 yᵀy floor), so BIC
    # took that wrong 4-term model as an exact fit
    rec = offset_record(1e4)
    cand = Candidates(2, 2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        sel = frols(cand, rec, n_terms=6, method=method)
    for k in range(1, 7):
        psi, y = stacked_regressors(sel.structure[:k], rec, start=cand.max_lag)
        theta = np.linalg.lstsq(psi, y, rcond=None)[0]
        resid = y - psi @ theta
        if resid @ resid > 1e-12:  # well above the round-off of either computation
            np.testing.assert_allclose(sel.rss[k - 1], resid @ resid, rtol=1e-6, err_msg=str(sel.structure[:k]))


@pytest.mark.parametrize("scale", [1.0, 1e-12])
def test_noise_free_far_from_zero_the_exact_fit_is_told_from_a_near_one(scale):
    # y ≈ 1e6 (and the same in units where y ≈ 1e-6): u(k-1)y(k-1) ≈ 1e6 u(k-1), so 1, u(k-1)y(k-1), y(k-1), u(k-1)^2
    # fits to RSS 4e-11 (1.4e-25 yᵀy), 3e6 eps² yᵀy; the true terms fit to ~1 eps² yᵀy. The floor at 1e-20 yᵀy
    # counted both exact: exact's "proven" best 4 terms were the wrong ones, and greedy stopped at them (BIC)
    rec = offset_record(1e6, scale=scale)
    cand = Candidates(2, 2, degree=2)
    true = set(Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        exact = frols(cand, rec, search="exact")
        greedy = frols(cand, rec, criterion="bic")
    assert set(exact.structure) == true
    assert true <= set(greedy.structure)  # greedy's path took u(k-1)y(k-1) first: it stays, the true terms join it
    _, y = stacked_regressors(exact.structure, rec, start=cand.max_lag)
    assert exact.subset_rss[list(exact.subsets).index(exact.structure)] < 1e-26 * (y @ y)


def test_candidates_skipped_on_signals_far_from_zero_name_the_offsets(method="gram"):
    # y ≈ 1e6 varying by ±1 with noise 1e-3: the Gram form skipped y(k-1), y(k-2) and every y product as
    # 'proportional to' 1 or another term, saying 'the data cannot tell them from others', and chose no y term at all;
    # the data tell them apart (noise 1e-3 against a spread of 1): the warning now names the offset and centre=True
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 3.0, 120), 5)
    y = Model(Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]), [0.6, 0.2, 0.3, 0.05, 0.4]).simulate(
        u, np.zeros(2))
    rec = Record(u, y + 1e6 + 1e-3 * rng.standard_normal(u.size))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # BIC at the largest size: not what this test is of
        with pytest.warns(CandidateWarning, match=r"skipped.*far from zero.*centre=True"):
            frols(Candidates(2, 2, degree=2), rec, max_terms=6, method=method)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert "y(k-1)" in map(str, frols(Candidates(2, 2, degree=2), rec, max_terms=6, method=method,
                                          centre=True).structure.terms)
