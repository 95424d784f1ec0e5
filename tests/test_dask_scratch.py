"""A LocalCluster's scratch folder outlives a SIGKILLed driver only until the next cluster starts (a real
subprocess holding it, a real SIGKILL, real folders)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

from graybox.experiments import _executors

HOLDER = textwrap.dedent("""
    import sys, tempfile, time
    tempfile.tempdir = sys.argv[1]
    from graybox.experiments._executors import _scratch_folder
    path, fd = _scratch_folder()
    print(path, flush=True)
    time.sleep(600)
""")


def _holder(base) -> tuple[subprocess.Popen, str]:
    """A process holding a new scratch folder in ``base`` (it sleeps), and the folder's path."""
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(base)], stdout=subprocess.PIPE, text=True)
    with proc.stdout:
        return proc, proc.stdout.readline().strip()


def test_a_killed_drivers_scratch_folder_is_swept_and_a_live_ones_kept(tmp_path):
    # was: a driver SIGKILLed while its LocalCluster ran left its graybox-dask-* folder (workers'
    # spill and lock files) in the temporary folder for ever
    dead, dead_path = _holder(tmp_path)
    live, live_path = _holder(tmp_path)
    try:
        assert os.path.isdir(dead_path) and os.path.isdir(live_path) and dead_path != live_path
        assert os.path.dirname(dead_path) == str(tmp_path)
        os.kill(dead.pid, signal.SIGKILL)
        dead.wait(timeout=30)
        ownerless = tmp_path / (_executors.SCRATCH_PREFIX + "other")  # not a folder graybox can tell is left
        ownerless.mkdir()
        (tmp_path / "graybox-other").mkdir()
        assert _executors._sweep_scratch(str(tmp_path)) == [dead_path]
        assert not os.path.exists(dead_path)
        assert os.path.isdir(live_path) and ownerless.is_dir() and (tmp_path / "graybox-other").is_dir()
    finally:
        live.kill()
        live.wait(timeout=30)
        dead.kill()
        dead.wait(timeout=30)
    # the live holder is gone now: the next sweep takes its folder too
    assert _executors._sweep_scratch(str(tmp_path)) == [live_path]


def test_a_new_scratch_folder_sweeps_the_left_ones(tmp_path, monkeypatch):
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead, dead_path = _holder(tmp_path)
    dead.send_signal(signal.SIGKILL)
    dead.wait(timeout=30)
    path, fd = _executors._scratch_folder()
    try:
        assert os.listdir(tmp_path) == [os.path.basename(path)]
        assert os.listdir(path) == [_executors.SCRATCH_OWNER]
    finally:
        os.close(fd)
