"""Structure selection and the signals' zeros: ``centre=False`` (the default) against ``centre=True``.

    .venv/bin/python benchmarks/bench_offsets.py [--part search|select|all] [--cases plant,buck,...]

bench_honest.py's six cases, every record and the static points shifted by offsets given in spreads
(the identification record's standard deviation of each input and of y): none; 3 spreads on u and
y; 1e4 spreads on u; 1e4 spreads on y (search only). Per case, offset and option:

- search: ``frols`` (greedy, BIC), ``frols(search="exact")`` (BIC; cases with at most 45 candidates)
  and ``semp`` (BIC, up to 16 terms or the candidates) on the identification record: the size chosen (centred terms and
  the closure's terms), the least-squares model's free-run J_S on the validation and test records.
- select: ``select_graybox`` black box (LS, ELS) and gray box (the case's band): the chosen row and
  its J_S on the test record (``JS_test``), one worker.

J_S is in output units², which an offset of y does not change: a model that does not depend on the
zeros gives the same figures in every row of a case.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
from bench_honest import cases  # noqa: E402

import graybox as gb  # noqa: E402

SEARCH_OFFSETS = ((0, 0), (3, 3), (1e4, 0), (0, 1e4))
SELECT_OFFSETS = ((0, 0), (3, 3), (1e4, 0))


def _shift(case, ku, ky):
    data, test, cand, band = case
    su = np.atleast_2d(data.ident.u.T).T.std(axis=0) * ku
    sy = data.ident.y.std() * ky
    du = su[0] if data.ident.u.ndim == 1 else su

    def rec(r):
        return replace(r, u=r.u + du, y=r.y + sy)

    sp = data.static
    if sp is not None:
        sp = replace(sp, ubar=sp.ubar + du, ybar=sp.ybar + sy)
    return gb.Dataset(rec(data.ident), rec(data.valid), sp), rec(test), cand, band


def _js(model, r):
    try:
        sim = model.simulate(r, r.y[:model.max_lag] if model.max_lag else None, on_diverge="nan")
    except Exception as e:  # noqa: BLE001 - a failed free run is a figure of the table
        return f"{type(e).__name__}"
    v = gb.mse(r.y, sim, start=model.max_lag)
    return v if np.isfinite(v) else "diverged"


def search(names) -> list[dict]:
    rows = []
    for name, case in cases().items():
        if names and name not in names:
            continue
        n_cand = len(case[2].process)
        for ku, ky in SEARCH_OFFSETS:
            data, test, cand, _ = _shift(case, ku, ky)
            runs = {"frols": lambda c: gb.frols(cand, data, criterion="bic", centre=c),
                    "semp": lambda c: gb.semp(cand, data, criterion="bic", max_terms=min(16, n_cand), centre=c)}
            if n_cand <= 45:
                runs["frols exact"] = lambda c: gb.frols(cand, data, criterion="bic", search="exact", centre=c)
            for how, fn in runs.items():
                for c in (False, True):
                    t0 = time.perf_counter()
                    row = {"case": name, "offset (u, y) spreads": f"{ku:g}, {ky:g}", "search": how, "centre": c}
                    try:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            r = fn(c)
                        chosen = r.stop.split(" terms chosen on centred")[0].rsplit("; ", 1)[-1] if c else len(r.structure)
                        row.update({"chosen": chosen, "n_terms": len(r.structure),
                                    "JS_valid": _js(r.model, data.valid), "JS_test": _js(r.model, test)})
                    except Exception as e:  # noqa: BLE001 - a refusal is a result here
                        row.update({"chosen": f"{type(e).__name__}: {str(e)[:50]}"})
                    row["s"] = time.perf_counter() - t0
                    rows.append(row)
            print(pd.DataFrame([r for r in rows if r["case"] == name and r["offset (u, y) spreads"] == f"{ku:g}, {ky:g}"])
                  .to_markdown(index=False, floatfmt=".4g"), flush=True)
    return rows


def select(names) -> list[dict]:
    rows = []
    for name, case in cases().items():
        if names and name not in names:
            continue
        for ku, ky in SELECT_OFFSETS:
            data, test, cand, band = _shift(case, ku, ky)
            for box, b, est in (("black", np.inf, ["ls", "els"]), ("gray", band, None)):
                for c in (False, True):
                    t0 = time.perf_counter()
                    row = {"case": name, "offset (u, y) spreads": f"{ku:g}, {ky:g}", "box": box, "centre": c}
                    try:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            r = gb.select_graybox(cand, data, band=b, estimator=est, test=test, centre=c)
                        ch = r.chosen
                        row.update({"row": f"{ch.name} {ch['estimator']}", "n_terms": len(r.structure),
                                    "JS_valid": ch["JS_valid"], "JS_test": ch["JS_test"], "JSF_test": ch["JSF_test"],
                                    "regret": r.regret})
                    except Exception as e:  # noqa: BLE001 - a refusal is a result here
                        row.update({"row": f"{type(e).__name__}: {str(e)[:60]}"})
                    row["s"] = time.perf_counter() - t0
                    rows.append(row)
                    print(pd.DataFrame([row]).to_markdown(index=False, floatfmt=".4g"), flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", default="all", choices=("search", "select", "all"))
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all six)")
    a = ap.parse_args()
    names = [s for s in a.cases.split(",") if s]
    print(f"# {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}, {machine()}")
    for part, fn in (("search", search), ("select", select)):
        if a.part in (part, "all"):
            rows = fn(names)
            print(f"\n## {part}\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"), flush=True)


if __name__ == "__main__":
    main()
