import re

import numpy as np
import pytest

# the fixtures' static points lie beyond their records' input range by design (gray-box knowledge
# where the data do not reach); the warning itself is tested in test_convex.py and test_se_dsf.py
pytestmark = pytest.mark.filterwarnings("ignore::graybox.core._records.StaticRangeWarning")

from graybox import Model, Record, StaticRangeWarning, reference
from graybox.core._simulation_kernels import encode, free_run_sensitivity
from graybox.estimation._simulation_error import GAOptions, SEProblem, ga_front, gradient_front, se_pareto


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(7)
    m = reference.paper_model(15, "PE")
    n = 700
    levels = rng.uniform(750, 1650, n // 70 + 1)
    levels[[3, 6]] = 750.0, 1650.0  # the record spans the static points (750-1650 rpm)
    u = np.repeat(levels, 70)[:n]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    y = m.simulate(u, y0) + 0.1 * rng.standard_normal(n)
    return SEProblem(m.structure, Record(u, y, 0.05), reference.eq1_points())


SMALL = GAOptions(population=30, generations=6)


def beyond(ubar: str):
    """The warning an SE sweep gives when static points lie beyond the record's inputs (expected
    where a test puts them there)."""
    return pytest.warns(StaticRangeWarning, match=re.escape(f"static points: ū = [{ubar}") + ".* outside the input range")


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
    from graybox.models._evaluate import evaluate_thetas

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
    np.testing.assert_array_equal(a.thetas, b.thetas)
    assert not np.array_equal(a.thetas, c.thetas)
    # the best of a run is never worse than its seed individual (elitism)
    rng = np.random.default_rng([11, 0])
    init = problem.random_ls(rng, SMALL.population, 30)
    assert a.costs[0] <= np.min(problem.cost(init, 1.0))
    # seeded with least squares (the default), the first run is never worse than LS
    d = ga_front(problem, lam, options=SMALL, seed=11, progress=False)
    assert d.costs[0] <= problem.cost(problem.ls_theta()[None], 1.0)[0]


def test_ga_with_no_bounded_individual_is_an_error(problem, monkeypatch):
    bad = problem.ls_theta().copy()
    bad[0] = 5.0  # the y(k-1) coefficient alone makes every free run diverge

    def exploding(self, rng, count, samples=30):
        return np.tile(bad, (count, 1)) * (1 + 0.01 * rng.standard_normal((count, bad.size)))

    monkeypatch.setattr(SEProblem, "random_ls", exploding)
    with pytest.raises(ValueError, match=r"every member of the SE sweep \(ga\) failed.*λ1 = 1: no individual"):
        se_pareto(problem.structure, problem.record, problem.static, lambdas=[1.0], method="ga", progress=False,
                  options=SMALL, theta0=None)


def test_gradient_front_beats_ls_and_tracks_lambda(problem):
    front = gradient_front(problem, [1.0, 0.5, 0.05], progress=False)
    ls = problem.ls_theta()
    assert front.costs[0] <= problem.cost(ls[None], 1.0)[0]
    np.testing.assert_allclose(front.costs, [problem.cost(t[None], lam)[0] for t, lam in zip(front.thetas, front.lambdas)],
                               rtol=1e-9)
    jsf = problem.jsf(front.thetas)
    assert jsf[2] <= jsf[0]  # more weight on the static objective: static error does not grow


def test_checkpoint_resume_equals_uninterrupted(problem, tmp_path, monkeypatch):
    import graybox.estimation._simulation_error as se

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
    np.testing.assert_array_equal(resumed.thetas, full.thetas)
    np.testing.assert_array_equal(resumed.costs, full.costs)


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
    ps = se_pareto(problem.structure, problem.record, problem.static, lambdas=[1.0, 0.2], method="gradient", progress=False)
    assert ps.thetas.shape == (2, 17) and np.all(np.isfinite(ps.JS))
    with pytest.raises(ValueError, match="method"):
        se_pareto(problem.structure, problem.record, problem.static, lambdas=[1.0], method="simplex", progress=False)
    with pytest.raises(ValueError, match="static points"):
        se_pareto(problem.structure, problem.record, None, lambdas=[1.0], progress=False)


@pytest.mark.parametrize("P", [1, 7, 30])
def test_parallel_sse_equals_serial(problem, P):
    from graybox.core._simulation_kernels import batch_sse

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
    z = two.ls_theta() * two.scale
    assert_factor_matches_finite_differences(two, z, 0.7)
    ps = se_pareto(problem.structure, [a, b], problem.static, lambdas=[1.0, 0.3], method="gradient", progress=False)
    assert ps.thetas.shape == (2, 17)


def test_bad_theta0_is_named(problem):
    with pytest.raises(ValueError, match="theta0 has 3 values but the structure has 17 terms"):
        ga_front(problem, [1.0], options=SMALL, progress=False, theta0=np.zeros(3))
    with pytest.raises(ValueError, match="theta0 has non-finite values"):
        gradient_front(problem, [1.0], progress=False, theta0=np.full(17, np.nan))


# -- the solver-facing problem: streamed QR factor against finite differences ---------------
def finite_difference_jacobian(problem, z, lam1):
    from graybox.estimation._simulation_error import _residuals

    J = np.empty((_residuals(problem, z, lam1).size, z.size))
    for j in range(z.size):
        h = 1e-6 * max(abs(z[j]), 1e-3 * np.max(np.abs(z)))
        zp, zm = z.copy(), z.copy()
        zp[j] += h
        zm[j] -= h
        J[:, j] = (_residuals(problem, zp, lam1) - _residuals(problem, zm, lam1)) / (2 * h)
    return J


def assert_factor_matches_finite_differences(problem, z, lam1, J=None):
    """The factor T of [J r] and the compressed pair (f̃, J̃) that least_squares sees carry the
    full problem's ‖r‖², Jᵀr and JᵀJ, J by central differences of the full residual vector."""
    from graybox.estimation._simulation_error import _Compressed, _r_factor, _residuals

    r = _residuals(problem, z, lam1)
    J = finite_difference_jacobian(problem, z, lam1) if J is None else J
    T = _r_factor(problem, z, lam1)
    n = z.size
    d = np.sqrt(np.diag(J.T @ J))
    assert np.all(d > 0)
    H = (J.T @ J) / np.outer(d, d)  # compared in correlation form: every entry matters
    np.testing.assert_allclose(T[:, :n].T @ T[:, :n] / np.outer(d, d), H, atol=2e-6)
    np.testing.assert_allclose(T[:, :n].T @ T[:, n] / d, J.T @ r / d, atol=2e-6 * np.linalg.norm(r))
    assert np.linalg.norm(T[:, n]) == pytest.approx(np.linalg.norm(r), rel=1e-12)
    cp = _Compressed(problem, lam1)
    f = cp.fun(z)
    Jt = cp.jac(z, f)
    assert f @ f == pytest.approx(r @ r, rel=1e-12)
    np.testing.assert_allclose(Jt.T @ f / d, J.T @ r / d, atol=2e-6 * np.linalg.norm(r))
    np.testing.assert_allclose(Jt.T @ Jt / np.outer(d, d), H, atol=2e-6)


def test_streamed_factor_matches_finite_differences(problem):
    z = problem.ls_theta() * problem.scale
    for lam1 in (1.0, 0.3):
        assert_factor_matches_finite_differences(problem, z, lam1)


def test_streamed_blocks_equal_one_pass(problem, monkeypatch):
    import graybox.estimation._simulation_error as se
    from graybox.core._simulation_kernels import free_run_sensitivity_blocks

    th = problem.ls_theta()
    rec = problem.record
    y, S = free_run_sensitivity(problem.code, th, rec.u, rec.y[:6], 6)
    rows, yb = [], None
    for k0, k1, yh, Sb in free_run_sensitivity_blocks(problem.code, th, problem.U[0], rec.y[:6], 6, block=50):
        rows.append(Sb.copy())
        yb = yh
    np.testing.assert_array_equal(np.vstack(rows), S[6:])
    np.testing.assert_array_equal(yb, y)
    z = th * problem.scale
    whole = se._r_factor(problem, z, 0.4)
    monkeypatch.setattr(se, "_BLOCK", 37)  # many blocks, none aligned with the record or the lags
    blocks = se._r_factor(problem, z, 0.4)
    np.testing.assert_allclose(blocks.T @ blocks, whole.T @ whole, rtol=1e-10, atol=1e-14 * np.abs(whole).max() ** 2)


# -- a non-rational structure (ℓ = 3: y up to the third power) ------------------------------
@pytest.fixture(scope="module")
def cubic_problem():
    m = reference.paper_model(17)
    rng = np.random.default_rng(0)
    n = 600
    u = np.repeat(rng.uniform(900, 1650, n // 60 + 1), 60)[:n]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    y = m.simulate(u, y0) + 0.05 * rng.standard_normal(n)
    return m, SEProblem(m.structure, Record(u, y, 0.05), reference.eq1_points())


def test_cubic_problem_objective_matches_shared_evaluator(cubic_problem):
    from graybox import evaluate_thetas
    from graybox.static._analysis import cluster_map

    m, problem = cubic_problem
    assert cluster_map(m.structure).max_y_power == 3
    ths = np.vstack([m.theta, problem.ls_theta()])
    ev = evaluate_thetas(problem.structure, ths, problem.record, problem.static)
    np.testing.assert_allclose(problem.js(ths), ev["JS"], rtol=1e-10)
    np.testing.assert_allclose(problem.jsf(ths), ev["JSF"], rtol=1e-10)
    assert np.all(np.isfinite(problem.cost(ths, 0.5)))


def test_cubic_problem_jacobian_matches_finite_differences(cubic_problem):
    from graybox.estimation._simulation_error import _residuals

    m, problem = cubic_problem
    z = m.theta * problem.scale
    M = len(problem.static)
    for lam1 in (0.6, 0.01):
        J = finite_difference_jacobian(problem, z, lam1)
        # the static rows alone: ∂ȳ_i/∂θ of the cubic equilibria, by implicit differentiation
        from graybox.static._analysis import static_theta_gradient

        yb = problem.static_outputs(m.theta[None])[0]
        G = np.sqrt((1 - lam1) / M) * static_theta_gradient(m.structure, m.theta, problem.static.ubar, yb)
        np.testing.assert_allclose(G / problem.scale, J[-M:], rtol=1e-5, atol=1e-7 * np.abs(J[-M:]).max())
        assert np.all(np.isfinite(_residuals(problem, z, lam1)))
        assert_factor_matches_finite_differences(problem, z, lam1, J)


def test_cubic_problem_small_sweep(cubic_problem):
    m, problem = cubic_problem
    lam = [1.0, 0.3, 0.05]
    front = gradient_front(problem, lam, theta0=m.theta, progress=False, max_nfev=30)
    assert not front.failures
    for th, l, c in zip(front.thetas, front.lambdas, front.costs):
        assert c == pytest.approx(problem.cost(th[None], l)[0], rel=1e-9)
        assert c <= problem.cost(m.theta[None], l)[0]  # never worse than the start the run was given
    jsf = problem.jsf(front.thetas)
    assert np.all(np.isfinite(jsf[1:])) and jsf[2] <= jsf[1]
    with beyond("750.0, 850.0"):  # the cubic model's record starts at 900 rpm
        ps = se_pareto(problem.structure, problem.record, problem.static, lambdas=lam, method="gradient",
                       progress=False, theta0=m.theta, max_nfev=30)
    assert not ps.failures and np.all(np.isfinite(ps.JS)) and np.all(np.isfinite(ps.JSF[1:]))


# -- a sweep survives a bad λ ------------------------------------------------------------------
@pytest.fixture(scope="module")
def buck_structure():
    """The real buck converter record with the structure a new user gets (degree 3, lags 4, BIC):
    its static points reach ū = 1.5, far outside the record, where no start has a stable
    equilibrium, so every λ1 < 1 of an SE sweep fails while λ1 = 1 (J_S only) fits."""
    import graybox as gb

    data = gb.load_buck()  # bundled: never skipped
    sel = gb.frols(gb.Candidates(4, 4, ne=0, degree=3), data.ident, criterion="bic")
    return sel.structure, data


@pytest.mark.parametrize("method", ["gradient", "ga"])
def test_sweep_keeps_failed_members_and_the_others(buck_structure, method):
    st, data = buck_structure
    kw = {"options": SMALL} if method == "ga" else {}
    with beyond("1.5, 1.75"):
        ps = se_pareto(st, data, None, lambdas=[1.0, 0.5, 0.1, 0.5], method=method, progress=False, **kw)
    assert len(ps) == 4 and 0 not in ps.failures and set(ps.failures) == {1, 2, 3}
    assert ps.failures[3] == ps.failures[1]  # λ1 = 0.5 given twice: one run, its failure twice
    ps = ps.subset([0, 1, 2])
    assert np.isfinite(ps.JS[0]) and np.isfinite(ps.J1[0]) and np.all(np.isfinite(ps.thetas[0]))
    assert np.all(np.isnan(ps.thetas[1:])) and np.all(ps.JS[1:] == np.inf) and np.all(ps.JSF[1:] == np.inf)
    assert "λ1 = 0.5" in ps.failures[1] and ("equilibrium" in ps.failures[1])
    ps.member_model(0).simulate(data.valid.u, data.valid.y[:4])
    with pytest.raises(ValueError, match="member 1 of this set failed: .*λ1 = 0.5"):
        ps.member_model(1)
    assert list(ps.to_frame()["failure"] != "") == [False, True, True]
    assert len(ps.nondominated()) == 1


def test_every_member_failed_is_an_error_listing_the_reasons(buck_structure):
    st, data = buck_structure
    with pytest.raises(ValueError, match=r"every member of the SE sweep \(gradient\) failed.*λ1 = 0\.5: no start.*"
                                         r"λ1 = 0\.2: no start.*ū = 1\.5") as err, beyond("1.5, 1.75"):
        se_pareto(st, data, None, lambdas=[0.5, 0.2], method="gradient", progress=False)
    # the gradient method has no generations (it was offered them); a margin (never offered) fits both members
    assert str(err.value).endswith("Try another structure, theta0 or starts; where free runs diverge or equilibria "
                                   "are unstable, a stability margin (margin=0.05, say) pulls the starts inside it by "
                                   "shrinking their output feedback")


def test_every_member_failed_advice_fits_the_method(buck_structure, problem, monkeypatch):
    import graybox.estimation._simulation_error as se

    st, data = buck_structure
    with pytest.raises(ValueError, match=r"failed.*Try another structure, theta0 or starts, or more generations or "
                                         r"a larger population \(options=GAOptions"), beyond("1.5, 1.75"):
        se_pareto(st, data, None, lambdas=[0.5, 0.2], method="ga", options=SMALL, progress=False)
    # every start diverging: was offered "more generations", never a margin (margin=0.05 then fits both members)
    bad = problem.ls_theta().copy()
    bad[0] = 5.0
    monkeypatch.setattr(se, "_pe_members", lambda prob, lam: np.vstack([bad] * len(lam)))
    for margin in (None, "auto"):
        with pytest.raises(ValueError, match=r"free run diverges.*Try another structure, theta0 or starts; where "
                                             r"free runs diverge or equilibria are unstable, a stability margin"):
            se_pareto(problem.structure, problem.record, problem.static, lambdas=[0.5, 0.2], method="gradient",
                      theta0=bad, starts=[bad], margin=margin, progress=False)
    # with a margin set already it is not offered again
    assert se._all_failed_advice("gradient", ["free run diverges"], 0.05) == "Try another structure, theta0 or starts"


def test_failed_member_is_retried_from_later_members(problem, monkeypatch):
    import graybox.estimation._simulation_error as se

    bad = problem.ls_theta().copy()
    bad[0] = 5.0  # diverging free run
    ls = problem.ls_theta()
    # the PE member of λ1 = 0.5 is no use, that of 0.2 is: λ1 = 0.5 fails in the sweep, then
    # starts again from the λ1 = 0.2 member's solution
    monkeypatch.setattr(se, "_pe_members", lambda prob, lam: np.vstack([bad, ls]))
    front = gradient_front(problem, [0.5, 0.2], theta0=bad, progress=False)
    assert not front.failures and np.all(np.isfinite(front.costs))
    assert front.nfev.dtype.kind == "i" and np.all(front.nfev > 0)
    assert front.costs[0] <= problem.cost(front.thetas[1][None], 0.5)[0]
    monkeypatch.setattr(se, "_pe_members", lambda prob, lam: np.vstack([bad, bad]))
    front = gradient_front(problem, [0.5, 0.2], theta0=bad, progress=False)
    assert set(front.failures) == {0, 1} and "free run diverges" in front.failures[0]


def test_checkpoint_records_failed_members(buck_structure, tmp_path, monkeypatch):
    import graybox.estimation._simulation_error as se

    st, data = buck_structure
    problem = SEProblem(st, data.ident, data.static)
    lam = [1.0, 0.5, 0.2, 0.1]
    full = gradient_front(problem, lam, progress=False)
    assert set(full.failures) == {1, 2, 3}
    ck = tmp_path / "front.npz"
    real = se._multistart
    calls = {"n": 0}

    def dying(*args, **kw):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt  # killed during the fourth λ, after two failed members
        return real(*args, **kw)

    monkeypatch.setattr(se, "_multistart", dying)
    with pytest.raises(KeyboardInterrupt):
        gradient_front(problem, lam, progress=False, checkpoint=ck)
    monkeypatch.setattr(se, "_multistart", real)
    with np.load(ck) as z:
        assert int(z["done"]) == 3
    resumed = gradient_front(problem, lam, progress=False, checkpoint=ck)
    np.testing.assert_array_equal(resumed.thetas, full.thetas)
    np.testing.assert_array_equal(resumed.costs, full.costs)
    assert dict(resumed.failures) == dict(full.failures)


def test_corrupt_checkpoint_is_named(problem, tmp_path):
    ck = tmp_path / "front.npz"
    ck.write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match="not a readable SE checkpoint"):
        gradient_front(problem, [1.0], progress=False, checkpoint=ck)


@pytest.mark.parametrize("kw, match", [({"solver": "newton"}, "solver must be one of 'auto'"),
                                       ({"max_nfev": 0}, "max_nfev"), ({"tol": -1.0}, "tol"),
                                       ({"starts": [np.zeros(3)]}, r"starts\[0\] has 3 values"),
                                       ({"seed": -1}, "seed"), ({"threads": 0}, "threads")])
def test_gradient_options_are_validated(problem, kw, match):
    with pytest.raises(ValueError, match=match):
        se_pareto(problem.structure, problem.record, problem.static, lambdas=[1.0], method="gradient", progress=False, **kw)


def test_gradient_front_second_pass_leaves_no_better_neighbour():
    import graybox as gb
    from graybox.estimation._simulation_error import _UP_MARGIN, _pe_members

    # the paper's eq. (15) structure on the bundled plant: going down alone, a member ends up
    # beaten at its own λ by its smaller-λ neighbour's solution (seen without the second pass)
    data = gb.load_pumping()
    problem = SEProblem(reference.STRUCTURE_15, data.ident, data.static)
    front = gradient_front(problem, np.logspace(-2, 0, 8), progress=False)
    assert not front.failures
    for i in range(len(front.lambdas) - 1):
        c_neighbour = problem.cost(front.thetas[i + 1][None], front.lambdas[i])[0]
        assert front.costs[i] * (1 - _UP_MARGIN) <= c_neighbour
    # the smallest λ restarted from every start: no worse than any of them
    starts = [problem.ls_theta(), *_pe_members(problem, front.lambdas[-1:])]
    assert front.costs[-1] <= min(problem.cost(s[None], front.lambdas[-1])[0] for s in starts)


def test_checkpoint_of_an_older_graybox_is_named(problem, tmp_path):
    ck = tmp_path / "front.npz"
    ga_front(problem, [1.0], options=SMALL, seed=5, checkpoint=ck, progress=False)
    with np.load(ck) as z:
        kept = {k: z[k] for k in ("meta", "thetas", "costs", "done")}  # as written before failures were kept
    np.savez(ck, **kept)
    with pytest.raises(ValueError, match="older graybox"):
        ga_front(problem, [1.0], options=SMALL, seed=5, checkpoint=ck, progress=False)
    np.savez(ck, **kept, failures="{not json", nfev=np.zeros(1))
    with pytest.raises(ValueError, match="not a readable SE checkpoint"):
        ga_front(problem, [1.0], options=SMALL, seed=5, checkpoint=ck, progress=False)


def test_fit_stops_at_the_last_accepted_point_when_the_jacobian_overflows(problem, monkeypatch):
    import graybox.estimation._simulation_error as se

    real = se._r_factor
    calls = {"n": 0}

    def overflowing(prob, z, lam1):
        calls["n"] += 1
        T = real(prob, z, lam1)
        return T if calls["n"] < 3 else np.full_like(T, np.nan)  # sensitivities overflow from the third step

    monkeypatch.setattr(se, "_r_factor", overflowing)
    th0 = problem.ls_theta()
    th, cost, nfev = se._fit(problem, th0, 1.0, "trf", 50, 1e-8)
    assert calls["n"] == 3 and nfev < 50
    assert cost == pytest.approx(problem.cost(th[None], 1.0)[0], rel=1e-12)
    assert cost < problem.cost(th0[None], 1.0)[0]  # two accepted steps were kept


@pytest.mark.parametrize("scale", [1.0, 1e14, 1e20])
def test_identifiability_with_static_points_does_not_depend_on_the_output_unit(scale):
    # a centred problem judged its records' rows in z (unit-RMS columns) but the static rows Q R in the centred
    # θ: with y in a unit 1e14 times smaller the static rows swamped the records' y columns, and a problem the
    # records alone identify was refused, "rank 4 for 5 terms" (adding rows can never lower a rank)
    from graybox import StaticPoints, Structure

    st = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-2)"])
    u = np.random.default_rng(1).uniform(-1.0, 1.0, 60)
    y = Model(st, np.array([0.1, 1.2, 0.25, 0.1, -0.4])).simulate(u, np.zeros(2))
    ub = np.array([-0.5, 0.0, 0.5])
    sp = StaticPoints(ub, scale * (0.1 + 0.25 * ub + 0.1 * ub ** 2) / 0.2)
    p = SEProblem(st, Record(u, scale * y), sp)
    assert p.records_identify()
    p.check_identified()  # the records with the points: no ValueError
    front = se_pareto(st, Record(u, scale * y), sp, lambdas=[0.5], method="gradient")
    assert front.JS[0] / scale ** 2 < 1e-20  # noise-free: the true system, its J_S round-off


def test_multistart_evaluates_each_start_once(problem, monkeypatch):
    """A start's residuals (its feasibility check, then every solver's first evaluation) and its Jacobian factor
    (every solver's first step) are computed once: each (z, λ1) at most once, the fit's result unchanged."""
    import graybox.estimation._simulation_error as se

    th0 = problem.ls_theta()
    lam = 0.6
    before = se._multistart(problem, lam, [("ls", th0)], ("trf", "dogbox"), 40, 1e-8)
    seen = {"r": [], "T": []}
    real_r, real_T = se._residuals, se._r_factor

    def count(kind, real):
        def wrapped(p, z, lam1):
            seen[kind].append((z.tobytes(), lam1))
            return real(p, z, lam1)
        return wrapped

    monkeypatch.setattr(se, "_residuals", count("r", real_r))
    monkeypatch.setattr(se, "_r_factor", count("T", real_T))
    after = se._multistart(problem, lam, [("ls", th0)], ("trf", "dogbox"), 40, 1e-8)
    z0 = (problem.to_z(th0).tobytes(), lam)
    assert seen["r"].count(z0) == 1 and seen["T"].count(z0) == 1
    np.testing.assert_array_equal(after[0], before[0])
    assert after[1:] == before[1:]  # the same cost, and the same count of evaluations the solvers asked for


@pytest.mark.parametrize("name, dtype", [("thetas", np.float32), ("costs", np.float32), ("thetas", np.longdouble)])
def test_checkpoint_in_another_precision_is_refused(tmp_path, name, dtype):
    # a checkpoint whose members another tool rewrote in float32 resumed them rounded (6.6e-9 off), silently
    from graybox.estimation._simulation_error import CheckpointError, _load_checkpoint, _save_checkpoint

    ck = tmp_path / "front.npz"
    meta = {"problem": "p", "method": "gradient", "lambdas": [1.0, 0.5], "seed": None, "settings": {},
            "graybox": "x"}
    th = np.array([[0.1 + 1e-9, 0.2], [0.3, 0.4]])
    _save_checkpoint(ck, meta, th, np.array([1.0, 2.0]), 2, {}, np.array([3, 4]))
    assert _load_checkpoint(ck, meta, 2)["thetas"].tolist() == th.tolist()
    with np.load(ck) as z:
        arrays = dict(z)
    if np.dtype(dtype).itemsize == np.dtype(float).itemsize and dtype is np.longdouble:
        pytest.skip("long double is float64 on this platform")
    arrays[name] = arrays[name].astype(dtype)
    np.savez(ck, **arrays)
    with pytest.raises(CheckpointError, match=f"{name} {np.dtype(dtype)} are not the float64 the sweep writes"):
        _load_checkpoint(ck, meta, 2)


def test_ga_lambda_given_twice_is_one_member_twice(problem):
    # each λ1 was its own GA run: [0.3, 1.0, 0.3] gave two members at 0.3 of costs 0.031 and 0.015
    ps = se_pareto(problem.structure, problem.record, problem.static, lambdas=[0.3, 1.0, 0.3], method="ga",
                   theta0=None, margin=None, options=GAOptions(population=16, generations=6), progress=False)
    assert ps.lambdas.tolist() == [0.3, 1.0, 0.3]
    np.testing.assert_array_equal(ps.thetas[2], ps.thetas[0])
    assert ps.extra["cost"][2] == ps.extra["cost"][0] and ps.JS[2] == ps.JS[0]
