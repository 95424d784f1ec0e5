"""review53a: checks of 59dd173 … 415e427 (Monte Carlo bands' memory, CorrelationTest labels, empty plot_pareto, stored
y_unit, leaderboard bands, grid duplicates, SEProblem._run_errors, CSV time columns in ticks, CLS/PE centring)."""

from __future__ import annotations

import re

import pytest

import graybox as gb


# ---- 208656b: a time column in ticks written as a power the usual ways ----------------------------------------------
@pytest.mark.parametrize("col, unit", [("t [10^-3 s]", "10^-3 s"), ("t [10\u207b\u00b3 s]", "10\u207b\u00b3 s"),
                                       ("t [1\u00b710^-3 s]", "1\u00b710^-3 s"), ("t [1e-3 * s]", "1e-3 * s"),
                                       ("t [0.001\u00b7s]", "0.001\u00b7s"), ("t [s/10]", "s/10"),
                                       ("t [1 s/10]", "1 s/10")])
def test_a_time_column_in_ticks_written_as_a_power_with_a_caret_or_superscript_is_refused(tmp_path, col, unit):
    # 208656b refused 't [1e-3 s]' and 't [1/10 s]', but 't [10^-3 s]' or 't [10⁻³ s]' were still read as seconds:
    # Ts = 1 s for 1 ms without a word
    p = tmp_path / "r.csv"
    p.write_text(f"{col};u;y\n" + "".join(f"{k};{k % 3};{0.5 * k}\n" for k in range(8)), encoding="utf-8")
    with pytest.raises(ValueError, match=re.escape(f"names its unit '{unit}', but time stamps are read as seconds")):
        gb.load_record_csv(p, u="u", y="y", time=col)


# (review54a's tick units beside them: "t [1s]", "t [1.0 sec]", "t [1 second]", "time (x)", "t_s")
@pytest.mark.parametrize("col", ["t [1 s]", "t [ 1 s ]", "t [1.0 s]", "t [1 sec]", "Time (s)", "t [sec]", "t [s]", "t [1s]",
                                 "t [1.0 sec]", "t [1 second]", "time (x)", "t_s"])
def test_a_time_column_in_seconds_is_still_read(tmp_path, col):
    p = tmp_path / "r.csv"
    p.write_text(f"{col};u;y\n" + "".join(f"{k / 2};{k % 3};{0.5 * k}\n" for k in range(8)), encoding="utf-8")
    assert gb.load_record_csv(p, u="u", y="y", time=col).Ts == 0.5


# ---- 5efd509 / 809d665: y_unit in a [[data]] table only checks the unit: the refusal says how to name one -----------
def test_a_y_unit_the_csv_data_do_not_give_says_how_to_name_their_unit(tmp_path):
    # 5efd509 took y_unit in a [[data]] table (a stored spec's), held to the data's unit: a spec writing it to give
    # its CSV data a unit was refused as "gives its output in no unit, but the spec says y_unit = 'mlc'", without
    # the key that names a unit (the file tables' units, or units_row)
    from graybox import experiments as gx

    rows = ["t,u,y"] + [f"{k * 0.1:.1f},{1 + k % 3},{0.5 * k}" for k in range(12)]
    for name in ("id.csv", "va.csv"):
        (tmp_path / name).write_text("\n".join(rows) + "\n", encoding="utf-8")
    (tmp_path / "st.csv").write_text("u,y\n1,2\n2,4\n3,6\n", encoding="utf-8")
    rec = dict(u="u", y="y", time="t")
    spec = {"name": "g", "data": [{"name": "m", "ident": dict(path="id.csv", **rec), "valid": dict(path="va.csv", **rec),
                                   "static": dict(path="st.csv", u="u", y="y"), "y_unit": "mlc"}],
            "structures": [{"name": "one", "terms": ["y(k-1)", "u(k-1)", "1"]}],
            "variants": [{"name": "LS", "estimator": "ls"}]}
    with pytest.raises(gx.SpecError, match=r"gives its output in no unit, but the spec says y_unit = 'mlc'.*"
                                           r"units = \[input unit, output unit\]"):
        gx.Grid.from_dict(spec, base_dir=tmp_path).load_data()
    # named as the hint says, the data give the unit y_unit holds them to
    named = dict(rec, units=["", "mlc"])
    spec["data"][0].update(ident=dict(path="id.csv", **named), valid=dict(path="va.csv", **named),
                           static=dict(path="st.csv", u="u", y="y", units=["", "mlc"]))
    assert gx.Grid.from_dict(spec, base_dir=tmp_path).load_data()["m"].valid.units[1] == "mlc"
