"""Extended least squares (ELS) for polynomial NARMAX models.

The paper (Sections III-A and IV-A) estimates the process parameters of the ERR-selected
structure together with a moving-average noise model of order ``ne = 2``:

    y(k) = ψ(k)ᵀθ + Σ_{l=1..ne} c_l ξ(k−l) + ξ(k).

The residuals ξ are unknown before a model exists, so ELS iterates: residuals of the
previous iterate become the regressors ``e(k−l)`` of the next least-squares problem. The
MA part soaks up the coloured part of the equation error, so that the process
parameters are not biased by it (plain least squares is, whenever the output lags are
regressors and the noise is not white). The MA part is returned with the model
(``Model.noise_structure`` / ``Model.noise_theta``) and never used in simulation.

Iteration
---------
Iteration 0 is plain least squares; its residuals ξ_0 start the MA regressors. Iteration
``i ≥ 1`` solves the least-squares problem in [θ; c] with ξ_{i−1} as the regressors
``e(k−l)`` and computes the residuals of that fit, ξ̃_i = y − Ψθ_i − Ψ_e(ξ_{i−1}) c_i (the
classic batch ELS of Aguirre's school and of SysIdentPy's ``unbiased=True``). Then

    ξ_i = ξ_{i−1} + β (ξ̃_i − ξ_{i−1}),      β = ``relaxation`` (default 1/2).

Why relax: with β = 1 the iteration is close to the map ξ ↦ v − Σ_l c_l ξ(k−l), which is not
a contraction for MA parts such as (0.8, 0.5) (|C(e^{jω})| reaches 2.3): there it oscillates
for ever with a 50 % change per iteration and leaves a biased estimate. Computing the residuals recursively
instead (pseudo-linear regression, ξ = (y − Ψθ)/C(q)) converges fast there but diverges on
the bundled plant data, whose equation-error MA polynomial has a root near 1 (output noise
on a slow plant). Under-relaxation converges in both cases, to the same fixed point: the
residuals for which ξ = y − Ψθ − Ψ_e(ξ)c, i.e. the model's own one-step prediction errors.

Stopping rule
-------------
ELS stops at the first iteration ``i`` with

    ‖ξ̃_i − ξ_{i−1}‖₂ ≤ tol · ‖ξ̃_i‖₂      (default tol = 1e-6),

that is, when the residuals a fit produces equal (to that relative precision) the residuals
it was given as regressors: the fixed point, after which no regressor or parameter
changes. The measure is unit-free. After ``max_iter`` iterations without convergence ELS
warns (:class:`ELSConvergenceWarning`) and returns the last iterate. Residuals of the first ``max_lag`` samples of each record, which have no
regression row, are taken as zero.

Every least-squares solve works on unit-RMS columns (:func:`graybox._ls.column_scales`; the
process block is QR-factored once and reused), so parameters come back in engineering units
without loss of precision.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from scipy.linalg import solve_triangular

from ._ls import column_scales, scaled_lstsq
from ._model import Model
from ._records import Dataset, Record, as_records
from ._regressors import regressor_matrix, stacked_regressors
from ._selection import Selection
from ._terms import Structure, Term
from ._validation import check_int, check_real, frozen

__all__ = ["els", "ELSResult", "ELSConvergenceWarning", "noise_terms"]

#: The paper's MA order (Section IV-A).
DEFAULT_NE = 2


class ELSConvergenceWarning(RuntimeWarning):
    """ELS reached ``max_iter`` before its residuals stopped changing."""


@dataclass(frozen=True, eq=False)
class ELSResult:
    """The result of :func:`els`: the model and how the iteration went.

    Attributes
    ----------
    model : Model
        Process parameters (engineering units) with the MA part in ``noise_structure`` /
        ``noise_theta`` (used for estimation only, never in simulation).
    n_iter : int
        Iterations with noise regressors (0 when there is no MA part).
    converged : bool
        Whether the stopping rule was met (see the module docstring).
    history : tuple of float
        ‖ξ̃_i − ξ_{i−1}‖ / ‖ξ̃_i‖ of each iteration (see the module docstring).
    residuals : tuple of ndarray
        Final residuals ξ per record, shape (N_r,), zero on the first ``max_lag`` samples.
    theta_ls : ndarray
        The plain least-squares process parameters (iteration 0), for comparison.
    """

    model: Model
    n_iter: int
    converged: bool
    history: tuple[float, ...]
    residuals: tuple[np.ndarray, ...]
    theta_ls: np.ndarray

    def __repr__(self) -> str:
        return (f"ELSResult(model={self.model.name!r}, n_params={self.model.n_params}, n_iter={self.n_iter}, "
                f"converged={self.converged})")


def noise_terms(ne: int) -> Structure:
    """The linear MA terms ``e(k-1) … e(k-ne)`` as a Structure."""
    ne = check_int(ne, "ne", low=0)
    return Structure(Term((("e", l, 1),)) for l in range(1, ne + 1))


def _resolve(structure, noise) -> tuple[Structure, Structure]:
    """Split the arguments of :func:`els` into (process, noise) structures."""
    if isinstance(structure, Selection):
        process, carried = structure.structure, structure.noise
    else:
        st = structure if isinstance(structure, Structure) else Structure(structure)
        process, carried = st.process, st.noise
    if len(process) == 0:
        raise ValueError("the structure has no process terms to estimate")
    if noise is None:
        ns = carried if len(carried) else noise_terms(DEFAULT_NE)
    elif isinstance(noise, (int, np.integer)) and not isinstance(noise, bool):
        ns = noise_terms(int(noise))
    else:
        ns = noise if isinstance(noise, Structure) else Structure(noise)
        not_noise = [str(t) for t in ns if not t.is_noise]
        if not_noise:
            raise ValueError(f"noise must hold noise terms e(k-l) only; got {', '.join(not_noise)}")
    return process, ns


def els(
    structure: Structure | Selection | Sequence[str],
    data: Record | Sequence[Record] | Dataset,
    *,
    noise: int | Structure | None = None,
    max_iter: int = 500,
    tol: float = 1e-6,
    relaxation: float = 0.5,
    name: str = "ELS",
) -> ELSResult:
    """Extended least squares: process parameters plus an MA noise model.

    Parameters
    ----------
    structure : Structure, Selection or sequence of str
        Process terms (in parameter order). A :class:`~graybox.Selection` from
        :func:`~graybox.frols` brings its selected terms and the noise terms of its
        candidates; a Structure may hold noise terms too (they are split off).
    data : Record or sequence of Record
        Identification data, engineering units. Rows never straddle two records.
    noise : int, Structure or None
        The MA part: ``ne`` for ``e(k-1) … e(k-ne)``, or explicit noise terms. ``None``: the
        noise terms carried by ``structure``, else the paper's ``ne = 2``. ``0`` gives plain
        least squares. Noise terms may be products with u and y too (e.g. ``e(k-1)u(k-1)``).
    max_iter : int
        Largest number of ELS iterations (>= 1).
    tol : float
        Relative residual change that ends the iteration (> 0); see the module docstring.
    relaxation : float
        β in (0, 1]: the fraction of the new residuals mixed into the regressors each
        iteration (1 is unrelaxed ELS; see the module docstring for why the default is 1/2).
    name : str
        Name of the returned model.

    Returns
    -------
    ELSResult
        ``.model``: ``theta`` (process, engineering units), ``noise_structure`` and
        ``noise_theta`` set (the MA part is ignored by ``simulate`` and ``predict``); the
        iteration count, convergence flag, history, final residuals and the plain LS θ.

    Raises
    ------
    ValueError
        Bad arguments, too-short records, or a regressor matrix without full column rank
        (collinear terms: the parameters are not identifiable from these data).

    Warns
    -----
    ELSConvergenceWarning
        When ``max_iter`` iterations pass without meeting the stopping rule.
    """
    process, ns = _resolve(structure, noise)
    max_iter = check_int(max_iter, "max_iter", low=1)
    tol = check_real(tol, "tol", low=0, low_open=True)
    relaxation = check_real(relaxation, "relaxation", low=0, high=1, low_open=True)
    recs = as_records(data)
    L = max(process.max_lag, ns.max_lag)
    psi, y = stacked_regressors(process, recs, start=L)
    n_p = len(process)
    if psi.shape[0] <= n_p + len(ns):
        raise ValueError(f"{psi.shape[0]} regression rows are too few for {n_p + len(ns)} parameters")
    theta_ls = scaled_lstsq(psi, y)
    xi = y - psi @ theta_ls
    bounds = np.cumsum([0] + [len(r) - L for r in recs])

    def per_record(x: np.ndarray) -> list[np.ndarray]:
        out = []
        for i, r in enumerate(recs):
            e = np.zeros(len(r))
            e[L:] = x[bounds[i] : bounds[i + 1]]
            out.append(e)
        return out

    def done(theta, c, n_iter, conv, hist, x) -> ELSResult:
        m = Model(process, theta, noise_structure=ns, noise_theta=c, name=name)
        res = tuple(frozen(a) for a in per_record(x))
        return ELSResult(m, n_iter, conv, tuple(hist), res, frozen(theta_ls))

    if len(ns) == 0:
        return done(theta_ls, np.zeros(0), 0, True, [], xi)
    # A model that explains the data to round-off leaves no noise to model: the MA
    # regressors would be round-off columns, so the MA part is zero by definition.
    if np.sqrt(np.mean(xi**2)) <= 1e-12 * np.sqrt(np.mean(y**2)):
        return done(theta_ls, np.zeros(len(ns)), 0, True, [], xi)

    # Ψ is the same in every iteration: factor it once (scaled columns, Householder QR) and
    # solve each extended problem by block elimination. The noise columns are made
    # orthogonal to range(Ψ), c comes from that small problem and θ by back-substitution;
    # each iteration then costs O(N·n·ne) instead of a fresh O(N·(n+ne)²) factorisation.
    sp = column_scales(psi)
    Q, R = np.linalg.qr(psi / sp)
    y_perp = y - Q @ (Q.T @ y)
    m_e = len(ns)
    hist: list[float] = []
    theta, c = theta_ls, np.zeros(m_e)
    converged = False
    for it in range(1, int(max_iter) + 1):
        E = np.vstack([regressor_matrix(ns, r.u, r.y, e=e, start=L, input_names=r.input_names)
                       for r, e in zip(recs, per_record(xi))])
        se = column_scales(E)
        Es = E / se
        E_perp = Es - Q @ (Q.T @ Es)
        cs, _, rank, _ = np.linalg.lstsq(E_perp, y_perp, rcond=None)
        if rank < m_e:
            raise ValueError(
                f"ELS: the noise regressors {ns} are collinear with the process terms or each other "
                f"(rank {rank} < {m_e}); the MA part is not identifiable from these data"
            )
        theta = solve_triangular(R, Q.T @ (y - Es @ cs), lower=False) / sp
        c = cs / se
        xi_fit = y_perp - E_perp @ cs  # = y − Ψθ − E c
        den = float(np.linalg.norm(xi_fit))
        delta = float(np.linalg.norm(xi_fit - xi)) / den if den > 0 else 0.0
        hist.append(delta)
        if delta <= tol:
            xi = xi_fit
            converged = True
            break
        xi = xi + relaxation * (xi_fit - xi)
    if not converged:
        warnings.warn(
            f"ELS did not converge in {max_iter} iterations (last relative residual change {hist[-1]:.2e} > "
            f"tol {tol:g}); returning the last iterate",
            ELSConvergenceWarning,
            stacklevel=2,
        )
    return done(theta, c, len(hist), converged, hist, xi)
