"""hunt39a: laws that must hold across the package (units, inputs' order and names, lists of records,
searches), and the bugs found where one failed."""

import numpy as np
import pytest

import graybox as gb


# -- the error measures take the model's output as they take the measured one ----------------------------
@pytest.mark.parametrize("measure", [gb.mse, gb.rrse, gb.fit_percent])
@pytest.mark.parametrize("yhat, said", [
    (np.array(["1.0", "2.0", "4.0"]), "strings"),      # was parsed: mse 0.33, a score of text
    ([True, False, True], "yhat"),                     # was read as 1, 0, 1
    ([1.0, None, 4.0], "yhat"),                        # was NaN, a "diverged" run (mse inf, fit -inf)
    (np.array([1.0 + 1j, 2.0, 4.0]), "complex"),       # was its real part, with at most numpy's warning
    (gb.Model(["y(k-1)"], [0.5]), "yhat"),             # was numpy's "float() argument must be …", naming nothing
])
def test_a_model_output_that_is_not_numbers_is_refused_naming_yhat(measure, yhat, said):
    y = np.array([1.0, 2.0, 3.0])
    with pytest.raises(TypeError, match=said):
        measure(y, yhat)
    # numbers are scored as they were, NaN (a diverged free run) included
    assert measure(y, np.array([1.0, 2.0, 3.0])) == (100.0 if measure is gb.fit_percent else 0.0)
    assert np.isinf(measure(y, np.array([1.0, np.nan, 3.0])))


# -- equilibria whose roots span the float range ----------------------------------------------------------
def test_a_quadratic_whose_far_root_is_beyond_1e205_keeps_its_near_root():
    # y = 1 + c y²: the stable root near 1 and an unstable one near 1/c. The root kernel scaled the cubic's
    # absent coefficient by s³, which overflowed (0 · inf = NaN) once 1/c passed ~1e205, and every root
    # was lost: no equilibrium, static curve NaN, while c = 0 (and c = 1e-200) gave ȳ = 1
    st = gb.Structure(["1", "y(k-1)^2"])
    for c in (1e-200, 1e-212, 1e-250, 1e-300):
        m = gb.Model(st, [1.0, c])
        eq = m.equilibria(0.0)
        assert [e.stable for e in eq] == [True, False]
        assert eq[0].ybar == pytest.approx(1.0 + c, rel=1e-12) and eq[1].ybar == pytest.approx(1.0 / c, rel=1e-9)
        assert m.static_curve([0.0])[0] == pytest.approx(1.0, rel=1e-12)


def test_an_equilibrium_whose_linearisation_overflows_is_unstable_not_a_crash():
    # y = 1 + 1e-100 y² + 1e-270 y³ has roots near 1, 1e100 and -1e170; at -1e170, ∂f/∂y = 2e-100 y + 3e-270 y²
    # is 3e70 but y² overflows on the way: the spectral radius was numpy's LinAlgError "Array must not
    # contain infs or NaNs", and equilibria() and the local model with it
    m = gb.Model(gb.Structure(["1", "y(k-1)^2", "y(k-1)^3"]), [1.0, 1e-100, 1e-270])
    eq = m.equilibria(0.0)
    assert [e.stable for e in eq] == [False, True, False]
    assert eq[0].ybar == pytest.approx(-1e170, rel=1e-9) and eq[1].ybar == pytest.approx(1.0, rel=1e-12)
    assert eq[0].spectral_radius > 1 and eq[2].spectral_radius > 1
    assert m.static_curve([0.0])[0] == pytest.approx(1.0, rel=1e-12)


# -- laws that hold, kept as guards -----------------------------------------------------------------------
from hypothesis import assume, given, settings, strategies as st  # noqa: E402

ST = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-2)y(k-1)"])
TH = np.array([0.3, 0.5, 0.2, 0.4, 0.1, 0.05])
Y_POWER = np.array([0, 1, 1, 0, 0, 1])
U_POWER = np.array([0, 0, 0, 1, 2, 1])
LEVELS = np.linspace(0.0, 2.0, 5)
POINTS = np.array([0.5, 1.0, 1.5])  # inside every record's range


def _plant(seed, n=200, noise=0.05):
    rng = np.random.default_rng(seed)
    levels = rng.uniform(0.0, 2.0, n // 10 + 1)
    levels[:2] = 0.0, 2.0  # the whole range, static points included, in every record
    u = np.repeat(levels, 10)[:n]
    y = gb.Model(ST, TH).simulate(u, np.zeros(2)) + noise * rng.standard_normal(n)
    return u, y


def _estimates(data, static):
    """The free-run θ of each estimator on ``data`` (one record or several) and ``static``."""
    pe = gb.pe_pareto(ST, data, static, lambdas=[0.5, 0.01])
    se = gb.se_pareto(ST, data, static, lambdas=[0.3], method="gradient")
    return {"els": gb.els(ST, data).model.theta, "cls": gb.cls(ST, data, static, how="points").model.theta,
            "pe": pe.thetas, "se": se.thetas, "oe": gb.output_error(ST, data, n_starts=0).model.theta}


@settings(max_examples=3, deadline=None)
@given(la=st.floats(-3.0, 3.0), lb=st.floats(-3.0, 3.0), seed=st.integers(0, 1000))
def test_every_estimator_gives_the_same_model_in_other_units(la, lb, seed):
    # u × a and y × b: θ_j of a term y^p u^q scales by b^(1-p) a^(-q), the errors by b², the static curve by b
    # and its gain by b/a; every least-squares, QP and free-run fit scales internally, so nothing else moves
    a, b = 10.0**la, 10.0**lb
    u, y = _plant(seed)
    pts = POINTS  # three points, fewer than the five clusters: CLS passes through each
    ybar = gb.Model(ST, TH).static_curve(pts) * 1.02
    base = _estimates(gb.Record(u, y), gb.StaticPoints(pts, ybar))
    other = _estimates(gb.Record(a * u, b * y), gb.StaticPoints(a * pts, b * ybar))
    back = b ** (1.0 - Y_POWER) * a ** (-U_POWER.astype(float))
    for name in base:
        np.testing.assert_allclose(other[name] / back, base[name], rtol=1e-6, atol=1e-9, err_msg=name)
    m, m2 = gb.Model(ST, base["els"]), gb.Model(ST, other["els"])
    np.testing.assert_allclose(m2.static_curve(a * LEVELS) / b, m.static_curve(LEVELS), rtol=1e-9)
    np.testing.assert_allclose(m2.static_gain(a * LEVELS) * a / b, m.static_gain(LEVELS), rtol=1e-8)


@settings(max_examples=3, deadline=None)
@given(order=st.permutations([0, 1, 2]), seed=st.integers(0, 1000))
def test_estimates_do_not_depend_on_the_order_the_records_are_listed(order, seed):
    assume(order != [0, 1, 2])
    recs = [gb.Record(*_plant(seed + i, n), name=f"run {i}") for i, n in enumerate((200, 120, 150))]
    static = gb.StaticPoints(POINTS, gb.Model(ST, TH).static_curve(POINTS) * 1.02)
    base, other = _estimates(recs, static), _estimates([recs[i] for i in order], static)
    for name in base:
        np.testing.assert_allclose(other[name], base[name], rtol=1e-7, atol=1e-10, err_msg=name)
    cand = gb.Candidates(2, 2, degree=2)
    for search in ("greedy", "exact"):
        s1 = gb.frols(cand, recs, n_terms=5, search=search)
        s2 = gb.frols(cand, [recs[i] for i in order], n_terms=5, search=search)
        assert s1.structure == s2.structure
        np.testing.assert_allclose(s2.theta, s1.theta, rtol=1e-8, atol=1e-12)


def test_records_given_as_a_set_are_refused_as_having_no_order():
    # a set of records was taken in its iteration order, which follows the records' addresses (Record hashes by
    # identity): the GA's and output_error's seeded starts, the model's period and input names are the first
    # record's, so se_pareto(..., seed=0) on {a, b} changed from one run to the next
    recs = [gb.Record(*_plant(i, n), name=f"run {i}") for i, n in enumerate((200, 120))]
    for data in (set(recs), frozenset(recs)):
        for call in (lambda d: gb.cls(ST, d), lambda d: gb.frols(gb.Candidates(2, 2), d, n_terms=3)):
            with pytest.raises(TypeError, match=r"data: an ordered sequence of records is needed, got a "
                                                r"(frozen)?set.*pass a list"):
                call(data)
    assert len(gb.cls(ST, {"a": recs[0], "b": recs[1]}.values()).model.theta) == len(ST)  # a dict's are ordered


# -- CLS, PE and SE covariances of a model that carries an MA part -------------------------------------------
@pytest.mark.parametrize("which", ["se", "pe", "cls"])
def test_a_gray_box_covariance_of_a_model_with_an_ma_part_says_so(which):
    # an ELS model passed to se_uncertainty (say, for its free run's spread at λ1 = 1) failed inside the result's
    # own check: "noise_cov must have shape (2, 2), the covariance of the model's 2 MA parameter(s), got (0, 0)"
    u, y = _plant(3)
    rec = gb.Record(u, y)
    static = gb.StaticPoints(POINTS, gb.Model(ST, TH).static_curve(POINTS))
    els = gb.els(ST, rec)  # MA(2)
    call = {"se": lambda m: gb.se_uncertainty(m, rec, static, lambda1=1.0),
            "pe": lambda m: gb.pe_uncertainty(m, rec, static, lambda1=1.0),
            "cls": lambda m: gb.cls_uncertainty(m, rec, static, how="context")}[which]
    for given_ in (els, els.model):
        with pytest.raises(ValueError, match=r"MA part .*e\(k-1\).*ls_uncertainty"):
            call(given_)


# -- numbers given as text are refused where they enter, as Record and StaticPoints refuse them -----------
def test_initial_outputs_lambdas_curve_coefficients_and_front_points_of_text_are_refused():
    rec = gb.Record(np.arange(20.0) % 3, np.arange(20.0) % 5)
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    cases = [  # each was parsed as numbers and used
        (lambda: m.simulate(np.ones(3), np.array(["1"])), "y0"),
        (lambda: m.simulate(np.ones(3), [None]), "y0"),
        (lambda: gb.pe_thetas(m.structure, rec, gb.StaticPoints([0.0, 1.0], [0.0, 1.0]), lambdas=["0.5"]), "lambdas"),
        (lambda: gb.StaticCurve.polynomial(["1", "2"]), "coefficients"),
        (lambda: gb.nondominated_mask([["1", "2"], ["3", "0"]]), "points"),
        (lambda: gb.nondominated_mask([[1.0, None], [3.0, 0.0]]), "points"),  # was NaN: the row silently dropped
    ]
    for call, said in cases:
        with pytest.raises(TypeError, match=said):
            call()
    # numbers pass as before
    np.testing.assert_allclose(m.simulate(np.ones(3), [1.0]), [1.0, 1.5, 1.75])
    assert gb.StaticCurve.polynomial([1, 2]).coefficients.tolist() == [1.0, 2.0]
    assert gb.nondominated_mask([[1.0, 2.0], [3.0, 0.0], [4.0, 4.0]]).tolist() == [True, True, False]


# -- an operating curve of several inputs names the input its settling time steps ---------------------------
def test_the_operating_curves_table_names_the_input_its_settling_time_steps():
    # the settling time is of a step of the model's first input; with several inputs the table's column said only
    # "settling time", so the same model with its inputs listed the other way round gave another number under the
    # same name (1.0 s against 0.9 s here): names did not follow the inputs
    st_ = gb.Structure(["1", "y(k-1)", "a(k-1)", "b(k-3)", "a(k-1)b(k-1)", "a(k-1)y(k-1)"])
    th = [0.2, 0.5, 0.3, 0.2, 0.1, 0.05]
    pts = np.array([[0.5, 0.5], [0.7, 1.2]])
    for names, order in ((("a", "b"), [0, 1]), (("b", "a"), [1, 0])):
        oc = gb.operating_curve(gb.Model(st_, th, input_names=names, Ts=0.1), pts[:, order])
        frame = oc.to_frame()
        assert "settling time" not in frame.columns
        np.testing.assert_array_equal(frame[f"settling time ({names[0]} step)"].to_numpy(),
                                      [lm.settling_time(names[0]) for lm in oc.local_models])
    one = gb.operating_curve(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], Ts=0.1), [1.0, 2.0]).to_frame()
    assert "settling time" in one.columns  # one input: nothing to name


ST3 = gb.Structure(["1", "y(k-1)", "a(k-1)", "b(k-2)", "c(k-1)", "a(k-1)b(k-1)", "c(k-1)y(k-1)"])
TH3 = np.array([0.3, 0.5, 0.4, -0.3, 0.2, 0.2, 0.05])


@settings(max_examples=3, deadline=None)
@given(order=st.permutations([0, 1, 2]), seed=st.integers(0, 1000))
def test_three_inputs_listed_in_any_order_give_the_same_models_their_gains_following_the_names(order, seed):
    assume(order != [0, 1, 2])
    names = ("a", "b", "c")
    rng = np.random.default_rng(seed)
    levels = rng.uniform(0.0, 1.0, (41, 3))
    levels[0], levels[1] = 0.0, 1.0  # every input over its whole range
    u = np.repeat(levels, 8, axis=0)[:320]
    y = gb.Model(ST3, TH3, input_names=names).simulate(u, [0.0, 0.0]) + 0.02 * rng.standard_normal(len(u))
    pts = np.array([[0.2, 0.5, 0.8], [0.8, 0.2, 0.5], [0.5, 0.8, 0.2], [0.5, 0.5, 0.5]])
    ybar = gb.Model(ST3, TH3, input_names=names).static_curve(pts) * 1.01
    perm = tuple(names[i] for i in order)

    def fits(cols, inputs):
        rec = gb.Record(u[:, cols], y, input_names=inputs)
        static = gb.StaticPoints(pts[:, cols], ybar, input_names=inputs)
        models = {"els": gb.els(ST3, rec).model, "pe": gb.pe_pareto(ST3, rec, static, lambdas=[0.3]).member_model(0),
                  "se": gb.se_pareto(ST3, rec, static, lambdas=[0.3], method="gradient").member_model(0),
                  "cls": gb.cls(ST3, rec, static, how="points").model,
                  "exact": gb.frols(gb.Candidates(1, 1, degree=2, input_names=inputs), rec, n_terms=6,
                                    search="exact").model}
        return {k: (m, dict(zip(m.input_names, m.static_gain(pts[:, cols]).T))) for k, m in models.items()}

    base, other = fits([0, 1, 2], names), fits(list(order), perm)
    for k in base:
        (m0, g0), (m1, g1) = base[k], other[k]
        assert m1.input_names == perm and set(m0.structure) == set(m1.structure), k
        np.testing.assert_allclose(m1.simulate(gb.Record(u[:, order], y, input_names=perm)), m0.simulate(
            gb.Record(u, y, input_names=names)), rtol=1e-7, atol=1e-9, err_msg=k)
        for n in names:
            np.testing.assert_allclose(g1[n], g0[n], rtol=1e-7, atol=1e-10, err_msg=f"{k}: gain along {n}")
