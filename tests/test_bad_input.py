import numpy as np
import pytest

from graybox import Model, Record, StaticPoints, parse_term, reference


def test_nan_or_inf_in_record():
    with pytest.raises(ValueError, match=r"u has 1 non-finite value.*index 3"):
        Record([1, 2, 3, np.nan, 5], [1, 2, 3, 4, 5])
    with pytest.raises(ValueError, match="y has 1 non-finite"):
        Record([1, 2, 3], [1, np.inf, 3])


def test_mismatched_lengths():
    with pytest.raises(ValueError, match="same length, got 3 and 4"):
        Record([1, 2, 3], [1, 2, 3, 4])


def test_two_d_where_one_d_expected():
    # u of shape (N, m) is m inputs (issue 15); y stays 1-D and u cannot be 3-D
    with pytest.raises(ValueError, match="must be 1-D"):
        Record(np.ones(5), np.ones((5, 2)))
    with pytest.raises(ValueError, match="must be 1-D .* or 2-D"):
        Record(np.ones((5, 2, 1)), np.ones(5))
    assert Record(np.ones((5, 1)), np.ones(5)).u.shape == (5,)
    assert Record(np.ones((5, 2)), np.ones(5)).input_names == ("u1", "u2")


def test_record_shorter_than_max_lag():
    m = reference.paper_model(15)
    r = Record(np.full(6, 1000.0), np.full(6, 5.0), Ts=reference.TS)
    with pytest.raises(ValueError, match="fewer than max lag"):
        m.predict(r)
    with pytest.raises(ValueError, match="fewer than max lag"):
        m.simulate(np.full(6, 1000.0), np.full(6, 5.0))
    with pytest.raises(ValueError, match="y0 has 3 samples"):
        m.simulate(np.full(60, 1000.0), np.full(3, 5.0))


def test_unparsable_term():
    with pytest.raises(ValueError, match="cannot parse term 'u\\(k-2\\)k\\(k-1\\)'"):
        parse_term("u(k-2)k(k-1)")


def test_theta_length():
    with pytest.raises(ValueError, match="theta has 16 values but the structure has 17 terms"):
        Model(reference.STRUCTURE_15, np.zeros(16))
    with pytest.raises(ValueError, match="non-finite"):
        Model(reference.STRUCTURE_15, np.full(17, np.nan))


def test_static_points_validation():
    with pytest.raises(ValueError, match="duplicated ubar.*StaticPoints.from_repeats"):
        StaticPoints([1.0, 1.0], [2.0, 3.0])
    # repeated measurements at one level: their mean, one point per level, sorted by ū
    sp = StaticPoints.from_repeats([2.0, 1.0, 2.0, 1.0, 3.0], [5.0, 2.0, 7.0, 4.0, 1.0])
    np.testing.assert_array_equal(sp.ubar, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(sp.ybar, [3.0, 6.0, 1.0])
    two = StaticPoints.from_repeats([[1.0, 2.0], [1.0, 2.0], [2.0, 1.0]], [1.0, 3.0, 5.0], input_names=("a", "b"))
    assert two.ubar.shape == (2, 2) and two.input_names == ("a", "b")
    np.testing.assert_allclose(two.ybar, [2.0, 5.0])
    with pytest.raises(ValueError, match="non-finite"):
        StaticPoints.from_repeats([1.0, 1.0], [2.0, np.nan])
    with pytest.raises(ValueError, match="non-finite"):
        StaticPoints([1.0, np.nan], [2.0, 3.0])


def test_noise_terms_rejected_in_process_structure():
    with pytest.raises(ValueError, match="noise terms belong"):
        Model(["y(k-1)", "e(k-1)"], [0.5, 0.1])


def test_models_are_immutable():
    m = reference.paper_model(15)
    with pytest.raises(ValueError):
        m.theta[0] = 1.0
    with pytest.raises(Exception):
        m.name = "x"


# -- one agreement per concept: types, values, bands (issue 22) ---------------------------------
from graybox.core._validation import check_band, check_bool, check_choice, check_int, check_real  # noqa: E402


@pytest.mark.parametrize("check, value, err", [
    (lambda v: check_int(v, "n", low=1), True, TypeError),
    (lambda v: check_int(v, "n", low=1), 2.5, TypeError),
    (lambda v: check_int(v, "n", low=1), "3", TypeError),
    (lambda v: check_int(v, "n", low=1), 0, ValueError),
    (lambda v: check_int(v, "n", low=1), np.nan, ValueError),
    (lambda v: check_real(v, "x", low=0), "0.1", TypeError),
    (lambda v: check_real(v, "x", low=0), True, TypeError),
    (lambda v: check_real(v, "x", low=0), np.inf, ValueError),
    (lambda v: check_real(v, "x", low=0), -1, ValueError),
    (lambda v: check_choice(v, "c", ("a", "b")), 1, TypeError),
    (lambda v: check_choice(v, "c", ("a", "b")), "A", ValueError),
    (lambda v: check_bool(v, "f"), 1, TypeError),
    (lambda v: check_band(v), 0.0, ValueError),
    (lambda v: check_band(v), (0.2, 0.1), ValueError),
    (lambda v: check_band(v), "0.1", TypeError),
])
def test_a_wrong_type_is_a_type_error_and_a_bad_value_a_value_error(check, value, err):
    with pytest.raises(err):
        check(value)


def test_integral_and_numpy_numbers_are_accepted():
    assert check_int(3.0, "n") == 3 and check_int(np.int64(4), "n") == 4 and check_int(np.array(5), "n") == 5
    assert check_real(np.float32(0.5), "x") == 0.5 and check_bool(np.bool_(True), "f") is True
    assert check_band(0.1) == (0.0, 0.1) and check_band((0.01, 0.1)) == (0.01, 0.1)


def test_the_inconsistencies_named_in_the_issue_are_gone():
    import graybox as gb

    with pytest.raises(TypeError, match="ny"):
        gb.Candidates(ny=True, nu=1)
    with pytest.raises(TypeError, match="nu"):
        gb.Candidates(ny=1, nu=True)
    with pytest.raises(TypeError, match="population"):
        gb.GAOptions(population=10.5)
    rec = Record(np.sin(np.arange(60.0)), np.cos(np.arange(60.0)))
    for select in (gb.frols, gb.semp):
        with pytest.raises(ValueError, match="criterion"):
            select(gb.Candidates(1, 1), rec, criterion="BIC")
        with pytest.raises(TypeError, match="tol"):
            select(gb.Candidates(1, 1), rec, tol="0.1")


def _per_unit_data():
    """A plant measured in per-unit: the static points carry no uncertainty."""
    import graybox as gb

    m = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.4, 0.05])
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(0.0, 1.0, 20), 10)
    y = m.simulate(u, np.zeros(1)) + 0.002 * rng.standard_normal(u.size)
    ub = np.linspace(0.1, 0.9, 5)
    return gb.Dataset(Record(u[:150], y[:150]), Record(u[150:], y[150:]), StaticPoints(ub, m.static_curve(ub)))


def test_a_band_left_out_without_an_uncertainty_says_what_to_pass():
    import graybox as gb

    data = _per_unit_data()
    st = gb.Structure(["y(k-1)", "u(k-1)", "1"])
    with pytest.raises(ValueError, match="carry no uncertainty.*band=B"):
        gb.se_dsf(st, data)
    with pytest.raises(ValueError, match="carry no uncertainty.*band=B"):
        gb.bootstrap_decision(st, data, n_boot=1, lambdas=[1.0, 0.5], options={"solver": "closed"})
    front = gb.pe_pareto(st, data, lambdas=[1.0, 0.5], solver="closed")
    with pytest.raises(ValueError, match="decide_dsf needs band=B"):
        gb.decide_dsf(front)
    with pytest.raises(ValueError, match="StaticBand needs its half-width"):
        gb.cls(st, data, constraints=gb.StaticBand())
    with pytest.raises(ValueError, match="band"):
        gb.bootstrap_decision(st, data, band=-1, n_boot=1, lambdas=[1.0], options={"solver": "closed"})


def test_the_points_uncertainty_gives_the_band_by_one_rule_in_any_units():
    import graybox as gb

    data = _per_unit_data()
    st = gb.Structure(["y(k-1)", "u(k-1)", "1"])
    sp = data.static.with_uncertainty([0.01, 0.02, 0.01, 0.02, 0.01])
    assert sp.band == pytest.approx(np.mean(np.array([0.01, 0.02, 0.01, 0.02, 0.01]) ** 2))
    scaled = StaticPoints(sp.ubar, 1000 * sp.ybar, uncertainty=1000 * sp.uncertainty)
    assert scaled.band == pytest.approx(1e6 * sp.band)  # output units²
    res = gb.se_dsf(st, data.ident, sp, lambdas=[0.5], pe_lambdas=[1.0, 0.1])
    assert res.band == sp.band
    # StaticBand without b: each point's own δ_i bounds its static error (points 0.05 off: the band binds)
    off = StaticPoints(sp.ubar, sp.ybar + 0.05, uncertainty=sp.uncertainty)
    th = gb.pe_thetas(st, data.ident, off, lambdas=[1.0], constraints=gb.StaticBand(), solver="clarabel")[0]
    err = np.abs(gb.Model(st, th).static_curve(off.ubar) - off.ybar)
    assert np.all(err <= off.uncertainty * (1 + 1e-4)) and np.isclose(err, off.uncertainty, rtol=1e-3).any()
    with pytest.raises(ValueError, match="uncertainty must be > 0"):
        StaticPoints([1.0, 2.0], [1.0, 2.0], uncertainty=[0.1, 0.0])
    with pytest.raises(TypeError, match="uncertainty"):
        StaticPoints([1.0, 2.0], [1.0, 2.0], uncertainty="x")


def test_the_bundled_data_carry_the_transmitters_error():
    import graybox as gb

    data = gb.load_pumping()
    assert np.all(data.static.uncertainty == 0.175) and data.static.band == pytest.approx(0.175**2)


# -- a result object's fields against their annotations (issue 22, the result objects) ------------
import dataclasses  # noqa: E402

from hypothesis import given, strategies as st  # noqa: E402

from graybox.core._validation import check_fields  # noqa: E402


@dataclasses.dataclass(frozen=True)
class _Result:
    """Annotations as strings, as every graybox module writes them (postponed evaluation)."""

    model: "Model"
    count: "int"
    figure: "float"
    flag: "bool"
    rule: "str"
    values: "np.ndarray"
    level: "float | None" = None
    names: "tuple[str, ...]" = ()
    hidden: "NameOnlyForTypeCheckers" = None  # noqa: F821: does not resolve, so it is not checked

    def __post_init__(self):
        check_fields(self)


_GOOD = dict(model=Model(["y(k-1)"], [0.5]), count=3, figure=0.5, flag=False, rule="D_SF", values=np.zeros(2))


@pytest.mark.parametrize("field, value", [
    ("model", "x"), ("count", True), ("count", 2.5), ("count", "3"), ("figure", True), ("figure", "0.5"),
    ("flag", 1), ("rule", 1.0), ("values", 2.5), ("values", "x"), ("level", "x"), ("names", "ab"),
])
def test_a_result_field_of_the_wrong_type_is_a_type_error_naming_class_and_field(field, value):
    with pytest.raises(TypeError, match=rf"^_Result: {field} must be "):
        _Result(**{**_GOOD, field: value})


@given(st.floats(allow_nan=True, allow_infinity=True) | st.integers() | st.floats(width=32).map(np.float32))
def test_a_float_field_takes_any_real_nan_and_inf_included(x):
    assert _Result(**{**_GOOD, "figure": x, "level": x}).figure is x


def test_numpy_scalars_none_and_array_likes_are_accepted_and_unresolved_names_skipped():
    r = _Result(**{**_GOOD, "count": np.int64(2), "flag": np.bool_(True), "values": [1.0, 2.0], "level": None,
                   "names": ("a",), "hidden": "anything"})
    assert r.count == 2 and r.hidden == "anything"
