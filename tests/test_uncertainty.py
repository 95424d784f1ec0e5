"""Parameter uncertainty (LS, ELS, CLS, PE, SE) and static-curve bands, checked by Monte Carlo."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb

STRUCT = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "1"])
THETA = np.array([0.6, 0.2, 2e-3, 1e-3, -5e-7, 0.3])
TRUE = gb.Model(STRUCT, THETA, name="true")


def narx_records(R, N, seed, sigma=0.05, same_input=False):
    """R realisations of the true NARX system with white equation noise, simulated all at once."""
    rng = np.random.default_rng(seed)
    U = rng.uniform(750, 1650, (1 if same_input else R, N)) * np.ones((R, 1))
    E = sigma * rng.standard_normal((R, N))
    Y = np.zeros((R, N))
    Y[:, :2] = 5.0
    t = THETA
    for k in range(2, N):
        Y[:, k] = (t[0] * Y[:, k - 1] + t[1] * Y[:, k - 2] + t[2] * U[:, k - 1] + t[3] * U[:, k - 2]
                   + t[4] * U[:, k - 1] ** 2 + t[5] + E[:, k])
    return [gb.Record(U[r], Y[r], name=f"mc{r}") for r in range(R)]


def test_monte_carlo_coverage_ls_and_cls():
    """400 noise realisations: the 95 % intervals cover the true θ in 92–98 % of cases."""
    points = gb.StaticPoints([900.0, 1400.0], TRUE.static_curve([900.0, 1400.0]))  # the truth passes through them
    ub = np.array([800.0, 1200.0, 1600.0])
    ls_cov, cls_cov, band_cov = [], [], []
    for rec in narx_records(400, 300, seed=0):
        ls = gb.els(STRUCT, rec, noise=0).model
        u = gb.ls_uncertainty(ls, rec)
        ls_cov.append(u.covers(THETA))
        b = gb.static_curve_band(u, ub)
        band_cov.append((b.ybar_low <= TRUE.static_curve(ub)) & (TRUE.static_curve(ub) <= b.ybar_high))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            c = gb.cls(STRUCT, rec, points, solver="closed").model
        uc = gb.cls_uncertainty(c, rec, points)
        assert uc.constraints.shape == (2, 6)
        cls_cov.append(uc.covers(THETA))
    assert 0.92 <= np.mean(ls_cov) <= 0.98
    assert 0.92 <= np.mean(cls_cov) <= 0.98
    assert 0.90 <= np.mean(band_cov) <= 0.99  # the delta-method band of the static curve


def test_cls_constrained_clusters_have_zero_variance():
    rec = narx_records(1, 400, seed=1)[0]
    curve = gb.StaticCurve.fit(gb.StaticPoints(np.linspace(800, 1600, 6), TRUE.static_curve(np.linspace(800, 1600, 6))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        c = gb.cls(STRUCT, rec, curve, reference=0.8).model
    u = gb.cls_uncertainty(c, rec, curve, reference=0.8)
    # the terms of the two-term clusters (y and u) still move, within their cluster …
    assert np.all(u.std[:4] > 0)
    # … single-term clusters are fixed outright …
    np.testing.assert_allclose(u.std[4:], 0.0, atol=1e-12)
    assert u.correlation[0, 1] == pytest.approx(-1.0)
    # … but eq. (22) fixes every cluster: Σ = Rθ has no variance
    np.testing.assert_allclose(u.cluster_cov(), 0.0, atol=1e-12 * np.max(np.abs(u.cov)))
    assert np.all(u.cluster_frame()["std"] <= 1e-6 * np.abs(u.cluster_frame()["value"]))
    np.testing.assert_allclose(u.cov @ u.constraints.T, 0.0, atol=1e-10 * np.max(np.abs(u.cov)))
    # a plain least-squares covariance is larger in every direction the constraints fix
    ls = gb.ls_uncertainty(gb.els(STRUCT, rec, noise=0).model, rec)
    assert np.all(np.diag(ls.cluster_cov()) > 0)
    # the static-curve band of a CLS estimate with an exact curve has zero width
    b = gb.static_curve_band(u, [900.0, 1300.0])
    np.testing.assert_allclose(b.ybar_high - b.ybar_low, 0.0, atol=1e-6)


def test_cls_active_inequalities_count_as_equalities():
    rec = narx_records(1, 300, seed=2)[0]
    tight = gb.ClusterBounds({"Σy": (None, 0.7)})  # the truth has Σy = 0.8: the bound is active
    c = gb.cls(STRUCT, rec, constraints=tight).model
    u = gb.cls_uncertainty(c, rec, constraints=tight)
    assert u.constraints.shape[0] == 1
    assert u.cluster_frame().loc["Σy", "std"] < 1e-6 * u.cluster_frame().loc["Σu", "std"] / 1e-3
    loose = gb.ClusterBounds({"Σy": (None, 0.99)})
    c2 = gb.cls(STRUCT, rec, constraints=loose).model
    assert gb.cls_uncertainty(c2, rec, constraints=loose).constraints.shape[0] == 0


def test_ls_matches_the_textbook_formula_and_els_has_a_noise_block():
    rec = narx_records(1, 300, seed=3)[0]
    m = gb.els(STRUCT, rec, noise=0).model
    u = gb.ls_uncertainty(m, rec)
    psi, y = gb.stacked_regressors(STRUCT, rec)
    res = y - psi @ m.theta
    sigma2 = res @ res / (psi.shape[0] - 6)
    assert u.sigma2 == pytest.approx(sigma2, rel=1e-10)
    np.testing.assert_allclose(u.cov, sigma2 * np.linalg.inv(psi.T @ psi), rtol=1e-6)
    assert u.dof == psi.shape[0] - 6 and u.method == "LS"
    fit = gb.els(STRUCT, rec, noise=2)
    ue = gb.ls_uncertainty(fit.model, rec)
    assert ue.method == "ELS" and ue.noise_cov.shape == (2, 2) and np.all(ue.noise_std > 0)
    # white noise: the MA part is near zero and the process covariance close to the LS one
    np.testing.assert_allclose(ue.std, u.std, rtol=0.1)
    df = ue.to_frame()
    assert list(df.index) == [str(t) for t in STRUCT]
    np.testing.assert_allclose(df["high"] - df["theta"], ue.quantile * ue.std)
    assert ue.with_level(0.99).quantile > ue.quantile


def test_pe_sandwich_matches_monte_carlo():
    ub = np.linspace(800, 1600, 6)
    yb = TRUE.static_curve(ub)
    rng = np.random.default_rng(4)
    for lam in (0.5, 0.1):
        thetas, stds = [], []
        for rec in narx_records(200, 200, seed=5, same_input=True):
            sp = gb.StaticPoints(ub, yb + 0.05 * rng.standard_normal(6))
            th = gb.pe_thetas(STRUCT, rec, sp, lambdas=[lam], solver="closed")[0]
            thetas.append(th)
            stds.append(gb.pe_uncertainty(gb.Model(STRUCT, th), rec, sp, lambda1=lam, static_sigma=0.05).std)
        ratio = np.std(thetas, axis=0) / np.mean(stds, axis=0)
        assert np.all((ratio > 0.85) & (ratio < 1.2)), (lam, ratio)


def test_pe_at_lambda_one_is_least_squares_and_takes_a_decision():
    data = gb.Dataset(narx_records(1, 300, seed=6)[0], narx_records(1, 100, seed=7)[0],
                      gb.StaticPoints(np.linspace(800, 1600, 5), TRUE.static_curve(np.linspace(800, 1600, 5))))
    front = gb.pe_pareto(STRUCT, data, lambdas=[1.0, 0.3, 0.01], solver="closed")
    u1 = gb.pe_uncertainty(front.member_model(0), data, lambda1=1.0)
    ls = gb.ls_uncertainty(front.member_model(0), data)
    np.testing.assert_allclose(u1.cov, ls.cov, rtol=1e-6)
    d = gb.decide_dsf(front, band=10.0)
    ud = gb.pe_uncertainty(d, data)
    assert ud.method == f"PE λ1={d.lambda1:.4g}"
    with pytest.raises(ValueError, match="not the optimum"):
        gb.pe_uncertainty(front.member_model(1), data, lambda1=0.9)
    with pytest.raises(ValueError, match="needs lambda1"):
        gb.pe_uncertainty(front.member_model(1), data)


def test_se_covariance_matches_monte_carlo():
    """Output-error data (white noise on the free run), as the SE covariance assumes."""
    from graybox.estimation._simulation_error import SEProblem, gradient_front

    s = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    true = gb.Model(s, [0.7, 3e-3, -6e-7, 0.5])
    rng = np.random.default_rng(8)
    N = 150
    u = np.repeat(rng.uniform(750, 1650, N // 10 + 1), 10)[:N]
    ysim = true.simulate(u, [true.static_curve([u[0]])[0]])
    ub = np.linspace(800, 1600, 5)
    yb = true.static_curve(ub)
    for lam in (1.0, 0.5):
        thetas, stds = [], []
        for _ in range(100):
            rec = gb.Record(u, ysim + 0.05 * rng.standard_normal(N))
            sp = gb.StaticPoints(ub, yb + 0.05 * rng.standard_normal(5))
            T = gradient_front(SEProblem(s, [rec], sp), [lam], theta0=true.theta, max_nfev=100, progress=False).thetas
            thetas.append(T[0])
            stds.append(gb.se_uncertainty(gb.Model(s, T[0]), rec, sp, lambda1=lam, static_sigma=0.05).std)
        ratio = np.std(thetas, axis=0) / np.mean(stds, axis=0)
        assert np.all((ratio > 0.8) & (ratio < 1.25)), (lam, ratio)


def test_a_static_sigma_estimated_from_few_points_widens_the_t_quantile():
    """σ_SF² estimated from the member's misfit at M = 6 points has at most M degrees of freedom: where the static
    points decide θ (small λ1) Student's t must have no more, or the 95 % intervals of the static terms covered the
    member's mean in 86-88 % of 300 draws (t of the records' 192). Given σ_SF (known), the records' dof stand."""
    rec = narx_records(1, 200, seed=13)[0]
    ub = np.linspace(800, 1600, 6)
    sp = gb.StaticPoints(ub, TRUE.static_curve(ub) + 0.05 * np.random.default_rng(14).standard_normal(6))
    th = gb.pe_thetas(STRUCT, rec, sp, lambdas=[1e-3], solver="closed")[0]
    est = gb.pe_uncertainty(gb.Model(STRUCT, th), rec, sp, lambda1=1e-3)
    assert 1 <= est.dof <= len(ub)
    known = gb.pe_uncertainty(gb.Model(STRUCT, th), rec, sp, lambda1=1e-3, static_sigma=0.05)
    assert known.dof == 200 - 2 - len(STRUCT)
    assert est.quantile > known.quantile
    front = gb.se_pareto(STRUCT, rec, sp, lambdas=[1e-3], method="gradient", theta0=THETA, max_nfev=50,
                         progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.UncertaintyWarning)  # a short run's member: the dof are the point here
        se = gb.se_uncertainty(front.member_model(0), rec, sp, lambda1=1e-3)
    assert 1 <= se.dof <= len(ub)


def test_se_warns_away_from_a_stationary_point():
    rec = narx_records(1, 200, seed=9)[0]
    sp = gb.StaticPoints([900.0, 1400.0], TRUE.static_curve([900.0, 1400.0]))
    off = gb.Model(STRUCT, THETA * 1.01)
    with pytest.warns(gb.UncertaintyWarning, match="not a stationary point"):
        u = gb.se_uncertainty(off, rec, sp, lambda1=0.5)
    assert u.method == "SE λ1=0.5" and np.all(np.isfinite(u.std))


def test_wrong_inputs_are_refused():
    rec = narx_records(1, 200, seed=10)[0]
    m = gb.els(STRUCT, rec, noise=0).model
    with pytest.raises(ValueError, match="not the optimum"):
        gb.ls_uncertainty(m.with_theta(m.theta * 1.001), rec)
    pts = gb.StaticPoints([900.0, 1400.0], TRUE.static_curve([900.0, 1400.0]))
    with pytest.raises(ValueError, match="does not satisfy"):
        gb.cls_uncertainty(m, rec, pts)
    user = gb.UserConstraint(lambda th: th[0] <= 0.9, name="cap")
    with pytest.raises(ValueError, match="not affine"):
        gb.cls_uncertainty(gb.cls(STRUCT, rec, constraints=user).model, rec, constraints=user)
    with pytest.raises(TypeError, match="model must be a Model"):
        gb.ls_uncertainty("m", rec)
    with pytest.raises(ValueError, match="level"):
        gb.ls_uncertainty(m, rec, level=1.5)
    with pytest.raises(ValueError, match="not identifiable|rank"):
        gb.ls_uncertainty(gb.Model(["u(k-1)", "1"], [0.5, 1.0]), gb.Record(np.ones(50), np.arange(50.0)))
    with pytest.raises(ValueError, match="diverges|undefined"):
        gb.se_uncertainty(gb.Model(STRUCT, [1.5, 0.2, 2e-3, 1e-3, -5e-7, 0.3]), rec, pts, lambda1=0.5)


@settings(max_examples=10, deadline=None)
@given(a=st.floats(1e-2, 1e2), b=st.floats(1e-2, 1e2))
def test_relative_uncertainty_does_not_depend_on_units(a, b):
    """u in other units (× a), y in other units (× b): every θ_i scales, its relative std does not."""
    rec = narx_records(1, 200, seed=11)[0]
    base = gb.ls_uncertainty(gb.els(STRUCT, rec, noise=0).model, rec)
    rec2 = gb.Record(a * rec.u, b * rec.y)
    other = gb.ls_uncertainty(gb.els(STRUCT, rec2, noise=0).model, rec2)
    np.testing.assert_allclose(other.to_frame()["rel std"], base.to_frame()["rel std"], rtol=1e-6)
    band = gb.static_curve_band(base, [1000.0, 1500.0])
    band2 = gb.static_curve_band(other, [1000.0 * a, 1500.0 * a])
    np.testing.assert_allclose(band2.ybar_std, b * band.ybar_std, rtol=1e-6)
    np.testing.assert_allclose(band2.gain_std, b / a * band.gain_std, rtol=1e-6)


def test_static_band_delta_gradients_and_monte_carlo():
    rec = narx_records(1, 300, seed=12)[0]
    u = gb.ls_uncertainty(gb.els(STRUCT, rec, noise=0).model, rec)
    ub = np.linspace(800, 1600, 5)
    delta = gb.static_curve_band(u, ub)
    m = u.model
    np.testing.assert_allclose(delta.ybar, m.static_curve(ub))
    np.testing.assert_allclose(delta.gain, m.static_gain(ub), rtol=1e-10)
    # the delta method's std from finite differences of the static map
    eps = 1e-6 * np.abs(m.theta)
    Gy = np.array([(m.with_theta(m.theta + e).static_curve(ub) - m.with_theta(m.theta - e).static_curve(ub)) / (2 * e[i])
                   for i, e in enumerate(np.diag(eps))]).T
    Gg = np.array([(m.with_theta(m.theta + e).static_gain(ub) - m.with_theta(m.theta - e).static_gain(ub)) / (2 * e[i])
                   for i, e in enumerate(np.diag(eps))]).T
    np.testing.assert_allclose(delta.ybar_std, np.sqrt(np.einsum("ij,jk,ik->i", Gy, u.cov, Gy)), rtol=1e-4)
    np.testing.assert_allclose(delta.gain_std, np.sqrt(np.einsum("ij,jk,ik->i", Gg, u.cov, Gg)), rtol=1e-4)
    mc = gb.static_curve_band(u, ub, method="monte-carlo", n_samples=4000, seed=1)
    np.testing.assert_allclose(mc.ybar_std, delta.ybar_std, rtol=0.1)
    np.testing.assert_allclose(mc.ybar_high - mc.ybar_low, delta.ybar_high - delta.ybar_low, rtol=0.12)
    np.testing.assert_allclose(mc.gain_std, delta.gain_std, rtol=0.1)
    assert np.all(mc.undefined == 0)
    again = gb.static_curve_band(u, ub, method="monte-carlo", n_samples=4000, seed=1)
    np.testing.assert_array_equal(again.ybar_low, mc.ybar_low)
    df = mc.to_frame()
    assert list(df.columns[:3]) == ["ybar", "ybar low", "ybar high"]
    with pytest.raises(ValueError, match="method"):
        gb.static_curve_band(u, ub, method="bootstrap")
    with pytest.raises(TypeError, match="ParameterUncertainty"):
        gb.static_curve_band(m, ub)


def test_static_band_figure(tmp_path):
    from matplotlib.figure import Figure

    from graybox.plots import plot_static_band

    rec = narx_records(1, 300, seed=13)[0]
    u = gb.ls_uncertainty(gb.els(STRUCT, rec, noise=0).model, rec)
    ub = np.linspace(800, 1600, 30)
    band = gb.static_curve_band(u, ub)
    pts = gb.StaticPoints(ub[::6], TRUE.static_curve(ub[::6]))
    fig = plot_static_band(band, pts)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    ax = fig.axes[0]
    (poly,) = ax.collections
    verts = poly.get_paths()[0].vertices
    assert verts[:, 1].min() == pytest.approx(band.ybar_low.min()) and verts[:, 1].max() == pytest.approx(band.ybar_high.max())
    line, star = ax.lines
    np.testing.assert_array_equal(line.get_ydata(), band.ybar)
    assert star.get_marker() == "*"
    assert "95% band (delta)" in [t.get_text() for t in ax.get_legend().get_texts()]
    fig.savefig(tmp_path / "band.png", dpi=50)
    assert len(plot_static_band(band, gain=False).axes) == 1
    with pytest.raises(TypeError, match="StaticCurveBand"):
        plot_static_band(u)


def test_a_static_band_of_one_input_refuses_a_grid_of_two_inputs_levels():
    # was: an (M, 2) ubar was flattened into 2M levels of the one input, a band at points nobody asked for
    rec = narx_records(1, 400, seed=5)[0]
    unc = gb.ls_uncertainty(gb.els(STRUCT, rec).model, rec)
    with pytest.raises(ValueError, match=r"one input, shape \(M,\), got shape \(2, 2\)"):
        gb.static_curve_band(unc, [[900.0, 1.0], [1300.0, 2.0]])
    assert gb.static_curve_band(unc, 1200.0).ubar.shape == (1,)  # one level as a number still works


def test_covers_a_constrained_parameter_equal_to_round_off():
    # hunt37b: CLS with the true static curve fixes a cluster; its interval has zero width, and the true
    # value, one ulp off the estimate, read as not covered
    rng = np.random.default_rng(7)
    a1, b1, b2 = 0.8, 10.0, 0.004
    c0 = 2e5 * (1 - a1) - b1 * 3000 - b2 * 3000**2
    th0 = np.array([c0, a1, 0.0, b1, b2])
    st = ["1", "y(k-1)", "y(k-2)", "speed(k-1)", "speed(k-1)^2"]
    curve = gb.StaticCurve.polynomial(np.array([c0, b1, b2]) / (1 - a1), domain=(2800.0, 3200.0))
    s = np.repeat(rng.uniform(2790, 3210, 21), 5)[:100]
    y = np.full(100, 2e5)
    for k in range(2, 100):
        y[k] = c0 + a1 * y[k - 1] + b1 * s[k - 1] + b2 * s[k - 1] ** 2 + 50 * rng.standard_normal()
    rec = gb.Record(s, y, input_names=("speed",), Ts=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        m = gb.cls(st, rec, curve, reference=a1).model
        unc = gb.cls_uncertainty(m, rec, curve, reference=a1)
    assert unc.std[-1] == 0 and unc.covers(th0).all()
    far = th0.copy()
    far[-1] *= 1 + 1e-9  # off by far more than round-off: outside the zero-width interval
    assert not unc.covers(far)[-1]


def test_monte_carlo_static_bands_say_when_draws_reach_no_equilibrium():
    """Draws of θ with no equilibrium are left out of a Monte Carlo band, which is then narrower than the
    parameters' uncertainty: said with an UncertaintyWarning, as simulation_band says it of diverging runs
    (they were counted in .undefined only)."""
    rng = np.random.default_rng(0)
    N = 60
    u = rng.uniform(0, 1, N)
    y = np.zeros(N)
    for k in range(1, N):
        y[k] = 0.98 * y[k - 1] + 0.1 * u[k - 1] + 0.05 * rng.standard_normal()
    rec = gb.Record(u, y)
    m = gb.els(gb.Structure(["y(k-1)", "u(k-1)"]), rec, noise=0).model
    unc = gb.ls_uncertainty(m, rec)  # a pole near 1 with a wide interval: some draws have none below 1
    with pytest.warns(gb.UncertaintyWarning, match="static_curve_band: up to .* reach no equilibrium"):
        # about 0.3 % of the draws reach a pole above 1: 2000 draws hold some whatever basis they are drawn in
        band = gb.static_curve_band(unc, [0.5, 1.0], method="monte-carlo", n_samples=2000, seed=1)
    assert np.all(band.undefined > 0)
    with pytest.warns(gb.UncertaintyWarning, match="operating_curve: up to .* reach no equilibrium"):
        oc = gb.operating_curve(m, [0.5, 1.0], uncertainty=unc, seed=1)
    assert np.all(oc.undefined > 0)
    # a pole far from 1: every draw has its equilibrium, and nothing is said
    y2 = np.zeros(N)
    for k in range(1, N):
        y2[k] = 0.5 * y2[k - 1] + 0.1 * u[k - 1] + 0.001 * rng.standard_normal()
    rec2 = gb.Record(u, y2)
    m2 = gb.els(gb.Structure(["y(k-1)", "u(k-1)"]), rec2, noise=0).model
    with warnings.catch_warnings():
        warnings.simplefilter("error", gb.UncertaintyWarning)
        band2 = gb.static_curve_band(gb.ls_uncertainty(m2, rec2), [0.5, 1.0], method="monte-carlo", n_samples=400)
    assert np.all(band2.undefined == 0)


def _first_order(a, b=1.0):
    """LS uncertainty of y(k) = a y(k-1) + b u(k-1) + noise: gain b/(1 − a)."""
    rng = np.random.default_rng(0)
    s = gb.Structure(["y(k-1)", "u(k-1)"])
    u = rng.uniform(0, 1, 300)
    rec = gb.Record(u, gb.simulate(s, np.array([a, b]), u, np.zeros(1)) + 0.01 * rng.standard_normal(300))
    return gb.ls_uncertainty(gb.els(s, rec, noise=0).model, rec)


def test_static_curve_band_far_out_is_the_band_there_or_names_its_overflow():
    # at ū = 1e200 the delta band's variance (1e396) and the draws' squares overflowed: "ybar_low must hold finite
    # numbers (NaN only where no draw was kept)", of a band about 2e200 ± 1e198
    q = _first_order(0.5)
    (a, b), cov = q.theta, q.cov
    g = np.array([b / (1 - a) ** 2, 1 / (1 - a)])  # ∂ȳ/∂(a, b) at ū = 1, by hand: ȳ = b ū / (1 − a)
    band = gb.static_curve_band(q, [1e200])
    assert band.ybar_std[0] == pytest.approx(1e200 * np.sqrt(g @ cov @ g), rel=1e-9)
    near, far = (gb.static_curve_band(q, [x], method="monte-carlo", n_samples=200) for x in (1.0, 1e200))
    assert far.ybar_std[0] == pytest.approx(1e200 * near.ybar_std[0], rel=1e-9)  # the same draws, ȳ linear in ū
    # ȳ = 1.785e308 at ū = 1e308: the delta method's gradient leaves the float range (∂ȳ/∂a = ȳ / (1 − a) = 3.2e308),
    # not the band (ū = 1e307's ten times over: 1.7815e308 … 1.7894e308), which was said to leave it, and the gain's
    # band too (1.78 ± 0.004 at every ū); the draws give the band
    q = _first_order(0.44)
    with pytest.raises(ValueError, match=r"the delta method's gradient of ȳ leaves the float range \(±1\.8e308\) at "
                                         r"ū = 1e\+308 \(ȳ = 1\.78.*e\+308\).*monte-carlo") as err:
        gb.static_curve_band(q, [1.0, 1e308])
    assert "band" not in str(err.value).split("monte-carlo")[0]
    mc = gb.static_curve_band(q, [1e308], method="monte-carlo", n_samples=200)
    assert np.isfinite(mc.ybar_high[0]) and mc.ybar_low[0] < mc.ybar[0] < mc.ybar_high[0]
    # a band whose gradient is a float but whose upper end is not: ȳ = b ū / (1 − a) at 0.9995 of the largest float,
    # its half width some 1e-3 of it (a = −0.2: ∂ȳ/∂a = ȳ / (1 − a) and ∂ȳ/∂b = ū / (1 − a) are floats)
    q = _first_order(-0.2, 2.0)
    (a, b) = q.theta
    ub = 0.9995 * np.finfo(float).max / b * (1 - a)
    with pytest.raises(ValueError, match=r"the band overflows at ū = .*: the band of ȳ leaves the float range"):
        gb.static_curve_band(q, [ub])
