"""mend49d: results checked on construction, frols's scaling, reports of partial stores, pe_pareto's failed
members, close equilibria, the Dask cell time limit's reason."""

from __future__ import annotations

import dataclasses
import functools
import warnings

import numpy as np
import pytest

import graybox as gb
from _reports import undrawn_figures
from conftest import STAIRCASE_THETA, STAIRCASE_TRUE, staircase_plant

CAND = gb.Candidates(2, 2, ne=0, degree=2)
TRUE = gb.Structure(STAIRCASE_TRUE)
THETA = STAIRCASE_THETA


def plant(seed, n=300, noise=0.02):
    return staircase_plant(seed, n, noise)


@functools.cache
def _selection() -> gb.GrayboxSelection:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(CAND, plant(1), validation=plant(2), test=plant(3), estimator="ls", sizes=[3],
                                 progress=False)


# -- 1. a GrayboxSelection's table is checked on construction -------------------------------------------------------

@pytest.mark.parametrize("column, value", [("JS_test", "abc"), ("JS_test", "0.5"), ("JS_test", "array"),
                                           ("JS_valid", "x"), ("JSF_test", True), ("in_band", "False"),
                                           ("rank", 1.5), ("vs_best", None)])
def test_a_selection_whose_table_holds_text_or_arrays_for_figures_is_refused_naming_the_column(column, value):
    """dataclasses.replace(sel, table=...) with text (or arrays) in JS_test was accepted (the check of negative figures
    coerced text to NaN); regret then failed with NumPy's bare "could not convert string to float"."""
    sel = _selection()
    table = sel.table
    if value == "array":
        table[column] = [np.array([1.0, 2.0])] * len(table)
    elif value is None:
        table[column] = table[column].astype(object)
        table.iloc[0, table.columns.get_loc(column)] = None
    else:
        table[column] = value
    with pytest.raises(TypeError, match=f"GrayboxSelection: the table's column '{column}' must hold"):
        dataclasses.replace(sel, table=table)


def test_a_selection_whose_table_repeats_a_column_is_refused():
    sel = _selection()
    table = sel.table
    table.insert(0, "JS_test", table["JS_test"], allow_duplicates=True)
    with pytest.raises(ValueError, match=r"column\(s\) \['JS_test'\] appear more than once"):
        dataclasses.replace(sel, table=table)


def test_a_selection_rebuilt_from_its_own_table_and_of_object_columns_of_numbers_is_kept():
    sel = _selection()
    again = dataclasses.replace(sel, table=sel.table)
    assert again.regret == sel.regret >= 1
    table = sel.table
    table["JS_test"] = table["JS_test"].astype(object)  # numbers all the same
    assert dataclasses.replace(sel, table=table).regret == sel.regret


# -- 2. frols gives the same structure in any units where the data are finite ---------------------------------------

from hypothesis import HealthCheck, assume, given, settings, strategies as st  # noqa: E402


def _expected_theta(sel: gb.Selection, sy: float, su: float) -> np.ndarray:
    """θ of the data y·sy, u·su from θ of the data themselves: a term y^a u^b scales as sy^(1-a) su^(-b)."""
    out = []
    for t, th in zip(sel.structure, sel.theta):
        a = sum(p for s, _, p in t.factors if s == "y")
        b = sum(p for s, _, p in t.factors if s == "u")
        out.append(th * sy / sy**a / su**b if a <= 1 else th / sy ** (a - 1) / su**b)
    return np.array(out)


@pytest.mark.parametrize("method", ["mgs", "gram"])
@pytest.mark.parametrize("sy, su", [(1e-200, 1.0), (1e160, 1.0), (1e-300, 1.0), (1e300, 1.0), (1.0, 1e100),
                                    (1e-200, 1e-150)])
def test_frols_chooses_the_same_structure_whatever_the_scale_of_finite_data(method, sy, su):
    """y × 1e-200 was "identically zero" (yᵀy underflowed to 0) and y × 1e160 raised (y² overflowed in the candidate
    columns), though the columns are scaled to unit RMS so that the result does not depend on units."""
    r = plant(1)
    base = gb.frols(CAND, r, n_terms=5, method=method)
    sel = gb.frols(CAND, gb.Record(r.u * su, r.y * sy, name="scaled"), n_terms=5, method=method)
    assert list(sel.structure) == list(base.structure)
    np.testing.assert_allclose(sel.err, base.err, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sel.theta, _expected_theta(base, sy, su), rtol=1e-10)
    assert np.all(np.isfinite(sel.criterion_curve))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ey=st.integers(-1000, 1000), eu=st.integers(-300, 300), search=st.sampled_from(["greedy", "swap"]))
def test_frols_on_data_scaled_by_powers_of_two_is_the_same_selection_bit_for_bit(ey, eu, search):
    """A power of two scales every column exactly: where y·2^ey and u·2^eu are normal numbers, the choice, ERR and the
    criterion's differences are those of the data themselves, θ theirs times powers of two."""
    r = plant(1, n=150)
    y, u = np.ldexp(r.y, ey), np.ldexp(r.u, eu)
    assume(np.all(np.abs(y[y != 0]) >= np.finfo(float).tiny) and np.all(np.abs(u[u != 0]) >= np.finfo(float).tiny))
    assume(np.all(np.isfinite(y)) and np.all(np.isfinite(u)))
    base = gb.frols(CAND, r, criterion="bic", search=search)
    shift = [ey - sum(p * (ey if s == "y" else eu) for s, _, p in t.factors) for t in base.structure]
    with np.errstate(over="ignore", under="ignore"):
        # θ in the scaled units a normal float (u(k-2)² at y·2^-418, u·2^300 is 0.05·2^-1018, subnormal: refused
        # by name as beyond the float range, no bit-for-bit θ to compare)
        assume(np.all(np.abs(np.ldexp(base.theta, shift)) >= np.finfo(float).tiny)
               and np.all(np.isfinite(np.ldexp(base.theta, shift))))
    sel = gb.frols(CAND, gb.Record(u, y, name="scaled"), criterion="bic", search=search)
    assert list(sel.structure) == list(base.structure)
    np.testing.assert_array_equal(sel.err_evaluated, base.err_evaluated)
    with np.errstate(over="ignore", under="ignore"):
        np.testing.assert_array_equal(sel.theta, np.ldexp(base.theta, shift))
    np.testing.assert_allclose(np.diff(sel.criterion_curve), np.diff(base.criterion_curve), rtol=1e-9, atol=1e-9)


# -- 3. the reports of a results frame lacking columns they do not read ----------------------------------------------

@pytest.fixture(scope="module")
def grid_results(tmp_path_factory):
    from graybox import experiments as gx

    structures = [gx.StructureSpec(f"s{i}", terms=["1", "y(k-1)", "u(k-1)", t]) for i, t in enumerate(["y(k-2)",
                                                                                                      "u(k-2)"])]
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structures, [gx.Variant("LS", "ls")], name="few")
    path = tmp_path_factory.mktemp("mend49d") / "few.sqlite"
    gx.run_grid(grid, path, progress=False)
    return gb.load_results(path)


@pytest.fixture(scope="module")
def full_leaderboard(grid_results, tmp_path_factory):
    """leaderboard.csv of the report of the whole frame (written once, not in each case below: its figures cost)."""
    from graybox import experiments as gx

    full = tmp_path_factory.mktemp("full")
    with pytest.MonkeyPatch.context() as m:
        undrawn_figures(m)  # its leaderboard.csv is read
        gx.write_report(grid_results, full, rule="chosen")
    return (full / "leaderboard.csv").read_text()


@pytest.mark.parametrize("drop", [["key"], ["theta"], ["warnings"], ["key", "theta", "warnings", "worker", "version"]])
def test_write_report_of_a_frame_without_the_columns_only_cells_csv_copies_writes_the_rest(grid_results, tmp_path,
                                                                                           drop, full_leaderboard,
                                                                                           monkeypatch):
    """A frame without key, theta or warnings (the leaderboard, heat maps and figures read none of them) failed
    write_report with a bare KeyError from cells.csv's copy; now cells.csv is written without them."""
    import matplotlib

    matplotlib.use("Agg")
    from graybox import experiments as gx

    if len(drop) == 1:  # the figures are drawn once, of the frame without all five columns (the last case)
        undrawn_figures(monkeypatch)
    written = gx.write_report(grid_results.drop(columns=drop), tmp_path, rule="chosen", html=True)
    assert {p.name for p in written} >= {"cells.csv", "leaderboard.csv", "summary.txt", "report.html"}
    head = (tmp_path / "cells.csv").read_text().splitlines()[0].split(",")
    assert not set(drop) & set(head) and {"data", "structure", "variant", "JS_valid"} <= set(head)
    assert (tmp_path / "leaderboard.csv").read_text() == full_leaderboard


@pytest.mark.parametrize("drop", [["JS_valid"], ["members", "band"]])
def test_the_reports_refuse_a_frame_without_a_column_they_read_naming_it(grid_results, tmp_path, drop):
    from graybox import experiments as gx

    for call in (lambda t: gx.leaderboard(t, rule="chosen"), lambda t: gx.write_report(t, tmp_path, rule="chosen")):
        with pytest.raises(ValueError, match=r"missing columns \[" + ", ".join(f"'{c}'" for c in sorted(drop))):
            call(grid_results.drop(columns=drop))


# -- 4. pe_pareto: a member whose solve stops at the solver's limit is a failed member --------------------------------

PE_ST = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])


def test_pe_pareto_keeps_a_member_the_solver_did_not_finish_as_a_failed_member():
    """solver_options={"max_iter": 1} for OSQP stopped the first member short of its optimum, and that one member's
    ValueError ended the whole sweep; the member solved in one iteration (λ1 = 1, least squares) was lost with it."""
    data = gb.load_pumping()
    lam = np.logspace(-4, 0, 5)
    front = gb.pe_pareto(PE_ST, data, lambdas=lam, solver="osqp", solver_options={"max_iter": 1})
    full = gb.pe_pareto(PE_ST, data, lambdas=lam, solver="osqp")
    assert set(front.failures) == {0, 1, 2, 3}
    assert all(f"λ1 = {lam[i]:g}: solver osqp stopped at its iteration or time limit" in why
               for i, why in front.failures.items())
    np.testing.assert_allclose(front.thetas[4], full.thetas[4], rtol=1e-6)
    assert np.isfinite(front.JS[4]) and np.all(np.isinf(np.asarray(front.JS)[:4]))
    assert gb.decide_dsf(front, band=1e9).lambda1 == 1.0  # the failed members cannot be chosen


def test_pe_pareto_fails_when_every_member_stopped_at_the_solver_limit_naming_them():
    data = gb.load_pumping()
    with pytest.raises(ValueError, match=r"λ1 = 0\.1, 0\.01 \(2 members\): solver osqp stopped at its iteration") as e:
        gb.pe_pareto(PE_ST, data, lambdas=[0.1, 0.01], solver="osqp", solver_options={"max_iter": 1})
    assert not isinstance(e.value, gb.InfeasibleError)
    with pytest.raises(ValueError, match="stopped at its iteration"):  # pe_thetas: every λ1 or none, as before
        gb.pe_thetas(PE_ST, data, lambdas=[1.0, 0.1], solver="osqp", solver_options={"max_iter": 1})


# -- 5. close equilibria: one root when the coefficients cannot tell them apart, two when they can --------------------

def _static_roots_model(roots, scale: float, ys: float = 1.0, us: float = 1.0) -> gb.Model:
    """ȳ = F(ȳ) + ū/us·us whose static equation at ū = us is scale/ys · ∏ (ȳ − r·ys) = 0 (y in units ys: the same
    model in other units, F' the same at the roots)."""
    c = np.polynomial.polynomial.polyfromroots(np.asarray(roots, float) * ys) * (scale / ys)
    terms = ["y(k-1)"] + [f"y(k-1)^{p}" for p in range(2, len(c))] + ["u(k-1)"]
    return gb.Model(terms, [c[1] + 1, *c[2:], c[0] / us])


@pytest.mark.parametrize("scale", [1.0, 10.0, -1.0])
@pytest.mark.parametrize("ys", [1.0, 1e-30, 1e40])
def test_two_distinct_roots_1_2e_7_apart_are_two_equilibria_not_a_fold(scale, ys):
    """Roots 1 and 1 + 1.2e-7 (y's scale 1) were merged into one 'fold' at their midpoint: the merge read |F(mid)| =
    F''δ²/8 = 3.6e-15 against Horner's worst-case bound 2 (D + 1) eps Σ|c_p||x|^p = 5.3e-15, a rounding error six times
    what the coefficients carry; a change within the coefficients' own rounding does not make them one root."""
    eqs = _static_roots_model([1.0, 1.0 + 1.2e-7], scale, ys).equilibria(1.0)
    assert len(eqs) == 2, eqs
    np.testing.assert_allclose([e.ybar / ys for e in eqs], [1.0, 1.0 + 1.2e-7], rtol=1e-8)  # each to its conditioning
    assert eqs[0].stable != eqs[1].stable  # F' of either sign: one of them attracts (scale < 0: the lower one)


@settings(max_examples=60, deadline=None)
@given(r=st.floats(-3, 3), others=st.lists(st.floats(-3, 3), max_size=3), scale_exp=st.floats(-2, 2),
       negative=st.booleans(), ys_exp=st.floats(-4, 4), us_exp=st.floats(-2, 2))
def test_a_double_root_is_at_most_one_equilibrium_and_never_stable(r, others, scale_exp, negative, ys_exp, us_exp):
    """Rounding splits a double root of the stored coefficients into two roots ~√eps apart (or a complex pair):
    read against the coefficients' conditioning it stays one equilibrium, a fold (not asymptotically stable)."""
    assume(all(abs(o - r) > 0.05 for o in others))
    ys, us = 10.0**ys_exp, 10.0**us_exp
    model = _static_roots_model([r, r, *others], (-1.0 if negative else 1.0) * 10.0**scale_exp, ys, us)
    near = [e for e in model.equilibria(us) if abs(e.ybar - r * ys) <= 1e-4 * max(abs(r), 0.05) * ys]
    assert len(near) <= 1, near
    assert all(not e.stable for e in near)


# -- 6. the Dask executor's cell time limit says which process it stopped ---------------------------------------------

def _hang_on_ls(marker_dir: str, cell, data, threads):
    """Run a cell, except: variant "LS" writes its pid and sleeps for ten minutes (a cell that hangs)."""
    import os
    import time
    from pathlib import Path

    from graybox.experiments._cell import run_cell

    if cell.variant == "LS":
        (Path(marker_dir) / f"{cell.key}.{os.getpid()}").touch()
        time.sleep(600)
    return run_cell(cell, data, threads=threads)


def test_a_cell_stopped_past_the_time_limit_on_dask_says_its_child_process_was_stopped_not_its_worker(tmp_path):
    """On Dask a cell under a time limit runs in a child process of its worker, and only that child is stopped and
    replaced; the failed row said "(its worker was stopped)", which reads as the Dask worker lost."""
    import os
    from functools import partial

    from graybox import experiments as gx
    from graybox.experiments._executors import DaskCluster

    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                [gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])],
                [gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "equality"}])], name="limit")
    datasets = g.load_data()
    cells = g.cells(datasets)
    data = {c.data_hash: datasets[c.data] for c in cells}
    with DaskCluster(workers=1, fn=partial(_hang_on_ls, str(tmp_path)), time_limit=5.0).session() as ex:
        rows = {r["variant"]: r for r in ex.run(cells, data)}
        worker_pids = set(ex._kept.run(os.getpid).values())  # the session's client: its LocalCluster's workers
    msg = rows["LS"]["message"]
    assert rows["LS"]["status"] == "failed" and "cell time limit of 5 s" in msg
    assert "its child process on its Dask worker was stopped and replaced; the Dask worker itself runs on" in msg
    assert "its worker was stopped" not in msg
    assert rows["CLS"]["status"] == "ok"
    (marker,) = tmp_path.glob("*.*")
    assert worker_pids and int(marker.suffix[1:]) not in worker_pids  # it ran in a child, not in the Dask worker
    with pytest.raises(ProcessLookupError):  # and that child was stopped
        os.kill(int(marker.suffix[1:]), 0)


def test_a_cell_stopped_past_the_time_limit_in_a_process_pool_names_its_worker_process(tmp_path):
    from functools import partial

    from graybox import experiments as gx
    from graybox.experiments._executors import ProcessPool

    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                [gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "1"])], [gx.Variant("LS", "ls")],
                name="limit")
    datasets = g.load_data()
    cells = g.cells(datasets)
    (row,) = ProcessPool(1, partial(_hang_on_ls, str(tmp_path)), time_limit=3.0).run(
        cells, {c.data_hash: datasets[c.data] for c in cells})
    assert row["status"] == "failed" and "(its worker process was stopped and replaced)" in row["message"]


@pytest.mark.parametrize("scale", [-0.5, -0.005, -5e-4, 0.003])
def test_a_double_root_of_a_quadratic_whose_y_coefficient_cancels_is_one_equilibrium_not_none(scale):
    """ȳ = θ1 ȳ + θ2 ȳ² + ū with θ1 = 1 + c1 near 1: the static coefficient c1 = θ1 − 1 is known to eps (of θ1), not
    to eps of itself, and rounding pushed the discriminant of the double root at 1.5 below 0 by more than its own
    rounding: at scale −0.005 the model had no equilibrium at all."""
    c = np.polynomial.polynomial.polyfromroots([1.5, 1.5]) * scale
    model = gb.Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [c[1] + 1, c[2], c[0]])
    eqs = model.equilibria(1.0)
    assert len(eqs) == 1 and eqs[0].ybar == pytest.approx(1.5, rel=1e-7) and not eqs[0].stable


@pytest.mark.parametrize("scale", [-0.5, -0.005, -5e-4, 0.005])
def test_a_double_root_beside_a_simple_one_of_a_cubic_whose_y_coefficient_cancels_is_kept(scale):
    """The same in a cubic's deflated quadratic: at scale −0.005, c (ȳ − 1.5)² (ȳ + 1) had only the equilibrium −1."""
    c = np.polynomial.polynomial.polyfromroots([1.5, 1.5, -1.0]) * scale
    model = gb.Model(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "u(k-1)"], [c[1] + 1, *c[2:], c[0]])
    ys = [e.ybar for e in model.equilibria(1.0)]
    np.testing.assert_allclose(ys, [-1.0, 1.5], rtol=1e-7)


def test_options_the_solver_refuses_end_the_sweep_at_its_first_solve(monkeypatch):
    """a07e3bc kept a solver's refusal of the options as one member's failure: every λ1 was tried, OSQP printing its
    error twice each (review49e): the options are the call's, refused at the first solve."""
    import graybox.estimation._prediction_error as pe

    solves = []
    original = pe._QP.solve

    def counted(self, *args, **kwargs):
        solves.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(pe._QP, "solve", counted)
    data = gb.load_pumping()
    st = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
    with pytest.raises(ValueError, match="solver_options"):
        gb.pe_pareto(st, data.ident, data.static, lambdas=np.logspace(-3, 0, 10), solver="osqp",
                     solver_options={"eps_abs": -1})
    assert len(solves) == 1
