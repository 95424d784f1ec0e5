"""numba, with a cache folder it can write: the one place graybox's compiled kernels import it from.

Every kernel is compiled with ``cache=True``, and numba looks for a writable folder at decoration (on import): beside
the package (``__pycache__``), else its user-wide folder under HOME. An install nobody may write to, run by a user
without a usable HOME (a service account, a container's ``nobody``), had neither, and every ``graybox`` command failed
on import: "RuntimeError: cannot cache function '_input_products': no locator available". Then, and only then (and
never over the user's own ``NUMBA_CACHE_DIR``), the kernels cache in a folder of the temporary directory.
"""

from __future__ import annotations

import os
import tempfile

import numba as nb
from numba.core import config

__all__ = ["nb"]


def _writable(folder: str) -> bool:
    """Whether a file can be made in ``folder`` (made first if missing), as numba's locators test it."""
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def _cache_folder() -> str | None:
    """The folder numba must be told to cache in: None where it finds one itself."""
    if config.CACHE_DIR:
        return None  # the user's NUMBA_CACHE_DIR
    from numba.misc.appdirs import AppDirs

    beside = os.path.join(os.path.dirname(__file__), "__pycache__")
    if _writable(beside) or _writable(AppDirs(appname="numba", appauthor=False).user_cache_dir):
        return None
    uid = os.getuid() if hasattr(os, "getuid") else os.getpid()
    return os.path.join(tempfile.gettempdir(), f"graybox-numba-cache-{uid}")


_folder = _cache_folder()
if _folder is not None:
    config.CACHE_DIR = _folder
