"""Static surfaces ȳ = H(ū₁, …, ū_m) as immutable values: polynomial, given or fitted to points.

The several-input twin of :class:`~graybox.StaticCurve`: a polynomial in the m constant inputs,
stored as monomials ``c_e ū₁^e₁ … ū_m^e_m`` in engineering units, so that its coefficients can be
matched one by one with a model's cluster coefficients (the eq. (22) idea on a surface).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ._curves import round_off_twins
from ..core._least_squares import scaled_lstsq
from ..core._records import StaticPoints, frame_inputs, outside_range
from ..core._terms import check_input_names
from ..core._validation import (Relocked, as_1d_finite, check_int, check_real, check_sequence, check_str, locked,
                                real_array)
from ..core._reprs import level_texts, listed, short_repr

__all__ = ["StaticSurface", "monomial_exponents", "box_grid"]


#: Most points of a grid of levels over a box of inputs (each point a row of a QP or a static evaluation): 25 levels
#: of four inputs are 390 625; a grid beyond this ran out of memory (MemoryError) or never finished.
MAX_GRID_POINTS = 10**6


def box_grid(box: Sequence[tuple[float, float]], levels: int, what: str = "levels",
             fix: str = "take fewer levels") -> np.ndarray:
    """Every combination of ``levels`` evenly spaced levels per input over ``box`` (one (low,
    high) per input), shape (K, m), the first input varying slowest; an input whose range is one
    level (low = high, e.g. a transient input at its static level 0) takes that one level, not
    ``levels`` copies of it (K = levels^(inputs that vary)).

    ``ValueError`` naming ``what`` (the option that set ``levels``) and saying ``fix`` (what the caller can change)
    when K exceeds :data:`MAX_GRID_POINTS`."""
    varying = sum(hi > lo for lo, hi in box)
    if levels ** varying > MAX_GRID_POINTS:
        raise ValueError(f"{what}: {levels} levels per input over {varying} varying inputs make a grid of "
                         f"{levels}^{varying} points, more than {MAX_GRID_POINTS:,}; {fix}")
    axes = [np.linspace(lo, hi, levels if hi > lo else 1) for lo, hi in box]
    return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)


def monomial_exponents(n_inputs: int, degree: int) -> tuple[tuple[int, ...], ...]:
    """All exponent vectors of total degree <= ``degree`` in ``n_inputs`` variables.

    Ordered by total degree, then lexicographically from the first input down
    (``(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), …``).
    """
    m = check_int(n_inputs, "n_inputs", low=1)
    d = check_int(degree, "degree", low=0)
    out: list[tuple[int, ...]] = []
    for total in range(d + 1):
        level = [e for e in itertools.product(range(total + 1), repeat=m) if sum(e) == total]
        out.extend(sorted(level, reverse=True))
    return tuple(out)


def _as_inputs(ubar: object, m: int, what: str, names: Sequence[str] | None = None) -> np.ndarray:
    """ū as a finite array of shape (K, m); a 1-D array is K points when m = 1, one point otherwise; a DataFrame
    is read by column name where its columns are the inputs ``names`` (:func:`~graybox.core._records.frame_inputs`)."""
    u = real_array(frame_inputs(ubar, names, f"{what}: ū"), f"{what}: ū", "points of input levels (numbers)")
    if u.ndim == 1:
        u = u[:, None] if m == 1 else u[None, :]
    if u.ndim != 2 or u.shape[1] != m:
        raise ValueError(f"{what}: ū must have shape (K, {m}) (one column per input), got shape {np.shape(ubar)}")
    if not np.all(np.isfinite(u)):
        raise ValueError(f"{what}: ū has non-finite values")
    return u


def _monomial_set(value: object, name: str, n_inputs: int | None = None) -> tuple[tuple[int, ...], ...]:
    """The exponent vectors of a surface's monomials: at least one, all of one length >= 1 (``n_inputs``
    when given), distinct; ``ValueError`` naming ``name`` (the surface) otherwise."""
    ex = _exponent_vectors(value, "exponents")
    if not ex:
        raise ValueError(f"{name}: a polynomial needs at least one monomial")
    m = len(ex[0]) if n_inputs is None else n_inputs
    if m < 1 or any(len(e) != m for e in ex):
        bad = next((len(e) for e in ex if len(e) != m), m)
        raise ValueError(f"{name}: every exponent vector must have the same length >= 1 (one entry per input"
                         + ("" if n_inputs is None else f": {m} inputs") + f"), got one of {bad} entries")
    if len(set(ex)) != len(ex):
        dup = sorted({e for e in ex if ex.count(e) > 1})
        raise ValueError(f"{name}: monomial(s) {dup} given twice")
    return ex


def _exponent_vectors(value: object, name: str) -> tuple[tuple[int, ...], ...]:
    """Exponent vectors as tuples of integers >= 0, or ``TypeError``/``ValueError`` naming ``name``."""
    out = []
    for i, e in enumerate(check_sequence(value, name, "a sequence of exponent vectors")):
        entries = check_sequence(e, f"{name}[{i}]", "an exponent vector")
        out.append(tuple(check_int(v, f"{name}[{i}]", low=0) for v in entries))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class StaticSurface(Relocked):
    """A polynomial static surface H(ū) = Σ_e c_e ū₁^e₁ … ū_m^e_m (engineering units).

    Attributes
    ----------
    exponents : tuple of tuple of int
        One exponent vector (e₁, …, e_m) per monomial, all distinct; shape (n_monomials, m).
    coefficients : ndarray, shape (n_monomials,)
        c_e for each exponent vector, output units per input unit^|e|.
    domain : tuple of (float, float), optional
        A box (low, high) per input over which the surface is known (e.g. the span of the static
        points); None when unknown. Evaluations outside it are refused.
    name : str
    input_names : tuple of str, optional
        Names of the inputs, in the order of the exponents' entries (default ``u1 … um``, or
        ``("u",)`` for one input).
    """

    exponents: tuple[tuple[int, ...], ...]
    coefficients: np.ndarray
    domain: tuple[tuple[float, float], ...] | None = None
    name: str = "static surface"
    input_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        check_str(self.name, "StaticSurface: name")
        ex = _monomial_set(self.exponents, self.name)
        m = len(ex[0])
        # text and booleans refused, not parsed; a column (K, 1) refused, not flattened: as a StaticCurve's
        what = f"{self.name}: coefficients"
        c = np.array(as_1d_finite(real_array(self.coefficients, what, "numbers, one per monomial"), what))
        if c.size != len(ex):
            raise ValueError(f"{self.name}: {c.size} coefficients for {len(ex)} monomials")
        object.__setattr__(self, "exponents", ex)
        object.__setattr__(self, "coefficients", locked(c))
        if self.domain is not None:
            dom = check_sequence(self.domain, "domain", "a sequence of (low, high) pairs, one per input")
            if len(dom) != m:
                raise ValueError(f"{self.name}: domain needs one (low, high) per input ({m}), got {len(dom)}")
            box = []
            for i, pair in enumerate(dom):
                pair = check_sequence(pair, f"domain[{i}]", "a pair (low, high)")
                if len(pair) != 2:
                    raise ValueError(f"{self.name}: domain[{i}] must be a pair (low, high), got {len(pair)} values")
                lo, hi = check_real(pair[0], f"domain[{i}] (low)"), check_real(pair[1], f"domain[{i}] (high)")
                if not lo < hi:
                    raise ValueError(f"{self.name}: domain of input {i + 1} must be (low, high) with low < high, "
                                     f"got {(lo, hi)}")
                box.append((lo, hi))
            object.__setattr__(self, "domain", tuple(box))
        if self.input_names is None:
            names = ("u",) if m == 1 else tuple(f"u{i + 1}" for i in range(m))
        else:
            names = tuple(check_sequence(self.input_names, "input_names", "a sequence of names"))
        if len(names) != m or len(set(names)) != m:
            raise ValueError(f"{self.name}: input_names must be {m} distinct names, got {names}")
        # the names a model's inputs can have (a surface meets a model's inputs by name): 1 is no name "1"
        object.__setattr__(self, "input_names", check_input_names(names, what=f"{self.name}: input_names"))

    # -- construction -------------------------------------------------------
    @classmethod
    def polynomial(
        cls,
        coefficients: Mapping[Sequence[int], float],
        *,
        domain: Sequence[tuple[float, float]] | None = None,
        name: str = "static surface",
        input_names: Sequence[str] | None = None,
    ) -> "StaticSurface":
        """A surface from ``{exponent vector: coefficient}``, e.g. ``{(0, 0): κ, (1, 0): a, (1, 1): b}``.

        Parameters
        ----------
        coefficients : mapping
            Exponent vector (one entry per input) to coefficient.
        domain : sequence of (low, high), optional
            Box per input where the surface is known, input units.
        name : str
            Label.
        input_names : sequence of str, optional
            Input names (default u1 … um; ``u`` for one input).

        Returns
        -------
        StaticSurface
        """
        if not coefficients:
            raise ValueError(f"{name}: give at least one monomial")
        ex = _exponent_vectors(list(coefficients), "coefficients' keys")
        return cls(ex, list(coefficients.values()), domain, name, input_names)  # checked there (text refused)

    @classmethod
    def fit(
        cls,
        points: StaticPoints,
        degree: int = 2,
        *,
        name: str | None = None,
        exponents: Sequence[Sequence[int]] | None = None,
        input_names: Sequence[str] | None = None,
    ) -> "StaticSurface":
        """Least-squares polynomial surface through static points (columns scaled internally).

        Parameters
        ----------
        points : StaticPoints
            Static points with ``ubar`` of shape (K, m) and ``ybar`` of shape (K,).
        degree : int
            Total degree: every monomial with e₁ + … + e_m <= degree (ignored when ``exponents``
            is given).
        name : str, optional
            Label (default "fit to <points' name>").
        exponents : sequence of exponent vectors, optional
            The monomials to fit instead of the full set of ``degree``.
        input_names : sequence of str, optional
            The surface's inputs, in the order of its exponents' entries (default: the points').
            The points' own names in another order take the points' columns by name; new names
            rename the points' inputs in their order.

        Returns
        -------
        StaticSurface
            Coefficients in the points' units.

        Notes
        -----
        The domain is the box spanned by the points. Needs at least as many points as monomials,
        spread so that the monomials are identifiable (else ``ValueError``).
        """
        if not isinstance(points, StaticPoints):
            raise TypeError(f"StaticSurface.fit: points must be StaticPoints, got {type(points).__name__}")
        yb = points.ybar
        m = points.n_inputs
        ub = _as_inputs(points.ubar, m, "StaticSurface.fit")
        names = tuple(points.input_names)
        if input_names is not None:
            given = tuple(check_sequence(input_names, "StaticSurface.fit: input_names", "a sequence of names"))
            if len(given) != m or len(set(given)) != m:
                raise ValueError(f"StaticSurface.fit: input_names must be {m} distinct names (one per input of the "
                                 f"points), got {given}")
            given = check_input_names(given, what="StaticSurface.fit: input_names")
            if set(given) == set(names):  # the points' own inputs in another order: their columns by name
                ub = ub[:, [names.index(v) for v in given]]
            elif set(given) & set(names):
                raise ValueError(f"StaticSurface.fit: input_names {given} rename some of the points' inputs {names} "
                                 "and not others; give the points' names in the surface's order, or new names for all")
            names = given
        ex = monomial_exponents(m, degree) if exponents is None else _monomial_set(exponents, "StaticSurface.fit", m)
        if len(yb) < len(ex):
            raise ValueError(f"fitting {len(ex)} monomials needs at least {len(ex)} static points, got {len(yb)}")
        box = tuple((float(ub[:, i].min()), float(ub[:, i].max())) for i in range(m))
        held = [n for n, (lo, hi) in zip(names, box) if lo == hi]
        if held:  # before the fit, whose rank test would say less
            raise ValueError(f"StaticSurface.fit: the points do not vary every input: they hold {held} at one value "
                             "(a flat direction has no domain)")
        # a power p of an input needs p + 1 levels of it (a 2 × 3 grid fits no u1²): said by name, before the fit,
        # whose rank test would name neither the input nor the power
        for i, n in enumerate(names):
            # levels apart by round-off (0.1 * 3 and 0.3) are one to the fit, whose rank test said "the inputs move
            # together" of a grid
            distinct = np.unique(ub[:, i])
            levels, top = distinct.size - len(round_off_twins(distinct)), max(e[i] for e in ex)
            if top >= levels:
                raise ValueError(f"StaticSurface.fit: the points hold input {n!r} at {levels} levels, too few for its "
                                 f"power {top} (a power p needs p + 1 levels): give points at more levels of {n!r}, a "
                                 "lower degree, or the monomials to fit as exponents=")
        V = _monomials(ub, ex)
        try:
            c = scaled_lstsq(V, yb)
        except ValueError as err:
            # every input at enough levels, yet the points lie on a curve of the inputs (two inputs
            # stepped together): said of the points, not as a regression's rank that reads as the records'
            monos = ", ".join("*".join(n if v == 1 else f"{n}^{v}" for n, v in zip(names, e) if v) or "1" for e in ex)
            raise ValueError(f"StaticSurface.fit: the {len(yb)} static points do not tell the monomials "
                             f"{monos} apart ({str(err).split(' (')[0].removeprefix('least squares: ')}): the inputs "
                             "move together over them; give points that vary the inputs independently (a grid), or "
                             "fewer monomials as exponents=") from None
        return cls(ex, c, box, name or f"fit to {points.name}", names)

    # -- properties ---------------------------------------------------------
    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return len(self.exponents[0])

    @property
    def degree(self) -> int:
        """Total degree of the highest monomial with a nonzero coefficient (0 for a zero surface)."""
        return max((sum(e) for e, c in zip(self.exponents, self.coefficients) if c != 0.0), default=0)

    def coefficient(self, exponent: Sequence[int]) -> float:
        """c_e of one monomial.

        Parameters
        ----------
        exponent : sequence of int, length m
            The monomial's exponent vector, one power >= 0 per input.

        Returns
        -------
        float
            Its coefficient, output units per product of input units to those powers (0 when the surface has
            none).
        """
        # integer powers only: int(1.7) read another monomial's coefficient
        e = tuple(check_int(v, "exponent", low=0) for v in check_sequence(exponent, "exponent", "an exponent vector"))
        if len(e) != self.n_inputs:
            raise ValueError(f"{self.name}: exponent {e} needs {self.n_inputs} entries")
        try:
            return float(self.coefficients[self.exponents.index(e)])
        except ValueError:
            return 0.0

    def as_dict(self) -> dict[tuple[int, ...], float]:
        """The polynomial as a dict.

        Returns
        -------
        dict of tuple of int to float
            ``{exponent vector: coefficient}``, one entry per monomial.
        """
        return {e: float(c) for e, c in zip(self.exponents, self.coefficients)}

    # -- evaluation ---------------------------------------------------------
    def check_domain(self, ubar: np.ndarray) -> None:
        """Raise ``ValueError`` if any point of ``ubar`` lies outside the domain box (when there is one).

        Parameters
        ----------
        ubar : array_like or pandas.DataFrame, shape (K, m), or (m,) for one point
            Points of input levels, input units: columns in ``input_names`` order (a DataFrame whose columns are the
            ``input_names`` is read by name), each finite.
        """
        if self.domain is None:
            return
        u = _as_inputs(ubar, self.n_inputs, self.name, self.input_names)
        for i, (lo, hi) in enumerate(self.domain):
            col = u[:, i]
            out = col[outside_range(col, lo, hi)]
            if out.size:
                raise ValueError("{} = {} outside the domain [{}, {}] of {}".format(  # ends told apart, as a curve's
                    self.input_names[i], listed(out.tolist()), *level_texts([lo, hi]), self.name))

    def __call__(self, ubar: np.ndarray) -> np.ndarray:
        """H(ū) at points ``ubar`` of shape (K, m) (or (m,) for one point); returns shape (K,)."""
        u = _as_inputs(ubar, self.n_inputs, self.name, self.input_names)
        self.check_domain(u)
        return _monomials(u, self.exponents) @ self.coefficients

    def gradient(self, ubar: np.ndarray) -> np.ndarray:
        """∂H/∂ū_j at points ``ubar``.

        Parameters
        ----------
        ubar : array_like or pandas.DataFrame, shape (K, m), or (m,) for one point
            Points of input levels, input units: columns in ``input_names`` order (a DataFrame whose columns are the
            ``input_names`` is read by name), each finite, within the domain.

        Returns
        -------
        ndarray, shape (K, m)
            One column per input, output units per that input's unit.
        """
        u = _as_inputs(ubar, self.n_inputs, self.name, self.input_names)
        self.check_domain(u)
        out = np.zeros(u.shape)
        for j in range(self.n_inputs):
            for e, c in zip(self.exponents, self.coefficients):
                if e[j] == 0 or c == 0.0:
                    continue
                lower = tuple(v - (i == j) for i, v in enumerate(e))
                out[:, j] += c * e[j] * _monomials(u, (lower,))[:, 0]
        return out

    def points(self, ubar: np.ndarray) -> StaticPoints:
        """The surface sampled at ``ubar`` as static points.

        Parameters
        ----------
        ubar : array_like or pandas.DataFrame, shape (K, m), or (m,) for one point
            Points of input levels, input units: columns in ``input_names`` order (a DataFrame whose columns are the
            ``input_names`` is read by name), each finite, within the domain.

        Returns
        -------
        StaticPoints
            K points (ū, H(ū)) of the surface's inputs, named as the surface.
        """
        u = _as_inputs(ubar, self.n_inputs, self.name, self.input_names)
        return StaticPoints(u if self.n_inputs > 1 else u[:, 0], self(u), name=self.name, input_names=self.input_names)

    def describe(self) -> str:
        """The polynomial as text.

        Returns
        -------
        str
            E.g. ``"-1.3 + 0.0015 u1 + 7.3e-06 u1*u2"`` (six significant digits).
        """
        parts = []
        for e, c in zip(self.exponents, self.coefficients):
            mono = "*".join(n if v == 1 else f"{n}^{v}" for n, v in zip(self.input_names, e) if v)
            parts.append(f"{c:.6g}" + (f" {mono}" if mono else ""))
        return " + ".join(parts).replace("+ -", "- ")

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def _monomials(u: np.ndarray, exponents: Sequence[tuple[int, ...]]) -> np.ndarray:
    """Columns ū₁^e₁ … ū_m^e_m, shape (K, len(exponents)); 0**0 is 1 (a missing factor)."""
    E = np.array(exponents, dtype=float)  # (n, m)
    return np.prod(u[:, None, :] ** E[None, :, :], axis=2)
