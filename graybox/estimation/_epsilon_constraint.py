"""The D_SF choice solved directly: min J_S(θ) subject to J_SF(θ) ≤ B.

D_SF (eq. (14)) picks, from a swept Pareto set, the member with the smallest free-run error among
those whose static error lies in the band B. That is the ε-constraint problem

    min_θ J_S(θ)   subject to   J_SF(θ) ≤ B,

and it can be solved without sweeping λ. Both J's are mean squares of residuals whose Jacobians
graybox computes exactly (the forward sensitivity recursion of the free run; implicit
differentiation of the equilibrium reached at each static point), so a Gauss–Newton model of
both is at hand. Each iteration solves the linearised problem

    min_d ‖r_S + J_S d‖²  s.t.  ‖r_SF + J_SF d‖² ≤ B

through its Lagrangian: d(μ) = argmin ‖r_S + J_S d‖² + μ ‖r_SF + J_SF d‖² (+ a Levenberg–Marquardt
damping ν), with the multiplier μ ≥ 0 found by bisection so that the linearised constraint holds;
a step is kept when the true J_SF stays in the band and the true J_S falls, else ν grows. A start
outside the band first restores feasibility: steps of the same linearised problem with the bound
at half the current J_SF (or B), so that J_S is not given away on the way in, and plain descent of
J_SF where the linearisation cannot get there; when that stalls above B the band is infeasible for
the structure, and the result says so with the smallest J_SF reached.

The problem is not convex (the weighted sums of nearby λ1 sit in different basins), so the
iteration runs from several starts and the best feasible end wins: the PE member nearest the band
(the closed form of eq. (11), milliseconds); the member of a coarse SE gradient sweep (14 λ1 below 1,
the sweep ``se_pareto(method="gradient")`` makes) with the smallest J_S in the band, so that the result is
never worse than sweep + D_SF on the same λ1; and the members outside the band (J_SF ≤ 4 B) with a
smaller J_S, from the sweep and from a few fresh weighted-sum fits at high λ1, which restoration
brings into the band. Along the band's edge the iteration goes where no weighted sum can when the
front is not convex.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal, Sequence

import numpy as np

from ._decisions import resolve_band
from ._local_models import check_margin
from ..models._coerce import as_structure, records_of, static_points
from ..models._model import Model
from ..core._least_squares import one_blas_thread, refuse_beyond_float_range, scaled_theta, unscaled_rss, unscaled_theta
from ..core._reprs import beside, bound_text
from ..core._records import Dataset, Record, StaticPoints, carried_from, warn_static_range
from ._simulation_error import (SEProblem, _Failed, _multistart, _pe_members, _pe_starts, _pull_inside,
                                free_run_scaled, gradient_front, refit_if_slow)
from ..core._terms import Structure
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface
from ..core._validation import (Relocked, _is_number, check_fields, check_int, check_lambdas, check_margin_value,
                                check_mean_square, check_real, check_theta, warn)

__all__ = ["se_dsf", "DSFResult"]


@dataclass(frozen=True, eq=False)
class DSFResult(Relocked):
    """The result of :func:`se_dsf`.

    Attributes
    ----------
    model : Model
        The solution (engineering units).
    JS, JSF : float
        Its free-run MSE on the identification record(s) and its static MSE at the static points
        (output units²), by the shared definitions.
    band : float
        B, the bound on J_SF (output units²; 0 or inf where it leaves the float range, as J_S and J_SF then do: an
        output near 1e-160 or 1e160, solved on the signals times a power of two).
    in_band : bool
        Whether J_SF ≤ B holds (the name :class:`Decision` uses too). When False, ``model`` has the
        smallest J_S among the solutions whose J_SF is within 0.1 % of the smallest J_SF reached.
    start : str
        Where the winning run started (e.g. ``"PE λ1=0.0123"``, ``"SE λ1=0.7197"`` or ``"theta0"``).
    start_JS, start_JSF : float
        J_S and J_SF of that start.
    n_iter : int
        Iterations (trial steps) taken, summed over the starts.
    message : str
        Why the winning run stopped, in words.
    margin : float
        The stability margin the model was solved with (NaN: none; with ``margin="auto"``, NaN or
        the margin of the second solve).
    """

    model: Model
    JS: float
    JSF: float
    band: float
    in_band: bool
    start: str
    start_JS: float
    start_JSF: float
    n_iter: int
    message: str
    margin: float

    def __post_init__(self) -> None:
        check_fields(self)
        # 0 or inf: a band beyond the float range in the data's units (se_dsf solved on scaled signals and judged
        # in_band there, which J_SF and B, both 0 or both inf here, no longer tell)
        beyond = self.band == 0.0 or self.band == np.inf
        if not beyond:
            check_real(self.band, "DSFResult: band", low=0, low_open=True)
        for name in ("JS", "JSF", "start_JS", "start_JSF"):
            check_mean_square(getattr(self, name), f"DSFResult: {name}")
        if not beyond and self.in_band != bool(self.JSF <= self.band * (1 + _BAND_RTOL)):  # as se_dsf judges it
            raise ValueError(f"DSFResult: in_band is {self.in_band} but JSF = {self.JSF!r} against the band "
                             f"B = {self.band!r}")
        if self.n_iter < 0:
            raise ValueError(f"DSFResult: n_iter counts trial steps, >= 0; got {self.n_iter}")
        check_margin_value(self.margin, "DSFResult: margin")

    def __repr__(self) -> str:
        # J_SF with the digits that keep it on its side of B as B is printed: a J_SF just above its band (the
        # solve ends on the constraint J_SF = B) read 'J_SF=0.03063, band=0.03063, in_band=False'; one within the
        # round-off se_dsf counts as in the band is said at B
        jsf = min(self.JSF, self.band) if self.in_band else self.JSF
        return (f"DSFResult(J_S={self.JS:.4g}, J_SF={beside(jsf, self.band)}, band={bound_text(self.band, jsf)}, "
                f"in_band={self.in_band}, start={self.start!r}, n_iter={self.n_iter})")


class _GN:
    """J_S, J_SF and their Gauss–Newton Gram matrices in the SE problem's coordinates z (:meth:`SEProblem.to_z`:
    z = s ⊙ θ, or centred ones for a structure closed under shifts, where the damped steps are then the same
    whatever the units' zeros)."""

    def __init__(self, problem: SEProblem):
        self.p = problem
        self.M = len(problem.static)

    def parts(self, z: np.ndarray, jac: bool):
        # a start whose free run diverges has finite residuals too large to square: J_S is then inf, said by the
        # caller (no bounded free run), not by numpy's "overflow encountered in matmul" (an error under -W error)
        with np.errstate(over="ignore", invalid="ignore"):
            return self._parts(z, jac)

    def _parts(self, z: np.ndarray, jac: bool):
        p = self.p
        th = p.from_z(z)
        # made from z as the optimisers' runs are (the centred model for a centred problem), not through raw θ
        ed, es, Jd, Js = p.run_residuals(z, jacobian=jac)
        r1 = ed / np.sqrt(p.n_dyn)
        r2 = es / np.sqrt(self.M)
        f = float(r1 @ r1) if np.all(np.isfinite(r1)) else np.inf
        g = float(r2 @ r2) if np.all(np.isfinite(r2)) else np.inf
        if p.margin is not None and np.isfinite(f) and np.isfinite(g) \
                and not p.within_margin(th, (es + p.static.ybar)[None])[0]:
            return np.inf, np.inf, None  # outside the stability margin: a wall, as a diverging run is
        if not jac or not (np.isfinite(f) and np.isfinite(g)):
            return f, g, None
        J1 = Jd / np.sqrt(p.n_dyn)
        J2 = Js / np.sqrt(self.M)
        if not (np.all(np.isfinite(J1)) and np.all(np.isfinite(J2))):
            return f, g, None
        return f, g, (J1.T @ J1, J1.T @ r1, J2.T @ J2, J2.T @ r2)


def _step(A1, b1, A2, b2, mu, nu):
    H = A1 + mu * A2
    D = np.diag(np.maximum(np.diag(H), 1e-12 * max(1.0, float(np.max(np.diag(H))))))
    try:
        return np.linalg.solve(H + nu * D, -(b1 + mu * b2))
    except np.linalg.LinAlgError:
        return None


def _lin(c: float, b: np.ndarray, A: np.ndarray, d: np.ndarray) -> float:
    return c + 2.0 * float(b @ d) + float(d @ A @ d)


def _constrained_step(g, G, band, nu, mu0=0.0):
    """d minimising the linearised J_S with the linearised J_SF ≤ band, and its multiplier μ.

    μ is bracketed and bisected (in log) to 0.01 %; the previous step's μ (``mu0``) starts the bracket,
    since μ changes little from one iteration to the next. (None, mu0) when no μ gets there.
    """
    A1, b1, A2, b2 = G

    def inside(mu):
        d = _step(A1, b1, A2, b2, mu, nu)
        return d if d is not None and _lin(g, b2, A2, d) <= band else None

    d = inside(0.0)
    if d is not None:
        return d, 0.0
    warm = mu0 > 0
    factor = 4.0 if warm else 10.0
    hi = mu0 if warm else 1e-6 * float(np.trace(A1)) / max(float(np.trace(A2)), 1e-300)
    d = inside(hi)
    lo = 0.0
    if d is not None:  # the warm μ is enough: look down for one that is not
        for _ in range(80):
            dm = inside(hi / factor)
            if dm is None:
                lo = hi / factor
                break
            hi, d = hi / factor, dm
    else:  # grow μ until the linearised constraint holds
        for _ in range(80):
            lo, hi = hi, hi * factor
            d = inside(hi)
            if d is not None:
                break
        else:
            return None, mu0
    for _ in range(60):  # then the smallest such μ (the multiplier), to _MU_RTOL
        if not (lo > 0 and hi > lo * (1 + _MU_RTOL)):
            break
        mid = np.sqrt(lo * hi)
        dm = inside(mid)
        if dm is not None:
            hi, d = mid, dm
        else:
            lo = mid
    return d, hi


#: Smallest and largest relative margin inside the band that the linearised constraint aims at; at the
#: largest, a step that still leaves the band is shortened instead (the same step would come again).
_MARGIN_FLOOR = 1e-4
_MARGIN_CAP = 0.5

#: Relative precision of the multiplier μ of the linearised band.
_MU_RTOL = 1e-4

#: A fall of J_S below this fraction of it is its rounding (a few ulps), not a decrease.
_ROUNDING = 1e-14

#: J_SF within this fraction above B is in the band (its round-off), for the iteration, its runs and the result.
_BAND_RTOL = 1e-12


def _pe_start(problem: SEProblem, band: float, lambdas: np.ndarray) -> tuple[np.ndarray, str]:
    th = _pe_members(problem, lambdas)  # NaN rows where the weights do not identify θ (λ1 = 1, a held input)
    lambdas = np.asarray(lambdas, float)
    if th is None:  # PE cannot solve these weights: least squares alone (its rows NaN, as those of unsolved members)
        th = np.full((lambdas.size, len(problem.structure)), np.nan)
    # the λ1 = 1 member weighs no static point: it is the least-squares estimate, appended below once (it was
    # scored twice, and reported as "PE λ1=1" when chosen)
    ok = np.all(np.isfinite(th), axis=1) & (lambdas < 1.0)
    th = np.vstack([th[ok], problem.ls_theta()[None, :]])
    lam = np.r_[lambdas[ok], 1.0]
    js, jsf = problem.js(th), problem.jsf(th)
    inside = np.isfinite(js) & (jsf <= band)
    if inside.any():
        i = int(np.flatnonzero(inside)[np.argmin(js[inside])])
    else:
        ok = np.isfinite(js) & np.isfinite(jsf)
        if not ok.any():
            raise ValueError("no PE member nor the least-squares estimate has a bounded free run and a static curve "
                             "at every static point: give theta0")
        i = int(np.flatnonzero(ok)[np.argmin(jsf[ok])])
    return th[i], ("least squares" if i == len(lam) - 1 else f"PE λ1={lam[i]:.4g}")


#: λ1 of the default coarse sweep. Without λ1 = 1: that member ignores the static points, and the
#: sweep restarts from every start right after it (the multi-start fits dominate the sweep's time).
_COARSE = np.logspace(-2, 0, 15)[:-1]

#: λ1 of the fresh weighted-sum fits (least squares and the PE member of the same λ1 as starts,
#: "dogbox") that add starts to the coarse sweep's: fits from afar land in basins that the sweep's
#: continuation does not reach (BENCHMARKS.md, structure selection).
_FRESH = (0.95, 0.85)


def _sweep_starts(problem: SEProblem, band: float, lambdas: np.ndarray,
                  n_out: int = 3) -> list[tuple[np.ndarray, str]]:
    """Starts near the band's edge: members of a coarse SE sweep and of a few fresh fits.

    The coarse sweep is :func:`graybox.se_pareto`'s gradient sweep itself (same starts and
    solvers), so the edge iteration from its best in-band member ends no worse than sweep + D_SF
    on the same λ1. Returned: that member, then the (at most ``n_out``) solutions outside the band
    with J_SF ≤ 4 B and a smaller J_S, best first, which restoration brings into the band
    (better basins); when there are none, the ``n_out`` of the smallest J_SF (the band may be out
    of reach: then they compete on J_S, see :data:`_JSF_TIE`); each as (θ, description).
    """
    front = gradient_front(problem, lambdas, progress=False, starts=_pe_starts(problem))
    if not np.all(np.isfinite(front.thetas), axis=1).any() and not np.any(np.asarray(lambdas) == 1.0):
        # no start below λ1 = 1 has a stable equilibrium at every static point (least squares and the PE members
        # lack one): the λ1 = 1 fit, which the points do not constrain, may have them, and the sweep continued
        # from it finds the members se_pareto's default sweep (λ1 = 1 first) finds
        front = gradient_front(problem, np.r_[1.0, lambdas], progress=False, starts=_pe_starts(problem))
    cands = [(th, f"SE λ1={lam:.4g}") for th, lam in zip(front.thetas, front.lambdas)]
    ls = problem.ls_theta()
    fresh = np.array(_FRESH)
    pe = _pe_members(problem, fresh)
    for k, lam in enumerate(fresh):
        starts = [("least squares", ls)] + ([("PE", pe[k])] if pe is not None and np.all(np.isfinite(pe[k])) else [])
        try:
            cands.append((_multistart(problem, float(lam), starts, ("dogbox",), 50, 1e-8)[0],
                          f"SE λ1={lam:.4g} (fresh fit)"))
        except _Failed:
            pass
    cands = [(th, name) for th, name in cands if np.all(np.isfinite(th))]
    if not cands:  # said by se_dsf's error (the first member's reason: the others' are alike)
        first = min(front.failures) if front.failures else None
        raise ValueError("every member failed" + (f" (λ1 = {front.lambdas[first]:.4g}: {front.failures[first]})"
                                                  if first is not None else ""))
    th = np.array([c[0] for c in cands])
    js, jsf = problem.js(th), problem.jsf(th)
    inside = np.flatnonzero(np.isfinite(js) & (jsf <= band))
    out, best = [], np.inf
    if inside.size:
        i = int(inside[np.argmin(js[inside])])
        out.append(cands[i])
        best = js[i]
    near = [k for k in np.argsort(js) if np.isfinite(js[k]) and band < jsf[k] <= 4 * band and js[k] < best]
    out += [(cands[k][0], cands[k][1] + " (outside the band, restored)") for k in near[:n_out]]
    if not out:  # none near the band (maybe out of reach): those of the smallest J_SF, whose J_S differ
        low = [k for k in np.argsort(jsf) if np.isfinite(js[k]) and np.isfinite(jsf[k])]
        out += [(cands[k][0], cands[k][1] + " (smallest J_SF)") for k in low[:n_out]]
    return out


def _inside_margin(problem: SEProblem, starts: list[tuple[np.ndarray, str]],
                   why: list[str]) -> list[tuple[np.ndarray, str]]:
    """The starts inside the stability margin: each outside it pulled in by shrinking its output
    feedback, or dropped (the reason added to ``why``)."""
    out = []
    for th, name in starts:
        if problem.within_margin(th, problem.static_outputs(th))[0]:
            out.append((th, name))
            continue
        pulled = _pull_inside(problem, th, _HALF)
        if pulled is None:
            why.append(f"{name} is outside the stability margin and no scaling of its output feedback brings it in")
        else:
            out.append((pulled[0], f"{name}, feedback ×{pulled[1]:g}"))
    return out


#: λ1 at which a start is pulled inside the margin (any λ1 < 1 asks the same: bounded free run, stable
#: equilibria at the static points, the margin).
_HALF = 0.5


def _edge(gn: _GN, th0: np.ndarray, band: float, max_iter: int, tol: float):
    """The constrained Gauss–Newton iteration from θ0: (θ, J_S, J_SF, J_S0, J_SF0, steps, message), or None
    when θ0 has an unbounded free run or reaches no equilibrium at some static point."""
    problem = gn.p
    z = problem.to_z(th0)
    f, g, G = gn.parts(z, True)
    if not (np.isfinite(f) and np.isfinite(g)):
        return None
    f0, g0 = f, g
    nu = 1e-3
    mu = 0.0
    # the linearised constraint aims a margin inside the band, so that the curvature of J_SF does not
    # throw most steps just outside it (they would be refused and the iteration would zigzag)
    margin = 0.05
    it = 0
    message = f"{max_iter} iterations reached"
    stall = 0
    with np.errstate(all="ignore"):
        while it < max_iter:
            it += 1
            if G is None:
                message = "the Jacobian is not finite at the current point"
                break
            A1, b1, A2, b2 = G
            # in the band as the result is judged (to its round-off): a start above B by 1e-14 relative was iterated as
            # outside it, by J_SF descent alone, and returned with J_S 11 % above the band's best, said in the band
            feasible = g <= band * (1 + _BAND_RTOL)
            if feasible:
                aim = min(band * (1.0 - margin), max(g, band * (1.0 - 2 * margin)))
                d, mu = _constrained_step(g, G, aim, nu, mu)
                if d is None and aim < g:
                    # the aim a margin inside the band lies below what the linearised J_SF reaches (a band within
                    # that margin of J_SF's least value): aim at J_SF as it is (d = 0 meets it), which leaves the
                    # steps along the valley of its least value. The run stopped at its start ("no feasible step")
                    d, mu = _constrained_step(g, G, g, nu, mu)
            else:
                # restoration: the smallest linearised J_S with J_SF at most half of now (or the band),
                # so that J_S is not given away on the way into the band; where the linearised J_SF
                # cannot get there, plain descent of J_SF with J_S as a small regulariser
                d, mu = _constrained_step(g, G, max(band * (1.0 - margin), 0.5 * g), nu, mu)
                if d is None:
                    d = _step(A2, b2, A1, b1, 1e-6, nu)
            if d is None:
                nu *= 10.0
                if nu > 1e12:
                    message = "no step improves (the linearised problem has no feasible step)"
                    break
                continue
            f_new, g_new, _ = gn.parts(z + d, False)  # the Jacobian only where the step is kept
            # a decrease within J_S's rounding is none: whether such a step was kept, and so how a converged run went
            # on and stopped, was decided by the rounding alone, which differs with the output's units (y × 1000
            # counted other steps, stopped for another reason and named another start of the same model)
            lower = f_new < f * (1.0 - _ROUNDING)
            if feasible:
                ok = np.isfinite(f_new) and g_new <= band * (1 + _BAND_RTOL) and lower
                gain = (f - f_new) / f if ok else 0.0
            else:
                ok = np.isfinite(f_new) and np.isfinite(g_new) and g_new < g
                gain = (g - g_new) / g if ok else 0.0
            if ok:
                z, f, g = z + d, f_new, g_new
                G = gn.parts(z, True)[2]
                nu = max(nu / 3.0, 1e-12)
                margin = max(margin / 1.5, _MARGIN_FLOOR)
                stall = stall + 1 if gain < tol else 0
                if not feasible and g <= band * (1 + _BAND_RTOL):
                    # restoration reached the band: J_S's stall count starts now (J_SF's small gains said nothing of
                    # it, and its "converged" was said of a run that went on, even when it then ran out of steps)
                    stall = 0
                if stall >= 3 and feasible and margin > _MARGIN_FLOOR:
                    # small steps while the aim is still well inside the band: aim at its edge first
                    margin, stall = _MARGIN_FLOOR, 0
                if stall >= 3:  # J_S stalls in the band, or J_SF outside it
                    message = (f"converged: relative decrease of {'J_S' if feasible else 'J_SF'} below {tol:g} "
                               "for 3 steps")
                    break
            elif feasible and np.isfinite(f_new) and lower and np.isfinite(g_new) and margin < _MARGIN_CAP:
                margin = min(2.0 * margin, _MARGIN_CAP)  # the model was right about J_S: only the band was missed
            else:
                nu *= 4.0
                if nu > 1e12 and feasible and margin > _MARGIN_FLOOR:
                    # no step improves while the aim is still a margin inside the band: the point is stationary for
                    # that aim (J_SF just under it, the linearised constraint leaves no room), not for the band. Aim
                    # at the band's edge before stopping (a run stopped here 2 % above the band's best J_S, or went on
                    # when a 1-ulp gain happened to be accepted: the result depended on the output's units)
                    margin, nu = _MARGIN_FLOOR, 1e-3
                elif nu > 1e12:
                    message = "converged: no step along which the model improves (step size vanished)"
                    break
    return problem.from_z(z), f, g, f0, g0, it, message


def se_dsf(
    structure: Structure | object,
    data: Record | Dataset | Sequence[Record],
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    band: float | None = None,
    theta0: np.ndarray | None = None,
    lambdas: Sequence[float] | np.ndarray | None = None,
    max_iter: int = 200,
    tol: float = 1e-9,
    pe_lambdas: np.ndarray | None = None,
    margin: float | Literal["auto"] | None = "auto",
    ubar: np.ndarray | None = None,
) -> DSFResult:
    """The D_SF model solved directly: min J_S(θ) subject to J_SF(θ) ≤ ``band``.

    Parameters
    ----------
    structure : Structure, sequence of str, Model, or a result that carries one
        Process terms (noise terms are dropped); a Selection, ELSResult, Decision … gives its own.
    data : Record, Dataset or sequence of Record
        Identification data (a Dataset's ``ident``); each record is run freely on its own.
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static points (default: the Dataset's); a curve or surface is sampled at ``ubar`` or over
        its domain, as :func:`graybox.se_pareto` samples it (sampled points carry no uncertainty:
        give ``band``).
    band : float
        B > 0, the bound on J_SF in output units² (D_SF's band). Default: the static points' own,
        :attr:`~graybox.StaticPoints.band` (the mean of their uncertainty δ_i²); static points
        without an uncertainty need it given (``ValueError`` otherwise).
    theta0 : ndarray, shape (n_terms,), optional
        The only start; default: several (see the module docstring).
    lambdas : sequence of float, optional
        λ1 of the coarse SE sweep that finds starts (default: the 14 values of logspace(-2, 0, 15)
        below 1; λ1 = 1 weighs no static point, and the least-squares estimate is a start anyway).
    max_iter : int
        Largest number of trial steps.
    tol : float
        Relative decrease of J_S (of J_SF while a run restores feasibility) below which a run stops.
    pe_lambdas : ndarray of shape (P,), optional
        λ1 values of the PE sweep (closed form) whose member nearest the band is one start
        (default: 60 in logspace(-6, 0)).
    margin : float in [0, 1), "auto" or None
        Stability margin, as in :func:`graybox.se_pareto`: every local linear model along the
        identification records and at the static points' equilibria keeps its spectral radius
        ≤ 1 − margin; no step leaves it, and a start outside it is pulled in by shrinking its output
        feedback (or dropped). Without it the iteration may buy identification error with
        near-unit roots that follow the record's slow drift (BENCHMARKS.md, "SE D_SF against
        ELS"). ``"auto"`` (default): solved without a margin, and again with (1 − ρ_LS) / 10 if
        the model's modes are over 10 times slower than the least-squares model's slowest (as
        :func:`graybox.se_pareto`). None: no margin; a :class:`~graybox.SlowModeWarning` says when
        the model is that slow.
    ubar : ndarray, optional
        Where to sample a StaticCurve (shape (K,)) or StaticSurface (shape (K, m)) given as
        ``static``, in input units.

    Returns
    -------
    DSFResult
        The model, its J_S and J_SF, whether the band was met (with a warning naming the smallest
        J_SF reached when it was not), the start and the iteration count.

    Raises
    ------
    ValueError
        θ is not identified by the records and the static points together (the one rule of
        ``identified_by``; the message names the free terms and
        what data would identify them); records whose input is held constant are fitted when the static
        points identify θ. No start has a bounded free run and a reached equilibrium at every point.
    """
    recs = records_of(data)
    sp = static_points(static, data, ubar=ubar, needed_by="se_dsf")
    if band is None and isinstance(static, (StaticCurve, StaticSurface)):
        raise ValueError(f"se_dsf: a {type(static).__name__} carries no uncertainty to take the band from: give band=B "
                         "(output units², the bound on J_SF)")
    if band is not None and not _is_number(band):  # a pair too: se_dsf takes one bound (check_band offers pairs)
        raise TypeError(f"se_dsf: band must be a number B > 0 (the bound on J_SF, output units²), got {band!r}")
    given_band = band is not None
    band = resolve_band(band, sp, "se_dsf")[1] if given_band else None  # from δ below, where δ² stays a float
    max_iter = check_int(max_iter, "max_iter", low=1)
    tol = check_real(tol, "tol", low=0, low_open=True)
    # checked here, not only where the sweeps run: with theta0 they do not, and bad weights would pass unseen
    lambdas = None if lambdas is None else check_lambdas(lambdas)
    pe_lambdas = None if pe_lambdas is None else check_lambdas(pe_lambdas, "pe_lambdas")
    margin = check_margin(margin)
    st = as_structure(structure)
    # solved on scaled signals as se_pareto is (at y near 1e-170 δ² and every J underflowed to 0, near 1e157 they
    # overflowed); the model and the J's are mapped back to the data's units
    fit_recs, fit_sp, exps = free_run_scaled(recs, sp, st)
    if exps and theta0 is not None:
        theta0 = scaled_theta(check_theta(len(st), theta0, "theta0"), st, exps)
    fit_band = resolve_band(None, fit_sp, "se_dsf")[1] if not given_band else band if not exps else float(
        np.ldexp(band, -2 * exps["y"]))
    problem = SEProblem(st, fit_recs, fit_sp, margin=None if margin == "auto" else margin)
    problem.check_identified()  # the records with the static points (an input held constant needs them)
    warn_static_range(sp.ubar, recs)  # after: bad input is an error, not a warning and an error
    solve = dict(band=fit_band, theta0=theta0, lambdas=lambdas, max_iter=max_iter, tol=tol, pe_lambdas=pe_lambdas)
    result = refit_if_slow(problem, lambda p: _solve(p, **solve), "se_dsf's model", margin == "auto")
    if exps:
        result = _unscaled(result, exps, recs, sp)
    band = result.band  # the points' own where none was given
    if not result.in_band:  # said of the model returned only (margin="auto" may have solved twice)
        warn(f"se_dsf: the band B = {bound_text(band, result.JSF)} is infeasible for this structure from the start {result.start}: the "
             f"smallest J_SF reached is {beside(result.JSF, band)} (J_S {result.JS:.4g}); widen the band or change the structure",
             RuntimeWarning)
    return result


def _unscaled(res: DSFResult, exps: dict[str, int], recs: list[Record], sp: StaticPoints) -> DSFResult:
    """A solve on the signals times 2^-e (:func:`~graybox.core._least_squares.binary_scaled`) in the data's own
    units: θ (refused where it is no float there), the band and the J's (output units²: 0 or inf where they leave the
    float range, as y² there)."""
    st = res.model.structure
    theta = unscaled_theta(res.model.theta, list(st), exps)
    refuse_beyond_float_range(st.terms, theta, prefix="se_dsf: the model cannot be used on these data: ")
    own = {k: float(unscaled_rss(getattr(res, k), exps)) for k in ("JS", "JSF", "band", "start_JS", "start_JSF")}
    return replace(res, model=Model(st, theta, name=res.model.name, **carried_from(recs, sp)), **own)


def _solve(problem: SEProblem, **options) -> DSFResult:
    """:func:`se_dsf` on one problem (its margin a number or None), BLAS on one thread: the fits and
    edge steps make thousands of small BLAS calls, which a multi-threaded BLAS only slows down."""
    with one_blas_thread():
        return _solve_one_thread(problem, **options)


#: Relative tolerance on J_SF when the band is out of reach: the model is the run of the smallest J_S
#: among those within it of the smallest J_SF reached. J_SF depends on the static clusters only, so
#: its minimisers form a valley along which J_S is free: the smallest J_SF alone returned an arbitrary
#: point of it (J_S 100 times another run's, whose J_SF was 3e-5 larger).
_JSF_TIE = 1e-3


def _solve_one_thread(problem: SEProblem, *, band, theta0, lambdas, max_iter, tol, pe_lambdas) -> DSFResult:
    why: list[str] = []
    if theta0 is not None:
        starts = [(check_theta(len(problem.structure), theta0, "theta0"), "theta0")]
    else:
        lams = np.logspace(-6, 0, 60) if pe_lambdas is None else pe_lambdas
        coarse = _COARSE if lambdas is None else lambdas
        starts = []
        try:
            starts.append(_pe_start(problem, band, lams))
        except ValueError as exc:  # the SE sweep may still find starts
            why.append(str(exc))
        try:
            starts += _sweep_starts(problem, band, coarse)
        except (ValueError, np.linalg.LinAlgError) as exc:
            why.append(f"the coarse SE sweep: {exc}")
    if problem.margin is not None:
        starts = _inside_margin(problem, starts, why)
    gn = _GN(problem)
    runs = []
    for th_s, start_s in starts:
        r = _edge(gn, th_s, band, max_iter, tol)
        if r is not None:
            runs.append((start_s, r))
    if not runs:
        named = ", ".join(name for _, name in starts) or "none found"
        inside = "" if problem.margin is None else " inside the stability margin"
        raise ValueError(f"no start ({named}) has a bounded free run and an equilibrium reached at every static "
                         f"point{inside}" + (f" ({'; '.join(why)})" if why else "") + "; give another theta0"
                         + (", or margin= (e.g. 0.01: the sweep's members then keep stable equilibria)"
                            if problem.margin is None else ""))
    # the feasible run with the smallest J_S; else, among the runs within _JSF_TIE of the smallest J_SF
    # reached, the smallest J_S
    inside = [t for t in runs if t[1][2] <= band * (1 + _BAND_RTOL)]
    if not inside:
        g_min = min(t[1][2] for t in runs)
        inside = [t for t in runs if t[1][2] <= g_min * (1 + _JSF_TIE)]
    # runs whose J_S are one within its rounding ended on one model (e.g. least squares and the fresh fit started from
    # it): the first start of them is named, not the one the last bit favoured (which changed with the output's zero:
    # 'least squares' at y, 'SE λ1=0.95 (fresh fit)' at y + 1e4, for the same model)
    best = min(t[1][1] for t in inside)
    start, (th, f, g, f0, g0, it, message) = next(t for t in inside if t[1][1] <= best * (1.0 + _ROUNDING))
    it = sum(r[5] for _, r in runs)
    # J_S and J_SF as the run computed them at its last z (the shared definitions, on the centred signals for a
    # centred problem: the same errors to round-off). Those of raw θ on the records as given carried the offsets'
    # powers: at y + 1e7 (1e9 of y's spreads) J_S came out 2.5e-6 and J_SF 6e-6 off relative, so the result
    # depended on the output's zero well beyond the final model's rounding
    feasible = bool(g <= band * (1 + _BAND_RTOL))
    name = "SE D_SF (direct)" if feasible else "SE min J_SF (band infeasible)"
    # the records' input order (not the structure's name order): an input array's columns as the user has them
    model = Model(problem.structure, th, name=name, **carried_from(problem.records, problem.static))
    return DSFResult(model, f, g, band, feasible, start, f0, g0, it, message,
                     float("nan") if problem.margin is None else problem.margin)
