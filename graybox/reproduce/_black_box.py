"""The black-box section of `graybox reproduce`: FROLS + ELS as in Section IV-A."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from ..estimation._extended_least_squares import DEFAULT_NE, els
from ..models._evaluate import evaluate
from ..models._model import Model
from ..core._records import Dataset, Record
from ..selection._forward_regression import Selection, frols
from ..core._terms import Candidates
from ..core._validation import check_sequence
from ..datasets import load_pumping

__all__ = ["PAPER_BLACK_BOX", "black_box_models", "section_black_box"]

#: (degree ℓ, number of terms) of the paper's models (15) and (17).
PAPER_BLACK_BOX: tuple[tuple[int, int], ...] = ((2, 17), (3, 23))


def black_box_models(
    ident: Record | Sequence[Record],
    ny: int = 6,
    nu: int = 6,
    ne: int = DEFAULT_NE,
    sizes: Sequence[tuple[int, int]] = PAPER_BLACK_BOX,
) -> dict[str, tuple[Selection, Model]]:
    """FROLS + ELS as in Section IV-A, for each (degree, n_terms) in ``sizes``: the black boxes of Table I.

    The constant term is always included (eq. (22) needs Σ0 to carry κ) and at degree 2 no candidate
    holds a power of y above 1: the paper's model (15) has that form (its static function is rational),
    as the ELS (15) of ``graybox.reproduce.section_table1``, which is this model.

    Returns
    -------
    dict
        ``"ELS ℓ=2"`` → (Selection, Model), … in the order of ``sizes``.
    """
    pairs = check_sequence(sizes, "sizes", "a sequence of (degree, n_terms) pairs, e.g. ((2, 17), (3, 23))",
                           ordered="(degree, n_terms) pairs")
    for i, pair in enumerate(pairs):  # unpacking said "cannot unpack non-iterable int object"
        if isinstance(pair, (str, bytes)) or not (isinstance(pair, Sequence)
                                                  or (isinstance(pair, np.ndarray) and pair.ndim == 1)):
            raise TypeError(f"sizes[{i}] must be a pair (degree, n_terms), got {pair!r} ({type(pair).__name__})")
        if len(pair) != 2:
            raise ValueError(f"sizes[{i}] must be a pair (degree, n_terms), got {pair!r}")
    degrees = [d for d, _ in pairs]
    twice = next((d for d in degrees if degrees.count(d) > 1), None)
    if twice is not None:  # the models are keyed by degree: the later one replaced the earlier, silently
        raise ValueError(f"sizes gives degree {twice} twice; the models are named by degree (\"ELS ℓ={twice}\"): one "
                         "n_terms per degree")
    out = {}
    for degree, n_terms in pairs:
        cand = Candidates(ny=ny, nu=nu, ne=ne, degree=degree, max_y_power=1 if degree == 2 else None)
        sel = frols(cand, ident, n_terms=n_terms, include=["1"])
        out[f"ELS ℓ={degree}"] = (sel, els(sel, ident, name=f"ELS ℓ={degree}").model)
    return out


def section_black_box(quick: bool = True, out: Path | None = None, data: Dataset | None = None) -> str:
    """``graybox reproduce`` section: black-box ERR + ELS models on the bundled plant data.

    Prints each model's Table I row (columns JS_ident, JS_valid, JSF, n_params; MSE in mlc²) and its
    equation. ``quick`` and ``out`` are accepted for the common section signature; this
    section is fast and draws nothing.
    """
    if data is None:
        data = load_pumping()
    elif not isinstance(data, Dataset):  # a Record failed on its missing .ident, a bare AttributeError
        raise TypeError(f"data must be a Dataset (ident and valid records, static points), got {type(data).__name__}")
    models = black_box_models(data.ident)
    table = evaluate({k: m for k, (_, m) in models.items()}, data)
    lines = [
        "== Black-box models: ERR (FROLS) structure selection + ELS with MA(2) (Section IV-A) ==",
        f"ny = nu = 6, ne = {DEFAULT_NE}; 17 terms at ℓ = 2 (eq. 15: at most one power of y), 23 terms at ℓ = 3 "
        "(eq. 17), the constant always included (Table I's ELS (15) and ELS (17)); the MA part is used for "
        "estimation only.",
        table[["JS_ident", "JS_valid", "JSF", "n_params"]].to_string(float_format=lambda v: f"{v:.4f}"),
    ]
    for key, (sel, m) in models.items():
        lines.append(f"-- {key}: 1 - ΣERR = {1.0 - sel.err_total:.3e}")
        lines.append("   " + m.equation())
    return "\n".join(lines)
