"""Fill numba's on-disk cache of graybox's kernels before the suite's processes start (tests/conftest.py).

``python tests/_warm_kernels.py PART`` runs one part: small calls of the public API that compile the kernels of one
half of the package. On a fresh checkout every process the suite starts (its pytests, the Sphinx build's notebook
kernels, worker processes) compiled the kernels it met before any other had cached them: 116 s of CPU where one
compilation of each is ~40 s (BENCHMARKS.md). Two parts side by side compile each kernel once; on a warm cache each
part only loads them. A kernel no part reaches is compiled by the first test that needs it, as before: this file saves
time, it decides nothing.
"""

from __future__ import annotations

import sys
import warnings

import numpy as np


def _first_order(n: int = 300, seed: int = 0):
    import graybox as gb

    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.5, 2.0, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.7 * y[k - 1] + 0.2 * u[k - 1] + 0.05 * u[k - 1] ** 2 + 0.05 * y[k - 1] * u[k - 1]
    return gb.Record(u, y + 0.002 * rng.standard_normal(n), name=f"warm {seed}")


def simulation() -> None:
    """Free runs, predictions, batches (one thread and several), sensitivities, SE fits, neural NARX, the plants."""
    import graybox as gb
    from graybox.core import _simulation_kernels as K
    from graybox.datasets import pumping

    rec, rec2 = _first_order(), _first_order(seed=1)
    m = gb.reference.paper_model(15)
    code = K.encode(m.structure)
    th = m.theta
    u, y = rec.u * 500 + 750, rec.y * 10
    K.simulate_one(code, th, u, y[:3], 3, None)
    K.simulate_one(code, th, u, y[:3], 3, 1e6)
    K.predict_ahead(code, th, u, y, 3, 5, None)
    for threads in (1, 2):
        K.simulate_batch(code, np.vstack([th] * 8), u, y, 3, threads=threads, bounded=True)
        K.batch_sse(code, np.vstack([th] * 8), u, y, 3, threads=threads, bounded=True)
    # a feedback through a second input at lag 3, growing: the steady gain stops its runs, which are run again by the
    # lattice margin (the lattice kernels)
    a = -np.real(np.poly([1.001 * np.exp(3.13j), 1.001 * np.exp(-3.13j), 0.5]))[1:]
    res = K.encode(gb.parse_structure(["y(k-1)", "y(k-2)", "y(k-3)v(k-1)", "u(k-1)"]), ("u", "v"))
    uv = np.column_stack([np.sin(3.13 * np.arange(4000)), np.ones(4000)])
    K.simulate_one(res, np.r_[a, 1.0], uv, np.zeros(3), 3, None)
    K.predict_ahead(res, np.r_[a, 1.0], uv, np.zeros(4000), 3, 4000, None)
    K.simulate_batch(res, np.vstack([np.r_[a, 1.0]] * 2), uv, np.zeros(3), 3, bounded=True)
    K.batch_sse(res, np.vstack([np.r_[a, 1.0]] * 2), uv, np.zeros(4000), 3, bounded=True)
    K.free_run_sensitivity(code, th, u, y[:3], 3)
    for _ in K.free_run_sensitivity_blocks(code, th, K.input_products(code.fptr, code.fsig, code.flag, code.fpow, u, 3),
                                           y[:3], 3, block=64):
        pass
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-1)u(k-1)", "1"])
    data = gb.Dataset(rec, rec2, gb.StaticPoints(np.linspace(0.6, 1.9, 5), np.linspace(1.0, 3.0, 5)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gb.se_pareto(s, data.ident, data.static, lambdas=[0.5, 1.0], method="gradient", progress=False)
        gb.se_pareto(s, data.ident, data.static, lambdas=[0.5], method="ga",
                     options=gb.GAOptions(population=16, generations=2), threads=2, progress=False)
        els = gb.els(gb.parse_structure(["y(k-1)", "u(k-1)", "e(k-1)"]), rec)
        gb.residual_tests(els.model, rec2)
        gb.Model(s, np.array([0.6, 0.2, 0.05, 0.05, 0.0])).simulate(rec2)  # feedback through the input
        gb.neural_narx(rec, ny=1, nu=1, ne=1, hidden=2, seed=0).model.simulate(rec2)
        gb.output_error(s, rec, n_starts=1)
    pumping.generate()  # the plant's integrator, as the data tests run it


def statics() -> None:
    """Equilibria, static curves and gains, stability tests, settling runs (grouped too), selection's searches."""
    import graybox as gb
    from graybox.datasets._pumping_miso import generate_miso

    rec, rec2 = _first_order(), _first_order(seed=1)
    static = gb.StaticPoints(np.linspace(0.6, 1.9, 5), np.linspace(1.0, 3.0, 5))
    data = gb.Dataset(rec, rec2, static)
    cand = gb.Candidates(ny=2, nu=2, degree=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gb.frols(cand, rec, n_terms=4)
        gb.frols(cand, rec, n_terms=3, search="exact")
        m = gb.reference.paper_model(17)
        for ub in (800.0, 1200.0):
            gb.equilibria(m.structure, m.theta, ub)
        gb.static_curve(m.structure, m.theta, np.linspace(800, 1500, 7))
        gb.static_gain(m.structure, m.theta, np.linspace(800, 1500, 7))
        gb.jsf(m, gb.load_pumping().static)
        gb.local_model(m, 1200.0)
        cubic = gb.parse_structure(["y(k-1)", "y(k-1)^2", "y(k-1)^3", "u(k-1)", "1"])
        gb.equilibria(cubic, np.array([0.5, 0.1, -0.05, 0.2, 0.01]), 1.0)
        gb.select_graybox(cand, data, band=1.0, sizes=[3], progress=False)
        quadratic = gb.parse_structure(["y(k-1)", "y(k-1)^2", "u(k-1)"])
        slow = gb.Model(quadratic, np.array([1 - 2e-5, -4e-7, 1.6e-5]))  # settles past the first budget
        gb.jsf(slow, static)  # settling runs (not rational in y), a second budget
        gb.se_pareto(quadratic, rec, static, lambdas=[0.5, 1.0], method="gradient", progress=False)  # members' J_SF
        generate_miso()


if __name__ == "__main__":
    {"simulation": simulation, "statics": statics}[sys.argv[1]]()
