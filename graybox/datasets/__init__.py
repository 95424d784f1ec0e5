"""Data sets: the bundled pumping-plant benchmark, the buck converter, and CSV loaders.

- :func:`load_pumping` — simulated stand-in for the paper's rig (bundled, works after install);
- :func:`load_pumping_miso` — the same rig with its two pump sets at independent speeds (two inputs, bundled);
- :func:`load_buck` — real buck-converter measurements kept outside the project;
- :func:`load_record_csv`, :func:`load_static_csv` — users' own files, columns chosen by name;
- :mod:`graybox.datasets.pumping` — the plant simulator and the generator of the bundled files
  (``python -m graybox.datasets.pumping`` rewrites them);
- :class:`TwoSpeedPumpingPlant` — the same rig with its two pump sets at independent speeds, a
  two-input benchmark (``python -m graybox.datasets._pumping_miso`` rewrites its bundled files).
"""

from ._loaders import (
    BUCK_STATIC_CURVE,
    find_buck_dir,
    load_buck,
    load_pumping,
    load_record_csv,
    load_static_csv,
    pumping_data_dir,
)
from ._miso_loader import load_pumping_miso, pumping_miso_data_dir

_PUMPING_NAMES = ("PlantRun", "PumpingPlant", "speed_reference", "static_experiment")
_PUMPING_MISO_NAMES = ("TwoSpeedPumpingPlant", "TwoSpeedRun", "two_speed_reference", "static_grid_experiment")


def __getattr__(name: str):
    # The simulator's names are loaded on first use, not at import: `python -m
    # graybox.datasets.pumping` would otherwise import that module twice (runpy warns).
    if name in _PUMPING_NAMES:
        from . import pumping

        return getattr(pumping, name)
    if name in _PUMPING_MISO_NAMES:
        from . import _pumping_miso

        return getattr(_pumping_miso, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "load_pumping",
    "load_pumping_miso",
    "pumping_miso_data_dir",
    "load_buck",
    "load_record_csv",
    "load_static_csv",
    "find_buck_dir",
    "pumping_data_dir",
    "BUCK_STATIC_CURVE",
    "PumpingPlant",
    "PlantRun",
    "speed_reference",
    "static_experiment",
    *_PUMPING_MISO_NAMES,
]
