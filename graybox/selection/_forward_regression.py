"""Structure selection by forward regression with orthogonal least squares (FROLS / ERR).

The error reduction ratio of a candidate term is the fraction of the output energy
``yᵀy`` that the term explains once it is made orthogonal to the terms already chosen
(Billings, Korenberg & Chen 1988; the paper's Section III-A). FROLS picks, one at a time,
the candidate with the largest ERR.

How it is computed, and why
---------------------------
* Every candidate column is scaled to unit RMS before anything else. ERR is invariant to
  column scale in exact arithmetic; scaling makes it so in floating point as well, and keeps
  ``u(k-1)³ ≈ 1e9`` next to ``y(k-1) ≈ 10`` from wrecking the orthogonalisation.
* Orthogonalisation is modified Gram–Schmidt applied to *all* remaining candidates at once:
  after a term is chosen, every remaining column loses its component along the new
  orthonormal vector (a rank-1 update of the N × n candidate matrix, fused with the norms
  and inner products the next ERR needs into one compiled pass). The cost is O(N·n·k) for
  k chosen terms out of n candidates on N rows, and the N × n matrix must fit in memory.
* For long records (``method="gram"``, what ``"auto"`` picks once the candidate matrix would
  exceed 32 MiB, and for Dask records) the same selection runs in the covariance form
  (Korenberg's fast orthogonal search): ΨᵀΨ, Ψᵀy and yᵀy are accumulated over chunks of rows
  in one pass (:mod:`graybox.core._gram`), scaled to unit-RMS columns, and the orthogonalisation is
  a pivoted Cholesky factorisation of that n × n matrix, O(n·k) a step whatever N. Memory does
  not grow with N. The Gram matrix squares the conditioning, so it only *ranks* the
  candidates (an orthogonalised energy below 1e-11 N is treated as a linear combination); the
  chosen terms' ERR, RSS and θ are then taken from a TSQR factor of just those k columns and
  y (a second, narrow pass), which carries QR accuracy: on the bundled plant the two methods
  choose the same terms with ERR and θ equal to ~1e-12.
* A candidate whose orthogonalised norm falls below ``rank_tol`` of its original norm is
  (numerically) a linear combination of the chosen terms. Its ERR would be round-off divided
  by round-off, so it is dropped and reported, never chosen.
* All-zero candidate columns (e.g. every term in ``u`` when the input is zero) and
  candidates whose columns are proportional to an earlier candidate's (e.g. ``u(k-1)`` and
  the constant when the input is constant, ``u(k-1)^2`` and the constant for a binary ±a
  input) carry no information of their own on these data: they are skipped before the
  search with a :class:`CandidateWarning` naming them. Asking for more terms than the
  remaining independent candidates is a ``ValueError``.

Noise terms
-----------
When the candidate structure contains noise terms ``e(k-l)`` (``Candidates(..., ne=2)``),
FROLS selects among the process terms only (residuals do not exist before a model does) and
carries the noise terms in :attr:`Selection.noise`. :func:`graybox.els` accepts the
:class:`Selection` itself and then uses those noise terms for its MA part.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Literal, Mapping, Sequence

from ..core._jit import nb
import numpy as np

from ..models._model import Model, model_input_names
from ..core._records import Dataset, Record, carried_from, check_units, require_lengths
from ..core._terms import Structure, Term, structure_of
from ..core._gram import (
    DaskRecord,
    as_gram_records,
    chunk_bytes,
    chunk_rows,
    fill_columns,
    gram_sums,
    is_dask_data,
    r_factor,
    require_memory,
    term_factors,
    triangular_factor,
)
from ..core._least_squares import (binary_scaled, one_blas_thread, refuse_beyond_float_range, unscaled_levels,
                                   unscaled_rss, unscaled_theta)
from ..core._regressors import check_structure_inputs, record_signals, stacked_regressors
from ..core._validation import (Relocked, as_1d_finite, check_bool, check_choice, check_fields, check_int,
                                check_mean_square, check_real, check_theta, locked, warn)
from ._stopping import choose_model, stop_rule, FewerTermsError, StopRule
from . import _centring
from ._subset_search import prefix_floors, rss_floor, search_sizes, SearchBudget, SubsetProblem

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["Selection", "frols", "CandidateWarning", "CRITERIA", "information_criterion"]

#: Information criteria understood by :func:`frols`.
CRITERIA: tuple[str, ...] = ("aic", "bic", "fpe", "ebic")

#: Why a candidate dropped during the forward pass was (it stays among EBIC's p: the search looked at it).
_DEPENDENT = "linear combination of the selected terms"

#: Candidates shown by default when the criterion has no stopping role.
_DEFAULT_MAX_TERMS = 50

# Columns whose |cos| with an earlier one exceeds 1 − this are the same column up to scale: columns that are (a held
# input's lags, a two-level input's square and the constant) meet it to the round-off of their sums, ~1e-15. At 1e-10
# (an angle of 1.4e-5) a lagged output 1e5 times its spread from zero was 'proportional to 1' in the Gram form, which
# tests |cos| alone (MGS groups by a random projection at 1e-8 first, and kept it): the two chose different terms.
_DUPLICATE_TOL = 1e-12

# The Gram form sees a candidate's orthogonalised energy as G_jj − Σ C_ij², a difference of
# O(N) numbers: below about this fraction of N it is round-off, so a candidate under it is
# treated as a linear combination of the chosen terms whatever ``rank_tol`` asks.
_GRAM_DEPENDENT = 1e-11

# method="auto" orthogonalises on the data (MGS) while the candidate matrix is at most this
# many bytes, and on the Gram matrix (one chunked pass, memory independent of N) beyond.
_AUTO_GRAM_BYTES = 32 * 2**20

#: Orthogonalisation methods understood by :func:`frols`.
METHODS: tuple[str, ...] = ("auto", "mgs", "gram")

#: Subset searches understood by :func:`frols`.
SEARCHES: tuple[str, ...] = ("greedy", "swap", "exact")

#: ``search="exact"`` is refused beyond this many usable candidates (not counting included terms).
EXACT_MAX_CANDIDATES = 100

#: Branch-and-bound nodes one exact search may visit (over all the sizes it looks at).
EXACT_NODES = 200_000


class CandidateWarning(UserWarning):
    """Candidates were skipped because the data cannot tell them apart from others."""


def information_criterion(name: str, rss: np.ndarray, n_rows: int, *, n_candidates: int | None = None,
                          n_included: int = 0) -> np.ndarray:
    """AIC, BIC, FPE or EBIC of models of size 1, 2, … from their residual sums of squares.

    Parameters
    ----------
    name : {"aic", "bic", "fpe", "ebic"}
    rss : ndarray, shape (K,)
        Residual sum of squares of the model with the first ``k + 1`` terms (output units²).
    n_rows : int
        N, the number of regression rows.
    n_candidates : int, optional
        p, the number of candidates the selected terms were chosen among (the included ones left
        out). EBIC needs it; the other criteria do not read it.
    n_included : int, optional
        Terms every model holds whatever the data (``include=``): they are not chosen, so EBIC
        counts the subsets of the other k − n_included terms only (default 0).

    Returns
    -------
    ndarray, shape (K,)
        With σ²_k = rss_k / N: ``N ln σ² + 2k`` (AIC), ``N ln σ² + k ln N`` (BIC),
        ``N ln σ² + N ln((N + k)/(N − k))`` (FPE, in its logarithmic form as in SysIdentPy),
        ``N ln σ² + k ln N + 2 ln C(p, k − n_included)`` (EBIC, the extended BIC of Chen & Chen
        (2008) with γ = 1: BIC plus twice the logarithm of the number of subsets of that size the
        selection compared, so a size is not chosen because the best of many subsets fits the
        record's noise).

    Raises
    ------
    ValueError
        An unknown criterion; an RSS that is not a 1-D array of finite values > 0; as many terms
        as rows or more; EBIC without ``n_candidates``, or with more chosen terms than
        candidates. (``TypeError`` for ``n_rows`` or ``n_candidates`` that is not an integer.)
    """
    check_choice(name, "name (the criterion)", CRITERIA)
    n_rows = check_int(n_rows, "n_rows", low=1)
    n_included = check_int(n_included, "n_included", low=0)
    if n_candidates is not None:
        n_candidates = check_int(n_candidates, "n_candidates", low=0)
    elif name == "ebic":
        raise ValueError("criterion ebic needs n_candidates (the number of candidates the terms were chosen among)")
    rss = as_1d_finite(rss, "rss")
    if np.any(rss <= 0):
        # ln 0 = -inf: an exact fit's residual is round-off (frols floors it at 1e4 eps² (yᵀy + N (Σ|θ|)²))
        raise ValueError(f"rss must be > 0 (output units²), got {float(rss.min())!r}: an exact fit's residual sum "
                         "of squares is its round-off; floor it at a small fraction of yᵀy")
    k = np.arange(1, rss.size + 1, dtype=float)
    N = float(n_rows)
    if np.any(k >= N):
        raise ValueError(f"criterion {name} needs fewer terms ({rss.size}) than rows ({n_rows})")
    base = N * np.log(rss / N)
    if name == "aic":
        return base + 2.0 * k
    if name == "bic":
        return base + k * math.log(N)
    if name == "ebic":
        chosen = np.maximum(k - n_included, 0.0)
        if np.any(chosen > n_candidates):
            raise ValueError(f"criterion ebic: {int(chosen.max())} chosen terms but only {n_candidates} candidates")
        ln_subsets = np.array([math.lgamma(n_candidates + 1) - math.lgamma(j + 1) - math.lgamma(n_candidates - j + 1)
                               for j in chosen])
        return base + k * math.log(N) + 2.0 * ln_subsets
    return base + N * np.log((N + k) / (N - k))


@dataclass(frozen=True, eq=False)
class Selection(Relocked):
    """The result of :func:`frols`: an immutable value.

    Attributes
    ----------
    structure : Structure
        The selected process terms, in the order they were chosen.
    err : ndarray, shape (n_selected,)
        Each selected term's error reduction ratio (fraction of yᵀy, in [0, 1]).
    theta : ndarray, shape (n_selected,)
        Least-squares parameters of the selected terms on the selection data (engineering
        units; no MA part: use :func:`graybox.els` for the paper's estimator).
    noise : Structure
        Noise terms ``e(k-l)`` carried over from the candidates (not selected; see the module
        docstring).
    evaluated : Structure
        Every term FROLS ranked, in order: the selected ones first, then those only looked at
        to draw the criterion curve (when stopping by a criterion).
    err_evaluated : ndarray, shape (K,)
        ERR of each evaluated term.
    rss : ndarray, shape (K,)
        Residual sum of squares after 1 … K terms (output units²), floored as :attr:`subset_rss` is.
    criterion : str
        The criterion of :attr:`criterion_curve` (``"aic"``, ``"bic"``, ``"fpe"`` or ``"ebic"``).
    criterion_curve : ndarray, shape (K,)
        That criterion for models of 1 … K terms.
    stop : str
        Why selection stopped, in words (e.g. ``"n_terms = 17"``, ``"bic minimum at 12"``).
    n_rows : int
        Number of regression rows (samples after the max lag, summed over records).
    n_candidates : int
        Number of process candidates offered.
    skipped : tuple of (Term, str)
        Candidates left out and why (zero column, duplicate of another candidate, linear
        combination of selected terms).
    search : str
        The subset search that chose :attr:`structure`: ``"greedy"`` (FROLS proper),
        ``"swap"`` or ``"exact"`` (see :func:`frols`).
    subsets : tuple of Structure
        With ``search="swap"`` or ``"exact"``: the best subset found of each size the stopping
        rule looked at, smallest first, each in ERR order within itself (included terms first);
        empty for greedy search, whose size-k model is ``evaluated[:k]``. :attr:`structure` is one
        of them.
    subset_rss : ndarray, shape (len(subsets),)
        Their residual sums of squares on the selection rows (output units²), from the triangular
        factor of the scaled candidates beside y: values at an exact fit's round-off are floored at it
        (1e4 eps² (yᵀy + N (Σ|θ_s|)²), θ_s the parameters of the unit-RMS columns: round-off, not signal; with
        ``centre=True``, of the centred signals, times the largest ratio of a signal's mean square as recorded to
        centred, whose round-off they keep, as :attr:`rss` is).
    input_names : tuple of str, optional
        The model's inputs, in the column order of an input array (default: as
        :class:`~graybox.Model`'s; :func:`frols` takes the records').
    Ts : float, optional
        The sampling period (s) of the records it was fitted on (None: unknown); :attr:`model` carries it.
    units : tuple, optional
        The units of the input(s) and the output of those records (the input's one str, or one per input;
        :func:`frols` takes the records'); :attr:`model` carries them. Empty: unknown.
    """

    structure: Structure
    err: np.ndarray
    theta: np.ndarray
    noise: Structure
    evaluated: Structure
    err_evaluated: np.ndarray
    rss: np.ndarray
    criterion: str
    criterion_curve: np.ndarray
    stop: str
    n_rows: int
    n_candidates: int
    skipped: tuple[tuple[Term, str], ...] = field(default=())
    search: str = "greedy"
    subsets: tuple[Structure, ...] = field(default=())
    subset_rss: np.ndarray = field(default=())
    input_names: tuple[str, ...] | None = None
    Ts: float | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_fields(self)
        # checked and defaulted as a Model's (:attr:`model` carries them)
        names = model_input_names(self.structure, self.input_names)
        object.__setattr__(self, "input_names", names)
        if self.Ts is not None:
            object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        object.__setattr__(self, "units", check_units(self.units, "Selection", len(names)))
        n, k = len(self.structure), len(self.evaluated)
        if tuple(self.evaluated)[:n] != tuple(self.structure):
            raise ValueError(f"the selected terms {self.structure} must be the first {n} evaluated terms, "
                             f"got {self.evaluated}")
        for name, size in (("err", n), ("theta", n), ("err_evaluated", k), ("rss", k), ("criterion_curve", k),
                           ("subset_rss", len(self.subsets))):
            a = np.array(getattr(self, name), dtype=float, copy=True)
            if a.shape != (size,):  # one value per selected term, per evaluated term or per subset
                raise ValueError(f"{name} must have shape ({size},), got {a.shape}")
            object.__setattr__(self, name, locked(a))
        check_theta(n, self.theta)  # finite, as the model it gives needs (a file loads through here: graybox.io)
        check_choice(self.search, "search", SEARCHES)
        if self.search == "greedy" and self.subsets:  # greedy's size-k model is evaluated[:k]: it keeps no subsets
            raise ValueError(f"Selection: a greedy search keeps no subsets, got {len(self.subsets)}")
        if self.subsets and set(self.structure) not in [set(S) for S in self.subsets]:
            raise ValueError(f"Selection: the {self.search} search's subsets hold no subset of the selected terms "
                             f"{self.structure} (the structure is the best subset of its size)")
        for name in ("err", "err_evaluated", "rss", "subset_rss"):
            check_mean_square(getattr(self, name), f"Selection: {name} (a share or a sum of squares)")
        if self.n_rows < 1 or self.n_candidates < 1:
            raise ValueError(f"Selection: n_rows and n_candidates are counts, >= 1; got {self.n_rows} and "
                             f"{self.n_candidates}")

    def __len__(self) -> int:
        return len(self.structure)

    @property
    def n_terms(self) -> int:
        """Number of selected terms."""
        return len(self.structure)

    @property
    def err_total(self) -> float:
        """Σ ERR of the selected terms: the fraction of yᵀy the selected model explains."""
        return float(np.sum(self.err))

    @property
    def model(self) -> Model:
        """The selected structure with its least-squares parameters (no MA part), named ``"LS"``."""
        return Model(self.structure, self.theta, name="LS", input_names=self.input_names, Ts=self.Ts,
                     units=self.units)

    def to_frame(self) -> pd.DataFrame:
        """One row per evaluated term, in order.

        Returns
        -------
        pandas.DataFrame
            Columns: ``term`` (str), ``ERR``, ``cumulative ERR`` (fractions of yᵀy), the criterion (e.g. ``aic``,
            value of the model made of this term and those above it), ``selected`` (bool),
            ``theta`` (LS parameter, engineering units, NaN when not selected). Index: rank 1 … K.
        """
        import pandas as pd

        k = len(self.evaluated)
        theta = np.full(k, np.nan)
        theta[: self.n_terms] = self.theta
        return pd.DataFrame(
            {
                "term": [str(t) for t in self.evaluated],
                "ERR": self.err_evaluated,
                "cumulative ERR": np.cumsum(self.err_evaluated),
                self.criterion: self.criterion_curve,
                "selected": np.arange(k) < self.n_terms,
                "theta": theta,
            },
            index=pd.RangeIndex(1, k + 1, name="rank"),
        )

    def __str__(self) -> str:
        width = max([len("term")] + [len(str(t)) for t in self.evaluated])
        head = (
            f"FROLS{'' if self.search == 'greedy' else f' ({self.search} search)'}: "
            f"{self.n_terms} of {self.n_candidates} candidate terms, {self.n_rows} rows; "
            f"stop: {self.stop}; 1 - ΣERR = {1.0 - self.err_total:.3e}"
        )
        lines = [head]
        if len(self.noise):
            lines.append(f"noise terms carried for ELS: {self.noise}")
        lines.append(f"{'rank':>4}  {'term':<{width}}  {'ERR':>11}  {'ΣERR':>11}  {self.criterion.upper():>12}  {'θ (LS)':>12}")
        cum = np.cumsum(self.err_evaluated)
        for i, t in enumerate(self.evaluated):
            if i == self.n_terms:
                lines.append(f"{'':>4}  {'-- not selected (criterion curve only) --':<{width}}")
            th = f"{self.theta[i]:12.5g}" if i < self.n_terms else f"{'':>12}"
            lines.append(
                f"{i + 1:>4}  {str(t):<{width}}  {self.err_evaluated[i]:11.5e}  {cum[i]:11.8f}  "
                f"{self.criterion_curve[i]:12.5g}  {th}"
            )
        if self.skipped:
            lines.append("skipped: " + "; ".join(f"{t} ({why})" for t, why in self.skipped))
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Selection(n_terms={self.n_terms}, n_candidates={self.n_candidates}, stop={self.stop!r})"


# --------------------------------------------------------------------------------------
# candidate matrix


def _candidate_matrix(terms: Sequence[Term], records: list[Record], start: int) -> tuple[np.ndarray, np.ndarray]:
    """Candidate columns over all records, Fortran-ordered (rows, n), and the target.

    Built chunk by chunk of rows (see :func:`graybox.core._gram.fill_columns`): each monomial is one
    multiply of a lower-degree monomial by a lagged signal, and the prefixes kept for that live
    only as long as one chunk, so the peak is the matrix plus one chunk's worth.
    """
    rows = sum(len(r) - start for r in records)
    factors = term_factors(terms)
    W = np.empty((rows, len(terms)), order="F")
    target = np.empty(rows)
    step = chunk_rows(len(terms))
    r0 = 0
    require_lengths(records, start)
    for rec in records:
        n = len(rec)
        sig = record_signals(rec)
        for k0 in range(start, n, step):
            k1 = min(k0 + step, n)
            fill_columns(W[r0 : r0 + k1 - k0], factors, sig, k0, k1)
            r0 += k1 - k0
        target[r0 - (n - start) : r0] = rec.y[start:]
    return W, target


def _duplicates(W: np.ndarray, active: np.ndarray) -> list[tuple[int, int]]:
    """Pairs (kept, dropped) of active unit-RMS columns that are proportional (|cos| ≈ 1).

    Cheap: a random projection puts proportional columns at equal |projection|, so after
    sorting by it each group of proportional columns is a run of neighbours; each run is
    checked against its first member with an exact inner product. In every group the
    candidate listed first is kept.
    """
    idx = np.flatnonzero(active)
    if idx.size < 2:
        return []
    N = W.shape[0]
    z = np.random.default_rng(0).standard_normal(N) / math.sqrt(N)
    # project every column (a GEMV over W in place) and pick the active ones afterwards:
    # W[:, idx] would copy the whole candidate matrix for one projection
    key = np.abs(z @ W)[idx]
    order = np.argsort(key, kind="stable")
    groups: list[list[int]] = [[int(idx[order[0]])]]
    for a in order[1:]:
        head = groups[-1][0]
        ia = int(idx[a])
        same_key = abs(key[a] - key[np.searchsorted(idx, head)]) <= 1e-8 * max(1.0, key[a])
        if same_key and abs(float(W[:, ia] @ W[:, head])) / N > 1.0 - _DUPLICATE_TOL:
            groups[-1].append(ia)
        else:
            groups.append([ia])
    pairs = []
    for g in groups:
        kept = min(g)
        pairs += [(kept, j) for j in sorted(g) if j != kept]
    return pairs


def _gram_duplicates(G: np.ndarray, active: np.ndarray) -> list[tuple[int, int]]:
    """As :func:`_duplicates`, from the Gram matrix: |cos θ_ij| = |G_ij| / √(G_ii G_jj) ≈ 1.

    Each dropped candidate is paired with the first earlier candidate it is proportional to
    that is itself kept (proportionality is transitive, so that is its group's first member).
    """
    idx = np.flatnonzero(active)
    if idx.size < 2:
        return []
    d = np.sqrt(np.diag(G)[idx])
    close = np.abs(G[np.ix_(idx, idx)]) / np.outer(d, d) > 1.0 - _DUPLICATE_TOL
    pairs: list[tuple[int, int]] = []
    dropped = np.zeros(idx.size, bool)
    for b in np.flatnonzero(np.triu(close, 1).any(axis=0)):
        for a in np.flatnonzero(close[:b, b]):
            if not dropped[a]:
                pairs.append((int(idx[a]), int(idx[b])))
                dropped[b] = True
                break
    return pairs


# --------------------------------------------------------------------------------------
# compiled MGS step


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _mgs_update(W, q, r, active, coef, nrm, num):  # pragma: no cover - compiled
    """For every active column w: c = qᵀw; w ← w − c q; then ‖w‖² and wᵀr, in one pass.

    W is Fortran-ordered (columns contiguous). ``r`` is the output residual already
    orthogonalised against ``q``.
    """
    N, n = W.shape
    for j in range(n):
        if not active[j]:
            continue
        c = 0.0
        for i in range(N):
            c += q[i] * W[i, j]
        s1 = 0.0
        s2 = 0.0
        for i in range(N):
            w = W[i, j] - c * q[i]
            W[i, j] = w
            s1 += w * w
            s2 += w * r[i]
        coef[j] = c
        nrm[j] = s1
        num[j] = s2


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _norms_and_dots(W, r, nrm, num):  # pragma: no cover - compiled
    """‖w_j‖² and w_jᵀr of every column (the state before the first selection)."""
    N, n = W.shape
    for j in range(n):
        s1 = 0.0
        s2 = 0.0
        for i in range(N):
            w = W[i, j]
            s1 += w * w
            s2 += w * r[i]
        nrm[j] = s1
        num[j] = s2


class _MGS:
    """Forward OLS state on the data: unit-RMS candidate matrix W (N × n, Fortran), residual r."""

    def __init__(self, W: np.ndarray, y: np.ndarray, K: int) -> None:
        N, n = W.shape
        self.W, self.r = W, y.copy()
        self.nrm, self.num, self.coef = np.empty(n), np.empty(n), np.zeros(n)
        _norms_and_dots(W, self.r, self.nrm, self.num)
        self.C = np.zeros((K, n))  # C[i, j] = q_iᵀ s_j: the upper triangle of the QR factor
        self.Q = np.empty((N, K))
        self.g = np.empty(K)

    def choose(self, k: int, j: int, active: np.ndarray, last: bool) -> None:
        Q, C = self.Q, self.C
        # The chosen column is re-orthogonalised once against the previous q's: cheap (one
        # column) and it keeps Q orthonormal to working precision, so ERR sums stay ≤ 1.
        w = self.W[:, j].copy()
        if k:
            corr = Q[:, :k].T @ w
            w -= Q[:, :k] @ corr
            C[:k, j] += corr
        norm_w = math.sqrt(float(w @ w))
        q = w / norm_w
        C[k, j] = norm_w
        Q[:, k] = q
        self.g[k] = float(q @ self.r)
        self.r -= self.g[k] * q
        if not last:
            _mgs_update(self.W, q, self.r, active, self.coef, self.nrm, self.num)
            C[k, active] = self.coef[active]

    def rss(self, k: int) -> float:
        return float(self.r @ self.r)


class _GramOLS:
    """Forward OLS on the Gram matrix (covariance form; Korenberg's fast orthogonal search).

    With G = SᵀS (unit-RMS columns s_j) and b = Sᵀy, the QR factor of the chosen columns is a
    pivoted, left-looking Cholesky factor of G: C[k, :] = (G[j, :] − C[:k, j]ᵀ C[:k, :]) / C[k, j]
    with C[k, j] = √(G_jj − Σ_i C[i, j]²), and q_kᵀy = (b_j − C[:k, j]ᵀ g[:k]) / C[k, j]. Every
    candidate's orthogonalised energy and its inner product with y follow by rank-1 updates, so
    a step costs O(n k) whatever N.
    """

    def __init__(self, G: np.ndarray, b: np.ndarray, yy: float, K: int) -> None:
        n = G.shape[0]
        self.G, self.b, self.yy = G, b, yy
        self.nrm = np.diag(G).copy()
        self.num = b.copy()
        self.C = np.zeros((K, n))
        self.g = np.empty(K)

    def choose(self, k: int, j: int, active: np.ndarray, last: bool) -> None:
        C = self.C
        # energy of the chosen column recomputed from its own C column (not the running update)
        d = float(self.G[j, j] - C[:k, j] @ C[:k, j])
        cjj = math.sqrt(d)
        row = (self.G[j] - C[:k, j] @ C[:k]) / cjj
        row[j] = cjj
        C[k] = row
        self.g[k] = float(self.b[j] - C[:k, j] @ self.g[:k]) / cjj
        self.nrm -= row * row
        self.num -= row * self.g[k]

    def rss(self, k: int) -> float:
        return self.yy - float(self.g[: k + 1] @ self.g[: k + 1])


def _choose_method(method: str, N: int, n: int, K: int, lazy: bool) -> str:
    """The orthogonalisation for ``method``, after checking that it fits in memory."""
    check_choice(method, "method", METHODS)
    if lazy:
        if method == "mgs":
            raise ValueError("method='mgs' needs the candidate matrix in memory; a DaskRecord is reduced by "
                             "method='gram' (or 'auto')")
        return "gram"
    mgs_bytes = 8 * N * (n + K + 6) + chunk_bytes(n)
    if method == "auto":
        return "mgs" if 8 * N * n <= _AUTO_GRAM_BYTES else "gram"
    if method == "mgs":
        require_memory(mgs_bytes, f"FROLS by MGS on {N} rows × {n} candidates",
                       hint="method='gram' needs memory independent of the record length")
    return method


# --------------------------------------------------------------------------------------
# FROLS


def frols(
    candidates: Structure,
    data: Record | Sequence[Record] | Dataset | DaskRecord | Sequence[DaskRecord],
    *,
    n_terms: int | None = None,
    tol: float | None = None,
    criterion: Literal["aic", "bic", "fpe", "ebic"] | None = None,
    max_terms: int | None = None,
    rank_tol: float = 1e-7,
    include: Sequence[Term | str] = (),
    method: Literal["auto", "mgs", "gram"] = "auto",
    search: Literal["greedy", "swap", "exact"] = "greedy",
    centre: bool = False,
) -> Selection:
    """Select model terms by forward regression with orthogonal least squares (ERR).

    Exactly one stopping rule applies:

    * ``n_terms``: the first ``n_terms`` terms by ERR;
    * ``tol``: the fewest terms with ``1 − ΣERR ≤ tol`` (at most ``max_terms``; a warning if
      the tolerance is not reached);
    * ``criterion``: the size with the global minimum of the criterion over sizes
      1 … ``max_terms`` (a warning if the minimum is at ``max_terms``: the curve was still
      falling; or at the most terms a short record's rows allow, rows − 1: an interpolation of
      the record, not a choice). This is the default when neither ``n_terms`` nor ``tol`` is given: BIC for
      the greedy search, EBIC for ``search="swap"`` and ``"exact"``.

    With ``n_terms`` or ``tol``, ``criterion`` (default ``"aic"``) only names the curve stored
    in the result.

    Parameters
    ----------
    candidates : Structure
        Candidate terms, e.g. ``Candidates(ny=6, nu=6, ne=2, degree=2)``. Noise terms are not
        selected; they are carried to :attr:`Selection.noise`.
    data : Record, sequence of Record, Dataset, DaskRecord or sequence of DaskRecord
        Identification data (engineering units; a Dataset contributes its ``ident`` record).
        Regression rows start at the candidates' largest process lag in each record and never
        straddle two records. A :class:`~graybox.DaskRecord` (u, y as Dask arrays) is reduced to
        its Gram matrix block by block on the active Dask scheduler (``method="gram"``).
    n_terms : int, optional
        Number of terms to select, 1 ≤ n_terms ≤ number of process candidates.
    tol : float, optional
        ERR tolerance in (0, 1): stop once the unexplained fraction ``1 − ΣERR`` of yᵀy is at
        most ``tol``, or at its round-off floor (an exact fit meets a tolerance below it; the floor is
        1e4 eps² (yᵀy + N (Σ|θ_s|)²) / yᵀy, about 1e-27 for an output's own terms).
    criterion : {"aic", "bic", "fpe", "ebic"}, optional
        Information criterion (see :func:`information_criterion`). Default: ``"bic"`` for the greedy search,
        ``"ebic"`` for ``"swap"`` and ``"exact"``: they compare many subsets of each size (C(p, k)), and the best
        of many fits the record's noise better than one path's model does, so BIC's penalty chose one or two
        terms too many (true size 6 among 28–55 candidates, 1 and 5 % noise: exact and swap recovered 124 of 160
        records under BIC, 157 under EBIC; BENCHMARKS.md, "Subset search beyond greedy"). EBIC counts the usable
        candidates besides the included ones.
    max_terms : int, optional
        Largest model size looked at for ``tol`` (default: min(candidates, regression rows − 1))
        and ``criterion`` (default: min(50, candidates, regression rows − 1)): what the record
        carries; a larger explicit one, or one above the candidates' count, is an error naming it.
        Not allowed with ``n_terms``.
    rank_tol : float, optional
        A candidate whose orthogonalised norm is below ``rank_tol`` times its original norm
        is treated as a linear combination of the selected terms and dropped.
    include : sequence of Term or str, optional
        Terms selected first, in this order, whatever their ERR (e.g. ``["1"]``: gray-box
        estimation with eq. (22) needs the constant, which ERR may rank late when slow
        disturbances dominate). They count towards ``n_terms`` and their ERR is reported; every
        model the stopping rule looks at holds them (``max_terms`` at least their count).
    method : {"auto", "mgs", "gram"}, optional
        How candidates are orthogonalised. ``"mgs"``: modified Gram–Schmidt on the N × n
        candidate matrix (most accurate; memory ~8·N·(n + n_terms) bytes, checked before
        allocation). ``"gram"``: the covariance form (Korenberg's fast orthogonal search) on
        ΨᵀΨ, Ψᵀy, yᵀy accumulated over chunks of rows: one pass over the data, memory
        independent of N; it resolves orthogonalised norms down to about √1e-11 ≈ 3e-6 of a
        column's norm (a looser ``rank_tol`` floor). ``"auto"`` (default): MGS while the
        candidate matrix takes at most 32 MiB, the Gram form beyond, and for Dask records.
    search : {"greedy", "swap", "exact"}, optional
        How the subset of each size is found. ``"greedy"`` (default): FROLS proper, one term at a
        time by ERR, never undone. ``"swap"``: from the greedy path and from greedy paths started
        at the next-best first picks, exchange one term for another while the residual sum of
        squares falls (deterministic; a local optimum). ``"exact"``: the subset of least RSS of
        each size, by branch and bound, started from the swap result. Both fit subsets on the
        triangular factor of the unit-RMS candidates beside y (QR's accuracy: far offsets on u or y
        do not blur them). Under slowly varying inputs (staircases, where ``u(k-1) ≈ u(k-2)``)
        greedy and swap can both settle on lag-shifted look-alikes of the true terms; exact cannot.
        All three work on the same scaled columns (results do not depend on units) and the same
        rows (never straddling two records), and respect ``include``. The stopping rule then
        compares the best subsets of each size: ``n_terms`` searches that size only, ``tol`` the
        sizes up to the first whose best subset reaches it, ``criterion`` every size up to
        ``max_terms`` (both stop at the largest size with a subset of independent terms), the exact search cutting each size at the RSS that would beat the other
        sizes' criterion. :attr:`Selection.subsets` keeps the best subset of each size looked at;
        :attr:`Selection.evaluated` is the chosen subset followed by the greedy terms after it.
        Exact search is refused (``ValueError``, naming ``"swap"``) beyond 100 usable candidates;
        when it visits 200 000 nodes without finishing it returns the best subset found (at least
        as good as swap's), says so in :attr:`Selection.stop` and warns.
    centre : bool, optional
        Select on centred signals (default False: on the raw ones). The search runs on y and each
        input minus their means over ``data``, and the chosen centred terms are expanded into the raw
        monomials they imply: :attr:`Selection.structure` is their hierarchical closure (every
        divisor of every chosen term, the constant included: more terms than were chosen), less any
        term the data cannot tell from its divisors (a two-level input's u(k-1)^2, and its multiples:
        in :attr:`Selection.skipped`, the stop text and a CandidateWarning; an included such term, or
        one of an input held at one level, is refused with a ValueError), with
        least-squares θ on the raw signals. The structure and the model's predictions are then the
        same wherever the signals' zeros are (°C or K, gauge or absolute pressure), up to round-off.
        ERR, RSS and the criterion curve are those of the closure on the centred signals (in the
        closure's order: the chosen terms first); :attr:`Selection.stop` says what was chosen before
        the closure; with ``search="swap"``/``"exact"`` :attr:`Selection.subsets` are the closures of
        the best subsets, with their RSS on the centred signals (two sizes may close to one structure).
        A criterion (AIC, BIC, ...) picks the size among the centred search's, counting the terms
        chosen, not the closure's. Not for Dask records.

    Returns
    -------
    Selection

    Raises
    ------
    ValueError
        Conflicting or out-of-range arguments; no process candidates; an output that is
        identically zero (with ``centre=True``, constant; or a closure of as many terms as
        regression rows, whose fit would interpolate the record); more terms asked than independent candidates on these data; a selected
        term that the accurate factor of the chosen columns finds dependent on those before it
        (noise-free data, where the Gram form's ranking cannot tell).
    MemoryError
        Before allocating, when the work of the chosen method would not fit in the memory
        available (the message names both, in bytes).

    Warns
    -----
    CandidateWarning
        When candidates are skipped (all-zero, proportional to another candidate, or a linear
        combination of selected terms). The result lists them in :attr:`Selection.skipped`.
    RuntimeWarning
        When ``tol`` is not reached within ``max_terms`` terms, or the criterion's minimum is
        at the edge of the range; when an exact search ran out of nodes.
    """
    # ---- validate arguments at the boundary ----
    # a candidate set is a structure: taken as every structure argument is (a list of terms, a result …)
    candidates = structure_of(candidates, "candidates")
    process, noise = candidates.process, candidates.noise
    n_cand = len(process)
    if n_cand == 0:
        raise ValueError("the candidate structure has no process terms to select from")
    if check_bool(centre, "centre"):
        return _frols_centred(candidates, data, n_terms=n_terms, tol=tol, criterion=criterion, max_terms=max_terms,
                              rank_tol=rank_tol, include=include, method=method, search=search)
    try:
        return _frols_raw(candidates, data, n_terms=n_terms, tol=tol, criterion=criterion, max_terms=max_terms,
                          rank_tol=rank_tol, include=include, method=method, search=search)
    except FewerTermsError as err:
        # raw monomials of signals far from their zero are nearly collinear with one another and the constant:
        # the likely cause of too few independent terms, said once for every place the search runs out
        note = _centring.offset_note(data, candidates.process, rank_tol)
        if not note:
            raise
        raise FewerTermsError(f"{err}; {note}", err.reached) from None


def _frols_raw(candidates: Structure, data: object, *, n_terms: int | None, tol: float | None,
               criterion: str | None, max_terms: int | None, rank_tol: float, include: Sequence[Term | str],
               method: str, search: str, round_off_gain: float = 1.0) -> Selection:
    """frols(centre=False) on checked candidates (see frols); ``round_off_gain``: that of centred signals (see
    :func:`~graybox.selection._subset_search.rss_floor`)."""
    process, noise = candidates.process, candidates.noise
    n_cand = len(process)
    # each value first (a wrong type is named as such), then how they combine
    if tol is not None:
        tol = check_real(tol, "tol", low=0, high=1, low_open=True, high_open=True)
    if max_terms is not None:  # as n_terms here and max_terms in semp: no more than the candidates
        max_terms = check_int(max_terms, "max_terms", low=1, high=n_cand)
    if n_terms is not None and tol is not None:
        raise ValueError("give either n_terms or tol, not both")
    if n_terms is not None:
        n_terms = check_int(n_terms, "n_terms", low=1)
        if n_terms > n_cand:
            raise ValueError(f"n_terms = {n_terms} is more than the {n_cand} process candidates")
        if max_terms is not None:
            raise ValueError("max_terms applies to tol and criterion stopping; with n_terms leave it out")
    if criterion is not None:
        check_choice(criterion, "criterion", CRITERIA)
    rank_tol = check_real(rank_tol, "rank_tol", low=0, high=1, low_open=True, high_open=True)
    mode = "n_terms" if n_terms is not None else "tol" if tol is not None else "criterion"
    check_choice(search, "search", SEARCHES)
    if mode == "criterion" and criterion is None:
        criterion = "bic" if search == "greedy" else "ebic"
    curve_name = criterion or "aic"

    forced = process.positions(include, "included term")
    if n_terms is not None and n_terms < len(forced):
        raise ValueError(f"n_terms = {n_terms} is fewer than the {len(forced)} included terms")
    if max_terms is not None and max_terms < len(forced):
        raise ValueError(f"{len(forced)} included terms exceed the {max_terms} terms max_terms allows")

    rule = stop_rule(n_terms, tol, criterion, curve_default="aic")
    # the search runs on y and each input times a power of two (exact: the same columns once scaled to unit RMS,
    # the same ERR), so that neither their products nor yᵀy overflow or underflow where the data are finite
    given, (data, exps) = data, binary_scaled(data, process)
    cols = _scaled_columns(process, data, rule, max_terms, method, keep=forced)
    cols.gain = round_off_gain
    N, yy, active, skipped = cols.n_rows, cols.yy, cols.active, cols.skipped
    # said together with the candidates dropped during the selection: one CandidateWarning per call
    said = [f"{len(skipped)} candidate(s) skipped (the data cannot tell them from others): "
            + "; ".join(f"{t} ({why})" for t, why in skipped[:10])
            + ("; …" if len(skipped) > 10 else "")] if skipped else []
    if skipped and any(why.startswith("proportional") for _, why in skipped):
        # columns varying little about a far offset look proportional: said as the search's running out is said
        note = _centring.offset_note(data, process, rank_tol)
        said[0] += f" ({note})" if note else ""
    n_usable = int(active.sum())
    if n_usable == 0:
        # every rule would look at no model at all: said here, not by the search's empty arrays
        raise FewerTermsError(
            f"none of the {n_cand} candidates is usable on these data: "
            + "; ".join(f"{t} ({why})" for t, why in skipped[:10]) + ("; …" if len(skipped) > 10 else ""), 0)
    if n_terms is not None and n_terms > n_usable:
        if said:
            warn("; ".join(said), CandidateWarning)
        raise FewerTermsError(
            f"n_terms = {n_terms} but only {n_usable} of the {n_cand} candidates are usable on these data "
            f"({len(skipped)} skipped: {', '.join(str(t) for t, _ in skipped[:5])}{', …' if len(skipped) > 5 else ''})",
            n_usable)
    if mode == "n_terms":
        K = n_terms
    elif mode == "tol":
        # a default follows the data, as for a criterion (and semp): a model of as many terms as rows interpolates
        # them, which the tolerance then met; it stops at rows − 1 and says the tolerance was not reached
        K = min(n_usable, max_terms or N - 1)
    else:
        # a default follows the data: no more terms than the rows carry (nobody asked for more: nothing said)
        K = min(n_usable, max_terms or min(_DEFAULT_MAX_TERMS, N - 1))
    if mode != "n_terms" and K < 1:  # N = 1: the default max_terms, N − 1, leaves no size to look at
        raise ValueError(f"{mode} needs more regression rows than model terms: {N} regression row after the "
                         f"candidates' largest lag {process.max_lag} is too few for any term (a longer record, or smaller lags)")
    if mode != "n_terms" and max(K, max_terms or 0) >= N:  # what was asked, even where fewer candidates are usable
        raise ValueError(f"{mode} needs more rows ({N}) than model terms ({max(K, max_terms or 0)}); lower max_terms")
    if mode != "n_terms" and K < len(forced):
        raise ValueError(f"{mode} needs more rows ({N}) than the {len(forced)} included terms")
    if mode == "n_terms" and K >= N:  # said before any search, in the same words for all of them
        raise ValueError(f"{K} terms need more than their {N} regression rows (no error left to fit); lower n_terms")

    plan = None
    n_included = len(forced)
    if search != "greedy":
        plan = _search_subsets(cols, forced, K, rule, search, rank_tol, process)
        n_plan = len(plan.subsets[plan.chosen])
        # the chosen subset first (ERR order within it), then, for the stored curve, greedy terms after it
        forced, K = list(plan.order), (K if mode == "criterion" else n_plan)
    chosen, n_dependent = _forward(cols, process, forced, K, rule if plan is None else None, rank_tol,
                                   n_included=n_included, search=search)
    C, g, rest = _chosen_factors(cols, process, chosen)
    if n_dependent:
        dep_terms = [t for t, why in skipped if why == _DEPENDENT]
        said.append(f"{n_dependent} candidate(s) dropped as linear combinations of selected terms on these data: "
                    + ", ".join(str(t) for t in dep_terms[:10]) + (", …" if len(dep_terms) > 10 else ""))
    if said:
        warn("; ".join(said), CandidateWarning)
    k_eval = len(chosen)
    g = g[:k_eval]
    err_eval = g**2 / yy
    # RSS from the orthogonal decomposition, floored at each fit's round-off (see rss_floor)
    floors = prefix_floors(C[:k_eval][:, chosen], g, yy, N, cols.gain)
    rss = np.maximum(rest + np.append(np.cumsum(g[::-1] ** 2)[::-1][1:], 0.0), floors)
    if k_eval >= N:
        raise ValueError(f"{k_eval} terms need more than their {N} regression rows (no error left to fit)")
    curve = _unscaled_curve(curve_name, rss, N, exps.get("y", 0), n_usable - n_included, n_included)
    if plan is None:
        # every model looked at holds the included terms: none of fewer terms is a candidate
        n0 = max(n_included, 1) - 1
        i, stop = choose_model(rule, np.arange(1, k_eval + 1)[n0:], curve[n0:], (rss / yy)[n0:],
                               can_grow=k_eval < min(n_usable - n_dependent, N - 1),
                               fraction="1 - ΣERR",
                               rows_cap=N if k_eval == N - 1 < n_usable - n_dependent else None,
                               round_off=(floors / yy)[n0:])
        n_sel = n0 + i + 1
    else:
        n_sel, stop = n_plan, plan.stop

    # θ of the selected terms: back-substitution in the triangular factor, then undo scaling
    idx = np.array(chosen[:n_sel], dtype=int)
    R = C[:n_sel][:, idx]
    # the factor of unit-RMS columns (norm √N): a selected term with almost no norm of its own is a
    # combination of those before it, which the Gram form's squared conditioning can hide from the
    # ranking (noise-free data); its θ would be an arbitrary point of a null space
    weak = np.flatnonzero(np.abs(np.diag(R)) <= rank_tol * math.sqrt(N))
    if weak.size:
        # in greedy's words ("only k independent terms"); select_graybox takes the sizes reached
        raise FewerTermsError(f"only {weak[0]} independent terms could be selected on these data: selected term "
                              f"{process[idx[weak[0]]]} is a linear combination of the terms selected before it, which "
                              f"the {cols.method} form could not tell (noise-free data?); ask for fewer terms"
                              + (", or method='mgs'" if cols.method == "gram" else ""), int(weak[0]))
    theta_scaled = _back_substitute(np.triu(R), g[:n_sel])
    with np.errstate(over="ignore"):  # a column of 1e-320 beside an output of 1: a θ of 1e320, refused below
        theta = unscaled_theta(theta_scaled / cols.scales[idx], [process[j] for j in idx], exps)
    refuse_beyond_float_range([process[j] for j in idx], theta, prefix="frols: ")
    if exps:  # chosen on the scaled signals, a term whose column is no float in the data's own units is refused as
        # els refuses it (y × 2^600 with y(k-1)²: the model's one-step predictions were NaN)
        stacked_regressors(Structure([process[j] for j in idx]), given)
    evaluated = Structure([process[j] for j in chosen])
    return Selection(
        structure=evaluated[:n_sel],
        err=err_eval[:n_sel],
        theta=theta,
        noise=noise,
        evaluated=evaluated,
        err_evaluated=err_eval,
        rss=unscaled_rss(rss, exps),
        criterion=curve_name,
        criterion_curve=curve,
        stop=stop,
        n_rows=N,
        n_candidates=n_cand,
        skipped=tuple(skipped),
        search=search,
        subsets=() if plan is None else tuple(Structure([process[j] for j in S]) for S in plan.subsets),
        subset_rss=() if plan is None else unscaled_rss(plan.rss, exps),
        **carried_from(as_gram_records(given)),
    )


def _unscaled_curve(name: str, rss: np.ndarray, N: int, ey: int, n_free: int, n_included: int) -> np.ndarray:
    """The criterion of the data's own RSS (``rss`` of the output times 2^-ey): of that RSS where it is a
    floating-point number, else of ``rss`` plus N ln 4^ey (the same curve, up to rounding). ``n_free``: the
    usable candidates besides the ``n_included`` included ones (EBIC's p)."""
    kw = {"n_candidates": n_free, "n_included": n_included}
    with np.errstate(over="ignore", under="ignore"):
        own = np.ldexp(rss, 2 * ey)
    if np.all(np.isfinite(own) & (own >= np.finfo(float).tiny)):
        return information_criterion(name, own, N, **kw)
    return information_criterion(name, rss, N, **kw) + N * 2 * ey * math.log(2.0)


def _closure_curve(name: str, rss: np.ndarray, N: int, ey: int, n_free: int, n_included: int,
                   n_chosen: int) -> np.ndarray:
    """:func:`_unscaled_curve` of a closure's nested fits whose first ``n_chosen`` terms the search chose: EBIC counts
    the subsets of the first min(k, n_chosen) terms (what the closure adds beyond them is not chosen)."""
    if name != "ebic":
        return _unscaled_curve(name, rss, N, ey, n_free, n_included)
    k = min(n_chosen, rss.size)
    at_n = np.full(k, float(N))  # RSS = N: the log term is 0, the criteria are their penalties
    ln_subsets = (information_criterion("ebic", at_n, N, n_candidates=n_free, n_included=n_included)
                  - information_criterion("bic", at_n, N))
    return _unscaled_curve("bic", rss, N, ey, n_free, n_included) + ln_subsets[np.minimum(np.arange(rss.size), k - 1)]


def _frols_centred(candidates: Structure, data: object, **options) -> Selection:
    """frols(centre=True): select on the centred signals, close the choice under shifts, refit (see frols)."""
    # the whole of it (the search, the closure's told_apart, its fit and the subsets' RSS) on y and each input times
    # a power of two where the data come near the float range's ends (:func:`binary_scaled`): the search alone was,
    # and told_apart on y × 2^-600 took y(k-1) for a linear combination of lower terms, a smaller closure returned
    given, (data, exps) = data, binary_scaled(data, candidates.process)
    offsets = _centring.search_offsets(data)
    centred = _centring.centred_data(data, offsets)
    gain = _centring.round_off_gain(data, centred)
    _centring.check_included(options["include"], candidates.process, given)
    # the search's CandidateWarning is said after the closure, which can bring back a term it left out
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always")
        sel = _frols_raw(candidates, centred, **options, round_off_gain=gain)
    for w in heard:
        if not issubclass(w.category, CandidateWarning):
            warn(str(w.message), w.category)
    rank_tol = options["rank_tol"]
    full = _centring.closure(sel.structure).process
    # less what the data cannot tell apart (a two-level input's u^2), or the fit below cannot hold every term
    L = candidates.process.max_lag  # the search's rows, from which the closure is judged and fitted
    closed, dropped = _centring.told_apart(full, centred, rank_tol, L)
    _centring.check_included(options["include"], candidates.process, given, dropped)
    _centring.check_closure_rows(closed, centred, len(sel.structure), L)
    skipped = tuple((t, why) for t, why in sel.skipped if t not in set(closed)) + dropped
    if skipped:
        warn(f"{len(skipped)} candidate(s) left out (the centred data cannot tell them from others): "
             + "; ".join(f"{t} ({why})" for t, why in skipped[:10]) + ("; …" if len(skipped) > 10 else ""),
             CandidateWarning)
    # the closure's own fit on the centred signals: its ERR, RSS and θ, the chosen terms first, on the search's rows
    # (from the candidates' largest lag L: the records from sample L − the closure's largest lag on)
    # (its RSS floored as the search's were, times the centring's round-off gain: the signals keep the round-off of
    # their recorded size)
    fit = _frols_raw(closed + candidates.noise, _centring.from_sample(centred, L - closed.max_lag),
                     n_terms=len(closed), tol=None, criterion=sel.criterion, max_terms=None, rank_tol=rank_tol,
                     include=list(closed), method=options["method"], search="greedy", round_off_gain=gain)
    subsets, subset_rss = (), ()
    if sel.subsets:
        subsets = tuple(_centring.told_apart(_centring.closure(S).process, centred, rank_tol, L)[0]
                        for S in sel.subsets)
        subset_rss = np.array([_centring.least_squares(S, centred, L, gain)[1] for S in subsets])
    stop = _centring.stop_note(sel.stop, len(sel.structure), len(full), unscaled_levels(offsets, exps), dropped)
    theta = _centring.round_off_zeroed(closed, _centring.raw_theta(closed, fit.theta, offsets), data, L)
    theta = unscaled_theta(theta, list(closed), exps)
    refuse_beyond_float_range(list(closed), theta, prefix="frols: ")
    # the closure's curve in the data's own units, counted as the search chose (the refit includes every term: its
    # EBIC compared no subsets): its first k terms hold min(k, chosen) the search chose, the included ones among them,
    # the others among the usable candidates besides the included (what the closure adds, nobody chose)
    n_included = len(candidates.process.positions(options["include"], "included term"))
    n_free = sel.n_candidates - n_included - sum(why != _DEPENDENT for _, why in sel.skipped)
    fit = replace(fit, criterion_curve=_closure_curve(fit.criterion, fit.rss, fit.n_rows, exps.get("y", 0), n_free,
                                                      n_included, len(sel.structure)))
    if exps:
        stacked_regressors(Structure(list(closed)), given)  # a column beyond the float range in the data's units
        fit = replace(fit, rss=unscaled_rss(fit.rss, exps))
        subset_rss = unscaled_rss(np.asarray(subset_rss), exps) if len(subset_rss) else subset_rss
    return replace(fit, theta=theta, stop=stop, n_candidates=sel.n_candidates, skipped=skipped, search=sel.search,
                   subsets=subsets, subset_rss=subset_rss)


# --------------------------------------------------------------------------------------
# FROLS's phases: scaled columns, subset search, forward orthogonalisation, accurate factors


@dataclass
class _Columns:
    """The candidates on the regression rows, scaled to unit RMS, with what cannot be used marked.

    ``W`` (N × n, Fortran) and ``y`` for MGS, or ``G`` = SᵀS and ``b`` = Sᵀy for the Gram form;
    ``active`` marks usable columns (the forward phase clears it as it goes), ``skipped`` lists
    the others and why.
    """

    method: str
    data: object
    start: int
    n_rows: int
    yy: float
    scales: np.ndarray
    active: np.ndarray
    skipped: list[tuple[Term, str]]
    W: np.ndarray | None = None
    y: np.ndarray | None = None
    G: np.ndarray | None = None
    b: np.ndarray | None = None
    engine: object = None
    gain: float = 1.0  # of the round-off floor (rss_floor): signals centred after they were recorded


def _scaled_columns(process: Structure, data: object, rule: StopRule, max_terms: int | None,
                    method: str, keep: Sequence[int] = ()) -> _Columns:
    """Build the candidate columns (or their Gram matrix), scale them and skip the unusable ones.

    Of candidates proportional to one another the first listed is kept, or the one in ``keep`` (the
    included terms): an included ``u(k-1)`` on a record whose input is held is kept, the constant skipped."""
    n_cand = len(process)
    lazy = is_dask_data(data)
    records = as_gram_records(data)
    check_structure_inputs(process, records)
    start = process.max_lag
    require_lengths(records, start)
    N = sum(len(r) - start for r in records)
    K_max = (n_cand if rule.mode == "tol" and max_terms is None
             else min(n_cand, rule.n_terms or max_terms or _DEFAULT_MAX_TERMS))
    method = _choose_method(method, N, n_cand, K_max, lazy)
    source = data if lazy else records

    if method == "mgs":
        W, y = _candidate_matrix(process.terms, records, start)
        if not np.all(np.isfinite(W)):
            bad = [str(process[j]) for j in np.flatnonzero(~np.all(np.isfinite(W), axis=0))[:5]]
            raise ValueError(f"candidate columns overflow to non-finite values (e.g. {', '.join(bad)})")
        yy = float(y @ y)
        scales = np.sqrt(np.einsum("ij,ij->j", W, W) / N)
    else:
        require_memory(chunk_bytes(n_cand) + 8 * 6 * (n_cand + 1) ** 2, f"FROLS (Gram form, {n_cand} candidates)")
        gs = gram_sums(process.terms, source, start)
        yy = gs.yy
        scales = np.sqrt(np.maximum(np.diag(gs.G), 0.0) / N)
    if yy == 0.0:
        raise ValueError("the output is identically zero on the regression rows: ERR is undefined")

    # ---- scale to unit RMS; skip columns that carry no information of their own ----
    active = scales > 0.0
    skipped: list[tuple[Term, str]] = [(process[j], "all-zero column") for j in np.flatnonzero(~active)]
    scales = np.where(active, scales, 1.0)
    cols = _Columns(method, source, start, N, yy, scales, active, skipped)
    if method == "mgs":
        W /= scales
        cols.W, cols.y = W, y
        dups = _duplicates(W, active)
    else:
        # D⁻¹ G D⁻¹ is the Gram matrix of the unit-RMS columns to the rounding of one division per
        # entry: scaling before or after accumulating the products gives the same relative accuracy.
        G = gs.G / scales / scales[:, None]
        np.fill_diagonal(G, np.where(active, float(N), 0.0))
        cols.G, cols.b = G, gs.b / scales
        dups = _gram_duplicates(G, active)
    groups: dict[int, list[int]] = {}
    for kept, dropped in dups:
        groups.setdefault(kept, [kept]).append(dropped)
    for kept, members in groups.items():
        choice = next((j for j in members if j in keep), kept)
        for j in members:
            if j != choice and active[j]:
                active[j] = False
                skipped.append((process[j], f"proportional to {process[choice]}"))
    return cols


def _dependent_threshold(cols: _Columns, rank_tol: float) -> float:
    """The remaining energy, as a fraction of a column's own, at or below which a column is a combination of those
    chosen: ``rank_tol``² on MGS's columns, never below :data:`_GRAM_DEPENDENT` on the Gram form's. One threshold
    for the forward pass and the subset search, which hands its subset to that pass."""
    return rank_tol**2 if cols.method == "mgs" else max(rank_tol**2, _GRAM_DEPENDENT)


def _forward(cols: _Columns, process: Structure, forced: list[int], K: int, rule: StopRule | None,
             rank_tol: float, *, n_included: int | None = None, search: str = "greedy") -> tuple[list[int], int]:
    """Forward selection of up to K terms (``forced`` first, in order), orthogonalising as it goes.

    ``forced``: the ``n_included`` included terms (default: all of them), then those of the
    subset ``search`` chose.

    Returns the chosen candidates' indices and how many candidates turned out to be linear
    combinations of them (added to ``cols.skipped``). A tolerance ``rule`` ends it early.
    """
    active, skipped, yy = cols.active, cols.skipped, cols.yy
    engine: _MGS | _GramOLS = (_MGS(cols.W, cols.y, K) if cols.method == "mgs"
                               else _GramOLS(cols.G, cols.b, yy, K))
    nrm0 = float(cols.n_rows)  # unit-RMS columns: ‖s_j‖² = N
    dependent_thr = _dependent_threshold(cols, rank_tol)
    chosen: list[int] = []
    n_dependent = 0
    for k in range(K):
        nrm, num = engine.nrm, engine.num
        dep = active & (nrm <= dependent_thr * nrm0)
        if dep.any():
            for j in np.flatnonzero(dep):
                skipped.append((process[j], _DEPENDENT))
            active &= ~dep
            n_dependent += int(dep.sum())
        if not active.any():
            if rule is not None and rule.mode == "n_terms":
                dep_terms = [str(t) for t, why in skipped if why == _DEPENDENT]
                raise FewerTermsError(
                    f"only {k} independent terms could be selected on these data, n_terms = {rule.n_terms} asked: "
                    f"the remaining candidates are linear combinations of the selected ones "
                    f"({', '.join(dep_terms[:8])}{', …' if len(dep_terms) > 8 else ''})", k)
            break
        if k < len(forced):
            j = forced[k]
            if not active[j]:
                why = next((w for t, w in skipped if t == process[j]), "skipped")
                if n_included is None or k < n_included:
                    raise ValueError(f"included term {process[j]} cannot be used on these data: {why}")
                # the search and this pass judge dependence by different factorisations: on noise-free
                # data, where the fit is exact with fewer terms, a column at the threshold can pass one
                raise ValueError(f"the best subset of {len(forced)} terms the {search} search found holds "
                                 f"{process[j]}: {why} on these data, at the edge of what the search could tell "
                                 "(noise-free data?); ask for fewer terms, or search='greedy'")
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                score = np.where(active, num * num / nrm, -1.0)
            j = int(np.argmax(score))
        active[j] = False
        engine.choose(k, j, active, last=k + 1 == K)
        chosen.append(j)
        # at the floor the fit is exact: it meets a tolerance below the floor too (the stopping rule's round_off)
        if rule is not None and rule.mode == "tol" and k + 1 >= len(forced):
            r = engine.rss(k)
            if r <= rule.tol * yy or r <= _floor_of(engine, chosen, yy, cols.n_rows, cols.gain):
                break
    cols.engine = engine
    return chosen, n_dependent


def _floor_of(engine: _MGS | _GramOLS, chosen: list[int], yy: float, N: int, gain: float) -> float:
    """:func:`rss_floor` of the fit of the terms chosen so far, from the forward pass's own factor."""
    from scipy.linalg import solve_triangular

    k = len(chosen)
    with np.errstate(all="ignore"):  # a nearly dependent pivot: inf parameters, floored at yy
        theta = solve_triangular(np.triu(engine.C[:k][:, chosen]), engine.g[:k], check_finite=False)
    return rss_floor(yy, N, theta, gain)


def _chosen_factors(cols: _Columns, process: Structure, chosen: list[int]) -> tuple[np.ndarray, np.ndarray, float]:
    """The triangular factor C (k × n) of the chosen columns, the output's coordinates g (k,) and the energy of the
    residual after all k (summed from the residual itself, not yᵀy − Σg²: that difference cancels to eps·yᵀy, far
    above an exact fit's round-off when y sits on an offset)."""
    engine = cols.engine
    C, g = engine.C, engine.g
    rest = engine.rss(len(chosen) - 1) if cols.method == "mgs" and chosen else None
    if cols.method == "gram" and chosen:
        # The Gram form ranks the candidates; the chosen ones' ERR, RSS and θ are then taken from
        # the triangular factor of [S_chosen, y] by TSQR over the same chunks (a second, narrow
        # pass: k+1 columns), so they carry QR accuracy instead of the Gram form's squared
        # conditioning, and agree with MGS and across chunkings (Dask blocks) to ~1e-12.
        R, _ = r_factor([process[j] for j in chosen], cols.data, cols.start)
        k_ = len(chosen)
        sign = np.where(np.diag(R)[:k_] < 0, -1.0, 1.0)
        C = np.zeros((k_, len(process)))
        C[:, chosen] = sign[:, None] * np.triu(R[:k_, :k_]) / cols.scales[chosen]
        g = sign * R[:k_, k_]
        rest = float(R[k_, k_] ** 2)
    return C, g, (cols.yy if rest is None else rest)


@dataclass(frozen=True, eq=False)
class _Plan:
    """What the subset search found: the best subset of each size, the chosen one and its order."""

    subsets: tuple[tuple[int, ...], ...]
    rss: np.ndarray
    chosen: int
    order: tuple[int, ...]
    stop: str


def _search_subsets(cols: _Columns, forced: list[int], K: int, rule: StopRule, search: str, rank_tol: float,
                    process: Structure) -> _Plan:
    """Swap or exact best-subset search over the sizes the stopping rule needs (see :func:`frols`), on one BLAS
    thread: its QR of N × (n + 1) (or TSQR's many small ones) and the small reductions after it gain nothing from
    more, and on a loaded machine lose much (the plant's QR: 160 ms on two threads, 9 ms on one)."""
    with one_blas_thread():
        return _search_subsets_on(cols, forced, K, rule, search, rank_tol, process)


def _search_subsets_on(cols: _Columns, forced: list[int], K: int, rule: StopRule, search: str, rank_tol: float,
                       process: Structure) -> _Plan:
    n_free = int(cols.active.sum()) - len(forced)
    if search == "exact" and n_free > EXACT_MAX_CANDIDATES:
        raise ValueError(
            f"exact search is refused for {n_free} usable candidates (at most {EXACT_MAX_CANDIDATES}: the branch "
            "and bound may grow as their number of subsets); use search='swap', or fewer candidates"
        )
    # the triangular factor of [S, y]: subset fits on it keep QR's accuracy where a Gram matrix squares
    # the conditioning (an offset on y). From the scaled columns MGS holds (before its pass) by one QR
    # while a copy of them is small; else TSQR over chunks of rows (memory independent of N)
    if cols.method == "mgs" and 8 * cols.n_rows * (len(process) + 1) <= _AUTO_GRAM_BYTES:
        R = triangular_factor(cols.W, cols.y)
    else:
        R, _ = r_factor(list(process.terms), cols.data, cols.start)
        R[:, :-1] /= cols.scales
    # a column is dependent at the forward pass's threshold, which runs on this subset next
    problem = SubsetProblem(R, cols.yy, cols.active, _dependent_threshold(cols, rank_tol), cols.gain)
    N = cols.n_rows
    problem.settle_floor(forced, K, N)
    lo = max(1, len(forced)) if rule.mode != "n_terms" else rule.n_terms
    sizes = list(range(lo, K + 1))
    budget = SearchBudget(EXACT_NODES)
    try:
        plan = search_sizes(problem, sizes, forced, exact=search == "exact", rule=rule,
                            criterion=lambda k, r: criterion_of_sizes(rule.criterion, k, r, N, n_free, len(forced)),
                            n_rows=N, budget=budget)
    except ValueError:
        # no independent subset holds the included terms: if they are dependent themselves, said as
        # greedy search says it (the forward pass raises, naming the term); the columns are spent then
        _forward(cols, process, forced, len(forced), None, rank_tol)
        raise
    ks = np.array([len(S) for S in plan.subsets])
    crit = criterion_of_sizes(rule.criterion, ks, plan.rss, N, n_free, len(forced))
    i, stop = choose_model(rule, ks, crit, plan.rss / cols.yy,
                           can_grow=not plan.exhausted and ks.max() < min(n_free + len(forced), N - 1),
                           fraction="1 - ΣERR",
                           rows_cap=N if not plan.exhausted and ks.max() == N - 1 < n_free + len(forced) else None,
                           round_off=problem.floor / cols.yy)
    how = ("exact (branch and bound, proven)" if plan.proven else
           f"exact search ran out of its {EXACT_NODES} nodes: best found, not proven") if search == "exact" else \
        "swap (local optimum under single exchanges)"
    if search == "exact" and not plan.proven:
        warn(f"exact subset search stopped after {EXACT_NODES} branch-and-bound nodes: the result is the best "
             "subset found (at least as good as search='swap'), not proven optimal", RuntimeWarning)
    # each subset in ERR order within itself, the included terms first
    subsets = tuple(tuple(problem.ordered(list(S), fixed=min(len(S), len(forced)))) for S in plan.subsets)
    return _Plan(subsets, plan.rss, i, subsets[i], f"{stop}; search: {how}")


def criterion_of_sizes(name: str, sizes: np.ndarray, rss: np.ndarray, N: int, n_free: int,
                       n_included: int) -> np.ndarray:
    """The criterion of models of the given sizes (≥ 1) and RSS, not necessarily 1, 2, … in turn; ``n_free``
    candidates besides ``n_included`` included terms (EBIC's p)."""
    sizes = np.atleast_1d(np.asarray(sizes, dtype=int))
    # at RSS = N the log term is 0
    penalty = information_criterion(name, np.full(int(sizes.max()), float(N)), N, n_candidates=n_free,
                                    n_included=n_included)
    return N * np.log(np.asarray(rss, dtype=float) / N) + penalty[sizes - 1]


def _back_substitute(R: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve the upper-triangular system R x = b."""
    from scipy.linalg import solve_triangular

    return solve_triangular(R, b, lower=False) if b.size else np.zeros(0)
