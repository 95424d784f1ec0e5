"""The settings Table I's SE rows are fitted with (`graybox reproduce`)."""

import pytest

import graybox.reproduce._table1 as t1


class _Stop(Exception):
    pass


def test_the_ga_row_is_seeded_with_pe_solutions_inside_the_margin(monkeypatch, tmp_path):
    calls = []

    def se_pareto(*args, **kwargs):  # record the first SE sweep's settings, then stop the section
        calls.append(kwargs)
        raise _Stop

    monkeypatch.setattr(t1, "se_pareto", se_pareto)
    with pytest.raises(_Stop):
        t1.section_table1(quick=True, out=None)
    ga = calls[0]
    assert ga["method"] == "ga" and ga["starts"] == "pe" == t1.GA_STARTS and ga["margin"] == t1.SE_MARGIN == 0.01
    # the seeded GA's checkpoints are not the unseeded GA's (a checkpoint records its settings)
    assert "_pe" in t1.checkpoint_path(tmp_path, "ga", 2, True).name
    assert "_pe" not in t1.checkpoint_path(tmp_path, "gradient", 2, True).name
