"""Review 45d: the lead's one atomic write (core._files), the select_graybox checkpoint's rows of another graybox,
GainBounds ranges by input name."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def test_a_row_of_this_version_with_a_field_it_does_not_know_is_refitted_once_and_then_reused(tmp_path, monkeypatch):
    # a graybox of the same version string (a development checkout) wrote a row under this version's key with a
    # field this one does not know: the row was taken for another graybox's, refitted, and written back merged
    # with the other's field, so it was "foreign" again at every run and refitted every time
    from graybox.core._files import write_atomically
    from graybox.experiments import _select
    from graybox.experiments._select_checkpoint import SelectionCheckpoint

    calls: list = []
    score = _select._score_job
    monkeypatch.setattr(_select, "_score_job", lambda job: (calls.append(job), score(job))[1])
    data = gb.load_pumping()
    path = tmp_path / "sel.npz"
    kw = dict(sizes=[3], estimator=["pe"], progress=False, checkpoint=path)
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    first = gb.select_graybox(cand, data, **kw)
    n = len(calls)
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    key = next(k.split("/")[0] for k in arrays if k.endswith("/thetas"))
    arrays[f"{key}/a_newer_score"] = np.array([1.5])
    write_atomically(path, lambda f: np.savez(f, **arrays))
    gb.select_graybox(cand, data, **kw)
    assert len(calls) == 2 * n  # not offered: refitted
    ck = SelectionCheckpoint(path)
    assert key in ck.rows and key not in ck.foreign  # this version's row, whole, written in the other's place
    with np.load(path, allow_pickle=False) as z:
        assert f"{key}/a_newer_score" not in z.files
    again = gb.select_graybox(cand, data, **kw)
    assert len(calls) == 2 * n  # reused from then on
    assert again.table.equals(first.table)


def test_select_graybox_says_a_range_of_an_unknown_input_before_any_row(monkeypatch):
    # GainBounds(ubar_range={"valve": …}) on data of u1, u2: the up-front check read only the bounds' names, so every
    # row was fitted and failed, and the run said so only after all of them ("no structure has a finite …")
    from graybox.experiments import _select

    calls: list = []
    score = _select._score_job
    monkeypatch.setattr(_select, "_score_job", lambda job: (calls.append(job), score(job))[1])
    with pytest.raises(ValueError, match=r"^constraints: .*no input named 'valve'"):
        gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=1, input_names=["u1", "u2"]), gb.load_pumping_miso(),
                          band=1.0, constraints=gb.GainBounds(lower=0.0, ubar_range={"valve": (0.0, 1.0)}),
                          progress=False)
    assert calls == []


@pytest.mark.parametrize("r, kind", [(5, TypeError), ("ab", TypeError), ([1.0], ValueError)])
def test_a_grid_specs_range_by_name_of_the_wrong_type_is_a_type_error(r, kind):
    # {"u2": 5} in a spec was a SpecError (a ValueError), where GainBounds(ubar_range={"u2": 5}) and a spec's
    # ubar_range = 5 are TypeErrors: a wrong type is a TypeError, a wrong value (a list of one) a ValueError
    from graybox import experiments as gx

    with pytest.raises(kind, match="ubar_range of input 'u2' must be") as got:
        gx.Variant("x", "pe", constraints=[{"type": "gain", "lower": 0.0, "ubar_range": {"u2": r}}])
    assert isinstance(got.value, gx.SpecError)
    if kind is ValueError:
        assert not isinstance(got.value, TypeError)
    with pytest.raises(kind):
        gb.GainBounds(lower=0.0, ubar_range={"u2": r})
