"""Every public name of the layers below the figures and the experiments, in one namespace.

:mod:`graybox` re-exports it; the experiment layer reads those layers through it
(``from .. import _api as gb``), so that nothing in :mod:`graybox.experiments` imports the
package that imports it. Names are loaded on first use (see :mod:`graybox._lazy`).
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version as _version
from typing import Any

from ._layers import PUBLIC_SUBPACKAGES

try:
    __version__ = _version("graybox")
except PackageNotFoundError:  # pragma: no cover - running from a source tree that was never installed
    __version__ = "0+unknown"

_HOME: dict[str, str] = {}
for _pkg in PUBLIC_SUBPACKAGES:
    for _name in importlib.import_module(f"graybox.{_pkg}").__all__:
        if _pkg == "datasets" and not _name.startswith("load_"):
            continue  # the simulators' names stay in graybox.datasets; only its loaders come up
        if _name in _HOME:
            raise RuntimeError(f"{_name} is exported by both graybox.{_HOME[_name]} and graybox.{_pkg}")
        _HOME[_name] = _pkg

#: Public modules reachable as attributes (``gb.datasets``, ``gb.reference``).
MODULES: tuple[str, ...] = ("datasets", "reference")

__all__ = sorted([*_HOME, *MODULES])


def __getattr__(name: str) -> Any:
    if name in MODULES:
        value = importlib.import_module(f"graybox.{name}")
    elif name in _HOME:
        value = getattr(importlib.import_module(f"graybox.{_HOME[name]}"), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__


def home(name: str) -> str:
    """The subpackage that holds a public name of this namespace (``"estimation"`` for ``"els"``)."""
    return _HOME[name]
