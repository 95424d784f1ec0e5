"""simulation_band: the confidence band of a model's free run from its parameters' covariance.

Judged against what it claims: pointwise coverage of the true noise-free free run over fresh
identification records, the sensitivities against central differences of the free run, the delta
method against Monte Carlo where the run is nearly linear in θ, and results that do not depend on
the units or on the order of a record's input columns."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as hs
from matplotlib.figure import Figure

import graybox as gb

STRUCT = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
THETA = np.array([0.7, 0.8, -0.2, 0.1])


def _run(theta: np.ndarray, u: np.ndarray, e: np.ndarray) -> np.ndarray:
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = theta[0] * y[k - 1] + theta[1] * u[k - 1] + theta[2] * u[k - 1] ** 2 + theta[3] + e[k]
    return y


def _records(seed: int, n: int = 300, noise: float = 0.05):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2, n)
    rec = gb.Record(u, _run(THETA, u, noise * rng.standard_normal(n)), name="ident")
    return rec


VAL_U = np.random.default_rng(99).uniform(0, 2, 150)
VAL = gb.Record(VAL_U, _run(THETA, VAL_U, 0.05 * np.random.default_rng(98).standard_normal(150)), name="valid")


def _unc(rec: gb.Record) -> gb.ParameterUncertainty:
    return gb.ls_uncertainty(gb.els(STRUCT, rec, noise=0).model, rec)


def test_delta_band_covers_the_true_free_run_at_its_level():
    # the law a confidence band states: over fresh identification records (equation noise, so LS
    # is consistent), the true model's noise-free free run lies inside the band at about the level
    truth = gb.Model(gb.parse_structure(STRUCT), THETA).simulate(VAL)
    ks = np.array([5, 40, 90, 140])
    inside = []
    for seed in range(200):
        b = gb.simulation_band(_unc(_records(seed)), VAL)
        inside.append((truth[ks] >= b.low[ks]) & (truth[ks] <= b.high[ks]))
    cover = np.mean(inside, axis=0)
    assert np.all(cover > 0.90) and np.all(cover < 0.99), cover  # 0.95 ± 3 binomial sd at 200 draws


def test_sensitivities_match_central_differences_across_blocks():
    # the streamed sensitivities (blocks of 4096 samples) against an independent reference: the
    # variance gᵀ cov g with g from central differences of the free run in θ, on a record longer than a block
    rng = np.random.default_rng(3)
    u = rng.uniform(0, 2, 5000)
    rec = gb.Record(u, _run(THETA, u, 0.05 * rng.standard_normal(5000)), name="long")
    unc = _unc(_records(1))
    b = gb.simulation_band(unc, rec)
    m = unc.model
    G = np.empty((5000, m.n_params))
    for j in range(m.n_params):
        h = 1e-6 * max(1.0, abs(m.theta[j]))
        tp, tm = m.theta.copy(), m.theta.copy()
        tp[j] += h
        tm[j] -= h
        G[:, j] = (gb.simulate(m.structure, tp, rec) - gb.simulate(m.structure, tm, rec)) / (2 * h)
    ref = np.sqrt(np.einsum("ij,jk,ik->i", G, unc.cov, G))
    assert b.std[0] == 0.0  # the initial sample is the record's
    np.testing.assert_allclose(b.std[1:], ref[1:], rtol=1e-5)
    np.testing.assert_allclose(b.high - b.yhat, unc.quantile * b.std, rtol=1e-12)


def test_monte_carlo_agrees_with_delta_where_the_run_is_nearly_linear():
    unc = _unc(_records(2, n=2000, noise=0.01))
    d = gb.simulation_band(unc, VAL)
    mc = gb.simulation_band(unc, VAL, method="monte-carlo", n_samples=4000, seed=5)
    assert mc.diverged == 0.0 and mc.n_samples == 4000 and d.n_samples == 0
    np.testing.assert_allclose(mc.std[1:], d.std[1:], rtol=0.08)
    np.testing.assert_allclose(mc.high[1:] - mc.low[1:], d.high[1:] - d.low[1:], rtol=0.1)
    again = gb.simulation_band(unc, VAL, method="monte-carlo", n_samples=4000, seed=5)
    np.testing.assert_array_equal(again.low, mc.low)  # seeded


def test_band_does_not_depend_on_units_or_input_order():
    rec = _records(4)
    b = gb.simulation_band(_unc(rec), VAL)
    su, ou, sy, oy = 1e3, 3e3, 1e5, 2e5  # rpm and Pa, far from 1
    rec2 = gb.Record(rec.u * su + ou, rec.y * sy + oy, name="ident")
    val2 = gb.Record(VAL.u * su + ou, VAL.y * sy + oy, name="valid")
    st2 = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
    unc2 = gb.ls_uncertainty(gb.els(st2, rec2, noise=0).model, rec2)
    b2 = gb.simulation_band(unc2, val2)
    np.testing.assert_allclose(b2.std, sy * b.std, rtol=1e-6, atol=0)
    np.testing.assert_allclose(b2.low, sy * b.low + oy, rtol=1e-9)
    # Monte Carlo at the offset agrees with the delta band (its draws go through the covariance's factor,
    # as static_curve_band's do since hunt37b found eigenvector draws 20 times too wide at such offsets)
    mc = gb.simulation_band(unc2, val2, method="monte-carlo", n_samples=3000, seed=2)
    np.testing.assert_allclose(mc.std[1:], b2.std[1:], rtol=0.1)


def test_two_inputs_read_by_name_in_any_column_order():
    rng = np.random.default_rng(5)
    n = 400
    p, s = rng.uniform(1, 2, n), rng.uniform(0, 1, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.5 * p[k - 1] - 0.3 * s[k - 1] * p[k - 1] + 0.02 * rng.standard_normal()
    rec = gb.Record(np.column_stack([p, s]), y, input_names=("press", "speed"), name="ident")
    st = ["y(k-1)", "press(k-1)", "speed(k-1)*press(k-1)"]
    unc = gb.ls_uncertainty(gb.els(st, rec, noise=0).model, rec)
    b = gb.simulation_band(unc, rec)
    swapped = gb.Record(np.column_stack([s, p]), y, input_names=("speed", "press"), name="ident")
    np.testing.assert_array_equal(gb.simulation_band(unc, swapped).std, b.std)
    assert np.all(b.std[1:] > 0)


def test_diverging_draws_are_counted_said_and_left_out():
    # a model near its stability limit with a wide covariance: some drawn runs diverge
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    m = gb.Model(st, np.array([0.95, 1.0]))
    unc = gb.ParameterUncertainty(m, np.diag([0.1**2, 0.01**2]), 0.95, 50, 1.0, "LS", np.zeros((0, 2)),
                                  np.zeros((0, 0)))
    rec = gb.Record(np.ones(400), np.zeros(400), name="steps")
    with pytest.warns(gb.UncertaintyWarning, match=r"of the Monte Carlo runs diverged on steps"):
        b = gb.simulation_band(unc, rec, method="monte-carlo", n_samples=400, seed=1)
    assert 0.05 < b.diverged < 0.6
    assert np.all(np.isfinite(b.low)) and np.all(np.isfinite(b.high))


def test_refusals_name_the_problem():
    unc = _unc(_records(6))
    bad = gb.ParameterUncertainty(gb.Model(gb.parse_structure(["y(k-1)", "u(k-1)"]), np.array([1.5, 1.0])),
                                  np.eye(2) * 1e-4, 0.95, 50, 1.0, "LS", np.zeros((0, 2)), np.zeros((0, 0)))
    with pytest.raises(ValueError, match="estimate's free run diverges on valid at sample"):
        gb.simulation_band(bad, VAL)
    with pytest.raises(TypeError, match="uncertainty must be a ParameterUncertainty"):
        gb.simulation_band(unc.model, VAL)
    with pytest.raises(TypeError, match="record must be a Record or a Dataset"):
        gb.simulation_band(unc, [VAL])
    with pytest.raises(ValueError, match="method"):
        gb.simulation_band(unc, VAL, method="bootstrap")
    with pytest.raises(ValueError, match="n_samples"):
        gb.simulation_band(unc, VAL, n_samples=3)
    with pytest.raises(ValueError, match="fewer than max lag"):
        gb.simulation_band(unc, gb.Record([1.0], [0.0]))


def test_a_dataset_stands_for_its_validation_record_and_the_band_saves_bit_for_bit(tmp_path):
    data = gb.Dataset(_records(7), VAL)
    unc = _unc(data.ident)
    b = gb.simulation_band(unc, data)
    assert b.record_name == "valid" and b.t.size == VAL.u.size
    path = tmp_path / "band.json"
    gb.save(b, path)
    back = gb.load(path, expect=gb.SimulationBand)
    for f in ("t", "y", "yhat", "low", "high", "std"):
        np.testing.assert_array_equal(getattr(back, f), getattr(b, f))
    assert (back.method, back.level, back.model_name) == (b.method, b.level, b.model_name)
    with pytest.raises(ValueError, match="read-only"):
        b.low[0] = 1.0
    import dataclasses
    for field, bad in (("level", 2.0), ("method", "bootstrap"), ("n_samples", -5), ("diverged", 1.5)):
        with pytest.raises(ValueError, match=field):  # as a hand-edited file would give them
            dataclasses.replace(b, **{field: bad})
    df = b.to_frame()
    assert list(df.columns) == ["y", "yhat", "low", "high", "std"] and df.index.name == "t"


def test_coverage_of_the_record_says_how_much_error_the_parameters_explain():
    # equation noise of 0.05 is far larger than the parameters' spread on 300 samples: the measured
    # output mostly lies outside the model's band
    b = gb.simulation_band(_unc(_records(8)), VAL)
    assert b.coverage < 0.6
    noiseless = gb.Record(VAL.u, gb.Model(gb.parse_structure(STRUCT), THETA).simulate(VAL), name="clean")
    assert gb.simulation_band(_unc(_records(8)), noiseless).coverage > 0.8


def test_plot_draws_the_measurement_the_run_and_the_band(tmp_path):
    b = gb.simulation_band(_unc(_records(9)), gb.Record(VAL.u, VAL.y, name="valid", units=("rpm", "Pa")))
    assert b.units == ("rpm", "Pa")
    assert gb.read_header(gb.save(b, tmp_path / "b.json"))["units"] == ("rpm", "Pa")  # the file says the band's units
    fig = gb.plots.plot_simulation_band(b)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert ax.get_ylabel() == "output (Pa)" and len(ax.get_lines()) == 2 and len(ax.collections) == 1
    with pytest.raises(TypeError, match="band must be a SimulationBand"):
        gb.plots.plot_simulation_band(b.to_frame())


@settings(max_examples=25, deadline=None)
@given(seed=hs.integers(0, 2**31), scale=hs.floats(1e-3, 1e4), offset=hs.floats(-1e4, 1e4))
def test_a_model_without_output_feedback_has_the_exact_linear_band(seed, scale, offset):
    # law: with no y term the free run is linear in θ, ŷ = Φθ, so its variance is exactly diag(Φ cov Φᵀ)
    rng = np.random.default_rng(seed)
    u = offset + scale * rng.uniform(0, 1, 120)
    assume(np.ptp(u) > 0)
    st = gb.parse_structure(["u(k-1)", "u(k-2)^2", "u(k-1)u(k-3)", "1"])
    A = rng.standard_normal((4, 4))
    cov = A @ A.T * 1e-4
    unc = gb.ParameterUncertainty(gb.Model(st, rng.standard_normal(4)), cov, 0.9, 40, 1.0, "LS", np.zeros((0, 4)),
                                  np.zeros((0, 0)))
    rec = gb.Record(u, np.zeros(120))
    b = gb.simulation_band(unc, rec)
    k = np.arange(3, 120)  # by hand, not by the library's regressors
    phi = np.column_stack([u[k - 1], u[k - 2] ** 2, u[k - 1] * u[k - 3], np.ones(k.size)])
    ref = np.sqrt(np.einsum("ij,jk,ik->i", phi, cov, phi))
    np.testing.assert_allclose(b.std[3:], ref, rtol=1e-9, atol=1e-12 * np.max(ref))
    assert np.all(b.std[:3] == 0)


def test_a_static_curve_band_is_held_to_what_a_band_can_be():
    # hunt37a: a StaticCurveBand took level 3, n_samples -5 and any method label (a hand-edited file loaded)
    import dataclasses
    band = gb.static_curve_band(_unc(_records(10)), [0.5, 1.0, 1.5])
    for field, bad in (("level", 3.0), ("method", "guess"), ("n_samples", -5), ("undefined", np.array([0, 2.0, 0]))):
        with pytest.raises(ValueError, match=field):
            dataclasses.replace(band, **{field: bad})



def test_monte_carlo_spread_at_one_or_two_degrees_of_freedom_is_the_scale_of_the_draws():
    # the draws are multivariate t, which has no variance at dof <= 2: their sample std came out 0.19 to 4.0 across
    # seeds where the delta band's was 0.05 (a PE member's σ_SF from 4-6 points). A map linear in θ (no y term) has
    # the exact std diag(Φ cov Φᵀ)^½, by hand, which every seed's Monte Carlo std must meet to its sampling error
    rng = np.random.default_rng(3)
    st = gb.parse_structure(["u(k-1)", "u(k-2)^2", "1"])
    A = rng.standard_normal((3, 3))
    cov = A @ A.T * 1e-4
    u = rng.uniform(0, 2, 40)
    k = np.arange(2, 40)
    ref = np.sqrt(np.einsum("ij,jk,ik->i", np.column_stack([u[k - 1], u[k - 2] ** 2, np.ones(k.size)]), cov,
                            np.column_stack([u[k - 1], u[k - 2] ** 2, np.ones(k.size)])))
    ub = np.array([0.5, 1.5])
    ref_static = np.sqrt(np.einsum("ij,jk,ik->i", np.column_stack([ub, ub**2, np.ones(2)]), cov,
                                   np.column_stack([ub, ub**2, np.ones(2)])))
    for dof in (1, 2):
        unc = gb.ParameterUncertainty(gb.Model(st, [0.5, -0.2, 0.1]), cov, 0.95, dof, 1.0, "LS", np.zeros((0, 3)),
                                      np.zeros((0, 0)))
        for seed in (0, 1):
            b = gb.simulation_band(unc, gb.Record(u, np.zeros(40)), method="monte-carlo", n_samples=2000, seed=seed)
            np.testing.assert_allclose(b.std[2:], ref, rtol=0.1)
            s = gb.static_curve_band(unc, ub, method="monte-carlo", n_samples=2000, seed=seed)
            np.testing.assert_allclose(s.ybar_std, ref_static, rtol=0.1)
