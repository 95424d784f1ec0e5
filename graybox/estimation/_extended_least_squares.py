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
changes. The measure is unit-free and does not depend on N. After ``max_iter`` iterations
without convergence ELS warns once (:class:`ELSConvergenceWarning`, saying why in words)
and returns the last iterate. Residuals of the first ``max_lag`` samples of each record,
which have no regression row, are taken as zero.

Long records
------------
On long plant records (N ≥ 10⁴) the relaxed iteration used to run to its cap with a
residual change stuck at 4–6 % per iteration. The stopping rule is not the cause: the
map itself stops contracting. Linearised, one relaxed step acts on the residuals as
I − β C(q) (C(q) = 1 + Σ c_l q^-l), which contracts at every frequency iff

    β < β* = 2 · min_ω Re 1/C(e^{jω})

(|1 − βC|² < 1 ⇔ β < 2 Re C / |C|²). The MA estimates of long plant records approach
C ≈ 1 − 1.6 q⁻¹ + 0.75 q⁻² (roots of modulus ≈ 0.87: output noise on a slow plant), for
which β* falls below 1/2 and then to 0 (C is barely positive real): no fixed relaxation
contracts there, and lowering β only freezes the iteration. The fixed point exists all
the same. So, when the relaxed iteration has stalled (no new smallest change for 10
iterations) and the MA part is made of plain lags ``e(k-l)``, ELS solves the fixed-point
equations directly: with ξ(c) = (y − Ψθ)/C(q) (the recursive one-step prediction errors)
and θ(c) eliminated by Ψᵀξ = 0, the ne equations E(ξ)ᵀξ / ξᵀξ = 0 (ξ uncorrelated with its
own lags 1 … ne) are solved for c by Levenberg–Marquardt, which copes with their nearly
singular direction (a near common factor of C and the output-lag polynomial makes them
flat along a curve of c). They also have spurious minima of |h| off the root, so the solve
starts from the stalled c and then, for lags 1 … ne, from C = (1 − ρq⁻¹)^ne with ρ in
(0.85, 0.7, 0.95, 0.5), until |h| ≤ 1e-9 (at most 600 evaluations of h in all). The
result then passes the same stopping rule, so the estimate
is the same fixed point that the relaxed iteration reaches whenever it converges; results
on short records, where it converges by itself, are unchanged.

Every least-squares solve works on unit-RMS columns (:func:`graybox.core._least_squares.column_scales`; the
process block is QR-factored once and reused), so parameters come back in engineering units
without loss of precision.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from scipy.linalg import solve_triangular

from ..core._simulation_kernels import inverse_ma_filter
from ..core._least_squares import (binary_scaled, check_identified, check_rows, column_scales, free_directions,
                                   refuse_beyond_float_range, scaled_lstsq, unscaled_theta)
from ..models._coerce import as_structure, records_of
from ..models._model import Model
from ..selection._centring import centred_data, is_closed, raw_theta, signal_offsets
from ..core._records import Dataset, Record, carried_from
from ..core._regressors import regressor_matrix, stacked_regressors
from ..core._terms import Structure, Term
from ..core._validation import (Relocked, check_bool, check_int, check_real, check_fields, check_sequence, check_str,
                                frozen, short_value, warn)

__all__ = ["els", "ELSResult", "ELSConvergenceWarning", "noise_terms"]

#: The paper's MA order (Section IV-A).
DEFAULT_NE = 2


class ELSConvergenceWarning(RuntimeWarning):
    """ELS reached ``max_iter`` before its residuals stopped changing."""


@dataclass(frozen=True, eq=False)
class ELSResult(Relocked):
    """The result of :func:`els`: the model and how the iteration went.

    Attributes
    ----------
    model : Model
        Process parameters (engineering units) with the MA part in ``noise_structure`` /
        ``noise_theta`` (used for estimation only, never in simulation).
    n_iter : int
        Iterations with noise regressors (0 when there is no MA part, or when least squares fits the data to
        round-off: the MA part is then zero).
    converged : bool
        Whether the stopping rule was met (see the module docstring).
    history : tuple of float
        ‖ξ̃_i − ξ_{i−1}‖ / ‖ξ̃_i‖ of each iteration (see the module docstring).
    residuals : tuple of ndarray
        Final residuals ξ per record, shape (N_r,), zero on the first ``max_lag`` samples.
    theta_ls : ndarray
        The plain least-squares process parameters (iteration 0), for comparison.
    n_direct : int
        Evaluations of the fixed-point equations by the direct solve (module docstring, "Long
        records"); 0 when the relaxed iteration converged by itself.
    """

    model: Model
    n_iter: int
    converged: bool
    history: tuple[float, ...]
    residuals: tuple[np.ndarray, ...]
    theta_ls: np.ndarray
    n_direct: int = 0

    def __post_init__(self) -> None:
        check_fields(self)
        # counts as els makes them, held to a result built by hand or read from an edited file
        check_int(self.n_iter, "ELSResult: n_iter", low=0)
        check_int(self.n_direct, "ELSResult: n_direct", low=0)
        # read-only copies: what the caller's arrays become afterwards never changes the result
        object.__setattr__(self, "theta_ls", frozen(self.theta_ls))
        n = len(self.model.structure)
        if self.theta_ls.shape != (n,):  # the least-squares estimate of the model's own process terms
            raise ValueError(f"ELSResult: theta_ls must have shape ({n},), one parameter per process term of the "
                             f"model, got {self.theta_ls.shape}")
        object.__setattr__(self, "residuals", tuple(frozen(r) for r in self.residuals))
        # what an iteration can report (a file edited by hand, a result built wrong is refused, as NeuralFit's)
        if len(self.history) != self.n_iter:
            raise ValueError(f"ELSResult: history holds one residual change per iteration, {self.n_iter} (n_iter); got "
                             f"{len(self.history)}")
        h = np.asarray(self.history, dtype=float)
        if np.any(np.isnan(h)) or np.any(h < 0):
            raise ValueError("ELSResult: history holds relative residual changes, never negative or NaN; got "
                             f"{short_value(self.history)}")
        if not self.residuals:
            raise ValueError("ELSResult: residuals holds the residuals of each record fitted, at least one")

    def __repr__(self) -> str:
        return (f"ELSResult(model={self.model.name!r}, n_params={self.model.n_params}, n_iter={self.n_iter}, "
                f"converged={self.converged})")


#: Iterations without a new smallest residual change after which the relaxed iteration has stalled.
_STALL = 10
#: Evaluations of the fixed-point equations allowed to the direct solve.
_LM_NFEV = 600
#: Double roots ρ of the extra starts of the direct solve, and |h| that counts as a root.
_RHO_STARTS = (0.85, 0.7, 0.95, 0.5)
_ROOT_TOL = 1e-9


def _pure_lags(ns: Structure) -> list[int | None]:
    """For each noise term: its lag l when it is exactly e(k-l), else None."""
    out: list[int | None] = []
    for t in ns:
        f = t.factors
        out.append(f[0][1] if len(f) == 1 and f[0][0] == "e" and f[0][2] == 1 else None)
    return out


def _shift_offsets(process: Structure, ns: Structure, recs: list[Record]) -> dict[str, float] | None:
    """The signals' centres (:func:`~graybox.selection._centring.signal_offsets`) where the model is closed under
    shifts of them, else None: the process terms (:func:`~graybox.selection._centring.is_closed`) and the MA part,
    each noise term with every divisor of its signal factors beside its e factors (e(k-1)y(k-1) needs e(k-1), as
    e(k-1)(y(k-1) − c) = e(k-1)y(k-1) − c e(k-1)); plain lags e(k-l) always are."""
    if not is_closed(process):
        return None
    offsets = signal_offsets(recs)
    try:  # the map to the raw signals' parameters names the divisor a term needs and the structure lacks
        raw_theta(Structure(list(process) + list(ns)), np.ones(len(process) + len(ns)), offsets)
    except ValueError:
        return None
    return offsets


def _ma_coefficients(c: np.ndarray, lags: list[int | None]) -> np.ndarray:
    """[1, c_1, …, c_L] of the linear MA part C(q) = 1 + Σ c_l q^-l (terms e(k-l) only)."""
    L = max([l for l in lags if l is not None], default=0)
    out = np.zeros(L + 1)
    out[0] = 1.0
    for ci, l in zip(c, lags):
        if l is not None:
            out[l] += ci
    return out


def _ma_invertible(C: np.ndarray) -> bool:
    """1/C(q) is stable: every root of C inside the unit circle (ξ = C⁻¹(q)(…) does not grow)."""
    return len(C) < 2 or bool(np.max(np.abs(np.roots(C))) < 1.0)


def _frequency_response(C: np.ndarray) -> np.ndarray:
    """C(e^{jω}) on a grid of [0, π] fine enough for its degree."""
    w = np.linspace(0.0, np.pi, max(513, 64 * len(C)))
    return np.exp(-1j * np.outer(w, np.arange(len(C)))) @ C


def _contraction_limit(C: np.ndarray) -> float:
    """β* = 2·min_ω Re 1/C(e^{jω}): the relaxed step contracts every frequency iff β < β*.

    |1 − β C|² = 1 − 2β Re C + β² |C|² < 1  ⇔  β < 2 Re C / |C|² = 2 Re 1/C. ``0`` when C is
    not positive real (then no β contracts every frequency).
    """
    F = _frequency_response(C)
    m2 = np.abs(F) ** 2
    if np.any(m2 <= 1e-300):
        return 0.0
    return max(0.0, float(2.0 * np.min(F.real / m2)))


def _ma_text(C: np.ndarray) -> str:
    parts = ["1"] + [f"{'-' if c < 0 else '+'} {abs(c):.3g} q^-{l}" for l, c in enumerate(C) if l and c != 0]
    return " ".join(parts)


def _no_convergence_message(max_iter: int, last: float, tol: float, beta: float, C: np.ndarray,
                            direct_failure: str = "") -> str:
    F = _frequency_response(C)
    rate = float(np.max(np.abs(1.0 - beta * F)))
    b = _contraction_limit(C)
    msg = (f"ELS did not converge in {max_iter} iterations: the residuals still changed by {last:.2e} "
           f"(relative) in the last one, above tol {tol:g}; returning the last iterate. ")
    if direct_failure:
        msg += f"Solving the fixed-point equations directly failed: {direct_failure}. "
    if len(C) == 1:
        return msg + "Its noise terms are not all plain lags e(k-l), so no cause is diagnosed."
    why = f"The MA part C(q) = {_ma_text(C)} "
    if b <= 0:
        why += ("is not positive real (Re 1/C(e^jw) <= 0 at some frequency): no relaxation makes the "
                "iteration contract there; the MA estimate is not reliable.")
    elif rate >= 1.0:
        why += (f"needs a relaxation below {b:.3g} for the relaxed iteration to contract; {beta:.3g} "
                "was used.")
    else:
        why += (f"lets the iteration contract only by a factor {rate:.3g} per iteration with relaxation "
                f"{beta:.3g}: raise max_iter or tol.")
    return msg + why


class _DirectMA:
    """The ELS fixed-point equations solved directly, for an MA part made of plain lags.

    The residuals are the model's one-step prediction errors ξ = (y − Ψθ) / C(q), computed
    from rest on each record. The fixed point has them orthogonal to every regressor:
    Ψᵀξ = 0, linear in θ for a given c (θ(c) = (Ψᵀ Ψ_C)⁻¹ Ψᵀ y_C with Ψ_C, y_C filtered by
    1/C), and E(ξ)ᵀξ = 0, the ne equations h(c) left for the MA coefficients. They are
    solved by Levenberg–Marquardt (MINPACK, forward differences), which copes with the
    nearly singular direction that a near common factor of C and the output-lag polynomial
    gives on long records.
    """

    def __init__(self, psis: np.ndarray, y: np.ndarray, lags: list, bounds: np.ndarray) -> None:
        self.n = psis.shape[1]
        self.X = np.column_stack([psis, y])  # [Ψ y], C-contiguous
        self.lags = [int(l) for l in lags]
        self.bounds = np.asarray(bounds, dtype=np.int64)
        self.nfev = 0

    def _shift(self, x: np.ndarray, l: int) -> np.ndarray:
        out = np.zeros_like(x)
        for k0, k1 in zip(self.bounds[:-1], self.bounds[1:]):
            if k1 - k0 > l:
                out[k0 + l : k1] = x[k0 : k1 - l]
        return out

    def _xi(self, c: np.ndarray):
        """(ξ, E(ξ)) with θ eliminated (Ψᵀξ = 0 solved for θ), or None when 1/C(q) is unstable."""
        C = _ma_coefficients(c, self.lags)
        if not _ma_invertible(C):
            return None
        F = inverse_ma_filter(self.X, C, self.bounds)  # [Ψ_C y_C]
        G = self.X[:, : self.n].T @ F  # [Ψᵀ Ψ_C, Ψᵀ y_C]
        th = np.linalg.solve(G[:, : self.n], G[:, self.n])
        xi = F[:, self.n] - F[:, : self.n] @ th
        return xi, np.column_stack([self._shift(xi, l) for l in self.lags])

    def _h(self, c: np.ndarray) -> np.ndarray:
        self.nfev += 1
        st = self._xi(c)
        if st is None:
            return np.ones(c.size)  # far from a root: the solver shortens its step
        xi, E = st
        return (E.T @ xi) / (xi @ xi)

    def starts(self, c: np.ndarray) -> list[np.ndarray]:
        """Where to start: the stalled iterate's c, then C(q) = (1 − ρq⁻¹)^ne for a few ρ (lags 1 … ne).

        The equations are flat along a curve of c and have spurious minima of ‖h‖ off it, so one
        start may end at a point that is no root; a double-root family spans that curve.
        """
        out = [np.asarray(c, float)]
        ne = len(self.lags)
        if sorted(self.lags) == list(range(1, ne + 1)):
            for rho in _RHO_STARTS:
                poly = np.poly(np.full(ne, rho))  # [1, c_1, …, c_ne]
                out.append(np.array([poly[l] for l in self.lags]))
        return out

    def solve(self, c: np.ndarray, max_nfev: int) -> np.ndarray | None:
        """Residuals ξ at a root of h found from the starts, or None when none is found."""
        from scipy.optimize import least_squares  # slow to import: loaded where used
        for c0 in self.starts(c):
            left = int(max_nfev) - self.nfev
            if left < 10:
                break
            with np.errstate(all="ignore"):
                # forward differences with a step well above the round-off of h (filters of N samples)
                sol = least_squares(self._h, c0, method="lm", xtol=1e-14, ftol=1e-15, gtol=1e-15,
                                    diff_step=1e-6, max_nfev=left)
            if np.all(np.isfinite(sol.fun)) and np.max(np.abs(sol.fun)) <= _ROOT_TOL:
                st = self._xi(sol.x)
                if st is not None:
                    return st[0]
        return None


def noise_terms(ne: int) -> Structure:
    """The linear MA terms ``e(k-1) … e(k-ne)`` as a Structure."""
    ne = check_int(ne, "ne", low=0)
    return Structure(Term((("e", l, 1),)) for l in range(1, ne + 1))


def _noise_structure(noise: object) -> Structure:
    """Explicit noise terms given as a sequence, parsed with errors that name ``noise``."""
    items = check_sequence(noise, "noise", "an integer ne >= 0, a Structure or a sequence of noise terms",
                           ordered="noise terms (the order of their θ)")
    try:
        return Structure(items)
    except (TypeError, ValueError) as exc:  # a number among the terms, too: said with the argument's name
        raise type(exc)(f"noise: {exc}") from None


def _resolve(structure, noise, data: object = None) -> tuple[Structure, Structure]:
    """Split the arguments of :func:`els` into (process, noise) structures (an MA order ``noise`` checked against
    ``data``'s longest record before its terms are built)."""
    st = as_structure(structure, with_noise=True)  # a Selection's or a Model's noise terms come along
    process, carried = st.process, st.noise
    if len(process) == 0:
        raise ValueError("the structure has no process terms to estimate")
    if noise is None:
        ns = carried if len(carried) else noise_terms(DEFAULT_NE)
    elif isinstance(noise, (int, np.integer)) and not isinstance(noise, bool):
        ne = check_int(noise, "noise: ne", low=0)
        if data is not None and ne:
            # a lag as long as the longest record fits no regression row; noise=10**12 built 10^12 terms before
            # the records said so (it never finished)
            longest = max(len(r) for r in records_of(data))
            if ne >= longest:
                raise ValueError(f"noise: ne = {ne} lags the residuals by as many samples as the longest record "
                                 f"has ({longest}) or more: no regression row is left; take a smaller ne")
        ns = noise_terms(ne)
    else:
        ns = noise if isinstance(noise, Structure) else _noise_structure(noise)
        not_noise = [str(t) for t in ns if not t.is_noise]
        if not_noise:
            raise ValueError(f"noise must hold noise terms e(k-l) only; got {', '.join(not_noise)}")
    return process, ns


@dataclass(frozen=True, eq=False)
class _Regression:
    """The stacked process regression of one :func:`els` call: Ψ (rows of all records), y, row bounds."""

    process: Structure
    ns: Structure
    recs: list[Record]
    L: int
    psi: np.ndarray
    y: np.ndarray
    bounds: np.ndarray

    def per_record(self, x: np.ndarray) -> list[np.ndarray]:
        """Stacked residuals ``x`` split per record, zero on the first ``L`` samples of each."""
        out = []
        for i, r in enumerate(self.recs):
            e = np.zeros(len(r))
            e[self.L :] = x[self.bounds[i] : self.bounds[i + 1]]
            out.append(e)
        return out

    def noise_regressors(self, x: np.ndarray) -> np.ndarray:
        """E: the noise terms' regressor matrix with ``x`` as the residuals e."""
        recs, ns, L = self.recs, self.ns, self.L
        if len(recs) == 1:
            return regressor_matrix(ns, recs[0].u, recs[0].y, e=self.per_record(x)[0], start=L,
                                    input_names=recs[0].input_names)
        return np.vstack([regressor_matrix(ns, r.u, r.y, e=e, start=L, input_names=r.input_names)
                          for r, e in zip(recs, self.per_record(x))])


def _regression(process: Structure, ns: Structure, recs: list[Record]) -> _Regression:
    """Build Ψ and y over all records (rows from the largest lag on), checking there are enough rows."""
    L = max(process.max_lag, ns.max_lag)
    psi, y = stacked_regressors(process, recs, start=L)
    n_p = len(process)
    check_rows(psi.shape[0], n_p + len(ns))
    bounds = np.cumsum([0] + [len(r) - L for r in recs])
    return _Regression(process, ns, recs, L, psi, y, bounds)


def _refuse_zero_noise_columns(reg: _Regression, E: np.ndarray) -> None:
    """ValueError naming the noise terms whose column is zero on every row (said as "collinear, rank 0" before), and
    why where the records are too short: residuals before sample L of a record are 0, so e(k-l) needs one longer
    than L + l."""
    zero = [t for t, z in zip(reg.ns, ~np.any(E, axis=0)) if z]
    if not zero:
        return
    longest = max(len(r) for r in reg.recs)
    lag = max(l for s, l, _ in zero[0].factors if s == "e")  # the first one's longest residual lag
    names = ", ".join(str(t) for t in zero)
    verb = "is" if len(zero) == 1 else "are"
    if all(longest <= reg.L + max(l for s, l, _ in t.factors if s == "e") for t in zero):
        why = (f"the residuals of each record's first {reg.L} samples (the largest lag) have no regression row and "
               f"are taken as 0, and the longest record has {longest} samples, where {zero[0]} needs more than "
               f"{reg.L} + {lag}; give longer records or a shorter MA part (noise=)")
    else:
        why = "its other factors vanish where the residuals do not; leave it out of the MA part (noise=)"
    raise ValueError(f"ELS: the noise regressor(s) {names} {verb} zero on every row: {why}")


class _ExtendedFit:
    """The least-squares step of ELS, with Ψ factored once.

    Ψ is the same in every iteration: factor it once (scaled columns, Householder QR) and
    solve each extended problem by block elimination. The noise columns are made
    orthogonal to range(Ψ), c comes from that small problem and θ by back-substitution
    from Qᵀy − (QᵀE)c; an iteration reads Q twice (QᵀE and Q(QᵀE)): O(N·n·ne).
    """

    def __init__(self, reg: _Regression) -> None:
        self.reg = reg
        self.sp = column_scales(reg.psi)
        self.Q, self.R = np.linalg.qr(reg.psi / self.sp)
        self.Qty = self.Q.T @ reg.y
        self.y_perp = reg.y - self.Q @ self.Qty

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """One ELS least-squares step with ``x`` in the noise regressors: (θ, c, ξ̃, change)."""
        Q, m_e = self.Q, len(self.reg.ns)
        E = self.reg.noise_regressors(x)
        _refuse_zero_noise_columns(self.reg, E)
        se = column_scales(E)
        Es = E / se
        B = Q.T @ Es
        E_perp = Es - Q @ B
        cs, _, rank, _ = np.linalg.lstsq(E_perp, self.y_perp, rcond=None)
        if rank < m_e:
            raise ValueError(
                f"ELS: the noise regressors {self.reg.ns} are collinear with the process terms or each other "
                f"(rank {rank} < {m_e}); the MA part is not identifiable from these data"
            )
        th = solve_triangular(self.R, self.Qty - B @ cs, lower=False) / self.sp
        x_fit = self.y_perp - E_perp @ cs  # = y − Ψθ − E c
        den = float(np.linalg.norm(x_fit))
        change = float(np.linalg.norm(x_fit - x)) / den if den > 0 else 0.0
        return th, cs / se, x_fit, change


class _DirectSolve:
    """The direct solve of the fixed-point equations, taken over once the relaxed iteration stalls."""

    def __init__(self, reg: _Regression, sp: np.ndarray, lags: list) -> None:
        self.reg, self.sp, self.lags = reg, sp, lags
        self.solver: _DirectMA | None = None
        self.n_direct = 0
        self.failure = ""

    def wanted(self, hist: list[float]) -> bool:
        """Whether to solve directly: once the iteration stalls (no new smallest change in ``_STALL``) and after."""
        return self.solver is not None or len(hist) - 1 - int(np.argmin(hist)) >= _STALL

    def step(self, c: np.ndarray) -> np.ndarray | None:
        """Residuals at a root of the fixed-point equations from ``c``, or None (budget spent or no root)."""
        if self.solver is None:
            self.solver = _DirectMA(self.reg.psi / self.sp, self.reg.y, self.lags, self.reg.bounds)
        if self.solver.nfev < _LM_NFEV and not self.failure:
            nxt = self.solver.solve(c, max_nfev=_LM_NFEV)
            self.n_direct = self.solver.nfev
            if nxt is not None:
                return nxt
            self.failure = f"no root found in {self.n_direct} evaluations"
        return None

    def why(self) -> str:
        """Why the direct solve did not end the iteration, for the warning ("" when it never started)."""
        if self.failure:
            return self.failure
        return f"it did not reach the fixed point in {self.n_direct} evaluations" if self.solver is not None else ""


def _iterate(fit: _ExtendedFit, xi: np.ndarray, theta: np.ndarray, max_iter: int, tol: float,
             relaxation: float, fallback: _DirectSolve | None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[float], bool]:
    """The relaxed iteration (module docstring), handing over to ``fallback`` when it stalls.

    Returns (θ, c, ξ, history, converged) of the last iterate.
    """
    hist: list[float] = []
    c = np.zeros(len(fit.reg.ns))
    converged = False
    for _ in range(int(max_iter)):
        theta, c, xi_fit, delta = fit(xi)
        hist.append(delta)
        if delta <= tol:
            xi = xi_fit
            converged = True
            break
        if fallback is not None and fallback.wanted(hist):
            # the relaxed iteration has stalled: solve the fixed-point equations directly
            # (again from each new fit while it has not met the stopping rule)
            nxt = fallback.step(c)
            if nxt is not None:
                xi = nxt
                continue
        xi = xi + relaxation * (xi_fit - xi)
    return theta, c, xi, hist, converged


def _result(reg: _Regression, theta: np.ndarray, c: np.ndarray, n_iter: int, conv: bool, hist: list[float],
            x: np.ndarray, theta_ls: np.ndarray, name: str, n_direct: int = 0,
            offsets: dict | None = None, exps: dict | None = None) -> ELSResult:
    """The ELSResult: the model with its MA part and the residuals per record (``offsets``: the signals' centres
    the fit ran on, its θ mapped back to the raw signals; the residuals are the same on both; ``exps``: the powers of
    two the signals were scaled by, :func:`~graybox.core._least_squares.binary_scaled`, undone here)."""
    if offsets is not None:
        n = len(reg.process)
        # the MA part too: a noise term's other factors were centred (e(k-1)(y(k-1) − c) = e(k-1)y(k-1) − c e(k-1))
        both = raw_theta(Structure(list(reg.process) + list(reg.ns)), np.r_[theta, c], offsets)
        theta, c, theta_ls = both[:n], both[n:], raw_theta(reg.process, theta_ls, offsets)
    if exps:
        terms = list(reg.process)
        theta, theta_ls = unscaled_theta(theta, terms, exps), unscaled_theta(theta_ls, terms, exps)
        c = unscaled_theta(c, list(reg.ns), exps)
        refuse_beyond_float_range(terms + list(reg.ns), np.r_[theta, c], np.r_[theta_ls, c], prefix=f"{name}: ")
        with np.errstate(over="ignore", under="ignore"):
            x = np.ldexp(x, exps["y"])  # the residuals in the output's units
    m = Model(reg.process, theta, noise_structure=reg.ns, noise_theta=c, name=name, **carried_from(reg.recs))
    res = tuple(frozen(a) for a in reg.per_record(x))
    return ELSResult(m, n_iter, conv, tuple(hist), res, frozen(theta_ls), n_direct)


def _warn_not_converged(max_iter: int, hist: list[float], tol: float, relaxation: float, c: np.ndarray,
                        lags: list, fallback: _DirectSolve | None) -> None:
    """The ELSConvergenceWarning saying why, attributed to the caller of :func:`els`."""
    why = fallback.why() if fallback is not None else ""
    # the contraction is diagnosed for an MA part of plain lags only: beside other noise terms, C(q) of its lags
    # would be part of the noise model, named as the whole
    C = _ma_coefficients(c, lags) if all(l is not None for l in lags) else np.ones(1)
    warn(_no_convergence_message(max_iter, hist[-1], tol, relaxation, C, why), ELSConvergenceWarning)


#: What identifies terms the records leave free, for an estimator that takes no static points.
_NO_STATIC_REMEDY = ("give a record whose input moves ({who} takes no static points: cls, pe_pareto or se_pareto fit the "
                     "records together with static points at several input levels)")


#: The raw output's round-off that :func:`els` reads as no residual at all, in ulps of its RMS: noise-free data at
#: y + 1e4 leave least-squares residuals of about one; noise of 1e-12 of the level (some 4500 ulps) is noise, whose
#: MA part the iteration finds as at y.
ROUNDOFF_ULPS = 16


def els(
    structure: object,
    data: Record | Sequence[Record] | Dataset,
    *,
    noise: int | Structure | None = None,
    max_iter: int = 500,
    tol: float = 1e-6,
    relaxation: float = 0.5,
    direct: bool = True,
    name: str = "ELS",
) -> ELSResult:
    """Extended least squares: process parameters plus an MA noise model.

    Parameters
    ----------
    structure : Structure, sequence of str, Selection, Model, or a result that carries one
        Process terms (in parameter order). A :class:`~graybox.Selection` from
        :func:`~graybox.frols` brings its selected terms and the noise terms of its
        candidates, a Model (or ELSResult) its MA part; a Structure may hold noise terms too
        (they are split off).
    data : Record, sequence of Record, or Dataset
        Identification data (a Dataset's ``ident``), engineering units. Rows never straddle two
        records.
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
    direct : bool
        When the relaxed iteration stalls (no new smallest residual change in
        10 iterations), solve the fixed-point equations directly from the last iterate
        (Levenberg–Marquardt; MA parts made of plain lags ``e(k-l)`` only; module
        docstring, "Long records"). False keeps the relaxed iteration throughout.
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
    process, ns = _resolve(structure, noise, data)
    name = check_str(name, "name")
    max_iter = check_int(max_iter, "max_iter", low=1)
    tol = check_real(tol, "tol", low=0, low_open=True)
    relaxation = check_real(relaxation, "relaxation", low=0, high=1, low_open=True)
    direct = check_bool(direct, "direct")
    # y and the inputs times a power of two where their products would leave the float range (as frols does): the
    # same fit bit for bit, where at y near 1e155 y² overflowed and near 1e-200 the residuals' squares underflowed,
    # and either way the MA part was skipped as if the fit were exact (the iterations' Gram entries underflowed too)
    given = records_of(data)
    recs, exps = binary_scaled(given, Structure(list(process) + list(ns)))
    if exps:  # but a term whose column is no float in the user's units is refused by name, as before (mend51d): the
        # model's own predictions multiply it out
        stacked_regressors(process, given)
    # A model closed under shifts (its process terms, and its MA part: plain lags, or products whose divisors it
    # holds, :func:`_shift_offsets`) is fitted on the centred signals and mapped back (as the SE fits are): the same
    # model, and the same convergence, at any offset of u and y. On the raw ones, terms near 1e8 at 1e4 spreads put
    # round-off into the residual change the stopping rule reads, and the iteration ran to max_iter where at offset 0
    # it converged in 22; an MA part with e(k-1)u(k-1) or e(k-1)y(k-1) kept the raw signals, and its residuals at
    # y + 1e4 were 2e-9 of their spread off those at y.
    reg = _regression(process, ns, recs)
    offsets = _shift_offsets(process, ns, recs)
    # the data's round-off is that of the raw levels: centred signals carry it too (y + 1e4: 1e4 ulps), a few ulps
    # of the raw output (ROUNDOFF_ULPS of them), beside 1e-12 of the output's RMS as fitted
    y_raw = ROUNDOFF_ULPS * np.finfo(float).eps * np.sqrt(np.mean(reg.y**2))
    raw, reg = reg, (reg if offsets is None else _regression(process, ns, centred_data(recs, offsets)))
    # the rule every estimator applies, so that ELS names the terms left free as CLS, PE and SE do (on the raw signals,
    # as they do); where the model is closed under shifts, θ is identified when the centred regression it is fitted on
    # has full rank: the same at every offset, where on the raw signals a closed quadratic in y(k-1), y(k-2) at
    # y + 1e6 read as rank 6 of 7 (its quadratic columns 2.5e-11 from the others) and was refused
    # without noise terms (noise=0) this is plain least squares, and says so (a grid's "ls" cell is this call)
    what, who = ("the ELS process θ", "ELS") if len(ns) else ("the least-squares θ (ELS with no noise terms)",
                                                              "least squares")
    remedy = _NO_STATIC_REMEDY.format(who=who)
    if offsets is None or free_directions([(reg.psi, reg.psi.shape[0])]).shape[1]:
        check_identified([("the identification records", raw.psi, raw.psi.shape[0])], list(process),
                         what=what, remedies=(remedy, remedy))
    theta_ls = scaled_lstsq(reg.psi, reg.y)
    xi = reg.y - reg.psi @ theta_ls
    # No MA part, or a model that explains the data to round-off (of the raw signals, whatever their zero): then the
    # MA regressors would be round-off columns, so the MA part is zero by definition.
    if len(ns) == 0 or np.sqrt(np.mean(xi**2)) <= 1e-12 * np.sqrt(np.mean(reg.y**2)) + y_raw:
        return _result(reg, theta_ls, np.zeros(len(ns)), 0, True, [], xi, theta_ls, name, offsets=offsets, exps=exps)

    fit = _ExtendedFit(reg)
    lags = _pure_lags(ns)
    fallback = _DirectSolve(reg, fit.sp, lags) if direct and all(l is not None for l in lags) else None
    theta, c, xi, hist, converged = _iterate(fit, xi, theta_ls, max_iter, tol, relaxation, fallback)
    if not converged:
        _warn_not_converged(max_iter, hist, tol, relaxation, c, lags, fallback)
    n_direct = fallback.n_direct if fallback is not None else 0
    return _result(reg, theta, c, len(hist), converged, hist, xi, theta_ls, name, n_direct, offsets, exps)
