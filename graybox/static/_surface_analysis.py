"""Static analysis of models with several inputs: the static surface ȳ(ū_1, …, ū_m).

At a constant input vector ū a term with output power p and input powers a_1 … a_m becomes
ȳ^p ū_1^a_1 ⋯ ū_m^a_m, so the steady states solve (eq. (5) in several variables)

    F(ȳ, ū) = Σ_{p, a} Σ_{y^p u1^a1 ⋯ um^am} ȳ^p ū_1^a_1 ⋯ ū_m^a_m − ȳ = 0,

whose coefficients are the cluster coefficients Σ = R θ of the clusters Ω_{y^p u1^a1 ⋯ um^am}
(:func:`surface_cluster_map`).

One definition, shared with the single-input case: at a fixed ū the input part of every term is
a number, so the model is, for its statics, a single-input model at ū' = 1 whose parameters are
θ_t · ū_1^a_t1 ⋯ ū_m^a_tm (the inputs folded into θ, as :func:`graybox.static._analysis.reached_equilibria`
already does for one input). Every static question at a point of the surface — the real roots,
their stability (the Schur–Cohn test), the equilibrium a free run from y0 settles on — is
answered by the single-input code on that folded model: one implementation, one definition of
"the equilibrium reached", whatever the number of inputs.

The static gain is the gradient ∂ȳ/∂ū_i = −F_{ū_i} / F_ȳ (implicit differentiation, the partials read from
:mod:`graybox.static._linearisation`), one
entry per input.
"""

from __future__ import annotations

import itertools

from dataclasses import dataclass
from typing import Mapping
from functools import lru_cache

import numpy as np

from . import _analysis as _static
from ._analysis import Equilibrium, Reached, ascii_cluster_name, key_index
from ._linearisation import input_monomials_of, static_gains, times_monomials, static_powers, static_theta_gradient_of
from ..core._records import frame_inputs, labelled_point
from ..core._terms import Structure, Term, carried_input_names, check_input_names, require_inputs, structure_of
from ..core._transient import steady_levels
from ..core._validation import Relocked, check_bool, check_fields, check_per_point, frozen, real_array
from ..core._renamed import RenamedAttribute
from ..core._reprs import exact_text, point_texts, short_repr

__all__ = [
    "SurfaceClusterMap",
    "surface_cluster_map",
    "surface_cluster_name",
    "surface_inputs",
    "input_monomials",
    "surface_equilibria",
    "reached_surface",
    "static_surface",
    "static_surface_gain",
    "surface_theta_gradient",
    "surface_static_rows",
]

_SUP = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


def surface_inputs(structure: Structure, inputs: tuple[str, ...] | None = None) -> tuple[str, ...]:
    """The input order of ū's columns: ``inputs`` (validated against the structure) or the structure's own."""
    if inputs is None:
        return structure.input_names or ("u",)
    names = check_input_names(inputs, what="input_names")
    require_inputs(structure.input_names, names, "which is not among the inputs")
    return names


def _model_inputs(structure: object, input_names: object) -> tuple[Structure, object]:
    """(the structure, the input order) of a public surface function's arguments: ``input_names``, else a model's own
    (a Model given as the structure reads ū in its ``input_names`` order, as its methods do: in the structure's order
    it read another input's levels for each, silently), else None (the structure's order)."""
    carried = carried_input_names(structure)
    return structure_of(structure), (carried if input_names is None else input_names)


def surface_powers(term: Term, inputs: tuple[str, ...]) -> tuple[int, ...]:
    return tuple(term.power_of(n) for n in inputs)


def surface_cluster_key(term: Term, inputs: tuple[str, ...]) -> tuple[int, ...]:
    """(power of y, power of each of ``inputs``) of a process term: its cluster Σ_{y^p u1^a1 ⋯ um^am}
    (with one input, :func:`graybox.static._analysis.cluster_key`)."""
    if term.is_noise:
        raise ValueError(f"noise term {term} has no cluster")
    return (term.power_of("y"),) + surface_powers(term, inputs)


def _cluster_factors(p: int, powers: tuple[int, ...], inputs: tuple[str, ...]) -> list[str]:
    """The factors of a cluster's name, ``["y", "u1²", "u2"]`` (none for Σ0)."""
    parts = ["y" + (str(p).translate(_SUP) if p > 1 else "")] if p else []
    return parts + [n + (str(a).translate(_SUP) if a > 1 else "") for n, a in zip(inputs, powers) if a]


def surface_cluster_name(p: int, powers: tuple[int, ...], inputs: tuple[str, ...], sep: str = "") -> str:
    """Cluster name, e.g. ``Σ0``, ``Σyu1``, ``Σu1²u2``, ``Σy²u2``; the factors joined by ``sep`` (``"·"``
    where the plain names of a structure's clusters would collide: inputs "pos" and "ypos")."""
    parts = _cluster_factors(p, powers, inputs)
    return "Σ" + sep.join(parts) if parts else "Σ0"


def _spellings(p: int, powers: tuple[int, ...], inputs: tuple[str, ...]) -> set[str]:
    """Every name that writes the cluster's factors in some order, one after the other or joined by ``·``: the
    same cluster whatever order the data list their inputs in (``Σspeedvalve`` is ``Σvalvespeed``)."""
    parts = _cluster_factors(p, powers, inputs)
    if not parts:
        return {"Σ0"}
    return {"Σ" + sep.join(perm) for perm in itertools.permutations(parts) for sep in ("", "·")}


@dataclass(frozen=True, eq=False)
class SurfaceClusterMap(Relocked):
    """The clusters Ω_{y^p u1^a1 ⋯ um^am} of a structure with several inputs and the 0/1 map R (Σ = R θ).

    Attributes
    ----------
    input_names : tuple of str
        The inputs, in the order of the powers in each key.
    keys : tuple of (p, a_1, …, a_m)
        Output power and input powers of each cluster, sorted.
    R : ndarray, shape (n_clusters, n_terms)
    """

    input_names: tuple[str, ...]
    keys: tuple[tuple[int, ...], ...]
    R: np.ndarray
    inputs = RenamedAttribute("input_names")

    def __post_init__(self) -> None:
        check_fields(self)
        # a map made by hand is as immutable as surface_cluster_map's: R read-only, one row per cluster
        R = frozen(self.R)
        if R.ndim != 2 or R.shape[0] != len(self.keys):
            raise ValueError(f"SurfaceClusterMap: R must have one row per cluster key ({len(self.keys)}), got shape "
                             f"{R.shape}")
        object.__setattr__(self, "R", R)

    @property
    def names(self) -> list[str]:
        """Cluster names in the order of ``keys``: the factors written one after the other (``Σyu1``), or
        joined by ``·`` when that would give two clusters one name (inputs "pos" and "ypos": ``Σy·pos``
        and ``Σypos``)."""
        plain = [surface_cluster_name(k[0], k[1:], self.input_names) for k in self.keys]
        if len(set(plain)) == len(plain):
            return plain
        return [surface_cluster_name(k[0], k[1:], self.input_names, "·") for k in self.keys]

    def index(self, name_or_key: str | tuple[int, ...]) -> int:
        """Row of R for one cluster.

        Parameters
        ----------
        name_or_key : str or tuple of int
            A cluster's name (``"Σyu1"``, its factors in any order, or ASCII ``"Syu1"``) or its key
            (p, a_1, …, a_m), the powers in ``input_names`` order.

        Returns
        -------
        int
            The cluster's row of R (and entry of ``keys`` and ``names``).

        Raises
        ------
        ValueError
            No cluster of that name or key, or a name that fits several.
        """
        if isinstance(name_or_key, tuple):
            # m_<input> in the order the powers are read (the data's input order), named: a key written in another
            # order was told "(p, a_b, a_a)", which read as inputs named a_b and a_a
            return key_index(self.keys, self.names, name_or_key,
                             "(p, " + ", ".join(f"m_{n}" for n in self.input_names) + "), the inputs in the order "
                             + ", ".join(map(repr, self.input_names)) + "; or give the cluster by name")
        names = self.names
        # every printed name is accepted as it is; ASCII ("Syu1", "Su1^2u2") is read as the paper's form
        name = name_or_key if name_or_key in names else ascii_cluster_name(name_or_key, single_input=False)
        if name in names:
            return names.index(name)
        # its factors in another order (the inputs listed in another order print them so), or joined by ·
        found = [i for i, k in enumerate(self.keys) if name in _spellings(k[0], k[1:], self.input_names)]
        if len(found) > 1:
            raise ValueError(f"cluster name {name!r} fits the clusters {[names[i] for i in found]}: name one of them "
                             "with its factors joined by · (e.g. Σy·u1)")
        if not found:
            raise ValueError(f"no cluster {name!r} in this structure; it has {names}")
        return found[0]

    @property
    def max_y_power(self) -> int:
        """Largest output power over the clusters."""
        return max((k[0] for k in self.keys), default=0)

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


@lru_cache(maxsize=256)
def _surface_cluster_map(structure: Structure, inputs: tuple[str, ...]) -> SurfaceClusterMap:
    keys = [surface_cluster_key(t, inputs) for t in structure]
    return SurfaceClusterMap(inputs, *_static.cluster_membership(keys))


def surface_cluster_map(structure: Structure, *, input_names: tuple[str, ...] | None = None) -> SurfaceClusterMap:
    """The clusters per output power and input powers of ``structure`` (cached).

    Parameters
    ----------
    structure : Structure
        Process terms (a Model, or a result that carries one, gives its structure).
    input_names : tuple of str, optional
        The inputs in the order of the key powers (default: a model's own ``input_names``, as its
        ``cluster_map()`` and the surface functions read them, else the structure's inputs).

    Returns
    -------
    SurfaceClusterMap
    """
    structure, names = _model_inputs(structure, input_names)
    return _surface_cluster_map(structure, surface_inputs(structure, names))


@lru_cache(maxsize=256)
def _skeleton(structure: Structure) -> Structure:
    """The single-input structure of the folded model.

    Term t keeps its output factors; its input factors become one factor ``u(k-j)`` with j
    numbering the terms that share the same output part, so the terms stay distinct. At ū' = 1
    the input factor is 1 whatever j is: only the output lags matter for the statics.
    """
    seen: dict[tuple, int] = {}
    terms = []
    for t in structure:
        ypart = tuple(f for f in t.factors if f[0] == "y")
        j = seen.get(ypart, 0) + 1
        seen[ypart] = j
        terms.append(Term(ypart + (("u", j, 1),)))
    return Structure(terms)


def input_monomials(structure: Structure, ubar: np.ndarray, inputs: tuple[str, ...] | None = None) -> np.ndarray:
    """g_t(ū) = ū_1^a_t1 ⋯ ū_m^a_tm for every term t at every point, shape (M, n_terms)."""
    names = surface_inputs(structure, inputs)
    ub = points_of_inputs(ubar, names)
    return input_monomials_of(static_powers(structure, names)[1], ub)


def points_of_inputs(ubar: object, names: tuple[str, ...], *, one_point: bool = False) -> np.ndarray:
    """ū as finite points, shape (M, m), columns in the order of the inputs ``names``; a 1-D ū of length m is
    one point; a DataFrame is read by column name as every input is (:func:`~graybox.core._records.frame_inputs`);
    transient inputs left out are 0, their level at every steady state (:func:`~graybox.core._transient.steady_levels`)."""
    m = len(names)
    ub = real_array(frame_inputs(ubar, names, "ubar", steady=True), "ubar", "points of input levels (numbers)")
    one_point = one_point or labelled_point(ubar, names)  # a Series labelled by the inputs: one ū
    ub = steady_levels(ub, names, one_point=one_point)  # a transient input's z̄ = 0 where ū gives the others only
    if ub.ndim == 1 and ub.size == m:
        ub = ub[None, :]
    if ub.ndim != 2 or ub.shape[1] != m:
        raise ValueError(f"ubar must have shape (M, {m}) (one column per input), got shape {ub.shape}")
    if not np.all(np.isfinite(ub)):
        raise ValueError("ubar has non-finite values")
    return ub


def _folded(structure: Structure, thetas: np.ndarray, ub: np.ndarray, inputs: tuple[str, ...]):
    """The skeleton structure and θ'[p, j, t] = θ_pt g_t(ū_j), shape (P, M, n_terms)."""
    sk = _skeleton(structure)
    names = surface_inputs(structure, inputs)
    # θ_t ū^a in range where ū^a alone is not (1e-300 · 1e200²); beyond it, inf: a point with no float equilibrium
    return sk, times_monomials(np.atleast_2d(np.asarray(thetas, float))[:, None, :], static_powers(structure, names)[1],
                               points_of_inputs(ub, names))


def surface_equilibria(structure: Structure, theta: np.ndarray, ubar: np.ndarray, *,
                       input_names: tuple[str, ...] | None = None) -> list[Equilibrium]:
    """Every real equilibrium at the constant input vector ``ubar``, sorted by ȳ, with its local stability.

    Parameters
    ----------
    structure : Structure
    theta : ndarray, shape (n_terms,)
    ubar : array_like, shape (m,)
        One point of input space (engineering units), columns in ``input_names`` order.
    input_names : tuple of str, optional
        Input order (default: a model's own ``input_names``, else the structure's inputs).

    Returns
    -------
    list of Equilibrium
        ``ubar`` of each is the tuple (ū_1, …, ū_m).
    """
    names = surface_inputs(*_model_inputs(structure, input_names))
    structure, theta = _static.checked_model(structure, theta)
    ub = points_of_inputs(ubar, names, one_point=True)
    if ub.shape[0] != 1:
        # a dict's shape is (): the points it holds are said (ū of two points by name read "got shape ()")
        raise ValueError(f"ubar must be one point of shape ({len(names)},), got {ub.shape[0]} points"
                         + ("" if isinstance(ubar, Mapping) else f" (shape {np.shape(ubar)})")
                         + ": call equilibria once per point")
    sk, th = _folded(structure, theta, ub, names)
    point = tuple(float(v) for v in ub[0])
    _static.refuse_continuum(sk, th[0, 0], 1.0, "(" + ", ".join(map(exact_text, point)) + ")")
    return [Equilibrium(point, e.ybar, e.stable, e.spectral_radius)
            for e in _static.folded_equilibria(sk, th[0, 0], 1.0)]


def reached_surface(structure: Structure, thetas: np.ndarray, ubar: np.ndarray, y0: np.ndarray, *,
                    inputs: tuple[str, ...] | None = None, until_failure: bool = False) -> Reached:
    """The equilibrium each member reaches at each point ū_j from the constant initial output y0_j.

    The definition of :func:`graybox.static._analysis.reached_equilibria`, at points of input space.

    Parameters
    ----------
    structure : Structure
    thetas : ndarray, shape (P, n_terms)
    ubar : ndarray, shape (M, m)
        Points of input space (input units), columns in ``input_names`` order.
    y0 : float or ndarray, shape (M,)
        Initial output of each point's run (output units).
    inputs : tuple of str, optional
    until_failure : bool
        As in :func:`~graybox.static._analysis.reached_equilibria`: a member's runs stop once one of its
        points is not reached (J_SF's question); a member that reaches every point gets the same result.

    Returns
    -------
    Reached
        ``ubar`` (M, m), ``ybar`` and ``status`` (P, M).
    """
    names = surface_inputs(structure, inputs)
    ub = points_of_inputs(ubar, names)
    M = ub.shape[0]
    y0s = np.broadcast_to(np.asarray(y0, float), (M,)).copy()
    sk, th = _folded(structure, thetas, ub, names)
    P, T = th.shape[0], th.shape[2]
    # every (member, point) pair is one member of the folded model at ū' = 1, in one call
    y0p = np.broadcast_to(y0s[None, :], (P, M)).reshape(P * M, 1)
    r = _static.reached_equilibria(sk, th.reshape(P * M, T), np.ones(1), y0p, until_failure=until_failure,
                                   members=np.repeat(np.arange(P), M))
    return Reached(ub, y0s, r.ybar.reshape(P, M), r.status.reshape(P, M),
                   None if r.start_on is None else r.start_on.reshape(P, M))


def static_surface(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    *,
    strict: bool = True,
    input_names: tuple[str, ...] | None = None,
) -> np.ndarray:
    """The steady state the model reaches at each constant input vector: the static surface ȳ(ū).

    As :func:`graybox.static_curve` at points of input space: with ``y0``, the equilibrium
    a free run at constant ū started from y0 settles on; without it, the unique stable
    equilibrium (rational structures: the equilibrium of eq. (6) when it is stable).

    Parameters
    ----------
    structure : Structure
    theta : ndarray, shape (n_terms,)
    ubar : array_like, shape (M, m)
        Points of input space (input units), columns in ``input_names`` order.
    y0 : float or array_like of shape (M,), optional
        Initial output (output units).
    strict : bool
        Raise ``ValueError`` naming each ū where no equilibrium is reached (the first 20, and how many more; else
        NaN there).
    input_names : tuple of str, optional
        Input order (default: a model's own ``input_names``, else the structure's inputs).

    Returns
    -------
    ndarray, shape (M,)
        Output units.
    """
    strict = check_bool(strict, "strict")
    names = surface_inputs(*_model_inputs(structure, input_names))
    structure, th = _static.checked_model(structure, theta)
    ub = points_of_inputs(ubar, names)
    if y0 is not None:
        y0 = check_per_point(y0, ub.shape[0], "y0")
    sk, thf = _folded(structure, th, ub, names)
    if y0 is not None or _static.is_rational(sk):
        res = reached_surface(structure, th[None, :], ub, 0.0 if y0 is None else y0, inputs=names)
        if strict and not res.ok.all():
            raise ValueError("the model reaches no equilibrium at " + _static.point_phrases(res.explain(0)))
        return res.ybar[0].copy()
    # every point is a member of the folded model at ū' = 1: its roots and their stability in one call
    roots, stab = _static.roots_and_stability(sk, thf[0], np.ones(1))  # (M, 1, D) each
    stab = stab[:, 0]
    out, problems = _static.only_stable(roots[:, 0, :], stab,
                                        [f"ū = {p}" for p in point_texts(ub)],  # told apart (10000.01, .02)
                                        _static.continuum(sk, thf[0], np.ones(1))[:, 0])
    if strict and problems:
        raise ValueError("the static surface is undefined: the model has " + _static.point_phrases(problems))
    return out


def static_surface_gain(
    structure: Structure,
    theta: np.ndarray,
    ubar: np.ndarray,
    y0: float | np.ndarray | None = None,
    *,
    strict: bool = True,
    input_names: tuple[str, ...] | None = None,
) -> np.ndarray:
    """The static gain as a gradient: ∂ȳ/∂ū_i along the static surface, by implicit differentiation.

    Parameters
    ----------
    structure, theta, ubar, y0, strict, input_names
        As for :func:`static_surface`.

    Returns
    -------
    ndarray, shape (M, m)
        Entry (j, i) in output units per unit of input i.
    """
    names = surface_inputs(*_model_inputs(structure, input_names))
    structure, th = _static.checked_model(structure, theta)
    ub = points_of_inputs(ubar, names)
    yb = static_surface(structure, th, ub, y0, strict=strict, input_names=names)
    p, A = static_powers(structure, names)
    gain = static_gains(p, A, th[None, :], ub, yb[None, :])[0]
    return np.where(np.isfinite(yb)[:, None], gain, np.nan)  # NaN⁰ is 1: no gain where no equilibrium is reached


def surface_theta_gradient(structure: Structure, theta: np.ndarray, ubar: np.ndarray, ybar: np.ndarray, *,
                           inputs: tuple[str, ...] | None = None) -> np.ndarray:
    """∂ȳ_j/∂θ_t at equilibria (ū_j, ȳ_j) of the surface: −ȳ^p_t g_t(ū_j) / F_ȳ, shape (M, n_terms).

    ``ubar`` (M, m) in ``inputs`` order (default: the structure's inputs), ``ybar`` (M,).
    """
    names = surface_inputs(structure, inputs)
    p, A = static_powers(structure, names)
    return static_theta_gradient_of(p, A, theta, points_of_inputs(ubar, names), ybar)


def surface_static_rows(cm: SurfaceClusterMap, ubar: np.ndarray, ybar: np.ndarray, wrt: str | None = None) -> np.ndarray:
    """Rows of Q in eq. (12) at points of input space (or their derivatives), per cluster of ``cm``.

    Parameters
    ----------
    cm : SurfaceClusterMap
        Cluster keys (p, a_1, …, a_m) and their inputs.
    ubar : ndarray, shape (M, m)
        Points of input space, columns in ``cm.input_names`` order.
    ybar : ndarray, shape (M,)
        Output levels (the measured or reference ȳ).
    wrt : None, "y" or an input name
        None: ``Q[j, c] = ȳ_j^p Π_i ū_ji^a_i`` (the static prediction is ``Q R θ``); ``"y"``:
        ``∂/∂ȳ``; an input name ``u_i``: ``∂/∂ū_i``.

    Returns
    -------
    ndarray, shape (M, n_clusters)
    """
    ub = points_of_inputs(ubar, cm.input_names)
    yb = np.asarray(ybar, float)[:, None]
    K = np.array(cm.keys, float).reshape(len(cm.keys), 1 + len(cm.input_names))
    p, A = K[None, :, 0], K[:, 1:]
    with np.errstate(all="ignore"):
        g = np.prod(ub[:, None, :] ** A[None, :, :], axis=2)  # (M, C); 0**0 == 1: a missing factor
        if wrt is None:
            return yb**p * g
        if wrt == "y":
            return np.where(p > 0, p * yb ** np.maximum(p - 1, 0) * g, 0.0)
        if wrt not in cm.input_names:
            raise ValueError(f"wrt must be None, 'y' or one of the inputs {cm.input_names}, got {wrt!r}")
        i = cm.input_names.index(wrt)
        Ad = A.copy()
        Ad[:, i] = np.maximum(Ad[:, i] - 1, 0)
        gd = np.prod(ub[:, None, :] ** Ad[None, :, :], axis=2)
        return np.where(A[None, :, i] > 0, A[None, :, i] * yb**p * gd, 0.0)
