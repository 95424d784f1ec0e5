"""Reading records from CSV: a long file in each dialect spreadsheets write, and the bundled plant.

A 10⁶-row file of three columns (time, input, output; ``%.17g``) written as ``,`` with ``.``,
``;`` with ``,`` (decimal comma) and tab with ``.``; each read by ``load_record_csv`` with the
dialect detected (median of 3 reads after one warm-up); then ``load_pumping()`` (two files, 4010
rows). The readers must give the same floats in every dialect (checked here too). Last, a logger's
file with a row of units under the header (``units_row=True``) against the same file without it:
10⁵ rows (``--units-rows``) of time, rpm near 3000 and Pa near 2e5, ``;`` with ``.`` and with ``,``.

Then (``--loggers N``, alone with ``--only-loggers``) a logger's files of N rows: a Campbell Scientific TOA5 file
(every text field quoted) read with ``Ts=`` and with ``time="TIMESTAMP"``, and a plain CSV whose time column holds
ISO 8601 stamps; run it with ``PYTHONPATH`` at an older checkout to compare (a time column of dates was refused
there).

    python benchmarks/bench_csv.py [--rows 1000000] [--units-rows 100000] [--loggers 200000] [--only-loggers]
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

import graybox as gb  # noqa: E402
from graybox.datasets import load_record_csv  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--units-rows", type=int, default=100_000)
    ap.add_argument("--loggers", type=int, default=200_000)
    ap.add_argument("--only-loggers", action="store_true")
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    if args.only_loggers:
        loggers(args.loggers)
        return
    rng = np.random.default_rng(0)
    table = np.column_stack([np.arange(args.rows) * 0.001, rng.standard_normal((args.rows, 2))])
    got = {}
    with tempfile.TemporaryDirectory() as d:
        for name, delim, dec in (("comma, point", ",", "."), ("semicolon, decimal comma", ";", ","),
                                 ("tab, point", "\t", ".")):
            p = Path(d) / "x.csv"
            lines = [delim.join(("t", "u", "y"))]
            lines += [delim.join(f"{v:.17g}".replace(".", dec) for v in row) for row in table]
            p.write_text("\n".join(lines) + "\n")
            size = p.stat().st_size / 1e6
            t = timeit(lambda: load_record_csv(p, u="u", y="y", time="t"), repeat=3)
            got[name] = load_record_csv(p, u="u", y="y", time="t")
            print(f"{name:26s} {args.rows} rows ({size:.1f} MB): {t:.2f} s")
    first = next(iter(got.values()))
    assert all(r.u.tobytes() == first.u.tobytes() and r.y.tobytes() == first.y.tobytes() for r in got.values())
    t = timeit(gb.load_pumping, repeat=20)
    print(f"load_pumping (bundled, 2 files): {t * 1e3:.1f} ms")
    units_row(args.units_rows)
    loggers(args.loggers)


def loggers(n: int) -> None:
    """A TOA5 file and a CSV of ISO stamps, n rows at 1 s (median of 3 reads); a refusal said as such."""
    t0 = datetime.datetime(2026, 1, 1)
    stamps = [f"{t0 + datetime.timedelta(seconds=k):%Y-%m-%d %H:%M:%S}" for k in range(n)]
    with tempfile.TemporaryDirectory() as d:
        toa5, iso = Path(d) / "CR1000_Table1.dat", Path(d) / "iso.csv"
        toa5.write_bytes(('"TOA5","CR1000","CR1000","1234","CR1000.Std.32","CPU:x.CR1","1","Table1"\r\n'
                          '"TIMESTAMP","RECORD","Power","Temp"\r\n"TS","RN","W","degC"\r\n"","","Smp","Avg"\r\n'
                          + "".join(f'"{s}",{k},{k % 7}.5,{0.25 * k}\r\n' for k, s in enumerate(stamps))).encode())
        iso.write_text("t,u,y\n" + "".join(f"{s},{k % 7}.5,{0.25 * k}\n" for k, s in enumerate(stamps)))
        for what, read in ((f"TOA5, Ts=1.0", lambda: load_record_csv(toa5, u="Power", y="Temp", Ts=1.0)),
                           ("TOA5, time='TIMESTAMP'", lambda: load_record_csv(toa5, u="Power", y="Temp",
                                                                             time="TIMESTAMP")),
                           ("CSV, ISO 8601 time column", lambda: load_record_csv(iso, u="u", y="y", time="t"))):
            try:
                t = timeit(read, repeat=3)
            except ValueError as exc:
                print(f"{what:26s} {n} rows: refused ({str(exc)[:60]}…)")
                continue
            assert read().Ts == 1.0 and read().y.size == n
            print(f"{what:26s} {n} rows: {t:.3f} s")


def units_row(n: int) -> None:
    """A units row under the header against none: numpy's reader both times (median of 5 reads)."""
    rng = np.random.default_rng(0)
    table = np.column_stack([np.arange(n) * 0.01, 3000 + 100 * rng.standard_normal(n), 2e5 + 1e3 * rng.standard_normal(n)])
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "x.csv"
        for dec in (".", ","):
            rows = [";".join(f"{v:.17g}".replace(".", dec) for v in row) for row in table]
            got = []
            for units in (False, True):
                p.write_text("\n".join(["t;speed;p"] + (["[s];[rpm];[Pa]"] if units else []) + rows) + "\n")
                read = lambda: load_record_csv(p, u="speed", y="p", time="t", units_row=units)  # noqa: E731
                t = timeit(read, repeat=5)
                got.append(read())
                print(f"decimal {dec!r}, units_row={units!s:5s}: {n} rows {t:.3f} s")
            assert got[0].y.tobytes() == got[1].y.tobytes() and got[1].units == ("rpm", "Pa")


if __name__ == "__main__":
    main()
