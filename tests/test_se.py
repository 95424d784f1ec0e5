import numpy as np
import pytest

from graybox import Model, Record, reference
from graybox._kernels import encode, free_run_sensitivity
from graybox._se import GAOptions, SEProblem, ga_front, gradient_front, se_pareto


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(7)
    m = reference.paper_model(15, "PE")
    n = 700
    u = np.repeat(rng.uniform(750, 1650, n // 70 + 1), 70)[:n]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    y = m.simulate(u, y0) + 0.1 * rng.standard_normal(n)
    return SEProblem(m.structure, Record(u, y, 0.05), reference.eq1_points())


SMALL = GAOptions(population=30, generations=6)


def test_sensitivity_matches_finite_differences(problem):
    th = problem.ls_theta()
    rec = problem.record
    y, S = free_run_sensitivity(problem.code, th, rec.u, rec.y[:6], 6)
    for j in range(len(th)):
        h = 1e-6 * max(abs(th[j]), 1e-12)
        tp = th.copy()
        tp[j] += h
        tm = th.copy()
        tm[j] -= h
        yp, _ = free_run_sensitivity(problem.code, tp, rec.u, rec.y[:6], 6)
        ym, _ = free_run_sensitivity(problem.code, tm, rec.u, rec.y[:6], 6)
        fd = (yp - ym) / (2 * h)
        assert np.max(np.abs(fd - S[:, j])) <= 1e-5 * np.max(np.abs(S[:, j])) + 1e-12, j


def test_sensitivity_for_cubic_structure():
    m = reference.paper_model(17)
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(750, 1650, 5), 40)
    y0 = np.full(6, 4.0)
    code = encode(m.structure)
    y, S = free_run_sensitivity(code, m.theta, u, y0, 6)
    np.testing.assert_allclose(y, m.simulate(u, y0), rtol=1e-12)
    for j in (1, 9, 11, 20):
        h = 1e-6 * abs(m.theta[j])
        tp = m.theta.copy()
        tp[j] += h
        tm = m.theta.copy()
        tm[j] -= h
        fd = (m.with_theta(tp).simulate(u, y0) - m.with_theta(tm).simulate(u, y0)) / (2 * h)
        assert np.max(np.abs(fd - S[:, j])) <= 1e-5 * np.max(np.abs(S[:, j])), j


def test_cost_definitions_match_shared_evaluator(problem):
    from graybox._evaluate import evaluate_thetas

    ths = problem.ls_theta() * (1 + 0.001 * np.random.default_rng(0).standard_normal((5, 17)))
    ev = evaluate_thetas(problem.structure, ths, problem.record, problem.static)
    np.testing.assert_allclose(problem.js(ths), ev["JS"], rtol=1e-10)
    np.testing.assert_allclose(problem.jsf(ths), ev["JSF"], rtol=1e-10)


def test_diverging_individual_gets_infinite_cost(problem):
    th = problem.ls_theta()
    bad = th.copy()
    bad[0] = 5.0
    c = problem.cost(np.vstack([th, bad]), 0.5)
    assert np.isfinite(c[0]) and c[1] == np.inf


def test_ga_is_reproducible_and_improves(problem):
    lam = [1.0, 0.3]
    a = ga_front(problem, lam, options=SMALL, seed=11, progress=False, theta0=None)  # the paper's seeding exactly
    b = ga_front(problem, lam, options=SMALL, seed=11, progress=False, theta0=None)
    c = ga_front(problem, lam, options=SMALL, seed=12, progress=False, theta0=None)
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[1], c[1])
    # the best of a run is never worse than its seed individual (elitism)
    rng = np.random.default_rng([11, 0])
    init = problem.random_ls(rng, SMALL.population, 30)
    assert a[2][0] <= np.min(problem.cost(init, 1.0))
    # seeded with least squares (the default), the first run is never worse than LS
    d = ga_front(problem, lam, options=SMALL, seed=11, progress=False)
    assert d[2][0] <= problem.cost(problem.ls_theta()[None], 1.0)[0]


def test_ga_with_no_bounded_individual_is_an_error(problem, monkeypatch):
    bad = problem.ls_theta().copy()
    bad[0] = 5.0  # the y(k-1) coefficient alone makes every free run diverge

    def exploding(self, rng, count, samples=30):
        return np.tile(bad, (count, 1)) * (1 + 0.01 * rng.standard_normal((count, bad.size)))

    monkeypatch.setattr(SEProblem, "random_ls", exploding)
    with pytest.raises(ValueError, match="no member with a finite cost"):
        se_pareto(problem.structure, problem.record, problem.static, [1.0], method="ga", progress=False,
                  options=SMALL, theta0=None)


def test_gradient_front_beats_ls_and_tracks_lambda(problem):
    lam, th, cost = gradient_front(problem, [1.0, 0.5, 0.05], progress=False)
    ls = problem.ls_theta()
    assert cost[0] <= problem.cost(ls[None], 1.0)[0]
    jsf = problem.jsf(th)
    assert jsf[2] <= jsf[0]  # more weight on the static objective: static error does not grow


def test_checkpoint_resume_equals_uninterrupted(problem, tmp_path, monkeypatch):
    import graybox._se as se

    lam = [1.0, 0.6, 0.3, 0.1]
    full = ga_front(problem, lam, options=SMALL, seed=5, progress=False)
    ck = tmp_path / "front.npz"
    calls = {"n": 0}
    real = se._ga_run

    def dying(*args, **kw):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt  # killed during the third λ
        return real(*args, **kw)

    monkeypatch.setattr(se, "_ga_run", dying)
    with pytest.raises(KeyboardInterrupt):
        ga_front(problem, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)
    monkeypatch.setattr(se, "_ga_run", real)
    with np.load(ck) as z:
        assert int(z["done"]) == 2
    resumed = ga_front(problem, lam, options=SMALL, seed=5, checkpoint=ck, progress=False)
    np.testing.assert_array_equal(resumed[1], full[1])
    np.testing.assert_array_equal(resumed[2], full[2])


def test_checkpoint_of_another_problem_is_refused(problem, tmp_path):
    ck = tmp_path / "front.npz"
    ga_front(problem, [1.0], options=SMALL, seed=5, checkpoint=ck, progress=False)
    other = SEProblem(problem.structure, problem.record.slice(0, 600), problem.static)
    with pytest.raises(ValueError, match="another problem.*problem"):
        ga_front(other, [1.0], options=SMALL, seed=5, checkpoint=ck, progress=False)
    with pytest.raises(ValueError, match="differs in: seed"):
        ga_front(problem, [1.0], options=SMALL, seed=6, checkpoint=ck, progress=False)


@pytest.mark.parametrize("lam", [[0.0], [1.5], [-0.1, 0.5], [np.nan], []])
def test_lambda_outside_unit_interval(problem, lam):
    with pytest.raises(ValueError, match="λ1"):
        ga_front(problem, lam, options=SMALL, progress=False)


def test_se_pareto_returns_evaluated_set(problem):
    ps = se_pareto(problem.structure, problem.record, problem.static, [1.0, 0.2], method="gradient", progress=False)
    assert ps.thetas.shape == (2, 17) and np.all(np.isfinite(ps.JS))
    with pytest.raises(ValueError, match="method"):
        se_pareto(problem.structure, problem.record, problem.static, [1.0], method="simplex", progress=False)
    with pytest.raises(ValueError, match="static points"):
        se_pareto(problem.structure, problem.record, None, [1.0], progress=False)


@pytest.mark.parametrize("P", [1, 7, 30])
def test_parallel_sse_equals_serial(problem, P):
    from graybox._kernels import batch_sse

    ths = problem.ls_theta() * (1 + 0.001 * np.random.default_rng(P).standard_normal((P, 17)))
    rec = problem.record
    one = batch_sse(problem.code, ths, rec.u, rec.y, 6, threads=1)
    two = batch_sse(problem.code, ths, rec.u, rec.y, 6, threads=2)
    np.testing.assert_array_equal(one, two)
    ref = np.sum((problem_free_runs(problem, ths)[:, 6:] - rec.y[6:]) ** 2, axis=1)
    np.testing.assert_allclose(one, ref, rtol=1e-12)


def problem_free_runs(problem, ths):
    from graybox import simulate_many

    return np.asarray(simulate_many(problem.structure, ths, problem.record))


def test_several_records_never_straddled(problem):
    from graybox import js as js_single

    rec = problem.record
    a, b = rec.slice(0, 300, name="a"), rec.slice(300, None, name="b")
    two = SEProblem(problem.structure, [a, b], problem.static)
    th = problem.ls_theta() * (1 + 0.001 * np.random.default_rng(1).standard_normal((3, 17)))
    # J_S over two experiments = sample-weighted mean of each one's own free-run MSE
    for row, val in zip(th, two.js(th)):
        m = Model(problem.structure, row)
        na, nb = len(a) - 6, len(b) - 6
        assert val == pytest.approx((na * js_single(m, a) + nb * js_single(m, b)) / (na + nb), rel=1e-10)
    # the gradient method's residuals and Jacobian stay consistent across the record boundary
    from graybox._se import _residuals_and_jac

    z = two.ls_theta() * two.scale
    r, J = _residuals_and_jac(two, z, 0.7, True)
    for j in (0, 5, 16):
        h = 1e-6 * max(abs(z[j]), 1e-9)
        zp, zm = z.copy(), z.copy()
        zp[j] += h
        zm[j] -= h
        fd = (_residuals_and_jac(two, zp, 0.7, False)[0] - _residuals_and_jac(two, zm, 0.7, False)[0]) / (2 * h)
        assert np.max(np.abs(fd - J[:, j])) <= 1e-5 * np.max(np.abs(J[:, j])) + 1e-12
    ps = se_pareto(problem.structure, [a, b], problem.static, [1.0, 0.3], method="gradient", progress=False)
    assert ps.thetas.shape == (2, 17)


def test_bad_theta0_is_named(problem):
    with pytest.raises(ValueError, match="theta0 has 3 values but the structure has 17 terms"):
        ga_front(problem, [1.0], options=SMALL, progress=False, theta0=np.zeros(3))
    with pytest.raises(ValueError, match="theta0 has non-finite values"):
        gradient_front(problem, [1.0], progress=False, theta0=np.full(17, np.nan))
