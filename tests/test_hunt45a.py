"""Bug hunt 45a: the model as a value and a file (simulation, statics, JSON)."""

import numpy as np
import pytest

import graybox as gb


# -- StaticSurface validates its fields as StaticCurve does ------------------------------------------------
def test_surface_refuses_text_and_booleans_as_coefficients():
    # StaticCurve refuses text (never parses it); the surface parsed "1.0" and read True as 1
    with pytest.raises(TypeError, match="coefficients"):
        gb.StaticSurface(((0, 0), (1, 0)), ["1.0", "2"])
    with pytest.raises(TypeError, match="coefficients"):
        gb.StaticSurface.polynomial({(0, 0): "1.5", (1, 0): 2.0})
    with pytest.raises(TypeError, match="coefficients"):
        gb.StaticSurface(((0, 0), (1, 0)), [True, 2.0])


def test_surface_refuses_a_column_of_coefficients():
    # shape (2, 1) was flattened silently; StaticCurve says the coefficients must be 1-D
    with pytest.raises(ValueError, match="1-D"):
        gb.StaticSurface(((0, 0), (1, 0)), [[1.0], [2.0]])


def test_surface_input_names_are_input_names():
    # numbers became the names "1", "2", which no model's input can be: refused as every input name is
    with pytest.raises(TypeError, match="input name"):
        gb.StaticSurface(((0, 0), (1, 0)), [1.0, 2.0], input_names=(1, 2))
    with pytest.raises(ValueError, match="input name"):
        gb.StaticSurface(((0, 0), (1, 0)), [1.0, 2.0], input_names=("a b", "c"))
    with pytest.raises(ValueError, match="input name"):
        gb.StaticSurface.fit(gb.StaticPoints(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), [1.0, 2.0, 3.0],
                                             input_names=("a", "b")), 1, input_names=("y", "c"))


def test_surface_coefficient_takes_integer_powers_only():
    s = gb.StaticSurface(((0, 0), (1, 0), (1, 1)), [1.0, 2.0, 0.5], input_names=("a", "b"))
    assert s.coefficient((1, 1)) == 0.5
    with pytest.raises(TypeError):
        s.coefficient((1.7, 0))  # was read as (1, 0): the coefficient of another monomial
    with pytest.raises(TypeError):
        s.coefficient((True, 0))


def test_curve_refuses_booleans_as_coefficients():
    with pytest.raises(TypeError, match="coefficients"):
        gb.StaticCurve([True, 2.0])


# -- an Equilibrium (a file edited by hand) is a finite point with a modulus ------------------------------
@pytest.mark.parametrize("field, value", [("ybar", "nan"), ("ybar", "inf"), ("ubar", "nan"), ("ubar", ["nan", 1.0]),
                                          ("ubar", []), ("spectral_radius", -1.0), ("spectral_radius", "nan")])
def test_equilibrium_file_with_a_point_at_nan_is_refused(field, value):
    import json

    doc = json.loads(gb.to_json(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).equilibria(1.0)[0]))
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=field):
        gb.from_json(json.dumps(doc))


def test_equilibria_still_load_and_compare():
    m = gb.Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [0.5, 0.1, 1.0])
    for e in m.equilibria(0.3):
        assert gb.from_json(gb.to_json(e)) == e
    assert not np.isfinite(gb.Equilibrium(1.0, 2.0, False, float("inf")).spectral_radius)


# -- a NumPy bool, which the values take for True or False, is saved as one ------------------------------
def test_values_holding_numpy_bools_are_saved():
    # Equilibrium(…, stable=rho < 1) or a Decision's in_band from an array comparison: the constructors take
    # np.bool_ (check_fields), but save failed with "Object of type bool is not JSON serializable", naming nothing
    e = gb.Equilibrium(1.0, 2.0, np.float64(0.5) < 1.0, 0.5)
    back = gb.from_json(gb.to_json(e))
    assert back.stable is True and back == gb.Equilibrium(1.0, 2.0, True, 0.5)
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    d = gb.Decision(m, 0, 0.5, 1.0, 0.1, "D_SF", np.array([0.1])[0] <= 0.2, 1.0)
    assert gb.from_json(gb.to_json(d)).in_band is True


# -- θ is numbers: a bool is no parameter, None no NaN, and an integer beyond the floats is said so ------------
@pytest.mark.parametrize("theta", [[True, 1.0], [0.5, np.True_], np.array([True, False])])
def test_theta_refuses_booleans(theta):
    # True was read as the parameter 1.0 (real_array refuses it everywhere else numbers are read)
    with pytest.raises(TypeError, match="theta"):
        gb.Model(["y(k-1)", "u(k-1)"], theta)
    with pytest.raises(TypeError, match="theta"):
        gb.simulate(["y(k-1)", "u(k-1)"], theta, np.ones(5), [0.0])


def test_theta_refuses_none_as_a_type():
    # None was read as NaN and refused as "non-finite values at [0]", a ValueError for a wrong type
    with pytest.raises(TypeError, match="theta"):
        gb.Model(["y(k-1)", "u(k-1)"], [None, 1.0])


def test_many_thetas_refuse_booleans():
    rec = gb.Record(np.ones(20), np.ones(20))
    with pytest.raises(TypeError, match="thetas"):
        gb.evaluate_thetas(["y(k-1)", "u(k-1)"], [[True, 0.5]], rec)
    with pytest.raises(TypeError, match="thetas"):
        gb.simulate_many(["y(k-1)", "u(k-1)"], np.array([[True, False]]), rec)


def test_numbers_beyond_the_float_range_are_named():
    # int(10**400) reached numpy's conversion, whose OverflowError ("int too large to convert to float") named nothing
    with pytest.raises(ValueError, match="theta"):
        gb.Model(["y(k-1)"], [10**400])
    with pytest.raises(ValueError, match="y"):
        gb.Record(np.ones(3), [1.0, 2.0, 10**400])


# -- text that is no UTF-8 (a file name's undecodable bytes, as os.listdir gives them) is saved ----------------
def test_a_name_from_an_undecodable_file_name_is_saved(tmp_path):
    # os.listdir reads a Latin-1 file name 'run\xe9.csv' as 'run\udce9.csv' (surrogateescape); the record it loads is
    # named so, and save failed with "'utf-8' codec can't encode character '\udce9'", naming nothing
    name = "run\udce9"
    r = gb.Record(np.arange(5.0), np.ones(5), name=name, units=("°C", "\udcb0C"))
    text = gb.to_json(r)
    text.encode("utf-8")  # a text any file takes
    path = gb.save(r, tmp_path / "r.json")
    back = gb.load(path)
    assert back.name == name and back.units == r.units
    assert gb.from_json(text).name == name


# -- a DataFrame whose columns name the structure's inputs is judged by those names, whatever its width ---------
def test_a_frame_with_the_input_and_another_column_is_said_so():
    import pandas as pd

    m = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 1.0])
    df = pd.DataFrame({"speed": np.ones(5), "valve": np.zeros(5)})
    # it said "u's 2 columns are the inputs ('u1', 'u2')" and asked to name columns that were named
    with pytest.raises(ValueError, match=r"name every input \['speed'\] and more columns.*not inputs: \['valve'\]"):
        m.simulate(df, [0.0])
    with pytest.raises(ValueError, match="and more columns"):
        gb.simulate(m.structure, m.theta, df, [0.0])
    # the input's own column alone, and unnamed columns, read as before
    assert np.array_equal(m.simulate(df[["speed"]], [0.0]), m.simulate(np.ones(5), [0.0]))
    assert np.array_equal(m.simulate(pd.DataFrame({0: np.ones(5)}), [0.0]), m.simulate(np.ones(5), [0.0]))


def test_predict_bounds_each_run_by_its_own_start():
    # predict's docstring said the bound came from y(0 … L−1): a run starting from a measured 1e9 after a start at
    # 1e-3 (bound 1e3) would then be NaN; each run's bound is its own start's, as the kernel does
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    r = gb.Record(np.zeros(6), [1e-3, 1e-3, 1e9, 1e9, 5e8, 1e9])
    p = m.predict(r, horizon=2)
    assert np.isfinite(p).all() and p[4] == 0.25 * 1e9


# -- a curve over many levels where none is reached: a message that names the first few, and how many more ----
@pytest.mark.parametrize("structure, theta, low", [
    (["y(k-1)", "y(k-1)^2", "u(k-1)"], [0.5, 0.1, 1.0], 1.0),       # no real root above ū = 0.625
    (["y(k-1)", "u(k-1)y(k-1)", "u(k-1)"], [0.5, 1.0, 1.0], 0.6),   # rational, unstable above ū = 0.5
])
def test_static_curve_error_over_many_levels_stays_short(structure, theta, low):
    # 20000 levels made a message of 1.4 MB (every ū named), which a notebook prints whole
    m = gb.Model(structure, theta)
    ub = np.linspace(low, 2.0, 20000)
    for f in (m.static_curve, m.static_gain):
        with pytest.raises(ValueError) as err:
            f(ub)
        text = str(err.value)
        assert len(text) < 5000
        assert "ū = 2" not in text and "19980 more" in text and "20000" in text
    with pytest.raises(ValueError) as err:  # a few levels are still named one by one
        m.static_curve(ub[:3])
    assert all(f"ū = {u:g}" in str(err.value) for u in ub[:3])


def test_static_surface_error_over_many_points_stays_short():
    m = gb.Model(["y(k-1)", "y(k-1)^2", "a(k-1)", "b(k-1)"], [0.5, 0.1, 1.0, 1.0])
    pts = np.column_stack([np.linspace(1.0, 2.0, 5000), np.ones(5000)])
    with pytest.raises(ValueError) as err:
        m.static_curve(pts)
    assert len(str(err.value)) < 5000 and "4980 more" in str(err.value)
    with pytest.raises(ValueError) as err:
        m.static_curve(pts, y0=0.0)
    assert len(str(err.value)) < 5000 and "4980 more" in str(err.value)


def test_messages_listing_many_levels_stay_short():
    import warnings

    c = gb.StaticCurve([1.0, 2.0], domain=(0.0, 1.0))
    with pytest.raises(ValueError, match=r"\(50000 in all\)") as err:
        c(np.linspace(0.0, 2.0, 100000))  # 50000 levels beyond the domain: the message was 1 MB
    assert len(str(err.value)) < 2000
    with pytest.raises(ValueError, match=r"ū = \[2\.0\] outside"):  # a few are listed as before
        c([0.5, 2.0])
    s = gb.StaticSurface(((0, 0), (1, 0)), [1.0, 2.0], domain=((0.0, 1.0), (0.0, 1.0)))
    with pytest.raises(ValueError, match=r"in all\)") as err:
        s(np.column_stack([np.linspace(0.0, 2.0, 100000), np.zeros(100000)]))
    assert len(str(err.value)) < 2000
    with pytest.raises(ValueError, match=r"\(5000 in all\)"):
        gb.StaticPoints(np.r_[np.arange(5000.0), np.arange(5000.0)], np.zeros(10000))
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], Ts=1.0)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        # 475 of 500 levels beyond the data: listed in full they would take 4,200 characters (5000 levels cost 3 s)
        gb.operating_curve(m, np.linspace(0.0, 20.0, 500), data=gb.Record(np.linspace(0, 1, 100), np.zeros(100)))
    said = [str(w.message) for w in seen if issubclass(w.category, gb.StaticRangeWarning)]
    assert len(said) == 1 and len(said[0]) < 2000 and "(475 in all)" in said[0]


def test_one_step_scores_say_how_to_add_a_missing_transient_input():
    # js and predict(horizon=2) said "add it with graybox.transient_inputs(...)"; j1, predict and the estimators,
    # which read the regressors, named the missing input only
    rec = gb.Record(np.r_[np.zeros(10), np.ones(10)], np.ones(20), Ts=0.5)
    m = gb.Model(["y(k-1)", "u(k-1)", "u_tau2(k-1)"], [0.5, 1.0, 3.0], input_names=("u", "u_tau2"), Ts=0.5)
    hint = r"needs input 'u_tau2'.*graybox\.transient_inputs\(record, taus=\[2\], input_names=\['u'\]\)"
    for call in (lambda: m.predict(rec), lambda: gb.j1(m, rec), lambda: gb.els(m.structure, rec)):
        with pytest.raises(ValueError, match=hint):
            call()


def test_loading_a_result_as_a_model_says_where_its_model_is(tmp_path):
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    d = gb.Decision(m, 0, 0.5, 1.0, 0.1, "D_SF", True, 1.0)
    path = gb.save(d, tmp_path / "d.json")
    with pytest.raises(gb.GrayboxFileError, match=r"holds a Decision, expected Model \(a Decision carries a Model: "
                                                  r"load it without expect= and take its \.model\)"):
        gb.load(path, expect=gb.Model)
    with pytest.raises(gb.GrayboxFileError, match=r"expected StaticCurve$"):  # no model asked for: no hint
        gb.load(path, expect=gb.StaticCurve)
    assert gb.load(path).model.theta.tolist() == [0.5, 1.0]


def test_a_frame_with_the_default_names_still_feeds_a_structure_using_some_of_them():
    import pandas as pd

    rng = np.random.default_rng(0)
    u = rng.uniform(size=(10, 2))
    df = pd.DataFrame({"u1": u[:, 0], "u2": u[:, 1]})
    st, th = ["y(k-1)", "u2(k-1)"], [0.5, 1.0]
    assert np.array_equal(gb.simulate(st, th, df, [0.0]), gb.simulate(st, th, u, [0.0]))


def test_levels_beyond_the_float_range_are_a_value_error():
    # real_array, which calls a ragged nesting a type error, took the overflow for one too
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    with pytest.raises(ValueError, match="beyond the float range"):
        m.static_curve([10**400])


def test_a_model_takes_its_structure_from_what_carries_one():
    # README: wherever a structure is meant a Model or a result that carries one will do; Model(selection, θ)
    # failed with "'Selection' object is not iterable", Model(None, θ) likewise, naming nothing
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(size=100), rng.uniform(size=100))
    sel = gb.frols(gb.Candidates(1, 1), rec, n_terms=2)
    m = gb.Model(sel, [0.5, 1.0])
    assert m.structure == sel.structure
    assert gb.Model(m, [0.1, 0.2]).structure == sel.structure
    with pytest.raises(TypeError, match="structure must be a Structure, a sequence of terms or a model"):
        gb.Model(None, [0.5])


def test_the_static_functions_take_a_structure_from_what_carries_one():
    # README: wherever a structure is meant a Model or a result that carries one will do; simulate, predict and
    # evaluate_thetas took them, static_curve, static_gain, equilibria and the cluster maps refused them
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(size=100), rng.uniform(size=100))
    sel = gb.frols(gb.Candidates(1, 1), rec, n_terms=2)
    m = sel.model
    for carrier in (sel, m):
        assert gb.static_curve(carrier, m.theta, [0.5])[0] == m.static_curve([0.5])[0]
        assert gb.static_gain(carrier, m.theta, [0.5])[0] == m.static_gain([0.5])[0]
        assert gb.equilibria(carrier, m.theta, 0.5) == m.equilibria(0.5)
        assert gb.cluster_map(carrier).names == m.cluster_map().names
        assert gb.surface_cluster_map(carrier).names == gb.surface_cluster_map(m.structure).names
    with pytest.raises(TypeError, match="structure must be a Structure, a sequence of terms or a model"):
        gb.static_curve(None, m.theta, [0.5])
