"""Several inputs (issue 15): terms, records, loaders, regressors, kernels, static surfaces."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox import Candidates, Record, StaticPoints, Structure, Term, parse_term
from graybox.core._records import Dataset, as_records
from graybox.core._regressors import record_signals, regressor_matrix
from graybox.datasets import load_record_csv, load_static_csv


# -- terms ---------------------------------------------------------------------
@pytest.mark.parametrize("text", ["u1(k-1)u2(k-2)", "u2(k-1)^2y(k-1)", "n1(k-3)n2(k-1)^2", "u1(k-1)", "u2(k-3)u10(k-1)"])
def test_miso_terms_print_and_parse(text):
    t = parse_term(text)
    assert str(t) == text
    assert parse_term(str(t)) == t


def test_miso_term_order_and_powers():
    t = parse_term("y(k-1)u2(k-1)^2")
    assert str(t) == "u2(k-1)^2y(k-1)" and t.input_names == ("u2",) and t.input_power == 2 and t.power_of("y") == 1
    assert parse_term("u2(k-2)u1(k-1)") == parse_term("u1(k-1)u2(k-2)")
    s = Structure(["u2(k-1)", "y(k-1)", "u1(k-2)y(k-1)", "1"])
    assert s.input_names == ("u1", "u2") and s.input_lag("u2") == 1 and s.input_lag("u1") == 2


def test_candidates_per_input_lags_and_delays():
    c = Candidates(1, {"u1": 2, "u2": 4}, delay={"u2": 3}, degree=1)
    assert [str(t) for t in c] == ["1", "u1(k-1)", "u1(k-2)", "u2(k-3)", "u2(k-4)", "y(k-1)"]
    c2 = Candidates(2, 2, input_names=["u1", "u2"], degree=2)
    # 1 + 6 linear + 21 quadratic in 6 variables
    assert len(c2) == 28 and set(c2.input_names) == {"u1", "u2"}
    assert Candidates(6, 6, ne=2, degree=2) == Candidates(6, {"u": 6}, ne=2, degree=2)


@pytest.mark.parametrize("kw,msg", [
    (dict(nu=2, input_names=["u1", "u1"]), "named twice"),
    (dict(nu=2, input_names=["y"]), "not a valid identifier other than y"),
    (dict(nu={"u1": 2}, delay={"u2": 1}), "not among the inputs"),
    (dict(nu={"u1": 2, "u2": 1}, delay={"u2": 3}), "delay of input 'u2' \\(3\\) must not exceed"),
    (dict(nu=2, input_names=["u1", "u2"], delay={"u1": 0}), "delay of input 'u1' must be an integer >= 1"),
])
def test_candidates_bad_input(kw, msg):
    with pytest.raises(ValueError, match=msg):
        Candidates(1, **kw)


# -- records -------------------------------------------------------------------
def _rec2(n=50, names=None, seed=0, name="r"):
    rng = np.random.default_rng(seed)
    return Record(rng.uniform(0, 1, (n, 2)), rng.normal(size=n), name=name, input_names=names)


def test_record_with_two_inputs():
    r = _rec2()
    assert r.u.shape == (50, 2) and r.n_inputs == 2 and r.input_names == ("u1", "u2") and len(r) == 50
    assert np.array_equal(r.input("u2"), r.u[:, 1])
    sig = record_signals(r)
    assert set(sig) == {"u1", "u2", "y"} and np.array_equal(sig["u1"], r.u[:, 0])
    assert r.slice(5, 20).input_names == ("u1", "u2") and len(r.slice(5, 20)) == 15
    siso = Record(np.arange(5.0), np.zeros(5))
    assert siso.u.ndim == 1 and siso.input_names == ("u",) and set(record_signals(siso)) == {"u", "y"}
    assert "u1 in" in repr(r)


def test_records_must_agree_in_inputs():
    a, b = _rec2(name="a"), _rec2(names=("n1", "n2"), name="b")
    with pytest.raises(ValueError, match="'a' has inputs \\('u1', 'u2'\\) but 'b' has inputs \\('n1', 'n2'\\)"):
        as_records([a, b])
    with pytest.raises(ValueError, match="has inputs"):
        Dataset(a, b)
    with pytest.raises(ValueError, match="has inputs"):
        Dataset(a, _rec2(name="v"), StaticPoints(np.arange(3.0), np.ones(3)))
    with pytest.raises(ValueError, match="named twice"):
        _rec2(names=("n1", "n1"))
    with pytest.raises(ValueError, match="2 names .* for 3 input"):
        Record(np.ones((5, 3)), np.ones(5), input_names=("a", "b"))


def test_static_points_in_input_space():
    sp = StaticPoints([[1, 2], [1, 3], [2, 2]], [0.1, 0.2, 0.3])
    assert sp.ubar.shape == (3, 2) and sp.n_inputs == 2 and len(sp) == 3
    with pytest.raises(ValueError, match="duplicated ubar"):
        StaticPoints([[1, 2], [1, 2]], [0.1, 0.2])


# -- loaders -------------------------------------------------------------------
def test_load_csv_with_several_inputs(tmp_path):
    p = tmp_path / "rig.csv"
    rng = np.random.default_rng(1)
    data = rng.uniform(size=(20, 3))
    p.write_text("n1,n2,p\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in data) + "\n")
    r = load_record_csv(p, ["n1", "n2"], "p", Ts=0.1)
    assert r.input_names == ("n1", "n2") and np.array_equal(r.u, data[:, :2]) and np.array_equal(r.y, data[:, 2])
    r2 = load_record_csv(p, ["n1", "n2"], "p", Ts=0.1, input_names=["u1", "u2"])
    assert r2.input_names == ("u1", "u2")
    sp = load_static_csv(p, ["n2", "n1"], "p")
    assert sp.input_names == ("n2", "n1") and np.array_equal(sp.ubar, data[:, [1, 0]])
    with pytest.raises(ValueError, match="named twice"):
        load_record_csv(p, ["n1", "n1"], "p", Ts=0.1)
    with pytest.raises(ValueError, match="no column 'n3'"):
        load_record_csv(p, ["n1", "n3"], "p", Ts=0.1)


# -- regressors ----------------------------------------------------------------
def test_regressor_columns_by_input_name():
    r = _rec2(names=("a", "b"))
    st = Structure(["a(k-1)b(k-2)", "b(k-1)^2y(k-1)", "1"])
    psi = regressor_matrix(st, r.u, r.y, input_names=r.input_names)
    a, b, y = r.u[:, 0], r.u[:, 1], r.y
    assert np.allclose(psi[:, 0], a[1:-1] * b[:-2])
    assert np.allclose(psi[:, 1], b[1:-1] ** 2 * y[1:-1])
    with pytest.raises(ValueError, match="needs input 'c'"):
        regressor_matrix(Structure(["c(k-1)"]), r.u, r.y, input_names=r.input_names)


# -- kernels and simulation ------------------------------------------------------
_ST2 = Structure(["y(k-1)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "u2(k-1)^2y(k-2)", "u1(k-2)y(k-1)", "1"])
_TH2 = np.array([0.5, 0.3, -0.2, 0.1, -0.05, 0.05, 0.1])


def _reference_free_run(st, th, u_by_name, y0, n):
    y = np.empty(n)
    L = st.max_lag
    y[:L] = y0[:L]
    for k in range(L, n):
        acc = 0.0
        for c, t in zip(th, st):
            v = c
            for s, lag, p in t.factors:
                v *= (y[k - lag] if s == "y" else u_by_name[s][k - lag]) ** p
            acc += v
        y[k] = acc
    return y


def _miso_record(n=300, seed=3, names=("u1", "u2")):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, (n // 20 + 1, 2)), 20, axis=0)[:n]
    m = gb.Model(_ST2, _TH2, input_names=names) if names == ("u1", "u2") else None
    y = _reference_free_run(_ST2, _TH2, {"u1": u[:, 0], "u2": u[:, 1]}, np.zeros(2), n)
    return Record(u, y, input_names=names), m


def test_miso_kernels_match_a_plain_loop():
    from graybox.core._simulation_kernels import batch_sse, encode, free_run_sensitivity, record_inputs

    rec, m = _miso_record()
    ref = rec.y
    assert np.allclose(m.simulate(rec), ref, rtol=1e-12, atol=1e-12)
    assert np.allclose(m.simulate(rec.u, rec.y[:2]), ref, rtol=1e-12, atol=1e-12)
    # columns taken by name: a record with the inputs swapped gives the same run
    swapped = Record(rec.u[:, ::-1], rec.y, input_names=("u2", "u1"))
    assert np.allclose(m.simulate(swapped), ref, rtol=1e-12, atol=1e-12)
    thetas = _TH2 * np.array([[1.0], [0.99], [1.01]])
    many = gb.simulate_many(_ST2, thetas, swapped)
    for i in range(3):
        assert np.allclose(many[i], gb.simulate(_ST2, thetas[i], rec), rtol=1e-12, atol=1e-12)
    code = encode(_ST2)
    assert code.input_names == ("u1", "u2")
    sse = batch_sse(code, thetas, record_inputs(swapped, code.input_names), rec.y, 2)
    assert np.allclose(sse, ((many[:, 2:] - rec.y[2:]) ** 2).sum(axis=1), rtol=1e-10)
    y, S = free_run_sensitivity(code, _TH2, rec.u, rec.y[:2], 2)
    h = 1e-6
    for j in (0, 3, 4):
        tp, tm = _TH2.copy(), _TH2.copy()
        tp[j] += h
        tm[j] -= h
        fd = (gb.simulate(_ST2, tp, rec) - gb.simulate(_ST2, tm, rec)) / (2 * h)
        assert np.allclose(S[:, j], fd, rtol=1e-5, atol=1e-7)
    assert np.allclose(m.predict(rec)[2:], ref[2:], rtol=1e-12, atol=1e-12)


def test_miso_model_knows_its_inputs():
    rec, m = _miso_record()
    assert m.input_names == ("u1", "u2") and m.n_inputs == 2
    assert gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).input_names == ("u",)
    with pytest.raises(ValueError, match="uses input 'u2', which is not among input_names"):
        gb.Model(_ST2, _TH2, input_names=("u1",))
    with pytest.raises(ValueError, match="named twice"):
        gb.Model(_ST2, _TH2, input_names=("u1", "u2", "u2"))


def test_miso_mismatched_inputs_are_clear_errors():
    rec, m = _miso_record()
    other = Record(rec.u, rec.y, input_names=("a", "b"))
    with pytest.raises(ValueError, match="uses input 'u1', but the record's inputs are \\('a', 'b'\\)"):
        m.simulate(other)
    with pytest.raises(ValueError, match="needs input 'u1'"):
        m.predict(other)
    with pytest.raises(ValueError, match="2 names .* for 3 input"):
        m.simulate(np.ones((50, 3)), np.zeros(2))
    with pytest.raises(ValueError, match="one input column"):
        gb.simulate(_ST2, _TH2, np.ones(50), np.zeros(2))
    with pytest.raises(ValueError, match="needs max lag = 9"):
        gb.simulate(Structure(["u1(k-9)", "u2(k-1)"]), [1.0, 1.0], Record(np.ones((5, 2)), np.ones(5)))
    with pytest.raises(ValueError, match="fewer than max lag"):
        gb.Model(Structure(["u1(k-9)", "u2(k-1)"]), [1.0, 1.0]).predict(Record(np.ones((5, 2)), np.ones(5)))


# -- FROLS ---------------------------------------------------------------------
_TRUE2 = Structure(["y(k-1)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "u2(k-1)y(k-1)", "1"])
_TRUE2_THETA = np.array([0.5, 0.8, -0.4, 0.3, -0.1, 0.2])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_frols_recovers_a_two_input_structure(seed):
    rng = np.random.default_rng(seed)
    n = 1500
    u = rng.uniform(-1, 1, (n, 2))
    e = 0.02 * rng.standard_normal(n)  # equation noise: a NARX model, as FROLS assumes
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = (0.5 * y[k - 1] + 0.8 * u[k - 1, 0] - 0.4 * u[k - 2, 1] + 0.3 * u[k - 1, 0] * u[k - 1, 1]
                - 0.1 * u[k - 1, 1] * y[k - 1] + 0.2 + e[k])
    rec = Record(u, y)
    cand = Candidates(2, 2, input_names=["u1", "u2"], degree=2)
    assert all(t in cand for t in _TRUE2)
    by_size = gb.frols(cand, rec, n_terms=len(_TRUE2))
    assert set(by_size.structure) == set(_TRUE2)
    by_bic = gb.frols(cand, rec)  # the default stopping rule (BIC) finds the size too
    assert set(by_bic.structure) == set(_TRUE2)
    # the Gram (covariance) form, which long records take, reads the inputs by name too
    gram = gb.frols(cand, rec, n_terms=len(_TRUE2), method="gram")
    assert list(gram.structure) == list(by_size.structure)
    np.testing.assert_allclose(gram.theta, by_size.theta, rtol=1e-8)


# -- static surface --------------------------------------------------------------
from hypothesis import assume, given, settings, strategies as hst  # noqa: E402

from graybox.static._surface_analysis import (  # noqa: E402
    static_surface, static_surface_gain, surface_cluster_map, surface_equilibria,
)

_RATIONAL2 = Structure(["y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "u2(k-1)y(k-1)",
                        "u1(k-2)^2", "1"])
_POLY2 = Structure(["y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-2)", "u1(k-1)u2(k-1)", "u2(k-1)y(k-1)",
                    "y(k-1)^2", "1"])


def _long_run(st, th, ub, y0, n=4000):
    return gb.simulate(st, th, np.tile(ub, (n, 1)), np.full(st.max_lag, y0), on_diverge="nan")


@given(th=hst.lists(hst.floats(-1, 1), min_size=8, max_size=8), ub=hst.tuples(hst.floats(-2, 2), hst.floats(-2, 2)),
       scale=hst.sampled_from([1e-3, 1.0, 1e3]), poly=hst.booleans(), y0=hst.floats(-1, 1))
@settings(max_examples=60, deadline=None)
def test_static_surface_is_the_simulated_steady_state(th, ub, scale, poly, y0):
    # θ of the y-terms kept small enough for a stable model over most of the input box; the
    # input scale (1e-3, 1, 1e3: mrpm, rpm, krpm) must not matter
    th = np.array(th) * np.array([0.5, 0.3, 1, 1, 0.5, 0.2, 0.3 if not poly else 0.2, 1])
    st = _POLY2 if poly else _RATIONAL2
    ubs = np.array(ub) * scale
    th = th / np.array([1, 1, scale, scale, scale**2, scale, 1 if poly else scale**2, 1])
    eqs = surface_equilibria(st, th, ubs)
    assume(any(e.stable and e.spectral_radius < 0.9 for e in eqs))
    y_start = 0.0 if not poly else y0
    y = _long_run(st, th, ubs, y_start)
    assume(np.isfinite(y[-1]))
    settled = y[-1]
    assert abs(y[-1] - y[-2]) <= 1e-9 * max(1.0, abs(settled))
    got = static_surface(st, th, ubs[None, :], y0=y_start, strict=False)[0]
    assert np.isclose(got, settled, rtol=1e-7, atol=1e-9)
    if not poly:  # rational: the closed form needs no initial output
        assert np.isclose(static_surface(st, th, ubs[None, :])[0], settled, rtol=1e-7, atol=1e-9)
    stable = [e.ybar for e in eqs if e.stable]
    assert np.isclose(stable, settled, rtol=1e-7, atol=1e-9).any()


def test_static_surface_gain_is_the_gradient():
    rec, m = _miso_record()
    ub = np.array([[0.5, 0.2], [1.0, -1.0], [-0.3, 0.7]])
    g = m.static_gain(ub)
    assert g.shape == (3, 2)
    h = 1e-6
    for i in range(2):
        d = np.zeros(2)
        d[i] = h
        fd = (m.static_curve(ub + d) - m.static_curve(ub - d)) / (2 * h)
        assert np.allclose(g[:, i], fd, rtol=1e-6, atol=1e-9)


def test_surface_clusters_per_input_power():
    rec, m = _miso_record()
    cl = m.clusters()
    # terms: y(k-1), u1(k-1), u2(k-2), u1(k-1)u2(k-1), u2(k-1)^2y(k-2), u1(k-2)y(k-1), 1
    assert cl == {"Σ0": 0.1, "Σu1": 0.3, "Σu2": -0.2, "Σu1u2": 0.1, "Σy": 0.5, "Σyu1": 0.05, "Σyu2²": -0.05}
    cm = surface_cluster_map(_ST2)
    assert cm.keys[cm.index("Σyu2²")] == (1, 0, 2) and cm.input_names == ("u1", "u2")
    # the static equation at a point, written from the clusters, holds at every equilibrium
    for u1, u2 in ((0.5, 0.2), (-1.0, 1.5)):
        for e in m.equilibria([u1, u2]):
            F = (cl["Σ0"] + cl["Σu1"] * u1 + cl["Σu2"] * u2 + cl["Σu1u2"] * u1 * u2
                 + (cl["Σy"] + cl["Σyu1"] * u1 + cl["Σyu2²"] * u2**2) * e.ybar - e.ybar)
            assert abs(F) < 1e-12 and e.ubar == (u1, u2)
    with pytest.raises(ValueError, match="2 inputs .*surface"):
        gb.cluster_map(_ST2)


def test_surface_bad_input():
    rec, m = _miso_record()
    with pytest.raises(ValueError, match="shape \\(M, 2\\)"):
        m.static_curve(np.ones((4, 3)))
    with pytest.raises(ValueError, match="shape \\(M, 2\\)"):
        m.static_curve(np.ones(3))
    with pytest.raises(ValueError, match="one point"):
        m.equilibria(np.ones((2, 2)))
    with pytest.raises(ValueError, match="not among the inputs"):
        static_surface(_ST2, _TH2, np.ones((1, 2)), input_names=("u1", "u3"))
    # a model that has several stable equilibria needs y0
    # y(k) = 1.5 y(k-1) − 0.5 y(k-1)³ at ū = 0: equilibria 0 (unstable) and ±1 (stable)
    st = Structure(["y(k-1)", "y(k-1)^3", "u1(k-1)", "u2(k-1)"])
    th = np.array([1.5, -0.5, 0.0, 0.0])
    with pytest.raises(ValueError, match="2 stable equilibria"):
        static_surface(st, th, np.zeros((1, 2)))
    assert static_surface(st, th, np.zeros((1, 2)), y0=0.3)[0] == pytest.approx(1.0)


def test_evaluate_a_two_input_model():
    rec, m = _miso_record()
    ub = np.array([[0.5, 0.2], [1.0, -1.0], [-0.3, 0.7]])
    yb = m.static_curve(ub)
    sp = StaticPoints(ub[:, ::-1], yb, input_names=("u2", "u1"))  # columns by name, in any order
    assert gb.jsf(m, sp) == pytest.approx(0.0, abs=1e-20)
    ds = Dataset(rec, rec, StaticPoints(ub, yb))
    tab = gb.evaluate({"m": m}, ds)
    assert tab.loc["m", "JSF"] == pytest.approx(0.0, abs=1e-20) and tab.loc["m", "JS_valid"] < 1e-20
    with pytest.raises(ValueError, match="has the inputs \\('u1', 'u2'\\) but the static points have \\('a', 'b'\\)"):
        gb.jsf(m, StaticPoints(ub, yb, input_names=("a", "b")))
    with pytest.raises(ValueError, match="2 input columns .* one input"):
        gb.jsf(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]), sp)


def test_frols_bad_input_is_a_clear_error():
    rec = _rec2(n=40)
    with pytest.raises(ValueError, match="terms use input 'u3', but the record's inputs are \\('u1', 'u2'\\)"):
        gb.frols(Candidates(1, 2, input_names=["u1", "u3"], degree=1), rec, n_terms=2)
    with pytest.raises(ValueError, match="fewer than max lag"):  # a delay larger than the record
        gb.frols(Candidates(1, {"u1": 45, "u2": 1}, delay={"u1": 45}, degree=1), rec, n_terms=2)


def test_miso_model_round_trips_through_json():
    rec, m = _miso_record()
    back = gb.from_json(gb.to_json(m))
    assert back.structure == m.structure and np.array_equal(back.theta, m.theta)
    assert back.input_names == ("u1", "u2") and np.array_equal(back.simulate(rec), m.simulate(rec))


def test_two_input_pipeline_frols_els_evaluate():
    rng = np.random.default_rng(0)
    n = 1500
    u = rng.uniform(-1, 1, (n, 2))
    e = 0.02 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = (0.5 * y[k - 1] + 0.8 * u[k - 1, 0] - 0.4 * u[k - 2, 1] + 0.3 * u[k - 1, 0] * u[k - 1, 1]
                - 0.1 * u[k - 1, 1] * y[k - 1] + 0.2 + e[k] + 0.3 * e[k - 1])
    rec = Record(u, y, input_names=("n1", "n2"))
    sel = gb.frols(Candidates(2, 2, input_names=["n1", "n2"], degree=2, ne=1), rec)
    m = gb.els(sel, rec).model
    assert m.input_names == ("n1", "n2") and set(m.structure.input_names) == {"n1", "n2"}
    assert m.noise_theta[0] == pytest.approx(0.3, abs=0.1)
    ds = Dataset(rec, rec, StaticPoints([[0, 0], [0.5, 0.5]], [0.4, 0.5], input_names=("n1", "n2")))
    tab = gb.evaluate({"els": m}, ds)
    assert np.isfinite(tab.loc["els", "JSF"]) and tab.loc["els", "JS_valid"] < 0.01
    # residual tests: every input test once per input; the true structure passes them, a model
    # without the input product n1·n2 fails a nonlinear one
    tests = gb.residual_tests(m, rec)
    assert {"u_xi:n1", "u_xi:n2", "u2_xi2:n1", "u2_xi2:n2", "xi_xi"} <= set(tests.tests)
    assert len(tests.tests) == 1 + 4 * 2 and tests.passed
    st = Structure([t for t in m.structure if str(t) != "n1(k-1)n2(k-1)"])
    assert len(st) == len(m.structure) - 1
    bad = gb.residual_tests(gb.els(st, rec, noise=1).model, rec)
    assert bad.linear_passed and not bad.nonlinear_passed


def test_reached_surface_batches_members_and_points():
    from graybox.static._surface_analysis import reached_surface

    rng = np.random.default_rng(5)
    th0 = np.array([0.3, 0.1, 0.5, -0.4, 0.2, 0.1, -0.2, 0.1])
    thetas = th0 * (1 + 0.2 * rng.standard_normal((6, 8)))
    ub = rng.uniform(-1, 1, (7, 2))
    y0 = rng.uniform(-0.5, 0.5, 7)
    res = reached_surface(_POLY2, thetas, ub, y0)
    assert res.ybar.shape == (6, 7) and res.ok.any()
    for p in range(6):
        one = static_surface(_POLY2, thetas[p], ub, y0=y0, strict=False)
        assert np.array_equal(np.isnan(one), ~res.ok[p])
        assert np.allclose(one[res.ok[p]], res.ybar[p, res.ok[p]], rtol=0, atol=0)


def test_surface_static_rows():
    from graybox.static._surface_analysis import surface_static_rows

    rec, m = _miso_record()
    cm = surface_cluster_map(_ST2)
    ub = np.array([[0.5, 0.2], [1.0, -1.0], [0.0, 0.7]])
    yb = m.static_curve(ub)
    Q = surface_static_rows(cm, ub, yb)
    assert np.allclose(Q @ cm.R @ _TH2, yb, rtol=1e-12, atol=1e-14)  # on the surface, QRθ = ȳ
    # F = QRθ − ȳ: its derivatives give the gradient of the surface
    Fy = surface_static_rows(cm, ub, yb, "y") @ cm.R @ _TH2 - 1
    for i, n in enumerate(("u1", "u2")):
        Fu = surface_static_rows(cm, ub, yb, n) @ cm.R @ _TH2
        assert np.allclose(-Fu / Fy, m.static_gain(ub)[:, i], rtol=1e-10, atol=1e-12)
    with pytest.raises(ValueError, match="wrt must be"):
        surface_static_rows(cm, ub, yb, "u3")


def test_readme_several_inputs_example_runs():
    import re
    import warnings
    from pathlib import Path

    text = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    section = text.split("## API: several inputs", 1)[1]
    block = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md (several inputs)", "exec"), ns)
    assert set(ns["model"].structure) == {parse_term(t) for t in
                                          ("y(k-1)", "n1(k-1)", "n2(k-2)", "n1(k-1)n2(k-1)", "1")}
    # the true surface: ȳ = (0.2 + 0.8 n1 − 0.4 n2 + 0.3 n1 n2) / (1 − 0.5)
    n1, n2 = np.array([0.0, 0.5]), np.array([0.0, -0.5])
    assert np.allclose(ns["surface"], (0.2 + 0.8 * n1 - 0.4 * n2 + 0.3 * n1 * n2) / 0.5, atol=0.05)
    assert ns["gradient"].shape == (2, 2)
    table = section.split("```python")[0]
    for name in re.findall(r"^\| `([A-Za-z_.]+)", table, re.M):
        obj = gb
        for part in name.split("."):
            obj = getattr(obj, part)


def test_static_curve_band_refuses_several_inputs_clearly():
    rec, m = _miso_record()
    fit = gb.els(m.structure, rec, noise=0).model
    unc = gb.ls_uncertainty(fit, rec)
    assert unc.cov.shape == (len(fit.structure),) * 2  # the parameter covariance itself works
    with pytest.raises(ValueError, match="defined for one input"):
        gb.static_curve_band(unc, [[0.0, 0.0], [0.5, 0.5]])


def test_single_input_equilibria_point_to_the_surface_function():
    st = gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "1"])
    with pytest.raises(ValueError, match=r"2 inputs.*surface_equilibria"):
        gb.equilibria(st, np.array([0.5, 0.1, 0.2, 0.0]), np.array([1.0, 2.0]))
    eqs = surface_equilibria(st, np.array([0.5, 0.1, 0.2, 0.0]), np.array([1.0, 2.0]))
    assert len(eqs) == 1 and eqs[0].ybar == pytest.approx((0.1 + 0.4) / 0.5)


def test_unnamed_candidates_for_data_of_named_inputs_are_told_how_to_name_them():
    # was: "the terms use input 'u', but the record's inputs are ('speed', 'valve')" and no way out said, where one
    # input's data got the advice to name the inputs alike
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.standard_normal((300, 2)), rng.standard_normal(300), input_names=("speed", "valve"))
    for call in (lambda: gb.frols(gb.Candidates(2, 2), rec, n_terms=3),
                 lambda: gb.select_graybox(gb.Candidates(2, 2), rec, estimator="ls")):
        with pytest.raises(ValueError, match=r"Candidates\(\.\.\., input_names=\['speed', 'valve'\]\)"):
            call()
    named = gb.frols(gb.Candidates(2, 2, input_names=["speed", "valve"]), rec, n_terms=3)
    assert set(named.model.structure.input_names) <= {"speed", "valve"}


def test_a_data_frames_column_names_are_its_inputs_names_as_a_dicts_keys_are():
    # a dict's keys named the inputs (StaticPoints({"flow": …, "inlet": …})) where a DataFrame's columns were
    # dropped: Record(df[["flow", "inlet"]], y) had the inputs u1, u2, and a structure written in flow(k-1) was
    # refused on it
    import pandas as pd

    rng = np.random.default_rng(61)
    df = pd.DataFrame({"flow": rng.random(40), "inlet": rng.random(40) + 20.0})
    y = rng.random(40)
    rec = gb.Record(df, y)
    assert rec.input_names == ("flow", "inlet")
    np.testing.assert_array_equal(rec.u, df.to_numpy())
    assert gb.Record(df[["inlet"]], y).input_names == ("inlet",)
    levels = pd.DataFrame({"flow": [1.0, 2.0, 3.0], "inlet": [20.0, 20.0, 25.0]})
    by_dict = gb.StaticPoints({k: levels[k].to_numpy() for k in levels}, [1.0, 2.0, 3.0])
    assert gb.StaticPoints(levels, [1.0, 2.0, 3.0]).input_names == by_dict.input_names == ("flow", "inlet")
    assert gb.StaticPoints.from_repeats(pd.concat([levels, levels]), np.arange(6.0)).input_names == ("flow", "inlet")
    # input_names= names them otherwise: by name where the columns are those names, by position where none
    assert gb.Record(df, y, input_names=("inlet", "flow")).u[0].tolist() == [df.inlet[0], df.flow[0]]
    assert gb.Record(df, y, input_names=("q", "T")).u[0].tolist() == [df.flow[0], df.inlet[0]]
    # pandas' default columns 0, 1 are no names: the default ones
    assert gb.Record(pd.DataFrame(df.to_numpy()), y).input_names == ("u1", "u2")
    # a column that cannot be a term's name is refused, saying where the name came from and the way out
    with pytest.raises(ValueError, match=r"the DataFrame's column names.*input_names=.*'flow rate' is not a valid"):
        gb.Record(df.rename(columns={"flow": "flow rate"}), y)
    # a time column is still no input for its name
    with pytest.raises(ValueError, match="column 't' .* looks like time"):
        gb.Record(df.assign(t=np.arange(40) * 0.5), y)
    # a column taken as a Series, df["flow"], is named by its name as df[["flow"]] is (it had the input u, and a
    # structure in flow(k-1) was refused on it); an unnamed Series, or one named by a number, has the default name
    assert gb.Record(df["flow"], y).input_names == ("flow",)
    assert gb.Record(df["flow"], y, input_names=["q"]).input_names == ("q",)
    assert gb.Record(pd.Series(df["flow"].to_numpy()), y).input_names == ("u",)
    assert gb.Record(pd.DataFrame(df.to_numpy())[0], y).input_names == ("u",)
    with pytest.raises(ValueError, match=r"the DataFrame's column names.*'flow rate' is not a valid"):
        gb.Record(df.rename(columns={"flow": "flow rate"})["flow rate"], y)
    with pytest.raises(ValueError, match="the output"):
        gb.Record(df["flow"], df["flow"])
    # and static points' levels so taken alike, so that a Dataset of both holds one input
    pts = pd.DataFrame({"flow": [0.2, 0.5, 0.8, 0.8], "h": [1.0, 2.0, 3.0, 3.2]})
    assert gb.StaticPoints(pts["flow"][:3], pts["h"][:3]).input_names == ("flow",)
    assert gb.StaticPoints.from_repeats(pts["flow"], pts["h"]).input_names == ("flow",)
    assert gb.Dataset(gb.Record(df["flow"], y), gb.Record(df["flow"], y),
                      gb.StaticPoints(pts["flow"][:3], pts["h"][:3])).input_names == ("flow",)
    # columns 0 and "flow" were read by position as u1, u2, "flow" dropped without a word: a name said is kept
    # or the frame refused (here), as a dict's keys; input_names= reads it by position
    mixed = pd.DataFrame({0: df.inlet, "flow": df.flow})
    for make in (lambda x: gb.Record(x, y), lambda x: gb.StaticPoints(x.iloc[:3], [1.0, 2.0, 3.0]),
                 lambda x: gb.StaticPoints.from_repeats(x.iloc[:3], [1.0, 2.0, 3.0])):
        with pytest.raises(ValueError, match=r"the DataFrame's columns \[0, 'flow'\] name some inputs \(\['flow'\]\) "
                                             r"and not others \(\[0\]\).*input_names="):
            make(mixed)
    assert gb.Record(mixed, y, input_names=("T", "q")).input_names == ("T", "q")
