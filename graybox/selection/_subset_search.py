"""Subset search beyond greedy forward selection: swap (local) and exact (branch and bound).

Forward selection never undoes a pick. Under slowly varying inputs (staircases) ``u(k-1)`` and
``u(k-2)`` agree on most samples, ERR ranks a lag-shifted look-alike first, and the true
structure, whose one-step error may be hundreds of times smaller, is never reached. Two searches
look further, both on the upper-triangular factor R of [S, y] = QR, S the unit-RMS candidate
columns (so nothing depends on units, and multi-record data arrive already reduced over records):
the fit of any subset of columns of S is the fit of the same columns of R, reduced by Householder
reflections, with QR's accuracy (a Gram matrix SᵀS would square the conditioning, which an offset
of 1e5 on y, or 1e3 on u, takes past what double precision holds):

* **swap**: from several starts (the greedy path, and greedy paths whose first free pick is each
  of the next-best first picks), repeatedly make the best exchange of one term of the subset for
  one outside it while that lowers the residual sum of squares (RSS); a local optimum under
  single exchanges (as in iterative OFR). Deterministic: no random starts, so no seed.
* **exact**: branch and bound over k-subsets (Furnival & Wilson's leaps and bounds in its
  simplest form). A node fixes some terms and leaves a pool of later candidates; the RSS of the
  fixed terms and the whole pool together is a lower bound on every subset below the node (adding
  columns never raises RSS), and a node whose bound is not below the best subset found so far is
  cut. One reduction of the node's columns, with the pool in reverse order, gives the
  bounds of all its children at once (the RSS after each prefix). The search starts from the swap
  result, so it only ever improves on it, and it proves the answer optimal when it finishes.

RSS at or below the round-off of an exact fit are treated as equal (see :func:`rss_floor`, greedy FROLS's floor
too).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from ..core._jit import nb
import math

import numpy as np

from ._stopping import FewerTermsError, StopRule

__all__ = ["SubsetProblem", "SearchBudget", "SizePlan", "swap_search", "exact_search", "search_sizes", "ROUND_OFF",
           "rss_floor", "prefix_floors"]

#: An exact fit's residual sum of squares is round-off of the order of eps² (yᵀy + N (Σ|θ_s|)²), θ_s the parameters of
#: the unit-RMS columns (N (Σ|θ_s|)² bounds the energy of the model's terms summed in absolute value: terms that cancel
#: to a small y, as raw monomials of an offset input do, leave the round-off of their own size). Measured by QR and by
#: MGS at most 7 times that on noise-free plants (N 50 … 1e5, y offsets to 1e8, inputs offset by 1e4 with terms
#: cancelling to 1e-11 of their size, poles 0.5 and 0.999); the floor is 1e4 times it. A fixed 1e-20 of yᵀy was
#: 1e11 eps² at once too high (at y ≈ 1e6 a wrong model's RSS, 1.4e-25 yᵀy, counted as an exact fit) and too low
#: (terms cancelling 1e11-fold: 5e-18 yᵀy).
ROUND_OFF = 1e4 * np.finfo(float).eps ** 2


def rss_floor(yy: float, n_rows: int, theta: np.ndarray, gain: float = 1.0) -> float:
    """The round-off floor of the RSS of a fit with unit-RMS-column parameters ``theta`` to an output of energy ``yy``
    on ``n_rows`` rows (see :data:`ROUND_OFF`), times ``gain`` (signals centred after they were recorded keep the
    round-off of their recorded size: the largest ratio of a signal's mean square as recorded to centred); at most
    ``yy`` (a fit whose terms are too large for any digit of y to survive explains nothing beyond round-off)."""
    T = float(np.sum(np.abs(theta)))
    bound = ROUND_OFF * gain
    if not T <= math.sqrt(yy / (n_rows * bound)):  # also inf and NaN (a singular factor)
        return float(yy)
    return min(bound * (yy + n_rows * T * T), float(yy))


def prefix_floors(U: np.ndarray, g: np.ndarray, yy: float, n_rows: int, gain: float = 1.0) -> np.ndarray:
    """:func:`rss_floor` of the nested fits of the first 1, 2, … K columns of a triangular factor: ``U`` (K × K, upper)
    of the unit-RMS columns in order, ``g`` (K,) the output's coordinates. One inverse: the leading blocks of U⁻¹ are
    the inverses of U's leading blocks, so the parameters of the first k columns are U⁻¹[:k, :k] g[:k]."""
    K = g.size
    if K == 0:
        return np.zeros(0)
    inv = np.zeros((K, K))
    with np.errstate(all="ignore"):  # a (nearly) singular pivot: inf or NaN parameters, floored at yy
        # column by column, not a triangular solve with K right-hand sides: that took 15 ms for K = 10 where other
        # processes held the cores (BLAS threads waiting), 1000 times a column's products here
        for j in range(K):
            inv[j, j] = 1.0 / U[j, j]
            inv[:j, j] = -(inv[:j, :j] @ U[:j, j]) * inv[j, j]
        theta = np.cumsum(inv * g, axis=1)  # column k-1: the parameters of the first k columns (zero below row k-1)
        T = np.sum(np.abs(theta), axis=0)
    return np.array([rss_floor(yy, n_rows, np.array([t]), gain) for t in T])


@nb.njit(cache=True, nogil=True, inline="always")  # inlined: a call per column cost 30 % of the search
def _reflect(B, t, row, h, ncols, tol):  # pragma: no cover - compiled
    """One Householder step of a reduction: column ``t`` of B (rows ``row`` … h − 1) reflected onto e_row and the
    reflection applied to columns t + 1 … ncols − 1, in place. False, and nothing touched, when the column's
    remaining energy is at most ``tol`` (it is a combination of the columns before it)."""
    x = B[t]
    s = 0.0
    for r in range(row, h):
        s += x[r] * x[r]
    if s <= tol:
        return False
    alpha = -np.sqrt(s) if x[row] >= 0.0 else np.sqrt(s)
    x[row] -= alpha  # the reflector v = x − α e1, stored in place; vᵀv = 2(s − α x0)
    vv = 2.0 * (s - alpha * (x[row] + alpha))
    for c in range(t + 1, ncols):
        _apply(x, vv, B[c], B[c], row, h)
    return True


@nb.njit(cache=True, nogil=True, inline="always")  # inlined: a call per column cost 30 % of the search
def _apply(v, vv, src, out, row, h):  # pragma: no cover - compiled
    """``out`` = the reflection (I − 2 v vᵀ / vv) of ``src`` over rows ``row`` … h − 1 (``out`` may be
    ``src``)."""
    d = 0.0
    for r in range(row, h):
        d += v[r] * src[r]
    f = 2.0 * d / vv
    for r in range(row, h):
        out[r] = src[r] - f * v[r]


@nb.njit(cache=True, nogil=True, inline="always")
def _with_column(z, yv, row, h, rest, tol):  # pragma: no cover - compiled
    """(z's energy over rows ``row`` … h − 1, the RSS of the reduced y with z added to the fit): the RSS is inf when
    that energy is at most ``tol`` (z is a combination of the columns already reduced). The residual itself is summed,
    not |y|² − (zᵀy)²/zᵀz: no cancellation where z explains nearly all of y."""
    d = 0.0
    dy = 0.0
    for r in range(row, h):
        d += z[r] * z[r]
        dy += z[r] * yv[r]
    if d <= tol:
        return d, np.inf
    f = dy / d
    e = rest
    for r in range(row, h):
        w = yv[r] - f * z[r]
        e += w * w
    return d, e


@nb.njit(cache=True, nogil=True)
def _reduce(R, own, tail, idx, p, dep_tol, nested, border, energy):  # pragma: no cover - compiled
    """Householder reduction of the columns ``idx`` of the triangular factor R of [S, y].

    R (n+1 × n+1, upper triangular, last column y) is the factor of the unit-RMS candidate columns
    S beside y: a least-squares fit of columns of S is the same fit of those columns of R, whose
    orthogonal reduction keeps QR's accuracy (a Gram matrix would square their conditioning: an
    offset of 1e5 on y makes every lagged-y column the constant to 1e-10 of its energy). ``own``
    holds the columns' squared norms, ``tail[r]`` y's energy in rows ≥ r (outside columns < r).

    The first ``p`` columns of ``idx`` are reduced in order; ``nested[t]`` is the RSS of the first
    t + 1 of them. For every later column c, ``border[c - p]`` is the RSS of the p columns together
    with c. A column whose remaining energy is at most ``dep_tol`` of its own is a linear
    combination of those before it and adds nothing: ``nested`` (the RSS of their span, a bound)
    goes on, but ``border`` is inf where c is one, or the p columns hold one (a subset is of
    independent columns: on noise-free data a dependent column ties with the true terms at the
    round-off floor, and a fit of that subset is not defined). ``energy[c - p]`` is c's remaining
    energy as a fraction of its own.
    """
    m = idx.size
    n = R.shape[0] - 1
    h = 0
    for c in range(m):
        h = max(h, idx[c] + 1)  # rows below every column here hold y alone
    # B[c] is column c of the reduced matrix (columns contiguous: the loops run down them); B[m] is y
    B = np.empty((m + 1, h))
    for c in range(m):
        for r in range(h):
            B[c, r] = R[r, idx[c]]
    for r in range(h):
        B[m, r] = R[r, n]
    rest = tail[h]
    row = 0
    dependent = False
    for t in range(p):
        if _reflect(B, t, row, h, m + 1, dep_tol * own[idx[t]]):
            row += 1
        else:
            dependent = True
        e = rest
        for r in range(row, h):
            e += B[m, r] * B[m, r]
        nested[t] = e
    yv = B[m]
    for c in range(p, m):
        z = B[c]
        d, e = _with_column(z, yv, row, h, rest, dep_tol * own[idx[c]])
        energy[c - p] = d / own[idx[c]]
        border[c - p] = np.inf if dependent else e


@nb.njit(cache=True, nogil=True)
def _leaves(R, own, tail, fixed, pool, bound, cutoff, dep_tol, floor, nodes_left):  # pragma: no cover - compiled
    """The last two levels of the branch and bound below the fixed columns ``fixed``, as :func:`_reduce` makes
    them one leaf at a time, to the last bit: for j = 0, 1, …, while ``bound[j]`` is below the best RSS so far
    (``cutoff`` at first), the child fixed + [pool[j]] takes the best of the columns pool[j+1:].

    ``fixed``'s reflections are made once for all children (a leaf made them again each time: most of the
    exact search's time), each child's on top of them; every sum runs over the rows a leaf of its own would
    (up to its columns' largest index), so the RSS are :func:`_reduce`'s. Returns (child position j, column,
    RSS, leaves visited, out of nodes); j = -1 when no leaf beat the cutoff. Each leaf is one node: past
    ``nodes_left`` the search stops with the best found before.
    """
    p = fixed.size
    M = pool.size
    n = R.shape[0] - 1
    # rows a child's leaf reduces: up to the largest index of fixed, pool[j] and pool[j+1:]
    hf = 0
    for c in range(p):
        hf = max(hf, fixed[c] + 1)
    hs = np.empty(M + 1, np.int64)  # hs[j]: largest index + 1 of pool[j:]
    hs[M] = 0
    for j in range(M - 1, -1, -1):
        hs[j] = max(hs[j + 1], pool[j] + 1)
    h = max(hf, hs[0])
    B = np.empty((p + M + 1, h))
    for c in range(p):
        for r in range(h):
            B[c, r] = R[r, fixed[c]]
    for c in range(M):
        for r in range(h):
            B[p + c, r] = R[r, pool[c]]
    for r in range(h):
        B[p + M, r] = R[r, n]
    row = 0
    dependent = False
    for t in range(p):
        if _reflect(B, t, row, h, p + M + 1, dep_tol * own[fixed[t]]):
            row += 1
        else:
            dependent = True
    best_j, best_c, best = -1, -1, cutoff
    used = 0
    if dependent:  # every leaf's border is inf: none beats the cutoff, but each is visited
        for j in range(M - 1):
            if bound[j] >= best:
                break
            used += 1
            if used > nodes_left:
                return best_j, best_c, best, used, True
        return best_j, best_c, best, used, False
    yv = np.empty(h)
    zc = np.empty(h)
    for j in range(M - 1):
        if bound[j] >= best:
            break  # the pools only shrink from here on
        used += 1
        if used > nodes_left:
            return best_j, best_c, best, used, True
        hc = max(hf, max(pool[j] + 1, hs[j + 1]))
        rest = tail[hc]
        x = B[p + j]
        s = 0.0
        for r in range(row, hc):
            s += x[r] * x[r]
        if s <= dep_tol * own[pool[j]]:
            continue  # the child holds a dependent column: every border inf
        # the child's reflector, in a copy (the next children need column j as fixed's reflections left it)
        v = np.empty(hc)
        for r in range(row, hc):
            v[r] = x[r]
        alpha = -np.sqrt(s) if v[row] >= 0.0 else np.sqrt(s)
        v[row] -= alpha
        vv = 2.0 * (s - alpha * (v[row] + alpha))
        _apply(v, vv, B[p + M], yv, row, hc)
        r1 = row + 1
        lbest = np.inf
        lc = -1
        for c in range(j + 1, M):
            _apply(v, vv, B[p + c], zc, row, hc)
            e = max(_with_column(zc, yv, r1, hc, rest, dep_tol * own[pool[c]])[1], floor)
            if e < lbest:
                lbest = e
                lc = c
        if lbest < best:
            best_j, best_c, best = j, lc, lbest
    return best_j, best_c, best, used, False


class SubsetProblem:
    """RSS of subsets of unit-RMS candidate columns, from the triangular factor of [S, y].

    Parameters
    ----------
    R : ndarray, shape (n+1, n+1)
        Upper-triangular factor of [S, y] = QR, S the scaled candidate columns (unit RMS for usable
        ones), y the output (fewer rows, from fewer regression rows than columns, are padded with zeros).
    yy : float
        yᵀy.
    usable : ndarray of bool, shape (n,)
        Candidates the search may use (zero and duplicate columns left out).
    dep_tol : float
        Relative remaining energy below which a column counts as a combination of others.
    gain : float, optional
        The round-off gain of centred signals (see :func:`rss_floor`; default 1).
    """

    def __init__(self, R: np.ndarray, yy: float, usable: np.ndarray, dep_tol: float, gain: float = 1.0) -> None:
        n1 = R.shape[1]
        self.R = np.zeros((n1, n1))
        self.R[: min(R.shape[0], n1)] = R[:n1]
        self.own = np.einsum("ij,ij->j", self.R, self.R)[:-1].copy()
        self.tail = np.append(np.cumsum((self.R[::-1, -1] ** 2))[::-1], 0.0)
        self.yy = float(yy)
        self.usable = np.flatnonzero(usable)
        self.dep_tol = float(dep_tol)
        self.gain = float(gain)
        self.floor = rss_floor(self.yy, 1, np.zeros(0), self.gain)  # until :meth:`settle_floor` finds an exact fit
        self.evaluations = 0

    def settle_floor(self, forced: list[int], k: int, n_rows: int) -> None:
        """Set the floor at the round-off of the first exact fit on the greedy path from ``forced`` to k terms, if
        it meets one (:func:`rss_floor` of its parameters: the subsets that fit these noise-free data exactly hold
        the same terms, with the same round-off); else leave that of yᵀy alone (no subset fits exactly: none ties
        there)."""
        S = self.forward(list(forced), k)
        if not S:
            return
        A = np.column_stack([self.R[:, S], self.R[:, -1]])
        F = np.linalg.qr(A, mode="r")
        m = len(S)
        U, g = F[:m, :m], F[:m, m]
        rest = float(F[m, m] ** 2) if F.shape[0] > m else 0.0
        rss = rest + np.append(np.cumsum(g[::-1] ** 2)[::-1][1:], 0.0)
        floors = prefix_floors(U, g, self.yy, n_rows, self.gain)
        hit = np.flatnonzero((rss <= floors) & (floors < self.yy))
        if hit.size:
            self.floor = max(self.floor, float(floors[hit[0]]))

    def _run(self, idx: list[int] | np.ndarray, p: int, dep_tol: float | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        idx = np.asarray(idx, dtype=np.int64)
        nested = np.empty(p)
        border = np.empty(idx.size - p)
        energy = np.empty(idx.size - p)
        _reduce(self.R, self.own, self.tail, idx, p, self.dep_tol if dep_tol is None else dep_tol,
                nested, border, energy)
        self.evaluations += 1
        return np.maximum(nested, self.floor), np.maximum(border, self.floor), energy

    def leaves(self, F: list[int], pool: list[int], bound: np.ndarray, cutoff: float, nodes_left: int
               ) -> tuple[int, int, float, int, bool]:
        """The last two levels of the branch and bound below F (see :func:`_leaves`)."""
        out = _leaves(self.R, self.own, self.tail, np.asarray(F, dtype=np.int64), np.asarray(pool, dtype=np.int64),
                      np.asarray(bound, dtype=float), float(cutoff), self.dep_tol, self.floor, int(nodes_left))
        self.evaluations += out[3]
        return out

    def bounds(self, order: list[int]) -> np.ndarray:
        """A lower bound on the RSS of every subset of each prefix of ``order``: the RSS of its span.

        Unlike a subset's RSS, a column is dropped only when no energy is left of it: one nearly a
        combination of the others in the prefix (at ``dep_tol``) may be independent in a smaller
        subset, whose RSS it lowers (noise-free data with an input offset: the true terms among
        the pool of all candidates), so dropping it would raise the bound above that subset's RSS
        and cut it. A bound from round-off pivots errs low (a later cut), never high.
        """
        return self._run(order, len(order), dep_tol=0.0)[0]

    def rss(self, S: list[int]) -> float:
        """RSS of the least-squares fit on the columns S (yᵀy for the empty set)."""
        return float(self._run(S, len(S))[0][-1]) if S else self.yy

    def added(self, S: list[int], cands: np.ndarray) -> np.ndarray:
        """RSS of S ∪ {c} for every c in ``cands`` (inf where the columns are dependent)."""
        return self._run(list(S) + list(cands), len(S))[1]

    def outside(self, S: list[int]) -> np.ndarray:
        """Usable candidates not in S."""
        return np.setdiff1d(self.usable, S, assume_unique=True)

    def forward(self, S: list[int], k: int) -> list[int]:
        """Greedy forward selection (smallest RSS, i.e. largest ERR, first) from S up to k terms."""
        S = list(S)
        while len(S) < k:
            cands = self.outside(S)
            if cands.size == 0:
                break
            _, r, energy = self._run(list(S) + list(cands), len(S))
            if not np.isfinite(r.min()):
                break  # every candidate left is a combination of S
            # on noise-free data every extension of the true terms ties at the round-off floor, where
            # the Gram form cannot tell a column that is a combination of S (its squared conditioning
            # leaves it ~1e-9 of its energy): of tied candidates, the one most independent of S
            tied = np.flatnonzero(r == r.min())
            S.append(int(cands[tied[int(np.argmax(energy[tied]))]]))
        return S

    def ordered(self, S: list[int], fixed: int = 0) -> list[int]:
        """S with its first ``fixed`` terms kept in place and the rest in forward (ERR) order among themselves."""
        out = list(S[:fixed])
        rest = list(S[fixed:])
        while rest:
            r = self.added(out, np.array(rest))
            j = int(np.argmin(r))
            if not np.isfinite(r[j]):
                # dependence at dep_tol depends on the order: in ERR order a term would follow terms it is
                # a combination of, where the order the search built S in (each term independent of
                # those before it: a forward pass, an exchange, a branch) is not; keep that one
                return list(S)
            out.append(rest.pop(j))
        return out


def _swap(problem: SubsetProblem, S: list[int], n_fixed: int) -> tuple[list[int], float]:
    """Best single exchanges from S (its first ``n_fixed`` terms stay) until none lowers the RSS."""
    S = list(S)
    rss = problem.rss(S)
    seen = {frozenset(S)}
    while len(S) > n_fixed:
        cands = problem.outside(S)
        if cands.size == 0:
            break
        best = (rss, -1, -1)
        for i in range(n_fixed, len(S)):
            rest = S[:i] + S[i + 1:]
            r = problem.added(rest, cands)
            j = int(np.argmin(r))
            if r[j] < best[0]:
                best = (float(r[j]), i, int(cands[j]))
        # an exchange must gain more than round-off, else two equal subsets would swap forever
        if best[1] < 0 or not best[0] < rss * (1.0 - 1e-12) or rss <= problem.floor:
            break
        S = S[: best[1]] + S[best[1] + 1:] + [best[2]]
        if frozenset(S) in seen:
            break
        seen.add(frozenset(S))
        rss = best[0]
    return S, rss


#: Starts of the swap search besides the greedy path: greedy paths whose first free pick is the
#: 2nd, 3rd, … best by ERR.
SWAP_STARTS = 4


def swap_search(problem: SubsetProblem, k: int, forced: list[int], extra_starts: Sequence[list[int]] = ()
                ) -> tuple[list[int], float]:
    """The best subset of size k (holding ``forced``) found by swaps from several starts.

    Starts: the greedy path, greedy paths whose first free pick is the next-best ERR candidates
    (:data:`SWAP_STARTS` in all), and ``extra_starts`` (completed greedily to size k).
    """
    f = len(forced)
    if k <= f:
        return list(forced[:k]), problem.rss(list(forced[:k]))
    cands = problem.outside(list(forced))
    firsts = cands[np.argsort(problem.added(list(forced), cands), kind="stable")[:SWAP_STARTS]]
    starts = [problem.forward(list(forced) + [int(j)], k) for j in firsts]
    starts += [problem.forward(list(s), k) for s in extra_starts if len(s) <= k]
    best: tuple[list[int], float] | None = None
    tried: set[frozenset[int]] = set()
    for s in starts:
        if len(s) < k or frozenset(s) in tried:
            continue
        tried.add(frozenset(s))
        S, r = _swap(problem, s, f)
        # a later start must gain more than round-off: of tied subsets (two spans that are one on these
        # data, a two-level input's u² = 3u − 2) the first start's, the greedy path's, stays
        if best is None or r < best[1] * (1.0 - 1e-12):
            best = (S, r)
    if best is None:
        # each start is a greedy path grown until no candidate left is independent of it: the longest is the most
        # independent terms there are (as greedy frols says it, so that a caller asking for several sizes takes those)
        most = max((len(s) for s in starts), default=f)
        raise FewerTermsError(f"no subset of {k} independent terms on these data: at most {most} of the candidates "
                              "are independent there", reached=most)
    return best


@dataclass
class SearchBudget:
    """Nodes the branch and bound may visit before giving up (shared by the sizes of one search)."""

    nodes: int
    used: int = 0


class _OutOfNodes(Exception):
    pass


def exact_search(problem: SubsetProblem, k: int, forced: list[int], incumbent: list[int], cutoff: float,
                 budget: SearchBudget) -> tuple[list[int], float, bool]:
    """Best subset of size k holding ``forced`` with RSS below ``cutoff``, by branch and bound.

    Returns (subset, rss, proven). The subset is ``incumbent`` (with its own RSS) when no subset
    below the cutoff exists; ``proven`` is False when the node budget ran out first, and then the
    best subset met so far is returned.
    """
    f = len(forced)
    need0 = k - f
    if need0 <= 0:
        return list(forced[:k]), problem.rss(list(forced[:k])), True
    # candidates in forward (ERR) order from the forced terms: the pools of late nodes then lack
    # the strong terms, their bounds are high, and they are cut
    free = problem.ordered(list(forced) + [int(j) for j in problem.outside(list(forced))], fixed=f)[f:]
    m = len(free)
    best: list = [None, float(cutoff)]

    def visit(F: list[int], i: int, need: int) -> None:
        budget.used += 1
        if budget.used > budget.nodes:
            raise _OutOfNodes
        pool = free[i:]
        if need == 1:
            r = problem.added(F, np.array(pool))
            j = int(np.argmin(r))
            if r[j] < best[1]:
                best[0], best[1] = F + [pool[j]], float(r[j])
            return
        # RSS of F with the pool's tails free[j:], j = m-1 … i (one elimination, pool reversed)
        nested = problem.bounds(F + pool[::-1])[len(F):]
        bound = nested[::-1]  # bound[j - i] = RSS(F ∪ free[j:])
        if need == 2:  # the children are leaves: made together, F's reflections once (the same RSS, node for node)
            j, c, r, used, out = problem.leaves(F, pool, bound, best[1], budget.nodes - budget.used)
            budget.used += used
            if j >= 0:
                best[0], best[1] = F + [pool[j], pool[c]], float(r)
            if out:
                raise _OutOfNodes
            return
        for j in range(i, m - need + 1):
            if bound[j - i] >= best[1]:
                break  # the pools only shrink from here on: no later child can do better
            visit(F + [free[j]], j + 1, need - 1)

    try:
        if m >= need0:
            visit(list(forced), 0, need0)
        proven = True
    except _OutOfNodes:
        proven = False
    if best[0] is None:
        return list(incumbent), problem.rss(list(incumbent)), proven
    return best[0], best[1], proven


@dataclass(frozen=True, eq=False)
class SizePlan:
    """The outcome of a subset search over sizes.

    Attributes
    ----------
    subsets : tuple of tuple of int
        The best subset found of each size looked at, smallest size first.
    rss : ndarray
        Their residual sums of squares (unit-RMS columns: output units²).
    proven : bool
        Whether the rule's answer is proven (exact search finished within its node budget).
    nodes : int
        Branch-and-bound nodes visited.
    exhausted : bool
        Whether the sizes stopped short of those asked because no larger subset of independent
        columns exists on these data (a larger ``max_terms`` would not look further).
    """

    subsets: tuple[tuple[int, ...], ...]
    rss: np.ndarray
    proven: bool
    nodes: int
    exhausted: bool = False


def _just_above(x: float) -> float:
    """The cutoff that lets RSS = x through (the search keeps what is strictly below its cutoff)."""
    return float(np.nextafter(x, np.inf))


def search_sizes(problem: SubsetProblem, sizes: list[int], forced: list[int], *, exact: bool, rule: StopRule,
                 criterion: Callable[[np.ndarray, np.ndarray], np.ndarray], n_rows: int,
                 budget: SearchBudget) -> SizePlan:
    """Best subsets of the sizes the stopping rule needs: swap, then branch and bound if ``exact``.

    * ``n_terms``: the one size.
    * ``tol`` (on RSS / yᵀy): sizes in turn up to the first whose best subset reaches the tolerance.
    * ``criterion``: every size; the exact search of a size only looks for subsets that would beat
      the best criterion of the other sizes (``criterion(sizes, rss)`` of the form N ln(RSS/N) +
      penalty(k)), and skips a size when not even all candidates together would.
    """
    subsets: list[tuple[int, ...]] = []
    rss: list[float] = []
    prev: list[int] = list(forced)
    # a subset at the round-off floor fits exactly and meets any tolerance (one below the floor too)
    target = max(rule.tol * problem.yy, problem.floor) if rule.mode == "tol" else None
    exhausted = False
    for k in sizes:
        try:
            S, r = swap_search(problem, k, forced, extra_starts=[prev])
        except FewerTermsError:
            if rule.mode == "n_terms" or not subsets:
                raise
            # a tolerance or a criterion looks at every size up to max_terms, not at one asked for: where
            # the candidates hold a linear dependence the sizes end with the independent subsets, as
            # greedy's path ends with the independent terms
            exhausted = True
            break
        subsets.append(tuple(S))
        rss.append(r)
        prev = S
        if target is not None and r <= target:
            break
    proven = True
    if not exact:
        return SizePlan(tuple(subsets), np.array(rss), False, 0, exhausted)

    def improve(i: int, cut: float) -> None:
        nonlocal proven
        S, r, ok = exact_search(problem, len(subsets[i]), forced, list(subsets[i]), cut, budget)
        proven &= ok
        if r < rss[i] * (1.0 - 1e-12):  # more than round-off, as a swap must gain
            subsets[i], rss[i] = tuple(S), r

    if rule.mode == "n_terms":
        improve(0, rss[0])
    elif rule.mode == "tol":
        # the smallest size that reaches the tolerance; then the best subset of that size
        for i in range(len(subsets)):
            last = i == len(subsets) - 1
            # below the tolerance (the search then keeps tightening to the best of the size) or, at the
            # last size when nothing reaches it, the best of that size
            improve(i, rss[i] if rss[i] <= target else _just_above(target))
            if rss[i] > target and last:
                improve(i, rss[i])
            if rss[i] <= target or last:
                del subsets[i + 1:], rss[i + 1:]
                break
    else:
        r_all = float(problem.bounds(list(problem.usable))[-1])
        ks = np.array([len(s) for s in subsets])
        pen = criterion(ks, np.full(ks.size, float(n_rows)))  # the penalty: N ln(N/N) = 0
        order = np.argsort(criterion(ks, np.array(rss)), kind="stable")
        for i in order:
            crit = criterion(ks, np.array(rss))
            others = np.delete(crit, i)
            level = n_rows * np.exp((others.min() - pen[i]) / n_rows) if others.size else np.inf
            if r_all >= level:
                continue  # no subset of this size can beat the best of the other sizes
            improve(int(i), min(rss[i], level))
    return SizePlan(tuple(subsets), np.array(rss), proven, budget.used, exhausted)
