"""hunt48h: select_graybox's honest selection protocol (checkpoints, the rule, the test record)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graybox as gb
from conftest import STAIRCASE_THETA, STAIRCASE_TRUE, staircase_plant

CAND = gb.Candidates(2, 2, ne=0, degree=2)
TRUE = gb.Structure(STAIRCASE_TRUE)
THETA = STAIRCASE_THETA


def plant(seed, n=400, noise=0.02):
    return staircase_plant(seed, n, noise)


def _select(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(CAND, plant(1), validation=plant(2), estimator="ls", sizes=[3], progress=False, **kw)


@pytest.fixture(scope="module")
def checkpoint_arrays(tmp_path_factory) -> dict:
    """The arrays of the checkpoint ``_select`` writes (made once; each case below edits a copy of the dict)."""
    path = tmp_path_factory.mktemp("hunt48h") / "sel.npz"
    _select(checkpoint=path)
    with np.load(path, allow_pickle=False) as z:
        return dict(z)


@pytest.mark.parametrize("edit", ["blocks columns", "blocks 1-d", "weights text", "thetas columns", "blocks nan",
                                  "lambdas empty", "jsf empty", "blocks negative"])
def test_a_checkpoint_row_of_the_wrong_shape_or_values_is_refused_as_corrupt(tmp_path, edit, checkpoint_arrays):
    """A row whose arrays a hand edit or a bad copy broke (shapes that do not agree, text for numbers, NaN or negative
    mean squares) was read as it was: a bare IndexError or a matmul ValueError after the search, or a table built on it
    (NaN scores: a row without a model; θ of fewer terms than the structure's)."""
    path = tmp_path / "sel.npz"
    arrays = dict(checkpoint_arrays)  # its entries are replaced below, never changed in place
    keys = sorted({k.split("/")[0] for k in arrays if "/" in k})
    for k in keys:
        field, new = {
            "blocks columns": ("blocks", arrays[f"{k}/blocks"][:, :2]),
            "blocks 1-d": ("blocks", arrays[f"{k}/blocks"].ravel()),
            "weights text": ("weights", np.array(["a"] * arrays[f"{k}/weights"].size)),
            "thetas columns": ("thetas", arrays[f"{k}/thetas"][:, :1]),
            "blocks nan": ("blocks", arrays[f"{k}/blocks"] * np.nan),
            "lambdas empty": ("lambdas", np.array([])),
            "jsf empty": ("jsf", np.array([])),
            "blocks negative": ("blocks", -arrays[f"{k}/blocks"]),
        }[edit]
        arrays[f"{k}/{field}"] = new
    np.savez(path, **arrays)
    with pytest.raises(ValueError, match="corrupt"):
        _select(checkpoint=path)


def test_a_fold_whose_search_stops_short_of_the_rows_sizes_is_said():
    # was: a fold fitted on one record of lags + 2 samples (2 regression rows) searched, reached the constant
    # alone, and every row was scored there with it (J_S the same to 1e-5 for 4 to 15 terms), without a word
    cand = gb.Candidates(2, 2, ne=0, degree=2)
    with pytest.warns(gb.SelectionWarning, match=r"fold's fitting records are too short.*\['v4'\] \(2 regression "
                                                 r"rows\): its search reached at most 1 terms"):
        gb.select_graybox(cand, [plant(1), plant(2).slice(0, 4, name="v4")], estimator="ls", progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", gb.SelectionWarning)  # folds of whole records reach every size: no word
        sel = gb.select_graybox(cand, [plant(1), plant(2), plant(3)], estimator="ls", progress=False)
    assert np.isfinite(sel.table["JS_valid"].to_numpy(float)).all()
