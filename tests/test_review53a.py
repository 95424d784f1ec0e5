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


@pytest.mark.parametrize("col", ["t [1 s]", "t [ 1 s ]", "t [1.0 s]", "t [1 sec]", "Time (s)", "t [sec]", "t [s]"])
def test_a_time_column_in_seconds_is_still_read(tmp_path, col):
    p = tmp_path / "r.csv"
    p.write_text(f"{col};u;y\n" + "".join(f"{k / 2};{k % 3};{0.5 * k}\n" for k in range(8)), encoding="utf-8")
    assert gb.load_record_csv(p, u="u", y="y", time=col).Ts == 0.5
