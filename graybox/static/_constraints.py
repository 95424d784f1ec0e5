"""Static-curve constraints on θ as small, composable, immutable objects.

Every constraint here is a value: it holds its own settings (a curve, a band width, a ū
range, cluster bounds, a user function) and, given the problem's data (a
:class:`StaticContext`: structure, static points, static curve, reference Σ*_y, the input
range of the dynamic data), yields

- :meth:`StaticConstraint.affine`: rows ``A_eq θ = b_eq`` and ``A_ub θ <= b_ub`` in
  engineering units (all built-in variants are affine in θ), which the estimators in
  the convex estimators (`graybox.estimation._prediction_error`) scale and normalise before handing them to a solver, and which the
  closed forms use directly (equalities);
- :meth:`StaticConstraint.constraints`: cvxpy constraints on a θ expression;
- :meth:`StaticConstraint.violation`: how far a given θ is from satisfying it.

Constraints combine with ``&`` (``band & gain & ClusterBounds(...)``) into :class:`AllOf`.

Several inputs: the static function is a surface ȳ(ū_1, …, ū_m), the clusters are
Ω_{y^p u1^a1 ⋯ um^am} (:func:`static_cluster_map`, the core's surface cluster map, in the order of
the data's inputs), static points have ū of shape (M, m), and every row below is built the same
way with ū^m read as the monomial Π_i ū_i^a_i: eq. (22) matches a :class:`~graybox.StaticSurface`
coefficient by coefficient, the band and the points are unchanged, and the gain bounds hold per
input (the gain is a gradient).

Why the static error is affine in θ (eq. (12)): at a steady state every term
``y^p(k-i) u^m(k-j)`` becomes ``ȳ^p ū^m``, so with the *measured* ȳ_i placed on the regressor
side the right-hand side of the static equation is ``q_iᵀ R θ`` with
``q_i = [ȳ_i^p ū_i^m for each cluster (p, m)]``, linear in θ. For a rational structure
(no y power above 1) the residual ``ȳ_i − q_iᵀRθ`` equals ``D(ū_i) (ȳ_i − ȳ_model(ū_i))``
with the denominator ``D(ū) = 1 − Σy − Σyu ū − …`` of eq. (6), which is also affine in θ.
That identity turns the band ``|ȳ_model(ū_i) − ȳ_i| <= b`` into two affine inequalities
(exactly, for rational structures) and the static-gain bounds into affine inequalities along
a reference curve (see :class:`GainBounds` for the approximation).
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Callable, Iterable, Iterator, Mapping, Sequence

import numpy as np

from ._curves import StaticCurve
from ..core._records import StaticPoints
from ._surfaces import StaticSurface, box_grid
from ._analysis import ClusterMap, cluster_map, cluster_name, denominator_vanishes, is_rational, vanishing_denominator
from ._surface_analysis import SurfaceClusterMap, surface_cluster_map, surface_static_rows
from ..core._terms import Structure, transient_source
from ..core._validation import (Relocked, FrozenMap, check_choice, check_int, check_real, check_sequence, check_str,
                                short_value)
from ..core._reprs import level_texts, short_repr

if TYPE_CHECKING:  # cvxpy takes seconds to import: loaded where a user constraint needs it
    import cvxpy as cp

__all__ = [
    "InfeasibleError",
    "StaticContext",
    "auto_min_denominator",
    "check_min_denominator",
    "DENOMINATOR_FACTOR",
    "AffineRows",
    "StaticConstraint",
    "CurveEquality",
    "PassesThrough",
    "StaticBand",
    "GainBounds",
    "ClusterBounds",
    "UserConstraint",
    "AllOf",
    "as_constraint_list",
    "static_rows",
    "cluster_powers",
    "n_static_inputs",
    "static_inputs",
    "sigma_y_index",
    "FREE_SIGMA_Y",
    "static_cluster_map",
]


class InfeasibleError(ValueError):
    """The constraints admit no θ (or the solver could not find one); the message names them."""


# --------------------------------------------------------------------------------------------
# static rows (eq. (12)) and their derivatives
# --------------------------------------------------------------------------------------------
def cluster_powers(key: tuple) -> tuple[int, tuple[int, ...]]:
    """(p, (m_1, …, m_m)) of a cluster key: the output power and one input power per input.

    SISO keys are (p, m); several-input keys are (p, m_1, …, m_m) or (p, (m_1, …, m_m)).
    """
    p, rest = int(key[0]), tuple(key[1:])
    if len(rest) == 1 and isinstance(rest[0], tuple):
        rest = rest[0]
    return p, tuple(int(v) for v in rest)


def n_static_inputs(cm: ClusterMap | SurfaceClusterMap) -> int:
    """Number of inputs the clusters of ``cm`` speak of (1 for a SISO structure)."""
    if isinstance(cm, SurfaceClusterMap):
        return len(cm.input_names)
    return max((len(cluster_powers(k)[1]) for k in cm.keys), default=1)


def static_cluster_map(structure: Structure, inputs: tuple[str, ...] | None = None) -> ClusterMap | SurfaceClusterMap:
    """The clusters of ``structure``: per input power for one input, per input powers for several.

    ``inputs`` are the data's input names (the order of ū's columns); a structure that uses fewer
    inputs than the data still gets one power per data input.
    """
    if len(structure.input_names) > 1 or (inputs is not None and len(inputs) > 1):
        return surface_cluster_map(structure, input_names=None if inputs is None else tuple(inputs))
    return cluster_map(structure)


#: ``sigma_y`` / ``reference`` value that estimates Σ_y of eq. (22) with the other parameters
FREE_SIGMA_Y = "free"


def sigma_y_index(cm: ClusterMap) -> int | None:
    """Row of R of the cluster Σ_y (output power 1, no input), or None when the structure has none."""
    for k, key in enumerate(cm.keys):
        p, e = cluster_powers(key)
        if p == 1 and not any(e):
            return k
    return None


def _has_sigma_y(cm: ClusterMap) -> bool:
    return sigma_y_index(cm) is not None


def static_inputs(ubar: object, m: int, what: str = "static points") -> np.ndarray:
    """ū as shape (M,) for one input, (M, m) for several; a clear error when the count differs."""
    ub = np.asarray(ubar, float)
    if m == 1:
        if ub.ndim == 2 and ub.shape[1] == 1:
            ub = ub[:, 0]
        if ub.ndim != 1:
            raise ValueError(f"{what}: the structure has one input but ū has shape {ub.shape} "
                             f"({ub.shape[-1]} inputs per point)")
        return ub
    if ub.ndim != 2 or ub.shape[1] != m:
        got = 1 if ub.ndim == 1 else ub.shape[-1]
        raise ValueError(f"{what}: the structure has {m} inputs but ū has shape {ub.shape} ({got} input(s) per "
                         f"point); give ū of shape (M, {m}), one column per input in the structure's order")
    return ub


def static_rows(cm: ClusterMap, ubar: np.ndarray, ybar: np.ndarray, wrt: str | None = None, *,
                input: int | None = None) -> np.ndarray:
    """Rows of Q in eq. (12) (or their derivatives) for the clusters of ``cm``.

    Parameters
    ----------
    cm : ClusterMap
        Cluster keys: output power p and input power(s) (m, or m_1 … m_m for several inputs).
    ubar : ndarray, shape (M,) or (M, m)
        Input levels (engineering units), one column per input for several inputs.
    ybar : ndarray, shape (M,)
        Output levels; ȳ is the *measured* (or reference) level.
    wrt : {None, "y", "u"}
        None: ``Q[i, c] = ȳ_i^p Π_j ū_ij^(m_j)`` (so the static prediction is ``Q R θ``);
        ``"y"``: ``∂/∂ȳ = p ȳ^(p-1) Π_j ū_j^(m_j)``; ``"u"``: ``∂/∂ū_input``.
    input : int, optional
        With ``wrt="u"``: which input (0-based); required when there are several.

    Returns
    -------
    ndarray, shape (M, n_clusters)
    """
    m_in = n_static_inputs(cm)
    if wrt not in (None, "y", "u"):
        raise ValueError(f"wrt must be None, 'y' or 'u', got {wrt!r}")
    if m_in == 1:
        if input not in (None, 0):
            raise ValueError(f"input must be 0 for a structure with one input, got {input!r}")
        ub = static_inputs(ubar, 1)[:, None]
        yb = np.asarray(ybar, float)[:, None]
        p = np.array([cluster_powers(k)[0] for k in cm.keys], float)[None, :]
        m = np.array([cluster_powers(k)[1][0] for k in cm.keys], float)[None, :]
        # np.power(0., 0.) == 1, which is what a missing factor means; negative exponents only
        # appear multiplied by a zero power, so mask them instead of evaluating 0**-1.
        if wrt is None:
            return yb**p * ub**m
        if wrt == "y":
            return np.where(p > 0, p * yb ** np.maximum(p - 1, 0) * ub**m, 0.0)
        return np.where(m > 0, m * yb**p * ub ** np.maximum(m - 1, 0), 0.0)
    U = static_inputs(ubar, m_in)
    if wrt == "u" and (input is None or not (0 <= int(input) < m_in)):
        raise ValueError(f"wrt='u' needs input = 0 … {m_in - 1} (which input) for a structure with {m_in} inputs, "
                         f"got {input!r}")
    if not isinstance(cm, SurfaceClusterMap):
        raise ValueError("several inputs need the structure's surface cluster map (static_cluster_map)")
    return surface_static_rows(cm, U, ybar, cm.input_names[int(input)] if wrt == "u" else wrt)


# --------------------------------------------------------------------------------------------
# problem data given to constraints
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StaticContext:
    """The problem's data as constraints see it.

    Attributes
    ----------
    structure : Structure
        Process terms, in parameter order.
    points : StaticPoints or None
        The problem's static points (measured steady states), if any.
    curve : StaticCurve, StaticSurface or None
        The problem's static curve (or surface, for several inputs), if any.
    sigma_y : float, "free" or None
        Σ*_y of the reference model (eq. (22)), or ``"free"`` (Σ_y estimated); used by
        :class:`CurveEquality` when it is not given its own value.
    inputs : tuple of str or None
        The data's input names, the order of ū's columns (None: the structure's own inputs).
    ls_theta : ndarray of shape (n_terms,) or None
        The problem's unconstrained least-squares estimate (engineering units): the reference of
        ``min_denominator="auto"`` (:func:`auto_min_denominator`); None when not needed or not
        identifiable.
    """

    structure: Structure
    points: StaticPoints | None = None
    curve: StaticCurve | StaticSurface | None = None
    sigma_y: float | str | None = None
    inputs: tuple[str, ...] | None = None
    ls_theta: np.ndarray | None = None

    @cached_property
    def cluster_map(self) -> ClusterMap | SurfaceClusterMap:
        """Clusters and the 0/1 map R of the structure (per input powers for several inputs)."""
        return static_cluster_map(self.structure, self.inputs)

    @property
    def n_terms(self) -> int:
        """Number of parameters."""
        return len(self.structure)

    def require_points(self, points: StaticPoints | None, what: str) -> StaticPoints:
        """The constraint's own points, or the problem's, or a clear error."""
        pts = points if points is not None else self.points
        if pts is None:
            raise ValueError(f"{what} needs static points: give them to the constraint or to the estimator")
        return pts

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


# --------------------------------------------------------------------------------------------
# affine rows
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class AffineRows:
    """``A_eq θ = b_eq`` and ``A_ub θ <= b_ub`` in engineering units.

    Attributes
    ----------
    A_eq : ndarray, shape (k, n_terms)
    b_eq : ndarray, shape (k,)
    A_ub : ndarray, shape (j, n_terms)
    b_ub : ndarray, shape (j,)
    """

    A_eq: np.ndarray
    b_eq: np.ndarray
    A_ub: np.ndarray
    b_ub: np.ndarray

    @classmethod
    def make(cls, n: int, A_eq=None, b_eq=None, A_ub=None, b_ub=None) -> "AffineRows":
        """Build with empty defaults and validated shapes."""
        def two(A, b, what):
            A = np.zeros((0, n)) if A is None else np.atleast_2d(np.asarray(A, float))
            b = np.zeros(A.shape[0]) if b is None else np.atleast_1d(np.asarray(b, float))
            if A.shape != (b.size, n):
                raise ValueError(f"{what}: rows of shape {A.shape} do not match {b.size} bounds and {n} terms")
            if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
                raise ValueError(f"{what}: non-finite coefficients (check the static points and curve)")
            A.setflags(write=False)
            b.setflags(write=False)
            return A, b

        Ae, be = two(A_eq, b_eq, "equality")
        Au, bu = two(A_ub, b_ub, "inequality")
        return cls(Ae, be, Au, bu)

    @property
    def n_eq(self) -> int:
        """Number of equality rows."""
        return self.b_eq.size

    @property
    def n_ub(self) -> int:
        """Number of inequality rows."""
        return self.b_ub.size

    def violation(self, theta: np.ndarray) -> float:
        """Largest violation relative to the size of the row's terms (unit-free, >= 0).

        Row ``a θ ≤ b`` is violated by ``max(a θ − b, 0) / (|b| + Σ_j |a_j θ_j|)``: the
        denominator is the magnitude of the quantities being compared, so 1e-9 means "satisfied
        to nine digits" whatever the units.
        """
        th = np.asarray(theta, float)
        worst = 0.0
        for A, b, eq in ((self.A_eq, self.b_eq, True), (self.A_ub, self.b_ub, False)):
            if b.size == 0:
                continue
            r = A @ th - b
            r = np.abs(r) if eq else np.maximum(r, 0.0)
            scale = np.abs(b) + np.abs(A) @ np.abs(th)
            worst = max(worst, float(np.max(r / np.where(scale > 0, scale, 1.0))))
        return worst

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


# --------------------------------------------------------------------------------------------
# the base class
# --------------------------------------------------------------------------------------------
class StaticConstraint(Relocked, ABC):
    """A constraint on θ that depends on the problem's data; combine with ``&``."""

    @abstractmethod
    def describe(self) -> str:
        """A short human-readable description used in error messages.

        Returns
        -------
        str
        """

    def affine(self, ctx: StaticContext) -> AffineRows | None:
        """Affine rows in engineering units for the problem ``ctx``.

        Parameters
        ----------
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        AffineRows or None
            ``A_eq θ = b_eq`` and ``A_ub θ <= b_ub``, each row of shape (n_terms,); None when the constraint is not
            affine.
        """
        return None

    def constraints(self, theta: cp.Expression, ctx: StaticContext) -> list[cp.Constraint]:
        """cvxpy constraints on ``theta`` for the problem ``ctx``.

        Parameters
        ----------
        theta : cvxpy.Expression, shape (n_terms,)
            The parameters, engineering units.
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        list of cvxpy.Constraint
        """
        rows = self.affine(ctx)
        if rows is None:  # pragma: no cover - subclasses that are not affine override this
            raise NotImplementedError(f"{type(self).__name__} must implement constraints()")
        out: list[cp.Constraint] = []
        if rows.n_eq:
            out.append(rows.A_eq @ theta == rows.b_eq)
        if rows.n_ub:
            out.append(rows.A_ub @ theta <= rows.b_ub)
        return out

    def violation(self, theta: np.ndarray, ctx: StaticContext) -> float:
        """How far ``theta`` is from satisfying the constraint on the problem ``ctx``.

        Parameters
        ----------
        theta : ndarray, shape (n_terms,)
            Process parameters, engineering units.
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        float
            >= 0, 0 when satisfied. For affine constraints the largest violation of a row relative to the size of its
            terms (``AffineRows.violation``: unit-free).
        """
        rows = self.affine(ctx)
        if rows is None:  # pragma: no cover - overridden by non-affine subclasses
            raise NotImplementedError
        return rows.violation(theta)

    def check(self, ctx: StaticContext) -> None:
        """Validate against the problem's data ``ctx`` (raises ``ValueError``); called before solving.

        Parameters
        ----------
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).
        """
        self.affine(ctx)

    def after_solve(self, theta: np.ndarray, ctx: StaticContext) -> None:
        """Checks on the estimate ``theta`` of the problem ``ctx`` that the rows cannot express (raises
        ``ValueError``).

        Parameters
        ----------
        theta : ndarray, shape (n_terms,)
            Process parameters, engineering units.
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).
        """

    def __iter__(self) -> Iterator["StaticConstraint"]:
        yield self

    def __and__(self, other: "StaticConstraint") -> "AllOf":
        if not isinstance(other, StaticConstraint):
            return NotImplemented
        return AllOf((*self, *other))

    def __repr__(self) -> str:
        return f"<{self.describe()}>"


def as_constraint_list(constraints: StaticConstraint | Iterable[StaticConstraint] | None) -> list[StaticConstraint]:
    """Flatten ``None``, one constraint, an :class:`AllOf` or a sequence of them into a list."""
    if constraints is None:
        return []
    if isinstance(constraints, StaticConstraint):
        return list(constraints)
    if isinstance(constraints, str) or not hasattr(constraints, "__iter__"):
        raise TypeError(f"constraints must be a constraint, a sequence of them or None, got {constraints!r}")
    if isinstance(constraints, Mapping):  # iterated, a table would be its keys ("got str")
        raise TypeError(f"constraints must be graybox constraint objects, got a dict {dict(constraints)!r}: tables such "
                        "as {'type': 'band', …} are a grid spec's form; here give the object (gb.StaticBand(b=…), …)")
    out: list[StaticConstraint] = []
    for c in constraints:
        if not isinstance(c, StaticConstraint):
            raise TypeError(
                f"constraints must be graybox constraint objects (gb.StaticBand, gb.CurveEquality, …), got {type(c).__name__}; "
                "wrap a cvxpy function of θ in UserConstraint(fn)"
            )
        out.extend(c)
    return out


@dataclass(frozen=True, eq=False, repr=False)
class AllOf(StaticConstraint):
    """Several constraints imposed together (what ``a & b`` returns)."""

    members: tuple[StaticConstraint, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "members", tuple(as_constraint_list(self.members)))

    def __iter__(self) -> Iterator[StaticConstraint]:
        return iter(self.members)

    def __len__(self) -> int:
        return len(self.members)

    def describe(self) -> str:
        return " & ".join(c.describe() for c in self.members) or "no constraints"

    def affine(self, ctx: StaticContext) -> AffineRows | None:
        parts = [c.affine(ctx) for c in self.members]
        if any(p is None for p in parts):
            return None
        n = ctx.n_terms
        return AffineRows.make(
            n,
            np.vstack([np.zeros((0, n))] + [p.A_eq for p in parts]),
            np.concatenate([np.zeros(0)] + [p.b_eq for p in parts]),
            np.vstack([np.zeros((0, n))] + [p.A_ub for p in parts]),
            np.concatenate([np.zeros(0)] + [p.b_ub for p in parts]),
        )

    def constraints(self, theta: cp.Expression, ctx: StaticContext) -> list[cp.Constraint]:
        return [k for c in self.members for k in c.constraints(theta, ctx)]

    def violation(self, theta: np.ndarray, ctx: StaticContext) -> float:
        return max((c.violation(theta, ctx) for c in self.members), default=0.0)

    def check(self, ctx: StaticContext) -> None:
        for c in self.members:
            c.check(ctx)

    def after_solve(self, theta: np.ndarray, ctx: StaticContext) -> None:
        for c in self.members:
            c.after_solve(theta, ctx)


# --------------------------------------------------------------------------------------------
# (22): the rational static function equals a polynomial static curve
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class CurveEquality(StaticConstraint):
    """Eq. (22): the model's rational static function equals the polynomial curve H(ū) (or surface).

    With ȳ = N(ū)/D(ū) (eq. (6)) and H(ū) = Σ_m c_m ū^m, the identity N ≡ D·H is met by
    making the denominator constant and matching the numerator:

    - ``Σ_{y u^m} = 0`` for every cluster with m >= 1,
    - ``Σ_y = Σ*_y``,
    - ``Σ_{u^m} = (1 − Σ*_y) c_m`` for every numerator cluster (c_m = 0 above the curve's degree).

    Σ*_y comes from a reference model (the paper: the ELS estimate's Σ_y) or is given here; or it is
    ``"free"``: Σ_y is estimated with the other parameters under ``Σ_{u^m} + c_m Σ_y = c_m`` (still
    affine), the least-squares model among all whose static function is H. A reference's Σ_y is its
    denominator's slope at ū = 0, which depends on where the input's zero is (rpm or rpm − 1000);
    the free Σ_y does not (graybox's estimators use it unless told otherwise).

    Several inputs: with a :class:`~graybox.StaticSurface` H(ū) = Σ_e c_e ū_1^e_1 ⋯ ū_m^e_m the same
    identity gives ``Σ_{y u^e} = 0`` for every e ≠ 0, ``Σ_y = Σ*_y`` and
    ``Σ_{u^e} = (1 − Σ*_y) c_e`` for every numerator cluster (c_e = 0 for monomials the surface
    does not have); every monomial of the surface needs its cluster.

    Parameters
    ----------
    curve : StaticCurve or StaticSurface
        Polynomial static curve (ascending coefficients), e.g. eq. (1); or, for a structure with
        several inputs, a polynomial static surface whose inputs are the data's, in their order.
    sigma_y : float or "free", optional
        Σ*_y, or ``"free"`` (estimated); default: the problem's (``StaticContext.sigma_y``).

    Raises
    ------
    ValueError
        The structure is not rational; the curve has a power of ū that no cluster carries;
        Σ*_y = 1 (the static function would not exist); Σ*_y > 1 (no model meeting (22) has a
        stable equilibrium); a free Σ_y estimated at 1 or above (the same, found after solving).
    """

    curve: StaticCurve | StaticSurface
    sigma_y: float | str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.curve, (StaticCurve, StaticSurface)):
            raise TypeError(f"CurveEquality needs a StaticCurve or a StaticSurface, got {type(self.curve).__name__}")
        if isinstance(self.sigma_y, str):
            check_choice(self.sigma_y, "CurveEquality: sigma_y", (FREE_SIGMA_Y,))
        elif self.sigma_y is not None:
            # 1 − Σ*_y is eq. (22)'s static denominator, and Σ*_y the sum of the linearised recursion's y
            # coefficients at every ū: at 1 no static function, above 1 no stable equilibrium (a structure
            # without Σy ignores it, so no use of a value >= 1 is lost)
            sy = check_real(self.sigma_y, "CurveEquality: sigma_y")
            if sy >= 1.0:
                raise ValueError(f"CurveEquality: sigma_y must be < 1 (1 − Σ*_y is eq. (22)'s static denominator; "
                                 f"at 1 or above no model meeting it has a stable equilibrium), got {sy:g}")
            object.__setattr__(self, "sigma_y", sy)

    def describe(self) -> str:
        if self.sigma_y is None:
            s = ""
        elif isinstance(self.sigma_y, str):
            s = ", Σ*y estimated"
        else:
            s = f", Σ*y = {self.sigma_y:.6g}"
        return f"static curve equality (22) to {self.curve.name}{s}"

    def resolved_sigma_y(self, ctx: StaticContext) -> float | None:
        """Σ*_y used: this constraint's, else the problem's (``ctx.sigma_y``).

        Parameters
        ----------
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        float or None
            Σ*_y (dimensionless); 0 when the structure has no Σy; None when Σ_y is estimated (``"free"``).

        Raises
        ------
        ValueError
            Neither the constraint nor the problem gives Σ*_y.
        """
        cm = ctx.cluster_map
        if not _has_sigma_y(cm):
            return 0.0  # no linear-in-y cluster: the denominator is 1 − Σ_{yu^m} ū^m → 1
        s = self.sigma_y if self.sigma_y is not None else ctx.sigma_y
        if s is None:
            raise ValueError(f"{self.describe()}: Σ*_y is unknown; give sigma_y or a reference model")
        return None if isinstance(s, str) else float(s)

    def affine(self, ctx: StaticContext) -> AffineRows:
        st = ctx.structure
        if not is_rational(st):
            raise ValueError(
                "eq. (22) needs a rational static function (no term with y to a power above 1); "
                f"this structure has {[str(t) for t in st if t.power_of('y') > 1]}. Use "
                "PassesThrough(points) or a StaticBand / PE objective instead"
            )
        cm = ctx.cluster_map
        sy = self.resolved_sigma_y(ctx)
        if sy is not None:
            if denominator_vanishes(np.array(1.0 - sy), np.array(1.0 + abs(sy))):
                raise ValueError(f"Σ*_y = {sy:.12g}: the denominator 1 − Σ*_y of eq. (22) vanishes, "
                                 "so no static function exists; use another reference model")
            if sy > 1.0 and _has_sigma_y(cm):
                # with Σ_yu^m = 0 the linearised recursion's coefficients sum to Σ*_y at every ū, and
                # a stable equilibrium needs that sum below 1: every model meeting (22) would be unstable
                raise ValueError(f"Σ*_y = {sy:.6g} > 1: every model satisfying eq. (22) would have no stable "
                                 "equilibrium (its y coefficients sum to Σ*_y); use a reference model with Σy < 1 "
                                 "(e.g. reference='els'), give sigma_y < 1, or estimate it (reference='free')")
        coefficient = self._coefficients(cm)
        # N ≡ D·H with D = 1 − Σ_y constant: Σ_{y u^e} = 0 (e ≠ 0), and Σ_{u^e} = (1 − Σ_y) c_e, which with
        # Σ_y free reads Σ_{u^e} + c_e Σ_y = c_e (affine in θ all the same)
        iy = sigma_y_index(cm)
        pivot = self._pivot(cm, ctx, coefficient) if sy is None and iy is not None else None
        pivot_row = None if pivot is None else [cluster_powers(key) for key in cm.keys].index((0, pivot))
        A, b = [], []
        for k, key in enumerate(cm.keys):
            p, e = cluster_powers(key)
            row = np.array(cm.R[k], dtype=float)
            if p == 1 and any(e):
                target = 0.0
            elif p == 1:
                if sy is None:
                    continue
                target = sy
            elif sy is None and pivot is not None and e != pivot:
                # c_p Σ_{u^e} = c_e Σ_{u^p}, p the pivot: the same conditions, without Σ_y. Every row of the form
                # above leans on Σ_y with c_e, which far from the input's zero dwarfs the rest (u = 1e6 ± 1: the
                # rows agreed to 1e-12 and one was lost to round-off, the curve missed by 7 % of its span)
                row = coefficient(pivot) * row - coefficient(e) * np.asarray(cm.R[pivot_row], dtype=float)
                target = 0.0
            elif sy is None:
                c_e = coefficient(e)
                if iy is not None:
                    row = row + c_e * cm.R[iy]
                target = c_e
            else:
                target = (1.0 - sy) * coefficient(e)
            A.append(row)
            b.append(target)
        return AffineRows.make(ctx.n_terms, A, b)

    def _pivot(self, cm: ClusterMap | SurfaceClusterMap, ctx: StaticContext,
               coefficient: Callable[[tuple[int, ...]], float]) -> tuple[int, ...] | None:
        """The numerator cluster whose term of H is largest over the static region (|c_e| · max|ū|^e, from the
        problem's points, else the curve's domain, else |c_e|): the row that keeps Σ_y, the others written
        against it. None when there is no choice to make (fewer than two numerator clusters, or H = 0)."""
        exps = [e for p, e in map(cluster_powers, cm.keys) if p == 0]
        if len(exps) < 2:
            return None
        m = n_static_inputs(cm)
        if ctx.points is not None:
            size = np.max(np.abs(np.asarray(ctx.points.ubar, float).reshape(len(ctx.points), -1)), axis=0)
        elif self.curve.domain is not None:
            dom = self.curve.domain if isinstance(self.curve, StaticSurface) else (self.curve.domain,)
            size = np.array([max(abs(lo), abs(hi)) for lo, hi in dom])
        else:
            size = np.ones(m)
        if size.size != m:  # the points speak of other inputs: their check says so elsewhere
            size = np.ones(m)
        with np.errstate(divide="ignore"):  # log of a zero coefficient: -inf, never the pivot
            weight = [float(np.log(abs(coefficient(e))) + np.dot(e, np.log(np.where(size > 0, size, 1.0))))
                      for e in exps]
        k = int(np.argmax(weight))
        return exps[k] if np.isfinite(weight[k]) else None

    def _coefficients(self, cm: ClusterMap | SurfaceClusterMap) -> Callable[[tuple[int, ...]], float]:
        """c_e of the curve or surface by its input powers e, once the structure is shown to carry every one."""
        m = n_static_inputs(cm)
        powers = [cluster_powers(k) for k in cm.keys]
        numer = {e for p, e in powers if p == 0}
        if isinstance(self.curve, StaticSurface):
            surf = self.curve
            if surf.n_inputs != m:
                raise ValueError(f"{surf.name} is a surface in {surf.n_inputs} input(s) but the structure has {m}: "
                                 "they must speak of the same inputs, in the same order")
            _check_surface_inputs(surf, cm)
            missing = [e for e, c in zip(surf.exponents, surf.coefficients) if c != 0.0 and e not in numer]
            if missing:
                raise ValueError(
                    f"{surf.name} has monomials with exponents {missing} (one power per input) that no cluster of "
                    "the structure carries (no process term with that input powers and no y): its static function "
                    "cannot equal the surface. Fit the surface on the structure's numerator monomials: pass the "
                    "static points themselves, cls(structure, data, points, how='curve'), or fit it with "
                    f"StaticSurface.fit(points, exponents={sorted(numer)!r})"
                )
            return lambda e: float(surf.coefficient(e))
        if m != 1:
            inputs = cm.input_names if isinstance(cm, SurfaceClusterMap) else ()
            transient = [n for n in inputs if transient_source(n, inputs) is not None]
            if transient:
                # the points hold them at 0, so no surface is fitted over them, and one in them would switch their
                # terms off (every cluster the surface lacks set to zero): the remedy numerator_surface names
                raise ValueError(
                    f"{self.curve.name} is a curve in one input but the structure has {m} inputs, among them the "
                    f"transient input(s) {transient} (zero at every steady state): eq. (22) would set their clusters "
                    "to zero, switching them off. Keep the static function within the points' band instead "
                    "(graybox.StaticBand), or use pe_pareto / se_pareto")
            raise ValueError(f"{self.curve.name} is a curve in one input but the structure has "
                             f"{m} inputs: give a StaticSurface (e.g. StaticSurface.fit(points))")
        c = self.curve.coefficients
        missing = [k for k, ck in enumerate(c) if ck != 0.0 and (k,) not in numer]
        if missing:
            raise ValueError(
                f"{self.curve.name} has ū^m terms with m = {missing} but the structure has no cluster "
                f"{[cluster_name(0, k) for k in missing]}: its static function cannot equal the curve"
            )
        return lambda e: float(c[e[0]]) if e[0] < c.size else 0.0

    def after_solve(self, theta: np.ndarray, ctx: StaticContext) -> None:
        cm = ctx.cluster_map
        if self.resolved_sigma_y(ctx) is not None:
            return
        sy = float((cm.R @ np.asarray(theta, float))[sigma_y_index(cm)])
        if sy > 1.0 or denominator_vanishes(np.array(1.0 - sy), np.array(1.0 + abs(sy))):
            # Σ_y = 1 with every Σ_{u^e} = 0 meets the rows as 0 = 0: no static function at all
            raise ValueError(f"{self.describe()}: the estimated Σ_y = {sy:.6g} leaves the model no stable "
                             "equilibrium (with Σ_{yu} = 0 its y coefficients sum to Σ_y, and a static function "
                             "needs 1 − Σ_y > 0); fix Σ*_y from a reference model (reference='ls' or 'els') or "
                             "give it as a number below 1. With other constraints beside it, they may admit no model "
                             "that meets the curve with 1 − Σ_y > 0 (a point to pass through off the curve meets it "
                             "only where the static function vanishes: Σ_y = 1)")


def _check_surface_inputs(surface: StaticSurface, cm: ClusterMap | SurfaceClusterMap) -> None:
    """A surface's monomials are read by position in the data's inputs: with several, its input names must
    be theirs, in their order (as for static points), or a permuted surface would be imposed silently. A
    surface of one input is of that input, whatever it calls it (as a curve)."""
    if isinstance(cm, SurfaceClusterMap) and surface.input_names != cm.input_names:
        raise ValueError(f"{surface.name} is a surface in the inputs {surface.input_names} but the data's inputs are "
                         f"{cm.input_names}: all data of one identification must have the same inputs, in the same order "
                         "(write the surface with input_names in the data's order)")


# --------------------------------------------------------------------------------------------
# the static function passes through given points
# --------------------------------------------------------------------------------------------
def _denominator_rows(cm: ClusterMap, ubar: np.ndarray, ybar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """D_i(θ) = 1 − ∂(q_iᵀRθ)/∂ȳ as ``(1, d_i R)``: D_i = 1 − (d R θ)_i. Shapes (M,), (M, n)."""
    d = static_rows(cm, ubar, ybar, wrt="y") @ cm.R
    return np.ones(len(ubar)), d


#: ``min_denominator="auto"`` keeps every denominator D_i >= min(ceiling, min_i D_i(θ_LS) / DENOMINATOR_FACTOR):
#: at most this factor below the least-squares estimate's own (D = Π (1 − λ_j) over the modes λ_j
#: of the linearised model, so D scales with the sampling period as the plant's does) ...
DENOMINATOR_FACTOR = 10.0
#: ... and never above the former fixed margins, so a plant whose least-squares D is over ten times
#: these keeps exactly the rows it had (StaticBand's exact form; GainBounds).
BAND_MIN_DENOMINATOR = 1e-3
GAIN_MIN_DENOMINATOR = 1e-6


def check_min_denominator(value: object, what: str, high: float | None) -> float | str:
    """``"auto"``, or a number in (0, high) (``high`` None: no upper end)."""
    if isinstance(value, str):
        return check_choice(value, what, ("auto",))
    if high is None:
        return check_real(value, what, low=0, low_open=True)
    return check_real(value, what, low=0, high=high, low_open=True, high_open=True)


def auto_min_denominator(value: float | str, ceiling: float, ctx: StaticContext, one: np.ndarray,
                         dR: np.ndarray) -> float:
    """The smallest denominator D_i = ``one`` − ``dR`` θ a constraint allows (dimensionless).

    A number is used as it is. ``"auto"``: ``ceiling``, lowered to the least-squares estimate's
    smallest positive D_i over the same rows divided by :data:`DENOMINATOR_FACTOR` when that is
    smaller: the margin follows the plant's time scale on these data (a slow plant sampled fast has
    a small D, and so has its least-squares estimate), not a number of samples. Without a
    least-squares reference (``ctx.ls_theta`` None, or no D_i(θ_LS) > 0) it is ``ceiling``.
    """
    if not isinstance(value, str):
        return float(value)
    if ctx.ls_theta is None:
        return ceiling
    d_ls = one - dR @ ctx.ls_theta
    d_ls = d_ls[np.isfinite(d_ls) & (d_ls > 0)]
    return min(ceiling, float(d_ls.min()) / DENOMINATOR_FACTOR) if d_ls.size else ceiling


def _vanishing_denominator(ctx: StaticContext, theta: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """Where the rational static function's denominator vanishes, shape (M,) (several inputs too)."""
    cm = ctx.cluster_map
    if n_static_inputs(cm) == 1 and not isinstance(cm, SurfaceClusterMap):
        return vanishing_denominator(ctx.structure, theta, ub)
    # D(ū) = 1 − Σ_c Σ_c p ū^e (p ∈ {0, 1}): the y-derivative rows at any ȳ
    terms = static_rows(cm, ub, np.ones(ub.shape[0]), wrt="y") * (cm.R @ np.asarray(theta, float))[None, :]
    return denominator_vanishes(1.0 - terms.sum(axis=1), 1.0 + np.abs(terms).sum(axis=1))


def _check_static_exists(ctx: StaticContext, theta: np.ndarray, ubar: np.ndarray, what: str, hint: str = "") -> None:
    """Refuse an estimate whose rational static function has a zero denominator at a static ū."""
    if not is_rational(ctx.structure):
        return
    ub = np.asarray(ubar, float)
    bad = _vanishing_denominator(ctx, theta, ub)
    if bad.any():
        raise ValueError(
            f"{what}: the estimated model's static function does not exist at ū = {(ub[bad] + 0.0).tolist()} "
            "(its denominator 1 − Σy − Σyu ū − … vanishes there, so the static equation holds as 0 = 0 "
            f"and the point is not matched){hint or '; move the point or constrain the y clusters'}"
        )


@dataclass(frozen=True, eq=False, repr=False)
class PassesThrough(StaticConstraint):
    """The static equation holds at given points: ``ȳ_i = q_iᵀ R θ`` for every i.

    For a rational structure this is ``ȳ_model(ū_i) = ȳ_i`` wherever the static function exists
    (checked after solving: the static function must exist at every point and meet it to
    1e-6 of the points' spread, or to round-off at points all at ȳ = 0, else ``ValueError``). For higher y powers it
    makes ȳ_i *an* equilibrium at ū_i (an isolated one, met to the same tolerance), not necessarily the stable one the
    model settles on.

    Parameters
    ----------
    points : StaticPoints, optional
        The points; default: the problem's static points.
    """

    points: StaticPoints | None = None

    def __post_init__(self) -> None:
        if self.points is not None and not isinstance(self.points, StaticPoints):
            raise TypeError(f"PassesThrough: points must be StaticPoints, got {type(self.points).__name__}")

    def describe(self) -> str:
        n = "the problem's" if self.points is None else f"{len(self.points)}"
        return f"static function passes through {n} static points"

    def affine(self, ctx: StaticContext) -> AffineRows:
        pts = ctx.require_points(self.points, self.describe())
        cm = ctx.cluster_map
        QR = static_rows(cm, pts.ubar, pts.ybar) @ cm.R
        return AffineRows.make(ctx.n_terms, QR, pts.ybar)

    def after_solve(self, theta: np.ndarray, ctx: StaticContext) -> None:
        pts = ctx.require_points(self.points, self.describe())
        k = len(ctx.cluster_map.keys)
        hint = ""
        if len(pts) >= k:
            # ȳ_i itself is the Σy column of Q, so Σy = 1 with every other cluster 0 "passes
            # through" any set of points as 0 = 0; with as many points as clusters that is
            # usually the only way through them
            hint = (f"; with {len(pts)} points and only {k} cluster coefficients the equalities are met by the "
                    "degenerate Σy = 1, other clusters 0 (no static function at all): use fewer points than "
                    "clusters, StaticCurve.fit + CurveEquality, a StaticBand or the PE problem")
        _check_static_exists(ctx, theta, pts.ubar, self.describe(), hint)
        if is_rational(ctx.structure):
            # the rows hold as D_i (ȳ_i − ȳ_model(ū_i)) = 0: met to the solver's round-off, a small D_i leaves the
            # static function itself far off the point (outputs at 1e4 ± 2.5 and as many points as clusters:
            # Σy = 1 − 2.5e-9, every point missed by 3e-3 and the near-integrator returned as passing through them)
            values, den, size = _rational_static_values(ctx, theta, pts.ubar)
            miss = np.abs(values - pts.ybar)
        else:
            sig, den = _equation_slopes(ctx, theta, pts)
            _check_isolated(ctx, sig, den, pts, self.describe(), hint)
            # the static equation's residual at each point over its derivative in ȳ (D_i, not vanishing): how far the
            # equilibrium near ȳ_i is from it (more points than clusters at an output of 1e4: the rank cut dropped
            # rows, and the equations were missed by 5e-4 with no word)
            miss, size = _equation_misses(ctx, sig, den, pts)
        yb = np.asarray(pts.ybar, float)
        spread = float(np.ptp(yb)) if yb.size > 1 and np.ptp(yb) > 0 else float(np.max(np.abs(yb)))
        # relative to the points' spread, with the round-off of the levels themselves (an output at 2e9 ± 50) and of
        # N(ū)/D(ū) summed from its terms (points all at ȳ = 0 have no spread nor level: N = 0 is met to round-off)
        tol = PASS_RTOL * spread + 1e3 * np.finfo(float).eps * (float(np.max(np.abs(yb))) + float(np.max(size)))
        if np.max(miss) > tol:
            i = int(np.argmax(miss))
            raise ValueError(
                f"{self.describe()}: the estimated model's static "
                f"{'function' if is_rational(ctx.structure) else 'equation (its equilibrium near ȳ)'} misses the point at ū = "
                f"{(np.asarray(pts.ubar)[i] + 0.0).tolist()} by {miss[i]:.3g} (output units; the points span "
                f"{spread:.3g}): the "
                "equalities were met as D(ū)·(ȳ − ȳ_model(ū)) = 0 only to round-off, or not at all, with "
                f"D = 1 − ∂(Σ_c Σ_c ȳ^p ū^m)/∂ȳ = {den[i]:.3g} there{hint or '; use fewer points or a StaticBand'}")


def _equation_slopes(ctx: StaticContext, theta: np.ndarray, pts: StaticPoints) -> tuple[np.ndarray, np.ndarray]:
    """The cluster values Σ = Rθ, and at each point the static equation's derivative in ȳ, D_i = 1 − ∂(q_iᵀRθ)/∂ȳ
    (the rational structures' denominator), shape (M,)."""
    theta = np.asarray(theta, float)
    one, dR = _denominator_rows(ctx.cluster_map, pts.ubar, pts.ybar)
    return ctx.cluster_map.R @ theta, one - dR @ theta


def _equation_misses(ctx: StaticContext, sig: np.ndarray, den: np.ndarray,
                     pts: StaticPoints) -> tuple[np.ndarray, np.ndarray]:
    """At each point, the static equation's residual |q_iᵀRθ − ȳ_i| over |D_i| (``sig``, ``den``:
    :func:`_equation_slopes`): about how far the equilibrium near ȳ_i is from it; and the size of the equation's
    terms over |D_i| (the scale of that miss's round-off). Shapes (M,)."""
    terms = static_rows(ctx.cluster_map, pts.ubar, pts.ybar) * sig[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        return (np.abs(terms.sum(axis=1) - np.asarray(pts.ybar, float)) / np.abs(den),
                np.abs(terms).sum(axis=1) / np.abs(den))


def _check_isolated(ctx: StaticContext, sig: np.ndarray, den: np.ndarray, pts: StaticPoints, what: str,
                    hint: str) -> None:
    """Refuse an estimate of a structure with y powers above 1 whose static equation holds at a point with a vanishing
    derivative in ȳ (``den``, D_i of :func:`_equation_slopes`): there ȳ_i is no isolated equilibrium, and at D ≡ 0
    (Σy = 1, every other cluster 0: y(k) = y(k−1)) every level is one."""
    size = 1.0 + np.abs(static_rows(ctx.cluster_map, pts.ubar, pts.ybar, wrt="y") * sig[None, :]).sum(axis=1)
    bad = denominator_vanishes(den, size)
    if bad.any():
        ub = np.asarray(pts.ubar, float)
        raise ValueError(
            f"{what}: the estimated model's static equation holds at ū = {(ub[bad] + 0.0).tolist()} with a vanishing "
            "derivative in ȳ (1 − ∂(Σ_c Σ_c ȳ^p ū^m)/∂ȳ = 0), so the point is no isolated equilibrium (at Σy = 1 with "
            f"every other cluster 0 every level is one){hint or '; move the point or constrain the y clusters'}")


#: Largest miss of a point by a :class:`PassesThrough` model's static function, relative to the points' spread.
PASS_RTOL = 1e-6


def _rational_static_values(ctx: StaticContext, theta: np.ndarray,
                            ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A rational structure's static function N(ū)/D(ū) at ``ubar`` (one or several inputs), its denominator D(ū) and
    the size of N's terms over |D| (Σ_j |N's term j| / |D|, the scale of N/D's round-off), shapes (M,)."""
    cm = ctx.cluster_map
    sig = cm.R @ np.asarray(theta, float)
    mono = static_rows(cm, ubar, np.ones(np.shape(ubar)[0]))  # ū^e of each cluster, its ȳ^p taken as 1
    p = np.array([cluster_powers(k)[0] for k in cm.keys])
    den = 1.0 - mono[:, p == 1] @ sig[p == 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        size = (np.abs(mono[:, p == 0]) @ np.abs(sig[p == 0])) / np.abs(den)
    return (mono[:, p == 0] @ sig[p == 0]) / den, den, size


# --------------------------------------------------------------------------------------------
# band |ȳ_model(ū_i) − ȳ_i| <= b
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class StaticBand(StaticConstraint):
    """The static function stays within ``b`` of each static point: the convex twin of D_SF.

    ``form="exact"`` (default) imposes ``−b D_i(θ) <= ȳ_i − q_iᵀRθ <= b D_i(θ)`` with
    ``D_i(θ) = 1 − ∂(q_iᵀRθ)/∂ȳ`` at the measured ȳ_i (both sides affine in θ). For a rational
    structure D_i is the denominator of eq. (6) at ū_i and ``ȳ_i − q_iᵀRθ = D_i (ȳ_i −
    ȳ_model(ū_i))``, so this is exactly ``|ȳ_model(ū_i) − ȳ_i| <= b`` with ``D_i >= 0`` (a
    necessary condition for a stable equilibrium: 1 − Σ a_i > 0). With y powers above 1 it is
    the first-order (Newton-step) version of the band at the measured ȳ_i.

    The exact form also keeps ``D_i >= min_denominator``: the two band rows alone imply only
    D_i >= 0, and as D_i → 0 they become vacuous (the residual bound b·D_i shrinks with the
    error it is meant to bound), which other constraints can drive a solver into. D_i is a number
    of the plant's time scale in samples (1 − a for y(k) = a y(k−1) + …: about Ts/τ), so the
    default margin follows the least-squares estimate's own D_i (``auto_min_denominator``):
    a plant sampled ten times faster gets a margin ten times smaller.

    ``form="residual"`` bounds the static-equation residual ``|ȳ_i − q_iᵀRθ| <= b`` instead;
    it is looser by the factor 1/D (≈ 14 for the paper's model (15), whose D ≈ 0.07).

    Parameters
    ----------
    b : float, optional
        Half-width of the band, output units (> 0). Default: each point's own uncertainty δ_i
        (:attr:`StaticPoints.uncertainty <graybox.StaticPoints>`, e.g. a transmitter's error);
        points without one need ``b`` given (``ValueError`` when the band is built into a problem).
    points : StaticPoints, optional
        Default: the problem's static points.
    form : {"exact", "residual"}
    min_denominator : float or "auto"
        Smallest D_i allowed by the exact form (a stability margin: 1 − Σ a_i >= it), in (0, 1).
        ``"auto"`` (default): 10⁻³, or a tenth of the smallest D_i of the problem's least-squares
        estimate at the points when that is smaller (``auto_min_denominator``).
    """

    b: float | None = None
    points: StaticPoints | None = None
    form: str = "exact"
    min_denominator: float | str = "auto"

    def __post_init__(self) -> None:
        if self.b is not None:
            object.__setattr__(self, "b", check_real(self.b, "StaticBand: b (the half-width)", low=0, low_open=True))
        if self.points is not None and not isinstance(self.points, StaticPoints):
            raise TypeError(f"StaticBand: points must be StaticPoints, got {type(self.points).__name__}")
        check_choice(self.form, "StaticBand: form", ("exact", "residual"))
        object.__setattr__(self, "min_denominator",
                           check_min_denominator(self.min_denominator, "StaticBand: min_denominator", 1.0))

    def half_widths(self, pts: StaticPoints) -> np.ndarray:
        """The band's half-width b at each point.

        Parameters
        ----------
        pts : StaticPoints
            M static points.

        Returns
        -------
        ndarray, shape (M,)
            Output units: ``b``, or the points' own uncertainty when ``b`` is None (``ValueError`` when they carry
            none).
        """
        if self.b is not None:
            return np.full(len(pts), self.b)
        if pts.uncertainty is None:
            raise ValueError(f"StaticBand needs its half-width: {pts.name} carry no uncertainty; pass b= (output "
                             "units, e.g. the static measurements' error) or give the points an uncertainty")
        return np.asarray(pts.uncertainty, float)

    def describe(self) -> str:
        n = "the problem's" if self.points is None else f"{len(self.points)}"
        w = "the points' uncertainty" if self.b is None else f"{self.b:g}"
        return f"static band ±{w} ({self.form}) at {n} static points"

    def affine(self, ctx: StaticContext) -> AffineRows:
        pts = ctx.require_points(self.points, self.describe())
        cm = ctx.cluster_map
        QR = static_rows(cm, pts.ubar, pts.ybar) @ cm.R
        if self.form == "exact":
            one, dR = _denominator_rows(cm, pts.ubar, pts.ybar)
        else:
            one, dR = np.ones(len(pts)), np.zeros_like(QR)
        b = self.half_widths(pts)
        # q θ − ȳ <= b (1 − dθ)   and   ȳ − q θ <= b (1 − dθ)
        A = [QR + b[:, None] * dR, -QR + b[:, None] * dR]
        rhs = [pts.ybar + b * one, b * one - pts.ybar]
        if self.form == "exact":
            A.append(dR)  # 1 − dθ >= min_denominator
            rhs.append(one - auto_min_denominator(self.min_denominator, BAND_MIN_DENOMINATOR, ctx, one, dR))
        return AffineRows.make(ctx.n_terms, A_ub=np.vstack(A), b_ub=np.concatenate(rhs))

    def after_solve(self, theta: np.ndarray, ctx: StaticContext) -> None:
        if self.form == "exact":
            pts = ctx.require_points(self.points, self.describe())
            _check_static_exists(ctx, theta, pts.ubar, self.describe())


# --------------------------------------------------------------------------------------------
# static-gain bounds over a ū range
# --------------------------------------------------------------------------------------------
#: Most levels per input of GainBounds' grid: far denser than any static test measures.
MAX_GAIN_LEVELS = 10**5


@dataclass(frozen=True, eq=False, repr=False)
class GainBounds(StaticConstraint):
    """Bounds on the static gain dȳ/dū over a ū range (e.g. ``lower=0``: a monotone curve).

    Implicit differentiation of the static equation ȳ = Σ_c Σ_c ȳ^p ū^m gives
    ``dȳ/dū = G(θ)/D(θ)`` with ``G = Σ_c Σ_c m ȳ^p ū^(m−1)`` and ``D = 1 − Σ_c Σ_c p ȳ^(p−1) ū^m``.
    Evaluated at a *reference* ȳ(ū) (a static curve, or the static points interpolated), both
    are affine in θ, and with ``D >= min_denominator > 0`` the bounds become the affine rows
    ``G − lower·D >= 0`` and ``G − upper·D <= 0``.

    Several inputs: the gain is the gradient, ``∂ȳ/∂ū_j = G_j/D`` with
    ``G_j = Σ_c Σ_c m_j ȳ^p Π_k ū_k^(m_k − δ_jk)``, and the bounds hold per input (``lower`` and
    ``upper`` may be one number for every input or one entry per input, None for no bound; one
    number leaves the transient inputs of :func:`~graybox.transient_inputs` free, whose z̄ is 0 at
    every steady state, so that a monotone static curve does not fix a transient effect's sign). The
    bounds are imposed on the grid of ``n`` levels per input over the box ``ubar_range`` (one
    (low, high) per input) with ȳ from a reference surface (a :class:`~graybox.StaticSurface` or
    any function of ū of shape (K, m)); without a reference surface they are imposed at the
    static points themselves, with their measured ȳ.

    Approximation: the gain is that of the model's static equation *along the reference curve*;
    it equals the model's own gain wherever the model's static curve passes through the
    reference (e.g. with :class:`CurveEquality` or :class:`PassesThrough`), and exactly
    everywhere for a rational structure none of whose clusters mixes y and u (then neither G nor D
    depends on ȳ). The error is ``(ȳ_model − ȳ_ref) Σ_{yu^m} m ū^(m−1) / D`` for rational
    structures; with y to a power above 1, D depends on ȳ too, so the model's gain may leave the
    bounds where its curve leaves the reference even when no cluster mixes y and u.

    Parameters
    ----------
    lower, upper : float, sequence of (float or None), or mapping input name -> float or None, optional
        Gain bounds, output units per input unit (at least one); per input for several inputs, in
        the data's input order, or by input name (``lower={"speed": 0.0}``: held whatever order the
        data list their inputs in; an input not named has no bound on that side).
    ubar_range : (float, float), one (low, high) per input, or mapping input name -> (low, high), optional
        ū interval (box), input units; default: the reference's domain, else the static points' range. By input
        name (``ubar_range={"speed": (800, 1500)}``), a range holds for that input whatever order the data list
        their inputs in, and an input not named keeps its default range.
    n : int
        Number of equally spaced ū in the interval (per input) where the bounds are imposed, 1 to 10⁵ (and
        at most 10⁶ points over every input that varies: ``ValueError`` when the problem's grid would exceed it).
    reference : StaticCurve, StaticSurface or callable ū ↦ ȳ, optional
        Default: the problem's static curve (or surface), else the problem's static points
        (interpolated linearly for one input, used as they are for several).
    min_denominator : float or "auto"
        D >= this (also a necessary condition for a stable equilibrium), > 0. ``"auto"``
        (default): 10⁻⁶, or a tenth of the smallest D of the problem's least-squares estimate on
        the grid when that is smaller (``auto_min_denominator``; as :class:`StaticBand`).
    """

    lower: float | Sequence[float | None] | Mapping[str, float | None] | None = None
    upper: float | Sequence[float | None] | Mapping[str, float | None] | None = None
    ubar_range: tuple | Mapping[str, tuple[float, float]] | None = None
    n: int = 25
    reference: StaticCurve | StaticSurface | Callable[[np.ndarray], np.ndarray] | None = None
    min_denominator: float | str = "auto"

    def __post_init__(self) -> None:
        for name in ("lower", "upper"):  # bounds by input name: read-only (the object is a value)
            v = getattr(self, name)
            if isinstance(v, Mapping):
                object.__setattr__(self, name, FrozenMap(_named_bounds(v, name)))
            elif v is not None and np.ndim(v) > 0:  # per input: a tuple of its checked bounds, not the caller's
                object.__setattr__(self, name, tuple(_per_input(v, name)))  # list (which changed the constraint)
            elif v is not None:
                object.__setattr__(self, name, check_real(v, f"{name} (a gain bound, or None)"))
        sides = [list(v.values()) if isinstance(v, Mapping) else _per_input(v, name)
                 for name, v in (("lower", self.lower), ("upper", self.upper))]
        if all(v is None for side in sides for v in side):
            raise ValueError("GainBounds needs a lower or an upper bound")
        if isinstance(self.lower, Mapping) or isinstance(self.upper, Mapping):
            self._check_named()
        else:
            lows, highs = sides
            if len(lows) > 1 and len(highs) > 1 and len(lows) != len(highs):
                raise ValueError(f"lower and upper give bounds for {len(lows)} and {len(highs)} inputs; give as many")
            k = max(len(lows), len(highs))
            for j in range(k):
                lo = lows[j if len(lows) > 1 else 0]
                hi = highs[j if len(highs) > 1 else 0]
                if lo is not None and hi is not None and lo > hi:
                    which = "" if k == 1 else f" of input {j + 1}"
                    raise ValueError(f"lower gain bound {lo} exceeds upper bound {hi}{which}")
        # each level a row of the QP per input: beyond this the grid alone ran out of memory (n=10**9: MemoryError)
        object.__setattr__(self, "n", check_int(self.n, "GainBounds: n", low=1, high=MAX_GAIN_LEVELS))
        ref = self.reference
        if ref is not None and not (isinstance(ref, (StaticCurve, StaticSurface)) or callable(ref)):
            raise TypeError(f"GainBounds: reference must be a StaticCurve, a StaticSurface or a callable ū ↦ ȳ, "
                            f"got {ref!r} ({type(ref).__name__})")
        if isinstance(self.ubar_range, Mapping):
            object.__setattr__(self, "ubar_range", FrozenMap(_named_ranges(self.ubar_range)))
        elif self.ubar_range is not None:
            rng = check_sequence(self.ubar_range, "GainBounds: ubar_range", "(low, high) or one (low, high) per input")
            if len(rng) == 2 and all(np.ndim(v) == 0 for v in rng):
                lo, hi = (check_real(v, f"GainBounds: ubar_range[{i}]") for i, v in enumerate(rng))
                if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                    raise ValueError(f"ubar_range must be (low, high) with low <= high, got {self.ubar_range}")
                object.__setattr__(self, "ubar_range", (lo, hi))
            else:
                box = []
                for j, pair in enumerate(rng):
                    # each end a number, as the one-input pair's and the named ranges' are (float() parsed "10" and
                    # read True as 1)
                    pair = check_sequence(pair, f"GainBounds: ubar_range of input {j + 1}", "(low, high)")
                    if len(pair) != 2:
                        raise ValueError(f"ubar_range must be (low, high) or one (low, high) per input, got {rng!r}")
                    lo, hi = (check_real(v, f"GainBounds: ubar_range of input {j + 1}") for v in pair)
                    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                        raise ValueError(f"ubar_range of input {j + 1} must be (low, high) with low <= high, got {pair}")
                    box.append((lo, hi))
                object.__setattr__(self, "ubar_range", tuple(box))
        object.__setattr__(self, "min_denominator",
                           check_min_denominator(self.min_denominator, "GainBounds: min_denominator", None))

    def describe(self) -> str:
        def one(v):
            return "none" if v is None else f"{v:g}"
        if isinstance(self.lower, Mapping) or isinstance(self.upper, Mapping):
            def side(v):
                if isinstance(v, Mapping):
                    return "{" + ", ".join(f"{k}: {one(x)}" for k, x in v.items()) + "}"
                return "none" if v is None else ("(" + ", ".join(map(one, _per_input(v, ""))) + ")")
            bounds = f"lower {side(self.lower)}, upper {side(self.upper)} by input"
            return f"static gain in {bounds}{self._where()}"
        lows, highs = _per_input(self.lower, "lower"), _per_input(self.upper, "upper")
        if len(lows) == 1 and len(highs) == 1:
            lo = "-inf" if lows[0] is None else f"{lows[0]:g}"
            hi = "inf" if highs[0] is None else f"{highs[0]:g}"
            bounds = f"[{lo}, {hi}]"
        else:
            bounds = f"lower ({', '.join(map(one, lows))}), upper ({', '.join(map(one, highs))}) per input"
        return f"static gain in {bounds}{self._where()}"

    def _where(self) -> str:
        rng = self.ubar_range
        if rng is None:
            return ""
        if isinstance(rng, Mapping):
            return " over " + " × ".join("{} in [{}, {}]".format(k, *level_texts(r)) for k, r in rng.items())
        if np.ndim(rng[0]) == 0:
            return " over ū in [{}, {}]".format(*level_texts(rng))  # ends told apart (10000.01, 10000.03)
        return " over ū in " + " × ".join("[{}, {}]".format(*level_texts(r)) for r in rng)

    def _check_named(self) -> None:
        """Bounds by input name (either side, the other a number, None or per input): lower <= upper for every input
        named on both sides (a number on one side is every input's)."""
        lows, highs = self.lower, self.upper
        for a, b, swap in ((lows, highs, False), (highs, lows, True)):
            if not isinstance(a, Mapping):
                continue
            for name, x in a.items():
                other = b.get(name) if isinstance(b, Mapping) else (b if b is None or np.ndim(b) == 0 else None)
                lo, hi = (other, x) if swap else (x, other)
                if lo is not None and hi is not None and lo > hi:
                    raise ValueError(f"lower gain bound {lo} exceeds upper bound {hi} of input {name!r}")

    def _bounds(self, m: int, inputs: tuple[str, ...] = ()) -> list[tuple[float | None, float | None]]:
        """(lower, upper) per input, checked against the structure's input count ``m``. One bound for every input
        leaves the transient inputs among ``inputs`` (the inputs' names) free: their z̄ is 0 at every steady state,
        so a gain along them is no static gain (a monotone curve must not fix the sign of a transient effect);
        a bound given per input holds where it is given. Bounds by input name hold where named (``inputs`` must then be the data's names); an input not named has
        none on that side. The names of ``ubar_range`` by input name are checked here too (a caller checking a
        constraint against its data before any fit, as ``select_graybox`` does, checks them all)."""
        named = [n for side in (self.lower, self.upper) if isinstance(side, Mapping) for n in side]
        if isinstance(self.ubar_range, Mapping):
            named += list(self.ubar_range)
        if named and len(inputs) != m:
            raise ValueError(f"{self.describe()}: bounds or ranges by input name need the data's input names")
        unknown = [n for n in dict.fromkeys(named) if n not in inputs]
        if unknown:
            raise ValueError(f"{self.describe()}: no input named {', '.join(map(repr, unknown))}; the inputs are "
                             f"{inputs}")
        transient = [len(inputs) == m and transient_source(inputs[j], inputs) is not None for j in range(m)]

        def side(v: object, name: str) -> list[float | None]:
            if isinstance(v, Mapping):
                return [v.get(n) for n in inputs]
            vals = _per_input(v, name)
            if len(vals) > 1:
                if len(vals) != m:
                    raise ValueError(f"{self.describe()}: {name} has {len(vals)} entries but the structure has {m} "
                                     "input(s)")
                return vals
            return [None if transient[j] else vals[0] for j in range(m)]

        return list(zip(side(self.lower, "lower"), side(self.upper, "upper")))

    def grid(self, ctx: StaticContext) -> tuple[np.ndarray, np.ndarray]:
        """The ū grid and the reference ȳ on it for the problem ``ctx``.

        Parameters
        ----------
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        ubar : ndarray, shape (K,), or (K, m) with several inputs
            The grid, input units.
        ybar : ndarray, shape (K,)
            The reference static output on it, output units.
        """
        m = n_static_inputs(ctx.cluster_map)
        if m > 1:
            return self._grid_several(ctx, m)
        ref = self.reference if self.reference is not None else ctx.curve
        rng = self.ubar_range
        if isinstance(rng, Mapping):  # by name: the one input's range, else its default (below)
            rng = self._named_box(_input_names(ctx), 1, None)[0]
        if rng is not None and np.ndim(rng[0]) != 0:
            if len(rng) != 1:
                raise ValueError(f"{self.describe()}: ubar_range has {len(rng)} ranges but the structure has one input")
            rng = rng[0]
        if rng is None:
            if isinstance(ref, StaticCurve) and ref.domain is not None:
                rng = ref.domain
            elif isinstance(ref, StaticSurface) and ref.domain is not None:  # a surface of the one input, as a curve
                rng = ref.domain[0]
            elif ctx.points is not None:
                rng = (float(ctx.points.ubar.min()), float(ctx.points.ubar.max()))
            else:
                raise ValueError(f"{self.describe()}: give ubar_range (no curve domain or static points to take it from)")
        ub = np.linspace(rng[0], rng[1], int(self.n))
        if ref is None:
            if ctx.points is None:
                raise ValueError(f"{self.describe()} needs a reference ȳ(ū): a static curve or static points")
            order = np.argsort(ctx.points.ubar)
            pu, py = ctx.points.ubar[order], ctx.points.ybar[order]
            if ub.min() < pu[0] - 1e-9 * abs(pu[0]) or ub.max() > pu[-1] + 1e-9 * abs(pu[-1]):
                ends = level_texts([ub.min(), ub.max(), pu[0], pu[-1]])  # told apart at any offset
                raise ValueError(f"{self.describe()}: the ū range [{ends[0]}, {ends[1]}] extends beyond the "
                                 f"static points [{ends[2]}, {ends[3]}] used as reference")
            yb = np.interp(ub, pu, py)
        else:
            try:
                yb = np.asarray(ref(ub), float)  # a StaticCurve refuses ū outside its domain
            except ValueError as exc:  # said with the constraint that asked, as every other problem of its grid
                raise ValueError(f"{self.describe()}: {exc}") from exc
            if yb.shape != ub.shape or not np.all(np.isfinite(yb)):
                raise ValueError(f"{self.describe()}: the reference must map ū of shape {ub.shape} to finite ȳ")
        return ub, yb

    def _grid_several(self, ctx: StaticContext, m: int) -> tuple[np.ndarray, np.ndarray]:
        ref = self.reference if self.reference is not None else ctx.curve
        if isinstance(ref, StaticCurve):
            raise ValueError(f"{self.describe()}: the reference {ref.name} is a curve in one input but the structure "
                             f"has {m}; give a StaticSurface or a function of ū of shape (K, {m})")
        if isinstance(ref, StaticSurface):
            _check_surface_inputs(ref, ctx.cluster_map)
        rng = self.ubar_range
        named = isinstance(rng, Mapping)
        if named:  # by name: each named input's range, the others' their default (below)
            rng = None
        elif rng is not None and (np.ndim(rng[0]) == 0 or len(rng) != m):
            raise ValueError(f"{self.describe()}: ubar_range must give one (low, high) per input ({m})")
        if ref is None:
            if ctx.points is None:
                raise ValueError(f"{self.describe()} needs a reference ȳ(ū): a static surface or static points")
            U = static_inputs(ctx.points.ubar, m, self.describe())
            yb = np.asarray(ctx.points.ybar, float)
            if named:
                rng = self._named_box(_input_names(ctx), m, [(-np.inf, np.inf)] * m)
            if rng is not None:
                inside = np.all([(U[:, j] >= lo) & (U[:, j] <= hi) for j, (lo, hi) in enumerate(rng)], axis=0)
                if not inside.any():
                    raise ValueError(f"{self.describe()}: no static point lies in ubar_range")
                U, yb = U[inside], yb[inside]
            return U, yb
        if rng is None:
            dom = getattr(ref, "domain", None)
            if dom is not None:
                rng = dom
            elif ctx.points is not None:
                U = static_inputs(ctx.points.ubar, m, self.describe())
                rng = tuple((float(U[:, j].min()), float(U[:, j].max())) for j in range(m))
            elif not named:
                raise ValueError(f"{self.describe()}: give ubar_range (no surface domain or static points to take it from)")
        if named:
            rng = self._named_box(_input_names(ctx), m, rng)
        U = box_grid(rng, int(self.n), f"{self.describe()}: n")
        try:
            yb = np.asarray(ref(U), float).reshape(-1)
        except ValueError as exc:  # a surface's refusal of ū outside its domain, said with the constraint
            raise ValueError(f"{self.describe()}: {exc}") from exc
        if yb.shape != (U.shape[0],) or not np.all(np.isfinite(yb)):
            raise ValueError(f"{self.describe()}: the reference must map ū of shape {U.shape} to finite ȳ of shape "
                             f"({U.shape[0]},)")
        return U, yb

    def _named_box(self, inputs: tuple[str, ...], m: int, default: Sequence[tuple[float, float]] | None
                   ) -> list[tuple[float, float]]:
        """The box of ``ubar_range`` by input name over ``inputs`` (the data's input names, ``m`` of them): a named
        input's range, the others' from ``default`` (one (low, high) per input; None when there is none to take)."""
        ranges = self.ubar_range
        if len(inputs) != m:
            raise ValueError(f"{self.describe()}: ranges by input name need the data's input names")
        unknown = [k for k in ranges if k not in inputs]
        if unknown:
            raise ValueError(f"{self.describe()}: no input named {', '.join(map(repr, unknown))}; the inputs are "
                             f"{inputs}")
        box = []
        for j, name in enumerate(inputs):
            if name in ranges:
                box.append(ranges[name])
            elif default is None:
                box.append(None)
            else:
                box.append(default[j])
        if any(r is None for r in box):
            missing = [n for n, r in zip(inputs, box) if r is None]
            raise ValueError(f"{self.describe()}: no range for {', '.join(map(repr, missing))} (no curve domain or "
                             "static points to take it from); name it in ubar_range")
        return box

    def affine(self, ctx: StaticContext) -> AffineRows:
        return self.rows_at(ctx, *self.grid(ctx))

    def rows_at(self, ctx: StaticContext, ub: np.ndarray, yb: np.ndarray) -> AffineRows:
        """The bounds' rows at the grid ``ub`` with the reference ``yb`` (:meth:`grid`'s), on the θ of ``ctx``: an
        estimator fitting on the centred signals gives the grid less the signals' offsets, where G and D are the same
        (derivatives of the static equation) without the offsets' powers.

        Parameters
        ----------
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).
        ub : ndarray, shape (K,), or (K, m) with several inputs
            The grid, input units.
        yb : ndarray, shape (K,)
            The reference static output on it, output units.

        Returns
        -------
        AffineRows
            Inequality rows, each of shape (n_terms,): the denominator bound and the gain bounds at each grid point.
        """
        cm = ctx.cluster_map
        m = n_static_inputs(cm)
        bounds = self._bounds(m, _input_names(ctx))
        one, dR = _denominator_rows(cm, ub, yb)
        rows, rhs = [], []
        # D = 1 − dR θ >= min_denominator   ⇔   dR θ <= 1 − δ
        rows.append(dR)
        rhs.append(one - auto_min_denominator(self.min_denominator, GAIN_MIN_DENOMINATOR, ctx, one, dR))
        for j, (lower, upper) in enumerate(bounds):
            if lower is None and upper is None:
                continue
            G = static_rows(cm, ub, yb, wrt="u", input=j if m > 1 else None) @ cm.R
            if not np.any(G) and ((lower is not None and lower > 0) or (upper is not None and upper < 0)):
                # the gain along this input is 0 for every θ: the solver's bare "infeasible" named no reason
                name = _input_names(ctx)[j] if len(_input_names(ctx)) == m else f"{j + 1}"
                why = ("the structure does not use input" if name not in (ctx.structure.input_names or ())
                       else "the structure's static function does not depend on input")
                raise InfeasibleError(f"{self.describe()}: {why} {name!r}, so its static gain along it is 0 for "
                                      f"every θ, outside [{'-inf' if lower is None else f'{lower:g}'}, "
                                      f"{'inf' if upper is None else f'{upper:g}'}]: bound only the inputs it uses "
                                      "(by input name, lower={'name': ...}) or add terms in that input")
            if lower is not None:  # G − l D >= 0  ⇔  −G − l dR θ <= −l
                rows.append(-G - lower * dR)
                rhs.append(-lower * one)
            if upper is not None:  # G − u D <= 0  ⇔  G + u dR θ <= u
                rows.append(G + upper * dR)
                rhs.append(upper * one)
        return AffineRows.make(ctx.n_terms, A_ub=np.vstack(rows), b_ub=np.concatenate(rhs))


def _input_names(ctx: StaticContext) -> tuple[str, ...]:
    """The names of a problem's static inputs, in its order (a surface's own, else the data's or structure's)."""
    cm = ctx.cluster_map
    return tuple(cm.input_names if isinstance(cm, SurfaceClusterMap) else (ctx.inputs or ctx.structure.input_names or ("u",)))


def _named_ranges(v: Mapping) -> dict[str, tuple[float, float]]:
    """ū ranges by input name: names are text, each range (low, high) finite with low <= high, at least one."""
    if not v:
        raise ValueError("GainBounds: ubar_range by input name: give at least one input's (low, high)")
    out: dict[str, tuple[float, float]] = {}
    for k, pair in v.items():
        if not isinstance(k, str):
            raise TypeError(f"GainBounds: ubar_range by input name takes input names, got {k!r} ({type(k).__name__})")
        pair = check_sequence(pair, f"GainBounds: ubar_range of input {k!r}", "(low, high)")
        if len(pair) != 2:
            raise ValueError(f"GainBounds: ubar_range of input {k!r} must be (low, high), got {pair!r}")
        lo, hi = (check_real(x, f"GainBounds: ubar_range of input {k!r}") for x in pair)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise ValueError(f"GainBounds: ubar_range of input {k!r} must be (low, high) with low <= high, got {pair!r}")
        out[k] = (lo, hi)
    return out


def _named_bounds(v: Mapping, name: str) -> dict[str, float | None]:
    """Gain bounds by input name: names are text, bounds numbers or None, at least one name."""
    if not v:
        raise ValueError(f"{name} gain bounds by input name: give at least one input's bound")
    out: dict[str, float | None] = {}
    for k, x in v.items():
        if not isinstance(k, str):
            raise TypeError(f"{name} gain bounds by input name take input names, got {k!r} ({type(k).__name__})")
        out[k] = None if x is None else check_real(x, f"{name} gain bound of input {k!r} (a number, or None)")
    return out


def _per_input(v: object, name: str) -> list[float | None]:
    """A gain bound as a list: [v] for one number (or None), one entry per input for a sequence."""
    if v is None or np.ndim(v) == 0:
        vals = [v]
    else:
        vals = list(v)
        if not vals:
            raise ValueError(f"{name} gain bounds: give a number or one entry per input, got an empty sequence")
    out: list[float | None] = []
    for x in vals:
        if x is None:
            out.append(None)
            continue
        out.append(check_real(x, f"{name} (a gain bound, or None)"))
    return out


# --------------------------------------------------------------------------------------------
# bounds on named cluster coefficients
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class ClusterBounds(StaticConstraint):
    """Bounds on named cluster coefficients, e.g. ``ClusterBounds({"Σy": (None, 1 - 1e-3)})``.

    Parameters
    ----------
    bounds : mapping name -> (lower, upper)
        Cluster name (``"Σy"``, ``"Σyu"``, ``"Σu²"``, or ASCII ``"Sy"``, ``"Su^2"``) or key
        (p, m), with several inputs (p, m_1, …, m_m) or (p, (m_1, …, m_m)), the powers in the data's input
        order; either bound may be
        None; equal bounds fix the cluster's value. With several inputs a name's factors may come in any order (``"Σspeedvalve"`` or ``"Σvalve·speed"``),
        so the bounds hold whatever order the data list their inputs in.
    """

    bounds: Mapping[str | tuple[int, int], tuple[float | None, float | None]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.bounds, Mapping):  # a number, a list, None: Python's own "not iterable" named nothing
            raise TypeError(f"ClusterBounds: bounds must be a mapping cluster name -> (lower, upper), e.g. "
                            f"{{'Σy': (None, 0.999)}}, got {short_value(self.bounds)} ({type(self.bounds).__name__})")
        if not self.bounds:
            raise ValueError("ClusterBounds needs at least one cluster")
        clean = {}
        for k, v in dict(self.bounds).items():
            try:
                lo, hi = v
            except (TypeError, ValueError):
                raise ValueError(f"bounds for cluster {k!r} must be (lower, upper), got {v!r}") from None
            lo, hi = (None if b is None else check_real(b, f"bound for cluster {k!r} (a finite number or None)")
                      for b in (lo, hi))
            if lo is None and hi is None:
                raise ValueError(f"cluster {k!r}: give a lower or an upper bound")
            if lo is not None and hi is not None and lo > hi:
                raise ValueError(f"cluster {k!r}: lower bound {lo} exceeds upper bound {hi}")
            key = _cluster_bound_key(k)
            if key in clean:  # (1, (1, 0)) and (1, 1, 0): one cluster, and a dict would keep the last one's bounds
                raise ValueError(f"cluster {k!r} is given twice (as {key!r} in another form): give its bounds once")
            clean[key] = (lo, hi)
        object.__setattr__(self, "bounds", FrozenMap(clean))  # read-only: the object is a value

    def describe(self) -> str:
        parts = []
        for k, (lo, hi) in self.bounds.items():
            name = (cluster_name(*k) if len(k) == 2 else f"cluster {k}") if isinstance(k, tuple) else k
            parts.append(f"{'' if lo is None else f'{lo:g} <= '}{name}{'' if hi is None else f' <= {hi:g}'}")
        return "cluster bounds " + ", ".join(parts)

    def affine(self, ctx: StaticContext) -> AffineRows:
        cm = ctx.cluster_map
        Ae, be, Au, bu = [], [], [], []
        for k, (lo, hi) in self.bounds.items():
            row = cm.R[cm.index(k)]
            if lo is not None and hi is not None and lo == hi:
                Ae.append(row)
                be.append(lo)
                continue
            if hi is not None:
                Au.append(row)
                bu.append(hi)
            if lo is not None:
                Au.append(-row)
                bu.append(-lo)
        n = ctx.n_terms
        return AffineRows.make(n, Ae or None, be or None, Au or None, bu or None)


def _non_finite_data(c: cp.Constraint) -> tuple[bool, bool]:
    """Whether the data of cvxpy constraint ``c`` (its constants and its parameters' values) hold a NaN, and an
    infinity."""
    import scipy.sparse

    nan = inf = False
    for leaf in [*c.constants(), *c.parameters()]:
        v = leaf.value
        if v is None:
            continue
        v = v.data if scipy.sparse.issparse(v) else v
        try:
            a = np.asarray(v, float)
        except (TypeError, ValueError):
            continue
        nan = nan or bool(np.isnan(a).any())
        inf = inf or bool(np.isinf(a).any())
    return nan, inf


def _no_bound(c: cp.Constraint) -> bool:
    """Whether an inequality ``c`` (``expr <= 0``) whose data hold an infinity is met by every θ, an infinite bound on
    the side that bounds nothing (θ1 <= inf, θ1 >= -inf; the solvers take it): ``expr`` is finite or −inf alike, and
    its gradient finite, at the variables 0 and ±1, where an infinite coefficient gives +inf or NaN in one of them
    (inf · (θ1 − 1e10) is −inf at all three, its gradient not). Points no larger: at ±1e9 a finite expression
    overflows (exp(θ), 1e300 θ) and inf − inf would read as an infinite coefficient. Anything else, or a constraint of
    another cone, is not; one that cannot be evaluated so (a parameter without a value) is left to the solve."""
    import cvxpy as cp
    import scipy.sparse

    if not isinstance(c, (cp.constraints.Inequality, cp.constraints.NonPos)):
        return False
    saved = [v.value for v in c.variables()]
    seen = []
    try:
        for z in (0.0, 1.0, -1.0):
            for v in c.variables():
                v.value = np.full(v.shape, z)
            with np.errstate(invalid="ignore", over="ignore"):  # inf·0 and inf − inf are what is looked for
                value = c.expr.value
                grads = c.expr.grad
            if value is None:  # a parameter without a value: the solve says so
                return True
            for g in grads.values():  # None where the expression has no gradient there: its value alone says
                g = g.data if scipy.sparse.issparse(g) else g
                if g is not None and not np.isfinite(np.asarray(g, float)).all():
                    return False
            seen.append(np.asarray(value, float))
    except ValueError:  # a variable of its own that takes no such value (nonneg=True): left to the solver, as before
        return True
    finally:
        for v, old in zip(c.variables(), saved):
            v.value = old
    finite = [np.isfinite(e) for e in seen]
    low = [np.isneginf(e) for e in seen]
    return bool(np.all(np.logical_and.reduce(finite) | np.logical_and.reduce(low)))


def _cluster_bound_key(k: object) -> str | tuple[int, ...]:
    """A cluster bound's key: a name as it is, a key in :func:`cluster_powers`' forms as the flat (p, m_1, …, m_m)
    the cluster maps index ((1, (1, 0)) is (1, 1, 0))."""
    if isinstance(k, str):
        return k
    if not isinstance(k, tuple) or len(k) < 2:
        raise TypeError(f"a cluster bound's key is a name (\"Σy\", \"Su^2\") or a key (p, m) / (p, m_1, …, m_m), "
                        f"got {k!r} ({type(k).__name__})")
    flat = [k[0], *(k[1] if len(k) == 2 and isinstance(k[1], tuple) else k[1:])]
    if not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in flat):
        raise TypeError(f"a cluster key holds integer powers (p, m) or (p, m_1, …, m_m), got {k!r}")
    p, powers = cluster_powers(k)
    if p < 0 or min(powers, default=0) < 0:
        raise ValueError(f"a cluster key's powers are >= 0, got {k!r}")
    return (p, *powers)


# --------------------------------------------------------------------------------------------
# anything a user writes in cvxpy
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class UserConstraint(StaticConstraint):
    """Any convex constraint(s) written in cvxpy on θ (engineering units).

    Parameters
    ----------
    fn : callable
        ``fn(theta)`` or ``fn(theta, ctx)`` returning a cvxpy constraint or a sequence of them;
        ``theta`` is a cvxpy expression of shape (n_terms,) in engineering units (internally an
        affine function of the scaled variable the solver sees).
    name : str
        Used in error messages.

    Notes
    -----
    Not usable with the closed forms (they handle equalities only, from affine rows).
    """

    fn: Callable[..., object]
    name: str = "user constraint"

    def __post_init__(self) -> None:
        check_str(self.name, "UserConstraint: name")
        if not callable(self.fn):
            raise TypeError(f"UserConstraint needs a callable θ ↦ constraint(s), got {type(self.fn).__name__}")

    def describe(self) -> str:
        return self.name

    def _call(self, theta: cp.Expression, ctx: StaticContext) -> list[cp.Constraint]:
        import cvxpy as cp

        try:
            n_args = len(inspect.signature(self.fn).parameters)
        except (TypeError, ValueError):
            n_args = 1
        res = self.fn(theta, ctx) if n_args >= 2 else self.fn(theta)
        if res is None:
            out = []
        elif isinstance(res, (cp.constraints.constraint.Constraint, str)) or not hasattr(res, "__iter__"):
            out = [res]  # one constraint, or a value that is none (a number, a text): refused below by name
        else:
            out = list(res)
        for c in out:
            if not isinstance(c, cp.constraints.constraint.Constraint):
                raise ValueError(f"{self.name}: the function must return cvxpy constraints, got {type(c).__name__}")
            if not c.is_dcp():
                raise ValueError(f"{self.name}: constraint {c} is not convex (DCP)")
            nan, inf = _non_finite_data(c)
            # a NaN reached the solve as cvxpy's "Problem data contains NaN", naming no constraint; an equality at an
            # infinite value came back from Clarabel as 'optimal', and cls returned θ with clusters near 1e19; an
            # inequality with an infinite coefficient (inf @ θ <= 1) or bound (θ1 >= inf) as "Problem data contains
            # NaN or Inf" or "solver clarabel failed"
            if nan or (inf and (isinstance(c, (cp.constraints.Equality, cp.constraints.Zero))
                                or not _no_bound(c))):
                what = ("a NaN" if nan else "an infinite value in an equality, which no finite θ meets"
                        if isinstance(c, (cp.constraints.Equality, cp.constraints.Zero)) else
                        "an infinite value that is no mere absent bound (θ <= inf): an infinite coefficient of θ, or "
                        "a bound no finite θ meets (θ >= inf)")
                raise ValueError(f"{self.name}: constraint {c} holds {what} (in its constants or its parameters' "
                                 "values); give finite numbers")
        return out

    def constraints(self, theta: cp.Expression, ctx: StaticContext) -> list[cp.Constraint]:
        return self._call(theta, ctx)

    def violation(self, theta: np.ndarray, ctx: StaticContext) -> float:
        """Largest cvxpy-reported violation at ``theta`` on the problem ``ctx``.

        Parameters
        ----------
        theta : ndarray, shape (n_terms,)
            Process parameters, engineering units.
        ctx : StaticContext
            The problem's data as the estimator gives them (its structure, static points, curve, Σ*_y and the data's
            input names).

        Returns
        -------
        float
            >= 0, in the constraint's own units (0 when satisfied).
        """
        import cvxpy as cp

        v = cp.Variable(ctx.n_terms)
        v.value = np.asarray(theta, float)
        return max((float(np.max(c.violation())) for c in self._call(v, ctx)), default=0.0)

    def check(self, ctx: StaticContext) -> None:
        import cvxpy as cp

        self._call(cp.Variable(ctx.n_terms), ctx)

