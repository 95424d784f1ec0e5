"""Cost of checking a result object's fields (``check_fields``, issue 22) when the library builds one.

    PYTHONPATH=. python benchmarks/bench_result_fields.py [--repeat 7]

Rebuilds a Decision, a ParetoSet (5 members) and a LocalModel from the fields of ones the library
made, with the check as it is and with it switched off (the classes' ``check_fields`` replaced by a
no-op in this process), and, for scale, times the call that makes a Decision (``decide_dsf``).
Median wall time per construction of ``--repeat`` rounds of 20 000 (noisy on a shared VM).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.control import _local  # noqa: E402
from graybox.estimation import _decisions, _pareto  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    st = gb.Structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    model = gb.Model(st, [0.5, 0.3, 0.05, 0.1])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 2.0, 20), 10)
    y = model.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    ub = np.linspace(0.2, 1.8, 5)
    data = gb.Dataset(gb.Record(u[:150], y[:150], Ts=0.1), gb.Record(u[150:], y[150:], Ts=0.1), gb.StaticPoints(ub, model.static_curve(ub), uncertainty=0.05))
    front = gb.pe_pareto(st, data, lambdas=[1.0, 0.5, 0.1, 0.05, 0.01], solver="closed")
    dec = gb.decide_dsf(front, band=data.static.band, fallback="min_jsf")
    local = gb.local_model(model, 0.5, Ts=0.1)
    cases = {"Decision": dec, "ParetoSet (5 members)": front, "LocalModel": local}
    n = 20000
    print(f"# bench_result_fields  {datetime.date.today()}  git {git_rev()}  {machine()}")
    off = {}
    for name, obj in cases.items():
        kw = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj) if f.init}
        cls = type(obj)
        on = timeit(lambda: cls(**kw), repeat=args.repeat, number=n)
        for mod in (_decisions, _pareto, _local):
            off[mod] = mod.check_fields
            mod.check_fields = lambda obj: None
        try:
            without = timeit(lambda: cls(**kw), repeat=args.repeat, number=n)
        finally:
            for mod, fn in off.items():
                mod.check_fields = fn
        print(f"{name:22s}: {1e6 * without:7.2f} µs without the check, {1e6 * on:7.2f} µs with it "
              f"({1e6 * (on - without):+.2f} µs)")
    t = timeit(lambda: gb.decide_dsf(front, band=data.static.band, fallback="min_jsf"), repeat=args.repeat, number=200)
    print(f"{'decide_dsf (for scale)':22s}: {1e6 * t:7.2f} µs per call")


if __name__ == "__main__":
    main()
