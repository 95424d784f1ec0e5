"""review49i: checks of the DaskRecord, GA and equilibria commits of round 49."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import graybox as gb


def _counting_record(u: np.ndarray, y: np.ndarray, chunk: int, calls: dict) -> gb.DaskRecord:
    da = pytest.importorskip("dask.array")
    lock = threading.Lock()

    def load(block_info=None, src=None):
        with lock:
            calls["n"] += 1
        a, b = block_info[None]["array-location"][0]
        return src[a:b].copy()

    def mk(src):
        return da.map_blocks(load, src=src, chunks=((chunk,) * (src.size // chunk),), dtype=float)

    return gb.DaskRecord(mk(u), mk(y), name="long")


@pytest.mark.parametrize("nan_at", [None, -1])
def test_the_finite_check_of_a_dask_record_reads_no_block_again(nan_at):
    # 27cbb33 checked every sample finite "in the same compute as the reduction (the blocks read once)", but the
    # array collection's graph is optimised apart from the delayed reduction's: every block was loaded once more
    # (frols on a record of 10 blocks per signal: 120 block loads where its two reductions alone made 80)
    dask = pytest.importorskip("dask")

    rng = np.random.default_rng(0)
    u = rng.uniform(0, 1, 1000)
    y = 0.5 * u + 0.1
    if nan_at is not None:
        u[nan_at] = np.nan  # read by no regression row
    calls = {"n": 0}
    rec = _counting_record(u, y, 100, calls)
    with dask.config.set(scheduler="synchronous"):
        if nan_at is None:
            gb.frols(gb.Candidates(2, 2, degree=2), rec, n_terms=2)
        else:
            with pytest.raises(ValueError, match=r"long: u has 1 non-finite value.*index 999"):
                gb.frols(gb.Candidates(2, 2, degree=2), rec, n_terms=2)
    # frols reduces twice; each reduction reads a block for its own stretch and for the next one's (the lags reach
    # back into it): 2 x 2 x 20 = 80 loads, as before 27cbb33 (the error path's pass naming the sample included)
    assert calls["n"] <= 80


def test_a_copied_or_pickled_dask_record_still_refuses_item_assignment():
    # 5907369 made a DaskRecord's u and y refuse item assignment (dask assigns in place: a frozen record's samples
    # were rewritten), but dask.array.Array's __reduce__ and copy rebuild a plain Array: pickle.loads(pickle.dumps(
    # record)) (a record sent to a worker process) or copy.deepcopy(record) gave a record whose u[1] = x was taken
    import copy
    import pickle

    da = pytest.importorskip("dask.array")
    u = da.from_array(np.linspace(0.0, 1.0, 40), chunks=10)
    rec = gb.DaskRecord(u, 0.5 * u, name="long")
    for other in (pickle.loads(pickle.dumps(rec)), copy.deepcopy(rec), copy.copy(rec)):
        for a in (other.u, other.y):
            with pytest.raises(TypeError, match="read-only"):
                a[1] = 7.0
        np.testing.assert_array_equal(other.u.compute(), rec.u.compute())


def test_a_solver_error_after_the_options_were_taken_is_one_members_failure(monkeypatch):
    # d7d53b4 made a SolverError under solver_options the call's ("check their values"), meaning the options the
    # solver refuses at setup (every λ1 fails alike); but a numerical failure at one λ1 (a07e3bc: that member's
    # failure) is a SolverError too: once a solve has taken the options, it ended the whole sweep blaming them
    import warnings

    cp = pytest.importorskip("cvxpy")
    real = cp.Problem.solve
    calls = {"n": 0}

    def flaky(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise cp.error.SolverError("Solver 'OSQP' failed. Try another solver")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(cp.Problem, "solve", flaky)
    data = gb.load_pumping()
    st = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        front = gb.pe_pareto(st, data.ident, data.static, lambdas=np.logspace(-3, 0, 5), solver="osqp",
                             solver_options={"eps_abs": 1e-7, "eps_rel": 1e-7})
    assert calls["n"] >= 5
    assert len(front.failures) == 1, front.failures
