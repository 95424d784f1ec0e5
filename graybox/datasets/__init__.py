"""Data sets: input design, the bundled pumping-plant benchmark, the buck converter, and CSV loaders.

- :func:`load_pumping` — simulated stand-in for the paper's rig (bundled, works after install);
- :func:`load_pumping_miso` — the same rig with its two pump sets at independent speeds (two inputs, bundled);
- :func:`load_buck` — real buck-converter measurements (bundled, MIT licence notice beside them);
- :func:`load_record_csv`, :func:`load_static_csv` — users' own files, columns chosen by name;
- :func:`design_input` — the input of an identification experiment (APRBS, staircase, PRBS, multisine);
- :func:`decimation_advice`, :func:`decimate` — how far an oversampled record may be decimated for a NARX
  model (Billings & Aguirre's rule), and decimation with an anti-alias filter on the output;
- :mod:`graybox.datasets.pumping` — the plant simulator and the generator of the bundled files
  (``python -m graybox.datasets.pumping`` rewrites them);
- :class:`TwoSpeedPumpingPlant` — the same rig with its two pump sets at independent speeds, a
  two-input benchmark (``python -m graybox.datasets._pumping_miso`` rewrites its bundled files).
"""

from .._lazy import attach

_PUMPING_NAMES = ("PlantRun", "PumpingPlant", "speed_reference", "static_experiment")
_PUMPING_MISO_NAMES = ("TwoSpeedPumpingPlant", "TwoSpeedRun", "two_speed_reference", "static_grid_experiment")

# Loaded on first use, not at import: `python -m graybox.datasets.pumping` would otherwise import that
# module twice (runpy warns), and `import graybox` stays light.
__getattr__, __dir__, __all__ = attach(__name__, {
    "_inputs": ("design_input",),
    "_decimation": ("DecimationAdvice", "decimate", "decimation_advice"),
    "_loaders": ("BUCK_STATIC_CURVE", "find_buck_dir", "load_buck", "load_pumping", "load_record_csv",
                 "load_static_csv", "pumping_data_dir"),
    "_miso_loader": ("load_pumping_miso", "pumping_miso_data_dir"),
    "pumping": _PUMPING_NAMES,
    "_pumping_miso": _PUMPING_MISO_NAMES,
})
