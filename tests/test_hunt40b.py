"""Bug hunt 40b: eq. (22) with Σ_y estimated, decimation advice, large-grid reports, k-step prediction."""

import numpy as np
import pytest

import graybox as gb
from _reports import undrawn_figures

# a rational plant whose denominator varies with ū (Σyu ≠ 0); the structure is closed under shifts of u
TRUE = gb.Structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)", "u(k-1)^2", "1"])
THETA = np.array([0.5, 0.15, 0.3, -0.05, 0.2])
UB = np.linspace(0.25, 1.75, 7)


def _record(seed: int, n: int = 400, noise: float = 0.02, offset: float = 0.0) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    y = gb.Model(TRUE, THETA).simulate(u, np.zeros(1)) + noise * rng.standard_normal(n)
    return gb.Record(u + offset, y)


def _points(offset: float = 0.0) -> gb.StaticPoints:
    return gb.StaticPoints(UB + offset, gb.Model(TRUE, THETA).static_curve(UB))


@pytest.mark.parametrize("solver", ["clarabel", "osqp"])
@pytest.mark.parametrize("offset", [3000.0, 1e4])
def test_the_qp_meets_eq22_with_a_free_sigma_y_when_u_is_far_from_its_zero(solver, offset):
    """u = 3000 ± 1 (rpm about a high speed): the equality rows, independent in the scaled parameters, fell under
    the rank cut once carried into the QP's ill-conditioned basis; one was dropped without a word and the model's
    static function missed the curve it was said to equal by 0.029 (the points' spread is 0.5)."""
    pts = _points(offset)
    curve = gb.StaticCurve.fit(pts, degree=2)
    rec = _record(1, offset=offset)
    closed = gb.cls(TRUE, rec, curve, solver="closed").model
    model = gb.cls(TRUE, rec, curve, solver=solver).model
    spread = np.ptp(pts.ybar)
    np.testing.assert_allclose(model.static_curve(pts.ubar), curve(pts.ubar), rtol=0, atol=1e-6 * spread)
    assert model.clusters()["Σy"] == pytest.approx(closed.clusters()["Σy"], abs=1e-5)
    th = gb.pe_thetas(TRUE, rec, pts, lambdas=[0.5], constraints=gb.CurveEquality(curve), solver=solver)[0]
    np.testing.assert_allclose(gb.Model(TRUE, th).static_curve(pts.ubar), curve(pts.ubar), rtol=0,
                               atol=1e-6 * spread)


@pytest.mark.parametrize("offset", [0.0, 3000.0, 1e4])
def test_the_qp_s_free_sigma_y_estimate_is_the_constrained_optimum_its_covariance_takes(offset):
    """Carried into the QP's basis (cond(Ψ)), eq. (22)'s rows held only to eps·cond: at u = 3000 ± 1 the QP's Σ_y was
    2e-7 off the constrained least squares, and cls_uncertainty refused cls's own estimate as no optimum."""
    pts = _points(offset)
    curve = gb.StaticCurve.fit(pts, degree=2)
    rec = _record(1, offset=offset)
    closed = gb.cls(TRUE, rec, curve, solver="closed").model
    model = gb.cls(TRUE, rec, curve).model
    assert model.clusters()["Σy"] == pytest.approx(closed.clusters()["Σy"], abs=1e-8)
    base = gb.cls_uncertainty(gb.cls(TRUE, _record(1), gb.StaticCurve.fit(_points(), degree=2)).model, _record(1),
                              gb.StaticCurve.fit(_points(), degree=2))
    unc = gb.cls_uncertainty(model, rec, curve)
    # Σ_y's standard error does not depend on where u's zero is
    assert np.sqrt(unc.cov[0, 0]) == pytest.approx(np.sqrt(base.cov[0, 0]), rel=1e-5)


def _oversampled(n: int = 4000) -> gb.Record:
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 1, n // 100 + 1), 100)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.98 * y[k - 1] + 0.02 * u[k - 1] + 0.01 * u[k - 1] ** 2
    return gb.Record(u, y + 0.001 * rng.standard_normal(n), Ts=0.01)


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e150])
def test_decimation_advice_does_not_depend_on_the_output_s_unit(scale):
    """The autocorrelations are unit-free, but y'² of an output in 1e-150 units underflowed (τ_y² lost, q 7 for 6,
    a RuntimeWarning of 0/0) and in 1e-300 units the advice was 'no minimum'; 1e150 overflowed."""
    rec = _oversampled()
    base = gb.decimation_advice(rec)
    moved = gb.decimation_advice(gb.Record(rec.u, rec.y * scale, Ts=rec.Ts))
    assert (moved.q, moved.q_range, moved.tau_y, moved.tau_y2) == (base.q, base.q_range, base.tau_y, base.tau_y2)


@pytest.mark.parametrize("kind, options", [("aprbs", {"hold": (5, 10)}), ("staircase", {"hold": 10}),
                                           ("prbs", {"hold": 5}), ("multisine", {"frequencies": (0.1, 0.5)})])
def test_design_input_over_a_range_wider_than_the_largest_float_stays_in_it(kind, options):
    """low = −1e308, high = 1e308 are finite levels, but high − low overflows: the signal was ±inf and NaN (with
    RuntimeWarnings), a made-up input."""
    x = gb.design_input(kind, 100, low=-1e308, high=1e308, **options)
    assert np.all(np.isfinite(x)) and x.min() == -1e308 and x.max() == 1e308
    # the same levels as on a range of ordinary width, in proportion
    y = gb.design_input(kind, 100, low=-1.0, high=1.0, **options)
    np.testing.assert_allclose(x / 1e308, y, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("offset", [3000.0, 3e4])
def test_equalities_that_fix_theta_whole_are_met_exactly_by_the_qp(offset):
    """Eq. (22) with a given Σ*_y fixes every parameter of this structure (five clusters, five terms); the QP's θ met
    the rows only to eps·cond of its basis: Σ_y = 0.67540098 for Σ*_y = 0.6754 at u = 3e4 ± 1 (before the rows were
    kept, the static function missed the curve by 0.026)."""
    pts = _points(offset)
    curve = gb.StaticCurve.fit(pts, degree=2)
    rec = _record(1, offset=offset)
    closed = gb.cls(TRUE, rec, curve, reference=0.6754, solver="closed").model
    for solver in ("clarabel", "osqp"):
        model = gb.cls(TRUE, rec, curve, reference=0.6754, solver=solver).model
        assert model.clusters()["Σy"] == pytest.approx(0.6754, abs=1e-12)
        np.testing.assert_allclose(model.theta, closed.theta, rtol=1e-12)


@pytest.mark.parametrize("solver", ["closed", "clarabel"])
def test_eq22_with_a_free_sigma_y_keeps_every_row_far_from_the_input_s_zero(solver):
    """Σ_{u^e} + c_e Σ_y = c_e: far from u's zero (u = 1e6 ± 1) every row is c_e Σ_y and little else, the rows agree to
    1e-12 and one fell to the rank cut in the scaled parameters themselves: the static function missed the curve by
    0.036 (7 % of the points' span). Written against one pivot row the others leave Σ_y out, and all are kept."""
    pts = _points(1e6)
    curve = gb.StaticCurve.fit(pts, degree=2)
    model = gb.cls(TRUE, _record(1, offset=1e6), curve, solver=solver).model
    np.testing.assert_allclose(model.static_curve(pts.ubar), curve(pts.ubar), rtol=0, atol=1e-2 * np.ptp(pts.ybar))


def test_eq22_on_a_surface_with_a_free_sigma_y_does_not_depend_on_the_inputs_zeros():
    """Two inputs, u1 offset by 1000: a surface row fell to the rank cut in the QP's basis and the free run moved by
    0.0077 (level 0.08); with every row kept, the rows leaning on Σ_y still moved it by 4e-6. Now the same model."""
    rng = np.random.default_rng(0)
    n = 1200
    st_ = gb.parse_structure(["1", "y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)^2", "u1(k-1)u2(k-1)", "u2(k-1)^2",
                              "u1(k-1)y(k-1)"])
    th = np.array([0.1, 0.6, 0.3, -0.2, 0.05, 0.02, -0.03, 0.05])
    u = np.column_stack([np.repeat(rng.uniform(0, 2, n // 30 + 1), 30)[:n],
                         np.repeat(rng.uniform(0, 2, n // 45 + 1), 45)[:n]])
    plant = gb.Model(st_, th, input_names=("u1", "u2"))
    y = plant.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(n)
    grid = np.array([[a, b] for a in np.linspace(0.2, 1.8, 4) for b in np.linspace(0.2, 1.8, 4)])
    runs = []
    for off in (np.zeros(2), np.array([1000.0, 5.0])):
        rec = gb.Record(u + off, y, input_names=("u1", "u2"))
        surface = gb.StaticSurface.fit(gb.StaticPoints(grid + off, plant.static_curve(grid)), 2)
        runs.append(gb.cls(st_, rec, surface).model.simulate(rec))
    np.testing.assert_allclose(runs[1], runs[0], rtol=1e-8, atol=1e-8 * np.abs(runs[0]).max())


@pytest.fixture(scope="module")
def ls_store(tmp_path_factory):
    from graybox import experiments as gx

    terms = ["y(k-2)", "u(k-2)", "u(k-1)^2"]
    structures = [gx.StructureSpec(f"s{i}", terms=["1", "y(k-1)", "u(k-1)", t]) for i, t in enumerate(terms)]
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structures, [gx.Variant("LS", "ls")], name="few")
    path = tmp_path_factory.mktemp("hunt40b") / "few.sqlite"
    gx.run_grid(grid, path, progress=False)
    return path


def test_a_report_of_unranked_structures_does_not_call_the_ones_it_draws_the_best(ls_store, tmp_path, monkeypatch):
    """With no model in the band no structure has a rank, and max_structures drew the grid's first ones under the title
    'the 2 best of 3 structures by rank'; with some in the band, the unranked ones it adds are said as such."""
    from graybox import experiments as gx

    undrawn_figures(monkeypatch)  # three reports read for their summary.txt

    gx.write_report(ls_store, tmp_path / "none", band=1e-12, max_structures=2)
    summary = (tmp_path / "none" / "summary.txt").read_text()
    assert "best of" not in summary
    assert "the figures draw the first 2 of 3 structures in the grid's order (none has a qualifying model)" in summary
    jsf = gx.leaderboard(ls_store, rule="chosen")["JSF"].to_numpy(float)
    band = float(np.sort(jsf)[0]) * 1.0001  # one structure in the band
    gx.write_report(ls_store, tmp_path / "one", band=band, max_structures=2)
    assert "the figures draw the 1 ranked and the first 1 unranked of 3 structures" in (
        tmp_path / "one" / "summary.txt").read_text()
    gx.write_report(ls_store, tmp_path / "all", band=float(jsf.max()) * 2, max_structures=2)
    summary = (tmp_path / "all" / "summary.txt").read_text()
    assert "the figures draw the 2 best of 3 structures (max_structures=2)" in summary


def test_a_bound_on_a_theta_the_equalities_fix_is_checked_at_that_theta():
    """y(k-1), u(k-1), 1 under eq. (22) with Σ*_y given: the equalities fix θ, and the static gain is the curve's 2.
    A lower gain bound of 2 + 2e-12 (met to round-off) ended in Clarabel's status 'user_limit', an InfeasibleError
    that blamed the solver, with cvxpy's overflow RuntimeWarning; a bound of 3 is refused naming the constraints."""
    st_ = gb.Structure(["y(k-1)", "u(k-1)", "1"])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 21), 20)[:400]
    y = gb.Model(st_, np.array([0.7, 0.6, 0.1])).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(400)
    curve = gb.StaticCurve.polynomial([1 / 3, 2.0], domain=(0.01, 1.8))
    for lower in (2.0, 2.0 + 2e-12):
        model = gb.cls(st_, gb.Record(u, y), curve, reference=0.7, constraints=gb.GainBounds(lower=lower)).model
        np.testing.assert_allclose(model.theta, [0.7, 0.6, 0.1], rtol=1e-12)
    with pytest.raises(gb.InfeasibleError, match=r"the equalities fix θ, and it misses .*static gain in \[3, inf\]"):
        gb.cls(st_, gb.Record(u, y), curve, reference=0.7, constraints=gb.GainBounds(lower=3.0))
