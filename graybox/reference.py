"""The paper's identified models (Tables II and III) and its comparison (Table I) as reference data.

Reading notes (see design.md): Table II's scale column is applied as printed; in
Table III θ14 is read ×1e−5 (the printed ×1e−7 does not reproduce the cluster list
after eq. (20)); Σy²u takes the table's sign (−3.462e−5; the text prints +); Table II's
SE column is shipped for completeness but its printed scales make its static curve
diverge, so it is flagged ``misprinted`` and must not be used as a model of the plant.
Table III's MA parameters are not printed; they are absent here.

Units: u in rpm, y in mlc (metres of liquid column), Ts = 0.05 s.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .models._model import Model
from .core._records import StaticPoints
from .core._terms import Structure
from .core._validation import check_bool, check_int, frozen_value, real_array

__all__ = [
    "STRUCTURE_15",
    "STRUCTURE_17",
    "TABLE_I",
    "TABLE_II",
    "TABLE_III",
    "MISPRINTED",
    "paper_model",
    "eq1",
    "EQ1_COEFFICIENTS",
    "eq1_points",
    "TS",
]

#: The paper's sampling period (s): "Ts = 50 ms" (Section II-B); its models' parameters hold at it.
TS = 0.05

#: Eq. (1): H(u) = β u² + α u + κ, coefficients (κ, α, β) in mlc, mlc/rpm, mlc/rpm².
EQ1_COEFFICIENTS = (-1.3312, 1.4933e-3, 7.2652e-6)


def eq1(u: np.ndarray) -> np.ndarray:
    """The plant's measured static curve, eq. (1), in mlc for u in rpm.

    Parameters
    ----------
    u : float or ndarray
        Pump speeds (rpm), any shape.

    Returns
    -------
    ndarray
        H(u) = β u² + α u + κ (mlc), the shape of ``u`` (:data:`EQ1_COEFFICIENTS`).
    """
    k, a, b = EQ1_COEFFICIENTS
    u = real_array(u, "u")  # a masked entry is no speed (its fill value is no sample)
    return b * u**2 + a * u + k


def eq1_points(ubar: np.ndarray | None = None) -> StaticPoints:
    """Eq. (1) sampled at ū = 750, 850, …, 1650 rpm (or at ``ubar``).

    Parameters
    ----------
    ubar : float or ndarray of shape (M,), optional
        Speeds (rpm) to sample the curve at (default the ten above).

    Returns
    -------
    StaticPoints
        ū (rpm) and ȳ = :func:`eq1` (ū) (mlc), shape (M,), named ``"eq. (1)"``, units ("rpm", "mlc"); no
        uncertainty.
    """
    ub = np.arange(750.0, 1651.0, 100.0) if ubar is None else real_array(ubar, "ubar")
    if ub.ndim > 1:  # speeds of the one input: said of ubar, not of the curve's values at them
        raise ValueError(f"ubar must be 1-D (speeds, rpm), got shape {ub.shape}")
    ub = ub.reshape(-1)  # one speed: one point
    return StaticPoints(ub, eq1(ub), name="eq. (1)", units=("rpm", "mlc"))


#: Table I as printed, MSE in mlc² of the measured plant: model → ``JS_ident``, ``JS_valid``, ``JSF``
#: and ``n_params``, the column names of :func:`graybox.evaluate`, under the names ``graybox
#: reproduce`` gives its own models. The extracted text lists the columns one after another; read
#: row by row, every ordering the text states holds (CLS and PE (D_SF) ℓ = 2 are worse dynamically
#: than ELS (15), model (17) beats (15) in every criterion, the SE (D_SF) ℓ = 3 model is better
#: than ELS (17) on identification and statically "but was worse over the dynamic validation data
#: set", the neural model beats the polynomial black boxes in every criterion).
TABLE_I: Mapping[str, Mapping[str, float]] = frozen_value({
    name: dict(zip(("JS_ident", "JS_valid", "JSF", "n_params"), row))
    for name, row in {
        "ELS (15)": (2.611, 2.116, 1.6040, 17),
        "CLS (22)": (3.221, 2.909, 0.0019, 17),
        "PE (D_SF) ℓ=2": (2.632, 2.389, 0.0009, 17),
        "SE (D_SF) ℓ=2": (2.173, 1.751, 0.0259, 17),
        "ELS (17)": (1.510, 1.104, 0.0603, 23),
        "PE (D_SF) ℓ=3": (2.296, 1.857, 0.0012, 23),
        "SE (D_SF) ℓ=3": (1.208, 1.306, 0.0291, 23),
        "Neural": (1.09, 0.536, 0.0496, 99),
    }.items()
}, "TABLE_I")  # read-only, as the tables below: the paper's figures are no one's to edit

#: The 17 process terms of the paper's eq. (15) (degree 2, ℓ = 2), in Table II's row order.
STRUCTURE_15 = Structure(
    [
        "y(k-1)", "y(k-4)", "u(k-4)u(k-6)", "y(k-2)", "u(k-2)y(k-6)", "u(k-2)y(k-5)", "u(k-2)y(k-1)",
        "u(k-2)y(k-3)", "u(k-4)u(k-5)", "u(k-6)", "1", "u(k-6)^2", "u(k-2)y(k-4)", "y(k-6)",
        "u(k-2)u(k-5)", "u(k-2)^2", "u(k-4)",
    ]
)

_SCALE_II = np.array([1, 1, 1e-7, 1, 1e-4, 1e-4, 1e-4, 1e-4, 1e-6, 1e-3, 1, 1e-6, 1e-4, 1, 1e-7, 1e-7, 1e-3])

_II = {
    "ELS": [0.6303, -0.0264, 0.0608, 0.4388, 2.3013, -1.6981, 2.4569, -1.5936, 0.5191, 1.2475, -0.4770,
            -0.4134, -1.1884, -0.1163, -3.7493, 1.3597, -0.3549],
    "CLS": [0.9667, -0.3122, 6.8554, 0.2219, -0.5289, -0.6784, -0.8580, 0.0761, -0.4136, 0.1051, -0.0980,
            -0.1309, 1.9893, 0.0526, 6.1912, -2.2525, 0.0048],
    "PE": [1.0113, -0.1258, 7.6177, 0.1603, 0.8248, -0.7551, 0.1681, -0.4746, -0.6799, -0.5049, 0.0767,
           -0.1136, 0.1347, -0.0739, 8.5091, -3.3413, 0.2257],
    "SE": [0.6011, 0.8246, 0.3383, 0.1005, 4.6482, 0.5876, 5.1472, -1.8397, -1.1277, -0.3730, -0.3355,
           -1.5104, -8.3407, -0.5735, -9.9186, 0.0097, 1.1591],
}

#: The 23 process terms of the paper's eq. (17) (degree 3, ℓ = 3), in Table III's row order.
STRUCTURE_17 = Structure(
    [
        "y(k-1)", "u(k-6)^2u(k-4)", "y(k-4)", "u(k-4)u(k-2)", "y(k-2)", "y(k-3)", "y(k-6)", "y(k-5)",
        "u(k-5)y(k-1)", "u(k-5)y(k-3)y(k-1)", "u(k-4)u(k-2)y(k-1)", "y(k-2)^2y(k-3)", "u(k-5)^3",
        "u(k-5)^2y(k-2)", "u(k-5)y(k-2)^2", "u(k-5)^2", "y(k-2)^2", "u(k-5)y(k-2)", "u(k-5)",
        "u(k-6)y(k-6)^2", "u(k-2)y(k-1)y(k-4)", "u(k-2)^2y(k-6)", "u(k-2)u(k-4)y(k-4)",
    ]
)

# θ14 read ×1e-5 (design.md), not the printed ×1e-7.
_SCALE_III = np.array([1, 1e-11, 1e-1, 1e-7, 1, 1e-1, 1e-1, 1, 1e-4, 1e-5, 1e-7, 1e-4, 1e-9, 1e-5, 1e-5,
                       1e-6, 1e-2, 1e-4, 1e-3, 1e-6, 1e-6, 1e-8, 1e-8])

_III = {
    "ELS": [0.7418, 5.8941, -0.8754, -2.0096, 0.5012, -0.2666, 0.3065, -0.1296, 0.9340, -0.5657, 0.6199,
            4.3873, -3.5459, 0.0601, -2.6161, 5.8340, 2.6150, -8.3492, -1.4475, 1.0767, -3.8788, 1.8040,
            -2.8455],
    "PE": [1.0122, 5.3573, 0.4728, -2.6422, -0.0486, -0.6566, -0.0946, -0.0599, -0.9738, -0.5847, 1.3015,
           3.8520, -1.0059, 1.0050, -0.4154, 1.5441, 0.3420, 0.8918, -0.0916, 0.5628, -4.7493, 2.4458,
           -9.6289],
    "SE": [1.3356, 0.9251, -3.4779, 1.3142, 0.0256, 1.6692, 2.7295, -0.3300, -4.1309, -1.1723, 0.5955,
           1.4885, -3.0426, 5.7248, -1.5776, 5.2165, 2.2269, -3.4293, -1.7539, 2.5579, 0.3530, -0.2781,
           -6.5877],
}

#: θ of each printed column of Table II (eq. (15): ELS, CLS, PE, SE), engineering units, in :data:`STRUCTURE_15`'s
#: order. Read-only (mappings and arrays): an in-place edit of a writeable table (``th = TABLE_II["ELS"]; th *= 2``)
#: changed every later :func:`paper_model`.
TABLE_II: Mapping[str, np.ndarray] = frozen_value({k: np.array(v) * _SCALE_II for k, v in _II.items()}, "TABLE_II")
#: θ of each printed column of Table III (eq. (17): ELS, PE, SE), engineering units, in :data:`STRUCTURE_17`'s
#: order; read-only as :data:`TABLE_II`.
TABLE_III: Mapping[str, np.ndarray] = frozen_value({k: np.array(v) * _SCALE_III for k, v in _III.items()}, "TABLE_III")

#: Columns whose printed values are known not to describe the plant (kept for the record only).
MISPRINTED = frozenset({("II", "SE")})


def paper_model(equation: int, column: str = "ELS", allow_misprinted: bool = False) -> Model:
    """A model of the paper: ``equation`` 15 (Table II) or 17 (Table III), ``column`` as printed.

    Parameters
    ----------
    equation : {15, 17}
    column : str
        ``"ELS"``, ``"CLS"``, ``"PE"`` or ``"SE"`` (Table II); ``"ELS"``, ``"PE"``, ``"SE"`` (Table III).
    allow_misprinted : bool
        Table II's SE column is misprinted (its static curve diverges); asking for it raises
        unless this is True.

    Returns
    -------
    Model
        The printed parameters, for u in rpm and y in mlc, sampled every :data:`TS` = 0.05 s (its ``Ts``: local
        models' time constants in seconds, and a record at another period refused).
    """
    equation = check_int(equation, "equation")  # 15.0 is 15 (its name said 'ELS (15.0)'); text is no equation
    allow_misprinted = check_bool(allow_misprinted, "allow_misprinted")  # 'no' is truthy: it let the misprint in
    if not isinstance(column, str):  # a list was 'unhashable type'
        raise TypeError(f"column must be a str (a column of Table II or III), got {column!r} ({type(column).__name__})")
    if equation == 15:
        table, structure, tab = TABLE_II, STRUCTURE_15, "II"
    elif equation == 17:
        table, structure, tab = TABLE_III, STRUCTURE_17, "III"
    else:
        raise ValueError(f"the paper's models are eq. 15 and eq. 17, not {equation!r}")
    if column not in table:
        raise ValueError(f"Table {tab} has columns {sorted(table)}, not {column!r}")
    if (tab, column) in MISPRINTED and not allow_misprinted:
        raise ValueError(f"Table {tab}'s {column} column is misprinted (its static curve diverges); "
                         "pass allow_misprinted=True to get it anyway")
    # the paper's parameters hold for the speed in rpm and the pressure in mlc (its eq. (1) and Figs. 2-3)
    return Model(structure, table[column], name=f"{column} ({equation}) [paper]", units=("rpm", "mlc"), Ts=TS)
