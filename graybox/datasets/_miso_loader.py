"""Loader of the bundled two-input benchmark: the pumping rig with its two pump sets at independent speeds."""

from __future__ import annotations

from pathlib import Path

from ..core._records import Dataset
from ._loaders import PUMPING_STATIC_UNCERTAINTY, bundled_data_dir, load_record_csv, load_static_csv

__all__ = ["load_pumping_miso", "pumping_miso_data_dir", "PUMPING_MISO_INPUTS"]

#: The names terms use for the two speed references.
PUMPING_MISO_INPUTS = ("u1", "u2")

PUMPING_MISO_DESCRIPTION = (
    "Simulated two-input variant of the bundled pumping rig (graybox.datasets.TwoSpeedPumpingPlant): "
    "the same motors, pumps, pipe, Francis-turbine load, transmitter noise and process disturbances, "
    "but the two pump sets run at independent speed references u1 and u2 (rpm), in parallel behind "
    "non-return valves into one pipe; the output is the pressure at the turbine (mlc). At equal speeds "
    "it is the bundled rig. Each reference is an independent staircase of 4-9 s holds within "
    "1150-1650 rpm, where both valves stay open at every steady state; 4800 identification and 1200 "
    "validation samples at Ts = 0.05 s. The 36 static points are a 6 x 6 grid over "
    "(1150, 1250, ..., 1650 rpm)^2, each the mean of 6 s of noisy measurements after waiting 180 s. "
    "It is a stand-in made for testing several-input identification, not a measured plant."
)


def pumping_miso_data_dir() -> Path:
    """The folder holding the bundled ``dynamic.csv`` and ``static.csv`` of the two-input rig.

    An installed package carries them as package data ``graybox/data/pumping_miso``; a source
    checkout (or an editable install) reads ``<repo>/data/pumping_miso``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        Neither place holds the data (both named).
    """
    return bundled_data_dir("pumping_miso", "the bundled two-input pumping data", "graybox.datasets._pumping_miso")


def load_pumping_miso() -> Dataset:
    """The bundled two-input benchmark: the pumping rig with its pump sets at independent speeds.

    Returns
    -------
    Dataset
        ``ident``: first 4800 samples, ``valid``: last 1200 (Records with ``u`` of shape (N, 2),
        inputs named ``u1``, ``u2`` (speed references, rpm), output the pressure (mlc),
        Ts = 0.05 s); ``static``: 36 measured points on the 6 × 6 grid (1150, 1250, …, 1650 rpm)²,
        ``ubar`` of shape (36, 2), carrying the transmitter's ±0.175 mlc as ``uncertainty``; ``description``: where the data come from; ``extra``:
        ``"static_surface"`` — the plant's theoretical static surface p̄(ū₁, ū₂), a function of ū
        of shape (K, 2) with a ``domain``; ``"plant"`` — the
        :class:`~graybox.datasets.TwoSpeedPumpingPlant` that generated the data; ``"seed"``; and
        ``"files"`` — the two CSV paths.
    """
    # imported here so that `python -m graybox.datasets._pumping_miso` does not import that module twice
    from ._pumping_miso import (
        DEFAULT_SEED,
        DYNAMIC_COLUMNS_MISO,
        N_IDENT_MISO,
        STATIC_COLUMNS_MISO,
        TwoSpeedPumpingPlant,
    )

    d = pumping_miso_data_dir()
    t_col, u1, u2, y_col = DYNAMIC_COLUMNS_MISO
    rec = load_record_csv(d / "dynamic.csv", u=[u1, u2], y=y_col, time=t_col, name="pumping_miso",
                          units=("rpm", "mlc"), input_names=PUMPING_MISO_INPUTS)
    if len(rec) <= N_IDENT_MISO:
        raise ValueError(f"{d / 'dynamic.csv'}: {len(rec)} samples, need more than {N_IDENT_MISO} to split ident/valid")
    s1, s2, sy = STATIC_COLUMNS_MISO
    static = load_static_csv(d / "static.csv", u=[s1, s2], y=sy, name="pumping_miso static points",
                             input_names=PUMPING_MISO_INPUTS, uncertainty=PUMPING_STATIC_UNCERTAINTY, units=rec.units)
    plant = TwoSpeedPumpingPlant()
    return Dataset(
        ident=rec.slice(0, N_IDENT_MISO, name="pumping_miso ident"),
        valid=rec.slice(N_IDENT_MISO, None, name="pumping_miso valid"),
        static=static,
        description=PUMPING_MISO_DESCRIPTION,
        extra={"static_surface": plant.surface(), "plant": plant, "seed": DEFAULT_SEED,
               "files": (str(d / "dynamic.csv"), str(d / "static.csv"))},
    )
