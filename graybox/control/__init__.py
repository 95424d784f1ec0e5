"""Control: local linear models at operating points and along the static curve, and the bridge to python-control.

python-control is an optional extra (``pip install graybox[control]``); only the functions that
return python-control systems need it. Inside this package ``import control`` is an absolute
import and reaches python-control.
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_local": ("LocalModel", "OperatingCurve", "local_model", "operating_curve"),
    "_systems": ("narx_initial_state", "narx_iosystem", "narx_state_names", "narx_steady_state"),
})
