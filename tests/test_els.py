"""Extended least squares (graybox.els)."""

import contextlib
import warnings

import numpy as np
import pytest

import graybox as gb

from graybox import Candidates, Model, Record, Structure, stacked_regressors
from graybox.estimation._extended_least_squares import ELSConvergenceWarning, ELSResult, els, noise_terms
from graybox.reproduce import section_black_box
from graybox.core._least_squares import scaled_lstsq
from graybox.core._records import Dataset
from graybox.selection._forward_regression import CandidateWarning, frols

PROCESS = Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
THETA = np.array([0.7, 0.5, -0.2, 0.3])
MA = np.array([0.8, 0.5])


def narmax_record(seed: int, n: int = 2000, sigma: float = 0.3, ma=MA) -> Record:
    """y(k) = ψ(k)ᵀθ + e(k) + c1 e(k-1) + c2 e(k-2): coloured equation error."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    e = sigma * rng.standard_normal(n)
    v = e.copy()
    for l, c in enumerate(ma, start=1):
        v[l:] += c * e[:-l]
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = THETA[0] * y[k - 1] + THETA[1] * u[k - 1] + THETA[2] * u[k - 1] ** 2 + THETA[3] + v[k]
    return Record(u, y, name=f"narmax{seed}")


def test_els_bias_is_smaller_than_least_squares_on_average():
    err_ls, err_els, ma = [], [], []
    for seed in range(8):
        rec = narmax_record(seed)
        info = els(PROCESS, rec, noise=2)
        m = info.model
        assert info.converged
        err_ls.append(info.theta_ls - THETA)
        err_els.append(m.theta - THETA)
        ma.append(m.noise_theta)
    bias_ls = np.linalg.norm(np.mean(err_ls, axis=0))
    bias_els = np.linalg.norm(np.mean(err_els, axis=0))
    # LS is biased by about 0.2 here (y(k-1) correlates with e(k-1), e(k-2)); ELS is not
    assert bias_ls > 0.1
    assert bias_els < 0.25 * bias_ls
    assert np.mean(np.linalg.norm(err_els, axis=1)) < np.mean(np.linalg.norm(err_ls, axis=1))
    np.testing.assert_allclose(np.mean(ma, axis=0), MA, atol=0.05)


def test_stopping_rule_and_info():
    tol = 1e-8
    info = els(PROCESS, narmax_record(11), tol=tol)
    m = info.model
    assert isinstance(info, ELSResult)
    assert info.converged and info.n_iter == len(info.history) >= 2
    assert info.history[-1] <= tol and all(h > tol for h in info.history[:-1])
    # the final residuals are the model's one-step prediction errors, computed recursively
    rec = narmax_record(11)
    psi, y = stacked_regressors(PROCESS, rec, start=2)
    v = y - psi @ m.theta
    xi = np.zeros(len(rec))
    for k in range(2, len(rec)):
        xi[k] = v[k - 2] - m.noise_theta[0] * xi[k - 1] - m.noise_theta[1] * xi[k - 2]
    np.testing.assert_allclose(info.residuals[0], xi, atol=1e-5 * np.abs(xi).max())
    assert np.all(info.residuals[0][:2] == 0.0)
    with pytest.raises(ValueError):
        info.residuals[0][5] = 1.0


def test_unrelaxed_els_oscillates_where_relaxed_converges():
    # why relaxation is the default: plain batch ELS does not contract for MA (0.8, 0.5)
    rec = narmax_record(0)
    with pytest.warns(ELSConvergenceWarning):
        plain = els(PROCESS, rec, relaxation=1.0, max_iter=100, direct=False)
    assert min(plain.history[-20:]) > 0.1
    relaxed = els(PROCESS, rec)
    assert relaxed.converged and relaxed.n_iter < 200


def test_noise_terms_with_input_factors():
    rec = narmax_record(9)
    m = els(PROCESS, rec, noise=Structure(["e(k-1)", "e(k-2)", "e(k-1)u(k-1)"])).model
    assert m.noise_theta.shape == (3,)
    np.testing.assert_allclose(m.noise_theta, [0.8, 0.5, 0.0], atol=0.1)


def test_non_convergence_warns_and_returns_last_iterate():
    with pytest.warns(ELSConvergenceWarning, match="did not converge in 2"):
        info = els(PROCESS, narmax_record(1), max_iter=2, tol=1e-14)
        m = info.model
    assert not info.converged and info.n_iter == 2
    assert m.noise_theta.shape == (2,)


def test_noise_part_is_never_simulated():
    rec = narmax_record(2)
    m = els(PROCESS, rec).model
    bare = Model(m.structure, m.theta)
    np.testing.assert_array_equal(m.simulate(rec), bare.simulate(rec))
    np.testing.assert_array_equal(m.predict(rec), bare.predict(rec))
    assert m.n_params == len(PROCESS)
    assert [str(t) for t in m.noise_structure] == ["e(k-1)", "e(k-2)"]
    assert "e(k-1)" in str(m)


def test_no_noise_terms_is_plain_least_squares():
    rec = narmax_record(3)
    m = els(PROCESS, rec, noise=0).model
    psi, y = stacked_regressors(PROCESS, rec)
    np.testing.assert_allclose(m.theta, scaled_lstsq(psi, y), rtol=1e-12)
    assert len(m.noise_structure) == 0 and m.noise_theta.size == 0


def test_noise_terms_flow_from_the_candidates():
    rec = narmax_record(4)
    sel = frols(Candidates(2, 2, ne=3, degree=2), rec, n_terms=4)
    assert len(sel.noise) == 3
    from_sel = els(sel, rec).model
    assert [str(t) for t in from_sel.noise_structure] == ["e(k-1)", "e(k-2)", "e(k-3)"]
    # a bare process structure gets the paper's MA(2)
    assert len(els(sel.structure, rec).model.noise_structure) == 2
    # an explicit argument wins; a structure with noise terms is split
    assert len(els(sel, rec, noise=1).model.noise_structure) == 1
    mixed = sel.structure + Structure(["e(k-2)"])
    m = els(mixed, rec).model
    assert m.structure == sel.structure and [str(t) for t in m.noise_structure] == ["e(k-2)"]
    # a Selection without noise candidates also gets MA(2)
    assert len(els(frols(Candidates(2, 2, ne=0, degree=2), rec, n_terms=4), rec).model.noise_structure) == 2


def test_engineering_units_and_several_records():
    # rpm-scale input, two records: same θ as on unit-scaled data mapped back
    recs = []
    for seed in (5, 6):
        r = narmax_record(seed, n=1200)
        recs.append(Record(1200.0 + 450.0 * r.u, r.y))
    st = Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    m = els(st, recs).model
    scaled = [Record((r.u - 0.0) / 1000.0, r.y) for r in recs]
    m2 = els(st, scaled).model
    np.testing.assert_allclose(m.theta * np.array([1.0, 1e3, 1e6, 1.0]), m2.theta, rtol=1e-6)
    np.testing.assert_allclose(m.noise_theta, m2.noise_theta, rtol=1e-6)


def test_noise_free_data_gives_zero_ma_part():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 500)
    y = Model(PROCESS, THETA).simulate(u, np.zeros(1))
    info = els(PROCESS, Record(u, y))
    m = info.model
    np.testing.assert_allclose(m.theta, THETA, atol=1e-10)
    np.testing.assert_array_equal(m.noise_theta, np.zeros(2))
    assert info.converged


def test_bad_arguments():
    rec = narmax_record(0, n=200)
    with pytest.raises(ValueError, match="noise terms e"):
        els(PROCESS, rec, noise=Structure(["y(k-1)"]))
    with pytest.raises(ValueError, match="relaxation"):
        els(PROCESS, rec, relaxation=0.0)
    with pytest.raises(ValueError, match="ne must"):
        els(PROCESS, rec, noise=-1)
    with pytest.raises(ValueError, match="max_iter"):
        els(PROCESS, rec, max_iter=0)
    with pytest.raises(ValueError, match="tol"):
        els(PROCESS, rec, tol=0.0)
    with pytest.raises(TypeError, match="direct must be True or False"):  # a wrong type, as every flag says it
        els(PROCESS, rec, direct="yes")
    with pytest.raises(ValueError, match="no process terms"):
        els(Structure(["e(k-1)"]), rec)
    # a Dataset stands for its identification record, as for every estimator
    np.testing.assert_array_equal(els(PROCESS, Dataset(rec, rec)).model.theta, els(PROCESS, rec).model.theta)
    with pytest.raises(ValueError, match="rank"):
        els(Structure(["y(k-1)", "u(k-1)", "1"]), Record(np.ones(200), rec.y))  # u constant: u ∝ 1
    with pytest.raises(ValueError, match="regression rows for .* parameters: the data are too short"):
        els(PROCESS, Record(rec.u[:6], rec.y[:6]))
    assert [str(t) for t in noise_terms(2)] == ["e(k-1)", "e(k-2)"]


# ---------------------------------------------------------------- the bundled plant


def _load_pumping():
    from graybox.datasets import load_pumping

    return load_pumping()


@pytest.mark.parametrize("degree, n_terms", [(2, 17), (3, 23)])
def test_plant_models_free_run_is_stable_on_validation(degree, n_terms):
    import warnings

    data = _load_pumping()
    # at degree 3 one cubic candidate is a combination of selected terms on this record, and FROLS says so
    with pytest.warns(CandidateWarning, match=r"u\(k-4\)u\(k-5\)\^2") if degree == 3 else contextlib.nullcontext():
        sel = frols(Candidates(ny=6, nu=6, ne=2, degree=degree), data.ident, n_terms=n_terms)
    info = els(sel, data.ident)
    m = info.model
    assert info.converged
    assert m.n_params == n_terms and len(m.noise_structure) == 2
    y = m.simulate(data.valid)  # raises DivergenceError if the free run is unstable
    assert np.all(np.isfinite(y))
    # bounded and informative: better than the validation mean as a predictor
    err = np.mean((y[m.max_lag :] - data.valid.y[m.max_lag :]) ** 2)
    assert err < np.var(data.valid.y)


def test_black_box_section_prints_table_rows_and_equations(paper_record):
    # synthetic data stand in for the plant so that the section is tested without it
    from graybox import reference

    rng = np.random.default_rng(3)
    noisy = Record(paper_record.u, paper_record.y + 0.02 * rng.standard_normal(len(paper_record)), Ts=0.05)
    data = Dataset(noisy.slice(0, 900), noisy.slice(900, None), reference.eq1_points())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        text = section_black_box(data=data)
    for col in ("JS_ident", "JS_valid", "JSF", "n_params"):
        assert col in text
    assert "ELS ℓ=2" in text and "ELS ℓ=3" in text
    assert text.count("y(k) = ") == 2


# ---------------------------------------------------------------- long records (issue 14)


def test_long_plant_record_converges_where_the_relaxed_iteration_stalls():
    # 3·10⁴ plant samples: the MA estimate (≈ 1 − 1.57 q⁻¹ + 0.72 q⁻²) is one for which the
    # relaxed map does not contract (2·min Re 1/C < 1/2); the stalled iteration hands over
    # to the direct solve of the fixed-point equations, which meets the same stopping rule
    from graybox.datasets.pumping import PumpingPlant, speed_reference
    from graybox.estimation._extended_least_squares import _contraction_limit, _ma_coefficients

    data = _load_pumping()
    st = frols(Candidates(ny=6, nu=6, ne=2, degree=2), data.ident, n_terms=17).structure
    n = 30_000
    run = PumpingPlant().simulate(speed_reference(n_samples=n + 1000, n_ident=n, seed=1), seed=1)
    rec = Record(run.u[:n], run.y[:n], Ts=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ELSConvergenceWarning)
        info = els(st, rec)
    assert info.converged and info.n_direct > 0 and info.history[-1] <= 1e-6
    c = info.model.noise_theta
    assert _contraction_limit(_ma_coefficients(c, [1, 2])) < 0.5
    # the fixed point: residuals are the recursive one-step prediction errors, orthogonal to every regressor
    psi, y = stacked_regressors(st, rec, start=6)
    xi = info.residuals[0][6:]
    v = y - psi @ info.model.theta
    rec_xi = np.zeros_like(v)
    for k in range(len(v)):
        rec_xi[k] = v[k] - c[0] * (rec_xi[k - 1] if k >= 1 else 0.0) - c[1] * (rec_xi[k - 2] if k >= 2 else 0.0)
    np.testing.assert_allclose(xi, rec_xi, atol=1e-6 * np.abs(xi).max())
    E = np.column_stack([np.r_[0.0, xi[:-1]], np.r_[0.0, 0.0, xi[:-2]]])
    A = np.column_stack([psi / np.sqrt(np.mean(psi**2, axis=0)), E / np.sqrt(np.mean(E**2, axis=0))])
    assert np.max(np.abs(A.T @ xi)) / (np.sqrt(len(xi)) * np.linalg.norm(xi)) < 1e-6


def test_an_iteration_that_cannot_converge_warns_once_in_words():
    # unrelaxed ELS oscillates for MA (0.8, 0.5), and a noise term with an input factor leaves no
    # direct solve to fall back on: the cap is reached, with one warning that says why
    rec = narmax_record(0)
    ns = Structure(["e(k-1)", "e(k-2)", "e(k-1)u(k-1)"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        info = els(PROCESS, rec, noise=ns, relaxation=1.0, max_iter=80)
    mine = [w for w in caught if issubclass(w.category, ELSConvergenceWarning)]
    assert len(mine) == 1 and not info.converged and info.n_iter == 80 and info.n_direct == 0
    text = str(mine[0].message)
    assert "did not converge in 80 iterations" in text and "returning the last iterate" in text
    assert min(info.history[-20:]) > 0.05


def test_els_names_the_terms_a_held_input_leaves_free_as_the_other_estimators_do():
    # was: "least squares: regressor matrix has rank 2 < 3 columns", while CLS, PE and SE on the same
    # record named the free terms and what would identify them (one identifiability rule for all)
    u = np.full(200, 3.0)
    y = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.2, 1.0]).simulate(u, np.zeros(1))
    rec = gb.Record(u, y + 0.01 * np.random.default_rng(0).standard_normal(200))
    msg = r"ELS process θ is not identifiable.*\['u\(k-1\)', '1'\].*record whose input moves"
    with pytest.raises(ValueError, match=msg):
        gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1", "e(k-1)"]), rec)
    with pytest.raises(ValueError, match=r"not identifiable from the identification records.*\['u\(k-1\)', '1'\]"):
        gb.cls(gb.Structure(["y(k-1)", "u(k-1)", "1"]), rec)


def test_noise_regressors_zero_on_every_row_are_named_as_such():
    # records of max_lag + 1 samples: each has one row, whose residual lags fall on the first max_lag samples (taken
    # as 0); the MA columns are zero, which ELS called "collinear with the process terms or each other (rank 0 < 2)"
    rng = np.random.default_rng(0)
    recs = [Record(rng.uniform(-1.0, 1.0, 3), rng.uniform(-1.0, 1.0, 3)) for _ in range(40)]
    with pytest.raises(ValueError, match=r"e\(k-1\), e\(k-2\) (is|are) zero on every row.*3 samples"):
        els(Structure(["y(k-1)", "u(k-1)"]), recs, noise=2)
    # four samples: e(k-1) has one nonzero row per record, e(k-2) none
    recs = [Record(rng.uniform(-1.0, 1.0, 4), rng.uniform(-1.0, 1.0, 4)) for _ in range(40)]
    with pytest.raises(ValueError, match=r"e\(k-2\) is zero on every row") as info:
        els(Structure(["y(k-1)", "u(k-1)"]), recs, noise=2)
    assert "e(k-1)," not in str(info.value)
