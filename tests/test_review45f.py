"""review45f: select_graybox's fallback from the structures searched per fold to those of all the data."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.experiments import _select

CAND = gb.Candidates(ny=2, nu=2, degree=2)


def record(n: int, seed: int) -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 4 + 1), 4)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1] + 0.05 * u[k - 1] ** 2 + 0.1
    return gb.Record(u, y + 0.1 * np.std(y) * rng.standard_normal(n), name=f"run {seed}")


def test_no_fallback_warning_when_the_structures_of_all_the_data_never_run_either(monkeypatch):
    # was: when no row ran on its held-out folds, the structures of all the data were fitted per fold again and the
    # call warned that "the choice is made on" them (optimistic) even when they never ran either: no choice was made,
    # the error that says so came after a warning that claimed one (and, with warnings as errors, never came)
    block_mse = _select._block_mse
    monkeypatch.setattr(_select, "_block_mse", lambda *a: np.full_like(block_mse(*a), np.inf))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(ValueError, match="no structure has a finite free-run J_S on the choosing data"):
            gb.select_graybox(CAND, record(240, 1), sizes=[3, 5], sources=["frols"], folds=3, estimator="ls")
    assert not [w for w in caught if "no finite free run on its held-out fold" in str(w.message)]



def test_a_fold_whose_semp_path_stops_early_takes_the_largest_size_it_reached(monkeypatch):
    # was: the fold's search was read at the rows' sizes only, so a row of 12 terms on a fold whose SEMP path stopped
    # at 9 took the path's 8 terms (the nearest of the rows' sizes), not its 9: not "the nearest size the fold's
    # search reached"
    path = [str(t) for t in CAND.process][:9]  # a path of sizes 1 … 9 (each size the first k candidates)

    def searched(candidates, ident, sizes, sources, forced, top):
        found = {(s, k): path[:k] for s in sources if s == "semp" for k in sizes if k <= len(path)}
        return found, {"semp": {k for s, k in found}}

    monkeypatch.setattr(_select, "_searched", searched)
    plan = _select._Plan(ident=(record(240, 1),), splits=(((record(100, 2),), None, None),), test=None, static=None,
                         band=None, lag=2)
    rows = [{"source": "semp", "size": k, "terms": ""} for k in (4, 8, 12)]
    got = _select._fold_structures(rows, CAND, plan, ["semp"], ["1"], None, False)
    assert [len(t[0].split(" + ")) for t in got] == [4, 8, 9]


def test_a_row_two_sources_share_at_other_sizes_takes_on_a_fold_the_other_sources_own_size(monkeypatch):
    # a gray box's row "semp-4" that FROLS's 3 terms also give (completed with Σu², u(k-1)^2): on a fold whose SEMP
    # path skips 4, the row is FROLS's 3 terms there, its own member; was: FROLS's 4 terms (the row's size, which no
    # member of the row had from FROLS)
    n = 240
    full = {("semp", 4): ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], ("frols", 3): ["1", "y(k-1)", "u(k-1)"]}
    order = ["1", "y(k-1)", "u(k-1)", "y(k-2)", "u(k-2)", "u(k-2)^2"]

    def searched(candidates, ident, sizes, sources, forced, top):
        if isinstance(ident, gb.Record) and len(ident) == n:  # all the identification data
            found = {key: t for key, t in full.items() if key[0] in sources and key[1] in sizes}
        else:  # a fold: SEMP's path passes 3 and 5, FROLS's order is `order`
            found = {("semp", k): order[:k] for k in (3, 5) if "semp" in sources and k in sizes}
            found |= {("frols", k): order[:k] for k in sizes if "frols" in sources and k <= len(order)}
        return found, {s: {k for src, k in found if src == s} for s in sources}

    monkeypatch.setattr(_select, "_searched", searched)
    seen: list = []
    real = _select._fold_structures
    monkeypatch.setattr(_select, "_fold_structures", lambda rows, *a: seen.append((rows, real(rows, *a))) or seen[-1][1])
    ub = np.linspace(0.5, 2.0, 6)
    static = gb.StaticPoints(ub, (0.3 * ub + 0.05 * ub**2 + 0.1) / 0.4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gb.select_graybox(CAND, record(n, 1), static, band=1e-6, sizes=[3, 4], folds=3, estimator="pe",
                          fallback="min_jsf")
    (rows, out), = seen
    (row, terms), = [(r, t) for r, t in zip(rows, out) if r["structure"] == "semp-4"]
    assert row["source"] == "semp, frols", rows
    for t in terms:
        assert set(t.split(" + ")) == {"1", "y(k-1)", "u(k-1)", "u(k-1)^2"}


def test_a_row_two_sources_share_takes_its_first_source_where_the_fold_reached_both_sizes(monkeypatch):
    paths = {("semp", 4): ["1", "y(k-1)", "u(k-1)", "u(k-2)"], ("frols", 3): ["1", "y(k-1)", "u(k-2)"]}
    monkeypatch.setattr(_select, "_searched", lambda *a, **k: (paths, {"semp": {4}, "frols": {3}}))
    plan = _select._Plan(ident=(record(240, 1),), splits=(((record(100, 2),), None, None),), test=None, static=None,
                         band=None, lag=2)
    rows = [{"source": "semp, frols", "size": 4, "terms": "", "_members": [("semp", 4), ("frols", 3)]}]
    (got,), = _select._fold_structures(rows, CAND, plan, ["semp", "frols"], ["1"], None, False)
    assert len(got.split(" + ")) == 4


def test_a_fold_searches_swap_at_the_size_of_a_shared_rows_swap_member(monkeypatch):
    # a row "semp-6" that swap's 5 terms also give: where the fold's SEMP path has no 6, the row is swap's 5 terms
    # there; was: swap searched at the rows' sizes only (6), its 5 never looked at
    terms = [str(t) for t in CAND.process]

    def searched(candidates, ident, sizes, sources, forced, top):
        found = {("semp", k): terms[:k] for k in (3, 9) if "semp" in sources and k in sizes}
        found |= {("swap", k): terms[-k:] for k in sizes if "swap" in sources}
        return found, {}

    monkeypatch.setattr(_select, "_searched", searched)
    plan = _select._Plan(ident=(record(240, 1),), splits=(((record(100, 2),), None, None),), test=None, static=None,
                         band=None, lag=2)
    rows = [{"source": "semp, swap", "size": 6, "terms": "", "_members": [("semp", 6), ("swap", 5)]}]
    (got,), = _select._fold_structures(rows, CAND, plan, ["semp", "swap"], ["1"], None, False)
    assert set(got.split(" + ")) == set(terms[-5:])
