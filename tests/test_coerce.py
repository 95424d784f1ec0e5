"""One coercion per concept: every public entry takes each result where it means a model or a structure.

The system is synthetic (a rational NARX model with a known static curve and static points that
disagree a little with the dynamics), not the bundled plant.
"""

from __future__ import annotations

import json
import warnings

import matplotlib
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox import plots

matplotlib.use("Agg")

TRUE = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)", "1"])
THETA = np.array([0.6, 0.2, 0.3, 0.05, -0.02, 0.4])
BAND = 0.05  # output units² of this system


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(11)
    m = gb.Model(TRUE, THETA)
    u = np.repeat(rng.uniform(0.0, 3.0, 60), 20)
    y = m.simulate(u, np.zeros(2)) + 0.05 * rng.standard_normal(u.size)
    ub = np.linspace(0.2, 2.8, 8)
    static = gb.StaticPoints(ub, m.static_curve(ub) + 0.2 * np.sin(ub))
    return gb.Dataset(gb.Record(u[:800], y[:800], name="ident"), gb.Record(u[800:], y[800:], name="valid"), static)


@pytest.fixture(scope="module")
def results(data):
    """Every kind of value that carries a model or a structure, each fitted on ``data``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # convergence and candidate notes are not under test here
        fit = gb.els(TRUE, data)
        front = gb.pe_pareto(TRUE, data, lambdas=np.logspace(-4, 0, 12))
        out = {
            "Model": gb.Model(TRUE, THETA, name="true"),
            "ELSResult": fit,
            "CLSResult": gb.cls(TRUE, data),
            "Decision": gb.decide_dsf(front, band=BAND, fallback="min_jsf"),
            "DSFResult": gb.se_dsf(TRUE, data, band=BAND, theta0=fit.model.theta, max_iter=5),
            "Selection": gb.frols(gb.Candidates(2, 2, degree=2, max_y_power=1), data, n_terms=5),
            "SEMPResult": gb.semp(gb.Candidates(2, 2, degree=1), data, n_terms=3),
            "ParetoSet": front,
        }
    return out


MODEL_CARRIERS = ["Model", "ELSResult", "CLSResult", "Decision", "DSFResult", "Selection", "SEMPResult"]
STRUCTURE_CARRIERS = MODEL_CARRIERS + ["ParetoSet", "Structure", "list of str"]


def _model_of(obj):
    return obj if isinstance(obj, gb.Model) else obj.model


def _carrier(results, kind):
    if kind == "Structure":
        return TRUE, TRUE
    if kind == "list of str":
        return [str(t) for t in TRUE], TRUE
    obj = results[kind]
    return obj, getattr(obj, "structure", None) or obj.model.structure


# -- a model where a model is meant -----------------------------------------------------------

@pytest.mark.parametrize("kind", MODEL_CARRIERS)
def test_scores_take_every_result_where_a_model_is_meant(results, data, kind):
    obj = results[kind]
    m = _model_of(obj)
    assert isinstance(m, gb.Model)
    # a Dataset stands for its validation record when a model is scored
    assert gb.j1(obj, data) == gb.j1(m, data.valid)
    assert gb.js(obj, data.valid) == gb.js(m, data.valid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a model that reaches no equilibrium somewhere: J_SF = inf
        assert gb.jsf(obj, data) == gb.jsf(m, data.static)
        table = gb.evaluate({"r": obj}, data)
        pd.testing.assert_frame_equal(table, gb.evaluate({"r": m}, data))
    assert list(table.columns[:4]) == ["JS_ident", "JS_valid", "JSF", "n_params"]


@pytest.mark.parametrize("kind", MODEL_CARRIERS)
def test_diagnostics_and_plots_take_every_result_where_a_model_is_meant(results, data, kind):
    obj = results[kind]
    m = _model_of(obj)
    a = gb.one_step_residuals(obj, data)
    b = gb.one_step_residuals(m, data.valid)  # a Dataset means its validation record here too
    np.testing.assert_array_equal(a[0], b[0])
    t1, t2 = gb.residual_tests(obj, data, max_lag=5), gb.residual_tests(m, data.valid, max_lag=5)
    assert t1.passed == t2.passed and t1.failed == t2.failed
    fig = plots.plot_free_run(data, obj)
    line = fig.axes[0].lines[1].get_ydata()
    np.testing.assert_array_equal(line, m.simulate(data.valid, on_diverge="nan"))


@pytest.mark.parametrize("kind", ["ELSResult", "Selection"])
def test_ls_uncertainty_takes_the_least_squares_results(results, data, kind):
    obj = results[kind]
    a = gb.ls_uncertainty(obj, data)  # a Dataset means its identification record for an estimate
    b = gb.ls_uncertainty(obj.model, data.ident)
    np.testing.assert_array_equal(a.cov, b.cov)


def test_cls_uncertainty_and_reference_take_a_cls_result(results, data):
    # (no Σyu cluster here: eq. (22) pins it at 0, and the covariance's check of that row is relative to
    # its own tiny |θ|, so it refuses a round-off residual)
    st = gb.Structure([t for t in TRUE if str(t) != "u(k-1)y(k-1)"])
    res = gb.cls(st, data)
    a = gb.cls_uncertainty(res, data)
    np.testing.assert_array_equal(a.cov, gb.cls_uncertainty(res.model, data).cov)
    curve = gb.StaticCurve.fit(data.static, degree=2)
    fit = results["ELSResult"]
    np.testing.assert_array_equal(gb.cls(TRUE, data, curve, reference=fit).model.theta,
                                  gb.cls(TRUE, data, curve, reference=fit.model).model.theta)


def test_neural_fit_is_taken_where_a_neural_model_is(data):
    fit = gb.neural_narx(data.ident, ny=2, nu=2, ne=0, hidden=3, epochs=5, sim_epochs=2, seed=0)
    assert gb.js(fit, data) == gb.js(fit.model, data.valid)
    t = gb.residual_tests(fit, data, max_lag=5)
    assert t.passed == gb.residual_tests(fit.model, data.valid, max_lag=5).passed


# -- a structure where a structure is meant ---------------------------------------------------

@pytest.mark.parametrize("kind", STRUCTURE_CARRIERS)
def test_estimators_take_every_result_where_a_structure_is_meant(results, data, kind):
    obj, st = _carrier(results, kind)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        np.testing.assert_array_equal(gb.cls(obj, data).model.theta, gb.cls(st, data).model.theta)
        np.testing.assert_array_equal(gb.pe_thetas(obj, data, lambdas=[0.3, 1.0]),
                                      gb.pe_thetas(st, data, lambdas=[0.3, 1.0]))
        a = gb.els(obj, data, noise=1)
        assert list(a.model.structure) == list(st)
        np.testing.assert_array_equal(a.model.theta, gb.els(st, data, noise=1).model.theta)
    th = np.atleast_2d(results["Model"].theta) if len(st) == len(TRUE) and list(st) == list(TRUE) else None
    if th is not None:
        ev = gb.evaluate_thetas(obj, th, data)  # a Dataset: its validation record and its static points
        ref = gb.evaluate_thetas(TRUE, th, data.valid, data.static)
        assert ev.keys() == ref.keys() == {"J1", "JS", "JSF"}
        for k in ev:
            np.testing.assert_array_equal(ev[k], ref[k])


@pytest.mark.parametrize("kind", ["ELSResult", "Decision", "Selection", "Model"])
def test_simulation_error_estimators_take_results(results, data, kind):
    obj, st = _carrier(results, kind)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = gb.se_pareto(obj, data, lambdas=[0.5, 1.0], method="gradient", max_nfev=3, progress=False)
        b = gb.se_pareto(st, data, lambdas=[0.5, 1.0], method="gradient", max_nfev=3, progress=False)
        np.testing.assert_array_equal(a.thetas, b.thetas)
        theta0 = results["ELSResult"].model.theta if list(st) == list(TRUE) else None
        if theta0 is not None:
            c = gb.se_dsf(obj, data, band=BAND, theta0=theta0, max_iter=3)
            np.testing.assert_array_equal(c.model.theta, gb.se_dsf(st, data, band=BAND, theta0=theta0,
                                                                   max_iter=3).model.theta)


def test_els_keeps_the_noise_part_a_model_or_selection_carries(results, data):
    fit = results["ELSResult"]
    again = gb.els(fit, data)
    assert list(again.model.noise_structure) == list(fit.model.noise_structure)
    sel = gb.frols(gb.Candidates(2, 2, ne=3, degree=1), data, n_terms=3)
    assert len(gb.els(sel, data).model.noise_structure) == 3


# -- anything else: a TypeError that lists what is accepted -------------------------------------

@pytest.mark.parametrize("call", [
    lambda d, r: gb.j1({"not": "a model"}, d),
    lambda d, r: gb.js(3.0, d),
    lambda d, r: gb.jsf(r["ParetoSet"], d),
    lambda d, r: gb.evaluate({"set": r["ParetoSet"]}, d),
    lambda d, r: gb.residual_tests("model", d),
    lambda d, r: gb.one_step_residuals(r["ParetoSet"], d),
    lambda d, r: gb.ls_uncertainty(r["ParetoSet"], d),
    lambda d, r: gb.pe_uncertainty(None, d, lambda1=0.5),
    lambda d, r: plots.plot_free_run(d, r["ParetoSet"]),
], ids=["j1", "js", "jsf", "evaluate", "residual_tests", "one_step_residuals", "ls_uncertainty", "pe_uncertainty",
        "plot_free_run"])
def test_a_model_argument_of_another_type_lists_what_is_accepted(results, data, call):
    with pytest.raises(TypeError, match=r"must be a Model.*result that carries one in \.model.*ELSResult") as exc:
        call(data, results)
    if "ParetoSet" in str(exc.value):  # a set: how to choose one of its models
        assert "member_model(i)" in str(exc.value) and "decide_dsf" in str(exc.value)


@pytest.mark.parametrize("call", [
    lambda d: gb.cls(3, d),
    lambda d: gb.pe_pareto({"y(k-1)": 1.0}, d),
    lambda d: gb.pe_thetas(None, d),
    lambda d: gb.els(1.5, d),
    lambda d: gb.se_pareto(object(), d, progress=False),
    lambda d: gb.se_dsf("y(k-1)", d, band=BAND),
    lambda d: gb.evaluate_thetas(2, np.zeros((1, 1)), d),
    lambda d: gb.bootstrap_decision(7, d),
], ids=["cls", "pe_pareto", "pe_thetas", "els", "se_pareto", "se_dsf", "evaluate_thetas", "bootstrap_decision"])
def test_a_structure_argument_of_another_type_lists_what_is_accepted(data, call):
    with pytest.raises(TypeError, match=r"structure must be a Structure, a sequence of terms.*Selection.*ELSResult"):
        call(data)


@pytest.mark.parametrize("call", [
    lambda d, m: gb.j1(m, [d.valid]),
    lambda d, m: gb.evaluate({"m": m}, d.valid),
    lambda d, m: gb.evaluate_thetas(TRUE, np.atleast_2d(m.theta), "valid"),
    lambda d, m: gb.els(TRUE, "ident"),
    lambda d, m: gb.se_pareto(TRUE, {"u": 1}, progress=False),
    lambda d, m: gb.residual_tests(m, 3),
    lambda d, m: plots.plot_free_run(np.zeros(3), m),
], ids=["j1", "evaluate", "evaluate_thetas", "els", "se_pareto", "residual_tests", "plot_free_run"])
def test_a_data_argument_of_another_type_lists_what_is_accepted(results, data, call):
    with pytest.raises(TypeError, match=r"must be a (Record|Dataset)"):
        call(data, results["Model"])


def test_a_static_argument_of_another_type_lists_what_is_accepted(data):
    with pytest.raises(TypeError, match="static must be StaticPoints, a StaticCurve, a StaticSurface or None"):
        gb.cls(TRUE, data, [1.0, 2.0])
    with pytest.raises(TypeError, match="static must be StaticPoints, a StaticCurve, a StaticSurface or None"):
        gb.se_pareto(TRUE, data, data.static.ubar, progress=False)
    with pytest.raises(TypeError, match="static must be StaticPoints or None"):  # J_SF scores points only
        gb.jsf(gb.Model(TRUE, np.zeros(len(TRUE))), [1.0, 2.0])


# -- the static points: one resolution, cls included --------------------------------------------

def test_every_estimator_takes_the_datasets_static_points(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # cls: the Dataset's points are the static information as if given; 8 points for 5 clusters
        # cannot all be passed through, so the curve the numerator carries is imposed (eq. (22))
        res = gb.cls(TRUE, data)
        assert res.static is data.static and res.constraints[0].startswith("static curve equality (22)")
        np.testing.assert_array_equal(res.model.theta, gb.cls(TRUE, data.ident, data.static).model.theta)
        np.testing.assert_array_equal(res.model.theta, gb.cls(TRUE, data.ident, data.static, how="curve").model.theta)
        plain = gb.cls(TRUE, data.ident)
        assert plain.static is None and plain.constraints == ()
        assert not np.allclose(plain.model.theta, res.model.theta)  # the points changed the estimate
        # PE and SE the same way
        np.testing.assert_array_equal(gb.pe_thetas(TRUE, data, lambdas=[0.5]),
                                      gb.pe_thetas(TRUE, data.ident, data.static, lambdas=[0.5]))
        a = gb.se_pareto(TRUE, data, lambdas=[0.5], method="gradient", max_nfev=2, progress=False)
        b = gb.se_pareto(TRUE, data.ident, data.static, lambdas=[0.5], method="gradient", max_nfev=2, progress=False)
        np.testing.assert_array_equal(a.thetas, b.thetas)
    # without any, each says it needs them, in the same words
    for call in (lambda: gb.pe_thetas(TRUE, data.ident, lambdas=[0.5]),
                 lambda: gb.se_pareto(TRUE, data.ident, progress=False),
                 lambda: gb.se_dsf(TRUE, data.ident, band=BAND),
                 lambda: gb.bootstrap_decision(TRUE, data.ident),
                 lambda: gb.jsf(gb.Model(TRUE, THETA), gb.Dataset(data.ident, data.valid))):
        with pytest.raises(ValueError, match="needs static points: pass static= or a Dataset with static points"):
            call()


# -- names: one per concept ---------------------------------------------------------------------

def test_results_carry_their_model_as_an_attribute(results):
    for kind in MODEL_CARRIERS[1:]:
        assert isinstance(results[kind].model, gb.Model), kind
    front = results["ParetoSet"]
    assert isinstance(front.member_model(0), gb.Model)
    assert not hasattr(front, "model")  # a set has no one model (model(i), deprecated in 0.1.0, is gone)


def test_met_the_band_is_in_band_everywhere_and_old_files_load(results):
    dsf = results["DSFResult"]
    assert isinstance(dsf.in_band, bool)
    assert not hasattr(dsf, "feasible")  # its former name (deprecated in 0.1.0) is gone
    doc = json.loads(gb.to_json(dsf))
    doc["object"]["feasible"] = doc["object"].pop("in_band")  # a file written before the rename
    back = gb.from_json(json.dumps(doc))
    assert back.in_band == dsf.in_band and back.JS == dsf.JS


def test_an_old_graybox_selection_file_loads_with_in_band(results):
    dec = results["Decision"]
    table = pd.DataFrame({"source": ["semp"], "size": [6], "n_terms": [6], "added": [""], "estimator": ["pe"],
                          "JS_valid": [dec.JS], "JSF": [dec.JSF], "in_band": [dec.in_band], "rank": [1]})
    sel = gb.experiments.GrayboxSelection(dec.model.structure, dec.model, dec, table, 2, BAND, dec.in_band, "min")
    doc = json.loads(gb.to_json(sel))
    doc["object"]["fallback"] = not doc["object"].pop("in_band")  # the old, inverted field
    del doc["object"]["rule"]  # written before the fit / choose / test protocol: it chose by the smallest J_S
    doc["object"]["store"] = "store.sqlite"  # it named the store its cells ran in
    back = gb.from_json(json.dumps(doc))
    assert back.in_band == dec.in_band and back.rule == "min" and not hasattr(back, "store")


# -- cluster names round-trip ---------------------------------------------------------------------

@pytest.mark.parametrize("structure, inputs", [
    (TRUE, None),
    (gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-1)^2"]), None),
    (gb.Structure(["1", "y(k-1)", "u1(k-1)", "u2(k-1)^2", "u1(k-1)u2(k-1)", "u2(k-1)y(k-1)"]), ("u1", "u2")),
])
def test_every_printed_cluster_name_names_its_cluster(structure, inputs):
    cm = gb.surface_cluster_map(structure, input_names=inputs) if inputs else gb.cluster_map(structure)
    assert "Σ0" in cm.names
    for i, name in enumerate(cm.names):
        assert cm.index(name) == i, name
    with pytest.raises(ValueError, match="no cluster"):
        cm.index("Σy³")


def test_cluster_bounds_by_every_printed_name(data):
    m = gb.Model(TRUE, THETA)
    for name, value in m.clusters().items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = gb.cls(TRUE, data.ident, constraints=gb.ClusterBounds({name: (value, value)})).model
        assert fit.clusters()[name] == pytest.approx(value, abs=1e-9 * max(1.0, abs(value))), name


# -- one keyword per concept: input_names=, seed=, estimator= (the former names, deprecated in 0.1.0, are gone) --

def test_input_names_is_the_one_input_names_keyword():
    st = gb.Structure(["1", "y(k-1)", "u1(k-1)", "u2(k-1)^2"])
    new = gb.Candidates(1, 1, degree=1, input_names=("u1", "u2"))
    assert {n for t in new for n in t.input_names} == {"u1", "u2"}
    th = np.array([0.2, 0.5, 0.3, 0.1])
    pts = np.array([[1.0, 2.0]])
    for call in (lambda: gb.Candidates(1, 1, degree=1, inputs=("u1", "u2")),
                 lambda: gb.static_surface(st, th, pts, inputs=("u1", "u2")),
                 lambda: gb.static_surface_gain(st, th, pts, inputs=("u1", "u2")),
                 lambda: gb.surface_equilibria(st, th, pts[0], inputs=("u1", "u2")),
                 lambda: gb.surface_cluster_map(st, inputs=("u1", "u2"))):
        with pytest.raises(TypeError, match="inputs"):
            call()
    assert gb.surface_cluster_map(st, input_names=("u2", "u1")).input_names == ("u2", "u1")


def test_seed_is_the_one_random_source_keyword():
    from graybox.datasets.pumping import PumpingPlant, speed_reference

    plant = PumpingPlant()
    u = speed_reference(n_samples=1600, n_ident=800, seed=0)[:300]
    with pytest.raises(TypeError, match="rng"):
        plant.simulate(u, rng=3)
    np.testing.assert_array_equal(plant.simulate(u, seed=3).y, plant.simulate(u, 3).y)


def test_method_names_an_algorithm_and_estimator_an_estimator(data):
    kw = dict(lambdas=[0.1, 1.0], n_boot=1, band=BAND, fallback="min_jsf", options={"solver": "closed"})
    new = gb.bootstrap_decision(TRUE, data, estimator="pe", **kw)
    assert new.estimator == "pe" and not hasattr(new, "method")
    with pytest.raises(TypeError, match="method"):
        gb.bootstrap_decision(TRUE, data, method="pe", **kw)


def test_parallel_map_speaks_run_grids_words(data):
    double = abs  # picklable, deterministic
    with gb.experiments.parallel_map(executor="inprocess") as pmap:
        assert pmap(double, [-1, 2, -3]) == [1, 2, 3]
    with pytest.raises(TypeError, match="processes"):
        with gb.experiments.parallel_map(workers=1, processes=True):
            pass
    with pytest.raises(ValueError, match="executor"):
        with gb.experiments.parallel_map(executor="threads"):
            pass
    with pytest.raises(ValueError, match="client and scheduler are for executor='dask'"):
        with gb.experiments.parallel_map(executor="processes", scheduler="tcp://x:1"):
            pass


def test_decision_makers_take_a_pareto_set_only(results, data):
    for wrong in (results["ELSResult"], results["Decision"]):
        with pytest.raises(TypeError, match="pareto must be a ParetoSet"):
            gb.decide_dsf(wrong, band=BAND)
        with pytest.raises(TypeError, match="pareto must be a ParetoSet"):
            gb.decide_min_correlation(wrong, data)
    front = results["ParetoSet"]
    a = gb.decide_min_correlation(front, data)  # a Dataset: its identification record
    assert a.index == gb.decide_min_correlation(front, data.ident).index


def test_a_cls_result_is_saved_whole_and_through_its_model(results, tmp_path):
    # a CLSResult is a saved type since its static information (points, curve, surface) has codecs
    res = results["CLSResult"]
    whole = gb.load(gb.save(res, tmp_path / "cls_result.json"), expect=gb.CLSResult)
    np.testing.assert_array_equal(whole.model.theta, res.model.theta)
    assert whole.constraints == res.constraints and whole.solver == res.solver
    back = gb.load(gb.save(res.model, tmp_path / "cls.json"), expect=gb.Model)
    np.testing.assert_array_equal(back.theta, res.model.theta)


def _read(x, names):
    """What the one coercion of inputs makes of ``x``: its array, or the error's type and words."""
    from graybox.core._records import as_input_array
    try:
        return np.asarray(as_input_array(x, "u", names)).tolist()
    except (TypeError, ValueError) as exc:
        return type(exc).__name__, str(exc)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 6), label=st.sampled_from([None, "u", "u1", "u2", "u6", "u01", "speed", "a", "y", 0]),
       names=st.sampled_from([None, ("u",), ("speed",), ("a", "b"), ("u1", "u2")]))
def test_a_series_of_samples_is_read_alike_whatever_its_index(n, label, names):
    """A Series whose index is numbers (a RangeIndex) skips reading its labels one by one (10⁶ of them took 0.7 s
    against 30 ms for the one-column DataFrame): read as the same Series with those labels as text, which are read
    one by one (mend60g)."""
    values = np.arange(1.0, n + 1.0)
    fast = pd.Series(values, name=label)
    slow = pd.Series(values, index=[str(k) for k in range(n)], name=label)
    assert _read(fast, names) == _read(slow, names)


def test_a_series_of_samples_meets_no_list_of_default_names_as_long_as_itself(monkeypatch):
    """The default names were made for every sample of a Series (u1 … uN, N of them) to look its labels up in:
    the cost of a 10⁶-sample input (mend60g). The samples still come through whole, as the one input."""
    import graybox.core._records as records
    made = []
    names = records.default_input_names
    monkeypatch.setattr(records, "default_input_names", lambda m: made.append(m) or names(m))
    u = pd.Series(np.linspace(0.0, 1.0, 5000) ** 2, name="speed")
    rec = gb.Record(u, np.cos(np.arange(5000.0)), Ts=0.1)
    np.testing.assert_array_equal(rec.u, u.to_numpy())
    assert max(made, default=0) < 100


_RUN = np.linspace(0.0, 1.0, 8)
_ONE = gb.Structure(["y(k-1)", "u(k-1)"])


@pytest.mark.parametrize("call", [
    lambda u: gb.Model(_ONE, [0.5, 1.0]).simulate(u, y0=[0.0]),
    lambda u: gb.simulate(_ONE, [0.5, 1.0], u, y0=[0.0]),
    lambda u: gb.regressor_matrix(_ONE, u, _RUN ** 2),
    lambda u: gb.Record(u, _RUN ** 2),
])
@pytest.mark.parametrize("stacked", [lambda: [_RUN, _RUN], lambda: np.array([_RUN, 2 * _RUN]), lambda: [list(_RUN)]])
def test_samples_stacked_as_rows_are_one_error_naming_both_readings(call, stacked):
    """[u, u] (two equal-length arrays) was read as 2 samples of 8 inputs by a free run ("the structure uses input
    'u', but u's 8 columns are the inputs ('u1', …, 'u8')"), as 2 samples against 8 outputs by the regressors, as
    rows of inputs by Record: one rule now, fewer samples than inputs, its error naming both readings (mend60g)."""
    with pytest.raises(ValueError, match=r"u has shape \((1|2), 8\), one row per input: .*shape \(8, (1|2)\).*\.T.*"
                                         r"(1|2) separate run\(s\) of one input: pass them one at a time"):
        call(stacked())


def test_inputs_as_columns_and_a_list_of_rows_are_read_as_before():
    rows = [[a, b] for a, b in zip(_RUN, 2 * _RUN)]  # one row per sample, as numpy reads it
    two = gb.Model(gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)"]), [0.5, 1.0, 1.0])
    np.testing.assert_array_equal(two.simulate(rows, y0=[0.0]), two.simulate(np.column_stack([_RUN, 2 * _RUN]),
                                                                              y0=[0.0]))
    assert gb.Record(np.ones((1, 1)), [1.0]).n_inputs == 1  # one sample of one input: no more inputs than samples


def test_fewer_samples_than_inputs_is_read_as_samples_where_the_output_or_the_names_settle_it():
    # the refusal of rows-as-inputs (mend60g) also refused a loader's one-line file of two inputs, u of shape (1, 2)
    # beside y of one sample (hypothesis in test_loaders): the output's length, or inputs named as many as the
    # columns, say which reading is meant
    import graybox as gb

    rec = gb.Record(np.array([[0.5, 2.0]]), np.array([1.0]))
    assert rec.u.shape == (1, 2)
    rec = gb.Record(np.array([[0.5, 2.0, 3.0]]), np.array([1.0]), input_names=("a", "b", "c"))
    assert rec.input_names == ("a", "b", "c")
    with pytest.raises(ValueError, match="one row per input"):
        gb.Record(np.array([[0.5, 2.0, 3.0], [1.0, 1.0, 1.0]]), np.array([1.0, 2.0, 3.0]))


def test_the_regressors_of_fewer_samples_than_inputs_are_read_as_record_reads_them():
    # Record(u, y) of u (2, 3) and y of 2 samples is 2 samples of 3 inputs (the output's length settles it), but
    # regressor_matrix on the same arrays refused them as "one row per input": the coercion was not shown the output
    s = gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "u3(k-1)"])
    u, y = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]), np.array([0.1, 0.2])
    np.testing.assert_array_equal(gb.regressor_matrix(s, u, y), [[0.1, 1.0, 2.0, 3.0]])
    rec = gb.Record(u, y)
    np.testing.assert_array_equal(gb.regressor_matrix(s, u.tolist(), list(y)), gb.regressor_matrix(s, rec.u, rec.y))


def test_the_refusal_of_fewer_samples_than_inputs_names_the_way_to_read_them_as_samples():
    # gb.simulate of a bare structure in u1 … u3 over 2 samples (no output, no model's names) was refused with the
    # transpose and separate runs as the only ways on; naming the inputs reads them as samples, and the message says so
    s, th = gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "u3(k-1)"]), [0.5, 1.0, 2.0, 3.0]
    u = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    with pytest.raises(ValueError, match=r"2 sample\(s\) of 3 inputs.*name the 3 inputs \(input_names=\.\.\.\)"):
        gb.simulate(s, th, u, y0=[0.0])
    got = gb.simulate(s, th, u, y0=[0.0], input_names=("u1", "u2", "u3"))
    np.testing.assert_allclose(got, [0.0, 1.0 + 4.0 + 9.0])


def test_equilibria_of_two_points_by_name_says_how_many_points_it_got():
    # a dict's np.shape is (): two points by name were refused as "got shape ()"
    m = gb.Model(gb.Structure(["y(k-1)", "a(k-1)", "b(k-1)", "1"]), [0.5, 1.0, 2.0, 0.1])
    assert m.equilibria({"a": 1.0, "b": 2.0})[0].ybar == pytest.approx(10.2)
    with pytest.raises(ValueError, match=r"one point of shape \(2,\), got 2 points: call equilibria once per point"):
        m.equilibria({"a": [1.0, 3.0], "b": [2.0, 4.0]})
