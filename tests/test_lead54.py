"""The lead's own small fixes of the session of 2026-11-28 14:34 UTC."""

import pytest


def test_an_se_checkpoint_named_as_a_folder_is_refused(tmp_path, monkeypatch):
    # hunt54f: se_pareto(..., checkpoint="ckpt/") with no folder ckpt wrote a file named 'ckpt' (Path drops the '/')
    from graybox.estimation._simulation_error import checkpoint_path

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="ends in a folder separator"):
        checkpoint_path("ckpt/")
    assert not (tmp_path / "ckpt").exists()
    assert checkpoint_path("front.npz").name == "front.npz"
