"""Several inputs (issue 15): terms, records, loaders, regressors, kernels, static surfaces."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox import Candidates, Record, StaticPoints, Structure, Term, parse_term
from graybox._records import Dataset, as_records
from graybox._regressors import record_signals, regressor_matrix
from graybox.datasets import load_record_csv, load_static_csv


# -- terms ---------------------------------------------------------------------
@pytest.mark.parametrize("text", ["u1(k-1)u2(k-2)", "u2(k-1)^2y(k-1)", "n1(k-3)n2(k-1)^2", "u1(k-1)", "u2(k-3)u10(k-1)"])
def test_miso_terms_print_and_parse(text):
    t = parse_term(text)
    assert str(t) == text
    assert parse_term(str(t)) == t


def test_miso_term_order_and_powers():
    t = parse_term("y(k-1)u2(k-1)^2")
    assert str(t) == "u2(k-1)^2y(k-1)" and t.inputs == ("u2",) and t.input_power == 2 and t.power_of("y") == 1
    assert parse_term("u2(k-2)u1(k-1)") == parse_term("u1(k-1)u2(k-2)")
    s = Structure(["u2(k-1)", "y(k-1)", "u1(k-2)y(k-1)", "1"])
    assert s.inputs == ("u1", "u2") and s.input_lag("u2") == 1 and s.input_lag("u1") == 2


def test_candidates_per_input_lags_and_delays():
    c = Candidates(1, {"u1": 2, "u2": 4}, delay={"u2": 3}, degree=1)
    assert [str(t) for t in c] == ["1", "u1(k-1)", "u1(k-2)", "u2(k-3)", "u2(k-4)", "y(k-1)"]
    c2 = Candidates(2, 2, inputs=["u1", "u2"], degree=2)
    # 1 + 6 linear + 21 quadratic in 6 variables
    assert len(c2) == 28 and set(c2.inputs) == {"u1", "u2"}
    assert Candidates(6, 6, ne=2, degree=2) == Candidates(6, {"u": 6}, ne=2, degree=2)


@pytest.mark.parametrize("kw,msg", [
    (dict(nu=2, inputs=["u1", "u1"]), "named twice"),
    (dict(nu=2, inputs=["y"]), "not a valid identifier other than y"),
    (dict(nu={"u1": 2}, delay={"u2": 1}), "not among the inputs"),
    (dict(nu={"u1": 2, "u2": 1}, delay={"u2": 3}), "delay of input 'u2' \\(3\\) must not exceed"),
    (dict(nu=2, inputs=["u1", "u2"], delay={"u1": 0}), "delay of input 'u1' must be an integer >= 1"),
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
    from graybox._kernels import batch_sse, encode, free_run_sensitivity, record_inputs

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
    assert code.inputs == ("u1", "u2")
    sse = batch_sse(code, thetas, record_inputs(swapped, code.inputs), rec.y, 2)
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
    cand = Candidates(2, 2, inputs=["u1", "u2"], degree=2)
    assert all(t in cand for t in _TRUE2)
    by_size = gb.frols(cand, rec, n_terms=len(_TRUE2))
    assert set(by_size.structure) == set(_TRUE2)
    by_bic = gb.frols(cand, rec)  # the default stopping rule (BIC) finds the size too
    assert set(by_bic.structure) == set(_TRUE2)
