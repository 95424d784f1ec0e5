"""Pareto sets as data, the non-dominated filter and the Figs. 5/7 plot."""

import dataclasses

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from graybox import Record, Structure, reference
from graybox.models._evaluate import evaluate_thetas, j1, js, jsf
from graybox.estimation._pareto import ParetoSet, nondominated_mask
from conftest import first_order_signals

S15 = reference.STRUCTURE_15


def dominates(a, b):
    return bool(np.all(a <= b) and np.any(a < b))


# ---------------------------------------------------------------------------------------------
# the filter
# ---------------------------------------------------------------------------------------------
objective_values = st.one_of(st.floats(0, 10, allow_nan=False), st.sampled_from([0.0, 1.0, np.inf]))


@settings(max_examples=30, deadline=None)
@given(P=st.integers(1, 40).flatmap(
    lambda k: st.integers(1, 3).flatmap(lambda m: arrays(float, (k, m), elements=objective_values))))
def test_property_filter_keeps_exactly_the_nondominated(P):
    keep = nondominated_mask(P)
    for i in range(len(P)):
        dominated = any(dominates(P[j], P[i]) for j in range(len(P)) if j != i)
        assert keep[i] == (not dominated)
    # every dropped member is dominated by a kept one (the front covers the set)
    for i in np.flatnonzero(~keep):
        assert any(dominates(P[j], P[i]) for j in np.flatnonzero(keep))


def test_filter_details():
    P = np.array([[1.0, 2.0], [1.0, 2.0], [2.0, 1.0], [2.0, 2.0], [np.nan, 0.0], [0.5, np.inf]])
    np.testing.assert_array_equal(nondominated_mask(P), [True, True, True, False, False, True])
    assert nondominated_mask(np.zeros((0, 2))).shape == (0,)
    with pytest.raises(ValueError, match="2-D"):
        nondominated_mask(np.ones(3))


# ---------------------------------------------------------------------------------------------
# ParetoSet
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(4)
    m = reference.paper_model(15)
    u = np.repeat(rng.uniform(750, 1650, 30), 50)[:1500]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    return Record(u, m.simulate(u, y0) + 0.05 * rng.standard_normal(1500), Ts=0.05)


@pytest.fixture(scope="module")
def thetas():
    return np.array([reference.TABLE_II[c] for c in ("ELS", "CLS", "PE")])


@pytest.fixture(scope="module")
def pset(record, thetas):
    return ParetoSet.from_thetas(S15, thetas, [1.0, 0.5, 0.01], record, reference.eq1_points(), method="test",
                                 extra={"tag": [1.0, 2.0, 3.0]})


def test_from_thetas_uses_the_shared_evaluator(pset, record, thetas):
    pts = reference.eq1_points()
    ev = evaluate_thetas(S15, thetas, record, pts)
    for k in ("J1", "JS", "JSF"):
        np.testing.assert_array_equal(getattr(pset, k), ev[k])
    for i, m in enumerate(pset.models()):
        assert getattr(pset, "J1")[i] == pytest.approx(j1(m, record), rel=1e-10)
        assert pset.JS[i] == pytest.approx(js(m, record), rel=1e-10)
        assert pset.JSF[i] == pytest.approx(jsf(m, pts), rel=1e-8)
    assert pset.JSF[0] == pytest.approx(1.618, abs=1e-3)  # ELS (15) against eq. (1), design.md


def test_from_thetas_several_records(record, thetas):
    a, b = record.slice(0, 700), record.slice(700, None)
    ps = ParetoSet.from_thetas(S15, thetas, None, [a, b], None)
    L = S15.max_lag
    for i in range(len(thetas)):
        ea = evaluate_thetas(S15, thetas[i:i + 1], a)
        eb = evaluate_thetas(S15, thetas[i:i + 1], b)
        wa, wb = len(a) - L, len(b) - L
        assert ps.J1[i] == pytest.approx((wa * ea["J1"][0] + wb * eb["J1"][0]) / (wa + wb))
        assert ps.JS[i] == pytest.approx((wa * ea["JS"][0] + wb * eb["JS"][0]) / (wa + wb))
    assert np.isnan(ps.JSF).all() and np.isnan(ps.lambdas).all()


def test_access_and_frame(pset, thetas):
    assert len(pset) == 3
    m = pset.member_model(1)
    np.testing.assert_array_equal(m.theta, thetas[1])
    assert "λ1=0.5" in m.name and pset.member_model(-1).name.endswith("0.01")
    df = pset.to_frame()
    assert list(df.columns) == ["lambda1", "J1", "JS", "JSF", "tag", "failure"] and len(df) == 3
    dfp = pset.to_frame(params=True)
    assert dfp.shape == (3, 6 + 17) and dfp["u(k-4)u(k-6)"].iloc[0] == thetas[0, 2]
    np.testing.assert_array_equal(pset.objective("tag"), [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="unknown objective"):
        pset.objective("J2")
    with pytest.raises(ValueError, match="out of range"):
        pset.member_model(3)


def test_nondominated_and_subset(pset):
    nd = pset.nondominated()
    pts = np.column_stack([pset.JS, pset.JSF])
    keep = nondominated_mask(pts)
    np.testing.assert_array_equal(nd.thetas, pset.thetas[keep])
    np.testing.assert_array_equal(nd.extra["tag"], pset.extra["tag"][keep])
    sub = pset.subset([2, 0])
    np.testing.assert_array_equal(sub.lambdas, [0.01, 1.0])
    one = pset.nondominated(objectives=("JSF",))
    assert len(one) == 1 and one.JSF[0] == pset.JSF.min()
    with pytest.raises(ValueError, match="mask"):
        pset.subset(np.array([True, False]))


def test_immutable(pset):
    with pytest.raises(dataclasses.FrozenInstanceError):
        pset.method = "x"
    for arr in (pset.thetas, pset.lambdas, pset.J1, pset.JS, pset.JSF, pset.extra["tag"]):
        with pytest.raises(ValueError):
            arr[0] = 0.0
    with pytest.raises(TypeError):
        pset.extra["new"] = np.zeros(3)


def test_validation():
    th = np.zeros((2, 17))
    ok = dict(lambdas=[0.1, 0.2], J1=[1, 2], JS=[1, 2], JSF=[1, 2])
    ParetoSet(S15, th, **ok)
    with pytest.raises(ValueError, match="shape"):
        ParetoSet(S15, np.zeros((2, 3)), **ok)
    with pytest.raises(ValueError, match="JS must have shape"):
        ParetoSet(S15, th, **{**ok, "JS": [1.0]})
    with pytest.raises(ValueError, match="finite"):
        ParetoSet(S15, np.full((2, 17), np.nan), **ok)
    with pytest.raises(ValueError, match="extra"):
        ParetoSet(S15, th, **ok, extra={"x": [1.0]})


# ---------------------------------------------------------------------------------------------
# Figs. 5 and 7
# ---------------------------------------------------------------------------------------------
def test_plot_pareto(pset):
    from matplotlib.figure import Figure

    from graybox.plots import plot_pareto

    table = pd.DataFrame({"JS_ident": [2.6, 3.2], "JSF": [1.6, 0.002]}, index=["ELS (15)", "CLS (22)"])
    fig = plot_pareto({"PE": pset}, table, band=0.031)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0] == "PE" and "ELS (15)" in labels and "CLS (22)" in labels and "B = [0, 0.031]" in labels
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    # a set with a diverging member: left out and said so
    bad = ParetoSet(S15, pset.thetas, pset.lambdas, pset.J1, np.array([1.0, np.inf, 2.0]), pset.JSF, "x")
    fig2 = plot_pareto(bad, {"ELS": (2.0, 1.0)}, band=None, log=False)
    assert "1 not drawn" in fig2.axes[0].get_legend().get_texts()[0].get_text()
    # a single model with an infinite J_SF: no marker, and the legend says why
    fig3 = plot_pareto(pset, {"ELS (17)": (0.8, np.inf)})
    assert any("ELS (17) (not drawn: J_SF = inf)" == t.get_text() for t in fig3.axes[0].get_legend().get_texts())
    with pytest.raises(TypeError, match="ParetoSet"):
        plot_pareto({"x": [1, 2]})
    with pytest.raises(ValueError, match="J_S, J_SF"):
        plot_pareto(pset, {"ELS": 3.0})
    with pytest.raises(ValueError, match="JS_ident"):
        plot_pareto(pset, pd.DataFrame({"a": [1]}))


def test_nondominated_refuses_an_objective_no_member_has():
    # a set evaluated without static points has J_SF NaN for every member; nondominated() (J_S, J_SF) dropped every
    # one (a row with a NaN is never kept) and returned an empty set without a word
    u, y = first_order_signals(200, 0, noise=0.0)
    st_ = Structure(["y(k-1)", "u(k-1)"])
    ps = ParetoSet.from_thetas(st_, [[0.5, 1.0], [0.4, 1.1], [0.6, 0.8]], [1.0, 0.5, 0.1], Record(u, y), None)
    assert np.isnan(ps.JSF).all()
    with pytest.raises(ValueError, match="no member of the set has a JSF.*without static points"):
        ps.nondominated()
    front = ps.nondominated(("J1", "JS"))  # the exact member dominates the others in both
    assert len(front) == 1 and front.thetas[0].tolist() == [0.5, 1.0]


@pytest.mark.parametrize("name", ["JS", "J1", "JSF", "lambda1", "failure"])
def test_extra_values_cannot_take_the_name_of_the_sets_own(name):
    # extra={"JS": …} was kept: to_frame() wrote it over the set's J_S column (9.0 where J_S was 1.0) while
    # objective("JS") gave the set's own
    st_ = Structure(["y(k-1)", "u(k-1)"])
    args = (st_, [[0.5, 1.0], [0.4, 1.1]], [1.0, 0.5], [0.1, 0.2], [1.0, 2.0], [3.0, 4.0], "x")
    with pytest.raises(ValueError, match=f"extra: '{name}' names a value the set holds itself"):
        ParetoSet(*args, {name: [9.0, 9.0]})
    with pytest.raises(TypeError, match="extra: a per-member value is named by a str"):
        ParetoSet(*args, {1: [9.0, 9.0]})
    frame = ParetoSet(*args, {"js": [9.0, 9.0]}).to_frame()
    assert frame["JS"].tolist() == [1.0, 2.0] and frame["js"].tolist() == [9.0, 9.0]


def _scaled_set(e: int) -> ParetoSet:
    """Two members of y(k-1), u(k-1) on a first-order record and three static points, y (and ȳ) times 2^e."""
    import graybox as gb
    from graybox import StaticPoints

    u, y = first_order_signals(200, 0, noise=0.1)
    s = 2.0**e
    ub = np.array([-0.5, 0.0, 0.5])
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    return ParetoSet.from_thetas(st, np.array([[0.5, 1.0], [0.45, 1.1]]) * [1, s], [0.5, 0.7],
                                 Record(u, y * s, Ts=1.0), StaticPoints(ub, (2 * ub + 0.01) * s))


@pytest.mark.parametrize("e", [512, -505])
def test_members_js_at_a_huge_or_tiny_output_are_the_ordinary_ones_times_its_square(e):
    """At y × 2^512 J_S (about 2^1018) was inf: the records' samples times J_S overflowed; the J's are the same
    problem's in ordinary units, times 2^(2e) (a power of two: exact)."""
    ordinary, far = _scaled_set(0), _scaled_set(e)
    for nm in ("J1", "JS", "JSF"):
        np.testing.assert_allclose(getattr(far, nm), np.ldexp(getattr(ordinary, nm), 2 * e), rtol=1e-12, err_msg=nm)


@pytest.mark.parametrize("e, reads", [(700, "inf"), (-700, "0")])
def test_members_js_beyond_the_float_range_are_refused_by_the_decision_rules(e, reads):
    """At y × 2^±700 the J's (output units², about 2^±1400) read inf (every member 'diverged') or 0 (every member
    perfect), and D_SF chose among them without a word; the set is kept (its θ are right), the choice refused."""
    from graybox import decide_dsf

    far = _scaled_set(e)
    assert np.all(far.JS == float(reads))
    said = rf"decide_dsf: member 0's J_S is {reads} .*2\^{e + 1}.*beyond the float range"
    with pytest.raises(ValueError, match=said):
        decide_dsf(far, band=1.0, fallback="min_jsf")


def test_choosing_records_at_a_huge_output_score_the_members_not_divergence():
    """At y × 2^512 D_SF on a validation record said every member diverged there (the samples times J_S, about
    2^1018, overflowed); it chooses as in ordinary units, its score the ordinary one times 2^1024."""
    import graybox as gb

    u, y = first_order_signals(400, 0, noise=0.1)
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    ub = np.array([-0.5, 0.0, 0.5])
    decisions = []
    for e in (0, 512):
        s = 2.0**e
        ident, valid = (Record(u[k:k + 200], y[k:k + 200] * s, Ts=1.0, name=n) for k, n in ((0, "i"), (200, "v")))
        ps = ParetoSet.from_thetas(st, np.array([[0.5, 1.0], [0.45, 1.1]]) * [1, s], [0.5, 0.7], ident,
                                   gb.StaticPoints(ub, (2 * ub + 0.01) * s))
        decisions.append(gb.decide_dsf(ps, band=float(np.ldexp(1.0, 2 * e - 4)), choose_on=valid))
    assert decisions[1].index == decisions[0].index
    assert decisions[1].score == pytest.approx(np.ldexp(decisions[0].score, 1024), rel=1e-12)


def test_a_grid_cells_members_on_a_huge_output_keep_their_validation_figures():
    """A grid cell's members at y × 2^512: every member's validation J_S read inf and its fit % -inf (the
    samples' squares overflowed); they are the ordinary units' (J_S times 2^1024, fit % the same), and gb.mse too."""
    import graybox as gb
    from graybox.experiments._cell import _members

    u, y = first_order_signals(400, 0, noise=0.1)
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    ub = np.array([-0.5, 0.0, 0.5])
    got = []
    for e in (0, 512):
        s = 2.0**e
        ident, valid = Record(u[:200], y[:200] * s, Ts=1.0), Record(u[200:], y[200:] * s, Ts=1.0)
        pts = gb.StaticPoints(ub, (2 * ub + 0.01) * s)
        ps = ParetoSet.from_thetas(st, np.array([[0.5, 1.0], [0.45, 1.1]]) * [1, s], [0.5, 0.7], ident, pts)
        got.append(_members(ps, gb.Dataset(ident, valid, pts)))
        got[-1]["mse"] = gb.mse(valid.y, gb.Model(st, ps.thetas[0]).simulate(valid), start=1)
    np.testing.assert_allclose(got[1]["JS_valid"], np.ldexp(got[0]["JS_valid"], 1024), rtol=1e-12)
    np.testing.assert_allclose(got[1]["fit_valid"], got[0]["fit_valid"], rtol=1e-12)
    assert got[1]["mse"] == pytest.approx(np.ldexp(got[0]["mse"], 1024), rel=1e-12)
    assert got[0]["mse"] == pytest.approx(got[0]["JS_valid"][0], rel=1e-12)


@pytest.mark.parametrize("e", [505, -505])
def test_a_diverging_or_exact_member_at_a_huge_or_tiny_output_is_no_range_artefact(e):
    """A member whose free run diverges (y(k-1) θ 1.3: J_S inf, J_SF inf) read as a J beyond the float range at
    y × 2^505 and even at y × 2^-505, where no J can overflow, and decide_dsf refused the set; so did a member whose
    static curve meets the points exactly (J_SF 0). The rule chooses what it chooses in ordinary units."""
    from graybox import StaticPoints, decide_dsf, parse_structure

    def chosen(k):
        u, y = first_order_signals(200, 0, noise=0.1)
        ub = np.array([-0.5, 0.0, 0.5])
        st = parse_structure(["y(k-1)", "u(k-1)"])
        th = np.array([[0.5, 1.0], [0.45, 1.0], [1.3, 1.0]]) * [1, 2.0**k]
        pset = ParetoSet.from_thetas(st, th, [0.5, 0.7, 0.9], Record(u, y * 2.0**k, Ts=1.0),
                                     StaticPoints(ub, 2 * ub * 2.0**k))
        return decide_dsf(pset, band=np.ldexp(0.5, 2 * k)).index

    assert chosen(e) == chosen(0) == 0


@pytest.mark.parametrize("e", [-600, 600])
def test_a_grid_cells_members_fit_percent_does_not_depend_on_the_outputs_units(e):
    """At y × 2^-600 every member's validation J_S (about 2^-1200) read 0 and its fit % read 100, a perfect fit
    made up: fit % is a ratio, the ordinary units' 100 (1 − ‖y − ŷ‖ / ‖y − mean y‖) in any units."""
    import graybox as gb
    from graybox.experiments._cell import _members

    u, y = first_order_signals(400, 0, noise=0.1)
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    ub = np.array([-0.5, 0.0, 0.5])
    th = np.array([[0.5, 1.0], [0.45, 1.1]])
    ident, valid = Record(u[:200], y[:200], Ts=1.0), Record(u[200:], y[200:], Ts=1.0)
    want = []
    for t in th:  # the free run and the fit % in ordinary units, by hand
        yh = np.zeros(200)
        yh[0] = valid.y[0]
        for k in range(1, 200):
            yh[k] = t[0] * yh[k - 1] + t[1] * valid.u[k - 1]
        want.append(100 * (1 - np.linalg.norm(valid.y[1:] - yh[1:]) / np.linalg.norm(valid.y[1:] - valid.y[1:].mean())))
    s = 2.0**e
    ident, valid = Record(ident.u, ident.y * s, Ts=1.0), Record(valid.u, valid.y * s, Ts=1.0)
    pts = gb.StaticPoints(ub, (2 * ub + 0.01) * s)
    ps = ParetoSet.from_thetas(st, th * [1, s], [0.5, 0.7], ident, pts)
    np.testing.assert_allclose(_members(ps, gb.Dataset(ident, valid, pts))["fit_valid"], want, rtol=1e-9)
