"""Every public name of the layers below the figures and the experiments, in one namespace.

:mod:`graybox` re-exports it; the experiment layer reads those layers through it
(``from .. import _api as gb``), so that nothing in :mod:`graybox.experiments` imports the
package that imports it. Names are loaded on first use (see :mod:`graybox._lazy`).
"""

from __future__ import annotations

import importlib

from ._layers import PUBLIC_SUBPACKAGES
from .core._version import graybox_version
from ._lazy import attach

__version__ = graybox_version()

# the simulators' names stay in graybox.datasets; only its loaders, the input design and decimation come up
_DATASET_NAMES = ("design_input", "decimate", "decimation_advice", "DecimationAdvice")
__getattr__, __dir__, __all__ = attach(
    __name__, {pkg: [n for n in importlib.import_module(f"graybox.{pkg}").__all__
                     if pkg != "datasets" or n.startswith("load_") or n in _DATASET_NAMES]
               for pkg in PUBLIC_SUBPACKAGES},
    base="graybox", modules=("datasets", "reference"))  # gb.datasets, gb.reference: modules themselves
