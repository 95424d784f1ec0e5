"""One atomic write, one leftover sweeper, one lock (graybox.core._files) under every file graybox writes."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import time

import numpy as np
import pytest

import graybox as gb
from graybox.core import _files
from graybox.estimation._simulation_error import read_npz, save_npz


def _gone_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_a_json_save_sweeps_what_a_killed_save_left(tmp_path):
    # a killed JSON save's file beside the target stayed for ever: its name had no writer, so nothing could sweep it
    target = tmp_path / "model.json"
    host = _files.writer_tag().rsplit("-", 1)[0]
    left = tmp_path / f"model.json.{host}-{_gone_pid()}-0badc0de.tmp"
    left.write_text("half a model")
    gb.save(gb.Record(u=np.arange(5.0), y=np.arange(5.0)), target)
    assert not left.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.json"]


def test_a_live_writers_file_is_left(tmp_path):
    target = tmp_path / "model.json"
    live = tmp_path / f"model.json.{_files.writer_tag()}-1badc0de.tmp"  # this very process: alive
    live.write_text("being written")
    gb.save(gb.Record(u=np.arange(5.0), y=np.arange(5.0)), target)
    assert live.exists()


def test_a_checkpoint_keeps_its_files_mode(tmp_path):
    # save_npz made every rewrite 0666 less the umask: a checkpoint made private (0600) by its user was opened again
    path = tmp_path / "front.npz"
    save_npz(path, x=np.zeros(2))
    os.chmod(path, 0o600)
    save_npz(path, x=np.ones(2))
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert np.array_equal(read_npz(path)["x"], np.ones(2))


def test_a_json_file_keeps_its_mode_and_a_link(tmp_path):
    real = tmp_path / "real.json"
    link = tmp_path / "link.json"
    gb.save(gb.Record(u=np.arange(5.0), y=np.arange(5.0)), real)
    os.chmod(real, 0o640)
    link.symlink_to(real)
    gb.save(gb.Record(u=np.arange(6.0), y=np.arange(6.0)), link)
    assert link.is_symlink() and stat.S_IMODE(real.stat().st_mode) == 0o640
    assert gb.load(real).y.size == 6


def test_a_failed_write_leaves_the_old_file_and_nothing_beside(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"old")

    def boom(f):
        f.write(b"half")
        raise RuntimeError("killed")

    with pytest.raises(RuntimeError, match="killed"):
        _files.write_atomically(path, boom)
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.bin"]


def test_an_unwritable_folder_is_named(tmp_path):
    # named by the folder and the path given, not by the file beside the target (a "folder" that is a file here:
    # a read-only folder would not refuse root, who runs some CI)
    folder = tmp_path / "not a folder"
    folder.write_text("")
    with pytest.raises(OSError, match="cannot write in the folder .*not a folder") as exc:
        _files.write_atomically(folder / "x.bin", lambda f: f.write(b"x"))
    assert exc.value.filename == str(folder / "x.bin")


def test_a_stores_leftovers_are_aged_on_the_folders_clock(tmp_path, monkeypatch):
    # the store's sweep read this host's clock: a host whose clock ran ahead of the file server's by more than the
    # leftover age deleted a live maker's lock and half-made store
    from graybox.experiments import _store

    store = tmp_path / "grid.sqlite"
    making = tmp_path / ".grid.sqlite.making"
    making.write_text("")
    real = time.time
    monkeypatch.setattr(time, "time", lambda: real() + 10 * _files.LEFTOVER_SECONDS)
    _store._sweep_leftovers(store)
    assert making.exists()
    monkeypatch.undo()
    old = time.time() - 2 * _files.LEFTOVER_SECONDS
    os.utime(making, (old, old))
    _store._sweep_leftovers(store)
    assert not making.exists()


def test_a_lock_held_elsewhere_is_not_taken(tmp_path):
    if not _files.CAN_FLOCK:
        pytest.skip("no flock here")
    path = tmp_path / "lock"
    a = os.open(path, os.O_RDWR | os.O_CREAT)
    b = os.open(path, os.O_RDWR)
    try:
        assert _files.lock_fd(a, 0.0)
        assert not _files.lock_fd(b, 0.0)  # flock is per open file: a second open of the file waits for the first
        assert not _files.lock_fd(b, 0.0, shared=True)
    finally:
        os.close(a)
        os.close(b)


def test_an_older_json_saves_leftover_is_swept_once_old(tmp_path):
    # graybox 0.3.0's JSON saves named their file beside the target without a writer: never swept
    target = tmp_path / "model.json"
    left = tmp_path / "model.json.0badc0de.tmp"
    left.write_text("half a model")
    record = gb.Record(u=np.arange(5.0), y=np.arange(5.0))
    gb.save(record, target)
    assert left.exists()  # young: perhaps a live writer's
    old = time.time() - 2 * _files.LEFTOVER_SECONDS
    os.utime(left, (old, old))
    gb.save(record, target)
    assert not left.exists()


@pytest.mark.parametrize("name", ["front.json", "sel.SQLITE", "x.csv"])
def test_a_checkpoint_named_as_another_format_is_refused(tmp_path, name):
    # checkpoint="x.json" wrote an .npz under that name, silently (hunt45c's note)
    from graybox.estimation._simulation_error import checkpoint_path

    with pytest.raises(ValueError, match=r"a checkpoint is an \.npz file.*such as"):
        checkpoint_path(tmp_path / name)
    assert checkpoint_path(tmp_path / "front.npz").name == "front.npz"
    assert checkpoint_path(tmp_path / "front").name == "front"


@pytest.mark.parametrize("encoding", ["utf-16", "utf-32", "utf-8-sig"])
def test_a_json_file_an_editor_saved_with_a_byte_order_mark_loads(tmp_path, encoding):
    # a file re-saved as "Unicode" (UTF-16 with its mark) was refused as "not UTF-8 text", where the CSV loaders
    # read it by its mark (hunt45a's note): one reading of byte-order marks, core._files.bom_encoding
    record = gb.Record(u=np.arange(5.0), y=np.arange(5.0) ** 2, name="café")
    path = tmp_path / "r.json"
    gb.save(record, path)
    path.write_bytes(path.read_text(encoding="utf-8").encode(encoding))
    back = gb.load(path)
    assert back.name == "café" and np.array_equal(back.y, record.y)


def test_units_with_surrounding_blanks_are_the_units(tmp_path):
    # (' rpm ', 'mlc') was another unit than 'rpm': a record so named was refused beside a model in rpm (hunt45a)
    a = gb.Record(u=np.arange(5.0), y=np.arange(5.0), units=(" rpm ", "mlc "))
    b = gb.Record(u=np.arange(5.0), y=np.arange(5.0), units=("rpm", "mlc"))
    assert a.units == b.units == ("rpm", "mlc")

