"""Subset search beyond greedy (issue 26): how often each selector recovers a known structure.

    .venv/bin/python benchmarks/bench_search.py [--seeds 10] [--n 1000] [--dump peers.npz]

Synthetic polynomial NARX systems of known structure (two single-input, two two-input), driven by
staircases (each level held 5 samples: u(k-1) = u(k-2) on 4 samples in 5) or by white uniform
inputs, with equation noise e(k) (y(k) = F(·) + e(k), the NARX model class itself, so the true
structure is what a consistent selector should find) of 0, 1 % and 5 % of the noise-free output's
standard deviation. Selectors: FROLS (greedy), ``frols(search="swap")``, ``frols(search="exact")``
and SEMP, each (a) given the true size (``n_terms``), (b) choosing it by BIC over 1 … 12 terms and (c) by EBIC
(BIC plus 2 ln C(p, k): the subsets of k terms among the p candidates; swap's and exact's default since
2026-11-29). ``--selectors`` and ``--modes`` pick among them.
A trial counts as recovered when the selected set of terms equals the true one.

``--dump`` writes the candidate matrices and targets of every trial to an .npz file for
``bench_search_peers.py``, which runs other libraries' selectors on exactly the same columns in a
separate environment (they are never installed in graybox's own).
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
from graybox import Candidates, Model, Record, Structure, stacked_regressors  # noqa: E402

#: name → (true terms, θ, input names, candidate lags ny = nu)
SYSTEMS = {
    "SISO-A": (["y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-2)^2", "1"],
               [0.5, 0.3, 0.4, -0.2, 0.15, 0.1], ("u",)),
    "SISO-B": (["1", "y(k-1)", "y(k-2)", "u(k-2)", "u(k-1)y(k-1)", "u(k-1)^2"],
               [0.3, 0.7, -0.3, 0.6, 0.2, -0.25], ("u",)),
    "MISO-A": (["y(k-1)", "y(k-2)", "u1(k-2)", "u2(k-1)", "u1(k-1)y(k-1)", "u2(k-2)^2"],
               [0.6, 0.2, 0.5, -0.4, -0.15, 0.2], ("u1", "u2")),
    "MISO-B": (["y(k-1)", "u1(k-1)", "u2(k-2)", "u1(k-2)u2(k-1)", "y(k-2)u2(k-1)", "1"],
               [0.7, 0.4, 0.3, 0.2, -0.1, 0.1], ("u1", "u2")),
}
INPUTS = ("staircase", "random")
NOISE = (0.0, 0.01, 0.05)
SELECTORS = ("greedy", "swap", "exact", "semp")
MAX_TERMS = 12
HOLD = 5


def record(system: str, kind: str, noise: float, seed: int, n: int) -> Record:
    terms, theta, inputs = SYSTEMS[system]
    rng = np.random.default_rng(seed)
    m = len(inputs)
    if kind == "staircase":
        u = np.column_stack([np.repeat(rng.uniform(-1, 1, n // HOLD + 1), HOLD)[:n] for _ in range(m)])
    else:
        u = rng.uniform(-1, 1, (n, m))
    clean = Model(Structure(terms), np.array(theta), input_names=inputs).simulate(u if m > 1 else u[:, 0],
                                                                                   np.zeros(2))
    e = noise * np.std(clean) * rng.standard_normal(n)
    # equation noise enters the recursion as one more input v with v(k-1) = e(k) and θ = 1
    v = np.r_[e[1:], 0.0]
    noisy = Model(Structure(terms + ["v(k-1)"]), np.r_[theta, 1.0], input_names=inputs + ("v",))
    y = noisy.simulate(np.column_stack([u, v]), np.zeros(2))
    return Record(u if m > 1 else u[:, 0], y, input_names=inputs, name=f"{system}/{kind}/{noise}/{seed}")


def candidates(system: str) -> Structure:
    return Candidates(3, 3, degree=2, input_names=SYSTEMS[system][2])


def select(name: str, cand: Structure, rec: Record, **kw):
    if name == "semp":
        return gb.semp(cand, rec, **kw).structure
    return gb.frols(cand, rec, search=name, **kw).structure


def one_step_rss(structure: Structure, rec: Record, start: int) -> float:
    psi, y = stacked_regressors(structure, rec, start=start)
    theta, *_ = np.linalg.lstsq(psi, y, rcond=None)
    return float(np.sum((y - psi @ theta) ** 2))


MODES = {"n_terms": None, "bic": {"criterion": "bic", "max_terms": MAX_TERMS},
         "ebic": {"criterion": "ebic", "max_terms": MAX_TERMS}}


def trials(seeds: int, n: int, dump: str | None, selectors=SELECTORS, modes=tuple(MODES)) -> pd.DataFrame:
    rows = []
    store: dict[str, np.ndarray] = {}
    for system in SYSTEMS:
        cand = candidates(system)
        true = set(Structure(SYSTEMS[system][0]))
        k = len(true)
        for kind in INPUTS:
            for noise in NOISE:
                for seed in range(seeds):
                    rec = record(system, kind, noise, seed, n)
                    rss_true = one_step_rss(Structure(SYSTEMS[system][0]), rec, cand.max_lag)
                    if dump:
                        psi, y = stacked_regressors(cand.process, rec, start=cand.max_lag)
                        key = f"{system}|{kind}|{noise}|{seed}"
                        store[key + "|X"], store[key + "|y"] = psi, y
                        store[key + "|true"] = np.array([cand.process.index(t) for t in true])
                    for sel in selectors:
                        for mode in modes:
                            kw = MODES[mode] or {"n_terms": k}
                            t0 = time.perf_counter()
                            with warnings.catch_warnings():
                                warnings.simplefilter("ignore")
                                got = select(sel, cand, rec, **kw)
                            dt = time.perf_counter() - t0
                            rows.append(dict(system=system, inputs=kind, noise=noise, seed=seed, selector=sel,
                                             mode=mode, recovered=set(got) == true, seconds=dt, size=len(got),
                                             rss_ratio=one_step_rss(got, rec, cand.max_lag) / rss_true))
                print(f"  {system} {kind} {noise:.0%} done", file=sys.stderr, flush=True)
    if dump:
        np.savez_compressed(dump, **store)
    return pd.DataFrame(rows)


def report(df: pd.DataFrame, seeds: int) -> None:
    df = df.assign(kind=np.where(df["system"].str.startswith("SISO"), "SISO", "2-input"))
    shown = [s for s in SELECTORS if s in set(df["selector"])]
    titles = {"n_terms": "given the true size", "bic": f"size by BIC over 1 … {MAX_TERMS}",
              "ebic": f"size by EBIC over 1 … {MAX_TERMS}"}
    for mode in [m for m in MODES if m in set(df["mode"])]:
        title = titles[mode]
        d = df[df["mode"] == mode]
        tab = d.pivot_table(index=["kind", "inputs", "noise"], columns="selector", values="recovered", aggfunc="sum")
        tab = tab[shown]
        print(f"\nTrue structure recovered, {title} (out of {2 * seeds} records: 2 systems × {seeds} seeds)\n")
        print("| systems | inputs | noise | " + " | ".join(shown) + " |")
        print("| --- | --- | --- | " + " | ".join("---" for _ in shown) + " |")
        for (kind, inputs, noise), r in tab.iterrows():
            print(f"| {kind} | {inputs} | {noise:.0%} | " + " | ".join(str(int(r[s])) for s in shown) + " |")
    d = df[df["mode"] == "n_terms"]
    if d.empty:
        return
    med = d.pivot_table(index=["kind", "inputs"], columns="selector", values="rss_ratio", aggfunc="median")[
        shown]
    print("\nMedian one-step RSS of the selected structure / the true structure's (given the true size)\n")
    print("| systems | inputs | " + " | ".join(shown) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in shown) + " |")
    for (kind, inputs), r in med.iterrows():
        print(f"| {kind} | {inputs} | " + " | ".join(f"{r[s]:.3g}" for s in shown) + " |")
    tim = df.pivot_table(index=["kind", "mode"], columns="selector", values="seconds", aggfunc="median")[
        shown]
    mx = df.pivot_table(index=["kind", "mode"], columns="selector", values="seconds", aggfunc="max")[shown]
    print("\nWall time per selection, median (max), seconds\n")
    print("| systems | stopping | " + " | ".join(shown) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in shown) + " |")
    for (kind, mode), r in tim.iterrows():
        print(f"| {kind} | {mode} | " + " | ".join(f"{r[s]:.3f} ({mx.loc[(kind, mode), s]:.2f})" for s in shown)
              + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--n", type=int, default=1000, help="samples per record")
    ap.add_argument("--dump", default=None, help="write the candidate matrices to this .npz (for the peers)")
    ap.add_argument("--csv", default=None, help="write every trial to this CSV")
    ap.add_argument("--selectors", default=",".join(SELECTORS), help="comma-separated, among " + ", ".join(SELECTORS))
    ap.add_argument("--modes", default=",".join(MODES), help="comma-separated, among " + ", ".join(MODES))
    args = ap.parse_args()
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    print(f"bench_search.py --seeds {args.seeds} --n {args.n} --selectors {args.selectors} --modes {args.modes}: "
          f"{now} UTC, git {git_rev()}, {machine()}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gb.semp(candidates("SISO-A"), record("SISO-A", "random", 0.0, 0, 200), n_terms=2)  # compile
    df = trials(args.seeds, args.n, args.dump, tuple(args.selectors.split(",")), tuple(args.modes.split(",")))
    if args.csv:
        df.to_csv(args.csv, index=False)
    report(df, args.seeds)


if __name__ == "__main__":
    main()
