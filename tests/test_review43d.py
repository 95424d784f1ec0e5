"""review43d: select_graybox's checkpoint, the grid's cell time limit, the Dask scratch sweep and the subset
searches on QR of [S, y], checked again."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox.experiments import _select

_FAILING_MAP = textwrap.dedent('''
    import os, sys, time
    from graybox.experiments import parallel_map


    def job(item):
        folder, x = item
        if x == 0:
            raise RuntimeError("job 0 fails")
        time.sleep(0.3)
        open(os.path.join(folder, str(x)), "w").close()  # this job ran to its end
        return x


    if __name__ == "__main__":
        folder = sys.argv[1]
        seen = []
        with parallel_map(executor="processes", workers=1) as pmap:
            try:
                pmap(job, [(folder, x) for x in range(12)], each=lambda i, r: seen.append(r))
            except RuntimeError as exc:
                print("raised:", exc)
        print("seen:", " ".join(map(str, sorted(seen))))
''')


def test_a_job_that_raises_under_processes_ends_the_map_without_running_the_queue_or_losing_what_finished(tmp_path):
    # select_graybox(checkpoint=, executor="processes"): a row whose job raised (an error its fit does not catch, a
    # warning the caller's filters make an error) ended the loop over finished jobs, and leaving parallel_map waited
    # for every job still queued (ProcessPoolExecutor's shutdown runs them), whose results were then thrown away and
    # never reached the checkpoint: all 11 ran, none was kept
    script = tmp_path / "failing_map.py"
    script.write_text(_FAILING_MAP)
    folder = tmp_path / "ran"
    folder.mkdir()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    out = subprocess.run([sys.executable, str(script), str(folder)], capture_output=True, text=True, timeout=300,
                         env=env, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert "raised: job 0 fails" in lines, out.stdout
    ran = sorted(int(p.name) for p in folder.iterdir())
    seen = [int(v) for v in lines[-1].removeprefix("seen:").split()]
    assert len(ran) < 11  # the jobs not started were dropped
    assert seen == ran  # every job that ran to its end was told of (a checkpoint keeps it)


@pytest.fixture(scope="module")
def data():
    return gb.load_pumping()


def test_a_selection_called_again_with_another_band_refits_no_row(tmp_path, data, monkeypatch):
    # the band decides the choice among the rows, not a row's scores (its fits, J_S blocks and J_SF): a checkpoint
    # keyed each row by the band too, so a selection called again with another B refitted every row
    cand, kw = gb.Candidates(ny=2, nu=2, degree=2), dict(sizes=[3, 4], estimator="pe", progress=False)
    path = tmp_path / "sel.npz"
    gb.select_graybox(cand, data, band=0.05, checkpoint=path, **kw)
    calls: list = []
    score = _select._score_job
    monkeypatch.setattr(_select, "_score_job", lambda job: (calls.append(job), score(job))[1])
    again = gb.select_graybox(cand, data, band=0.02, checkpoint=path, **kw)
    assert calls == []
    fresh = gb.select_graybox(cand, data, band=0.02, **kw)
    assert len(calls) == len(fresh.table)
    pd.testing.assert_frame_equal(again.table, fresh.table)
    assert again.band == fresh.band == 0.02


def _tiny_grid():
    from graybox import experiments as gx

    return gx.Grid(name="tiny", data=[gx.DataSpec("pumping", bundled="pumping")],
                   structures=[gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])],
                   variants=[gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "equality"}])])


def test_a_long_cell_time_limit_runs_the_grid(tmp_path):
    # a limit of 30 days (a bound meant never to be reached) made the driver wait on its workers with a timeout
    # poll() cannot take (more than 2^31 ms): OverflowError once a cell had started, the whole run stopped
    from graybox import experiments as gx

    gx.run_grid(_tiny_grid(), tmp_path / "s.sqlite", executor="processes", workers=1,
                      cell_time_limit=30 * 86400.0)
    df = gx.load_results(tmp_path / "s.sqlite")
    assert len(df) == 2 and (df["status"] == "ok").all(), df[["status", "message"]]


def _blas_threads() -> int:
    from graybox.core._least_squares import thread_pools

    return max(p.num_threads for p in thread_pools().select(user_api="blas").lib_controllers)


@pytest.mark.parametrize("how", ["swap", "exact", "semp"])
def test_the_subset_searches_and_semp_factor_on_one_blas_thread(how, monkeypatch):
    # the searches' and semp's factor of [S, y] (one QR of N × 92 on the plant's ny = nu = 6, degree 2) and semp's
    # per-step QRs ran on every BLAS thread: on the loaded 2-core machine the QR took 160 ms for 9 ms on one
    # thread, frols(search='swap') 0.27 s for 0.065 s and semp(n_terms=10) 7.2 s for 3.4 s (select_graybox's
    # structure search runs them in the driver, outside the jobs' one BLAS thread)
    import scipy.linalg

    from graybox.core._least_squares import thread_pools

    seen: list[int] = []
    qr = scipy.linalg.qr
    monkeypatch.setattr(scipy.linalg, "qr", lambda *a, **k: (seen.append(_blas_threads()), qr(*a, **k))[1])
    nqr = np.linalg.qr
    monkeypatch.setattr(np.linalg, "qr", lambda *a, **k: (seen.append(_blas_threads()), nqr(*a, **k))[1])
    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, 400)
    y = np.convolve(u, [0.0, 0.5, 0.3], mode="full")[:400] + 0.05 * rng.standard_normal(400)
    cand = gb.Candidates(2, 2, degree=2)
    with thread_pools().limit(limits=2, user_api="blas"):
        assume_two = _blas_threads()
        if how == "semp":
            gb.semp(cand, gb.Record(u, y), n_terms=3)
        else:
            gb.frols(cand, gb.Record(u, y), n_terms=3, search=how)
    if assume_two < 2:
        pytest.skip("this BLAS runs on one thread only")
    assert seen and max(seen) == 1, seen


def _reference_leaves(problem, F, pool, bound, cutoff, nodes_left):
    """The last two levels of the branch and bound leaf by leaf, as exact_search made them (one reduction each)."""
    best_j, best_c, best, used = -1, -1, cutoff, 0
    for j in range(len(pool) - 1):
        if bound[j] >= best:
            break
        used += 1
        if used > nodes_left:
            return best_j, best_c, best, used, True
        r = problem.added(F + [pool[j]], np.array(pool[j + 1:]))
        c = int(np.argmin(r))
        if r[c] < best:
            best_j, best_c, best = j, j + 1 + c, float(r[c])
    return best_j, best_c, best, used, False


@pytest.mark.parametrize("seed", range(8))
def test_the_exact_search_s_leaves_made_together_are_those_made_one_by_one(seed):
    # the branch and bound's leaves (most of its nodes) each reduced their fixed columns again: 9.8 s on the plant
    # at the node cap, 3.6 s with the fixed columns' reflections made once per parent; the RSS are the same to the
    # last bit (the same reflections over the same rows), so are the cuts, the nodes and the answer
    from graybox.selection._subset_search import SubsetProblem

    rng = np.random.default_rng(seed)
    N, n = 200, 14
    S = rng.standard_normal((N, n)) + [0.0, 1e3, 1e5, 0.0][seed % 4] * (np.arange(n) % 3 == 0)
    S[:, 5] = S[:, 2] - 2.0 * S[:, 7]  # a column dependent on two others
    y = S[:, [1, 4, 9]] @ [0.5, -1.0, 2.0] + [0.0, 1e-3, 0.3, 0.0][seed % 4] * rng.standard_normal(N) + 1e4 * (seed % 2)
    S = S / np.sqrt(np.mean(S**2, axis=0))
    R = np.linalg.qr(np.column_stack([S, y]), mode="r")
    problem = SubsetProblem(R, float(y @ y), np.ones(n, bool), 1e-14)
    found = out = 0
    for _ in range(20):
        F = [int(j) for j in rng.choice(n, rng.integers(0, 4), replace=False)]
        pool = [int(j) for j in rng.permutation(np.setdiff1d(np.arange(n), F))][: rng.integers(2, n - len(F) + 1)]
        bound = problem.bounds(F + pool[::-1])[len(F):][::-1]
        cutoff = np.inf if rng.random() < 0.5 else problem.rss(F + pool[:2])
        nodes_left = int(rng.choice([1000, 3]))
        got = problem.leaves(F, pool, bound, cutoff, nodes_left)
        want = _reference_leaves(problem, F, pool, bound, cutoff, nodes_left)
        assert tuple(got) == want
        found += got[0] >= 0
    assert found
    pool = list(range(n))  # out of nodes at the first leaf
    bound = problem.bounds(pool[::-1])[::-1]
    got = problem.leaves([], pool, bound, np.inf, 0)
    assert tuple(got) == (-1, -1, np.inf, 1, True) == _reference_leaves(problem, [], pool, bound, np.inf, 0)
