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

Every least-squares solve works on unit-RMS columns (:func:`graybox.ls.column_scales`; the
process block is QR-factored once and reused), so parameters come back in engineering units
without loss of precision.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from scipy.linalg import solve_triangular

from .ls import column_scales, scaled_lstsq
from .model import Model
from .records import Dataset, Record
from .regressors import regressor_matrix, stacked_regressors
from .selection import Selection, _as_records, frols
from .terms import Candidates, Structure, Term

__all__ = ["els", "ElsInfo", "ELSConvergenceWarning", "noise_terms", "black_box_models", "section_black_box"]

#: The paper's MA order (Section IV-A).
DEFAULT_NE = 2


class ELSConvergenceWarning(RuntimeWarning):
    """ELS reached ``max_iter`` before its residuals stopped changing."""


@dataclass(frozen=True, eq=False)
class ElsInfo:
    """How an ELS run went (returned with ``full_output=True``).

    Attributes
    ----------
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

    n_iter: int
    converged: bool
    history: tuple[float, ...]
    residuals: tuple[np.ndarray, ...]
    theta_ls: np.ndarray


def noise_terms(ne: int) -> Structure:
    """The linear MA terms ``e(k-1) … e(k-ne)`` as a Structure."""
    if isinstance(ne, bool) or int(ne) != ne or ne < 0:
        raise ValueError(f"ne must be an integer >= 0, got {ne!r}")
    return Structure(Term((("e", l, 1),)) for l in range(1, int(ne) + 1))


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
    data: Record | Sequence[Record],
    noise: int | Structure | None = None,
    max_iter: int = 500,
    tol: float = 1e-6,
    relaxation: float = 0.5,
    name: str = "ELS",
    full_output: bool = False,
) -> Model | tuple[Model, ElsInfo]:
    """Extended least squares: process parameters plus an MA noise model.

    Parameters
    ----------
    structure : Structure, Selection or sequence of str
        Process terms (in parameter order). A :class:`~graybox.selection.Selection` from
        :func:`~graybox.selection.frols` brings its selected terms and the noise terms of its
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
    full_output : bool
        Also return an :class:`ElsInfo`.

    Returns
    -------
    Model
        ``theta`` (process, engineering units), ``noise_structure`` and ``noise_theta`` set;
        the MA part is ignored by ``simulate`` and ``predict``.
    ElsInfo
        Only with ``full_output=True``.

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
    if isinstance(max_iter, bool) or int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"max_iter must be a positive integer, got {max_iter!r}")
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a positive number, got {tol!r}")
    if not (np.isfinite(relaxation) and 0 < relaxation <= 1):
        raise ValueError(f"relaxation must lie in (0, 1], got {relaxation!r}")
    recs = _as_records(data)
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

    def info(n_iter, conv, hist, x, th_ls=theta_ls) -> ElsInfo:
        res = tuple(per_record(x))
        for a in res:
            a.setflags(write=False)
        th = np.array(th_ls, copy=True)
        th.setflags(write=False)
        return ElsInfo(n_iter, conv, tuple(hist), res, th)

    def done(theta, c, n_iter, conv, hist, x):
        m = Model(process, theta, noise_structure=ns, noise_theta=c, name=name)
        return (m, info(n_iter, conv, hist, x)) if full_output else m

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
        E = np.vstack([regressor_matrix(ns, r.u, r.y, e, start=L) for r, e in zip(recs, per_record(xi))])
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


# --------------------------------------------------------------------------------------
# the paper's black-box models on the bundled plant data (hook for `graybox reproduce`)

#: (degree ℓ, number of terms) of the paper's models (15) and (17).
PAPER_BLACK_BOX: tuple[tuple[int, int], ...] = ((2, 17), (3, 23))


def black_box_models(
    ident: Record | Sequence[Record],
    ny: int = 6,
    nu: int = 6,
    ne: int = DEFAULT_NE,
    sizes: Sequence[tuple[int, int]] = PAPER_BLACK_BOX,
) -> dict[str, tuple[Selection, Model]]:
    """FROLS + ELS as in Section IV-A, for each (degree, n_terms) in ``sizes``.

    Returns
    -------
    dict
        ``"ELS ℓ=2"`` → (Selection, Model), … in the order of ``sizes``.
    """
    out = {}
    for degree, n_terms in sizes:
        sel = frols(Candidates(ny=ny, nu=nu, ne=ne, degree=degree), ident, n_terms=n_terms)
        out[f"ELS ℓ={degree}"] = (sel, els(sel, ident, name=f"ELS ℓ={degree}"))
    return out


def section_black_box(quick: bool = True, out: Path | None = None, data: Dataset | None = None) -> str:
    """``graybox reproduce`` section: black-box ERR + ELS models on the bundled plant data.

    Prints each model's Table I row (J_S ident, J_S valid, J_SF, N_p; MSE in mlc²) and its
    equation. ``quick`` and ``out`` are accepted for the common section signature; this
    section is fast and draws nothing.
    """
    from .evaluate import evaluate

    if data is None:
        from .datasets import load_pumping  # imported late: the data module is optional here

        data = load_pumping()
    models = black_box_models(data.ident)
    table = evaluate({k: m for k, (_, m) in models.items()}, data)
    lines = [
        "== Black-box models: ERR (FROLS) structure selection + ELS with MA(2) (Section IV-A) ==",
        f"ny = nu = 6, ne = {DEFAULT_NE}; 17 terms at ℓ = 2 (eq. 15), 23 terms at ℓ = 3 (eq. 17); "
        "the MA part is used for estimation only.",
        table[["J_S ident", "J_S valid", "J_SF", "N_p"]].to_string(float_format=lambda v: f"{v:.4f}"),
    ]
    for key, (sel, m) in models.items():
        lines.append(f"-- {key}: 1 - ΣERR = {1.0 - sel.err_total:.3e}")
        lines.append("   " + m.equation())
    return "\n".join(lines)
