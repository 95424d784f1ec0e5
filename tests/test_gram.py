"""FROLS in the Gram (covariance) form, bounded memory, and records held as Dask arrays (issue 14)."""

from __future__ import annotations

import gc
import subprocess
import sys
import tracemalloc
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import graybox as gb
import graybox.core._gram as gram
from graybox import Candidates, Model, Record, Structure, stacked_regressors
from graybox.selection._forward_regression import CandidateWarning, frols

from conftest import traced_peak
from test_selection import BIN_TERMS, narx_record, rpm_record


def _both(cand, data, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        return frols(cand, data, method="mgs", **kw), frols(cand, data, method="gram", **kw)


def assert_same_selection(a, b, *, err_rtol=1e-9, theta_rtol=1e-8):
    """Same terms in the same order; ERR and θ equal to the stated tolerances.

    Terms looked at only for the criterion curve may part at an exact tie (two candidates that
    are each a combination of the chosen terms plus the same remainder, e.g. products of a
    staircase input): there both ERRs agree and the comparison stops.
    """
    assert a.structure == b.structure
    np.testing.assert_allclose(b.theta, a.theta, rtol=theta_rtol, atol=1e-14 * np.abs(a.theta).max())
    assert a.stop == b.stop
    k = min(len(a.evaluated), len(b.evaluated))
    same = [s == t for s, t in zip(a.evaluated, b.evaluated)]
    i = same.index(False) if False in same else k
    assert i >= a.n_terms
    np.testing.assert_allclose(b.err_evaluated[: i + (i < k)], a.err_evaluated[: i + (i < k)], rtol=err_rtol,
                               atol=1e-15)
    if i == k:
        assert len(a.evaluated) == len(b.evaluated)
        assert [(str(t), w) for t, w in a.skipped] == [(str(t), w) for t, w in b.skipped]


# ---------------------------------------------------------------- the sums themselves


def test_gram_sums_and_r_factor_are_those_of_the_stacked_regressors():
    r1, r2 = narx_record(5, n=700, noise=0.02), narx_record(6, n=500, noise=0.02)
    cand = Candidates(3, 3, ne=0, degree=3)
    psi, y = stacked_regressors(cand, [r1, r2], start=3)
    gs = gram.gram_sums(cand.terms, [r1, r2], 3)
    assert gs.N == psi.shape[0] == (700 - 3) + (500 - 3)
    scale = np.sqrt(np.outer(np.diag(psi.T @ psi), np.diag(psi.T @ psi)))
    np.testing.assert_allclose(gs.G / scale, (psi.T @ psi) / scale, atol=1e-13)
    np.testing.assert_allclose(gs.b, psi.T @ y, rtol=1e-12, atol=1e-12 * np.abs(psi.T @ y).max())
    np.testing.assert_allclose(gs.yy, y @ y, rtol=1e-13)
    R, N = gram.r_factor(cand.terms, [r1, r2], 3)
    A = np.column_stack([psi, y])
    np.testing.assert_allclose(np.abs(R), np.abs(np.linalg.qr(A, mode="r")), rtol=1e-9, atol=1e-9 * np.abs(R).max())


def test_chunks_smaller_than_the_record_give_the_same_sums(monkeypatch):
    rec = narx_record(3, n=3000, noise=0.05)
    cand = Candidates(3, 3, ne=0, degree=2)
    whole = gram.gram_sums(cand.terms, rec, 3)
    monkeypatch.setattr(gram, "_CHUNK_ENTRIES", 4096)  # 256-row chunks: 12 of them
    assert gram.chunk_rows(len(cand) + 1) < 3000 // 10
    parts = gram.gram_sums(cand.terms, rec, 3)
    np.testing.assert_allclose(parts.G, whole.G, rtol=1e-13)
    np.testing.assert_allclose(parts.b, whole.b, rtol=1e-13)


# ---------------------------------------------------------------- accuracy against MGS


def collinear_record(seed: int, n: int = 4000) -> Record:
    """u in rpm held on a slow staircase with a small spread (u, u², u³ and 1 nearly collinear:
    |cos| ≈ 1 − 1e-5) and an oversampled output (y(k-1), y(k-2), y(k-3) nearly collinear)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(1180.0, 1220.0, n // 40 + 1), 40)[:n]
    x = (u - 1200.0) / 20.0
    y = np.zeros(n)
    y[:3] = 15.0
    for k in range(3, n):
        y[k] = 1.9 * y[k - 1] - 0.905 * y[k - 2] + 0.075 + 0.02 * x[k - 1] + 0.004 * x[k - 1] ** 3 \
            + 0.002 * x[k - 2] * y[k - 1] / 15.0
    return Record(u, y + 1e-4 * rng.standard_normal(n))


@pytest.mark.parametrize("seed", [0, 1])
def test_gram_selects_as_mgs_on_ill_conditioned_data(seed):
    # u ≈ 1e3 rpm with degree-3 products (u³ ≈ 1e9), nearly collinear candidates: the Gram form
    # squares the conditioning, so the terms are ranked on it and the chosen terms' ERR and θ
    # come from a QR of those terms; both must match MGS.
    cand = Candidates(3, 3, ne=0, degree=3)
    rec = collinear_record(seed)
    psi, _ = stacked_regressors(cand, rec, start=3)
    s = psi / np.sqrt((psi**2).mean(axis=0))
    assert np.linalg.cond(s) > 1e7  # really ill-conditioned after scaling
    a, b = _both(cand, rec, n_terms=8)
    assert_same_selection(a, b, err_rtol=1e-8, theta_rtol=1e-6)
    a, b = _both(Candidates(4, 4, ne=0, degree=3), rpm_record(seed), n_terms=12)
    assert_same_selection(a, b, err_rtol=1e-9, theta_rtol=1e-8)


@pytest.mark.parametrize("degree,n_terms", [(2, 17), (3, 23)])
def test_bundled_plant_same_selection_with_either_method(degree, n_terms):
    ds = gb.load_pumping()
    cand = Candidates(6, 6, ne=0, degree=degree)
    assert_same_selection(*_both(cand, ds.ident, n_terms=n_terms))
    assert_same_selection(*_both(cand, ds.ident, n_terms=17, include=["1"]))  # as Table I runs it
    a, b = _both(cand, ds.ident, criterion="bic")
    assert_same_selection(a, b)
    assert "bic minimum" in b.stop


@pytest.mark.parametrize("criterion", ["aic", "bic", "fpe"])
def test_criteria_and_tol_with_the_gram_form(criterion):
    rec = narx_record(3, noise=0.01)
    cand = Candidates(3, 3, ne=0, degree=2)
    assert_same_selection(*_both(cand, rec, criterion=criterion, max_terms=12))
    assert_same_selection(*_both(cand, rec, tol=1e-3))


def test_gram_duplicates_and_dependent_candidates_as_mgs():
    rng = np.random.default_rng(2)
    u = rng.choice([-1.0, 1.0], 800)
    y = Model(Structure(BIN_TERMS), [0.3, 0.7, -0.3, 0.6, 0.2]).simulate(u, np.zeros(2))
    with pytest.warns(CandidateWarning, match=r"u\(k-1\)\^2 \(proportional to 1\)"):
        sel = frols(Candidates(2, 2, ne=0, degree=2), Record(u, y + 1e-3 * rng.standard_normal(800)), n_terms=5,
                    method="gram")
    assert set(map(str, sel.structure)) == set(BIN_TERMS)
    cand = Candidates(3, 3, ne=0, degree=2)
    with pytest.raises(ValueError, match="independent terms.*linear combinations"):
        frols(cand, narx_record(0), n_terms=len(cand), method="gram")


def test_auto_picks_mgs_for_short_and_gram_for_long_records():
    from graybox.selection._forward_regression import _choose_method

    assert _choose_method("auto", 3000, 455, 23, False) == "mgs"
    assert _choose_method("auto", 10**6, 91, 17, False) == "gram"
    assert _choose_method("auto", 100, 5, 2, True) == "gram"
    with pytest.raises(ValueError, match="method"):
        frols(Candidates(2, 2, ne=0, degree=1), narx_record(0, n=100), n_terms=2, method="qr")


# ---------------------------------------------------------------- memory


def test_gram_memory_does_not_grow_with_the_record(monkeypatch):
    monkeypatch.setattr(gram, "_CHUNK_ENTRIES", 1 << 16)  # 720-row chunks for 91 candidates
    cand = Candidates(6, 6, ne=0, degree=2)
    recs = {n: narx_record(9, n=n, noise=0.05) for n in (20_000, 40_000)}
    warm = frols(cand, recs[20_000], n_terms=10, method="gram")
    peaks = {n: traced_peak(lambda r=r: frols(cand, r, n_terms=10, method="gram")) for n, r in recs.items()}
    matrix_40k = 8 * (40_000 - 6) * len(cand)
    assert peaks[40_000] < 1.2 * peaks[20_000]  # twice the samples, the same peak
    assert peaks[40_000] < matrix_40k / 4  # far below the candidate matrix it never builds
    # while MGS holds the matrix: its peak doubles with the record
    mgs = {n: traced_peak(lambda r=r: frols(cand, r, n_terms=10, method="mgs")) for n, r in recs.items()}
    assert mgs[40_000] > 1.8 * mgs[20_000] and mgs[40_000] > matrix_40k
    assert warm.n_rows == 20_000 - 6


def test_candidate_builder_keeps_nothing_after_return():
    # the old builder's recursive closure kept its column cache alive until the garbage collector ran
    cand = Candidates(6, 6, ne=0, degree=3)
    rec = narx_record(4, n=6000, noise=0.05)
    frols(cand, rec, n_terms=5, method="mgs")
    gc.collect()
    gc.disable()
    try:
        tracemalloc.start()
        sel = frols(cand, rec, n_terms=5, method="mgs")
        left, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    finally:
        gc.enable()
    matrix = 8 * sel.n_rows * len(cand)
    assert peak > matrix  # the matrix was built …
    assert left < matrix / 20  # … and nothing of that size outlives the call without gc


def test_work_that_does_not_fit_is_refused_before_allocation(monkeypatch):
    cand = Candidates(6, 6, ne=0, degree=2)
    rec = narx_record(2, n=20_000, noise=0.05)
    monkeypatch.setattr(gram, "available_memory", lambda: 4 * 2**20)
    peak = []

    def run(method):
        tracemalloc.start()
        try:
            frols(cand, rec, n_terms=5, method=method)
        finally:
            peak.append(tracemalloc.get_traced_memory()[1])
            tracemalloc.stop()

    with pytest.raises(MemoryError, match=r"needs .*MiB \(\d+ bytes\) but only 4.0 MiB \(4194304 bytes\) are available"):
        run("mgs")
    assert peak[-1] < 2**20  # refused before the 14 MiB candidate matrix was allocated
    with pytest.raises(MemoryError, match="Gram form"):
        run("gram")
    monkeypatch.setattr(gram, "available_memory", lambda: 2**40)
    assert frols(cand, rec, n_terms=5, method="mgs").n_terms == 5


def test_available_memory_is_a_positive_byte_count():
    assert gram.available_memory() > 2**20


# ---------------------------------------------------------------- Dask records


def test_dask_is_imported_only_when_a_dask_record_is_given():
    # nor pandas (about 0.3 s), which makes the result tables (Selection.to_frame), not the fits: a first frols leaves
    # it out (tests/test_layers.py holds the modules below the figures to importing it where a table is made)
    code = ("import sys, numpy as np, graybox as gb, warnings\n"
            "rec = gb.load_pumping().ident\n"
            "gb.frols(gb.Candidates(2, 2, ne=0, degree=2), rec, n_terms=3, method='gram')\n"
            "assert 'dask' not in sys.modules, 'dask imported'\n"
            "assert 'pandas' not in sys.modules, 'pandas imported'\n")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_dask_record_validates_its_arrays():
    da = pytest.importorskip("dask.array")
    u = da.from_array(np.arange(10.0), chunks=4)
    with pytest.raises(TypeError, match="dask array"):  # a wrong type (hunt49g)
        gb.DaskRecord(np.arange(10.0), u)
    with pytest.raises(ValueError, match="same known length"):
        gb.DaskRecord(u, da.from_array(np.arange(9.0), chunks=4))
    with pytest.raises(ValueError, match="1-D"):
        gb.DaskRecord(u.reshape(2, 5), u.reshape(2, 5))
    with pytest.raises(ValueError, match="Ts"):
        gb.DaskRecord(u, u, Ts=0.0)
    r = gb.DaskRecord(u, da.from_array(np.arange(10.0), chunks=3))
    assert r.y.chunks == r.u.chunks and len(r) == 10
    with pytest.raises(ValueError, match="fewer than max lag"):
        frols(Candidates(12, 12, ne=0, degree=1), r, n_terms=1)
    with pytest.raises(ValueError, match="mgs"):
        frols(Candidates(2, 2, ne=0, degree=1), r, n_terms=1, method="mgs")


@pytest.fixture(scope="module")
def dask_client():
    pytest.importorskip("distributed")
    from distributed import Client, LocalCluster

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def test_frols_and_pe_on_dask_records_reduced_on_a_local_cluster(dask_client):
    import dask.array as da

    ds = gb.load_pumping()
    ident, valid = ds.ident, ds.valid
    # two records in uneven blocks: rows must neither straddle the records nor miss a block edge
    lazy = [gb.DaskRecord(da.from_array(ident.u, chunks=700), da.from_array(ident.y, chunks=450)),
            gb.DaskRecord(da.from_array(valid.u, chunks=300), da.from_array(valid.y, chunks=300))]
    mem = [ident, valid]
    cand = Candidates(6, 6, ne=0, degree=2)
    ref = frols(cand, mem, n_terms=17)  # in memory, the default (MGS at this size)
    got = frols(cand, lazy, n_terms=17)
    assert got.structure == ref.structure and got.n_rows == ref.n_rows
    np.testing.assert_allclose(got.err, ref.err, rtol=1e-10)
    np.testing.assert_allclose(got.theta, ref.theta, rtol=1e-10)
    np.testing.assert_allclose(got.rss, ref.rss, rtol=1e-10)

    # the PE closed form reduces the lazy records to the triangular factor of [Ψ, y]
    import graybox.estimation._prediction_error as cx

    st = ref.structure
    d_mem, d_lazy = cx._dynamic(st, mem), cx._dynamic(st, lazy)
    np.testing.assert_allclose(d_lazy.R1, d_mem.R1, rtol=1e-10, atol=1e-10 * np.abs(d_mem.R1).max())
    np.testing.assert_allclose(d_lazy.c1, d_mem.c1, rtol=1e-10, atol=1e-10 * np.abs(d_mem.c1).max())
    np.testing.assert_allclose(d_lazy.rss, d_mem.rss, rtol=1e-10)
    lam = [1.0, 0.1, 1e-3]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        th_mem = gb.pe_thetas(st, mem, ds.static, lambdas=lam, solver="closed")
        th_lazy = gb.pe_thetas(st, lazy, ds.static, lambdas=lam, solver="closed")
    np.testing.assert_allclose(th_lazy[0], th_mem[0], rtol=1e-10)  # λ1 = 1: least squares
    # the weighted members amplify the factors' 1e-15 differences by their own conditioning
    np.testing.assert_allclose(th_lazy, th_mem, rtol=1e-8)
    with pytest.raises(ValueError, match="pe_thetas"):
        gb.pe_pareto(st, lazy[0], ds.static, solver="closed")


def test_pe_reduces_a_record_chunk_by_chunk_when_its_regressors_would_not_fit(monkeypatch):
    import graybox.estimation._prediction_error as cx

    ds = gb.load_pumping()
    st = Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-2)y(k-1)", "1"])
    dense = cx._dynamic(st, [ds.ident])
    monkeypatch.setattr(cx, "available_memory", lambda: 100_000)  # under 4 copies of the 3200 × 7 Ψ
    used = []
    monkeypatch.setattr(cx, "_dynamic_chunked", lambda *a, f=cx._dynamic_chunked: used.append(1) or f(*a))
    chunked = cx._dynamic(st, [ds.ident])
    assert used
    np.testing.assert_allclose(chunked.R1, dense.R1, rtol=1e-10, atol=1e-10 * np.abs(dense.R1).max())
    np.testing.assert_allclose(chunked.c1, dense.c1, rtol=1e-10, atol=1e-10 * np.abs(dense.c1).max())
    np.testing.assert_allclose(chunked.rss, dense.rss, rtol=1e-10)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(60, 400),
    log_su=st.floats(-3, 4),
    offset=st.floats(-2, 2),
    n_terms=st.integers(1, 10),
)
def test_gram_err_is_the_least_squares_fit_of_what_it_selects(seed, n, log_su, offset, n_terms):
    rng = np.random.default_rng(seed)
    u = 10**log_su * (offset + rng.standard_normal(n))
    y = np.zeros(n)
    e = rng.standard_normal(n)
    for k in range(2, n):
        y[k] = 0.5 * y[k - 1] + 0.1 * (u[k - 1] / 10**log_su) ** 2 + e[k]
    cand = Candidates(2, 2, ne=0, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CandidateWarning)
        try:
            sel = frols(cand, Record(u, y), n_terms=n_terms, method="gram")
        except ValueError as exc:
            assume("usable" not in str(exc) and "independent" not in str(exc))
            raise
    assert np.all(sel.err >= 0.0) and sel.err.sum() <= 1.0 + 1e-12
    psi, target = stacked_regressors(sel.structure, Record(u, y), start=2)
    theta, *_ = np.linalg.lstsq(psi, target, rcond=None)
    resid = target - psi @ theta
    np.testing.assert_allclose(sel.rss[-1], max(resid @ resid, 1e-20 * (target @ target)), rtol=1e-8)
    np.testing.assert_allclose(sel.theta, theta, rtol=1e-6, atol=1e-9 * np.abs(theta).max())


def test_dask_blocks_shorter_than_the_lags_see_their_lags():
    da = pytest.importorskip("dask.array")
    import dask

    r1, r2 = narx_record(5, n=300, noise=0.02), narx_record(6, n=200, noise=0.02)
    cand = Candidates(6, 6, ne=0, degree=2)
    lazy = [gb.DaskRecord(da.from_array(r.u, chunks=c), da.from_array(r.y, chunks=7)) for r, c in ((r1, 4), (r2, 13))]
    with dask.config.set(scheduler="synchronous"):
        got = gram.gram_sums(cand.terms, lazy, 6)
        R, N = gram.r_factor(cand.terms, lazy, 6)
    ref = gram.gram_sums(cand.terms, [r1, r2], 6)
    assert got.N == ref.N == N == (300 - 6) + (200 - 6)
    np.testing.assert_allclose(got.G, ref.G, rtol=1e-12, atol=1e-12 * np.abs(ref.G).max())
    np.testing.assert_allclose(got.b, ref.b, rtol=1e-12, atol=1e-12 * np.abs(ref.b).max())
    A = np.column_stack(stacked_regressors(cand, [r1, r2], start=6))
    np.testing.assert_allclose(R.T @ R, A.T @ A, rtol=1e-10, atol=1e-10 * np.abs(A.T @ A).max())


@pytest.mark.parametrize("seed", [0, 1])
def test_gram_form_does_not_depend_on_units(seed):
    rec = rpm_record(seed)
    su, sy = rec.u.std(), rec.y.std()
    cand = Candidates(4, 4, ne=0, degree=3)
    eng = frols(cand, rec, n_terms=12, method="gram")
    unit = frols(cand, Record(rec.u / su, rec.y / sy), n_terms=12, method="gram")
    assert eng.structure == unit.structure
    np.testing.assert_allclose(eng.err, unit.err, rtol=1e-9, atol=1e-15)
    back = np.array(
        [th * sy / (su ** t.power_of("u") * sy ** t.power_of("y")) for th, t in zip(unit.theta, unit.structure)]
    )
    np.testing.assert_allclose(eng.theta, back, rtol=1e-6)


def test_dask_records_at_another_period_are_refused():
    # as in-memory records are: a 0.1 s record beside a 0.2 s one is one discrete-time model's data by mistake
    import dask.array as da

    rng = np.random.default_rng(0)
    u, y = rng.standard_normal(300), rng.standard_normal(300)
    a = gb.DaskRecord(da.from_array(u, chunks=100), da.from_array(y, chunks=100), Ts=0.1, name="a")
    b = gb.DaskRecord(da.from_array(u, chunks=100), da.from_array(y, chunks=100), Ts=0.2, name="b")
    with pytest.raises(ValueError, match="'a' is sampled every 0.1 s but 'b' every 0.2 s"):
        gb.frols(gb.Candidates(1, 1, degree=1), [a, b], n_terms=2)


def test_a_lagged_output_on_an_offset_is_not_called_proportional_to_the_constant_by_the_gram_form():
    # hunt62f: noise-free y ≈ 1e5 (±2 about it): y(k-1)'s angle to the constant is 4.5e-6 rad, told apart by the data
    # to 1e-16. MGS keeps it (its duplicate test groups columns by a random projection first, at 1e-8); the Gram form
    # took |cos| > 1 − 1e-10 alone for proportional, skipped y(k-1) and every y term 'proportional to 1' and chose
    # 1, u(k-1), u(k-2) where MGS chooses the true 1, y(k-1), u(k-1), u(k-1)^2
    u = np.random.default_rng(1).uniform(-1.0, 1.0, 200)
    z = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2"]), np.array([0.5, 1.0, 0.1])).simulate(u, np.zeros(1))
    rec = gb.Record(u, z + 1e5)
    cand = gb.Candidates(2, 2, degree=2)
    true = set(gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        got = {m: gb.frols(cand, rec, search="exact", method=m) for m in ("mgs", "gram")}
    assert set(got["mgs"].structure) == true
    assert set(got["gram"].structure) == true
    assert not any("proportional" in why for _, why in got["gram"].skipped)
