"""Review 37: today's features used as a control engineer would on their own plant.

simulation_band, design_input, GrayboxSelection.uncertainty, the loaders' units row and the SE
start pulled inside a stability margin, tried with units far from 1 (Pa near 2e5, rpm near 3000),
inputs not named "u", one and two inputs, short records, MA terms and constrained estimates.
"""

import warnings

import numpy as np
import pytest

import graybox as gb


def _plant(n, seed, off=2e5):
    """y(k) = 0.6 y(k-1) + 20 (u − 3000) + 0.4 off + 2e-3 (u − 3000)² + e(k) + 0.5 e(k−1), Pa and rpm."""
    u = gb.design_input("aprbs", n, low=2900, high=3100, hold=(5, 20), seed=seed)
    e = 30 * np.random.default_rng(seed).standard_normal(n)
    y = np.full(n, off)
    for k in range(2, n):
        y[k] = 0.6 * y[k - 1] + 20 * (u[k - 1] - 3000) + 0.4 * off + 2e-3 * (u[k - 1] - 3000) ** 2 + e[k] + 0.5 * e[k - 1]
    return gb.Record(u, y, Ts=0.1, name=f"run{seed}", units=("rpm", "Pa"), input_names=("speed",))


def test_a_monte_carlo_band_of_a_fully_determined_model_has_no_spread():
    # was wrong: the Monte Carlo std was the spread of identical runs taken at 2e5 Pa, round-off of
    # about 1e-8 Pa, so a CLS estimate whose static curve fixes every parameter (a zero covariance)
    # got a band with std > 0 whose coverage read 0.0 where the delta method's read nan
    rec, val = _plant(400, 1), _plant(120, 5)
    sp = np.linspace(2900, 3100, 5)
    pts = gb.StaticPoints(sp, (20 * (sp - 3000) + 0.4 * 2e5 + 2e-3 * (sp - 3000) ** 2) / 0.4, input_names=("speed",))
    curve = gb.StaticCurve.fit(pts, degree=2)
    data = gb.Dataset(rec, val, pts)
    # Σ*_y from the least-squares reference: eq. (22) then fixes every parameter (Σ_y estimated leaves one free)
    fit = gb.cls(["1", "y(k-1)", "speed(k-1)", "speed(k-1)^2"], data, curve, reference="ls")
    unc = gb.cls_uncertainty(fit, data, curve, reference="ls")
    assert np.all(unc.cov == 0)
    band = gb.simulation_band(unc, val, method="monte-carlo", n_samples=50)
    assert np.all(band.std == 0)
    np.testing.assert_allclose(band.low, band.yhat, rtol=1e-12)  # the runs' own round-off (simulate_many)
    np.testing.assert_allclose(band.high, band.yhat, rtol=1e-12)
    assert np.isnan(band.coverage)


@pytest.mark.parametrize("bad", ["ab", 0.5, {0.1, 0.5}])
def test_design_input_refuses_frequencies_of_a_wrong_type_with_a_type_error(bad):
    # was wrong: a string, a number or a set for the multisine's band was a ValueError ("must be a
    # pair"), where the library's rule is a TypeError for a wrong type
    with pytest.raises(TypeError, match="frequencies"):
        gb.design_input("multisine", 64, low=1e-3, high=2e-3, frequencies=bad)


def test_design_input_takes_the_band_as_an_array_pair():
    # was wrong: np.array([f_low, f_high]), what a script computes the band as, was refused as "not a pair"
    band = np.array([0.1, 0.5])
    np.testing.assert_array_equal(gb.design_input("multisine", 64, low=1e-3, high=2e-3, frequencies=band),
                                  gb.design_input("multisine", 64, low=1e-3, high=2e-3, frequencies=(0.1, 0.5)))
    with pytest.raises(ValueError, match="pair"):
        gb.design_input("multisine", 64, low=1e-3, high=2e-3, frequencies=np.array([0.1, 0.2, 0.5]))


def _select(est, data, **options):
    black = {"band": np.inf} if est in ("ls", "els", "oe") else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(gb.Candidates(2, 2, degree=2, input_names=("speed",)), data, estimator=est,
                                 sizes=[4], **black, **options)


def test_an_output_error_choice_refuses_data_it_was_not_fitted_on():
    # was wrong: with the oe estimator, uncertainty(other data) returned a covariance with only
    # se_uncertainty's "not a stationary point" warning, the one the docstring says output error's
    # ridge gives anyway (and here the right data gave no warning at all): nothing told them apart
    rec, other = _plant(400, 1), _plant(400, 3)
    sel = _select("oe", rec)  # a record alone: the choice on folds, the model fitted on the whole record
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        right = sel.uncertainty(rec)
    np.testing.assert_array_equal(right.model.theta, sel.model.theta)
    with pytest.raises(ValueError, match="output_error on these data does not give the chosen model's θ"):
        sel.uncertainty(other)
    with pytest.raises(ValueError, match="does not give the chosen model's θ"):
        sel.uncertainty(gb.Dataset(other, rec))


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_a_units_row_keeps_numpys_reader_and_the_files_line_numbers(tmp_path, monkeypatch, newline):
    # was wrong: the units row was blanked in place, and a blank line sends every file to the careful
    # (Python) reader: 1e5 rows read in 0.34 s instead of 0.06 s (BENCHMARKS, review37)
    from graybox.datasets import _loaders

    fast = []
    real = _loaders._fast_columns
    monkeypatch.setattr(_loaders, "_fast_columns", lambda *a, **k: fast.append(real(*a, **k)) or fast[-1])
    rows = [f"{0.1 * k:.1f};{3000 + k};{2e5 + 10 * k:.1f}" for k in range(6)]
    body = ["t;speed;p", "[s];[rpm];[Pa]"] + rows
    p = tmp_path / "log.csv"
    p.write_bytes(newline.join(body + [""]).encode())
    rec = gb.load_record_csv(p, u="speed", y="p", time="t", units_row=True)
    assert fast[-1] is not None and rec.units == ("rpm", "Pa") and rec.Ts == pytest.approx(0.1)
    np.testing.assert_array_equal(rec.y, [2e5 + 10 * k for k in range(6)])
    # the file's own line numbers in a message from the fast reader's columns: line 6 (t = 0.3 s) made 0.1 s
    body[5] = body[5].replace("0.3;", "0.1;", 1)
    p.write_bytes(newline.join(body + [""]).encode())
    with pytest.raises(ValueError, match=r"from line 5 \(0.2 s\) to line 6 "):
        gb.load_record_csv(p, u="speed", y="p", time="t", units_row=True)
    assert fast[-1] is not None


@pytest.mark.parametrize(("cell", "unit"), [("[kPa (abs)]", "kPa (abs)"), ("(m^3/h)", "m^3/h"), ("[rpm]", "rpm"),
                                            ("kPa (abs)", "kPa (abs)"), ("Pa", "Pa")])
def test_a_units_rows_brackets_are_taken_off_as_a_pair(tmp_path, cell, unit):
    # was wrong: every bracket and parenthesis was stripped from both ends of a cell, so a logger's
    # "[kPa (abs)]" became the unit 'kPa (abs' and "kPa (abs)" became 'kPa (abs'
    p = tmp_path / "log.csv"
    p.write_text(f"t;speed;p\n[s];[rpm];{cell}\n0.0;3000;200000.5\n0.1;3001;200001.5\n")
    assert gb.load_record_csv(p, u="speed", y="p", time="t", units_row=True).units == ("rpm", unit)


def test_a_file_of_a_header_and_a_units_row_alone_names_the_line_after_the_units(tmp_path):
    # was wrong: "line 2: no data rows after the header" pointed at the units row, read as units
    p = tmp_path / "log.csv"
    p.write_text("t;speed;p\ns;rpm;Pa\n")
    with pytest.raises(ValueError, match="line 3: no data rows after the header's units row"):
        gb.load_record_csv(p, u="speed", y="p", time="t", units_row=True)


def test_a_prbs_of_several_inputs_never_repeats_a_column():
    # was wrong: the columns are one sequence shifted by i/n_inputs of its period, and a period shorter
    # than n_inputs gave two columns the same shift: with 4 inputs on a 20-sample record of 10-sample
    # bits (order 2, period 3) the first two inputs were identical, collinear for any estimator
    with pytest.raises(ValueError, match="too short for 4 different input columns"):
        gb.design_input("prbs", 20, low=2900, high=3100, hold=10, n_inputs=4)
    x = gb.design_input("prbs", 40, low=2900, high=3100, hold=10, n_inputs=4)  # 4 bits: a register of 3
    assert len({col.tobytes() for col in x.T}) == 4
    with pytest.raises(ValueError, match="order"):
        gb.design_input("prbs", 200, low=2900, high=3100, hold=1, n_inputs=4, order=2)
    assert gb.design_input("prbs", 200, low=2900, high=3100, hold=1, n_inputs=3, order=2).shape == (200, 3)


def test_a_start_pulled_inside_the_margin_where_the_record_alone_does_not_identify_the_rest():
    # was wrong: _pull_inside refits the non-feedback parameters on the dynamic rows alone, and where
    # only the static points identify them (the valve held at 2e-3 V through the record, varied in
    # the static points) its least squares raised "not identifiable", ending the whole se_pareto
    # sweep, which without a margin fits these data
    n = 300
    rng = np.random.default_rng(1)
    speed = np.repeat(rng.uniform(2500, 3500, n // 8 + 1), 8)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.3 * (speed[k - 1] - 3000) / 500
    rec = gb.Record(np.column_stack([speed, np.full(n, 2e-3)]), 2e5 + 1e4 * y + 20 * rng.standard_normal(n), Ts=0.1,
                    input_names=("n", "v"))
    a, b = (g.ravel() for g in np.meshgrid(np.linspace(2500, 3500, 3), np.linspace(1e-3, 3e-3, 3)))
    pts = gb.StaticPoints(np.column_stack([a, b]), 2e5 + 1e4 * ((a - 3000) / 500 + (b - 2e-3) / 3e-3),
                          input_names=("n", "v"))
    with pytest.warns(gb.StaticRangeWarning, match="outside the input box"):  # the valve's points, as meant
        front = gb.se_pareto(["1", "y(k-1)", "n(k-1)", "v(k-1)"], rec, pts, lambdas=[0.5], method="gradient",
                             margin=0.5, progress=False)
    assert not front.failures and np.isfinite(front.JS[0])
    assert abs(front.thetas[0][1]) <= 0.5 + 1e-9  # the feedback inside the margin (the plant's pole is 0.7)
