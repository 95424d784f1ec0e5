"""A polynomial NARMAX model as a LaTeX equation (math mode, without delimiters)."""

from __future__ import annotations

import re

import numpy as np

from ._terms import Structure, Term

__all__ = ["latex_number", "latex_term", "latex_equation"]

_SIGNAL = {"y": "y", "e": r"\xi"}


def _latex_signal(name: str) -> str:
    """A signal's name in math mode: y, ξ for e, one letter as it is (``u``), a letter and digits
    with the digits as subscript (``u_{1}``), any other input name upright with ``_`` escaped."""
    if name in _SIGNAL:
        return _SIGNAL[name]
    m = re.fullmatch(r"([A-Za-z])(\d*)", name)
    if m:
        return m.group(1) + (f"_{{{m.group(2)}}}" if m.group(2) else "")
    return r"\mathrm{" + name.replace("_", r"\_") + "}"


def latex_number(value: float, digits: int = 4) -> str:
    """|value| with ``digits`` significant digits; powers of ten as ``\\times 10^{-4}``."""
    text = f"{abs(float(value)):.{digits}g}"
    if "e" in text:
        mant, exp = text.split("e")
        return f"{mant} \\times 10^{{{int(exp)}}}"
    return text


def latex_term(term: Term) -> str:
    """``u(k-2)\\,y(k-6)``, ``u(k-6)^{2}``, ``\\xi(k-1)``; the constant term is the empty string."""
    parts = []
    for s, lag, p in term.factors:
        f = f"{_latex_signal(s)}(k-{lag})"
        parts.append(f + (f"^{{{p}}}" if p > 1 else ""))
    return r"\,".join(parts)


def latex_equation(
    structure: Structure,
    theta: np.ndarray,
    noise_structure: Structure | None = None,
    noise_theta: np.ndarray | None = None,
    digits: int = 4,
    terms_per_line: int | None = None,
) -> str:
    """``y(k) = θ_1 ψ_1 + … + c_1 ξ(k-1) + … + ξ(k)`` in LaTeX (the MA part with ξ as the paper writes it).

    With ``terms_per_line`` the equation is an ``aligned`` block broken every that many terms.
    """
    items = list(zip(theta, structure))
    ns = noise_structure if noise_structure is not None else Structure(())
    nth = noise_theta if noise_theta is not None else np.zeros(0)
    items += list(zip(nth, ns))
    pieces = []
    for i, (th, t) in enumerate(items):
        num = latex_number(th, digits)
        body = num if t.is_constant else f"{num}\\,{latex_term(t)}"
        sign = "-" if th < 0 else "+"
        pieces.append((f"-{body}" if sign == "-" else body) if i == 0 else f"{sign} {body}")
    if len(ns):
        pieces.append(r"+ \xi(k)")
    if not pieces:
        pieces = ["0"]
    if not terms_per_line:
        return "y(k) = " + " ".join(pieces)
    lines = [" ".join(pieces[i: i + terms_per_line]) for i in range(0, len(pieces), terms_per_line)]
    return "\\begin{aligned}\ny(k) ={}& " + " \\\\\n&".join(lines) + "\n\\end{aligned}"
