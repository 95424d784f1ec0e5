"""Structure selection by simulation error: SEMP (Piroddi & Spinelli, 2003).

FROLS ranks terms by how much of the one-step-ahead output energy they explain. That criterion
knows nothing of the free run, and under slowly varying inputs (staircases, where u(k-1) ≈ u(k-2)
almost everywhere) it picks wrong terms even on noise-free data. SEMP scores a structure by what a
model is for: its free-run (simulation) error.

Algorithm (Piroddi & Spinelli, Int. J. Control 76(17), 2003, "simulation error minimization with
pruning"): start from the included terms (default none); then repeat

1. *forward*: for every remaining candidate, fit the structure with that term added by least
   squares (one-step prediction error, cheap) and score it by the mean squared free-run error;
   add the candidate with the smallest score;
2. *pruning*: for every term of the structure, fit and score the structure without it; while the
   best removal does not increase the score by more than ``prune_tol`` (relative), remove that term
   (never the term just added, nor an included one);

until the stopping rule holds. On noise-free data a structure can run exactly (at the round-off floor)
while a smaller one does too, and no removal reaches it (y(k-2), u(k-1), u(k-2), u(k-1)², u(k-2)² beside
the true y(k-1), u(k-1), u(k-1)²: y(k-1), a combination of the five, is collinear with them): there the
search swaps a term for a candidate that keeps the run exact when a removal then does too (the path
shows the swap as a removal and an addition), so the smallest exact structure wins the tie.

All candidates of one step are scored at once by the compiled
population kernel: every candidate model is a member of a population of the full candidate
structure, with zeros for the terms it does not hold, so one batched free run per record scores
a whole step. The least-squares fits of all candidates of a step come from one QR factorisation
of the current structure's columns of the triangular factor of [scaled candidates, y] (a border
per candidate, with QR's accuracy: no Gram matrix, whose squared conditioning an offset of the
signals makes felt), so a step costs one batched free run plus O(n_candidates²) per term.

Free runs start from each record's first L measured samples, L the largest lag among the
candidates, and every score counts samples L … N−1 of every record, so all structures are judged
on the same samples. A free run that diverges scores inf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal, Sequence

import numpy as np
import pandas as pd
import scipy.linalg

from ..core._gram import triangular_factor
from ..core._least_squares import (binary_scaled, column_scales, one_blas_thread, output_scale, rank_tolerance,
                                   refuse_beyond_float_range, unscaled_levels, unscaled_theta)
from ..core._regressors import refuse_non_finite_columns, stacked_regressors
from ..core._simulation_kernels import batch_sse, encode, input_products, record_inputs
from ..models._model import Model, model_input_names
from ..core._records import Dataset, Record, as_records, carried_from, check_units, require_lengths
from ._forward_regression import _DUPLICATE_TOL, CRITERIA, CandidateWarning, criterion_of_sizes
from ._stopping import choose_model, stop_rule
from ..core._terms import Structure, Term, structure_of
from . import _centring
from ..core._validation import (Relocked, FrozenFrame, check_bool, check_choice, check_fields, check_int,
                                check_mean_square, check_real, check_theta, frozen, warn)

__all__ = ["semp", "SEMPResult"]

#: The free-run RMS error that is round-off at least, in ulps of the output's RMS level (fast plants).
ROUND_OFF_ULPS = 2.0**13
#: The free-run MSE that is round-off at least, as a fraction of the output's mean square: (2^13 ulps)^2.
ROUND_OFF_MS = (ROUND_OFF_ULPS * np.finfo(float).eps) ** 2
#: Ulps of round-off per unit of the free run's error amplification (exact runs erred up to 4 per unit: a margin of 8).
ROUND_OFF_GAIN = 2.0**5
#: Scores this close (relative) are one score: the same data in other units scored the candidates of a step 1e-13
#: apart (relative), and two candidates 1.4e-14 apart (one model: u(k-1)u(k-3) and u(k-2)u(k-3) beside the others
#: on a staircase) swapped places with y × 1000 and u × 60.
TIE = ROUND_OFF_ULPS * np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class SEMPResult(Relocked):
    """The result of :func:`semp`: the chosen structure and the path that led to it.

    Attributes
    ----------
    structure : Structure
        The selected process terms, in the order they were added.
    theta : ndarray, shape (n_terms,)
        Least-squares (one-step) parameters of ``structure`` on the selection data, engineering units.
    score : float
        Mean squared free-run error of that model (output units²).
    path : pandas.DataFrame
        One row per accepted step: ``step``, ``action`` (``"add"``, ``"remove"``, ``"include"``),
        ``term``, ``n_terms`` after the step, ``score`` (MSE of the free run, output units²),
        ``criterion`` (the information criterion of the structure after the step) and
        ``structure`` (the terms after the step, as text).
    forward_scores : pandas.DataFrame
        Every candidate's score at every forward step (rows: step, columns: candidate terms;
        NaN for terms already in the structure, inf for a diverging or collinear candidate):
        the terms tried and their scores.
    criterion : str
        The information criterion of the path (``"aic"``, ``"bic"``, ``"fpe"`` or ``"ebic"``).
    stop : str
        Why selection stopped, in words.
    n_rows : int
        Samples scored (after the largest lag, summed over records).
    input_names : tuple of str, optional
        The model's inputs, in the column order of an input array (default: as
        :class:`~graybox.Model`'s; :func:`semp` takes the records').
    Ts : float, optional
        The sampling period (s) of the records it was fitted on (None: unknown); :attr:`model` carries it.
    units : tuple, optional
        The units of the input(s) and the output of those records (the input's one str, or one per input;
        :func:`semp` takes the records'); :attr:`model` carries them. Empty: unknown.
    """

    structure: Structure
    theta: np.ndarray
    score: float
    path: pd.DataFrame = FrozenFrame()
    forward_scores: pd.DataFrame = FrozenFrame()
    criterion: str
    stop: str
    n_rows: int
    input_names: tuple[str, ...] | None = None
    Ts: float | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")

    #: Columns every path holds (a loaded file is checked against them).
    PATH_COLUMNS = ("step", "action", "term", "n_terms", "score", "criterion", "structure")

    def __post_init__(self) -> None:
        check_fields(self)  # types first: path and forward_scores are DataFrames
        # checked and defaulted as a Model's (:attr:`model` carries them)
        names = model_input_names(self.structure, self.input_names)
        object.__setattr__(self, "input_names", names)
        if self.Ts is not None:
            object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        object.__setattr__(self, "units", check_units(self.units, "SEMPResult", len(names)))
        # finite, as the model it gives needs (files load through here); a read-only copy, as a Selection keeps
        object.__setattr__(self, "theta", frozen(check_theta(len(self.structure), self.theta)))
        check_choice(self.criterion, "criterion", CRITERIA)
        check_mean_square(self.score, "SEMPResult: score (the free-run MSE)")
        if self.n_rows < 1:
            raise ValueError(f"SEMPResult: n_rows counts the samples scored, >= 1; got {self.n_rows}")
        missing = [c for c in self.PATH_COLUMNS if c not in self.path.columns]
        if missing:
            raise ValueError(f"the path lacks the column(s) {missing}")

    @property
    def model(self) -> Model:
        """The selected structure with its least-squares parameters, named ``"SEMP"``."""
        return Model(self.structure, self.theta, name="SEMP", input_names=self.input_names, Ts=self.Ts,
                     units=self.units)

    def __repr__(self) -> str:
        return (f"SEMPResult(n_terms={len(self.structure)}, score={self.score:.4g}, steps={len(self.path)}, "
                f"stop={self.stop!r})")


class _Scorer:
    """Least-squares fits and batched free-run scores of sub-structures of one candidate set."""

    def __init__(self, process: Structure, records: list[Record], threads: int):
        self.process = process
        self.records = records
        self.L = L = process.max_lag
        self.code = code = encode(process)
        self.threads = threads
        blocks, targets, slopes = [], [], []
        self.U = []
        require_lengths(records, L)
        for r in records:
            U = input_products(code.fptr, code.fsig, code.flag, code.fpow, record_inputs(r, code.input_names), L)
            self.U.append(U)
            with np.errstate(over="ignore", invalid="ignore"):  # a product beyond the float range: named below
                blocks.append(_psi(code, U, r.y, L))
                slopes.append(_output_slopes(code, U, r.y, L).sum(axis=0))  # summed: no second N × C array
            targets.append(r.y[L:])
        psi = np.vstack(blocks)
        y = np.concatenate(targets)
        # numpy's 'overflow encountered in multiply' escaped, and the message named no candidate
        refuse_non_finite_columns(psi, process, "candidate ")
        if not np.any(y):
            # every model then scores 0 (its criterion N ln 0): nothing to rank, as for frols
            raise ValueError("the output is identically zero on the scored samples (after the largest lag): "
                             "free-run errors cannot rank structures")
        self.n_rows = y.size
        self.zero = ~np.any(psi, axis=0)
        self.s = column_scales(psi)  # RMS without squaring a large column past the float range
        # the triangular factor of [S, y] (S the unit-RMS candidates): every fit below is a fit of its
        # columns, reduced by QR, with QR's accuracy; a Gram matrix SᵀS squares the conditioning (u in
        # [1000, 1002] put noise-free θ 3 % off, y about 1e6 made the true terms 'collinear')
        self.R = triangular_factor(psi, y, self.s)
        self.own = np.einsum("ij,ij->j", self.R[:, :-1], self.R[:, :-1])  # ‖s_j‖²: N, or 0 for a zero column
        # what a candidate holds beyond its mean, ‖s_j − mean‖², the reference of the rank test (an offset is no
        # information: y(k-1) beside y(k-2) at y near 1e6, rho 0.999, added 7.6e-8 of its raw norm, 9e-4 without
        # the offset, and was called collinear); a column constant to round-off (the constant, u² of a two-level
        # input) is judged on its whole norm
        with np.errstate(over="ignore", under="ignore"):
            centred = y.size * np.var(psi / np.where(self.s > 0, self.s, 1.0), axis=0)
        del psi
        # and more than √eps of its raw norm: a fit conditioned past 1/√eps carries more round-off than digits (its
        # κ² term), and u + 1e4, y − 1e5 with degree-2 monomials then gave inexact 6-term structures, not the offsets'
        # note (centre=True) of a search that runs out of terms
        self.eps = max(rank_tolerance(1.0, y.size, len(process)), math.sqrt(np.finfo(float).eps))
        self.ref = np.where(centred > self.eps**2 * self.own, centred, self.own)
        # the tolerance's scale: var(y), or for a constant output its mean square (not 1 output unit²)
        self.yvar = output_scale(y) ** 2
        # free-run errors below this are round-off, not signal: such structures tie (noise-free data). In ulps of the
        # output's level, where round-off lives, times the free run's error amplification: an exact structure's run
        # of y(k) = c + rho y(k-1) + b u(k-1) + d u(k-1)^2 erred by up to 4 ulps RMS × min(1/(1 − rho), N) for rho
        # 0.9 … 0.99999, N 2000 and 20000, y + 0 and + 1e6 (1.7e4 ulps at rho 0.9999, N 20000: past a fixed 2^13), and
        # by up to 38 ulps on fast plants; 1e-20 of the mean square (4.5e5 ulps) took a run 3.5e-5 off at y near 1e6
        # (1.6e5 ulps) for an exact one, and scored it 1e-8 for its 1.2e-9
        gain = _amplification(self.R, np.sum(slopes, axis=0) / y.size, self.s, max(len(r) - L for r in records))
        self.floor = round_off_floor(float(np.mean(y**2)), gain)

    def independent(self, d: np.ndarray, cols: np.ndarray, rank_tol: float) -> np.ndarray:
        """Whether columns ``cols``, adding ``d`` (squared norm) beyond the terms before them, are independent of
        those: more than ``rank_tol`` of what each holds beyond its mean, and more than round-off of its norm."""
        return (d > rank_tol**2 * self.ref[cols]) & (d > self.eps**2 * self.own[cols])

    def fit(self, S: Sequence[int], rank_tol: float) -> np.ndarray | None:
        """θ (engineering units, full candidate length) of the LS fit of terms S, or None if singular (a term
        collinear with those before it, by the rank test of :meth:`bordered`)."""
        S = list(S)
        th = np.zeros(len(self.process))
        if not S:
            return th
        Q, R = np.linalg.qr(self.R[:, S])
        if not np.all(self.independent(np.diag(R) ** 2, np.array(S), rank_tol)):
            return None
        with np.errstate(over="ignore"):  # a θ beyond the float range is inf (scored as a diverging run)
            th[S] = scipy.linalg.solve_triangular(R, Q.T @ self.R[:, -1]) / self.s[S]
        return th

    def bordered(self, S: list[int], cands: np.ndarray, rank_tol: float) -> np.ndarray:
        """θ rows (engineering units) of S ∪ {c} for every c in ``cands``; NaN rows where c is collinear."""
        n = len(self.process)
        out = np.zeros((cands.size, n))
        Gcc = self.own[cands]
        if not S:
            ok = (Gcc > 0) & ~self.zero[cands]
            bc = self.R[:, cands].T @ self.R[:, -1]
            # (over: a candidate whose θ is beyond the float range, u ~ 1e-160 giving u² ~ 1e-320 and θ ~ 1e320,
            # has an inf row, scored as a run that diverges)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                out[np.arange(cands.size), cands] = np.where(ok, bc / Gcc, np.nan) / self.s[cands]
            out[~ok] = np.nan
            return out
        # Q of the columns S; in its coordinates the candidates' and y's parts in S's span (V, w) and
        # beyond it (what c adds beyond S, and y's residual), each formed by rotation, not by subtraction
        k = len(S)
        Q, RS = np.linalg.qr(self.R[:, S], mode="complete")
        R = RS[:k]
        T = Q.T @ self.R[:, cands]
        ty = Q.T @ self.R[:, -1]
        V, w = T[:k], ty[:k]  # (k, C), (k,)
        d = np.sum(T[k:] ** 2, axis=0)
        ok = self.independent(d, cands, rank_tol) & ~self.zero[cands]
        dd = np.where(ok, d, 1.0)
        zc = (T[k:].T @ ty[k:]) / dd
        ZS = scipy.linalg.solve_triangular(R, w[:, None] - V * zc[None, :])  # (k, C)
        with np.errstate(over="ignore"):  # a θ beyond the float range: an inf row, scored as a diverging run
            out[:, S] = (ZS / self.s[S, None]).T
            out[np.arange(cands.size), cands] = zc / self.s[cands]
        out[~ok] = np.nan
        return out

    def scores(self, thetas: np.ndarray) -> np.ndarray:
        """Mean squared free-run error of each row (inf where a run diverges or a row is NaN)."""
        th = np.atleast_2d(thetas)
        good = np.all(np.isfinite(th), axis=1)
        out = np.full(th.shape[0], np.inf)
        if good.any():
            # bounded as gb.js is: a candidate whose free run diverges slowly scores inf, not 1e27
            sse = sum(batch_sse(self.code, th[good], record_inputs(r, self.code.input_names), r.y, self.L, self.threads,
                                U, bounded=True)
                      for r, U in zip(self.records, self.U))
            mse = np.maximum(sse / self.n_rows, self.floor)
            out[good] = np.where(np.isfinite(mse), mse, np.inf)
        return out


def _output_slopes(code, U: np.ndarray, y: np.ndarray, L: int) -> np.ndarray:
    """Each candidate's derivative by the past outputs, summed over its lags (Σ_i ∂ψ/∂y(k−i), from measured y), rows
    L … N−1: a model's θ · their mean is the sum of its output coefficients, linearised along the record."""
    out = np.zeros((y.size - L, code.ny.size))
    for t in range(code.ny.size):
        for d in range(code.ny[t]):  # the product rule: the factor y(k - lag_d) left out, the others kept
            f = U[L:, t].copy()
            for e in range(code.ny[t]):
                if e != d:
                    f *= y[L - code.ylag[t, e]: y.size - code.ylag[t, e]]
            out[:, t] += f
    return out


def _amplification(R: np.ndarray, slope: np.ndarray, s: np.ndarray, longest: int) -> float:
    """How much the free run amplifies an error: 1 / |1 − σ|, σ the sum of the output coefficients (linearised) of
    the least-squares fit of every candidate (the least-norm one where they are collinear), at most the longest
    record's scored samples (an error grows at most so many steps), at least 1. ``slope``: each candidate's mean
    :func:`_output_slopes`, shape (n,)."""
    if not np.any(slope):
        return 1.0
    theta = scipy.linalg.lstsq(R[:, :-1], R[:, -1], cond=np.finfo(float).eps * R.shape[0])[0]
    with np.errstate(all="ignore"):
        sigma = float(np.nansum(theta / np.where(s > 0, s, 1.0) * slope))
    gap = abs(1.0 - sigma)
    return float(min(max(longest, 1), max(1.0, 1.0 / gap if gap > 0 and math.isfinite(gap) else math.inf)))


def round_off_floor(mean_square: float, gain: float) -> float:
    """The free-run MSE that is round-off, not signal (output units²): (2^13 ulps)² of ``mean_square`` (the scored
    output's mean square), or (32 ulps × ``gain``, the free run's error amplification)² where that is more."""
    return (ROUND_OFF_MS * max(1.0, ROUND_OFF_GAIN * gain / ROUND_OFF_ULPS) ** 2
            * max(mean_square, np.finfo(float).tiny))


def free_run_floor(process: Structure, record: Record) -> float:
    """:func:`round_off_floor` of ``record`` scored from the candidates' largest lag on, its amplification that of
    the least-squares fit of every candidate of ``process`` on it (as :func:`semp` floors its scores): a number of
    the data and the candidates, the same for every structure scored on the record, so exact structures tie."""
    L = process.max_lag
    code = encode(process)
    U = input_products(code.fptr, code.fsig, code.flag, code.fpow, record_inputs(record, code.input_names), L)
    y = record.y[L:]
    with np.errstate(all="ignore"):  # a product beyond the float range: no amplification read (1)
        psi = _psi(code, U, record.y, L)
        slope = _output_slopes(code, U, record.y, L).mean(axis=0)
    gain = 1.0
    if np.all(np.isfinite(psi)) and np.all(np.isfinite(slope)) and np.any(y):
        s = column_scales(psi)
        gain = _amplification(triangular_factor(psi, y, s), slope, s, y.size)
    return round_off_floor(float(np.mean(y**2)), gain)


def _psi(code, U: np.ndarray, y: np.ndarray, L: int) -> np.ndarray:
    """Candidate regressors from measured y: input products × output monomials, rows L … N−1."""
    psi = U[L:].copy()
    for t in range(code.ny.size):
        for d in range(code.ny[t]):
            psi[:, t] *= y[L - code.ylag[t, d]: y.size - code.ylag[t, d]]
    return psi


def semp(
    candidates: Structure,
    data: Record | Sequence[Record] | Dataset,
    *,
    n_terms: int | None = None,
    tol: float | None = None,
    criterion: Literal["aic", "bic", "fpe", "ebic"] | None = None,
    max_terms: int | None = None,
    include: Sequence[Term | str] = (),
    prune: bool = True,
    prune_tol: float = 0.0,
    rank_tol: float = 1e-7,
    threads: int = 1,
    centre: bool = False,
) -> SEMPResult:
    """Select model terms by simulation error with pruning (SEMP, Piroddi & Spinelli 2003).

    Exactly one stopping rule applies:

    * ``n_terms``: the structure of that size with the smallest free-run error met on the path; the
      search looks past it, up to 2·n_terms + 4 terms (a term found later can make earlier ones
      redundant, and pruning brings the size back down);
    * ``tol``: stop at the first structure whose free-run error is at most ``tol`` of the output's
      variance (``MSE_free-run / var(y) <= tol``, a unit-free 1 − R² of the free run; for a constant
      output, its mean square instead of var(y));
    * ``criterion`` (the default, ``"bic"``): grow the structure to ``max_terms`` and return the
      structure of the path with the smallest criterion ``N ln MSE_free-run + penalty(k)``.

    Parameters
    ----------
    candidates : Structure
        Candidate terms, e.g. ``Candidates(ny=6, nu=6, degree=2)``; noise terms are ignored.
    data : Record, sequence of Record, or Dataset
        Identification data, engineering units (a Dataset contributes its ``ident`` record).
        Free runs never straddle two records.
    n_terms : int, optional
        Size of the structure to return.
    tol : float, optional
        Relative free-run error in (0, 1) that ends the search (met too by a free run at round-off:
        (2^13 ulps)² of the output's mean square, 3.3e-24 of it, or (32 ulps × the free run's error
        amplification)² where that is more, the amplification 1 / |1 − σ| of the least-squares fit of every
        candidate, σ its output coefficients' sum, at most the record's length: an exact fit meets a
        tolerance below it).
    criterion : {"aic", "bic", "fpe", "ebic"}, optional
        Information criterion of the free-run error (see :func:`graybox.information_criterion`; default
        ``"bic"``; EBIC's p counts the candidates besides the included ones, the all-zero ones and those
        proportional to another on these data, as frols counts its usable candidates).
    max_terms : int, optional
        Largest structure looked at (``tol`` and ``criterion``; default min(30, candidates,
        samples after the largest lag − 1), what the record carries; a larger explicit one is an
        error naming it).
    include : sequence of Term or str
        Terms in every structure, added first (e.g. ``["1"]``); never pruned.
    prune : bool
        Run the pruning steps (``False`` gives forward selection by simulation error only).
    prune_tol : float
        A term is removed when the score without it is at most ``(1 + prune_tol)`` times the
        current score (0: removal must not hurt at all).
    rank_tol : float
        A candidate whose column adds less than ``rank_tol`` of what it holds beyond its mean (of its
        norm, for a constant column) to the current structure is collinear with it and is not tried at
        that step (nor is one adding no more than round-off of its norm); an offset of the signals
        makes no column collinear.
    threads : int
        Threads of the batched free runs.
    centre : bool, optional
        Search on centred signals (default False: on the raw ones): y and each input minus their
        means over ``data``; the chosen centred terms are then expanded into the raw monomials they
        imply, so :attr:`SEMPResult.structure` is their hierarchical closure (every divisor of every
        chosen term, the constant included: more terms than were chosen), less any term the data
        cannot tell from its divisors (a two-level input's u(k-1)^2, and its multiples: in the stop
        text and a CandidateWarning; an included such term, or one of an input held at one level, is
        refused with a ValueError), with least-squares θ on the raw signals and
        :attr:`SEMPResult.score` its free run's MSE (inf, with a RuntimeWarning, when that run
        diverges). The structure and the model's free run are then the same wherever the signals'
        zeros are, up to round-off. :attr:`SEMPResult.path` is the
        centred search's; :attr:`SEMPResult.stop` says what it chose.

    Returns
    -------
    SEMPResult
        The structure, its LS parameters and score, the path (every accepted step) and the
        score of every candidate at every forward step.

    Raises
    ------
    ValueError
        Conflicting or out-of-range arguments, no process candidates, records shorter than the
        candidates' largest lag, an output that is identically zero (with ``centre=True``, constant; or
        a closure of as many terms as regression rows, whose fit would interpolate the record),
        or no candidate that can be added (all collinear or diverging).

    Warns
    -----
    RuntimeWarning
        As :func:`graybox.frols` (the same stopping rule): when ``tol`` is not reached within
        ``max_terms`` terms, or the criterion is smallest at ``max_terms`` terms while candidates
        were left (the curve may still be falling), or at the largest size the record's rows allow
        (samples after the largest lag − 1: the structure interpolates the record). When pruning
        stopped for its budget (6 × the size limit + 10 additions: the limit is ``max_terms`` or its
        default, and 2·n_terms + 4 for ``n_terms``; the later steps only add terms) before the step that
        gave the structure chosen.
    """
    candidates = structure_of(candidates, "candidates")  # a list of terms, a result … (as every structure argument)
    opt = _options(candidates, n_terms, tol, criterion, max_terms, include, prune, prune_tol, rank_tol, threads)
    if check_bool(centre, "centre"):
        return _semp_centred(candidates, data, n_terms=n_terms, tol=tol, criterion=criterion, max_terms=max_terms,
                             include=include, prune=prune, prune_tol=prune_tol, rank_tol=rank_tol, threads=threads)
    # y and the inputs times a power of two where their products would leave the float range (as frols does): the
    # same search bit for bit, where y near 1e-200 underflowed the free-run errors' squares (ln 0 in the criterion)
    given, (data, exps) = data, binary_scaled(data, opt.process)
    # one BLAS thread: the factor of [S, y] and each step's small QRs gain nothing from more, and on a loaded
    # machine lose much (the plant's semp(n_terms=10): 7.2 s on two threads, 3.4 s on one)
    with one_blas_thread():
        sc = _Scorer(opt.process, as_records(data), opt.threads)
        # the size asked for (n_terms, an explicit max_terms) must fit the rows; the look-ahead past n_terms
        # and a default max_terms stop where the rows do (nobody asked for more: nothing said)
        if opt.mode == "n_terms" and sc.n_rows <= opt.n_terms:
            raise ValueError(f"{sc.n_rows} samples after the largest lag are too few for {opt.n_terms} terms")
        if max_terms is not None and sc.n_rows <= opt.limit:
            raise ValueError(f"{sc.n_rows} samples after the largest lag are too few for max_terms = {opt.limit} "
                             "terms: lower it, or leave it out (then it is what the rows carry)")
        opt = replace(opt, limit=min(opt.limit, sc.n_rows - 1))
        if opt.limit < 1:  # a default max_terms follows the rows: one row leaves no size to look at
            raise ValueError(f"{sc.n_rows} sample after the largest lag {opt.process.max_lag} is too few for any term "
                             "(a model needs more samples than terms): a longer record, or smaller lags")
        if np.all(sc.zero):
            raise ValueError("every candidate column is zero on these data (an input held at zero?): "
                             + ", ".join(str(t) for t in opt.process[:10]) + (", …" if len(opt.process) > 10 else ""))
        if len(opt.forced) > opt.limit:
            raise ValueError(f"{sc.n_rows} samples after the largest lag are too few for the {len(opt.forced)} "
                             "included terms")
        run = _Search(sc, opt)
        stop, capped = _grow(run)
        return _unscaled(_result(run, stop, capped, given), exps, given)


def _unscaled(res: SEMPResult, exps: dict[str, int], given: object) -> SEMPResult:
    """A search's result on the signals times 2^-e (:func:`~graybox.core._least_squares.binary_scaled`) in the data's
    own units: θ; the free-run MSEs (output units², 0 or inf where they leave the float range, as y² there); the
    criterion, N ln of the MSE, plus N ln 4^e."""
    if not exps:
        return res
    ey = exps["y"]
    path, fwd = res.path, res.forward_scores
    with np.errstate(over="ignore", under="ignore"):
        path["score"] = np.ldexp(path["score"].to_numpy(float), 2 * ey)
        path["criterion"] = path["criterion"].to_numpy(float) + res.n_rows * 2 * ey * math.log(2.0)
        fwd[:] = np.ldexp(fwd.to_numpy(float), 2 * ey)
        score = float(np.ldexp(res.score, 2 * ey))
    theta = unscaled_theta(res.theta, list(res.structure), exps)
    refuse_beyond_float_range(res.structure, theta, prefix="semp: the structure chosen cannot be used on these data: ")
    # and a term whose column is no float in the data's own units, as els refuses it (y × 2^600 with y(k-2)²: the
    # model's one-step predictions were NaN)
    stacked_regressors(res.structure, given)
    return replace(res, theta=frozen(theta), score=score, path=path, forward_scores=fwd)


def _semp_centred(candidates: Structure, data: Record | Sequence[Record] | Dataset, **options) -> SEMPResult:
    """semp(centre=True): search on the centred signals, close the choice under shifts, refit (see semp)."""
    # the whole of it on the signals times a power of two where they come near the float range's ends (as semp)
    given, (data, exps) = data, binary_scaled(data, candidates.process)
    offsets = _centring.search_offsets(data)
    centred = _centring.centred_data(data, offsets)
    _centring.check_included(options["include"], candidates.process, data)
    res = semp(candidates, centred, **options)
    full = _centring.closure(res.structure).process
    # less what the data cannot tell apart (a two-level input's u^2): its θ would be a point of a null space
    L = candidates.process.max_lag  # the search's rows, from which the closure is judged and fitted
    closed, dropped = _centring.told_apart(full, centred, options["rank_tol"], L)
    _centring.check_included(options["include"], candidates.process, data, dropped)
    _centring.check_closure_rows(closed, centred, len(res.structure), L)
    if dropped:
        warn(f"{len(dropped)} term(s) of the closure left out, the data cannot tell them from their divisors: "
             + ", ".join(str(t) for t, _ in dropped), CandidateWarning)
    # fitted, and its free run scored, on the centred signals over the same rows as the search's (from L on)
    theta, _ = _centring.least_squares(closed, centred, L)
    recs = centred if isinstance(centred, list) else [centred]
    model = Model(closed, theta, **carried_from(recs))
    # from each record's measured y(0) … y(L-1), as the search's runs start (its own max_lag would simulate the
    # samples between: the same model scored otherwise than with centre=False)
    a = L - model.max_lag
    err = np.concatenate([model.simulate(r.slice(a, len(r)), on_diverge="nan")[model.max_lag:] - r.y[L:]
                          for r in recs])
    # a free run that diverges scores inf, as in the search (the closure's extra terms can make it unstable)
    score = float(np.mean(err * err)) if np.all(np.isfinite(err)) else math.inf
    if not math.isfinite(score):
        warn(f"the closure of the {len(res.structure)} terms chosen on the centred signals ({len(closed)} terms, "
             "fitted by least squares) diverges in free run on the identification records: its score is inf; take "
             "fewer terms, or centre out", RuntimeWarning)
    # the offsets in the data's own units (those of the signals times 2^-e said 'y − 0.436' of a mean of 3.6e180)
    stop = _centring.stop_note(res.stop, len(res.structure), len(full), unscaled_levels(offsets, exps), dropped)
    # (a θ at round-off is 0: in other units it could leave the float range, see round_off_zeroed)
    theta = _centring.round_off_zeroed(closed, _centring.raw_theta(closed, theta, offsets), data, L)
    return _unscaled(replace(res, structure=closed, theta=frozen(theta), score=score, stop=stop), exps, given)


# --------------------------------------------------------------------------------------
# SEMP's phases: options, the search state, forward steps with pruning, the chosen structure


@dataclass(frozen=True, eq=False)
class _Options:
    """The checked arguments of :func:`semp`, its stopping mode and the size limit of the search."""

    process: Structure
    n_terms: int | None
    tol: float | None
    criterion: str | None
    mode: str
    crit: str
    forced: list[int]
    limit: int
    prune: bool
    prune_tol: float
    rank_tol: float
    threads: int


def _options(candidates: Structure, n_terms: int | None, tol: float | None, criterion: str | None,
             max_terms: int | None, include: Sequence[Term | str], prune: bool, prune_tol: float, rank_tol: float,
             threads: int) -> _Options:
    """The arguments of :func:`semp` checked (TypeError / ValueError naming the argument), and its plan."""
    candidates = structure_of(candidates, "candidates")
    process = candidates.process
    nc = len(process)
    if nc == 0:
        raise ValueError("the candidate structure has no process terms to select from")
    # each value first (a wrong type is named as such), then how they combine
    if tol is not None:
        tol = check_real(tol, "tol", low=0, high=1, low_open=True, high_open=True)
    if max_terms is not None:
        max_terms = check_int(max_terms, "max_terms", low=1, high=nc)
    if sum(x is not None for x in (n_terms, tol)) > 1:
        raise ValueError("give either n_terms or tol, not both")
    if n_terms is not None:
        n_terms = check_int(n_terms, "n_terms", low=1, high=nc)
        if max_terms is not None:
            raise ValueError("max_terms applies to tol and criterion stopping; with n_terms leave it out")
    if criterion is not None:
        check_choice(criterion, "criterion", CRITERIA)
    prune_tol = check_real(prune_tol, "prune_tol", low=0)
    rank_tol = check_real(rank_tol, "rank_tol", low=0, high=1, low_open=True, high_open=True)
    threads = check_int(threads, "threads", low=1)
    prune = check_bool(prune, "prune")
    mode = "n_terms" if n_terms is not None else "tol" if tol is not None else "criterion"
    crit = criterion or "bic"
    forced = process.positions(include, "included term")
    # with n_terms the search still looks past that size (a term found later can make earlier ones
    # redundant, and pruning then brings the structure back down); the answer is the best structure
    # of that size met on the path
    limit = min(nc, 2 * n_terms + 4) if mode == "n_terms" else (max_terms or min(30, nc))
    if len(forced) > (n_terms if mode == "n_terms" else limit):
        raise ValueError(f"{len(forced)} included terms exceed the {n_terms or limit} terms asked for")
    return _Options(process, n_terms, tol, criterion, mode, crit, forced, limit, prune, prune_tol, rank_tol, threads)


def _free_candidates(S: np.ndarray, zero: np.ndarray, forced: list[int]) -> int:
    """EBIC's p: the candidates a term can be chosen among, counted as frols counts its usable ones: not included,
    not all-zero, and not proportional to an included or earlier counted candidate (|cos| > 1 − _DUPLICATE_TOL on
    ``S``, the triangular factor's candidate columns)."""
    G = S.T @ S
    d = np.sqrt(np.maximum(np.diag(G), np.finfo(float).tiny))
    kept = [j for j in forced if not zero[j]]
    n = 0
    for j in range(S.shape[1]):
        if j in forced or zero[j]:
            continue
        if kept and np.max(np.abs(G[j, kept]) / (d[j] * d[kept])) > 1.0 - _DUPLICATE_TOL:
            continue
        kept.append(j)
        n += 1
    return n


class _Search:
    """The state of a SEMP search: the current structure, its θ and score, the structures visited, the path."""

    def __init__(self, sc: _Scorer, opt: _Options) -> None:
        self.sc, self.opt = sc, opt
        self.names = [str(t) for t in opt.process]
        self.current = list(opt.forced)
        self.n_free = _free_candidates(sc.R[:, :-1], sc.zero, opt.forced)
        zero = [self.names[j] for j in opt.forced if sc.zero[j]]
        if zero:  # in frols's words: one zero column is not 'collinear'
            raise ValueError(f"included term {zero[0]} cannot be used on these data: all-zero column")
        th = sc.fit(self.current, opt.rank_tol)
        if th is None:
            raise ValueError(f"the included terms {[self.names[j] for j in opt.forced]} are collinear on these data")
        if not np.all(np.isfinite(th)):
            raise ValueError(f"the included terms {[self.names[j] for j in opt.forced]} cannot be used on these data: "
                             "their least-squares parameters are beyond the float range")
        self.th = th
        # the empty structure predicts 0: its free-run error is the output's mean square
        self.score = (float(sc.scores(th)[0]) if self.current
                      else float(np.mean(np.concatenate([r.y[sc.L:] for r in sc.records]) ** 2)))
        self.rows: list[dict] = []  # the path: one row per accepted step
        self.unpruned_from: int | None = None  # the first step after which pruning stopped for its budget
        self.prune_budget = 0
        self.fwd: list[np.ndarray] = []  # every candidate's score at each forward step
        if opt.forced:
            self.log("include", ", ".join(self.names[j] for j in opt.forced))
        self.visited = {frozenset(self.current)}

    def log(self, action: str, term: str) -> None:
        """Append the current structure to the path."""
        current, score, N = self.current, self.score, self.sc.n_rows
        self.rows.append({
            "step": len(self.rows), "action": action, "term": term, "n_terms": len(current), "score": score,
            "criterion": float(criterion_of_sizes(self.opt.crit, len(current), score * N, N, self.n_free,
                                                  len(self.opt.forced))[0]) if current else math.inf,
            "structure": " + ".join(self.names[j] for j in current) or "(empty)", "_set": tuple(current),
            "_theta": self.th.copy()})

    def move(self, action: str, term: int, structure: list[int], th: np.ndarray, score: float) -> None:
        """Take a step: ``structure`` (parameters ``th``, free-run MSE ``score``) becomes the current one."""
        self.current, self.th, self.score = structure, th, score
        self.visited.add(frozenset(structure))
        self.log(action, self.names[term])


def _grow(run: _Search) -> tuple[str, bool]:
    """Forward steps, each followed by pruning, until a stopping condition holds.

    Returns why the search stopped, and whether the size limit cut it short while candidates were left.
    """
    opt, sc = run.opt, run.sc
    budget = _prune_budget(opt.limit)
    n_add = 0
    while True:
        cands = np.array([j for j in range(len(opt.process)) if j not in run.current and not sc.zero[j]], dtype=int)
        stop, capped = _stop_reason(run, cands)
        added = None if stop else _add(run, cands)
        if added is None:
            # an exact structure (at the round-off floor) that no removal keeps exact may still not be the smallest:
            # noise-free, y(k-2), u(k-1), u(k-2), u(k-1)^2, u(k-2)^2 runs as exactly as the true y(k-1), u(k-1),
            # u(k-1)^2, and y(k-1), a combination of those five, adds nothing to them (collinear); a swap reaches it
            if opt.prune and n_add < budget and run.score <= sc.floor:
                tried = None if stop else run.fwd.pop()  # the failed step's scores: the swap's step stands for it
                if _exchange(run):
                    n_add += 1
                    continue
                if tried is not None:
                    run.fwd.append(tried)
            stop = stop or "no candidate improves: every extension diverges, is collinear or was visited"
            break
        n_add += 1
        if opt.prune and n_add <= budget:
            _prune(run, added)
        elif opt.prune and run.unpruned_from is None:  # the first step pruning did not follow: said by _result
            run.unpruned_from, run.prune_budget = len(run.rows) - 1, budget
    if opt.prune and n_add > budget:
        stop += f" (pruning stopped after {budget} additions)"
    return stop, capped


def _prune_budget(limit: int) -> int:
    """Additions after which the search stops pruning and only adds: pruning on noisy data can keep the size
    from growing (a removal that does not hurt is taken), so every size up to the limit is still reached."""
    return 6 * limit + 10


def _stop_reason(run: _Search, cands: np.ndarray) -> tuple[str, bool]:
    """Why the search ends before the next forward step ("" to go on), and whether the size limit cut it short."""
    opt, sc, current, score = run.opt, run.sc, run.current, run.score
    if opt.mode == "tol" and current and score <= max(opt.tol * sc.yvar, sc.floor):  # at the floor: exact
        return f"free-run MSE / var(y) = {score / sc.yvar:.3g} ≤ {max(opt.tol, sc.floor / sc.yvar):.3g}", False
    if len(current) >= opt.limit:
        # cut short only if a larger structure could have been looked at: candidates and rows left
        return f"{opt.limit} terms reached", opt.limit < min(int(np.sum(~sc.zero)), sc.n_rows - 1)
    if opt.mode == "n_terms" and score <= sc.floor and len(current) > opt.n_terms:
        return "exact free run (noise-free data) reached", False
    if cands.size == 0:
        return "no candidate left", False
    return "", False


def _add(run: _Search, cands: np.ndarray) -> int | None:
    """The forward step: score the current structure plus each of ``cands``, take the best unvisited one.

    Returns the term added, or None when every extension diverges, is collinear or was visited.
    """
    sc = run.sc
    thetas = sc.bordered(run.current, cands, run.opt.rank_tol)
    s_c = sc.scores(thetas)
    row = np.full(len(run.opt.process), np.nan)
    row[cands] = s_c
    run.fwd.append(row)
    # a candidate whose structure was visited before would re-open a cycle: skip it
    pick = _best(s_c, np.array([frozenset(run.current + [int(c)]) not in run.visited for c in cands], bool))
    if pick is None:
        if not run.current or not run.rows:
            raise ValueError("no candidate gives a bounded free run (every one-term extension diverges or is "
                             "collinear); check the data or the candidate set")
        return None
    added = int(cands[pick])
    run.move("add", added, run.current + [added], thetas[pick], float(s_c[pick]))
    return added


def _best(scores: np.ndarray, eligible: np.ndarray | None = None) -> int | None:
    """The first (in the given order) of the finite ``eligible`` scores within :data:`TIE` of their smallest: ties to
    round-off go by order, not by the round-off, which differs between units. None if there is none."""
    ok = np.isfinite(scores) if eligible is None else np.isfinite(scores) & eligible
    if not ok.any():
        return None
    return int(np.flatnonzero(ok & (scores <= np.min(scores[ok]) * (1.0 + TIE)))[0])


def _exchange(run: _Search) -> bool:
    """At the round-off floor: swap a term j of the structure for a candidate c where S − j + c is exact too and a
    term of it can then be removed at the floor; take the steps (remove j, add c, prune). Whether it did."""
    opt, sc = run.opt, run.sc
    S = run.current
    cands = np.array([j for j in range(len(opt.process)) if j not in S and not sc.zero[j]], dtype=int)
    if cands.size == 0:
        return False
    for j in [k for k in S if k not in opt.forced]:
        base = [k for k in S if k != j]
        thetas = sc.bordered(base, cands, opt.rank_tol)
        s_c = sc.scores(thetas)
        tied = np.flatnonzero(s_c <= sc.floor)
        for i in tied:
            c = int(cands[i])
            swapped = base + [c]
            if frozenset(swapped) in run.visited:
                continue
            # a removal at the floor after the swap (never of c, as pruning removes): else the swap gains nothing
            trial = [sc.fit([k for k in swapped if k != r], opt.rank_tol) for r in swapped if r not in opt.forced
                     and r != c]
            trial = np.array([t if t is not None else np.full(len(opt.process), np.nan) for t in trial])
            if not trial.size or not np.any(sc.scores(trial) <= sc.floor):
                continue
            th_base = sc.fit(base, opt.rank_tol)
            if th_base is None:
                continue
            run.move("remove", j, base, th_base, float(sc.scores(th_base)[0]))
            row = np.full(len(opt.process), np.nan)
            row[cands] = s_c
            run.fwd.append(row)  # a forward step from S − j: its candidates' scores, as _add keeps them
            run.move("add", c, swapped, thetas[i], float(s_c[i]))
            _prune(run, c)
            return True
    return False


def _prune(run: _Search, added: int) -> None:
    """The pruning steps after ``added`` came in: remove the term whose removal hurts least, while it does not hurt."""
    opt, sc = run.opt, run.sc
    while len(run.current) > len(opt.forced) + 1:
        removable = [j for j in run.current if j not in opt.forced and j != added]
        trial = []
        for j in removable:
            t_ = sc.fit([i for i in run.current if i != j], opt.rank_tol)
            trial.append(t_ if t_ is not None else np.full(len(opt.process), np.nan))
        if not trial:
            break
        s_r = sc.scores(np.array(trial))
        i = _best(s_r)
        if i is None:
            break
        if not (np.isfinite(s_r[i]) and s_r[i] <= run.score * (1.0 + opt.prune_tol)):
            break
        nxt = [k for k in run.current if k != removable[i]]
        if frozenset(nxt) in run.visited and not s_r[i] < run.score:
            break  # back to an earlier structure without a gain: a cycle
        run.move("remove", removable[i], nxt, trial[i], float(s_r[i]))


def _result(run: _Search, stop: str, capped: bool, data: object) -> SEMPResult:
    """The structure of the path that the stopping rule chooses (warning as frols does), as a SEMPResult; ``data``,
    the raw records, for the offsets' note where the size asked was not reached."""
    opt, sc = run.opt, run.sc
    path = pd.DataFrame(run.rows)
    if opt.mode == "n_terms" and not (path["n_terms"] == opt.n_terms).any():
        # as frols says: offsets make the raw monomials collinear, the likely cause (centre=True reaches the size)
        note = _centring.offset_note(data, opt.process, opt.rank_tol)
        raise ValueError(f"the search never reached {opt.n_terms} terms ({stop})" + (f"; {note}" if note else ""))
    # the same rule as frols: the size asked for, the smallest model within the tolerance, or the
    # criterion's minimum (warning when the size limit cut the curve or the search short)
    scored = path[path["n_terms"] > 0] if (path["n_terms"] > 0).any() else path
    # the rows alone kept larger structures from being looked at (candidates were left): a criterion smallest
    # there has met the record's end, which frols says in the same words
    largest = int(scored["n_terms"].max())
    rows_cap = sc.n_rows if largest == sc.n_rows - 1 < int(np.sum(~sc.zero)) else None
    i, why = choose_model(stop_rule(opt.n_terms, opt.tol, opt.criterion, curve_default="bic"),
                          scored["n_terms"].to_numpy(), scored["criterion"].to_numpy(),
                          scored["score"].to_numpy() / sc.yvar, can_grow=capped, fraction="free-run MSE / var(y)",
                          rows_cap=rows_cap, round_off=sc.floor / sc.yvar)
    best = scored.iloc[i]
    if run.unpruned_from is not None and int(best["step"]) >= run.unpruned_from:
        # said as frols says its caps: the structure chosen was grown by steps that only added terms, not the
        # pruned search the caller asked for (one chosen earlier on the path was pruned as asked: nothing said)
        # the budget follows the search's size limit: max_terms (or its default) for tol and criterion, 2·n_terms + 4
        # for n_terms, which takes no max_terms (each capped by the candidates and the rows)
        advice = ("" if run.opt.mode == "n_terms" else
                  " (a smaller max_terms keeps the search within the budget)")
        warn(f"semp: pruning stopped after {run.prune_budget} additions (its budget, 6 × the search's size limit "
             f"{run.opt.limit} + 10), at step {run.unpruned_from} of the path; the structure chosen (step "
             f"{int(best['step'])}) was grown after it by steps that only added terms, so it may hold terms pruning "
             f"would have removed{advice}", RuntimeWarning)
    current = list(best["_set"])
    fwd = pd.DataFrame(np.array(run.fwd) if run.fwd else np.zeros((0, len(run.names))), columns=run.names)
    fwd.index.name = "forward step"
    return SEMPResult(Structure([opt.process[j] for j in current]), frozen(best["_theta"][current]),
                      float(best["score"]), path.drop(columns=["_set", "_theta"]), fwd, opt.crit,
                      f"{why}: step {int(best['step'])} of the path; search: {stop}", sc.n_rows,
                      **carried_from(sc.records))
