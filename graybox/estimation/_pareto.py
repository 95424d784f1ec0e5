"""Pareto sets as immutable data, and a non-dominated filter.

A :class:`ParetoSet` holds the members of a bi-objective estimate (PE, SE, …) of one
structure: θ, the weight λ1 that produced each, and the errors J_1, J_S and J_SF computed by
the shared evaluator (:func:`graybox.evaluate_thetas`), so every front is judged by the
same definitions as Table I.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from ..models._evaluate import evaluate_thetas
from ..models._coerce import as_structure
from ..models._model import Model, model_input_names
from ..core._records import (Dataset, Record, RecordPrint, StaticPoints, as_records, carried_from, check_fitted_on,
                             check_units)
from ..core._validation import (Relocked, FrozenMap, check_bool, check_fields, check_int, check_mean_square, check_real,
                                check_weight, float_array, frozen, real_array)
from ..core._terms import Structure
from ..selection._centring import centred_data, centred_points

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["ParetoSet", "nondominated_mask", "OBJECTIVES"]

#: Objective names a ParetoSet carries (minimised).
OBJECTIVES = ("J1", "JS", "JSF")
#: The columns of :meth:`ParetoSet.to_frame` that are the set's own: no key of ``extra``.
_OWN_COLUMNS = ("lambda1", *OBJECTIVES, "failure")


def nondominated_mask(points: np.ndarray) -> np.ndarray:
    """Which rows of ``points`` no other row dominates (all objectives minimised).

    Row a dominates row b when a <= b in every objective and a < b in at least one. Equal rows
    do not dominate each other (both are kept). A row with a NaN is never kept; ``inf`` is an
    ordinary (worst) value.

    Parameters
    ----------
    points : array_like, shape (K, m)

    Returns
    -------
    ndarray of bool, shape (K,)
    """
    P = real_array(points, "points", "objective values (numbers, members × objectives)")  # None is no NaN here
    if P.ndim != 2:
        raise ValueError(f"points must be 2-D (members × objectives), got shape {P.shape}")
    if P.shape[1] == 0:  # was numpy's lexsort TypeError ("need sequence of keys"), naming nothing
        raise ValueError(f"points must hold at least one objective (a column), got shape {P.shape}")
    keep = ~np.isnan(P).any(axis=1)
    # Visit in lexicographic order so strong members knock out many others early; a dominated
    # member is skipped safely because whatever it dominates its dominator dominates too.
    order = np.lexsort(P.T[::-1])
    for i in order:
        if not keep[i]:
            continue
        le = np.all(P[i] <= P, axis=1)
        lt = np.any(P[i] < P, axis=1)
        keep &= ~(le & lt)
    return keep


def members_js(structure: Structure, thetas: np.ndarray, records: Sequence[Record], static: StaticPoints | None = None,
               *, one_step: bool = True, threads: int = 1) -> dict[str, np.ndarray]:
    """J_1 (with ``one_step``) and J_S, the sample-weighted means over ``records`` (each from its own max-lag on), and
    J_SF at ``static`` (NaN without), of each row of ``thetas``, output units², shape (P,) each.

    Each record's J's are :func:`~graybox.models._evaluate.evaluate_thetas`' (on the signals times powers of two near
    the float range's ends) and each is weighted by its share of the samples: at y × 2^512 the samples times J_S
    (about 2^1018) overflowed, and every member read diverged. inf or 0 where a J itself is beyond the float range,
    as y² there (the decision rules refuse them)."""
    L = structure.max_lag
    P = np.atleast_2d(thetas).shape[0]
    total = sum(len(r) - L for r in records)
    names = ("J1", "JS") if one_step else ("JS",)
    out = {nm: np.zeros(P) for nm in names}
    for r in records:
        ev = evaluate_thetas(structure, thetas, r, None, one_step=one_step, threads=threads)
        share = (len(r) - L) / total
        with np.errstate(invalid="ignore"):
            for nm in names:
                out[nm] += share * ev[nm]
    out["JSF"] = np.full(P, np.nan) if static is None else evaluate_thetas(structure, thetas, None, static)["JSF"]
    return out


def _failures(method: object, extra: object, failures: object, K: int) -> dict[int, str]:
    """The failed members as {index: reason}, after checking the set's descriptive fields' types."""
    if not isinstance(method, str):
        raise TypeError(f"method must be a description (str), got {method!r} ({type(method).__name__})")
    for nm, v in (("extra", extra), ("failures", failures)):
        if v is not None and not isinstance(v, Mapping):
            raise TypeError(f"{nm} must be a mapping, got {v!r} ({type(v).__name__})")
    fails = {}
    for k, why in dict(failures or {}).items():
        if not (isinstance(k, (int, np.integer)) and not isinstance(k, bool) and 0 <= k < K):
            raise ValueError(f"failures: member index {k!r} out of range for a set of {K}")
        fails[int(k)] = str(why)
    return fails


@dataclass(frozen=True, eq=False)
class ParetoSet(Relocked):
    """Members of a bi-objective estimate of one structure.

    Attributes
    ----------
    structure : Structure
    thetas : ndarray, shape (K, n_terms)
        Parameters, engineering units.
    lambdas : ndarray, shape (K,)
        λ1 of each member, in (0, 1] (λ2 = 1 − λ1); NaN when a member came from no weight. The estimators
        (:func:`~graybox.pe_pareto`, :func:`~graybox.se_pareto`) keep the caller's order of their
        ``lambdas``, whatever order their sweeps run in.
    J1, JS, JSF : ndarray, shape (K,)
        One-step-ahead MSE and free-run MSE on the identification data, static-function MSE at
        the static points (output units²; inf where a free run diverges or the static curve is
        undefined).
    method : str
        How the set was produced (e.g. ``"PE (clarabel, mse)"``).
    extra : mapping str -> ndarray, shape (K,)
        Further per-member values (e.g. ``"JSF_QR"``, the affine static error PE trades), by names other than
        the set's own columns ``"lambda1"``, ``"J1"``, ``"JS"``, ``"JSF"`` and ``"failure"``.
    failures : mapping int -> str
        Members whose estimate failed (e.g. no start of an SE fit was feasible at that λ), with
        the reason in words. Such a member stays in the set so that a sweep reports every λ: its
        θ row is NaN and its J's are inf; :meth:`member_model` refuses it, naming the reason.
    input_names : tuple of str, optional
        The members' inputs, in the column order of an input array (default: as
        :class:`~graybox.Model`'s; :meth:`from_thetas` takes the records').
    Ts : float, optional
        The sampling period (s) of the records the set was fitted on (:meth:`from_thetas` takes the
        records'); its members' models carry it, and choosing records at another period are
        refused. None: unknown.
    units : tuple, optional
        The units of the input(s) and the output of those records (the input's one str, or one per input;
        :meth:`from_thetas` takes the records'); its members' models carry them, and choosing records in other
        units are refused. Empty: unknown.
    fitted_on : tuple of Record or RecordPrint, optional
        The records the set was fitted on (:meth:`from_thetas` and the estimators keep them), or, for a set read
        from a file, their prints (names, lengths and hashes of blocks of samples, which :mod:`graybox.io` saves in
        their stead): :func:`graybox.decide_dsf` refuses them, a copy or a slice of one as choosing records.
        Prints compare the samples' bits: they see a copy or a slice sample for sample, not the same samples in
        other units or from another zero (y × 1000, °C as K) or rounded by a file (6 digits), which records refuse;
        :meth:`check_record` refuses other units where the set and the choosing record both name them. To run the
        records' check on a set read from a file, give it the records again where they are at hand:
        ``dataclasses.replace(pareto, fitted_on=(data.ident,))``.
        A field, so that ``dataclasses.replace``, copies, pickles and files keep it; not shown in the repr.
        Empty (default): unknown, that check left to the set's own J_S.
    """

    structure: Structure
    thetas: np.ndarray
    lambdas: np.ndarray
    J1: np.ndarray
    JS: np.ndarray
    JSF: np.ndarray
    method: str = ""
    extra: Mapping[str, np.ndarray] = field(default_factory=dict)
    failures: Mapping[int, str] = field(default_factory=dict)
    input_names: tuple[str, ...] | None = None
    Ts: float | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")
    fitted_on: tuple[Record | RecordPrint, ...] = ()

    def __post_init__(self) -> None:
        check_fields(self)
        bad = [r for r in self.fitted_on if not isinstance(r, (Record, RecordPrint))]
        if bad:
            raise TypeError("ParetoSet: fitted_on must hold the Records the set was fitted on (or their prints), got "
                            f"a {type(bad[0]).__name__}")
        if self.Ts is not None:
            object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        # checked and defaulted as a Model's (the members' models carry them)
        names = model_input_names(self.structure, self.input_names)
        object.__setattr__(self, "input_names", names)
        object.__setattr__(self, "units", check_units(self.units, "ParetoSet", len(names)))
        th = frozen(self.thetas)
        if th.shape == (0, 0):  # no member (a JSON file gives back [] for none)
            th = frozen(np.zeros((0, len(self.structure))))
        if th.ndim != 2 or th.shape[1] != len(self.structure):
            raise ValueError(f"thetas must have shape (K, {len(self.structure)}), got {th.shape}")
        K = th.shape[0]
        fails = _failures(self.method, self.extra, self.failures, K)
        ok = np.ones(K, bool)
        ok[list(fails)] = False
        if not np.all(np.isfinite(th[ok])):
            raise ValueError("thetas must be finite (a failed member is listed in failures)")
        object.__setattr__(self, "failures", FrozenMap(fails))
        object.__setattr__(self, "thetas", th)
        for nm in ("lambdas", "J1", "JS", "JSF"):
            v = frozen(getattr(self, nm))
            if v.shape != (K,):
                raise ValueError(f"{nm} must have shape ({K},), got {v.shape}")
            # what no estimate gives (a file edited by hand, a set built wrong) is refused, not ranked by D_SF
            if nm == "lambdas":
                check_weight(v, "ParetoSet: lambdas")
            else:
                check_mean_square(v, f"ParetoSet: {nm}")
            if nm != "lambdas" and fails:
                v = np.array(v)
                v[~ok] = np.inf
                v = frozen(v)
            object.__setattr__(self, nm, v)
        ex = {}
        for k, v in dict(self.extra).items():
            if not isinstance(k, str):  # a file writes the name as text: 1 would read back as '1'
                raise TypeError(f"extra: a per-member value is named by a str, got {k!r} ({type(k).__name__})")
            if k in _OWN_COLUMNS:  # to_frame wrote it over the set's own column, objective() never gave it
                raise ValueError(f"extra: {k!r} names a value the set holds itself ({', '.join(_OWN_COLUMNS)}); "
                                 "give it another name")
            a = frozen(v)
            if a.shape != (K,):
                raise ValueError(f"extra[{k!r}] must have shape ({K},), got {a.shape}")
            ex[k] = a
        object.__setattr__(self, "extra", FrozenMap(ex))

    # -- construction -------------------------------------------------------------------
    @classmethod
    def from_thetas(
        cls,
        structure: Structure,
        thetas: np.ndarray,
        lambdas: np.ndarray | None,
        data: Record | Sequence[Record] | Dataset,
        static: StaticPoints | None,
        method: str = "",
        extra: Mapping[str, np.ndarray] | None = None,
        threads: int = 1,
        failures: Mapping[int, str] | None = None,
        centred: tuple[np.ndarray, Mapping[str, float]] | None = None,
    ) -> "ParetoSet":
        """Evaluate θs with :func:`graybox.evaluate_thetas` and build the set.

        Parameters
        ----------
        structure : Structure, sequence of str, Model, or a result that carries one
            The members' process terms.
        thetas : ndarray, shape (P, n_terms)
            One member per row, engineering units.
        lambdas : ndarray, shape (P,), or None
            Their λ1 (None: NaN).
        data : Record, sequence of Record, or Dataset
            J_1 and J_S are computed on it (output units²); with several records they are the sample-weighted
            means over the records (each counted from its own max-lag on).
        static : StaticPoints or None
            J_SF is computed at them (output units²); None leaves J_SF as NaN.
        method : str, optional
            Labels the set.
        extra : mapping of str to ndarray of shape (P,), optional
            Per-member arrays (e.g. ``"radius"``).
        threads : int, optional
            Threads that run the free runs (default 1).
        failures : mapping of int to str, optional
            Rows (index -> reason) kept as failed members (θ NaN, J's inf).
        centred : (ndarray of shape (P, n_terms), mapping of str to float), optional
            (θ_c, offsets), the members as a fit on the signals less ``offsets`` holds them (a structure closed
            under shifts), whose J's are computed there, on the records and points less the offsets (the same
            J's, without the offsets' powers that ``thetas`` carry); the offsets name y and every input, each in
            its signal's units.

        Returns
        -------
        ParetoSet
            P members, in the order of ``thetas``.
        """
        structure = as_structure(structure)
        th = np.atleast_2d(np.asarray(thetas, float)).copy()
        K = th.shape[0]
        fails = _failures(method, extra, failures, K)
        bad = np.zeros(K, bool)
        bad[list(fails)] = True
        th[bad] = 0.0  # evaluated as a harmless null model, then reported as failed
        recs = as_records(data)
        run, run_recs, run_static = th, recs, static
        if centred is not None:
            if not (isinstance(centred, tuple) and len(centred) == 2 and isinstance(centred[1], Mapping)):
                raise TypeError("centred must be a pair (the members' centred parameters, shape of thetas; the "
                                f"offsets, a map of y and each input to its level), got {centred!r}")
            run = np.atleast_2d(float_array(centred[0], "centred parameters")).copy()
            if run.shape != th.shape:
                raise ValueError(f"centred parameters must have the shape of thetas, {th.shape}, got {run.shape}")
            run[bad] = 0.0
            missing = sorted({"y", *recs[0].input_names} - set(centred[1]))
            if missing:
                raise ValueError(f"centred offsets must name y and every input of the records; missing {missing}")
            run_recs = centred_data(recs, centred[1], keep=frozenset(centred[1]))  # each signal less its offset
            run_static = None if static is None else centred_points(static, centred[1])
        j = members_js(structure, run, run_recs, run_static, threads=threads)
        lam = np.full(K, np.nan) if lambdas is None else np.asarray(lambdas, float)
        th[bad] = np.nan
        return cls(structure, th, lam, j["J1"], j["JS"], j["JSF"], method, extra or {}, fails,
                   **carried_from(recs, static), fitted_on=tuple(recs))

    def check_record(self, record: Record) -> None:
        """``ValueError`` when ``record`` (or static points) was sampled at another period than the set was fitted
        at, or is in other units where both name them (as :meth:`graybox.Model.check_record`).

        Parameters
        ----------
        record : Record or StaticPoints
            Its ``Ts`` (s) and units are compared with the set's.
        """
        check_fitted_on(self.Ts, self.units, "the Pareto set was fitted", record,
                        "its members' parameters hold in those units only; convert the data", self.input_names)

    # -- access -------------------------------------------------------------------------
    def __len__(self) -> int:
        return int(self.thetas.shape[0])

    def objective(self, name: str) -> np.ndarray:
        """One objective by name.

        Parameters
        ----------
        name : str
            ``"J1"``, ``"JS"``, ``"JSF"`` or a key of ``extra`` (another is refused: ``ValueError``).

        Returns
        -------
        ndarray, shape (K,)
            One value per member (J's in output units²; inf for a failed member).
        """
        if name in OBJECTIVES:
            return getattr(self, name)
        if name in self.extra:
            return self.extra[name]
        raise ValueError(f"unknown objective {name!r}; this set has {list(OBJECTIVES) + list(self.extra)}")

    def member_model(self, i: int, name: str | None = None) -> Model:
        """Member ``i`` as a :class:`~graybox.Model`.

        A set holds many models, so it has no ``.model`` of its own (that name is, on every other
        result, the one model it carries): pick a member here, or one by a rule with
        :func:`graybox.decide_dsf`.

        Parameters
        ----------
        i : int
            Member index, -K <= i < K (negative from the end); a failed member is refused (``ValueError``).
        name : str, optional
            The model's label (default: the method and λ1, or the method and ``#i`` without λ1).

        Returns
        -------
        Model
            With the set's inputs, ``Ts`` and units.
        """
        K = len(self)
        i = check_int(i, "i")
        if not -K <= i < K:
            raise ValueError(f"member index {i} out of range for a set of {K}")
        i %= K
        if i in self.failures:
            raise ValueError(f"member {i} of this set failed: {self.failures[i]}")
        lam = self.lambdas[i]
        label = name or (f"{self.method} λ1={lam:.3g}" if np.isfinite(lam) else f"{self.method} #{i}")
        return Model(self.structure, self.thetas[i], name=label, input_names=self.input_names, Ts=self.Ts,
                     units=self.units)

    def models(self) -> list[Model]:
        """Every member that did not fail, as a Model, in order.

        Returns
        -------
        list of Model
            As :meth:`member_model` gives each.
        """
        return [self.member_model(i) for i in range(len(self)) if i not in self.failures]

    def subset(self, index: np.ndarray | Sequence[int]) -> "ParetoSet":
        """The members at ``index``, in that order.

        Parameters
        ----------
        index : ndarray or sequence of int, or boolean mask of shape (K,)
            Member indices (negative from the end), or a mask over the members.

        Returns
        -------
        ParetoSet
            Those members, failed ones kept with their reasons.
        """
        idx, K = np.asarray(index), len(self)
        if idx.dtype == bool:
            if idx.shape != (K,):
                raise ValueError(f"mask must have shape ({K},), got {idx.shape}")
            idx = np.flatnonzero(idx)
        if idx.ndim != 1 or (idx.size and idx.dtype.kind not in "iu"):
            raise TypeError(f"index must be a boolean mask or a sequence of integer member indices, got {index!r}")
        idx = idx.astype(int)
        bad = idx[(idx < -K) | (idx >= K)]
        if bad.size:
            raise ValueError(f"member index {bad[0]} out of range for a set of {K}")
        idx = idx % max(K, 1)  # a failed member named from the end, or twice, keeps its failure
        fails = {new: self.failures[old] for new, old in enumerate(idx.tolist()) if old in self.failures}
        return ParetoSet(self.structure, self.thetas[idx], self.lambdas[idx], self.J1[idx], self.JS[idx],
                         self.JSF[idx], self.method, {k: v[idx] for k, v in self.extra.items()}, fails,
                         self.input_names, self.Ts, self.units, self.fitted_on)

    def nondominated(self, objectives: Sequence[str] = ("JS", "JSF")) -> "ParetoSet":
        """The members that no other member dominates in ``objectives`` (order kept).

        A member with a NaN objective is not kept; an objective that no member has (J_SF of a set evaluated
        without static points) is refused with ``ValueError``, not answered with an empty set.

        Parameters
        ----------
        objectives : sequence of str, optional
            Names as :meth:`objective` takes them, at least one (default ``("JS", "JSF")``), each minimised.

        Returns
        -------
        ParetoSet
            The nondominated members that did not fail.
        """
        if isinstance(objectives, str) or not hasattr(objectives, "__len__"):
            raise TypeError(f"objectives must be a sequence of objective names, got {objectives!r}")
        if len(objectives) < 1:
            raise ValueError("objectives: give at least one objective")
        try:
            pts = np.column_stack([self.objective(o) for o in objectives])
        except ValueError as exc:
            raise ValueError(f"objectives: {exc}") from None
        ok = np.ones(len(self), bool)
        ok[list(self.failures)] = False
        unknown = [o for o, col in zip(objectives, pts.T) if ok.any() and np.isnan(col[ok]).all()]
        if unknown:  # every member would be dropped (a row with a NaN is never kept): an empty front, said nowhere
            raise ValueError(f"objectives: no member of the set has a {unknown[0]} (NaN"
                             + (": the set was evaluated without static points); evaluate it at static points "
                                "(ParetoSet.from_thetas(..., static=points)) or" if unknown[0] == "JSF" else ");")
                             + f" filter by other objectives (this set has {list(OBJECTIVES) + list(self.extra)})")
        keep = nondominated_mask(pts)
        keep[~ok] = False
        return self.subset(keep)

    def to_frame(self, params: bool = False) -> pd.DataFrame:
        """The set as a table.

        Parameters
        ----------
        params : bool, optional
            Also one column per term with the members' θ, engineering units (default False).

        Returns
        -------
        pandas.DataFrame
            One row per member (index ``member``): ``lambda1``, ``J1``, ``JS``, ``JSF`` (output units²), the
            extras, ``failure`` (the reason, ``""`` for a member that did not fail), and θ by term if ``params``.
        """
        import pandas as pd

        params = check_bool(params, "params")
        cols = {"lambda1": self.lambdas, "J1": self.J1, "JS": self.JS, "JSF": self.JSF}
        cols.update(self.extra)
        cols["failure"] = [self.failures.get(i, "") for i in range(len(self))]
        df = pd.DataFrame(cols)
        if params:
            df = pd.concat([df, pd.DataFrame(self.thetas, columns=[str(t) for t in self.structure])], axis=1)
        df.index.name = "member"
        return df

    def __repr__(self) -> str:
        failed = f", failed={len(self.failures)}" if self.failures else ""
        return f"ParetoSet(method={self.method!r}, members={len(self)}{failed}, n_terms={len(self.structure)})"
