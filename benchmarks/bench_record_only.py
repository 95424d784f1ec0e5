"""One record only: a held-out tail used as the validation record, against the folds of select_graybox.

    .venv/bin/python benchmarks/bench_record_only.py

For four of bench_honest.py's cases: the identification record cut into a head (67, 75, 80 %) and a
tail; the gray box (the case's band) and the black box (no band) fitted on the head, chosen on the
tail's blocks, scored on the case's test record. Compare with ``bench_honest.py --record-only``
(refitted folds of the whole record).
"""

from __future__ import annotations

import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402
from bench_honest import cases  # noqa: E402

import graybox as gb  # noqa: E402

CASES = ("two-speed rig", "buck", "plant", "slow disturbance")
SHARES = (0.67, 0.75, 0.8)


def main() -> None:
    print(f"# bench_record_only ({datetime.date.today()}, git {git_rev()}): {machine()}")
    warnings.simplefilter("ignore")
    all_cases = cases()
    print("| case | head share | gray: terms, estimator, test J_S | black: terms, estimator, test J_S | gray / black | "
          "regret | J_SF |")
    print("|---|---|---|---|---|---|---|")
    for name in CASES:
        data, test, cand, band = all_cases[name]
        for share in SHARES:
            n = int(share * len(data.ident))
            head, tail = data.ident.slice(0, n, name="head"), data.ident.slice(n, None, name="tail")
            kw = dict(validation=tail, test=test, executor="processes", workers=2)
            g = gb.select_graybox(cand, head, data.static, band=band, **kw)
            k = gb.select_graybox(cand, head, data.static, band=np.inf, **kw)
            gj, kj = g.chosen["JS_test"], k.chosen["JS_test"]
            print(f"| {name} | {share} | {len(g.structure)}, {g.chosen['estimator']}, {gj:.4g} | "
                  f"{len(k.structure)}, {k.chosen['estimator']}, {kj:.4g} | {gj / kj:.3g} | "
                  f"{gj / g.table['JS_test'].min():.3g} | {g.chosen['JSF_test']:.3g} |", flush=True)


if __name__ == "__main__":
    main()
