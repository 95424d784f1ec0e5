"""Mend 36b: items left open by earlier bug hunts.

1. Identifiability is one rule (core._least_squares.check_identified, through
   estimation._prediction_error.identified_by) for the least-squares start, CLS, PE and the SE
   estimators: the records' regression stacked with the static rows where they carry weight must
   have full rank, judged units-free. An input held constant is refused only when the static points
   do not identify θ either, with a message that says what is missing.
2. A pandas DataFrame of inputs is read by column name where its columns are the inputs' names, by
   position where they name none, and refused where they name some: one rule in the one coercion of
   inputs (core._records.frame_inputs, used by as_input_array and the static-surface paths).
3. A ParetoSet's members are in the caller's order of ``lambdas`` for se_pareto as for pe_pareto
   (the sweep from λ1 = 1 down is an internal matter of the SE solvers).
"""

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._prediction_error import pe_thetas
from graybox.estimation._simulation_error import SEProblem

# y(k) = 0.5 y(k−1) + 0.2 u(k−1) + 0.01 u(k−1)² + 1: a known answer
TRUE = np.array([0.5, 0.2, 0.01, 1.0])
STRUCT = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]


def held(level, n=200, y0=0.0, noise=0.01, seed=0, unit=1.0):
    """A record whose input is held at ``level`` (u in ``unit``s), y starting from ``y0``."""
    rng = np.random.default_rng(seed)
    y = np.empty(n)
    y[0] = y0
    for k in range(1, n):
        y[k] = TRUE[0] * y[k - 1] + TRUE[1] * level + TRUE[2] * level ** 2 + TRUE[3]
    return gb.Record(np.full(n, level * unit), y + noise * rng.standard_normal(n), name=f"held at {level:g}")


def points(levels=(1.0, 2.0, 4.0, 5.0, 6.0), unit=1.0):
    ub = np.asarray(levels, float)
    return gb.StaticPoints(ub * unit, (TRUE[1] * ub + TRUE[2] * ub ** 2 + TRUE[3]) / (1 - TRUE[0]))


def in_units(theta, unit):
    """θ of the true system written for u in ``unit``s."""
    return np.asarray(theta) * np.array([1.0, 1.0 / unit, 1.0 / unit ** 2, 1.0])


@pytest.fixture(autouse=True)
def _quiet_range():
    # the static points lie outside a held record's one level on purpose
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        yield


# -- 1. one identifiability rule ---------------------------------------------------------------

@pytest.mark.parametrize("method", ["gradient", "ga"])
def test_se_pareto_fits_a_held_record_that_static_points_identify(method):
    # was: "least squares: regressor matrix has rank 2 < 4 columns": the least-squares start was
    # taken on the record alone, so a record at one level was refused although the static points
    # at five levels identify θ (PE fitted the same data)
    kw = dict(options=gb.GAOptions(population=30, generations=10)) if method == "ga" else {}
    front = gb.se_pareto(STRUCT, held(3.0), points(), lambdas=[1.0, 0.5, 0.1], method=method, **kw)
    # λ1 = 1 gives the static points no weight: θ is not identified there, and the member says so
    assert set(front.failures) == {0}
    assert "λ1 = 1" in front.failures[0] and "not identifiable" in front.failures[0]
    for i in (1, 2):
        assert np.allclose(front.thetas[i], TRUE, rtol=0.02, atol=0.01)
        assert front.JSF[i] < 1e-3


def test_se_dsf_fits_a_held_record_that_static_points_identify():
    # was: "no start (none found) ... least squares: regressor matrix has rank 2 < 4 columns"
    res = gb.se_dsf(STRUCT, held(3.0), points(), band=1e-3)
    assert res.in_band
    assert np.allclose(res.model.theta, TRUE, rtol=0.02, atol=0.01)


def test_several_records_each_held_at_its_level_with_static_points():
    # two levels do not separate u, u² and the constant; the static points do: SE fits, PE agrees
    recs = [held(1.0, 80, seed=1), held(4.0, 80, seed=2)]
    with pytest.raises(ValueError, match=r"not identifiable from the identification records:.*u\(k-1\)\^2"):
        gb.output_error(STRUCT, recs)
    front = gb.se_pareto(STRUCT, recs, points(), lambdas=[0.5], method="gradient")
    assert np.allclose(front.thetas[0], TRUE, rtol=0.02, atol=0.01)


def test_least_squares_start_of_a_held_record_is_the_stacked_least_squares():
    # the start where the records alone leave θ free: records and static rows, each as a mean
    # square, i.e. PE's closed form at λ1 = 1/2 (an independent computation)
    rec, pts = held(3.0), points()
    ls = SEProblem(gb.Structure(STRUCT), rec, pts).ls_theta()
    pe = pe_thetas(STRUCT, rec, pts, lambdas=[0.5], solver="closed")[0]
    assert np.allclose(ls, pe, rtol=1e-8, atol=1e-10)
    # where the records identify θ the start is least squares on them, as before
    moving = gb.Record(np.repeat([1.0, 3.0, 5.0], 60), np.r_[held(1.0, 60).y, held(3.0, 60).y, held(5.0, 60).y])
    ls2 = SEProblem(gb.Structure(STRUCT), moving, pts).ls_theta()
    assert np.allclose(ls2, gb.els(STRUCT, moving, noise=0).model.theta, rtol=1e-8, atol=1e-10)


def test_pe_member_at_lambda_one_on_a_held_record_is_failed_not_made_up():
    # was: pe_pareto returned a θ at λ1 = 1 (one of infinitely many minimisers: [0.499, 0.188,
    # 0.063, 0.564] against the system's [0.5, 0.2, 0.01, 1]) without a word
    rec, pts = held(3.0), points()
    front = gb.pe_pareto(STRUCT, rec, pts, lambdas=[1.0, 0.5])
    assert set(front.failures) == {0} and "λ1 = 1" in front.failures[0]
    assert np.allclose(front.thetas[1], TRUE, rtol=0.02, atol=0.01)
    with pytest.raises(ValueError, match=r"λ1 = 1.*not identifiable.*static points at several input levels"):
        pe_thetas(STRUCT, rec, pts, lambdas=[1.0, 0.5])
    with pytest.raises(ValueError, match="not identifiable"):  # no member left: refused
        gb.pe_pareto(STRUCT, rec, pts, lambdas=[1.0])


def test_cls_on_a_held_record_follows_the_same_rule():
    # the curve's equality rows identify θ with the record: CLS fits (given Σ*_y); its least-squares
    # reference is refused in the rule's words, saying what else to give
    rec, pts = held(3.0), points()
    with pytest.raises(ValueError, match=r"reference='ls'.*not identifiable from the identification records"):
        gb.cls(STRUCT, rec, pts, reference="ls")
    assert np.allclose(gb.cls(STRUCT, rec, pts, reference=TRUE[0]).model.theta, TRUE, rtol=0.02, atol=0.01)
    # Σ_y estimated (the default) needs no reference: the curve's rows and the record identify θ together
    assert np.allclose(gb.cls(STRUCT, rec, pts).model.theta, TRUE, rtol=0.02, atol=0.01)


def test_terms_static_points_cannot_separate_name_a_moving_input_as_what_is_missing():
    # u(k−1) and u(k−2) share the cluster Σu: no static point separates them, only a moving input
    st = ["y(k-1)", "u(k-1)", "u(k-2)", "1"]
    for call in (lambda: gb.se_pareto(st, held(3.0), points(), lambdas=[0.5], method="gradient"),
                 lambda: gb.se_dsf(st, held(3.0), points(), band=1e-3),
                 lambda: pe_thetas(st, held(3.0), points(), lambdas=[0.5])):
        with pytest.raises(ValueError, match=r"\['u\(k-1\)', 'u\(k-2\)'\]: give a record whose input moves \("):
            call()


@pytest.mark.parametrize("unit", [1e-3, 1.0, 1e3])
def test_the_rule_does_not_depend_on_units(unit):
    # the same data in other input units: the same verdicts and the same estimate (in those units)
    rec, pts = held(3.0, unit=unit), points(unit=unit)
    problem = SEProblem(gb.Structure(STRUCT), rec, pts)
    assert not problem.records_identify()
    problem.check_identified()  # the static points identify θ
    assert np.allclose(problem.ls_theta(), in_units(SEProblem(gb.Structure(STRUCT), held(3.0), points()).ls_theta(),
                                                     unit), rtol=1e-6)
    with pytest.raises(ValueError, match="not identifiable"):
        problem.check_identified(1.0)


# -- 2. a DataFrame of inputs is read by name where its columns are the inputs ---------------------

def _frame(n=40, seed=0):
    import pandas as pd

    rng = np.random.default_rng(seed)
    return pd.DataFrame({"p": rng.uniform(0.0, 1.0, n), "n": rng.uniform(10.0, 20.0, n)})


def test_record_reads_a_dataframe_by_its_column_names():
    # was: read by position, so columns ("p", "n") for input_names ("n", "p") swapped the inputs
    df = _frame()
    rec = gb.Record(df, np.zeros(len(df)), input_names=("n", "p"))
    assert np.array_equal(rec.input("n"), df["n"].to_numpy()) and np.array_equal(rec.input("p"), df["p"].to_numpy())
    # the default names are names too: columns u2, u1 are read as u2, u1
    rec2 = gb.Record(df.set_axis(["u2", "u1"], axis=1), np.zeros(len(df)))
    assert np.array_equal(rec2.input("u1"), df["n"].to_numpy())
    # columns that name no input (here pandas' 0, 1) are read by position, as documented
    rec3 = gb.Record(df.set_axis([0, 1], axis=1), np.zeros(len(df)), input_names=("n", "p"))
    assert np.array_equal(rec3.input("n"), df["p"].to_numpy())


@pytest.mark.parametrize("columns", [["p", "speed"], ["n", "p", "time"], ["n", "n"]])
def test_a_dataframe_naming_some_inputs_is_refused_naming_its_columns(columns):
    # was: read by position: "p" landed on the input "n" (or a column was taken as an input unseen)
    df = _frame().iloc[:, [0, 1, 1][:len(columns)]].set_axis(columns, axis=1)
    with pytest.raises(ValueError, match=r"columns \[.*\] (name only some of the inputs|name every input) \['n', 'p'\]"):
        gb.Record(df, np.zeros(len(df)), input_names=("n", "p"))


def test_every_input_path_reads_a_dataframe_by_name():
    # the one coercion (core._records.frame_inputs) serves records, static points, free runs and surfaces:
    # each of these read ("p", "n") as ("n", "p") before
    df = _frame()
    model = gb.Model(["n(k-1)", "p(k-1)", "y(k-1)"], [1.0, 10.0, 0.5], input_names=("n", "p"))
    arr = df[["n", "p"]].to_numpy()
    y0 = np.zeros(1)
    assert np.array_equal(model.simulate(df, y0), model.simulate(arr, y0))
    assert np.array_equal(gb.simulate(model.structure, model.theta, df, y0), model.simulate(arr, y0))
    assert np.array_equal(model.static_curve(df.iloc[:5]), model.static_curve(arr[:5]))
    pts = gb.StaticPoints(df.iloc[:5], np.ones(5), input_names=("n", "p"))
    assert np.array_equal(pts.ubar, arr[:5])
    rep = gb.StaticPoints.from_repeats(df.iloc[:5], np.ones(5), input_names=("n", "p"))
    assert np.array_equal(rep.ubar, np.unique(arr[:5], axis=0))
    surface = gb.StaticSurface.fit(gb.StaticPoints(arr[:6], arr[:6] @ [1.0, 2.0], input_names=("n", "p")), degree=1)
    assert np.allclose(surface(df.iloc[:3]), surface(arr[:3]))
    with pytest.raises(ValueError, match="name only some"):
        model.simulate(df.set_axis(["n", "q"], axis=1), y0)


# -- 3. a Pareto set's members are in the caller's order of lambdas --------------------------------

@pytest.mark.parametrize("method", ["gradient", "ga"])
def test_se_pareto_keeps_the_callers_order_of_lambdas_as_pe_pareto_does(method):
    # was: se_pareto returned its members from λ1 = 1 down (the sweep's order) while pe_pareto kept
    # the caller's, so member i of the two sets of one call named different λ1
    rec = gb.Record(np.repeat([1.0, 3.0, 5.0, 2.0], 50), np.r_[held(1.0, 50).y, held(3.0, 50, y0=3.0).y,
                                                              held(5.0, 50, y0=5.0).y, held(2.0, 50, y0=9.0).y])
    lams = [0.1, 1.0, 0.5]
    kw = dict(options=gb.GAOptions(population=20, generations=5)) if method == "ga" else {}
    front = gb.se_pareto(STRUCT, rec, points(), lambdas=lams, method=method, seed=0, **kw)
    pe = gb.pe_pareto(STRUCT, rec, points(), lambdas=lams)
    assert front.lambdas.tolist() == lams == pe.lambdas.tolist()
    # the sweep runs from λ1 = 1 down whatever the order given: the same members, in the caller's order
    swept = gb.se_pareto(STRUCT, rec, points(), lambdas=sorted(lams, reverse=True), method=method, seed=0, **kw)
    assert np.array_equal(front.thetas, swept.thetas[[2, 0, 1]])
    assert np.array_equal(front.extra["cost"], swept.extra["cost"][[2, 0, 1]])
    assert np.array_equal(front.JS, swept.JS[[2, 0, 1]])


def test_se_pareto_failed_members_keep_their_lambda_in_the_callers_order():
    # a failure's key is the member's index in the caller's order (here λ1 = 1, given second)
    front = gb.se_pareto(STRUCT, held(3.0), points(), lambdas=[0.5, 1.0], method="gradient")
    assert set(front.failures) == {1} and front.lambdas[1] == 1.0
    assert np.all(np.isfinite(front.thetas[0])) and np.all(np.isnan(front.thetas[1]))


def test_a_pe_member_refused_at_lambda_one_says_its_lambda_once():
    # was: "λ1 = 1: θ at λ1 = 1 (no weight on the static points) is not identifiable …", λ1 said twice
    u = np.full(200, 3.0)
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    y = gb.Model(st, [0.5, 0.2, 0.01, 1.0]).simulate(u, np.zeros(1)) + 0.01 * np.random.default_rng(0).standard_normal(200)
    ub = np.linspace(1.0, 5.0, 5)
    pe = gb.pe_pareto(st, gb.Record(u, y), gb.StaticPoints(ub, (0.2 * ub + 0.01 * ub**2 + 1) / 0.5), lambdas=[1.0, 0.5])
    assert list(pe.failures) == [0] and pe.failures[0].count("λ1 = 1") == 1
    assert pe.failures[0].startswith("θ at λ1 = 1 (no weight on the static points) is not identifiable")


def test_a_dataframe_naming_every_input_and_more_says_the_extra_columns_are_the_fault():
    # was: "name only some of the inputs" for a frame that names every input, beside a time column
    df = _frame().iloc[:, [0, 1, 1]].set_axis(["n", "p", "time"], axis=1)
    with pytest.raises(ValueError, match=r"name every input \['n', 'p'\] and more columns \(not inputs: \['time'\]"):
        gb.Record(df, np.zeros(len(df)), input_names=("n", "p"))
    with pytest.raises(ValueError, match=r"name only some of the inputs \['n', 'p'\]"):
        gb.Record(df.set_axis(["p", "q", "time"], axis=1), np.zeros(len(df)), input_names=("n", "p"))


def test_a_dataframe_naming_an_input_twice_says_so():
    df = _frame().iloc[:, [0, 1, 1]].set_axis(["n", "p", "p"], axis=1)
    with pytest.raises(ValueError, match=r"name every input \['n', 'p'\], some more than once .*repeated: \['p'\]"):
        gb.Record(df, np.zeros(len(df)), input_names=("n", "p"))
