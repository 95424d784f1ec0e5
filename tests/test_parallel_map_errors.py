"""A worker process that dies under ``parallel_map`` is explained, not left as a bare BrokenProcessPool."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

import graybox as gb


def test_a_killed_worker_is_a_clear_error():
    # os._exit ends the worker at once, as a kill would: the pool breaks under the map
    with gb.experiments.parallel_map(executor="processes", workers=1) as pmap:
        with pytest.raises(RuntimeError, match="worker process died") as info:
            pmap(os._exit, [3])
    assert type(info.value.__cause__).__name__ == "BrokenProcessPool"


def test_a_script_without_main_guard_is_told_what_to_add(tmp_path):
    script = tmp_path / "unguarded.py"
    script.write_text(textwrap.dedent("""
        import graybox as gb
        with gb.experiments.parallel_map(executor="processes", workers=1) as pmap:
            print(pmap(abs, [-1, -2]))
    """))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode != 0
    assert 'if __name__ == "__main__":' in out.stderr
    guarded = tmp_path / "guarded.py"
    guarded.write_text("if __name__ == '__main__':\n" + textwrap.indent(script.read_text(), "    "))
    out = subprocess.run([sys.executable, str(guarded)], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[1, 2]"


_SLOW_MAP = '''
import signal, sys, time
from graybox.experiments import parallel_map

# Ctrl-C raises KeyboardInterrupt, as at a terminal (a test runner in the background starts us with SIGINT ignored)
signal.signal(signal.SIGINT, signal.default_int_handler)


def slow(x):
    time.sleep(60)
    return x


if __name__ == "__main__":
    with parallel_map(executor="processes", workers=2) as pmap:
        print("mapping", flush=True)
        pmap(slow, [1, 2, 3])
'''


def test_ctrl_c_stops_a_process_map_at_once_with_the_driver_s_traceback_only(tmp_path):
    # Ctrl-C (SIGINT to the terminal's whole process group) during select_graybox(workers=...) or
    # bootstrap_decision(map=...): each worker took it as its job's result and went on to the jobs still
    # queued, so the driver's exit waited for them (here 60 s more); now the workers ignore it and the
    # driver cancels what is queued and stops what runs, at once
    import os
    import signal
    import subprocess
    import sys
    import time

    script = tmp_path / "slow_map.py"
    script.write_text(_SLOW_MAP)
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, cwd=tmp_path)
    try:
        assert proc.stdout.readline().strip() == "mapping"
        time.sleep(8)  # the two workers spawned, imported graybox and started their jobs
        t0 = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=45)  # the jobs would take 60 s
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert took < 30
    assert proc.returncode != 0 and err.count("Traceback") == 1 and "KeyboardInterrupt" in err, err
    assert "leaked" not in err, err
