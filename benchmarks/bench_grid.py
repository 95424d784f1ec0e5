"""A grid of about 200 cheap cells in-process and on a Dask LocalCluster: speed-up and scheduler overhead.

    .venv/bin/python benchmarks/bench_grid.py [--workers 2] [--quick] [--scale K [--repeat R]]

Bundled pumping-plant data; 20 structures made by FROLS (ny = nu = 1…6, 4…17 terms, rational
candidates) × 10 variants: CLS with eq. (22) and with static bands, PE by the closed form (11)
with several λ sets and decision makers, SE by the gradient method with 10 λ: 200 cells.

Both runs use warmed-up processes (a small grid first), so the times are the grid's own: the
in-process run on the driver, the Dask run on a ``LocalCluster`` started beforehand the way
``graybox grid run --workers N`` starts it (its start-up time is printed separately). Every
cell's own wall time is stored in its row; the worker time not spent in cells, averaged over
the run's cells, is (wall × workers − Σ cell times) / cells. That figure includes the run's
fixed costs (loading the data, opening the store, the first task's trip to a worker, the last
result's trip back) and the last cells' imbalance, so it is split from the rows' timestamps (each
row's ``finished_at`` less its ``wall_time`` is when the cell started on its worker): the time
each worker spent between its first cell's start and its last cell's end outside cells (the
per-cell hand-over: task dispatch, results, the driver's CPU on the shared cores), the fixed
start and end, and the imbalance.

Part of that time is paid once per run, whatever the number of cells. ``--scale K`` separates
the two: it runs grids of 1, 2, …, K copies of the data (200, 400, … cells whose work is the
same), in-process and on the cluster, and fits the time lost outside cells against the number
of cells. The slope is the scheduler's overhead per cell (the issue's goal: at most 5 % of the
median cell); the intercept is the run's own cost (loading,
keying, the store, the first dispatch and the last result, the end imbalance). ``--repeat R``
runs each size R times and pools the fit.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

from graybox import experiments as gx  # noqa: E402
from graybox.experiments._executors import local_cluster  # noqa: E402


def grid(quick: bool, copies: int = 0) -> gx.Grid:
    """The benchmark grid on the bundled plant; with ``copies`` = k > 0, on k copies of its data
    held in memory (copy i's static points scaled by 1 + i × 1e-12, so each copy has its own cells,
    whose work is the same): k × 200 cells of one distribution of cell times."""
    structures = []
    for ny, sizes in ((1, (4, 5)), (2, (4, 6, 9, 12)), (3, (4, 6, 9, 12)), (4, (4, 6, 9, 12)), (5, (4, 6, 9, 12)),
                      (6, (9, 17))):
        for n in sizes:
            structures.append(gx.StructureSpec(f"ny{ny}-{n}", candidates={"ny": ny, "nu": ny, "degree": 2,
                                                                           "max_y_power": 1},
                                               n_terms=n, include=["1"]))
    variants = [
        gx.Variant("CLS eq(22)", "cls", constraints=[{"type": "equality"}]),
        gx.Variant("CLS eq(22) els", "cls", constraints=[{"type": "equality"}], options={"reference": "els"}),
        gx.Variant("CLS band .175", "cls", constraints=[{"type": "band", "b": 0.175}]),
        gx.Variant("CLS band .1", "cls", constraints=[{"type": "band", "b": 0.1}]),
        gx.Variant("PE 30", "pe", lambdas={"logspace": [-6, 0, 30]}, options={"solver": "closed"}),
        gx.Variant("PE 100", "pe", options={"solver": "closed"}),
        gx.Variant("PE min-corr", "pe", lambdas={"logspace": [-6, 0, 30]}, decision={"rule": "min_correlation"},
                   options={"solver": "closed"}),
        gx.Variant("PE min-JSF", "pe", lambdas={"logspace": [-6, 0, 30]}, decision={"rule": "min_jsf"},
                   options={"solver": "closed"}),
        gx.Variant("SE grad 10", "se-gradient", lambdas={"logspace": [-2, 0, 10]}, options={"max_nfev": 20}),
        gx.Variant("SE grad 10 fb", "se-gradient", lambdas={"logspace": [-2, 0, 10]},
                   decision={"rule": "dsf", "fallback": "min_jsf"}, options={"max_nfev": 30}),
    ]
    if quick:
        structures, variants = structures[:4], variants[:6]
    data = [gx.DataSpec("pumping", bundled="pumping")]
    if copies:
        import graybox as gb

        ds = gb.load_pumping()
        st = ds.static
        data = [gx.DataSpec(f"pumping-{i}", band=0.031, dataset=gb.Dataset(
            ds.ident, ds.valid, gb.StaticPoints(st.ubar, st.ybar * (1 + i * 1e-12), name=st.name,
                                                input_names=st.input_names)))
                for i in range(copies)]
    return gx.Grid(data, structures, variants, name="bench")


def warm_up() -> gx.Grid:
    return gx.Grid([gx.DataSpec("pumping", bundled="pumping")],
                   [gx.StructureSpec("w", candidates={"ny": 1, "nu": 1, "degree": 2, "max_y_power": 1}, n_terms=3)],
                   [gx.Variant("c", "cls", constraints=[{"type": "equality"}]),
                    gx.Variant("p", "pe", lambdas=[0.1, 1.0], options={"solver": "closed"}),
                    gx.Variant("s", "se-gradient", lambdas=[0.1, 1.0], options={"max_nfev": 3})], name="warm")


def _busy(_: int) -> float:
    t = time.perf_counter()
    s = 0.0
    for i in range(20_000_000):
        s += i * 0.5
    return time.perf_counter() - t


def machine_ceiling(workers: int) -> float:
    """What ``workers`` processes of pure CPU work get done in parallel here, against one alone.

    A 2-vCPU VM need not deliver 2x (shared host cores, steal time): this is the ceiling any
    parallel executor meets on the machine at the time of the run.
    """
    import multiprocessing as mp

    one = _busy(0)
    with mp.get_context("spawn").Pool(workers) as pool:
        pool.map(_busy, [0] * workers)  # start-up
        t = time.perf_counter()
        pool.map(_busy, list(range(workers)))
        both = time.perf_counter() - t
    return workers * one / both


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="24 cells instead of 200")
    ap.add_argument("--scale", type=int, default=0, metavar="K",
                    help="also run grids of 1..K copies of the data (200 K cells) and fit the time lost "
                         "outside cells against the number of cells: per-cell slope and per-run intercept")
    ap.add_argument("--repeat", type=int, default=1, metavar="R", help="run each --scale size R times (pooled fit)")
    args = ap.parse_args()
    g = grid(args.quick)
    n = len(g.cells())
    print(f"# bench_grid: {n} cells; {machine()}; git {git_rev()}; {datetime.datetime.now():%Y-%m-%d %H:%M}")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        gx.run_grid(warm_up(), tmp / "warm-in.sqlite")
        t = time.perf_counter()
        called_in = time.time()
        r_in = gx.run_grid(g, tmp / "inprocess.sqlite")
        wall_in = time.perf_counter() - t
        returned_in = time.time()
        df_in = gx.load_results(tmp / "inprocess.sqlite")
        from distributed import Client

        t = time.perf_counter()
        with local_cluster(args.workers) as cluster, Client(cluster) as client:
            start = time.perf_counter() - t
            gx.run_grid(warm_up(), tmp / "warm-dask.sqlite", client=client)
            t = time.perf_counter()
            cpu0 = time.process_time()
            called = time.time()
            r_dk = gx.run_grid(g, tmp / "dask.sqlite", client=client)
            wall_dk = time.perf_counter() - t
            returned = time.time()
            driver_cpu = time.process_time() - cpu0
            scaled = [scale_point(k, tmp / f"r{r}", client, args.workers)
                      for r in range(args.repeat) for k in range(1, args.scale + 1)]
        df_dk = gx.load_results(tmp / "dask.sqlite")
    assert r_in.ran == r_dk.ran == n
    same = all(np.array_equal(df_in[c].to_numpy(float), df_dk[c].to_numpy(float), equal_nan=True)
               for c in ("JS_valid", "JSF", "J1_ident"))
    cell_in, cell_dk = df_in["wall_time"].to_numpy(), df_dk["wall_time"].to_numpy()
    overhead = (wall_dk * args.workers - cell_dk.sum()) / n
    med = statistics.median(cell_in)
    print(f"statuses: {dict(r_in.counts)}; identical figures in-process vs Dask: {same}")
    print(f"cell wall time in-process: median {med * 1e3:.1f} ms, mean {cell_in.mean() * 1e3:.1f} ms, "
          f"total {cell_in.sum():.2f} s; by estimator (median ms): "
          + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in df_in.groupby("estimator")["wall_time"].median().items()))
    print(f"cell wall time on Dask workers: median {statistics.median(cell_dk) * 1e3:.1f} ms, total {cell_dk.sum():.2f} s")
    print(f"in-process grid: {wall_in:.2f} s ({r_in.wall_time:.2f} s inside run_grid)")
    print(f"Dask, {args.workers} workers: {wall_dk:.2f} s (cluster start-up {start:.1f} s, not included)")
    print(f"driver process (client, scheduler thread, SQLite writes) CPU during the Dask run: {driver_cpu:.2f} s "
          f"= {driver_cpu / wall_dk:.0%} of one core")
    print(f"speed-up: {wall_in / wall_dk:.2f}x (goal >= 1.6x); this machine's own parallel throughput of "
          f"{args.workers} busy processes right after: {machine_ceiling(args.workers):.2f}x")
    print(f"worker time outside cells, all in, averaged over this run's {n} cells (its fixed costs included): "
          f"{overhead * 1e3:.2f} ms = {overhead / med * 100:.1f} % of the median cell, made of:")
    sp = split(df_dk, called, returned, args.workers)
    gaps, fixed, imbalance = sp["hand-over"], sp["fixed"], sp["imbalance"]
    print(f"  hand-over between cells on the workers: {gaps / n * 1e3:.2f} ms per cell = {gaps / n / med * 100:.1f} % "
          f"of the median cell ({args.workers} workers, {gaps:.3f} s in all)")
    print(f"  the run's fixed start and end (run_grid called -> first cell starts: {sp['start'] * 1e3:.0f} ms; "
          f"last cell ends -> run_grid returns: {sp['end'] * 1e3:.0f} ms), x {args.workers} workers: "
          f"{fixed / n * 1e3:.2f} ms per cell")
    end_in = ends(df_in)
    print(f"  (the in-process run's own start and end, for comparison: {((end_in - cell_in).min() - called_in) * 1e3:.0f} "
          f"ms and {(returned_in - end_in.max()) * 1e3:.0f} ms: loading the data, keying the cells, the store)")
    print(f"  the workers' start and end imbalance: {imbalance * 1e3:.0f} ms in all, {imbalance / n * 1e3:.2f} ms per cell")
    own_in = (wall_in - cell_in.sum()) / n
    print(f"the in-process run's own time outside cells (the same loading, keying, store writes): {own_in * 1e3:.2f} ms "
          f"per cell; what Dask adds beyond it: {(overhead - own_in) * 1e3:.2f} ms per cell = "
          f"{(overhead - own_in) / med * 100:.1f} % of the median cell")
    if scaled:
        report_scale(scaled, med)


def ends(df) -> np.ndarray:
    """When each row's cell ended (epoch seconds, from its ``finished_at``)."""
    return df["finished_at"].map(lambda s: datetime.datetime.fromisoformat(s).timestamp()).to_numpy()


def split(df, called: float, returned: float, workers: int) -> dict:
    """The worker time outside cells of a run on the cluster, by where it went (seconds).

    hand-over: on each worker, from its first cell's start to its last cell's end, the time
    outside cells; start, end: ``run_grid`` called -> first cell starts, last cell ends ->
    ``run_grid`` returns (fixed = their sum x workers); imbalance: the workers' idle time
    between the first start and the last end before their own first start and after their own
    last end.
    """
    cell = df["wall_time"].to_numpy()
    end = ends(df)
    start = end - cell
    gaps, spans = 0.0, []
    for w in df["worker"].unique():
        on = (df["worker"] == w).to_numpy()
        spans.append((start[on].min(), end[on].max()))
        gaps += end[on].max() - start[on].min() - cell[on].sum()
    first, last = min(s for s, _ in spans), max(e for _, e in spans)
    return {"hand-over": gaps, "start": first - called, "end": returned - last,
            "fixed": workers * ((first - called) + (returned - last)),
            "imbalance": sum((s - first) + (last - e) for s, e in spans)}


def scale_point(k: int, tmp: Path, client, workers: int) -> dict:
    """One grid of k data copies, in-process and on the cluster: cells and time lost outside cells."""
    g = grid(False, copies=k)
    tmp.mkdir(exist_ok=True)
    out = {"cells": len(g.cells())}
    for name, kw in (("in", {}), ("dask", {"client": client})):
        path = tmp / f"scale-{k}-{name}.sqlite"
        t = time.perf_counter()
        called = time.time()
        gx.run_grid(g, path, **kw)
        wall = time.perf_counter() - t
        returned = time.time()
        df = gx.load_results(path)
        out[name] = (wall * (workers if name == "dask" else 1) - df["wall_time"].sum(), wall)
        if name == "dask":
            out["split"] = split(df, called, returned, workers)
    print(f"  scale {k}: {out['cells']} cells; in-process {out['in'][1]:.2f} s, {out['in'][0] * 1e3:.0f} ms outside "
          f"cells; Dask {out['dask'][1]:.2f} s, {out['dask'][0] * 1e3:.0f} ms of worker time outside cells (hand-over "
          f"{out['split']['hand-over'] * 1e3:.0f}, fixed {out['split']['fixed'] * 1e3:.0f}, imbalance "
          f"{out['split']['imbalance'] * 1e3:.0f} ms)", flush=True)
    return out


def report_scale(points: list[dict], med: float) -> None:
    """Least-squares line of the time lost outside cells against the number of cells."""
    n = np.array([p["cells"] for p in points], float)
    print("time outside cells against the number of cells (the slope is the overhead per cell; goal for Dask <= 5 % of "
          "the median cell):")
    for name, label in (("dask", "Dask (worker time: wall x workers - cells)"), ("in", "in-process (wall - cells)")):
        lost = np.array([p[name][0] for p in points])
        (slope, icpt), cov = np.polyfit(n, lost, 1, cov=True) if n.size > 3 else (np.polyfit(n, lost, 1), None)
        se = "" if cov is None else f" (standard error {np.sqrt(cov[0, 0]) * 1e3:.3f} ms)"
        print(f"{label}: per cell {slope * 1e3:.3f} ms{se} = {slope / med * 100:.1f} % of the median cell; per run "
              f"{icpt * 1e3:.0f} ms (fit over {', '.join(str(int(c)) for c in n)} cells; lost "
              f"{', '.join(f'{x * 1e3:.0f}' for x in lost)} ms)")
        print(f"  {label.split(' (')[0]}, all in, per cell at each size: "
              + ", ".join(f"{int(c)}: {x / c / med * 100:.1f} %" for c, x in zip(n, lost)) + " of the median cell")
    for part in ("hand-over", "fixed", "imbalance"):
        x = np.array([p["split"][part] for p in points])
        print(f"  Dask {part} per cell at each size: "
              + ", ".join(f"{int(c)}: {v / c / med * 100:.1f} %" for c, v in zip(n, x)) + " of the median cell")


if __name__ == "__main__":
    main()
