"""A newcomer's first hour (first36): the messages met on a lab's own files say what to do.

Each test failed before its fix: a logger's header block was reported as a delimiter problem, a
column name given as the static points' uncertainty as a bare type error, and a closed loop that
diverged through ``narx_iosystem`` as numpy overflow warnings and python-control's "algebraic loop
detected" (there is no algebraic loop: the system has no feedthrough).
"""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox import Model

BLOCKS = {
    "plain": "# Logger TL-400 serial 0412\n# started 2026-11-20 09:14:03\n",
    # a block whose lines hold the delimiters too must not be taken for mixed delimiters or short rows
    "with delimiters": "Logger TL-400, serial 0412\nchannels: speed (rpm), pressure (Pa); period 0.5 s\n",
}


@pytest.mark.parametrize("block", list(BLOCKS))
def test_a_header_block_before_the_column_names_is_named_with_its_lines(tmp_path, block):
    rows = "".join(f"{0.5 * k},{1500 + k},{2e5 + k}\n" for k in range(20))
    path = tmp_path / "run.log"
    path.write_text(BLOCKS[block] + "time_s,speed,pressure\n" + rows, encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 3 names the columns.*2 line\(s\) before") as err:
        gb.load_record_csv(path, u="speed", y="pressure", time="time_s")
    assert "delimiter=" not in str(err.value)  # the delimiter was never the problem
    assert "skiprows=2" in str(err.value)  # what to do
    steady = tmp_path / "steady.csv"
    steady.write_text(BLOCKS[block] + "speed,pressure\n1000,1.5e5\n2000,2e5\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 3 names the columns"):
        gb.load_static_csv(steady, u="speed", y="pressure")


def test_a_column_missing_from_a_file_without_a_header_block_is_still_said_as_before(tmp_path):
    path = tmp_path / "run.csv"
    path.write_text("time_s,speed,pressure\n" + "".join(f"{0.5 * k},{k},{k}\n" for k in range(5)), encoding="utf-8")
    with pytest.raises(ValueError, match=r"no column 'speeed'.*Did you mean 'speed'"):
        gb.load_record_csv(path, u="speeed", y="pressure", time="time_s")


def test_a_column_name_given_as_uncertainty_reads_that_column(tmp_path):
    # was a TypeError saying to read the column's values yourself (loaders36: a str names the column)
    path = tmp_path / "steady.csv"
    path.write_text("speed,pressure,sem\n1000,1.5e5,150\n2000,2e5,150\n", encoding="utf-8")
    points = gb.load_static_csv(path, u="speed", y="pressure", uncertainty="sem")
    assert points.band == pytest.approx(150.0**2)


def test_a_diverging_loop_through_narx_iosystem_raises_divergence_error_naming_the_time():
    ct = pytest.importorskip("control")
    unstable = Model(["y(k-1)", "u(k-1)"], [1e3, 1.0], name="runaway")
    sys = gb.narx_iosystem(unstable, Ts=0.5)
    t = 0.5 * np.arange(400)
    with pytest.raises(gb.DivergenceError, match=r"runaway.*t = \d+(\.\d+)? s") as err:
        ct.input_output_response(sys, t, np.ones(t.size), np.array([1.0, 0.0]))
    assert "controller" in str(err.value)
    # a stable model is untouched: its response is the free run of Model.simulate
    stable = Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    out = ct.input_output_response(gb.narx_iosystem(stable, Ts=0.5), t[:20], np.ones(20), np.zeros(2))
    assert np.allclose(out.outputs, stable.simulate(np.ones(20), [0.0]))


def test_the_static_degree_the_candidates_cannot_carry_says_what_would_carry_it():
    from graybox.experiments._select import _static_points
    from graybox.static._form_check import static_fit_mse

    ub = np.linspace(0.5, 2.0, 8)
    static = gb.StaticPoints(ub, (0.2 * ub + 0.05 * ub**2) / 0.3 + 0.01 * ub**3)  # a small cubic part
    band = static_fit_mse(static, 2) / 10  # a quadratic misses it, a cubic does not
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    record = gb.Record(np.linspace(0.5, 2.0, 50), np.zeros(50))
    with pytest.warns(gb.SelectionWarning, match=r"degree-3 curve.*carry degree 2.*Candidates\(\.\.\., degree=3\)"):
        _, form = _static_points(static, cand.process, band, record)
    assert form.degree == 2


def test_a_warning_of_the_chosen_rows_fit_says_how_to_act_on_it(monkeypatch):
    """An ELS that did not converge says "raise max_iter or tol", which select_graybox does not take."""
    import warnings

    import graybox.experiments._select as sel

    fit_ls = sel._BLACK_BOX_FITS["ls"]

    def doubtful_ls(st, rec):
        warnings.warn("did not converge: raise max_iter", RuntimeWarning)
        return fit_ls(st, rec)

    monkeypatch.setitem(sel._BLACK_BOX_FITS, "ls", doubtful_ls)
    with pytest.warns(gb.SelectionWarning, match=r"the chosen row's: RuntimeWarning.*default options.*refit the chosen "
                                                  r"structure \(\.structure\) with ls"):
        gb.select_graybox(gb.Candidates(2, 2, degree=2), _first_order_data(), band=np.inf, estimator="ls",
                          sizes=[2, 4])


def _first_order_data(static: gb.StaticPoints | None = None) -> gb.Dataset:
    rng = np.random.default_rng(0)
    records = []
    for seed in (1, 2):
        u = np.repeat(np.random.default_rng(seed).uniform(0.0, 2.0, 21), 20)[:400]
        y = gb.simulate(gb.Structure(["y(k-1)", "u(k-1)", "1"]), np.array([0.7, 0.3, 0.2]), u, np.zeros(1))
        records.append(gb.Record(u, y + 0.01 * rng.standard_normal(400), name=f"r{seed}"))
    return gb.Dataset(*records, static)


def test_a_black_box_selection_does_not_claim_to_be_in_a_band():
    """Chosen with band=inf, every row is 'in band'; its repr said in_band=True beside a J_SF far off the points."""
    points = gb.StaticPoints([0.5, 1.0, 1.5], [5.0, 6.0, 7.0], uncertainty=0.01)  # not the system's: J_SF large
    black = gb.select_graybox(gb.Candidates(2, 2, degree=2), _first_order_data(points), band=np.inf, estimator="ls",
                              sizes=[2, 4])
    assert black.in_band and black.chosen["JSF"] > points.band  # the field keeps its documented meaning
    assert "in_band" not in repr(black) and "black box" in repr(black)


@pytest.mark.parametrize("stamp", ["20.11.2026 09:14:{:04.1f}", "11/20/2026 9:14:{:04.1f}"])
def test_dates_not_in_iso_order_say_what_time_stamps_are_read_and_what_to_pass(tmp_path, stamp):
    """ISO 8601 dates and clock times are read (test_time_stamps); a date in another order is not."""
    path = tmp_path / "logger.csv"
    path.write_text("timestamp,speed,pressure\n" + "".join(f"{stamp.format(0.5 * k)},1500,2e5\n" for k in range(6)),
                    encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 2, column 'timestamp'.*not a number.*seconds.*Ts="):
        gb.load_record_csv(path, u="speed", y="pressure", time="timestamp")
    record = gb.load_record_csv(path, u="speed", y="pressure", Ts=0.5)  # what it says to do
    assert record.Ts == 0.5 and record.y.size == 6
    with pytest.raises(ValueError, match=r"column 'timestamp'.*is not a number$"):  # said of the time column only
        gb.load_record_csv(path, u="timestamp", y="pressure", Ts=0.5)


def test_uncertainty_of_a_selected_els_model_without_its_ma_part_says_to_refit_it():
    """select_graybox keeps an ELS fit's process part (a free run sets the noise to zero); ls_uncertainty
    refused that model as 'not the least-squares estimate' without saying where its MA part went."""
    rng = np.random.default_rng(3)
    records = []
    for seed in (1, 2):
        u = np.repeat(np.random.default_rng(seed).uniform(0.0, 2.0, 41), 20)[:800]
        e = 0.05 * rng.standard_normal(800)
        y = np.zeros(800)
        for k in range(1, 800):
            y[k] = 0.7 * y[k - 1] + 0.3 * u[k - 1] + 0.2 + e[k] + 0.9 * e[k - 1]  # coloured: ELS is not LS
        records.append(gb.Record(u, y, name=f"r{seed}"))
    black = gb.select_graybox(gb.Candidates(1, 1, degree=1), gb.Dataset(*records), band=np.inf, estimator="els",
                              sizes=[2])
    assert not len(black.model.noise_structure)
    with pytest.raises(ValueError, match=r"MA part.*els\("):
        gb.ls_uncertainty(black.model, records[0])
    refit = gb.els(black.structure, records[0])  # what it says to do
    assert gb.ls_uncertainty(refit, records[0]).cov.shape == (len(black.structure),) * 2


def test_the_chosen_gray_model_is_named_as_its_row():
    """print(sel.model) began 'pe, J_S on the choosing data D_SF:' (an internal front's name), where
    model_of and a black box's model say 'pe (frols-2)'; python-control systems inherit the name."""
    ub = np.array([0.5, 1.0, 1.5])
    points = gb.StaticPoints(ub, (0.3 * ub + 0.2) / 0.3, uncertainty=0.05)  # the system's own steady states
    gray = gb.select_graybox(gb.Candidates(1, 1, degree=1), _first_order_data(points), estimator="pe", sizes=[2])
    row = gray.chosen
    assert gray.model.name == f"{row['estimator']} ({row.name})" == gray.model_of(row.name, row["estimator"]).name
    assert np.array_equal(gray.model.theta, gray.model_of(row.name, row["estimator"]).theta)
    assert str(gray.model).startswith(f"{row['estimator']} ({row.name}): y(k) =")
