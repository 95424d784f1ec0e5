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
