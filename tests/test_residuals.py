"""Residual validation: the five correlation tests of Billings & Voon."""

import dataclasses
import json
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from scipy import stats

import graybox as gb
from graybox.diagnostics._residuals import _xcorr

GOOD = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"])
MISSING_U2 = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])


def simulate(seed, N=1000, ma=(0.0, 0.0), offset=1000.0, gain=300.0):
    """y(k) = 0.5 y(k-1) + 0.8 u(k-1) + 0.4 u(k-1)² − 0.2 y(k-1)u(k-1) + e(k) + c1 e(k-1) + c2 e(k-2).

    u is white and symmetric (E u³ = 0), so a model without u² leaves the linear tests clean and
    only the higher-order ones can see what is missing. The record holds u in "engineering units"
    (offset + gain · u).
    """
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, N)
    e = 0.05 * rng.standard_normal(N)
    v = e.copy()
    v[1:] += ma[0] * e[:-1]
    v[2:] += ma[1] * e[:-2]
    y = np.zeros(N)
    for k in range(1, N):
        y[k] = 0.5 * y[k - 1] + 0.8 * u[k - 1] + 0.4 * u[k - 1] ** 2 - 0.2 * y[k - 1] * u[k - 1] + v[k]
    return gb.Record(offset + gain * u, y, name=f"sim{seed}")


def ls(structure, rec):
    return gb.els(structure, rec, noise=0).model


def test_correct_model_passes_and_missing_nonlinear_term_fails():
    seeds = range(20)
    good = [gb.residual_tests(ls(GOOD, simulate(s)), simulate(s)) for s in seeds]
    bad = [gb.residual_tests(ls(MISSING_U2, simulate(s)), simulate(s)) for s in seeds]
    # each test is a 95 % test: a correct model passes all five in about 80 % of records
    assert sum(t.passed for t in good) >= 14
    for name in good[0].tests:
        assert sum(t[name].passed for t in good) >= 17
    # the missing u² shows in the higher-order tests every time, and only there (E u³ = 0)
    assert all(not t.nonlinear_passed for t in bad)
    assert all(not t["u2_xi"].passed for t in bad)
    assert sum(t.linear_passed for t in bad) >= 17
    worst = bad[0]["u2_xi"]
    assert worst.worst_lag == 1 and abs(worst.phi[list(worst.lags).index(1)]) > 0.5


def test_pointwise_rule_is_the_literal_reading_and_stricter():
    rec = simulate(3)
    m = ls(GOOD, rec)
    sim_ = gb.residual_tests(m, rec)
    pw = gb.residual_tests(m, rec, rule="pointwise")
    for k in sim_.tests:
        a, b = sim_[k], pw[k]
        np.testing.assert_array_equal(a.phi, b.phi)
        assert b.limit == b.band == pytest.approx(1.96 / np.sqrt(sim_.n), rel=1e-3)
        assert a.limit > a.band
        assert b.passed == (b.outside.size == 0)
        np.testing.assert_array_equal(b.outside, b.lags[np.abs(b.phi) > b.band])
    # over many records the pointwise rule fails a correct model far more often
    fails_pw = sum(not gb.residual_tests(ls(GOOD, simulate(s)), simulate(s), rule="pointwise").passed
                   for s in range(10))
    fails_sim = sum(not gb.residual_tests(ls(GOOD, simulate(s)), simulate(s)).passed for s in range(10))
    assert fails_pw > fails_sim


def test_lags_follow_the_literature():
    rec = simulate(0, N=400)
    t = gb.residual_tests(ls(GOOD, rec), rec, max_lag=7)
    assert t["xi_xi"].lags.tolist() == list(range(1, 8))
    assert t["xi_xiu"].lags.tolist() == list(range(0, 8))
    for k in ("u_xi", "u2_xi", "u2_xi2"):
        assert t[k].lags.tolist() == list(range(-7, 8))
    assert t.n == 399


def test_correlation_against_a_direct_formula():
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal(50), rng.standard_normal(50)
    lags = np.arange(-5, 6)
    phi = _xcorr([a], [b], lags)
    ac, bc = a - a.mean(), b - b.mean()
    for t, p in zip(lags, phi):
        num = sum(ac[k - t] * bc[k] for k in range(50) if 0 <= k - t < 50)
        assert p == pytest.approx(num / np.sqrt((ac @ ac) * (bc @ bc)), rel=1e-12)


def test_records_are_not_straddled():
    """Two records give the pooled sums of their own lagged products, not those of the concatenation."""
    rng = np.random.default_rng(2)
    a1, a2 = rng.standard_normal(30), rng.standard_normal(40)
    lags = np.array([1, 2])
    two = _xcorr([a1, a2], [a1, a2], lags)
    joined = _xcorr([np.concatenate([a1, a2])], [np.concatenate([a1, a2])], lags)
    assert not np.allclose(two, joined)
    m = np.concatenate([a1, a2]).mean()
    c1, c2 = a1 - m, a2 - m
    den = c1 @ c1 + c2 @ c2
    assert two[0] == pytest.approx((c1[:-1] @ c1[1:] + c2[:-1] @ c2[1:]) / den)


def test_moving_average_part_whitens_the_residuals():
    """With MA noise the LS model's residuals are coloured; the ELS model's (MA part included) are not."""
    rec = simulate(5, N=2000, ma=(0.7, 0.3))
    ls_model = ls(GOOD, rec)
    fit = gb.els(GOOD, rec, noise=2)
    assert not gb.residual_tests(ls_model, rec)["xi_xi"].passed
    t = gb.residual_tests(fit.model, rec)
    assert t["xi_xi"].passed
    # without its MA part the ELS model's equation error is coloured again
    assert not gb.residual_tests(fit.model, rec, moving_average=False)["xi_xi"].passed
    # the residuals are ELS's own fixed point
    L = 2
    np.testing.assert_allclose(t.residuals[0], fit.residuals[0][L:], atol=1e-4 * np.std(fit.residuals[0]))  # ELS stops at tol 1e-6


def test_general_noise_terms_match_the_filter():
    rec = simulate(6, N=300)
    base = gb.els(GOOD, rec, noise=0).model
    lin = gb.Model(base.structure, base.theta, noise_structure=["e(k-1)", "e(k-2)"], noise_theta=[0.3, -0.2])
    # the same MA part written with a product term of zero weight forces the sample-by-sample path
    gen = gb.Model(base.structure, base.theta, noise_structure=["e(k-1)", "e(k-2)", "e(k-1)u(k-1)"],
                   noise_theta=[0.3, -0.2, 0.0])
    r1 = gb.one_step_residuals(lin, rec)[0]
    r2 = gb.one_step_residuals(gen, rec)[0]
    np.testing.assert_allclose(r1, r2, rtol=1e-12, atol=1e-14)


@settings(max_examples=25, deadline=None)
@given(scale_u=st.floats(1e-3, 1e3), scale_y=st.floats(1e-3, 1e3), shift_u=st.floats(-1e3, 1e3))
def test_tests_do_not_depend_on_units(scale_u, scale_y, shift_u):
    assume(abs(shift_u) < 1e3 * scale_u)
    rec = simulate(7, N=300, offset=0.0, gain=1.0)
    m = ls(GOOD, rec)
    base = gb.residual_tests(m, rec)
    rec2 = gb.Record(shift_u + scale_u * rec.u, scale_y * rec.y)
    m2 = ls(GOOD, rec2)
    other = gb.residual_tests(m2, rec2)
    for k in base.tests:
        np.testing.assert_allclose(other[k].phi, base[k].phi, atol=1e-7)


def test_neural_model_residuals():
    rec = simulate(8, N=400)
    fit = gb.neural_narx(rec, ny=1, nu=1, ne=1, hidden=3, epochs=5, seed=0)
    t = gb.residual_tests(fit.model, rec)
    _, e = fit.model.predict_narmax(rec)
    np.testing.assert_allclose(t.residuals[0], e[1:])
    t0 = gb.residual_tests(fit.model, rec, moving_average=False)
    np.testing.assert_allclose(t0.residuals[0], (rec.y - fit.model.predict(rec))[1:])


def test_bad_input():
    rec = simulate(0, N=100)
    m = ls(GOOD, rec)
    with pytest.raises(ValueError, match="max_lag"):
        gb.residual_tests(m, rec, max_lag=0)
    with pytest.raises(ValueError, match="too few"):
        gb.residual_tests(m, rec, max_lag=99)
    with pytest.raises(ValueError, match="level"):
        gb.residual_tests(m, rec, level=1.0)
    with pytest.raises(ValueError, match="rule"):
        gb.residual_tests(m, rec, rule="any")
    with pytest.raises(TypeError, match="model must be a Model, a NeuralModel or a result"):
        gb.residual_tests("model", rec)
    exact = gb.Record(rec.u, m.simulate(rec))
    with pytest.raises(ValueError, match="constant"):
        gb.residual_tests(m, exact)
    flat = gb.Record(np.full(100, 3.0), rec.y)
    with pytest.raises(ValueError, match="input is constant"):
        gb.residual_tests(m, flat)


def test_result_reads_well():
    rec = simulate(0, N=400)
    t = gb.residual_tests(ls(MISSING_U2, rec), rec)
    df = t.to_frame()
    assert list(df.index) == ["xi_xi", "u_xi", "xi_xiu", "u2_xi", "u2_xi2"]
    assert not df.loc["u2_xi", "passed"]
    assert "FAIL" in repr(t["u2_xi"]) and "failed" in repr(t)


def test_figure(tmp_path):
    from matplotlib.figure import Figure

    from graybox.plots import plot_residual_tests

    rec = simulate(0, N=400)
    t = gb.residual_tests(ls(MISSING_U2, rec), rec, max_lag=10)
    fig = plot_residual_tests(t)
    assert isinstance(fig, Figure) and len(fig.axes) == 5
    titles = [ax.get_title(loc="left") for ax in fig.axes]
    assert titles[3] == "φ_(u²)'ξ(τ): FAIL" and titles[0].endswith("pass")
    # the band lines sit at ±1.96/√N and the limit lines at the Bonferroni half-width
    levels = sorted({round(abs(line.get_ydata()[0]), 12) for line in fig.axes[1].lines if line.get_linestyle() in ("--", ":")})
    assert levels == sorted({round(t["u_xi"].band, 12), round(t["u_xi"].limit, 12)})
    fig.savefig(tmp_path / "r.png", dpi=50)
    host = Figure()
    axes = host.subplots(5, 1)
    assert plot_residual_tests(t, axes=axes) is host
    with pytest.raises(ValueError, match="5 Axes"):
        plot_residual_tests(t, axes=axes[:2])


def test_an_input_held_constant_leaves_its_tests_out_and_the_others_are_made():
    # a record with a second input held at one value (a valve never moved) refused every test
    # ("input 'valve' is constant"), the model not even using it
    rec = simulate(0, N=400)
    m = ls(GOOD, rec)
    two = gb.Record(np.column_stack([rec.u, np.full(len(rec), 0.5)]), rec.y, input_names=("u", "valve"))
    with pytest.warns(UserWarning, match="4 test\\(s\\) undefined.*'valve' is constant"):
        t = gb.residual_tests(m, two)
    assert set(t.undefined) == {f"{k}:valve" for k in ("u_xi", "xi_xiu", "u2_xi", "u2_xi2")}
    assert set(t.tests) == {"xi_xi"} | {f"{k}:u" for k in ("u_xi", "xi_xiu", "u2_xi", "u2_xi2")}
    one = gb.residual_tests(m, rec)
    np.testing.assert_allclose(t["u_xi:u"].phi, one["u_xi"].phi)
    assert t.passed == one.passed


def test_fourth_moment_test_keeps_its_size_on_heavy_tailed_white_data():
    """φ_(u²)'ξ² correlates u'² with ξ²: with a Gaussian input (u'² of kurtosis 15) and Laplace noise (ξ² of
    kurtosis 88) their products are heavy-tailed, and the normal Bonferroni limit (z = 3.04 for 21 lags) rejected
    11 of these 60 white records (a correct model, its own parameters) where the test says 5 %. Its limit now takes
    the products' tails into account (an Edgeworth term in their kurtosis and skewness)."""
    model = gb.Model(gb.Structure(["u(k-1)"]), [0.8])
    rng = np.random.default_rng(59)
    rejected = {k: 0 for k in ("xi_xi", "u_xi", "xi_xiu", "u2_xi", "u2_xi2")}
    R = 60
    for _ in range(R):
        u = rng.standard_normal(300)
        y = np.concatenate([[0.0], 0.8 * u[:-1]]) + rng.laplace(size=300)
        t = gb.residual_tests(model, gb.Record(u, y), max_lag=10)
        for k in rejected:
            rejected[k] += not t[k].passed
    assert rejected["u2_xi2"] <= 0.10 * R  # 5 % expected: 3 of 60
    assert max(rejected.values()) <= 0.10 * R


def test_the_limit_is_set_on_permutations_and_older_files_read_with_their_own(tmp_path):
    model = gb.Model(gb.Structure(["u(k-1)"]), [0.8])
    rng = np.random.default_rng(3)
    u = rng.standard_normal(300)
    rec = gb.Record(u, np.concatenate([[0.0], 0.8 * u[:-1]]) + rng.laplace(size=300))
    t = gb.residual_tests(model, rec)
    c = t["u2_xi2"]
    # by hand: (κ(u'²) − 3)(κ(ξ²) − 3) and γ(u'²) γ(ξ²), means removed: the products' tails, said, not the limit's
    a, b = t.residuals[0] ** 2, (u[1:] - u[1:].mean()) ** 2  # u over the residuals' samples, k = 1 … N − 1
    kurt = lambda x: np.mean((x - x.mean()) ** 4) / np.var(x) ** 2
    skew = lambda x: np.mean((x - x.mean()) ** 3) / np.var(x) ** 1.5
    assert c.excess_kurtosis == pytest.approx((kurt(a) - 3) * (kurt(b) - 3) - 6, rel=1e-9)
    assert c.skewness == pytest.approx(skew(a) * skew(b), rel=1e-9)
    # 199 permutations at 95 %: 10 of 200 maxima (the record's own among them) at or above the limit
    assert all(x.permutations == 199 for x in t.tests.values())
    assert gb.residual_tests(model, rec, level=0.99)["u_xi"].permutations == 999
    gb.io.save(t, tmp_path / "t.json")
    back = gb.io.load(tmp_path / "t.json")
    assert back["u2_xi2"].limit == c.limit and back["u2_xi2"].permutations == 199
    # a file of an older graybox: no tails, no permutations, the Bonferroni limit
    doc = json.loads((tmp_path / "t.json").read_text(encoding="utf-8"))
    old = doc["object"]["tests"]["u_xi"]
    del old["excess_kurtosis"], old["skewness"], old["permutations"]
    old["limit"] = float(stats.norm.ppf(1 - 0.05 / 82) / np.sqrt(t.n))
    old["passed"] = bool(np.all(np.abs(t["u_xi"].phi) <= old["limit"]))
    (tmp_path / "old.json").write_text(json.dumps(doc), encoding="utf-8")
    was = gb.io.load(tmp_path / "old.json")["u_xi"]
    assert was.excess_kurtosis == was.skewness == 0.0 and was.permutations == 0
    with pytest.raises(ValueError, match="limit of tests"):  # an older file's tails edited without their limit
        gb.ResidualTests({**t.tests, "u_xi": dataclasses.replace(was, excess_kurtosis=40.0)}, t.n, t.level, t.rule,
                         t.model_name, t.residuals)
    with pytest.raises(ValueError, match="permutations"):  # not the count residual_tests uses at this level
        gb.ResidualTests({**t.tests, "u2_xi2": dataclasses.replace(c, permutations=99)}, t.n, t.level, t.rule,
                         t.model_name, t.residuals)
    with pytest.raises(ValueError, match="pointwise"):
        pw = gb.residual_tests(model, rec, rule="pointwise")
        gb.ResidualTests({**pw.tests, "u_xi": dataclasses.replace(pw["u_xi"], permutations=199)}, pw.n, pw.level,
                         pw.rule, pw.model_name, pw.residuals)
    with pytest.raises(ValueError, match="at most 1"):
        dataclasses.replace(c, limit=1.5, passed=True)
    with pytest.raises(ValueError, match="excess_kurtosis"):
        dataclasses.replace(c, excess_kurtosis=float("nan"))


def test_an_impulse_input_fails_a_wrong_gain_only_where_its_residual_stands_out():
    """With an impulse u the φ_uξ(τ) are single residuals over ‖ξ‖, and the permutation limit is the 95 % point of
    the largest of 41 residuals drawn from the record. At N = 2000 a gain 4σ off puts the record's largest residual
    at τ = 1, which 41 draws of 2000 catch in 2 % of permutations: the test fails it, and passes the right gain.
    At N = 300 the 41 draws catch it in 14 %: no gain error fails (the test assumes nothing of the noise's tails,
    and one 4σ residual in 300 is no evidence without them; the module docstring says so)."""
    model = gb.Model(gb.Structure(["u(k-1)"]), [0.8])
    for seed, n in ((7, 2000), (8, 2000), (7, 300)):
        rng = np.random.default_rng(seed)
        u = np.zeros(n)
        u[50] = 1.0
        e = rng.standard_normal(n)
        e[51] = 0.0
        right = gb.residual_tests(model, gb.Record(u, np.concatenate([[0.0], 0.8 * u[:-1]]) + e))
        assert right.passed
        off = gb.Record(u, np.concatenate([[0.0], (0.8 + 4 * np.std(e)) * u[:-1]]) + e)
        assert gb.residual_tests(model, off)["u_xi"].passed == (n == 300)
        assert gb.residual_tests(model, off, rule="pointwise")["u_xi"].worst_lag == 1


def test_the_permutations_recompute_each_test_as_the_direct_formula(monkeypatch):
    """Under the identity 'permutation' every permuted maximum is the record's own max |φ| by _xcorr (two records of
    different lengths, a skewed input): the fast path (FFT and lagged products, records apart) is the statistic."""
    from graybox.diagnostics import _residuals as R

    class Identity:
        def __init__(self, seed):
            pass

        def permuted(self, a, axis):
            return np.array(a)

    rng = np.random.default_rng(3)
    xs = [rng.standard_normal(57), rng.chisquare(1, 80)]
    inputs = {0: [rng.chisquare(2, 57), rng.standard_normal(80)], 1: [rng.uniform(size=57), rng.laplace(size=80)]}
    keys = [("xi_xi", "xi_xi", -1)] + [(f"{k}:{j}", k, j) for k in list(R.TESTS)[1:] for j in inputs]
    monkeypatch.setattr(R.np.random, "default_rng", Identity)
    limits = R._permutation_limits(xs, inputs, keys, 5, 0.95, 0)
    monkeypatch.undo()
    for key, k, j in keys:
        u = inputs[max(j, 0)]
        a, b, shift = {"xi_xi": (xs, xs, 0), "u_xi": (u, xs, 0), "xi_xiu": ([e * v for e, v in zip(xs, u)], xs, 1),
                       "u2_xi": ([v**2 for v in u], xs, 0), "u2_xi2": ([v**2 for v in u], [e**2 for e in xs], 0)}[k]
        lags = R._lags(R.TESTS[k][2], 5)
        assert limits[key] == pytest.approx(np.max(np.abs(_xcorr(a, b, lags + shift))), rel=1e-10), key


def test_the_tests_keep_their_size_with_heavy_tailed_input_and_noise():
    """Student-t (3 degrees of freedom) input and noise, the true model, N = 300: the Bonferroni limit with an
    Edgeworth term in the products' kurtosis failed φ_(u²)'ξ² on 10 of these 40 records (25 %, where the test says
    5 %; 22 % on 300 records of bench_residual_tests.py --families), its expansion in κ/N no longer small. The
    limit set on permutations of the residuals is exact under the null whatever the tails."""
    model = gb.Model(gb.Structure(["u(k-1)"]), [0.8])
    rng = np.random.default_rng(61)
    rejected = {k: 0 for k in ("xi_xi", "u_xi", "xi_xiu", "u2_xi", "u2_xi2")}
    R = 40
    for _ in range(R):
        u = rng.standard_t(3, 300)
        t = gb.residual_tests(model, gb.Record(u, np.concatenate([[0.0], 0.8 * u[:-1]]) + rng.standard_t(3, 300)))
        for k in rejected:
            rejected[k] += not t[k].passed
    assert rejected["u2_xi2"] <= 4  # 2 expected
    assert max(rejected.values()) <= 6


def test_the_permutation_limit_is_seeded():
    rec = simulate(4, N=300)
    m = ls(GOOD, rec)
    a, b = gb.residual_tests(m, rec), gb.residual_tests(m, rec, seed=0)
    c = gb.residual_tests(m, rec, seed=1)
    assert all(a[k].limit == b[k].limit for k in a.tests)
    assert any(a[k].limit != c[k].limit for k in a.tests)
    np.testing.assert_array_equal(a["u_xi"].phi, c["u_xi"].phi)
    with pytest.raises(ValueError, match="seed"):
        gb.residual_tests(m, rec, seed=-1)
    with pytest.raises(TypeError, match="seed"):
        gb.residual_tests(m, rec, seed=1.5)


def test_the_result_keeps_its_seed_and_older_files_load_with_it_unknown(tmp_path):
    # the seed that set the limits was not kept: neither the result nor its file said which limits they were
    rec = simulate(4, N=300)
    m = ls(GOOD, rec)
    c = gb.residual_tests(m, rec, seed=7)
    assert c.seed == 7 and repr(c).endswith("; seed 7)")
    assert all(c[k].limit == gb.residual_tests(m, rec, seed=c.seed)[k].limit for k in c.tests)  # its limits again
    pw = gb.residual_tests(m, rec, rule="pointwise", seed=7)
    assert pw.seed is None and "seed" not in repr(pw)  # nothing drawn
    gb.io.save(c, tmp_path / "t.json")
    assert gb.io.load(tmp_path / "t.json").seed == 7
    doc = json.loads((tmp_path / "t.json").read_text(encoding="utf-8"))
    del doc["object"]["seed"]  # as an older graybox wrote it
    (tmp_path / "old.json").write_text(json.dumps(doc), encoding="utf-8")
    old = gb.io.load(tmp_path / "old.json")
    assert old.seed is None and repr(old).endswith("; seed unknown)")
    with pytest.raises(ValueError, match="nothing was drawn"):
        dataclasses.replace(pw, seed=7)
    with pytest.raises(ValueError, match="seed"):
        dataclasses.replace(c, seed=-1)


def test_the_excess_kurtosis_of_a_correlation_with_gaussian_noise_is_the_spheres():
    # with b Gaussian, b / ‖b‖ is uniform on the sphere and φ = a·b / (‖a‖‖b‖) is exactly 2 Beta(m, m) − 1, m = (N −
    # 1)/2, whatever a: N times its excess kurtosis is −6 N / (N + 2) (Beta's −6 / (2m + 3)); the field said 0 there
    # (review59h), which reads φ as normal where its tails are lighter
    from graybox.diagnostics._residuals import _product_shape

    rng = np.random.default_rng(3)
    n = 4000
    b = rng.standard_normal(n)
    for a in (rng.standard_normal(n), rng.laplace(size=n), rng.standard_normal(n) ** 2):
        kurt, _ = _product_shape([a], [b])
        sample = (np.mean((b - b.mean()) ** 4) / np.var(b) ** 2 - 3)  # b's own excess, a sampling error about 0
        ka = np.mean((a - a.mean()) ** 4) / np.var(a) ** 2
        assert kurt == pytest.approx((ka - 3) * sample - 6 * n / (n + 2), abs=0.02)


def test_a_held_first_input_of_two_raises_no_numpy_warning():
    """Two inputs, the first held constant: its four tests are left out (said), but φ_ξξ standardised the first
    input anyway, 0/0, and numpy's 'invalid value encountered in divide' went out with a correct verdict (an error
    where warnings are)."""
    rng = np.random.default_rng(0)
    u = np.column_stack([np.full(300, 5.0), rng.standard_normal(300)])
    y = np.concatenate([[0.0], u[:-1, 1]]) + 0.1 * rng.standard_normal(300)
    model = gb.Model(gb.Structure(["v(k-1)"]), [1.0], input_names=["c", "v"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.warns(UserWarning, match="input 'c' is constant"):
            t = gb.residual_tests(model, gb.Record(u, y, input_names=["c", "v"]))
    assert list(t.tests) == ["xi_xi", "u_xi:v", "xi_xiu:v", "u2_xi:v", "u2_xi2:v"]


def test_a_tie_with_the_permutation_limit_is_no_exceedance():
    """Three residuals have six orders: the record's own, or its reverse (the same φ_ξξ(1)), is among the 199 drawn,
    and its max |φ| equals the limit in exact arithmetic; the limit's FFT and the record's direct sums put one an ulp
    above the other, and the correct model failed by round-off (φ_ξξ in 39 of 300 such records: 13 % at 95 %). A
    permutation test counts a tie as no exceedance."""
    model = gb.Model(gb.Structure(["u(k-1)"]), [0.8])
    rng = np.random.default_rng(2)
    ties = 0
    for _ in range(25):
        u = rng.standard_normal(4)
        y = np.concatenate([[0.0], 0.8 * u[:-1]]) + rng.standard_normal(4)
        t = gb.residual_tests(model, gb.Record(u, y), max_lag=1, seed=int(rng.integers(1000)))
        for v in t.tests.values():
            if abs(np.max(np.abs(v.phi)) - v.limit) <= 1e-12:
                ties += 1
                assert v.passed, v.name
    assert ties >= 5
    # a file written before (a tie kept as failed) still loads; beyond the round-off it is held to the verdict
    tie = next(v for v in t.tests.values() if v.permutations)
    top = float(np.max(np.abs(tie.phi)))
    for limit, passed in ((top * (1 - 1e-15), False), (top * (1 - 1e-15), True)):
        dataclasses.replace(tie, limit=limit, passed=passed)
    with pytest.raises(ValueError, match="passed is True"):
        dataclasses.replace(tie, limit=top * (1 - 1e-9), passed=True)
