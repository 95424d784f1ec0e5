"""Output error: the simulation-error fit of a black box, min_θ J_S(θ), no static points.

Least squares minimises the one-step prediction error; when the noise enters at the output
(y = ŷ_true + v, v white) its regressors hold the noisy past outputs and the estimate is biased.
The output-error (simulation-error) estimate minimises the free-run error J_S instead, and is
consistent in that case; on measured data the best black box is often such a fit (on a real
electric heater the pure simulation-error member of a 14-term structure reached a validation J_S
of 2.7e-5 against least squares' 4.1e-5).

:func:`output_error` is the SE problem (:mod:`._simulation_error`) at λ1 = 1 without static points:
the same compressed ``least_squares`` on the free run's forward sensitivities, from several
starts — least squares, ELS (its process part) and seeded perturbations of least squares (least
squares on random halves of the rows) — each
fitted by "trf" and "dogbox", every start's outcome reported. J_S is not convex: a free run
that diverges is a wall, and so are the parameters outside the stability margin when one is
given. Three things keep the estimate from buying identification error with near-unit roots that
follow the record's slow drift (what the SE front does on the bundled plant; BENCHMARKS.md,
"Output error and the stability margin", measures each on records nothing was fitted or chosen on):

- ``margin``: every local linear model along the record keeps its spectral radius ≤ 1 − margin
  (:mod:`._local_models`); a start outside it is pulled in by shrinking its output feedback;
- ``ridge``: regularisation towards least squares, γ · mean_j (s_j (θ_j − θ_LS,j))² added to J_S
  (s_j the RMS of regressor j: each term counts the change of its contribution to ŷ, in output
  units, so γ is dimensionless and the cost independent of units; for a structure closed under shifts
  θ_j and s_j are those of the centred signals, so it does not depend on offsets either). The drift-following fits
  move θ far along directions the one-step fit pins down, and even a small γ keeps the fit in
  the least-squares basin. The default γ = 1 is the one setting that was never worse than least
  squares on the records nothing was fitted on (three structures of the plant, the buck
  converter, a synthetic output-error system); pure output error (γ = 0) reached a test J_S 20
  times least squares' on the plant, and where the system truly is output-error it recovers θ
  more closely (‖θ − θ_true‖ 0.040 against 0.088 with γ = 1 and 0.22 for least squares);
- ``choose_on``: a choosing record (not the fitting one): the iterate, over every start and
  every step of every fit, with the smallest J_S on it is returned (early stopping and the choice
  of start on data nothing was fitted on; report the result on a third record).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Literal, Mapping, Sequence

import numpy as np
import pandas as pd

from ..core._least_squares import (one_blas_thread, refuse_beyond_float_range, scaled_records, scaled_theta,
                                   unscaled_rss, unscaled_theta)
from ..core._progress import progress_bar
from ..core._records import (Dataset, Record, as_records, carried_from, check_alike, check_overlap, choosing_records,
                             require_lengths, same_record)
from ..core._terms import Structure
from ..core._validation import (Relocked, FrozenFrame, FrozenMap, check_bool, check_choice, check_fields, check_int,
                                check_margin_value, check_mean_square, check_real, check_seed, check_str, check_theta)
from ..models._coerce import as_structure
from ..models._model import Model
from ._extended_least_squares import ELSConvergenceWarning, els
from ._local_models import check_margin
from ._simulation_error import (_SOLVERS, SEProblem, _fit, _pull_inside, _why_infeasible, check_lsq_tol,
                                free_run_scaled, refit_if_slow)

__all__ = ["OEResult", "output_error"]

#: Columns of :attr:`OEResult.starts`.
START_COLUMNS = ("start", "solver", "status", "message", "JS_start", "JS", "JS_choose", "nfev")


@dataclass(frozen=True, eq=False)
class OEResult(Relocked):
    """The result of :func:`output_error`.

    Attributes
    ----------
    model : Model
        The estimate (engineering units).
    JS : float
        Its free-run MSE on the fitting record(s) (output units²). Near the float range's ends (an output near
        1e-160 or 1e160; the fit itself runs on the signals times a power of two) it is the nearest float to the
        data's value, as y² there: a subnormal of fewer digits below 2.2e-308 (about 3e-323 at y × 1e-160, never
        rounded to a 0 that would read as an exact fit), 0 only below 2.5e-324, inf above 1.8e308.
    JS_choose : float
        Its free-run MSE on the choosing record(s); NaN when none was given.
    chosen_on : str
        The choosing records' names (``""``: chosen on the fitting records, by the smallest cost: J_S
        plus the ridge term).
    start : str
        The start of the winning fit (e.g. ``"least squares (trf)"``, ``"subsample #3 (dogbox)"``).
    starts : pandas.DataFrame
        One row per start and solver: ``start``, ``solver``, ``status`` (``"fitted"``,
        ``"infeasible"`` or ``"failed"``), ``message`` (why, in words), ``JS_start``, ``JS`` and
        ``JS_choose`` (output units²; NaN where not reached; with choosing records both of the θ the
        start offers, its iterate with the smallest J_S on them) and ``nfev`` (free runs spent).
    margin : float
        The stability margin (NaN: none).
    radius : float
        The largest spectral radius of the estimate's local models along the fitting record(s).
    seed : int
        The seed of the perturbed starts.
    """

    model: Model
    JS: float
    JS_choose: float
    chosen_on: str
    start: str
    starts: pd.DataFrame = FrozenFrame()
    margin: float
    radius: float
    seed: int

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("JS", "JS_choose"):
            check_mean_square(getattr(self, name), f"OEResult: {name}")
        check_margin_value(self.margin, "OEResult: margin")
        if not self.radius >= 0:  # a spectral radius
            raise ValueError(f"OEResult: radius is a spectral radius, >= 0; got {self.radius!r}")
        check_seed(self.seed, "OEResult: seed")
        missing = [c for c in START_COLUMNS if c not in self.starts.columns]
        if missing:  # failures and repr read them (a hand-edited file, a table built by hand)
            raise ValueError(f"starts lacks the column(s) {missing}; it has {list(self.starts.columns)}")

    @property
    def failures(self) -> Mapping[str, str]:
        """Starts (and solvers) that gave no fit, with the reason: ``{"start (solver)": reason}``."""
        df = self.starts
        bad = df[df["status"] != "fitted"]
        return FrozenMap({(f"{s} ({v})" if v else str(s)): str(m)
                          for s, v, m in zip(bad["start"], bad["solver"], bad["message"])})

    def __repr__(self) -> str:
        chosen = f", J_S on {self.chosen_on}={self.JS_choose:.4g}" if self.chosen_on else ""
        return (f"OEResult(J_S={self.JS:.4g}{chosen}, start={self.start!r}, radius={self.radius:.4g}, "
                f"failed starts={len(self.failures)})")


def output_error(
    structure: Structure,
    data: Record | Dataset | Sequence[Record],
    *,
    n_starts: int = 8,
    subsample: float = 0.5,
    theta0: np.ndarray | None = None,
    margin: float | Literal["auto"] | None = "auto",
    ridge: float = 1.0,
    choose_on: Record | Sequence[Record] | None = None,
    seed: int = 0,
    max_nfev: int = 100,
    tol: float = 1e-8,
    solver: Literal["auto", "trf", "dogbox", "lm"] = "auto",
    progress: bool | None = None,
    name: str = "OE",
) -> OEResult:
    """Output-error (pure simulation-error) estimate of a black box: min J_S, no static points.

    Parameters
    ----------
    structure : Structure
        Process terms (noise terms are dropped: the free run has no MA part).
    data : Record, Dataset or sequence of Record
        Fitting data (a Dataset's ``ident``); with several records each is run freely on its own
        and J_S is the mean over all their samples.
    n_starts : int
        Seeded perturbations of the least-squares estimate tried besides least squares, ELS and
        ``theta0`` (>= 0): least squares on a random subset of the regression rows. (Perturbing
        each parameter by a few per cent instead makes most free runs of a nonlinear structure
        diverge; a subsample moves θ along the directions the data leave loose.)
    subsample : float in (0, 1]
        Fraction of the rows in each of those fits (at least n_terms + 1 rows).
    theta0 : ndarray, shape (n_terms,), optional
        A further start (engineering units).
    margin : float in [0, 1), "auto" or None
        Stability margin: every local linear model at up to 64 samples (u(k), y(k)) of the
        fitting records keeps its spectral radius ≤ 1 − margin (see
        ``SEProblem``); a start outside it is pulled in
        by scaling its output-feedback parameters down, and no step leaves it. ρ = 1 − margin is
        a time constant of about Ts / margin: choose it from the slowest dynamics the system may
        have, not from this record. ``"auto"`` (default): fitted without a margin, and refitted
        with (1 − ρ_LS) / 10 if its modes are over 10 times slower than the least-squares
        model's slowest (as :func:`graybox.se_pareto`; ``margin`` of the result says which).
        None: no margin; a :class:`~graybox.SlowModeWarning` says when the fit is that slow.
    ridge : float >= 0
        Regularisation towards least squares (dimensionless γ): γ · mean_j (s_j (θ_j − θ_LS,j))²
        is added to J_S, s_j the RMS of regressor j (each term: the change of that term's
        contribution to ŷ, output units; for a structure closed under shifts, of the centred signals'
        terms, the same at every offset). Default 1 (see the module docstring for why); 0: pure
        output error, min J_S alone.
    choose_on : Record or sequence of Record, optional
        A choosing record, not used for fitting: the iterate (over every start, solver and step)
        with the smallest J_S on it is returned (early stopping). None: the fit with the smallest
        cost on the fitting data, the one it minimises (J_S, plus the ridge term when ``ridge`` > 0).
    seed : int
        Seeds the perturbed starts.
    max_nfev, tol : int, float
        Per ``least_squares`` run: evaluations and tolerances (``ftol = xtol = tol``, relative, and ``gtol``
        on the gradient over the output's standard deviation, on a problem whose parameters and residuals
        are divided by the power of two nearest that deviation, so the stop does not depend on units).
    solver : {"auto", "trf", "dogbox", "lm"}
        ``least_squares`` method; ``"auto"`` fits every start with both "trf" and "dogbox".
    progress : bool, optional
        Show a progress bar over the starts; default: only on a terminal.
    name : str
        Name of the returned model.

    Returns
    -------
    OEResult
        ``.model`` is the estimate; ``.starts`` reports every start (fitted, infeasible or
        failed, with the reason) and ``.failures`` the ones that gave no fit.

    Raises
    ------
    ValueError
        No start gave a fit (the reasons are listed); or the records do not identify θ (the one rule of
        ``identified_by``: e.g. an input held constant, whose
        terms and the constant are then collinear; the message names them: give a record whose input
        moves, or static points to :func:`~graybox.se_pareto` / :func:`~graybox.se_dsf`).
    """
    given = as_records(data)
    n_starts = check_int(n_starts, "n_starts", low=0)
    subsample = check_real(subsample, "subsample", low=0.0, high=1.0, low_open=True)
    seed = check_seed(seed)
    max_nfev = check_int(max_nfev, "max_nfev", low=1)
    tol = check_lsq_tol(tol)
    check_choice(solver, "solver", _SOLVERS)
    progress = None if progress is None else check_bool(progress, "progress")
    margin = check_margin(margin)
    check_str(name, "name")
    st = as_structure(structure)
    if theta0 is not None:  # before the fits, not after the least-squares and ELS starts
        theta0 = check_theta(len(st), theta0, "theta0")
    crec: list[Record] = []
    if choose_on is not None:  # checked once here, not again by a refit inside the margin
        crec = choosing_records(choose_on)
        require_lengths(crec, st.max_lag, prefix="choose_on: ", what="choosing")  # else blamed on a fitting record
        for c in crec:
            check_alike(given, c)
        if any(same_record(c, r) for c in crec for r in given):
            raise ValueError("choose_on: a choosing record is a fitting record; choose on data the fit did not see "
                             "(e.g. data.valid)")
        for c in crec:
            for r in given:
                check_overlap(c, r, "choosing", "fitting", "choose on data the fit did not see (e.g. data.valid)",
                              prefix="choose_on: ")
    # fitted on scaled signals where J_S would leave the float range (at y near 1e-157 every start failed on NaNs);
    # the choosing records take the same powers
    rec, _, exps = free_run_scaled(given, None, st)
    crec = scaled_records(crec, exps)
    if exps and theta0 is not None:
        theta0 = scaled_theta(theta0, st, exps)
    problem = SEProblem(st, rec, None, margin=None if margin == "auto" else margin, ridge=ridge)
    problem.check_identified()  # the records alone must identify θ: an input held constant does not
    if exps:  # a least-squares θ that is no float in the data's own units is refused as on them, before any fit
        refuse_beyond_float_range(st.terms, unscaled_theta(problem.ls_theta(), list(st), exps),
                                  prefix="least squares: ")
    chooser, chosen_on = None, ""
    if crec:
        chooser, chosen_on = SEProblem(st, crec, None, scored_only=True), ", ".join(r.name for r in crec)
    fit = dict(n_starts=n_starts, subsample=subsample, theta0=theta0, chooser=chooser, chosen_on=chosen_on, seed=seed,
               max_nfev=max_nfev, tol=tol, solver=solver, progress=progress, name=name)
    res = refit_if_slow(problem, lambda p: _oe_fit(p, rec, **fit), "the output-error fit", margin == "auto")
    return _unscaled(res, exps, given)


def _unscaled(res: OEResult, exps: dict[str, int], given: list[Record]) -> OEResult:
    """A fit on the signals times 2^-e (:func:`~graybox.core._least_squares.binary_scaled`) in the data's own units:
    θ (refused where it is no float there), and the free-run MSEs (output units²: 0 or inf where they leave the float
    range, as y² there)."""
    if not exps:
        return res
    st = res.model.structure
    theta = unscaled_theta(res.model.theta, list(st), exps)
    refuse_beyond_float_range(st.terms, theta, prefix="output_error: the estimate cannot be used on these data: ")

    starts = res.starts.copy()
    for c in ("JS_start", "JS", "JS_choose"):
        starts[c] = unscaled_rss(starts[c].to_numpy(float), exps)
    return replace(res, model=Model(st, theta, name=res.model.name, **carried_from(given)),
                   JS=float(unscaled_rss(res.JS, exps)), JS_choose=float(unscaled_rss(res.JS_choose, exps)),
                   starts=starts)


def _oe_fit(problem: SEProblem, rec: list[Record], *, n_starts, subsample, theta0, chooser, chosen_on, seed, max_nfev,
            tol, solver, progress, name) -> OEResult:
    """:func:`output_error` on one problem (its margin a number or None); ``chooser``: the choosing
    records' problem (None: the choice is on the fitting records)."""
    st = problem.structure
    n = len(st)
    solvers = ("trf", "dogbox") if solver == "auto" else (solver,)

    rows: list[dict] = []

    def row(start, solver_, status, message, js0=np.nan, js=np.nan, jc=np.nan, nfev=0):
        rows.append({"start": start, "solver": solver_, "status": status, "message": message, "JS_start": js0,
                     "JS": js, "JS_choose": jc, "nfev": int(nfev)})

    # -- the starts ---------------------------------------------------------------------------------
    ls = problem.ls_theta()
    cands: list[tuple[str, np.ndarray]] = [("least squares", ls)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ELSConvergenceWarning)
        try:
            th_els = els(st, rec).model.theta
        except (ValueError, np.linalg.LinAlgError) as exc:
            row("ELS", "", "failed", f"ELS failed: {exc}")
            th_els = None
    if th_els is not None:
        cands.append(("ELS" + (" (not converged)" if any(issubclass(w.category, ELSConvergenceWarning)
                                                         for w in caught) else ""), th_els))
    if theta0 is not None:
        cands.append(("theta0", check_theta(n, theta0, "theta0")))
    rng = np.random.default_rng(seed)
    rows_n = problem.psi.shape[0]
    size = max(n + 1, int(round(subsample * rows_n)))
    for k in range(n_starts):
        pick = rng.choice(rows_n, size=min(size, rows_n), replace=False)
        cands.append((f"subsample #{k + 1}", problem.from_z(problem.z_lstsq(pick))))

    best: dict = {"score": np.inf}

    def offer(th, score, start):
        if score < best["score"]:
            best.update(score=score, theta=np.array(th), start=start)

    bar = progress_bar(len(cands), f"output error ({len(cands)} starts)", progress)
    try:
        with one_blas_thread():
            for label, th0 in cands:
                bar.update(1)
                js0 = float(problem.js(th0[None])[0])
                # a start whose free run diverges is pulled in too: an unstable least squares is what the margin
                # makes stable (they were dropped as diverging, and margin=0.1 ended with no start at all)
                if not problem.within_margin(th0)[0]:
                    pulled = _pull_inside(problem, th0, 1.0)
                    if pulled is None:
                        row(label, "", "infeasible", _why_infeasible(problem, th0, 1.0) + "; no scaling of its "
                            "output feedback brings it inside")
                        continue
                    th0, c = pulled
                    label = f"{label}, feedback ×{c:g}"
                    js0 = float(problem.js(th0[None])[0])
                if not np.isfinite(js0):
                    row(label, "", "infeasible", _why_infeasible(problem, th0, 1.0), js0)
                    continue
                for sv in solvers:
                    watched = {"score": np.inf}

                    def watch(th, label=label, sv=sv, watched=watched):
                        if chooser is not None:
                            s = float(chooser.js(th[None], bounded=True)[0])
                            if s < watched["score"]:
                                watched.update(score=s, theta=np.array(th))
                            offer(th, s, f"{label} ({sv})")

                    try:
                        th, cost, k = _fit(problem, th0, 1.0, sv, max_nfev, tol, watch=watch)
                    except (ValueError, np.linalg.LinAlgError) as exc:  # a numerical breakdown ends this run
                        row(label, sv, "failed", str(exc), js0)
                        continue
                    js = float(problem.js(th[None], bounded=True)[0])  # inf where the run leaves the bound (diverges)
                    if not np.isfinite(js):
                        row(label, sv, "failed", "the fit ended where the free run diverges", js0, nfev=k)
                        continue
                    if chooser is None:
                        offer(th, cost, f"{label} ({sv})")  # the optimised cost: J_S (+ the ridge term)
                        row(label, sv, "fitted", "", js0, js, nfev=k)
                    else:
                        jc = float(chooser.js(th[None], bounded=True)[0])  # as gb.js: inf where the run diverges
                        offer(th, jc, f"{label} ({sv})")
                        if watched["score"] < jc:  # an earlier iterate chose better: the row's θ is that one
                            jc = watched["score"]
                            js = float(problem.js(watched["theta"][None], bounded=True)[0])
                        row(label, sv, "fitted", "" if np.isfinite(jc) else "its free run diverges on the choosing "
                            "record(s)", js0, js, jc, nfev=k)
    finally:
        bar.close()
    starts = pd.DataFrame(rows, columns=list(START_COLUMNS))
    if "theta" not in best:
        reasons = "; ".join(f"{s}{f' ({v})' if v else ''}: {m}" for s, v, m in
                            zip(starts["start"], starts["solver"], starts["message"]))
        margin = ("a smaller margin" if problem.margin is not None else
                  "a stability margin (e.g. margin=0.1: starts outside it are pulled inside by shrinking their output "
                  "feedback)")
        raise ValueError(f"no start of the output-error fit gave a model: {reasons}. Try theta0, more starts, "
                         f"{margin} or another structure")
    th = best["theta"]
    model = Model(st, th, name=name, **carried_from(rec))
    return OEResult(
        model=model,
        JS=float(problem.js(th[None])[0]),
        JS_choose=float(best["score"]) if chooser is not None else float("nan"),
        chosen_on=chosen_on,
        start=best["start"],
        starts=starts,
        margin=float("nan") if problem.margin is None else problem.margin,
        radius=problem.radius(th),
        seed=seed,
    )
