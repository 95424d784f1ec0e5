"""Other libraries' subset selection on bench_search.py's candidate matrices (issue 26).

Run in a separate environment, never graybox's own (the libraries are not graybox dependencies):

    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install fastcan
    .venv/bin/python benchmarks/bench_search.py --dump /tmp/peers.npz
    /tmp/peers/bin/python benchmarks/bench_search_peers.py /tmp/peers.npz

fastcan (canonical-correlation forward selection; its ``beam_width`` keeps several partial
subsets; ``refine`` exchanges selected terms for others, two-stage OLS) works on centred columns,
so the constant column is left out and a true structure's constant is not counted: recovered
means the selected non-constant columns are the true structure's non-constant terms, given their
number. Uses only numpy and fastcan.
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np


def main(path: str) -> None:
    from fastcan import FastCan, refine

    data = np.load(path)
    keys = sorted({k.rsplit("|", 1)[0] for k in data.files})
    variants = {"fastcan": dict(beam_width=1), "fastcan beam 10": dict(beam_width=10)}
    counts: dict[tuple, dict[str, int]] = {}
    times: dict[str, list[float]] = {}
    for key in keys:
        system, kind, noise, _seed = key.split("|")
        X, y, true = data[key + "|X"], data[key + "|y"], data[key + "|true"]
        const = np.flatnonzero(np.ptp(X, axis=0) == 0.0)
        keep = np.setdiff1d(np.arange(X.shape[1]), const)
        want = set(int(j) for j in true) - set(int(j) for j in const)
        group = ("SISO" if system.startswith("SISO") else "2-input", kind, float(noise))
        c = counts.setdefault(group, {})
        for name, kw in variants.items():
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sel = FastCan(len(want), verbose=0, **kw).fit(X[:, keep], y)
            times.setdefault(name, []).append(time.perf_counter() - t0)
            c[name] = c.get(name, 0) + (set(keep[sel.indices_]) == want)
            if kw["beam_width"] == 1:
                t0 = time.perf_counter()
                idx, _ = refine(sel, drop=1, verbose=0)
                times.setdefault("fastcan + refine", []).append(time.perf_counter() - t0 + times[name][-1])
                c["fastcan + refine"] = c.get("fastcan + refine", 0) + (set(keep[np.asarray(idx)]) == want)
    names = ["fastcan", "fastcan + refine", "fastcan beam 10"]
    from importlib.metadata import version

    print(f"fastcan {version('fastcan')}; true structure recovered, given its size (records per row as in "
          "bench_search.py)\n")
    print("| systems | inputs | noise | " + " | ".join(names) + " |")
    print("| --- | --- | --- | " + " | ".join("---" for _ in names) + " |")
    for (kind, inputs, noise), c in sorted(counts.items(), key=lambda kv: (kv[0][0] != "2-input", kv[0][1], kv[0][2])):
        print(f"| {kind} | {inputs} | {noise:.0%} | " + " | ".join(str(c.get(n, 0)) for n in names) + " |")
    print("\nmedian (max) seconds: " + "; ".join(f"{n} {np.median(times[n]):.3f} ({max(times[n]):.2f})" for n in names))


if __name__ == "__main__":
    main(sys.argv[1])
