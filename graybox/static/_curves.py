"""Static curves ȳ = H(ū) as immutable values: polynomial, given or fitted to points."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core._least_squares import scaled_lstsq
from ..core._records import StaticPoints, outside_range
from ..core._validation import Relocked, as_1d_finite, check_int, check_real, check_str, locked, real_array
from ..core._reprs import exact_text, level_texts, listed, short_repr

__all__ = ["StaticCurve", "fit_on_powers", "round_off_twins"]


@dataclass(frozen=True, eq=False)
class StaticCurve(Relocked):
    """A polynomial static curve H(ū) = c0 + c1 ū + c2 ū² + … (engineering units).

    Attributes
    ----------
    coefficients : ndarray, shape (degree + 1,)
        Ascending powers: eq. (1) is ``[κ, α, β]``.
    domain : (float, float) or None
        The input range over which the curve is known (e.g. the measured ū range); None
        when unknown. Constraints and evaluations outside it are refused.
    name : str
    """

    coefficients: np.ndarray
    domain: tuple[float, float] | None = None
    name: str = "static curve"

    def __post_init__(self) -> None:
        check_str(self.name, "StaticCurve: name")
        what = f"{self.name}: coefficients"  # booleans refused too (True is no coefficient 1)
        c = np.array(as_1d_finite(real_array(self.coefficients, what, "numbers in ascending powers"), what))
        if c.size == 0:
            raise ValueError(f"{self.name}: a polynomial needs at least one coefficient")
        object.__setattr__(self, "coefficients", locked(c))
        if self.domain is not None:
            d = self.domain
            if isinstance(d, str) or not hasattr(d, "__len__") or len(d) != 2:
                raise TypeError(f"{self.name}: domain must be a pair (low, high), got {d!r}")
            lo = check_real(d[0], f"{self.name}: domain low")
            hi = check_real(d[1], f"{self.name}: domain high", low=lo, low_open=True)
            object.__setattr__(self, "domain", (lo, hi))

    @classmethod
    def polynomial(cls, coefficients, domain: tuple[float, float] | None = None, name: str = "static curve") -> "StaticCurve":
        """A curve from ascending coefficients, e.g. ``StaticCurve.polynomial([κ, α, β])`` for eq. (1).

        Parameters
        ----------
        coefficients : array_like, shape (degree + 1,)
            Ascending powers of ū; the k-th in output units per (input unit)^k.
        domain : (float, float), optional
            (ū_min, ū_max), input units, the range over which the curve is known (None: none known).
        name : str, optional
            Its label (default ``"static curve"``).

        Returns
        -------
        StaticCurve
        """
        return cls(coefficients, domain, name)  # checked there, as every curve's (text refused, not parsed)

    @classmethod
    def fit(cls, points: StaticPoints, degree: int = 2, name: str | None = None) -> "StaticCurve":
        """Least-squares polynomial of ``degree`` through static points (columns scaled internally).

        Parameters
        ----------
        points : StaticPoints
            Of one input (several: :meth:`StaticSurface.fit`); at least ``degree + 1`` points, and two at least
            (one level has no range).
        degree : int, optional
            The polynomial's degree, >= 0 (default 2, eq. (1)).
        name : str, optional
            Its label (default ``"fit to <points' name>"``).

        Returns
        -------
        StaticCurve
            Coefficients in the points' units; its domain is the points' ū range.
        """
        if not isinstance(points, StaticPoints):
            raise TypeError(f"StaticCurve.fit: points must be StaticPoints, got {type(points).__name__}")
        if points.n_inputs > 1:
            raise ValueError(f"StaticCurve.fit: the points have {points.n_inputs} inputs {points.input_names}; a curve "
                             "is of one input (fit a surface: StaticSurface.fit)")
        degree = check_int(degree, "degree", low=0)
        if len(points) == 1:  # a curve is known over the points' range: one level has none
            raise ValueError(f"StaticCurve.fit: {points.name} is one level (ū = {exact_text(points.ubar[0])}); a fitted curve "
                             "needs points at two levels or more (its domain is their range)")
        if len(points) < degree + 1:
            raise ValueError(f"fitting degree {degree} needs at least {degree + 1} static points, got {len(points)}")
        return fit_on_powers(points, range(degree + 1), name)

    @property
    def degree(self) -> int:
        """Polynomial degree: the highest power with a nonzero coefficient (0 for a constant), as
        :attr:`StaticSurface.degree <graybox.StaticSurface>` reads it."""
        nz = np.flatnonzero(self.coefficients)
        return int(nz[-1]) if nz.size else 0

    def check_domain(self, ubar: np.ndarray) -> None:
        """Raise ``ValueError`` if any ū of ``ubar`` lies outside the curve's domain (when it has one).

        Parameters
        ----------
        ubar : array_like, any shape
            Input levels, input units, each finite.
        """
        if self.domain is None:
            return
        lo, hi = self.domain
        ub = np.atleast_1d(self._finite(ubar))  # NaN lies in no range, so it was outside none
        out = ub[outside_range(ub, lo, hi)]
        if out.size:
            # the ends told apart ([10000.01, 10000.05] read [10000, 10000], and ū = 10000.0 lay "outside" it)
            raise ValueError("ū = {} outside the domain [{}, {}] of {}".format(listed(out.tolist()), *level_texts([lo, hi]),
                                                                            self.name))

    def __call__(self, ubar: np.ndarray) -> np.ndarray:
        """H(ū), same shape as ``ubar`` (finite, checked against the domain)."""
        ub = self._levels(ubar)
        return np.polynomial.polynomial.polyval(ub, self.coefficients)

    def gain(self, ubar: np.ndarray) -> np.ndarray:
        """dH/dū at ``ubar``.

        Parameters
        ----------
        ubar : array_like, any shape
            Input levels, input units, each finite and within the domain (else ``ValueError``).

        Returns
        -------
        ndarray, the shape of ``ubar``
            Gain in output units per input unit.
        """
        ub = self._levels(ubar)
        return np.polynomial.polynomial.polyval(ub, np.polynomial.polynomial.polyder(self.coefficients))

    def _levels(self, ubar: object) -> np.ndarray:
        """``ubar`` as input levels: numbers (``TypeError``), finite and within the domain (``ValueError``): NaN
        lies in no range, so it passed the domain's check and came back as a NaN "value" of the curve."""
        ub = self._finite(ubar)
        self.check_domain(ub)
        return ub

    def _finite(self, ubar: object) -> np.ndarray:
        """``ubar`` as numbers (``TypeError``), every one finite (``ValueError`` naming the first that is not)."""
        ub = real_array(ubar, "ubar", "input levels (numbers)")
        bad = ~np.isfinite(ub)
        if bad.any():
            raise ValueError(f"{self.name}: ubar has {int(bad.sum())} non-finite value(s) (NaN or inf), first at "
                             f"index {np.argwhere(bad)[0].tolist() if ub.ndim > 1 else int(np.flatnonzero(bad)[0])}")
        return ub

    def points(self, ubar: np.ndarray, input_name: str = "u") -> StaticPoints:
        """The curve sampled at ``ubar`` as static points.

        Parameters
        ----------
        ubar : float or array_like, shape (M,) or (M, 1)
            Input levels, input units, as :meth:`graybox.Model.static_curve` takes them.
        input_name : str, optional
            The points' input (a curve is of one input, whatever the records call it: e.g.
            ``record.input_names[0]``; default ``"u"``).

        Returns
        -------
        StaticPoints
            M points (ū, H(ū)), named as the curve.
        """
        ub = real_array(ubar, "ubar", "input levels (numbers)")
        if ub.ndim == 2 and ub.shape[1] == 1:  # a column: its levels (it was said as "ybar must be 1-D")
            ub = ub[:, 0]
        ub = np.atleast_1d(ub)
        if ub.ndim != 1:
            raise ValueError(f"{self.name}: ubar must be levels of the one input (a number, shape (M,) or (M, 1)), "
                             f"got shape {np.shape(ubar)}")
        return StaticPoints(ub, self(ub), name=self.name, input_names=(input_name,))

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


def fit_on_powers(points: StaticPoints, powers, name: str | None = None) -> StaticCurve:
    """Least-squares polynomial in the given powers of ū (the others 0) through static points of one input.

    Parameters
    ----------
    points : StaticPoints
        At least two levels of one input, at least as many as ``powers`` (the caller checks).
    powers : iterable of int
        Ascending powers of ū the curve has, e.g. ``range(3)`` for a quadratic, ``[0, 2]`` for κ + β ū².
    name : str, optional
        The curve's label (default ``"fit to <points' name>"``).

    Returns
    -------
    StaticCurve
        Over the points' ū range (its domain).
    """
    powers = list(powers)
    degree = max(powers, default=0)
    V = np.vander(points.ubar, degree + 1, increasing=True)[:, powers]
    c = np.zeros(degree + 1)
    try:
        c[powers] = scaled_lstsq(V, points.ybar)
    except ValueError as err:
        # distinct levels (StaticPoints has no duplicates) determine the polynomial, so the rank was lost to
        # round-off: powers of ū far from zero over a narrow range agree to 16 digits (the curve, like the
        # model's clusters Σ_{u^m}, is in powers of ū itself)
        lo, hi = float(points.ubar.min()), float(points.ubar.max())
        which = f"ū⁰ … ū^{degree}" if powers == list(range(degree + 1)) else f"ū^{powers}"
        twins = round_off_twins(points.ubar)
        if twins:
            # levels distinct to StaticPoints (0.1 * 3 and 0.3) and one to the fit: said as such, not as an input far
            # from zero (levels in [0, 0.3] were told to be expressed nearer zero)
            a, b = twins[0]
            n_levels = points.ubar.size - len(twins)
            raise ValueError(
                f"StaticCurve.fit: {points.name} hold the levels {a!r} and {b!r}"
                + (f" (and {len(twins) - 1} more such pair(s))" if len(twins) > 1 else "")
                + f", one level to round-off: the fit has about {n_levels} distinct levels for the "
                f"{len(powers)} powers {which}; give the level once (its ȳ averaged) or fit a lower degree"
            ) from err
        raise ValueError(
            f"StaticCurve.fit: the powers {which} of {points.name} (ū in [{lo:.12g}, {hi:.12g}]) are collinear to "
            "round-off, as powers of an input far from zero over a narrow range are: express the input nearer zero "
            "(e.g. minus a reference level, in the records too) or fit a lower degree"
        ) from err
    return StaticCurve(c, (float(points.ubar.min()), float(points.ubar.max())), name or f"fit to {points.name}")


def round_off_twins(ubar: np.ndarray) -> list[tuple[float, float]]:
    """Adjacent levels of ``ubar`` that differ by no more than the round-off of the levels themselves (a few hundred
    eps of their magnitude: 0.1 * 3 and 0.3), in ascending order."""
    u = np.sort(np.asarray(ubar, float))
    gap = np.diff(u)
    near = gap <= 256 * np.finfo(float).eps * np.maximum(np.abs(u[:-1]), np.abs(u[1:]))
    return [(float(u[i]), float(u[i + 1])) for i in np.flatnonzero(near)]
