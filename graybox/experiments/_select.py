"""Structure selection that says how its choice will do on data nothing was chosen on.

:func:`select_graybox` makes a family of candidate structures, fits each with one or more
estimators, scores every member on data the fit never saw, and chooses by a rule that accounts
for the spread of that score. Its phases (one function each below):

1. **inputs** (:func:`_inputs`) — the records and their jobs: *fit* on the identification record,
   *choose* on the validation record (cut into contiguous blocks) or, with one record only, on k
   contiguous folds of it (searching and refitting per fold), and *report* on an optional test record that no
   step of the choice reads;
2. **structures** (:func:`_structures`) — for each size, the best structure of that size on the
   SEMP path (:func:`graybox.semp`) and the FROLS structure of that size (and, with ``sources``,
   the best subset of that size by a swap or exact search), completed (gray box) with the
   simplest terms the static curve's form needs (:func:`static_terms`);
3. **scoring** (:func:`_score_job`, one job per structure × estimator, in the driver or on the
   experiment layer's executors) — every member's free-run J_S on each block, its J_SF, and its
   J_S on the test record;
4. **choice** (:func:`_choose`) — per row the member chosen by D_SF on the choosing data (the
   smallest J_S among the members with J_SF ≤ B; a black box has one member), then the row: with
   ``rule="one-se"`` the fewest parameters among the rows whose log ratio of J_S to the best row's
   is within one standard error of zero (the error of that ratio over the blocks, paired); with
   ``rule="min"`` the smallest J_S;
5. **refit** — the chosen row's member fitted on all the identification data.

The winner of many candidates scored on one short record is optimistic on that record (the
winner's curse); the blocks measure how much of its lead is noise, and the rule gives the lead
to the simpler structure when it is. The test columns measure what the choice is worth.

Without a band (none given and none carried by the static points' uncertainty, or ``band=inf``)
the same search picks a black box: LS, ELS and output-error fits, chosen by J_S alone.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from .. import _api as gb

from ..io._json import register_type
from ..estimation._prediction_error import pe_members
from ..models._coerce import static_info, static_points
from ..selection import _centring
from ..selection._simulation_error_pruning import free_run_floor
from ..selection._stopping import FewerTermsError
from ..static._form_check import carried_degree, static_degree, static_fit_mse, varied_inputs, static_terms
from ..core._simulation_kernels import encode, record_inputs, simulate_batch
from ..core._least_squares import one_blas_thread
from ..core._progress import progress_bar, show_progress
from ..core._records import (as_records, carried_from, check_alike, check_compatible, choosing_records, check_overlap,
                             same_record, warn_static_range)
from ..core._terms import require_inputs
from ..core._reprs import beside, bound_text, listed, squared_text, squared_unit
from ..core._validation import FrozenFrame, check_bool, check_choice, check_fields, check_frame_columns, check_int, check_lambdas, check_real, check_sequence, warn, check_workers
from ._cell import cell_constraints, warning_texts
from ._executors import check_cluster
from ._map import parallel_map
from ._select_checkpoint import SelectionCheckpoint, checkpoint_of, plan_digest, row_key, test_digest
from ._spec import build_constraint, constraint_entries, constraint_from_object

__all__ = ["select_graybox", "GrayboxSelection", "SelectionWarning", "GRAY_BOX_ESTIMATORS", "BLACK_BOX_ESTIMATORS"]


class SelectionWarning(UserWarning):
    """select_graybox took an explicit fallback (fewer blocks, sizes a search did not reach, a
    lower static degree than the points ask for, the smallest J_SF when no structure meets the
    band), some rows' fits warned (their text is in the table's ``warnings``), or some rows' fits
    failed on these data (e.g. terms collinear on a fold: those rows are left out of the choice,
    their ``reason`` says why); the message says which."""


#: Estimators that trade J_S against J_SF along λ1 (a front per structure).
GRAY_BOX_ESTIMATORS = ("pe", "se-gradient", "se-ga")
#: Estimators of one model per structure, chosen by J_S alone: least squares, extended least
#: squares and output error (simulation error, no static points; :func:`graybox.output_error`).
BLACK_BOX_ESTIMATORS = ("ls", "els", "oe")
RULES = ("one-se", "min")
#: Where the structures of each size come from: the SEMP path, the FROLS (greedy) path, and the best
#: subsets of each size found by exchanging terms (``frols(search="swap")``) or by branch and bound
#: (``search="exact"``, proven or best found within its node budget).
SOURCES = ("semp", "frols", "swap", "exact")
#: Estimators whose fits cost seconds per structure: run on the shortlist the others rank best.
SLOW_ESTIMATORS = ("se-gradient", "se-ga", "oe")


def _fit_ls(st: gb.Structure, rec: gb.Record | list[gb.Record]) -> np.ndarray:
    return np.asarray(gb.els(st, rec, noise=0).model.theta, float)


def _fit_els(st: gb.Structure, rec: gb.Record | list[gb.Record]) -> np.ndarray:
    return _process_theta(gb.els(st, rec).model)


def _process_theta(m: gb.Model) -> np.ndarray:
    """θ of the process terms only: a free run sets the noise terms to zero."""
    return np.array([th for t, th in zip(m.structure, m.theta) if not t.is_noise], float)


def _fit_oe(st: gb.Structure, rec: gb.Record | list[gb.Record]) -> np.ndarray:
    # no start gave a fit: a ValueError, which _fit_or_fail makes a failed row with its reason
    return np.asarray(gb.output_error(st, rec, progress=False).model.theta, float)


#: name -> fit(process structure, identification record or records) -> θ of the process terms.
_BLACK_BOX_FITS: dict[str, Callable[[gb.Structure, Any], np.ndarray]] = {"ls": _fit_ls, "els": _fit_els,
                                                                          "oe": _fit_oe}


def _score_ratio(a: float, b: float) -> float:
    """a / b of two mean squares, where b = 0 (a noise-free test record met exactly) gives 1 if a is 0 too (as
    good), else inf."""
    if b == 0.0:
        return 1.0 if a == 0.0 else float("inf")
    return a / b


@dataclass(frozen=True, eq=False)
class GrayboxSelection:
    """The result of :func:`select_graybox`.

    Attributes
    ----------
    structure : Structure
        The chosen structure (static-form terms included).
    model : Model
        Its model, refitted on all the identification data (gray box: the member chosen by D_SF
        on the choosing data), named as :meth:`model_of` names it (``"se-gradient (frols-8)"``). The process part only: an ELS fit's MA part is left out (free runs
        set the noise to zero); for it (residual tests with the noise model, ``ls_uncertainty``)
        refit ``graybox.els(sel.structure, data)``.
    decision : Decision
        How that member was chosen (``JS`` is its J_S on the choosing data).
    table : pandas.DataFrame
        Everything compared, one row per structure and estimator: ``source`` (semp, frols, swap or
        exact; several when they give one structure), ``size`` (terms before the static terms),
        ``n_terms``, ``added`` (static-form terms),
        ``estimator``, ``lambda1`` (of the member chosen, NaN for a black box), ``JS_valid``
        (its J_S on the choosing data: the validation record, or all the folds' held-out samples,
        each fold's by the structure of the row's source and size that the fold's own search found,
        fitted on its fit records, where ``terms`` and ``n_terms`` are those of the search on all the
        identification data; every row's errors counted from the candidates' largest lag on, the
        same samples for all; an error below the record's round-off floor, as :func:`graybox.semp` floors its
        scores, counts as that floor), ``JSF``
        (its static error, worst fold; NaN without static points), ``in_band``, ``vs_best`` and
        ``vs_best_se`` (log of its J_S over the best row's, and that log ratio's standard error over
        the blocks by the delta method, both rows on the same blocks), ``wanders`` (its model, run free over
        an identification or choosing record's input from the output held at the 5th, 50th or 95th percentile of
        those records' outputs, diverges: it stays bounded only near the records' own starts; such rows are not
        eligible, unless every in-band row wanders; nor taken by the fallback, unless every row with a static curve
        wanders), ``eligible`` (the rule could choose it),
        ``rank`` (1: the choice); with a test
        record also ``JS_test`` (its refitted model's J_S there, counted as ``JS_valid`` is: from
        the candidates' largest lag on, the same samples for every row, so it differs from
        ``graybox.js(model, test)``, which counts from the model's own largest lag, when the row's
        structure has shorter lags than the candidates) and ``JSF_test`` (that model's J_SF).
        Nothing in the test columns took part in the choice. ``reason``: why a row has no
        qualifying model (every member failed, with which fit and why, or diverged; the smallest
        J_SF reached when the band is missed); empty when it has one. ``warnings``: what its fits
        warned of (e.g. an ELS iteration that did not converge), each message once; empty when
        nothing. ``failed_members``: the members of the row's front whose fit on the identification
        data (or on a fold) failed, e.g. λ1 = 1 where the records alone do not identify θ, their λ1
        and why; they cannot be chosen; empty when none. The call then says once, with a
        :class:`SelectionWarning`, how many rows warned and whether the chosen one did. ``terms``: the row's structure, its terms joined by
        ``" + "`` (:meth:`structure_of` reads it back); ``theta``: the parameters of its member
        (the model the test columns score), exact decimal text, empty for a row without a model
        (:meth:`model_of` reads it back). On folds also ``fold_terms``: the structure each fold's search
        found and ``JS_valid`` scored on that fold, one terms text per fold in the folds' order, joined by
        ``" | "`` (``"(none)"`` where that fold's search reached none of the row's source, why in parentheses
        where the structure it reached cannot be completed on the fold's records); absent when the
        choice fell back to the structures of all the data.
    degree : int or None
        Degree of the static curve the static information asks for (None for a black box).
    band : float
        B (output units²); inf for a black box (no static constraint).
    in_band : bool
        Whether the chosen structure met the band (the name :class:`Decision` and
        :class:`DSFResult` use); False when none did and ``fallback="min_jsf"`` chose the
        smallest J_SF. Always True for a black box (band inf), whatever its J_SF (the table's
        ``JSF``); its repr then says "black box" instead.
    rule : str
        The rule that chose (``"one-se"`` or ``"min"``; ``"min"`` also when one block only could
        be cut, and when no row meets the band: ``in_band`` False, the smallest J_SF chose).
    """

    structure: gb.Structure
    model: gb.Model
    decision: gb.Decision
    table: pd.DataFrame = FrozenFrame()
    degree: int | None
    band: float
    in_band: bool
    rule: str

    #: Columns every table holds (a loaded file is checked against them).
    TABLE_COLUMNS = ("source", "size", "n_terms", "added", "estimator", "JS_valid", "JSF", "in_band", "rank")
    #: The kind of each column read as numbers or flags, where the table has it.
    COLUMN_KINDS = {"size": "int", "n_terms": "int", "lambda1": "real", "JS_valid": "real", "JSF": "real",
                    "in_band": "bool", "JS_test": "real", "JSF_test": "real", "vs_best": "real", "vs_best_se": "real",
                    "eligible": "bool", "rank": "int", "wanders": "bool"}

    def __post_init__(self) -> None:
        check_fields(self)  # types first: the table is a DataFrame, the band a real number
        missing = [c for c in self.TABLE_COLUMNS if c not in self.table.columns]
        if missing:
            raise ValueError(f"the table lacks the column(s) {missing}")
        # the columns its properties and repr read as numbers and flags (regret, optimism, chosen): text, arrays or
        # bools there (a dataclasses.replace, a hand-edited file) failed later in NumPy or pandas, or read "False" as True
        check_frame_columns(self.table, self.COLUMN_KINDS, "GrayboxSelection")
        first = int((self.table["rank"] == 1).sum())
        if first != 1:  # the row ranked 1 is the choice (chosen, repr)
            raise ValueError(f"the table has {first} rows ranked 1; the choice is one row")
        if list(self.model.structure) != list(self.structure):
            raise ValueError("the model's structure is not the chosen structure")
        # the model is the decision's (select_graybox gives it so): another one, from an edited file, was simulated by
        # .model while .uncertainty took the decision's
        d = self.decision.model
        if list(d.structure) != list(self.model.structure) or not np.array_equal(d.theta, self.model.theta):
            raise ValueError("the model is not the decision's model (select_graybox gives the chosen member's)")
        if not self.band > 0:
            raise ValueError(f"band must be > 0 (inf for a black box), got {self.band!r}")
        check_choice(self.rule, "rule", RULES)
        if self.degree is not None and self.degree < 0:
            raise ValueError(f"degree must be None (a black box) or >= 0, got {self.degree}")
        # the figures are mean squares (NaN: no model; inf: a diverged run): a negative one, which no run gives and a
        # hand-edited file can, made regret and optimism negative
        for c in ("JS_valid", "JSF", "JS_test", "JSF_test"):
            if c in self.table.columns:
                v = pd.to_numeric(self.table[c], errors="coerce").to_numpy(float)
                if np.any(v < 0):
                    raise ValueError(f"the table's {c} must be >= 0 (a mean square; NaN or inf where a row has none), "
                                     f"got {v[v < 0][0]:g} in row {self.table.index[int(np.flatnonzero(v < 0)[0])]!r}")
        said = self.table.loc[self.table["rank"] == 1, "in_band"].iloc[0]
        if bool(said) != bool(self.in_band):  # in_band is the choice's, as its row says
            raise ValueError(f"in_band is {self.in_band} but the chosen row's in_band is {bool(said)}")
        if "terms" in self.table.columns:  # the structure is the choice's too (model_of of its row gave another)
            terms = str(self.table.loc[self.table["rank"] == 1, "terms"].iloc[0])
            if set(gb.parse_structure(terms)) != set(self.structure):
                raise ValueError(f"the chosen row's terms ({terms}) are not the chosen structure ({self.structure})")

    @property
    def chosen(self) -> pd.Series:
        """The table's row of the choice."""
        return self.table[self.table["rank"] == 1].iloc[0]

    def structure_of(self, row: str) -> gb.Structure:
        """The structure of the table's row named ``row`` (e.g. ``"frols-10"``), static terms included.

        Parameters
        ----------
        row : str
            A name in the table's index.

        Returns
        -------
        Structure
        """
        if not isinstance(row, str):
            raise TypeError(f"row must be a row name (str), got {type(row).__name__}")
        if "terms" not in self.table.columns:
            raise ValueError("this table keeps no terms (a selection saved by graybox 0.2.2 or earlier)")
        if row not in self.table.index:
            raise ValueError(f"no row {row!r}; rows: {sorted(set(self.table.index))}")
        return gb.parse_structure(str(self.table.loc[[row], "terms"].iloc[0]))

    def model_of(self, row: str, estimator: str | None = None) -> gb.Model:
        """The model of the table's row named ``row`` (e.g. ``"frols-10"``): its member chosen on the choosing
        data, fitted on all the identification data (the model the row's ``JS_test`` scores).

        Parameters
        ----------
        row : str
            A name in the table's index.
        estimator : str, optional
            Which of the row's estimators (e.g. ``"pe"``, ``"se-gradient"``, ``"ls"``); needed when the
            structure was fitted by more than one.

        Returns
        -------
        Model
            With the chosen model's input names and sampling period.
        """
        structure = self.structure_of(row)
        if "theta" not in self.table.columns:
            raise ValueError("this table keeps no parameters (a selection saved by graybox 0.2.3 or earlier)")
        rows = self.table.loc[[row]]
        ests = list(rows["estimator"])
        if estimator is None and len(ests) > 1:
            raise ValueError(f"row {row!r} was fitted by {ests}: pass estimator= to say which")
        if estimator is not None:
            check_choice(estimator, "estimator", tuple(ests))
            rows = rows[rows["estimator"] == estimator]
        r = rows.iloc[0]
        text = r["theta"]
        if not isinstance(text, str) or not text:  # "" (or NaN, as a CSV reader gives it back)
            raise ValueError(f"row {row!r} ({r['estimator']}) has no model: {r['reason']}")
        try:
            theta = np.array([float(v) for v in text.split()])
        except ValueError:  # a hand-edited table: name the row, not only the bad word
            raise ValueError(f"row {row!r} ({r['estimator']}): its theta {text!r} is not numbers") from None
        return gb.Model(structure, theta, name=f"{r['estimator']} ({row})", input_names=self.model.input_names,
                        Ts=self.model.Ts, units=self.model.units)

    def uncertainty(
        self,
        data: gb.Dataset | gb.Record | Sequence[gb.Record],
        static: gb.StaticPoints | gb.StaticCurve | gb.StaticSurface | None = None,
        *,
        constraints: Any = (),
        static_sigma: float | None = None,
        level: float = 0.95,
    ) -> gb.ParameterUncertainty:
        """The chosen model's parameter covariance, by its estimator's own rule, on the data it was fitted on.

        ``ls``: :func:`graybox.ls_uncertainty`; ``els``: the same of the ELS fit refitted with its MA
        part (the selection keeps the process part, whose covariance needs the MA regressors);
        ``oe``: :func:`graybox.se_uncertainty` at λ1 = 1 (output error's fit is regularised, a ridge
        towards least squares, so it warns that θ is not the plain SE optimum: the covariance is the
        SE objective's curvature at θ); ``pe``: :func:`graybox.pe_uncertainty` of
        the decision (its λ1); ``se-gradient`` / ``se-ga``: :func:`graybox.se_uncertainty` of the
        decision. Give it to :func:`graybox.simulation_band` or :func:`graybox.static_curve_band`.

        Parameters
        ----------
        data : Dataset, Record or sequence of Record
            What :func:`select_graybox` was given (a Dataset's identification record, the record
            alone, or the identification records): the chosen model was fitted on it.
        static : StaticPoints, StaticCurve or StaticSurface, optional
            The static information the selection was given, if not the Dataset's (gray boxes only).
        constraints : optional
            The constraints the selection was given (PE only).
        static_sigma : float, optional
            Standard deviation of the measured ȳ_i, output units (gray boxes only; 0 takes the points
            as exact): as :func:`graybox.pe_uncertainty` and :func:`graybox.se_uncertainty` take it.
            Default: from the member's own static misfit, which a member that meets the points
            exactly does not have (``ValueError`` then: give it).
        level : float
            Confidence level of the intervals, in (0, 1).

        Returns
        -------
        ParameterUncertainty

        Raises
        ------
        ValueError
            ``data`` is not what the chosen model was fitted on (the estimator's own check: not a
            least-squares or ELS solution there; output error's refit there not the chosen θ); constraints with an estimator other than PE.
        """
        est = str(self.chosen["estimator"])
        constraints = tuple(check_sequence(constraint_entries(constraints), "constraints",
                                           "a constraint, a table of them or a sequence"))
        if constraints and est != "pe":
            raise ValueError(f"constraints apply to the PE estimator; the chosen row's is {est!r}")
        if static is not None and est in _BLACK_BOX_FITS:
            raise ValueError(f"static applies to a gray box; the chosen row's estimator is {est!r} (a black box)")
        if static_sigma is not None and est in _BLACK_BOX_FITS:
            raise ValueError(f"static_sigma applies to a gray box; the chosen row's estimator is {est!r} (a black box)")
        if est == "ls":
            return gb.ls_uncertainty(self.model, data, level=level)
        if est == "els":
            fit = gb.els(self.structure, data)
            self._refit_is_chosen(_process_theta(fit.model), "ELS")
            return gb.ls_uncertainty(fit, data, level=level)
        if est == "oe":
            # se_uncertainty's stationarity warning cannot tell other data from output error's own ridge
            # (it may warn on the right data too): the refit can
            with one_blas_thread():  # as the selection's jobs fit it: the same θ to the last bit
                self._refit_is_chosen(_fit_oe(self.structure, _fit_data(tuple(as_records(data, name="data")))),
                                      "output_error")
            return gb.se_uncertainty(self.model, data, lambda1=1.0, level=level)
        if est == "pe":
            return gb.pe_uncertainty(self.decision, data, static, constraints=self._constraint_objects(
                constraints, data, static) or None, static_sigma=static_sigma, level=level)
        return gb.se_uncertainty(self.decision, data, static, static_sigma=static_sigma, level=level)

    def _constraint_objects(self, constraints: tuple, data: object, static: object) -> list:
        """The constraints as objects, tables built as the selection's fits built them (an equality's curve
        fitted to the static points, or the data set's own), objects as they are."""
        if not any(isinstance(c, Mapping) for c in constraints):
            return list(constraints)
        recs = as_records(data, name="data")
        pts = static if isinstance(static, gb.StaticPoints) else None
        if isinstance(static, (gb.StaticCurve, gb.StaticSurface)):
            pts = static_points(static, list(recs), takes_ubar=False)  # sampled as select_graybox samples it
        if static is None and isinstance(data, gb.Dataset):
            pts = data.static
        extra = data.extra if isinstance(data, gb.Dataset) else {}
        specs = _constraint_specs(constraints, recs[0].input_names)
        return cell_constraints(specs, self.structure, gb.Dataset(recs[0], recs[0], pts, extra=extra))

    def _refit_is_chosen(self, theta: np.ndarray, estimator: str) -> None:
        """``ValueError`` unless a refit on the data given is the chosen θ (those data are what it was fitted on)."""
        if not np.allclose(theta, self.model.theta, rtol=1e-8, atol=0):
            raise ValueError(f"{estimator} on these data does not give the chosen model's θ: give the data "
                             "select_graybox fitted on (its Dataset, or the record it was given alone)")

    @property
    def regret(self) -> float:
        """The choice's J_S on the test record over the best J_S there among the rows compared (>= 1;
        1: no row would have done better on new data; inf: the choice diverged there). The rows compared
        are those in the band when the choice is (a row that misses the band was never a candidate), else
        every row. Needs the call's ``test=`` record; ``ValueError`` when every such row's free run
        diverged on it."""
        js = self._test_column()
        rows = "row's"
        if self.in_band:
            js = np.where(self.table["in_band"].to_numpy(bool), js, np.inf)
            rows = "in-band row's"  # the rows compared
        if not np.isfinite(js).any():
            raise ValueError(f"no {rows} model ran through the test record (every such JS_test is inf: its free run "
                             "diverged there, or the row has no model): no best row to compare the choice with")
        return _score_ratio(float(self.chosen["JS_test"]), float(js[np.isfinite(js)].min()))

    @property
    def optimism(self) -> float:
        """The choice's J_S on the choosing data over its J_S on the test record (below 1: the choosing data
        flattered it, as the smallest of many scores on one record tends to). Needs the call's ``test=`` record."""
        self._test_column()
        return _score_ratio(float(self.chosen["JS_valid"]), float(self.chosen["JS_test"]))

    def _test_column(self) -> np.ndarray:
        if "JS_test" not in self.table.columns:
            raise ValueError("this selection was made without a test record: pass test= to select_graybox")
        return self.table["JS_test"].to_numpy(float)

    def __repr__(self) -> str:
        row = self.chosen
        unit = self.model.units[1]  # the table's J_S, J_SF and B are in output units²
        sq = squared_unit(unit)
        test = ""
        if "JS_test" in self.table:
            test = f", J_S test={squared_text(row['JS_test'], unit)}"
            try:
                test += f", regret={beside(self.regret, 1.0, 3)}"  # a regret above 1 never printed as 1
            except ValueError:  # every row compared diverged on the test record: no regret to give
                pass
        # a black box's band is inf, which every row meets: in_band=True there says nothing of the points
        band = "black box (band=inf)" if np.isinf(self.band) else f"in_band={self.in_band}"
        # no row in the band: the smallest J_SF chose (fallback "min_jsf"), not the J_S rule
        rule = (f"rule={self.rule!r}" if self.in_band else
                f"chosen by the smallest J_SF, {beside(row['JSF'], self.band)}{sq} (no row meets the band "
                f"B = {bound_text(self.band, row['JSF'])}{sq})")
        return (f"GrayboxSelection(n_terms={len(self.structure)}, rows compared={len(self.table)}, {rule}, "
                f"J_S valid={squared_text(row['JS_valid'], unit)}{test}, {band})")


register_type("GrayboxSelection", GrayboxSelection,
              (("structure", "structure"), ("model", "Model"), ("decision", "Decision"), ("table", "frame"),
               ("degree", "int_or_none"), ("band", "float"), ("in_band", "bool"), ("rule", "str")))


# -- 1. inputs ---------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class _Plan:
    """What every job needs: where to fit, where to choose (blocks), where to report."""

    ident: tuple[gb.Record, ...]  # every identification record (the fits take them together)
    # ((fit records, choosing record, block edges), ...): k folds, each fitted on its records; or one per
    # validation record, whose fit records are None: the fit on all the identification records
    splits: tuple
    test: tuple[gb.Record, ...] | None
    static: gb.StaticPoints | None
    band: float
    lag: int  # the candidates' largest lag: every row's errors are counted from this sample on
    extra: dict = field(default_factory=dict)
    # the round-off floor of each split's choosing record and of each test record (free_run_floor): one number per
    # record, whatever the structure, so structures exact to round-off tie
    floors: tuple = ()
    test_floors: tuple = ()

    @property
    def folds(self) -> bool:
        return any(fit is not None for fit, _, _ in self.splits)


def _block_edges(n: int, L: int, blocks: int, name: str = "validation") -> np.ndarray:
    """Edges of ``blocks`` contiguous blocks of the error samples L … n − 1 of a free run, fewer
    (with a warning) when the record (the ``name`` record) is too short for blocks of at least
    max(2L + 2, 10) samples."""
    min_len = max(2 * L + 2, 10)
    b = min(blocks, max(1, (n - L) // min_len))
    if b < blocks:
        if n - L < min_len:  # not even one block of that length: the record is one (shorter) block
            said = (f"are too few for blocks of at least {min_len} samples: they make one block, not {blocks}")
        else:
            said = f"make {b} block(s) of at least {min_len} samples, not {blocks}"
        warn(f"the {name} record's {n - L} error samples {said}" + ("; with one block the rule is 'min'" if b < 2
                                                                     else ""), SelectionWarning)
    return np.linspace(L, n, b + 1).astype(int)


def _folds(records: tuple[gb.Record, ...], k: int | None,
           min_len: int) -> list[tuple[tuple[gb.Record, ...], gb.Record]]:
    """(fit records, held-out record) per fold. One record: ``k`` contiguous folds, each fitted on the
    segments around it, given as separate records (no regressor reaches across the cut). Several
    records: each record is a fold, fitted on the others (``k``, when given, must be their number)."""
    if len(records) > 1:
        if k is not None and k != len(records):
            raise ValueError(f"folds={k}, but the {len(records)} identification records are the folds (each chosen on, "
                             "fitted on the others): drop folds, or pass validation=")
        return [(records[:i] + records[i + 1:], r) for i, r in enumerate(records)]
    record = records[0]
    k = FOLDS if k is None else k
    n = len(record)
    edges = np.linspace(0, n, k + 1).astype(int)
    out = []
    for i in range(k):
        a, b = edges[i], edges[i + 1]
        short = min(b - a, n - (b - a))
        if short < min_len:
            raise ValueError(f"fold {i + 1} of {k}: segments of {short} samples are too short for the candidates' "
                             f"largest lag {min_len - 2} (each segment needs {min_len} samples); use fewer folds "
                             "or a validation record")
        valid = record.slice(a, b, name=f"{record.name} fold {i + 1} valid")
        # the segments before and after, as two records (each at least the fold's length, or empty)
        fit = tuple(record.slice(lo, hi, name=f"{record.name} fold {i + 1} ident {part}")
                    for lo, hi, part in ((0, a, "before"), (b, n, "after")) if hi > lo)
        out.append((fit, valid))
    return out


def _static_points(sp, process: gb.Structure, band: float | None,
                   records: tuple[gb.Record, ...]) -> tuple[gb.StaticPoints | None, _Form | None]:
    """Static points for the jobs and the static form the structures must carry (None: black box);
    ``records``: the identification records (a curve's points are of their one input)."""
    if sp is None:
        return None, None
    if isinstance(sp, (gb.StaticCurve, gb.StaticSurface)):
        degree = sp.degree
        sp = static_points(sp, list(records), takes_ubar=False)  # sampled over its domain, of the records' input
    elif band is None:
        return sp, None  # J_SF reported, no form asked
    else:
        degree = static_degree(sp, band=band)
    if band is None:
        return sp, None
    varied = varied_inputs(sp)  # an input the points hold (a transient input's z̄ = 0) asks for no cluster
    top = carried_degree(process, degree, varied)
    if top is None:
        static_terms(gb.Structure([]), process, degree, varied)  # raises, naming the clusters the candidates lack
    if top < degree:
        # a rational structure (Σ_y) bends its static curve beyond its numerator's degree: ask what the
        # candidates carry, say so, and let the band judge (the table reports every J_SF)
        fit = static_fit_mse(sp, top) if isinstance(sp, gb.StaticPoints) else None
        carry = (f"candidates of degree {degree} (Candidates(..., degree={degree}))"
                 if max(t.degree for t in process) < degree else
                 f"candidates with terms in {', '.join(varied)} up to power {degree} (a lag of at least 1 for each)")
        warn(f"the static information asks for a degree-{degree} curve, the candidates carry degree {top} at most: "
             f"the structures get the clusters of degree {top}" +
             (f" (a degree-{top} polynomial fits the points with MSE {beside(fit, band)}, band B = "
              f"{bound_text(band, fit)})"
              if fit is not None else "") +
             f"; {carry} would carry it, and the band judges these structures (a rational one can still meet "
             "it: the table's JSF says)", SelectionWarning)
        degree = top
    return sp, _Form(degree, varied)


def _static_way(given: object, names: tuple[str, ...]) -> str:
    """How a curve or surface whose sampled points do not speak of the records' inputs (``names``) can: a curve is of
    the records' first input, a surface of its own inputs; "" for anything else."""
    if isinstance(given, gb.StaticSurface):
        own = tuple(given.input_names)
        if set(own) == set(names):
            return (f"a StaticSurface in the inputs {own} beside records in {names}: fit it on points in the records' "
                    "order (the same inputs, reordered)")
        if not set(own) <= set(names):
            return ""
        return (f"a StaticSurface speaks of its inputs {own} only: sample it into static points (its .points(ubar)) "
                "and give those the records' other inputs (e.g. gb.transient_inputs(points, taus=...))")
    if isinstance(given, gb.StaticCurve):
        return ("a StaticCurve speaks of the records' first input only: sample it into static points (its "
                ".points(ubar, name)) and give those the records' other inputs (e.g. gb.transient_inputs(points, "
                "taus=...))")
    return ""


@dataclass(frozen=True)
class _Form:
    """The static form the structures are completed to: its degree, in the inputs the static information varies."""
    degree: int
    input_names: tuple[str, ...]


#: The terms every structure holds unless ``include`` says otherwise: the constant.
_INCLUDE = ("1",)

#: Blocks of the validation record and folds of a record alone, when not given.
BLOCKS, FOLDS = 5, 3


def _moot_split(folds: int | None, blocks: int | None, valid: tuple[gb.Record, ...] | None) -> None:
    """An explicit ``folds`` or ``blocks`` the data make moot: said, not ignored (``ValueError``)."""
    if valid is not None and folds is not None:
        raise ValueError(f"folds={folds} applies when the choice is on folds of one record, but there is a "
                         f"validation record ({valid[0].name!r}): the choice is on blocks of it; drop folds "
                         "(blocks= sets how many), or pass the identification record alone")
    if valid is None and blocks is not None:
        raise ValueError(f"blocks={blocks} cuts a validation record, but there is no validation record: the "
                         "choice is on folds of the identification record (each fold one block); drop blocks "
                         "(folds= sets how many), or pass validation=")


def _inputs(candidates, data, sp, validation, test, band, folds, blocks,
            black_asked: bool = False) -> tuple[_Plan, _Form | None]:
    if not isinstance(candidates, gb.Structure):
        raise TypeError(f"candidates must be a candidate set (a Structure, e.g. graybox.Candidates(...)), got "
                        f"{type(candidates).__name__}")
    process = candidates.process
    extra: dict = {}
    if isinstance(data, gb.Dataset):
        idents = (data.ident,)
        valid = validation if validation is not None else data.valid
        extra = dict(data.extra)  # e.g. the curve of an equality with curve="dataset"
    elif isinstance(data, (gb.Record, list, tuple)):
        idents, valid = tuple(as_records(data, name="data")), validation  # checks each, and that they agree
    else:
        raise TypeError(f"data must be a Dataset, a Record or a list of Records (several identification records), "
                        f"got {type(data).__name__}")
    ident = idents[0]  # what the records share (inputs, period) is read off the first
    # (a Dataset is refused: it would stand for its identification record)
    valids = None if valid is None else tuple(choosing_records(valid, "validation"))
    tests = None if test is None else tuple(choosing_records(test, "test", "a fresh record of the plant"))
    _moot_split(folds, blocks, valids)
    if band is not None and sp is None:
        raise ValueError("a band needs static information: pass static= or a Dataset with static points "
                         "(without a band the search picks a black box)")
    given = sp
    sp, form = _static_points(sp, process, band, idents)
    if sp is not None:
        try:
            check_compatible(ident, sp)  # e.g. a curve in u for records with transient inputs: said here, once
        except ValueError as exc:
            way = _static_way(given, ident.input_names)
            if way:
                raise ValueError(f"{exc}; {way}") from None
            raise
    L = process.max_lag
    named = _named(idents, "identification") + _named(valids, "validation") + _named(tests, "test")
    for name, rec in named:
        # said now, not after the structure search and the fits
        check_alike(list(idents), rec)
        require_inputs(process.input_names, rec.input_names, "but the record's inputs are",
                       prefix=f"the {name} record {rec.name!r}: ")
        if len(rec) <= L + 1:  # each is fitted, chosen or scored on alone (a Record's own check says "record")
            raise ValueError(f"the {name} record{f' {rec.name!r}' if name[0].isdigit() else ''} ({len(rec)} samples) "
                             f"is shorter than the candidates' lags + 2 ({L + 2})")
        _check_output_scale(rec, name)
    for a, (name_a, rec_a) in enumerate(named):
        for name_b, rec_b in named[a + 1:]:
            advice = _OVERLAP_ADVICE[name_b.split()[-1], name_a.split()[-1]]
            if same_record(rec_b, rec_a):
                raise ValueError(f"the {name_b} record is the {name_a} record: {advice}")
            check_overlap(rec_b, rec_a, name_b, name_a, advice)
    if valids is not None:
        b = BLOCKS if blocks is None else blocks
        splits = tuple((None, v, _block_edges(len(v), L, b, name)) for name, v in _named(valids, "validation"))
    else:
        splits = tuple((a, b, np.array([L, len(b)])) for a, b in _folds(idents, folds, L + 2))
    if sp is not None and band is None and not black_asked:
        # static points given, yet no band to hold a model to them (none given, none carried by the points'
        # uncertainty: _band) and no black box asked for: a black box would come back unannounced
        warn("select_graybox: static information was given but no band (band=) and no uncertainty on the points, so "
             "this search is a black box chosen by J_S alone (the static information only scores J_SF); give band=B "
             "(output units²) or StaticPoints(..., uncertainty=δ) for a gray box, or band=numpy.inf to ask for a "
             "black box", SelectionWarning)
    if sp is not None:
        # said here, once, after the errors: every job's fits silence it (a units mix-up must not go unsaid)
        # a black box (no band) is fitted without them: saying they extrapolate it would say they were used
        unused = ("this search is a black box (no band: none given, or inf, and none carried by the points' "
                  "uncertainty), fitted without them: they only score its J_SF; a band B (band=, or the points' "
                  "uncertainty) makes it a gray box held to them")
        warn_static_range(sp.ubar, list(idents), "static points" if isinstance(given, gb.StaticPoints) else
                          f"the {type(given).__name__}'s domain", **({} if band is not None else
                                                                      {"consequence": unused}))
    floors = tuple(free_run_floor(process, choose) for _, choose, _ in splits)
    test_floors = () if tests is None else tuple(free_run_floor(process, r) for r in tests)
    return _Plan(idents, splits, tests, sp, np.inf if band is None else band, L, extra, floors, test_floors), form


def _check_output_scale(rec: gb.Record, name: str) -> None:
    """``ValueError`` where the free-run mean squares the choice compares (output units²) are no numbers on ``rec``: its
    output's mean square below the normal floats (y near 1e-160: every row's J_S was 0 and a row was chosen among ties
    of nothing), or the sum of squares of errors up to twice the output over the record beyond the largest (y near
    1e154: every run read as diverging)."""
    with np.errstate(over="ignore", under="ignore"):
        ms = float(np.mean(np.square(rec.y)))
        top = ms * 4.0 * len(rec.y)
    info = np.finfo(float)
    if ms == 0.0 and not np.any(rec.y):  # an output at rest: said where it is read (a constant output)
        return
    if ms < info.tiny or not top <= info.max:
        what = "small" if ms < info.tiny else "large"
        raise ValueError(f"the {name} record{f' {rec.name!r}' if name[0].isdigit() else ''}'s output is too {what} "
                         f"for the free-run mean squares the choice compares (output units²; its mean square, "
                         f"{ms:.3g}, lies too near an end of the float range): rescale y (other units) and select again")


def _named(records: tuple[gb.Record, ...] | None, role: str) -> list[tuple[str, gb.Record]]:
    """The records of one role with the names the messages give them ("validation", or "2nd validation"
    when there are several)."""
    if records is None:
        return []
    if len(records) == 1:
        return [(role, records[0])]
    return [(f"{_ordinal(i + 1)} {role}", r) for i, r in enumerate(records)]


#: (later role, earlier role) -> what to do when their records overlap.
_OVERLAP_ADVICE = {
    ("identification", "identification"): "each identification record must be other data (its samples would count "
                                          "twice in the fits, and be chosen on while fitted on)",
    ("validation", "identification"): "choose on data the fit did not see, or pass the identification data alone "
                                      "(folds)",
    ("validation", "validation"): "each validation record must be other data (its samples would count twice in "
                                  "the choice)",
    **{("test", role): "a test must be data nothing was fitted or chosen on"
       for role in ("identification", "validation", "test")},
}


def _ordinal(k: int) -> str:
    return f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"


# -- 2. structures -----------------------------------------------------------------------------

def _structures(candidates: gb.Structure, idents: tuple[gb.Record, ...], sizes, sources, include,
                form: _Form | None, centre: bool = False) -> list[dict]:
    """One dict per distinct structure: name, source(s), size, terms, added static-form terms; searched on
    all the identification records together (``centre``: on the centred signals, each structure closed)."""
    process = candidates.process
    n_max = len(process)
    ident = _fit_data(idents)
    if centre:
        _centring.check_included(include, process, list(idents))
        ident = _centring.centred_data(ident, _centring.search_offsets(list(idents)))
    samples = sum(len(r) for r in idents)
    data, of = (("the identification record", "the identification record's") if len(idents) == 1 else
                (f"the {len(idents)} identification records", f"the {len(idents)} identification records'"))
    rows = sum(len(r) - process.max_lag for r in idents)  # the searches' regression rows: a structure has fewer terms
    forced = list(include)
    asked = sizes is not None
    # the default sizes' largest: even sizes from 4 (or fewer, for small spaces or short records) to
    # min(16, n) (larger structures were never the honest choice in BENCHMARKS.md, honest selection, and
    # the SEMP path's cost grows quickly past them)
    top = min(16, n_max, rows - 1)
    if asked:
        sizes = sorted({check_int(s, "sizes", low=1) for s in sizes})
        if sizes and sizes[-1] > n_max:
            raise ValueError(f"sizes {[s for s in sizes if s > n_max]} exceed the {n_max} candidate process terms")
        if not sizes:
            raise ValueError("sizes must name at least one size")
        if sizes[-1] >= rows:
            raise ValueError(f"sizes {[s for s in sizes if s >= rows]} need more than {of} "
                             f"{max(rows, 0)} samples after the candidates' largest lag {process.max_lag}")
        n_forced = len(process.positions(forced, "included term"))  # each checked, as the searches check them
        if sizes[-1] < n_forced:
            raise ValueError(f"sizes {sizes} are fewer than the {n_forced} included terms {forced}: every "
                             "structure holds them")
    else:
        if top < 1:
            raise ValueError(f"{data} ({samples} samples) {'is' if len(idents) == 1 else 'are'} too short for the candidates' "
                             f"largest lag {process.max_lag}: no structure can be fitted")
        sizes = sorted(set(range(min(4, top), top + 1, 2)) | {top})
    found, reached = _searched(candidates, ident, sizes, sources, forced, top)
    most = max((max(r) for r in reached.values() if r), default=0)
    if not found and not asked and most:
        # the default sizes are of the candidates' count, and none of them is independent on these records (a
        # two-level input's u(k-1)^2 among three candidates): the same sizes below the most terms the searches reached
        sizes = sorted(set(range(min(4, most), most + 1, 2)) | {most})
        found, reached = _searched(candidates, ident, sizes, sources, forced, top)
    if not found:
        raise ValueError(f"no search reached any of the sizes {sizes} (reached: "
                         f"{ {s: sorted(r) for s, r in reached.items()} })")
    if asked:
        missed = {s: [k for k in sizes if k not in r] for s, r in reached.items()}
        missed = {s: m for s, m in missed.items() if m}
        if missed:
            warn("sizes no search reached are left out: " + "; ".join(f"{s}: {m}" for s, m in missed.items()),
                 SelectionWarning)
    rows, seen = [], {}
    for (src, k), terms in found.items():
        st, added = _completed(terms, candidates, idents, ident, include, form, centre)
        key = frozenset(st)
        if key in seen:  # e.g. two SEMP sizes that the static terms complete to one structure
            if src not in seen[key]["source"].split(", "):
                seen[key]["source"] += f", {src}"
                seen[key]["_members"].append((src, k))  # each source's own size (frols-3 + Σu² = semp-4), for the folds
            continue
        seen[key] = {"structure": f"{src}-{k}", "source": src, "size": k, "n_terms": len(st),
                     "added": ", ".join(map(str, added)), "terms": str(st), "_members": [(src, k)]}
        rows.append(seen[key])
    return rows


def _searched(candidates: gb.Structure, ident, sizes: list[int], sources, forced: list, top: int
              ) -> tuple[dict[tuple[str, int], list[str]], dict[str, set]]:
    """The searches' structures on ``ident`` (the fit data, centred already when asked): {(source, size): terms},
    and the sizes each source reached."""
    found: dict[tuple, list[str]] = {}
    reached: dict[str, set] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        # the path is grown to the largest size asked for (or the rows allow) on purpose; that its criterion may
        # still fall there is no news to the caller, who chooses among the sizes on other data
        warnings.filterwarnings("ignore", r".* is smallest at the largest size (looked at|the data allow)",
                                RuntimeWarning)
        # nor is the structure semp's criterion chose: its word that this choice came after the pruning budget ran
        # out is of a choice made here by other rules (its path's rows, size by size)
        warnings.filterwarnings("ignore", r"semp: pruning stopped after \d+ additions", RuntimeWarning)
        if "semp" in sources:
            # grown by criterion at least as far as the default sizes' path, whatever sizes are asked: a path cut
            # at the largest size asked has no look-ahead there (SEMP's pruning improves a size only once larger
            # structures were tried), so a size's row would depend on the others asked; a path that stops early
            # gives the sizes it reached
            path = gb.semp(candidates, ident, criterion="bic", max_terms=max(max(sizes), top), include=forced).path
            reached["semp"] = set(path["n_terms"])
            for k in sizes:
                same = path[path["n_terms"] == k]
                if len(same):
                    found[("semp", k)] = same.loc[same["score"].idxmin()]["structure"].split(" + ")
        if "frols" in sources:
            try:
                sel = gb.frols(candidates, ident, n_terms=max(sizes), include=forced)
            except FewerTermsError as e:  # fewer usable (or independent) candidates on these data: the sizes they reach
                if not e.reached:  # not known, or none at all: frols's own words say why
                    raise
                sel = gb.frols(candidates, ident, n_terms=e.reached, include=forced)
            # its structure begins with the included terms: a size below their number would drop some
            n0 = max(len(gb.Structure(list(forced))), 1)
            reached["frols"] = set(range(n0, len(sel.structure) + 1))
            for k in sizes:
                if n0 <= k <= len(sel.structure):
                    found[("frols", k)] = [str(t) for t in sel.structure[:k]]
        for src in (s for s in ("swap", "exact") if s in sources):
            # the best subset of each size by a non-greedy search (frols(search=...)), one size at a time:
            # a criterion run would cut the sizes its criterion rules out, which the choice here compares
            reached[src] = set()
            n0 = max(len(gb.Structure(list(forced))), 1)
            for k in sizes:
                if k < n0:  # every structure holds the included terms: no subset of k, as the paths above reach none
                    continue
                try:
                    sel = gb.frols(candidates, ident, n_terms=k, include=forced, search=src)
                except FewerTermsError as e:  # fewer usable or independent candidates: the sizes below are reached
                    # named as frols names its own (else an unreached size read "reached: {'exact': []}")
                    reached[src] |= set(range(n0, (e.reached or 0) + 1))
                    break
                reached[src].add(k)
                found[(src, k)] = [str(t) for t in sel.structure]
    return found, reached


def _completed(terms: list[str], candidates: gb.Structure, idents: tuple[gb.Record, ...], ident, include,
               form: _Form | None, centre: bool) -> tuple[gb.Structure, list]:
    """A search's structure as a row fits it: closed (``centre``), less what the records cannot tell apart (a
    centred black box), completed with the static form's terms (a gray box); and those added terms."""
    process = candidates.process
    st = gb.Structure(terms)
    if centre:
        st = _centring.closure(st).process
    if centre and form is None:
        # a black box: less what the records cannot tell apart (a two-level input's u^2: no fit takes it),
        # unsaid, as the searches' skipped candidates are (the row's terms show it); a gray box keeps it, as
        # the static form's terms: its static points tell u^2 from u and 1. Judged on the rows the search chose the
        # terms on (from the candidates' largest lag), as frols and semp judge it: a term told apart only by the
        # samples before them (an input's first sample off its two levels) would have a θ fitted to those samples
        st, gone = _centring.told_apart(st, ident, 1e-7, process.max_lag)  # frols's and semp's rank_tol
        _centring.check_included(include, process, list(idents), gone)
    added = static_terms(st, process, form.degree, form.input_names) if form is not None else []
    st = st + gb.Structure(added)
    if centre:  # the static form's terms (u(k-1)^2 for Σ_{u^2}) bring their divisors too, or the set is not closed
        closed = _centring.closure(st).process
        added += [t for t in closed if t not in st]
        st = closed
    return st, added


def _fold_structures(rows: list[dict], candidates: gb.Structure, plan: _Plan, sources, include,
                     form: _Form | None, centre: bool) -> list[tuple[str, ...]]:
    """Per row, its structure searched again on each fold's fit records alone (the held-out fold unseen: a search
    on all the identification data would choose the terms with it): one terms text per split, that of the row's
    source at its size (each of its sources at its own size when several share the row; or the size nearest it the
    fold's search reached), ``""`` where that fold's search reached no structure of the row's sources, ``"(why)"``
    where the structure it reached cannot be completed on the fold's records (the row then fails on that fold)."""
    process = candidates.process
    # every member's size (a row two sources share: each at its own), for swap and exact, which search each size apart
    sizes = sorted({k for r in rows for _, k in (r.get("_members") or [(None, r["size"])])})
    forced = list(include)
    per_fold = []
    short: list[str] = []  # folds whose search stopped short of the rows' sizes: said, not scored silently
    for fit, _, _ in plan.splits:
        got: dict[tuple[str, int], str] = {}
        if fit is not None:
            n_rows = sum(len(r) - process.max_lag for r in fit)
            ident = _fit_data(fit)
            with warnings.catch_warnings():
                # the search on all the identification data said what there is to say of the sizes and candidates
                warnings.simplefilter("ignore")
                try:
                    if centre:
                        ident = _centring.centred_data(ident, _centring.search_offsets(list(fit)))
                    top = min(16, len(process), n_rows - 1)
                    # SEMP's path and FROLS's order hold every size up to the largest at no extra cost: all of them,
                    # so that a row's nearest size is the nearest the fold's search reached, not the nearest of the
                    # rows' sizes; swap and exact search each size apart, at the rows' members' sizes only
                    path_sources = [s for s in sources if s in ("semp", "frols")]
                    found = _searched(candidates, ident, list(range(1, min(max(sizes), n_rows - 1) + 1)),
                                      path_sources, forced, top)[0] if path_sources else {}
                    if len(path_sources) < len(sources):
                        found |= _searched(candidates, ident, [k for k in sizes if k < n_rows],
                                           [s for s in sources if s not in path_sources], forced, top)[0]
                except (ValueError, FewerTermsError, np.linalg.LinAlgError):  # this fold's records support none
                    found = {}
                for key, terms in found.items():
                    # a structure the fold's records cannot complete (an included term they cannot tell apart) fails
                    # its own row on this fold, saying why; not the fold's other structures, nor taken at another size
                    try:
                        got[key] = str(_completed(terms, candidates, fit, ident, include, form, centre)[0])
                    except (ValueError, FewerTermsError, np.linalg.LinAlgError) as exc:
                        got[key] = f"({exc})"
            if n_rows <= max(sizes):  # too few rows to fit the largest rows' structures: the search stops short
                top_size = max((k for _, k in got), default=0)
                short.append(f"fitted on {listed([r.name for r in fit])} ({n_rows} regression rows): "
                             + (f"its search reached at most {top_size} terms" if top_size else "its search reached "
                                "no structure"))
        per_fold.append(got)
    if short:
        warn(f"a fold's fitting records are too short for the rows' sizes (up to {max(sizes)} terms): "
             + "; ".join(short) + ". Its rows are scored there with the nearest structure its search reached (or fail "
             "on it): their J_S there says little of their own size. Give each fold more fitting data (fewer folds, "
             "longer records) or choose on a validation record", SelectionWarning)
    out = []
    for r in rows:
        # each source of the row at its own size (a row two sources share may be two sizes: frols-3 and semp-4 that
        # the static terms complete alike), the row's first source first; else the size nearest a source's own that
        # the fold's search reached (a SEMP path on other records passes through other sizes; the smaller on a tie)
        own = dict(r.get("_members") or [(s, r["size"]) for s in r["source"].split(", ")])
        rank = {s: i for i, s in enumerate(own)}
        out.append(tuple(f[min(near, key=lambda key: (abs(key[1] - own[key[0]]), rank[key[0]], key[1]))] if near
                         else "" for f in per_fold for near in [[key for key in f if key[0] in own]]))
    return out


# -- 3. scoring --------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class _Job:
    name: str
    terms: str
    estimator: str
    plan: _Plan
    lambdas: tuple | None
    constraints: tuple  # canonical tables (constraint_from_object), checked by the driver
    filters: tuple = ()  # the caller's warning filters, as warnings.filters held them at the call
    # choosing on folds: the row's structure searched on each split's fit records (one terms text per split, "" where
    # that fold's search reached none, "(why)" where it cannot be completed there); None: every split fits ``terms``
    fold_terms: tuple[str, ...] | None = None


def _lambdas(estimator: str, lambdas: Sequence[float] | None) -> np.ndarray | None:
    if lambdas is not None:
        return np.asarray(lambdas, float)
    if estimator == "pe":
        return np.logspace(-6, 0, 40)  # closed form: a front dense enough for D_SF at a third of the default's cost
    if estimator.startswith("se"):
        return np.logspace(-2, 0, 8)  # a coarse front ranks structures; the chosen one is refitted on it
    return None


#: Tolerance of the gradient SE fits that rank the rows (``se_pareto``'s ``tol``, relative; its default
#: is 1e-8): the rows' scores differ by per cents and the rule's standard errors are per cents too, so
#: solving each fit to 1e-8 bought nothing the choice can see (BENCHMARKS.md, "Session of 2026-11-26,
#: 08:48"); the chosen member is the fit made here.
_SE_TOL = 1e-6


def _fit_data(records: tuple[gb.Record, ...]) -> gb.Record | list[gb.Record]:
    """What the searches and estimators take: the record, or the list of several."""
    return records[0] if len(records) == 1 else list(records)


def _fit(job: _Job, st: gb.Structure,
         records: tuple[gb.Record, ...]) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """(θ rows (P, n), λ1 (P,), {member: why it failed}) fitted on ``records`` together; a failed member's row is
    NaN."""
    est, plan = job.estimator, job.plan
    rec = _fit_data(records)
    if est in _BLACK_BOX_FITS:
        return _BLACK_BOX_FITS[est](st, rec)[None, :], np.array([np.nan]), {}
    lam = _lambdas(est, job.lambdas)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        if est == "pe":
            # only the static points and the data set's extra matter to the constraints
            cons = cell_constraints(job.constraints, st, gb.Dataset(records[0], records[0], plan.static,
                                                                    extra=plan.extra))
            # as pe_pareto and the SE rows: a λ1 whose weights do not identify θ (λ1 = 1 on records with an
            # input held) is one failed member (a NaN row), not the whole row's failure
            th, why = pe_members(st, rec, plan.static, lambdas=lam, constraints=cons or None,
                                 solver="clarabel" if cons else "closed")
            return th, lam, why
        gradient = est == "se-gradient"
        front = gb.se_pareto(st, rec, plan.static, lambdas=lam, progress=False,
                             method="gradient" if gradient else "ga", **({"tol": _SE_TOL} if gradient else {}))
        th = np.array(front.thetas, float)
        th[list(front.failures)] = np.nan
        return th, np.asarray(front.lambdas, float), dict(front.failures)


def _fit_or_fail(job: _Job, st: gb.Structure,
                 records: tuple[gb.Record, ...]) -> tuple[np.ndarray, np.ndarray, list[str], dict[int, str]]:
    """:func:`_fit`, with a fit these data cannot make (e.g. terms collinear on a fold's two input
    levels) a failed member at every λ and its reason, not an error that ends the whole search:
    as a grid cell's, a row's failure is data. Returns θ, λ1, the row's failure (a list of one reason, or
    empty) and the failed members' reasons {member: why}, each naming the records fitted."""
    names = ", ".join(repr(r.name) for r in records)
    try:
        th, lam, why = _fit(job, st, records)
        # pe_members names a member by its λ1 ("λ1 = 0.01: <a constraint's check>"), which the table says beside
        # the reason: without it, members refused for one reason share it, said once
        return th, lam, [], {i: f"the fit on {names} failed: {r.removeprefix(f'λ1 = {lam[i]:g}: ')}"
                             for i, r in why.items()}
    except (ValueError, np.linalg.LinAlgError) as exc:
        return *_no_fit(job, st), [f"the fit on {names} failed: {exc}"], {}


def _no_fit(job: _Job, st: gb.Structure) -> tuple[np.ndarray, np.ndarray]:
    """(θ rows, λ1) of a row with no fit: a NaN row per member its estimator would fit (one for a black box)."""
    lam = _lambdas(job.estimator, job.lambdas)
    lam = np.array([np.nan]) if lam is None else lam
    return np.full((lam.size, len(st)), np.nan), lam


def _block_mse(st: gb.Structure, thetas: np.ndarray, rec: gb.Record, edges: np.ndarray, floor: float) -> np.ndarray:
    """(P, B) free-run MSE of each member on each block of ``rec`` (one free run from its first L samples).

    An MSE below ``floor``, the record's round-off floor (:func:`free_run_floor`, as :func:`graybox.semp` floors
    its scores), is that floor: on noise-free data exact structures tie there, instead of the one with the least
    round-off (often the largest) leading the others by orders of magnitude. (1e-20 of the mean square was far
    above a free run's round-off: at y near 1e6 a structure 2.8e-5 off tied with the exact one and, having fewer
    terms, was chosen.) The floor is the whole record's, not each block's: a block where the output rests at zero
    (a record that starts at rest) would have none, and the round-off there would rank the exact structures."""
    P, B = thetas.shape[0], len(edges) - 1
    out = np.full((P, B), np.inf)
    ok = np.all(np.isfinite(thetas), axis=1)
    if not ok.any():
        return out
    code = encode(st)
    L = st.max_lag
    y = simulate_batch(code, thetas[ok], record_inputs(rec, code.input_names), rec.y, max(L, 1), bounded=True)
    with np.errstate(over="ignore", invalid="ignore"):
        e2 = (y - rec.y[None, :]) ** 2
        mse = np.stack([np.maximum(e2[:, a:b].mean(axis=1), floor)
                        for a, b in zip(edges[:-1], edges[1:])], axis=1)
    out[ok] = np.where(np.isfinite(mse), mse, np.inf)
    return out


#: Where a row's model is started from besides each record's own first samples: the output held at these quantiles
#: of the identification and choosing records' outputs (see :func:`_wanders`).
_HELD_STARTS = (0.05, 0.5, 0.95)


def _wanders(jobs: list, results: list[dict], members: list[int], plan: _Plan) -> np.ndarray:
    """(rows,) whether each row's model diverges when started away from the records' own first samples.

    Each row's member (the model its figures are of) runs free over every identification and choosing record's
    input from the output held at :data:`_HELD_STARTS` of those records' outputs; a run the free run's own bound
    stops (:func:`simulate_batch`, ``bounded``) marks the row. A model of the plant forgets where it started; one
    that stays bounded only from the records' own starts (a small basin around the records' trajectories) was seen
    to diverge on a longer test record after a bounded validation run (BENCHMARKS.md, "Models that diverge from a
    held start"). Rows without a model: False (they are not chosen anyway)."""
    records = list(plan.ident) + [r for fit, r, _ in plan.splits if fit is None]
    levels = np.quantile(np.concatenate([r.y for r in records]), _HELD_STARTS)
    out = np.zeros(len(jobs), bool)
    for k, (job, res, i) in enumerate(zip(jobs, results, members)):
        th = res["thetas"][i:i + 1] if i >= 0 else np.full((1, 1), np.nan)
        if not np.all(np.isfinite(th)):
            continue
        st = gb.parse_structure(job.terms)
        code, start = encode(st), max(st.max_lag, 1)
        out[k] = any(not np.all(np.isfinite(simulate_batch(code, th, record_inputs(rec, code.input_names),
                                                            np.full(start, level), start, bounded=True)))
                     for rec in records for level in levels)
    return out


def _steady(table: pd.DataFrame, ok: np.ndarray) -> np.ndarray:
    """The rows of the bool mask ``ok`` whose model does not diverge from a held start (:func:`_wanders`), or ``ok``
    itself where every one of them does (or the table has no ``wanders``: a loaded older selection)."""
    if "wanders" not in table.columns:
        return ok
    steady = ok & ~table["wanders"].to_numpy(bool)
    return steady if steady.any() else ok


def _jsf(st: gb.Structure, thetas: np.ndarray, sp: gb.StaticPoints | None) -> np.ndarray:
    out = np.full(thetas.shape[0], np.nan if sp is None else np.inf)
    ok = np.all(np.isfinite(thetas), axis=1)
    if sp is not None and ok.any():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            out[ok] = gb.evaluate_thetas(st, thetas[ok], None, sp)["JSF"]
    return out


def _apply_filters(filters: tuple) -> None:
    """Install the caller's warning filters (``warnings.filters`` entries) in this process, with every
    action that shows a warning turned into "always" (so that each row keeps its own)."""
    warnings.resetwarnings()
    for action, message, category, module, lineno in reversed(filters):
        # an entry holds a compiled pattern, a string (some tools insert those) or None
        warnings.filterwarnings(action if action in ("ignore", "error") else "always",
                                getattr(message, "pattern", message) or "", category,
                                getattr(module, "pattern", module) or "", lineno)
    warnings.simplefilter("always", append=True)


def _score_job(job: _Job) -> dict[str, np.ndarray]:
    """Fit, per split and on all the identification data, and score every member.

    Returns ``blocks`` (P, B): J_S per block of the choosing data (with folds: one block per fold,
    members matched by λ) and ``weights`` (B,): the blocks' shares of its samples (``blocks @
    weights`` is J_S on all the choosing samples); ``jsf`` (P,): the worst J_SF over the fits; ``thetas`` (P, n) and
    ``lambdas`` of the fit on all the identification data; ``test`` (P,): their J_S over the test records.
    """
    st = gb.parse_structure(job.terms)
    plan = job.plan
    blocks, jsf, weights = [], [], []
    full = None
    # a fit's warnings belong to its row: kept as text (a worker process's warnings never reach the
    # driver otherwise), said once by the driver for the whole table; the caller's filters hold in
    # the job too (what it ignores is not kept, what it makes an error raises)
    # one BLAS thread: the fits make thousands of small BLAS calls (see core._least_squares.one_blas_thread)
    with warnings.catch_warnings(record=True) as caught, one_blas_thread():
        _apply_filters(job.filters)
        failed: list[str] = []
        member_failed: dict[int, str] = {}  # a member's first failure, over the folds' fits and the full one

        def fit(records, st=st):
            th, lam, why, members = _fit_or_fail(job, st, records)
            failed.extend(why)
            for i, reason in members.items():
                member_failed.setdefault(i, reason)
            jsf.append(_jsf(st, th, plan.static))
            return th, lam

        for j, (records, choose, edges) in enumerate(plan.splits):
            fold_st = st
            if records is None:  # every validation record scores the fit on all the identification records, made once
                full = full or fit(plan.ident)
                th = full[0]
            elif job.fold_terms is not None and job.fold_terms[j][:1] in ("", "("):  # no such structure on this fold
                on = ', '.join(repr(r.name) for r in records)
                failed.append(f"the structure search on {on} found no structure of this row's source"
                              if not job.fold_terms[j] else
                              f"the structure found on {on} cannot be completed there: {job.fold_terms[j][1:-1]}")
                th = _no_fit(job, st)[0]
            else:  # a fold: its own fit (of the structure its own search chose, when searched per fold)
                fold_st = st if job.fold_terms is None else gb.parse_structure(job.fold_terms[j])
                th = fit(records, fold_st)[0]
            blocks.append(_block_mse(fold_st, th, choose, edges, plan.floors[j]))
            weights.append(np.diff(edges))
        full = full or fit(plan.ident)  # (last: jsf[-1] is its J_SF)
        w = np.concatenate(weights).astype(float)
        out = {"blocks": np.concatenate(blocks, axis=1), "weights": w / w.sum(), "jsf": np.max(np.stack(jsf), axis=0),
               "jsf_full": jsf[-1], "thetas": full[0], "lambdas": full[1], "failed": failed,
               "member_failed": [member_failed.get(i, "") for i in range(len(full[0]))]}
        # a member the refit on all the identification data failed has no model to give: it cannot be chosen
        out["blocks"][~np.all(np.isfinite(full[0]), axis=1)] = np.inf
        if plan.test is not None:
            out["test"] = _test_scores(st, full[0], plan)
    out["warnings"] = warning_texts(caught)
    return out


def _test_scores(st: gb.Structure, thetas: np.ndarray, plan: _Plan) -> np.ndarray:
    """(P,) each member's J_S over every test sample (each test record's from the candidates' largest lag on)."""
    n = np.array([len(r) - plan.lag for r in plan.test], float)
    mse = np.stack([_block_mse(st, thetas, r, np.array([plan.lag, len(r)]), floor)[:, 0]
                    for r, floor in zip(plan.test, plan.test_floors)], axis=1)
    return mse @ (n / n.sum())


def _rescore_test(job: _Job, row: dict, key: str | None) -> bool:
    """Make a row read from a checkpoint score the call's test records (``key`` their :func:`test_digest`, None for
    none): its test scores dropped, kept, or remade from its members' θ when they scored other records. Whether the
    row changed."""
    if key is None:  # (the file keeps them for a later call)
        row.pop("test", None)
        return False
    if row.get("test_key") == [key] and "test" in row:
        return False
    row["test"] = _test_scores(gb.parse_structure(job.terms), row["thetas"], job.plan)
    row["test_key"] = [key]
    return True


def _row_shape(job: _Job) -> tuple[int, int, int]:
    """(members, blocks, parameters) of the scores :func:`_score_job` gives ``job``."""
    lam = _lambdas(job.estimator, job.lambdas)
    return (1 if lam is None else lam.size, sum(len(edges) - 1 for _, _, edges in job.plan.splits),
            len(gb.parse_structure(job.terms)))


def _run_jobs(jobs: list[_Job], *, executor, workers, client, scheduler, progress,
              checkpoint: SelectionCheckpoint | None = None) -> list[dict]:
    """Every job's scores, in order: those the checkpoint holds read from it, the others run (and kept in it as
    each finishes)."""
    out: list = [None] * len(jobs)
    keys = [None] * len(jobs)
    tests: dict[int, str] = {}
    if checkpoint is not None:
        # each plan hashed once (the jobs share the call's; its records may be long)
        plans = {id(j.plan): j.plan for j in jobs}
        digests = {i: plan_digest(p) for i, p in plans.items()}
        tests = {i: test_digest(p) for i, p in plans.items() if p.test is not None}
        keys = [row_key(j, digests[id(j.plan)]) for j in jobs]
        out = [checkpoint.get(k, _row_shape(j)) for k, j in zip(keys, jobs)]
        rescored = False
        for i, r in enumerate(out):  # a kept row's fits serve any test record: its test scores are remade if another
            if r is not None and _rescore_test(jobs[i], r, tests.get(id(jobs[i].plan))):
                checkpoint.put(keys[i], r, write=False)
                rescored = True
        if rescored:
            checkpoint.write()
    todo = [i for i, r in enumerate(out) if r is None]
    if not todo:
        return out

    def finished(i: int, r: dict) -> None:
        out[i] = r
        if checkpoint is not None:
            if id(jobs[i].plan) in tests:
                r["test_key"] = [tests[id(jobs[i].plan)]]
            checkpoint.put(keys[i], r)

    if executor is None:
        executor = "inprocess" if workers is None and client is None and scheduler is None else "dask"
    if executor == "inprocess":  # (executor, workers, client and scheduler checked by select_graybox)
        bar = progress_bar(len(jobs), "select_graybox", progress, initial=len(jobs) - len(todo))
        for i in todo:
            finished(i, _score_job(jobs[i]))
            bar.update()
        bar.close()
        return out
    kw = dict(workers=workers, client=client, scheduler=scheduler)
    if executor == "processes":
        kw = dict(executor="processes", workers=workers or 2)
    elif not any(v is not None for v in kw.values()):
        kw["workers"] = 2
    # the slow fronts first, largest structures first: the workers finish together
    order = sorted(todo, key=lambda i: (jobs[i].estimator not in SLOW_ESTIMATORS, -jobs[i].terms.count(" + ")))
    with parallel_map(**kw) as pmap:
        pmap(_score_job, [jobs[i] for i in order], each=lambda k, r: finished(order[k], r))
    return out


# -- 4. choice ---------------------------------------------------------------------------------

def _member(res: dict, band: float) -> tuple[int, bool]:
    """D_SF on the choosing data: the smallest mean block J_S among the members in the band
    (``None``-like -1 when no member has a finite J_S)."""
    js = res["blocks"] @ res["weights"]
    finite = np.isfinite(js)
    inside = finite & (res["jsf"] <= band) if np.isfinite(band) else finite
    if inside.any():
        c = np.flatnonzero(inside)
        return int(c[np.lexsort((c, res["jsf"][c], js[c]))[0]]), True
    ok = np.flatnonzero(finite & np.isfinite(res["jsf"])) if np.isfinite(band) else np.array([], int)
    if ok.size == 0:
        return -1, False
    return int(ok[np.lexsort((ok, js[ok], res["jsf"][ok]))[0]]), False


def _ratio_se(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """log(J_a / J_b) of two rows' J_S (``J = w @ blocks``) and its standard error over the blocks, paired: the
    delta method, z_i = a_i / J_a − b_i / J_b (Σ w_i z_i = 0), SE² = Σ w_i² z_i² / (1 − Σ w_i²) (NaN SE with one
    block). A block of n_i samples has a variance ∝ 1 / n_i ∝ 1 / w_i, so E[w_i² z_i²] ∝ w_i − w_i²: the divisor makes
    SE² unbiased for blocks of any length (n / (n − 1) does so for equal blocks only; blocks of 20, 20, 20, 20 and 920
    samples gave SE 0.43 of the ratio's spread with it).

    The ratio is the one the table's J_S columns show, so a row that fails badly on one block counts as it does
    in J_S; a mean of per-block log ratios (the rule before) let such a row in (BENCHMARKS.md, the choosing rule).
    """
    ja, jb = float(w @ a), float(w @ b)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.log(ja / jb)
        z = a / ja - b / jb
    if not (np.isfinite(r) and np.all(np.isfinite(z))):
        return np.inf, np.nan
    se = float(np.sqrt(np.sum((w * z) ** 2) / (1.0 - np.sum(w ** 2)))) if z.size > 1 else np.nan
    return float(r), se


def _choose(table: pd.DataFrame, scores: list[np.ndarray], weights: np.ndarray, rule: str) -> tuple[int, str]:
    """Position of the chosen row among the in-band rows (``table`` gains vs_best, vs_best_se,
    eligible); the rule used. Rows whose ``wanders`` is True are left out, and the best row is the best of the
    others, unless every in-band row wanders."""
    ok = np.flatnonzero(_steady(table, table["in_band"].to_numpy(bool)))
    js = table["JS_valid"].to_numpy(float)
    best = int(ok[np.argmin(js[ok])])
    vs, se = np.full(len(table), np.nan), np.full(len(table), np.nan)
    for i in ok:
        vs[i], se[i] = _ratio_se(scores[i], scores[best], weights)
    table["vs_best"], table["vs_best_se"] = vs, se
    if rule == "one-se" and scores[best].size < 2:
        rule = "min"
    if rule == "min":
        # rows tied with the best (exact structures on noise-free data): the fewest terms, as under one-se
        eligible = np.zeros(len(table), bool)
        eligible[ok] = js[ok] == js[best]
    else:
        # within one standard error of the best: the lead is not distinguishable from block noise
        eligible = np.zeros(len(table), bool)
        eligible[ok] = vs[ok] <= np.nan_to_num(se[ok], nan=0.0)
        eligible[best] = True
    table["eligible"] = eligible
    c = np.flatnonzero(eligible)
    n = table["n_terms"].to_numpy()
    return int(c[np.lexsort((js[c], n[c]))[0]]), rule


def _decision(row: pd.Series, res: dict, i: int, st: gb.Structure, plan: _Plan, estimator: str, in_band: bool):
    """The chosen member as a Decision: J_S on the choosing data, J_SF of the refitted member."""
    js_choose = res["blocks"] @ res["weights"]
    if estimator in _BLACK_BOX_FITS:
        model = gb.Model(st, res["thetas"][0], name=f"{estimator} ({row.name})", **carried_from(list(plan.ident), plan.static))
        return gb.Decision(model, 0, float("nan"), float(js_choose[0]), float(res["jsf_full"][0]), "min J_S", True,
                           float(js_choose[0]))
    thetas = res["thetas"]
    keep = np.all(np.isfinite(thetas), axis=1)
    failures = {int(k): _member_failure(res, k) for k in np.flatnonzero(~keep)}
    th = np.where(keep[:, None], thetas, 0.0)
    scored = gb.ParetoSet(st, th, res["lambdas"], np.full(len(th), np.nan), js_choose, res["jsf_full"],
                          f"{estimator}, J_S on the choosing data", {}, failures,
                          **carried_from(list(plan.ident), plan.static))
    name = f"{estimator} ({row.name})"  # as model_of names it, not after the internal front
    if in_band:
        d = gb.decide_dsf(scored, band=plan.band, fallback="min_jsf")
        if d.index == i:
            return dataclasses.replace(d, model=scored.member_model(i, name=name))
    return gb.Decision(scored.member_model(i, name=name), int(i), float(res["lambdas"][i]),
                       float(js_choose[i]), float(res["jsf_full"][i]), "D_SF" if in_band else "min J_SF", in_band,
                       float(js_choose[i] if in_band else res["jsf_full"][i]))


# -- the whole -----------------------------------------------------------------------------------

def select_graybox(
    candidates: gb.Structure,
    data: gb.Dataset | gb.Record | Sequence[gb.Record],
    static: gb.StaticPoints | gb.StaticCurve | gb.StaticSurface | None = None,
    *,
    band: float | None = None,
    sizes: Sequence[int] | None = None,
    sources: Sequence[str] = ("semp", "frols"),
    estimator: str | Sequence[str] | None = None,
    constraints: Any = (),
    lambdas: Sequence[float] | None = None,
    validation: gb.Record | None = None,
    test: gb.Record | None = None,
    rule: str = "one-se",
    blocks: int | None = None,
    folds: int | None = None,
    shortlist: int | None = None,
    include: Sequence[str] = _INCLUDE,
    fallback: str | None = None,
    executor: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool | None = None,
    centre: bool = False,
    checkpoint: str | os.PathLike | None = None,
) -> GrayboxSelection:
    """Choose a structure (and estimator, and λ member) on data it was not fitted on.

    Parameters
    ----------
    candidates : Structure
        Candidate terms (noise terms are ignored), e.g. ``Candidates(6, 6, degree=2, max_y_power=1)``.
    data : Dataset, Record or sequence of Record
        A Dataset brings the identification and validation records and the static points; a
        Record is identification data only (the choice on ``folds`` contiguous folds of it, each
        fitted on the segments around it); several Records (a list or tuple: experiments of one
        plant, same inputs and sampling period) are identification data fitted together; without a
        validation record each is a fold, chosen on while fitted on the others. The structure
        searches and every fit take the records together (no regressor reaches across two). On
        folds, each fold's structures are searched again on its fit records alone (the held-out
        fold unseen), a row being a source and size; when in every row such a structure has no
        finite free run on its held-out fold, the structures of all the data are fitted per fold
        instead, with a ``SelectionWarning`` (optimistic), when one of them runs.
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static information (default: the Dataset's). A curve is sampled at 10 levels over its
        domain, a surface (several inputs) on a grid of 6 levels per input over its domain box
        (as by every estimator that takes a curve for points).
        Without a band it is only reported (the table's J_SF).
    band : float, optional
        B: the bound on J_SF (output units²), the static measurements' uncertainty: a gray box
        (fronts of J_S against J_SF, D_SF). Omitted: the static points' own band
        (``StaticPoints.band``, the mean of their uncertainty δ², as :func:`graybox.se_dsf` takes it)
        when they carry one; otherwise, or with ``band=numpy.inf`` (no static requirement), a
        black box chosen by J_S alone (static information given without a band, an uncertainty or
        a black-box ``estimator`` is said by a :class:`SelectionWarning`: a black box was likely not
        meant). A gray box's structures are completed with the clusters of
        a static curve of degree d: a curve's or surface's own, or for points the smallest degree
        whose least-squares polynomial fits them with a mean squared error within B (at most 3);
        lowered, with a :class:`SelectionWarning`, to the degree the candidates carry.
    sizes : sequence of int, optional
        Distinct structure sizes (before the static terms); default 4, 6, …, up to min(16, candidates)
        (fewer for a small candidate set or an identification record of few samples). Sizes asked
        for that a search does not reach are left out with a :class:`SelectionWarning`; default
        sizes it does not reach (candidates that are not independent on the records) are left out
        without one. The SEMP path grows at
        least as far as the default sizes' (its pruning improves a size only once larger structures
        were tried): asking for a few sizes leaves each one's row as the default call makes it.
    sources : sequence of {"semp", "frols", "swap", "exact"}
        Where the structures of each size come from: the SEMP path, the FROLS path (greedy), the
        best subset of each size by term exchanges from the greedy paths (``frols(search="swap")``,
        about 0.1 s a size on the bundled plant) or by branch and bound (``search="exact"``: up to
        100 usable candidates, seconds a size). Structures several sources give are one row.
    estimator : str or sequence of str, optional
        Gray box: ``"pe"`` (closed form unless constraints need a QP), ``"se-gradient"``,
        ``"se-ga"`` (default PE and SE gradient; PE alone with constraints). Black box: ``"ls"``,
        ``"els"``, ``"oe"`` (output error, :func:`graybox.output_error` with its defaults; default
        all three). Every structure is scored with each; the rule chooses among all (structure,
        estimator) rows. The gradient SE fits stop at a relative tolerance of 1e-6 (``se_pareto``'s
        default is 1e-8; the scores move by about 1e-5, far below the rule's spread): refit the
        chosen structure with ``se_pareto``/``se_dsf`` for a tighter solution.
    constraints : optional
        Constraint objects or tables imposed by PE, as in :class:`Variant`. Naming another
        estimator with them is an error.
    lambdas : sequence of float, optional
        λ1 of each front (default: PE 40 in logspace(-6, 0); SE 8 in logspace(-2, 0)).
    validation : Record or sequence of Record, optional
        The choosing record (default: the Dataset's validation record), or several: each is cut
        into ``blocks`` blocks, every block of every record one score of the rule.
    test : Record or sequence of Record, optional
        Records nothing is fitted or chosen on: the table gets ``JS_test`` (J_S over all their
        samples) and ``JSF_test`` columns. The choice is the same with and without them.
    rule : {"one-se", "min"}
        How the row is chosen from the scores on the choosing data: ``"one-se"`` (default) the
        fewest parameters among the rows within one standard error of the best (the log ratio of
        J_S, its error over the blocks), ``"min"`` the smallest J_S (the fewest parameters among rows tied on it).
    blocks : int, optional
        Contiguous blocks each validation record is cut into for the standard errors (>= 2;
        default 5; fewer, with a :class:`SelectionWarning`, when the record is too short for
        them). Refused (``ValueError``) without a validation record: the choice is then on folds.
    folds : int, optional
        Contiguous folds of one record when there is no validation record (>= 2; default 3); each
        fold is one block. Refused (``ValueError``) with a validation record (the choice is then on
        its blocks), and with several identification records unless it is their number (they are
        the folds).
    shortlist : int, optional
        Faster, less thorough: with PE, LS or ELS among the estimators, the slow ones (SE and
        output error, seconds per structure) fit only the ``shortlist`` structures those rank best
        (in band first, then by J_S on the choosing data). Default: every structure (PE's ranking
        does not predict SE's: BENCHMARKS.md, honest selection). Refused (``ValueError``) unless the
        estimators hold a fast and a slow one.
    include : sequence of str
        Terms in every structure (default the constant, which eq. (22)-style static fits need;
        candidates without the constant need ``include=()``).
    fallback : {None, "min_jsf"}
        When no structure meets the band: None raises ``ValueError`` naming the smallest J_SF
        reached; ``"min_jsf"`` takes the structure with the smallest J_SF (the nearest B = [0, band],
        as :func:`graybox.decide_dsf`'s fallback takes the member nearest its band) and says so.
    centre : bool, optional
        Search the structures on centred signals (default False: on the raw ones): the searches run
        on the identification records' y and inputs minus their means, and each structure they find
        is replaced by its hierarchical closure (every divisor of every term, the constant included;
        for a black box, less a term the records cannot tell from its divisors, a two-level input's
        u(k-1)^2), which spans the same raw-signal models wherever the signals' zeros are; fits, scores and the
        choice are then on the raw records as always. A row's ``size`` counts the centred terms
        searched, its ``n_terms`` the closure's (and the static terms').
    executor : {"inprocess", "processes", "dask"}, optional
        Where the jobs (one per structure × estimator) run: default in the driver, or on Dask
        when ``workers``, ``client`` or ``scheduler`` is given. Worker processes are spawned and
        import the main module again: a script must call this under
        ``if __name__ == "__main__":`` (a notebook needs nothing).
    workers : int, optional
        Local worker processes (Dask ``LocalCluster``, or a process pool with ``"processes"``).
    client : distributed.Client, optional
        Run on this Dask client's cluster.
    scheduler : str, optional
        Run on the Dask scheduler at this address.
    progress : bool, optional
        A progress bar over the jobs (default: on a terminal, in the driver only).
    checkpoint : path, optional
        An ``.npz`` file that keeps each structure × estimator row's scores as it finishes (its
        folder must exist): a run killed and called again with it refits only the rows it did not
        finish, and gives the table an uninterrupted run gives. A row is reused only when its
        terms, estimator, options, data and splits and graybox's version are the same (a hash of
        them is its key), so one file may serve calls that differ: what changed is fitted (the
        band chooses among the rows and changes none: another B refits nothing; nor does another
        ``test=``, whose scores are remade from the kept rows' θ). The
        structure search is made again (seconds). Read without pickle; a file that is no such
        checkpoint is refused (``ValueError``) before anything runs. One call at a time per file:
        two running at once each rewrite it with their own rows (the file stays whole; the rows of
        the one that wrote first are fitted again next time).

    Returns
    -------
    GrayboxSelection
        The chosen structure and model, and the table of everything compared. Nothing is
        written to disk but the checkpoint, when one is given.

    Raises
    ------
    ValueError
        Candidates without a term of a cluster the static form needs; records shorter than the
        lags, or whose output's mean square lies too near an end of the float range (y near 1e-160
        or 1e154: rescale it); a test or validation record that is (or overlaps) a fitting record, or identification
        records that overlap each other; a band without static points;
        sizes beyond the candidates; no structure meeting the band (without ``fallback``); bad
        arguments.
    """
    sp = static_info(static, data, curves=True)
    no_requirement = isinstance(band, (float, np.floating)) and band == np.inf
    band = _band(band, sp)
    # read once: a generator is used up
    constraints = tuple(check_sequence(constraint_entries(constraints), "constraints",
                                       "a constraint, a table of them or a sequence"))
    estimators = _estimators(estimator, band, constraints)
    if band is None and (lambdas is not None or fallback is not None):
        # a black box has no front and no band to miss: said, not ignored
        why = ("band=inf asks for no static requirement; give a finite band B > 0 (output units²)" if no_requirement
               else "no band was given and the static points carry no uncertainty; give band= (and static points)")
        raise ValueError(f"{'lambdas' if lambdas is not None else 'fallback'} applies to a gray box (a band on J_SF), "
                         f"but this search is a black box ({', '.join(estimators)}): {why}, or drop it")
    sources = (sources,) if isinstance(sources, str) else check_sequence(sources, "sources")
    if sizes is not None:
        sizes = [check_int(s, "sizes", low=1) for s in check_sequence(sizes, "sizes")]
        if len(set(sizes)) != len(sizes):  # as sources and estimator: each named once (a typo, not a wish)
            raise ValueError(f"sizes must be distinct numbers of terms, got {sizes!r}")
    if include is _INCLUDE and isinstance(candidates, gb.Structure) and gb.Term(()) not in candidates.process:
        # not the caller's word: say which default the candidates refuse, and how to do without it
        raise ValueError("include defaults to the constant '1', which the candidates lack (Candidates(..., "
                         "constant=False)): pass include=() to search without it, or candidates with the constant")
    include = check_sequence(include, "include", ordered="terms (as the searches read them)")
    lam = None if lambdas is None else tuple(float(x) for x in check_lambdas(lambdas))
    folds, blocks = (None if v is None else check_int(v, k, low=2) for v, k in ((folds, "folds"), (blocks, "blocks")))
    if shortlist is not None:
        shortlist = check_int(shortlist, "shortlist", low=1)
        slow = [e for e in estimators if e in SLOW_ESTIMATORS]
        if not slow or len(slow) == len(estimators):
            raise ValueError(f"shortlist has nothing to do with estimator(s) {estimators}: it lets the fast "
                             f"estimators (PE, LS, ELS) choose the structures the slow ones {SLOW_ESTIMATORS} fit, "
                             "so name one of each (e.g. estimator=['pe', 'se-gradient']), or drop shortlist")
    check_cluster(client, scheduler)
    show_progress(progress)  # checked now, not after the structure search
    if executor is not None:
        check_choice(executor, "executor", ("inprocess", "processes", "dask"))
    if workers is not None:
        workers = check_workers(workers)  # 0 is no count of processes (it read as the default 2)
    if executor == "inprocess" and (workers is not None or client is not None or scheduler is not None):
        raise ValueError("workers, client and scheduler need executor='processes' or 'dask'")
    for s in sources:
        check_choice(s, "sources", SOURCES)
    if not sources or len(set(sources)) != len(sources):  # as estimator: each named once
        raise ValueError(f"sources must name one or more distinct sources of {SOURCES}, got {sources!r}")
    if fallback is not None:
        check_choice(fallback, "fallback", ("min_jsf",))
    check_choice(rule, "rule", RULES)
    centre = check_bool(centre, "centre")
    ck = checkpoint_of(checkpoint)  # read and checked before the search
    # band=inf, or black-box estimators named, ask for a black box; only the defaults leave it unannounced
    plan, form = _inputs(candidates, data, sp, validation, test, band, folds, blocks,
                         no_requirement or estimator is not None)
    constraints = _constraint_specs(constraints, plan.ident[0].input_names)
    rows = _structures(candidates, plan.ident, sizes, sources, include, form, centre)
    run = functools.partial(_run_jobs, executor=executor, workers=workers, client=client, scheduler=scheduler,
                            progress=progress, checkpoint=ck)
    fast = [e for e in estimators if e not in SLOW_ESTIMATORS]
    filters = tuple(warnings.filters)
    # on folds, each fold's structures are searched on its fit records alone (the held-out fold unseen)
    fold_terms = dict(zip((r["structure"] for r in rows), _fold_structures(rows, candidates, plan, sources, include,
                                                                           form, centre))) if plan.folds else {}

    def make_job(r: dict, e: str, per_fold: Mapping[str, tuple[str, ...]]) -> _Job:
        return _Job(r["structure"], r["terms"], e, plan, lam, constraints, filters, per_fold.get(r["structure"]))

    def score(per_fold: Mapping[str, tuple[str, ...]]) -> tuple[list[_Job], list[dict]]:
        jobs = [make_job(r, e, per_fold) for r in rows for e in fast]
        results = run(jobs)
        slow_rows = rows
        if fast and shortlist is not None and len(rows) > shortlist:
            # the slow fronts only for the structures the fast ones rank best (in band first)
            first, _, _ = _table(rows, jobs, results, plan)
            # in band first, then by J_S (out of band too: all rows there tied at inf went by their names)
            ranked = first.assign(_out=~first["in_band"].to_numpy(bool)).sort_values(["_out", "JS_valid"], kind="stable")
            keep = set(list(dict.fromkeys(ranked.index))[:shortlist])
            slow_rows = [r for r in rows if r["structure"] in keep]
        more = [make_job(r, e, per_fold) for r in slow_rows for e in estimators if e in SLOW_ESTIMATORS]
        return jobs + more, results + run(more)

    jobs, results = score(fold_terms)
    table, members, scores = _table(rows, jobs, results, plan)
    if fold_terms and not np.isfinite(table["JS_valid"].to_numpy(float)).any():
        again = score({})
        tabled = _table(rows, *again, plan)
        # only when those run: else no choice is made on them, and the rows' reasons stay those of the honest search
        if np.isfinite(tabled[0]["JS_valid"].to_numpy(float)).any():
            # the structures searched per fold never ran on their held-out folds: said, and chosen as before the
            # per-fold search (optimistic: the held-out folds then shaped the structures)
            warn("select_graybox: in every row, the structure searched on a fold's fit records has no finite free "
                 "run on its held-out fold; the choice is made on the structures searched on all the "
                 "identification data, fitted per fold (optimistic: those searches saw the held-out folds); a "
                 "validation record (a Dataset) gives an honest choice", SelectionWarning)
            (jobs, results), (table, members, scores) = again, tabled
    table["wanders"] = _wanders(jobs, results, members, plan)
    if table["in_band"].any():
        pos, used = _choose(table, scores, results[0]["weights"], rule)
        used_fallback = False
    else:
        pos, used = _fallback(table, results, band, fallback), "min"
        used_fallback = True
        warn(f"no structure meets the band B = {bound_text(band, table.iloc[pos]['JSF'])}: fallback 'min_jsf' chose {table.index[pos]} "
             f"({table.iloc[pos]['estimator']}), the smallest J_SF reached, {beside(table.iloc[pos]['JSF'], band)}",
             SelectionWarning)
    order = [pos] + [i for i in np.lexsort((table["JS_valid"].to_numpy(float), ~table["in_band"].to_numpy()))
                     if i != pos]
    table["rank"] = 0
    table.iloc[order, table.columns.get_loc("rank")] = np.arange(1, len(table) + 1)
    said = table["warnings"].to_numpy()
    if any(said):
        chosen = said[pos]
        warn(f"select_graybox: the fits of {sum(map(bool, said))} of {len(said)} structure × estimator rows warned "
             "(table['warnings'] says what); " +
             (f"the chosen row's: {chosen} (its fits used {table.iloc[pos]['estimator']}'s default options, which "
              "select_graybox does not change: to act on this, refit the chosen structure (.structure) with "
              f"{table.iloc[pos]['estimator']} and the options the warning names)" if chosen
              else "not the chosen row's"), SelectionWarning)
    failed = [r["failed"][0] for r in results if r["failed"]]
    if failed:
        what = "fits" if not plan.folds else "fits (or, on a fold, structure searches)"
        warn(f"select_graybox: the {what} of {len(failed)} of {len(results)} structure × estimator rows failed and "
             f"those rows were left out of the choice (table['reason'] says why), e.g. {failed[0]}", SelectionWarning)
    job, res, i = jobs[pos], results[pos], members[pos]
    structure = gb.parse_structure(job.terms)
    decision = _decision(table.iloc[pos], res, i, structure, plan, job.estimator, not used_fallback)
    table = table.sort_values("rank")
    long = ["terms", "theta"]  # long: last
    table = table[[c for c in table.columns if c not in long] + long]
    return GrayboxSelection(structure, decision.model, decision, table, None if form is None else form.degree, plan.band,
                            not used_fallback, used)


def _band(band: object, sp: gb.StaticPoints | gb.StaticCurve | gb.StaticSurface | None) -> float | None:
    """B for a gray box, None for a black box: ``band`` as given (inf: no static requirement, a black
    box), else the static points' own (:attr:`StaticPoints.band`, when they carry their uncertainty),
    as :func:`graybox.se_dsf` and :func:`graybox.bootstrap_decision` take it."""
    if isinstance(band, (float, np.floating)) and band == np.inf:
        return None
    if band is not None:
        try:
            return check_real(band, "band", low=0, low_open=True)
        except ValueError:  # check_real's "finite" would deny the inf this option takes
            raise ValueError(f"band must be a number B > 0 (J_SF's bound, output units²) or inf (no static "
                             f"requirement: a black box), got {band!r}") from None
    if isinstance(sp, gb.StaticPoints) and sp.uncertainty is not None:
        return sp.band
    return None


def _constraint_specs(constraints: tuple, input_names: tuple[str, ...]) -> tuple[dict, ...]:
    """The constraints as a grid's tables (what the jobs carry to any executor), checked once here: an
    object that is no constraint, or gain bounds for another number of inputs, would otherwise fail
    every row's fit and be said only after all of them."""
    try:
        specs = tuple(d for c in constraints for d in constraint_from_object(c))
        for d in specs:
            if d["type"] == "gain":
                build_constraint(d)._bounds(len(input_names), tuple(input_names))
    except ValueError as exc:
        raise ValueError(f"constraints: {exc}") from None
    return specs


def _estimators(estimator, band, constraints) -> list[str]:
    if estimator is None:
        estimator = BLACK_BOX_ESTIMATORS if band is None else (("pe",) if constraints else ("pe", "se-gradient"))
    estimators = [estimator] if isinstance(estimator, str) else check_sequence(estimator, "estimator")
    if not estimators or len(set(estimators)) != len(estimators):
        raise ValueError(f"estimator must name one or more distinct estimators, got {estimator!r}")
    for e in estimators:
        check_choice(e, "estimator", GRAY_BOX_ESTIMATORS + BLACK_BOX_ESTIMATORS)
    if band is None and any(e in GRAY_BOX_ESTIMATORS for e in estimators):
        raise ValueError(f"{', '.join(e for e in estimators if e in GRAY_BOX_ESTIMATORS)} trade(s) J_S against "
                         "J_SF within a band: give band= (and static points), or a black-box estimator "
                         f"{BLACK_BOX_ESTIMATORS}")
    if constraints and any(e != "pe" for e in estimators):
        raise ValueError(f"constraints are imposed by PE only; {', '.join(e for e in estimators if e != 'pe')} "
                         "cannot impose them: use estimator='pe' (the default with constraints) or drop the "
                         "constraints")
    return estimators


def _table(rows, jobs, results, plan) -> tuple[pd.DataFrame, list[int], list[np.ndarray]]:
    """One row per job: its member chosen on the choosing data and that member's figures."""
    by_name = {r["structure"]: r for r in rows}
    no_jsf = np.inf if plan.static is not None else np.nan  # a row without a model: no static error to speak of
    out, members, scores = [], [], []
    for job, res in zip(jobs, results):
        i, in_band = _member(res, plan.band)
        members.append(i)
        blk = res["blocks"][i] if i >= 0 else np.full(res["blocks"].shape[1], np.inf)
        scores.append(blk)
        js = float(blk @ res["weights"])
        row = dict({k: v for k, v in by_name[job.name].items() if not k.startswith("_")}, estimator=job.estimator,
                   lambda1=float(res["lambdas"][i]) if i >= 0 else np.nan,
                   JS_valid=js, JSF=float(res["jsf"][i]) if i >= 0 else no_jsf, in_band=bool(in_band and np.isfinite(js)))
        row["reason"] = _reason(res, i, in_band, js, plan.band)
        row["warnings"] = "; ".join(res["warnings"])
        row["failed_members"] = _failed_members(res)
        th = res["thetas"][i] if i >= 0 else np.full(1, np.nan)
        # exact decimal text (repr round-trips a float): a table saved to JSON or CSV keeps every row's model
        row["theta"] = " ".join(repr(float(v)) for v in th) if np.all(np.isfinite(th)) else ""
        if job.fold_terms is not None:  # the structures JS_valid scored: each fold's own search's, not ``terms``
            row["fold_terms"] = " | ".join(t or "(none)" for t in job.fold_terms)
        if plan.test is not None:
            row["JS_test"] = float(res["test"][i]) if i >= 0 else np.inf
            row["JSF_test"] = float(res["jsf_full"][i]) if i >= 0 else no_jsf
        out.append(row)
    table = pd.DataFrame(out).set_index("structure")
    return table, members, scores


def _member_failure(res: dict, k: int) -> str:
    """Why member ``k``'s fit failed, as its fit said (rows a checkpoint kept before the reasons were kept have none)."""
    return (res.get("member_failed") or [""] * (k + 1))[k] or "the fit failed at this λ"


def _failed_member_indices(res: dict) -> np.ndarray:
    """The members with no fit: on all the identification data (a NaN θ row) or on a fold (a reason kept, the full
    fit's θ finite)."""
    said_failed = np.array([bool(r) for r in res.get("member_failed", ())] or [False] * len(res["thetas"]))
    return np.flatnonzero(~np.all(np.isfinite(res["thetas"]), axis=1) | said_failed)


def _failed_members(res: dict) -> str:
    """Which of a row's λ1 members have no fit (on all the identification data, or on a fold) and why, each
    distinct reason once (empty when none; a row whose fit failed whole says so in its ``reason``)."""
    bad = _failed_member_indices(res)
    if not bad.size or res["failed"]:
        return ""
    lam = np.asarray(res["lambdas"], float)
    groups: dict[str, list[int]] = {}  # reason -> its members
    for k in bad:
        groups.setdefault(_member_failure(res, k), []).append(int(k))

    def lambdas(members: list[int]) -> str:
        return "λ1 = " + ", ".join(f"{v:g}" for v in lam[members])

    said = (next(iter(groups)) if len(groups) == 1 else
            "; ".join(f"{lambdas(members)}: {reason}" for reason, members in groups.items()))
    return f"{bad.size} of {lam.size} ({lambdas(list(bad))}): {said}"


def _reason(res: dict, i: int, in_band: bool, js: float, band: float | None) -> str:
    """Why a row has no qualifying model (empty when it has one): every member failed or diverged,
    or the band was missed, with the smallest J_SF its members reached."""
    finite = np.isfinite(res["blocks"]).all(axis=1)
    if not finite.any():
        if res["failed"]:
            return "every member failed: " + "; ".join(res["failed"])
        bad = _failed_member_indices(res)  # a member failing on a fold only did not diverge
        said = "; ".join(dict.fromkeys(_member_failure(res, k) for k in bad))  # each distinct reason once
        if bad.size == len(finite):
            return f"every member's fit failed: {said}"
        return (f"every member failed or diverged on the choosing data ({bad.size} of {len(finite)} fits failed"
                + (f": {said}" if bad.size else "") + "; the others' free runs diverged)")
    if i < 0 or not np.isfinite(js):
        return "no member has a finite free-run J_S on every block of the choosing data"
    if band is not None and not in_band:
        jsf = res["jsf"][finite]
        best = float(jsf[np.isfinite(jsf)].min()) if np.isfinite(jsf).any() else np.inf
        return f"no member meets the band B = {bound_text(band, best)}: the smallest J_SF reached is {beside(best, band)}"
    return ""


def _fallback(table: pd.DataFrame, results: list[dict], band: float | None, fallback: str | None) -> int:
    if not np.isfinite(table["JS_valid"].to_numpy(float)).any():
        row = table.iloc[0]
        raise ValueError(f"no structure has a finite free-run J_S on the choosing data (over {len(table)} structure × "
                         f"estimator rows), e.g. {row.name} by {row['estimator']}: {row['reason']}")
    # the smallest static error reached by any member of any structure, among the members the rows count (a finite
    # free-run J_S on every block of the choosing data, as _reason says it per row)
    counted = [r["jsf"][np.isfinite(r["blocks"]).all(axis=1)] for r in results]
    finite = [j[np.isfinite(j)] for j in counted]
    best = min((float(f.min()) for f in finite if f.size), default=np.inf)
    if fallback is None:
        raise ValueError(f"no structure meets the band B = {bound_text(band, best)}: the smallest J_SF reached is {beside(best, band)} "
                         f"(over {len(table)} structure × estimator rows); widen the band, change the candidates, "
                         "or pass fallback='min_jsf'")
    jsf = table["JSF"].to_numpy(float)
    if not np.isfinite(jsf).any():
        raise ValueError("fallback 'min_jsf': no structure has a defined static curve (J_SF = inf everywhere)")
    return int(np.nanargmin(np.where(_steady(table, np.isfinite(jsf)), jsf, np.nan)))
