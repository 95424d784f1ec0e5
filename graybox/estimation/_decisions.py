"""Decision makers: pick one model from a Pareto set.

:func:`decide_dsf` is the paper's D_SF (eq. (14)): the member with the smallest free-run
error J_S among those whose static error J_SF lies in the uncertainty interval
B = [0, band]. B is in the output's units² and belongs to the data: it is given, or read from
the static points' uncertainty δ (:attr:`graybox.StaticPoints.band`, the mean of δ_i²; the
paper's 0.031 mlc² = 0.175² for its transmitter); never a default.
With ``choose_on`` it scores
the members on a choosing record instead of the identification data they were fitted on: on the
bundled plant the gradient SE members of structure (15) have identification J_S 0.54 and
validation J_S near 2000 (near-integrators that follow the record's drift), which the paper's
rule cannot see.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..models._coerce import as_record
from ..models._model import Model
from ._pareto import ParetoSet, members_js
from ..core._records import (Record, RecordPrint, check_overlap, check_print_overlap, choosing_records, require_lengths,
                             same_record)
from ..core._least_squares import binary_exponent, binary_scaled, scaled_theta
from ..core._reprs import beside, bound_text, squared_text
from ..core._regressors import regressor_matrix
from ..core._simulation import simulate_many
from ..core._validation import Relocked, check_band, check_choice, check_fields, check_mean_square, check_weight
from ..static._constraints import InfeasibleError
from ..core._records import StaticPoints

__all__ = ["Decision", "decide_dsf", "decide_min_correlation", "FALLBACKS", "resolve_band"]


def resolve_band(band: object, static: StaticPoints | None, who: str) -> tuple[float, float]:
    """D_SF's band as ``(low, high)``: ``band`` checked, or, when it is None, the static points' own.

    ``ValueError`` saying what to pass when neither is there: a band has no unit-free default.
    """
    if band is not None:
        return check_band(band, "band")
    if static is None:
        raise ValueError(f"{who} needs band=B, J_SF's bound in output units² (e.g. the square of the static "
                         "measurements' error, or data.static.band when the static points carry their uncertainty)")
    return 0.0, static.band


#: The rules a :class:`Decision` is made by, and whether each says its member is in the band: D_SF (eq. (14)),
#: its explicit fallback (J_SF nearest B: the smallest when B = [0, b]), the minimal-correlation rule and
#: ``select_graybox``'s black-box choice (no band).
DECISION_RULES = {"D_SF": True, "min J_SF": False, "min correlation": True, "min J_S": True}


@dataclass(frozen=True, eq=False)
class Decision(Relocked):
    """One member chosen from a Pareto set, and why.

    Attributes
    ----------
    model : Model
        The chosen member (named after the set's method and the rule).
    index : int
        Its position in the Pareto set.
    lambda1 : float
        Its weight λ1 (NaN when the member came from no weight).
    JS, JSF : float
        Its free-run and static errors as stored in the set (output units²).
    rule : str
        ``"D_SF"``, ``"min J_SF"`` (D_SF's explicit fallback: no member in the band, the member
        whose J_SF is nearest the band taken — the smallest J_SF when B = [0, b]),
        ``"min correlation"`` or ``"min J_S"`` (``select_graybox``'s black box, chosen without a band).
    in_band : bool
        Whether J_SF lies in the band B (always False for the fallback; True for rules without a band).
    score : float
        The value the rule minimised at the chosen member (J_S for D_SF — on the choosing record
        when there is one —, J_SF for the fallback (whose distance to B it minimised), ρ for the
        minimal-correlation rule).
    chosen_on : str
        The choosing records' names when the rule scored the members on data other than the
        set's own (``""``: on the set's J_S, or for the minimal-correlation rule on its record).
    """

    model: Model
    index: int
    lambda1: float
    JS: float
    JSF: float
    rule: str
    in_band: bool
    score: float
    chosen_on: str = ""

    def __post_init__(self) -> None:
        check_fields(self)
        check_choice(self.rule, "Decision: rule", tuple(DECISION_RULES))
        if self.in_band != DECISION_RULES[self.rule]:
            raise ValueError(f"Decision: in_band is {self.in_band} but rule {self.rule!r} "
                             f"{'chooses in the band' if DECISION_RULES[self.rule] else 'is the fallback: no member in the band'}")
        if self.index < 0:
            raise ValueError(f"Decision: index is a member's position, >= 0; got {self.index}")
        check_weight(self.lambda1, "Decision: lambda1")
        for name in ("JS", "JSF"):
            check_mean_square(getattr(self, name), f"Decision: {name}")
        if self.score < 0:  # a mean square or a correlation's magnitude
            raise ValueError(f"Decision: score is never negative; got {self.score!r}")

    def __repr__(self) -> str:
        unit = self.model.units[1]  # J_S and J_SF are in output units²; ρ has none
        score = f"{self.score:.4g}" if self.rule == "min correlation" else squared_text(self.score, unit)
        on = f", chosen_on={self.chosen_on!r}, score={score}" if self.chosen_on else ""
        return (f"Decision(rule={self.rule!r}, index={self.index}, λ1={self.lambda1:.4g}, "
                f"J_S={squared_text(self.JS, unit)}, J_SF={squared_text(self.JSF, unit)}, in_band={self.in_band}{on})")


def _decision(pareto: ParetoSet, i: int, rule: str, in_band: bool, score: float, label: str,
              chosen_on: str = "") -> Decision:
    return Decision(pareto.member_model(i, name=label), int(i), float(pareto.lambdas[i]), float(pareto.JS[i]),
                    float(pareto.JSF[i]), rule, in_band, float(score), chosen_on)

def check_choosable(pareto: ParetoSet, what: str, needs_jsf: bool = True) -> None:
    """A clear error naming ``what`` when a set has nothing a rule could choose: every member failed
    (``InfeasibleError`` with the first reason; their J's are inf, which read as "diverged" or "undefined static
    curve"), or, where the rule ranks J_SF (``needs_jsf``), no member's J_SF was computed (NaN: the set was
    evaluated without static points, and no band or fallback can help)."""
    K = len(pareto)
    if K and len(pareto.failures) == K:
        first = min(pareto.failures)
        raise InfeasibleError(f"{what}: every member of the Pareto set ({K} members, method {pareto.method!r}) "
                              f"failed, so there is no model to choose (member {first}: {pareto.failures[first]})")
    ok = np.ones(K, bool)
    ok[list(pareto.failures)] = False
    if needs_jsf and ok.any() and np.all(np.isnan(pareto.JSF[ok])):
        raise ValueError(f"{what}: no member of the Pareto set ({K} members, method {pareto.method!r}) has a J_SF (NaN: "
                         "the set was evaluated without static points); evaluate it at static points "
                         "(ParetoSet.from_thetas(..., static=points))")
    if needs_jsf:  # the rules that rank J_SF rank (or break its ties by) J_S: a member not computed is not skipped
        _check_in_float_range(pareto, what, ok)
        for nm, v in (("J_S", pareto.JS), ("J_SF", pareto.JSF)):
            nan = np.flatnonzero(np.isnan(v) & ok)
            if nan.size:
                raise ValueError(f"{what}: member{'s' if nan.size > 1 else ''} {', '.join(map(str, nan[:5]))}"
                                 f"{' …' if nan.size > 5 else ''} of the Pareto set ({K} members, method "
                                 f"{pareto.method!r}) {'have' if nan.size > 1 else 'has'} {nm} NaN (not computed), "
                                 "which no rule can rank: evaluate every member (ParetoSet.from_thetas) or drop it")


def _check_in_float_range(pareto: ParetoSet, what: str, ok: np.ndarray) -> None:
    """``ValueError`` naming ``what`` when the set's output (its fitting records') is so large or small that a J of 0
    or inf may be a mean square beyond the float range (output units²), not a perfect or a diverged member: at
    y × 2^±700 every J read so, and a rule chose among them without a word.

    Only a J that is an artefact, and would be read, is refused: below the range a J can only underflow (to 0), above
    it only overflow (to inf). A J_S is run again on the fitting records times a power of two (a free run that
    diverges there, or meets them exactly, is no artefact: at y × 2^±505 such a member refused the set); a J_SF
    (the set keeps no static points) where its reading is lost: two or more members at 0 (their order) or every
    member at inf."""
    recs = [r for r in pareto.fitted_on if isinstance(r, Record)]
    e = binary_exponent(max((float(np.max(np.abs(r.y), initial=0.0)) for r in recs), default=0.0))
    if abs(2 * e) < 1000:  # y² and its mean squares stay well inside the float range (2^±1022)
        return
    edge = 0.0 if e < 0 else np.inf  # what a J beyond the range reads here
    off = np.flatnonzero(ok & (pareto.JS == edge))
    if off.size and len(recs) == len(pareto.fitted_on):  # the records at hand (not a file's prints): run J_S again
        scaled, exps = binary_scaled(recs, pareto.structure)
        th = pareto.thetas[off]
        js = members_js(pareto.structure, scaled_theta(th, pareto.structure, exps) if exps else th, scaled,
                        one_step=False)["JS"]
        off = off[js != edge]
    jsf = np.flatnonzero(ok & (pareto.JSF == edge))
    if jsf.size < (2 if e < 0 else max(int(ok.sum()), 1)):
        jsf = jsf[:0]
    for nm, v, bad in (("J_S", pareto.JS, off), ("J_SF", pareto.JSF, jsf)):
        if bad.size:
            i = int(bad[0])
            raise ValueError(f"{what}: member {i}'s {nm} is {v[i]:g} on an output whose samples reach 2^{e}: its "
                             f"mean squares (output units², about 2^{2 * e} times a relative error's square) are "
                             "beyond the float range in these units, so 0 or inf says nothing of the member; express "
                             "the output in other units (a power of ten or two nearer 1) and fit again")


def min_jsf_index(pareto: ParetoSet, what: str = "min J_SF", js: np.ndarray | None = None,
                  on: str = "", band: tuple[float, float] | None = None) -> int:
    """The member with the smallest J_SF or, given ``band`` = (low, high), the member whose J_SF is nearest
    B = [low, high] (its distance to the interval; for low = 0 that is the smallest J_SF again), ties: the smaller
    J_S, then the lower index; ``InfeasibleError`` naming ``what`` when every member's static curve is undefined.
    ``js``: J_S on choosing records (``on`` names them), whose free runs must then stay finite there too."""
    check_choosable(pareto, what)
    jsf = pareto.JSF
    js = pareto.JS if js is None else js
    ok = np.flatnonzero(np.isfinite(jsf))
    if ok.size == 0:
        raise InfeasibleError(f"{what}: every member has an undefined static curve (J_SF = inf)")
    if on:
        ok = ok[np.isfinite(js[ok])]
        if ok.size == 0:
            raise InfeasibleError(f"{what}: every member with a static curve diverges on {on} (free run)")
    j = jsf[ok]
    if band is None or band[0] <= 0:  # J_SF >= 0: nearest [0, high] is smallest, with J_SF's own ties
        return int(ok[np.lexsort((ok, js[ok], j))[0]])
    low, high = band
    # the distance to B first; among members as far (round-off), the nearer J_SF on its own side
    return int(ok[np.lexsort((ok, js[ok], np.where(j < low, -j, j), band_distance(j, low, high)))[0]])


def band_distance(jsf: np.ndarray, low: float, high: float) -> np.ndarray:
    """How far each J_SF lies from B = [low, high] (0 inside it), output units²."""
    return np.maximum(np.maximum(low - jsf, jsf - high), 0.0)


def nearest_jsf(jsf: np.ndarray, low: float, high: float) -> float | None:
    """The finite J_SF nearest B = [low, high] (the smallest when low = 0), None when there is none."""
    finite = jsf[np.isfinite(jsf)]
    if not finite.size:
        return None
    return float(finite[np.lexsort((finite, band_distance(finite, low, high)))[0]])


#: What :func:`decide_dsf` may do when no member lies in the band, if the user says so.
FALLBACKS = ("min_jsf",)


def choosing_js(pareto: ParetoSet, records: Record | Sequence[Record]) -> np.ndarray:
    """J_S of every member on choosing record(s) (sample-weighted mean; inf where a run diverges), shape (K,)."""
    recs = choosing_records(records)
    for r in recs:
        pareto.check_record(r)
    # the records the set was fitted on, when it keeps them: one of several, a copy or a slice of one is refused by
    # its samples (the J_S check below sees only the set's mean over all of them)
    advice = "choose on data the fit did not see (e.g. data.valid)"
    for c in recs:
        for f in pareto.fitted_on:
            if isinstance(f, RecordPrint):  # a set read from a file: its records' prints
                check_print_overlap(c, f, "choosing", "fitting", advice, prefix="choose_on: ")
                continue
            if same_record(c, f):
                raise ValueError(f"choose_on: the choosing record {c.name!r} is a fitting record ({f.name!r}): {advice}")
            check_overlap(c, f, "choosing", "fitting", advice, prefix="choose_on: ")
    th = np.where(np.isfinite(pareto.thetas), pareto.thetas, 0.0)
    require_lengths(recs, pareto.structure.max_lag, prefix="choose_on: ", what="choosing")
    out = members_js(pareto.structure, th, recs, one_step=False)["JS"]
    out[list(pareto.failures)] = np.inf
    out = np.where(np.isfinite(out), out, np.inf)
    # the set's own J_S is on the records it was fitted on: where every member scores the choosing records as that
    # (to round-off, J_S above none), they are those records, and the choice would be the plain D_SF said to be
    # honest. Records the fit did not see give every member the same J_S by no chance.
    both = np.isfinite(out) & np.isfinite(pareto.JS) & (pareto.JS > 0)
    if both.any() and np.allclose(out[both], pareto.JS[both], rtol=1e-6, atol=0.0):
        raise ValueError(f"choose_on: every member's J_S on {', '.join(repr(r.name) for r in recs)} is the set's own "
                         "J_S, on the records it was fitted on: choose on data the fit did not see (e.g. data.valid)")
    return out


def decide_dsf(
    pareto: ParetoSet,
    *,
    band: float | tuple[float, float] | None = None,
    fallback: str | None = None,
    choose_on: Record | Sequence[Record] | None = None,
) -> Decision:
    """Eq. (14): argmin J_S subject to J_SF ∈ B.

    Parameters
    ----------
    pareto : ParetoSet
        Members with J_S and J_SF (output units²).
    band : float or (float, float)
        B = [0, band] with band > 0, or (low, high) with 0 <= low < high, in the output's units²
        (J_SF's units). Required: a Pareto set does not know its data's uncertainty; with static
        points that carry one, pass ``band=data.static.band`` (the mean of δ_i²).
    fallback : {None, "min_jsf"}
        When no member has J_SF in B (with a finite J_S): None (default) raises
        ``InfeasibleError`` (a ``ValueError``) naming the smallest J_SF reached (with low > 0: the
        J_SF nearest B);
        ``"min_jsf"`` picks the member whose J_SF is nearest B (its distance to the interval:
        for B = [0, band], the smallest J_SF; for (low, high) with every J_SF below low, the
        largest), ties: smaller J_S, instead; with ``choose_on``, among the members whose free run
        stays finite there, ties by J_S there. The choice must be explicit because the result then
        is *not* a D_SF decision; its rule is ``"min J_SF"`` whatever the band, its model's name
        says ``"min J_SF (no member in B)"``, or ``"J_SF nearest B (no member in B)"`` when low > 0.
    choose_on : Record or sequence of Record, optional
        Choosing record(s), not the identification data the set was fitted on: the J_S that is
        minimised over the band is the members' free-run MSE there (``.score``; ``.JS`` stays the
        set's own). None (default): the paper's rule, on the set's J_S. Report the chosen model on
        a third record: its J_S on the choosing record is optimistic. Records on which every member
        scores the set's own J_S (to 1e-6) are the fitting records: ``ValueError``; so is a record with
        the samples of one of its fitting records, or a slice of one: for a set fitted in this session
        (``pe_pareto``, ``se_pareto``, ``from_thetas``) by those records' samples, for one loaded from
        a file by their prints saved with it (files written before prints were kept have none). The samples also
        show the fitting data in other units, from another zero or rounded by a file (y × 1000); prints do not,
        so a set read from a file does not refuse those unless units both name differ (give it its records,
        ``dataclasses.replace(pareto, fitted_on=(data.ident,))``, for the samples' check).

    Returns
    -------
    Decision
        ``.model`` is the chosen member; ties in J_S are broken by the smaller J_SF, then the
        lower index.
    """
    if not isinstance(pareto, ParetoSet):
        raise TypeError(f"pareto must be a ParetoSet (from pe_pareto or se_pareto); got {type(pareto).__name__}")
    lo, hi = resolve_band(band, None, "decide_dsf")
    if len(pareto) == 0:
        raise ValueError("the Pareto set is empty")
    if fallback is not None:
        check_choice(fallback, "fallback", FALLBACKS)
    check_choosable(pareto, "decide_dsf")
    js, jsf = pareto.JS, pareto.JSF
    chosen_on = ""
    if choose_on is not None:
        js = choosing_js(pareto, choose_on)
        chosen_on = ", ".join(r.name for r in ([choose_on] if isinstance(choose_on, Record) else choose_on))
    inside = (jsf >= lo) & (jsf <= hi) & np.isfinite(js)
    if inside.any():
        cand = np.flatnonzero(inside)
        i = int(cand[np.lexsort((cand, jsf[cand], js[cand]))[0]])
        where = f" on {chosen_on}" if chosen_on else ""
        return _decision(pareto, i, "D_SF", True, js[i], f"{pareto.method} D_SF{where}", chosen_on)
    else:
        # the J_SF nearest B (the smallest when B = [0, b]), with the digits that keep it outside B as B is printed
        # (0.03060003, not "0.0306" beside B = [0, 0.0306])
        least = nearest_jsf(jsf, lo, hi)
        which = "smallest J_SF" if lo <= 0 else "J_SF nearest B"
        best = "inf for every member" if least is None else beside(least, hi if least > hi else lo)
        n_in = int(((jsf >= lo) & (jsf <= hi)).sum())
        if fallback is None and n_in:  # in the band, but no free run to score: a wider band would not help
            on = chosen_on or "the identification data"
            raise InfeasibleError(
                f"no member of the Pareto set ({len(pareto)} members, method {pareto.method!r}) has J_SF in "
                f"B = [{bound_text(lo, least)}, {bound_text(hi, least)}] with a finite J_S: the {n_in} member{'s' if n_in > 1 else ''} with J_SF in B "
                f"{'all diverge' if n_in > 1 else 'diverges'} on {on} (free run). Extend the λ sweep, fit with a "
                f"stability margin, or pass fallback='min_jsf' to take the member with the {which}"
            )
        if fallback is None:
            raise InfeasibleError(
                f"no member of the Pareto set ({len(pareto)} members, method {pareto.method!r}) has J_SF in "
                f"B = [{bound_text(lo, least)}, {bound_text(hi, least)}] with a finite J_S; the {which} is {best}. Widen the band, extend "
                f"the λ sweep, or pass fallback='min_jsf' to take the member with the {which}"
            )
        # on choosing records, as D_SF would have chosen: a member whose free run diverges there is none
        i = min_jsf_index(pareto, "fallback 'min_jsf'", js, chosen_on, (lo, hi))
        label = "min J_SF" if lo <= 0 else "J_SF nearest B"
        return _decision(pareto, i, "min J_SF", False, jsf[i], f"{pareto.method} {label} (no member in B)", chosen_on)


def decide_min_correlation(
    pareto: ParetoSet,
    record: Record,
    *,
    output: str = "free-run",
) -> Decision:
    """The minimal-correlation decision maker (Barroso, Takahashi & Aguirre, J. Process Control, 2007).

    As we read that paper: the chosen member is the one whose one-step residuals
    ξ(k) = y(k) − ŷ₁(k) are least correlated with the model's output, ρ = |corr(ξ, ŷ)|, on the
    identification data. With ``output="free-run"`` (default) ŷ is the free-run simulation; with
    ``"one-step"`` it is ŷ₁ itself (then plain least squares, whose residuals are orthogonal to
    its predictions when the structure has a constant term, is always a minimiser: that variant
    is useful only for constrained sets). Members whose free run diverges are never chosen.

    Parameters
    ----------
    pareto : ParetoSet
    record : Record or Dataset
        Identification data (a Dataset's ``ident``), shape (N,) each; counted from sample max_lag on.
    output : {"free-run", "one-step"}

    Returns
    -------
    Decision
        ``.score`` is the chosen member's ρ.
    """
    if not isinstance(pareto, ParetoSet):
        raise TypeError(f"pareto must be a ParetoSet (from pe_pareto or se_pareto); got {type(pareto).__name__}")
    check_choice(output, "output", ("free-run", "one-step"))
    record = as_record(record, "ident", "record")
    pareto.check_record(record)
    if len(pareto) == 0:
        raise ValueError("the Pareto set is empty")
    check_choosable(pareto, "decide_min_correlation", needs_jsf=False)
    st = pareto.structure
    L = st.max_lag
    record.require_length(L)
    if len(record) - L < 3:  # two points are always perfectly correlated (ρ = 1 for every member), one is undefined
        raise ValueError(f"record: {len(record) - L} sample(s) after the largest lag {L}; a correlation needs 3 "
                         "or more")
    # ρ has no units: on the signals times powers of two (exact) where a regressor leaves the float range in the
    # data's own (y(k-1)² at y × 2^512 refused a set whose J's are floats)
    (scaled,), exps = binary_scaled([record], st)
    thetas = scaled_theta(pareto.thetas, st, exps) if exps else pareto.thetas
    y = scaled.y[L:]
    psi = regressor_matrix(st, scaled.u, scaled.y, start=L, input_names=scaled.input_names)
    K = len(pareto)
    rho = np.empty(K)
    diverged = np.zeros(K, bool)
    # members in blocks of at most ~2^22 samples of output: bounded memory on long records
    step = max(1, (1 << 22) // max(1, y.size))
    for k0 in range(0, K, step):
        th = thetas[k0 : k0 + step]
        Y1 = psi @ th.T  # (N-L, block)
        xi = y[:, None] - Y1
        Yo = Y1 if output == "one-step" else np.asarray(simulate_many(st, th, scaled)).T[L:]
        with np.errstate(all="ignore"):
            xc = xi - xi.mean(axis=0)
            oc = Yo - Yo.mean(axis=0)
            # ρ has no units: each column over the power of two above its largest |entry| (exact), where the product
            # of the sums of squares (output units⁴) left the float range at y × 2^±260 (ρ read 0, or undefined)
            xc = np.ldexp(xc, -binary_exponent(np.max(np.abs(xc), axis=0, initial=0.0)))
            oc = np.ldexp(oc, -binary_exponent(np.max(np.abs(oc), axis=0, initial=0.0)))
            r = np.abs(np.sum(xc * oc, axis=0)) / np.sqrt(np.sum(xc**2, axis=0) * np.sum(oc**2, axis=0))
        diverged[k0 : k0 + step] = ~np.all(np.isfinite(Yo), axis=0)
        rho[k0 : k0 + step] = np.where(np.isfinite(r) & ~diverged[k0 : k0 + step], r, np.inf)
    if not np.isfinite(rho).any():
        if diverged.all():
            raise ValueError("no member has a defined residual/output correlation: every member's free run diverged "
                             "on this record")
        # finite runs but no correlation: the output or the residuals do not vary over the record
        gone = f" ({int(diverged.sum())} of {K} members' free runs diverged)" if diverged.any() else ""
        raise ValueError(f"no member has a defined residual/output correlation on this record{gone}: the members' "
                         f"{output} output or one-step residuals are constant over it, as on a record that does not "
                         "move (held at a steady state; its output's spread is "
                         f"{float(np.ptp(record.y[L:])):.3g}); give a "
                         "record whose input moves")
    i = int(np.argmin(rho))
    return _decision(pareto, i, "min correlation", True, rho[i], f"{pareto.method} min-corr (ρ = {rho[i]:.3g})")
