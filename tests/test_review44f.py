"""review44f: what the reviewed hunts (44b, 44c, 44e) left wrong."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

import graybox as gb


def test_a_checkpoint_write_of_another_host_is_not_swept_while_fresh(tmp_path):
    # a checkpoint in a folder two hosts share (NFS): a write's file named by its pid alone was swept as a killed
    # writer's whenever that pid is no process of *this* host, so the other host's os.replace found nothing
    from graybox.estimation._simulation_error import checkpoint_path, save_npz, writer_tag

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    path = tmp_path / "sel.npz"
    other = tmp_path / f"sel.npz.otherhost-{gone.pid}-0badc0de.tmp"  # a live write on another host
    mine = tmp_path / f"sel.npz.{writer_tag().rsplit('-', 1)[0]}-{gone.pid}-1badc0de.tmp"  # this host's, its writer gone
    untold = tmp_path / f"sel.npz.{gone.pid}-2badc0de.tmp"  # no host named: which host's process is not known
    for f in (other, mine, untold):
        f.write_bytes(b"half")
    checkpoint_path(path)
    assert other.exists() and untold.exists() and not mine.exists()
    save_npz(path, x=np.zeros(2))
    assert other.exists() and untold.exists()
    an_hour_ago = time.time() - 3600
    import os
    for f in (other, untold):
        os.utime(f, (an_hour_ago, an_hour_ago))
    checkpoint_path(path)  # once old, any host's is a killed writer's
    assert sorted(f.name for f in tmp_path.iterdir()) == ["sel.npz"]
