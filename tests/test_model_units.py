"""A model knows the units it was identified in, and refuses data in other units: its parameters hold
in those units only (graybox.Model.units, as Model.Ts for the sampling period)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import graybox as gb

UNITS = ("rpm", "mlc")
ST = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2"])


def _record(seed: int = 0, n: int = 400, units: tuple[str, str] = UNITS, name: str = "") -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 1.0, n // 10), 10)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.05 * u[k - 2] ** 2 + 0.4
    return gb.Record(u, y + 0.01 * rng.standard_normal(n), Ts=0.1, units=units, name=name or f"run {seed}")


def _static(units: tuple[str, str] = UNITS) -> gb.StaticPoints:
    return gb.StaticPoints(np.array([0.2, 0.5, 0.8]), np.array([2.3, 2.7, 3.1]), units=units)


@pytest.fixture(scope="module")
def data() -> gb.Dataset:
    return gb.Dataset(_record(0), _record(1), _static())


@pytest.fixture(scope="module")
def models(data) -> dict:
    cand = gb.Candidates(2, 2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "frols": gb.frols(cand, data, n_terms=5).model,
            "frols centred": gb.frols(cand, data, n_terms=4, centre=True).model,
            "semp": gb.semp(cand, data, n_terms=4).model,
            "els": gb.els(ST, data).model,
            "cls": gb.cls(ST, data, gb.StaticCurve.fit(data.static, degree=2)).model,
            "pe": gb.pe_pareto(ST, data, lambdas=[1.0, 0.1]).member_model(0),
            "se": gb.se_pareto(ST, data, lambdas=[1.0, 0.5], method="gradient").member_model(1),
            "se_dsf": gb.se_dsf(ST, data, band=1.0).model,
            "output_error": gb.output_error(ST, data, n_starts=1).model,
            "neural": gb.neural_narx(data.ident, ny=2, nu=2, ne=0, hidden=2, epochs=2, sim_epochs=2, seed=0).model,
        }


def test_every_estimator_gives_its_model_the_records_units(models, data):
    for name, m in models.items():
        assert m.units == UNITS, name
        m.simulate(data.valid, on_diverge="nan")  # the same units: fine
        unlabelled = _record(1, units=("", ""))  # a record that names no unit says nothing: not checked
        m.simulate(unlabelled, on_diverge="nan")
        other = _record(1, units=("rad/s", "mlc"), name="logger in rad/s")
        with pytest.raises(ValueError, match=r"input unit 'rpm' but 'logger in rad/s' has 'rad/s'"):
            m.simulate(other)
        with pytest.raises(ValueError, match="input unit 'rpm'"):
            gb.js(m, other)
        with pytest.raises(ValueError, match="output unit 'mlc'"):
            gb.jsf(m, _static(("rpm", "Pa")))


def test_prediction_residual_tests_and_the_control_bridge_refuse_other_units(models):
    m = models["els"]
    other = _record(2, units=("rpm", "Pa"), name="pressure in Pa")
    with pytest.raises(ValueError, match="output unit 'mlc' but 'pressure in Pa' has 'Pa'"):
        m.predict(other)
    with pytest.raises(ValueError, match="output unit 'mlc'"):
        gb.residual_tests(m, other)
    m.predict(_record(2))


def test_a_choosing_record_in_other_units_is_refused(data):
    front = gb.pe_pareto(ST, data, lambdas=[1.0, 0.1, 0.01])
    assert front.units == UNITS and all(m.units == UNITS for m in front.models())
    gb.decide_dsf(front, band=1.0, choose_on=_record(2))
    with pytest.raises(ValueError, match="Pareto set was fitted with input unit 'rpm'"):
        gb.decide_dsf(front, band=1.0, choose_on=_record(2, units=("1/s", "mlc")))


def test_units_survive_saving_and_the_header_says_them(models):
    for name in ("els", "pe", "semp", "neural"):
        m = models[name]
        text = gb.to_json(m)
        assert json.loads(text)["units"] == {"u": "rpm", "y": "mlc"}, name
        assert gb.from_json(text).units == UNITS, name
    sel = gb.frols(gb.Candidates(2, 2, degree=2), _record(0), n_terms=5)
    assert gb.from_json(gb.to_json(sel)).units == UNITS and gb.from_json(gb.to_json(sel)).model.units == UNITS
    # a file written before models carried units reads as "none said"
    doc = json.loads(gb.to_json(models["els"]))
    del doc["object"]["units"]
    assert gb.from_json(json.dumps(doc)).units == ("", "")


def test_a_hand_written_model_says_nothing_and_its_units_are_checked_as_a_records():
    m = gb.Model(ST, np.array([0.4, 0.6, 0.2, 0.3, 0.05]))
    assert m.units == ("", "")
    m.simulate(_record(0, units=("rad/s", "Pa")))  # nothing said, nothing checked
    labelled = gb.Model(ST, m.theta, units=["rpm", "mlc"])
    assert labelled.units == UNITS and labelled.with_theta(m.theta).units == UNITS
    assert "units=('rpm', 'mlc')" in repr(labelled)
    for bad in ("rpm", ("rpm",), ("rpm", 3)):
        with pytest.raises(TypeError, match="units must be a pair of strings"):
            gb.Model(ST, m.theta, units=bad)


def test_records_in_other_units_cannot_be_fitted_together():
    with pytest.raises(ValueError, match="input unit 'rpm' but 'b' has 'rad/s'"):
        gb.frols(gb.Candidates(2, 2, degree=2), [_record(0, name="a"), _record(1, units=("rad/s", "mlc"), name="b")],
                 n_terms=4)


def test_the_papers_models_hold_in_rpm_and_mlc():
    m = gb.reference.paper_model(15, "ELS")
    assert m.units == UNITS
    data = gb.load_pumping()
    assert data.ident.units == UNITS
    assert np.isfinite(gb.js(m, data.valid))
    radians = gb.Record(data.valid.u * 2 * np.pi / 60, data.valid.y, Ts=data.valid.Ts, units=("rad/s", "mlc"),
                        name="valid in rad/s")
    with pytest.raises(ValueError, match="input unit 'rpm' but 'valid in rad/s' has 'rad/s'"):
        m.simulate(radians)


def test_a_choosing_or_test_record_in_other_units_is_refused_before_any_fit(data):
    other = _record(3, units=("rad/s", "mlc"), name="test in rad/s")
    with pytest.raises(ValueError, match="input unit 'rpm' but 'test in rad/s' has 'rad/s'"):
        gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=1.0, test=other)
    with pytest.raises(ValueError, match="input unit 'rpm' but 'test in rad/s' has 'rad/s'"):
        gb.output_error(ST, data.ident, n_starts=0, choose_on=other)


def test_the_selections_models_carry_the_units(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sel = gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=1.0, sizes=(4,))
    assert sel.model.units == UNITS
    row = sel.table.index[0]
    assert sel.model_of(row, estimator=sel.table.iloc[0]["estimator"]).units == UNITS


def test_static_bands_carry_the_models_units_and_refuse_points_in_others(data):
    fit = gb.cls(ST, data, gb.StaticCurve.fit(data.static, degree=2))
    unc = gb.cls_uncertainty(fit, data)
    band = gb.static_curve_band(unc, [0.2, 0.5, 0.8])
    assert band.units == UNITS
    back = gb.from_json(gb.to_json(band))
    assert back.units == UNITS and json.loads(gb.to_json(band))["units"] == {"u": "rpm", "y": "mlc"}
    fig = gb.plots.plot_static_band(band, data.static)
    assert "rpm" in fig.axes[0].get_xlabel() and "mlc" in fig.axes[0].get_ylabel()
    with pytest.raises(ValueError, match="the band is in input unit 'rpm' but"):
        gb.plots.plot_static_band(band, _static(("rad/s", "mlc")))
    doc = json.loads(gb.to_json(band))
    del doc["object"]["units"]  # a band saved before bands carried units: none said
    assert gb.from_json(json.dumps(doc)).units == ("", "")


def test_a_dataset_speaks_in_the_units_any_of_its_parts_names():
    # an identification record loaded without units beside a validation record that names them: the fits that
    # read the ident only (ELS, frols) gave models that named none, and took data in any units
    data = gb.Dataset(_record(0, units=("", "")), _record(1), None)
    assert data.units == UNITS
    assert gb.els(ST, data).model.units == UNITS
    assert gb.frols(gb.Candidates(2, 2, degree=2), data, n_terms=4).model.units == UNITS
    assert data.ident.units == ("", "")  # the Dataset's own records are left as given


def _two_inputs(units, names=("q", "T"), seed=3, n=300):
    rng = np.random.default_rng(seed)
    u = np.column_stack([np.repeat(rng.uniform(0, 10, n // 10), 10), np.repeat(rng.uniform(20, 60, n // 10), 10)])
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.1 * u[k - 1, 0] + 0.02 * u[k - 1, 1]
    return gb.Record(u, y, Ts=2.0, units=units, input_names=names, name=f"run {seed}")


def test_inputs_in_units_of_their_own_are_kept_shown_and_checked_input_by_input():
    # a Record held one input unit: a flow in l/min beside a temperature in °C could not both be said
    each = (("l/min", "°C"), "m")
    rec = _two_inputs(each)
    assert rec.units == each
    assert "q in [" in repr(rec) and "] l/min, T in [" in repr(rec) and "] °C, y in" in repr(rec)
    assert _two_inputs((["s", "s"], "m")).units == ("s", "m")  # one unit said per input is that one unit
    with pytest.raises(ValueError, match=r"3 input units .* for 2 input"):
        _two_inputs((("l/min", "°C", "bar"), "m"))
    with pytest.raises(TypeError, match="units must be a pair of strings"):
        _two_inputs(((), "m"))
    m = gb.els(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), rec).model
    assert m.units == each
    m.simulate(_two_inputs(each, seed=4))
    m.simulate(_two_inputs((("l/min", ""), "m"), seed=4))  # an input whose unit is not said is not refused
    with pytest.raises(ValueError, match=r"input 'T' unit '°C' but 'run 4' has 'K'"):
        m.simulate(_two_inputs((("l/min", "K"), "m"), seed=4))
    # inputs are read by name: a record with its columns the other way round, and its units with them, is the same
    swapped = gb.Record(rec.u[:, ::-1], rec.y, Ts=2.0, units=(("°C", "l/min"), "m"), input_names=("T", "q"))
    np.testing.assert_allclose(m.simulate(swapped), m.simulate(rec))
    with pytest.raises(ValueError, match=r"input 'q' unit 'l/min' but 'run 4' has 'm3/h'"):
        m.simulate(_two_inputs((("m3/h", "°C"), "m"), seed=4))
    # one identification's data are held to each other alike, and the units said per input are merged
    with pytest.raises(ValueError, match=r"input 'T' unit '°C' but 'run 5' has 'K'"):
        gb.Dataset(rec, _two_inputs((("l/min", "K"), "m"), seed=5))
    pts = gb.StaticPoints(np.array([[2.0, 30], [5, 40], [8, 50]]), np.array([6.0, 7, 8]), input_names=("q", "T"),
                          units=(("", "°C"), "m"))
    assert gb.Dataset(_two_inputs((("l/min", ""), "m")), _two_inputs(("", ""), seed=4), pts).units == each


def test_inputs_in_units_of_their_own_survive_a_file_and_label_the_plots(tmp_path):
    each = (("l/min", "°C"), "m")
    rec = _two_inputs(each)
    m = gb.els(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), rec).model
    for value in (rec, m):
        path = tmp_path / f"{type(value).__name__}.json"
        gb.save(value, path)
        assert gb.load(path).units == each
        assert gb.read_header(path)["units"] == each
    fig = gb.plots.plot_record(rec)
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["q (l/min)", "T (°C)"]
    assert fig.axes[0].get_ylabel() == "input"  # no one unit to name on the shared axis
    pts = gb.StaticPoints(np.array([[2.0, 0.0], [5, 0.0], [8, 0.0]]), np.array([6.0, 7, 8]), input_names=("q", "T"),
                          units=each)
    assert gb.plots.plot_static_curve(pts).axes[0].get_xlabel() == "input q (l/min)"


def test_a_pareto_set_reads_a_records_inputs_by_name_with_their_units():
    # ParetoSet.check_record compared the inputs' units by position: a record with its columns the other way round
    # (T, q) and its units with them, which every member simulates as the set's own, was refused ('l/min' vs '°C')
    each = (("l/min", "°C"), "m")
    rec = _two_inputs(each)
    pts = gb.StaticPoints(np.array([[2.0, 30], [5, 40], [8, 50]]), np.array([1.6, 2.25, 3.0]), input_names=("q", "T"),
                          units=each)
    ps = gb.pe_pareto(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), rec, pts, lambdas=[0.5])
    other = _two_inputs(each, seed=4)
    swapped = gb.Record(other.u[:, ::-1], other.y, Ts=2.0, units=(("°C", "l/min"), "m"), input_names=("T", "q"))
    ps.check_record(swapped)
    np.testing.assert_allclose(gb.js(ps.member_model(0), swapped), gb.js(ps.member_model(0), other))
    with pytest.raises(ValueError, match=r"input 'T' unit '°C' but 'run 4' has 'K'"):
        ps.check_record(_two_inputs((("l/min", "K"), "m"), seed=4))


def test_units_given_to_save_per_input_are_checked_against_the_values_inputs_and_filled_by_its_own():
    each = (("l/min", "°C"), "m")
    m = gb.els(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), _two_inputs(each)).model
    # three input units for a model of two inputs raised IndexError ('tuple index out of range')
    with pytest.raises(ValueError, match="3 input units .* 2 input"):
        gb.to_json(m, units=(("l/min", "°C", "bar"), "m"))
    hand = gb.Model(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), np.array([0.5, 0.1, 0.02]))
    with pytest.raises(ValueError, match="3 input units .* 2 input"):
        gb.to_json(hand, units=(("l/min", "°C", "bar"), "m"))
    # units naming fewer than the value's are filled by its own, input by input (the header said '' for T)
    assert json.loads(gb.to_json(m, units=(("l/min", ""), "")))["units"] == {"u": ["l/min", "°C"], "y": "m"}
    # a header edited to list three input units for the model's two is refused as a file's error, not an IndexError
    doc = json.loads(gb.to_json(m))
    doc["units"]["u"] = ["l/min", "°C", "bar"]
    with pytest.raises(gb.GrayboxFileError, match="header"):
        gb.from_json(json.dumps(doc))


def test_a_dask_record_of_one_input_takes_one_input_unit():
    # a DaskRecord holds one input, yet units=(('l/min', '°C'), 'm') was kept: two input units for one input, which a
    # model fitted on it then carried
    da = pytest.importorskip("dask.array")
    u, y = da.from_array(np.arange(40.0), chunks=20), da.from_array(np.arange(40.0), chunks=20)
    with pytest.raises(ValueError, match=r"2 input units .* for 1 input"):
        gb.DaskRecord(u, y, units=(("l/min", "°C"), "m"))
    assert gb.DaskRecord(u, y, units=(("l/min",), "m")).units == ("l/min", "m")


def test_a_pareto_set_or_selection_takes_one_unit_per_input_it_has():
    # units listing 3 input units for 2 inputs were kept (a hand-edited file, a dataclasses.replace) and failed only
    # later, when a member's model was made
    from dataclasses import replace

    each = (("l/min", "°C"), "m")
    rec = _two_inputs(each)
    pts = gb.StaticPoints(np.array([[2.0, 30], [5, 40], [8, 50]]), np.array([1.6, 2.25, 3.0]), input_names=("q", "T"),
                          units=each)
    ps = gb.pe_pareto(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), rec, pts, lambdas=[0.5])
    sel = gb.frols(gb.Candidates(1, 1, degree=1, input_names=("q", "T")), rec, n_terms=2)
    assert ps.units == sel.units == each
    for value in (ps, sel):
        with pytest.raises(ValueError, match=r"3 input units .* for 2 input"):
            replace(value, units=(("l/min", "°C", "bar"), "m"))


def test_a_network_reads_its_input_by_name_with_its_unit():
    # a network of T alone runs on a record of (q, T), reading T by name, yet with the record's units (l/min, °C) it
    # was refused by position: 'trained with input 1 unit '°C' but 'run 3' has 'l/min''
    rec = _two_inputs((("l/min", "°C"), "m"), n=200)
    one = gb.Record(rec.input("T"), rec.y, Ts=2.0, units=("°C", "m"), input_names=("T",))
    net = gb.neural_narx(one, ny=1, nu=1, ne=0, hidden=2, epochs=1, sim_epochs=1).model
    assert gb.js(net, rec) == gb.js(net, one)
    with pytest.raises(ValueError, match=r"input 'T' unit '°C' but 'run 3' has 'K'"):
        gb.js(net, _two_inputs((("l/min", "K"), "m"), n=200))


def test_static_points_beside_records_are_held_to_their_units_input_by_input():
    # static= beside records with inputs in units of their own: an input the points leave unsaid says nothing, one
    # they name otherwise is refused, named
    rec = _two_inputs((("l/min", "°C"), "m"))
    st = gb.Structure(["1", "y(k-1)", "q(k-1)", "T(k-1)"])
    ubar = np.array([[2.0, 30.0], [5, 40], [8, 50]])
    ybar = np.array([(0.1 * q + 0.02 * T) / 0.4 for q, T in ubar])
    partial = gb.StaticPoints(ubar, ybar, input_names=("q", "T"), units=(("", "°C"), "m"))
    model = gb.cls(st, rec, partial).model
    np.testing.assert_allclose(model.static_curve({"q": [5.0], "T": [40.0]}), [(0.5 + 0.8) / 0.4], rtol=1e-6)
    with pytest.raises(ValueError, match=r"input 'T' unit '°C' but .* has 'K'"):
        gb.cls(st, rec, gb.StaticPoints(ubar, ybar, input_names=("q", "T"), units=(("l/min", "K"), "m")))


def test_a_band_on_a_record_of_more_inputs_takes_their_units_by_name():
    # said_units merged per-input units by position: a model of (q, T) run on a record of (z, q, T), whose third
    # unit the model's pair does not have, raised IndexError
    rec = _two_inputs((("l/min", "°C"), "m"))
    unc = gb.ls_uncertainty(gb.els(gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"]), rec).model, rec)
    wider = gb.Record(np.column_stack([np.linspace(0, 1, len(rec)), rec.u]), rec.y, Ts=2.0,
                      units=(("V", "", ""), "m"), input_names=("z", "q", "T"))
    assert gb.simulation_band(unc, wider).units == (("V", "l/min", "°C"), "m")


def test_results_and_bands_take_one_unit_per_input_their_model_has():
    # SEMPResult, StaticCurveBand, StaticSurfaceBand and SimulationBand kept units=(('a', 'b', 'c'), 'm') for a model
    # of two inputs (one input for the curve band, and for a network), which a Model refuses
    import pandas as pd

    from graybox.selection._simulation_error_pruning import SEMPResult

    three, z, Z = (("a", "b", "c"), "m"), np.zeros(3), np.zeros((3, 2))
    st = gb.Structure(["y(k-1)", "q(k-1)", "T(k-1)"])
    path = pd.DataFrame({c: [] for c in SEMPResult.PATH_COLUMNS})
    with pytest.raises(ValueError, match=r"SEMPResult: units give 3 input units .* for 2 input"):
        SEMPResult(st, np.ones(3), 0.1, path, pd.DataFrame(), "aic", "", 10, units=three)
    with pytest.raises(ValueError, match=r"StaticCurveBand: units give 2 input units .* for 1 input"):
        gb.StaticCurveBand(z, z, z, z, z, z, z, z, z, 0.95, "delta", 0, z, units=(("a", "b"), "m"))
    with pytest.raises(ValueError, match=r"StaticSurfaceBand: units give 3 input units .* for 2 input"):
        gb.StaticSurfaceBand(Z, ("q", "T"), z, z, z, z, Z, Z, Z, Z, 0.95, "delta", 0, z, units=three)
    with pytest.raises(ValueError, match=r"network 'Neural': units give 2 input units .* for 1 input"):
        gb.NeuralModel(np.zeros((2, 2)), np.zeros(2), np.zeros(2), 0.0, ny=1, nu=1, units=(("a", "b"), "m"))
    with pytest.raises(ValueError, match=r"SimulationBand: units give 3 input units .* for 2 input"):
        gb.SimulationBand(np.arange(3.0), z, z, z, z, z, 0.95, "delta", 0, 0.0, units=three, input_names=("q", "T"))
    # one per input is kept; a band made by simulation_band names the inputs its units are of, and keeps them in a file
    rec = _two_inputs((("l/min", "°C"), "m"))
    band = gb.simulation_band(gb.ls_uncertainty(gb.els(st, rec).model, rec), rec)
    assert (band.input_names, band.units) == (("q", "T"), (("l/min", "°C"), "m"))
    back = gb.from_json(gb.to_json(band))
    assert (back.input_names, back.units) == (("q", "T"), (("l/min", "°C"), "m"))
