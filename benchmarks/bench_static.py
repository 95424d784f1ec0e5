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

    benchmarks/.env/bin/python benchmarks/bench_static.py --part single [--repeat 7]

"single": what a gradient SE fit pays at every trial θ, one member at a time: the equilibria reached
at the static points (`reached_equilibria`, P = 1) the stability-margin check (`within_margin`,
along the record and at those equilibria) and the streamed QR factor of the free run's Jacobian, for the README's selection structures on the plant
(SEMP from Candidates(6, 6, degree=2), 6, 12 and 16 terms, least-squares θ).
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

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


def cpu_time(fn, repeat: int, number: int = 5, clock=time.process_time) -> float:
    """Median CPU seconds per call of ``fn`` (after a warm-up call); or of another ``clock``."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = clock()
        for _ in range(number):
            fn()
        times.append((clock() - t0) / number)
    return statistics.median(times)


def single(repeat: int) -> None:
    from graybox import semp
    from graybox.estimation._simulation_error import _r_factor
    from graybox.static._analysis import reached_equilibria

    data = load_pumping()
    print(f"# bench_static --part single  {datetime.date.today()}  {machine()}")
    for n in (6, 12, 16):
        st = semp(Candidates(6, 6, degree=2), data, n_terms=n).structure
        prob = SEProblem(st, data.ident, data.static, margin=0.006)
        th = prob.ls_theta()[None, :]
        sp = data.static
        # wall time, one BLAS thread as inside a sweep: the process's CPU time counts the BLAS threads
        # still spinning after SEMP's fits (measured up to 2× the wall time of these calls)
        with threadpool_limits(limits=1, user_api="blas"):
            t_r = cpu_time(lambda: reached_equilibria(st, th, sp.ubar, sp.ybar), repeat, 200, time.perf_counter)
            t_m = cpu_time(lambda: prob.within_margin(th, sp.ybar[None, :]), repeat, 200, time.perf_counter)
            z = th[0] * prob.scale
            t_j = cpu_time(lambda: _r_factor(prob, z, 0.5), repeat, 50, time.perf_counter)
        print(f"semp-{n} ({len(st)} terms): reached_equilibria {1e3 * t_r:.3f} ms, within_margin {1e3 * t_m:.3f} ms "
              f"per θ ({len(sp)} static points); the Jacobian's factor (_r_factor, {len(data.ident)} samples, "
              f"λ1 = 0.5) {1e3 * t_j:.3f} ms")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--part", default="generation", choices=("generation", "single"))
    args = ap.parse_args()
    if args.part == "single":
        single(args.repeat)
        return
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
