"""Bugs found by hunt50h in the foundation layer (terms, records, kernels, models)."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("text", ["y(k-1)*", "u(k-2) * ", "y(k-1)u(k-1)*"])
def test_term_ending_in_a_product_sign_is_refused(text):
    # 'y(k-1)*' is a product with its last factor missing (a truncated 'y(k-1)*u(k-2)'): it read as y(k-1)
    with pytest.raises(ValueError, match="factor"):
        gb.parse_term(text)
    with pytest.raises(ValueError, match="factor"):
        gb.parse_structure(text + " + y(k-2)")


def test_inputs_whose_names_differ_only_in_leading_zeros_have_one_order():
    # a01 and a1 ranked alike in natural name order: one monomial written in two factor orders was two
    # distinct terms (a structure held both, two equal columns), and a structure's inputs came in the order of a
    # set's iteration, which a str's hash (PYTHONHASHSEED) sets: a Model's input columns changed between processes
    a, b = gb.parse_term("a01(k-1)a1(k-1)"), gb.parse_term("a1(k-1)a01(k-1)")
    assert a == b and str(a) == str(b)
    with pytest.raises(ValueError, match="duplicated"):
        gb.Structure([a, b])
    assert gb.Structure(["a1(k-1)", "a01(k-1)"]).input_names == gb.Structure(["a01(k-1)", "a1(k-1)"]).input_names


def test_structure_input_order_does_not_depend_on_the_hash_seed():
    import os
    import subprocess
    import sys

    code = ("import graybox as gb; print(gb.Model(['a1(k-1)', 'a01(k-1)', 'x(k-1)', 'x0(k-1)', 'x00(k-1)'], "
            "[1, 2, 3, 4, 5]).input_names)")
    seen = set()
    for seed in range(6):
        env = {**os.environ, "PYTHONHASHSEED": str(seed)}
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
        seen.add(out.stdout.strip())
    assert len(seen) == 1, seen


@pytest.mark.parametrize("terms", [{"y(k-1)": 0.5, "u(k-1)": 1.0}, 3, None, b"y(k-1)"])
def test_structure_refuses_what_is_no_sequence_of_terms(terms):
    # a dict of term -> value was read as its keys, its values silently dropped (structure_of, parse_structure and
    # Model refuse a mapping); a number or None was a bare "'int' object is not iterable"
    with pytest.raises(TypeError, match="sequence of terms"):
        gb.Structure(terms)


@pytest.mark.parametrize("bad", [True, False, 1.5, "2"])
def test_record_slice_refuses_what_is_no_sample_index(bad):
    # slice(True) was the samples 1: (a bool read as 1), slice(1.5) numpy's "slice indices must be integers"
    r = gb.Record(np.arange(6.0), np.arange(6.0))
    with pytest.raises(TypeError, match="start"):
        r.slice(bad)
    with pytest.raises(TypeError, match="stop"):
        r.slice(0, bad)


def test_record_slice_keeps_integer_indices():
    r = gb.Record(np.arange(6.0), np.arange(6.0) * 2)
    s = r.slice(np.int64(1), -1)
    assert s.y.tolist() == [2.0, 4.0, 6.0, 8.0] and r.slice(2.0).y.tolist() == [4.0, 6.0, 8.0, 10.0]


def test_model_of_a_result_keeps_the_inputs_of_the_result_model():
    # Model(res, θ) of a result that carries a model (ELSResult, Decision …) took its structure but not its
    # inputs: a structure in b alone made a model of the one input b, which read a 2-column array of (a, b) as
    # (u1, u2) and refused it, and took levels of b alone where res.model takes points (a, b)
    rng = np.random.default_rng(0)
    n = 200
    u = rng.normal(size=(n, 2))
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1, 1] + 0.01 * rng.normal()
    res = gb.els(["y(k-1)", "b(k-1)"], gb.Record(u, y, input_names=("a", "b")))
    m = gb.Model(res, res.model.theta)
    assert m.input_names == res.model.input_names == ("a", "b")
    np.testing.assert_array_equal(m.simulate(u, y0=y[:1]), res.model.simulate(u, y0=y[:1]))


from hypothesis import given, settings, strategies as st  # noqa: E402

_NAMES = ["u", "y", "e", "u1", "u01", "u001", "u10", "u2", "a1", "a01", "y1", "e1", "k1", "x_", "u_tau1em07"]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(_NAMES), st.integers(1, 2), st.integers(1, 3)), max_size=6),
       st.randoms(use_true_random=False))
def test_a_term_does_not_depend_on_the_order_of_its_factors(factors, rnd):
    # the law behind 97c27d1: one monomial is one term, printed one way, whatever order its factors are given in
    shuffled = list(factors)
    rnd.shuffle(shuffled)
    a, b = gb.Term(tuple(factors)), gb.Term(tuple(shuffled))
    assert a == b and str(a) == str(b) and gb.parse_term(str(a)) == a
    terms = [gb.Term(((s, lag, 1),)) for s, lag, _ in factors if s not in ("y", "e")]
    terms = list(dict.fromkeys(terms))
    assert gb.Structure(terms).input_names == gb.Structure(terms[::-1]).input_names


def test_one_step_prediction_beyond_the_float_range_is_nan_without_numpy_warnings():
    # predict promised one step ahead is never NaN for finite data: a term beyond the float range made inf − inf,
    # NaN with numpy's "overflow encountered in power" and "invalid value encountered in matmul"; now NaN where the
    # prediction leaves the float range, as a prediction further ahead is where its run leaves the bound, said so
    import warnings

    r = gb.Record(np.ones(5), np.array([1e3, 1e3, 1e3, 2.0, 1e3]))
    m = gb.Model(["y(k-1)^200", "y(k-2)^200", "u(k-1)"], [1.0, -1.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yhat = m.predict(r)
        j = gb.j1(m, r)
    assert yhat[:2].tolist() == [1e3, 1e3] and np.isnan(yhat[2]) and np.isnan(yhat[3]) and np.isnan(yhat[4])
    assert j == np.inf
    r2 = gb.Record(np.ones(5), np.array([1.0, 1.1, 0.9, 1.0, 1.2]))
    np.testing.assert_allclose(m.predict(r2)[2:], r2.y[1:4] ** 200 - r2.y[0:3] ** 200 + 1.0)


def test_regressor_matrix_names_start_when_start_is_what_the_record_is_short_of():
    # 6 samples, start=6 for y(k-1): the message said "fewer than max lag + 1 = 7", a max lag the structure has not
    r = gb.Record(u=np.arange(6.0), y=np.arange(6.0) ** 2)
    with pytest.raises(ValueError, match=r"fewer than start \+ 1 \(start = 6, the structure's max lag 1\) = 7"):
        gb.regressor_matrix(["y(k-1)"], r.u, r.y, start=6)
    with pytest.raises(ValueError, match=r"fewer than max lag \+ 1 = 3"):
        gb.regressor_matrix(["y(k-2)"], r.u[:2], r.y[:2])
