"""Bug hunt 45c: issue 26's promises (select_graybox, frols, semp, output_error) on small plants of one's own."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.static._form_check import carried_degree, static_terms


def _plant(n, seed, noise=0.02, hold=10):
    """A first-order NARX plant under a staircase in 0..2: y(k) = 0.8 y(k-1) + 0.5 u(k-1) + 0.1 u(k-1)² + 0.3."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // hold + 1), hold)[:n]
    y = np.zeros(n)
    y[0] = (0.5 * u[0] + 0.1 * u[0] ** 2 + 0.3) / 0.2
    for k in range(1, n):
        y[k] = 0.8 * y[k - 1] + 0.5 * u[k - 1] + 0.1 * u[k - 1] ** 2 + 0.3
    return gb.Record(u, y + noise * np.std(y) * rng.standard_normal(n), name=f"run {seed}")


def _static(delta=0.05):
    ub = np.linspace(0.0, 1.9, 5)
    return gb.StaticPoints(ub, (0.5 * ub + 0.1 * ub ** 2 + 0.3) / 0.2, uncertainty=np.full(5, delta))


# --- a gray box of candidates without output terms (NFIR) ------------------------------------------------------
def test_a_candidate_set_without_output_terms_carries_a_polynomial_static_curve():
    # with no y term the static function is the numerator alone (Σy = 0): the clusters Σ0 … Σ_{u^d} carry a
    # degree-d curve; Σy was asked all the same, and select_graybox refused an NFIR gray box ("they need
    # output terms (Σy)") that pe_pareto and se_dsf fit
    cand = gb.Candidates(ny=0, nu=4, degree=2)
    assert carried_degree(cand, 2) == 2
    assert static_terms(gb.parse_structure("u(k-2)"), cand, 2) == [gb.parse_structure("1")[0],
                                                                   gb.parse_structure("u(k-1)^2")[0]]


def test_select_graybox_chooses_a_gray_box_among_nfir_structures():
    data = gb.Dataset(_plant(200, 1), _plant(150, 2), _static())
    sel = gb.select_graybox(gb.Candidates(ny=0, nu=4, degree=2), data, estimator="pe", sizes=[4, 6])
    assert sel.in_band and sel.degree == 2
    assert not any(t.power_of("y") for t in sel.structure)
    # the chosen static curve meets the points within the band
    assert gb.jsf(sel.model, data.static) <= sel.band


# --- semp at the largest size a short record allows ----------------------------------------------------------------
def _short_random(n, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, 2.0, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.8 * y[k - 1] + 0.5 * u[k - 1] + 0.1 * u[k - 1] ** 2 + 0.3
    return gb.Record(u, y + 0.05 * rng.standard_normal(n))


def test_semp_warns_when_its_criterion_is_smallest_where_the_records_rows_end():
    # 10 samples, lags 2: 8 regression rows, so the default max_terms is 7 of 15 candidates. BIC smallest at 7
    # terms has met the record's end (the model interpolates it), which frols says in these words; semp chose
    # it silently
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    rec = _short_random(10, 2)
    with pytest.warns(RuntimeWarning, match="largest size the data allow"):
        f = gb.frols(cand, rec, criterion="bic")
    assert len(f.structure) == 7
    with pytest.warns(RuntimeWarning, match="largest size the data allow") as said:
        s = gb.semp(cand, rec)
    assert len(s.structure) == 7 == s.path["n_terms"].max()
    assert "8 regression rows" in str(said[0].message)


def test_semp_says_nothing_of_the_rows_when_its_minimum_lies_below_them():
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    rec = _plant(120, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = gb.semp(cand, rec)
    assert len(s.structure) < s.path["n_terms"].max()


def test_select_graybox_keeps_the_rows_cap_warning_of_its_own_path_to_itself():
    # select_graybox grows the SEMP path to the sizes it compares on other data: that the criterion is smallest
    # at the largest size (candidates' or rows') is no news to its caller
    # two records of 9 samples: 14 regression rows, so the path stops at 13 terms of 15 candidates
    recs = [_short_random(9, 4), _short_random(9, 14)]
    with pytest.warns(RuntimeWarning, match="largest size the data allow"):
        gb.semp(gb.Candidates(ny=2, nu=2, degree=2), recs, max_terms=13)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("ignore", gb.experiments.SelectionWarning)
        sel = gb.select_graybox(gb.Candidates(ny=2, nu=2, degree=2), recs, validation=_short_random(60, 5),
                                estimator="ls", sources=["semp"])
    assert len(sel.table)


# --- a centred search of an output that never moves --------------------------------------------------------------
@pytest.mark.parametrize("level", [4.5, 7.3, 1e4 + 0.1])
def test_a_centred_search_of_a_constant_output_is_refused_saying_so_whatever_its_level(level):
    # centred on its mean, a constant output is zero: at 4.5 (whose mean is exact in floating point) the searches
    # said "the output is identically zero", untrue of y = 4.5; at 7.3 (mean off by round-off) they ranked
    # structures on that round-off, and select_graybox chose a 4-term model of a constant
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    rec = gb.Record(np.random.default_rng(0).uniform(0.0, 2.0, 100), np.full(100, level))
    calls = [lambda: gb.frols(cand, rec, centre=True, criterion="bic"), lambda: gb.semp(cand, rec, centre=True),
             lambda: gb.select_graybox(cand, rec, centre=True, estimator="ls")]
    for call in calls:
        with pytest.raises(ValueError, match=r"the output is constant \(y = ") as err:
            call()
        assert "identically zero" not in str(err.value) and "centre" in str(err.value)


# --- a centred search with an input held over the identification record ------------------------------------------
def _rig(n, seed, hold=8):
    """y(k) = 1.1 y(k-1) − 0.3 y(k-2) + 0.4 s(k-1) + 0.2 v(k-2) + 0.05 s(k-1) v(k-2) + 0.3 under staircases in s, v."""
    rng = np.random.default_rng(seed)
    s = np.repeat(rng.uniform(0.0, 2.0, n // hold + 1), hold)[:n]
    v = np.repeat(rng.uniform(0.0, 3.0, n // (hold + 3) + 1), hold + 3)[:n]
    y = np.zeros(n)
    y[:2] = (0.4 * s[0] + 0.2 * v[0] + 0.05 * s[0] * v[0] + 0.3) / 0.2
    for k in range(2, n):
        y[k] = 1.1 * y[k - 1] - 0.3 * y[k - 2] + 0.4 * s[k - 1] + 0.2 * v[k - 2] + 0.05 * s[k - 1] * v[k - 2] + 0.3
    return s, y + 0.02 * np.std(y) * np.random.default_rng(seed + 7).standard_normal(n)


def test_a_centred_search_is_the_same_whatever_level_an_input_is_held_at():
    # one record, only the held valve's recorded level differs: its terms are constants, which centred are zero at
    # 1.5 (whose mean is exact in floating point) and a column of round-off at 7.3 or 1e4 + 0.3. semp took those
    # for candidates (15 sizes instead of 14) and chose 'speed(k-2) + 1' there, a 6-term structure at 1.5
    cand = gb.Candidates(ny=2, nu=2, degree=2, input_names=("speed", "valve"))
    s, y = _rig(200, 1)
    found = []
    for level in (1.5, 7.3, 1e4 + 0.3):
        rec = gb.Record(np.c_[s, np.full(200, level)], y, input_names=("speed", "valve"))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.CandidateWarning)  # the valve's terms, which the record cannot tell
            found.append((frozenset(map(str, gb.semp(cand, rec, centre=True).structure)),
                          frozenset(map(str, gb.frols(cand, rec, centre=True, criterion="bic").structure))))
    assert found[0] == found[1] == found[2]
    assert len(found[0][0]) > 2


# --- the default include and candidates without the constant ----------------------------------------------------
def test_select_graybox_says_its_default_include_is_what_candidates_without_a_constant_lack():
    # include was not given: the refusal read "included term 1 is not among the process candidates"
    cand = gb.Candidates(ny=2, nu=2, degree=2, constant=False)
    data = gb.Dataset(_plant(150, 1), _plant(120, 2))
    with pytest.raises(ValueError, match=r"include defaults to the constant.*constant=False.*include=\(\)"):
        gb.select_graybox(cand, data, estimator="ls")
    # what it advises runs: a black box without the constant
    sel = gb.select_graybox(cand, data, estimator="ls", include=(), sizes=[4])
    assert "1" not in map(str, sel.structure)


# --- a validation record too short for one block of the minimum length -----------------------------------------
def test_the_fewer_blocks_warning_does_not_claim_a_block_longer_than_the_record():
    # 9 samples, lags 2: 7 error samples, said to "make 1 block(s) of at least 10 samples"
    with pytest.warns(gb.experiments.SelectionWarning, match="blocks") as said:
        gb.select_graybox(gb.Candidates(ny=2, nu=2, degree=2), _plant(150, 1), validation=_plant(9, 2),
                          estimator="ls", sizes=[4])
    text = " ".join(str(w.message) for w in said if "block" in str(w.message))
    assert "at least 10 samples" not in text or "too few" in text
    assert "7 error samples" in text and "one block" in text


# --- static points on a grid with an input at two levels ----------------------------------------------------------
def _curved_in_speed(s, v):
    return 0.4 * s + 0.3 * s ** 2 + 0.2 * v + 0.3


def test_points_at_two_levels_of_one_input_still_ask_the_curvature_of_the_other():
    # a static test at 4 speeds × 2 valve positions, curved in speed: the full quadratic surface needs valve²,
    # which two valve levels cannot determine, so the degree stopped at 1 (MSE 0.43, band 0.0025), silently, and
    # the structures were not completed with Σspeed². The monomials the points determine (each input's power
    # below its number of levels) fit it at degree 2
    from graybox.static._form_check import static_degree, static_fit_mse
    g = np.array([(a, b) for a in (0.0, 0.6, 1.3, 2.0) for b in (0.5, 2.5)])
    pts = gb.StaticPoints(g, _curved_in_speed(g[:, 0], g[:, 1]) / 0.2, input_names=("speed", "valve"),
                          uncertainty=np.full(len(g), 0.05))
    assert static_fit_mse(pts, 1) > pts.band
    assert static_fit_mse(pts, 2) < 1e-20  # s², sv determined; v² is not asked of two levels
    assert static_degree(pts, band=pts.band) == 2
    # a full grid determines the full surface as before
    full = np.array([(a, b) for a in (0.0, 1.0, 2.0) for b in (0.5, 1.5, 2.5)])
    grid = gb.StaticPoints(full, _curved_in_speed(full[:, 0], full[:, 1]), input_names=("speed", "valve"))
    assert static_degree(grid, band=1e-6) == 2


def test_select_graybox_completes_the_structures_with_the_curvature_two_valve_levels_leave_determined():
    rng = np.random.default_rng(1)

    def run(n, name):
        s = np.repeat(rng.uniform(0, 2, n // 8 + 1), 8)[:n]
        v = np.repeat(rng.uniform(0, 3, n // 11 + 1), 11)[:n]
        y = np.zeros(n)
        y[0] = _curved_in_speed(s[0], v[0]) / 0.2
        for k in range(1, n):
            y[k] = 0.8 * y[k - 1] + _curved_in_speed(s[k - 1], v[k - 1])
        return gb.Record(np.c_[s, v], y + 0.02 * np.std(y) * rng.standard_normal(n), input_names=("speed", "valve"),
                         name=name)

    g = np.array([(a, b) for a in (0.1, 0.6, 1.3, 1.9) for b in (0.5, 2.5)])
    pts = gb.StaticPoints(g, _curved_in_speed(g[:, 0], g[:, 1]) / 0.2, input_names=("speed", "valve"),
                          uncertainty=np.full(len(g), 0.05))
    sel = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2, input_names=("speed", "valve")),
                            gb.Dataset(run(250, "ident"), run(200, "valid"), pts), estimator="pe", sizes=[3, 4])
    assert sel.degree == 2 and sel.in_band
    for row in sel.table.index.unique():  # every structure carries Σspeed²
        assert "speed(k-1)^2" in map(str, sel.structure_of(row))
