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
