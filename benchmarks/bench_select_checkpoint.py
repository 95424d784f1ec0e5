"""select_graybox(checkpoint=): what a call costs with every row kept, with a new test record, and without.

    python benchmarks/bench_select_checkpoint.py

The README's gray call on the bundled plant (28 rows) with a test record made of the validation record's last
300 samples (the choice made on its first 500): a fresh call, the same call again with every row kept, the same
rows reporting on another test record (its scores remade from the kept θ, no fit), and a call without the
checkpoint for reference. Prints one table row per call, the machine, git hash and load average.
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings
from pathlib import Path

import graybox as gb
from _common import git_rev, machine


def main() -> None:
    data = gb.load_pumping()
    valid = data.valid
    ds = gb.Dataset(data.ident, valid.slice(0, 500), data.static)
    tests = {"A": valid.slice(500, 650), "B": valid.slice(650, 800)}
    cand = gb.Candidates(ny=6, nu=6, degree=2)
    print(f"# {machine()}, git {git_rev()}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"load average {os.getloadavg()[0]:.1f}")
    print("| call | wall | rows | chosen | JS_test |")
    print("| --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sel.npz"
        runs = (("no checkpoint, test A", None, "A"), ("new checkpoint, test A", path, "A"),
                ("every row kept, test A", path, "A"), ("every row kept, test B (scores remade)", path, "B"),
                ("every row kept, test B again", path, "B"))
        for what, ck, t in runs:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t0 = time.perf_counter()
                sel = gb.select_graybox(cand, ds, test=tests[t], checkpoint=ck, progress=False)
                wall = time.perf_counter() - t0
            print(f"| {what} | {wall:.1f} s | {len(sel.table)} | {sel.chosen.name} {sel.chosen['estimator']} | "
                  f"{sel.chosen['JS_test']:.4g} |")
    print(f"# load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
