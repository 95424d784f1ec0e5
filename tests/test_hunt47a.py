"""Bug hunt 47a: plots and reports (figures, leaderboards, the HTML page, the report command)."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
import graybox.experiments as gx

_PUMPING = '''name = "p"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]
[[variants]]
name = "LS"
estimator = "ls"
'''


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "r.sqlite"
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING), path)
    return path


@pytest.mark.parametrize("band, said", [({"pumpin": 1.0}, "pumpin"), (-1.0, "band")])
def test_a_refused_band_leaves_the_reports_folder_as_it_was(store, tmp_path, band, said):
    # write_report wrote cells.csv before the leaderboard refused a band naming no data set: the folder of an earlier
    # report then held a new cells.csv beside the old leaderboard and figures, and a new folder was made for nothing
    out = tmp_path / "rep"
    gx.write_report(store, out)
    (out / "cells.csv").write_text("an earlier report's cells\n", encoding="utf-8")  # told apart from a new one
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(ValueError, match=said):
        gx.write_report(store, out, band=band)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    with pytest.raises(ValueError, match=said):
        gx.write_report(store, tmp_path / "new", band=band)
    assert not (tmp_path / "new").exists()
