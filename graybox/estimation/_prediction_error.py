"""Gray-box convex estimation: CLS (eq. (22)) and the PE bi-objective problem (eqs. (9), (11)).

Both problems are least squares in θ with static information that is affine in θ
(eq. (12): ŷ_static = Q R θ with the measured ȳ on the regressor side):

- **CLS**: min J_1(θ) subject to static equalities (the rational static function equals a
  polynomial curve, eq. (22); or it passes through given points) and any of the constraint
  constraint objects (:class:`graybox.StaticBand` …, module `graybox.static._constraints`).
- **PE**: min λ1 J_1(θ) + λ2 J_SF^QR(θ), λ2 = 1 − λ1, over a sweep of λ1, with
  ``J_1 = ‖Ψθ − y‖²/N`` and ``J_SF^QR = ‖QRθ − ȳ‖²/N_SF`` (the static-equation error that is
  affine in θ; for a rational model it is the true static error times the denominator D(ū)).

Each is solved as a cvxpy problem (Clarabel by default, OSQP selectable) and, when the
constraints are equalities only, by a closed form (the KKT conditions by the null-space
method; eq. (11) for PE). The closed forms are the cross-checks: tests hold the two to 1e-6.

Numerics. Regressors in engineering units span many decades (u² ≈ 1e6 rpm², u³ ≈ 1e9), so
every path works in ``z = s ⊙ θ`` with ``s`` the RMS of each column of Ψ (the static rows Q R hold
the same monomials at steady state, so they come out near unit scale too); constraint rows are
normalised to unit norm; θ is reported in engineering units. The dynamic data enter through the
triangular factor of ``[Ψ/s, y]``, so no solve grows with the record length N. A structure closed under shifts
(every divisor of every term, as ``centre=True`` returns) is fitted, as ELS and SE fit it, on the signals less their
means over the records, with the static points shifted alike, and θ mapped back (:func:`_data`), when its constraints
are made there too (none, PassesThrough, StaticBand, GainBounds, ClusterBounds and cvxpy constraints mapped to the
centred parameters: :func:`centrable`; an input held over the records is centred on its static points): the fit is
then the same model at any zero of y and u (on the raw signals y(k-1)² at y + 1e6 carried the offset's round-off, 1e-4,
into the fit). With a curve's eq. (22) the fit stays on the raw signals and carries that round-off. The cvxpy problem
goes one step further (:class:`_Basis`): its variable is the step from the least-squares estimate
in a basis where both quadratic forms are diagonal (a generalised SVD of the two factors), so the
ill-conditioning of a sweep down to λ1 = 1e-6 lives in a fixed change of variables rather than in
the solver; λ enters as nonnegative cvxpy Parameters multiplying the two convex terms (DPP), so a
sweep compiles once and re-solves (OSQP warm-started from the neighbouring λ).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Iterable, Mapping, Sequence

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.sparse

from ..static._constraints import (
    AffineRows,
    ClusterBounds,
    CurveEquality,
    GainBounds,
    InfeasibleError,
    PassesThrough,
    StaticBand,
    StaticConstraint,
    StaticContext,
    UserConstraint,
    as_constraint_list,
    cluster_powers,
    n_static_inputs,
    sigma_y_index,
    FREE_SIGMA_Y,
    static_cluster_map,
    static_inputs,
    static_rows,
)
from ..static._curves import StaticCurve, fit_on_powers
from ._extended_least_squares import els
from ..static._surfaces import StaticSurface
from ..static._form_check import varied_inputs
from ..core._least_squares import (REMEDIES, check_identified, check_rows, column_scales, free_directions,
                                   mean_square, output_scale, rank_tolerance, refuse_parameter_scales,
                                   regular_by_bounds, scaled_norm, scaled_norms, spread_scale, binary_exponent)
from ..models._coerce import as_model, as_structure, static_info, static_points
from ..models._model import Model
from ._pareto import ParetoSet
from ..core._records import (Dataset, Record, StaticPoints, as_records, carried_from, check_compatible,
                             check_same_units, warn_static_range)
from ..core._gram import as_gram_records, available_memory, is_dask_data, r_factor
from ..core._regressors import refuse_non_finite_columns, stacked_regressors
from ..core._terms import Structure
from ..selection._centring import (_centre_of, centred_dask, centred_data, centred_points, dask_levels, is_closed,
                                   is_held, shift_map, signal_offsets)
from ..core._validation import (Relocked, check_bool, check_choice, check_fields, check_int, check_lambdas, check_real,
                                check_theta, locked, warn)

if TYPE_CHECKING:  # cvxpy (and the scipy.stats it imports) takes seconds to import: loaded by the QP paths only
    import cvxpy as cp

__all__ = [
    "SOLVERS",
    "static_matrices",
    "identified_by",
    "pe_members",
    "static_prediction",
    "qr_static_error",
    "cls",
    "CLSResult",
    "pe_thetas",
    "pe_pareto",
    "PE_LAMBDAS",
]

#: The paper's PE sweep (Section IV-B), the default ``lambdas``: 100 λ1 in logspace(−6, 0).
PE_LAMBDAS = locked(np.logspace(-6, 0, 100))

#: Accepted ``how`` values of :func:`cls`: what static points impose.
HOW = ("auto", "curve", "points", "context")

#: Accepted ``solver`` values: cvxpy with Clarabel or OSQP, or the closed form.
SOLVERS = ("clarabel", "osqp", "closed")

# Tight defaults: the closed forms and the QPs are compared to 1e-6 in θ, and the PE sweep
# reaches λ1 = 1e-6 where the problem is ill-conditioned (see _Basis).
_SOLVER_DEFAULTS: dict[str, dict] = {
    "clarabel": dict(tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10, max_iter=400),
    # ADMM needs tight stopping to reach 1e-6 in θ; a least-squares objective is never unbounded,
    # so dual-infeasibility detection is switched off (it misfires at λ1 = 1e-6).
    "osqp": dict(eps_abs=1e-12, eps_rel=1e-12, eps_prim_inf=1e-9, eps_dual_inf=1e-15, polishing=False,
                 max_iter=200_000),
}

# --------------------------------------------------------------------------------------------
# eq. (12)
# --------------------------------------------------------------------------------------------
def static_matrices(structure: Structure, points: StaticPoints) -> tuple[np.ndarray, np.ndarray]:
    """Q and R of eq. (12) for any structure (clusters with any powers of y and u).

    Parameters
    ----------
    structure : Structure
        Process terms.
    points : StaticPoints
        Measured steady states (ū_i, ȳ_i), N_SF of them.

    Returns
    -------
    Q : ndarray, shape (N_SF, n_clusters)
        ``Q[i, c] = ȳ_i^p ū_i^m`` for cluster c = (p, m) (order of ``cluster_map(structure).keys``):
        the measured ȳ sits on the regressor side, so ``Q R θ`` is affine in θ.
    R : ndarray, shape (n_clusters, n_terms)
        The 0/1 map from θ to the cluster coefficients, Σ = R θ.
    """
    st = _process_structure(structure)
    cm = static_cluster_map(st, points.input_names)
    return static_rows(cm, points.ubar, points.ybar), np.array(cm.R)


def identified_by(structure: Structure, dynamic: np.ndarray, rows: int, *, points: StaticPoints | None = None,
                  equalities: np.ndarray | None = None, inputs: tuple[str, ...] | None = None,
                  what: str = "θ") -> None:
    """Every estimator's one identifiability rule (LS, CLS, PE, SE, output error): ``ValueError`` unless the
    records' regression, stacked with the static rows Q R of eq. (12) where the static points carry weight
    and with the equality constraints' rows, has full rank, judged units-free
    (:func:`graybox.core._least_squares.check_identified`). An input held constant leaves its terms and the
    constant collinear in the records; static points at several levels (weighted) or a constraint can
    still identify θ, and then the estimate is made.

    ``dynamic``: the records' regressors Ψ (N, n) or a triangular factor of them, in θ's coordinates
    (``rows`` = N); ``points``: the static points when they carry weight; ``equalities``: equality rows
    (r, n) in θ's coordinates; ``inputs``: the records' input names (for the clusters).
    """
    blocks = [("the identification records", dynamic, rows)]
    if points is not None:
        Q, R = static_matrices(structure, points)
        blocks.append((f"the {len(points)} static points", Q @ R, len(points)))
    if equalities is not None and equalities.shape[0]:
        blocks.append(("the equality constraints", equalities, equalities.shape[0]))
    clusters = np.array(static_cluster_map(structure, inputs).R, float)
    remedies = REMEDIES
    if len(blocks) == 1:  # no static points weighted: say where they would be
        remedies = ("give a record whose input moves, or static points at several input levels, with a weight on "
                    "them (λ1 < 1 of se_pareto, pe_pareto; se_dsf)", REMEDIES[1])
    check_identified(blocks, list(structure), clusters=clusters, what=what, remedies=remedies)


def static_prediction(structure: Structure, thetas: np.ndarray, points: StaticPoints) -> np.ndarray:
    """``Q R θ`` for one or many θ: the static equation's right-hand side at the measured ȳ.

    Returns
    -------
    ndarray, shape (K, N_SF) (or (N_SF,) for one θ), output units.
    """
    Q, R = static_matrices(structure, points)
    th = np.asarray(thetas, float)
    return th @ (Q @ R).T


def qr_static_error(structure: Structure, thetas: np.ndarray, points: StaticPoints) -> np.ndarray:
    """J_SF^QR = mean((ȳ − Q R θ)²): the static error the PE problem minimises, output units².

    For a rational model it is mean(D(ū_i)² (ȳ_i − ȳ_model(ū_i))²) with D the denominator of
    eq. (6); it is what the weighted sum (9)/(11) trades against J_1.

    Parameters
    ----------
    structure : Structure
        Process terms.
    thetas : ndarray, shape (n_terms,) or (K, n_terms)
    points : StaticPoints
        Static points (ū_i, ȳ_i); ȳ_i enters Q.

    Returns
    -------
    ndarray, shape (K,) (a float for one θ).
    """
    pred = static_prediction(structure, thetas, points)
    return mean_square(pred - points.ybar, axis=-1)


@dataclass(frozen=True, eq=False)
class CLSResult(Relocked):
    """The result of :func:`cls`: the model and what was imposed on it.

    Attributes
    ----------
    model : Model
        θ in engineering units.
    static : StaticPoints, StaticCurve, StaticSurface or None
        The static information the estimate used (the ``static`` argument, else the Dataset's
        static points; None when there was none).
    constraints : tuple of str
        Every constraint imposed, in words (the static one first).
    solver : str
        ``"clarabel"``, ``"osqp"`` or ``"closed"``.
    """

    model: Model
    static: StaticPoints | StaticCurve | StaticSurface | None
    constraints: tuple[str, ...]
    solver: str

    def __post_init__(self) -> None:
        check_fields(self)

    def __repr__(self) -> str:
        return (f"CLSResult(model={self.model.name!r}, n_params={self.model.n_params}, "
                f"constraints={list(self.constraints)}, solver={self.solver!r})")


# --------------------------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------------------------
def _process_structure(structure: object) -> Structure:
    st = as_structure(structure)
    if len(st) == 0:
        raise ValueError("the structure has no terms")
    noise = [str(t) for t in st if t.is_noise]
    if noise:
        raise ValueError(f"noise terms {noise} have no place in a gray-box estimate (the MA part is for ELS "
                         "bias only); pass structure.process")
    return st


def _check_solver(solver: str) -> str:
    return check_choice(solver, "solver", SOLVERS)


# --------------------------------------------------------------------------------------------
# the scaled, reduced problem data
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Data:
    """Scaled least-squares data: J_1 = (‖R1 z − c1‖² + rss)/N with z = s ⊙ θ."""

    structure: Structure
    s: np.ndarray  # (n,) column RMS of Ψ
    R1: np.ndarray  # (n, n) upper triangular
    c1: np.ndarray  # (n,)
    rss: float  # residual sum of squares of the unconstrained LS fit
    N: int  # regression rows
    y_scale: float  # the target's spread about its mean (core._least_squares.output_scale), output units
    # a structure closed under shifts is fitted on the signals less their ``offsets`` (:func:`_data`): z = s ⊙ θ_c,
    # θ_c the parameters on the centred signals, θ = A θ_c + t (:func:`~graybox.selection._centring.shift_map`);
    # None: z = s ⊙ θ on the signals as given
    A: np.ndarray | None = None
    t: np.ndarray | None = None
    offsets: Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        # a parameter is of the order of the output's spread over its column's RMS: a column of 1e-320 (u(k-1)^2 of
        # an input of 1e-160) beside an output of 1 has a θ beyond the float range, and the QP's θ overflowed (numpy
        # warned, then "theta has non-finite values"); refused as scaled_lstsq refuses it
        # (and below: a θ under the normal floats was 0 or a subnormal of a few bits, the term dropped silently)
        refuse_parameter_scales(self.structure.terms, self.y_scale, self.s)

    def theta(self, z: np.ndarray) -> np.ndarray:
        """θ (engineering units, on the signals as given) of z, shape (n,) or (K, n)."""
        z = np.asarray(z, float)
        if self.A is None:
            return z / self.s
        return (z / self.s) @ self.A.T + self.t

    def run_points(self, points: StaticPoints) -> StaticPoints:
        """The static points on the signals the fit runs on (less the offsets of a centred fit), on which the
        static residual Q R θ − ȳ is the same as on the raw ones, without the cancellation of the offsets' powers."""
        if self.offsets is None:
            return points
        ub, yb = self.run_levels(points.ubar, points.ybar, points.input_names)
        return replace(points, ubar=ub, ybar=yb)

    def run_levels(self, ubar: np.ndarray, ybar: np.ndarray, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Levels ū (shape (K,), or (K, m) with columns ``names``) and ȳ less the offsets of a centred fit."""
        off = self.offsets
        ub = np.asarray(ubar, float)
        # one input: the records' (the points may call it otherwise); several: by name, as the records' (checked)
        ub = ub - (next(v for k, v in off.items() if k != "y") if ub.ndim == 1 else
                   np.array([off[nm] for nm in names]))
        return ub, np.asarray(ybar, float) - off["y"]


def _tri_inv(R: np.ndarray) -> np.ndarray:
    """Inverse of an upper-triangular matrix by LAPACK trtri (no BLAS threads to wait for; see
    BENCHMARKS.md, "Implementation choices")."""
    inv, info = scipy.linalg.lapack.dtrtri(np.asarray(R, float), lower=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"singular triangular factor (trtri info {info})")
    return np.triu(inv)


def _r_factor(A: np.ndarray) -> np.ndarray:
    """Upper-triangular R of A = Q R (Q not formed), shape (n, n), for tall A (m > n).

    CholeskyQR2 (two passes of Gram matrix + Cholesky, Yamamoto et al. 2015): BLAS-3 only, which
    keeps thin factors fast and steady on a busy machine (BENCHMARKS.md, "Implementation choices").
    It is as accurate as Householder QR while cond(A) stays below ~1e8; beyond 1e6 (a tiny
    residual, nearly collinear columns) Householder QR is used.
    """
    try:
        R1 = scipy.linalg.cholesky(A.T @ A, lower=False, check_finite=False)
        d = np.abs(np.diag(R1))
        if not (np.all(np.isfinite(R1)) and d.min() > 1e-6 * d.max()):
            raise np.linalg.LinAlgError("too ill-conditioned for CholeskyQR2")
        # A R1⁻¹ through the small explicit inverse. einsum, not `@`: a threaded BLAS GEMM of this
        # thin shape waits on thread hand-offs on a busy machine.
        Q1 = np.einsum("ij,jk->ik", A, _tri_inv(R1))
        R2 = scipy.linalg.cholesky(Q1.T @ Q1, lower=False, check_finite=False)
        return R2 @ R1
    except np.linalg.LinAlgError:
        return scipy.linalg.qr(A, mode="r", check_finite=False)[0][: A.shape[1]]


def _r_factor_target(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """R of M = [A, y] (A's n columns at unit RMS, y in output units; M's last column is scaled in place) as (R_A
    (n, n), Q_Aᵀy (n,), the residual's squared norm, output units²: inf or 0 where it leaves the float range, as y²
    there).

    y is taken over the power of two above max|y| and its column mapped back (exact): the Gram matrix of an output
    near 1e155 overflowed (yᵀy ≈ 1e312: numpy's 'overflow encountered in matmul', and the fit was lost), of one near
    1e-170 underflowed."""
    n = M.shape[1] - 1
    e = binary_exponent(np.max(np.abs(M[:, n]), initial=0.0))
    if e:  # in place: no copy beside [A, y] (ls_uncertainty's peak memory holds to a few Ψ)
        np.ldexp(M[:, n], -e, out=M[:, n])
    R = _r_factor(M)
    with np.errstate(over="ignore", under="ignore"):
        return R[:n, :n], np.ldexp(R[:n, n], e), float(np.ldexp(R[n, n] ** 2, 2 * e))


def _dynamic(structure: Structure, records: list) -> _Data:
    if is_dask_data(records):
        return _dynamic_chunked(structure, records)
    rows = sum(max(len(r) - structure.max_lag, 0) for r in records)
    if 8 * 4 * rows * (len(structure) + 1) > available_memory():
        # Ψ, its scaled copy, [Ψ/s, y] and the CholeskyQR2 Q would not fit: reduce chunk by chunk
        return _dynamic_chunked(structure, records)
    with np.errstate(over="ignore", invalid="ignore"):  # refused below, naming the terms
        psi, y = stacked_regressors(structure, records)
    n = len(structure)
    check_rows(psi.shape[0], n)
    refuse_non_finite_columns(psi, structure)  # y is a Record's: finite
    s = column_scales(psi)
    # R-factor of [Ψ/s, y]: its top-left block is Ψ's triangular factor, its last column Q1ᵀy and
    # its corner the LS residual norm; Q itself is never formed.
    return _Data(structure, s, *_r_factor_target(np.column_stack([psi / s, y])), psi.shape[0], output_scale(y))


def _held_level(levels: np.ndarray, held: float) -> float:
    """Where an input held over the records at ``held`` is centred (as SE's ``SEProblem._held_offset``): its level less
    the RMS distance of its static points' ``levels`` from it, so that on the records it is that distance (a constant
    the points, the only ones to tell its terms apart, scale with the input's unit) at any zero of the input; 0 (left
    at its level) with every point at the held level to round-off."""
    if is_held(np.append(levels, held)):
        return 0.0
    return held - float(np.sqrt(np.mean((levels - held) ** 2)))


def _data(structure: Structure, records: list, points: StaticPoints | None = None) -> _Data:
    """The scaled least-squares data of CLS and PE: :func:`_dynamic` on the signals less their means over the records
    for a structure closed under shifts (:func:`~graybox.selection._centring.is_closed`, records in memory or on Dask,
    whose blocks are shifted as they are read: fitted raw, a DaskRecord at y + 1e7 was refused as not identifiable
    where the same samples in memory fit), as ELS
    and the SE fits are, with the map back to θ (``_Data.A``, ``_Data.t``); for a problem whose constraints are made
    on the centred signals too (:func:`centrable`), else the raw :func:`_dynamic`. On the raw signals the regressors of a
    closed quadratic in y at y + 1e6 carry the offset's powers (y(k-1)² ≈ 1e12 for a spread of 25): its round-off,
    1e-4, was 4e-6 of what the data say, and the fits (one-step predictions, free runs) moved by 4e-6 of y's spread
    with the output's zero, and PE's closed form called λ1 < 1 singular. A signal held over the records keeps its
    zero (centred, its terms would be round-off of nothing) unless static ``points`` tell its terms apart: it is then
    centred on them (:func:`_held_level`; kept at its zero, its terms carried the offset's powers into what only the
    points identify: a PE member's static function at u + 1e5 moved by 6e-5 output units)."""
    if not is_closed(structure):
        return _dynamic(structure, records)
    lazy = is_dask_data(records)
    try:
        if lazy:
            recs = list(records) if isinstance(records, (list, tuple)) else [records]
            off, held, first = dask_levels(recs)
            if not all(np.isfinite(v) for v in off.values()):  # a sample not finite: the raw reduction names it
                return _dynamic(structure, records)
        else:
            recs = as_records(records)
            off = signal_offsets(recs)
            ys = np.concatenate([r.y for r in recs])
            us = np.concatenate([r.u.reshape(len(r.y), -1) for r in recs])
            held = frozenset([n for i, n in enumerate(recs[0].input_names) if is_held(us[:, i])]
                             + (["y"] if is_held(ys) else []))
            first = {n: float(us[0, i]) for i, n in enumerate(recs[0].input_names)}
        names = recs[0].input_names
        off = {k: (0.0 if k in held else v) for k, v in off.items()}
        if points is not None:
            ub = np.asarray(points.ubar, float).reshape(len(points), -1)
            for i, n in enumerate(names):
                if n in held and ub.shape[1] == len(names):
                    off[n] = _held_level(ub[:, i], first[n])
        A, t = shift_map(structure, off)
    # records that do not fit the structure, or offsets whose powers overflow (u ≈ 1e160 with u(k-1)^2: a bare
    # OverflowError from cls): _dynamic says so, naming the regressor
    except (ValueError, KeyError, IndexError, OverflowError):
        return _dynamic(structure, records)
    d = _dynamic(structure, centred_dask(recs, off) if lazy else centred_data(recs, off, keep=held))
    return replace(d, A=A, t=t, offsets=off)


def _dynamic_chunked(structure: Structure, records: list) -> _Data:
    """As :func:`_dynamic` by TSQR over chunks of rows: for Dask records (the blocks reduced on the
    active Dask scheduler; the record is never held whole) and for records whose dense Ψ would not
    fit in memory."""
    n = len(structure)
    R, N = r_factor(structure.terms, records, structure.max_lag)
    check_rows(N, n)
    # column RMS from the factor (‖A e_j‖ = ‖R e_j‖); R D⁻¹ is the factor of the scaled matrix
    # (norms over a power of two: a column about 2^515, y(k-1) of such an output, overflowed in its square)
    s = scaled_norms(R[:, :n], 0) / np.sqrt(N)
    s = np.where(s > 0, s, 1.0)
    Rs = R[:, :n] / s
    # QR sign convention: make the diagonal positive, as the Cholesky-based factor has it
    sign = np.where(np.diag(R) < 0, -1.0, 1.0)[:, None]
    Rs, c = sign * Rs, sign[:, 0] * R[:, n]
    with np.errstate(over="ignore", under="ignore"):  # output units²: inf or 0 beyond the float range, as y² there
        rss = float(np.float64(c[n]) ** 2)
    # ‖y‖ is the norm of R's last column: the targets' RMS, to scale them by before their squares are taken
    rms = scaled_norm(R[:, n]) / np.sqrt(N)
    return _Data(structure, s, Rs[:n, :n], c[:n], rss, N, _target_scale(records, structure.max_lag, rms))


def _target_scale(records: list, L: int, rms: float = 1.0) -> float:
    """output_scale of the regression targets y[L:] of every record, on the Dask scheduler for Dask records (their
    RMS ``rms`` known, output units: they are taken over the power of two above it, whose squares stay floats)."""
    if not is_dask_data(records):
        return output_scale(np.concatenate([np.asarray(r.y[L:], float) for r in as_records(records)]))
    import dask
    import dask.array as da

    e = binary_exponent(rms)
    y = da.concatenate([r.y[L:] for r in records]) * math.ldexp(1.0, -e)
    std, ms = dask.compute(da.std(y), da.mean(y**2))
    return math.ldexp(spread_scale(float(std), float(np.sqrt(ms))), e)


def _static_part(d: _Data, points: StaticPoints) -> tuple[np.ndarray, np.ndarray, int]:
    """Scaled static rows (R2, c2) with ‖QRθ − ȳ‖² = ‖R2 z − c2‖² + const, and N_SF."""
    points = d.run_points(points)  # on the centred signals for a centred fit: Q R θ − ȳ is the same there
    Q, R = static_matrices(d.structure, points)
    A2 = (Q @ R) / d.s
    if not np.all(np.isfinite(A2)):
        raise ValueError("non-finite static rows: check the static points")
    M = len(points)
    n = A2.shape[1]
    if M > n:  # reduce as for Ψ so the QP never grows with N_SF either
        R2, c2, _ = _r_factor_target(np.column_stack([A2, points.ybar]))
        return R2, c2, M
    return A2, np.array(points.ybar), M


def _ls_theta(d: _Data, what: str = "the least-squares θ") -> np.ndarray:
    """Unconstrained least squares, engineering units (identifiability checked: :func:`identified_by`)."""
    identified_by(d.structure, d.R1 * d.s, d.N, what=what)
    return d.theta(scipy.linalg.solve_triangular(d.R1, d.c1))


def _sigma_y(d: _Data, records: list[Record], reference: Model | np.ndarray | float | str
             ) -> float | str | None:
    """Σ*_y of eq. (22) from ``reference``: "free" (estimated), "ls", "els", a Model, a θ of this structure, a
    number."""
    cm = static_cluster_map(d.structure, records[0].input_names if records else None)
    iy = sigma_y_index(cm)
    if iy is None:
        return None
    if isinstance(reference, str) and reference == FREE_SIGMA_Y:
        return FREE_SIGMA_Y
    if isinstance(reference, str) and reference == "ls":
        th = _ls_theta(d, "the least-squares reference for Σ*_y (reference='ls'; or give it as a number or a Model)")
    elif isinstance(reference, str) and reference == "els":
        if is_dask_data(records):  # said of the reference, not as els's refusal of "data" the caller gave rightly
            raise ValueError("reference='els' fits extended least squares on the records, which needs them in memory; "
                             "for a DaskRecord give reference='free' (the default), 'ls', a Model (e.g. an ELS fit on "
                             "a record that fits) or the value of Σ*_y")
        return float(els(d.structure, records).model.clusters().get("Σy", 0.0))
    elif isinstance(reference, str):
        raise ValueError(f"reference must be 'free', 'ls', 'els', a Model, a θ or a number, got {reference!r}")
    elif isinstance(reference, Model) or isinstance(getattr(reference, "model", None), Model):
        return float(as_model(reference, "reference").clusters().get("Σy", 0.0))
    elif np.ndim(reference) == 0:
        return check_real(reference, "reference (Σ*_y)")
    else:
        th = np.asarray(reference, float)
        if th.shape != (len(d.structure),):
            raise ValueError(f"reference θ must have shape ({len(d.structure)},), got {th.shape}")
    return float((cm.R @ th)[iy])


# --------------------------------------------------------------------------------------------
# constraint rows → scaled, normalised, reduced
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Rows:
    """Constraint rows in the solver's coordinates y (z = T y, θ = z / s)."""

    V: np.ndarray  # (r, n) orthonormal equality rows
    g: np.ndarray  # (r,)
    G: np.ndarray  # (j, n) unit-norm inequality rows
    h: np.ndarray  # (j,)
    user: tuple[StaticConstraint, ...]  # not affine: built as cvxpy constraints on θ(y)
    names: tuple[str, ...]


#: The constraints a fit on the centred signals (:func:`_data`) takes, each made on the centred signals: their meaning
#: is the same there (the static equation at the shifted points, a band's half-width, the denominator D = 1 − ∂/∂ȳ,
#: the gains on the shifted grid; cluster bounds and cvxpy constraints on θ = A θ_c + t, mapped exactly); a problem
#: with a curve's eq. (22) is fitted raw.
_CENTRED_CONSTRAINTS = (PassesThrough, StaticBand, GainBounds, ClusterBounds, UserConstraint)


def centrable(cons: Sequence[StaticConstraint]) -> bool:
    """Whether a problem with constraints ``cons`` is fitted on the centred signals when its structure is closed."""
    return all(type(c) in _CENTRED_CONSTRAINTS for c in cons)


def _centred_context(ctx: StaticContext, d: _Data) -> StaticContext:
    """``ctx`` on the centred signals of ``d``: its points shifted, its least-squares θ that of the centred fit."""
    ls = None
    if ctx.ls_theta is not None:
        ls = scipy.linalg.solve_triangular(d.R1, d.c1) / d.s
    return StaticContext(ctx.structure, None if ctx.points is None else d.run_points(ctx.points), None, None,
                         ctx.inputs, ls)


def _centred_affine(c: StaticConstraint, ctx: StaticContext, ctx_c: StaticContext, d: _Data) -> AffineRows:
    """The rows of a :data:`_CENTRED_CONSTRAINTS` constraint on θ_c, made on the centred signals of ``d``
    (``ctx_c``): with its own points (if any) shifted; gains on their grid (taken on the signals as given) shifted;
    cluster bounds, which speak of the raw parameters θ = A θ_c + t, mapped (exact: a bound on a cluster that is
    the same at any zero, Σyu, stays one on θ_c's; fitted raw, at y + 1e9 it moved the fit by the output's spread)."""
    if isinstance(c, ClusterBounds):
        r = c.affine(ctx)
        return AffineRows.make(ctx.n_terms, r.A_eq @ d.A, r.b_eq - r.A_eq @ d.t, r.A_ub @ d.A, r.b_ub - r.A_ub @ d.t)
    if isinstance(c, GainBounds):
        ub, yb = c.grid(ctx)
        names = ctx_c.cluster_map.input_names if np.ndim(ub) > 1 else ()
        return c.rows_at(ctx_c, *d.run_levels(ub, yb, names))
    return _centred_constraint(c, d).affine(ctx_c)


def _raw_pins(cons: Sequence[StaticConstraint], ctx: StaticContext, d: _Data, theta: np.ndarray) -> np.ndarray:
    """θ (shape (n,) or (K, n), NaN rows kept) of a fit on the centred signals with each parameter that a cluster
    bound fixes alone (a cluster of one term, equal bounds) set to its value: mapped back, A θ_c + t carries the
    offsets' round-off (Σyu = 0 came out -3.5e-16, a term asked to be absent present; Σ0 = 0 as 6e-9 at y + 1e5),
    where the raw fit met such a pin exactly."""
    if d.A is None:
        return theta
    for c in cons:
        if not isinstance(c, ClusterBounds):
            continue
        r = c.affine(ctx)
        for a, b in zip(r.A_eq, r.b_eq):
            nz = np.flatnonzero(a)
            if nz.size == 1:  # NaN rows (members that failed) stay NaN
                theta[..., nz[0]] = np.where(np.isnan(theta[..., nz[0]]), np.nan, b / a[nz[0]])
    return theta


def _centred_constraint(c: StaticConstraint, d: _Data) -> StaticConstraint:
    """``c`` with its own points (if any) on the centred signals of ``d``."""
    pts = getattr(c, "points", None)
    return c if pts is None else replace(c, points=d.run_points(pts))


def _after_solve(cons: Sequence[StaticConstraint], ctx: StaticContext, d: _Data, z: np.ndarray) -> None:
    """Each constraint's own checks on the estimate θ of z (``ValueError``). For a fit on the centred signals, a check
    that refuses θ is made again on the centred signals (θ_c = z / s, the constraint's points shifted), where the static
    equation's terms do not carry the offsets' powers, and the estimate is refused only when it fails there too (with
    the message of the signals as given): a derivative D = 1 − ∂/∂ȳ of −0.004 at a point, beside terms of 3.7e6 at
    y + 1e6, read as vanishing (1e-9 of them) at y + 1e6 and not at y + 1e5."""
    theta = d.theta(z)
    ctx_c = None
    for c in cons:
        try:
            c.after_solve(theta, ctx)
        except ValueError as exc:
            if d.A is None or type(c) not in _CENTRED_CONSTRAINTS:
                raise
            ctx_c = _centred_context(ctx, d) if ctx_c is None else ctx_c
            try:
                _centred_constraint(c, d).after_solve(z / d.s, ctx_c)
            except ValueError:
                raise exc from None


def _rows(cons: list[StaticConstraint], ctx: StaticContext, d: _Data, T: np.ndarray | None = None,
          at: np.ndarray | None = None) -> _Rows:
    """The rows in y (z = T y, z the coordinates of ``d``: θ's, or θ_c's for a centred fit); with ``at`` (a z) their right-hand
    sides are those of the step y − T⁻¹ at, each row's residual at ``at`` formed in z, where no ill-conditioned T has
    touched it. The equalities' consistency is judged on the output's spread ``d.y_scale`` (output units)."""
    y_scale, s = d.y_scale, d.s
    n = s.size
    at = np.zeros(n) if at is None else at
    E, f, G, h, user, eq_names = [np.zeros((0, n))], [np.zeros(0)], [np.zeros((0, n))], [np.zeros(0)], [], []
    eq_cons: list[tuple[StaticConstraint, AffineRows]] = []
    ctx_c = None if d.A is None else _centred_context(ctx, d)
    for c in cons:
        c.check(ctx)
        # a centred fit (its constraints :func:`centrable`) takes the rows the constraint makes on the centred signals,
        # on θ_c; mapped from the raw rows they would carry the offsets' powers (2e9 ± 100, a curve's 1e9 coefficients)
        r: AffineRows | None = c.affine(ctx) if ctx_c is None else _centred_affine(c, ctx, ctx_c, d)
        if r is None:
            user.append(c)
            continue
        if r.n_eq:
            e = _row_exponents(r.A_eq, s)
            E.append(np.ldexp(r.A_eq, -e) / s)
            f.append(np.ldexp(r.b_eq, -e[:, 0]))
            eq_names.append(c.describe())
            eq_cons.append((c, r))
        if r.n_ub:
            e = _row_exponents(r.A_ub, s)
            A_ub, b_ub = np.ldexp(r.A_ub, -e) / s, np.ldexp(r.b_ub, -e[:, 0])
            G.append(A_ub if T is None else A_ub @ T)
            h.append(b_ub - A_ub @ at)
    names = tuple(c.describe() for c in cons)
    E, f, G, h = np.vstack(E), np.concatenate(f), np.vstack(G), np.concatenate(h)
    G, h = _normalise_ub(G, h, names)
    # which equalities are independent, and whether they agree, is decided in z, where each row is of unit norm
    # per scaled parameter; after the ill-conditioned T a row that is independent in z could fall under the rank
    # cut (eq. (22) with Σ_y free and u far from its zero: the constraint was dropped and the curve not met)
    # the hint that points over-determine the static function only where points are imposed
    points = any(isinstance(c, PassesThrough) for c in cons)
    V, g = _reduce_eq(E, f, eq_names, cluster_count=len(ctx.cluster_map.keys) if points else None, scale=y_scale,
                      centred=_centred_eq_rows(eq_cons, ctx if ctx_c is None else ctx_c))
    if T is not None and V.shape[0]:
        U, S, Vt = np.linalg.svd(V @ T, full_matrices=False)  # the same rows, orthonormal in y, every one kept
        V, g = Vt, (U.T @ (g - V @ at)) / S
    return _Rows(V, g, G, h, tuple(user), names)


def _row_exponents(A: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Powers of two (shape (rows, 1)) that bring each constraint row of ``A`` (in θ) in z = s ⊙ θ, A / s, to about
    unit size, exact: a row and its right-hand side over one power of two are the same condition, in any units. eq.
    (22) at u about 1e-120 has rows of 1e240 beside column scales of 1e-121 (A / s overflowed); a gain bound at y
    about 1e-211 rows of 1e-212 in z beside the denominator's rows of 1, read as zero rows and dropped (the bound
    silently ignored), or refused as infeasible. A zero row stays zero (0 to the power 0)."""
    low = np.iinfo(np.int32).min
    top = np.where(A != 0, np.frexp(A)[1] - np.frexp(s)[1], low)
    e = np.max(top, axis=1, keepdims=True, initial=low)
    return np.where(e == low, 0, e)


def _normalise_ub(G: np.ndarray, h: np.ndarray, names: tuple[str, ...], tol: float = 0.0
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Rows of unit norm; a zero row dropped when it reads 0 <= h with h >= −``tol`` (else no θ meets it)."""
    norms = scaled_norms(G, 1)
    zero = norms <= 1e-14 * max(1.0, norms.max(initial=0.0))
    if np.any(h[zero] < -tol):  # 0 <= h with h < 0: no θ can satisfy it
        raise InfeasibleError(f"infeasible constraints (a row reads 0 <= {h[zero].min():g}): {list(names)}")
    G, h, norms = G[~zero], h[~zero], norms[~zero]
    return G / norms[:, None], h / norms


def _centred_eq_rows(eq_cons: list[tuple[StaticConstraint, AffineRows]], ctx: StaticContext
                     ) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The equality rows of ``eq_cons`` in the parameters of the signals centred on the static points' means, for a
    structure closed under shifts with static points imposed (else None): the rows :func:`_reduce_eq` decides the rank
    on. A closed structure's parameters on centred and raw signals are one invertible linear map apart
    (:func:`~graybox.selection._centring.shift_map`), so the rank is the same, but in raw coordinates it depended on the
    signals' zero: at u + 3e3 (spread 3) and y + 2e9 an independent point's row fell under the 1e-10 cut, and the
    estimate missed the point. A PassesThrough's rows are formed from its centred points (no cancellation); other rows
    are mapped. Returned with their right-hand sides (the output's offset taken out), on which the equalities'
    consistency is judged, and the rank cut (1e-10, or the points' round-off relative to their centred spread where
    that is larger)."""
    pts = [c.points if c.points is not None else ctx.points for c, _ in eq_cons if isinstance(c, PassesThrough)]
    if not pts or pts[0] is None or not is_closed(ctx.structure):
        return None
    cm = ctx.cluster_map
    m = n_static_inputs(cm)
    names = (tuple(cm.input_names) if hasattr(cm, "input_names") else
             tuple(ctx.inputs or ctx.structure.input_names or ("u",)))
    ub0 = static_inputs(pts[0].ubar, m).reshape(-1, m)
    # a level held at every point is its own centre (exactly zero centred, not its mean's round-off, which the
    # column scaling below would have made a direction of its own)
    cu = np.array([_centre_of(ub0[:, j]) for j in range(m)])
    cy = _centre_of(np.asarray(pts[0].ybar, float))
    offsets = {"y": cy} | {nm: float(cu[j]) for j, nm in enumerate(names)}
    try:
        A, t = shift_map(ctx.structure, offsets)
    except (ValueError, KeyError):  # a structure whose inputs are named otherwise: the raw rows decide
        return None
    rows, rhs = [], []
    for c, r in eq_cons:
        if isinstance(c, PassesThrough):
            p = c.points if c.points is not None else ctx.points
            ub = static_inputs(p.ubar, m).reshape(-1, m) - cu
            yc = np.asarray(p.ybar, float) - cy
            rows.append(static_rows(cm, ub[:, 0] if m == 1 else ub, yc) @ cm.R)
            rhs.append(yc)
        else:
            rows.append(r.A_eq @ A)
            rhs.append(r.b_eq - r.A_eq @ t)
    # the points' round-off relative to their centred spread (ū and ȳ stored at their offsets: at y + 2e9, 2.4e-7
    # of a spread of 2.6): a centred row independent by less than that is round-off, not a condition of its own
    raw = np.column_stack([ub0, np.asarray(pts[0].ybar, float)])
    spread = np.max(np.abs(raw - np.append(cu, cy)), axis=0)
    held = spread == 0
    level = float(np.max(np.where(held, 0.0, np.max(np.abs(raw), axis=0) / np.where(held, 1.0, spread))))
    return np.vstack(rows), np.concatenate(rhs), max(1e-10, 10 * np.finfo(float).eps * level)


def _equilibrated(C: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centred equality rows with columns, then rows, of unit norm (zero ones kept), and their right-hand sides."""
    cn = scaled_norms(C, 0)
    C = C / np.where(cn > 0, cn, 1.0)
    rn = scaled_norms(C, 1)
    rn = np.where(rn > 0, rn, 1.0)
    return C / rn[:, None], f / rn


def centred_eq_rank(cons: list[StaticConstraint], ctx: StaticContext) -> int | None:
    """The rank of the equality rows of ``cons`` as :func:`_reduce_eq` decides it for the estimators (on centred rows,
    :func:`_centred_eq_rows`), or None where it decides it on the raw rows (then the 1e-10 cut there)."""
    eq = [(c, r) for c in cons if (r := c.affine(ctx)) is not None and r.n_eq]
    centred = _centred_eq_rows(eq, ctx) if eq else None
    if centred is None:
        return None
    C = centred[0][scaled_norms(centred[0], 1) > 0]
    return _centred_rank(C, np.zeros(C.shape[0]), centred[2])[1]


def _centred_rank(C: np.ndarray, f: np.ndarray, cut: float) -> tuple[np.ndarray, int | None, np.ndarray]:
    """Centred equality rows ``C`` equilibrated (:func:`_equilibrated`): their left singular vectors, their rank at
    ``cut`` relative to the largest singular value (None when every row is 0) and the right-hand sides ``f``
    equilibrated alike."""
    C, fc = _equilibrated(C, f)
    Uc, Sc, _ = np.linalg.svd(C, full_matrices=False)
    return Uc, (int(np.sum(Sc > cut * Sc[0])) if Sc.size and Sc[0] > 0 else None), fc


def _reduce_eq(E: np.ndarray, f: np.ndarray, names: list[str], cluster_count: int | None,
               scale: float, centred: tuple[np.ndarray, np.ndarray, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Independent, orthonormal equality rows V y = g, or an error if the equalities disagree.

    The rows are of unit norm in z = θ·s, so their right-hand sides are in output units: a disagreement is
    judged against ``scale`` (the output's spread) or the right-hand sides' size, not against one output
    unit, which for an output in A (1e-9) took contradictory equalities for one and met them halfway.
    ``cluster_count``: the structure's cluster coefficients where static points are imposed (then the
    message says that they over-determine it), else None."""
    n = E.shape[1]
    if E.shape[0] == 0:
        return np.zeros((0, n)), np.zeros(0)
    norms = scaled_norms(E, 1)
    ok = norms > 0
    if np.any(np.abs(f[~ok]) > 0):
        raise InfeasibleError(f"inconsistent equality constraints (a row reads 0 = {f[~ok][0]:g}): {names}")
    E, f = E[ok] / norms[ok, None], f[ok] / norms[ok]
    U, S, Vt = np.linalg.svd(E, full_matrices=False)
    # not the rank rule of identifiability (core._least_squares.rank_tolerance): these are the few equality rows,
    # each of unit norm, standing for no regression rows; rows within 1e-10 are one condition said twice (a
    # curve's equality at nearby ū), whose round-off difference must not become a second, contradictory row
    r = int(np.sum(S > 1e-10 * S[0]))
    Ur = U[:, :r]
    resid = f - Ur @ (Ur.T @ f)
    judged = f
    if centred is not None:
        # the same rows and right-hand sides in centred coordinates (_centred_eq_rows): the rank decided there, and
        # the consistency, judged against the right-hand sides without the output's offset (at y + 2e9, 1e-8 of
        # ‖f‖ was 45 output units, and inconsistent points 0.1 apart were met halfway)
        Uc, rc, fc = _centred_rank(centred[0][ok], centred[1][ok], centred[2])
        if rc is not None:
            r = rc
            Ur, Uk = U[:, :r], Uc[:, :r]
            resid, judged = fc - Uk @ (Uk.T @ fc), fc
    if scaled_norm(resid) > 1e-8 * max(scale, scaled_norm(judged)):
        more = ""
        if E.shape[0] > r and cluster_count is None:
            more = (f" ({E.shape[0]} equality rows but only {r} independent ones: some fix the same combination of "
                    "the parameters at different values)")
        elif E.shape[0] > r:
            more = (f" ({E.shape[0]} equality rows but only {r} independent ones: the static function of this "
                    f"structure has {cluster_count} cluster coefficients, so generic static points over-determine "
                    "it; use fewer points, StaticCurve.fit + CurveEquality, a StaticBand or the PE problem)")
        raise InfeasibleError(f"the equality constraints are inconsistent{more}: {names}")
    return Vt[:r], (Ur.T @ f) / S[:r]


# --------------------------------------------------------------------------------------------
# the cvxpy problem (one per estimator call; λ as Parameters)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Basis:
    """The QP's coordinates: z = z0 + T y, the step y from the least-squares estimate z0, in which both
    quadratic forms are diagonal.

    With Ψ of full rank and static rows R2, T = R_s⁻¹ V from the CS decomposition of the stacked
    factors, [R1; R2] = [Q1; Q2] R_s and Q2 = W S Vᵀ (Q1ᵀQ1 = I − Q2ᵀQ2, so V diagonalises both): the
    objective is w1 yᵀdiag(H1)y + w2 (yᵀdiag(H2)y + 2 l2ᵀy) up to constants, whatever λ is, H2 = S²
    and H1 the column norms² of Q1 V. The ill-conditioning of the data then lives in T (applied once,
    by backward-stable triangular solves) instead of in the solver's KKT system, which is why Clarabel
    and OSQP reach the closed form to ~1e-8 down to λ1 = 1e-6. Without static rows T = R1⁻¹ and
    H1 = 1; without full rank, T = I and the forms are dense.

    Only the step goes through T, and l2 = S Wᵀ(R2 z0 − c2) is formed from the static residual at z0:
    the former basis R1⁻¹V from the SVD of R2 R1⁻¹, and the least-squares point and gradient taken in
    it, carried ‖ŷ‖, an output's offset included, through the explicit inverse; at an output of
    2e9 ± 50 (cond R1 ≈ 1e10) that moved the fitted output by its whole spread.
    """

    T: np.ndarray  # (n, n)
    H1: np.ndarray  # (n,) diagonal, or (n, n)
    H2: np.ndarray | None  # (n,) diagonal, or (n, n)
    z0: np.ndarray  # (n,) the least-squares estimate (a minimiser of the dynamic term), scaled coordinates
    l1: np.ndarray  # (n,) half the dynamic term's gradient at z0 in y (0 up to round-off)
    l2: np.ndarray | None  # half the static term's


def _full_rank(blocks: Sequence[tuple[np.ndarray, int]]) -> bool:
    """Whether the stacked factors (each with the regression rows it stands for) are of full rank, judged by
    the one identifiability rule (:func:`~graybox.core._least_squares.free_directions`), so that the basis
    takes the triangular path exactly where :func:`identified_by` called θ identified."""
    return not free_directions(blocks).shape[1]


def _basis(d: _Data, static: tuple[np.ndarray, np.ndarray] | None, eq: _Rows | None = None,
           n_static: int = 0) -> _Basis:
    """The QP's coordinates (:class:`_Basis`). ``eq``: the equality rows in z (T = I), used where Ψ is rank
    deficient and the static rows do not complete it, to start the step where they hold; ``n_static``:
    the static points the static rows stand for (N_SF)."""
    n = d.s.size
    full = _full_rank([(d.R1, d.N)])
    if full and static is None:
        return _Basis(_tri_inv(d.R1), np.ones(n), None, scipy.linalg.solve_triangular(d.R1, d.c1), np.zeros(n), None)
    if static is not None:
        R2, c2 = static
        Qs, Rs = np.linalg.qr(np.vstack([d.R1, R2]))
        if full or _full_rank([(d.R1, d.N), (R2, n_static)]):
            # z0: the least-squares estimate; where Ψ alone leaves θ free (an input held) and the static rows
            # complete it, the least squares of both terms, so that the step is of the data's size there too
            z0 = (scipy.linalg.solve_triangular(d.R1, d.c1) if full
                  else scipy.linalg.solve_triangular(Rs, Qs.T @ np.concatenate([d.c1, c2])))
            W, S, Vt = np.linalg.svd(Qs[n:], full_matrices=True)
            k = S.size
            H2 = np.zeros(n)
            H2[:k] = S**2
            Q1V = Qs[:n] @ Vt.T  # orthogonal columns: their squared norms (1 − S² without its cancellation)
            l2 = np.zeros(n)
            l2[:k] = S * (W.T @ (R2 @ z0 - c2))[:k]
            l1 = np.zeros(n) if full else Q1V.T @ (d.R1 @ z0 - d.c1)
            return _Basis(scipy.linalg.solve_triangular(Rs, Vt.T), np.einsum("ij,ij->j", Q1V, Q1V), H2, z0, l1, l2)
    # rank-deficient Ψ (the constraints may still identify θ): plain normal forms
    H1, g1 = d.R1.T @ d.R1, d.R1.T @ d.c1
    z0 = np.linalg.lstsq(H1, g1, rcond=None)[0]
    if eq is not None and eq.V.shape[0]:
        # the least squares within the equalities: from the minimum-norm point the step along the directions
        # Ψ leaves free is of the size of θ itself (an output's offset), not of the data's spread
        z_p = eq.V.T @ eq.g  # V has orthonormal rows
        Nb = scipy.linalg.null_space(eq.V)
        z0 = z_p + Nb @ np.linalg.lstsq(d.R1 @ Nb, d.c1 - d.R1 @ z_p, rcond=None)[0]
    if static is None:
        return _Basis(np.eye(n), H1, None, z0, H1 @ z0 - g1, None)
    H2 = static[0].T @ static[0]
    return _Basis(np.eye(n), H1, H2, z0, H1 @ z0 - g1, H2 @ z0 - static[0].T @ static[1])


def _quad(y: cp.Variable, H: np.ndarray) -> cp.Expression:
    import cvxpy as cp

    if H.ndim == 1:
        if np.all(H == 1.0):
            return cp.sum_squares(y)
        # a constant matrix goes to the solver as P itself (no auxiliary variables)
        return cp.quad_form(y, scipy.sparse.diags(H))
    return cp.quad_form(y, cp.psd_wrap(H))


def _rows_feasible(V: np.ndarray, g: np.ndarray, G: np.ndarray, h: np.ndarray) -> bool:
    """Whether some δ meets V δ = g and G δ <= h (a linear program, HiGHS): the feasibility of the rows alone, without
    the objective. Each row is taken over the power of two of its largest |entry|, and δ in units of the power of two
    of the largest right-hand side (δ is free: neither changes the answer), so that HiGHS sees entries and bounds of
    order 1, not a bound of 1e8 (which it reads as infeasible where its rows hold 1e-8 after a row's scaling)."""
    from scipy.optimize import linprog

    A, b = np.vstack([V, G]), np.concatenate([g, h])
    e = binary_exponent(np.max(np.abs(A), axis=1, initial=0.0))
    A, b = np.ldexp(A, -e[:, None]), np.ldexp(b, -e)
    b = np.ldexp(b, -binary_exponent(np.max(np.abs(b), initial=0.0)))
    m = V.shape[0]
    res = linprog(np.zeros(A.shape[1]), A_ub=A[m:] if A.shape[0] > m else None, b_ub=b[m:] if A.shape[0] > m else None,
                  A_eq=A[:m] if m else None, b_eq=b[:m] if m else None, bounds=(None, None), method="highs")
    return bool(res.status == 0)


def _member_failure(exc: ValueError) -> ValueError:
    """``exc`` marked as one solve's failure (the solver stopped at its limit, failed numerically, or returned no
    optimum), which a sweep keeps as that member's failure (:func:`pe_members`), not the whole call's; constraints
    that admit no θ, or options the solver refuses, are the call's."""
    exc.member = True  # type: ignore[attr-defined]
    return exc


class _QP:
    """min w1 (δᵀH1δ + 2l1ᵀδ) + w2 (δᵀH2δ + 2l2ᵀδ)  s.t.  V δ = g', G δ <= h', user(θ(δ)).

    The variable is δ = y / σ, the step from the unconstrained least-squares estimate in
    the solver basis (:class:`_Basis`) in units of the output's spread σ about its mean (so that the problem the solver sees, and its
    optimum, do not depend on the output's units). Centring matters: the objective is then the *change* of the weighted squared
    errors (0 at the LS estimate), so the solvers' relative gap tolerances apply to what is being
    traded instead of to ‖y‖² ≈ N·mean(y²), which would leave active constraints ~1e-6 loose.

    Built once; ``w1``, ``w2`` are nonnegative Parameters multiplying convex terms (DPP), so a
    sweep re-solves the compiled problem (warm-started) instead of rebuilding it.
    """

    def __init__(self, d: _Data, static: tuple[np.ndarray, np.ndarray] | None, cons: list[StaticConstraint],
                 ctx: StaticContext, solver: str, options: Mapping | None, n_static: int = 0):
        import cvxpy as cp

        n = d.s.size
        self.fixed_only = False
        zrows = _rows(cons, ctx, d)  # in z: the equalities reduced, the inequalities of unit norm
        k = n - zrows.V.shape[0]
        if zrows.V.shape[0] and k:
            # the equalities eliminated in z, z = z_p + N w (as the closed form does), where they are as well
            # conditioned as the constraints themselves: carried into the basis T (cond(Ψ)) they held only to
            # about eps·cond(T) (eq. (22) with Σ_y free and u = 3000 ± 1: Σ_y 2e-7 off the constrained optimum,
            # which cls_uncertainty then refused as no optimum)
            self.z_p, self.N = zrows.V.T @ zrows.g, scipy.linalg.null_space(zrows.V)
            Qr, Rr = np.linalg.qr(d.R1 @ self.N)
            c = d.c1 - d.R1 @ self.z_p
            cq = Qr.T @ c
            with np.errstate(over="ignore"):  # output units²: inf beyond the float range, as the data's rss
                rss = d.rss + np.float64(scaled_norm(c - Qr @ cq)) ** 2
            dr = _Data(d.structure, np.ones(k), Rr, cq, rss, d.N, d.y_scale)
            static_r = None if static is None else (static[0] @ self.N, static[1] - static[0] @ self.z_p)
            # a row the equalities leave constant is its slack at z_p, formed to the round-off of z_p's size (an
            # output offset 2e9 ± 50: Σyu <= 0 beside eq. (22)'s Σyu = 0 read 0 <= -1.1e-7 and was refused)
            tol = 1e-9 * max(d.y_scale, scaled_norm(self.z_p))
            G, h = _normalise_ub(zrows.G @ self.N, zrows.h - zrows.G @ self.z_p, zrows.names, tol=tol)
            self.basis = b = _basis(dr, static_r, None, n_static)
            V, g = np.zeros((0, k)), np.zeros(0)
            self.fixed = None
        else:  # no equalities, or equalities that fix θ whole: the rows go to the solver (in its basis)
            self.z_p, self.N, k = np.zeros(n), np.eye(n), n
            # fixed whole, θ is the equalities' solution in z, exactly; the solver only says whether the other
            # constraints admit it (its own θ meets the equalities to eps·cond(T): Σ_y = 0.67540098 for 0.6754)
            self.fixed = zrows.V.T @ zrows.g if zrows.V.shape[0] == n else None
            if self.fixed is not None and not zrows.user:
                # nothing left to optimise, and only the inequalities to check: at the point itself, to its
                # round-off, not by a solver searching a feasible set of one point (a bound the point misses by
                # 1e-12 ended in Clarabel's 'user_limit' and an overflow warning from cvxpy)
                slack = zrows.h - zrows.G @ self.fixed
                tol = 1e-9 * max(d.y_scale, scaled_norm(self.fixed))
                if np.any(slack < -tol):
                    raise InfeasibleError(f"the constraints admit no θ: the equalities fix θ, and it misses "
                                          f"{list(zrows.names)} by {-slack.min():.3g} (output units)")
                self.fixed_only = True
            self.basis = b = _basis(d, static, None if _full_rank([(d.R1, d.N)]) else zrows, n_static)
            rows = _rows(cons, ctx, d, b.T, at=b.z0)
            V, g, G, h = rows.V, rows.g, zrows.G, zrows.h
        # the inequalities in the basis, each row's slack at z0 formed where no ill-conditioned T has touched it
        G, h = _normalise_ub(G @ b.T, h - G @ b.z0, zrows.names)
        rows = _Rows(V, g, G, h, zrows.user, zrows.names)
        z0 = b.z0  # T only ever carries the step, whose size is the output's spread (see _Basis)
        # y is in output units (the linear terms scale with the output, the objective with its
        # square): the variable is the step in units of the output's spread σ, because Clarabel's
        # tolerances and starting point are absolute and its optimum moved with the output's units.
        # The spread about the mean, not the RMS: an offset (2e9 ± 50) made every step ~1e-8 of σ.
        self.sigma = sig = d.y_scale
        self.dy = cp.Variable(k, name="dy")  # y / σ
        # engineering units, for user constraints
        theta = (self.z_p + self.N @ z0) / d.s + cp.multiply(sig / d.s, (self.N @ b.T) @ self.dy)
        if d.A is not None:  # a fit on the centred signals: user constraints speak of the raw θ = A θ_c + t
            theta = d.A @ theta + d.t
        self.w1 = cp.Parameter(nonneg=True, name="w1")
        self.w2 = cp.Parameter(nonneg=True, name="w2")
        obj = self.w1 * (_quad(self.dy, b.H1) + 2 * (b.l1 / sig) @ self.dy)
        if b.H2 is not None:
            obj = obj + self.w2 * (_quad(self.dy, b.H2) + 2 * (b.l2 / sig) @ self.dy)
        cons_cp: list[cp.Constraint] = []
        if rows.V.shape[0]:
            cons_cp.append(rows.V @ self.dy == rows.g / sig)
        if rows.G.shape[0]:
            cons_cp.append(rows.G @ self.dy <= rows.h / sig)
        for c in rows.user:
            cons_cp.extend(c.constraints(theta, ctx))
        self.problem = cp.Problem(cp.Minimize(obj), cons_cp)
        # the affine rows alone (in δ), to tell constraints that admit no θ from a solve that failed numerically
        self.rows = (rows.V, rows.g / sig, rows.G, rows.h / sig)
        self.affine = None if rows.user else self.rows
        # First warm start: the LS estimate (OSQP converges slowly from elsewhere when λ1 is
        # tiny); later solves start from the previous one.
        self.dy.value = np.zeros(k)
        if not self.problem.is_dcp(dpp=True):
            raise ValueError("the problem is not convex (DCP/DPP): check the user constraints")
        if solver == "osqp" and not self.problem.is_qp():
            # OSQP takes linear constraints only; cvxpy's refusal came back as a solver failure, said as constraints
            # that admit no θ
            raise ValueError(f"solver='osqp' solves quadratic programs (linear constraints) only, and "
                             f"{[c.describe() for c in rows.user]} are not linear in θ: use solver='clarabel'")
        self.solver = solver
        self.names = rows.names
        self.options = dict(_SOLVER_DEFAULTS[solver])
        self.options.update(options or {})
        self.user_options = dict(options or {})
        self.solved = False  # a solve has taken the options: a later SolverError is that member's, not theirs
        #: (w1, w2) of the solves the solver called inaccurate: said once per estimate (warn_inaccurate)
        self.inaccurate: list[tuple[float, float]] = []

    def solve(self, w1: float, w2: float, warm_start: bool = True) -> np.ndarray:
        """z for one weight pair (the weights are normalised to sum 1: the argmin is unchanged)."""
        import cvxpy as cp

        if self.fixed_only:  # θ fixed by the equalities and the inequalities checked there
            return self.fixed.copy()

        tot = float(w1) + float(w2)
        self.w1.value, self.w2.value = float(w1) / tot, float(w2) / tot
        # Warm starts help OSQP (first order) only. Through cvxpy, a warm-started Clarabel re-uses
        # its solver object and stops early on the PE sweep (BENCHMARKS.md); an interior-point
        # method gains nothing from a warm start anyway.
        warm = warm_start and self.solver == "osqp"
        try:
            with warnings.catch_warnings():
                # cvxpy's "Solution may be inaccurate": graybox says it itself, once per sweep (warn_inaccurate), or
                # refuses a solve stopped at its iteration limit below
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                self.problem.solve(solver=self.solver.upper(), warm_start=warm, **self.options)
        except cp.error.SolverError as exc:
            if self.user_options and not self.solved:
                # a value the solver refuses at its setup (OSQP's eps_abs = -1: "failed (2)"), said of the options, not
                # as constraints that admit no θ
                # (the call's failure, not one member's: every λ1 would fail alike, each printing the solver's error)
                raise ValueError(
                    f"solver {self.solver} failed ({exc}) with solver_options {self.user_options!r}: check "
                    "their values (tolerances > 0, iteration limits >= 1; the solver may have printed "
                    "which it refuses), or leave them out for graybox's defaults") from exc
            if self.user_options:  # taken by an earlier solve: this λ1's numerical failure (a07e3bc)
                raise _member_failure(ValueError(f"solver {self.solver} failed ({exc}) with solver_options "
                                                 f"{self.user_options!r}, which an earlier λ1's solve took")) from exc
            raise _member_failure(InfeasibleError(f"solver {self.solver} failed ({exc}) with constraints "
                                                  f"{list(self.names)}")) from exc
        except (TypeError, ValueError, OverflowError) as exc:
            if not self.user_options:
                raise
            # a value the solver's binding refuses (max_iter = -2: an OverflowError), not the constraints
            raise ValueError(f"solver {self.solver} refused solver_options {self.user_options!r}: "
                             f"{type(exc).__name__}: {exc}") from exc
        self.solved = True
        st = self.problem.status
        if st in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            if self.affine is not None and _rows_feasible(*self.affine):
                # Σ0 <= -1e7 on an output of order 1: any θ with that constant meets it, yet Clarabel said
                # 'infeasible' and this said "the constraints admit no θ"
                raise _member_failure(InfeasibleError(
                    f"solver {self.solver} reports status {st!r} for {list(self.names)}, but these constraints "
                    "alone admit θ (a linear program on them finds one): the solve failed numerically, most likely "
                    "a bound far beyond what these data's fit reaches (check the bounds' units: output units for a "
                    "cluster's sum, against an output whose spread is " f"{self.sigma:.3g})"))
            raise InfeasibleError(
                f"the constraints admit no θ: solver {self.solver} reports status {st!r} for "
                f"{list(self.names) or ['(none)']}"
            )
        if st == cp.USER_LIMIT:
            # a feasible problem the solver did not finish, not constraints that admit no θ
            limit = self.options.get("max_iter")
            # a time limit the caller set is named as the limit reached (clarabel's time_limit said "max_iter = 400",
            # the default, and asked to raise max_iter)
            timed = "time_limit" in self.user_options
            what = (f"time_limit = {self.user_options['time_limit']}, max_iter = {limit}" if timed else
                    f"max_iter = {limit}")
            raise_ = "{'max_iter': ...} or a larger time_limit" if timed else "{'max_iter': ...}"
            raise _member_failure(ValueError(
                f"solver {self.solver} stopped at its iteration or time limit (status {st!r}, {what}) "
                f"before it converged, with constraints {list(self.names)}: raise it with "
                f"solver_options={raise_}" + (", or use solver='clarabel'" if self.solver == "osqp" else "")))
        if st not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or self.dy.value is None:
            raise _member_failure(InfeasibleError(f"solver {self.solver} returned status {st!r} with constraints "
                                                  f"{list(self.names)}"))
        if st == cp.OPTIMAL_INACCURATE:
            self._check_inaccurate(np.array(self.dy.value, float))
            self.inaccurate.append((float(w1), float(w2)))
        if self.fixed is not None:
            return self.fixed.copy()
        return self.z_p + self.N @ (self.basis.z0 + self.sigma * (self.basis.T @ np.array(self.dy.value, float)))

    def _check_inaccurate(self, dy: np.ndarray) -> None:
        """A member's failure when an optimum the solver called inaccurate misses the affine rows by more than 1e-6 of
        the output's spread (the rows in units of σ, each over its norm): OSQP stopped early with loose tolerances
        returned a θ 60 % outside a static band, said only as "an inaccurate optimum"."""
        V, g, G, h = self.rows
        miss = np.concatenate([np.abs(V @ dy - g), G @ dy - h])  # an equality missed either way, an inequality above
        norms = np.linalg.norm(np.vstack([V, G]), axis=1)
        worst = float(np.max(miss / np.maximum(norms, np.finfo(float).tiny), initial=0.0))
        if not worst <= 1e-6:  # NaN too
            raise _member_failure(InfeasibleError(
                f"solver {self.solver} reports an inaccurate optimum (status 'optimal_inaccurate') that misses the "
                f"constraints {list(self.names)} by {worst * self.sigma:.3g} (output units): not taken; tighten "
                "or leave out solver_options, or use solver='clarabel'"))

    def warn_inaccurate(self) -> None:
        """One warning for the whole sweep, naming the weights whose optimum the solver called inaccurate."""
        if self.inaccurate:
            said = ", ".join(f"(w1={a:g}, w2={b:g})" for a, b in self.inaccurate[:5])
            more = f" and {len(self.inaccurate) - 5} more" if len(self.inaccurate) > 5 else ""
            warn(f"solver {self.solver} reports an inaccurate optimum at {len(self.inaccurate)} weight(s): "
                 f"{said}{more}", RuntimeWarning)


# --------------------------------------------------------------------------------------------
# closed forms
# --------------------------------------------------------------------------------------------
def _closed_form(d: _Data, static: tuple[np.ndarray, np.ndarray] | None, rows: _Rows,
                 w1: np.ndarray, w2: np.ndarray, n_static: int = 0) -> np.ndarray:
    """argmin w1‖R1 z − c1‖² + w2‖R2 z − c2‖² s.t. V z = g, for K weight pairs at once (``n_static``: the
    static points R2 stands for).

    The KKT conditions are solved by the null-space method: z = z_p + N w with V z_p = g and
    V N = 0, then an unconstrained least squares in w. Without constraints this *is* eq. (11),
    evaluated through a QR factorisation of the stacked, weighted factors instead of forming
    [λ1 ΨᵀΨ + λ2 (QR)ᵀQR]⁻¹ (which squares the condition number). It works in the scaled
    coordinates z directly (not in the solver basis of :class:`_Basis`), so comparing it with
    the QPs checks two independent computations.

    Returns
    -------
    ndarray, shape (K, n): z for each pair; a NaN row for a pair whose weighted stack is singular (each pair is
    judged on its own: in a sweep one such pair is one failed member, the others solved as they are alone).
    """
    if rows.G.shape[0] or rows.user:
        raise ValueError("the closed form handles equality constraints only; use solver='clarabel' or 'osqp' "
                         f"for {[c.describe() for c in rows.user] or 'the inequality rows'}")
    n = d.s.size
    if rows.V.shape[0]:
        z_p = rows.V.T @ rows.g  # V has orthonormal rows
        Nb = scipy.linalg.null_space(rows.V)
    else:
        z_p, Nb = np.zeros(n), np.eye(n)
    if Nb.shape[1] == 0:  # the equalities fix θ completely
        return np.tile(z_p, (len(w1), 1))
    blocks = [(d.R1, d.c1, w1)] + ([(static[0], static[1], w2)] if static is not None else [])
    B = np.concatenate([np.sqrt(w)[:, None, None] * (A @ Nb)[None] for A, _, w in blocks], axis=1)
    rhs = np.concatenate([np.sqrt(w)[:, None] * (c - A @ z_p)[None] for A, c, w in blocks], axis=1)
    Qb, Rb = np.linalg.qr(B)
    # the one rank rule (core._least_squares.rank_tolerance) on the weighted stack actually solved
    bad = _singular_stacks(Rb, rank_tolerance(1.0, d.N + n_static, n))
    out = np.full((len(w1), n), np.nan)
    good = ~bad
    if good.any():
        wv = np.linalg.solve(Rb[good], np.einsum("kij,ki->kj", Qb[good], rhs[good])[..., None])[..., 0]
        out[good] = z_p[None, :] + wv @ Nb.T
    return out


def _singular_stacks(R: np.ndarray, tol: float) -> np.ndarray:
    """Whether σ_min <= ``tol`` · σ_max for each of the K matrices ``R`` (K, r, c), shape (K,) bool: the SVD of every
    matrix cost a third of the closed form's time (100 λ: 1.2 of 3.5 ms), so those whose bounds settle it
    (:func:`~graybox.core._least_squares.regular_by_bounds`) are not decomposed; the others are judged by their
    singular values, as all were."""
    undecided = ~regular_by_bounds(R, tol)
    bad = np.zeros(R.shape[0], dtype=bool)
    if undecided.any():
        sv = np.linalg.svd(R[undecided], compute_uv=False)
        bad[undecided] = sv[:, -1] <= tol * sv[:, 0]
    return bad


#: Why the closed form gives a weight pair no θ (a NaN row of :func:`_closed_form`).
_SINGULAR = "the closed form is singular at these weights: θ is not identifiable from these data and constraints"


# --------------------------------------------------------------------------------------------
# CLS
# --------------------------------------------------------------------------------------------
def cls(
    structure: Structure | Model,
    data: Record | Sequence[Record] | Dataset,
    static: StaticCurve | StaticSurface | StaticPoints | None = None,
    *,
    how: str = "auto",
    reference: Model | np.ndarray | float | str = "free",
    constraints: StaticConstraint | Iterable[StaticConstraint] | None = None,
    solver: str = "clarabel",
    solver_options: Mapping | None = None,
    name: str = "CLS",
) -> CLSResult:
    """Constrained least squares: min J_1(θ) with the static information imposed exactly.

    Parameters
    ----------
    structure : Structure, sequence of str, Model, or a result that carries one
        Process terms (a Model's or a result's structure is used, e.g. a Selection or an
        ELSResult; noise terms are refused).
    data : Record, sequence of Record, Dataset, DaskRecord or sequence of DaskRecord
        Dynamic identification data (a Dataset's ``ident`` record). A
        :class:`~graybox.DaskRecord` is reduced to the triangular factor of [Ψ, y] block by
        block on the active Dask scheduler (never held whole).
    static : StaticCurve, StaticSurface or StaticPoints, optional
        What the static function must match:

        - a polynomial curve → eq. (22) (:class:`~graybox.CurveEquality`), for a
          structure whose static function is rational; with several inputs a polynomial
          surface (:class:`~graybox.StaticSurface`) → eq. (22) on the surface;
        - points → "the static function passes through these points"
          (:class:`~graybox.PassesThrough`), any structure;
        - None → the Dataset's static points when ``data`` is a Dataset that has them (as for
          :func:`pe_pareto` and :func:`se_pareto`); otherwise only ``constraints``.
    how : {"auto", "curve", "points", "context"}
        What StaticPoints impose. ``"context"``: nothing by themselves; they are only the points
        that ``constraints`` without points of their own speak of (a band, gain bounds over
        their range). ``"points"``: pass through each. ``"auto"``: pass through each
        when there are fewer points than the structure has clusters (as many, for a structure without
        a Σy cluster), else (the points cannot all be passed through, save degenerately with Σy = 1)
        as ``"curve"`` for a rational structure.
        ``"curve"`` with StaticPoints fits the polynomial the structure's numerator can carry
        (on the powers of ū of its Σ_{u^m} clusters, the others 0) and imposes eq. (22); it needs
        as many points as there are such clusters, at two levels or more. With several inputs it fits a surface on exactly the monomials
        of the structure's Σ_{u^e} clusters (:meth:`StaticSurface.fit`), so it needs at least as
        many points as there are such clusters.
    reference : {"free", "ls", "els"}, Model, ndarray of shape (n_terms,) or float
        Where Σ*_y of eq. (22) comes from: ``"free"`` (default) estimated with the other
        parameters (the least-squares model among all whose static function is the curve; it does
        not depend on where the input's zero is); ``"ls"`` the unconstrained least-squares
        estimate's Σy on ``data``; ``"els"`` extended least squares' (the paper's choice:
        :func:`graybox.els` with its default MA(2)); a reference Model (its Σy); a θ of this
        structure; or the value itself. A reference's Σy is its denominator's slope at ū = 0: with
        an input far from zero (rpm, kelvin) it can leave the curve's range with no stable model
        (refused: Σ*_y > 1) or a poor one (BENCHMARKS.md, "Where Σ*_y of eq. (22) comes from").
    constraints : constraint or iterable of constraints, optional
        More constraints (band, gain, cluster bounds, user cvxpy constraints), combined with the
        static ones.
    solver : {"clarabel", "osqp", "closed"}
        cvxpy with Clarabel (default) or OSQP, or the KKT closed form (equalities only).
    solver_options : mapping, optional
        Passed to ``cvxpy.Problem.solve`` (overrides graybox's tight defaults). An optimum the solver
        calls inaccurate is kept (with one warning) only where it meets the affine constraints to
        1e-6 of the output's spread; else that member fails, naming them.
    name : str
        The returned model's name.

    Returns
    -------
    CLSResult
        ``.model`` (θ in engineering units), the static information used and the constraints
        imposed, in words.

    Raises
    ------
    ValueError
        Bad input (non-rational structure with a curve, too few points, a zero denominator of the
        estimated static function at a static point, …). Static points outside the records'
        input range are welcome: a :class:`StaticRangeWarning` names them once.
        Also when the records and the equality constraints do not identify θ (``identified_by``; an
        input held constant leaves its terms free unless eq. (22) or the points fix them), or when
        ``reference="ls"`` and the records alone do not; the message says what is missing.
    InfeasibleError
        The constraints admit no θ; the message names them and the solver status.
    """
    st = _process_structure(structure)
    solver = _check_solver(solver)
    _check_solver_options(solver_options, solver)
    recs = as_gram_records(data)
    try:  # the points that tell a held input's terms apart (:func:`_data`), if any; refused below, after the records
        sp = static_info(static, data, curves=True)
    except (ValueError, TypeError):
        sp = None
    d = _data(st, recs, sp if isinstance(sp, StaticPoints) else None)
    cons, ctx, curve = _cls_setup(st, recs, d, data, static, how, reference, constraints)
    if d.A is not None and not centrable(cons):  # constraints that are made on the raw signals only
        d = _dynamic(st, recs)
    rows = _rows(cons, ctx, d)  # validates every constraint before any solver runs
    _warn_static_range(cons, ctx, curve, recs)  # after: bad input is an error, not a warning and an error
    # the records and the equality constraints must identify θ (an input held constant leaves its terms free)
    identified_by(st, d.R1 * d.s, d.N, equalities=rows.V * d.s, inputs=recs[0].input_names, what="the CLS θ")
    if solver == "closed":
        z = _closed_form(d, None, rows, np.ones(1), np.zeros(1))[0]
        if not np.all(np.isfinite(z)):
            raise ValueError(_SINGULAR)
    else:
        qp = _QP(d, None, cons, ctx, solver, solver_options)
        z = qp.solve(1.0, 0.0)
        qp.warn_inaccurate()
    theta = _raw_pins(cons, ctx, d, d.theta(z))
    _after_solve(cons, ctx, d, z)
    info = sp  # (read above; _cls_setup has raised whatever reading it raises)
    model = Model(st, theta, name=name, **carried_from(recs, info))  # the records' input order, period and units
    return CLSResult(model, info,
                     tuple(c.describe() for c in cons), solver)


def _cls_setup(st: Structure, recs: list[Record], d: _Data, data, static, how: str, reference,
               constraints) -> tuple[list[StaticConstraint], StaticContext, StaticCurve | StaticSurface | None]:
    """The constraints and context of a CLS problem (shared by :func:`cls` and the covariance of its estimate)."""
    inputs = recs[0].input_names
    cm = static_cluster_map(st, inputs)
    static_cons: list[StaticConstraint] = []
    points: StaticPoints | None = None
    curve: StaticCurve | StaticSurface | None = None
    check_choice(how, "how", HOW)
    static = static_info(static, data, curves=True)  # the Dataset's points unless static is given, as PE and SE
    if static is None and how in ("points", "curve"):  # was: the plain least-squares model, nothing imposed, unsaid
        what = "the static points" if how == "points" else "the static curve eq. (22) matches (or points to fit it to)"
        raise ValueError(f"how={how!r} imposes {what}, but there is no static information: pass static= "
                         "(StaticPoints, a StaticCurve or a StaticSurface) or a Dataset with static points")
    _check_point_inputs(recs, static if isinstance(static, StaticPoints) else None)
    if how == "context":
        if isinstance(static, (StaticCurve, StaticSurface)):
            raise ValueError("how='context' makes static points the context of the constraints; a curve or surface is "
                             "imposed by eq. (22): leave how='auto'")
        points, static = static, None
    if isinstance(static, StaticPoints) and how == "auto":
        # as many points as clusters or more: the static function cannot pass through them all (at best
        # degenerately, Σy = 1: ȳ is Q's Σy column), so a rational structure takes the curve its numerator carries
        # (eq. (22)). Without a Σy cluster as many points as clusters are a square system a true static function
        # meets (a FIR model with its gain at one point was sent to a curve fit, which one level refuses)
        over = len(static) > len(cm.keys) or (len(static) == len(cm.keys) and sigma_y_index(cm) is not None)
        how = "curve" if over and cm.max_y_power <= 1 else "points"
    if isinstance(static, (StaticCurve, StaticSurface)):
        if how == "points":
            raise ValueError("how='points' needs StaticPoints; sample the curve with curve.points(ubar)")
        curve = static
    elif isinstance(static, StaticPoints) and how == "curve" and n_static_inputs(cm) > 1:
        points = static
        curve = numerator_surface(cm, points)
    elif isinstance(static, StaticPoints):
        points = static
        if how == "curve":
            curve = numerator_curve(cm, points)
    if curve is not None:
        static_cons.append(CurveEquality(curve))
    elif points is not None and how != "context":
        static_cons.append(PassesThrough(points))
    cons = static_cons + as_constraint_list(constraints)
    ctx_points = points if points is not None else static_info(None, data)  # a curve: the Dataset's points are the context
    for c in cons:  # every set of static points speaks of the records' inputs
        _check_point_inputs(recs, getattr(c, "points", None))
    _check_point_inputs(recs, ctx_points)
    ctx = StaticContext(st, ctx_points, curve, _needed_sigma_y(cons, d, recs, reference), inputs,
                        _needed_ls_theta(cons, d))
    return cons, ctx, curve


def _check_point_inputs(recs: list[Record], points: StaticPoints | None) -> None:
    """Static points must speak of the records' inputs: same count; same names when there are several; the same
    units where both name them (a constraint's own points and ``eval_static`` as ``static=``'s)."""
    if points is None or not recs:
        return
    r = recs[0]
    if points.n_inputs != r.n_inputs or (r.n_inputs > 1 and points.input_names != r.input_names):
        check_compatible(r, points)
    for rec in recs:
        check_same_units(getattr(rec, "units", ("", "")), f"{rec.name!r} has", points, "the records and the static "
                         "points of one identification must be in the same units (convert one of them)")


def numerator_curve(cm, points: StaticPoints) -> StaticCurve:
    """The polynomial in ū on the powers of the Σ_{u^m} clusters (what the numerator can carry), fitted to
    ``points`` by least squares; powers the structure lacks (Σ_u of a structure with Σ_0 and Σ_{u²} only) stay 0,
    where a full-degree fit would ask eq. (22) for a cluster that is not there."""
    powers = sorted({m for p, m in cm.keys if p == 0})
    degree = max(powers, default=0)
    if len(points) < len(powers):
        raise ValueError(
            f"fewer static points than the constraints need: eq. (22) for this structure matches a degree-{degree} "
            f"curve in the powers {powers} of ū, which needs at least {len(powers)} points; got {len(points)}"
        )
    if not powers or len(points) == 1:  # no numerator cluster, or one level: StaticCurve.fit's own answer
        return StaticCurve.fit(points, degree=degree)
    return fit_on_powers(points, powers)


def numerator_surface(cm, points: StaticPoints) -> StaticSurface:
    """The surface on the monomials of the Σ_{u^e} clusters (what the numerator can carry), fitted to ``points``.

    The surface eq. (22) can impose on a several-input structure (:class:`~graybox.CurveEquality`);
    ``cm`` is the structure's :class:`ClusterMap`.
    """
    m = n_static_inputs(cm)
    static_inputs(points.ubar, m, points.name)
    varied = varied_inputs(points)
    held = [n for n in points.input_names if n not in varied]
    if held and len(points) > 1:
        # the surface cannot be fitted in an input the points hold, and eq. (22) would force every cluster in
        # it to the surface's (absent) coefficient, zero: a transient input's terms would be switched off
        raise ValueError(
            f"{points.name} hold the input(s) {held} at one value: eq. (22)'s surface cannot be fitted over them. "
            "Keep the static function within the points' band instead (how='context', "
            "constraints=graybox.StaticBand()), or use pe_pareto / se_pareto, which take such points")
    exps = sorted({e for p, e in map(cluster_powers, cm.keys) if p == 0}, key=lambda e: (sum(e), tuple(-v for v in e)))
    if not exps:
        raise ValueError("how='curve': the structure has no cluster without y (no Σ_u… or constant term), so its "
                         "static function is 0 wherever it exists; give points (how='points') or more terms")
    if len(points) < len(exps):
        raise ValueError(
            f"fewer static points than the constraints need: eq. (22) for this structure matches a surface with "
            f"{len(exps)} monomials, which needs at least {len(exps)} points; got {len(points)}"
        )
    return StaticSurface.fit(points, exponents=exps)


# --------------------------------------------------------------------------------------------
# PE bi-objective
# --------------------------------------------------------------------------------------------
def _check_reference(reference: object, n_terms: int) -> None:
    """``reference`` is one of the forms :func:`_sigma_y` reads, checked even where no constraint needs it."""
    if reference is None:
        # once silently the least-squares reference ('ls'), where the default is 'free' and the docstrings name no None
        raise TypeError("reference must be 'free' (the default: Σ_y estimated), 'ls', 'els', a Model, a θ or a "
                        "number, got None")
    if isinstance(reference, Model) or isinstance(getattr(reference, "model", None), Model):
        return
    if isinstance(reference, str):
        if reference not in (FREE_SIGMA_Y, "ls", "els"):
            raise ValueError(f"reference must be 'free', 'ls', 'els', a Model, a θ or a number, got {reference!r}")
    elif np.ndim(reference) == 0:
        check_real(reference, "reference (Σ*_y)")
    else:
        check_theta(n_terms, reference, "reference θ")


def _needed_sigma_y(cons: list[StaticConstraint], d: _Data, recs: list[Record], reference) -> float | str | None:
    """Σ*_y only when some CurveEquality will ask for it (ELS is not free)."""
    _check_reference(reference, len(d.structure))
    if any(isinstance(c, CurveEquality) and c.sigma_y is None for c in cons):
        return _sigma_y(d, recs, reference)
    return None


def _needed_ls_theta(cons: list[StaticConstraint], d: _Data) -> np.ndarray | None:
    """The least-squares θ when some constraint's ``min_denominator`` is "auto" (None when not identifiable:
    the constraint then keeps its fixed margin)."""
    if not any(isinstance(getattr(c, "min_denominator", None), str) for c in cons):
        return None
    try:
        return _ls_theta(d)
    except ValueError:
        return None


def _warn_static_range(cons: list[StaticConstraint], ctx: StaticContext, curve: StaticCurve | StaticSurface | None,
                       recs: list[Record]) -> None:
    """One warning per estimate naming every static ū (points, constraints' points) outside the records."""
    ub = [ctx.points.ubar] if ctx.points is not None else []
    ub += [c.points.ubar for c in cons if getattr(c, "points", None) is not None]
    if curve is not None and curve.domain is not None:
        # a surface's domain is one (low, high) per input: its two corners are the rows of the transpose
        dom = np.array(curve.domain, dtype=float)
        ub.append(dom.T if isinstance(curve, StaticSurface) and curve.n_inputs > 1 else dom.ravel())
    if ub:
        warn_static_range(np.concatenate(ub), recs)


def _pe_setup(structure, data, static, constraints, weights, ubar, reference="free", centre=False):
    """The PE problem's data; ``centre``: a structure closed under shifts on the centred signals (:func:`_data`, the
    fit's), else on the signals as given (z = s ⊙ θ, what the covariances of ``diagnostics`` read)."""
    st = _process_structure(structure)
    check_choice(weights, "weights", ("mse", "sum"))
    recs = as_gram_records(data)
    cons = as_constraint_list(constraints)
    try:  # read first for the points that tell a held input's terms apart (:func:`_data`); refused after the records
        pts, late = static_points(static, data, ubar=ubar, needed_by="the PE problem"), None
    except (ValueError, TypeError) as exc:
        pts, late = None, exc
    d = _data(st, recs, pts) if centre and centrable(cons) else _dynamic(st, recs)
    if late is not None:
        raise late
    curve = static if isinstance(static, (StaticCurve, StaticSurface)) else None
    for p in [pts] + [getattr(c, "points", None) for c in cons]:
        _check_point_inputs(recs, p)
    ctx = StaticContext(st, pts, curve, _needed_sigma_y(cons, d, recs, reference), recs[0].input_names,
                        _needed_ls_theta(cons, d))
    rows = _rows(cons, ctx, d)
    _warn_static_range(cons, ctx, curve, recs)
    R2, c2, M = _static_part(d, pts)
    return st, recs, d, pts, ctx, cons, rows, (R2, c2), M


def _solver_settings(solver: str) -> set[str] | None:
    """The option names ``solver_options`` may give ``solver``: its own settings and cvxpy's solve keywords; None
    where this version of the solver does not list them (the solver then says what it refuses)."""
    import inspect

    import cvxpy as cp

    try:
        if solver == "clarabel":
            import clarabel

            names = {a for a in dir(clarabel.DefaultSettings()) if not a.startswith("_")}
        else:
            import osqp

            names = {a for a in dir(osqp.ext_builtin.OSQPSettings()) if not a.startswith("_")}
        # cvxpy's own solve keywords, read off a private method: guarded as the solver's settings are
        cvx = set(inspect.signature(cp.Problem._solve).parameters) - {"self", "solver", "kwargs"}
    except Exception:  # noqa: BLE001 - another release's layout: leave the check to the solver
        return None
    return names | cvx | {"use_quad_obj"}


#: cvxpy solve keywords that solver_options may not give, and why
_CVXPY_TAKEN: dict[str, str] = {
    "warm_start": "graybox sets warm_start itself (pe_thetas and pe_pareto take warm_start=... as their own argument)",
    "solver": "give the solver as solver='clarabel' or 'osqp'",
    "gp": "the problem is a convex QP, not a geometric program",
    "qcp": "the problem is a convex QP, not a quasiconvex program",
    "nlp": "the problem is a convex QP, not a nonlinear program",
    "requires_grad": "graybox does not differentiate through the solve",
}


def _check_solver_options(options: object, solver: str) -> None:
    if options is not None and not isinstance(options, Mapping):
        raise TypeError(f"solver_options must be a mapping of the solver's keyword options, got {options!r}")
    if options and solver == "closed":  # not dropped unseen
        raise ValueError(f"solver_options apply to the cvxpy solvers ('clarabel', 'osqp'), not to solver='closed'; "
                         f"got {dict(options)!r}")
    if options:
        # cvxpy's solve keywords that graybox sets itself or that make it another problem (warm_start came back as
        # "got multiple values for keyword argument", gp as cvxpy's DGPError)
        taken = [k for k in options if k in _CVXPY_TAKEN]
        if taken:
            raise ValueError(f"solver_options: {taken} cannot be given: " + "; ".join(_CVXPY_TAKEN[k] for k in taken))
        # an option the solver does not know failed inside the solve: as clarabel's TypeError, or as osqp's
        # SolverError, which was said as constraints that admit no θ
        known = _solver_settings(solver)
        unknown = [k for k in options if known is not None and k not in known]
        if unknown:
            raise ValueError(f"solver_options: {unknown} are not settings of {solver} (its settings include "
                             f"{sorted(k for k in known if k in _SOLVER_DEFAULTS[solver]) or sorted(known)[:8]}, …)")


def pe_thetas(
    structure: Structure | Model,
    data: Record | Sequence[Record] | Dataset,
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    lambdas: np.ndarray | Sequence[float] | None = None,
    constraints: StaticConstraint | Iterable[StaticConstraint] | None = None,
    solver: str = "clarabel",
    solver_options: Mapping | None = None,
    weights: str = "mse",
    ubar: np.ndarray | None = None,
    warm_start: bool = True,
    reference: Model | np.ndarray | float | str = "free",
) -> np.ndarray:
    """θ of the PE weighted sum (9) for each λ1 (λ2 = 1 − λ1), without evaluating them.

    ``weights="mse"`` minimises ``λ1 ‖Ψθ − y‖²/N + λ2 ‖QRθ − ȳ‖²/N_SF`` (the paper's J_1 and
    J_SF are mean squared errors); ``weights="sum"`` drops the 1/N, 1/N_SF as eq. (11) is
    printed (the same front, reached at other λ).

    Parameters
    ----------
    structure, data, static, lambdas, constraints, solver, solver_options, weights, ubar, warm_start, reference
        As for :func:`pe_pareto` (``reference``: where Σ*_y comes from when a constraint needs it,
        as for :func:`cls`), except that ``data`` may also be a :class:`~graybox.DaskRecord` (or a
        sequence of them): it is reduced to the triangular factor of [Ψ, y] block by block on the
        active Dask scheduler, so a record larger than memory can be used.

    Returns
    -------
    ndarray, shape (K, n_terms), engineering units, in the order of ``lambdas``.

    Raises
    ------
    ValueError
        Some λ1 whose weights do not identify θ (``identified_by``): the records, with the static
        points where λ1 < 1 and the equality constraints, must have a stacked regression of full rank.
        An input held constant leaves θ free at λ1 = 1 (the static points carry no weight there); the
        message names the λ1, the free terms and what data would identify them. Some λ1 whose θ a
        constraint's own check refuses (a free Σ_y of eq. (22) at 1 or above: as λ1 → 0 the points'
        residual (1 − Σ_y)(ȳ − H(ū)) pulls Σ_y towards 1). :func:`pe_pareto` keeps such a λ1 as a
        failed member instead.
    """
    thetas, failures = pe_members(structure, data, static, lambdas=lambdas, constraints=constraints, solver=solver,
                                  solver_options=solver_options, weights=weights, ubar=ubar, warm_start=warm_start,
                                  reference=reference)
    if failures:
        raise ValueError("; ".join(failures.values()))
    return thetas


def _unidentified(st: Structure, d: _Data, pts: StaticPoints, rows: _Rows, lam: np.ndarray,
                  inputs: tuple[str, ...]) -> dict[int, str]:
    """The members whose weights do not identify θ (:func:`identified_by`: at λ1 = 1 the static points carry
    no weight), as {index: reason}."""
    reasons: dict[bool, str] = {}
    for weighted in sorted(set((lam < 1.0).tolist())):
        try:
            # judged in the coordinates of the fit (θ on the centred signals for a centred one, :func:`_data`), the
            # same rank at every offset of the signals
            identified_by(st, d.R1 * d.s, d.N, points=d.run_points(pts) if weighted else None, equalities=rows.V * d.s,
                          inputs=inputs, what="θ" if weighted else "θ at λ1 = 1 (no weight on the static points)")
        except ValueError as exc:
            reasons[weighted] = str(exc)
    # at λ1 = 1 the reason names its λ1 already ("θ at λ1 = 1 …")
    return {i: (f"λ1 = {v:g}: " if v < 1.0 else "") + reasons[bool(v < 1.0)] for i, v in enumerate(lam)
            if bool(v < 1.0) in reasons}


def pe_members(structure, data, static=None, *, lambdas=None, constraints=None, solver="clarabel", solver_options=None,
               weights="mse", ubar=None, warm_start=True, reference="free") -> tuple[np.ndarray, dict[int, str]]:
    """:func:`pe_thetas`' θs (NaN rows for the members whose weights do not identify θ, or whose θ a constraint's
    own check refuses, e.g. a free Σ_y of eq. (22) at 1) and those members' reasons, {index: reason}: what
    :func:`pe_pareto`, ``select_graybox``'s PE rows and the SE starts keep as failed members. ``ValueError``
    (their reasons) when every member is such; the options are :func:`pe_thetas`'."""
    thetas, failures, _ = _pe_fit(structure, data, static, lambdas=lambdas, constraints=constraints, solver=solver,
                                  solver_options=solver_options, weights=weights, ubar=ubar, warm_start=warm_start,
                                  reference=reference)
    return thetas, failures


def _pe_fit(structure, data, static=None, *, lambdas=None, constraints=None, solver="clarabel", solver_options=None,
            weights="mse", ubar=None, warm_start=True, reference="free"
            ) -> tuple[np.ndarray, dict[int, str], tuple[np.ndarray, Mapping[str, float]] | None]:
    """:func:`pe_members`, and for a fit on the centred signals (a closed structure, :func:`_data`) the members'
    parameters there with the offsets (θ_c, offsets), else None: what :func:`pe_pareto` evaluates them by."""
    solver = _check_solver(solver)
    lam = check_lambdas(PE_LAMBDAS if lambdas is None else lambdas)
    warm_start = check_bool(warm_start, "warm_start")
    _check_solver_options(solver_options, solver)
    st, recs, d, pts, ctx, cons, rows, stat, M = _pe_setup(structure, data, static, constraints, weights, ubar,
                                                            reference, centre=True)
    failures = _unidentified(st, d, pts, rows, lam, recs[0].input_names)
    if len(failures) == lam.size:
        raise ValueError(_every_member_failed(failures, lam))
    ok = np.array([i not in failures for i in range(lam.size)])
    w1 = lam / d.N if weights == "mse" else lam.copy()
    w2 = (1.0 - lam) / M if weights == "mse" else 1.0 - lam
    Z = np.full((lam.size, d.s.size), np.nan)
    if ok.any() and solver == "closed":
        Z[ok] = _closed_form(d, stat, rows, w1[ok], w2[ok], M)
        for i in np.flatnonzero(ok & ~np.all(np.isfinite(Z), axis=1)):  # a singular pair: one failed member
            failures[int(i)] = f"λ1 = {lam[i]:g}: {_SINGULAR}"
    elif ok.any():
        qp = _QP(d, stat, cons, ctx, solver, solver_options, M)
        # sweep from λ1 = 1 (least squares) towards the static end, each solve warm-started from
        # its neighbour; results are returned in the caller's order
        # one member's solve that stops at the solver's limit or fails numerically is that member's failure: the
        # sweep goes on (as the SE sweeps' do), and the call fails only when every member failed
        unsolved: list[ValueError] = []
        for i in np.argsort(-lam, kind="stable"):
            if ok[i]:
                try:
                    Z[i] = qp.solve(w1[i], w2[i], warm_start)
                except ValueError as exc:
                    if not getattr(exc, "member", False):
                        raise
                    failures[int(i)] = f"λ1 = {lam[i]:g}: {exc}"
                    unsolved.append(exc)
        qp.warn_inaccurate()
        if len(failures) == lam.size:  # as the one solve's error would be: InfeasibleError where each was one
            kind = InfeasibleError if all(isinstance(e, InfeasibleError) for e in unsolved) else ValueError
            raise kind(_every_member_failed(failures, lam)) from unsolved[0]
    thetas = _raw_pins(cons, ctx, d, d.theta(Z))
    # a member the constraints' own checks refuse is a failed member (a free Σ_y of eq. (22) reaches 1 as λ1 → 0,
    # where the points' linear residual (1 − Σ_y)(ȳ − H(ū)) vanishes): the sweep goes on
    for i in np.flatnonzero(ok):
        if int(i) in failures:  # the closed form's singular pair: no θ to check
            continue
        try:
            _after_solve(cons, ctx, d, Z[i])
        except ValueError as exc:
            failures[int(i)] = f"λ1 = {lam[i]:g}: {exc}"
            thetas[i] = np.nan
    if len(failures) == lam.size:
        raise ValueError(_every_member_failed(failures, lam))
    centred = None
    if d.A is not None:
        tc = Z / d.s
        tc[np.isnan(thetas).any(axis=1)] = np.nan
        centred = (tc, dict(d.offsets))
    return thetas, failures, centred


def _every_member_failed(failures: dict[int, str], lam: np.ndarray) -> str:
    """Every member's reason, each told once: the members failing for the same reason are named together by their
    λ1 (40 members refused by one constraint check read as 40 copies of its message)."""
    groups: dict[str, list[int]] = {}
    for i in sorted(failures):
        prefix = f"λ1 = {lam[i]:g}: "
        reason = failures[i][len(prefix):] if failures[i].startswith(prefix) else failures[i]
        groups.setdefault(reason, []).append(i)
    said = []
    for reason, members in groups.items():
        if len(members) == 1:
            said.append(failures[members[0]])
        else:
            said.append(f"λ1 = {', '.join(f'{lam[i]:g}' for i in members[:3])}{', …' if len(members) > 3 else ''} "
                        f"({len(members)} members): {reason}")
    return "; ".join(said)


def pe_pareto(
    structure: Structure | Model,
    data: Record | Sequence[Record] | Dataset,
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    lambdas: np.ndarray | Sequence[float] | None = None,
    constraints: StaticConstraint | Iterable[StaticConstraint] | None = None,
    solver: str = "clarabel",
    solver_options: Mapping | None = None,
    weights: str = "mse",
    ubar: np.ndarray | None = None,
    eval_static: StaticPoints | None = None,
    warm_start: bool = True,
    threads: int = 1,
    reference: Model | np.ndarray | float | str = "free",
) -> ParetoSet:
    """The PE bi-objective Pareto set (eq. (9)): one model per λ1, evaluated by the shared evaluator.

    Parameters
    ----------
    structure : Structure or Model
        Process terms ((15) without the MA part in the paper).
    data : Record, sequence of Record, or Dataset
        Dynamic identification data. (For a :class:`~graybox.DaskRecord` use
        :func:`pe_thetas`: the members' free-run J_S needs the record in memory.)
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static information; a curve is sampled at ``ubar`` (default: 10 levels over its domain),
        a surface at ``ubar`` of shape (K, m) (default: a grid of 6 levels per input over its
        domain box), as everywhere a curve stands for points.
        Default: the Dataset's static points. Points outside the records' input range are
        welcome (a :class:`StaticRangeWarning` names them once).
    lambdas : array_like, shape (K,), optional
        λ1 values in (0, 1]; λ2 = 1 − λ1. Default: the paper's ``np.logspace(-6, 0, 100)``.
    constraints : optional
        Constraint objects imposed on every member (band, gain, clusters, user cvxpy).
    solver : {"clarabel", "osqp", "closed"}
        cvxpy (one Problem with λ as Parameters, re-solved with warm starts) or eq. (11)
        (equality constraints only).
    weights : {"mse", "sum"}
        Objective normalisation (see :func:`pe_thetas`).
    solver_options : mapping, optional
        Passed to ``cvxpy.Problem.solve`` (overrides graybox's tight defaults). An optimum the solver
        calls inaccurate is kept (with one warning) only where it meets the affine constraints to
        1e-6 of the output's spread; else that member fails, naming them.
    ubar : ndarray, optional
        Where to sample a StaticCurve (shape (K,)) or StaticSurface (shape (K, m)) given as
        ``static``, in input units.
    eval_static : StaticPoints, optional
        Points for the members' J_SF (default: the static points used in the objective).
    warm_start : bool
        Warm-start OSQP from the neighbouring λ (the sweep runs from λ1 = 1 downwards).
    threads : int
        Threads for the batch free runs of the evaluator.
    reference : {"free", "ls", "els"}, Model, ndarray of shape (n_terms,) or float
        Σ*_y for a :class:`~graybox.CurveEquality` among ``constraints`` (see :func:`cls`; default
        ``"free"``: estimated).

    Returns
    -------
    ParetoSet
        θ, λ1, J_1 and J_S on ``data``, J_SF (true static-curve MSE, stable equilibria only) and,
        in ``extra["JSF_QR"]``, the affine static error the problem trades (output units²). A λ1 whose
        weights do not identify θ (e.g. λ1 = 1 on a record whose input is held constant: the static
        points carry no weight there) is a failed member with the reason in ``failures``, as in
        :func:`~graybox.se_pareto`; so is a λ1 whose solve the solver did not finish (stopped at a
        ``max_iter`` or ``time_limit`` of ``solver_options``, failed numerically): the sweep goes on. When
        every λ1 is such, ``ValueError`` naming each reason (see :func:`pe_thetas`).
    """
    threads = check_int(threads, "threads", low=1)
    if eval_static is not None and not isinstance(eval_static, StaticPoints):
        raise TypeError(f"eval_static must be StaticPoints, got {type(eval_static).__name__}")
    if is_dask_data(data):
        raise ValueError("pe_pareto evaluates every member by a free run on the record, which needs it in memory; "
                         "for a DaskRecord call pe_thetas (it reduces the record on the Dask scheduler) and evaluate "
                         "the θs on a record that fits")
    if eval_static is not None:  # they speak of the records' inputs, as the fit's
        _check_point_inputs(as_records(data), eval_static)
    thetas, failures, centred = _pe_fit(structure, data, static, lambdas=lambdas, constraints=constraints,
                                        solver=solver, solver_options=solver_options, weights=weights, ubar=ubar,
                                        warm_start=warm_start, reference=reference)
    st = _process_structure(structure)
    pts = static_points(static, data, ubar=ubar, needed_by="the PE problem")
    ev = pts if eval_static is None else eval_static
    # the J's of the members as fitted, on the centred signals for a closed structure: the raw θ carries the offsets'
    # powers, and its J's moved with the output's zero (at y + 2^20 by 7e-4 relative for a quadratic in y, J_SF^QR 2 %)
    jsf_qr = (qr_static_error(st, thetas, pts) if centred is None else
              qr_static_error(st, centred[0], centred_points(pts, centred[1])))
    return ParetoSet.from_thetas(
        st, thetas, check_lambdas(PE_LAMBDAS if lambdas is None else lambdas), data, ev, method=f"PE ({solver}, {weights})",
        extra={"JSF_QR": jsf_qr}, threads=threads, failures=failures, centred=centred,
    )
