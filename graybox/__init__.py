"""graybox: black- and gray-box identification of nonlinear dynamic systems.

Polynomial NARMAX models, structure selection, static analysis and gray-box estimation
with static-curve information, after Barbosa, Aguirre, Martinez & Braga (IEEE TCST 2011).

The implementation lives in subpackages by concern (:mod:`graybox.core`, :mod:`graybox.static`,
:mod:`graybox.models`, :mod:`graybox.selection`, :mod:`graybox.estimation`,
:mod:`graybox.diagnostics`, :mod:`graybox.control`, :mod:`graybox.io`, :mod:`graybox.datasets`), each of private modules;
every public name is exported here. :mod:`graybox.plots`, :mod:`graybox.experiments` and
:mod:`graybox.reproduce` sit above them. Names load on first use, so ``import graybox`` is quick.
"""

from __future__ import annotations

import importlib
from typing import Any

from . import _api
from ._api import __version__

#: Subpackages reachable as attributes, loaded on first use.
_SUBMODULES = ("plots", "experiments", "reproduce")
#: Names of the experiment layer re-exported at the top.
_EXPERIMENT_NAMES = ("GrayboxSelection", "SelectionWarning", "load_results", "select_graybox")

__all__ = sorted([*_api.__all__, *_SUBMODULES, *_EXPERIMENT_NAMES, "__version__"])


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        value = importlib.import_module(f"graybox.{name}")
    elif name in _EXPERIMENT_NAMES:
        value = getattr(importlib.import_module("graybox.experiments"), name)
    elif name in _api.__all__:
        value = getattr(_api, name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
