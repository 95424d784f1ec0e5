"""Gray-box structure selection: choose the terms with the static information and the free run.

:func:`select_graybox` makes a family of candidate structures, gives each one what the static
information needs, fits every structure's gray-box front through the experiment layer (in the
driver, in local processes or on a Dask cluster) and picks by D_SF on validation data:

1. **structures** — for each size in ``sizes``, the best structure of that size on the SEMP path
   (:func:`graybox.semp`: simulation error with pruning) and the FROLS structure of that size;
2. **static form** — the degree d the static information asks for (:func:`static_degree`: the
   smallest polynomial fitting the static points within the band), and for each structure the
   simplest candidates of the clusters Σ_{u^0} … Σ_{u^d}, Σ_y it lacks (:func:`static_terms`);
3. **scoring** — every structure × each gray-box estimator (PE closed form by default, or SE), one
   grid cell per structure and validation fold; each cell's Pareto members are scored on the
   validation record, and a structure's score is D_SF on validation: the smallest validation J_S
   among its members with J_SF ≤ B (averaged over folds);
4. **choice** — the structure with the smallest score among those that meet the band, refitted on
   all the identification data, its member chosen by D_SF on the validation record (with folds: on
   the identification record).

Validation data: the Dataset's validation record, or — when there is only one record — k folds of
contiguous segments of it (each fold validates on one segment and identifies on the others, which
are joined: the max-lag samples after a joint are a short transient of the identification data).
"""

from __future__ import annotations

import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from .. import _api as gb

from ..io._json import register_type
from ..static._form_check import static_degree, static_fit_mse, static_terms
from ..core._validation import check_choice, check_int, check_real
from ._report import leaderboard
from ._run import run_grid
from ._cell import cell_constraints
from ._spec import DataSpec, DecisionRule, Grid, StructureSpec, Variant, constraint_entries, constraint_from_object
from ._store import load_results

__all__ = ["select_graybox", "GrayboxSelection"]


@dataclass(frozen=True, eq=False)
class GrayboxSelection:
    """The result of :func:`select_graybox`.

    Attributes
    ----------
    structure : Structure
        The chosen structure (static-form terms included).
    model : Model
        Its gray-box model, refitted on all the identification data and chosen by D_SF.
    decision : Decision
        How that member was chosen from its Pareto set.
    table : pandas.DataFrame
        Everything tried, one row per structure and estimator: ``structure`` (name), ``source``
        (semp / frols), ``size`` (terms before the static terms), ``n_terms``, ``added`` (static-form
        terms added), ``estimator``, ``JS_valid`` (D_SF on validation, mean over folds), ``JSF`` (its static error, worst fold),
        ``in_band`` (the band met in every fold), ``rank``, ``reason`` (why a structure has no
        qualifying model: the smallest J_SF reached, the sample where a free run diverged, the
        error of a failed cell; empty when it qualified).
    degree : int
        Degree of the static curve the static information asks for.
    band : float
        B (output units²).
    in_band : bool
        Whether the chosen structure met the band (the name :class:`Decision` and
        :class:`DSFResult` use); False when none did and ``fallback="min_jsf"`` chose the
        smallest J_SF.
    store : str
        The SQLite store holding every cell (kept: the fronts can be drawn from it later).
    """

    structure: gb.Structure
    model: gb.Model
    decision: gb.Decision
    table: pd.DataFrame
    degree: int
    band: float
    in_band: bool
    store: str

    #: Columns every table holds (a loaded file is checked against them).
    TABLE_COLUMNS = ("source", "size", "n_terms", "added", "estimator", "JS_valid", "JSF", "in_band", "rank")

    def __post_init__(self) -> None:
        if not isinstance(self.table, pd.DataFrame):
            raise ValueError(f"table must be a DataFrame, got {type(self.table).__name__}")
        missing = [c for c in self.TABLE_COLUMNS if c not in self.table.columns]
        if missing:
            raise ValueError(f"the table lacks the column(s) {missing}")
        if list(self.model.structure) != list(self.structure):
            raise ValueError("the model's structure is not the chosen structure")
        check_real(self.band, "band", low=0, low_open=True)

    def __repr__(self) -> str:
        return (f"GrayboxSelection(n_terms={len(self.structure)}, structures tried={len(self.table)}, "
                f"JS_valid={self.table['JS_valid'].min():.4g}, in_band={self.in_band})")


register_type("GrayboxSelection", GrayboxSelection,
              (("structure", "structure"), ("model", "Model"), ("decision", "Decision"), ("table", "frame"),
               ("degree", "int"), ("band", "float"), ("in_band", "bool"), ("store", "str")))


def _folds(record: gb.Record, k: int, min_len: int) -> list[tuple[gb.Record, gb.Record]]:
    n = len(record)
    edges = np.linspace(0, n, k + 1).astype(int)
    out = []
    for i in range(k):
        a, b = edges[i], edges[i + 1]
        if b - a < min_len or n - (b - a) < min_len:
            raise ValueError(f"fold {i + 1} of {k}: segments of {b - a} samples are too short for the candidates' "
                             f"largest lag {min_len - 1}; use fewer folds or a validation record")
        valid = record.slice(a, b, name=f"{record.name} fold {i + 1} valid")
        ident = gb.Record(np.r_[record.u[:a], record.u[b:]], np.r_[record.y[:a], record.y[b:]], record.Ts,
                          f"{record.name} fold {i + 1} ident", record.units, record.input_names)
        out.append((ident, valid))
    return out


def select_graybox(
    candidates: gb.Structure,
    data: gb.Dataset | gb.Record,
    static: gb.StaticPoints | gb.StaticCurve | gb.StaticSurface | None = None,
    *,
    band: float,
    sizes: Sequence[int] | None = None,
    sources: Sequence[str] = ("semp", "frols"),
    estimator: str | Sequence[str] | None = None,
    constraints: Any = (),
    lambdas: Sequence[float] | None = None,
    validation: gb.Record | None = None,
    folds: int = 3,
    include: Sequence[str] = ("1",),
    fallback: str | None = None,
    store: str | os.PathLike | None = None,
    executor: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool | None = None,
) -> GrayboxSelection:
    """Choose a structure for gray-box use by its D_SF model on validation data.

    Parameters
    ----------
    candidates : Structure
        Candidate terms (noise terms are ignored), e.g. ``Candidates(6, 6, degree=2, max_y_power=1)``.
    data : Dataset or Record
        A Dataset brings the identification and validation records and the static points; a
        Record is identification data only (validation by ``folds``).
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static information (default: the Dataset's points). A curve is sampled at 10 points of
        its domain for the cells, a surface (several inputs) on a grid of 6 points per input over
        its domain.
    band : float
        B: the bound on J_SF (output units²), the static measurements' uncertainty.
    sizes : sequence of int, optional
        Structure sizes (before the static terms); default 4, 6, …, up to min(20, candidates).
    sources : sequence of {"semp", "frols"}
        Where the structures of each size come from.
    estimator : {"pe", "se-gradient", "se-ga"} or a sequence of them, optional
        The gray-box front of each structure (PE uses the closed form unless constraints need a QP).
        With several, every structure is scored with each, and the best (structure, estimator) pair
        wins. Default: PE and the SE gradient method (where the static and the dynamic data
        disagree they choose differently, and either can be the better one — BENCHMARKS.md,
        structure selection); with ``constraints``, PE alone, the one that imposes them.
    constraints : optional
        Constraint objects or tables imposed in every cell, as in :class:`Variant`. Only PE
        imposes them: naming an SE estimator with constraints is an error.
    lambdas : sequence of float, optional
        λ1 of each front (default: PE 100 in logspace(-6, 0), the closed form; SE 10 in
        logspace(-2, 0), a coarse front is enough to rank structures).
    validation : Record, optional
        Validation record (default: the Dataset's).
    folds : int
        Contiguous folds when there is no validation record (>= 2).
    include : sequence of str
        Terms in every structure (default the constant, which eq. (22)-style static fits need).
    fallback : {None, "min_jsf"}
        When no structure meets the band: None raises ``ValueError`` naming the smallest J_SF
        reached; ``"min_jsf"`` takes the structure with the smallest J_SF and says so.
    store : path, optional
        SQLite store of the cells (default: a new file in a temporary folder, kept).
    executor, workers, client, scheduler, progress
        Where the cells run, as for :func:`run_grid` (default: in the driver).

    Returns
    -------
    GrayboxSelection
        The chosen structure and model, and the table of everything tried.

    Raises
    ------
    ValueError
        Candidates that cannot represent the static curve's form; validation data shorter than
        the lags; no structure meeting the band (without ``fallback``); bad arguments.
    """
    if not isinstance(candidates, gb.Structure):
        raise ValueError(f"candidates must be a Structure, got {type(candidates).__name__}")
    process = candidates.process
    band = check_real(band, "band", low=0, low_open=True)
    constraints = tuple(constraint_entries(constraints))  # read once: a generator is used up
    if estimator is None:
        estimator = ("pe",) if constraints else ("pe", "se-gradient")
    estimators = [estimator] if isinstance(estimator, str) else list(estimator)
    if not estimators or len(set(estimators)) != len(estimators):
        raise ValueError(f"estimator must name one or more distinct estimators, got {estimator!r}")
    for e in estimators:
        check_choice(e, "estimator", ("pe", "se-gradient", "se-ga"))
    if constraints and any(e != "pe" for e in estimators):
        raise ValueError(f"constraints are imposed by PE only; {', '.join(e for e in estimators if e != 'pe')} "
                         "cannot impose them: use estimator='pe' (the default with constraints) or drop the "
                         "constraints")
    for s in sources:
        check_choice(s, "sources", ("semp", "frols"))
    if not sources:
        raise ValueError("sources must name at least one of 'semp', 'frols'")
    if fallback is not None:
        check_choice(fallback, "fallback", ("min_jsf",))
    extra: dict = {}
    if isinstance(data, gb.Dataset):
        ident = data.ident
        valid = validation if validation is not None else data.valid
        sp = static if static is not None else data.static
        extra = dict(data.extra)  # e.g. the curve of an equality with curve="dataset"
    elif isinstance(data, gb.Record):
        ident, valid, sp = data, validation, static
    else:
        raise ValueError(f"data must be a Dataset or a Record, got {type(data).__name__}")
    if sp is None:
        raise ValueError("select_graybox needs static information: pass static= or a Dataset with static points")
    if isinstance(sp, (gb.StaticCurve, gb.StaticSurface)):
        if sp.domain is None:
            raise ValueError(f"a {type(sp).__name__} without a domain cannot be sampled: give static points")
        degree = sp.degree
        if isinstance(sp, gb.StaticCurve):
            sp = sp.points(np.linspace(*sp.domain, 10))
        else:  # a grid over the surface's box, 6 points per input
            axes = [np.linspace(lo, hi, 6) for lo, hi in sp.domain]
            sp = sp.points(np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1))
    else:
        degree = static_degree(sp, band=band)
        if static_fit_mse(sp, degree) > band:
            # no polynomial fits the points within the band: their form is not known, so ask only
            # what the candidates can carry (the band is then out of reach, which step 4 reports)
            degree = min(degree, max((t.input_power for t in process if t.power_of("y") == 0), default=0))
    L = process.max_lag
    if valid is not None:
        valid.require_length(L)
        if len(valid) <= L + 1:
            raise ValueError(f"the validation record ({len(valid)} samples) is shorter than the candidates' lags + 2")
        splits = [(ident, valid)]
    else:
        splits = _folds(ident, check_int(folds, "folds", low=2), L + 2)
    k_max = min(20, len(process))
    sizes = list(range(4, k_max + 1, 2)) if sizes is None else [check_int(s, "sizes", low=1, high=len(process))
                                                                 for s in sizes]
    forced = list(include)
    # -- the candidate structures -------------------------------------------------------------
    found: dict[tuple, dict] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        if "semp" in sources:
            res = gb.semp(candidates, ident, n_terms=max(sizes), include=forced)
            path = res.path
            for k in sizes:
                same = path[path["n_terms"] == k]
                if len(same):
                    best = same.loc[same["score"].idxmin()]
                    found.setdefault(("semp", k), {"terms": best["structure"].split(" + ")})
        if "frols" in sources:
            sel = gb.frols(candidates, ident, n_terms=max(sizes), include=forced)
            for k in sizes:
                found.setdefault(("frols", k), {"terms": [str(t) for t in sel.structure[:k]]})
    structs, rows, seen = [], [], {}
    for (src, k), v in found.items():
        st = gb.Structure(v["terms"])
        added = static_terms(st, process, degree)
        st = st + gb.Structure(added)
        key = frozenset(st)
        if key in seen:
            rows[seen[key]]["source"] += f", {src}"
            continue
        name = f"{src}-{k}"
        seen[key] = len(rows)
        structs.append(StructureSpec(name, terms=[str(t) for t in st]))
        rows.append({"structure": name, "source": src, "size": k, "n_terms": len(st),
                     "added": ", ".join(map(str, added)), "terms": str(st)})
    # -- one grid cell per structure × fold ------------------------------------------------------
    data_specs = [DataSpec(f"fold{i + 1}" if len(splits) > 1 else "data",
                           dataset=gb.Dataset(a, b, sp, description="select_graybox", extra=extra), band=band)
                  for i, (a, b) in enumerate(splits)]
    variants = [Variant(e, e, constraints=constraints, lambdas=_lambdas(e, lambdas),
                        decision=DecisionRule("dsf", band=band, fallback="min_jsf"),
                        options={"solver": "closed"} if e == "pe" and not constraints else {})
                for e in estimators]
    grid = Grid(data_specs, structs, variants, name="select_graybox")
    if store is None:
        store = Path(tempfile.mkdtemp(prefix="graybox-select-")) / "cells.sqlite"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        run_grid(grid, store, executor=executor, workers=workers, client=client, scheduler=scheduler,
                 progress=progress)
    results = load_results(store)
    board = leaderboard(results, rule="dsf_valid", band=band).reset_index()
    per = board.groupby(["structure", "variant"]).agg(JS_valid=("JS_valid", "mean"), JSF=("JSF", "max"),
                                                      in_band=("in_band", "all"),
                                                      reason=("reason", _reasons)).reset_index()
    per = per.rename(columns={"variant": "estimator"})
    table = pd.DataFrame(rows).merge(per, on="structure", how="left")
    table["estimator"] = table["estimator"].fillna(estimators[0])
    table = table.set_index("structure")
    table["in_band"] = table["in_band"].fillna(False).astype(bool) & np.isfinite(table["JS_valid"])
    table["reason"] = table["reason"].fillna("no cell of this structure is in the store")
    ok = table[table["in_band"]]
    used_fallback = False
    if len(ok):
        chosen = ok["JS_valid"].astype(float).to_numpy().argmin()
        chosen_row = ok.iloc[chosen]
    else:
        # the smallest static error reached by any member of any structure, from the stored fronts
        best_jsf = _smallest_jsf(results)
        if fallback is None:
            raise ValueError(f"no structure meets the band B = {band:g}: the smallest J_SF reached is {best_jsf:.4g} "
                             f"(over {len(table)} structures); widen the band, change the candidates, or pass "
                             "fallback='min_jsf'")
        jsf = table["JSF"].astype(float).to_numpy()
        chosen_row = table.iloc[int(np.nanargmin(jsf)) if np.isfinite(jsf).any() else 0]
        used_fallback = True
    table = table.sort_values(["in_band", "JS_valid"], ascending=[False, True])
    table["rank"] = np.arange(1, len(table) + 1)
    structure = gb.Structure(chosen_row["terms"].split(" + "))
    # -- the chosen structure refitted on all the identification data ------------------------
    est = chosen_row["estimator"]
    decision = _refit(structure, ident, valid, sp, band, est, constraints, _lambdas(est, lambdas), used_fallback,
                      extra)
    return GrayboxSelection(structure, decision.model, decision, table.drop(columns=["terms"]), degree, band,
                            not used_fallback, str(store))


def _reasons(r: pd.Series) -> str:
    """The leaderboard's reasons of a structure's folds, each once (empty: every fold qualified)."""
    return "; ".join(dict.fromkeys(x for x in r if isinstance(x, str) and x))


def _lambdas(estimator: str, lambdas: Sequence[float] | None) -> list[float] | None:
    if lambdas is None and estimator.startswith("se"):
        return list(np.logspace(-2, 0, 10))
    return None if lambdas is None else list(lambdas)


def _smallest_jsf(results: pd.DataFrame) -> float:
    best = float(results["JSF"].astype(float).min()) if len(results) else np.inf
    for m in results["members"]:
        v = np.asarray((m or {}).get("JSF", []), float)
        if np.isfinite(v).any():
            best = min(best, float(np.nanmin(np.where(np.isfinite(v), v, np.nan))))
    return best


def _refit(structure, ident, valid, sp, band, estimator, constraints, lambdas, fallback, extra) -> gb.Decision:
    specs = sum((constraint_from_object(c) for c in constraints), [])
    # only the static points and the data set's extra matter to the constraints
    cons = cell_constraints(specs, structure, gb.Dataset(ident, ident if valid is None else valid, sp, extra=extra))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        if estimator == "pe":
            front = gb.pe_pareto(structure, ident, sp, lambdas=lambdas, constraints=cons or None,
                                 solver="clarabel" if cons else "closed")
        else:
            front = gb.se_pareto(structure, ident, sp, lambdas=lambdas, method="gradient" if estimator == "se-gradient" else "ga")
    if valid is None or fallback:
        return gb.decide_dsf(front, band=band, fallback="min_jsf")
    # D_SF on the validation record: the members' validation J_S
    js_valid = gb.evaluate_thetas(structure, front.thetas, valid, one_step=False)["JS"]
    scored = gb.ParetoSet(front.structure, front.thetas, front.lambdas, front.J1, js_valid, front.JSF,
                          f"{front.method}, J_S on validation", dict(front.extra), dict(front.failures))
    return gb.decide_dsf(scored, band=band, fallback="min_jsf")
