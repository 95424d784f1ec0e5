"""A grid variant chooses the SE stability margin: "auto" (the default), "none" (the paper's problem) or a number."""

import numpy as np
import pytest

import graybox as gb
import graybox.experiments as gx
from graybox.reference import STRUCTURE_15


def _grid(**margins):
    return gx.Grid(
        name="margins",
        data=[gx.DataSpec("pumping", bundled="pumping")],
        structures=[gx.StructureSpec("eq15", terms=[str(t) for t in STRUCTURE_15])],
        variants=[gx.Variant(name, "se-gradient", lambdas=[0.6, 0.359, 0.2], options={} if m is None else {"margin": m})
                  for name, m in margins.items()],
    )


def test_a_variant_can_ask_for_the_papers_problem_or_a_margin(tmp_path):
    grid = _grid(default=None, paper="none", fixed=0.01)
    gx.run_grid(grid, tmp_path / "store.sqlite")
    rows = gx.load_results(tmp_path / "store.sqlite").set_index("variant")
    assert rows.loc["default", "status"] == "ok" and rows.loc["paper", "status"] == "ok"
    # without a margin the D_SF member on structure (15) is a near-integrator that wanders off on validation
    assert rows.loc["paper", "JS_valid"] > 100
    assert rows.loc["default", "JS_valid"] < 5
    # a margin of 0.01 (ρ ≤ 0.99) is tighter than auto's here: on these three λ1 no member meets the band,
    # and the cell says so instead of making a member up
    assert rows.loc["fixed", "status"] == "infeasible" and "J_SF" in rows.loc["fixed", "message"]
    keys = [c.key for c in grid.cells()]
    assert len(set(keys)) == 3  # each choice is its own cell


def test_a_bad_margin_is_refused_naming_it():
    with pytest.raises(gx.SpecError, match="margin"):
        _grid(bad="slow").cells()
    with pytest.raises(gx.SpecError, match="margin"):
        _grid(bad=1.5).cells()
