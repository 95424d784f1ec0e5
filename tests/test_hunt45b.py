"""hunt45b: trusting a model (residual tests, covariances, bands, bootstrap) and the long-record path."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb

from conftest import traced_peak

STRUCTURE = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]



def plant(N: int = 600, seed: int = 0, noise: float = 0.05) -> gb.Record:
    """y(k) = 0.6 y(k−1) + 0.5 u(k−1) − 0.2 u(k−1)² + 0.3 + e(k), a staircase input in [0.5, 1.5]."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 1.5, N // 10 + 1), 10)[:N]
    y = np.zeros(N)
    for k in range(1, N):
        y[k] = 0.6 * y[k - 1] + 0.5 * u[k - 1] - 0.2 * u[k - 1] ** 2 + 0.3 + noise * rng.standard_normal()
    return gb.Record(u, y)


# --------------------------------------------------------------------------------------------
# a DaskRecord's samples are read only when it is reduced: a NaN there is the data's, not an overflow
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("signal", ["u", "y"])
@pytest.mark.parametrize("fit", ["frols", "frols-gram", "cls", "pe_thetas"])
def test_a_dask_record_with_a_nan_sample_is_refused_naming_the_sample(signal, fit):
    da = pytest.importorskip("dask.array")
    rec = plant(N=2000)
    u, y = rec.u.copy(), rec.y.copy()
    (u if signal == "u" else y)[1234] = np.nan
    dr = gb.DaskRecord(da.from_array(u, chunks=500), da.from_array(y, chunks=500), name="long")
    points = gb.StaticPoints([0.5, 1.0, 1.5], [1.0, 2.0, 3.0])
    run = {"frols": lambda: gb.frols(gb.Candidates(ny=2, nu=2, degree=2), dr, n_terms=3),
           "frols-gram": lambda: gb.frols(gb.Candidates(ny=2, nu=2, degree=2), dr, n_terms=3, method="gram"),
           "cls": lambda: gb.cls(STRUCTURE, dr, points),
           "pe_thetas": lambda: gb.pe_thetas(STRUCTURE, dr, points, lambdas=[0.5])}[fit]
    with pytest.raises(ValueError, match=rf"long.*{signal} has 1 non-finite value.*index 1234") as info:
        run()
    assert "overflow" not in str(info.value)


# --------------------------------------------------------------------------------------------
# noise-free data: a member that fits exactly is the optimum, whatever direction its round-off points in
# --------------------------------------------------------------------------------------------
def _static_of_plant(ubar: np.ndarray) -> np.ndarray:
    return (0.5 * ubar - 0.2 * ubar**2 + 0.3) / 0.4


@pytest.mark.parametrize("offset", [0.0, 1e4])
@pytest.mark.parametrize("lam", [0.5, 1.0])
def test_se_uncertainty_of_an_exact_fit_on_noise_free_data_says_no_stationarity_warning(offset, lam):
    rec = plant(noise=0.0)
    rec = gb.Record(rec.u, rec.y + offset)
    ub = np.linspace(0.5, 1.5, 6)
    points = gb.StaticPoints(ub, _static_of_plant(ub) + offset)
    member = gb.se_pareto(STRUCTURE, rec, points, lambdas=[lam], method="gradient").member_model(0)
    true = np.array([0.3 + 0.4 * offset, 0.6, 0.5, -0.2])  # the structure's order: 1, y(k-1), u(k-1), u(k-1)^2
    np.testing.assert_allclose(member.theta, true, rtol=1e-9, atol=1e-9)  # the exact optimum
    with warnings.catch_warnings():
        warnings.simplefilter("error", gb.UncertaintyWarning)
        unc = gb.se_uncertainty(member, rec, points, lambda1=lam, static_sigma=0.0)
    assert np.all(unc.std <= 1e-9 * (1 + np.abs(true)))


# --------------------------------------------------------------------------------------------
# the chunked reduction names an input the records lack, as the in-memory regressors do (not KeyError)
# --------------------------------------------------------------------------------------------
SPEED = ["1", "y(k-1)", "speed(k-1)"]


@pytest.mark.parametrize("fit", ["cls", "pe_thetas"])
def test_a_dask_record_without_the_terms_input_is_refused_naming_it(fit):
    da = pytest.importorskip("dask.array")
    rec = plant(N=1000)
    dr = gb.DaskRecord(da.from_array(rec.u, chunks=300), da.from_array(rec.y, chunks=300), name="long")
    points = gb.StaticPoints([0.5, 1.0, 1.5], [1.0, 2.0, 3.0])
    run = {"cls": lambda: gb.cls(SPEED, dr, points),
           "pe_thetas": lambda: gb.pe_thetas(SPEED, dr, points, lambdas=[0.5])}[fit]
    with pytest.raises(ValueError, match=r"long.*input 'speed'.*inputs are \('u',\)"):
        run()


def test_r_factor_of_records_in_memory_names_the_missing_input():
    from graybox.core._gram import gram_sums, r_factor

    terms = gb.Structure(SPEED).terms
    for reduce in (r_factor, gram_sums):
        with pytest.raises(ValueError, match=r"input 'speed'.*inputs are \('u',\)"):
            reduce(terms, plant(N=300), 1)


# --------------------------------------------------------------------------------------------
# regressors that overflow on the data are refused by name, not as "non-finite derivatives"
# --------------------------------------------------------------------------------------------
def test_ls_uncertainty_names_the_regressor_that_overflows_on_the_data():
    rec = plant()
    huge = gb.Record(rec.u * 1e160, rec.y)  # legal samples; u(k-1)^2 is 1e320
    theta = [0.3, 0.6, 0.5e-160, -0.2e-320]
    ls = gb.Model(gb.Structure(STRUCTURE), theta)
    els = gb.Model(gb.Structure(STRUCTURE), theta, gb.Structure(["e(k-1)"]), [0.3])
    for model in (ls, els):
        with pytest.raises(ValueError, match=r"regressors overflow.* \(e\.g\. u\(k-1\)\^2\)") as info:
            gb.ls_uncertainty(model, huge)
        assert "derivatives" not in str(info.value)


# --------------------------------------------------------------------------------------------
# long records: the Monte Carlo band's n_samples × N runs are refused before allocation when they would not fit
# --------------------------------------------------------------------------------------------
def test_monte_carlo_simulation_band_that_would_not_fit_is_refused_naming_the_bytes(monkeypatch):
    import graybox.core._gram as gram

    rec = plant()
    unc = gb.ls_uncertainty(gb.els(STRUCTURE, rec, noise=0), rec)
    runs = 8 * 1000 * len(rec)  # the default 1000 draws' free runs, float64
    monkeypatch.setattr(gram, "available_memory", lambda: runs)  # room for the runs once, not for the band's copies
    with pytest.raises(MemoryError, match=r"simulation_band.*1000 Monte Carlo.*600 samples.*needs .* bytes.*method='delta'"):
        gb.simulation_band(unc, rec, method="monte-carlo")
    # the delta band streams its sensitivities: memory independent of the draws, it still runs
    assert gb.simulation_band(unc, rec).std.shape == (len(rec),)
    monkeypatch.setattr(gram, "available_memory", lambda: 100 * runs)
    assert gb.simulation_band(unc, rec, method="monte-carlo", n_samples=10).n_samples == 10


# --------------------------------------------------------------------------------------------
# long records: ls_uncertainty holds no more copies of Ψ than the estimate did, and reduces in chunks where Ψ won't fit
# --------------------------------------------------------------------------------------------
def test_ls_uncertainty_needs_no_more_memory_than_the_least_squares_fit():
    rec = plant(N=200_000)
    short = rec.slice(0, 2000)
    gb.ls_uncertainty(gb.els(STRUCTURE, short, noise=0), short)  # imports and compiled kernels out of the count
    model = gb.els(STRUCTURE, rec, noise=0)
    psi_bytes = 8 * len(STRUCTURE) * len(rec)
    peak = traced_peak(lambda: gb.ls_uncertainty(model, rec))
    assert peak <= 5 * psi_bytes, f"ls_uncertainty peaked at {peak / psi_bytes:.1f} × Ψ"


def test_ls_uncertainty_of_records_that_would_not_fit_is_reduced_in_chunks(monkeypatch):
    import graybox.estimation._prediction_error as pe

    rec = gb.Record(plant().u + 1e3, plant().y + 1e4)  # at an offset: the factor's accuracy counts
    model = gb.els(STRUCTURE, rec, noise=0)
    dense = gb.ls_uncertainty(model, rec)
    monkeypatch.setattr(pe, "available_memory", lambda: 1000)  # Ψ would not fit: TSQR over chunks
    chunked = gb.ls_uncertainty(model, rec)
    np.testing.assert_allclose(chunked.std, dense.std, rtol=1e-6)
    assert chunked.dof == dense.dof and chunked.sigma2 == pytest.approx(dense.sigma2, rel=1e-9)


# --------------------------------------------------------------------------------------------
# bootstrap_decision: a record shorter than a block is in the reference decision but in no replicate: said
# --------------------------------------------------------------------------------------------
def test_bootstrap_says_which_records_no_block_can_come_from():
    long_, short = plant(N=1000), gb.Record(plant(N=150, seed=4).u, plant(N=150, seed=4).y, name="short run")
    points = gb.StaticPoints([0.5, 1.0, 1.5], [1.0, 1.9, 2.4])
    with pytest.warns(gb.UncertaintyWarning, match=r"shorter than block_length = 200.*short run \(150 samples\)"):
        bd = gb.bootstrap_decision(STRUCTURE, [long_, short], points, block_length=200, band=1.0,
                                   lambdas=[0.5, 1.0], n_boot=2)
    assert bd.n_replicates == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error", gb.UncertaintyWarning)  # every record long enough: nothing to say
        gb.bootstrap_decision(STRUCTURE, [long_, short], points, block_length=100, band=1.0, lambdas=[0.5, 1.0],
                              n_boot=2)


# --------------------------------------------------------------------------------------------
# pe_uncertainty on exact static points says so among the reasons, and takes static_sigma=0 for them
# --------------------------------------------------------------------------------------------
def test_pe_uncertainty_on_noise_free_points_names_them_among_the_reasons():
    rec = plant(noise=0.0)
    ub = np.linspace(0.5, 1.5, 6)
    points = gb.StaticPoints(ub, _static_of_plant(ub))  # 6 exact points, 3 static coefficients, no constraint
    member = gb.pe_pareto(STRUCTURE, rec, points, lambdas=[0.5]).member_model(0)
    with pytest.raises(ValueError, match=r"meets its 6 static points exactly .*noise-free.*give static_sigma"):
        gb.pe_uncertainty(member, rec, points, lambda1=0.5)
    assert gb.pe_uncertainty(member, rec, points, lambda1=0.5, static_sigma=0.0).static_sigma2 == 0.0


def test_els_uncertainty_holds_few_copies_of_the_extended_regressors():
    rec = plant(N=100_000)
    short = rec.slice(0, 3000)
    gb.ls_uncertainty(gb.els(STRUCTURE, short, noise=2), short)  # imports and compiled kernels out of the count
    fit = gb.els(STRUCTURE, rec, noise=2)
    phi_bytes = 8 * (len(STRUCTURE) + 2) * len(rec)  # [Ψ, Ψ_e]
    peak = traced_peak(lambda: gb.ls_uncertainty(fit, rec))
    assert peak <= 6 * phi_bytes, f"ls_uncertainty (ELS) peaked at {peak / phi_bytes:.1f} × [Ψ, Ψ_e]"


def test_se_uncertainty_streams_the_free_run_jacobian():
    rec = plant(N=50_000)
    ub = np.linspace(0.5, 1.5, 6)
    points = gb.StaticPoints(ub, _static_of_plant(ub) + 0.01 * np.random.default_rng(1).standard_normal(6))
    short = rec.slice(0, 3000)
    warm = gb.se_pareto(STRUCTURE, short, points, lambdas=[0.5], method="gradient").member_model(0)
    gb.se_uncertainty(warm, short, points, lambda1=0.5)  # imports and compiled kernels out of the count
    member = gb.se_pareto(STRUCTURE, rec, points, lambdas=[0.5], method="gradient").member_model(0)
    jac_bytes = 8 * len(STRUCTURE) * len(rec)  # the free run's N × n Jacobian
    got = []
    peak = traced_peak(lambda: got.append(gb.se_uncertainty(member, rec, points, lambda1=0.5)))
    unc = got[0]
    assert peak <= 8 * jac_bytes, f"se_uncertainty peaked at {peak / jac_bytes:.1f} × the Jacobian"
    assert np.all(unc.std > 0) and np.isfinite(unc.static_sigma2)
