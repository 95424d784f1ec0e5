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


def _no_chmod_by_fd(monkeypatch):
    """os.chmod as Windows' Python before 3.13 has it: no file descriptors (a TypeError for one)."""
    import os

    real = os.chmod

    def chmod(path, mode, *a, **kw):
        if isinstance(path, int):
            raise TypeError(f"chmod: path should be string, bytes or os.PathLike, not {type(path).__name__}")
        return real(path, mode, *a, **kw)

    monkeypatch.setattr(os, "chmod", chmod)
    monkeypatch.setattr(os, "supports_fd", {f for f in os.supports_fd if f is not real})


def test_a_checkpoints_rewrite_where_chmod_takes_no_file_descriptor(tmp_path, monkeypatch):
    # core._files gave every checkpoint rewrite the old file's mode by os.chmod(fd, …), which Windows' Python before
    # 3.13 refuses (a TypeError): every SE sweep's or selection's second checkpoint write failed there, its file
    # beside the checkpoint left behind
    import os
    import stat

    from graybox.estimation._simulation_error import read_npz, save_npz

    path = tmp_path / "front.npz"
    save_npz(path, x=np.zeros(2))
    os.chmod(path, 0o600)
    _no_chmod_by_fd(monkeypatch)
    save_npz(path, x=np.ones(2))
    monkeypatch.undo()
    assert np.array_equal(read_npz(path)["x"], np.ones(2))
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert [p.name for p in tmp_path.iterdir()] == ["front.npz"]


def test_a_file_system_refusing_modes_still_takes_a_save_never_wider_than_the_file_was(tmp_path, monkeypatch):
    # a mount that refuses chmod (EPERM: some FUSE and CIFS mounts), where open(path, "w") writes: a JSON save
    # failed as "cannot write in the folder", leaving its file beside the target (and its descriptor open)
    import errno
    import os
    import stat

    path = tmp_path / "model.json"
    gb.save(gb.Record(u=np.arange(5.0), y=np.arange(5.0)), path)
    os.chmod(path, 0o600)

    def refuse(*a, **kw):
        raise PermissionError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "chmod", refuse)
    gb.save(gb.Record(u=np.arange(6.0), y=np.arange(6.0)), path)
    monkeypatch.undo()
    assert gb.load(path).y.size == 6
    assert stat.S_IMODE(path.stat().st_mode) & 0o077 == 0  # a private file stays private
    assert [p.name for p in tmp_path.iterdir()] == ["model.json"]
