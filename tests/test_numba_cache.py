"""An install nobody may write to, run without a usable HOME: numba finds no cache folder (graybox/core/_jit.py)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import graybox

_PROBE = ("import graybox.core._simulation_kernels, graybox.static._equilibrium_kernels, numba; "
          "print(numba.config.CACHE_DIR)")


def _unwritable_copy(tmp_path: Path) -> dict:
    """graybox copied with a file where each ``__pycache__`` folder would go (nothing can be cached beside it, even
    for root), HOME a file (no user-wide folder): the environment to run it in."""
    root = tmp_path / "site"
    shutil.copytree(Path(graybox.__file__).parent, root / "graybox", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in [p for p in (root / "graybox").rglob("*") if p.is_dir()] + [root / "graybox"]:
        (folder / "__pycache__").write_text("")
    home = tmp_path / "home-is-a-file"
    home.write_text("")
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_CACHE_HOME", "NUMBA_CACHE_DIR", "PYTHONPATH")}
    env.update(HOME=str(home), PYTHONPATH=str(root), PYTHONDONTWRITEBYTECODE="1", TMPDIR=str(tmp_path))
    return env


def test_kernels_cache_in_the_temporary_folder_where_numba_finds_none(tmp_path):
    # was: RuntimeError: cannot cache function '_input_products': no locator available, on `import` of any kernel
    env = _unwritable_copy(tmp_path)
    run = subprocess.run([sys.executable, "-c", _PROBE], env=env, cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    assert Path(run.stdout.strip()).parent == tmp_path and "graybox-numba-cache" in run.stdout
    # the user's own NUMBA_CACHE_DIR is kept
    own = tmp_path / "mine"
    run = subprocess.run([sys.executable, "-c", _PROBE], env={**env, "NUMBA_CACHE_DIR": str(own)}, cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == str(own), run.stderr
