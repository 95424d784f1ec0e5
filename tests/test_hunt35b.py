"""Hunt 35b: the models and core layers (and today's changes on main) used as a control engineer
would on their own data: engineering units far from 1, inputs not named u, short records, odd
term strings and bad input. Each test names what was wrong before its fix."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


# An empty Record was accepted and its repr (and so any message or print naming it) raised numpy's
# "zero-size array to reduction operation minimum"; a slice past the end made one silently.
def test_empty_record_is_refused_by_name():
    with pytest.raises(ValueError, match="no samples"):
        gb.Record([], [], name="run1")
    rec = gb.Record(np.linspace(2900.0, 3100.0, 50), np.linspace(2e5, 2.1e5, 50), input_names=["speed"])
    with pytest.raises(ValueError, match="no samples"):
        rec.slice(40, 10)


# Complex samples (a spectrum or an FFT left in place of a signal) were cast to their real part,
# with at most numpy's ComplexWarning: a silent wrong number in a record, a free run's input, a
# static level or θ.
@pytest.mark.parametrize("make", [
    lambda z: gb.Record(np.full(5, 3000.0) + z, np.full(5, 2e5), input_names=["speed"]),
    lambda z: gb.Record(np.full(5, 3000.0), np.full(5, 2e5) + z),
    lambda z: gb.StaticPoints([3000.0 + z], [2e5]),
    lambda z: gb.Model(["y(k-1)", "u(k-1)"], [0.5 + z, 1.0]),
    lambda z: gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).simulate(np.full(5, 3000.0) + z, [0.0]),
    lambda z: gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).static_curve([3000.0 + z]),
])
def test_complex_values_are_refused(make):
    with pytest.raises((TypeError, ValueError), match="complex"):
        make(1e-3j)


# A single string where a sequence of terms is meant was iterated character by character:
# Structure("y(k-1)") and Model("y(k-1)", [0.5]) said "cannot parse term 'y'", naming neither the
# argument nor the fix (a list, or parse_structure).
def test_structure_of_one_string_names_the_fix():
    with pytest.raises(TypeError, match="parse_structure"):
        gb.Structure("y(k-1)")
    with pytest.raises(TypeError, match="parse_structure"):
        gb.Model("speed(k-1)", [0.5])
    assert gb.parse_structure("y(k-1)") == gb.Structure(["y(k-1)"])


# A lag of 0 written y(k) or speed(k) was "cannot parse term 'speed(k)' at position 0", while the
# same lag written speed(k-0) said what is wrong (lags start at 1).
@pytest.mark.parametrize("text", ["speed(k)", "y(k)", "e(k)", "y(k-1)speed(k)"])
def test_lag_zero_says_lags_start_at_one(text):
    with pytest.raises(ValueError, match=r"lag of \w+ must be an integer >= 1, got 0"):
        gb.Structure([text])


def _quadratic_record(rng, n, lo, hi, name, cap=np.inf):
    """y(k) = 0.5 y(k−1) + 0.1 min(y(k−1)², cap) + v(k−1): a capped square saturates where the model's diverges."""
    v = np.repeat(rng.uniform(lo, hi, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.1 * min(y[k - 1] ** 2, cap) + v[k - 1]
    return gb.Record(v, y + 1e-3 * rng.standard_normal(n), name=name, input_names=["v"])


# GrayboxSelection.regret, and so the selection's repr, raised numpy's "zero-size array to reduction
# operation minimum" when no row's model ran through the test record (every JS_test inf: each
# free run diverged there).
def test_regret_when_every_row_diverges_on_the_test_record():
    rng = np.random.default_rng(0)
    data = gb.Dataset(_quadratic_record(rng, 300, -0.5, 0.5, "ident"), _quadratic_record(rng, 200, -0.5, 0.5, "valid"))
    test = _quadratic_record(rng, 200, 2.0, 3.0, "test", cap=4.0)  # no equilibrium of the model there
    cand = gb.Structure(["1", "v(k-1)", "y(k-1)", "y(k-1)^2"])
    sel = gb.experiments.select_graybox(cand, data, test=test, sizes=[3, 4], sources=("frols",),
                                        include=["1", "y(k-1)^2"])
    assert np.isinf(sel.table["JS_test"]).all()
    with pytest.raises(ValueError, match="test record"):
        sel.regret
    assert "J_S test=inf" in repr(sel) and "regret" not in repr(sel)


# gb.mse took its arrays unchecked: start=-1 scored the last sample only (rrse refused it), a
# measured NaN gave inf as a diverged model does, and arrays of different lengths (mse and rrse)
# raised numpy's "operands could not be broadcast together".
@pytest.mark.parametrize("score", [gb.mse, gb.rrse, gb.fit_percent])
def test_error_measures_check_their_arrays(score):
    y = 2e5 + np.arange(5.0)
    assert np.isfinite(score(y, y + 0.5 * np.arange(5.0), start=1))
    assert score(y, np.r_[y[:4], np.nan]) == (-np.inf if score is gb.fit_percent else np.inf)  # a diverged run
    with pytest.raises(ValueError, match="start"):
        score(y, y, start=-1)
    with pytest.raises(ValueError, match="same length"):
        score(y, y[:4])
    with pytest.raises(ValueError, match="y has 1 non-finite"):
        score(np.r_[y[:4], np.nan], y)


# evaluate_thetas cast complex parameter vectors to their real part (numpy's ComplexWarning only).
def test_evaluate_thetas_refuses_complex_thetas():
    rec = gb.Record(3000.0 + np.arange(20.0), 2e5 + np.arange(20.0), input_names=["speed"])
    with pytest.raises(TypeError, match="complex"):
        gb.evaluate_thetas(["y(k-1)", "speed(k-1)"], np.array([[0.5 + 1e-3j, 1.0]]), rec)


# Model.to_latex raised KeyError for any input not named u (speed, u1, a transient input u_tau2p5):
# the LaTeX names were a table of u, y and e only.
def test_to_latex_writes_any_input_name():
    from matplotlib.mathtext import MathTextParser

    m = gb.Model(["y(k-1)", "u_tau2p5(k-1)", "flow_rate(k-2)^2", "u1(k-1)y(k-1)", "speed(k-1)", "1"],
                 [0.5, -1e-3, 2e5, 1.5e-12, 7.0, -3.0], noise_structure=["e(k-1)"], noise_theta=[0.2],
                 input_names=["u1", "u_tau2p5", "flow_rate", "speed"])
    tex = m.to_latex()
    assert r"\mathrm{speed}(k-1)" in tex and "u_{1}(k-1)" in tex and r"\mathrm{flow\_rate}(k-2)^{2}" in tex
    assert r"\xi(k-1)" in tex and r"0.5\,y(k-1)" in tex
    MathTextParser("path").parse(f"${tex}$")  # valid math: one subscript per name, no stray _
    assert gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).to_latex() == r"y(k) = 0.5\,y(k-1) + 1\,u(k-1)"


# Structure.index of a term not in the structure raised Python's bare "tuple.index(x): x not in
# tuple", naming neither the term nor the structure.
def test_structure_index_names_the_missing_term():
    s = gb.Structure(["y(k-1)", "speed(k-1)"])
    assert s.index("speed(k - 1)") == 1
    with pytest.raises(ValueError, match=r"u\(k-1\) is not in the structure"):
        s.index("u(k-1)")


# A file whose thousands separator shows only in a cell with both marks (1,234.5 or 1.234,5) and
# otherwise in grouped integers (1,236) was called ambiguous at the grouped integer, with the hint
# to pass the wrong decimal mark (decimal=',' for 1,234.5); the cell with both marks is the
# thousands separator the loaders refuse by its line.
@pytest.mark.parametrize("text", ['t,u,y\n0,"1,234.5",2\n1,"1,235.5",3\n2,"1,236",4\n',
                                  "t;u;y\n0;1.234,5;2\n1;1.235,5;3\n2;1.236;4\n"])
def test_csv_thousands_separator_in_a_cell_with_both_marks_is_named(tmp_path, text):
    path = tmp_path / "run.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 2, column 'u': '1[.,]234[.,]5' .*thousands separator") as info:
        gb.load_record_csv(path, u="u", y="y", time="t")
    assert "ambiguous" not in str(info.value)


# encoding= naming one of Python's codecs that is no text encoding (hex, rot13, base64) raised
# Python's LookupError from deep inside the decoder, not the ValueError an unknown name gets.
@pytest.mark.parametrize("encoding", ["hex", "rot13", "base64"])
def test_csv_encoding_that_is_no_text_encoding(tmp_path, encoding):
    path = tmp_path / "steady.csv"
    path.write_bytes(b"speed;pressure\n3000;200000\n3100;201000\n")
    with pytest.raises(ValueError, match=f"encoding '{encoding}' is not a text encoding"):
        gb.load_static_csv(path, u="speed", y="pressure", encoding=encoding)


# An encoding= that contradicts the file's byte-order mark was obeyed: a UTF-8-with-BOM file read as
# cp1252 had no column 'u' (its header read 'ï»¿u'), and a UTF-16 file read as UTF-8 was told to
# try encoding='cp1252'.
@pytest.mark.parametrize("bom, text_encoding, given", [(b"\xef\xbb\xbf", "utf-8", "cp1252"),
                                                        (b"\xff\xfe", "utf-16-le", "utf-8"),
                                                        (b"\xff\xfe", "utf-16-le", "cp1252")])
def test_csv_encoding_that_contradicts_the_byte_order_mark(tmp_path, bom, text_encoding, given):
    path = tmp_path / "steady.csv"
    path.write_bytes(bom + "u;y\n3000;200000\n3100;201000\n".encode(text_encoding))
    with pytest.raises(ValueError, match=f"byte-order mark.*encoding='{given}'"):
        gb.load_static_csv(path, u="u", y="y", encoding=given)
    assert gb.load_static_csv(path, u="u", y="y").ubar.tolist() == [3000.0, 3100.0]
    assert gb.load_static_csv(path, u="u", y="y", encoding=text_encoding.split("-le")[0]).ubar.tolist() == [3000.0, 3100.0]


# plot_selection's test panel, for a selection whose every row diverged on the test record, was
# titled "the choice is nan× the best row" (it computed the regret itself, over positive J_S only,
# apart from GrayboxSelection.regret), and its empty legend raised matplotlib's "No artists with
# labels found" warning.
def test_plot_selection_when_every_row_diverges_on_the_test_record():
    rng = np.random.default_rng(0)
    data = gb.Dataset(_quadratic_record(rng, 300, -0.5, 0.5, "ident"), _quadratic_record(rng, 200, -0.5, 0.5, "valid"))
    test = _quadratic_record(rng, 200, 2.0, 3.0, "test", cap=4.0)
    cand = gb.Structure(["1", "v(k-1)", "y(k-1)", "y(k-1)^2"])
    sel = gb.experiments.select_graybox(cand, data, test=test, sizes=[3, 4], sources=("frols",),
                                        include=["1", "y(k-1)^2"])
    title = gb.experiments.plot_selection(sel).axes[-1].get_title()
    assert "nan" not in title and "diverged" in title


# A free run of a structure without lags (a static map, "1" and nothing else) from an input array
# asked for y0, "the first max-lag outputs", of which there are none.
def test_free_run_without_lags_needs_no_initial_outputs():
    m = gb.Model(["1"], [2e5])
    assert m.simulate(np.full(10, 3000.0)).tolist() == [2e5] * 10
    assert gb.simulate(gb.Structure(["1"]), [2e5], np.full(10, 3000.0)).tolist() == [2e5] * 10


# gb.simulate, gb.predict and gb.simulate_many took only a Structure: a list of terms (which the
# README says will do wherever a structure is meant) raised AttributeError "'list' object has no
# attribute 'max_lag'", and a Model "object of type 'Model' has no len()".
@pytest.mark.parametrize("structure", [["y(k-1)", "speed(k-1)"], gb.Model(["y(k-1)", "speed(k-1)"], [0.0, 0.0])])
def test_core_free_runs_take_any_structure(structure):
    u = 3000.0 + 10 * np.sin(np.arange(30.0))
    rec = gb.Record(u, 2e5 + np.cos(np.arange(30.0)), input_names=["speed"])
    m = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 30.0])
    assert np.array_equal(gb.simulate(structure, m.theta, rec), m.simulate(rec))
    assert np.array_equal(gb.predict(structure, m.theta, rec, horizon=2), m.predict(rec, horizon=2))
    assert np.array_equal(gb.simulate_many(structure, m.theta[None, :], rec)[0], m.simulate(rec))
    with pytest.raises(TypeError, match="structure"):
        gb.simulate(3, m.theta, rec)


# evaluate refused the whole table ("RRSE undefined: the measured output is constant") when the
# validation output was constant (a record held at one steady state), for the sake of its fit_valid
# column alone: J_S and J_SF, defined there, were lost with it.
def test_evaluate_with_a_constant_validation_output():
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(2900.0, 3100.0, 10), 10)
    m = gb.Model(["y(k-1)", "speed(k-1)", "1"], [0.5, 30.0, 1e5], input_names=["speed"])
    ident = gb.Record(u, m.simulate(u, [2e5]) + rng.standard_normal(100), name="ident", input_names=["speed"])
    ybar = m.static_curve([3000.0])[0]
    valid = gb.Record(np.full(50, 3000.0), np.full(50, ybar), name="valid", input_names=["speed"])
    data = gb.Dataset(ident, valid, gb.StaticPoints([3000.0], [ybar], input_names=["speed"]))
    with pytest.warns(RuntimeWarning, match="fit_valid.*constant"):
        table = gb.evaluate({"m": m}, data)
    assert np.isnan(table.loc["m", "fit_valid"])
    assert table.loc["m", "JS_valid"] == pytest.approx(0.0, abs=1e-12 * ybar**2)
    assert table.loc["m", "JSF"] == pytest.approx(0.0, abs=1e-12 * ybar**2)


# Numbers given as strings (a column read as text) were parsed silently by numpy where samples,
# levels or θ are meant (Record, StaticPoints, Model, a static curve's ū), while Model.equilibria
# refused the same '3000' with a TypeError; strings are a wrong type.
@pytest.mark.parametrize("make", [
    lambda: gb.Record(["3000", "3001"], [2e5, 2e5]),
    lambda: gb.Record([3000.0, 3001.0], np.array([b"2e5", b"2e5"])),
    lambda: gb.StaticPoints(["3000"], [2e5]),
    lambda: gb.Model(["y(k-1)"], ["0.5"]),
    lambda: gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).static_curve("3000"),
])
def test_numbers_as_strings_are_refused(make):
    with pytest.raises(TypeError, match="strings"):
        make()


# A Record (or StaticPoints) with no input column, u of shape (N, 0), was accepted, printed as
# "Record('record': 100 samples, Ts = 1 s, , y in …)", and then failed in j1, frols or els with
# "input_names: at least one input name is needed", an argument the user never gave.
def test_data_without_an_input_column_is_refused_where_made():
    with pytest.raises(ValueError, match="no input column"):
        gb.Record(np.ones((100, 0)), np.ones(100))
    with pytest.raises(ValueError, match="no input column"):
        gb.StaticPoints(np.ones((1, 0)), [1.0])


# Structure + "u(k-1)" split the string into characters ("cannot parse term 'u'"); a list of terms
# worked, so one string reads as a slip for [string] and is a TypeError naming the fix.
def test_structure_plus_one_string():
    s = gb.Structure(["y(k-1)"])
    assert s + ["speed(k-1)"] == gb.Structure(["y(k-1)", "speed(k-1)"])
    with pytest.raises(TypeError, match="parse_structure"):
        s + "speed(k-1)"


# gb.simulate_many checked neither its record (an array raised AttributeError "'numpy.ndarray'
# object has no attribute 'require_length'") nor its thetas (text raised numpy's "could not convert
# string to float: 'a'").
def test_simulate_many_checks_its_arguments():
    rec = gb.Record(3000.0 + np.arange(10.0), 2e5 + np.arange(10.0), input_names=["speed"])
    st = ["y(k-1)", "speed(k-1)"]
    with pytest.raises(TypeError, match="record must be a Record"):
        gb.simulate_many(st, [[0.5, 1.0]], rec.u)
    with pytest.raises(TypeError, match="thetas"):
        gb.simulate_many(st, [["a", 1.0]], rec)
    assert gb.simulate_many(st, [[0.5, 1.0]], rec).shape == (1, 10)
