"""select_graybox: a fit's warnings belong to its row of the table, from any executor, and are said once."""

import warnings

import numpy as np
import pytest

import graybox as gb
import graybox.experiments._select as sel

TRUE = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
THETA = np.array([0.7, 0.3, 0.05, 0.2])


def _record(seed, n=400):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    y = gb.simulate(TRUE, THETA, u, np.zeros(1)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, name=f"r{seed}")


def _noisy_ls(monkeypatch, sizes):
    fit_ls = sel._BLACK_BOX_FITS["ls"]

    def noisy_ls(st, rec):  # some structure sizes warn, as a fit may (an ELS that did not converge …)
        if len(st) in sizes:
            warnings.warn("this fit is doubtful", RuntimeWarning)
        return fit_ls(st, rec)

    monkeypatch.setitem(sel._BLACK_BOX_FITS, "ls", noisy_ls)


@pytest.mark.parametrize("one_record", [False, True], ids=["validation record", "folds"])
def test_a_members_warning_is_in_its_row_and_said_once_by_the_call(monkeypatch, one_record):
    _noisy_ls(monkeypatch, {2})
    data = _record(1) if one_record else gb.Dataset(_record(1), _record(2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=np.inf, estimator="ls", sizes=[2, 4])
    said = res.table["warnings"]
    two = res.table["n_terms"] == 2
    assert two.any() and (~two).any()
    # once per row, though with folds the row's structure is fitted once per fold and once on all
    assert (said[two] == "RuntimeWarning: this fit is doubtful").all()
    assert (said[~two] == "").all()
    # nothing but the call's own summary reaches the caller
    assert [w.category for w in caught] == [gb.SelectionWarning]
    msg = str(caught[0].message)
    assert f"{int(two.sum())} of {len(said)} structure × estimator rows warned" in msg
    assert ("the chosen row's: RuntimeWarning" in msg) == bool(said.iloc[0])


def test_the_summary_says_when_the_chosen_row_warned(monkeypatch):
    _noisy_ls(monkeypatch, {2, 4})
    with pytest.warns(gb.SelectionWarning, match="the chosen row's: RuntimeWarning: this fit is doubtful"):
        res = gb.select_graybox(gb.Candidates(2, 2, degree=2), gb.Dataset(_record(1), _record(2)), band=np.inf,
                                estimator="ls", sizes=[2, 4])
    assert (res.table["warnings"] != "").all()


def test_the_callers_filters_hold_in_the_fits(monkeypatch):
    _noisy_ls(monkeypatch, {2})
    data = gb.Dataset(_record(1), _record(2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warnings.filterwarnings("ignore", "this fit is doubtful")
        res = gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=np.inf, estimator="ls", sizes=[2, 4])
    assert (res.table["warnings"] == "").all() and not caught  # ignored: not kept, nothing said
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(RuntimeWarning, match="doubtful"):
            gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=np.inf, estimator="ls", sizes=[2, 4])


def test_no_warning_no_column_text_no_summary():
    data = gb.Dataset(_record(3), _record(4))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the suite's own rule, said here too
        res = gb.select_graybox(gb.Candidates(2, 2, degree=2), data, band=np.inf, estimator="ls", sizes=[2, 4])
    assert (res.table["warnings"] == "").all()


def test_a_worker_process_warning_reaches_the_driver_through_the_table():
    """The bundled plant's black box: one ELS fit (SEMP's 4-term structure) does not converge. In a worker
    process its warning would never reach the caller; the table carries it and the call says it."""
    data = gb.load_pumping()
    with pytest.warns(gb.SelectionWarning, match="1 of 28 structure × estimator rows warned") as rec:
        res = gb.select_graybox(gb.Candidates(6, 6, degree=2), data, band=np.inf, executor="processes", workers=2,
                                estimator=("ls", "els"))
    assert all(w.category is gb.SelectionWarning for w in rec)
    row = res.table[res.table["warnings"] != ""]
    assert list(row["estimator"]) == ["els"]
    assert row["warnings"].iloc[0].startswith("ELSConvergenceWarning: ELS did not converge in 500 iterations")
