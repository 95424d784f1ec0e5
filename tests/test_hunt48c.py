"""hunt48c: grids and their store (spec, run, cells, store, CLI)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox import experiments as gx

FIRST = gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])


def test_n_params_is_stored_by_one_rule_whatever_the_status(tmp_path):
    # a failed LS cell (too short a record) kept no N_p while an infeasible PE cell of the same
    # structure kept 4: N_p is the structure's number of terms once the structure is made
    d = gb.load_pumping()
    short = gb.Dataset(d.ident.slice(0, 12), d.valid, d.static)
    g = gx.Grid(data=[gx.DataSpec("short", dataset=short)], structures=[FIRST],
                variants=[gx.Variant("LS", "ls"), gx.Variant("CLS", "cls", constraints=[{"type": "gain", "lower": 1e6}]),
                          gx.Variant("PE", "pe", lambdas=[0.1, 1.0], decision={"rule": "dsf", "band": 1e-12})],
                name="np")
    gx.run_grid(g, tmp_path / "s.sqlite")
    df = gx.load_results(tmp_path / "s.sqlite").set_index("variant")
    assert set(df["status"]) >= {"failed", "infeasible"}
    for v, r in df.iterrows():
        assert r["terms"] is not None
        assert not pd.isna(r["n_params"]), (v, r["status"])
        assert int(r["n_params"]) == len(r["terms"]) == 4, (v, r["status"], r["n_params"])
