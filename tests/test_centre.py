"""centre=True: structure selection that does not depend on where the signals' zeros are.

The candidate terms are monomials of the raw signals, so frols, semp and select_graybox chose
different structures for u in °C and in K (hunt38b: u + 1e4 spreads, a black box 25 times worse on
validation). With centre=True they search on the centred signals and close the choice under shifts.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.selection._centring import closure, raw_theta, signal_offsets

TRUE = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "u(k-2)^2"])
THETA = np.array([0.5, 0.3, 0.2, 0.1])


def _record(seed: int, n: int = 400) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, name=f"narx {seed}")


IDENT, VALID = _record(0), _record(1)
CAND = gb.Candidates(ny=2, nu=2, degree=2)


def _shift(rec: gb.Record, du: float, dy: float) -> gb.Record:
    return replace(rec, u=rec.u + du, y=rec.y + dy)


def _js(model: gb.Model, rec: gb.Record) -> float:
    return gb.mse(rec.y, model.simulate(rec, rec.y[: model.max_lag]), start=model.max_lag)


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        return fn(*args, **kw)


# offsets up to 300 spreads of u and of y: the raw closure's free run loses about (offset / spread)² ulps
offsets = st.tuples(st.floats(-300.0, 300.0), st.floats(-300.0, 300.0))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(offsets)
def test_frols_centred_is_invariant_under_offsets(shift):
    du, dy = shift[0] * IDENT.u.std(), shift[1] * IDENT.y.std()
    assume(abs(du) + abs(dy) > 0)  # the base case itself proves nothing
    base = _quiet(gb.frols, CAND, IDENT, criterion="bic", centre=True)
    moved = _quiet(gb.frols, CAND, _shift(IDENT, du, dy), criterion="bic", centre=True)
    assert set(moved.structure) == set(base.structure)
    assert _js(moved.model, _shift(VALID, du, dy)) == pytest.approx(_js(base.model, VALID), rel=1e-6)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(offsets)
def test_semp_and_exact_centred_are_invariant_under_offsets(shift):
    du, dy = shift[0] * IDENT.u.std(), shift[1] * IDENT.y.std()
    assume(abs(du) + abs(dy) > 0)
    moved_rec, moved_valid = _shift(IDENT, du, dy), _shift(VALID, du, dy)
    for fn, kw in ((gb.semp, {"n_terms": 4}), (gb.frols, {"n_terms": 4, "search": "exact"})):
        base = _quiet(fn, CAND, IDENT, centre=True, **kw)
        moved = _quiet(fn, CAND, moved_rec, centre=True, **kw)
        assert set(moved.structure) == set(base.structure)
        assert _js(moved.model, moved_valid) == pytest.approx(_js(base.model, VALID), rel=1e-6)


def test_raw_selection_does_depend_on_offsets():
    # what the option is for: without it, an offset of u changes the greedy pick
    base = _quiet(gb.frols, CAND, IDENT, n_terms=4)
    moved = _quiet(gb.frols, CAND, _shift(IDENT, 1e4 * IDENT.u.std(), 0.0), n_terms=4)
    assert set(moved.structure) != set(base.structure)


def test_closure_holds_every_divisor_and_the_chosen_terms_first():
    cl = closure(gb.Structure(["u(k-1)y(k-1)", "u(k-2)^2"]))
    assert list(cl)[:2] == list(gb.Structure(["u(k-1)y(k-1)", "u(k-2)^2"]))
    assert set(cl) == set(gb.Structure(["u(k-1)y(k-1)", "u(k-2)^2", "1", "u(k-1)", "y(k-1)", "u(k-2)"]))


def test_raw_theta_gives_the_centred_model_on_raw_signals():
    # a model fitted on centred signals, expanded, predicts the raw output the same
    st_ = closure(gb.Structure(["u(k-1)y(k-1)", "u(k-2)^2", "y(k-1)"])).process
    rng = np.random.default_rng(3)
    theta_c = rng.uniform(-0.3, 0.3, len(st_))
    off = {"y": 7.5, "u": -40.0}
    u = rng.uniform(-1.0, 1.0, 50)
    y_c = gb.Model(st_, theta_c).simulate(u, np.zeros(2))
    y_raw = gb.Model(st_, raw_theta(st_, theta_c, off)).simulate(u + off["u"], y_c[:2] + off["y"])
    np.testing.assert_allclose(y_raw - off["y"], y_c, atol=1e-9)


def test_raw_theta_refuses_an_open_structure():
    with pytest.raises(ValueError, match="not closed under shifts"):
        raw_theta(gb.Structure(["u(k-1)y(k-1)"]), np.ones(1), {"y": 0.0, "u": 1.0})


def test_offsets_are_the_pooled_means_of_every_record():
    a, b = _record(5, 100), _record(6, 300)
    off = signal_offsets([a, b])
    assert off["y"] == pytest.approx(np.concatenate([a.y, b.y]).mean())
    assert off["u"] == pytest.approx(np.concatenate([a.u, b.u]).mean())


def test_select_graybox_centred_is_invariant_under_offsets():
    data = gb.Dataset(IDENT, VALID)
    du, dy = 50 * IDENT.u.std(), -20 * IDENT.y.std()
    moved = gb.Dataset(_shift(IDENT, du, dy), _shift(VALID, du, dy))
    kw = {"band": np.inf, "estimator": "ls", "sizes": [2, 4], "sources": ["frols"], "centre": True}
    a, b = gb.select_graybox(CAND, data, **kw), gb.select_graybox(CAND, moved, **kw)
    assert set(a.structure) == set(b.structure)
    np.testing.assert_allclose(b.table["JS_valid"], a.table["JS_valid"], rtol=1e-6)
    assert (a.table["n_terms"] > a.table["size"]).any()  # the closures carry more terms than were searched


def test_select_graybox_centred_gray_rows_are_invariant_under_offsets():
    # the static form's terms (e.g. u(k-2)^2 for Σ_{u^2}) are closed too: every PE row, not only the structures
    ub = np.linspace(-0.9, 0.9, 7)
    yb = gb.Model(TRUE, THETA).static_curve(ub)
    du, dy = 30 * IDENT.u.std(), 10 * IDENT.y.std()
    data = gb.Dataset(IDENT, VALID, gb.StaticPoints(ub, yb))
    moved = gb.Dataset(_shift(IDENT, du, dy), _shift(VALID, du, dy), gb.StaticPoints(ub + du, yb + dy))
    kw = {"band": 0.01, "estimator": "pe", "sizes": [2, 3], "sources": ["frols"], "centre": True}
    a, b = gb.select_graybox(CAND, data, **kw), gb.select_graybox(CAND, moved, **kw)
    assert list(a.table.index) == list(b.table.index)
    for row in a.table.index:
        assert set(a.structure_of(row)) == set(b.structure_of(row))
        assert set(a.structure_of(row)) == set(closure(a.structure_of(row)))  # closed, static terms included
    np.testing.assert_allclose(b.table["JS_valid"], a.table["JS_valid"], rtol=1e-5)
    np.testing.assert_allclose(b.table["JSF"], a.table["JSF"], rtol=1e-5, atol=1e-12)


@pytest.mark.parametrize("bad", [1, "yes", None, np.array([True])])
def test_centre_must_be_a_flag(bad):
    with pytest.raises(TypeError, match="centre must be True or False"):
        gb.frols(CAND, IDENT, n_terms=3, centre=bad)
    with pytest.raises(TypeError, match="centre must be True or False"):
        gb.semp(CAND, IDENT, n_terms=3, centre=bad)
    with pytest.raises(TypeError, match="centre must be True or False"):
        gb.select_graybox(CAND, gb.Dataset(IDENT, VALID), band=np.inf, centre=bad)


def test_centre_refuses_dask_records():
    da = pytest.importorskip("dask.array")
    rec = gb.DaskRecord(da.from_array(IDENT.u, chunks=100), da.from_array(IDENT.y, chunks=100))
    with pytest.raises(ValueError, match="centre=True needs the records in memory"):
        gb.frols(CAND, rec, n_terms=3, centre=True)
    # its advice was to subtract the means by hand, which gives a model of the centred signals, not of the user's
    for fit in (gb.frols, gb.semp):
        with pytest.raises(ValueError, match=r"give a Record of its samples.*not of the signals in their own units"):
            fit(CAND, [rec, rec], n_terms=3, centre=True)


def test_centred_selection_on_several_records_gives_a_model_in_their_units():
    # checked (mend62b): several records are centred on their pooled means (as their concatenation), each record's
    # rows its own; the model returned is the closure's least-squares fit on the raw records, in their units and
    # period, and the same structure whatever the units and zeros (rpm and Pa far from zero here)
    from graybox.selection._centring import least_squares

    a, b = _record(5, 200), _record(6, 300)
    base = None
    for su, sy, du, dy in ((1.0, 1.0, 0.0, 0.0), (1e3, 1e5, 1200.0, 2e5)):
        recs = [gb.Record(r.u * su + du, r.y * sy + dy, Ts=0.5, units=("rpm", "Pa")) for r in (a, b)]
        sel = _quiet(gb.frols, CAND, recs, criterion="bic", centre=True)
        np.testing.assert_allclose(sel.theta, least_squares(sel.structure, recs, CAND.max_lag)[0], rtol=1e-9)
        assert (sel.model.units, sel.model.Ts) == (("rpm", "Pa"), 0.5)
        X, y = gb.stacked_regressors(sel.structure, recs, start=CAND.max_lag)
        assert np.sqrt(np.mean((X @ sel.theta - y) ** 2)) < 0.02 * sy  # the records' noise, 0.01, in their units
        base = base or set(sel.structure)
        assert set(sel.structure) == base


def test_centred_rss_of_exact_fits_are_floored_at_the_round_off_of_the_recorded_signals():
    # noise-free y ≈ 1e6, u ≈ 1e3: the search floors its RSS at 1e4 eps² yᵀy (centred) times the centring's gain, the
    # ratio of y's mean square as recorded to centred (its digits were rounded at 1e6); the subsets' RSS came
    # unfloored (3.5e-18) and the closure's refit floored without the gain (5.6e-17), below that round-off
    true = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    u = np.random.default_rng(0).uniform(0.0, 2.0, 400) + 1e3
    y = gb.simulate(true, np.array([0.2, 0.7, 0.3, 0.1]), u, np.zeros(1)) + 1e6
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (candidates the centred data cannot tell apart)
        sel = gb.frols(gb.Candidates(2, 2, degree=2), gb.Record(u, y), centre=True, search="swap", criterion="bic")
    rows = y[2:]
    gain = max(np.mean(rows**2) / np.var(rows), np.mean(u**2) / np.var(u))  # (the pooled signals: near enough)
    bound = 0.99 * 1e4 * np.finfo(float).eps ** 2 * gain * np.sum((rows - rows.mean()) ** 2)
    exact = [i for i, S in enumerate(sel.subsets) if set(true) <= set(S)]
    assert exact and np.all(sel.subset_rss[exact] >= bound)
    assert sel.rss[-1] >= bound and set(true) <= set(sel.structure)


@pytest.mark.parametrize("select", [lambda d: gb.frols(gb.Candidates(3, 3, degree=2), d, centre=True, search="greedy"),
                                    lambda d: gb.semp(gb.Candidates(2, 2, degree=2), d, centre=True)])
def test_centred_selection_on_noise_free_data_is_the_same_in_units_1e300_apart(select):
    # the closure of u(k-2)^2 brings 1 and u(k-2), whose raw parameters are truly 0 and came out of the expansion as
    # round-off (7e-18): with y × 1e-300 those were 7e-318, no float, and frols and semp refused 'the parameter(s) of
    # ['1', 'u(k-2)'] are beyond the float range' where y × 1 gave a model
    u = np.random.default_rng(1).uniform(-1.0, 1.0, 400)
    rec = gb.Record(u, gb.Model(TRUE, THETA).simulate(u, np.zeros(2)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (candidates the centred data cannot tell apart)
        a, b = select(rec), select(replace(rec, y=rec.y * 1e-300))
    assert list(a.structure) == list(b.structure) and set(TRUE) <= set(a.structure)
    # θ of a term with j output factors scales by 1e-300 ^ (1 − j)
    j = np.array([sum(p for s, _, p in t.factors if s == "y") for t in a.structure])
    ta, tb = np.asarray(a.theta), np.asarray(b.theta)
    assert np.allclose(tb, ta * 1e-300 ** (1 - j), rtol=1e-9, atol=0)
