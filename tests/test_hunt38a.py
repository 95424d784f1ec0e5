"""Bugs found by a bug hunt from a model to its use and trust (graybox.control, graybox.diagnostics,
graybox.io and the statics), used as a control engineer would: units scaled and offset, several
inputs, short records, hand-edited files. Each test fails without its fix."""

import numpy as np
import pytest

import graybox as gb
from conftest import edited_json


def _settled_after(step: np.ndarray, final: float, band: float = 0.02) -> int:
    """Samples after which a step response stays within ``band`` of ``final`` (brute force, long horizon)."""
    out = np.flatnonzero(np.abs(step - final) > band * abs(final))
    return int(out[-1]) + 1 if out.size else 0


def _step(a: list[float], b: list[float], n: int) -> np.ndarray:
    """Δy(k) of A(q⁻¹)Δy = B(q⁻¹)Δu for a unit step from k = 0, by its own recursion (not lfilter)."""
    y = np.zeros(n)
    for k in range(n):
        y[k] = sum(a[l] * y[k - 1 - l] for l in range(len(a)) if k - 1 - l >= 0) \
            + sum(b[l] for l in range(len(b)) if k - 1 - l >= 0)
    return y


@pytest.mark.parametrize("b2", [-0.99999, -0.9999, -0.999, -0.99])
def test_settling_time_waits_for_a_transient_much_larger_than_the_final_value(b2):
    # settling_time ran the step response over a window sized for a transient of the final value's size
    # (its envelope ρ^k down to 1e-3 of the band) and took the window's end for the settling time when the
    # response was still outside the band there: with a zero near z = 1 (a final value 1e-4 of the first
    # sample's) it said 108 s for a response that leaves the 2 % band last at 126 s, and operating_curve too
    Ts = 0.5
    model = gb.Model(["y(k-1)", "u(k-1)", "u(k-2)"], [0.9, 1.0, b2], Ts=Ts)
    lm = gb.local_model(model, 1.0)
    want = _settled_after(_step([0.9], [1.0, b2], 3000), (1.0 + b2) / 0.1)
    assert lm.settling_time() == pytest.approx(want * Ts)
    assert gb.operating_curve(model, [1.0]).settling_time[0] == pytest.approx(want * Ts)


def test_settling_time_of_a_plain_first_order_model_is_unchanged():
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [0.8, 0.4], Ts=0.1), 2.0)
    assert lm.settling_time() == pytest.approx(_settled_after(_step([0.8], [0.4], 500), 2.0) * 0.1)
    fir = gb.local_model(gb.Model(["u(k-1)", "u(k-3)"], [1.0, 2.0], Ts=0.1), 2.0)
    assert fir.settling_time() == pytest.approx(0.3)


@pytest.mark.parametrize("omega, error", [
    (None, TypeError), ("abc", TypeError), (True, TypeError), ([1.0 + 1j], TypeError),
    ([np.nan], ValueError), ([np.inf], ValueError), ([[1.0, 2.0], [3.0, 4.0]], ValueError), ([], ValueError),
])
def test_frequency_response_refuses_frequencies_that_are_not_real_finite_levels(omega, error):
    # frequency_response took ω through np.asarray(omega, float): None became NaN (a NaN response and a
    # RuntimeWarning), True 1 rad/s, text a ValueError of numpy's about a string and a 2-D grid a 2-D
    # response the docstring's shape (K,) does not allow
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [0.8, 0.4], Ts=0.1), 2.0)
    with pytest.raises(error, match="omega"):
        lm.frequency_response(omega)
    g = lm.frequency_response([0.0, 1.0])
    assert g.shape == (2,) and g[0] == pytest.approx(lm.dc_gain[0])
    assert lm.frequency_response(1.0).shape == (1,)


@pytest.mark.parametrize("a2", [0.25, 0.81])
def test_the_dominant_pole_of_two_of_one_modulus_is_the_least_damped(a2):
    # y(k) = a2 y(k-2) + u(k-1) has the poles ±√a2, as slow as each other: the dominant pole was the one the
    # eigensolver listed first among them by imaginary part (both 0), here +√a2, so damping said 1 (a
    # positive real pole, "tune on τ") for a response whose −√a2 mode alternates as slowly as the other decays
    model = gb.Model(["y(k-2)", "u(k-1)"], [a2, 1.0], Ts=0.1)
    lm = gb.local_model(model, 1.0)
    r = np.sqrt(a2)
    assert lm.dominant_pole == pytest.approx(-r)
    s = complex(np.log(r), np.pi)
    assert lm.damping == pytest.approx(-s.real / abs(s)) and lm.damping < 1
    assert lm.time_constant == pytest.approx(-0.1 / np.log(r))
    assert gb.operating_curve(model, [1.0]).damping[0] == pytest.approx(lm.damping)
    # a conjugate pair keeps its member of positive angle
    pair = gb.local_model(gb.Model(["y(k-1)", "y(k-2)", "u(k-1)"], [1.0, -0.5, 1.0], Ts=0.1), 1.0)
    assert pair.dominant_pole.imag > 0


def _els_uncertainty():
    rng = np.random.default_rng(0)
    N = 300
    u = rng.uniform(0, 2, N)
    y = np.zeros(N)
    e = 0.01 * rng.standard_normal(N)
    for k in range(1, N):
        y[k] = 0.5 * y[k - 1] + 0.8 * u[k - 1] + 0.1 + e[k] + 0.4 * e[k - 1]
    rec = gb.Record(u, y, Ts=1.0)
    model = gb.els(["1", "y(k-1)", "u(k-1)"], rec).model
    return gb.ls_uncertainty(model, rec)


@pytest.mark.parametrize("field, value, why", [
    ("constraints", [[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]], r"constraints must have shape \(r, 3\)"),  # was: two rows
    ("constraints", [[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]], r"constraints must have shape \(r, 3\)"),  # was: rows mixed
    ("constraints", [[1.0, "nan", 0.0]], "constraints has non-finite"),
    ("noise_cov", [[1.0, 0.0, 0.0, 1.0]], r"noise_cov must have shape \(2, 2\)"),  # was: reshaped
    ("noise_cov", [[1.0]], r"noise_cov must have shape \(2, 2\)"),  # was: numpy's 'cannot reshape'
    ("noise_cov", [[-1.0, 0.0], [0.0, 1.0]], "noise_cov has negative variances"),  # was: noise_std 0
    ("noise_cov", [["nan", 0.0], [0.0, 1.0]], "noise_cov has non-finite"),  # was: noise_std NaN
    ("noise_cov", [[1.0, 5.0], [5.0, 1.0]], "noise_cov is no covariance"),  # a correlation of 5
    ("sigma2", -1.0, "sigma2"),
    ("sigma2", "nan", "sigma2"),
    ("static_sigma2", -0.5, "static_sigma2"),
])
def test_a_parameter_uncertainty_whose_constraints_or_noise_covariance_cannot_be_is_refused(field, value, why):
    # ParameterUncertainty reshaped its constraint rows to (-1, n_terms) and its MA covariance to (n_e, n_e) and
    # checked neither: a hand-edited file with three rows of two for three terms loaded as two rows of three (the
    # numbers moved to other terms), a flat noise_cov loaded reshaped, a wrong size failed in numpy's words, and a
    # negative or NaN MA variance gave noise_std 0 or NaN without a word (the process cov is checked since mend36a)
    unc = _els_uncertainty()
    with pytest.raises(gb.GrayboxFileError, match=f"not a valid ParameterUncertainty: .*{why}"):
        gb.from_json(edited_json(unc, **{field: value}))
    back = gb.from_json(gb.to_json(unc))
    np.testing.assert_array_equal(back.noise_std, unc.noise_std)
    assert back.constraints.shape == (0, 3) and np.all(np.isfinite(back.noise_std))


@pytest.mark.parametrize("field, value", [
    ("ybar", [2.0, "nan"]), ("gain", [1.0, "nan"]), ("time_constant", [0.5, "nan"]), ("spectral_radius", [0.1, "nan"]),
])
def test_an_operating_curve_whose_columns_disagree_with_its_local_models_is_refused(field, value):
    # OperatingCurve checked its columns' shapes and its status and ū against its local models, not its
    # figures: a hand-edited file whose gain column said 1.0 where its local model's gain is 1.6 loaded, and
    # to_frame and plot_operating_curve showed one gain, local_models and plot_local_models another
    model = gb.Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], [0.1, 0.5, 0.8, -0.05], Ts=0.1)
    no_eq = gb.Model(["1", "y(k-1)", "y(k-2)", "u(k-1)"], [1.0, 1.2, -0.2, 0.1], Ts=0.1)
    curve = gb.operating_curve(model, [1.0, 2.0])
    with pytest.raises(gb.GrayboxFileError, match=f"not a valid OperatingCurve: {field} disagrees with the local "
                                                  "models' own at operating point 0"):
        gb.from_json(edited_json(curve, **{field: value}))
    for c in (curve, gb.operating_curve(no_eq, [1.0, 2.0])):  # with and without equilibria
        back = gb.from_json(gb.to_json(c))
        np.testing.assert_array_equal(back.gain, c.gain)


def test_static_curve_band_takes_the_levels_of_one_input_as_every_static_path_does():
    # static_curve_band refused a column of levels (M, 1), e.g. a one-column DataFrame df[["speed"]], that
    # Model.static_curve, static_gain, local_model and operating_curve all take as the one input's levels:
    # "ubar must be levels of the model's one input, shape (M,), got shape (2, 1)"
    import pandas as pd

    rng = np.random.default_rng(0)
    u = rng.uniform(0, 2, 200)
    y = np.zeros(200)
    for k in range(1, 200):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.01 * rng.standard_normal()
    rec = gb.Record(u, y, input_names=("speed",))
    model = gb.els(["y(k-1)", "speed(k-1)"], rec, noise=0).model
    unc = gb.ls_uncertainty(model, rec)
    flat = gb.static_curve_band(unc, [0.5, 1.5])
    for column in (np.array([[0.5], [1.5]]), pd.DataFrame({"speed": [0.5, 1.5]})):
        band = gb.static_curve_band(unc, column)
        np.testing.assert_array_equal(band.ybar, model.static_curve(column))
        np.testing.assert_array_equal(band.ybar_std, flat.ybar_std)
    with pytest.raises(ValueError, match="one input"):  # points of two inputs are still no levels of one
        gb.static_curve_band(unc, [[0.5, 1.0], [1.5, 1.0]])
    with pytest.raises(ValueError, match="non-empty"):
        gb.static_curve_band(unc, [])


@pytest.mark.parametrize("other", ["inputs", "period"])
def test_an_operating_curve_of_local_models_of_several_models_is_refused(other):
    # an OperatingCurve whose local models have other inputs or another sampling period (a hand-edited file
    # pasting one in) failed in numpy's words ("all the input array dimensions except for the concatenation
    # axis must match exactly …") or, with its columns edited alike, loaded with τ of two periods in one curve
    import json

    model = gb.Model(["1", "y(k-1)", "u(k-1)"], [0.1, 0.5, 0.8], Ts=1.0)
    curve = gb.operating_curve(model, [1.0, 2.0])
    if other == "inputs":
        pasted = gb.local_model(gb.Model(["1", "y(k-1)", "a(k-1)", "b(k-1)"], [0.1, 0.5, 0.8, 0.2], Ts=1.0), [2.0, 1.0])
    else:
        pasted = gb.local_model(model, 2.0, Ts=2.0)
    doc = json.loads(gb.to_json(curve))
    doc["object"]["local_models"][1] = json.loads(gb.to_json(pasted))["object"]
    doc["object"]["time_constant"][1] = pasted.time_constant
    with pytest.raises(gb.GrayboxFileError, match="not a valid OperatingCurve: the local models are not of one model: "
                                                  "local model 1"):
        gb.from_json(json.dumps(doc))


def _first_order(u, rng, **record):
    """The record of y(k) = 0.5 y(k-1) + 0.8 u(k-1) + 0.1 + 0.01 e(k) driven by ``u``, e drawn from ``rng``."""
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.5 * y[k - 1] + 0.8 * u[k - 1] + 0.1 + 0.01 * rng.standard_normal()
    return gb.Record(u, y, **record)


def _bands():
    rng = np.random.default_rng(1)
    rec = _first_order(rng.uniform(0, 2, 200), rng, Ts=1.0, units=("rpm", "mlc"))
    unc = gb.ls_uncertainty(gb.els(["1", "y(k-1)", "u(k-1)"], rec, noise=0).model, rec)
    return gb.static_curve_band(unc, [0.5, 1.0, 1.5]), gb.simulation_band(unc, rec)


@pytest.mark.parametrize("kind, field, why", [
    ("static", "ybar_std", "ybar_std must be >= 0"), ("static", "gain_std", "gain_std must be >= 0"),
    ("static", "ybar_low", "ybar_low must not exceed ybar_high"), ("static", "gain_high", "gain_low must not exceed"),
    ("run", "std", "std must be >= 0"), ("run", "low", "low must not exceed high"),
])
def test_a_band_that_cannot_be_is_refused(kind, field, why):
    # StaticCurveBand and SimulationBand checked their shapes, level and method, not their numbers: a
    # hand-edited file with a negative standard deviation or a low end above the high one loaded, and
    # SimulationBand.coverage counted the samples of that "band" (none inside it)
    import json

    static, run = _bands()
    band = static if kind == "static" else run
    doc = json.loads(gb.to_json(band))
    values = doc["object"][field]
    values[1] = 1e6 if field.endswith("low") else -1e3  # a low end above the high one, or a negative std
    doc["object"][field] = values
    with pytest.raises(gb.GrayboxFileError, match=why):
        gb.from_json(json.dumps(doc))
    assert gb.from_json(gb.to_json(band)).level == band.level


def test_a_simulation_band_takes_its_units_as_a_record_does():
    # SimulationBand turned every unit into text: units=("rpm", 3) became ("rpm", "3") where a Record, static
    # points and the file header refuse it
    _, run = _bands()
    assert run.units == ("rpm", "mlc")
    fields = {f: getattr(run, f) for f in ("t", "y", "yhat", "low", "high", "std", "level", "method", "n_samples",
                                           "diverged")}
    with pytest.raises(TypeError, match=r"units must be a pair of strings \(input unit, output unit\)"):
        gb.SimulationBand(units=("rpm", 3), **fields)


def _step_record():
    rng = np.random.default_rng(0)
    return _first_order(np.repeat(rng.uniform(0, 2, 200 // 20 + 1), 20)[:200], rng)


@pytest.mark.parametrize("estimator, options", [("pe", {}), ("se", {"method": "gradient", "max_nfev": 5})])
def test_bootstrap_decision_samples_a_curve_at_the_ubar_its_options_give(estimator, options):
    # bootstrap_decision took ubar as an option of the sweep (pe_pareto and se_pareto sample a curve there) but
    # sampled the curve itself first, over its domain, and handed the sweep points and ubar: every call failed
    # on the original data with "ubar is for sampling a StaticCurve or StaticSurface; static points carry their
    # own ū", about points the user never gave
    import warnings

    curve = gb.StaticCurve.polynomial([0.2, 1.6], domain=(0.0, 2.0))
    ubar = np.array([0.2, 1.0, 1.8])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        boot = gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)"], _step_record(), curve, estimator=estimator,
                                     lambdas=[1.0, 0.1], n_boot=2, band=0.01, progress=False,
                                     options={**options, "ubar": ubar})
        sweep = (gb.pe_pareto if estimator == "pe" else gb.se_pareto)(
            ["1", "y(k-1)", "u(k-1)"], _step_record(), curve, lambdas=[1.0, 0.1], ubar=ubar, **options)
    ref = gb.decide_dsf(sweep, band=0.01)
    assert boot.reference["lambda1"] == ref.lambda1 and boot.reference["JSF"] == pytest.approx(ref.JSF)
    np.testing.assert_array_equal(boot.options["ubar"], ubar)
    with pytest.raises(ValueError, match="static points carry their own"):  # points and ubar: still refused
        gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)"], _step_record(), curve.points(ubar), lambdas=[1.0, 0.1],
                              n_boot=2, band=0.01, progress=False, options={"ubar": ubar})


def test_a_decision_bootstrap_has_no_field_a_user_could_change():
    # DecisionBootstrap kept the reference decision's θ as a list (boot.reference["theta"][0] = 99.0 changed the
    # result) and the options as given (a list of constraints stayed the caller's list): results are immutable
    # values all the way down, as test_immutable_results holds every savable value to
    import sys
    import warnings
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_immutable_results import _holes

    sp = gb.StaticPoints([0.2, 1.0, 1.8], [(0.1 + 0.8 * x) / 0.5 for x in [0.2, 1.0, 1.8]], uncertainty=0.05)
    constraints = [gb.GainBounds(lower=0.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        boot = gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)"], _step_record(), sp, lambdas=[1.0, 0.1], n_boot=2,
                                     progress=False, options={"weights": "mse", "constraints": constraints})
    out = []
    _holes(boot, "boot", set(), out)
    assert out == []
    constraints.append(gb.GainBounds(upper=1.0))  # the caller's list, changed afterwards
    assert len(boot.options["constraints"]) == 1
    assert np.isfinite(boot.reference["theta"]).all() and len(boot.reference["theta"]) == 3


@pytest.mark.parametrize("tau_samples", [1.2e6, 2.5e6])
def test_settling_time_of_a_slow_plant_sampled_fast_is_finite_below_ten_million_samples(tau_samples):
    # settling_time said inf for every response whose window (the envelope ρ^k down to 1e-3 of the band: 10.8 τ
    # for a first-order one) exceeded 10⁷ samples, though its docstring promises inf only beyond 10⁷ samples of
    # settling: a heater with τ = 20 min sampled at 1 kHz (τ = 1.2·10⁶ samples) settles in 78 min, 4.7·10⁶
    # samples, and was said never to settle. The response now runs in blocks (memory does not grow) over a
    # window up to 4·10⁷ samples
    rho = np.exp(-1.0 / tau_samples)
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [rho, 1.0 - rho], Ts=1e-3), 1.0)
    # Δy(k) = 1 − ρ^k: outside the 2 % band while ρ^k > 0.02
    assert lm.settling_time() == pytest.approx(np.ceil(np.log(0.02) / np.log(rho)) * 1e-3, rel=1e-6)


def test_settling_time_beyond_ten_million_samples_is_inf():
    # (the limit of the test above, once: it ran in each of its cases, 0.6 s apiece)
    slower = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [np.exp(-1.0 / 3e6), 1.0 - np.exp(-1.0 / 3e6)], Ts=1e-3),
                            1.0)
    assert slower.settling_time() == np.inf  # 1.17·10⁷ samples: beyond the limit, as documented


@pytest.mark.parametrize("expect, error, why", [
    ([gb.Model], TypeError, r"expect must be a graybox type \(e.g. graybox.Model\) or a tuple of them, got \[<class"),
    ("Model", TypeError, "expect must be a graybox type .* got 'Model' \\(str\\)"),
    ((gb.Model, "x"), TypeError, "got 'x' \\(str\\)"),
    (3, TypeError, "got 3 \\(int\\)"),
    (dict, ValueError, "expect must be one of graybox's saved types"),
])
def test_load_says_what_is_wrong_with_expect_before_reading_the_file(expect, error, why, tmp_path):
    # expect=[gb.Model] (a list, not a tuple) failed with Python's "unhashable type: 'list'", a type's name
    # (expect="Model") was a ValueError for a wrong type, and a bad expect was judged only after the file was
    # read, so a missing or corrupt file hid it
    p = gb.save(gb.Model(["y(k-1)"], [0.5]), tmp_path / "m.json")
    with pytest.raises(error, match=why):
        gb.load(p, expect=expect)
    with pytest.raises(error, match=why):
        gb.load(tmp_path / "missing.json", expect=expect)
    with pytest.raises(error, match=why):
        gb.from_json("not json", expect=expect)
    assert isinstance(gb.load(p, expect=(gb.Model, gb.ParetoSet)), gb.Model)


@pytest.mark.parametrize("name", ["", "   "])
def test_narx_iosystem_refuses_a_blank_name(name):
    # narx_iosystem(model, name=model.name) with the default empty name made a system named "", and
    # control.interconnect then failed on it with python-control's IndexError "string index out of range"
    ct = pytest.importorskip("control")
    model = gb.Model(["1", "y(k-1)", "u(k-1)"], [0.1, 0.5, 0.8], Ts=1.0)
    with pytest.raises(ValueError, match="name must name the system"):
        gb.narx_iosystem(model, name=name)
    pi = ct.ss([[1.0]], [[1.0]], [[0.1]], [[0.1]], dt=1.0, inputs="e", outputs="u", name="pi")
    for ok in (None, "plant"):
        loop = ct.interconnect([gb.narx_iosystem(model, name=ok), pi, ct.summing_junction(["r", "-y"], "e", dt=1.0)],
                               inputs="r", outputs="y")
        assert loop.ninputs == 1


def test_bootstrap_decision_says_when_map_returns_no_results():
    # a map returning anything but the jobs' results (a Dask client's map returns futures) failed with Python's
    # "argument of type 'Future' is not iterable" from inside the summary
    import warnings

    sp = gb.StaticPoints([0.2, 1.0, 1.8], [(0.1 + 0.8 * x) / 0.5 for x in [0.2, 1.0, 1.8]], uncertainty=0.05)

    class Future:  # what a Dask client's map hands back
        pass

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(TypeError, match="map must return the jobs' results in order .* result 0 is a Future"):
            gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)"], _step_record(), sp, lambdas=[1.0, 0.1], n_boot=2,
                                  progress=False, map=lambda job, ids: [Future() for _ in ids])
        boot = gb.bootstrap_decision(["1", "y(k-1)", "u(k-1)"], _step_record(), sp, lambdas=[1.0, 0.1], n_boot=2,
                                     progress=False, map=lambda job, ids: (job(i) for i in ids))
    assert boot.n_replicates == 2
