"""ELS, SEMP, se_pareto and se_dsf on signals near the ends of the float range: the same fit as in ordinary units.

At y near 1e155, y² overflowed (ELS's round-off threshold became inf); near 1e-200 the residuals' squares underflowed to
0; either way ELS returned least squares as if the fit were exact, its MA part skipped, and SEMP's criterion took
ln 0. Both now run, as frols does, on y and each input times a power of two (exact), and map θ back.
se_pareto (J_S 0 near y × 1e-170: every member stopped at its start) and se_dsf run so too.
"""
import warnings
from dataclasses import replace

import numpy as np
import pytest

import graybox as gb


def _plant(n: int = 300):
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    e = 0.01 * rng.standard_normal(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2 + e[k] + 0.5 * e[k - 1]
    return u, y


TERMS = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-2)y(k-2)"]


def _unit_free(theta, terms, sy, su):
    """θ of the same model in units where y is sy times and u su times larger (y(k) = Σ θ_t Π factors)."""
    out = []
    for th, t in zip(theta, gb.Structure(terms)):
        a = sum(p for s, _, p in t.factors if s in ("y", "e"))
        b = sum(p for s, _, p in t.factors if s == "u")
        out.append(th * sy / sy**a / su**b)
    return np.array(out)


@pytest.mark.parametrize("sy, su", [(1e155, 1.0), (1e-200, 1.0), (1.0, 1e-100), (1e200, 1e100)])
def test_els_is_the_same_fit_in_any_units(sy, su):
    u, y = _plant()
    base = gb.els(TERMS, gb.Record(u, y), noise=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = gb.els(TERMS, gb.Record(u * su, y * sy), noise=2)
    assert far.n_iter == base.n_iter and far.n_iter > 0  # the MA part was fitted (it was skipped)
    np.testing.assert_allclose(far.model.theta, _unit_free(base.model.theta, TERMS, sy, su), rtol=1e-12)
    np.testing.assert_allclose(far.model.noise_theta, base.model.noise_theta, rtol=1e-12)
    np.testing.assert_allclose(far.residuals[0] / sy, base.residuals[0], rtol=0, atol=1e-11 * np.std(base.residuals[0]))


@pytest.mark.parametrize("sy", [1e155, 1e-200])
def test_semp_is_the_same_search_in_any_units(sy):
    u, y = _plant()
    cand = gb.Candidates(2, 2, degree=2)
    base = gb.semp(cand, gb.Record(u, y), n_terms=4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = gb.semp(cand, gb.Record(u, y * sy), n_terms=4)
    assert list(far.structure) == list(base.structure)
    terms = [str(t) for t in base.structure]
    np.testing.assert_allclose(far.theta, _unit_free(base.theta, terms, sy, 1.0), rtol=1e-12)
    # the MSEs in output units² where they are floats (about 1e308 × 0.02 overflows, 1e-400 × 4e-4 underflows)
    for a, b in ((far.score, base.score), (far.path["score"].to_numpy(), base.path["score"].to_numpy()),
                 (far.forward_scores.to_numpy(), base.forward_scores.to_numpy())):
        a, b = np.atleast_1d(a), np.atleast_1d(b)
        own = np.isfinite(a) & (a > np.finfo(float).tiny) & np.isfinite(b)
        np.testing.assert_allclose(a[own] / sy / sy, b[own], rtol=1e-12)
        # the others left the range: 0 or inf where the data's own MSE was finite
        assert np.all(((a == 0) | np.isinf(a))[~own & np.isfinite(b)])
    # the criterion is N ln of the MSE: shifted by N ln sy² (2 N ln sy)
    shift = 2 * base.n_rows * np.log(sy)
    finite = np.isfinite(base.path["criterion"].to_numpy())
    np.testing.assert_allclose(far.path["criterion"].to_numpy()[finite] - shift,
                               base.path["criterion"].to_numpy()[finite], rtol=1e-9)


def test_els_refuses_a_parameter_beyond_the_float_range_in_the_users_units():
    # u × 1e-200: u(k-1)² is about 1e-400 of the ordinary one, its θ about 1e399: fitted on the scaled signals, it is no
    # float in the user's units, said naming the term
    u, y = _plant()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"ELS: the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the float range"):
            gb.els(TERMS, gb.Record(u * 1e-200, y), noise=2)



def test_semp_centred_names_the_datas_own_offsets_where_the_signals_were_scaled():
    # semp(centre=True) on signals scaled by a power of two (7d9347f) named the scaled signals' means in its stop
    # note: 'y − 0.564541' of an output whose mean is 1.17e180, 'u − 0.650764' of an input whose mean is 1.30 (× 1/2)
    u, y = _plant()
    cand = gb.Candidates(2, 2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = gb.semp(cand, gb.Record(u, y * 1e180), n_terms=4, centre=True)
    assert f"y − {np.mean(y * 1e180):.6g}" in far.stop and f"u − {np.mean(u):.6g}" in far.stop


def _two_input_records(ky, ku):
    out = []
    for seed in (0, 1):  # two records, two inputs, an offset (the centred path)
        rng = np.random.default_rng(seed)
        a = np.repeat(rng.uniform(0.5, 2.0, 16), 10)[:150]
        b = np.repeat(rng.uniform(-1.0, 1.0, 22), 7)[:150]
        y, e = np.zeros(150), 0.01 * rng.standard_normal(150)
        for k in range(2, 150):
            y[k] = (0.6 * y[k - 1] + 0.2 * a[k - 1] + 0.05 * a[k - 1] ** 2 + 0.1 * b[k - 2] * y[k - 2] + e[k]
                    + 0.5 * e[k - 1])
        out.append(gb.Record(np.ldexp(np.column_stack([a, b]), ku), np.ldexp(y + 48.0, ky), input_names=("a", "b")))
    return out


def _powers_of_two(theta, terms, ky, ku):
    """θ of the same model on y × 2^ky and each input × 2^ku: θ_t × 2^(ky − Σ powers × exponents), exact."""
    return np.array([np.ldexp(th, ky - sum(p * (ky if s in ("y", "e") else ku) for s, _, p in t.factors))
                     for th, t in zip(theta, gb.Structure([str(t) for t in terms]))])


@pytest.mark.parametrize("ky, ku", [(600, 0), (-700, 3), (2, -500)])
def test_els_and_frols_are_the_same_fit_bit_for_bit_on_signals_scaled_by_powers_of_two(ky, ku):
    # the law 7d9347f claims (a power of two is exact): the same θ, MA part and residuals to the last bit, where the
    # signals are scaled internally (600, -700, -500) and where they are not (2, 3), with several records and inputs
    terms = ["1", "y(k-1)", "a(k-1)", "a(k-1)^2", "b(k-1)", "y(k-1)b(k-1)"]
    ns = gb.Structure(["e(k-1)", "e(k-2)", "e(k-1)a(k-1)"])
    base, far = (gb.els(terms, _two_input_records(*k), noise=ns) for k in ((0, 0), (ky, ku)))
    assert far.n_iter == base.n_iter > 0
    assert np.array_equal(far.model.theta, _powers_of_two(base.model.theta, terms, ky, ku))
    assert np.array_equal(far.model.noise_theta, _powers_of_two(base.model.noise_theta, ns, ky, ku))
    assert all(np.array_equal(f, np.ldexp(b, ky)) for f, b in zip(far.residuals, base.residuals))
    cand = gb.Candidates(2, {"a": 2, "b": 2}, degree=2)
    for centre in (False, True):
        base, far = (gb.frols(cand, _two_input_records(*k), n_terms=5, centre=centre) for k in ((0, 0), (ky, ku)))
        assert list(far.structure) == list(base.structure)
        assert np.array_equal(far.theta, _powers_of_two(base.theta, base.structure, ky, ku))
        with np.errstate(over="ignore"):  # an RSS beyond the float range in output units² is inf, as y² there
            assert np.array_equal(far.rss, np.ldexp(base.rss, 2 * ky))


_QP_TERMS = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]


def _qp_points(ky, ku):
    ub = np.array([0.6, 1.0, 1.5, 1.9])
    return gb.StaticPoints(np.ldexp(ub, ku), np.ldexp((0.2 * ub + 0.05 * ub**2) / 0.3, ky))


@pytest.mark.parametrize("ky, ku", [(515, 0), (-700, 0), (600, 300)])
def test_cls_and_pe_are_the_same_fit_on_signals_near_the_float_ranges_ends(ky, ku):
    # at y about 1e155 the R factor of [Ψ, y] squared y (numpy: 'overflow encountered in matmul') and output_scale's y²
    # overflowed (the QP's step scale fell to 1): the same fit as in ordinary units, θ mapped by powers of two
    u, y = _plant()
    fits = [lambda r, p: gb.cls(_QP_TERMS, r).model.theta[None],
            lambda r, p: gb.pe_thetas(_QP_TERMS, r, p, lambdas=[1.0, 0.5, 1e-3])]
    for fit in fits:
        base = fit(gb.Record(u, y), _qp_points(0, 0))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            far = fit(gb.Record(np.ldexp(u, ku), np.ldexp(y, ky)), _qp_points(ky, ku))
        for b, f in zip(base, far):
            np.testing.assert_allclose(f, _powers_of_two(b, _QP_TERMS, ky, ku), rtol=1e-9)


@pytest.mark.parametrize("ky, ku", [(600, 0), (-700, 0), (0, -400), (600, 300)])
def test_cls_with_static_information_is_the_same_fit_in_any_units(ky, ku):
    # far from ordinary units the constraint rows left the float range: norms of points' rows overflowed (600), eq. (22)
    # rows over column scales overflowed (u × 2^-400), and rows of a gain bound (y × 2^-700; y × 2^600 beside
    # u × 2^300) or of a band (y × 2^-700) were read as zero rows: refused as infeasible, or dropped (the bound
    # silently ignored: θ 14 % off)
    u, y = _plant()
    fits = [lambda r, p, ky, ku: gb.cls(_QP_TERMS, r, p, how="points"),
            lambda r, p, ky, ku: gb.cls(_QP_TERMS, r, p, how="points", solver="closed"),
            lambda r, p, ky, ku: gb.cls(_QP_TERMS, r, p, how="curve"),
            lambda r, p, ky, ku: gb.cls(_QP_TERMS, r, p, how="context", constraints=gb.StaticBand(np.ldexp(0.01, ky))),
            lambda r, p, ky, ku: gb.cls(_QP_TERMS, r, p, how="context",
                                        constraints=gb.GainBounds(upper=np.ldexp(0.5, ky - ku)))]
    for fit in fits:
        base = fit(gb.Record(u, y), _qp_points(0, 0), 0, 0).model.theta
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            far = fit(gb.Record(np.ldexp(u, ku), np.ldexp(y, ky)), _qp_points(ky, ku), ky, ku).model.theta
        # in the ordinary units (the constant's θ is round-off of 0 there)
        np.testing.assert_allclose(_powers_of_two(far, _QP_TERMS, -ky, -ku), base, rtol=0,
                                   atol=1e-13 * np.max(np.abs(base)))


def test_frols_and_semp_refuse_a_chosen_term_whose_column_is_no_float_in_the_users_units():
    # y × 2^600: y(k-1)² is about 2^1200 in the user's units. Chosen on the scaled signals it was returned with a θ
    # of 1e-182, and the model's one-step predictions were NaN; els refuses that structure: the same words now
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.5, 2.0, 31), 10)[:300]
    y = np.zeros(300)
    for k in range(1, 300):
        y[k] = 0.5 * y[k - 1] + 0.1 * y[k - 1] ** 2 + 0.3 * u[k - 1] + 0.001 * rng.standard_normal()
    rec = gb.Record(u, np.ldexp(y, 600))
    cand = gb.Candidates(2, 2, degree=2)
    said = r"regressors overflow to non-finite values on these data \(e.g. y\(k-[12]\)\^2\).*rescale the signals"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=said):
            gb.els(["y(k-1)", "y(k-1)^2", "u(k-1)"], rec, noise=0)
        for centre in (False, True):
            with pytest.raises(ValueError, match=said):
                gb.frols(cand, rec, n_terms=3, include=["y(k-1)^2"], centre=centre)
            with pytest.raises(ValueError, match=said):
                gb.semp(cand, rec, n_terms=3, include=["y(k-1)^2"], centre=centre)
        # a structure whose columns are floats is chosen and fitted as in ordinary units
        base, far = gb.frols(cand, gb.Record(u, y), n_terms=3), gb.frols(cand, rec, n_terms=3)
        assert list(far.structure) == list(base.structure) and "y(k-1)^2" not in [str(t) for t in far.structure]
        assert np.array_equal(far.theta, _powers_of_two(base.theta, base.structure, 600, 0))


def test_pe_pareto_runs_on_an_output_near_the_float_ranges_end():
    # y × 2^600: the members' static errors J_SF^QR squared errors of about 2^600 ('overflow encountered in square', an
    # error under warnings-as-errors); now each mean square is taken over a power of two: inf where it is no float in
    # output units² (as y² there), the members' θ those of ordinary units
    u, y = _plant()
    base = gb.pe_pareto(_QP_TERMS, gb.Record(u, y), _qp_points(0, 0), lambdas=[1.0, 0.5])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = gb.pe_pareto(_QP_TERMS, gb.Record(u, np.ldexp(y, 600)), _qp_points(600, 0), lambdas=[1.0, 0.5])
    for b, f in zip(base.thetas, far.thetas):
        np.testing.assert_allclose(_powers_of_two(f, _QP_TERMS, -600, 0), b, rtol=0,
                                   atol=1e-13 * np.max(np.abs(b)))
    assert np.all(np.isinf(far.extra["JSF_QR"]))


@pytest.mark.parametrize("ky, ku", [(515, 0), (600, 300)])
def test_cls_on_a_dask_record_is_the_same_fit_near_the_float_ranges_ends(ky, ku):
    # the chunked reduction squared the output (its RSS, c[n]² of 2^515: 'overflow encountered in scalar power') and
    # the factor's columns (their RMS) and took the targets' mean square: as the in-memory records now, θ to round-off
    import dask.array as da

    u, y = _plant()
    base = gb.cls(_QP_TERMS, gb.Record(u, y)).model.theta
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = gb.DaskRecord(da.from_array(np.ldexp(u, ku), chunks=100), da.from_array(np.ldexp(y, ky), chunks=100))
        far = gb.cls(_QP_TERMS, rec).model.theta
    np.testing.assert_allclose(_powers_of_two(far, _QP_TERMS, -ky, -ku), base, rtol=0,
                               atol=1e-13 * np.max(np.abs(base)))


def _uncertainties_refuse(rec, pts, said: str) -> None:
    """cls_, ls_ and pe_uncertainty on ``rec`` and ``pts`` each refuse with ``said`` after their name, warning nothing."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="^cls_uncertainty: " + said):
            gb.cls_uncertainty(gb.cls(_QP_TERMS, rec, pts, how="points").model, rec, pts, how="points")
        with pytest.raises(ValueError, match="^ls_uncertainty: " + said):
            gb.ls_uncertainty(gb.els(_QP_TERMS, rec, noise=0).model, rec)
        member = gb.pe_pareto(_QP_TERMS, rec, pts, lambdas=[0.5]).models()[0]
        with pytest.raises(ValueError, match="^pe_uncertainty: " + said):
            gb.pe_uncertainty(member, rec, pts, lambda1=0.5)


def test_uncertainty_refuses_a_variance_beyond_the_float_range_in_the_users_units():
    # y × 2^-700: σ² (output units², about 2^-1400) underflowed to 0, and cls_uncertainty returned a covariance of 0
    # (every parameter known exactly, from noisy data) without a word; so did ls_uncertainty
    u, y = _plant()
    rec, pts = gb.Record(u, np.ldexp(y, -700)), _qp_points(-700, 0)
    said = (r"the noise variance σ² and the covariance are in output units².*beyond the float range in these units: "
            "rescale the signals")
    _uncertainties_refuse(rec, pts, said)
_POINTS_U = np.array([[0.6, -0.5], [1.0, 0.2], [1.5, 0.7], [1.9, -0.1], [1.2, 0.9], [0.8, 0.0], [1.7, 0.4]])
_POINTS_Y = 48.0 + (0.2 * _POINTS_U[:, 0] + 0.05 * _POINTS_U[:, 0] ** 2) / 0.4


@pytest.mark.parametrize("ky, ku", [(600, 0), (515, 0), (-700, 3), (2, -500)])
def test_cls_and_pe_are_the_same_fit_bit_for_bit_on_signals_scaled_by_powers_of_two(ky, ku):
    # the law ELS and frols hold, for the QP paths (cvxpy, the closed form): the same θ to the last bit. column_scales
    # took a far column's RMS (y(k-1) of y × 2^600, whose square overflows) over its largest |value| and as a lone
    # column, another rounding than the plain RMS of the same column in ordinary units: θ moved by ~1e-15; two
    # records, two inputs, an offset
    terms = ["1", "y(k-1)", "a(k-1)", "a(k-1)^2", "b(k-1)", "y(k-1)b(k-1)"]

    def fits(ky, ku):
        recs = _two_input_records(ky, ku)
        pts = gb.StaticPoints(np.ldexp(_POINTS_U, ku), np.ldexp(_POINTS_Y, ky), input_names=("a", "b"))
        pe = gb.pe_pareto(terms, recs, pts, lambdas=[1e-3, 0.5, 1.0])
        two = gb.StaticPoints(pts.ubar[:2], pts.ybar[:2], input_names=("a", "b"))
        return [gb.cls(terms, recs, two, how="points").model.theta, pe.thetas,
                gb.pe_thetas(terms, recs, pts, lambdas=[1e-3, 0.5, 1.0], solver="closed")], pe.extra["JSF_QR"]

    (base, base_qr), (far, far_qr) = fits(0, 0), (None, None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far, far_qr = fits(ky, ku)
    for b, f in zip(base, far):
        want = np.array([_powers_of_two(t, terms, ky, ku) for t in np.atleast_2d(b)]).reshape(b.shape)
        assert np.array_equal(f, want)
    with np.errstate(over="ignore"):  # J_SF^QR in output units²: inf where it is beyond the float range, as y² there
        np.testing.assert_array_equal(far_qr, np.ldexp(base_qr, 2 * ky))


def test_cls_refuses_a_parameter_below_the_float_range_naming_the_term():
    # u × 2^300 beside y × 2^-600: u(k-1)²'s θ is about 2^-1200, no float; cls warned 'invalid value encountered in
    # divide' (an error here) where ELS names the term
    u, y = _plant()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the float range"):
            gb.cls(TERMS, gb.Record(np.ldexp(u, 300), np.ldexp(y, -600)))


@pytest.mark.parametrize("ku", [-400, -300, 400])
def test_uncertainty_names_the_term_whose_variance_leaves_the_float_range(ku):
    # u × 2^-300: u(k-1)²'s θ about 2^600, its standard deviation about 2^589 (a float) and its variance about 2^1178
    # (none): cls_uncertainty warned 'divide by zero' (an error here) or said "cov has non-finite entries at [[3, 3]]",
    # and at u × 2^400 (a variance about 2^-1622, 0) "cov is no covariance"; at u × 2^-200 it is the ordinary units'
    u, y = _plant()
    rec, pts = gb.Record(np.ldexp(u, ku), y), _qp_points(0, ku)
    said = r"the variance of the parameter of u\(k-1\)\^2 .*beyond the float range in these units.*rescale"
    _uncertainties_refuse(rec, pts, said)


def test_uncertainty_on_a_small_input_is_the_ordinary_units_one_scaled():
    u, y = _plant()
    base = gb.cls_uncertainty(gb.cls(_QP_TERMS, gb.Record(u, y), _qp_points(0, 0), how="points").model,
                              gb.Record(u, y), _qp_points(0, 0), how="points")
    rec, pts = gb.Record(np.ldexp(u, -200), y), _qp_points(0, -200)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = gb.cls_uncertainty(gb.cls(_QP_TERMS, rec, pts, how="points").model, rec, pts, how="points")
    want = _powers_of_two(np.sqrt(np.diag(base.cov)), _QP_TERMS, 0, -200)
    np.testing.assert_allclose(np.sqrt(np.diag(far.cov))[1:], want[1:], rtol=1e-6)


@pytest.mark.parametrize("ky, ku", [(512, 0), (-480, 0), (300, -200)])
def test_evaluate_thetas_gives_the_js_of_ordinary_units_near_the_float_ranges_ends(ky, ku):
    """gb.evaluate_thetas summed squared errors in the data's own units: at y × 2^512 J_1, J_S and J_SF (about
    2^1012, floats) read inf, the sums of squares (2^1020 and more) overflowing; with a y² term the equilibria did
    too. Record and static points (or static points alone) now give the J's of ordinary units times 2^(2 ky)."""
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.5, 2.0, 30), 10)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1]
    y += 0.01 * rng.standard_normal(u.size)
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "y(k-1)^2"])
    th = np.array([[0.5, 0.3, 0.01], [0.45, 0.35, 0.0]])
    ub = np.linspace(0.6, 1.9, 4)
    base = gb.evaluate_thetas(s, th, gb.Record(u, y), gb.StaticPoints(ub, 0.6 * ub))
    # the same models on y × 2^ky, u × 2^ku: θ of y(k-1) unchanged, of u(k-1) times 2^(ky − ku), of y² times 2^-ky
    scaled = np.ldexp(th, np.array([0, ky - ku, -ky]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = gb.evaluate_thetas(s, scaled, gb.Record(np.ldexp(u, ku), np.ldexp(y, ky)),
                                 gb.StaticPoints(np.ldexp(ub, ku), np.ldexp(0.6 * ub, ky)))
        alone = gb.evaluate_thetas(s, scaled, None, gb.StaticPoints(np.ldexp(ub, ku), np.ldexp(0.6 * ub, ky)))
    for name in ("J1", "JS", "JSF"):
        np.testing.assert_allclose(np.ldexp(got[name], -2 * ky), base[name], rtol=1e-9, err_msg=name)
    np.testing.assert_allclose(np.ldexp(alone["JSF"], -2 * ky), base["JSF"], rtol=1e-9)


def test_evaluate_thetas_names_static_points_of_other_inputs_at_y_times_2_to_the_512():
    """Static points of inputs ('c', 'd') beside a record of ('a', 'b'): in ordinary units a ValueError naming
    both; at y × 2^512 (evaluated on scaled signals) a bare KeyError 'c'."""
    u = np.column_stack([np.linspace(0.5, 2.0, 40), np.linspace(2.0, 0.5, 40)])
    y = np.ldexp(np.linspace(1.0, 3.0, 40), 512)
    s = gb.parse_structure(["y(k-1)", "a(k-1)", "b(k-1)"])
    pts = gb.StaticPoints(np.array([[1.0, 1.0], [1.5, 0.7]]), np.ldexp([1.0, 1.6], 512), input_names=("c", "d"))
    with pytest.raises(ValueError, match=r"inputs \('a', 'b'\) but the static points have \('c', 'd'\)"):
        gb.evaluate_thetas(s, np.ldexp([0.5, 0.3, 0.2], [0, 512, 512]), gb.Record(u, y, input_names=("a", "b")), pts)


def test_evaluate_thetas_at_static_points_named_otherwise_for_one_input_at_y_times_2_to_the_512():
    """One input's static points may carry another name than the structure's input (StaticPoints' default 'u'
    beside terms of 'a'): in ordinary units J_SF is 0.325; at y × 2^512 the points alone set the exponents under
    their own name, ū was scaled and the a(k-1) parameter not, and J_SF read 0.90625 × 2^1024 (a ParetoSet's too)."""
    s = gb.parse_structure(["y(k-1)", "a(k-1)"])
    ub, yb = np.array([1.0, 1.5]), np.array([1.0, 1.6])
    # by hand: the equilibrium of y = 0.5 y + 0.3 ū is ȳ = 0.6 ū
    want = np.mean((0.6 * ub - yb) ** 2)
    for k in (0, 512):
        got = gb.evaluate_thetas(s, np.ldexp([0.5, 0.3], [0, k]), None, gb.StaticPoints(ub, np.ldexp(yb, k)))["JSF"]
        assert np.ldexp(got[0], -2 * k) == pytest.approx(want, rel=1e-12)


def test_uncertainty_at_y_times_2_to_the_512_is_the_ordinary_units_one_scaled():
    """At y × 2^512 the variances are floats (about 2^1024 times the ordinary units' 1e-6), but cls_uncertainty and
    ls_uncertainty warned 'overflow encountered in dot' (an error under warnings-as-errors): the stationarity check
    took the norms of the fitted values and the output (about 2^516) in the data's own units."""
    u, y = _plant()

    def sds(ky):
        rec, pts = gb.Record(u, np.ldexp(y, ky)), _qp_points(ky, 0)
        cls = gb.cls_uncertainty(gb.cls(_QP_TERMS, rec, pts, how="points").model, rec, pts, how="points")
        ls = gb.ls_uncertainty(gb.els(_QP_TERMS, rec, noise=0).model, rec)
        return [np.sqrt(np.diag(c.cov)) for c in (cls, ls)]

    base = sds(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = sds(512)
    for b, f in zip(base, far):
        np.testing.assert_allclose(f[1:], _powers_of_two(b, _QP_TERMS, 512, 0)[1:], rtol=1e-6)


def test_pe_uncertainty_at_y_times_2_to_the_512_is_the_ordinary_units_one_scaled():
    """pe_uncertainty at y × 2^512 warned 'overflow encountered in dot' (an error under warnings-as-errors) in the
    norms of the static points' ȳ (about 2^513) where the variances are floats."""
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(0.0, 2.0, 40), 10)
    y = np.zeros(u.size)
    for k in range(1, u.size):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.1 * u[k - 1] ** 2
    y += 0.02 * rng.standard_normal(u.size)
    ub = np.linspace(0.1, 1.9, 6)
    terms = ["y(k-1)", "u(k-1)", "u(k-1)^2"]

    def sds(ky):
        yb = (0.3 * ub + 0.1 * ub**2) / 0.5 + 0.01
        rec, pts = gb.Record(u, np.ldexp(y, ky)), gb.StaticPoints(ub, np.ldexp(yb, ky))
        member = gb.pe_pareto(terms, rec, pts, lambdas=[0.3]).models()[0]
        return np.sqrt(np.diag(gb.pe_uncertainty(member, rec, pts, lambda1=0.3).cov))

    base = sds(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = sds(512)
    np.testing.assert_allclose(far, _powers_of_two(base, terms, 512, 0), rtol=1e-6)


SE_TERMS = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "1"]
SE_THETA = np.array([1.2, -0.45, 0.5, -0.1, 0.05])


def _se_data(ey: int, eu: int):
    """A record and static points of the SE tests' plant with y times 2^ey and u times 2^eu, and the powers of two
    that take each term's θ from ordinary units to those (y(k) = Σ θ_t Π factors)."""
    st = gb.Structure(SE_TERMS)
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1.0, 1.0, 31), 4)[:120]
    y = gb.simulate(st, SE_THETA, u, np.zeros(2)) + 0.05 * rng.standard_normal(120)
    ub = np.linspace(-1.0, 1.0, 5)
    yb = (SE_THETA[2] * ub + SE_THETA[4]) / (1 - SE_THETA[0] - SE_THETA[1] - SE_THETA[3] * ub)
    shift = np.array([0, 0, ey - eu, -eu, ey])
    return st, gb.Record(np.ldexp(u, eu), np.ldexp(y, ey)), gb.StaticPoints(np.ldexp(ub, eu), np.ldexp(yb, ey)), shift


@pytest.mark.parametrize("method", ["gradient", "ga"])
@pytest.mark.parametrize("ey, eu", [(-565, 0), (520, 0), (-520, 300)])
def test_se_pareto_near_the_float_ranges_ends_fits_as_in_ordinary_units(method, ey, eu):
    # y × 2^-565 (about 1e-170): J_S underflowed to 0 and every member stopped at its start (θ 0.03 off the fit in
    # ordinary units, the λ1 = 0.5 and 1 members one model, every J 0); y × 2^520 (1e157): every start's free run
    # read as diverging and the sweep failed. Fitted on the signals times powers of two (exact), as output_error is,
    # each member is the same model, its J's and cost the same in the data's units (0 or inf beyond the range)
    kw = dict(lambdas=[0.5, 1.0], method=method, progress=False)
    kw.update(max_nfev=10, margin=None) if method == "gradient" else kw.update(options=gb.GAOptions(20, 5))
    st, rec, sp, _ = _se_data(0, 0)
    ref = gb.se_pareto(st, rec, sp, **kw)
    st, rec, sp, shift = _se_data(ey, eu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        got = gb.se_pareto(st, rec, sp, **kw)
    np.testing.assert_allclose(got.thetas, np.ldexp(ref.thetas, shift), rtol=1e-9)
    with np.errstate(over="ignore", under="ignore"):
        for nm in ("J1", "JS", "JSF"):
            np.testing.assert_allclose(getattr(got, nm), np.ldexp(getattr(ref, nm), 2 * ey), rtol=1e-6, atol=1e-320)
        np.testing.assert_allclose(got.extra["cost"], np.ldexp(ref.extra["cost"], 2 * ey), rtol=1e-6, atol=1e-320)
    np.testing.assert_allclose(got.extra["radius"], ref.extra["radius"], rtol=1e-9)


@pytest.mark.parametrize("ey, eu", [(-565, 0), (520, 0), (-520, 300)])
def test_se_dsf_near_the_float_ranges_ends_solves_as_in_ordinary_units(ey, eu):
    # the band from the points' uncertainty δ (0.01 in ordinary units): at y × 2^-565 the band δ² and every J_S
    # underflowed to 0, at y × 2^520 they overflowed. Solved on the signals times powers of two (exact), the model is
    # the same, its J's, the band and the start's J's the same in the data's units (0 or inf beyond the range)
    st, rec, sp, _ = _se_data(0, 0)
    start = SE_THETA * 0.9  # the one start (theta0, in the data's units): a single run, as fast as can be
    ref = gb.se_dsf(st, rec, gb.StaticPoints(sp.ubar, sp.ybar, uncertainty=0.01), theta0=start)
    st, rec, sp, shift = _se_data(ey, eu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        far = gb.StaticPoints(sp.ubar, sp.ybar, uncertainty=np.ldexp(0.01, ey))
        got = gb.se_dsf(st, rec, far, theta0=np.ldexp(start, shift))
    np.testing.assert_allclose(got.model.theta, np.ldexp(ref.model.theta, shift), rtol=1e-9)
    assert (got.in_band, got.start, got.n_iter) == (ref.in_band, ref.start, ref.n_iter)
    with np.errstate(over="ignore", under="ignore"):
        for nm in ("JS", "JSF", "band", "start_JS", "start_JSF"):
            assert getattr(got, nm) == pytest.approx(np.ldexp(getattr(ref, nm), 2 * ey), rel=1e-6, abs=1e-320), nm
        want = np.ldexp(1e-4, 2 * ey)
    assert far.band == pytest.approx(want, rel=1e-9, abs=1e-320)  # δ²'s mean: 0 or inf there, without a warning


@pytest.mark.parametrize("ky", [-505, 0])
def test_cls_uncertainty_of_a_term_the_static_points_pin_is_0_in_any_units(ky):
    # the points lie on a curve through the origin, so how="points" fixes the constant at 0 (its θ 6.7e-16, round-off):
    # its variance is 0 by the constraints, not a number. cls_uncertainty gave it the round-off (a standard deviation
    # of 2.6e-18) and at y × 2^-505 refused: "the variance of the parameter of 1 ... is beyond the float range"
    u, y = _plant()

    def sds(ky):
        rec, pts = gb.Record(u, np.ldexp(y, ky)), _qp_points(ky, 0)
        unc = gb.cls_uncertainty(gb.cls(_QP_TERMS, rec, pts, how="points").model, rec, pts, how="points")
        return unc.cov, np.sqrt(np.diag(unc.cov))

    base_cov, base = sds(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cov, far = sds(ky)
    assert not base_cov[0].any() and not cov[0].any() and not cov[:, 0].any()
    assert np.all(base[1:] > 0)
    np.testing.assert_allclose(far, _powers_of_two(base, _QP_TERMS, ky, 0), rtol=1e-6)


@pytest.mark.parametrize("ey", [-565, 520])
def test_se_uncertainty_refuses_a_variance_beyond_the_float_range_in_the_users_units(ey):
    # y × 2^-565: σ² (output units², about 2^-1130) underflowed and se_uncertainty returned a covariance of 0 (every
    # parameter known exactly, from noisy data) without a word; at y × 2^520 it warned 'overflow encountered in
    # matmul' (an error here) and said "non-finite derivatives". Now refused as cls_uncertainty refuses it; at
    # y × 2^-300 the standard deviations are the ordinary units' scaled
    st, rec, sp, _ = _se_data(0, 0)
    theta = gb.se_pareto(st, rec, sp, lambdas=[0.5], method="gradient", max_nfev=10, margin=None,
                         progress=False).thetas[0]
    base = np.sqrt(np.diag(gb.se_uncertainty(gb.Model(st, theta), rec, sp, lambda1=0.5).cov))
    for e in (-300, ey):
        st, rec, sp, shift = _se_data(e, 0)
        model = gb.Model(st, np.ldexp(theta, shift))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            if e == -300:
                sd = np.sqrt(np.diag(gb.se_uncertainty(model, rec, sp, lambda1=0.5).cov))
                np.testing.assert_allclose(sd, np.ldexp(base, shift), rtol=1e-6)
                continue
            with pytest.raises(ValueError, match=r"^se_uncertainty: the noise variance σ² and the covariance are in "
                                                 r"output units².*beyond the float range in these units: rescale"):
                gb.se_uncertainty(model, rec, sp, lambda1=0.5)


@pytest.mark.parametrize("ky", [-505, 0])
def test_pe_uncertainty_of_a_term_passes_through_pins_is_0_in_any_units(ky):
    # as cls_uncertainty's above: PassesThrough the points on a curve through the origin fixes the constant at 0, and
    # pe_uncertainty gave it the projection's round-off (a standard deviation 3e-18) and at y × 2^-505 refused "the
    # variance of the parameter of 1 ... is beyond the float range"
    u, y = _plant()

    def sds(ky, lam):
        rec, pts = gb.Record(u, np.ldexp(y, ky)), _qp_points(ky, 0)
        pt = gb.PassesThrough(pts)
        member = gb.pe_pareto(_QP_TERMS, rec, pts, lambdas=[lam], constraints=pt).member_model(0)
        unc = gb.pe_uncertainty(member, rec, pts, lambda1=lam, constraints=pt, static_sigma=np.ldexp(0.01, ky))
        return unc.cov, np.sqrt(np.diag(unc.cov))

    for lam in (0.5, 1.0):
        base_cov, base = sds(0, lam)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            cov, far = sds(ky, lam)
        assert not base_cov[0].any() and not cov[0].any() and not cov[:, 0].any()
        assert np.all(base[1:] > 0)
        np.testing.assert_allclose(far, _powers_of_two(base, _QP_TERMS, ky, 0), rtol=1e-6)


def test_an_inactive_bound_stays_inactive_and_a_broken_equality_is_refused_at_large_output_units():
    # at u + 1000 and y × 2^505 the uncertainty's tolerance 1e-6 ‖z‖ overflowed in numpy's norm (z about 1e154 squared;
    # 'overflow encountered in dot'): with the tolerance infinite the inactive bound Σy <= 0.99 (θ_y 0.70) counted as
    # active, the standard deviation of y(k-1) came out 0 and the others 0.6 of ordinary units', and a model 2^505
    # (1 in ordinary units) off its equality Σ0 = 0 was taken for the estimate; the stationarity check's allowance
    # ‖A‖ ‖z‖ eps overflowed as well, and a θ off the optimum passed for it
    u, y = _plant()
    cb = gb.ClusterBounds({"Σ0": (0.0, 0.0), "Σy": (None, 0.99)})
    ub, yb = np.array([0.6, 1.0, 1.5, 1.9]) + 1000.0, np.array([0.5, 0.9, 1.4, 1.8])

    def sds(ky):
        rec, pts = gb.Record(u + 1000.0, np.ldexp(y, ky)), gb.StaticPoints(ub, np.ldexp(yb, ky))
        fit = gb.cls(_QP_TERMS, rec, constraints=cb).model
        member = gb.pe_pareto(_QP_TERMS, rec, pts, lambdas=[0.5], constraints=cb).member_model(0)
        uncs = [gb.cls_uncertainty(fit, rec, constraints=cb),
                gb.pe_uncertainty(member, rec, pts, lambda1=0.5, constraints=cb)]
        off = replace(fit, theta=fit.theta + np.ldexp([1.0, 0.0, 0.0, 0.0], ky))
        with pytest.raises(ValueError, match="does not satisfy"):
            gb.cls_uncertainty(off, rec, constraints=cb)
        moved = replace(fit, theta=fit.theta + np.array([0.0, 0.01, 0.0, 0.0]))  # on the constraints, off the optimum
        with pytest.raises(ValueError, match="not the optimum"):
            gb.cls_uncertainty(moved, rec, constraints=cb)
        return [(unc.constraints.shape[0], np.sqrt(np.diag(unc.cov))) for unc in uncs]

    base = sds(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = sds(505)
    for (n0, b), (n1, f) in zip(base, far):
        assert n0 == n1 == 1  # Σ0 = 0 only: θ_y is 0.70, far from 0.99
        np.testing.assert_allclose(f, _powers_of_two(b, _QP_TERMS, 505, 0), rtol=1e-6)


@pytest.mark.parametrize("ky", [60, 300])
def test_cls_uncertainty_pins_no_term_the_curve_leaves_free_at_large_output_units(ky):
    # the pinned test of a3825931 scaled each column of the constraint rows by its norm: at y × 2^60 the curve's row
    # 2^60 θ_y + θ_u = c (its rows in mixed units) left y(k-1)'s entry 2^-60 of its column's, and y(k-1), which the
    # curve leaves free (standard deviation 0.0033 in any units), was given variance 0
    u, y = _plant()
    terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
    ub, yb = np.array([0.6, 1.0, 1.5, 1.9]), np.array([0.5, 0.9, 1.4, 1.8])

    def sds(ky):
        rec, pts = gb.Record(u, np.ldexp(y, ky)), gb.StaticPoints(ub, np.ldexp(yb, ky))
        return np.sqrt(np.diag(gb.cls_uncertainty(gb.cls(terms, rec, pts).model, rec, pts).cov))

    base = sds(0)
    assert np.all(base[[0, 1, 3]] > 0)  # u(k-1)^2's is 0: the points lie on a line, and the curve's u² row pins it
    np.testing.assert_allclose(sds(ky), _powers_of_two(base, terms, ky, 0), rtol=1e-6)
