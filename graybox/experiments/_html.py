"""One self-contained HTML page of a grid's report: figures embedded (base64 PNG), the tables,
the reasons, the spec and the environment. Standard library only (:mod:`html`, :mod:`base64`):
the page opens offline in any browser and can be sent as a single file."""

from __future__ import annotations

import base64
import datetime
import html
import json
import platform
import sys
from typing import Mapping, Sequence

import pandas as pd

from ..core._reprs import apart_digits, bound_text, squared_unit
from ._cell import STATUSES
from ._store import held_text, output_units

__all__ = ["report_page"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:1.5em auto;max-width:1200px;
padding:0 1em;color:#222;line-height:1.4}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}th,td{border:1px solid #ddd;padding:.2em .5em;
text-align:right;vertical-align:top}th{background:#f3f3f3}td.t,th.t{text-align:left}
tr.why td{background:#fff7e6}img{max-width:100%;height:auto;border:1px solid #eee;margin:.4em 0}
pre{background:#f7f7f7;padding:.6em;overflow:auto;font-size:.8em}.st-ok{color:#176d2b}.st-bad{color:#a3361b}
details{margin:.5em 0}summary{cursor:pointer}
"""


def _e(x: object) -> str:
    return html.escape("" if x is None else str(x))


def _missing(v: object) -> bool:
    """Whether a table's value is missing (None, NaN, pandas' NA), not a value to write."""
    return v is None or (not isinstance(v, str) and pd.api.types.is_scalar(v) and bool(pd.isna(v)))


def _text(v: object) -> str:
    """A text cell: the value escaped, a missing one as a dash (not "nan" nor "<NA>")."""
    return "—" if _missing(v) else _e(v)


def _num(v: object, digits: int = 4) -> str:
    if _missing(v):
        return "—"  # a missing figure: the row's reason says why
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return _e(v)


def _band(b: object, jsf: object, digits: int) -> str:
    """A band B as the reasons say it (:func:`~graybox.core._reprs.bound_text` beside the row's J_SF), with at least
    the ``digits`` that tell the column's bands apart."""
    if _missing(b) or not isinstance(b, float):
        return _num(b, digits)
    apart = f"{b:.{digits}g}"
    said = bound_text(b, None if _missing(jsf) else float(jsf))
    return _e(said if len(said) > len(apart) else apart)


def _table(df: pd.DataFrame, *, index: bool = True, text_cols: Sequence[str] = (), why: str | None = None) -> str:
    """An HTML table (every value escaped); ``why``: a column whose non-empty rows are highlighted."""
    d = df.reset_index() if index else df
    # text: left-aligned and escaped as is; numbers: formatted, a missing one as a dash
    text = [c in text_cols or not pd.api.types.is_numeric_dtype(d[c]) for c in d.columns]
    head = "".join(f'<th class="t">{_e(c)}</th>' if t else f"<th>{_e(c)}</th>" for c, t in zip(d.columns, text))
    # a band B is said as the reasons say it (bound_text: %g, six digits, or more to keep the row's J_SF on its side):
    # B = 0.030625 read "0.03062" in its column beside a reason saying 0.030625
    digits = [4 if t or not pd.api.types.is_float_dtype(d[c]) else
              apart_digits(d[c].to_numpy(float), low=6 if c == "band" else 4) for c, t in zip(d.columns, text)]
    body = []
    for _, r in d.iterrows():
        cls = ' class="why"' if why is not None and isinstance(r.get(why), str) and r.get(why) else ""
        cells = "".join(f'<td class="t">{_text(r[c])}</td>' if t else
                        f"<td>{_band(r[c], r.get('JSF'), n) if c == 'band' else _num(r[c], n)}</td>"
                        for c, t, n in zip(d.columns, text, digits))
        body.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _img(name: str, png: bytes) -> str:
    data = base64.b64encode(png).decode("ascii")
    return f'<figure><img alt="{_e(name)}" src="data:image/png;base64,{data}"><figcaption>{_e(name)}</figcaption></figure>'


def _selection(attrs: Mapping) -> str:
    """Which cells the page shows, in words: a spec's number alone ("1") read as a count of cells."""
    sel = attrs.get("selection", "latest")
    # stores compared (their specs carry the store's label): compare_results' spec, applied to each
    several = any("store" in s for s in attrs.get("specs") or [])
    if sel == "all":
        return "every cell the stores hold (spec='all')" if several else "every cell the store holds (spec='all')"
    if sel == "latest":
        return "each store's latest spec" if several else "the cells of the latest spec"
    return f"the cells of spec {sel}" + (" of each store" if several else "")


def _environment(attrs: Mapping) -> dict[str, str]:
    import matplotlib
    import numpy

    from .. import _api as gb

    return {"graybox (this report)": gb.__version__, "graybox (the cells)": str(attrs.get("version")),
            "python": sys.version.split()[0], "numpy": numpy.__version__, "pandas": pd.__version__,
            "matplotlib": matplotlib.__version__, "platform": platform.platform(),
            "store": str(attrs.get("store")), "cells shown": _selection(attrs),
            "written": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}


def report_page(df: pd.DataFrame, lb: pd.DataFrame, *, rule: str, summary: Sequence[str],
                figures: Mapping[str, bytes], attrs: Mapping | None = None) -> str:
    """The page's text: ``df`` from :func:`graybox.load_results`, ``lb`` its leaderboard,
    ``summary`` the lines of summary.txt, ``figures`` PNG bytes by file name, ``attrs`` the
    store's facts (default ``df.attrs``)."""
    attrs = df.attrs if attrs is None else attrs
    title = f"graybox grid report: {attrs.get('grid')}"
    counts = df["status"].value_counts()
    parts = [f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{_e(title)}</title>"
             f"<style>{_CSS}</style></head><body><h1>{_e(title)}</h1>"]
    parts.append("<p>" + _e(f"{held_text(len(df), attrs)}: ") + ", ".join(
        f'<span class="{"st-ok" if s == "ok" else "st-bad"}">{int(counts.get(s, 0))} {_e(s)}</span>'
        for s in STATUSES) + _e(f". Ranking rule: {rule}.") + "</p>")
    # the reasons first: what did not work, and why
    why = lb[lb["reason"] != ""]
    bad = df[df["status"] != "ok"]
    parts.append("<h2 id=\"reasons\">Why some results are missing</h2>")
    if not len(why) and not len(bad):
        parts.append("<p>Every (structure, variant) has a qualifying model and every cell is ok.</p>")
    if len(why):
        parts.append(f"<p>{len(why)} (data, structure, variant) with no qualifying model:</p>")
        parts.append(_table(why[["cells", "ok", "candidates", "n_params", "reason"]], text_cols=("reason",)))
    if len(bad):
        parts.append(f"<p>{len(bad)} cell(s) not ok, with their messages:</p>")
        cols = ["data", "structure", "variant", "seed", "status", "message"]
        parts.append(_table(bad[cols].assign(message=bad["message"].fillna("no message stored")), index=False))
    parts.append("<h2 id=\"leaderboard\">Leaderboard</h2><p>The best model of every (data, structure, variant), "
                 "ranked within each data set by J_S on the validation record (models whose J_S agree to a relative "
                 "1e-8, such as one model fitted twice, share a rank); a row without figures says why in "
                 "<em>reason</em>.</p>")
    units = output_units(attrs) or output_units(df.attrs)
    if units:  # what the figures are in
        parts.append("<p>" + _e("JS_valid and JS_ident (J_S, the free-run simulation's mean squared error on the "
                                "validation and identification records), JSF (J_SF, the mean squared static error "
                                "on the static points) and band (B, the bound on J_SF a row's model was judged "
                                "against) are in the output's unit squared: "
                                + "; ".join(f"{d}:{squared_unit(u)}" for d, u in units.items()) + "; fit_valid in %.") + "</p>")
    parts.append(_table(lb, text_cols=("data", "structure", "variant", "reason"), why="reason"))
    parts.append("<h2 id=\"figures\">Figures</h2>")
    for name, png in figures.items():
        parts.append(_img(name, png))
    parts.append("<h2 id=\"summary\">Summary (summary.txt)</h2><pre>" + _e("\n".join(summary)) + "</pre>")
    specs = attrs.get("specs") or []
    if specs:
        parts.append("<h2 id=\"specs\">Specs of the store</h2>")
        rows = pd.DataFrame([{k: s.get(k) for k in ("store", "id", "name", "created", "last_run", "version", "n_cells")
                              if k in s or k != "store"} for s in specs])
        parts.append(_table(rows, index=False, text_cols=tuple(c for c in rows.columns if c != "n_cells")))
        for s in specs:
            label = (f"{s['store']}: " if "store" in s else "") + f"spec {s['id']} {s['name']!r}"
            parts.append(f"<details><summary>{_e(label)}</summary><pre>"
                         f"{_e(json.dumps(s.get('spec'), indent=2, sort_keys=True))}</pre></details>")
    parts.append("<h2 id=\"environment\">Environment</h2>")
    env = pd.DataFrame(list(_environment(attrs).items()), columns=["", "value"])
    parts.append(_table(env, index=False, text_cols=("", "value")))
    parts.append("</body></html>\n")
    return "\n".join(parts)
