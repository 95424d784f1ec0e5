import numpy as np
import pytest

from graybox import Dataset, Record, evaluate, fit_percent, j1, js, jsf, reference, rrse
from graybox.models._evaluate import evaluate_thetas


def test_table_shape_and_values(paper_record):
    m = reference.paper_model(15)
    noise = 0.1 * np.sin(np.arange(len(paper_record)))
    noise[:6] = 0.0  # keep the initial conditions exact so the free run is the noise-free one
    noisy = Record(paper_record.u, paper_record.y + noise, Ts=0.05)
    data = Dataset(noisy, noisy.slice(600), reference.eq1_points())
    df = evaluate({"ELS (15)": m, "PE (15)": reference.paper_model(15, "PE")}, data)
    assert list(df.columns[:4]) == ["JS_ident", "JS_valid", "JSF", "n_params"]
    assert df.loc["ELS (15)", "n_params"] == 17
    assert df.loc["ELS (15)", "JSF"] == pytest.approx(1.618, abs=1e-3)
    # the noise is 0.1 sin(k): the model's own free run has MSE ≈ 0.005
    assert df.loc["ELS (15)", "JS_ident"] == pytest.approx(np.mean(noise[6:] ** 2), rel=1e-9)


def test_errors_count_from_max_lag(paper_record):
    m = reference.paper_model(15)
    assert j1(m, paper_record) < 1e-18 and js(m, paper_record) < 1e-18
    y = paper_record.y.copy()
    y[:6] += 100.0  # initial conditions change: the free run changes but errors before max lag are not counted
    r = Record(paper_record.u, y, Ts=paper_record.Ts)
    assert js(m, r) > 0


def test_fit_percent_matches_matlab_definition():
    y = np.array([1.0, 2.0, 3.0, 4.0])
    yh = np.array([1.0, 2.5, 2.5, 4.0])
    assert rrse(y, yh) == pytest.approx(np.sqrt(0.5) / np.sqrt(5.0))
    assert fit_percent(y, yh) == pytest.approx(100 * (1 - np.sqrt(0.5 / 5.0)))


def test_vectorised_evaluator_matches_single(paper_record):
    m15 = reference.paper_model(15)
    thetas = np.array([reference.TABLE_II[c] for c in ("ELS", "CLS", "PE")])
    pts = reference.eq1_points()
    out = evaluate_thetas(m15.structure, thetas, paper_record, pts)
    for i, th in enumerate(thetas):
        mi = m15.with_theta(th)
        assert out["J1"][i] == pytest.approx(j1(mi, paper_record), rel=1e-10)
        assert out["JS"][i] == pytest.approx(js(mi, paper_record), rel=1e-10)
        assert out["JSF"][i] == pytest.approx(jsf(mi, pts), rel=1e-10)


def test_jsf_infinite_when_no_stable_equilibrium():
    m = reference.paper_model(17, "PE")
    with pytest.warns(RuntimeWarning, match="no stable equilibrium"):
        assert jsf(m, reference.eq1_points()) == float("inf")
    out = evaluate_thetas(m.structure, m.theta[None, :], static=reference.eq1_points())
    assert out["JSF"][0] == float("inf")


def test_population_errors_equal_the_dense_definition_without_its_temporaries(paper_record):
    # J1 in row blocks and J_S from the compiled SSE kernel: the same numbers as the dense
    # N × P residual matrices (P = 400 members: the rows come in several blocks), one member diverging
    from graybox.core._regressors import regressor_matrix
    from graybox.core._simulation import simulate_many

    m15 = reference.paper_model(15)
    st = m15.structure
    rng = np.random.default_rng(7)
    rec = Record(np.tile(paper_record.u, 3), np.tile(paper_record.y, 3) + 0.05 * rng.standard_normal(3 * len(paper_record)))
    thetas = m15.theta * (1.0 + 0.01 * rng.standard_normal((400, len(st))))
    thetas[3] = m15.theta * 3.0
    out = evaluate_thetas(st, thetas, rec)
    L = st.max_lag
    psi = regressor_matrix(st, rec.u, rec.y, start=L)
    dense_j1 = np.mean((rec.y[L:, None] - psi @ thetas.T) ** 2, axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        dense_js = np.mean((simulate_many(st, thetas, rec)[:, L:] - rec.y[None, L:]) ** 2, axis=1)
    dense_js = np.where(np.isfinite(dense_js), dense_js, np.inf)
    assert np.isinf(out["JS"][3]) and np.isinf(dense_js[3])
    np.testing.assert_allclose(out["J1"], dense_j1, rtol=1e-12)
    np.testing.assert_allclose(out["JS"], dense_js, rtol=1e-12)
    assert np.sum(np.isfinite(out["JS"])) > 300


def _two_records():
    rng = np.random.default_rng(3)
    recs = []
    for _ in range(2):
        u, y = rng.uniform(0, 1, 40), np.zeros(40)
        for k in range(1, 40):
            y[k] = 0.5 * y[k - 1] + u[k - 1]
        recs.append(Record(u, y))
    return recs


@pytest.mark.parametrize("score", [js, j1])
def test_scores_of_a_list_of_records_say_to_score_each(score):
    # a list of records was refused with no word of how to score several: one call per record
    from graybox import Model, Structure
    model = Model(Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 1.0]))
    recs = _two_records()
    with pytest.raises(TypeError, match=rf"once per record.*\[{score.__name__}\(model, r\) for r in records\]"):
        score(model, recs)
    assert score(model, recs[0]) < 1e-20  # the model that made the data, one record at a time


def test_simulate_of_a_list_of_records_says_to_run_each():
    # gb.simulate(model, θ, [a, b]) said "u must be an array of numbers, got list"
    from graybox import Model, Structure, simulate
    model = Model(Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 1.0]))
    recs = _two_records()
    # called as graybox.simulate(structure, theta, …), where the caller may hold no model: told that call too
    with pytest.raises(TypeError, match=r"once per record.*for r in records.*simulate\(structure, theta, r\)"):
        simulate(model.structure, model.theta, recs)
    with pytest.raises(TypeError, match=r"once per record.*for r in records"):
        model.simulate(tuple(recs))
    np.testing.assert_allclose(simulate(model.structure, model.theta, recs[1]), recs[1].y, atol=1e-12)
    with pytest.raises(TypeError, match=r"once per record, \[model\.predict\(r\) for r in records\]"):
        model.predict(recs)


def test_fit_percent_on_a_constant_output_names_itself():
    # fit_percent said "RRSE undefined", a function the user did not call
    y = np.full(20, 3.0)
    with pytest.raises(ValueError, match=r"^fit_percent undefined: the measured output is constant") as err:
        fit_percent(y, y + 0.1)
    assert "RRSE" not in str(err.value)
    with pytest.raises(ValueError, match=r"^RRSE undefined: the measured output is constant"):
        rrse(y, y + 0.1)


def test_rrse_and_fit_near_the_float_range_s_end():
    # y alternating ±1e308 was "constant" (its norm, inf, below CONSTANT_RTOL × inf) and y = [1e308, 0, …] had an inf
    # mean: ratios of norms are read in y's own scale. By hand: ŷ = −y gives ‖2y‖ / ‖y‖ = 2; with ŷ = 0 and y = c [1, 0,
    # 1, 0], ‖y‖ / ‖y − c/2‖ = √2 c / c = √2
    y = np.array([1e308, -1e308, 1e308, -1e308])
    assert rrse(y, -y) == pytest.approx(2.0)
    assert fit_percent(y, -y) == pytest.approx(-100.0)
    z = np.array([1e308, 0.0, 1e308, 0.0])
    assert rrse(z, np.zeros(4)) == pytest.approx(np.sqrt(2.0))
    assert rrse(z * 1e-308 * 1e-10, np.zeros(4)) == pytest.approx(np.sqrt(2.0))


def test_jsf_of_a_list_of_static_point_sets_says_how_to_pool_them():
    # jsf(M, [p, q]) said "make them of the levels and the settled outputs: StaticPoints(ubar, ybar)", as if for arrays
    from graybox import Model, StaticPoints, Structure
    model = Model(Structure(["y(k-1)", "u(k-1)"]), np.array([0.5, 1.0]))
    p, q = StaticPoints(np.array([0.5, 1.0]), np.array([1.1, 2.0])), StaticPoints(np.array([2.0]), np.array([3.9]))
    with pytest.raises(TypeError, match=r"one StaticPoints of all their points.*np\.concatenate") as err:
        jsf(model, [p, q])
    assert "settled outputs" not in str(err.value)
    # as told, pooled: ȳ = 2 ū, so J_SF = mean of (0.1², 0, 0.1²)
    pooled = StaticPoints(np.concatenate([s.ubar for s in (p, q)]), np.concatenate([s.ybar for s in (p, q)]))
    assert jsf(model, pooled) == pytest.approx(0.02 / 3)
