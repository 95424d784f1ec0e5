"""Equilibria of static equations of degree >= 4 over many input levels: one polynomial at a time, and together.

    benchmarks/.env/bin/python benchmarks/bench_equilibria_batch.py [--levels 20000] [--repeat 3]

The companion-matrix path of the static analysis (`graybox.static._analysis._real_roots_companion`) solved
each (member, level)'s polynomial on its own (numpy.roots per group of roots, then Newton steps on it); it now
stacks the companion matrices of every polynomial with the same groups through one `numpy.linalg.eigvals` and
takes the Newton steps on all of them together. "one at a time" is that path with the batch switched off (as
for one or two polynomials, where it is still taken); the roots of both are compared (they are the same numbers).
Timed: the roots alone for a quartic and a quintic structure, `Model.static_curve` (the equilibria reached, every
level at once) for the quartic, at the same levels, and `operating_curve` (a local model per level; its levels'
equilibria now found together too, against each point's own `Model.equilibria`) at `--curve-levels` of them.
Median wall time of `--repeat` runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import machine, timeit  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.control import _local  # noqa: E402
from graybox.static import _analysis  # noqa: E402

QUARTIC = (gb.Structure(["y(k-1)", "y(k-2)", "y(k-1)^4", "u(k-1)y(k-1)^2", "1"]), [0.3, 0.2, -0.05, 0.001, 0.4])
QUINTIC = (gb.Structure(["1", "y(k-1)", "y(k-1)^3", "y(k-1)^5", "u(k-1)", "u(k-1)y(k-1)^2"]),
           [0.1, 0.7, -0.02, 0.001, 0.5, -0.01])


def _one_at_a_time(fn):
    old = _analysis._BATCH_FROM
    _analysis._BATCH_FROM = 10**12
    try:
        return fn()
    finally:
        _analysis._BATCH_FROM = old


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, default=20000)
    ap.add_argument("--curve-levels", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(machine())
    ub = np.linspace(-300.0, 300.0, args.levels)
    print(f"{args.levels} levels; median wall time of {args.repeat} runs")
    for label, (st, th) in (("quartic", QUARTIC), ("quintic", QUINTIC)):
        theta = np.array([th])
        roots = lambda: _analysis._roots_and_folds(st, theta, ub)  # noqa: E731
        a, b = roots(), _one_at_a_time(roots)
        same = all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a, b))
        before = timeit(lambda: _one_at_a_time(roots), repeat=args.repeat)
        after = timeit(roots, repeat=args.repeat)
        print(f"{label} roots and folds: one at a time {before:.2f} s ({before / args.levels * 1e3:.3f} ms per level), "
              f"together {after:.3f} s ({before / after:.0f}x); the same numbers: {same}")
    model = gb.Model(*QUARTIC)
    curve = lambda: model.static_curve(ub)  # noqa: E731
    before = timeit(lambda: _one_at_a_time(curve), repeat=args.repeat)
    after = timeit(curve, repeat=args.repeat)
    same = np.array_equal(curve(), _one_at_a_time(curve), equal_nan=True)
    print(f"quartic static_curve: one at a time {before:.2f} s, together {after:.2f} s ({before / after:.1f}x); "
          f"the same curve: {same}")
    levels = np.linspace(-300.0, 300.0, args.curve_levels)
    oc = lambda: gb.operating_curve(model, levels, Ts=1.0)  # noqa: E731

    def each_point():
        keep = _local._equilibria_at
        _local._equilibria_at = lambda m, u: [None] * u.shape[0]
        try:
            return _one_at_a_time(oc)
        finally:
            _local._equilibria_at = keep

    before = timeit(each_point, repeat=args.repeat)
    after = timeit(oc, repeat=args.repeat)
    same = gb.to_json(oc()) == gb.to_json(each_point())
    print(f"quartic operating_curve, {args.curve_levels} levels: each point's own equilibria {before:.2f} s, "
          f"together {after:.2f} s ({before / after:.1f}x); the same curve: {same}")


if __name__ == "__main__":
    main()
