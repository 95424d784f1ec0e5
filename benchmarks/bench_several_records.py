"""Several identification records in select_graybox: each record a fold, against a validation record.

    .venv/bin/python benchmarks/bench_several_records.py [--cases plant,buck]

For bench_honest.py's cases (test records untouched by every choice): the identification record cut
into halves E1, E2 and the validation record E3, three experiments of one plant. Three ways to give
them, gray box (the case's band) and black box (no band) chosen the same way, scored on the test record:

- ``valid``: ``select_graybox(cand, Dataset(ident, valid))``: fit on the identification record, choose on
  the validation record's blocks (the default protocol);
- ``records``: ``select_graybox(cand, [E1, E2, E3])``: each record a fold (fitted on the other two,
  scored on it), the chosen structure refitted on all three;
- ``one record``: ``select_graybox(cand, ident)``: 3 contiguous folds of the identification record alone
  (each fitted on the segments around it, as separate records).
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
from bench_honest import cases  # noqa: E402

import graybox as gb  # noqa: E402


def ways(data: gb.Dataset) -> dict[str, tuple]:
    """name -> (data argument, validation) of the three ways to give the experiments."""
    n = len(data.ident)
    e1, e2 = data.ident.slice(0, n // 2, name="E1"), data.ident.slice(n // 2, None, name="E2")
    return {"valid": (data, None), "records": ([e1, e2, data.valid], None), "one record": (data.ident, None)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    ap.add_argument("--ways", default="", help="comma-separated ways (default: all; 'one record' alone runs on a "
                    "graybox without several records, e.g. PYTHONPATH=<older checkout>, to compare its folds)")
    args = ap.parse_args()
    names = [c for c in args.cases.split(",") if c]
    chosen_ways = [w for w in args.ways.split(",") if w]
    print(f"# bench_several_records ({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"git {git_rev()}, graybox from {Path(gb.__file__).parent}): {machine()}", flush=True)
    warnings.simplefilter("ignore")
    rows = []
    for name, (data, test, cand, band) in cases().items():
        if names and name not in names:
            continue
        for way, (arg, valid) in ways(data).items():
            if chosen_ways and way not in chosen_ways:
                continue
            t0 = time.perf_counter()
            kw = dict(test=test, executor="processes", workers=2)
            g = gb.select_graybox(cand, arg, data.static, band=band, **kw)
            k = gb.select_graybox(cand, arg, data.static, band=np.inf, **kw)
            gj, kj = g.chosen["JS_test"], k.chosen["JS_test"]
            rows.append({"case": name, "way": way, "gray": f"{len(g.structure)} {g.chosen['estimator']}",
                         "gray JS_test": gj, "black": f"{len(k.structure)} {k.chosen['estimator']}",
                         "black JS_test": kj, "gray / black": gj / kj, "gray regret": g.regret,
                         "black regret": k.regret, "gray JSF_test": g.chosen["JSF_test"],
                         "s": time.perf_counter() - t0})
            print(f"{name}, {way}: {rows[-1]['s']:.0f} s (load {os.getloadavg()[0]:.1f})", flush=True)
    print("\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))


if __name__ == "__main__":
    main()
