"""Cost of the SE objective's static part (J_SF) per GA generation, ℓ = 3 structure.

    benchmarks/.env/bin/python benchmarks/bench_static.py [--repeat 7]

The degree-3, 23-term structure `graybox reproduce` selects on the bundled plant (FROLS, ny = nu = 6,
constant included), its SE problem with the 10 static points, and two populations of 200:
"seeds" is a first generation (the least-squares estimate plus 199 least-squares fits on 30 random
samples, the paper's seeds); "late" is the best member of a short GA run at λ1 = 0.5 with the GA's
own variation (heuristic crossover with it and 5 % Gaussian mutation), which is what most
generations of a sweep evaluate. Reported: the median CPU time of the process (less sensitive than
wall time to the steal time of a shared VM) of `SEProblem.jsf` (every member × every static point)
and of `SEProblem.js` (the free runs, for scale), and how the members' static points end (reached /
no stable equilibrium / diverged / did not settle).
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import machine  # noqa: E402

from graybox import Candidates  # noqa: E402
from graybox.datasets import load_pumping  # noqa: E402
from graybox.estimation._simulation_error import GAOptions, SEProblem, ga_front  # noqa: E402
from graybox.selection._forward_regression import frols  # noqa: E402


def populations(prob: SEProblem) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(0)
    seeds = np.vstack([prob.ls_theta()[None, :], prob.random_ls(rng, 199)])
    th = ga_front(prob, [1.0, 0.5], options=GAOptions(population=60, generations=15), seed=0, progress=False).thetas
    best = th[-1]
    mates = seeds[rng.integers(0, 200, 199)]
    r = rng.random((199, 1))
    kids = mates + r * (best - mates) * 1.2
    kids = np.where(rng.random((199, 1)) < 0.7, best + (kids - best) * 0.05, kids)
    mut = rng.random(kids.shape) < 0.1
    kids = kids + mut * rng.standard_normal(kids.shape) * 0.05 * np.abs(kids)
    return {"seeds": seeds, "late": np.vstack([best[None, :], kids])}


def cpu_time(fn, repeat: int, number: int = 5) -> float:
    """Median CPU seconds per call of ``fn`` (after a warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        for _ in range(number):
            fn()
        times.append((time.process_time() - t0) / number)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    data = load_pumping()
    sel = frols(Candidates(6, 6, ne=2, degree=3), data.ident, n_terms=23, include=["1"])
    prob = SEProblem(sel.structure, data.ident, data.static)
    print(f"# bench_static  {datetime.date.today()}  {machine()}")
    print(f"# structure: {prob.structure}")
    for name, pop in populations(prob).items():
        t_sf = cpu_time(lambda: prob.jsf(pop), args.repeat)
        t_s = cpu_time(lambda: prob.js(pop), args.repeat)
        jsf = prob.jsf(pop)
        line = (f"{name:6s}: J_SF {1e3 * t_sf:8.2f} ms per generation (200 members × {len(data.static)} points), "
                f"J_S {1e3 * t_s:7.2f} ms; finite J_SF for {int(np.isfinite(jsf).sum())}/200")
        try:
            from graybox.static._analysis import reached_equilibria

            res = reached_equilibria(prob.structure, pop, data.static.ubar, data.static.ybar)
            codes, counts = np.unique(res.status, return_counts=True)
            line += "; points: " + ", ".join(f"{res.STATUS[c]} {n}" for c, n in zip(codes, counts))
        except ImportError:
            pass
        print(line)


if __name__ == "__main__":
    main()
