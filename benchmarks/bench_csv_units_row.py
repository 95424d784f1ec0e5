"""Reading a logger's file with a row of units under the header (``units_row=True``) against the same file without it.

A 10⁵-row file of time, input (rpm near 3000) and output (Pa near 2e5), ``;`` with ``.`` and ``;``
with decimal commas; each read by ``load_record_csv`` (median of 5 reads after one warm-up). Both
readings must give the same floats (checked).

    python benchmarks/bench_csv_units_row.py [--rows 100000]
"""

from __future__ import annotations

import argparse
import datetime
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

from graybox.datasets import load_record_csv  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=100_000)
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    rng = np.random.default_rng(0)
    n = args.rows
    table = np.column_stack([np.arange(n) * 0.01, 3000 + 100 * rng.standard_normal(n), 2e5 + 1e3 * rng.standard_normal(n)])
    with tempfile.TemporaryDirectory() as d:
        for dec in (".", ","):
            rows = [";".join(f"{v:.17g}".replace(".", dec) for v in row) for row in table]
            got = []
            for units in (False, True):
                p = Path(d) / "x.csv"
                p.write_text("\n".join(["t;speed;p"] + (["[s];[rpm];[Pa]"] if units else []) + rows) + "\n")
                read = lambda: load_record_csv(p, u="speed", y="p", time="t", units_row=units)  # noqa: E731
                t = timeit(read, repeat=5)
                got.append(read())
                print(f"decimal {dec!r}, units_row={units!s:5s}: {n} rows {t:.3f} s")
            assert got[0].y.tobytes() == got[1].y.tobytes() and got[1].units == ("rpm", "Pa")


if __name__ == "__main__":
    main()
