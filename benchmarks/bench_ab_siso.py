"""A/B timing of the single-input kernels: this tree against an older copy of the package.

    python benchmarks/bench_ab_siso.py /path/to/dir_holding_graybox_base

The older tree is imported as ``graybox_base`` (copy its ``graybox`` folder under that name);
both are timed in alternation in one process, many short rounds, and the minimum per case is
kept, so that the load of a shared machine affects both alike. Model (15), 3200 samples, P = 200.
"""

from __future__ import annotations

import sys
import time

import numpy as np

sys.path.insert(0, sys.argv[1])
import graybox as new  # noqa: E402
import graybox_base as old  # noqa: E402
from graybox.core._simulation_kernels import batch_sse as sse_new, encode as enc_new, free_run_sensitivity as sen_new  # noqa: E402
from graybox_base._kernels import batch_sse as sse_old, encode as enc_old, free_run_sensitivity as sen_old  # noqa: E402

N, P = 3200, 200


def cases(gb, enc, sse, sen):
    rng = np.random.default_rng(0)
    m = gb.reference.paper_model(15)
    u = np.repeat(rng.uniform(750, 1650, N // 80 + 1), 80)[:N]
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    rec = gb.Record(u, m.simulate(u, y0), Ts=0.05)
    th = m.theta * (1 + 0.002 * rng.standard_normal((P, m.n_params)))
    code, L = enc(m.structure), m.max_lag
    return {
        "single free run (Model.simulate)": (lambda: m.simulate(rec), 1),
        "batch of 200 (simulate_many)": (lambda: gb.simulate_many(m.structure, th, rec), P),
        "batch SSE of 200 (batch_sse)": (lambda: sse(code, th, rec.u, rec.y, L), P),
        "free-run sensitivities": (lambda: sen(code, m.theta, rec.u, rec.y[:L], L), 1),
    }, (N - L) * m.n_params


def main() -> None:
    a, evals = cases(new, enc_new, sse_new, sen_new)
    b, _ = cases(old, enc_old, sse_old, sen_old)
    best = {k: [np.inf, np.inf] for k in a}
    for _ in range(40):
        for k in a:
            for i, (fn, _) in enumerate((a[k], b[k])):
                fn()
                t0 = time.perf_counter()
                for _ in range(5):
                    fn()
                best[k][i] = min(best[k][i], (time.perf_counter() - t0) / 5)
    print(f"{'case':40s} {'this tree':>12s} {'base':>12s} {'ratio':>7s}")
    for k, (tn, to) in best.items():
        print(f"{k:40s} {tn * 1e3:9.3f} ms {to * 1e3:9.3f} ms {tn / to:7.3f}")


if __name__ == "__main__":
    main()
