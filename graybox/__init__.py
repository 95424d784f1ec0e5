"""graybox: black- and gray-box identification of nonlinear dynamic systems.

Polynomial NARMAX models, structure selection, static analysis and gray-box estimation
with static-curve information, after Barbosa, Aguirre, Martinez & Braga (IEEE TCST 2011).

The implementation lives in subpackages by concern (:mod:`graybox.core`, :mod:`graybox.static`,
:mod:`graybox.models`, :mod:`graybox.selection`, :mod:`graybox.estimation`,
:mod:`graybox.diagnostics`, :mod:`graybox.control`, :mod:`graybox.io`, :mod:`graybox.datasets`), each of private modules;
their public names are exported here, but for the plant simulators and data folders of :mod:`graybox.datasets`,
reached through it (``gb.datasets.PumpingPlant``). :mod:`graybox.reference`, :mod:`graybox.plots`,
:mod:`graybox.experiments` and :mod:`graybox.reproduce` are used through their subpackage (of the experiments,
``select_graybox``, ``GrayboxSelection``, ``SelectionWarning`` and ``load_results`` are exported here too).
Names load on first use, so ``import graybox`` is quick.
"""

from __future__ import annotations

from . import _api
from ._api import __version__
from ._lazy import attach

# The experiment layer's names re-exported at the top, the rest through graybox._api; plots,
# experiments and reproduce are reachable as attributes. All load on first use.
__getattr__, __dir__, _names = attach(
    __name__, {"experiments": ("GrayboxSelection", "SelectionWarning", "load_results", "select_graybox"),
               "_api": _api.__all__},
    base="graybox", modules=("plots", "experiments", "reproduce"), present=("__version__",))
__all__ = _names
