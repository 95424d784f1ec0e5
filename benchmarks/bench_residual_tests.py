"""How often the residual tests reject the true structure (their size), on fresh data and on the
identification data.

A NARX system of known structure, y(k) = 0.6 y(k−1) + 0.2 y(k−2) + 0.3 u(k−1) + 0.05 u(k−2)² + 0.4
+ e(k), white equation noise e (σ = 0.03), driven by a random staircase (levels uniform in [0, 2]
held 10 samples) or by white uniform input on [0, 2]; N samples per record. ``gb.residual_tests``
runs under both rules on ``--records`` records in four cases that separate the test from the fit:

- ``true θ, fresh``: the system's own θ (no estimation error): the test's size itself;
- ``θ̂ on its own record``: the true structure fitted by least squares (``gb.els(..., noise=0)``)
  on each record and tested on it (the identification record);
- ``θ̂ (new fit), fresh``: fitted on one record (``--n-ident`` samples, default N), tested on
  another seed's, a new fit each time;
- ``one θ̂ (seed 0), fresh``: a single fit (``--n-ident`` samples) tested on every fresh record.

Under the null (true θ, white noise) a test fails at most 1 − level of the time under the
simultaneous rule (Bonferroni over its K lags) and about 1 − 0.95^K under the pointwise one (any of
K lags outside the pointwise band, were the lags independent). ± is one binomial standard error.

    python benchmarks/bench_residual_tests.py [--records 200] [--n 1000] [--n-ident 1000] [--noise sensor]

With ``--noise sensor`` e is white noise on the measured output instead (y = x + e, x the noise-free
run): the one-step residuals of the true process part are then coloured (e(k) − 0.6 e(k−1) − 0.2 e(k−2)),
the case docs/guide/trust.md describes: φ_ξξ fails by design, the input tests show how much.

    python benchmarks/bench_residual_tests.py --families [--records 200] [--ns 200,500,2000]
        [--pairs gaussian:gaussian,chisq:chisq,...] [--weak 0.01]

``--families``: the simultaneous rule's size and power over input and noise families. The same system with
u = 1 + 0.5 z and e = σ z', z and z' of zero mean and unit variance drawn from a family: ``gaussian``,
``uniform``, ``chisq`` ((χ²₁ − 1)/√2, skewed and heavy-tailed), ``t3`` (Student t of 3 degrees of freedom over
√3) or, for the input, ``staircase`` (uniform levels held 10 samples). Size: the true θ on fresh records (the
share failing each test, and any of the five). Power: the system with a weaker square term (θ of u(k−2)² =
``--weak``) and the model without it, fitted by least squares on the record it is tested on (the true model minus
one term, a missing nonlinearity): the share of records on which each test, and any, fails.
"""

from __future__ import annotations

import argparse
import datetime
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.diagnostics._residuals import TESTS, _lags  # noqa: E402

STRUCTURE = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]
THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])
SIGMA = 0.03
WARMUP = 200  # samples simulated and dropped: a record starts in steady motion


NOISE = "equation"  # or "sensor" (--noise): e added to the free run's output, seen through no dynamics


def record(seed: int, n: int, kind: str) -> gb.Record:
    rng = np.random.default_rng(seed)
    m = n + WARMUP
    u = np.repeat(rng.uniform(0.0, 2.0, m // 10 + 1), 10)[:m] if kind == "staircase" else rng.uniform(0.0, 2.0, m)
    e = SIGMA * rng.standard_normal(m)
    y = np.zeros(m)
    for k in range(2, m):
        y[k] = (THETA[0] * y[k - 1] + THETA[1] * y[k - 2] + THETA[2] * u[k - 1] + THETA[3] * u[k - 2] ** 2
                + THETA[4] + (e[k] if NOISE == "equation" else 0.0))
    if NOISE == "sensor":
        y = y + e
    return gb.Record(u[WARMUP:], y[WARMUP:], Ts=1.0, name=f"seed {seed}")


def fit(rec: gb.Record) -> gb.Model:
    return gb.els(STRUCTURE, rec, noise=0).model


FAMILIES = ("gaussian", "uniform", "chisq", "t3")


def draw(rng: np.random.Generator, family: str, m: int) -> np.ndarray:
    """m samples of zero mean and unit variance from ``family`` (``staircase``: uniform levels held 10 samples)."""
    if family == "gaussian":
        return rng.standard_normal(m)
    if family == "uniform":
        return rng.uniform(-np.sqrt(3), np.sqrt(3), m)
    if family == "chisq":
        return (rng.chisquare(1, m) - 1) / np.sqrt(2)
    if family == "t3":
        return rng.standard_t(3, m) / np.sqrt(3)
    if family == "staircase":
        return np.repeat(rng.uniform(-np.sqrt(3), np.sqrt(3), m // 10 + 1), 10)[:m]
    raise ValueError(f"unknown family {family!r}")


def family_record(seed: int, n: int, inp: str, noise: str, theta: np.ndarray) -> gb.Record:
    """The system of ``theta`` driven by u = 1 + 0.5 z (z of the input family), equation noise σ z' (z' of the
    noise family)."""
    rng = np.random.default_rng(seed)
    m = n + WARMUP
    u = 1.0 + 0.5 * draw(rng, inp, m)
    e = SIGMA * draw(rng, noise, m)
    y = np.zeros(m)
    for k in range(2, m):
        y[k] = (theta[0] * y[k - 1] + theta[1] * y[k - 2] + theta[2] * u[k - 1] + theta[3] * u[k - 2] ** 2
                + theta[4] + e[k])
    return gb.Record(u[WARMUP:], y[WARMUP:], Ts=1.0, name=f"seed {seed}")


def families(args: argparse.Namespace) -> None:
    """Size (true θ) and power (the model without u(k−2)², fitted) of the simultaneous rule per family pair."""
    R = args.records
    weak = THETA.copy()
    weak[3] = args.weak
    minus = [t for t in STRUCTURE if t != "u(k-2)^2"]
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    print(f"# simultaneous rule, max_lag = {args.max_lag}, {R} records per cell, σ_e = {SIGMA}; power: θ of "
          f"u(k-2)^2 = {args.weak}, the model without it fitted by LS on the record it is tested on")
    print("| input × noise | N | case | " + " | ".join(TESTS[k][0] for k in TESTS) + " | any |")
    print("| --- " * (len(TESTS) + 4) + "|")
    for pair in args.pairs.split(","):
        inp, noise = pair.split(":")
        truth = fit(family_record(0, 500, inp, noise, THETA)).with_theta(THETA, name="true θ")
        for n in (int(v) for v in args.ns.split(",")):
            for case in ("size", "power"):
                fails = np.zeros((R, len(TESTS)), bool)
                for s in range(R):
                    if case == "size":
                        model, rec = truth, family_record(1000 + s, n, inp, noise, THETA)
                    else:
                        rec = family_record(1000 + s, n, inp, noise, weak)
                        model = gb.els(minus, rec, noise=0).model
                    r = gb.residual_tests(model, rec, max_lag=args.max_lag)
                    fails[s] = [not r[k].passed for k in TESTS]
                cells = [f"{100 * f:.1f}" for f in fails.mean(axis=0)] + [f"{100 * fails.any(axis=1).mean():.1f}"]
                print(f"| {inp} × {noise} | {n} | {case} | " + " | ".join(cells) + " |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--records", type=int, default=200)
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--n-ident", type=int, default=None, help="samples of the fits' records in the fresh cases")
    ap.add_argument("--max-lag", type=int, default=20)
    ap.add_argument("--noise", choices=("equation", "sensor"), default="equation",
                    help="equation: e(k) enters the recursion (the process part is the whole model); sensor: white "
                         "noise on the measured output (coloured one-step residuals of the true process part)")
    ap.add_argument("--families", action="store_true",
                    help="size and power of the simultaneous rule over input and noise families (see above)")
    ap.add_argument("--pairs", default="gaussian:gaussian,uniform:uniform,staircase:gaussian,gaussian:chisq,"
                    "chisq:chisq,t3:t3,gaussian:t3,chisq:gaussian", help="input:noise families, comma-separated")
    ap.add_argument("--ns", default="200,500,2000", help="record lengths, comma-separated")
    ap.add_argument("--weak", type=float, default=0.01, help="θ of u(k-2)^2 in the power case")
    args = ap.parse_args()
    if args.families:
        families(args)
        return
    global NOISE
    NOISE = args.noise
    R, n = args.records, args.n
    ni = args.n_ident or n
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    print(f"# N = {n} per record (fits for fresh data: {ni}), max_lag = {args.max_lag}, {R} records per case, "
          f"σ_e = {SIGMA}, {NOISE} noise")
    K = {k: _lags(side, args.max_lag).size for k, (_, _, side) in TESTS.items()}
    for kind in ("staircase", "white"):
        truth = fit(record(0, n, kind)).with_theta(THETA, name="true θ")
        one = fit(record(0, ni, kind))
        cases = {
            "true θ, fresh": lambda s: (truth, record(1000 + s, n, kind)),
            "θ̂ on its own record": lambda s: ((lambda r: (fit(r), r))(record(1000 + s, n, kind))),
            "θ̂ (new fit), fresh": lambda s: (fit(record(1000 + s, ni, kind)), record(5000 + s, n, kind)),
            "one θ̂ (seed 0), fresh": lambda s: (one, record(1000 + s, n, kind)),
        }
        print(f"\n## input: {kind}; failure rates per test, pointwise rule / simultaneous rule "
              f"(one θ̂ − θ = {np.array2string(one.theta - THETA, precision=4)})")
        print("| case | " + " | ".join(f"{TESTS[k][0]} (K = {K[k]})" for k in TESTS) + " | any of the five |")
        print("| --- " * (len(TESTS) + 2) + "|")
        print("| expected under the null | " + " | ".join(f"≈ {100 * (1 - 0.95 ** K[k]):.0f} % / ≤ 5 %" for k in TESTS)
              + " | / ≤ 25 % |")
        for case, draw in cases.items():
            fails = {rule: np.zeros((R, len(TESTS)), bool) for rule in ("pointwise", "simultaneous")}
            for s in range(R):
                model, rec = draw(s)
                for rule, f in fails.items():
                    r = gb.residual_tests(model, rec, max_lag=args.max_lag, rule=rule)
                    f[s] = [not r[k].passed for k in TESTS]
            cells = []
            for j in range(len(TESTS)):
                pw, si = fails["pointwise"][:, j].mean(), fails["simultaneous"][:, j].mean()
                cells.append(f"{100 * pw:.0f} / {100 * si:.1f} ± {100 * np.sqrt(si * (1 - si) / R):.1f} %")
            anyf = {rule: f.any(axis=1).mean() for rule, f in fails.items()}
            cells.append(f"{100 * anyf['pointwise']:.0f} / {100 * anyf['simultaneous']:.1f} %")
            print(f"| {case} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
