"""The command's help is plain text, and `reproduce` says how it resumes and how to start over."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from graybox._cli import main
from graybox.core._version import graybox_version


def _help(capsys, *argv: str) -> str:
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--help"])
    assert exc.value.code == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("argv", [(), ("reproduce",), ("grid",), ("grid", "run"), ("grid", "report")])
def test_help_is_plain_text(capsys, argv):
    text = _help(capsys, *argv)
    for markup in ("``", ":func:", ":class:", ":mod:"):  # reStructuredText has no place in a terminal
        assert markup not in text, (markup, text)


def test_top_help_says_what_the_command_is_for(capsys):
    text = _help(capsys)
    assert "reproduce" in text and "grid" in text and "examples:" in text and "import graybox" in text


def test_reproduce_help_tells_about_checkpoints_and_fresh(capsys):
    text = _help(capsys, "reproduce")
    assert "resumes" in text and ".npz" in text and "--fresh" in text


@pytest.mark.parametrize("fresh", [False, True])
def test_reproduce_names_the_checkpoints_it_resumes_and_fresh_deletes_them(tmp_path, monkeypatch, fresh):
    import graybox.reproduce as rp
    from graybox.reproduce._table1 import checkpoint_paths

    monkeypatch.setattr(rp, "SECTIONS", ())  # the sections themselves are tested elsewhere
    kept = checkpoint_paths(tmp_path, quick=True)[:2]
    other_mode = checkpoint_paths(tmp_path, quick=False)[0]
    for p in (*kept, other_mode):  # as little as a checkpoint holds: the version that wrote it
        np.savez(p, meta=json.dumps({"graybox": graybox_version()}))
    out = io.StringIO()
    rp.run(quick=True, out=tmp_path, stream=out, fresh=fresh)
    text = out.getvalue()
    assert all(p.name in text for p in kept)
    assert [p.exists() for p in kept] == [not fresh] * 2
    assert other_mode.exists()  # the full run's checkpoints are not this run's to delete
    assert ("deleted 2 checkpoint(s)" in text) == fresh and ("resuming from 2 checkpoint(s)" in text) != fresh


def test_the_cli_passes_fresh_on(monkeypatch, tmp_path):
    import graybox.reproduce as rp

    seen = {}
    monkeypatch.setattr(rp, "run", lambda **kw: seen.update(kw))
    assert main(["reproduce", "--quick", "--fresh", "--out", str(tmp_path)]) == 0
    assert seen == {"quick": True, "out": tmp_path, "fresh": True}


def test_python_dash_m_graybox_is_the_same_command():
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "graybox", "reproduce", "--help"], capture_output=True, text=True,
                         check=True)
    assert out.stdout.startswith("usage: graybox reproduce") and "--fresh" in out.stdout
