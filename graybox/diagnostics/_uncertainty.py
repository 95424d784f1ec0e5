"""Parameter uncertainty: covariance and confidence intervals of LS, ELS, CLS, PE and SE estimates,
and the confidence band of the static curve and static gain they imply.

Every estimator of graybox minimises a weighted sum of squared errors, possibly under affine
equality constraints, so one formula covers them all. Near the estimate θ̂ (first order), with
H the Hessian of the objective, M the covariance of its gradient (the "meat") and Z a basis of
the null space of the equality constraints that hold at θ̂,

    cov(θ̂) = Z (ZᵀHZ)⁻¹ ZᵀMZ (ZᵀHZ)⁻¹ Zᵀ           (sandwich form).

- **LS**: J = ‖Ψθ − y‖², H = ΨᵀΨ, M = σ² ΨᵀΨ, so cov = σ² (ΨᵀΨ)⁻¹ with σ² = RSS / (N − n).
- **ELS**: a pseudo-linear regression: [θ; c] solves Σ φ(k)ξ(k) = 0 with the extended regressors
  φ = [ψ, ψ_e(ξ)] on the model's own one-step residuals ξ (MA part included), which move with
  [θ; c] through the MA filter. Its covariance is the sandwich (Φᵀ∂)⁻¹ σ²ΦᵀΦ (∂ᵀΦ)⁻¹ with
  ∂(k) = −dξ(k)/d[θ; c] (φ filtered by 1/C(q) for an MA part of plain lags; the same recursion as
  ξ's for products with ξ), σ² from the residuals; the plain LS formula σ²(ΦᵀΦ)⁻¹ is off by
  the filter (with C = 1 + 0.5q⁻¹ its 95 % intervals covered 80–85 % in a Monte Carlo). The process
  block is ``cov`` and the MA block ``noise_cov``.
- **CLS**: the LS formula restricted to the null space of the equality constraints (and of the
  inequality rows active at θ̂, which hold as equalities there), so cov·Aᵀ = 0: every constrained
  combination of θ — e.g. a cluster fixed by eq. (22) — has zero variance; σ² = RSS / (N − n + r)
  with r independent constraints.
- **PE member** (λ1): J = w1‖Ψθ − y‖² + w2‖QRθ − ȳ‖² (w1 = λ1/N, w2 = λ2/N_SF). H is its Hessian;
  M collects the dynamic noise (σ² from least squares on the same data: the noise belongs to the
  data, not to the member) and the static points' noise σ_SF² (``static_sigma``; default: the
  member's own static misfit over its degrees of freedom, in the static equation's units: Σ g_i² at λ1 = 1,
  g_i = ∂s_i/∂ȳ_i, and less as the member comes to meet the points; SE the same in ȳ, M at λ1 = 1). The
  measured ȳ_i sits on both sides of the static equation (eq. (12)), so its effect on θ̂ is differentiated
  through both.
- **SE member** (gradient or GA solution): the Gauss–Newton Hessian JᵀJ of the stacked residuals
  [√(λ1/N) e_sim, √(λ2/N_SF) e_SF] at θ̂ (J from the free run's sensitivity recursion, the Jacobian
  the gradient method uses), with M = σ_S² J_SᵀJ_S + σ_SF² J_SFᵀJ_SF, σ_S² = Σe_sim²/(N − n).

Caveats, said once here and in each docstring: the intervals are first-order (delta method) and
assume the structure is right. LS and CLS intervals assume white equation noise (their coverage
is checked by Monte Carlo in the tests); the SE intervals assume white output errors, so with
coloured simulation errors (equation noise) they are optimistic. A PE or SE member is a biased
estimate of the true θ by design (it trades dynamic fit for static fit): its interval says how
much the *member* would move with another noise realisation, not where the true θ lies.
Towards small λ1 a PE member of a rational structure leans on static points that nearly leave one
direction free (numerator and denominator of eq. (6) scaled together; the measured ȳ sits on both
sides of eq. (12)): θ̂ is then far from linear in the noise and the first-order covariance is off
(in a Monte Carlo like the tests' it matched at λ1 = 0.5 and 0.1 and overstated the spread by up to 20 % at
λ1 = 0.01): use :func:`graybox.bootstrap_decision` or a Monte Carlo there.
Intervals use Student's t with the residual degrees of freedom; where σ_SF is estimated from a handful of static
points (PE and SE without ``static_sigma``), with Satterthwaite's fewer (:attr:`ParameterUncertainty.dof`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Iterable, Sequence

import numpy as np
import scipy.linalg

from ..static._constraints import StaticConstraint, static_cluster_map, static_rows
from ..estimation._prediction_error import (_centred_affine, _centred_context, _cls_setup, _data, _Data, _dynamic,
                                             _pe_setup, _process_structure, centrable, centred_eq_rank)
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface
from ..estimation._decisions import Decision
from ..models._coerce import as_model, records_of, static_info, static_points
from ..models._model import Model
from ..core._least_squares import (binary_exponent, check_rows, one_blas_thread, output_scale, rank_tolerance,
                                   scaled_norm, scaled_norms)
from ..core._simulation_kernels import free_run_sensitivity_blocks, inverse_ma_filter
from ..core._terms import Structure, check_input_names
from ..core._records import Dataset, Record, StaticPoints, StaticRangeWarning, check_units, require_lengths
from ..core._regressors import record_signals, refuse_non_finite_columns, regressor_columns, regressor_matrix
from ._residuals import _model_residuals
from ..estimation._simulation_error import SEProblem
from ..selection._centring import affine_map, centred_data, shift_map
from ..estimation._extended_least_squares import _ma_coefficients, _pure_lags, _shift_offsets
from ..static._analysis import one_input_levels, reached_equilibria, static_theta_gradient
from ..static._linearisation import static_gain_gradient, static_gains, static_powers, static_theta_gradient_of
from ..static._surface_analysis import points_of_inputs, reached_surface, static_surface, surface_theta_gradient
from ..core._reprs import point_texts, share_text
from ..core._validation import (Relocked, check_count, check_band_finite, check_band_values, check_choice, check_fields,
                                check_int, check_level, check_real, check_seed, frozen, warn)

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = [
    "ParameterUncertainty",
    "UncertaintyWarning",
    "ls_uncertainty",
    "cls_uncertainty",
    "pe_uncertainty",
    "se_uncertainty",
    "StaticCurveBand",
    "static_curve_band",
    "StaticSurfaceBand",
    "static_surface_band",
    "theta_draws",
]


#: ls_uncertainty takes an ELS model as the estimate on its data when the share of its one-step residuals
#: along the extended regressors is at most this: ~1e-7 at ELS's fixed point (tol 1e-6), 1e-4 for a run
#: stopped at its cap while its residuals still changed by 2e-3, 0.1-0.4 for the estimate of another record.
ELS_STATIONARY_RTOL = 1e-2


#: How a band (static curve, free run) is taken from a parameter covariance: to first order, or by draws.
BAND_METHODS = ("delta", "monte-carlo")
#: Fewest Monte Carlo draws a band is taken from.
MIN_DRAWS = 10


def check_band_draws(method: str, n_samples: int, share: np.ndarray | float, share_name: str) -> None:
    """A band's method, its number of draws and the share of them left out, checked against each other (a band
    made here meets them; a hand-edited file is held to them): the delta method draws nothing (n_samples 0, none
    left out), a Monte Carlo band at least :data:`MIN_DRAWS`, and leaves out a whole number of them."""
    check_choice(method, "method", BAND_METHODS)
    n = check_int(n_samples, "n_samples", low=0)
    s = np.asarray(share, float)
    if np.any(~np.isfinite(s) | (s < 0) | (s > 1)):
        raise ValueError(f"{share_name} must hold shares of the draws, in [0, 1]")
    if method == "delta":
        if n != 0:
            raise ValueError(f"n_samples must be 0 for the delta method (it draws nothing), got {n}")
        if np.any(s != 0):
            raise ValueError(f"{share_name} must be 0 for the delta method (it draws nothing, so leaves none out)")
        return
    if n < MIN_DRAWS:
        raise ValueError(f"n_samples must be >= {MIN_DRAWS} for the Monte Carlo method, got {n}")
    counts = s * n
    if np.any(np.abs(counts - np.round(counts)) > 1e-9 * n):
        raise ValueError(f"{share_name} must be shares of the n_samples = {n} draws (whole numbers of them), got "
                         f"{s[np.abs(counts - np.round(counts)) > 1e-9 * n].ravel()[:3].tolist()}")


class UncertaintyWarning(UserWarning):
    """The uncertainty was computed, but at a point where its assumptions are doubtful."""


def warn_dropped_draws(what: str, undefined: np.ndarray) -> None:
    """Say (:class:`UncertaintyWarning`) that Monte Carlo draws reaching no equilibrium were left out of a band
    (``undefined``: their share at each level, NaN where none was drawn), as ``simulation_band`` says it of
    draws that diverge: the band is then narrower than the parameters' uncertainty."""
    shares = np.asarray(undefined, float)
    worst = float(np.nanmax(shares)) if np.isfinite(shares).any() else 0.0
    if worst > 0:
        where = int(np.sum(shares > 0))
        warn(f"{what}: up to {share_text(worst)} of the Monte Carlo draws reach no equilibrium (at {where} of {shares.size} "
             "levels) and are left out of the band there, which is therefore narrower than the parameters' "
             "uncertainty (.undefined says how many at each level)", UncertaintyWarning)


@dataclass(frozen=True, eq=False)
class ParameterUncertainty(Relocked):
    """Covariance and confidence intervals of a model's process parameters.

    Attributes
    ----------
    model : Model
        The estimate θ̂ (engineering units).
    cov : ndarray, shape (n_terms, n_terms)
        Covariance of θ̂, engineering units (θ_i θ_j); symmetric positive semidefinite, singular
        along constrained directions.
    level : float
        Confidence level of :attr:`intervals` (0.95).
    dof : int
        Degrees of freedom of Student's t (the intervals, the bands, the Monte Carlo draws): the residual ones
        (rows minus free parameters); for a PE or SE member whose σ_SF is estimated from its static misfit (no
        ``static_sigma``), fewer: Satterthwaite's for the variance that mixes the records' σ² with σ_SF² of a
        handful of points, the least over the parameters and the static curve at the points (so terms the records
        alone decide get intervals wider than they need).
    sigma2 : float
        Noise variance of the dynamic data, output units² (equation noise for LS/ELS/CLS/PE,
        simulation error for SE).
    method : str
        ``"LS"``, ``"ELS"``, ``"CLS"``, ``"PE λ1=…"`` or ``"SE λ1=…"``.
    constraints : ndarray, shape (r, n_terms)
        Rows A (engineering units) of the equalities that hold exactly at θ̂ (with the active
        inequalities); ``cov @ A.T`` is zero.
    noise_cov : ndarray, shape (n_noise, n_noise)
        Covariance of the MA parameters (ELS); empty otherwise.
    static_sigma2 : float
        Variance of the static points' ȳ used (PE and SE), output units²; NaN otherwise.
    cov_factor : ndarray, shape (k, n_terms), optional
        F with ``cov`` = FᵀF, in the units of θ, as the estimators' scaled coordinates give it, stored as
        its triangular factor in the terms' order by degree (the same draws of the same models at every
        offset and unit of the signals, where those map θ linearly; k is then at most n_terms).
        Contractions gᵀ cov g (bands, cluster variances) are taken as ‖F g‖²: ``cov`` itself holds
        its small directions only to eps × its largest entry, which lost 1 % of a static band's
        std at an input offset of 1e4 ± 10 (cond of the scaled regressors 3e7). None (a covariance
        given by hand, or read from an older file): contractions use ``cov``.
    """

    model: Model
    cov: np.ndarray
    level: float
    dof: int
    sigma2: float
    method: str
    constraints: np.ndarray
    noise_cov: np.ndarray
    static_sigma2: float = float("nan")
    cov_factor: np.ndarray | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        # the intervals' t quantile needs both (a file loads through here: graybox.io)
        check_level(self.level)
        check_int(self.dof, "dof (degrees of freedom)", low=1)
        n = self.model.n_params
        cov = frozen(self.cov)
        if cov.shape != (n, n):
            raise ValueError(f"cov must have shape ({n}, {n}), got {cov.shape}")
        sd = _check_cov(cov)
        object.__setattr__(self, "cov", cov)
        # shapes as they are, never reshaped: a (3, 2) table read as (2, 3) moves its numbers to other terms
        A = frozen(self.constraints)
        if A.size == 0:  # no constraint row (a JSON file gives back [] for one)
            A = frozen(np.zeros((0, n)))
        if A.ndim != 2 or A.shape[1] != n:
            raise ValueError(f"constraints must have shape (r, {n}), one row of the {n} terms per constraint, got "
                             f"{A.shape}")
        if not np.all(np.isfinite(A)):
            raise ValueError("constraints has non-finite entries")
        object.__setattr__(self, "constraints", A)
        ne = len(self.model.noise_structure)
        nc = frozen(self.noise_cov)
        if nc.size == 0 and ne == 0:
            nc = frozen(np.zeros((0, 0)))
        if nc.shape != (ne, ne):
            raise ValueError(f"noise_cov must have shape ({ne}, {ne}), the covariance of the model's {ne} MA "
                             f"parameter(s), got {nc.shape}")
        _check_cov(nc, "noise_cov")
        object.__setattr__(self, "noise_cov", nc)
        check_real(self.sigma2, "sigma2 (the noise variance)", low=0)
        if not np.isnan(self.static_sigma2):  # NaN: no static points in the estimate
            check_real(self.static_sigma2, "static_sigma2 (the static points' variance, or NaN)", low=0)
        if self.cov_factor is not None:
            F = frozen(self.cov_factor)
            if F.size == 0:  # every θ fixed by constraints: no row (a JSON file gives back [] for it)
                F = frozen(np.zeros((0, n)))
            if F.ndim != 2 or F.shape[1] != n:
                raise ValueError(f"cov_factor must have shape (k, {n}), got {F.shape}")
            _check_factor(F, cov, sd)
            object.__setattr__(self, "cov_factor", frozen(_canonical_factor(F, self.model.structure, A)))

    def contract(self, G: np.ndarray) -> np.ndarray:
        """The variances gᵀ cov g of the linear functions g of θ in the rows of ``G``: ‖F g‖² through
        :attr:`cov_factor` where there is one (accurate to eps × cond of the estimate's scaled problem, where
        contracting ``cov`` is accurate to eps × cond²).

        Parameters
        ----------
        G : ndarray, shape (M, n_terms), or (n_terms,) for one
            Each row a linear function g of θ (engineering units).

        Returns
        -------
        ndarray, shape (M,)
            Each >= 0, in the units of gᵀθ, squared.
        """
        G = np.atleast_2d(np.asarray(G, float))
        if self.cov_factor is not None:
            return np.einsum("ij,ij->i", G @ self.cov_factor.T, G @ self.cov_factor.T)
        return np.clip(np.einsum("ij,jk,ik->i", G, self.cov, G), 0, None)

    def std_of(self, G: np.ndarray) -> np.ndarray:
        """The standard deviations √(gᵀ cov g) of the rows of ``G``: each row over the power of two above its
        largest |entry| (exact), so that a deviation within the float range is one where its variance is not (a
        static curve's at ū = 1e200, about 1e198, read inf through its variance 1e396).

        Parameters
        ----------
        G : ndarray, shape (M, n_terms), or (n_terms,) for one
            Each row a linear function g of θ (engineering units).

        Returns
        -------
        ndarray, shape (M,)
            Each >= 0, in the units of gᵀθ (NaN for a row with an infinite entry).
        """
        G = np.atleast_2d(np.asarray(G, float))
        e = binary_exponent(np.max(np.abs(G), axis=1, initial=0.0))
        # a gradient beyond the float range (inf) gives NaN here, which the bands name (_refuse_overflow)
        with np.errstate(over="ignore", invalid="ignore"):
            return np.ldexp(np.sqrt(self.contract(np.ldexp(G, -e[:, None]))), e)

    @property
    def theta(self) -> np.ndarray:
        """θ̂, shape (n_terms,)."""
        return self.model.theta

    @property
    def std(self) -> np.ndarray:
        """Standard deviations √diag(cov), shape (n_terms,) (0 for a constrained parameter)."""
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    @property
    def quantile(self) -> float:
        """Student's t quantile of the two-sided interval at :attr:`level` with :attr:`dof`."""
        from scipy import stats  # slow to import: loaded where used
        return float(stats.t.ppf(0.5 + self.level / 2, self.dof))

    @property
    def intervals(self) -> np.ndarray:
        """Confidence intervals θ̂ ± t·std, shape (n_terms, 2) (low, high)."""
        h = self.quantile * self.std
        return np.column_stack([self.theta - h, self.theta + h])

    @property
    def noise_std(self) -> np.ndarray:
        """Standard deviations of the MA parameters, shape (n_noise,)."""
        return np.sqrt(np.clip(np.diag(self.noise_cov), 0.0, None))

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix of θ̂, shape (n_terms, n_terms) (NaN rows for constrained parameters)."""
        s = self.std
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.cov / np.outer(s, s)

    def covers(self, theta: np.ndarray) -> np.ndarray:
        """Which components of ``theta`` lie in their interval (to the round-off of the estimate: a constrained
        parameter's interval has zero width).

        Parameters
        ----------
        theta : ndarray, shape (n_terms,)
            Finite parameters, engineering units (e.g. the true ones of a simulated plant).

        Returns
        -------
        ndarray of bool, shape (n_terms,)
        """
        th = np.asarray(theta, float)
        if th.shape != self.theta.shape:
            raise ValueError(f"theta must have shape {self.theta.shape} (one value per term), got {th.shape}")
        if not np.all(np.isfinite(th)):  # NaN compared False: it read as a value outside its interval
            raise ValueError(f"theta must be finite, got {th[~np.isfinite(th)][0]} for term "
                             f"{self.model.structure[int(np.flatnonzero(~np.isfinite(th))[0])]}")
        iv = self.intervals
        # a parameter the constraints fix has an interval of zero width, and a value equal to it up to the
        # round-off of the estimate (an ulp or so) is in it, not outside
        slack = 64 * np.finfo(float).eps * (np.abs(th) + np.abs(self.theta))
        return (th >= iv[:, 0] - slack) & (th <= iv[:, 1] + slack)

    def with_level(self, level: float) -> "ParameterUncertainty":
        """The same covariance with intervals at another confidence level.

        Parameters
        ----------
        level : float
            Confidence level, in (0, 1) (e.g. 0.95).

        Returns
        -------
        ParameterUncertainty
        """
        level = check_level(level)
        return ParameterUncertainty(self.model, self.cov, level, self.dof, self.sigma2, self.method,
                                    self.constraints, self.noise_cov, self.static_sigma2, self.cov_factor)

    def cluster_cov(self) -> np.ndarray:
        """Covariance of the cluster coefficients Σ = Rθ.

        Returns
        -------
        ndarray, shape (n_clusters, n_clusters)
            R cov Rᵀ, in the clusters' units (products of their pairs'), clusters in ``cluster_map()`` order.
        """
        R = self.model.cluster_map().R
        if self.cov_factor is not None:
            FR = self.cov_factor @ R.T
            return FR.T @ FR
        return R @ self.cov @ R.T

    def cluster_frame(self) -> pd.DataFrame:
        """The clusters' estimates and their uncertainty as a table.

        Returns
        -------
        pandas.DataFrame
            One row per cluster (index ``cluster``, its name): ``value`` (Σ), ``std`` (0 for a constrained
            cluster), ``low`` and ``high`` (the interval at :attr:`level`), in the cluster's units.
        """
        import pandas as pd

        cm = self.model.cluster_map()
        sig = cm.R @ self.theta
        sd = np.sqrt(self.contract(cm.R))
        h = self.quantile * sd
        return pd.DataFrame({"value": sig, "std": sd, "low": sig - h, "high": sig + h},
                            index=pd.Index(cm.names, name="cluster"))

    def to_frame(self) -> pd.DataFrame:
        """The parameters' estimates and their uncertainty as a table.

        Returns
        -------
        pandas.DataFrame
            One row per term (index ``term``): ``theta``, ``std``, ``low`` and ``high`` (the interval at
            :attr:`level`), in the parameter's engineering units, and ``rel std`` (std / |θ|, dimensionless).
        """
        import pandas as pd

        iv = self.intervals
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = self.std / np.abs(self.theta)
        return pd.DataFrame({"theta": self.theta, "std": self.std, "low": iv[:, 0], "high": iv[:, 1],
                             "rel std": rel}, index=pd.Index([str(t) for t in self.model.structure], name="term"))

    def __repr__(self) -> str:
        return (f"ParameterUncertainty({self.method}, model={self.model.name!r}, n_params={self.model.n_params}, "
                f"constraints={self.constraints.shape[0]}, dof={self.dof}, level={self.level:g})")


# --------------------------------------------------------------------------------------------
# the one formula
# --------------------------------------------------------------------------------------------
#: How far (relative to std_i · std_j) a covariance may be from symmetric, or from its factor's FᵀF: the
#: estimators' two agree to ~1e-15, a covariance edited by hand (or replaced without its factor) is far off.
COV_RTOL = 1e-6


def _check_cov(cov: np.ndarray, name: str = "cov") -> np.ndarray:
    """``ValueError`` unless ``cov`` (named ``name``) can be a covariance (finite, variances ≥ 0, symmetric,
    correlations in [−1, 1], to :data:`COV_RTOL`); its standard deviations."""
    if not np.all(np.isfinite(cov)):
        raise ValueError(f"{name} has non-finite entries at {np.argwhere(~np.isfinite(cov)).tolist()[:3]}")
    var = np.diag(cov)
    if np.any(var < 0):
        raise ValueError(f"{name} has negative variances at {np.flatnonzero(var < 0).tolist()}: not a covariance")
    sd = np.sqrt(var)
    bound = (1 + COV_RTOL) * np.outer(sd, sd)
    bad = np.argwhere((np.abs(cov - cov.T) > COV_RTOL * np.outer(sd, sd)) | (np.abs(cov) > bound))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise ValueError(f"{name} is no covariance: its entry ({i}, {j}) = {cov[i, j]:.6g} is not symmetric or exceeds "
                         f"std_{i} · std_{j} = {sd[i] * sd[j]:.6g} (a correlation beyond ±1)")
    return sd


def _check_factor(F: np.ndarray, cov: np.ndarray, sd: np.ndarray) -> None:
    """``ValueError`` unless FᵀF is ``cov`` (to :data:`COV_RTOL` of std_i · std_j): bands and contractions read the
    factor, the intervals ``cov``, so a covariance changed without its factor would give each its own answer."""
    if not np.all(np.isfinite(F)):
        raise ValueError("cov_factor has non-finite entries")
    with np.errstate(over="ignore", invalid="ignore"):
        FtF = F.T @ F
        sc = np.maximum(sd, np.sqrt(np.diag(FtF)))
        # a factor whose FᵀF overflows is no factor of a finite cov (its tolerance, inf too, let it pass)
        off = ~np.isfinite(FtF) | ~(np.abs(FtF - cov) <= COV_RTOL * np.outer(sc, sc))
    if off.any():
        i, j = (int(v) for v in np.argwhere(off)[0])
        raise ValueError(f"cov_factor F is not a factor of cov: (FᵀF)[{i}, {j}] = {FtF[i, j]:.6g} against cov[{i}, {j}] "
                         f"= {cov[i, j]:.6g} (a covariance changed without its factor?); give cov_factor=None with a "
                         "covariance of your own")


def _canonical_factor(F: np.ndarray, structure, constraints: np.ndarray | None = None) -> np.ndarray:
    """The one factor R of cov = FᵀF that Monte Carlo draws θ̂ + zR take, whoever computed F.

    Each estimator's F comes from its own coordinates, so one seed drew other models when u or y moved
    by an offset or changed unit. Units map θ' = Aθ + t: A diagonal for a unit's scale, and for an offset
    of a structure closed under shifts (:func:`~graybox.selection._centring.shift_map`) A mixes a term only
    into its divisors. With the terms ordered by degree, highest first, every such A is lower triangular
    with a positive diagonal, and so is the step from one Cholesky factor to the other: R, upper triangular
    in that order with a nonnegative diagonal (QR of F, never forming cov: F's accuracy is kept), moves to
    R Aᵀ, and θ̂' + zRAᵀ is the same model as θ̂ + zR. Idempotent to the bit (a triangular F is its own R).

    Where equality ``constraints`` (rows r × n) leave k < n directions and pin a combination of the first k
    terms in that order (CLS on static points pins u(k−1)y(k−1) of a closed structure), F's leading columns
    are dependent, the plain QR has a zero on its diagonal and keeps the estimator's rows as they came. R is
    then the echelon factor: row i starts at the i-th column not spanned by those before it (read off the
    constraints, exactly: :func:`_free_pivots`), there positive, zero (to round-off) before it; R Aᵀ is again one.
    """
    k, n = F.shape
    if k == 0 or n == 0:
        return F
    order = sorted(range(n), key=lambda j: -structure[j].degree)  # stable: ties keep the structure's order
    P = F[:, order]
    piv = None if constraints is None or k >= n else _free_pivots(constraints[:, order], k)
    if piv is not None and piv != list(range(k)):
        return _echelon_factor(P, piv, order)
    if k <= n and np.array_equal(P, np.triu(P)) and np.all(np.diag(P) >= 0):
        return F  # canonical already (a file read back): kept to the bit
    R = np.linalg.qr(P, mode="r")
    sign = np.where(np.diag(R) < 0, -1.0, 1.0)
    out = np.empty_like(R)
    out[:, order] = R * sign[:, None] + 0.0  # + 0.0: no negative zeros below the diagonal
    return out


def _free_pivots(C: np.ndarray, k: int) -> list[int] | None:
    """The columns at which an echelon basis of {v: C v = 0} starts its rows (ascending), or None where that
    space is not k-dimensional. Column j is not one exactly where C's column j adds to the rank of the
    columns right of it (the orthogonal complement's echelon from the right): decided on C, whose pinned
    directions are exact, where F holds them only as round-off of zero. Each column is judged relative to
    its own norm (units scale columns), with rows normalised and the rank rule of :func:`_null_space`."""
    norms = scaled_norms(C, axis=1)  # rows of a static point's ȳ about 2^512 overflowed in their squares
    C = C[norms > 0] / norms[norms > 0, None]
    n = C.shape[1]
    basis = np.zeros((C.shape[0], 0))
    pinned = []
    for j in range(n - 1, -1, -1):
        c = C[:, j]
        nc = float(np.linalg.norm(c))
        if nc == 0.0:
            continue
        r = c - basis @ (basis.T @ c)
        r -= basis @ (basis.T @ r)  # twice is enough (Kahan)
        nr = float(np.linalg.norm(r))
        if nr > 1e-10 * nc:
            pinned.append(j)
            basis = np.column_stack([basis, r / nr])
    free = [j for j in range(n) if j not in pinned]
    return free if len(free) == k else None


def _echelon_factor(P: np.ndarray, piv: list[int], order: list[int]) -> np.ndarray:
    """The echelon factor of PᵀP (P: a k × n factor with its columns in ``order``) whose row i starts at column
    ``piv[i]``, positive there (Householder reflections column by column), returned in the structure's order."""
    R = np.array(P, float)
    k = R.shape[0]
    if all(np.all(R[i + 1:, p] == 0) and R[i, p] > 0 for i, p in enumerate(piv)):
        out = np.empty_like(R)
        out[:, order] = R
        return out  # echelon already (a file read back): kept to the bit
    for i, p in enumerate(piv):
        x = R[i:, p].copy()
        nx = float(np.linalg.norm(x))
        if nx == 0.0:
            continue
        v = x
        # x onto +‖x‖ e1 without cancellation in x0 − ‖x‖
        v[0] = -float(x[1:] @ x[1:]) / (x[0] + nx) if x[0] > 0 else x[0] - nx
        vv = float(v @ v)
        if vv > 0:
            R[i:] -= np.outer(v, (2.0 / vv) * (v @ R[i:]))
        R[i, p] = nx
        R[i + 1:, p] = 0.0
    # left of each row's start: round-off of zero, kept (the pinned directions' variances are that round-off, and
    # FᵀF must stay the covariance there too)
    out = np.empty((k, R.shape[1]))
    out[:, order] = R + 0.0
    return out


def _equality_rank(cons: list[StaticConstraint], ctx, A: np.ndarray) -> int | None:
    """The estimator's rank of the equality rows where ``A`` holds them alone (no active inequality), else None: at
    u + 3e3, y + 2e5 the raw 1e-10 cut left a direction the estimator had pinned, and the CLS estimate was refused
    as "not the optimum of this problem"."""
    n_eq = sum(r.n_eq for c in cons if (r := c.affine(ctx)) is not None)
    return centred_eq_rank(cons, ctx) if A.shape[0] == n_eq else None


def _null_space(A: np.ndarray, n: int, rank: int | None = None) -> tuple[np.ndarray, int]:
    """Orthonormal basis of {z: A z = 0} (rows normalised first) and the rank of A; ``rank``: the rank the estimator
    decided for these rows (:func:`~graybox.estimation._prediction_error.centred_eq_rank`), else the 1e-10 cut."""
    if A.shape[0] == 0:
        return np.eye(n), 0
    norms = scaled_norms(A, axis=1)  # rows of a static point's ȳ about 2^512 overflowed in their squares
    A = A[norms > 0] / norms[norms > 0, None]
    if A.shape[0] == 0:
        return np.eye(n), 0
    _, S, Vt = np.linalg.svd(A, full_matrices=True)
    # the equality rows' rank as the estimator reduced them (estimation._prediction_error._reduce_eq), not the
    # regression's (rank_tolerance): the same constraints must leave θ the same directions to move in
    r = int(np.sum(S > 1e-10 * S[0])) if rank is None else min(rank, S.size)
    return Vt[r:].T, r


def _sandwich(Z: np.ndarray, A: np.ndarray, G: np.ndarray, what: str, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """Z (ZᵀHZ)⁻¹ ZᵀMZ (ZᵀHZ)⁻¹ Zᵀ with H = AᵀA and M = GᵀG, from the factors (never forming H), and
    a square-root factor F of it (k × n, the same matrix as FᵀF).

    With AZ = U S Vᵀ the result is WᵀW, W = (GZV S⁻²)(ZV)ᵀ: positive semidefinite by construction,
    and accurate to about eps·cond(AZ) where forming H would lose eps·cond(AZ)² (an SE Jacobian of
    a slow plant can have cond ≈ 1e9). F = R_G S⁻²(ZV)ᵀ with R_G the triangular factor of GZV keeps
    that accuracy for a contraction ‖F g‖, which the matrix itself has only relative to its largest
    entry. ValueError when AZ is rank deficient (not identifiable), judged by the one rank rule
    (:func:`~graybox.core._least_squares.rank_tolerance`, A standing for ``rows`` regression rows): what the
    estimators call identified has a covariance here.
    """
    n = A.shape[1]
    if Z.shape[1] == 0:
        return np.zeros((n, n)), np.zeros((0, n))
    AZ = A @ Z
    if not (np.all(np.isfinite(AZ)) and np.all(np.isfinite(G))):
        raise ValueError(f"{what}: non-finite derivatives; the covariance is undefined here")
    # one BLAS thread: a threaded SVD of a thin matrix mostly waits for threads on a busy machine (BENCHMARKS.md)
    with one_blas_thread():
        _, S, Vt = np.linalg.svd(AZ, full_matrices=False)
        if S.size < Z.shape[1] or S[0] == 0 or S[-1] <= rank_tolerance(S[0], rows, S.size):
            raise ValueError(f"{what}: the parameters are not identifiable from these data and constraints "
                             "(singular information matrix), so they have no finite covariance")
        ZV = Z @ Vt.T
        GZV = G @ ZV
        W = (GZV / S**2) @ ZV.T
        return W.T @ W, (np.linalg.qr(GZV, mode="r") / S**2) @ ZV.T


def _check_variance_units(y_scale: float, what: str) -> None:
    """``ValueError`` where the output's spread squared (output units², the units of σ² and of the output's terms'
    variances) is no normal float: at y about 1e-211 σ² underflowed to 0 and the covariance returned was 0 (every
    parameter known exactly, said of noisy data), at y about 1e180 it overflowed."""
    with np.errstate(over="ignore", under="ignore"):
        sq = float(np.float64(y_scale) ** 2)
    if not np.finfo(float).tiny <= sq < np.inf:
        raise ValueError(f"{what}: the noise variance σ² and the covariance are in output units², and the output's "
                         f"spread ({y_scale:.3g}) squared is beyond the float range in these units: rescale the "
                         "signals (other units) and estimate again")


def _to_theta(cov_z: tuple[np.ndarray, np.ndarray], s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Covariance and its factor in z = s ⊙ θ → in θ (one scale at a time: s_i s_j of a column of 2^-800 was 0, of
    2^600 inf, where the entry is a float; an entry beyond the float range is refused, named,
    by :func:`_refuse_beyond_float_range`)."""
    with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
        return cov_z[0] / s[:, None] / s[None, :], cov_z[1] / s


def _factor_cov(F: np.ndarray) -> np.ndarray:
    """FᵀF, each column of F over the power of two above its largest |entry| (exact) and mapped back: a column of
    a parameter's standard deviation about 2^600 overflowed in the product (an entry beyond the float range there is
    refused, named, by :func:`_refuse_beyond_float_range`)."""
    e = binary_exponent(np.max(np.abs(F), axis=0, initial=0.0))
    Fs = np.ldexp(F, -e)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        return np.ldexp(Fs.T @ Fs, e[:, None] + e[None, :])


def _pinned_zeroed(cov: np.ndarray, F: np.ndarray, Z: np.ndarray, s: np.ndarray,
                   fc: "_FitCoordinates") -> tuple[np.ndarray, np.ndarray]:
    """The covariance and its factor (in θ) with the parameters the constraints fix exactly set to variance 0. θ_j is
    fixed where its functional in the fit's coordinates z (θ = A (z / s) + t, A the centring map of ``fc``, the
    identity without) is orthogonal to the directions Z the constraints leave z free: the cosine between them at
    most 1e-9. Judged in z, where every column is in output units (the rows the estimator's null space came from),
    it is the same in any units; their variance is otherwise the projection's round-off (a standard deviation 1e-15
    of the others'), which at y × 2^-505 fell below the float range and was refused as no float. On the raw rows with
    each column over its norm the verdict moved with the units: at y × 2^60 a curve's row 2^60 θ_y + θ_u = c left
    y(k-1)'s entry 2^-60 of its column's, and y(k-1), free, was given variance 0."""
    n = F.shape[1]
    if Z.shape[1] == n:
        return cov, F  # nothing constrained
    V = (fc.d.A if fc.centred else np.eye(n)) / s[None, :]  # row j: θ_j as a functional of z
    norms = scaled_norms(V, axis=1)
    ok = norms > 0
    V[ok] = np.ldexp(V[ok], -binary_exponent(norms[ok])[:, None])  # rows over a power of two of their norms (exact)
    cosine = scaled_norms(V @ Z, axis=1) / np.where(ok, scaled_norms(V, axis=1), 1.0)
    pinned = ok & (cosine <= 1e-9)
    if not pinned.any():
        return cov, F
    cov, F = np.array(cov, float), np.array(F, float)
    cov[pinned, :] = cov[:, pinned] = 0.0
    F[:, pinned] = 0.0
    return cov, F


def _refuse_beyond_float_range(F: np.ndarray, terms: Sequence, what: str) -> None:
    """``ValueError`` naming the terms whose parameter's variance (the square of its standard deviation, F's column
    norm, in the parameter's units²) is no float in these units: at u × 2^-300 u(k-1)²'s standard deviation is about
    2^589 and its variance 2^1178 (inf), at u × 2^400 about 2^-1622 (0: the parameter known exactly); a subnormal of
    fewer than 30 bits counts as none."""
    sd = scaled_norms(np.asarray(F, float), axis=0)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        var = sd * sd
    far = np.flatnonzero((sd > 0) & ~(np.isfinite(var) & (var >= np.ldexp(np.finfo(float).tiny, -22))))
    if far.size:
        names = ", ".join(str(terms[j]) if j < len(terms) else f"noise parameter {j - len(terms)}" for j in far)
        k = int(binary_exponent(sd[far[0]])) if np.isfinite(sd[far[0]]) else None
        about = f" (a standard deviation about 2^{k}, a variance about 2^{2 * k})" if k is not None else ""
        raise ValueError(f"{what}: the variance of the parameter of {names}{about} is beyond the float range in "
                         "these units: rescale the signals (other units) and estimate again")


def _check_stationary(Z: np.ndarray, A: np.ndarray, r: np.ndarray, rest2: float, size: float, what: str,
                      hint: str, rows: int, rtol: float = 1e-6, z: np.ndarray | None = None,
                      z_round: np.ndarray | None = None) -> None:
    """θ̂ must be the optimum of the problem whose covariance is asked for.

    The objective is ‖r‖² + rest2 with residuals r = A z − c (A in the scaled coordinates z, rest2
    the part no parameter reaches), and θ may move along the columns of Z. ‖Uᵀr‖, U an orthonormal
    basis of AZ's columns, is the square root of what a step could still remove from the objective:
    it must be at most ``rtol`` (1e-6) of the whole residual norm (a units-free angle, unchanged by the
    output's offset or scale, which a gradient measured against |Aᵀy| was not), or at the round-off level
    of the fit, 1e-11 of ``size`` (the fitted values' and targets' norms). AZ's range is taken by the one
    rank rule (A standing for ``rows`` regression rows). With ``z`` (the estimate in A's coordinates) the
    round-off of forming A z, ‖A‖ ‖z‖ eps, is allowed too: where the terms cancel (u = −50 ± 0.0015 with a u² term,
    ‖z‖ = 6e8 for fitted values of order 1) an estimate accurate to its last digits left 2e-6 of its residual
    along the free directions and was refused as no optimum. ``z_round``: the round-off of each entry of ``z``
    where z was mapped from θ (the centred parameters of a closed structure, :class:`_FitCoordinates`), allowed too.
    """
    if Z.shape[1] == 0:
        return  # the constraints fix θ: nothing left to optimise
    U, S, _ = np.linalg.svd(A @ Z, full_matrices=False)
    # norms over powers of two (scaled_norm): residuals and fitted values about 2^516 (y × 2^512) overflowed in
    # their squares where the norms and the variances are floats
    g = scaled_norm(U[:, S > rank_tolerance(S[0], rows, S.size)].T @ r) if S.size and S[0] > 0 else 0.0
    whole = float(np.hypot(scaled_norm(r), np.sqrt(rest2)))
    # (‖z‖ over a power of two too: numpy's overflowed at z about 1e154, and an infinite allowance passed any θ)
    cancel = 0.0 if z is None else 1e-15 * float(np.linalg.norm(A, 2) * scaled_norm(z))
    if z_round is not None:
        cancel += scaled_norm(np.abs(A) @ z_round)
    if not np.isfinite(g) or g > rtol * whole + 1e-11 * size + cancel:
        raise ValueError(f"{what}: the model's θ is not the optimum of this problem (a fraction "
                         f"{g / max(whole, 1e-300):.1e} of its residual lies along the directions θ may move); {hint}")


def _size(*parts: np.ndarray) -> float:
    """The magnitude of a fit's parts: what round-off is measured against."""
    return float(sum(scaled_norm(np.ravel(p)) for p in parts))


def _check_level(level: float) -> float:
    return check_level(level)


def _lambda_arg(model: object, lambda1: float | None, what: str) -> float:
    if lambda1 is None:
        if isinstance(model, Decision) and np.isfinite(model.lambda1):
            lambda1 = model.lambda1
        else:
            raise ValueError(f"{what} needs lambda1, the weight the member was estimated with (a Decision carries it)")
    return check_real(lambda1, "lambda1", low=0, high=1, low_open=True)


def _equalities(cons: list[StaticConstraint], ctx, theta: np.ndarray, s: np.ndarray, what: str,
                fit: np.ndarray, rows: int, scale: float, affine=None,
                theta_round: np.ndarray | None = None) -> np.ndarray:
    """Equality rows and the inequality rows active at θ (engineering units); user constraints refused.

    A row is measured in the estimators' scaled coordinates z = s ⊙ θ (each z_j in output units): a
    residual measured against |A||θ| alone was its own scale for a cluster of one term set to 0 (eq.
    (22)'s Σ_yu), which a QP leaves at round-off, not at 0. An equality holds, and an inequality is
    active, when the fit need change by at most 1e-6 of ``scale`` (the output's
    spread), or by the round-off of z, to reach its hyperplane: the distance in the metric ‖``fit`` Δz‖ (``fit``: the problem's
    stacked factors, standing for ``rows`` regression rows), which is the solvers' own (their step is
    in units of the spread, in the basis that whitens these factors). Unlike a Euclidean distance in z,
    it does not move with the units or offsets of u and y: against 1e-6 ‖z‖, with u = 1e4 ± 1
    (‖z‖ = 3e7) every row of a band 0.06 wide counted as active, and the covariance was that of a
    model held on all of them. Where the factors leave θ free (not identifiable without the
    constraints) the Euclidean rule is kept: within 1e-6 ‖z‖ of each hyperplane. ``affine(c)``: a
    constraint's rows in the coordinates of ``theta`` (default ``c.affine(ctx)``; those of the centred
    parameters for a fit on the centred signals, :class:`_FitCoordinates`), with ``theta_round`` the round-off of
    each entry of ``theta`` mapped there, allowed too.
    """
    n = theta.size
    z = theta * s
    znorm = scaled_norm(z)  # over a power of two: numpy's norm of z about 1e154 overflowed, and every row was near
    tol = 1e-6 * max(znorm, 1e-300)
    Rf = np.linalg.qr(np.asarray(fit, float), mode="r")
    sv = np.linalg.svd(Rf, compute_uv=False)
    whiten = Rf if sv.size == n and sv[0] > 0 and sv[-1] > rank_tolerance(sv[0], rows, n) else None
    dz = None if theta_round is None else theta_round * s  # the round-off of z (a θ mapped to centred parameters)

    def gap(A: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """How far the fit is from each inequality's hyperplane (output units), or the Euclidean distance in z;
        and how far the round-off of z (``dz``) can move it (zeros without)."""
        if whiten is None:
            return off(A, r)
        # min ‖Rf Δz‖ subject to a·Δz = r is |r| / ‖Rf⁻ᵀ a‖
        W = scipy.linalg.solve_triangular(whiten, (A / s).T, trans="T")
        nrm = np.linalg.norm(W, axis=0)
        return _scaled(A, r, np.where(nrm > 0, nrm, 1.0))

    def off(A: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance of z from each row's hyperplane (signed like ``r``, output units), and its round-off."""
        nrm = np.linalg.norm(A / s, axis=1)
        return _scaled(A, r, np.where(nrm > 0, nrm, 1.0))

    def _scaled(A: np.ndarray, r: np.ndarray, nrm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return r / nrm, (np.zeros(r.shape) if dz is None else (np.abs(A / s) @ dz) / nrm)

    # a row holds (or is active) within 1e-6 of the spread, or of the round-off of z itself in this metric
    # (‖Rf‖ ‖z‖ eps: u = −50 ± 0.0015 with a u² term, cond 8e10, left an active band row 2.4e-6 of the spread off
    # its hyperplane); equalities and inequalities alike (against 1e-6 ‖z‖, at u = 1e4 ± 1 an equality the model
    # missed by 0.3 of outputs of order 1 held); and within what the last digits of a θ mapped to the centred
    # parameters move the row (per row: a bound over all rows counted rows active that were not, at y + 1e6)
    near = 1e-6 * scale + 1e-15 * float(np.linalg.norm(whiten, 2) * znorm) if whiten is not None else tol
    rows = [np.zeros((0, n))]
    for c in cons:
        r = c.affine(ctx) if affine is None else affine(c)
        if r is None:
            raise ValueError(f"{what}: {c.describe()} is not affine in θ; the covariance is defined for affine "
                             "constraints (equalities, bands, gain and cluster bounds) only")
        if r.n_eq:
            miss, rounding = gap(r.A_eq, r.A_eq @ theta - r.b_eq)
            if np.any(np.abs(miss) > near + rounding):
                raise ValueError(f"{what}: the model does not satisfy {c.describe()}; was it estimated with these "
                                 "constraints, data and reference (Σ*_y)?")
            rows.append(np.asarray(r.A_eq))
        if r.n_ub:
            slack, rounding = gap(r.A_ub, r.b_ub - r.A_ub @ theta)
            if np.any(slack < -(near + rounding)):
                # a broken row would count as active below: the covariance of another problem, said as the model's
                raise ValueError(f"{what}: the model does not satisfy {c.describe()}; was it estimated with these "
                                 "constraints, data and static points?")
            rows.append(np.asarray(r.A_ub)[slack <= near + rounding])
    return np.vstack(rows)


# --------------------------------------------------------------------------------------------
# LS / ELS
# --------------------------------------------------------------------------------------------
def ls_uncertainty(
    model: Model,
    data: Record | Sequence[Record] | Dataset,
    *,
    level: float = 0.95,
) -> ParameterUncertainty:
    """Covariance of a least-squares estimate, σ²(ΨᵀΨ)⁻¹, or of an ELS one (a pseudo-linear sandwich).

    Parameters
    ----------
    model : Model, or a result that carries one in ``.model`` (ELSResult, Selection …)
        The estimate on ``data``: plain least squares (e.g. ``Selection.model`` or
        ``els(..., noise=0)``) or ELS (a model with an MA part: the covariance is that of the
        pseudo-linear regression in [θ; c], whose regressors move with its residuals; see the
        module docstring).
    data : Record, sequence of Record, or Dataset
        The identification data the model was estimated on (a Dataset's ``ident``).
    level : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    ParameterUncertainty
        ``cov`` of θ (engineering units), ``noise_cov`` of the MA part (ELS).

    Raises
    ------
    ValueError
        A plain LS model that is not the least-squares estimate on ``data`` (its gradient is not
        zero; among them an ELS estimate without its MA part, as :func:`graybox.select_graybox`
        returns it), an ELS model that is not the ELS estimate on ``data`` (its residuals are not
        orthogonal to its extended regressors), collinear regressors, too few rows.
    """
    model = as_model(model)
    level = _check_level(level)
    _check_meets(model, data)
    recs = records_of(data)
    st, ns = model.structure, model.noise_structure
    n, ne = len(st), len(ns)
    if ne == 0:
        return _ls_uncertainty(model, recs, level)
    what = "ls_uncertainty (ELS)"
    L = max(st.max_lag, ns.max_lag)
    require_lengths(recs, L)  # named, as the LS path names it (regressor_matrix's start = L named no record)
    for r in recs:
        model.check_record(r)
    # on the centred signals where els fits there (a closed model, :func:`_shift_offsets`), [θ; c] mapped to the
    # centred parameters: on the raw ones y(k-1)^2 at y + 2^20 was refused as "not identifiable"
    fit, recs_fit, Afull, z_round = model, recs, None, None
    try:
        offsets = _shift_offsets(st, ns, recs)
        if offsets is not None:
            both = Structure(list(st) + list(ns))
            Afull, _ = affine_map(both, offsets)
            Ainv, tinv = affine_map(both, {k: -v for k, v in offsets.items()})
    except (ValueError, KeyError, IndexError, OverflowError):  # the raw regressors say what does not fit
        offsets = Afull = None
    if Afull is not None:
        raw_all = np.concatenate([model.theta, model.noise_theta])
        cen = Ainv @ raw_all + tinv
        z_round = np.finfo(float).eps * (np.abs(Ainv) @ np.abs(raw_all) + np.abs(tinv))
        fit = replace(model, theta=cen[:n], noise_theta=cen[n:], name="centred")
        recs_fit = centred_data(recs, offsets)
    blocks, grads, targets = [], [], []
    for r in recs_fit:
        proc = regressor_columns(st, r.u, r.y, start=L, input_names=r.input_names)
        refuse_non_finite_columns(proc, st, f"{what}: ")
        xi, _ = _model_residuals(fit, r, True)
        e = np.zeros(len(r))
        e[L:] = xi
        block = np.hstack([proc, regressor_matrix(ns, r.u, r.y, e=e, start=L, input_names=r.input_names)])
        del proc
        blocks.append(block)
        grads.append(_residual_gradient(ns, fit.noise_theta, block, r, e, L))
        targets.append(r.y[L:])
    # one N × (n + ne) array each for the regressors and the residuals' gradient, scaled in place: a long record's
    # ELS covariance held eight of them (stacked copies, scaled copies), twice what the estimate held
    A = blocks[0] if len(blocks) == 1 else np.vstack(blocks)
    del blocks
    G = grads[0] if len(grads) == 1 else np.vstack(grads)
    del grads
    y = np.concatenate(targets)
    theta_all = np.concatenate([fit.theta, fit.noise_theta])
    N = A.shape[0]
    check_rows(N, n + ne, f"{what}: ")
    s = np.sqrt(np.einsum("ij,ij->j", A, A) / N)
    s = np.where(s > 0, s, 1.0)
    res = y - A @ theta_all
    A /= s
    G /= s
    dof = N - n - ne
    sigma2 = float(res @ res) / dof
    cov, F = _to_theta(_pseudo_linear_cov(A, G, sigma2, what), s)
    del G
    # ELS's fixed point: its residuals orthogonal to the extended regressors they build (to round-off
    # of the iteration's tolerance; an estimate of another record is far from it)
    _check_stationary(np.eye(n + ne), A, -res, 0.0, _size(A @ (theta_all * s), y), what,
                      "pass the ELS estimate on these data, with its MA part (graybox.els(model.structure, "
                      "data); a run stopped at a loose tol, e.g. 0.1, is short of its fixed point too)",
                      N, rtol=ELS_STATIONARY_RTOL, z_round=None if z_round is None else z_round * s)
    if Afull is not None:  # back to the raw parameters, from the mapped factor (as _FitCoordinates.back)
        with np.errstate(over="ignore", invalid="ignore"):
            F = F @ Afull.T
        cov = _factor_cov(F)
    _refuse_beyond_float_range(F, [*st, *ns], what)
    return ParameterUncertainty(model, cov[:n, :n], level, dof, sigma2, "ELS", np.zeros((0, n)), cov[n:, n:],
                                cov_factor=F[:, :n])


def _ls_uncertainty(model: Model, recs: list[Record], level: float) -> ParameterUncertainty:
    """σ²(ΨᵀΨ)⁻¹ of a least-squares estimate from the triangular factor of [Ψ/s, y] (as CLS's and PE's: reduced chunk
    by chunk where Ψ would not fit in memory), never from Ψ itself: its SVDs held a dozen copies of Ψ, where the
    estimate held four."""
    st = _process_structure(model)
    n = len(st)
    what = "ls_uncertainty"
    # on the centred signals for a closed structure, as the least squares of els and cls (:class:`_FitCoordinates`):
    # on the raw ones y(k-1)^2 at y + 2^20 was refused as "not identifiable", and 6e-5 off at y + 2^18
    d = _data(st, recs)
    check_rows(d.N, n, f"{what}: ")
    _check_variance_units(d.y_scale, what)
    fc = _FitCoordinates(d, [], None, model.theta)
    z = fc.theta * d.s
    dof = d.N - n
    sigma2 = float(np.sum((d.R1 @ z - d.c1) ** 2) + d.rss) / dof
    cov, F = _to_theta(_sandwich(np.eye(n), d.R1, np.sqrt(sigma2) * d.R1, what, d.N), d.s)
    _check_stationary(np.eye(n), d.R1, d.R1 @ z - d.c1, d.rss, _size(d.R1 @ z, d.c1), what,
                      "pass the least-squares estimate on these data (or use cls_/pe_/se_uncertainty); an ELS "
                      "estimate needs its MA part, which select_graybox's models leave out (a free run sets the "
                      "noise to zero): refit it with graybox.els(model.structure, data)", d.N, z=z,
                      z_round=None if fc.round is None else fc.round * d.s)
    cov, F, _ = fc.back(cov, F, np.zeros((0, n)))
    _refuse_beyond_float_range(F, st, what)
    return ParameterUncertainty(model, cov, level, dof, sigma2, "LS", np.zeros((0, n)), np.zeros((0, 0)),
                                cov_factor=F)


def _residual_gradient(ns, c: np.ndarray, phi: np.ndarray, rec: Record, e: np.ndarray, L: int) -> np.ndarray:
    """−dξ(k)/d[θ; c] for k = L … N−1, shape (N − L, n + ne), of the residual recursion
    ξ(k) = y(k) − φ(k)ᵀ[θ; c] with the noise regressors in φ built from ξ itself (zero before L).

    An MA part of plain lags e(k−l) filters φ by 1/C(q); products with e follow ξ's own recursion.
    """
    lags = _pure_lags(ns)
    if None not in lags:  # invertible: the residuals' own recursion (_model_residuals) refuses it otherwise
        return inverse_ma_filter(phi, _ma_coefficients(c, lags), np.array([0, phi.shape[0]]))  # 1/C(q) from rest
    sig = record_signals(rec) | {"e": e}
    # each noise term's derivative in one lagged e: (c_j · ∂term/∂e(k−lag) as a series over k, lag)
    parts = []
    for cj, t in zip(c, ns):
        for i, (s_, lag, pw) in enumerate(t.factors):
            if s_ != "e":
                continue
            d = np.full(len(rec), cj * pw)
            d[lag:] *= e[:-lag] ** (pw - 1) if lag else e ** (pw - 1)
            for jf, (s2, lag2, pw2) in enumerate(t.factors):
                if jf != i:
                    d[lag2:] *= sig[s2][:len(rec) - lag2] ** pw2
            parts.append((d, lag))
    g = np.zeros((len(rec), phi.shape[1]))  # g(k) = −dξ(k)/d[θ; c], zero before L as ξ is
    for k in range(L, len(rec)):
        acc = phi[k - L].copy()
        for d, lag in parts:
            acc -= d[k] * g[k - lag]
        g[k] = acc
    return g[L:]


def _pseudo_linear_cov(A: np.ndarray, G: np.ndarray, sigma2: float, what: str) -> tuple[np.ndarray, np.ndarray]:
    """σ² (AᵀG)⁻¹ AᵀA (GᵀA)⁻¹ = σ² K Kᵀ with K = (QᵀG)⁻¹ and A = QR (σ²(AᵀA)⁻¹ when G = A), and its
    factor σKᵀ; singular by the one rank rule (A's rows the regression rows)."""
    with one_blas_thread():
        Q, _ = np.linalg.qr(A)
        M = Q.T @ G
        S = np.linalg.svd(M, compute_uv=False)
        if not np.all(np.isfinite(M)) or S[0] == 0 or S[-1] <= rank_tolerance(S[0], A.shape[0], S.size):
            raise ValueError(f"{what}: the parameters are not identifiable from these data (singular information "
                             "matrix), so they have no finite covariance")
        K = np.linalg.inv(M)
        return sigma2 * (K @ K.T), np.sqrt(sigma2) * K.T


class _FitCoordinates:
    """The parameters a CLS or PE estimate was fitted in, and the map of its covariance back to θ.

    For a structure closed under shifts (fitted on the signals less their means, :func:`~graybox.estimation.
    _prediction_error._data`) these are θ_c, the parameters on the centred signals (θ = A θ_c + t), with the static
    points and the constraints' rows made on the centred signals too; else θ itself. The covariance is computed
    there and mapped back (A cov_c Aᵀ): on the raw signals a quadratic in y(k-1) at y + 1e4 carried the offset's
    powers into the regressors, and the covariance came out 2.3 times off (mapped to θ_c), at y + 1e6 refused as
    "not identifiable", where the estimators (which centre) fit the same model at every offset."""

    def __init__(self, d: _Data, cons: list[StaticConstraint], ctx, theta: np.ndarray):
        self.d = d
        self.centred = d.A is not None
        if not self.centred:
            self.theta, self.ctx, self.affine, self.round = np.asarray(theta, float), ctx, None, None
            return
        self.Ainv, tinv = shift_map(d.structure, {k: -v for k, v in d.offsets.items()})
        self.theta = self.Ainv @ theta + tinv
        # θ as stored carries the offsets' powers: its last digits, mapped here, are this much of θ_c (the rounding
        # of the model the user holds, which the checks of θ̂ against its problem must allow)
        self.round = np.finfo(float).eps * (np.abs(self.Ainv) @ np.abs(theta) + np.abs(tinv))
        if ctx is None:  # no static information (least squares)
            self.ctx, self.affine = None, None
        else:
            self.ctx = _centred_context(ctx, d)
            self.affine = lambda c: _centred_affine(c, ctx, self.ctx, d)

    def points(self, pts: StaticPoints) -> StaticPoints:
        """The static points on the signals the fit ran on."""
        return self.d.run_points(pts) if self.centred else pts

    def back(self, cov: np.ndarray, F: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The covariance, its factor (cov = FᵀF) and the constraint rows of the fit's parameters, in θ."""
        if not self.centred:
            return cov, F, rows
        # the covariance from the mapped factor (FᵀF): A cov Aᵀ held a pinned direction's round-off (1e-24 where FᵀF
        # has 1e-37), and the pair was refused as no covariance and its factor
        with np.errstate(over="ignore", invalid="ignore"):
            F = F @ self.d.A.T
        return _factor_cov(F), F, rows @ self.Ainv


# --------------------------------------------------------------------------------------------
# CLS
# --------------------------------------------------------------------------------------------

def _check_meets(model: Model, data: object, static: object = None) -> None:
    """``ValueError`` when ``data`` (its records, and the static points given or a Dataset's) are sampled at
    another period than the model was identified at or are in other units (:meth:`Model.check_record`): a
    covariance of θ judged on data θ does not hold for is no uncertainty of the model."""
    for r in records_of(data):
        model.check_record(r)
    sp = static if static is not None else data.static if isinstance(data, Dataset) else None
    if isinstance(sp, StaticPoints):
        model.check_record(sp)


def _process_model(model: object, who: str) -> Model:
    """The model of a CLS, PE or SE covariance: those estimates have no MA part, so one that carries it (an
    ELS estimate) is refused here, naming the way out, not deep in :class:`ParameterUncertainty`'s own check."""
    m = as_model(model)
    if len(m.noise_structure):
        raise ValueError(f"{who}: the model carries an MA part ({m.noise_structure}), as an ELS estimate does; CLS, PE "
                         "and SE estimates have none. For an ELS or least-squares estimate use ls_uncertainty; for "
                         "its process part alone pass model.with_theta(model.theta)")
    return m


def cls_uncertainty(
    model: Model,
    data: Record | Sequence[Record] | Dataset,
    static: StaticCurve | StaticSurface | StaticPoints | None = None,
    *,
    how: str = "auto",
    reference: Model | np.ndarray | float | str = "free",
    constraints: StaticConstraint | Iterable[StaticConstraint] | None = None,
    level: float = 0.95,
) -> ParameterUncertainty:
    """Covariance of a CLS estimate, projected on the null space of its equality constraints.

    Give the same ``data``, ``static``, ``how``, ``reference`` and ``constraints`` as to
    :func:`graybox.cls`: the constraint rows are rebuilt from them. Inequality rows active at θ̂
    count as equalities (the covariance is then conditional on the active set; near-active rows
    make it unreliable).

    Parameters
    ----------
    model : Model, or a result that carries one in ``.model`` (CLSResult …)
        The CLS estimate.
    data : Record, sequence of Record, or Dataset
        Its identification data.
    static : StaticCurve, StaticSurface or StaticPoints, optional
        As for :func:`graybox.cls`.
    how : {"auto", "curve", "points", "context"}
        As for :func:`graybox.cls`.
    reference : {"free", "ls", "els"}, Model, ndarray of shape (n_terms,) or float
        As for :func:`graybox.cls` (Σ*_y of eq. (22)); its own randomness is not propagated.
    constraints : constraint or iterable of constraints, optional
        As for :func:`graybox.cls` (affine ones only).
    level : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    ParameterUncertainty
        ``cov @ constraints.T`` is zero: constrained clusters have zero variance.

    Raises
    ------
    ValueError
        The model does not satisfy the constraints or is not their least-squares solution (other
        data or settings than its estimate's), a non-affine constraint, not identifiable.
    """
    model = _process_model(model, "cls_uncertainty")
    level = _check_level(level)
    _check_meets(model, data, static)
    st = _process_structure(model)
    recs = records_of(data)
    try:  # the points that tell a held input's terms apart, as cls reads them; refused below, after the records
        sp = static_info(static, data, curves=True)
    except (ValueError, TypeError):
        sp = None
    # the data and coordinates cls fits in: on the centred signals for a closed structure with centrable constraints
    d = _data(st, recs, sp if isinstance(sp, StaticPoints) else None)
    cons, ctx, _ = _cls_setup(st, recs, d, data, static, how, reference, constraints)
    if d.A is not None and not centrable(cons):
        d = _dynamic(st, recs)
    _check_variance_units(d.y_scale, "cls_uncertainty")
    fc = _FitCoordinates(d, cons, ctx, model.theta)
    A = _equalities(cons, fc.ctx, fc.theta, d.s, "cls_uncertainty", d.R1, d.N, d.y_scale, fc.affine, fc.round)
    n = len(st)
    Z, r = _null_space(A / d.s, n, _equality_rank(cons, ctx, A))
    z = fc.theta * d.s
    dof = d.N - (n - r)
    rss = float(np.sum((d.R1 @ z - d.c1) ** 2) + d.rss)
    sigma2 = rss / dof
    cov, F = _to_theta(_sandwich(Z, d.R1, np.sqrt(sigma2) * d.R1, "cls_uncertainty", d.N), d.s)
    _check_stationary(Z, d.R1, d.R1 @ z - d.c1, d.rss, _size(d.R1 @ z, d.c1), "cls_uncertainty",
                      "pass the CLS estimate with the data, static information and constraints it was estimated with",
                      d.N, z=z, z_round=None if fc.round is None else fc.round * d.s)
    cov, F, A = fc.back(cov, F, A)
    cov, F = _pinned_zeroed(cov, F, Z, d.s, fc)  # the constraints fix them: variance 0 in any units, not round-off
    _refuse_beyond_float_range(F, st, "cls_uncertainty")
    return ParameterUncertainty(model, cov, level, dof, sigma2, "CLS", A, np.zeros((0, 0)), cov_factor=F)


# --------------------------------------------------------------------------------------------
# PE
# --------------------------------------------------------------------------------------------
def pe_uncertainty(
    model: Model | Decision,
    data: Record | Sequence[Record] | Dataset,
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    lambda1: float | None = None,
    constraints: StaticConstraint | Iterable[StaticConstraint] | None = None,
    weights: str = "mse",
    ubar: np.ndarray | None = None,
    reference: Model | np.ndarray | float | str = "free",
    static_sigma: float | None = None,
    level: float = 0.95,
) -> ParameterUncertainty:
    """Sandwich covariance of a PE member (eq. (9)) at its weight λ1.

    Parameters
    ----------
    model : Model, Decision, or a result that carries one in ``.model``
        The member (``ParetoSet.member_model(i)``, or a Decision from :func:`graybox.decide_dsf`, which
        brings its λ1).
    data : Record, sequence of Record, or Dataset
        Its identification data.
    static : StaticPoints, StaticCurve or StaticSurface, optional
        As for :func:`graybox.pe_pareto` (default: the Dataset's points).
    lambda1 : float, optional
        The member's λ1 in (0, 1] (default: the Decision's).
    constraints, weights, ubar, reference
        As for :func:`graybox.pe_pareto` (affine constraints only; active inequalities count as
        equalities).
    static_sigma : float, optional
        Standard deviation of the measured ȳ_i, output units (e.g. 0.175 mlc for the plant's
        transmitter; 0 takes the points as exact). Default: from the member's own static misfit,
        √(Σ s_i² / ν), s = QRθ − ȳ the static equation's residuals (eq. (12)) and ν = E Σ s_i² / σ_SF² to
        first order, its degrees of freedom (Σ g_i² at λ1 = 1, where the points do not move θ, g_i = ∂s_i/∂ȳ_i,
        −D(ū_i) for a rational structure; less as the member comes to meet the points; capped at Σ g_i²
        where a large misfit makes the first order say more; ``ValueError`` when it meets them exactly).
        Residuals are weighed as the fit weighs them: a point where the member's static curve folds
        (g_i ≈ 0) counts for little, where its ȳ-distance s_i/g_i would have decided σ_SF alone. It
        includes any systematic misfit and so errs on the safe side (in a Monte Carlo of noisy points without
        it, λ1 from 1e-3 to 1, the median σ_SF was 0.85–1.01 of the noise's and √mean σ_SF² 0.98–1.19:
        ``benchmarks/bench_static_sigma.py``). An estimate from M points has fewer than M degrees of freedom,
        which Student's t counts (:attr:`ParameterUncertainty.dof`): with a handful of points the intervals
        widen a lot (t = 12.7 at one dof); give the transmitter's σ where it is known.
    level : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    ParameterUncertainty
        ``sigma2``: the dynamic noise variance (least squares on the data); ``static_sigma2``: σ_SF²; ``dof``: fewer
        where σ_SF² is estimated (no ``static_sigma``): it comes from M points. First order: unreliable towards small
        λ1 (see the module docstring).

    Raises
    ------
    ValueError
        θ is not the PE optimum at this λ1 with these data (e.g. a wrong λ1), not identifiable.
    """
    m = _process_model(model, "pe_uncertainty")
    lam = _lambda_arg(model, lambda1, "pe_uncertainty")
    level = _check_level(level)
    _check_meets(m, data, static)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StaticRangeWarning)  # the estimator has said it
        # the data and coordinates pe_pareto fits in (on the centred signals for a closed structure, :class:`_FitCoordinates`)
        st, recs, d, pts, ctx, cons, rows, stat, M = _pe_setup(m, data, static, constraints, weights, ubar, reference,
                                                               centre=True)
    n = len(st)
    _check_variance_units(d.y_scale, "pe_uncertainty")
    fc = _FitCoordinates(d, cons, ctx, m.theta)
    theta, pts = fc.theta, fc.points(pts)
    cm = static_cluster_map(st, recs[0].input_names)  # a surface's clusters for several inputs
    QR = static_rows(cm, pts.ubar, pts.ybar) @ cm.R / d.s  # (M, n) in z
    # the estimator's QP works in the basis that whitens the dynamic and static factors stacked
    A = _equalities(cons, fc.ctx, theta, d.s, "pe_uncertainty", np.vstack([d.R1, QR]), d.N + M, d.y_scale, fc.affine,
                    fc.round)
    Z, r = _null_space(A / d.s, n, _equality_rank(cons, ctx, A))
    w1 = lam / d.N if weights == "mse" else lam
    w2 = (1 - lam) / M if weights == "mse" else 1 - lam
    dQR = static_rows(cm, pts.ubar, pts.ybar, wrt="y") @ cm.R / d.s
    z = theta * d.s
    sres = QR @ z - pts.ybar  # affine static residual s_i
    g = dQR @ z - 1.0  # ∂s_i/∂ȳ_i (−D(ū_i) for a rational structure)
    if np.any(np.abs(g) < 1e-12):
        raise ValueError("pe_uncertainty: the static equation does not depend on ȳ at some static point "
                         "(its denominator vanishes): the member's static function is undefined there")
    A2 = np.vstack([np.sqrt(w1) * d.R1, np.sqrt(w2) * QR])  # the stacked rows: H = A2ᵀA2
    r2 = np.concatenate([np.sqrt(w1) * (d.R1 @ z - d.c1), np.sqrt(w2) * sres])
    _check_stationary(Z, A2, r2, w1 * d.rss, _size(A2 @ z, np.sqrt(w1) * d.c1, np.sqrt(w2) * pts.ybar),
                      "pe_uncertainty", f"pass the member's own λ1 (got {lam:g}) and the data, static "
                      "points and constraints of its estimate", d.N + M, z=z,
                      z_round=None if fc.round is None else fc.round * d.s)
    dof_ls = d.N - n
    sigma2 = d.rss / dof_ls  # the data's noise, from least squares on the same data
    B = sres[:, None] * dQR + g[:, None] * QR  # ∂(gradient of the static term)/∂ȳ_i, row i
    dof = d.N - (n - r)
    if static_sigma is not None:
        ss2 = check_real(static_sigma, "static_sigma (0 for exact points)", low=0) ** 2
    else:
        ss2, dof_sf = _static_sigma2(Z, A2, QR, w2 * B, g, sres, pts.ybar, d.N + M)
    G1, G2 = w1 * np.sqrt(sigma2) * d.R1, w2 * np.sqrt(ss2) * B
    G = np.vstack([G1, G2])  # M = GᵀG
    cov, F = _to_theta(_sandwich(Z, A2, G, "pe_uncertainty", d.N + M), d.s)
    if static_sigma is None and lam < 1:  # σ_SF² estimated from M points too: Student's t of fewer dof
        shown = np.vstack([(d.A if fc.centred else np.eye(n)) / d.s, QR])  # each θ_j and the static rows, in z
        dof = _two_variances_dof(dof, *(_sandwich(Z, A2, Gj, "pe_uncertainty", d.N + M)[1] for Gj in (G1, G2)),
                                 dof_sf, shown)
    cov, F, A = fc.back(cov, F, A)
    cov, F = _pinned_zeroed(cov, F, Z, d.s, fc)  # as cls_uncertainty: what the constraints fix has variance 0
    _refuse_beyond_float_range(F, st, "pe_uncertainty")
    return ParameterUncertainty(m, cov, level, dof, sigma2, f"PE λ1={lam:.4g}", A, np.zeros((0, 0)), ss2,
                                cov_factor=F)


def _static_sigma2(Z: np.ndarray, A2: np.ndarray, QR: np.ndarray, wB: np.ndarray, g: np.ndarray, s: np.ndarray,
                   ybar: np.ndarray, rows: int) -> tuple[float, float]:
    """The default σ_SF² of a PE member: Σ s_i² / ν, its static equation's residuals s = QRz − ȳ over their
    degrees of freedom ν = E Σ s_i² / σ_SF² for noise of variance σ_SF² in the measured ȳ_i; and the degrees of
    freedom of that estimate as a χ² (:func:`_quadratic_form_dof`, at most M), which Student's t needs.

    s moves with ȳ directly (∂s_i/∂ȳ_i = g_i) and through the estimate (dz/dȳ = −Z (ZᵀA2ᵀA2Z)⁻¹ Zᵀ (w2 B)ᵀ), so
    to first order ν = ‖diag(g) − QR Z (ZᵀA2ᵀA2Z)⁻¹ Zᵀ (w2 B)ᵀ‖²_F: Σ g_i² at λ1 = 1 (the points do not move θ),
    less as the member comes to meet them. Where B = g ⊙ QR (a small misfit) that is Σ g_i² times at most one,
    and ν is capped there: beyond it (a misfit so large that ȳ_i moves the static rows themselves) the first order
    says the member absorbs less than nothing, which no fit does, and the cap errs on the safe side.

    The residuals are taken as the fit takes them, in the static equation's units, not as ȳ-distances s_i/g_i:
    near a fold of the member's static curve (g_i → 0) s_i/g_i and its first-order ν both blow up and are not
    what the noise gives (7 points of a y(k-1)^2 structure at λ1 = 1e-3: g = 0.001 at one point, ν = 466 for
    7 points, σ_SF decided by that point alone; under a systematic misfit of 4 times the noise it read as little
    as 1.3 times the noise), where s_i itself stays of the noise's size and its share of ν goes to 0. The two agree where g is the same at every point (a structure whose static equation has no
    products of y with u). ``ValueError`` when ν vanishes: the member meets its points exactly.
    """
    M = QR.shape[0]
    top = float(g @ g)
    # met exactly (to round-off of ȳ), e.g. by constraints through the points: no noise is left to estimate
    exact = scaled_norm(s) <= 1e-10 * scaled_norm(g * ybar)  # over powers of two: ȳ about 2^512 overflowed
    nu = 0.0 if exact else top
    T = np.diag(g)
    if Z.shape[1] and not exact:
        _, S, Vt = np.linalg.svd(A2 @ Z, full_matrices=False)  # (ZᵀA2ᵀA2Z)⁻¹ = V S⁻² Vᵀ, never formed (cond²)
        if S.size and np.all(np.isfinite(S)) and S[-1] > rank_tolerance(S[0], rows, S.size):
            T = np.diag(g) - ((QR @ Z @ Vt.T) / S) @ ((wB @ Z @ Vt.T) / S).T
            nu = min(float(np.sum(T**2)), top)
        # else not identifiable: the sandwich that follows refuses it, saying so
    _checked_dof(M * nu / top, M)  # ν measured against its top, Σ g_i² (in the units of s)
    # the estimate's own degrees of freedom: of Σ s_i² = ‖Tδ‖², by the first order's T (diag(g) where it is capped)
    return float(s @ s) / nu, _quadratic_form_dof(T if nu < top else np.diag(g))


def _checked_dof(nu: float, M: int) -> float:
    """``nu``, or ``ValueError`` when it vanishes: the member meets its M static points exactly."""
    if not np.isfinite(nu) or nu <= 1e-6 * M:
        raise ValueError(f"pe_uncertainty: the member meets its {M} static points exactly (its static function has as "
                         "many free coefficients as there are points, constraints hold it on them, or the points are "
                         "noise-free), so its misfit says nothing of the points' "
                         "noise: give static_sigma (the standard deviation of the measured ȳ_i; 0 for exact points)")
    return nu


def _quadratic_form_dof(T: np.ndarray) -> float:
    """The degrees of freedom of σ² estimated as ‖Tδ‖² / ‖T‖²_F from δ ~ N(0, σ² I): those of the χ² with its mean
    and variance (Satterthwaite), (tr TᵀT)² / tr((TᵀT)²); M − k where T projects M residuals off k directions."""
    ev = np.linalg.svd(np.asarray(T, float), compute_uv=False) ** 2
    return float(ev.sum() ** 2 / (ev @ ev)) if ev.size and ev[0] > 0 else 0.0


def _two_variances_dof(dof: int, F1: np.ndarray, F2: np.ndarray, dof2: float, shown: np.ndarray) -> int:
    """Student's degrees of freedom of a covariance F1ᵀF1 + F2ᵀF2 that holds two estimated variances: the records'
    σ² in F1 (with ``dof``) and the static points' σ_SF² in F2 (with ``dof2``, from M points: a handful).

    A combination c of the parameters has the variance a + b, a = ‖F1 c‖² and b = ‖F2 c‖²; Satterthwaite's degrees
    of freedom of it, (a + b)² / (a²/dof + b²/dof2), fall from dof to dof2 as b/a grows. One number serves every
    interval and band, so it is the least of those of the combinations ``shown`` (rows, in the coordinates of F1
    and F2): each parameter and the static curve at each static point, where the points decide what they decide. At
    most ``dof``, at least 1. With σ_SF estimated from M = 6 points at λ1 = 0.1 the records' dof alone left the
    static terms' 95 % intervals covering 86-88 % of 300 draws (PE) and 89-90 % of 200 (SE), the static curve's band
    84-89 %.
    """
    # the ratio b/a of norms, each row over a power of two first: at y × 2^512 the squares left the float range
    C = np.asarray(shown, float)
    C = np.ldexp(C, -binary_exponent(scaled_norms(C, axis=1))[:, None])
    with np.errstate(over="ignore", under="ignore"):
        n1, n2 = scaled_norms(C @ F1.T, axis=1), scaled_norms(C @ F2.T, axis=1)
    seen = (n1 > 0) | (n2 > 0)  # a combination the constraints fix has no variance, nor degrees of freedom
    if not seen.any():
        return int(dof)
    n1, n2 = n1[seen], n2[seen]
    rec = n1 >= n2  # the records' share the larger: b/a = u; else a/b = u (0 where the points alone decide)
    u = (np.minimum(n1, n2) / np.maximum(n1, n2)) ** 2
    eff = (1 + u) ** 2 / np.where(rec, 1 / dof + u**2 / dof2, u**2 / dof + 1 / dof2)
    return int(max(1, min(dof, np.floor(eff.min() + 1e-9))))


# --------------------------------------------------------------------------------------------
# SE
# --------------------------------------------------------------------------------------------
def se_uncertainty(
    model: Model | Decision,
    data: Record | Sequence[Record] | Dataset,
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    lambda1: float | None = None,
    static_sigma: float | None = None,
    level: float = 0.95,
) -> ParameterUncertainty:
    """Covariance of an SE member (eq. (13)) from the Jacobian of its residuals at θ̂.

    Parameters
    ----------
    model : Model, Decision, or a result that carries one in ``.model``
        The member (from :func:`graybox.se_pareto`, gradient or GA; a Decision brings its λ1).
    data : Record, sequence of Record, or Dataset
        Its identification data (each record run freely from its own first samples).
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Its static points (default: the Dataset's); a curve or surface is sampled over its domain
        as every estimator samples it.
    lambda1 : float, optional
        The member's λ1 in (0, 1] (default: the Decision's).
    static_sigma : float, optional
        Standard deviation of the measured ȳ_i, output units (0 takes the points as exact);
        default: from the member's static misfit, √(M·J_SF / ν) with ν its degrees of freedom (M at
        λ1 = 1; towards M − k as the member comes to meet the points with k free static
        coefficients; ``ValueError`` when it meets them exactly). Student's t counts its degrees of freedom (at
        most M: :attr:`ParameterUncertainty.dof`); give the transmitter's σ where it is known.
    level : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    ParameterUncertainty
        ``sigma2``: the free-run error variance Σe_sim²/(N − n); ``dof``: fewer where σ_SF² is estimated (no
        ``static_sigma``, λ1 < 1): it comes from M points.

    Raises
    ------
    ValueError
        The member's free run diverges or its static curve is undefined at a static point; not
        identifiable.

    Warns
    -----
    UncertaintyWarning
        θ̂ is not a stationary point of the SE objective (e.g. a GA member, or a gradient run
        stopped by its evaluation budget): the intervals then describe the curvature there.
    """
    m = _process_model(model, "se_uncertainty")
    lam = _lambda_arg(model, lambda1, "se_uncertainty")
    level = _check_level(level)
    _check_meets(m, data, static)
    recs = records_of(data)
    sp = static_points(static, data, needed_by=None if lam == 1 else "se_uncertainty", takes_ubar=False)
    if sp is None:  # λ1 = 1 ignores the static points; SEProblem still wants some, of the records' inputs
        names = recs[0].input_names
        sp = StaticPoints(np.zeros((1, len(names))) if len(names) > 1 else [0.0], [0.0], input_names=names)
    problem = SEProblem(m.structure, recs, sp)
    # as for CLS and PE: at y × 2^-565 σ² underflowed and the covariance came out 0, at y × 2^520 it overflowed
    _check_variance_units(output_scale(np.concatenate([np.asarray(r.y, float) for r in recs])), "se_uncertainty")
    n, nd, M = len(m.structure), problem.n_dyn, len(sp)
    th = m.theta
    # the weighted problem of eq. (13) in the solvers' coordinates z (SEProblem.to_z): θ · scale, or for a structure
    # closed under shifts the centred parameters times their regressors' RMS, with the free runs and equilibria made
    # on the centred signals as the fits make them. On the raw signals y(k-1)^2 at y + 2^18 carried the offset's
    # powers: the std came out 0.6 % off, and at y + 2^20 the covariance was refused as "not identifiable"
    z = problem.to_z(th)
    th_run = problem.run_theta(th, z)
    div = problem.scale if problem.run_scale is None else problem.run_scale  # ∂/∂z = ∂/∂θ_run / div
    w1, w2 = np.sqrt(lam / nd), np.sqrt((1 - lam) / M)
    with np.errstate(all="ignore"):
        # the free run's rows as the triangular factor T of [w1 ∂ŷ/∂z, w1 (ŷ − y)], streamed block by block as the
        # gradient sweep takes it: the N × n Jacobian is never held (its copies and SVDs held a dozen of them)
        T = _free_run_factor(problem, th_run, w1, div)
        if lam < 1:
            e = problem.static_errors(th[None], z=z[None])[0]  # ȳ_model − ȳ, of the centred model where centred
            points = sp if problem.static_run is None else problem.run_points()
            yb = e + points.ybar
            rs = w2 * e
            if problem.surface_inputs is not None:
                grad = surface_theta_gradient(problem.structure, th_run, points.ubar, yb, inputs=problem.surface_inputs)
            else:
                grad = static_theta_gradient(problem.structure, th_run, points.ubar, yb)
            Js = w2 * grad / div
        else:
            rs, Js = np.zeros(0), np.zeros((0, n))
    if not (np.all(np.isfinite(T)) and np.all(np.isfinite(rs)) and np.all(np.isfinite(Js))):
        raise ValueError("se_uncertainty: the member's free run diverges or its static curve is undefined (no stable "
                         "equilibrium) at a static point; it has no local covariance")
    Rd, qd = T[:n, :n], T[:n, n]  # RdᵀRd = JdᵀJd; qd = Qᵀ(w1 e_sim), the rest of whose norm is T[n, n]
    rd2 = float(qd @ qd + T[n, n] ** 2)  # ‖w1 e_sim‖²
    J = np.vstack([Rd, Js])  # JᵀJ of the weighted residuals' Jacobian (free-run rows, then static ones)
    rows = nd + Js.shape[0]
    sigma2 = rd2 / w1**2 / (nd - n)
    if lam < 1:
        if static_sigma is not None:
            ss2 = check_real(static_sigma, "static_sigma (0 for exact points)", low=0) ** 2
        else:
            # the misfit's degrees of freedom: e_SF = ȳ_model − ȳ moves with ȳ directly and through θ̂, by
            # −(I − U_s U_sᵀ) with U an orthonormal basis of the Jacobian's columns and U_s its static rows
            # (U = J V S⁻¹: its static rows are Js V S⁻¹)
            _, S, Vt = np.linalg.svd(J, full_matrices=False)
            keep = S > rank_tolerance(S[0], rows, S.size) if S.size and S[0] > 0 else np.zeros(S.size, bool)
            Us = (Js @ Vt[keep].T) / S[keep]
            P = np.eye(M) - Us @ Us.T
            nu = float(np.sum(P**2))
            if nu <= 1e-6 * M:
                raise ValueError(f"se_uncertainty: the member meets its {M} static points exactly (its static "
                                 "function has as many free coefficients as there are points), so its misfit says "
                                 "nothing of the points' noise: give static_sigma (the standard deviation of the "
                                 "measured ȳ_i; 0 for exact points)")
            ss2 = float(np.sum((rs / w2) ** 2)) / nu
            dof_sf = _quadratic_form_dof(P)  # the estimate's own, at most M: Student's t needs them
    else:
        ss2 = float("nan")
    # J holds the weighted residuals' derivatives (w ∂e/∂z): H = JᵀJ, and the gradient Jᵀr = Σ_b w_b² Ĵ_bᵀe_b
    # has covariance Σ_b w_b⁴ σ_b² Ĵ_bᵀĴ_b = Σ_b w_b² σ_b² J_bᵀJ_b
    G = w1 * np.sqrt(sigma2) * Rd if lam == 1 else np.vstack([w1 * np.sqrt(sigma2) * Rd, w2 * np.sqrt(ss2) * Js])
    g = np.linalg.norm(Rd.T @ qd + Js.T @ rs)  # ‖Jᵀr‖
    nJ = float(np.linalg.norm(J, 2))
    rel = g / max(nJ * np.sqrt(rd2 + float(rs @ rs)), 1e-300)
    # residuals at the round-off of the fit (1e-11 of the weighted targets, as _check_stationary allows) point
    # anywhere: a member that fits noise-free data exactly is the optimum, whatever its relative gradient
    floor = 1e-11 * nJ * _size(w1 * problem.z_target, *([w2 * problem.run_points().ybar] if lam < 1 else []))
    if problem.z_map is not None:  # and the residuals the last digits of θ make, mapped to z (θ carries the offsets)
        dz = np.finfo(float).eps * (np.abs(problem.z_inv) @ (np.abs(th) + np.abs(problem.z_shift)))
        floor += nJ * float(np.linalg.norm(np.abs(J) @ dz))
    if rel > 1e-3 and g > floor:
        warn(f"se_uncertainty: θ is not a stationary point of the SE objective at λ1 = {lam:g} (relative gradient "
             f"{rel:.1e}); the intervals describe the curvature at this θ, not at an optimum", UncertaintyWarning)
    cov_z, F = _sandwich(np.eye(n), J, G, "se_uncertainty", rows)
    dof = nd - n
    if lam < 1 and static_sigma is None:  # σ_SF² estimated from M points too: Student's t of fewer dof
        shown = np.vstack([np.diag(1 / problem.scale) if problem.z_map is None else problem.z_map, Js])  # θ_j, statics
        dof = _two_variances_dof(dof, *(_sandwich(np.eye(n), J, Gj, "se_uncertainty", rows)[1]
                                        for Gj in (w1 * np.sqrt(sigma2) * Rd, w2 * np.sqrt(ss2) * Js)), dof_sf, shown)
    if problem.z_map is None:
        cov, F = _to_theta((cov_z, F), problem.scale)
    else:  # θ = z_map z + z_shift; the covariance from the mapped factor, as for CLS and PE (:class:`_FitCoordinates`)
        with np.errstate(over="ignore", invalid="ignore"):
            F = F @ problem.z_map.T
        cov = _factor_cov(F)
    _refuse_beyond_float_range(F, m.structure, "se_uncertainty")
    return ParameterUncertainty(m, cov, level, dof, sigma2, f"SE λ1={lam:.4g}", np.zeros((0, n)),
                                np.zeros((0, 0)), ss2, cov_factor=F)


def _free_run_factor(problem: SEProblem, theta: np.ndarray, w1: float, div: np.ndarray) -> np.ndarray:
    """The triangular factor T, shape (n + 1, n + 1), of [w1 ∂ŷ/∂z, w1 (ŷ − y)] over every record's free run as the
    fits make it (``theta`` the parameters of the runs on :attr:`SEProblem.run_records`, z = ``theta`` · ``div``;
    TᵀT is that matrix's Gram matrix), by TSQR over blocks of the streamed sensitivities: memory independent of the
    records' length. NaN where the run or its sensitivities are not finite."""
    n, L = theta.size, problem.L
    colw = w1 / div
    T = np.zeros((0, n + 1))
    for rec, U in zip(problem.run_records, problem.run_U):
        for k0, k1, yh, S in free_run_sensitivity_blocks(problem.code, theta, U, rec.y[:L], L):
            work = np.empty((T.shape[0] + k1 - k0, n + 1))
            work[: T.shape[0]] = T
            np.multiply(S, colw, out=work[T.shape[0]:, :n])
            np.subtract(yh[k0:k1], rec.y[k0:k1], out=work[T.shape[0]:, n])
            work[T.shape[0]:, n] *= w1
            if not np.all(np.isfinite(work)):
                return np.full((n + 1, n + 1), np.nan)
            T = np.linalg.qr(work, mode="r")
    if T.shape[0] < n + 1:
        T = np.vstack([T, np.zeros((n + 1 - T.shape[0], n + 1))])
    return T


# --------------------------------------------------------------------------------------------
# static curve and gain
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StaticCurveBand(Relocked):
    """Confidence band of a model's static curve ȳ(ū) and static gain dȳ/dū.

    Attributes
    ----------
    ubar : ndarray, shape (M,)
        Input levels (engineering units).
    ybar, gain : ndarray, shape (M,)
        The estimate's static curve and gain (the stable equilibrium it reaches).
    ybar_low, ybar_high, gain_low, gain_high : ndarray, shape (M,)
        The band at :attr:`level`.
    ybar_std, gain_std : ndarray, shape (M,)
        Standard deviations (delta method, or of the Monte Carlo draws' deviations from the estimate, each
        brought back to the normal draw it came from: the multivariate t's own has none at dof <= 2).
    level : float
    method : str
        ``"delta"`` or ``"monte-carlo"``.
    n_samples : int
        Monte Carlo draws (0 for the delta method).
    undefined : ndarray, shape (M,)
        Fraction of draws without a stable equilibrium near the estimate's at each ū (Monte
        Carlo; 0 for the delta method). Those draws are left out of the band.
    model_name : str
    units : (str, str)
        The model's units (input, output), as it was identified in: the band's ū, ȳ and gains are in them.
    """

    ubar: np.ndarray
    ybar: np.ndarray
    ybar_low: np.ndarray
    ybar_high: np.ndarray
    ybar_std: np.ndarray
    gain: np.ndarray
    gain_low: np.ndarray
    gain_high: np.ndarray
    gain_std: np.ndarray
    level: float
    method: str
    n_samples: int
    undefined: np.ndarray
    model_name: str = ""
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_fields(self)
        object.__setattr__(self, "units", check_units(self.units, "StaticCurveBand", 1))  # a curve is of one input
        M = np.shape(self.ubar)[0]
        _check_static_band(self, (M,), (M,))

    def to_frame(self) -> pd.DataFrame:
        """The band as a table.

        Returns
        -------
        pandas.DataFrame
            One row per ū (index ``ubar``, input units): ``ybar``, ``ybar low``, ``ybar high``, ``ybar std`` (output
            units), ``gain``, ``gain low``, ``gain high``, ``gain std`` (output units per input unit) and
            ``undefined`` (the fraction of Monte Carlo draws without a stable equilibrium near the
            estimate's there, left out of the band; 0 for the delta method).
        """
        import pandas as pd

        return pd.DataFrame({"ybar": self.ybar, "ybar low": self.ybar_low, "ybar high": self.ybar_high,
                             "ybar std": self.ybar_std, "gain": self.gain, "gain low": self.gain_low,
                             "gain high": self.gain_high, "gain std": self.gain_std, "undefined": self.undefined},
                            index=pd.Index(self.ubar, name="ubar"))

    def __repr__(self) -> str:
        return (f"StaticCurveBand({self.model_name or 'model'}: {self.ubar.size} levels, {self.method}, "
                f"level={self.level:g}, {_widest(self)})")


@dataclass(frozen=True, eq=False)
class StaticSurfaceBand(Relocked):
    """Confidence band of a model's static surface ȳ(ū) and its gains ∂ȳ/∂ū_i (several inputs).

    Attributes
    ----------
    ubar : ndarray, shape (M, m)
        Points of input space (engineering units), columns in :attr:`input_names` order.
    input_names : tuple of str, length m
    ybar, ybar_low, ybar_high, ybar_std : ndarray, shape (M,)
        The estimate's static surface (the stable equilibrium it reaches), its band at :attr:`level` and
        standard deviations (output units; of Monte Carlo draws as :class:`StaticCurveBand`'s).
    gain, gain_low, gain_high, gain_std : ndarray, shape (M, m)
        The gains ∂ȳ/∂ū_i (output units per unit of input i), their band and standard deviations.
    level : float
    method : str
        ``"delta"`` or ``"monte-carlo"``.
    n_samples : int
        Monte Carlo draws (0 for the delta method).
    undefined : ndarray, shape (M,)
        Fraction of draws without a stable equilibrium near the estimate's at each point (Monte Carlo;
        0 for the delta method). Those draws are left out of the band.
    model_name : str
    units : (str, str)
        The model's units (input, output), as it was identified in: the band's ū, ȳ and gains are in them.
    """

    ubar: np.ndarray
    input_names: tuple[str, ...]
    ybar: np.ndarray
    ybar_low: np.ndarray
    ybar_high: np.ndarray
    ybar_std: np.ndarray
    gain: np.ndarray
    gain_low: np.ndarray
    gain_high: np.ndarray
    gain_std: np.ndarray
    level: float
    method: str
    n_samples: int
    undefined: np.ndarray
    model_name: str = ""
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_fields(self)
        # a name given twice would merge two inputs' gain columns in to_frame
        object.__setattr__(self, "input_names", check_input_names(self.input_names, what="input_names"))
        object.__setattr__(self, "units", check_units(self.units, "StaticSurfaceBand", len(self.input_names)))
        ub = frozen(self.ubar)
        m = len(self.input_names)
        if ub.ndim != 2 or ub.shape[1] != m:
            raise ValueError(f"ubar must have shape (M, {m}) (a column per input of input_names), got {ub.shape}")
        object.__setattr__(self, "ubar", ub)
        _check_static_band(self, (ub.shape[0],), ub.shape)

    def to_frame(self) -> pd.DataFrame:
        """The band as a table.

        Returns
        -------
        pandas.DataFrame
            One row per point (a MultiIndex of the inputs' levels, named by the inputs): ``ybar``, ``ybar low``,
            ``ybar high``, ``ybar std`` (output units), each input's gain with its band and std (columns
            ``gain <name>``, ``gain <name> low``, ``gain <name> high``, ``gain <name> std``; output units per that
            input's unit) and ``undefined`` (the fraction of Monte Carlo draws without a stable equilibrium near the
            estimate's there, left out of the band; 0 for the delta method).
        """
        import pandas as pd

        cols: dict[str, np.ndarray] = {"ybar": self.ybar, "ybar low": self.ybar_low, "ybar high": self.ybar_high,
                                       "ybar std": self.ybar_std}
        for i, n in enumerate(self.input_names):
            cols.update({f"gain {n}": self.gain[:, i], f"gain {n} low": self.gain_low[:, i],
                         f"gain {n} high": self.gain_high[:, i], f"gain {n} std": self.gain_std[:, i]})
        cols["undefined"] = self.undefined
        return pd.DataFrame(cols, index=pd.MultiIndex.from_arrays(list(self.ubar.T), names=list(self.input_names)))

    def __repr__(self) -> str:
        return (f"StaticSurfaceBand({self.model_name or 'model'}: {self.ubar.shape[0]} points of "
                f"({', '.join(self.input_names)}), {self.method}, level={self.level:g}, "
                f"{_widest(self)})")


def _widest(band) -> str:
    """A static band's widest half-width in words, over the points that have a band (a Monte Carlo band has none,
    NaN, where no draw reached an equilibrium: one such point made the whole repr 'max ±nan')."""
    w = (band.ybar_high - band.ybar_low) / 2
    w = w[np.isfinite(w)]
    return f"max ±{w.max():.4g} in ȳ" if w.size else "no band (no draw reached an equilibrium)"


def _check_static_band(band, point_shape: tuple[int, ...], gain_shape: tuple[int, ...]) -> None:
    """A static band's arrays frozen and of their shapes (ȳ's per point, the gains' per point and input), and its
    other fields what a band can be (a value read from a hand-edited file is held to them)."""
    for f in ("ubar", "ybar", "ybar_low", "ybar_high", "ybar_std", "gain", "gain_low", "gain_high", "gain_std",
              "undefined"):
        a = frozen(getattr(band, f))
        shape = gain_shape if f.startswith("gain") or f == "ubar" else point_shape  # ū and the gains: (M[, m])
        if a.shape != shape:
            raise ValueError(f"{f} must have shape {shape}, got {a.shape}")
        object.__setattr__(band, f, a)
    check_level(band.level)
    check_band_draws(band.method, band.n_samples, band.undefined, "undefined")
    check_band_finite(band, ("ubar", "ybar", "gain"))  # the estimate's own curve: it reaches its equilibria
    check_band_finite(band, ("ybar_low", "ybar_high", "ybar_std", "gain_low", "gain_high", "gain_std"),
                      band.undefined == 1)
    check_band_values(band.ybar_std, band.ybar_low, band.ybar_high, "ybar_std", "ybar_low", "ybar_high")
    check_band_values(band.gain_std, band.gain_low, band.gain_high, "gain_std", "gain_low", "gain_high")


def _draws_band(Y: np.ndarray, G: np.ndarray, level: float, y: np.ndarray, g: np.ndarray,
                w: np.ndarray) -> tuple[np.ndarray, ...]:
    """The band of Monte Carlo draws: ȳ (P, M) and gains (P, M[, m]) → (undefined, ȳ low, high, std, gain low,
    high, std), a draw left out at a point where its ȳ or a gain is not finite. The spreads are of the draws'
    deviations from the estimate's ȳ ``y`` and gains ``g``, each times its draw's weight ``w`` (:func:`theta_draws`):
    the normal draws' spread, which the multivariate t's is not at small dof (it has none at dof <= 2: a PE
    member's σ_SF from 4-6 points gave 0.19 to 4.0 across seeds where the delta method's was 0.05)."""
    ok = np.isfinite(Y) & np.isfinite(G).reshape(G.shape[:2] + (-1,)).all(axis=2)
    undefined = 1.0 - ok.mean(axis=0)
    a = (1 - level) / 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns give NaN bands
        Yn, Gn = np.where(ok, Y, np.nan), np.where(ok.reshape(ok.shape + (1,) * (G.ndim - 2)), G, np.nan)
        ylo, yhi = np.nanquantile(Yn, [a, 1 - a], axis=0)
        glo, ghi = np.nanquantile(Gn, [a, 1 - a], axis=0)
        wy, wg = w.reshape((-1,) + (1,) * (Y.ndim - 1)), w.reshape((-1,) + (1,) * (G.ndim - 1))
        return (undefined, ylo, yhi, _scaled_nanstd(wy * (Yn - y)), glo, ghi, _scaled_nanstd(wg * (Gn - g)))


def _scaled_nanstd(D: np.ndarray) -> np.ndarray:
    """nanstd along the first axis, each column over the power of two above its largest |entry| (exact): draws
    deviating by 1e198 (a static curve at ū = 1e200) have a spread of that size, which their squares read inf."""
    with warnings.catch_warnings(), np.errstate(over="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns give NaN
        e = binary_exponent(np.nanmax(np.abs(D), axis=0, initial=0.0))
        return np.ldexp(np.nanstd(np.ldexp(D, -e), axis=0), e)


def _refuse_overflow(ub: np.ndarray, yb: np.ndarray, hy: np.ndarray, gain: np.ndarray, hg: np.ndarray,
                     drawn: bool, gradients: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """``ValueError`` naming the first level ``ub`` (M,) or point (M, m) where the band of ȳ (``yb`` ± ``hy``, its
    half width or spread) or of a gain (``gain`` ± ``hg``) leaves the float range: said as that, not as a band whose
    ends are not finite numbers. ``drawn`` (Monte Carlo): a NaN spread is no draw kept there, no overflow.
    ``gradients``: the delta method's of ȳ (M, n) and of the gains (M, …, n); where one leaves the float range (its
    spread then NaN or inf) that is said, not the band, which may well be floats there (ȳ = 1.785e308 ± 4e305 at
    ū = 1e308, ∂ȳ/∂a = 3.2e308), and Monte Carlo offered, which needs no gradient."""
    M = len(yb)
    if gradients is not None:
        lost = {k: ~np.isfinite(np.asarray(G).reshape(M, -1)).all(axis=1) for k, G in zip(("ȳ", "its gain"), gradients)}
        if (lost["ȳ"] | lost["its gain"]).any():
            i = int(np.flatnonzero(lost["ȳ"] | lost["its gain"])[0])
            what = "ȳ" if lost["ȳ"][i] else "its gain"  # the gain's follows from ȳ's: the first said alone
            raise ValueError(f"the delta method's gradient of {what} leaves the float range (±1.8e308) at "
                             f"ū = {point_texts(np.asarray(ub))[i]} (ȳ = {yb[i]:g}): method='monte-carlo' draws the "
                             "band without it; or give levels where the static map's gradient is a float")
    with np.errstate(over="ignore", invalid="ignore"):
        ends = {"ȳ": (np.column_stack([yb + hy, yb - hy]), hy.reshape(M, -1)),
                "its gain": (np.column_stack([(gain + hg).reshape(M, -1), (gain - hg).reshape(M, -1)]),
                             hg.reshape(M, -1))}
    over = {k: (np.isinf(x) | (np.isnan(x) & ~(drawn & np.isnan(h)).all(axis=1, keepdims=True))).any(axis=1)
            for k, (x, h) in ends.items()}
    bad = over["ȳ"] | over["its gain"]
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        what = " and ".join(f"the band of {k}" for k in over if over[k][i])
        leave = "leave" if " and " in what else "leaves"
        at = point_texts(np.asarray(ub))[i]
        raise ValueError(f"the band overflows at ū = {at} (ȳ = {yb[i]:g}): {what} {leave} "
                         "the float range (±1.8e308); give levels where the static map and its band are floats")


def _own(y: np.ndarray, g: np.ndarray, y_est: np.ndarray, g_est: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The estimate's ȳ and gains as the draws' batch computed them (``y``, ``g``): a draw equal to θ̂ then deviates by
    exactly 0 (a CLS estimate fixed by its constraints has a band of no spread, not of round-off times the draws'
    weights); the estimate's own ``y_est``, ``g_est`` where the batch gave no number."""
    return np.where(np.isfinite(y), y, y_est), np.where(np.isfinite(g), g, g_est)


def theta_draws(theta: np.ndarray, cov: np.ndarray, n: int, rng: np.random.Generator,
                dof: int | None = None, factor: np.ndarray | None = None,
                weights: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """``n`` draws θ ~ N(θ, cov) (or the multivariate t with ``dof``), shape (n, n_terms), in the units of θ.

    With ``factor`` F (cov = FᵀF, :attr:`ParameterUncertainty.cov_factor`) the draws are θ + Fᵀz, z
    standard normal: exact to the factor's accuracy. Without it they are drawn in standardised
    coordinates (the correlation matrix's eigenvectors, scaled back by the standard deviations): in
    engineering units the entries of ``cov`` span decades, and the eigensolver's round-off on ``cov``
    itself, of the size of its largest entry, swamps the small-scale parameters. Even standardised, the
    eigensolver holds the correlation matrix's small directions only to eps: at an offset (y near 2e5,
    u near 3000) those are the directions the static curve is known along, and a Monte Carlo band drawn
    so was 20 times too wide.

    Parameters
    ----------
    theta : ndarray, shape (n_terms,)
        The mean.
    cov : ndarray, shape (n_terms, n_terms)
        The covariance (symmetrised; negative eigenvalues of round-off taken as 0).
    n : int
        Number of draws.
    rng : numpy.random.Generator
        Source of the normal deviates.
    dof : int, optional
        Degrees of freedom of an estimated covariance (:attr:`ParameterUncertainty.dof`): the draws
        are then multivariate t, normal draws over √(χ²_dof / dof), the spread the intervals'
        Student's t quantile stands for (normal draws are too narrow on a short record).
    factor : ndarray, shape (k, n_terms), optional
        F with cov = FᵀF, in the units of θ (preferred over ``cov`` when given).
    weights : bool
        Return also each draw's √(χ²_dof / dof), shape (n,) (ones without ``dof``): a draw's deviation times it
        is the normal draw it came from, whose spread exists at every dof (the t's has no variance at dof <= 2).
    """
    if factor is not None:
        F = np.asarray(factor, float)
        dev = rng.standard_normal((n, F.shape[0])) @ F
    else:
        cov = (cov + cov.T) / 2
        sd = np.sqrt(np.clip(np.diag(cov), 0, None))
        sd = np.where(sd > 0, sd, 1.0)
        w, V = np.linalg.eigh(cov / np.outer(sd, sd))
        dev = ((rng.standard_normal((n, theta.size)) * np.sqrt(np.clip(w, 0, None))) @ V.T) * sd
    w = np.ones(n) if dof is None else np.sqrt(rng.chisquare(dof, n) / dof)
    dev /= w[:, None]
    return (theta[None, :] + dev, w) if weights else theta[None, :] + dev


def static_curve_band(
    uncertainty: ParameterUncertainty,
    ubar: np.ndarray | Sequence[float],
    *,
    method: str = "delta",
    n_samples: int = 2000,
    seed: int = 0,
    y0: float | np.ndarray | None = None,
) -> StaticCurveBand:
    """Confidence band of the static curve and gain implied by a parameter covariance.

    Parameters
    ----------
    uncertainty : ParameterUncertainty
        From :func:`ls_uncertainty`, :func:`cls_uncertainty`, :func:`pe_uncertainty` or
        :func:`se_uncertainty`.
    ubar : array_like, shape (M,)
        Input levels (engineering units).
    method : {"delta", "monte-carlo"}
        ``"delta"``: first order through the static map, ±t·std with std² = gᵀ cov g, g the
        gradient of ȳ(ū) (implicit differentiation of eq. (5)) or of the gain, and t the
        quantile of the parameters' intervals (Student's, :attr:`ParameterUncertainty.quantile`).
        ``"monte-carlo"``: θ drawn from the multivariate t around θ̂ with scale ``cov`` and the
        same degrees of freedom (the normal's draws, like a z band, are too narrow on a short
        record), the stable equilibrium nearest the estimate's taken for each
        draw, the band from the draws' quantiles (honest where the map is curved, e.g. near a
        vanishing denominator).
    n_samples : int
        Monte Carlo draws (at least 10; checked for either method).
    seed : int
        Seed of the Monte Carlo draws.
    y0 : float or array_like of shape (M,), optional
        Initial output (output units; one for all ū or one per ū) to pick the estimate's equilibrium where
        several are stable (as for :meth:`graybox.Model.static_curve`).

    Returns
    -------
    StaticCurveBand
        Draw it with :func:`graybox.plots.plot_static_band`.

    Warns
    -----
    UncertaintyWarning
        Monte Carlo draws that reach no equilibrium at some ū were left out of the band there (its
        ``undefined`` says how many): the band is narrower than the parameters' uncertainty.

    Raises
    ------
    ValueError
        The estimate has no stable equilibrium at some ū; a model with several inputs.
    TypeError
        ``uncertainty`` is not a :class:`ParameterUncertainty`.
    """
    if not isinstance(uncertainty, ParameterUncertainty):
        raise TypeError(f"uncertainty must be a ParameterUncertainty (from ls_uncertainty, cls_uncertainty, "
                        f"pe_uncertainty or se_uncertainty), got {type(uncertainty).__name__}")
    check_choice(method, "method", BAND_METHODS)
    n_samples = check_count(n_samples, "n_samples", low=MIN_DRAWS)  # checked for either method: a bad value is never ignored
    seed = check_seed(seed)
    if uncertainty.model.n_inputs > 1:
        raise ValueError(f"static_curve_band is defined for one input; the model has {uncertainty.model.n_inputs} "
                         f"inputs {uncertainty.model.input_names}: static_surface_band gives the band at points of input space")
    # the one input's levels as every static path reads them, a column (M, 1) too; flattened, an (M, 2) grid of two
    # inputs' levels would be read as 2M levels of the one
    shape = np.shape(ubar)
    if len(shape) > 2 or (len(shape) == 2 and shape[1] != 1):
        raise ValueError(f"ubar must be levels of the model's one input, shape (M,), got shape {shape} (a column "
                         "(M, 1) is read as those levels)")
    ub = one_input_levels(ubar)
    if ub.size == 0:
        raise ValueError("ubar must be a non-empty array of finite input levels")
    m = uncertainty.model
    if method == "monte-carlo":  # each draw's gains are M × n_terms floats (static_gains): counted before any work
        check_count(n_samples, "n_samples", each=((ub.size, "points"), (m.theta.size, "terms")))
    st, th, cov = m.structure, m.theta, uncertainty.cov
    yb = m.static_curve(ub, y0=y0)
    p, A = static_powers(st, curve=True)
    uc = ub[:, None]
    gain = static_gains(p, A, th[None], uc, yb[None])[0, :, 0]
    if method == "delta":
        z = uncertainty.quantile  # Student's t, as the parameters' intervals: σ² is estimated
        Gy = static_theta_gradient_of(p, A, th, uc, yb)
        Gg = static_gain_gradient(p, A, th, uc, yb, Gy)[:, 0, :]
        sy, sg = uncertainty.std_of(Gy), uncertainty.std_of(Gg)
        _refuse_overflow(ub, yb, z * sy, gain, z * sg, drawn=False, gradients=(Gy, Gg))
        return StaticCurveBand(ub, yb, yb - z * sy, yb + z * sy, sy, gain, gain - z * sg, gain + z * sg, sg,
                               uncertainty.level, "delta", 0, np.zeros(ub.size), m.name, m.units)
    rng = np.random.default_rng(seed)
    thetas, w = theta_draws(th, cov, n_samples, rng, dof=uncertainty.dof, factor=uncertainty.cov_factor, weights=True)
    both = np.vstack([th, thetas])  # the estimate first: the draws' deviations from it, with the same round-off
    Y = reached_equilibria(st, both, ub, yb).ybar
    G = static_gains(p, A, both, uc, Y)[..., 0]
    undefined, ylo, yhi, sy, glo, ghi, sg = _draws_band(Y[1:], G[1:], uncertainty.level, *_own(Y[0], G[0], yb, gain),
                                                        w)
    _refuse_overflow(ub, yb, sy, gain, sg, drawn=True)
    warn_dropped_draws("static_curve_band", undefined)
    return StaticCurveBand(ub, yb, ylo, yhi, sy, gain, glo, ghi, sg, uncertainty.level, "monte-carlo", n_samples,
                           undefined, m.name, m.units)


def static_surface_band(
    uncertainty: ParameterUncertainty,
    ubar: np.ndarray | Sequence[Sequence[float]] | pd.DataFrame,
    *,
    method: str = "delta",
    n_samples: int = 2000,
    seed: int = 0,
    y0: float | np.ndarray | None = None,
) -> StaticSurfaceBand:
    """Confidence band of the static surface and its gains implied by a parameter covariance (several inputs).

    :func:`static_curve_band` at points of input space: the same two methods, the same draws.

    Parameters
    ----------
    uncertainty : ParameterUncertainty
        Of a model of several inputs (or one), from :func:`ls_uncertainty`, :func:`cls_uncertainty`,
        :func:`pe_uncertainty` or :func:`se_uncertainty`.
    ubar : array_like, shape (M, m), or DataFrame
        Points of input space (engineering units), columns in the model's ``input_names`` order (a
        DataFrame is read by column name); one point may be given as shape (m,).
    method : {"delta", "monte-carlo"}
        ``"delta"``: first order through the static map, ±t·std with std² = gᵀ cov g, g the gradient of ȳ(ū)
        or of a gain ∂ȳ/∂ū_i (implicit differentiation of eq. (5)), t the quantile of the parameters' intervals.
        ``"monte-carlo"``: θ drawn from the multivariate t around θ̂ (scale ``cov``), the stable equilibrium
        reached from the estimate's taken for each draw, the band from the draws' quantiles.
    n_samples : int
        Monte Carlo draws (at least 10; checked for either method).
    seed : int
        Seed of the Monte Carlo draws.
    y0 : float or array_like of shape (M,), optional
        Initial output to pick the estimate's equilibrium where several are stable (output units).

    Returns
    -------
    StaticSurfaceBand

    Warns
    -----
    UncertaintyWarning
        Monte Carlo draws that reach no equilibrium at some point were left out of the band there.

    Raises
    ------
    ValueError
        The estimate reaches no equilibrium at some point; ``ubar`` of the wrong shape or not finite.
    TypeError
        ``uncertainty`` is not a :class:`ParameterUncertainty`.
    """
    if not isinstance(uncertainty, ParameterUncertainty):
        raise TypeError(f"uncertainty must be a ParameterUncertainty (from ls_uncertainty, cls_uncertainty, "
                        f"pe_uncertainty or se_uncertainty), got {type(uncertainty).__name__}")
    check_choice(method, "method", BAND_METHODS)
    n_samples = check_count(n_samples, "n_samples", low=MIN_DRAWS)  # for either method, as static_curve_band
    seed = check_seed(seed)
    m = uncertainty.model
    names = tuple(m.input_names)
    ub = points_of_inputs(ubar, names)
    if ub.shape[0] == 0:
        raise ValueError("ubar must hold at least one point of input levels")
    st, th = m.structure, m.theta
    if method == "monte-carlo":  # each draw's gains are M × n_terms × m floats (static_gains): counted before any work
        check_count(n_samples, "n_samples", each=((ub.shape[0], "points"), (th.size, "terms"), (len(names), "inputs")))
    yb = static_surface(st, th, ub, y0, input_names=names)  # ValueError naming the points it reaches nothing at
    p, A = static_powers(st, names)
    gain = static_gains(p, A, th[None], ub, yb[None])[0]
    if method == "delta":
        z = uncertainty.quantile
        dy = static_theta_gradient_of(p, A, th, ub, yb)
        Gg = static_gain_gradient(p, A, th, ub, yb, dy)  # (M, m, n)
        sy = uncertainty.std_of(dy)
        sg = uncertainty.std_of(Gg.reshape(-1, th.size)).reshape(gain.shape)
        _refuse_overflow(ub, yb, z * sy, gain, z * sg, drawn=False, gradients=(dy, Gg))
        return StaticSurfaceBand(ub, names, yb, yb - z * sy, yb + z * sy, sy, gain, gain - z * sg, gain + z * sg, sg,
                                 uncertainty.level, "delta", 0, np.zeros(ub.shape[0]), m.name, m.units)
    rng = np.random.default_rng(seed)
    thetas, w = theta_draws(th, uncertainty.cov, n_samples, rng, dof=uncertainty.dof, factor=uncertainty.cov_factor,
                            weights=True)
    both = np.vstack([th, thetas])  # the estimate first, as static_curve_band
    Y = reached_surface(st, both, ub, yb, inputs=names).ybar  # (P + 1, M)
    G = static_gains(p, A, both, ub, Y)
    undefined, ylo, yhi, sy, glo, ghi, sg = _draws_band(Y[1:], G[1:], uncertainty.level, *_own(Y[0], G[0], yb, gain), w)
    _refuse_overflow(ub, yb, sy, gain, sg, drawn=True)
    warn_dropped_draws("static_surface_band", undefined)
    return StaticSurfaceBand(ub, names, yb, ylo, yhi, sy, gain, glo, ghi, sg, uncertainty.level, "monte-carlo",
                             n_samples, undefined, m.name, m.units)
