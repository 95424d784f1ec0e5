"""Reports of a grid: leaderboard, heat map, scatter and fronts (DataFrames and matplotlib Figures).

Every function takes the results as a DataFrame from :func:`graybox.load_results` (or the path
of a store). Figures are built with :class:`matplotlib.figure.Figure` directly, as in
:mod:`graybox.plots` (no pyplot state).

Ranking rules (``rule``):

- ``"dsf_valid"`` (default): D_SF judged on the *validation* record — among every candidate of
  a (data, structure, variant) (all Pareto members of all its cells, or the single model of a
  one-model estimator) whose J_SF lies in the band, the one with the smallest J_S on the
  validation record;
- ``"chosen"``: the model each cell's own decision maker chose, the smallest validation J_S
  over seeds (cells that are not ``ok`` are left out).
"""

from __future__ import annotations

import io
import os
import re
import shlex
import textwrap
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.ticker import LogLocator, MaxNLocator, NullFormatter, ScalarFormatter
from matplotlib.figure import Figure

from ..plots._data import distinct_colours
from ..core._reprs import apart_digits, beside, bound_text, level_texts, squared_unit
from ..core._validation import (FrozenFrame, FrozenMap, check_bool, check_choice, check_fields, check_int, check_path,
                                check_real, check_sequence, check_str)
from ._cell import STATUSES
from ._store import compare_results, encode_value, held_text, load_results, output_units, running_cells

__all__ = ["RULES", "GridStatus", "grid_status", "leaderboard", "heatmap_table", "plot_scatter", "plot_fronts", "plot_heatmap", "write_report"]

#: Ranking rules of :func:`leaderboard`.
RULES = ("dsf_valid", "chosen")
_KEYS = ["data", "structure", "variant"]
#: Validation J_S values this close (relative to the smaller) are one result: the same model fitted twice (least
#: squares and an unconstrained CLS, two solvers) scores J_S apart by round-off (1e-12 relative), no difference of
#: the models; the leaderboard gives them one rank.
_JS_TIE_RTOL = 1e-8
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "<", ">", "h", "p")


#: The columns of :func:`graybox.load_results` the reports read.
_RESULT_COLUMNS = (*_KEYS, "seed", "status", "message", "terms", "n_params", "lambda1", "band", "JS_ident", "JS_valid",
                   "fit_valid", "JSF", "members")


def _frame(results: pd.DataFrame | str | os.PathLike | Sequence, spec: str | int = "latest",
           attrs: bool = False) -> pd.DataFrame:
    """The results as a frame; without its ``attrs`` unless asked (pandas deep-copies them on every
    operation, and a store's specs made that the larger part of a leaderboard's time)."""
    if isinstance(results, pd.DataFrame):
        missing = set(_RESULT_COLUMNS) - set(results.columns)
        if missing:
            raise ValueError(f"results must come from graybox.load_results; missing columns {sorted(missing)}")
        df = results
    elif isinstance(results, (list, tuple)):
        df = compare_results(results, spec=spec)
    elif isinstance(results, (str, os.PathLike)):
        df = load_results(results, spec=spec)
    else:
        raise TypeError(f"results must be a frame from graybox.load_results, a store's path or a list of paths, got "
                        f"{results!r} ({type(results).__name__})")
    if attrs or not df.attrs:
        return df
    bare = df.copy(deep=False)
    units = output_units(df.attrs)
    bare.attrs = {"y_units": units} if units else {}  # a few names: the figures' and the summary's units
    return bare


def _sq(df: pd.DataFrame, data: str) -> str:
    """`` (unit²)`` of data set ``data``'s output (J_S, J_SF and B are mean squares of it), or empty."""
    unit = df.attrs.get("y_units", {}).get(data, "")
    sq = squared_unit(unit).strip()  # "(m/s)²", not "m/s²" (an acceleration)
    return f" ({sq})" if sq else ""


def _n_params(df: pd.DataFrame) -> pd.Series:
    """N_p of every cell, also of a Pareto cell that a store of the first format kept without it
    (its members share the structure: N_p = the number of its terms)."""
    n = df["n_params"].copy()
    gap = n.isna() & df["members"].map(lambda m: isinstance(m, Mapping)) & df["terms"].map(lambda t: t is not None)
    if gap.any():
        n[gap] = [len(t) for t in df.loc[gap, "terms"]]
    return n


def _short(text: object, n: int = 160) -> str:
    t = " ".join(str(text).split())
    return t if len(t) <= n else t[: n - 1] + "…"


def _cell_reasons(status: np.ndarray, message: np.ndarray, brief: Sequence[str] = ()) -> list[str]:
    """Why cells of a group are not ok (their ``status`` and ``message`` arrays): their count and first
    messages per status (only the count for the statuses in ``brief``, whose reason is already said)."""
    out = []
    for st in STATUSES[1:]:
        bad = status == st
        if bad.any() and st in brief:
            out.append(f"{int(bad.sum())} {st}")
        elif bad.any():
            msgs = list(dict.fromkeys(_short(m) for m in message[bad] if isinstance(m, str) and m))
            out.append(f"{int(bad.sum())} {st}: " + ("; ".join(msgs[:2]) if msgs else "no message stored"))
    return out


def _checked_options(rule: str = RULES[0], band: float | Mapping[str, float] | None = None,
                     data: str | None = None, value: str = "JS_valid") -> float | Mapping[str, float] | None:
    """The report functions' shared options checked where they are given; the band in canonical
    form (a number B > 0, output units², or a mapping data set name -> B)."""
    check_choice(rule, "rule", RULES)
    if data is not None and not isinstance(data, str):
        raise TypeError(f"data must be a data set's name (str), got {data!r} ({type(data).__name__})")
    if not isinstance(value, str):
        raise TypeError(f"value must be a leaderboard column's name (str), got {value!r} ({type(value).__name__})")
    if isinstance(band, Mapping):
        return {k: check_real(b, f"band[{k!r}]", low=0, low_open=True) for k, b in band.items()}
    return None if band is None else check_real(band, "band", low=0, low_open=True)


def _known_bands(band: float | Mapping[str, float] | None, df: pd.DataFrame) -> None:
    """``ValueError`` when a mapping of bands names a data set the results do not hold (a typo would leave
    the data set meant to the store's own band, without a word)."""
    if isinstance(band, Mapping):
        held = list(dict.fromkeys(df["data"]))
        unknown = [k for k in band if k not in held]
        if unknown:
            raise ValueError(f"band names data sets the results do not hold: {', '.join(map(repr, unknown))} "
                             f"(they hold {', '.join(map(repr, held)) or 'none'})")


def _given_band(band: float | Mapping[str, float] | None, data: str) -> float | None:
    """The band given for data set ``data``: one number for all, a mapping's entry, or None (a mapping that does not
    name it leaves it, as no band given does, to the band its cells stored)."""
    if isinstance(band, Mapping):
        return float(band[data]) if data in band else None
    return None if band is None else float(band)


def _band_of(rows: pd.DataFrame | np.ndarray, band: float | Mapping[str, float] | None, data: str) -> float:
    """J_SF's bound for ``rows`` of data set ``data`` (a frame, or their stored bands): ``band``'s, else the first
    band stored on the rows (the leaderboard judges each cell's members by the band stored on their own cell, this
    one where a cell stored none)."""
    given = _given_band(band, data)
    if given is not None:
        return given
    b = np.asarray(rows["band"] if isinstance(rows, pd.DataFrame) else rows, dtype=float)
    b = b[~np.isnan(b)]
    if not b.size:
        raise ValueError(f"data set {data!r} has no band in the store (its static points carry no uncertainty, and "
                         "the spec gave it none): pass band=B, J_SF's bound in output units² (graybox grid report "
                         f"--band B), or band={{{data!r}: B}} (--band {shlex.quote(data + '=B')}) to leave the other data sets "
                         "to their own, or rank each cell's own choice with rule='chosen' (--rule chosen)")
    return float(b[0])


_CANDIDATE_COLUMNS = (*_KEYS, "seed", "lambda1", "JS_ident", "JS_valid", "JSF", "fit_valid", "n_params", "chosen",
                      "status", "failure", "band")


def _chosen_members(m: Mapping, lam: np.ndarray, chosen_lambda: float) -> np.ndarray:
    """Which of a cell's members its decision chose: the member the cell marked (``m["chosen"]``), else, in a store
    written before cells marked it, the member whose λ is the chosen λ exactly (the store keeps both as written; a
    tolerance marked a neighbour of close λ chosen too)."""
    if "chosen" in m:
        return np.asarray(m["chosen"], float) == 1.0
    return lam == chosen_lambda if pd.notna(chosen_lambda) else np.zeros(lam.size, bool)


def _candidates(g: pd.DataFrame) -> pd.DataFrame:
    """Every model of the cells of ``g`` (its (data, structure, variant) in the first columns; ``n_params``
    completed by :func:`_n_params`): Pareto members and single models (one frame built from columns, in one pass
    over every cell: a frame per row, or per group, made the leaderboard's time)."""
    cols: dict[str, list] = {k: [] for k in _CANDIDATE_COLUMNS}
    for r in g[[*_KEYS, "members", "lambda1", "seed", "status", "JS_ident", "JS_valid", "JSF", "fit_valid",
                "n_params", "band"]].itertuples(index=False):
        m, n_p = r.members, r.n_params
        if isinstance(m, Mapping) and len(m.get("JSF", ())):
            K = len(m["JSF"])
            lam = np.asarray(m["lambda1"], float)
            parts = {"seed": [r.seed] * K, "lambda1": lam, "JS_ident": m["JS"], "JS_valid": m["JS_valid"],
                     "JSF": m["JSF"], "fit_valid": m.get("fit_valid", np.full(K, np.nan)), "n_params": [n_p] * K,
                     "chosen": _chosen_members(m, lam, r.lambda1),
                     "status": [r.status] * K, "failure": list(m.get("failure", [""] * K))}
        elif r.status == "ok":
            K = 1
            parts = {"seed": [r.seed], "lambda1": [np.nan], "JS_ident": [r.JS_ident], "JS_valid": [r.JS_valid],
                     "JSF": [r.JSF], "fit_valid": [r.fit_valid], "n_params": [n_p], "chosen": [True],
                     "status": [r.status], "failure": [""]}
        else:
            continue
        # the band stored on the cell: read with spec="all", one group's cells may hold two specs' bands
        parts.update(data=[r.data] * K, structure=[r.structure] * K, variant=[r.variant] * K, band=[r.band] * K)
        for k, v in parts.items():
            cols[k].extend(np.asarray(v).tolist() if isinstance(v, np.ndarray) else v)
    out = pd.DataFrame(cols, columns=list(_CANDIDATE_COLUMNS))
    for k in ("lambda1", "JS_ident", "JS_valid", "JSF", "fit_valid", "band"):
        out[k] = out[k].astype(float)
    return out


class _Columns:
    """Columns of a frame as numpy arrays, and each (data, structure, variant) group's row positions: the
    reasons of many groups read without a pandas operation per group."""

    def __init__(self, frame: pd.DataFrame, names: Sequence[str]):
        self.col = {k: frame[k].to_numpy() for k in names}
        self.at = {k: np.asarray(v) for k, v in frame.groupby(_KEYS, sort=False).indices.items()} if len(frame) else {}

    def of(self, key: tuple, name: str) -> np.ndarray:
        return self.col[name][self.at.get(key, np.zeros(0, int))]


def _no_model_reason(key: tuple, cells: _Columns, members: _Columns | None, b: float | None, n: int) -> str:
    """Why no model of the (data, structure, variant) ``key`` qualified (``n`` models compared, band ``b``;
    ``members``: every member's columns, None for the rule "chosen")."""
    why: list[str] = []
    if members is not None:
        failure = members.of(key, "failure")
        failed = failure != ""
        failures = list(dict.fromkeys(_short(f) for f in failure[failed]))
        jsf = members.of(key, "JSF").astype(float)[~failed]
        # each member's own cell's band (cells of two specs' bands read together), else the group's
        bs = members.of(key, "band").astype(float)[~failed] if "band" in members.col else np.full(jsf.size, b)
        several = np.unique(bs).size > 1
        inside = jsf <= bs
        if n:
            finite = np.isfinite(jsf)
            if inside.any():
                within = (f"its cell's B ({', '.join(f'{x:g}' for x in np.unique(bs[inside]))})" if several else
                          f"B = {bs[inside][0]:g}")
                why.append(f"every one of the {int(inside.sum())} model(s) with J_SF ≤ {within} diverges on the "
                           "validation record")
            elif finite.any():
                i = int(np.flatnonzero(finite)[np.argmin(jsf[finite])])
                lam1, seed = members.of(key, "lambda1")[~failed][i], members.of(key, "seed")[~failed][i]
                lam = f", λ1 = {lam1:.3g}" if pd.notna(lam1) else ""
                seed = f", seed {int(seed)}" if pd.notna(seed) else ""
                bi = float(bs[i])
                if several:  # the cells' bands differ: each member was judged by its own cell's
                    why.append(f"no model has J_SF within its cell's band (B = {', '.join(f'{x:g}' for x in np.unique(bs))}): "
                               f"the smallest J_SF reached is {beside(jsf[i], bi)}, its cell's B = {bound_text(bi, jsf[i])}"
                               f"{lam}{seed} ({n} model(s) compared)")
                else:
                    why.append(f"no model has J_SF ≤ B = {bound_text(bi, jsf[i])}: the smallest J_SF reached is "
                               f"{beside(jsf[i], bi)}{lam}{seed} ({n} model(s) compared)")
            else:
                why.append(f"every one of the {n} model(s) has an undefined static curve (J_SF = inf)")
        if failures:
            why.append(f"{int(failed.sum())} member fit(s) failed: " + "; ".join(failures[:2]))
    elif n:
        why.append(f"the chosen model of every one of the {n} ok cell(s) has no finite J_S on the validation record "
                   "(it diverges there)")
    # an infeasible cell whose members were judged above: its own D_SF said the same
    why += _cell_reasons(cells.of(key, "status"), cells.of(key, "message"), brief=("infeasible",) if why and n else ())
    return "; ".join(why) or ("no cell is ok" if members is None else "no model qualified")


def leaderboard(
    results: pd.DataFrame | str | os.PathLike,
    *,
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """The best model of every (data, structure, variant), ranked within each data set.

    Parameters
    ----------
    results : DataFrame, path or sequence of paths
        From :func:`graybox.load_results` (or :func:`compare_results`), or a store's path (its
        latest spec's cells), or several stores' paths (compared side by side).
    rule : {"dsf_valid", "chosen"}
        See the module docstring: D_SF on the validation record over all members, or each
        cell's own choice.
    band : float or mapping data -> float, optional
        The J_SF band B = [0, band] (output units²) for ``"dsf_valid"``; default: each data
        set's band as stored (also for the data sets a mapping does not name). Under ``"chosen"`` it
        changes no row (each cell's choice was made by its own decision); :func:`write_report` draws it on
        the figures and says so in summary.txt.

    Returns
    -------
    pandas.DataFrame
        Index (data, structure, variant), sorted by data set and rank; columns ``rank`` (1 = best within the data
        set, by J_S valid; models whose J_S valid agree to a relative 1e-8, such as the same
        model fitted twice, share a rank, listed the fewer parameters first, then in the grid's order; the
        next rank counts the models before it: 1, 1, 3), ``JS_valid``, ``JS_ident``, ``JSF``, ``fit_valid``, ``n_params``, ``seed``,
        ``lambda1`` (of the member, NaN for single models), ``in_band`` (nullable boolean: True or False as
        the band decided, <NA> where none did: under ``"chosen"`` a model whose cell decided no band, such as
        least squares, and a group with no finished model), ``band`` (the B it was judged against under
        ``"dsf_valid"``: ``band``'s, else the one stored on the model's own cell, each cell's members judged by
        their cell's where results of several specs hold a group under two bands; NaN under ``"chosen"``, and
        for a group without a qualifying model whose cells hold several), ``candidates`` (how many
        models were compared), ``cells`` and ``ok`` (cells of the group, cells with status ok),
        ``reason`` (empty for a ranked row). A group with no qualifying model keeps a row with NaN
        figures (rank NaN) and says why in ``reason``: the smallest J_SF reached when no model
        is in the band, and the messages of its infeasible, diverged or failed cells. Results without a
        finished cell give no row, with the same index and columns.
    """
    band = _checked_options(rule, band)
    df = _frame(results)
    _known_bands(band, df)
    df = df.assign(n_params=_n_params(df))
    sizes = df.groupby(_KEYS, sort=False).size()
    cells_np = _Columns(df, ("status", "message", "band", "n_params"))
    # every group's candidates and its best, in one pass; a group with none is revisited for its reasons
    if rule == "chosen":
        counted = df[df["status"] == "ok"]
        # a chosen model that diverged on the validation record (J_S inf or NaN) is no model to rank
        pool = counted[np.isfinite(counted["JS_valid"].to_numpy(float))]
    else:
        # each group by its own cells' band: read with spec="all", a data set's cells carry the band of the
        # spec that holds them, which two specs may give differently
        bands = {key: _band_of(cells_np.of(key, "band"), band, key[0]) for key in sizes.index}
        allc = _candidates(df)
        # each member by the band of its own cell (a group's cells under two specs' bands: each by its own, not the
        # first's); band= given, or a cell without one, by the group's
        group_b = (pd.Series(list(bands.values()), index=pd.MultiIndex.from_tuples(list(bands), names=_KEYS))
                   .reindex(pd.MultiIndex.from_frame(allc[list(_KEYS)])).to_numpy(float)) if len(allc) else np.zeros(0)
        own = allc["band"].to_numpy(float)
        given = np.array([_given_band(band, d) is not None for d in allc["data"]], bool) if len(allc) else np.zeros(0, bool)
        allc["band"] = np.where(given | np.isnan(own), group_b, own)
        counted = allc[allc["failure"] == ""]  # a member whose fit failed is no model: not compared
        inside = counted["JSF"].to_numpy(float) <= counted["band"].to_numpy(float)
        pool = counted[inside & np.isfinite(counted["JS_valid"].to_numpy(float))].assign(in_band=True)
    # the first of each group by (J_S valid, J_SF), ties in the cells' order (a stable sort)
    firsts = pool.sort_values(["JS_valid", "JSF"], kind="stable").drop_duplicates(_KEYS)
    best = {(r.data, r.structure, r.variant): r for r in firsts.itertuples(index=False)}
    n_of = counted.groupby(_KEYS, sort=False).size().to_dict()
    members_np = None if rule == "chosen" else _Columns(allc, ("failure", "JSF", "lambda1", "seed", "band"))
    rows = []
    for (d, s, v), cells in sizes.items():
        base = {"data": d, "structure": s, "variant": v, "cells": int(cells),
                "ok": int((cells_np.of((d, s, v), "status") == "ok").sum())}
        n = int(n_of.get((d, s, v), 0))
        hit = best.get((d, s, v))
        if hit is not None:
            base.update({k: getattr(hit, k, np.nan) for k in ("JS_valid", "JS_ident", "JSF", "fit_valid", "n_params",
                                                             "seed", "lambda1", "in_band", "band")})
            if rule == "chosen":  # each cell's own choice: no band of the leaderboard's judged it
                base["band"] = np.nan
            base["reason"] = ""
        else:
            n_ps = pd.unique(pd.Series(cells_np.of((d, s, v), "n_params")).dropna())
            base.update(JS_valid=np.nan, JS_ident=np.nan, JSF=np.nan, fit_valid=np.nan,
                        n_params=n_ps[0] if len(n_ps) == 1 else pd.NA, seed=pd.NA, lambda1=np.nan,
                        in_band=pd.NA if rule == "chosen" else False)  # "chosen": no model, no band known
            mine = () if members_np is None else np.unique(members_np.of((d, s, v), "band"))
            base["band"] = mine[0] if len(mine) == 1 else (np.nan if rule == "chosen" or len(mine) else bands[(d, s, v)])
            base["reason"] = _no_model_reason((d, s, v), cells_np, members_np,
                                              None if rule == "chosen" else bands[(d, s, v)], n)
        base["candidates"] = n
        rows.append(base)
    out = pd.DataFrame(rows)
    if out.empty:  # no finished cell yet: no row, but the index and columns a leaderboard has
        out = pd.DataFrame({**{k: pd.Series(dtype=str) for k in (*_KEYS, "reason")},
                            **{k: pd.Series(dtype=int) for k in ("cells", "ok", "candidates")},
                            **{k: pd.Series(dtype=float) for k in ("JS_valid", "JS_ident", "JSF", "fit_valid",
                                                                   "n_params", "seed", "lambda1", "band")},
                            "in_band": pd.Series(dtype="boolean")})
    for c in ("JS_valid", "JS_ident", "JSF", "fit_valid", "lambda1", "band"):
        out[c] = out[c].astype(float)
    out["in_band"] = pd.array(out["in_band"], dtype="boolean")  # True, False or <NA> (not known): never NaN
    out["n_params"] = pd.array(out["n_params"], dtype="Int64")
    out["seed"] = pd.array(out["seed"], dtype="Int64")
    out["rank"] = _tied_ranks(out["data"].to_numpy(), out["JS_valid"].to_numpy(float))
    cols = ["rank", "JS_valid", "JS_ident", "JSF", "fit_valid", "n_params", "seed", "lambda1", "in_band", "band",
            "candidates", "cells", "ok", "reason"]
    # within a shared rank the fewer parameters first, then the grid's order (not J_SF: the same model fitted
    # twice has J_SF apart by round-off too)
    return out.set_index(_KEYS)[cols].sort_values(["data", "rank", "n_params"], kind="stable", na_position="last")


def _tied_ranks(data: np.ndarray, js: np.ndarray) -> np.ndarray:
    """Each row's rank within its data set by ``js`` (1: the smallest; NaN for NaN): a row within
    ``_JS_TIE_RTOL`` of the first of a run of rows (in ascending order) shares that row's rank, and the next
    rank counts the rows before it (1, 1, 3)."""
    rank = np.full(len(js), np.nan)
    for d in pd.unique(data):
        idx = np.flatnonzero((data == d) & ~np.isnan(js))
        idx = idx[np.argsort(js[idx], kind="stable")]
        first = None
        for pos, i in enumerate(idx):
            if first is None or js[i] > js[first] + _JS_TIE_RTOL * abs(js[first]):
                first, r = i, pos + 1
            rank[i] = r
    return rank


def heatmap_table(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    value: str = "JS_valid",
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """Structure × variant table of one leaderboard figure for one data set.

    Parameters
    ----------
    results : DataFrame, path or sequence of paths
        As for :func:`leaderboard`.
    data : str, optional
        The data set (default: the only one; required when the grid has several).
    value : str
        A leaderboard column, e.g. ``"JS_valid"``, ``"JSF"``, ``"fit_valid"``.
    rule, band
        As for :func:`leaderboard`.

    Returns
    -------
    pandas.DataFrame
        Index: structures, columns: variants (grid order); NaN where no model qualified (or the
        structure and the variant never ran together: specs read with ``spec="all"``, stores
        compared), and where the model that qualified has no such value (``lambda1`` of a
        one-model estimator, ``seed`` of a deterministic one: the leaderboard's ``rank`` tells).
    """
    band = _checked_options(rule, band, data, value)
    return _heatmap_tables(_frame(results), data, value, rule, band)[0]


def _heatmap_tables(df: pd.DataFrame, data: str | None, value: str, rule: str,
                    band: float | Mapping[str, float] | None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`heatmap_table`'s table, and beside it which of its cells have a qualifying model (True/False)."""
    _known_bands(band, df)
    d = _one_data(df, data)
    sub = df[df["data"] == d]
    lb = leaderboard(sub, rule=rule, band=_given_band(band, d))
    if value not in lb.columns:
        raise ValueError(f"value must be a leaderboard column ({', '.join(lb.columns)}); got {value!r}")
    order = {"index": list(dict.fromkeys(sub["structure"])), "columns": list(dict.fromkeys(sub["variant"]))}
    t = lb[value].reset_index().pivot(index="structure", columns="variant", values=value)
    ranked = lb["rank"].notna().reset_index().pivot(index="structure", columns="variant", values="rank")
    return t.reindex(**order), ranked.reindex(**order).fillna(False).astype(bool)


def _held_data(df: pd.DataFrame) -> list[str]:
    """The data sets of the results, in their order; ``ValueError`` when they hold no cell (a run stopped before
    its first cell finished: there is nothing to draw, and matplotlib's message for it named no cause)."""
    names = list(dict.fromkeys(df["data"]))
    if not names:
        raise ValueError("the results hold no finished cell to draw or tabulate (graybox grid status shows a "
                         "store's progress)")
    return names


def _one_data(df: pd.DataFrame, data: str | None) -> str:
    names = _held_data(df)
    if data is None:
        if len(names) != 1:
            raise ValueError(f"the results hold {len(names)} data sets {names}: choose one with data=…")
        return names[0]
    if data not in names:
        raise ValueError(f"no data set {data!r} in the results; they hold {names}")
    return data


def _shown(name: object) -> str:
    """A data set's, structure's or variant's name as figure text, drawn as written (as the tables show it): a
    ``$`` escaped, lest matplotlib typeset the text between two as math (or fail to draw the figure on text such
    as ``$\\x$``), and a leading ``_`` kept off the start, where matplotlib leaves a label out of the legend."""
    text = str(name).replace("$", r"\$")
    return " " + text if text.startswith("_") else text


def _wrapped(text: str, fig: Figure, fontsize: float) -> str:
    """``text`` broken into lines that fit the figure's width at ``fontsize`` points (a title longer than its
    figure is cut at both edges: a one-panel figure is 5.2 in wide)."""
    chars = max(20, int(fig.get_figwidth() * 72 / (0.6 * fontsize)))  # a character is at most ~0.6 em wide
    return "\n".join(textwrap.fill(line, chars, break_long_words=False) or line for line in text.split("\n"))


def _colours(names: Sequence[str]) -> dict[str, object]:
    """A distinct colour per name (:func:`graybox.plots._data.distinct_colours`)."""
    return dict(zip(names, distinct_colours(len(names))))


def _finite_pos(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, float)
    return np.isfinite(x) & (x > 0)


def _spans_decades(values) -> bool:
    """Whether the finite positive values span a decade or more (then a log scale reads best)."""
    v = np.asarray(values, float)
    v = v[_finite_pos(v)]
    return bool(v.size) and v.max() >= 10 * v.min()


def _ticks(axis, log: bool, nbins: int) -> None:
    """Few major ticks and no minor labels, so that tick labels never run into each other."""
    if log:
        axis.set_major_locator(LogLocator(base=10, numticks=5))
        axis.set_minor_locator(LogLocator(base=10, subs=np.arange(2, 10) * 0.1, numticks=12))
        axis.set_minor_formatter(NullFormatter())
    else:
        axis.set_major_locator(MaxNLocator(nbins=nbins, min_n_ticks=2))
        fmt = ScalarFormatter(useMathText=True)
        fmt.set_powerlimits((-2, 3))  # 0.0123 reads 1.23 with ×10⁻² once at the axis end
        axis.set_major_formatter(fmt)


def _scale(ax, which: str, values) -> None:
    """A log axis where the values span a decade or more, else a linear one (see :func:`_ticks`)."""
    log = _spans_decades(values)
    (ax.set_xscale if which == "x" else ax.set_yscale)("log" if log else "linear")
    _ticks(ax.xaxis if which == "x" else ax.yaxis, log, 4 if which == "x" else 6)


def _band_on(ax, b: float | None, label: bool = False) -> bool:
    """Shade J_SF ≤ B where B is inside the panel; say where B is when it is not (a panel that
    is all band, or none of it, tells nothing by its colour). Whether it shaded."""
    if b is None:
        return False
    lo, hi = ax.get_ylim()
    if lo < b < hi:
        ax.axhspan(lo, b, color="0.9", zorder=0, label=f"J_SF ≤ B = {b:g}" if label else None)
        ax.axhline(b, color="0.45", lw=0.8, ls="--", zorder=1)
        ax.set_ylim(lo, hi)
        return True
    else:
        where = "above" if b >= hi else "below"
        ax.text(0.99, 0.99 if where == "above" else 0.01, f"B = {b:g}: {where} every point", transform=ax.transAxes,
                ha="right", va="top" if where == "above" else "bottom", fontsize=7, color="0.3")
        return False


def _bands(sub: pd.DataFrame, band: float | Mapping[str, float] | None, data: str) -> list[tuple[float, str]]:
    """The J_SF bounds a data set's panel shows: ``band``'s, else each distinct band its cells stored, with
    the variants that stored it when they differ (as the leaderboard judges each group by its own cells'),
    or none without a band."""
    given = _given_band(band, data)
    if given is not None:
        return [(given, "")]
    stored = sub.dropna(subset=["band"])
    if not len(stored):
        return []
    values = list(dict.fromkeys(stored["band"].astype(float)))
    if len(values) == 1:
        return [(values[0], "")]
    return [(b, ", ".join(map(_shown, dict.fromkeys(stored.loc[stored["band"] == b, "variant"])))) for b in values]


def _bands_on(ax, bands: list[tuple[float, str]], label: bool = False) -> bool:
    """One band as :func:`_band_on` draws it; several (variants with bands of their own) as one dashed line
    each, named by its variants in the legend, none shaded (no region is every variant's). Whether it shaded."""
    if len(bands) <= 1:
        return _band_on(ax, bands[0][0] if bands else None, label=label)
    lo, hi = ax.get_ylim()
    for i, (b, who) in enumerate(bands):
        ax.axhline(b, color=f"0.{3 + 2 * (i % 3)}", lw=0.9, ls=("--", ":", "-.")[i % 3], zorder=1,
                   label=f"B = {b:g} ({who})")
    ax.set_ylim(lo, hi)
    return False


def plot_scatter(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    band: float | Mapping[str, float] | None = None,
) -> Figure:
    """J_S on the validation record against J_SF of every cell's chosen model, band drawn.

    One panel per data set (or only ``data``); colour = variant, marker = structure (one marker
    for all when a data set has more structures than there are markers, 12: its legend then counts
    them); an axis is logarithmic where its values span a decade or more (tick labels never overlap).
    Cells without a finite chosen model (infeasible, diverged, failed) are counted in the title; a J of 0 (an exact
    fit) is drawn on a linear axis, and named in the title where a log axis, which has no 0, leaves it out.

    Parameters
    ----------
    results : DataFrame, path or sequence of paths
        As for :func:`leaderboard`.
    data : str, optional
        Only this data set.
    band : float or mapping data -> float, optional
        The band B to shade (default: as stored).

    Returns
    -------
    matplotlib.figure.Figure
    """
    band = _checked_options(band=band, data=data)
    df = _frame(results)
    _known_bands(band, df)
    names = [_one_data(df, data)] if data is not None else _held_data(df)
    fig = Figure(figsize=(6.4 * len(names), 4.8), layout="constrained")
    axes = fig.subplots(1, len(names), squeeze=False)[0]
    for ax, d in zip(axes, names):
        sub = df[df["data"] == d]
        variants = list(dict.fromkeys(sub["variant"]))
        structures = list(dict.fromkeys(sub["structure"]))
        colors = _colours(variants)
        # a marker per structure while the markers tell them apart; beyond, one for all (a legend of every structure
        # of a large grid covers the points and runs off the figure): leaderboard.csv names them
        apart = len(structures) <= len(_MARKERS)
        marks = {s: _MARKERS[i] if apart else "o" for i, s in enumerate(structures)}
        # a J of 0 (an exact fit) is drawn on a linear axis; a log axis has no 0, and the title says so
        js, jsf = sub["JS_valid"].to_numpy(float), sub["JSF"].to_numpy(float)
        finite = np.isfinite(js) & np.isfinite(jsf)
        logs = {col: _spans_decades(x[finite]) for col, x in (("J_S", js), ("J_SF", jsf))}
        zero = {col: finite & (x == 0) for col, x in (("J_S", js), ("J_SF", jsf))}
        off = {col: int(z.sum()) for col, z in zero.items() if logs[col] and z.any()}
        ok = finite & (js >= 0) & (jsf >= 0) & ~(zero["J_S"] & logs["J_S"]) & ~(zero["J_SF"] & logs["J_SF"])
        ok = pd.Series(ok, index=sub.index)
        for (s, v), g in sub[ok].groupby(["structure", "variant"], sort=False):
            ax.plot(g["JS_valid"], g["JSF"], marks[s], color=colors[v], ms=7, alpha=0.8, ls="none")
        for v in variants:
            ax.plot([], [], "o", color=colors[v], label=_shown(v))
        if apart:
            for s in structures:
                ax.plot([], [], marks[s], color="0.3", label=_shown(s), ls="none")
        else:
            ax.plot([], [], "o", color="0.3", ls="none", label=f"{len(structures)} structures (one marker)")
        _scale(ax, "x", sub.loc[ok, "JS_valid"])
        _scale(ax, "y", sub.loc[ok, "JSF"])
        if ok.any():
            _bands_on(ax, _bands(sub, band, d), label=True)
        else:  # empty axes would show a scale of J values no cell has (matplotlib's ±0.05)
            ax.text(0.5, 0.5, "no cell with a finite chosen model\n(the leaderboard's reason says why)",
                    transform=ax.transAxes, ha="center", va="center", color="0.4", fontsize=8)
            ax.set_xticks([])
            ax.set_yticks([])
        ax.set_xlabel(f"J_S on the validation record{_sq(df, d)}")
        ax.set_ylabel(f"J_SF{_sq(df, d)}")
        said = "; ".join(f"{n} with {col} = 0" for col, n in off.items())
        ax.set_title(f"{_shown(d)}: {int(ok.sum())} of {len(sub)} cells drawn"
                     + (f" ({said}, which a log axis cannot show)" if said else ""))
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, ncol=2, loc="best")
    return fig


def _known_structures(structures: Sequence[str], every: Sequence[str], data: str) -> list[str]:
    """``structures`` checked: a non-empty sequence of names of the data set's structures."""
    names = list(check_sequence(structures, "structures", "a sequence of structure names"))
    if not names:
        raise ValueError("structures must name at least one structure (None: every structure)")
    for n in names:
        check_str(n, "structures[…]")
    if len(set(names)) < len(names):  # a panel or a row drawn twice says nothing more
        raise ValueError(f"structures names {sorted({n for n in names if names.count(n) > 1})} more than once")
    unknown = [s for s in names if s not in set(every)]
    if unknown:
        raise ValueError(f"structures holds {unknown}: no such structure in data set {data!r}; it has {list(every)}")
    return names


def _best_structures(lb: pd.DataFrame, data: str, k: int | None) -> tuple[list[str] | None, int]:
    """The ``k`` structures of ``data`` with the best leaderboard rank (over their variants; unranked last, in
    the grid's order), or None when it has ``k`` or fewer (every one drawn); and how many it has."""
    sub = lb.xs(data, level="data")
    order = list(dict.fromkeys(sub.index.get_level_values("structure")))
    if k is None or len(order) <= k:
        return None, len(order)
    best = sub["rank"].groupby(level="structure", sort=False).min().reindex(order)
    return list(best.sort_values(kind="stable", na_position="last").index[:k]), len(order)


def plot_fronts(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    structures: Sequence[str] | None = None,
    band: float | Mapping[str, float] | None = None,
) -> Figure:
    """Fronts (J_S on the validation record against J_SF) of every variant, one panel per structure.

    Pareto variants draw all their members (the non-dominated ones joined by a line) and their
    chosen member as a large marker; one-model variants draw their model as a large marker. A panel's
    title counts the models it cannot draw (J_S or J_SF inf, e.g. a member that reaches no
    equilibrium at a static point).

    Parameters
    ----------
    results : DataFrame, path or sequence of paths
        As for :func:`leaderboard`.
    data : str, optional
        The data set (required when the grid has several).
    structures : sequence of str, optional
        Panels to draw (default: every structure).
    band : float or mapping data -> float, optional
        The band B to shade (default: as stored).

    Returns
    -------
    matplotlib.figure.Figure
    """
    band = _checked_options(band=band, data=data)
    df = _frame(results)
    _known_bands(band, df)
    d = _one_data(df, data)
    sub = df[df["data"] == d]
    every = list(dict.fromkeys(sub["structure"]))
    names = every if structures is None else _known_structures(structures, every, d)
    variants = list(dict.fromkeys(sub["variant"]))
    colors = _colours(variants)
    ncol = min(3, len(names))
    nrow = -(-len(names) // ncol)
    fig = Figure(figsize=(5.2 * ncol, 4.2 * nrow), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    bands = _bands(sub, band, d)
    shaded = False  # whether a panel shades the band (B inside its J_SF range)
    seen: set[str] = set()  # the variants with a point in some panel
    for ax, s in zip(axes, names):
        drawn = False
        xs: list[np.ndarray] = []
        ys: list[np.ndarray] = []
        models = hidden = zero = 0  # the panel's models, those it cannot draw, and of those the finite ones (J 0)
        for v in variants:
            g = sub[(sub["structure"] == s) & (sub["variant"] == v)]
            for _, r in g.iterrows():
                m = r["members"]
                if isinstance(m, Mapping) and len(m.get("JSF", ())):
                    x, y = np.asarray(m["JS_valid"], float), np.asarray(m["JSF"], float)
                    ok = _finite_pos(x) & _finite_pos(y)
                    models += ok.size
                    hidden += int((~ok).sum())
                    zero += int((~ok & np.isfinite(x) & np.isfinite(y)).sum())
                    if ok.any():
                        ax.plot(x[ok], y[ok], "o", ms=3, alpha=0.4, color=colors[v])
                        o = np.argsort(x[ok])
                        best = np.minimum.accumulate(y[ok][o])
                        keep = np.r_[True, best[1:] < best[:-1]]
                        ax.plot(x[ok][o][keep], y[ok][o][keep], "-", lw=1.2, color=colors[v])
                        xs.append(x[ok])
                        ys.append(y[ok])
                        drawn = True
                        seen.add(v)
                elif r["status"] in ("ok", "diverged"):  # a single model (a diverged one: J_S inf)
                    models += 1
                    xy = np.array([r["JS_valid"], r["JSF"]], float)
                    hidden += int(not _finite_pos(xy).all())
                    zero += int(np.isfinite(xy).all() and not _finite_pos(xy).all())
                if r["status"] == "ok" and _finite_pos([r["JS_valid"]])[0] and _finite_pos([r["JSF"]])[0]:
                    ax.plot([r["JS_valid"]], [r["JSF"]], "*" if isinstance(m, Mapping) else "D", ms=11,
                            mec="k", color=colors[v], zorder=5)
                    xs.append(np.array([r["JS_valid"]]))
                    ys.append(np.array([r["JSF"]]))
                    drawn = True
                    seen.add(v)
            ax.plot([], [], "o-", color=colors[v], label=_shown(v))
        _scale(ax, "x", np.concatenate(xs) if xs else [])
        _scale(ax, "y", np.concatenate(ys) if ys else [])
        if drawn:
            shaded = _bands_on(ax, bands) or shaded
        else:
            ax.text(0.5, 0.5, "no model with finite J_S and J_SF\n(the leaderboard's reason says why)",
                    transform=ax.transAxes, ha="center", va="center", color="0.4", fontsize=8)
            ax.set_xticks([])
            ax.set_yticks([])
        # a model left out is said, not dropped without a word (a member without a static curve: J_SF inf)
        ax.set_title(_shown(s) + (f"\n({hidden} of {models} models not drawn: J_S or J_SF not finite"
                                  f"{' or 0' if zero else ''})" if drawn and hidden else ""))
        ax.set_xlabel(f"J_S on the validation record{_sq(df, d)}")
        ax.set_ylabel(f"J_SF{_sq(df, d)}")
        ax.grid(True, which="major", alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    # a variant with no finite point in any panel (every member diverged, failed or without a static curve) is named
    # in the legend as the others were, as if drawn: it says so
    unseen = {_shown(v) for v in variants if v not in seen}
    handles, labels = axes[0].get_legend_handles_labels()
    labels = [f"{lab} (nothing drawn: no finite J_S and J_SF)" if lab in unseen else lab for lab in labels]
    axes[0].legend(handles, labels, fontsize=7, loc="best", title="★ chosen, ◆ single model", title_fontsize=7)
    said = ""
    unit = df.attrs.get("y_units", {}).get(d, "")
    unit = squared_unit(unit)
    if len(bands) == 1:  # the shade named only where a panel draws it (else each panel says where B lies)
        said = f" ({'shaded below the dashed line: ' if shaded else ''}J_SF ≤ B = {bands[0][0]:g}{unit})"
    elif bands:
        said = " (J_SF ≤ B: the variants' own bands, " + "; ".join(f"{b:g}{unit} for {who}" for b, who in bands) + ")"
    fig.suptitle(_wrapped(f"{_shown(d)}: fronts per structure" + said, fig, 12), fontsize=12)
    return fig


def plot_heatmap(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    value: str = "JS_valid",
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
    structures: Sequence[str] | None = None,
) -> Figure:
    """Structure × variant heat map of a leaderboard figure (log colour scale for errors that span a decade).

    Parameters
    ----------
    results : DataFrame, path or sequence of paths
        As for :func:`leaderboard`.
    data : str, optional
        The data set (required when the grid has several).
    value, rule, band
        As for :func:`heatmap_table`.
    structures : sequence of str, optional
        Rows to draw, in this order (default: every structure, in the grid's order).

    Returns
    -------
    matplotlib.figure.Figure
        Each cell annotated with its value; "—" where no model qualified, "n/a" where one did but
        has no such value (``lambda1`` of a one-model estimator), "not run" for a
        structure and a variant that never ran together (specs read with ``spec="all"``, or
        stores compared, that do not share them). A value the colour
        scale cannot show (inf, e.g. J_SF of a model that reaches no equilibrium at a point; 0 on
        a log scale) is written on an uncoloured cell.
    """
    band = _checked_options(rule, band, data, value)  # said before a store is read, as heatmap_table says it
    df = _frame(results)  # a store read once: the table, the structures and the pairs run all come from it
    t, ranked = _heatmap_tables(df, data, value, rule, band)
    d = _one_data(df, data)
    if structures is not None:
        t = t.loc[_known_structures(structures, list(t.index), d)]
        ranked = ranked.loc[t.index]
    try:
        vals = t.to_numpy(dtype=float)
    except (TypeError, ValueError):  # a text column (reason): heatmap_table shows it, a colour scale cannot
        raise ValueError(f"value must be a numeric leaderboard column to colour, got {value!r} (text); "
                         "heatmap_table gives it as a table") from None
    sub = df[df["data"] == d]
    run = set(zip(sub["structure"], sub["variant"]))  # pairs of two specs (or stores) may never have run together
    # room for the names beyond the half inch the cells' size leaves them: the y labels beside the cells, the
    # x labels (at 35°, right-aligned on their column) below them and out to the left; counted by cells only,
    # a grid of one structure and variant with names of ten characters left its axes no room ("axes sizes
    # collapsed to zero")
    em = 8 * 0.6 / 72  # inches per character of the ticks' 8 pt
    xl = max((len(_shown(c)) for c in t.columns), default=0) * em
    yl = max((len(_shown(i)) for i in t.index), default=0) * em
    fig = Figure(figsize=(1.2 + 1.1 * t.shape[1] + max(0.0, yl - 0.5, 0.82 * xl - 1.05),
                          1.4 + 0.5 * t.shape[0] + max(0.0, 0.57 * xl - 0.5)), layout="constrained")
    ax = fig.add_subplot()
    pos = np.isfinite(vals) & (vals > 0)
    log = value.startswith("J") and _spans_decades(vals)
    norm = LogNorm(vmin=vals[pos].min(), vmax=vals[pos].max()) if log else None
    shown = np.where(pos if log else np.isfinite(vals), vals, np.nan)
    im = ax.imshow(np.ma.masked_invalid(shown), cmap="viridis_r" if value.startswith("J") else "viridis",
                   norm=norm, aspect="auto")
    ax.set_xticks(range(t.shape[1]), [_shown(c) for c in t.columns], rotation=35, ha="right", fontsize=8)
    ax.set_yticks(range(t.shape[0]), [_shown(i) for i in t.index], fontsize=8)
    for i in range(t.shape[0]):
        for j in range(t.shape[1]):
            v = shown[i, j]
            if not np.isfinite(v):  # no model ("—"), or a figure the colours cannot show (inf; 0 on a log scale)
                # a qualifying model without this figure (λ1 of a one-model estimator) is no "no model"
                missing = "n/a" if ranked.iat[i, j] else "—" if (t.index[i], t.columns[j]) in run else "not run"
                said = missing if np.isnan(vals[i, j]) else f"{vals[i, j]:.3g}"
                ax.text(j, i, said, ha="center", va="center", fontsize=7, color="k" if said != "not run" else "0.5")
                continue
            r, g, b_ = np.asarray(im.to_rgba(np.array([v])), float).reshape(-1)[:3]  # one value: vmin = vmax
            light = 0.299 * r + 0.587 * g + 0.114 * b_ > 0.5  # dark text on light colours
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=7, color="k" if light else "w")
    title = f"{_shown(d)}: {value} ({rule})"
    if np.isfinite(shown).any():
        unit = _sq(df, d) if value in ("JS_valid", "JS_ident", "JSF") else " (%)" if value == "fit_valid" else ""
        cbar = fig.colorbar(im, ax=ax, label=value + unit)
        _ticks(cbar.ax.yaxis, log, 5)
    else:  # nothing to colour: a scale would show values no cell has (matplotlib's default ±0.1)
        title += (": no model qualified (the leaderboard's reason says why)" if not ranked.to_numpy().any() else
                  ": no value a colour scale can show")
    ax.set_title(_wrapped(title, fig, 9), fontsize=9)
    return fig


def _slugs(names: Sequence[str]) -> dict[str, str]:
    """A distinct file-name part per data set name (ASCII letters, digits, ``._-``): names that differ only in
    other characters ("plant A" and "plant_A", or two names in another script) or only in case ("Plant" and
    "plant": one file where the file system does not tell case apart, as macOS's and Windows' do not) get ``_2``,
    ``_3`` … in order, lest one data set's files overwrite another's."""
    out: dict[str, str] = {}
    taken: set[str] = set()
    for name in names:
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "data"
        slug, i = base, 1
        while slug.lower() in taken:
            i += 1
            slug = f"{base}_{i}"
        out[name] = slug
        taken.add(slug.lower())
    return out


def write_report(
    store: str | os.PathLike | Sequence[str | os.PathLike],
    out: str | os.PathLike,
    *,
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
    spec: str | int = "latest",
    html: bool = False,
    max_structures: int | None = 12,
) -> list[Path]:
    """Write a store's tables (CSV) and figures (PNG) into a folder, and optionally one HTML page.

    Files: ``cells.csv`` (every cell, θ and members as JSON text), ``leaderboard.csv``,
    ``summary.txt`` (cells by status, the top five per data set, and why a group has no
    qualifying model or a cell is not ok), and per data set ``heatmap_<data>.csv``,
    ``heatmap_<data>.png``, ``fronts_<data>.png``; ``scatter.png``; with ``html``,
    ``report.html``: one self-contained page (the figures embedded, the tables, the reasons,
    the spec and the environment) to open offline in any browser or send to a colleague.

    Parameters
    ----------
    store : path or sequence of paths
        A grid store; two or more are compared side by side (:func:`compare_results`).
    out : path
        Folder (created if missing; "." for the current folder, an empty name is a ``ValueError``).
    rule, band
        As for :func:`leaderboard`.
    spec : "latest", "all" or int
        Which cells of the store (see :func:`graybox.load_results`).
    html : bool
        Also write ``report.html``.
    max_structures : int or None
        Most structures a data set's figures draw: its heat map and fronts show the best ones by
        the leaderboard's rank (the title says how many of how many); the tables keep every one.
        None draws every structure (a grid of 200 structures makes figures tens of thousands of
        pixels tall).

    Returns
    -------
    list of Path
        The files written. A report written again into its folder removes the files the last one wrote
        that it does not (listed in the folder's ``.graybox-report``): every report file there is of the
        new report; other files stay.
    """
    band = _checked_options(rule, band)
    out = check_path(out, "out")  # '~/rep' the home folder's, as check_path reads it
    if not os.fspath(out):  # Path("") is the current folder, a folder nobody named
        raise ValueError("out is empty: give the report's folder ('.' for the current folder)")
    html = check_bool(html, "html")
    if max_structures is not None:
        max_structures = check_int(max_structures, "max_structures", low=1)
    df = _frame(list(store) if isinstance(store, (list, tuple)) else store, spec=spec, attrs=True)
    attrs = dict(df.attrs)
    df = _frame(df)
    if df.empty:  # a run stopped before its first cell finished: no table or figure has anything to show
        raise ValueError(f"{store}: no finished cell to report (spec {spec!r}); graybox grid status shows the "
                         "store's progress")
    # ranked before any file is written: a band refused (a data set it names the results lack, one without a band)
    # leaves the folder of an earlier report as it was, not a new cells.csv beside the old leaderboard and figures
    lb = leaderboard(df, rule=rule, band=band)
    o = Path(out)
    if o.exists() and not o.is_dir():
        raise NotADirectoryError(f"{o} is a file, not a folder for the report")
    o.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    pngs: dict[str, bytes] = {}

    def save(path: Path, obj) -> None:
        if isinstance(obj, Figure):
            buf = io.BytesIO()
            obj.savefig(buf, format="png", dpi=110)
            pngs[path.name] = buf.getvalue()
            path.write_bytes(pngs[path.name])
        elif isinstance(obj, pd.DataFrame):
            obj.to_csv(path)
        else:
            path.write_text(obj, encoding="utf-8")
        written.append(path)

    # every column the results hold, as they hold it: a frame without the store's key, θ or warnings (the reports
    # read none of them) writes cells.csv without them, as it would any column it lacks
    flat = df.copy()
    flat["terms"] = [None if t is None else " + ".join(t) for t in flat["terms"]]
    for col in ("theta", "members"):  # as JSON text, as the store holds them
        if col in flat.columns:
            flat[col] = [encode_value(col, v) for v in flat[col]]
    if "warnings" in flat.columns:
        flat["warnings"] = ["; ".join(w) for w in flat["warnings"]]
    save(o / "cells.csv", flat.set_index("key") if "key" in flat.columns else flat)
    save(o / "leaderboard.csv", lb)
    lines = _summary_lines(df, lb, rule, attrs, band)
    for d, slug in _slugs(list(dict.fromkeys(df["data"]))).items():
        save(o / f"heatmap_{slug}.csv", heatmap_table(df, data=d, rule=rule, band=band))
        shown, total = _best_structures(lb, d, max_structures)
        figs = (plot_heatmap(df, data=d, rule=rule, band=band, structures=shown),
                plot_fronts(df, data=d, band=band, structures=shown))
        if shown is not None:  # say which part of the grid a figure shows
            sub = lb.xs(d, level="data")
            ranked = set(sub.index.get_level_values("structure")[sub["rank"].notna().to_numpy()])
            k = sum(s in ranked for s in shown)
            # structures without a qualifying model have no rank: those shown are the grid's first, not its best
            what = (f"the {len(shown)} best of {total} structures by rank" if k == len(shown) else
                    f"the first {len(shown)} of {total} structures in the grid's order (none has a qualifying model)"
                    if k == 0 else f"the {k} ranked and the first {len(shown) - k} unranked of {total} structures")
            for f in figs:
                f.suptitle(_wrapped("\n".join(t for t in (f.get_suptitle(), f"{what}\n(every one in leaderboard.csv)")
                                              if t), f, 9), fontsize=9)
            lines.append(f"{d}: the figures draw {what.replace(' by rank', '')} (max_structures={max_structures}); "
                         "the tables hold every one")
        save(o / f"heatmap_{slug}.png", figs[0])
        save(o / f"fronts_{slug}.png", figs[1])
    save(o / "scatter.png", plot_scatter(df, band=band))
    save(o / "summary.txt", "\n".join(lines) + "\n")
    if html:
        from ._html import report_page

        save(o / "report.html", report_page(df, lb, rule=rule, summary=lines, figures=pngs, attrs=attrs))
    _replace_manifest(o, written)
    return written


#: The file in a report's folder that lists the files the report wrote (one name a line).
_MANIFEST = ".graybox-report"


def _replace_manifest(folder: Path, written: Sequence[Path]) -> None:
    """Remove the files the folder's last report wrote that this one did not (a data set's figures it no longer
    holds, a report.html of an older leaderboard), so that every report file there is of this report; then list
    this report's. Only names the manifest lists are removed: files the reports did not write stay."""
    manifest = folder / _MANIFEST
    names = [p.name for p in written]
    try:
        before = manifest.read_text(encoding="utf-8").splitlines()
    except (FileNotFoundError, UnicodeDecodeError):
        before = []
    for name in before:
        # a plain file name of this folder (a hand-edited line naming another folder's file is not followed)
        if name and name not in names and Path(name).name == name and name not in (".", ".."):
            (folder / name).unlink(missing_ok=True)
    manifest.write_text("".join(f"{n}\n" for n in names), encoding="utf-8")


def _figures_text(frame: pd.DataFrame, index: bool = True) -> str:
    """A table of figures as text: each float column to 6 significant digits, or as many more as print every two of
    its values apart (pandas' 6 decimals read a J_SF of 6.3e-6 bar² as 0.000006, and one within B = 0.000210786
    as 0.000211, above it)."""
    fmt = {c: (lambda x, n=apart_digits(frame[c].to_numpy(float)): " " + ("NaN" if pd.isna(x) else f"{x:#.{n}g}"))
           for c in frame.columns if pd.api.types.is_float_dtype(frame[c])}
    return frame.to_string(index=index, formatters=fmt)


def _summary_lines(df: pd.DataFrame, lb: pd.DataFrame, rule: str, attrs: Mapping | None = None,
                   band: float | Mapping[str, float] | None = None) -> list[str]:
    """summary.txt: counts, the best five per data set (and how many are ranked), within which band, and every
    reason (``attrs``: the store's, default ``df.attrs``; ``band``: as given to the report)."""
    attrs = df.attrs if attrs is None else attrs
    counts = df["status"].value_counts()
    fp = attrs.get("fingerprint")
    lines = [f"grid {attrs.get('grid')!r} ({f'fingerprint {fp}, ' if fp else ''}graybox "
             f"{attrs.get('version')}): {held_text(len(df), attrs)}; "
             + ", ".join(f"{int(counts.get(s, 0))} {s}" for s in STATUSES),
             f"ranking rule: {rule}"]
    units = output_units(attrs) or output_units(df.attrs)
    for d in dict.fromkeys(df["data"]):
        part = lb.loc[d]
        rows = df[df["data"] == d]
        sub = part.dropna(subset=["JS_valid"]).head(5)
        unit = squared_unit(units.get(d)).strip()
        if rule == "chosen":
            # a band given is drawn on the figures, not used here: said, not silently dropped
            given = _given_band(band, d)
            within = " (each cell's own choice" + ("" if given is None else
                                                   f"; the band given, B = {given:g}, is drawn on the figures only, "
                                                   "it does not change this ranking") + ")"
        else:  # the band that ranked it: given, or stored (the variants' own where their cells stored several)
            bs = _bands(rows, band, d)
            within = (f" among the models with J_SF ≤ B = {bs[0][0]:g}{unit and ' ' + unit}" if len(bs) == 1 else
                      " among the models with J_SF ≤ B, the variants' own: " +
                      "; ".join(f"{b:g}{unit and ' ' + unit} for {who}" for b, who in bs) if bs else "")
        lines.append(f"\n{d}: best by J_S on the validation record{within}")
        if unit and len(sub):  # what the columns are, in which units
            lines.append(f"  (JS_valid: J_S on the validation record, JSF: J_SF on the static points, both in {unit}; "
                         "fit_valid in %)")
        lines.append(_figures_text(sub[["JS_valid", "JSF", "fit_valid", "n_params"]]) if len(sub) else
                     "  (no model qualified: the reasons follow)")
        n_ranked = int(part["JS_valid"].notna().sum())
        if n_ranked > len(sub):  # the rest are not dropped: say where they are
            lines.append(f"{d}: the best {len(sub)} of {n_ranked} ranked models; every one in leaderboard.csv")
        empty = part[part["reason"] != ""]
        if len(empty):
            lines.append(f"{d}: {len(empty)} of {len(part)} (structure, variant) with no qualifying model, and why")
            lines += [f"  {s} / {v}: {r}" for (s, v), r in empty["reason"].items()]
        # a ranked group's failed members are not compared: say which and why (an unranked group's reason says it)
        ranked = set(part.index[part["reason"] == ""])
        failed = [_failed_members(r) for r in rows.itertuples(index=False)
                  if (r.structure, r.variant) in ranked]
        failed = [f for f in failed if f]
        if failed:
            lines.append(f"{d}: member fits that failed in ranked (structure, variant), not compared")
            lines += failed
    bad = df[df["status"] != "ok"]
    if len(bad):
        lines.append(f"\ncells not ok ({len(bad)}), with their messages")
        for _, r in bad.iterrows():
            seed = f" seed {int(r['seed'])}" if pd.notna(r["seed"]) else ""
            lines.append(f"  [{r['status']}] {r['data']} / {r['structure']} / {r['variant']}{seed}: "
                         f"{r['message'] if isinstance(r['message'], str) and r['message'] else 'no message stored'}")
    return lines


def _failed_members(r) -> str:
    """A line for a cell (a row of the results) whose Pareto members failed in part: how many, at which λ1 and why;
    empty when none failed."""
    m = r.members
    failure = list(m.get("failure", ())) if isinstance(m, Mapping) else []
    bad = [i for i, f in enumerate(failure) if f]
    if not bad:
        return ""
    lam = level_texts(np.asarray(m["lambda1"], float))
    seed = f" seed {int(r.seed)}" if pd.notna(r.seed) else ""
    why = "; ".join(list(dict.fromkeys(_short(failure[i]) for i in bad))[:2])
    return (f"  {r.structure} / {r.variant}{seed}: {len(bad)} of {len(failure)} member fit(s) failed "
            f"(λ1 = {', '.join(lam[i] for i in bad)}): {why}")


@dataclass(frozen=True, eq=False)
class GridStatus:
    """Where a grid stands (:func:`grid_status`): readable while another process writes the store.

    Attributes
    ----------
    store : str
    spec : int
        The spec shown (by default the one run last); 0 when the cells of all specs are (``spec="all"``).
    grid : str
        Its name.
    cells : int
        Cells of the spec.
    done : int
        Cells the store holds (any status).
    left : int
        Cells not finished yet.
    counts : mapping str -> int
        Cells by status.
    time_per_cell : float
        Mean seconds per finished cell that has its run time (NaN before the first, and while every cell
        done is one stopped at the cell time limit or whose worker was lost: those have none).
    last_finished : str or None
        When the last cell finished (UTC, ISO 8601).
    best : pandas.DataFrame
        The best model so far per data set (the leaderboard's first row), with the ``rule`` it was
        ranked by: ``"dsf_valid"``, or ``"chosen"`` for a data set without a band.
    specs : int
        Specs the store has seen.
    running : mapping str -> int
        Cells being run into the store now, by run ("pid 123 on host h"; any spec's cells).
    reasons : mapping str -> str
        Why cells are not ok: per status (failed, infeasible, diverged) the message of the one that
        finished last, shortened.
    waiting : tuple of str
        Data sets with finished cells but no qualifying model yet (absent from ``best``).
    units : mapping str -> str
        Each data set's output unit, by name, where its spec stored one (J_S and J_SF are in its square).
    """

    store: str
    spec: int
    grid: str
    cells: int
    done: int
    left: int
    counts: Mapping[str, int]
    time_per_cell: float
    last_finished: str | None
    best: pd.DataFrame = FrozenFrame()
    specs: int
    running: Mapping[str, int] = dataclasses.field(default_factory=dict)
    reasons: Mapping[str, str] = dataclasses.field(default_factory=dict)
    waiting: tuple = ()
    units: Mapping[str, str] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        check_fields(self)
        object.__setattr__(self, "units", FrozenMap(self.units))
        object.__setattr__(self, "waiting", tuple(check_str(d, "waiting[…]") for d in self.waiting))
        object.__setattr__(self, "counts", FrozenMap(self.counts))  # not the caller's dict
        object.__setattr__(self, "running", FrozenMap(self.running))
        object.__setattr__(self, "reasons", FrozenMap(self.reasons))

    def summary(self) -> str:
        """A few lines for a terminal.

        Returns
        -------
        str
        """
        st = ", ".join(f"{self.counts.get(s, 0)} {s}" for s in STATUSES)
        # a cell stopped at its time limit, or whose worker died, is done (failed) with no run time stored
        tpc = (f"{self.time_per_cell:.3g} s per cell" if np.isfinite(self.time_per_cell) else
               "no run time recorded for the cells done (stopped at the cell time limit or their worker lost)"
               if self.done else "no cell finished yet")
        which = f"spec {self.spec} of {self.specs}" if self.spec else f"all {self.specs} specs"
        lines = [f"{self.store}: {which} ({self.grid!r}): {self.done} of {self.cells} cells "
                 f"done ({st}), {self.left} left; {tpc}"
                 + (f"; last finished {self.last_finished}" if self.last_finished else "")]
        if self.running:
            lines.append("being run now: " + "; ".join(f"{n} cell(s) by {who}" for who, n in self.running.items()))
        if self.reasons:
            lines.append("why cells are not ok (the last of each status):")
            lines += [f"  {st}: {why}" for st, why in self.reasons.items()]
        yet = "" if self.left == 0 and not self.running else " yet"  # (a finished grid waits for nothing)
        if len(self.best):
            lines.append("best so far:")
            lines += ["  " + ln for ln in _figures_text(self.best.reset_index(), index=False).splitlines()]
            told = {d: squared_unit(self.units.get(d)).strip() for d in self.best.index}
            if any(told.values()):
                lines.append("  (JS_valid: J_S on the validation record, JSF: J_SF on the static points; in " +
                             ", ".join(f"{u} for {d}" for d, u in told.items() if u) + ")")
            if "rule" in self.best.columns and (self.best["rule"] == "chosen").any():
                lines.append("  (rule chosen: each cell's own choice, for a data set without a band; dsf_valid: D_SF "
                             "on the validation record within the data set's band)")
            if self.waiting:
                lines.append(f"no model qualifies{yet} for data set {', '.join(map(repr, self.waiting))} "
                             "(graybox grid report says why)")
        elif self.done:
            lines.append(f"best so far: no model qualifies{yet} (graybox grid report says why)")
        else:
            lines.append("best so far: none yet")
        return "\n".join(lines)


def grid_status(store: str | os.PathLike, *, spec: str | int = "latest") -> GridStatus:
    """How far a grid has run: cells done, failed and left, time per cell, the best so far.

    Reads the store read-only, so it can be called (``graybox grid status``) while another
    process runs the grid into it.

    Parameters
    ----------
    store : path
        A grid store.
    spec : "latest", "all" or int
        Which spec's cells (see :func:`graybox.load_results`); default the one run last.

    Returns
    -------
    GridStatus
    """
    df = load_results(store, spec=spec)
    attrs = dict(df.attrs)
    df = _frame(df)
    counts = {s: int((df["status"] == s).sum()) for s in STATUSES}
    n = int(attrs.get("n_cells", len(df)))
    wall = df["wall_time"].astype(float)
    best = pd.DataFrame()
    tops: list[pd.DataFrame] = []
    waiting: list[str] = []
    for d, sub in df.groupby("data", sort=False):
        # each data set by D_SF in its band, as its report ranks it; one without a band by each cell's own choice
        # (the others keep theirs), and the row says which
        rule = "dsf_valid"
        try:
            lb = leaderboard(sub)
        except ValueError:
            rule = "chosen"
            lb = leaderboard(sub, rule=rule)
        top = lb.dropna(subset=["JS_valid"]).reset_index().head(1).assign(rule=rule)
        if len(top):
            tops.append(top)
        else:
            waiting.append(str(d))
    if tops:
        best = pd.concat(tops).set_index("data")[["structure", "variant", "JS_valid", "JSF", "n_params", "rule"]]
    last = df["finished_at"].dropna()
    reasons = {}
    for st in STATUSES[1:]:  # the cell of each status that finished last: a run going wrong says so now
        bad = df[df["status"] == st]
        if len(bad):
            msg = bad.sort_values("finished_at", kind="stable", na_position="first")["message"].iloc[-1]
            reasons[st] = _short(msg) if isinstance(msg, str) and msg else "no message stored"
    sel = attrs.get("selection")
    return GridStatus(str(store), int(sel) if isinstance(sel, (int, np.integer)) else 0, str(attrs.get("grid")),
                      n, len(df), max(0, n - len(df)), FrozenMap(counts),
                      float(wall.mean()) if wall.notna().any() else float("nan"), max(last) if len(last) else None,
                      best, len(attrs.get("specs", [])), running_cells(store), reasons, tuple(waiting),
                      output_units(attrs))
