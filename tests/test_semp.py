"""SEMP: structure selection by simulation error with pruning (graybox.semp)."""

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox import Candidates, Model, Record, Structure

# A NARX system whose terms FROLS gets wrong under staircase inputs, even without noise: with
# u(k-1) = u(k-2) = u(k-3) almost everywhere, one-step ERR cannot tell the input lags apart.
TRUE = Structure(["y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-2)^2", "1"])
THETA = np.array([0.5, 0.3, 0.4, -0.2, 0.15, 0.1])
SECOND = Structure(["y(k-1)", "u(k-1)", "u(k-2)", "u(k-2)y(k-1)", "1"])
THETA2 = np.array([0.6, 0.3, 0.2, -0.1, 0.05])


def staircase_record(structure, theta, seed, n=1000, hold=10, noise=0.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // hold + 1), hold)[:n]
    y = Model(structure, theta).simulate(u, np.zeros(structure.max_lag))
    if noise:
        y = y + noise * np.std(y) * rng.standard_normal(n)
    return Record(u, y, name=f"stair{seed}")


@pytest.mark.parametrize("structure,theta,seed,hold", [
    (TRUE, THETA, 0, 10), (TRUE, THETA, 1, 5), (TRUE, THETA, 2, 10), (SECOND, THETA2, 0, 20), (SECOND, THETA2, 1, 5),
])
def test_recovers_the_true_structure_where_frols_fails(structure, theta, seed, hold):
    rec = staircase_record(structure, theta, seed, hold=hold)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        wrong = gb.frols(Candidates(3, 3, ne=0, degree=2), rec, n_terms=len(structure))
    assert set(wrong.structure) != set(structure)  # the case is a real one: ERR picks wrong terms
    for res in (gb.semp(Candidates(3, 3, ne=0, degree=2), rec, n_terms=len(structure)),
                gb.semp(Candidates(3, 3, ne=0, degree=2), rec)):  # criterion (BIC) stopping
        assert set(res.structure) == set(structure)
        order = [res.structure.index(t) for t in structure]
        np.testing.assert_allclose(res.theta[order], theta, atol=1e-8)
        assert res.score < 1e-15 * np.mean(rec.y**2)


def test_path_and_scores_are_consistent():
    rec = staircase_record(TRUE, THETA, 3, noise=0.02)
    res = gb.semp(Candidates(3, 3, ne=0, degree=2), rec, n_terms=4, include=["1"])
    assert res.structure[0] == gb.parse_term("1") and len(res.structure) == 4
    path = res.path
    assert list(path.columns) == ["step", "action", "term", "n_terms", "score", "criterion", "structure"]
    assert path["action"].iloc[0] == "include"
    assert set(path["action"]) <= {"include", "add", "remove"}
    # each size changes by one per step
    assert np.all(np.abs(np.diff(path["n_terms"])) == 1)
    # the returned score is the model's own free-run MSE (the shared evaluator's J_S on these samples)
    m = res.model
    L = Candidates(3, 3, ne=0, degree=2).max_lag  # every structure is run from the candidates' largest lag
    sim = np.r_[rec.y[:L], gb.simulate(m.structure, m.theta, rec.u[L - m.max_lag:], rec.y[L - m.max_lag:L])[m.max_lag:]]
    assert res.score == pytest.approx(np.mean((sim[L:] - rec.y[L:]) ** 2), rel=1e-9)
    # at every forward step the accepted term had the smallest finite score among the unvisited
    fs = res.forward_scores
    assert fs.shape[1] == len(Candidates(3, 3, ne=0, degree=2).process)
    adds = path[path["action"] == "add"]
    for k, (_, row) in enumerate(adds.iterrows()):
        assert fs.iloc[k][row["term"]] == pytest.approx(row["score"])
    # the rule that picked it: the minimum of that step (cycles aside, which this small case does not hit)
    assert fs.iloc[0].min() == pytest.approx(adds["score"].iloc[0])


def test_prune_false_is_forward_selection_and_tol_stops():
    rec = staircase_record(TRUE, THETA, 4)
    fwd = gb.semp(Candidates(3, 3, ne=0, degree=2), rec, n_terms=3, prune=False)
    assert set(fwd.path["action"]) == {"add"} and len(fwd.structure) == 3
    res = gb.semp(Candidates(3, 3, ne=0, degree=2), rec, tol=1e-6)
    assert res.score / np.var(rec.y[3:]) <= 1e-6 and "≤" in res.stop


def test_several_records_never_straddle():
    recs = [staircase_record(TRUE, THETA, s, n=500) for s in (5, 6)]
    res = gb.semp(Candidates(3, 3, ne=0, degree=2), recs, n_terms=len(TRUE))
    assert set(res.structure) == set(TRUE)
    joined = Record(np.concatenate([r.u for r in recs]), np.concatenate([r.y for r in recs]))
    assert res.n_rows == sum(len(r) - 3 for r in recs) < len(joined)


def test_bad_input():
    rec = staircase_record(TRUE, THETA, 0, n=200)
    cand = Candidates(3, 3, ne=0, degree=2)
    with pytest.raises(TypeError, match="Structure"):  # a list of terms is a candidate set (test_hunt46b); 3.0 none
        gb.semp(3.0, rec)
    with pytest.raises(ValueError, match="either n_terms or tol"):
        gb.semp(cand, rec, n_terms=2, tol=0.1)
    with pytest.raises(ValueError, match="n_terms"):
        gb.semp(cand, rec, n_terms=0)
    with pytest.raises(ValueError, match="criterion"):
        gb.semp(cand, rec, criterion="hqc")
    with pytest.raises(ValueError, match="tol"):
        gb.semp(cand, rec, tol=1.5)
    with pytest.raises(ValueError, match="not among"):
        gb.semp(cand, rec, include=["u(k-9)"])
    with pytest.raises(ValueError, match="max lag"):
        gb.semp(cand, Record([1.0, 2.0], [1.0, 2.0]))
    with pytest.raises(ValueError, match="no process terms"):
        gb.semp(Structure(["e(k-1)"]), rec)


def test_stopping_at_the_size_cap_warns_as_frols_does():
    rec = staircase_record(TRUE, THETA, 3, noise=0.05)
    cand = Candidates(3, 3, ne=0, degree=2)
    with pytest.warns(RuntimeWarning, match="smallest at the largest size looked at"):
        res = gb.semp(cand, rec, criterion="bic", max_terms=3)
    assert len(res.structure) == 3 and "bic minimum at 3 of 3 sizes" in res.stop
    with pytest.warns(RuntimeWarning, match="smallest at the largest size looked at"):
        gb.frols(cand, rec, criterion="bic", max_terms=3)
    with pytest.warns(RuntimeWarning, match="tolerance 1e-09 not reached"):
        res = gb.semp(cand, rec, tol=1e-9, max_terms=3)
    assert "not reached" in res.stop and len(res.structure) == 3
    # no warning when the minimum lies inside the range
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = gb.semp(cand, staircase_record(TRUE, THETA, 3), criterion="bic", max_terms=10)
    assert set(res.structure) == set(TRUE)


def test_centred_score_is_the_free_run_from_the_candidates_first_lag_samples():
    # every SEMP score is the free run from each record's first L measured outputs (L the candidates' largest lag),
    # counted from L on; with centre=True the closure's run started from its own max_lag (here 1 of L = 4), so
    # samples 1 … 3 were simulated: the same model on the same data scored 0.00974 here, 0.00988 with centre=False
    rng = np.random.default_rng(5)
    n, L = 200, 4
    recs = []
    for _ in range(2):
        u = rng.uniform(-1.0, 1.0, n)
        y = Model(Structure(["y(k-1)", "u(k-1)", "1"]), [0.8, 1.0, 2.0]).simulate(u, [10.0])
        recs.append(Record(u, y + 0.1 * rng.standard_normal(n)))
    res = gb.semp(Candidates(4, 4, ne=0, degree=1), recs, n_terms=3, centre=True)
    m = res.model
    assert set(res.structure) == {Structure(["1"])[0], Structure(["y(k-1)"])[0], Structure(["u(k-1)"])[0]}
    assert m.max_lag < L
    # by hand: the run from the measured y(L - max_lag) … y(L - 1), its errors from L on
    err = np.concatenate([m.simulate(r.u[L - m.max_lag:], r.y[L - m.max_lag:L])[m.max_lag:] - r.y[L:] for r in recs])
    assert res.score == pytest.approx(float(np.mean(err**2)), rel=1e-9)
    raw = gb.semp(Candidates(4, 4, ne=0, degree=1), recs, n_terms=3)
    assert set(raw.structure) == set(res.structure)
    assert res.score == pytest.approx(raw.score, rel=1e-9)


def test_a_small_free_run_error_at_a_large_output_level_is_not_taken_for_round_off():
    # noise-free y near 1e6 with a spread near 1: leaving out u(k-1)^2 (θ 1e-4) errs by 3.5e-5 RMS, some 1.6e5 ulps of
    # the level, where the exact structure errs by about 4; the round-off floor of 1e-20 of the output's mean square
    # (4.5e5 ulps) took the 3-term model for an exact fit (its score the floor, 1e-8, not its MSE 1.2e-9), and
    # n_terms=4 chose u(k-2), a term the system does not have
    rng = np.random.default_rng(0)
    u = rng.uniform(-1.0, 1.0, 300)
    true = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    y = Model(true, [5e5, 0.5, 1.0, 1e-4]).simulate(u, [1e6])
    rec = Record(u, y)
    cands = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-2)", "y(k-2)"])
    assert set(gb.semp(cands, rec, n_terms=4).structure) == set(true)
    res = gb.semp(cands, rec, tol=1e-12)
    assert set(res.structure) == set(true)
    three = gb.semp(cands, rec, n_terms=3)
    m = three.model
    # by hand: its free run from the measured y(1) (L = 2, the candidates' largest lag), its errors from y(2) on
    mse = float(np.mean((m.simulate(rec.slice(1, 300))[1:] - y[2:]) ** 2))
    assert 1e-10 < mse < 1e-8
    assert three.score == pytest.approx(mse, rel=1e-6)


def slow_offset_record(level, *, u_unit=1.0, y_unit=1.0, rho=0.999, n=2000, hold=100, seed=0):
    """Noise-free y(k) = c + rho y(k-1) + b u(k-1) + d u(k-1)^2 about ``level``, input steps of ``hold`` samples,
    u given in units ``u_unit`` times smaller (u_unit = 100: the same plant's u in a unit 100 × smaller), y in
    ``y_unit``."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // hold + 1), hold)[:n]
    c = 0.1 + level * (1.0 - rho)
    true = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    y = Model(true, [c, rho, 0.5, 0.2]).simulate(u, [level])
    # the same record in other units: θ's scale with them, the structure does not
    return Record(u * u_unit, y * y_unit), true


#: the true structure's terms, a lag-shifted output and two lag-shifted inputs: y(k-2) scores best on its own
SLOW_CANDIDATES = Structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-2)", "u(k-2)", "u(k-3)"])


@pytest.mark.parametrize("level,u_unit,y_unit", [(0.0, 1.0, 1.0), (1e6, 1.0, 1.0), (1e6, 100.0, 1e-3),
                                                 (-3e4, 0.01, 1e3)])
def test_a_slow_plant_at_an_offset_gets_its_true_structure(level, u_unit, y_unit):
    # at y near 1e6, once y(k-2) was in (its one-term free run the best of the first step), y(k-1) added 7.6e-8 of
    # its raw norm beyond the structure: 'collinear' by rank_tol = 1e-7, never tried, and with u(k-2)^2 not a
    # candidate no exact structure was left; semp stopped at 9.2e-7 of var y ('no candidate improves') where the
    # true 4 terms run exactly. Without the offset the same column adds 9e-4 of its norm: the test was the offset's
    rec, true = slow_offset_record(level, u_unit=u_unit, y_unit=y_unit)
    # by hand: the true structure's least-squares fit runs the record exactly (to round-off)
    X = np.column_stack([np.ones(len(rec) - 3), rec.y[2:-1], rec.u[2:-1], rec.u[2:-1] ** 2])
    theta = np.linalg.lstsq(X, rec.y[3:], rcond=None)[0]
    sim = Model(true, theta).simulate(rec.u[2:], rec.y[2:3])
    assert np.mean((sim[1:] - rec.y[3:]) ** 2) < 1e-12 * np.var(rec.y[3:])
    for kw in ({"tol": 1e-12}, {"n_terms": 4}, {}):
        res = gb.semp(SLOW_CANDIDATES, rec, **kw)
        assert set(res.structure) == set(true), kw
        assert res.score < 1e-12 * np.var(rec.y[3:])


def _exact_subsets_by_hand(rec, candidates):
    """Every subset of ``candidates`` (y(k-1), y(k-2) and input terms) whose least-squares fit runs ``rec`` exactly
    (free-run MSE below 1e-20 of var y) from y(0), y(1): numpy's lstsq, and a free run written out (for the subsets
    exact one step ahead, which every exact free run is)."""
    import itertools

    L, y, u = 2, rec.y, rec.u
    cols = {"y(k-1)": y[1:-1], "y(k-2)": y[:-2], "u(k-1)": u[1:-1], "u(k-2)": u[:-2], "u(k-1)^2": u[1:-1] ** 2,
            "u(k-2)^2": u[:-2] ** 2}
    exact, tiny = [], 1e-20 * np.var(y[L:])
    names = [str(t) for t in candidates]
    for k in range(1, len(names) + 1):
        for sub in itertools.combinations(names, k):
            X = np.column_stack([cols[n] for n in sub])
            theta = np.linalg.lstsq(X, y[L:], rcond=None)[0]
            if np.mean((X @ theta - y[L:]) ** 2) > tiny:
                continue
            a = dict(zip(sub, theta))
            x = sum(a[n] * cols[n] for n in sub if n.startswith("u")) + np.zeros(len(y) - L)
            sim = list(y[:L])
            for k_ in range(L, len(y)):
                sim.append(a.get("y(k-1)", 0.0) * sim[-1] + a.get("y(k-2)", 0.0) * sim[-2] + x[k_ - L])
            if np.mean((np.array(sim[L:]) - y[L:]) ** 2) < tiny:
                exact.append(set(sub))
    return exact


@pytest.mark.parametrize("seed", [0, 1])
def test_the_smallest_exact_structure_wins_the_tie_at_the_round_off_floor(seed):
    # noise-free y(k) = 0.99 y(k-1) + 0.5 u(k-1) + 0.2 u(k-1)^2: y(k-2), u(k-1), u(k-2), u(k-1)^2, u(k-2)^2 runs as
    # exactly (y(k-1) eliminated); semp reached those five first, and no removal keeps them exact while y(k-1), a
    # combination of them, is collinear with them: tol=1e-30 ('at its round-off floor') and bic ('bic minimum at 5
    # of 6 sizes') returned the five terms, n_terms=3 an inexact structure
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, 201), 10)[:2000]
    true = Structure(["y(k-1)", "u(k-1)", "u(k-1)^2"])
    rec = Record(u, Model(true, [0.99, 0.5, 0.2]).simulate(u, [0.0]))
    cands = Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-2)^2"])
    exact = _exact_subsets_by_hand(rec, cands)
    smallest = min(len(s) for s in exact)
    assert [s for s in exact if len(s) == smallest] == [{str(t) for t in true}]  # the case: one smallest, others
    assert any(len(s) == 5 and "y(k-1)" not in s for s in exact)
    for kw in ({"tol": 1e-30}, {}, {"n_terms": 3}):
        res = gb.semp(cands, rec, **kw)
        assert set(res.structure) == set(true), kw
        np.testing.assert_allclose(res.theta[[res.structure.index(t) for t in true]], [0.99, 0.5, 0.2], rtol=1e-9)
    # the path still changes size by one per step, and each add is its forward step's score
    adds = res.path[res.path["action"] == "add"]
    assert np.all(np.abs(np.diff(res.path["n_terms"])) == 1)
    for k, (_, row) in enumerate(adds.iterrows()):
        assert res.forward_scores.iloc[k][row["term"]] == row["score"]


@pytest.mark.parametrize("rho,level,y_unit", [(0.9999, 1e6, 1.0), (0.99999, 0.0, 1.0), (0.99999, 0.0, 1e3)])
def test_the_round_off_floor_grows_with_the_free_runs_error_amplification(rho, level, y_unit):
    # 20000 samples of a slow plant: an exact structure's least-squares free run errs by some 1/(1 - rho) ulps of the
    # output's RMS (each step's rounding, and θ's, carried on for as many steps), up to 1.7e4 here, past the fixed
    # (2^13 ulps)^2 floor: exact structures no longer tied, and tol=1e-30 and bic returned 5 or 6 terms (at rho
    # 0.99999, y + 1e6, tol=1e-30 'not reached')
    rec, true = slow_offset_record(level, y_unit=y_unit, rho=rho, n=20000)
    eps, ms = np.finfo(float).eps, np.mean(rec.y[3:] ** 2)
    X = np.column_stack([np.ones(len(rec) - 3), rec.y[2:-1], rec.u[2:-1], rec.u[2:-1] ** 2])
    theta = np.linalg.lstsq(X, rec.y[3:], rcond=None)[0]
    sim = Model(true, theta).simulate(rec.u[2:], rec.y[2:3])
    ulps = np.sqrt(np.mean((sim[1:] - rec.y[3:]) ** 2) / ms) / eps
    assert 1e2 < ulps < 1e5  # by hand: round-off, hundreds to thousands of ulps
    res = gb.semp(SLOW_CANDIDATES, rec, tol=1e-30)
    assert set(res.structure) == set(true) and "round-off floor" in res.stop
    assert set(gb.semp(SLOW_CANDIDATES, rec).structure) == set(true)
    # the floor, an exact run's score in ulps of the level: above what the run erred, below 1e3 times it
    assert ulps < np.sqrt(res.score / ms) / eps < 1e3 * ulps


_HAND_TERMS = {"1": lambda y, u, k: 1.0, "y(k-1)": lambda y, u, k: y[k - 1], "y(k-2)": lambda y, u, k: y[k - 2],
               "u(k-1)": lambda y, u, k: u[k - 1], "u(k-2)": lambda y, u, k: u[k - 2],
               "u(k-1)^2": lambda y, u, k: u[k - 1] ** 2, "u(k-1)y(k-1)": lambda y, u, k: u[k - 1] * y[k - 1],
               "y(k-1)^2": lambda y, u, k: y[k - 1] ** 2}


def _semp_by_hand(y, u, n_max, L=2):
    """Simulation-error pruning written out: numpy's lstsq, a free run from y(0), y(1), forward by the smallest
    free-run MSE among unvisited structures, then remove the term whose removal hurts least while it does not."""
    def score(S):
        X = np.array([[_HAND_TERMS[n](y, u, k) for n in S] for k in range(L, len(y))])
        theta = np.linalg.lstsq(X, y[L:], rcond=None)[0]
        sim = list(y[:L])
        for k in range(L, len(y)):
            sim.append(sum(t * _HAND_TERMS[n](sim, u, k) for t, n in zip(theta, S)))
            if abs(sim[-1]) > 1e6 * np.max(np.abs(y)):
                return np.inf  # diverging
        return float(np.mean((np.array(sim[L:]) - y[L:]) ** 2))

    S, path, visited = [], [], {frozenset()}
    while len(S) < n_max:
        tried = {c: score(S + [c]) for c in _HAND_TERMS if c not in S}
        c = min((c for c in tried if frozenset(S + [c]) not in visited), key=tried.get)
        S, current = S + [c], tried[c]
        visited.add(frozenset(S))
        path.append(("add", c))
        while len(S) > 1:
            removed = {j: score([i for i in S if i != j]) for j in S if j != c}
            j = min(removed, key=removed.get)
            if not removed[j] <= current or (frozenset(set(S) - {j}) in visited and not removed[j] < current):
                break
            S, current = [i for i in S if i != j], removed[j]
            visited.add(frozenset(S))
            path.append(("remove", j))
    return path


@pytest.mark.parametrize("seed,level,prunes", [(0, 0.0, False), (3, 1e3, True)])
def test_the_path_is_a_hand_written_simulation_error_pruning(seed, level, prunes):
    # a noisy tiny problem (no ties): every step of semp's path, adds and removals, as written out by hand
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, 41), 5)[:200]
    y = Model(Structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"]), [0.6, 1.0, 0.3, 0.2]).simulate(u, [0.0])
    y = y + 0.05 * rng.standard_normal(200) + level
    hand = _semp_by_hand(y, u, 5)
    assert any(action == "remove" for action, _ in hand) == prunes
    res = gb.semp(Structure(list(_HAND_TERMS)), Record(u, y), n_terms=5)  # looks on to 8 terms
    steps = list(zip(res.path["action"], res.path["term"]))
    assert steps[:len(hand)] == hand


@pytest.mark.parametrize("ky, ku", [(1000.0, 1.0), (1.0, 60.0), (1e-3, 1.0 / 7.0)])
def test_candidates_that_tie_to_round_off_are_taken_in_order_in_any_units(ky, ku):
    # an input of period 3: beside 1 and u(k-1), u(k-2) and u(k-3) span one space (u(k-1) + u(k-2) + u(k-3) is
    # constant), so their fits are one model and their scores differ by round-off only; the round-off took u(k-3)
    # in mlc and u(k-2) with u × 60 (on the bundled plant SEMP's 16 terms differed at y × 1000 and u × 60 by such a
    # tie, u(k-1)u(k-3) against u(k-2)u(k-3) 1.4e-14 apart, and select_graybox's semp-16 rows with them)
    u = np.tile([0.3, 1.7, 1.1], 100)
    y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)", "1"]), np.array([0.5, 1.0, 0.4, 0.2]), u, np.zeros(2))
    rec = gb.Record(u, y + 0.05 * np.random.default_rng(0).standard_normal(u.size))
    a, b = (gb.semp(gb.Candidates(1, 3, degree=1), gb.Record(r.u, r.y), n_terms=3, include=["1", "u(k-1)"])
            for r in (rec, gb.Record(rec.u * ku, rec.y * ky)))
    assert list(a.structure) == list(b.structure) == list(gb.Structure(["1", "u(k-1)", "u(k-2)"]))
    assert b.score / ky**2 == pytest.approx(a.score, rel=1e-9)
