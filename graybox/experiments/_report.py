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

import os
import re
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

from ._cell import STATUSES
from ._store import encode_value, load_results

__all__ = ["RULES", "leaderboard", "heatmap_table", "plot_scatter", "plot_fronts", "plot_heatmap", "write_report"]

#: Ranking rules of :func:`leaderboard`.
RULES = ("dsf_valid", "chosen")
_KEYS = ["data", "structure", "variant"]
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "<", ">", "h", "p")


def _frame(results: pd.DataFrame | str | os.PathLike) -> pd.DataFrame:
    if isinstance(results, pd.DataFrame):
        missing = {"data", "structure", "variant", "status", "JS_valid", "JSF", "members"} - set(results.columns)
        if missing:
            raise ValueError(f"results must come from graybox.load_results; missing columns {sorted(missing)}")
        return results
    return load_results(results)


def _band_of(rows: pd.DataFrame, band: float | Mapping[str, float] | None, data: str) -> float:
    if isinstance(band, Mapping):
        if data not in band:
            raise ValueError(f"band gives no value for data set {data!r}")
        return float(band[data])
    if band is not None:
        return float(band)
    b = rows["band"].dropna()
    if b.empty:
        raise ValueError(f"data set {data!r} has no band in the store: pass band=…")
    return float(b.iloc[0])


def _candidates(g: pd.DataFrame) -> pd.DataFrame:
    """Every model of a (data, structure, variant): Pareto members and single models."""
    out = []
    for _, r in g.iterrows():
        m = r["members"]
        if isinstance(m, Mapping) and len(m.get("JSF", ())):
            K = len(m["JSF"])
            chosen = r["lambda1"]
            out.append(pd.DataFrame({
                "seed": [r["seed"]] * K, "lambda1": m["lambda1"], "JS_ident": m["JS"], "JS_valid": m["JS_valid"],
                "JSF": m["JSF"], "fit_valid": m.get("fit_valid", np.full(K, np.nan)),
                "n_params": [r["n_params"]] * K, "chosen": np.isclose(m["lambda1"], chosen) if pd.notna(chosen)
                else np.zeros(K, bool), "status": [r["status"]] * K}))
        elif r["status"] == "ok":
            out.append(pd.DataFrame({"seed": [r["seed"]], "lambda1": [np.nan], "JS_ident": [r["JS_ident"]],
                                     "JS_valid": [r["JS_valid"]], "JSF": [r["JSF"]], "fit_valid": [r["fit_valid"]],
                                     "n_params": [r["n_params"]], "chosen": [True], "status": [r["status"]]}))
    if not out:
        return pd.DataFrame(columns=["seed", "lambda1", "JS_ident", "JS_valid", "JSF", "fit_valid", "n_params",
                                     "chosen", "status"])
    return pd.concat(out, ignore_index=True)


def leaderboard(
    results: pd.DataFrame | str | os.PathLike,
    *,
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """The best model of every (data, structure, variant), ranked within each data set.

    Parameters
    ----------
    results : DataFrame or path
        From :func:`graybox.load_results`, or a store's path.
    rule : {"dsf_valid", "chosen"}
        See the module docstring: D_SF on the validation record over all members, or each
        cell's own choice.
    band : float or mapping data -> float, optional
        The J_SF band B = [0, band] (output units²) for ``"dsf_valid"``; default: each data
        set's band as stored.

    Returns
    -------
    pandas.DataFrame
        Index (data, structure, variant); columns ``rank`` (1 = best within the data set, by
        J_S valid), ``JS_valid``, ``JS_ident``, ``JSF``, ``fit_valid``, ``n_params``, ``seed``,
        ``lambda1`` (of the member, NaN for single models), ``in_band``, ``candidates`` (how many
        models were compared), ``cells`` and ``ok`` (cells of the group, cells with status ok).
        A group with no qualifying model keeps a row with NaN figures (rank NaN).
    """
    if rule not in RULES:
        raise ValueError(f"rule must be one of {', '.join(map(repr, RULES))}; got {rule!r}")
    df = _frame(results)
    rows = []
    for (d, s, v), g in df.groupby(_KEYS, sort=False):
        base = {"data": d, "structure": s, "variant": v, "cells": len(g), "ok": int((g["status"] == "ok").sum())}
        if rule == "chosen":
            ok = g[g["status"] == "ok"]
            cand = ok.assign(in_band=ok["in_band"])
            n = len(cand)
        else:
            b = _band_of(g, band, d)
            allc = _candidates(g)
            n = len(allc)
            cand = allc[(allc["JSF"] <= b) & np.isfinite(allc["JS_valid"].astype(float))].assign(in_band=True)
        if len(cand):
            best = cand.sort_values(["JS_valid", "JSF"], kind="stable").iloc[0]
            base.update({k: best.get(k, np.nan) for k in ("JS_valid", "JS_ident", "JSF", "fit_valid", "n_params",
                                                         "seed", "lambda1", "in_band")})
        else:
            base.update(JS_valid=np.nan, JS_ident=np.nan, JSF=np.nan, fit_valid=np.nan, n_params=pd.NA, seed=pd.NA,
                        lambda1=np.nan, in_band=False)
        base["candidates"] = n
        rows.append(base)
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    for c in ("JS_valid", "JS_ident", "JSF", "fit_valid", "lambda1"):
        out[c] = out[c].astype(float)
    out["n_params"] = pd.array(out["n_params"], dtype="Int64")
    out["seed"] = pd.array(out["seed"], dtype="Int64")
    out["rank"] = out.groupby("data")["JS_valid"].rank(method="min")
    cols = ["rank", "JS_valid", "JS_ident", "JSF", "fit_valid", "n_params", "seed", "lambda1", "in_band",
            "candidates", "cells", "ok"]
    return out.set_index(_KEYS)[cols].sort_values(["data", "rank"], kind="stable", na_position="last")


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
    results : DataFrame or path
    data : str, optional
        The data set (default: the only one; required when the grid has several).
    value : str
        A leaderboard column, e.g. ``"JS_valid"``, ``"JSF"``, ``"fit_valid"``.
    rule, band
        As for :func:`leaderboard`.

    Returns
    -------
    pandas.DataFrame
        Index: structures, columns: variants (grid order); NaN where no model qualified.
    """
    df = _frame(results)
    d = _one_data(df, data)
    lb = leaderboard(df[df["data"] == d], rule=rule, band=band)
    if value not in lb.columns:
        raise ValueError(f"value must be a leaderboard column ({', '.join(lb.columns)}); got {value!r}")
    t = lb[value].reset_index().pivot(index="structure", columns="variant", values=value)
    sub = df[df["data"] == d]
    return t.reindex(index=list(dict.fromkeys(sub["structure"])), columns=list(dict.fromkeys(sub["variant"])))


def _one_data(df: pd.DataFrame, data: str | None) -> str:
    names = list(dict.fromkeys(df["data"]))
    if data is None:
        if len(names) != 1:
            raise ValueError(f"the results hold {len(names)} data sets {names}: choose one with data=…")
        return names[0]
    if data not in names:
        raise ValueError(f"no data set {data!r} in the results; they hold {names}")
    return data


def _finite_pos(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, float)
    return np.isfinite(x) & (x > 0)


def plot_scatter(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    band: float | Mapping[str, float] | None = None,
) -> Figure:
    """J_S on the validation record against J_SF of every cell's chosen model, band drawn.

    One panel per data set (or only ``data``); colour = variant, marker = structure; log axes.
    Cells without a finite chosen model (infeasible, diverged, failed) are counted in the title.

    Parameters
    ----------
    results : DataFrame or path
    data : str, optional
        Only this data set.
    band : float or mapping data -> float, optional
        The band B to shade (default: as stored).

    Returns
    -------
    matplotlib.figure.Figure
    """
    df = _frame(results)
    names = [_one_data(df, data)] if data is not None else list(dict.fromkeys(df["data"]))
    fig = Figure(figsize=(6.4 * len(names), 4.8), layout="constrained")
    axes = fig.subplots(1, len(names), squeeze=False)[0]
    for ax, d in zip(axes, names):
        sub = df[df["data"] == d]
        variants = list(dict.fromkeys(sub["variant"]))
        structures = list(dict.fromkeys(sub["structure"]))
        colors = {v: f"C{i % 10}" for i, v in enumerate(variants)}
        marks = {s: _MARKERS[i % len(_MARKERS)] for i, s in enumerate(structures)}
        ok = _finite_pos(sub["JS_valid"]) & _finite_pos(sub["JSF"])
        for (s, v), g in sub[ok].groupby(["structure", "variant"], sort=False):
            ax.plot(g["JS_valid"], g["JSF"], marks[s], color=colors[v], ms=7, alpha=0.8, ls="none")
        for v in variants:
            ax.plot([], [], "o", color=colors[v], label=v)
        for s in structures:
            ax.plot([], [], marks[s], color="0.3", label=s, ls="none")
        b = _band_of(sub, band, d) if (band is not None or sub["band"].notna().any()) else None
        ax.set_xscale("log")
        ax.set_yscale("log")
        if b is not None and ok.any():
            lo, hi = ax.get_ylim()
            ax.axhspan(min(lo, b / 10), b, color="0.88", zorder=0, label=f"B = [0, {b:g}]")
            ax.set_ylim(min(lo, b / 10), max(hi, b))
        ax.set_xlabel("J_S on the validation record")
        ax.set_ylabel("J_SF")
        ax.set_title(f"{d}: {int(ok.sum())} of {len(sub)} cells drawn")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=2, loc="best")
    return fig


def plot_fronts(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    structures: Sequence[str] | None = None,
    band: float | Mapping[str, float] | None = None,
) -> Figure:
    """Fronts (J_S on the validation record against J_SF) of every variant, one panel per structure.

    Pareto variants draw all their members (the non-dominated ones joined by a line) and their
    chosen member as a large marker; one-model variants draw their model as a large marker.

    Parameters
    ----------
    results : DataFrame or path
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
    df = _frame(results)
    d = _one_data(df, data)
    sub = df[df["data"] == d]
    names = list(dict.fromkeys(sub["structure"])) if structures is None else list(structures)
    unknown = [s for s in names if s not in set(sub["structure"])]
    if unknown:
        raise ValueError(f"no structure(s) {unknown} in data set {d!r}")
    variants = list(dict.fromkeys(sub["variant"]))
    colors = {v: f"C{i % 10}" for i, v in enumerate(variants)}
    ncol = min(3, len(names))
    nrow = -(-len(names) // ncol)
    fig = Figure(figsize=(5.2 * ncol, 4.2 * nrow), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False).ravel()
    b = _band_of(sub, band, d) if (band is not None or sub["band"].notna().any()) else None
    for ax, s in zip(axes, names):
        drawn = False
        for v in variants:
            g = sub[(sub["structure"] == s) & (sub["variant"] == v)]
            for _, r in g.iterrows():
                m = r["members"]
                if isinstance(m, Mapping) and len(m.get("JSF", ())):
                    x, y = np.asarray(m["JS_valid"], float), np.asarray(m["JSF"], float)
                    ok = _finite_pos(x) & _finite_pos(y)
                    if ok.any():
                        ax.plot(x[ok], y[ok], "o", ms=3, alpha=0.4, color=colors[v])
                        o = np.argsort(x[ok])
                        best = np.minimum.accumulate(y[ok][o])
                        keep = np.r_[True, best[1:] < best[:-1]]
                        ax.plot(x[ok][o][keep], y[ok][o][keep], "-", lw=1.2, color=colors[v])
                        drawn = True
                if r["status"] == "ok" and _finite_pos([r["JS_valid"]])[0] and _finite_pos([r["JSF"]])[0]:
                    ax.plot([r["JS_valid"]], [r["JSF"]], "*" if isinstance(m, Mapping) else "D", ms=11,
                            mec="k", color=colors[v], zorder=5)
                    drawn = True
            ax.plot([], [], "o-", color=colors[v], label=v)
        ax.set_xscale("log")
        ax.set_yscale("log")
        if b is not None and drawn:
            lo, hi = ax.get_ylim()
            ax.axhspan(min(lo, b / 10), b, color="0.88", zorder=0)
            ax.set_ylim(min(lo, b / 10), max(hi, b))
        ax.set_title(s)
        ax.set_xlabel("J_S on the validation record")
        ax.set_ylabel("J_SF")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    axes[0].legend(fontsize=7, loc="best", title="★ chosen, ◆ single model", title_fontsize=7)
    fig.suptitle(f"{d}: fronts per structure" + (f" (shaded: J_SF ≤ {b:g})" if b is not None else ""))
    return fig


def plot_heatmap(
    results: pd.DataFrame | str | os.PathLike,
    *,
    data: str | None = None,
    value: str = "JS_valid",
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
) -> Figure:
    """Structure × variant heat map of a leaderboard figure (log colour scale for errors).

    Parameters
    ----------
    results : DataFrame or path
    data : str, optional
        The data set (required when the grid has several).
    value, rule, band
        As for :func:`heatmap_table`.

    Returns
    -------
    matplotlib.figure.Figure
        Each cell annotated with its value; "—" where no model qualified.
    """
    t = heatmap_table(results, data=data, value=value, rule=rule, band=band)
    vals = t.to_numpy(dtype=float)
    fig = Figure(figsize=(1.2 + 1.1 * t.shape[1], 1.4 + 0.5 * t.shape[0]), layout="constrained")
    ax = fig.add_subplot()
    pos = np.isfinite(vals) & (vals > 0)
    log = value.startswith("J") and pos.any()
    norm = LogNorm(vmin=vals[pos].min(), vmax=vals[pos].max()) if log else None
    shown = np.where(pos if log else np.isfinite(vals), vals, np.nan)
    im = ax.imshow(np.ma.masked_invalid(shown), cmap="viridis_r" if value.startswith("J") else "viridis",
                   norm=norm, aspect="auto")
    ax.set_xticks(range(t.shape[1]), [str(c) for c in t.columns], rotation=35, ha="right", fontsize=8)
    ax.set_yticks(range(t.shape[0]), [str(i) for i in t.index], fontsize=8)
    for i in range(t.shape[0]):
        for j in range(t.shape[1]):
            v = shown[i, j]
            if not np.isfinite(v):
                ax.text(j, i, "—", ha="center", va="center", fontsize=7, color="k")
                continue
            r, g, b_, _ = im.cmap(im.norm(v))
            light = 0.299 * r + 0.587 * g + 0.114 * b_ > 0.5  # dark text on light colours
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=7, color="k" if light else "w")
    fig.colorbar(im, ax=ax, label=value)
    d = _one_data(_frame(results), data)
    ax.set_title(f"{d}: {value} ({rule})", fontsize=9)
    return fig


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "data"


def write_report(
    store: str | os.PathLike,
    out: str | os.PathLike,
    *,
    rule: str = "dsf_valid",
    band: float | Mapping[str, float] | None = None,
) -> list[Path]:
    """Write a store's tables (CSV) and figures (PNG) into a folder.

    Files: ``cells.csv`` (every cell, θ and members as JSON text), ``leaderboard.csv``,
    ``summary.txt`` (cells by status, the top five per data set), and per data set
    ``heatmap_<data>.csv``, ``heatmap_<data>.png``, ``fronts_<data>.png``; ``scatter.png``.

    Parameters
    ----------
    store : path
        A grid store.
    out : path
        Folder (created if missing).
    rule, band
        As for :func:`leaderboard`.

    Returns
    -------
    list of Path
        The files written.
    """
    df = load_results(store)
    o = Path(out)
    o.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []

    def save(path: Path, obj) -> None:
        if isinstance(obj, Figure):
            obj.savefig(path, dpi=110)
        elif isinstance(obj, pd.DataFrame):
            obj.to_csv(path)
        else:
            path.write_text(obj, encoding="utf-8")
        written.append(path)

    flat = df.copy()
    flat["terms"] = [None if t is None else " + ".join(t) for t in flat["terms"]]
    for col in ("theta", "members"):  # as JSON text, as the store holds them
        flat[col] = [encode_value(col, v) for v in flat[col]]
    flat["warnings"] = ["; ".join(w) for w in flat["warnings"]]
    save(o / "cells.csv", flat.set_index("key"))
    lb = leaderboard(df, rule=rule, band=band)
    save(o / "leaderboard.csv", lb)
    counts = df["status"].value_counts()
    lines = [f"grid {df.attrs.get('grid')!r} (fingerprint {df.attrs.get('fingerprint')}, graybox "
             f"{df.attrs.get('version')}): {len(df)} of {df.attrs.get('n_cells', len(df))} cells in the store; "
             + ", ".join(f"{int(counts.get(s, 0))} {s}" for s in STATUSES),
             f"ranking rule: {rule}"]
    for d in dict.fromkeys(df["data"]):
        sub = lb.loc[d].dropna(subset=["JS_valid"]).head(5)
        lines.append(f"\n{d}: best by J_S on the validation record")
        lines.append(sub[["JS_valid", "JSF", "fit_valid", "n_params"]].to_string() if len(sub) else "  (no model qualified)")
        slug = _slug(d)
        save(o / f"heatmap_{slug}.csv", heatmap_table(df, data=d, rule=rule, band=band))
        save(o / f"heatmap_{slug}.png", plot_heatmap(df, data=d, rule=rule, band=band))
        save(o / f"fronts_{slug}.png", plot_fronts(df, data=d, band=band))
    save(o / "scatter.png", plot_scatter(df, band=band))
    save(o / "summary.txt", "\n".join(lines) + "\n")
    return written
