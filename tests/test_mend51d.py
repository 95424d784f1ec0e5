"""mend51d: residual tests held to their own n, level and rule; a unit named in a label; a regressor beyond the
float range; numbers beyond float64's range said so; a grid structure listed twice in another order."""

from __future__ import annotations

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from graybox.plots._data import unit_label

# --- 2. unit_label: a unit that is also a word ("in", "A") was taken for the unit named; "Speed/rpm" got it again ---

@pytest.mark.parametrize("text, unit, label", [
    ("Speed (rpm)", "rpm", "Speed (rpm)"),
    ("Speed [rpm]", "rpm", "Speed [rpm]"),
    ("Speed/rpm", "rpm", "Speed/rpm"),
    ("Speed / rpm", "rpm", "Speed / rpm"),
    ("speed_rpm", "rpm", "speed_rpm"),
    ("Speed, rpm", "rpm", "Speed, rpm"),
    ("Speed in rpm", "rpm", "Speed in rpm"),
    ("Speed", "rpm", "Speed (rpm)"),
    ("rpm counter", "rpm", "rpm counter (rpm)"),       # the word, not the unit said
    ("Current (A)", "A", "Current (A)"),
    ("Current in A", "A", "Current in A"),
    ("Current_A", "A", "Current_A"),
    ("Current", "A", "Current (A)"),
    ("A pump's current", "A", "A pump's current (A)"),  # the article
    ("Current of pump A", "A", "Current of pump A (A)"),  # the pump's name
    ("Level in tank", "in", "Level in tank (in)"),       # the preposition
    ("Level in tank 2", "in", "Level in tank 2 (in)"),
    ("Level in in", "in", "Level in in"),
    ("Level (in)", "in", "Level (in)"),
    ("level [mlc]", "mlc", "level [mlc]"),
    ("level in mlc", "mlc", "level in mlc"),
    ("level_mlc", "mlc", "level_mlc"),
    ("level", "mlc", "level (mlc)"),
    ("Temperature in °C (mean)", "°C", "Temperature in °C (mean)"),
    ("Speed", "", "Speed"),
])
def test_unit_label_takes_a_unit_as_named_only_where_a_unit_is_written(text, unit, label):
    assert unit_label(text, unit) == label


@given(head=st.sampled_from(["Speed", "Level in tank", "A pump", "Pump A", "in", "Current in"]),
       unit=st.sampled_from(["A", "in", "rpm", "mlc", "°C"]),
       form=st.sampled_from(["{h} ({u})", "{h} [{u}]", "{h}/{u}", "{h}_{u}", "{h} in {u}", "{h}, {u}"]))
def test_a_label_with_its_unit_is_kept_and_a_label_without_it_gets_it_once(head, unit, form):
    named = form.format(h=head, u=unit)
    assert unit_label(named, unit) == named
    assert unit_label(unit_label(head, unit), unit) == unit_label(head, unit)  # never doubled
    assert unit_label(head, unit) == f"{head} ({unit})"


# --- 4. Decimal and longdouble numbers beyond float64's range were "non-finite (NaN or inf)" ----------------------

import math  # noqa: E402
import re  # noqa: E402
import warnings  # noqa: E402
from decimal import Decimal  # noqa: E402

import numpy as np  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.core._validation import as_1d_finite, check_int, check_real, float_array  # noqa: E402

HUGE = [Decimal("1e400"), Decimal("-2.5e309"), np.longdouble("1e400"), np.longdouble("-1e4000")]
_HAS_LONG = np.isfinite(np.longdouble("1e400"))  # a longdouble wider than float64 (not on every platform)


def _huge():
    return [v for v in HUGE if _HAS_LONG or not isinstance(v, np.longdouble)]


@pytest.mark.parametrize("convert", [
    lambda v: float_array([1.0, v], "x"),
    lambda v: as_1d_finite([1.0, v], "x"),
    lambda v: as_1d_finite(np.array([1.0, v], dtype=object), "x"),
    lambda v: gb.Record([1.0, v, 2.0], [1.0, 2.0, 3.0]),
    lambda v: gb.Record([[1.0, 0.0], [v, 1.0], [2.0, 0.0]], [1.0, 2.0, 3.0]),
    lambda v: gb.Model(gb.Structure(["y(k-1)"]), [v]),
])
def test_a_number_beyond_float64s_range_is_said_so_not_non_finite(convert):
    for v in _huge():
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy's "overflow encountered in cast" is no message
            with pytest.raises(ValueError, match="beyond the float range") as info:
                convert(v)
        assert "non-finite" not in str(info.value) and "NaN" not in str(info.value)


@pytest.mark.skipif(not _HAS_LONG, reason="longdouble is float64 here")
def test_a_longdouble_scalar_beyond_float64s_range_is_said_so():
    with pytest.raises(ValueError, match="x.*beyond the float range"):
        check_real(np.longdouble("1e400"), "x")
    with pytest.raises(ValueError, match="x.*beyond the float range"):
        check_int(np.longdouble("1e400"), "x")
    with pytest.raises(ValueError, match="x.*beyond the float range"):
        float_array(np.array([1.0, 1e300], dtype=np.longdouble) * np.longdouble("1e300"), "x")  # an array of them
    assert check_real(np.longdouble("1e300"), "x") == 1e300  # within the range: its value


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -np.inf, Decimal("nan"), Decimal("-Infinity"),
                                 np.longdouble("nan"), np.longdouble("inf")])
def test_nan_and_inf_keep_their_message(bad):
    with pytest.raises(ValueError, match="non-finite") as info:
        as_1d_finite([1.0, bad], "x")
    assert "beyond" not in str(info.value)
    with pytest.raises(ValueError, match="non-finite"):
        gb.Model(gb.Structure(["y(k-1)"]), [bad])
    if not isinstance(bad, Decimal):
        with pytest.raises(ValueError, match="finite") as info:
            check_real(bad, "x")
        assert "beyond" not in str(info.value)


def test_decimals_and_longdoubles_within_the_range_are_their_values():
    assert float_array([Decimal("1.5"), np.longdouble("2.5")], "x").tolist() == [1.5, 2.5]
    assert as_1d_finite([Decimal("1e300")], "x")[0] == 1e300


# --- 3. regressor_matrix: a term's product beyond the float range was an inf column with numpy's warnings ----------

def _huge_record(n=120):
    rng = np.random.default_rng(3)
    u = rng.uniform(-1, 1, n)
    y = 1e200 * (1.0 + 0.1 * rng.standard_normal(n))
    return gb.Record(u, y)


OVER = gb.Structure(["y(k-1)", "u(k-1)", "y(k-1)^2"])


def test_regressor_matrix_names_the_term_beyond_the_float_range_without_numpys_warning():
    rec = _huge_record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"y\(k-1\)\^2") as info:
            gb.regressor_matrix(OVER, rec.u, rec.y)
        assert "u(k-1)," not in str(info.value)  # the finite columns are not named
        with pytest.raises(ValueError, match=r"y\(k-1\)\^2"):
            gb.stacked_regressors(OVER, [rec, rec])
        psi = gb.regressor_matrix(OVER[:2], rec.u, rec.y)  # the terms within the range: their columns
    assert np.all(np.isfinite(psi)) and psi.shape == (len(rec) - 1, 2)


@given(exponent=st.integers(30, 300), power=st.integers(1, 4))
def test_a_column_is_finite_or_refused_as_its_product_leaves_the_range(exponent, power):
    # the law: finite columns where every product is within float64's range, else a ValueError naming the term;
    # never inf, never numpy's warning
    rec = gb.Record(np.linspace(-1, 1, 20), 10.0 ** exponent * np.linspace(1, 2, 20))
    structure = gb.Structure(["u(k-1)", f"y(k-1)^{power}" if power > 1 else "y(k-1)"])
    beyond = power * math.log10(float(np.max(rec.y[:-1]))) > math.log10(np.finfo(float).max)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if beyond:
            with pytest.raises(ValueError, match=re.escape(str(structure[1]))):
                gb.regressor_matrix(structure, rec.u, rec.y)
        else:
            assert np.all(np.isfinite(gb.regressor_matrix(structure, rec.u, rec.y)))


@pytest.mark.parametrize("fit", [
    lambda rec: gb.els(OVER, rec, noise=0),
    lambda rec: gb.els(OVER, rec, noise=2),
    lambda rec: gb.pe_pareto(OVER, rec, None, lambdas=[1.0]),
    lambda rec: gb.residual_tests(gb.Model(OVER, [0.1, 1.0, 1e-300]), rec),
    lambda rec: gb.one_step_residuals(gb.Model(OVER, [0.1, 1.0, 1e-300]), rec),
])
def test_the_estimators_refuse_such_data_naming_the_term(fit):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"y\(k-1\)\^2"):
            fit(_huge_record())


def test_a_one_step_prediction_beyond_the_float_range_stays_nan():
    rec = _huge_record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yhat = gb.Model(OVER, [0.1, 1.0, 1.0]).predict(rec)
    assert np.isnan(yhat[1:]).all() and yhat[0] == rec.y[0]


# --- 5. a grid structure listed twice, its terms in another order, was two structures: two cells of one fit -------

from graybox import experiments as gx  # noqa: E402
from graybox.experiments._spec import StructureSpec  # noqa: E402

TERMS = ["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"]


def _grid(structures, variants=None):
    return gx.Grid([gx.DataSpec("p", bundled="pumping")], structures, variants or [gx.Variant("LS", "ls")])


@given(order=st.permutations(range(len(TERMS))))
def test_a_structure_listed_again_in_another_order_is_refused(order):
    assume(list(order) != sorted(order))  # in the same order it is 'identical', refused as before
    again = [TERMS[i] for i in order]
    with pytest.raises(gx.SpecError, match=r"'b'.*same terms as 'a'"):
        _grid([gx.StructureSpec("a", terms=TERMS), gx.StructureSpec("b", terms=again)])
    # the factors of a term in another order are the same term too
    with pytest.raises(gx.SpecError, match="same terms"):
        _grid([gx.StructureSpec("a", terms=TERMS), gx.StructureSpec("b", terms=[t.replace("u(k-1)y(k-1)",
                                                                                           "y(k-1)u(k-1)") for t in again])])


def test_a_structure_with_other_terms_and_the_order_given_are_kept():
    g = _grid([gx.StructureSpec("a", terms=TERMS), gx.StructureSpec("b", terms=TERMS[::-1][1:])])
    assert [s.name for s in g.structures] == ["a", "b"]
    assert g.structures[1].content() == {"terms": TERMS[::-1][1:]}  # θ's order, and the cells' keys, as given


def test_a_made_structure_with_its_included_terms_in_another_order_is_refused():
    cand = {"ny": 1, "nu": 1, "degree": 2}
    with pytest.raises(gx.SpecError, match="'b'.*included terms as 'a'"):
        _grid([gx.StructureSpec("a", candidates=cand, n_terms=3, include=["1", "u(k-1)"]),
               gx.StructureSpec("b", candidates=cand, n_terms=3, include=["u(k-1)", "1"])])
    _grid([gx.StructureSpec("a", candidates=cand, n_terms=3, include=["1", "u(k-1)"]),
           gx.StructureSpec("b", candidates=cand, n_terms=4, include=["u(k-1)", "1"])])  # another rule: kept


def test_a_toml_spec_listing_a_structure_twice_in_another_order_names_its_line():
    text = '''name = "g"
[[data]]
name = "p"
bundled = "pumping"
[[structures]]
name = "a"
terms = ["y(k-1)", "u(k-1)"]
[[structures]]
name = "b"
terms = ["u(k-1)", "y(k-1)"]
[[variants]]
name = "LS"
estimator = "ls"
'''
    with pytest.raises(gx.SpecError, match="same terms") as info:
        gx.Grid.from_toml_text(text)
    assert "line" in str(info.value)


def test_a_store_written_with_such_a_structure_twice_is_still_read(tmp_path, monkeypatch):
    # a store written before the check: two structures of one set of terms, two rows each
    with monkeypatch.context() as m:
        m.setattr(StructureSpec, "identity", StructureSpec.content)
        g = _grid([gx.StructureSpec("a", terms=["y(k-1)", "u(k-1)"]), gx.StructureSpec("b", terms=["u(k-1)", "y(k-1)"])])
        run = gx.run_grid(g, tmp_path / "s.sqlite", executor="inprocess", progress=False)
    assert run.counts["ok"] == 2
    df = gx.load_results(tmp_path / "s.sqlite")
    assert sorted(df["structure"]) == ["a", "b"] and set(df["status"]) == {"ok"}
    a, b = (df[df["structure"] == s].iloc[0] for s in "ab")
    assert np.allclose(a["theta"], b["theta"][::-1])
    from _reports import undrawn_figures

    undrawn_figures(monkeypatch)  # the report is read from the store; its figures are not what is asked
    assert gx.write_report(tmp_path / "s.sqlite", tmp_path / "r")


# --- 1. ResidualTests held its bands to nothing: a band its n and level would not give said "passed" -------------

import dataclasses  # noqa: E402
import json  # noqa: E402

from scipy import stats  # noqa: E402

from graybox.diagnostics._residuals import TESTS, _label_of  # noqa: E402


def _narx(n=300, seed=0, inputs=1):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, inputs)) if inputs > 1 else rng.uniform(-1, 1, n)
    drive = u.sum(axis=1) if inputs > 1 else u
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + drive[k - 1] + 0.05 * rng.standard_normal()
    return gb.Record(u, y)


REC1 = _narx()
MODEL1 = gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), REC1, noise=0).model


def _bands(n, level, size, rule):
    band = stats.norm.ppf(0.5 + level / 2) / np.sqrt(n)
    limit = band if rule == "pointwise" else stats.norm.ppf(1 - (1 - level) / (2 * size)) / np.sqrt(n)
    return float(band), float(limit)


def _test(name, lags, n=5, level=0.95, rule="pointwise", phi=None):
    lags = np.asarray(lags)
    band, limit = _bands(n, level, lags.size, rule)
    phi = np.zeros(lags.size) if phi is None else np.asarray(phi, float)
    _, kind, _ = TESTS[name.split(":")[0]]
    label = _label_of(name)  # a test keyed by an input ("u_xi:u1") names it in its label
    return gb.CorrelationTest(name, label, kind, lags, phi, band, limit, lags[np.abs(phi) > band],
                              bool(np.all(np.abs(phi) <= limit)))


@pytest.mark.parametrize("name, lags", [
    ("u_xi", np.arange(1, 4)),      # an autocorrelation's lags 1 … L for a cross-correlation's −L … L
    ("xi_xi", np.arange(-3, 4)),    # τ = 0 is φ_ξξ = 1, never tested
    ("xi_xi", np.arange(0, 4)),
    ("xi_xiu", np.arange(1, 4)),    # 0 … L
    ("u2_xi", np.arange(-3, 3)),    # not symmetric
    ("u2_xi2:u1", np.array([-2, 0, 2])),  # gaps
    ("xi_xi", np.array([3, 2, 1])),  # out of order
])
def test_a_correlation_test_holding_lags_its_name_has_not_is_refused(name, lags):
    with pytest.raises(ValueError, match="lags"):
        _test(name, lags)


@pytest.mark.parametrize("name, lags", [("xi_xi", np.arange(1, 4)), ("u_xi", np.arange(-3, 4)),
                                        ("xi_xiu", np.arange(0, 4)), ("u2_xi:u2", np.arange(-1, 2)),
                                        ("xi_xi", np.arange(1, 2))])
def test_a_correlation_test_with_its_names_lags_is_built(name, lags):
    assert _test(name, lags).lags.tolist() == lags.tolist()


@pytest.mark.parametrize("edit, said", [
    (dict(n=398, residuals=(np.zeros(398),)), "band"),  # n that the bands were not made with
    (dict(level=0.99), "band"),
    (dict(rule="pointwise"), "limit"),
])
def test_residual_tests_whose_bands_their_n_level_or_rule_would_not_give_are_refused(edit, said):
    rt = gb.residual_tests(MODEL1, REC1)
    with pytest.raises(ValueError, match=said):
        dataclasses.replace(rt, **edit)


def test_a_hand_built_residual_tests_with_a_band_of_another_n_is_refused():
    good = _test("u_xi", np.arange(-2, 3), n=5)
    rt = gb.ResidualTests({"u_xi": good}, 5, 0.95, "pointwise", "m", (np.zeros(5),))
    assert rt.passed
    # a band of n = 500 (0.088) beside n = 5 (0.877): |φ| = 0.5 passes at n = 5, fails at 500; said 'failed'
    wide = _test("u_xi", np.arange(-2, 3), n=500, phi=[0.5, 0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"band of tests\['u_xi'\]"):
        gb.ResidualTests({"u_xi": wide}, 5, 0.95, "pointwise", "m", (np.zeros(5),))
    with pytest.raises(ValueError, match=r"limit of tests\['u_xi'\]"):
        gb.ResidualTests({"u_xi": _test("u_xi", np.arange(-2, 3), n=5, rule="simultaneous")}, 5, 0.95, "pointwise",
                         "m", (np.zeros(5),))
    with pytest.raises(ValueError, match="lags"):  # tests of one call share their max lag
        gb.ResidualTests({"xi_xi": _test("xi_xi", np.arange(1, 4)), "u_xi": good}, 5, 0.95, "pointwise", "m",
                         (np.zeros(5),))


@given(n=st.integers(5, 10_000), level=st.floats(0.5, 0.999), lag=st.integers(1, 30),
       rule=st.sampled_from(["pointwise", "simultaneous"]))
def test_bands_of_their_own_n_level_and_rule_are_taken(n, level, lag, rule):
    tests = {"xi_xi": _test("xi_xi", np.arange(1, lag + 1), n, level, rule),
             "u_xi": _test("u_xi", np.arange(-lag, lag + 1), n, level, rule)}
    rt = gb.ResidualTests(tests, n, level, rule, "m", (np.zeros(n),))
    assert rt.passed and rt.n == n


@pytest.mark.parametrize("rule", ["simultaneous", "pointwise"])
@pytest.mark.parametrize("inputs", [1, 2])
def test_residual_tests_files_graybox_writes_still_load(tmp_path, rule, inputs):
    rec = _narx(inputs=inputs, seed=inputs)
    terms = ["y(k-1)", "1"] + (["u(k-1)"] if inputs == 1 else ["u1(k-1)", "u2(k-1)"])
    model = gb.els(gb.Structure(terms), rec, noise=0).model
    rt = gb.residual_tests(model, rec, rule=rule, level=0.9, max_lag=7)
    path = tmp_path / "r.json"
    gb.save(rt, path)
    back = gb.load(path)
    assert repr(back) == repr(rt) and list(back.tests) == list(rt.tests)
    assert all(np.array_equal(back[k].phi, rt[k].phi) and back[k].band == rt[k].band for k in rt.tests)
    # a band edited in the file (the simultaneous limit of 41 lags where 7 … 15 were made): refused by name
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc["object"]["tests"]["xi_xi"]["band"] *= 0.5
    path.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match="band"):
        gb.load(path)


# --- 3b. semp: the same overflow let numpy's warning through and named no candidate ----------------------------

def test_semp_searches_candidates_beyond_the_float_range_as_frols_does_without_numpys_warning():
    # semp once refused such data ('candidate regressors overflow … (e.g. y(k-1)^2)'), where numpy had warned; it now
    # searches, as frols does, on y and u times a power of two (scale54): the same structure as in ordinary units
    cand = gb.Structure(["u(k-1)", "y(k-1)", "u(k-1)^2", "y(k-1)^2", "1"])
    rec = _huge_record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        huge = gb.semp(cand, rec, n_terms=2)
    own = gb.semp(cand, gb.Record(rec.u, rec.y * 1e-200), n_terms=2)
    assert list(huge.structure) == list(own.structure)
