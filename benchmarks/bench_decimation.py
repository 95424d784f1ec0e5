"""Decimating an oversampled record before identification: does Billings & Aguirre's rule pay?

    .venv/bin/python benchmarks/bench_decimation.py [--cases synthetic,plant]

Cases (identification, validation and test records of one plant; the test record untouched):

- ``synthetic``: a first-order nonlinear plant in continuous time, T dy/dt = −(y + 0.2 y³) + u + 0.5 u²,
  T = 1 s, integrated by RK4 at 100 Hz under APRBS inputs (levels in [0, 2] held 0.5–3 s), white
  measurement noise σ = 0.02 on y; identification 60 000 samples, validation and test 20 000 (other
  seeds). The test is scored against its noise-free output. Variants: ``synthetic held 36``, the input's levels changing
  only at multiples of 36 samples (held over every decimation window of the factors tried), and
  ``synthetic held 36 noisy``, with noise σ = 0.2 as well.
- ``plant``: the bundled pumping plant (20 Hz), its identification and validation records; the test a
  fresh run of its simulator (seed + 1), scored against its true pressure (no transmitter noise).

Ways: the record as it is (q = 1), and decimated by factors around ``decimation_advice``'s q, with
the anti-alias filter on the output (the default) and without it. Each way chooses a black box by
``select_graybox(Candidates(ny, nu, degree), ident, validation=valid, estimator=["ls", "els"])`` (the
same candidates at every rate: lags count samples), scores its free run on the test record decimated
the same way (every way's error is a time average over the same 1000 s or 200 s), and times the call.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402


def _plant_rhs(y, u):
    return -(y + 0.2 * y**3) + u + 0.5 * u**2


def synthetic_record(n: int, seed: int, name: str, align: int = 1, noise: float = 0.02) -> tuple[gb.Record, np.ndarray]:
    """(noisy record, noise-free output) of the synthetic plant at 100 Hz; the input's levels change only
    at multiples of ``align`` samples (held over every decimation window of a factor dividing it)."""
    dt, T = 0.01, 1.0
    m = -(-n // align)
    u = np.repeat(gb.design_input("aprbs", m, low=0.0, high=2.0, hold=(max(1, 50 // align), 300 // align),
                                  seed=seed), align)[:n]
    y = np.zeros(n)
    for k in range(n - 1):  # RK4 with u held over the step
        a = _plant_rhs(y[k], u[k]) / T
        b = _plant_rhs(y[k] + 0.5 * dt * a, u[k]) / T
        c = _plant_rhs(y[k] + 0.5 * dt * b, u[k]) / T
        d = _plant_rhs(y[k] + dt * c, u[k]) / T
        y[k + 1] = y[k] + dt / 6 * (a + 2 * b + 2 * c + d)
    noisy = y + noise * np.random.default_rng([seed, 9]).standard_normal(n)
    return gb.Record(u, noisy, Ts=dt, name=name), y


def cases() -> dict:
    out = {}
    for name, align, noise in (("synthetic", 1, 0.02), ("synthetic held 36", 36, 0.02),
                               ("synthetic held 36 noisy", 36, 0.2)):
        ident, _ = synthetic_record(60000, 1, "synthetic ident", align, noise)
        valid, _ = synthetic_record(20000, 2, "synthetic valid", align, noise)
        test, truth = synthetic_record(20000, 3, "synthetic test", align, noise)
        out[name] = (ident, valid, test, truth, gb.Candidates(2, 2, degree=3))
    from graybox.datasets import pumping

    data = gb.load_pumping()
    run = pumping.generate(seed=data.extra["seed"] + 1)[0]
    out["plant"] = (data.ident, data.valid, run.record("pumping, seed + 1"), np.asarray(run.pressure, float),
                    gb.Candidates(6, 6, degree=2))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    args = ap.parse_args()
    names = [c for c in args.cases.split(",") if c]
    print(f"# bench_decimation ({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}): "
          f"{machine()}", flush=True)
    rows = []
    for name, (ident, valid, test, truth, cand) in cases().items():
        if names and name not in names:
            continue
        advice = gb.decimation_advice(ident)
        print(f"{name}: {advice}", flush=True)
        q0 = advice.q
        ways = [(1, True)] + [(q, True) for q in sorted({max(2, q0 // 2), q0, 2 * q0})] + [(q0, False)]
        for q, aa in ways:
            dec = [gb.decimate(r, q, antialias=aa) for r in (ident, valid, test)]
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sel = gb.select_graybox(cand, dec[0], validation=dec[1], estimator=["ls", "els"])
            s = time.perf_counter() - t0
            m = sel.model
            sim = m.simulate(dec[2], on_diverge="nan")
            L = cand.max_lag
            err = sim[L:] - truth[::q][L:]
            js_true = float(np.mean(err**2)) if np.all(np.isfinite(err)) else np.inf
            rows.append({"case": name, "q": q, "antialias": aa, "Ts (s)": ident.Ts * q, "ident samples": len(dec[0]),
                         "chosen": f"{len(m.structure)} {sel.chosen['estimator']}",
                         "J_S test vs truth": js_true, "J_S valid": sel.chosen["JS_valid"], "select s": s})
            print(f"  q={q} antialias={aa}: {rows[-1]}", flush=True)
    print("\n" + pd.DataFrame(rows).to_markdown(index=False, floatfmt=".4g"))


if __name__ == "__main__":
    main()
