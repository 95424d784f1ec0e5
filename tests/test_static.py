from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox import Model, Record, StaticPoints, Structure, evaluate_thetas, jsf, reference
from graybox.static._analysis import (
    DENOMINATOR_RTOL, _real_roots_companion, cluster_map, rational_static_curve, reached_equilibria, schur_stable,
    spectral_radius, vanishing_denominator,
)
from graybox.static._equilibrium_kernels import real_roots_upto_cubic


def test_eq16_clusters_from_table_ii():
    c = reference.paper_model(15).clusters()
    # eq. (16) as printed, to the table's 4-digit rounding (design.md)
    assert c["Σ0"] == pytest.approx(-0.4770, abs=5e-5)
    assert c["Σy"] == pytest.approx(0.9264, abs=5e-5)
    assert c["Σu"] == pytest.approx(8.925e-4, rel=2e-4)
    assert c["Σu²"] == pytest.approx(-1.2727e-7, rel=1e-3)
    assert c["Σyu"] == pytest.approx(2.7797e-5, rel=1e-3)


def test_eq20_clusters_from_table_iii():
    c = reference.paper_model(17).clusters()
    printed = {"Σy": 1.0299, "Σu": -1.4475e-3, "Σy²": 2.6151e-2, "Σu²": 5.6331e-6, "Σy³": 4.3873e-4,
               "Σu³": -3.4869e-9, "Σyu": -7.4151e-4, "Σy²u": -3.4620e-5, "Σyu²": 6.5291e-7}
    for k, v in printed.items():
        assert c[k] == pytest.approx(v, rel=6e-3), k   # Σyu² 6.526e-7 vs printed 6.5291e-7
    assert set(c) == set(printed)


def test_jsf_of_els15_against_eq1():
    from graybox import jsf

    assert jsf(reference.paper_model(15), reference.eq1_points()) == pytest.approx(1.618, abs=1e-3)


def test_model17_three_equilibria_at_750():
    eqs = reference.paper_model(17).equilibria(750.0)
    assert len(eqs) == 3
    stable = [e for e in eqs if e.stable]
    assert len(stable) == 1 and stable[0].ybar == pytest.approx(4.04, abs=0.01)
    assert eqs[1] is stable[0]  # the middle root
    assert reference.paper_model(17).static_curve([1650.0])[0] == pytest.approx(20.49, abs=0.01)


@pytest.mark.parametrize("eq,ubar", [(15, 750.0), (15, 1650.0), (17, 750.0), (17, 1200.0), (17, 1650.0)])
def test_static_curve_is_end_of_long_constant_input_run(eq, ubar):
    m = reference.paper_model(eq)
    ys = m.static_curve([ubar])[0]
    y = m.simulate(np.full(4000, ubar), np.full(m.max_lag, ys + 0.5))
    assert y[-1] == pytest.approx(ys, abs=1e-8)


def test_rational_form_equals_roots():
    m = reference.paper_model(15)
    u = np.linspace(750, 1650, 7)
    np.testing.assert_allclose(rational_static_curve(m.structure, m.theta, u), m.static_curve(u), rtol=1e-12)
    with pytest.raises(ValueError, match="not rational"):
        rational_static_curve(reference.STRUCTURE_17, reference.TABLE_III["ELS"], u)


def test_static_gain_matches_finite_difference():
    for eq in (15, 17):
        m = reference.paper_model(eq)
        u = np.array([800.0, 1200.0, 1600.0])
        h = 1e-3
        fd = (m.static_curve(u + h) - m.static_curve(u - h)) / (2 * h)
        np.testing.assert_allclose(m.static_gain(u), fd, rtol=1e-6)


def test_cluster_map_R():
    cm = cluster_map(reference.STRUCTURE_15)
    assert cm.R.shape == (5, 17) and np.all(cm.R.sum(axis=0) == 1)
    assert cm.names == ["Σ0", "Σu", "Σu²", "Σy", "Σyu"]
    assert cm.index("Syu") == cm.index("Σyu") == cm.index((1, 1))


@st.composite
def stable_models(draw):
    """Random rational/cubic-free structures with a contracting y part."""
    a = draw(st.lists(st.floats(-0.3, 0.3), min_size=2, max_size=2))
    b = draw(st.floats(0.001, 0.01))
    c = draw(st.floats(-1e-6, 1e-6))
    d = draw(st.floats(-2e-4, 2e-4))
    e0 = draw(st.floats(-1, 1))
    s = Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-2)", "1"])
    return Model(s, [a[0], a[1], b, c, d, e0])


@given(stable_models(), st.floats(750, 1650))
@settings(max_examples=40, deadline=None)
def test_property_static_curve_equals_simulated_steady_state(m, ubar):
    stable = [e for e in m.equilibria(ubar) if e.stable]
    assume(len(stable) == 1)
    ys = stable[0].ybar
    y = m.simulate(np.full(3000, ubar), np.full(m.max_lag, ys * 1.01 + 0.1), on_diverge="nan")
    assert y[-1] == pytest.approx(ys, rel=1e-6, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# real roots of the static polynomial: exact checks (rational arithmetic), any relative scales
# ---------------------------------------------------------------------------------------------
def _sturm_count(coef: list[Fraction]) -> int:
    """Number of distinct real roots of Σ coef[k] x^k (exact, Sturm's theorem)."""
    def trim(p):
        while p and p[-1] == 0:
            p = p[:-1]
        return p

    def rem(a, b):  # remainder of a / b, ascending coefficients
        a = list(a)
        while len(a) >= len(b) and a:
            f = a[-1] / b[-1]
            shift = len(a) - len(b)
            for i, bi in enumerate(b):
                a[shift + i] -= f * bi
            a = trim(a[:-1])
        return a

    p = trim(list(coef))
    seq = [p, trim([k * c for k, c in enumerate(p)][1:])]
    while len(seq[-1]) > 1 or (len(seq[-1]) == 1 and len(seq[-2]) > 1 and False):
        r = rem(seq[-2], seq[-1])
        if not r:
            break
        seq.append([-c for c in r])

    def changes(signs):
        s = [x for x in signs if x != 0]
        return sum(1 for a, b in zip(s, s[1:]) if a != b)

    at_minus = [(-1) ** (len(q) - 1) * (1 if q[-1] > 0 else -1) for q in seq if q]
    at_plus = [1 if q[-1] > 0 else -1 for q in seq if q]
    return changes(at_minus) - changes(at_plus)


def _poly_exact(coef: list[Fraction], x: Fraction) -> Fraction:
    v = Fraction(0)
    for c in reversed(coef):
        v = v * x + c
    return v


def _is_root_within(coef: list[Fraction], x: float, rel: float) -> bool:
    """Does Σ coef[k] t^k change sign (or vanish) on [x − rel|x|, x + rel|x|]? Exact."""
    fx = Fraction(x)
    if x == 0.0:
        return _poly_exact(coef, fx) == 0
    h = Fraction(rel) * abs(fx)
    lo, hi = _poly_exact(coef, fx - h), _poly_exact(coef, fx + h)
    return lo == 0 or hi == 0 or (lo > 0) != (hi > 0)


def _well_separated(c: np.ndarray, rel: float = 1e-3) -> bool:
    """Every pair of roots (numpy.roots, complex too) is more than ``rel`` apart, relatively."""
    r = np.roots(c[::-1])
    if r.size < 2:
        return True
    with np.errstate(invalid="ignore"):  # two zero roots: 0/0 is NaN, and NaN > rel is False (not separated)
        d = np.abs(np.subtract.outer(r, r)) / np.maximum.outer(np.abs(r), np.abs(r))
    return bool(np.min(d[~np.eye(r.size, dtype=bool)]) > rel)


coefficient = st.tuples(st.sampled_from([-1.0, 1.0]), st.floats(1.0, 9.99), st.integers(-15, 15)).map(
    lambda t: t[0] * t[1] * 10.0 ** t[2])


@given(st.lists(coefficient, min_size=4, max_size=4), st.booleans())
@settings(max_examples=200, deadline=None)
def test_property_cubic_roots_exact_over_many_decades_of_relative_scale(coef, drop_lead):
    """Each coefficient has its own scale (10^-15 … 10^15): the roots found are the real roots, all of them."""
    c = np.array(coef)
    if drop_lead:
        c[3] = 0.0  # an exact zero lowers the degree, nothing else does
    assume(_well_separated(c[: 3 if drop_lead else 4]))
    got = real_roots_upto_cubic(c[:, None, None])[0, 0]
    got = got[np.isfinite(got)]
    exact = [Fraction(v) for v in c]
    assert got.size == _sturm_count(exact)
    assert np.all(np.diff(got) > 0)  # sorted, distinct
    for x in got:
        assert _is_root_within(exact, float(x), 1e-10), (x, c)


@given(st.lists(coefficient, min_size=4, max_size=6), st.integers(-8, 8))
@settings(max_examples=100, deadline=None)
def test_property_roots_follow_a_change_of_units(coef, e):
    """y → k y maps c_p to c_p k^(1−p) and every root r to k r, whatever k (cubic and companion branches)."""
    c = np.array(coef)
    assume(_well_separated(c))
    k = 10.0 ** e * 1.7
    roots = real_roots_upto_cubic if c.size == 4 else _real_roots_companion
    a = roots(c[:, None, None])[0, 0]
    b = roots((c * k ** (1.0 - np.arange(c.size)))[:, None, None])[0, 0]
    np.testing.assert_array_equal(np.isfinite(a), np.isfinite(b))
    np.testing.assert_allclose(b[np.isfinite(b)], k * a[np.isfinite(a)], rtol=1e-10)


@given(st.lists(coefficient, min_size=5, max_size=6))
@settings(max_examples=100, deadline=None)
def test_property_companion_branch_roots_exact(coef):
    """Degree 4 and 5 (companion matrix): the real roots, all of them, over many decades of scale."""
    c = np.array(coef)
    assume(_well_separated(c))
    got = _real_roots_companion(c[:, None, None])[0, 0]
    got = got[np.isfinite(got)]
    exact = [Fraction(v) for v in c]
    assert got.size == _sturm_count(exact)
    for x in got:
        assert _is_root_within(exact, float(x), 1e-10), (x, c)


def test_quartic_model_equilibria_and_reached_state():
    """A structure with y⁴ takes the companion branch: every equilibrium, and the one a run reaches."""
    # y = 0.3 y1 + 0.2 y2 − 0.05 y1⁴ + 0.6 y1² u − …: a quartic static equation
    s = Structure(["y(k-1)", "y(k-2)", "y(k-1)^4", "u(k-1)y(k-1)^2", "1"])
    m = Model(s, [0.3, 0.2, -0.05, 0.001, 0.4])
    for ub in (-300.0, 0.0, 300.0):
        eqs = m.equilibria(ub)
        c = np.array([0.4, 0.5 - 1.0, 0.001 * ub, 0.0, -0.05])  # ascending: F(ȳ)
        ref = np.sort(np.roots(c[::-1]))
        ref = ref[np.abs(ref.imag) < 1e-9].real
        np.testing.assert_allclose([e.ybar for e in eqs], ref, rtol=1e-12)
        assert [e.stable for e in eqs] == [e.spectral_radius < 1 for e in eqs]
        for e in eqs:
            if e.stable:  # started next to a stable equilibrium, a long run ends on it
                y = m.simulate(np.full(5000, ub), np.full(2, e.ybar * (1 + 1e-3)), on_diverge="nan")
                assert y[-1] == pytest.approx(e.ybar, rel=1e-9)
                assert m.static_curve([ub], y0=e.ybar * (1 + 1e-3))[0] == pytest.approx(e.ybar, rel=1e-12)


def test_companion_root_found_when_the_first_newton_step_overshoots():
    """Degree 6 with roots −16000 … 160000: the top group of the Newton polygon starts the largest root at
    −c5/c6 ≈ 144000, whose full Newton step overshoots to ≈ 182000 with a larger |F|; that step, refused, left the
    root unpolished and then dropped as no root (an equilibrium at ȳ = 160000 silently missing)."""
    roots = [-16000.0, -50.0, -4.0, 8.0, 80.0, 160000.0]
    c = np.polynomial.polynomial.polyfromroots(roots) * 0.025  # F(ȳ), ascending
    for many in (1, 5):  # one polynomial alone, and several solved together
        got = _real_roots_companion(np.repeat(c[:, None, None], many, axis=2))[0]
        np.testing.assert_allclose(got, np.tile(roots, (many, 1)), rtol=1e-12)
    # the same through a model: y(k) = F(y(k−1)) + y(k−1), one equilibrium per root, every one listed
    s = Structure(["1", "y(k-1)"] + [f"y(k-1)^{p}" for p in range(2, 7)])
    m = Model(s, c + np.eye(7)[1])
    np.testing.assert_allclose([e.ybar for e in m.equilibria(0.0)], roots, rtol=1e-12)


def test_companion_roots_of_one_group_do_not_settle_on_one_root():
    """Degree 6 with roots −860000, −810000, −710000 in one group of the Newton polygon: Newton's steps from the
    group's starts took two of them to −810000 and none to −860000 (the equilibrium listed twice, one missing); the
    simultaneous (Aberth) steps keep each start off the roots the others take."""
    roots = [-860000.0, -810000.0, -710000.0, 1.0, 27.0, 1660.0]
    c = np.polynomial.polynomial.polyfromroots(roots)
    for many in (1, 5):  # one polynomial alone, and several solved together
        got = _real_roots_companion(np.repeat(c[:, None, None], many, axis=2))[0]
        np.testing.assert_allclose(got, np.tile(roots, (many, 1)), rtol=1e-12)


# ---------------------------------------------------------------------------------------------
# the one stability test
# ---------------------------------------------------------------------------------------------
@given(st.lists(st.floats(-2.0, 2.0), min_size=1, max_size=7))
@settings(max_examples=200, deadline=None)
def test_property_schur_cohn_agrees_with_eigenvalues(a):
    rho = spectral_radius(np.array(a))
    assume(abs(rho - 1.0) > 1e-9)
    assert schur_stable(np.array(a)) == (rho < 1.0)


# ---------------------------------------------------------------------------------------------
# units: every static path gives the same equilibria in any units of u and y
# ---------------------------------------------------------------------------------------------
def _in_units(model: Model, cu: float, cy: float) -> Model:
    """The same model with u in units cu times smaller (u' = cu u) and y' = cy y."""
    p = np.array([t.power_of("y") for t in model.structure])
    m_ = np.array([t.power_of("u") for t in model.structure])
    return model.with_theta(model.theta * cy ** (1.0 - p) * cu ** (-m_.astype(float)))


def _population(model: Model, n: int = 12) -> np.ndarray:
    rng = np.random.default_rng(1)
    return model.theta * (1 + 0.01 * rng.standard_normal((n, len(model.theta))))


@pytest.mark.parametrize("eq", [15, 17])
@pytest.mark.parametrize("cu,cy", [(1.0, 9806.65), (1e-4, 1.0), (1e4, 1e-4), (1e-4, 1e4), (2 * np.pi / 60, 1e-2),
                                   (1e4, 1e4)])
def test_every_static_path_is_the_same_in_any_units(eq, cu, cy, paper_record):
    from graybox.estimation._simulation_error import SEProblem

    m = reference.paper_model(eq)
    mu = _in_units(m, cu, cy)
    pts = reference.eq1_points()
    ptu = StaticPoints(pts.ubar * cu, pts.ybar * cy)
    rtol = 1e-9
    # single model: every equilibrium and its stability, the static curve with and without y0, the gain
    for ub in (750.0, 1200.0, 1650.0):
        a, b = m.equilibria(ub), mu.equilibria(ub * cu)
        assert [e.stable for e in a] == [e.stable for e in b]
        np.testing.assert_allclose([e.ybar * cy for e in a], [e.ybar for e in b], rtol=rtol)
    np.testing.assert_allclose(mu.static_curve(ptu.ubar) / cy, m.static_curve(pts.ubar), rtol=rtol)
    np.testing.assert_allclose(mu.static_curve(ptu.ubar, y0=ptu.ybar) / cy, m.static_curve(pts.ubar, y0=pts.ybar),
                               rtol=rtol)
    np.testing.assert_allclose(mu.static_gain(ptu.ubar) * cu / cy, m.static_gain(pts.ubar), rtol=1e-8)
    # batch path, SE objective and evaluator, on a population around the model
    th, thu = _population(m), _population(mu)
    r, ru = reached_equilibria(m.structure, th, pts.ubar, pts.ybar), reached_equilibria(mu.structure, thu, ptu.ubar,
                                                                                        ptu.ybar)
    np.testing.assert_array_equal(r.status, ru.status)
    np.testing.assert_allclose(ru.ybar / cy, r.ybar, rtol=rtol)
    rec = Record(paper_record.u, paper_record.y)
    recu = Record(paper_record.u * cu, paper_record.y * cy)
    se, seu = SEProblem(m.structure, rec, pts), SEProblem(mu.structure, recu, ptu)
    np.testing.assert_allclose(seu.static_outputs(thu) / cy, se.static_outputs(th), rtol=rtol)
    np.testing.assert_allclose(seu.jsf(thu) / cy**2, se.jsf(th), rtol=rtol)
    assert np.isfinite(se.jsf(th)).sum() >= 6  # most of the population reaches the points
    np.testing.assert_allclose(evaluate_thetas(mu.structure, thu, static=ptu)["JSF"] / cy**2,
                               evaluate_thetas(m.structure, th, static=pts)["JSF"], rtol=rtol)
    assert jsf(mu, ptu) / cy**2 == pytest.approx(jsf(m, pts), rel=rtol)


def test_model17_in_pascal_issue_numbers():
    """Issue 10: in Pa the batched path gave 4.043 / 10.746 / NaN and the SE objective J_SF = inf."""
    m = reference.paper_model(17)
    mp = _in_units(m, 1.0, 9806.65)
    ub = np.array([750.0, 1200.0, 1650.0])
    np.testing.assert_allclose(m.static_curve(ub), [4.044, 10.470, 20.485], atol=1e-3)
    y_pa = reached_equilibria(mp.structure, mp.theta[None], ub, reference.eq1(ub) * 9806.65).ybar[0]
    np.testing.assert_allclose(y_pa / 9806.65, m.static_curve(ub), rtol=1e-12)
    pts = reference.eq1_points()
    assert jsf(mp, StaticPoints(pts.ubar, pts.ybar * 9806.65)) / 9806.65**2 == pytest.approx(0.1027, abs=1e-4)


def test_one_relative_threshold_for_a_vanishing_denominator():
    # D(ū) = 1 − Σy − Σyu ū vanishes at ū = 1000 (in any units of u): no static function there
    s = Structure(["y(k-1)", "u(k-1)y(k-1)", "u(k-1)", "1"])
    th = np.array([0.5, 5e-4, 1e-3, 0.1])
    for cu in (1e-4, 1.0, 1e4):
        mu = _in_units(Model(s, th), cu, 1.0)
        assert vanishing_denominator(s, mu.theta, [1000.0 * cu]).all()
        assert not vanishing_denominator(s, mu.theta, [1000.0 * cu * (1 + 1e-6)]).any()
        with pytest.raises(ValueError, match="vanishes"):
            rational_static_curve(s, mu.theta, [1000.0 * cu])
        assert mu.equilibria(1000.0 * cu) == []
    assert DENOMINATOR_RTOL == 1e-9


def _slow_first_order(eps=5.2e-6, g=0.01):
    """y(k) = (1 − ε) y(k−1) − ε g y(k−1)² + ε u(k−1): ȳ + g ȳ² = ū, a time constant near 1/ε samples."""
    return Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [1 - eps, -eps * g, eps])


def test_a_run_proven_to_settle_is_not_run_on(monkeypatch):
    # static_curve(y0=…) ran every level's settling run to its end: 200 levels of a plant with τ ≈ 1.9e5 samples
    # took seconds (runs of ~10⁶ steps each, past the first SETTLE_STEPS). Where the recursion contracts at a
    # proven rate onto the root nearest the run's state, the run's end is known: the same root, not run on
    import graybox.static._analysis as an

    longer = []  # the pairs of the runs that go on from a first pass (given its last outputs)
    real = an.settle_runs
    monkeypatch.setattr(an, "settle_runs", lambda *a, **k: longer.append(a[12].shape[0]) or real(*a, **k))
    m = _slow_first_order()
    ub = np.linspace(0.5, 10.0, 200)
    exact = (np.sqrt(1 + 0.04 * ub) - 1) / 0.02
    alone = m.static_curve(ub)  # the one stable root (θ = 1 − ε rounded: 1e-11 off the exact one)
    np.testing.assert_allclose(alone, exact, rtol=1e-9)
    for y0 in (0.0, 2.0 * exact, exact[::-1]):
        np.testing.assert_array_equal(m.static_curve(ub, y0=y0), alone)
    assert sum(longer) == 0
    # a start beyond the basin (the unstable root at ȳ = −100 − ȳ_stable) still runs on, and diverges, as before
    with pytest.raises(ValueError, match="diverged"):
        m.static_curve([1.0], y0=-150.0)
    assert sum(longer) == 1


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4), st.floats(-3.0, 3.0), st.floats(-0.9, 0.99),
       st.lists(st.floats(-20.0, 20.0), min_size=3, max_size=3), st.integers(-3, 3), st.floats(1e-4, 1e-3),
       st.booleans())
def test_property_a_run_proven_to_settle_ends_as_its_run_does(c, ubar, pole, y0, e, eps, second):
    # the proof (a contraction at a proven rate onto the root nearest the run) only skips running on: with it and
    # without it every level of a slow plant (a pole at 1 − eps) reaches the same equilibrium, or fails for the
    # same reason, in any units (10^e), first order or second (its other pole ``pole``)
    import graybox.static._analysis as an

    s = 10.0 ** e
    p2 = pole if second else 0.0
    d = eps * (1 - p2)
    if second:
        st_ = Structure(["1", "y(k-1)", "y(k-2)", "y(k-1)y(k-2)", "y(k-1)^3", "u(k-1)"])
        theta = np.array([d * c[0] * s, 1 - eps + p2, -(1 - eps) * p2, d * c[1] / s, d * c[2] * 0.1 / s ** 2, d])
    else:
        st_ = Structure(["1", "y(k-1)", "y(k-1)^2", "y(k-1)^3", "u(k-1)"])
        theta = np.array([d * c[0] * s, 1 - eps, d * c[1] / s, d * c[2] * 0.1 / s ** 2, d])
    ub = np.array([ubar * s, 0.5 * ubar * s, c[3] * s])
    y0s = np.array(y0) * s
    proven = an.reached_equilibria(st_, theta[None, :], ub, y0s)
    real = an._contracting_runs
    try:
        an._contracting_runs = lambda *a: (np.zeros(a[2].size, dtype=bool), np.full(a[2].size, np.nan))
        ran = an.reached_equilibria(st_, theta[None, :], ub, y0s)
    finally:
        an._contracting_runs = real
    np.testing.assert_array_equal(proven.status, ran.status)
    np.testing.assert_array_equal(proven.ybar, ran.ybar)


def test_a_vanishing_denominator_at_an_input_of_minus_zero_is_said_at_zero():
    # was "ū = [-0.0]" (mend58b made the local models' texts say 0; these lists were left)
    import graybox as gb
    from graybox.static._analysis import rational_static_curve

    s = gb.parse_structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)"])
    theta = np.array([1.0, 0.5, 1.0])  # 1 − 1 − 0.5 ū vanishes at ū = 0
    with pytest.raises(ValueError, match=r"vanishes at ū = \[0\.0\]"):
        rational_static_curve(s, theta, np.array([-0.0, 1.0]))
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(-1, 1, 200), rng.normal(size=200))
    with pytest.raises(ValueError, match=r"does not exist at ū = \[0\.0\]"):
        gb.cls(s, rec, gb.StaticPoints(np.array([-0.0, 1.0]), np.array([1.0, 2.0])))


def test_surface_cluster_map_of_a_model_reads_its_keys_in_the_models_input_order():
    # a Model given as the structure: static_surface, static_surface_gain and surface_equilibria read its points in
    # the model's input order (5103455), surface_cluster_map read its keys in the structure's: with input_names
    # ('b', 'a') the key (p, m_b, m_a) = (0, 1, 0) was Σa there and Σb in model.cluster_map()
    import graybox as gb

    m = gb.Model(["y(k-1)*b(k-1)", "a(k-1)", "b(k-1)^2"], [0.5, 1.0, 0.1], input_names=("b", "a"))
    cm = gb.surface_cluster_map(m)
    assert cm.input_names == ("b", "a") == m.cluster_map().input_names
    assert cm.names[cm.index((0, 0, 1))] == "Σa" and cm.names[cm.index((1, 1, 0))] == "Σyb"
    sigma = cm.R @ m.theta
    assert sigma[cm.index((0, 2, 0))] == 0.1 and sigma[cm.index((0, 0, 1))] == 1.0
    # a Structure keeps its own order, and input_names given still win over the model's
    assert gb.surface_cluster_map(m.structure).input_names == ("a", "b")
    assert gb.surface_cluster_map(m, input_names=("a", "b")).input_names == ("a", "b")


def test_surface_statics_at_a_point_whose_input_power_overflows_give_none_without_a_warning():
    # the folded θ_t ū^a of u1(k-1)^2 at u1 = 1e200 is inf, and the cluster sums θ @ Rᵀ met inf · 0 outside any
    # errstate: a RuntimeWarning ('invalid value encountered in matmul'), an error where warnings are, from
    # equilibria and static_curve of a two-input model; one input at the same level gave [] and NaN quietly
    import warnings

    import graybox as gb

    for terms in (["y(k-1)", "u1(k-1)^2", "u2(k-1)", "y(k-1)^2"], ["y(k-1)", "u1(k-1)^2", "u2(k-1)"]):
        m = gb.Model(terms, [0.5, 1.0, 1.0, -1e-300][:len(terms)])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert m.equilibria([1e200, 1.0]) == []
            assert np.isnan(m.static_curve([[1e200, 1.0]], strict=False)).all()
            assert m.static_curve([[1.0, 1.0]])[0] == pytest.approx(4.0, rel=1e-12)  # (1 + 1) / 0.5


def test_surface_statics_where_a_folded_parameter_overflows_give_none_without_a_warning():
    # θ_t = 1e200 on u1(k-1)^3 at u1 = 1e50: ū^a is finite (1e150), θ_t ū^a is not, and the product was taken outside
    # any errstate ('overflow encountered in multiply', an error where warnings are)
    import warnings

    import graybox as gb

    m = gb.Model(["y(k-1)", "u1(k-1)^3", "u2(k-1)"], [0.5, 1e200, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert m.equilibria([1e50, 1.0]) == []
        assert np.isnan(m.static_curve([[1e50, 1.0]], strict=False)).all()
        assert np.isnan(m.static_gain([[1e50, 1.0]], strict=False)).all()
        assert m.static_curve([[0.0, 1.0]])[0] == pytest.approx(2.0, rel=1e-12)


def test_an_equilibrium_beyond_the_float_range_is_not_said_to_be_no_root_at_all():
    # y = 0.5 y + u at ū = 1e308 has its equilibrium at 2e308, past the largest float: the refusal said "the static
    # equation has no real root", which it has (hunt59b)
    m = Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    assert m.equilibria(1e308) == [] and m.equilibria(1e307)[0].ybar == pytest.approx(2e307)
    with pytest.raises(ValueError, match="no real root within the float range"):
        m.static_curve([1e308])


def test_an_equilibrium_in_the_float_range_is_found_where_the_input_power_alone_leaves_it():
    # the static equation's coefficient σ ū^m was taken as σ · (ū^m): y = 0.5 y + 1e-300 u² at ū = 1e200 (ū² = 1e400,
    # no float) was refused as having 'no real root within the float range', where its root is 2e100, and at the
    # other end y = 0.5 y + 1e300 u² at ū = 1e-200 (ū² = 0 in floats) gave ȳ = 0, silently, for 2e-100. The same
    # model in other units (u' = u / 1e200, θ' = θ · 1e400) found both: a result that depended on the units
    import warnings

    import graybox as gb

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for th, ub, yb in ((1e-300, 1e200, 2e100), (1e300, 1e-200, 2e-100)):
            for extra, ex_th in (([], []), (["y(k-1)^2"], [-1e-300 if ub < 1 else -1e-200])):
                m = gb.Model(["y(k-1)", "u(k-1)^2"] + extra, [0.5, th] + ex_th)
                near = [e for e in m.equilibria(ub) if e.stable]
                assert len(near) == 1 and near[0].ybar == pytest.approx(yb, rel=1e-9), (extra, ub, near)
                assert m.static_curve([ub])[0] == pytest.approx(yb, rel=1e-9)
        # two inputs (the surface folds θ_t ū^a): y = 0.5 y + 1e-300 u1² + u2 at (1e200, 1) and (1e-200, 1)
        m = gb.Model(["y(k-1)", "u1(k-1)^2", "u2(k-1)"], [0.5, 1e-300, 1.0])
        assert m.static_curve([[1e200, 1.0]])[0] == pytest.approx(2e100, rel=1e-9)
        m = gb.Model(["y(k-1)", "u1(k-1)^2", "u2(k-1)"], [0.5, 1e300, 1e-100])
        assert m.static_curve([[1e-200, 1.0]])[0] == pytest.approx(2e-100 + 2e-100, rel=1e-9)


def test_an_equilibrium_in_the_float_range_is_found_where_a_coefficient_of_its_equation_leaves_it():
    # y = 0.5 y + 1e-10 y u + 10 u at ū = 1e308: the numerator 10 ū = 1e309 of eq. (6) is no float, its denominator
    # 1 − 0.5 − 1e-10 ū = −1e298 is, and the equilibrium −1e11 lies well inside the float range; it was refused as
    # 'no real root within the float range'. Read over a power of two common to the level's coefficients it is found
    # (unstable: a_1 = 0.5 + 1e298); with a small y² term, the polynomial path alike
    import warnings

    import graybox as gb

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for extra, th in (([], []), (["y(k-1)^2"], [-1e-300])):
            m = gb.Model(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)"] + extra, [0.5, 1e-10, 10.0] + th)
            eq = [e for e in m.equilibria(1e308) if abs(e.ybar) < 1e300]
            assert len(eq) == 1 and eq[0].ybar == pytest.approx(-1e11, rel=1e-9)  # 10 ū / (1 − 0.5 − 1e-10 ū)
            assert not eq[0].stable
            # in range the coefficients are as they were: the same model at ū = 1e290
            assert m.equilibria(1e290)[0].ybar == pytest.approx(1e291 / (0.5 - 1e280), rel=1e-9)


@pytest.mark.parametrize("second, made", [
    (([2.0, 4.0], [2.2, 4.0]), {1.0: 1.0, 2.0: 2.1, 3.0: 3.1, 4.0: 4.0}),  # level 2 measured in both sets: averaged
    (([5.0, 4.0], [5.0, 4.0]), {1.0: 1.0, 2.0: 2.0, 3.0: 3.1, 4.0: 4.0, 5.0: 5.0}),
])
def test_the_hint_for_several_sets_of_points_makes_them_when_followed(second, made):
    """Several sets passed as static= were told to join them with StaticPoints(np.concatenate(...)), which refuses a
    level measured in two sets (and dropped their δ): the hint names StaticPoints.from_repeats where levels repeat,
    and carries the uncertainty; followed as written, it makes the points (mend60g)."""
    sets = [gb.StaticPoints([1.0, 2.0, 3.0], [1.0, 2.0, 3.1], uncertainty=0.1),
            gb.StaticPoints(*second, uncertainty=0.3)]
    rec = gb.Record(np.sin(np.arange(30.0)), np.cos(np.arange(30.0)))
    with pytest.raises(TypeError, match="several sets are one StaticPoints") as err:
        gb.pe_pareto(["y(k-1)", "u(k-1)"], rec, sets)
    code = str(err.value).split("all their points: graybox.", 1)[1].split(" (from_repeats", 1)[0]
    assert ("from_repeats" in code) == (len(made) < 5)
    points = eval(code, {"np": np, "sets": sets, "StaticPoints": gb.StaticPoints})  # noqa: S307 (the hint's code)
    assert dict(zip(points.ubar.tolist(), points.ybar.round(12).tolist())) == made
    assert points.uncertainty is not None


def test_a_one_input_models_levels_by_name_in_a_dict():
    # local_model and the surfaces took {"u": ...} by the input's name; a one-input model's static_curve said
    # "got dict" (hunt60e): the same levels by name give the same curve, gain and equilibria; a wrong name is named
    import graybox as gb

    m = gb.Model(["y(k-1)", "pump(k-1)", "pump(k-1)^2"], [0.5, 1.0, -0.1], input_names=("pump",))
    lv = np.array([0.5, 1.0, 2.0])
    np.testing.assert_array_equal(m.static_curve({"pump": lv}), m.static_curve(lv))
    np.testing.assert_array_equal(m.static_gain({"pump": lv}), m.static_gain(lv))
    assert m.equilibria({"pump": 1.0}) == m.equilibria(1.0)
    with pytest.raises(ValueError, match="'u'.*name none of the inputs"):
        m.static_curve({"u": lv})


def test_static_points_take_their_levels_by_input_name_in_a_dict():
    """StaticPoints({"a": [...], "b": [...]}, ybar) said "ubar must be an array of numbers, got dict" while
    static_curve and local_model took the same dict by input name (mend60i): the keys are the input_names, a dict
    read in another order than input_names lands on the inputs by name, and names other than input_names are refused."""
    ybar = [5.0, 6.0]
    p = StaticPoints({"a": [1.0, 2.0], "b": [3.0, 4.0]}, ybar)
    assert p.input_names == ("a", "b")
    np.testing.assert_array_equal(p.ubar, [[1.0, 3.0], [2.0, 4.0]])
    q = StaticPoints({"b": [3.0, 4.0], "a": [1.0, 2.0]}, ybar, input_names=("a", "b"))
    assert q.input_names == ("a", "b")
    np.testing.assert_array_equal(q.ubar, p.ubar)
    one = StaticPoints({"pump": [0.5, 1.0, 2.0]}, [1.0, 2.0, 3.0])
    assert one.input_names == ("pump",) and one.ubar.shape == (3,)
    assert StaticPoints({"a": 1.0, "b": 3.0}, [5.0]).ubar.tolist() == [[1.0, 3.0]]  # one number each: one point
    rep = StaticPoints.from_repeats({"pump": [1.0, 1.0, 2.0]}, [1.0, 3.0, 5.0])
    assert rep.input_names == ("pump",) and rep.ybar.tolist() == [2.0, 5.0]
    with pytest.raises(ValueError, match=r"keys \['a', 'b'\] are not the input_names \('a', 'c'\)"):
        StaticPoints({"a": [1.0, 2.0], "b": [3.0, 4.0]}, ybar, input_names=("a", "c"))
    with pytest.raises(ValueError, match=r"different numbers of levels"):
        StaticPoints({"a": [1.0, 2.0], "b": [3.0]}, ybar)
    with pytest.raises(TypeError, match=r"ubar\['b'\]"):
        StaticPoints({"a": [1.0, 2.0], "b": [3.0, "x"]}, ybar)
    with pytest.raises(ValueError, match=r"ubar: the dict names no input"):
        StaticPoints({}, [1.0])


def test_a_dict_level_of_more_than_one_dimension_is_refused_not_flattened():
    # {"a": [[1, 2], [3, 4]], "b": [1, 2, 3, 4]} was read as four points, a's matrix flattened row by row without a
    # word (a 2-D ȳ is refused as not 1-D): each key's levels are one number or a 1-D sequence
    with pytest.raises(ValueError, match=r"ubar\['a'\] must be one level or a 1-D sequence of levels, got shape "
                                         r"\(2, 2\)"):
        StaticPoints({"a": [[1.0, 2.0], [3.0, 4.0]], "b": [1.0, 2.0, 3.0, 4.0]}, [1.0, 2.0, 3.0, 4.0])
    with pytest.raises(ValueError, match=r"\['pump'\] must be one level or a 1-D sequence of levels, got shape "
                                         r"\(2, 1\)"):
        StaticPoints({"pump": np.array([[1.0], [2.0]])}, [1.0, 2.0])
    m = Model(Structure(["y(k-1)", "a(k-1)", "b(k-1)"]), [0.5, 1.0, 2.0])
    with pytest.raises(ValueError, match=r"\['a'\] must be one level or a 1-D sequence"):
        m.static_curve({"a": [[1.0, 2.0], [3.0, 4.0]], "b": [1.0, 2.0, 3.0, 4.0]})
    np.testing.assert_array_equal(m.static_curve({"a": [1.0, 2.0], "b": [3.0, 4.0]}), [14.0, 20.0])


def test_dict_levels_as_series_of_other_indexes_are_refused_not_paired_by_position():
    # {'a': Series([1, 2], index=[5, 6]), 'b': Series([3, 4], index=[6, 5])} made the points (1, 3), (2, 4), where
    # pandas aligns (1, 4), (2, 3): Series of one index are read as given, of different indexes refused by name
    import pandas as pd

    a = pd.Series([1.0, 2.0], index=[5, 6])
    same = StaticPoints({"a": a, "b": pd.Series([3.0, 4.0], index=[5, 6])}, [5.0, 6.0])
    np.testing.assert_array_equal(same.ubar, [[1.0, 3.0], [2.0, 4.0]])
    with pytest.raises(ValueError, match=r"ubar: the Series of 'a' and 'b' have different indexes \(\[5, 6\] and "
                                         r"\[6, 5\]\); the levels are paired by position, not aligned by label"):
        StaticPoints({"a": a, "b": pd.Series([3.0, 4.0], index=[6, 5])}, [5.0, 6.0])
    m = Model(Structure(["y(k-1)", "a(k-1)", "b(k-1)"]), [0.5, 1.0, 2.0])
    with pytest.raises(ValueError, match=r"different indexes"):
        m.static_curve({"a": a, "b": pd.Series([3.0, 4.0], index=[0, 1])})
    np.testing.assert_array_equal(m.static_curve({"a": a, "b": [3.0, 4.0]}), [14.0, 20.0])  # a sequence: by position


def test_a_denominator_below_the_rule_is_no_equilibrium_and_the_reason_names_the_rule():
    # y = (1 − 1e-10) y(k−1) + 1e-9 u(k−1) has ȳ = 10 ū in exact arithmetic, a stable pole at 1 − 1e-10; its
    # denominator 1e-10 is below DENOMINATOR_RTOL = 1e-9 of its terms' size (1 + |1 − 1e-10| ≈ 2), which the rule
    # counts as vanishing. local_model said only "its denominator vanishes", untrue of 1e-10: it names the rule now
    m = gb.Model(["y(k-1)", "u(k-1)"], [1 - 1e-10, 1e-9])
    assert abs(1 - (1 - 1e-10)) <= 1e-9 * (1 + (1 - 1e-10))  # the rule's test, computed here
    assert m.equilibria(1.0) == []
    lm = gb.local_model(m, 1.0, Ts=1.0)
    assert lm.status == "no equilibrium"
    assert "DENOMINATOR_RTOL = 1e-09" in lm.reason and "10⁹ times its numerator" in lm.reason
