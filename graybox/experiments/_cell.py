"""One cell of a grid: make the structure, estimate, decide, evaluate; a row of plain values.

:func:`run_cell` is what every executor runs (in the driver, in a local worker process or on a
Dask worker). It never raises for a problem of the cell itself: an infeasible constraint set, a
diverging free run, any other error become a row with that status and the message. Its
result depends only on the cell and the data — BLAS and numba run on one thread inside a cell
(parallelism is across cells), so every executor gives the same numbers.
"""

from __future__ import annotations

import datetime
import os
import socket
import time
import warnings
from dataclasses import replace
from typing import Any, Iterable, Mapping

import numba
import numpy as np

from .. import _api as gb

from ..static._constraints import static_cluster_map
from ..estimation._decisions import min_jsf_index
from ..estimation._prediction_error import numerator_surface
from ..core._processes import interrupted_by_user
from ..core._least_squares import binary_exponent, scaled_theta, thread_pools
from ..core._validation import check_int
from ..models._evaluate import fit_or_nan, output_spread
from ._spec import Cell, build_constraint, canonical_json

__all__ = ["COLUMNS", "JSON_COLUMNS", "STATUSES", "run_cell", "failed_row", "warning_texts"]

#: Statuses of a finished cell.
STATUSES = ("ok", "infeasible", "diverged", "failed")

#: The columns of a cell's row and their SQLite types (figures are MSEs in output units², fit in %).
COLUMNS: dict[str, str] = {
    "key": "TEXT PRIMARY KEY",
    "cell_index": "INTEGER NOT NULL",
    "data": "TEXT NOT NULL",
    "structure": "TEXT NOT NULL",
    "variant": "TEXT NOT NULL",
    "seed": "INTEGER",
    "estimator": "TEXT NOT NULL",
    "status": "TEXT NOT NULL",
    "message": "TEXT",
    "terms": "TEXT",
    "theta": "TEXT",
    "n_params": "INTEGER",
    "lambda1": "REAL",
    "rule": "TEXT",
    "in_band": "INTEGER",
    "band": "REAL",
    "J1_ident": "REAL",
    "JS_ident": "REAL",
    "fit_ident": "REAL",
    "J1_valid": "REAL",
    "JS_valid": "REAL",
    "fit_valid": "REAL",
    "JSF": "REAL",
    "static_miss": "REAL",
    "members": "TEXT",
    "wall_time": "REAL",
    "version": "TEXT NOT NULL",
    "warnings": "TEXT",
    "worker": "TEXT",
    "finished_at": "TEXT",
}
#: Columns stored as JSON text.
JSON_COLUMNS = ("terms", "theta", "members", "warnings")

# FROLS is deterministic and shared by every variant of a (data, structure): each process keeps
# the structures it has made.
_STRUCTURES: dict[tuple[str, str], tuple[str, ...]] = {}
_STRUCTURE_CACHE_SIZE = 256


def _row(cell: Cell) -> dict[str, Any]:
    row: dict[str, Any] = {k: None for k in COLUMNS}
    row.update(key=cell.key, cell_index=cell.index, data=cell.data, structure=cell.structure, variant=cell.variant,
               seed=cell.seed, estimator=cell.variant_spec["estimator"], band=cell.band, version=gb.__version__,
               worker=f"{socket.gethostname()}:{os.getpid()}")
    return row


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


def failed_row(cell: Cell, message: str) -> dict[str, Any]:
    """The row of a cell that could not be run at all (e.g. its worker died twice)."""
    row = _row(cell)
    row.update(status="failed", message=message, worker=None, finished_at=_now(), warnings=[])
    return row


def make_structure(spec: Mapping[str, Any], data: gb.Dataset, data_hash: str) -> gb.Structure:
    """The cell's structure: given terms, or FROLS on the identification record (cached per process)."""
    if "terms" in spec:
        return gb.parse_structure(list(spec["terms"]))
    k = (data_hash, canonical_json(spec))
    if k not in _STRUCTURES:
        kw = {n: spec[n] for n in ("n_terms", "tol", "criterion", "max_terms") if spec[n] is not None}
        cand = dict(spec["candidates"])
        if not isinstance(cand["nu"], Mapping):  # one lag count for every input of the data set
            cand["input_names"] = data.ident.input_names
        sel = gb.frols(gb.Candidates(**cand), data.ident, include=list(spec["include"]), **kw)
        if len(_STRUCTURES) >= _STRUCTURE_CACHE_SIZE:
            _STRUCTURES.clear()
        _STRUCTURES[k] = tuple(str(t) for t in sel.structure)
    return gb.parse_structure(list(_STRUCTURES[k]))


def _numerator_fit(st: gb.Structure, points: gb.StaticPoints) -> gb.StaticCurve | gb.StaticSurface:
    """The polynomial in ū with exactly the powers the structure's numerator carries (its Σ_{u^m}
    clusters), least squares through the static points: the curve eq. (22) can impose. With
    several inputs: the surface on the monomials of the Σ_{u^e} clusters."""
    if getattr(points, "n_inputs", 1) > 1:
        return numerator_surface(static_cluster_map(st, points.input_names), points)
    powers = sorted(m for p, m in gb.cluster_map(st).keys if p == 0)
    if not powers:
        raise ValueError("eq. (22) needs numerator clusters (the constant or terms in u only); this structure has none")
    if len(points) < len(powers):
        raise ValueError(f"fitting the {len(powers)} numerator coefficients (ū powers {powers}) needs at least "
                         f"{len(powers)} static points, got {len(points)}")
    V = points.ubar[:, None] ** np.array(powers, float)[None, :]
    scale = np.sqrt(np.mean(V**2, axis=0))  # columns in engineering units span decades (ū² ≈ 1e6)
    z = np.linalg.lstsq(V / scale, points.ybar, rcond=None)[0]
    coef = np.zeros(max(powers) + 1)
    coef[powers] = z / scale
    return gb.StaticCurve.polynomial(coef, domain=(float(points.ubar.min()), float(points.ubar.max())),
                                     name=f"fit of ū^{powers} to {points.name}")


def cell_constraints(specs, st: gb.Structure, data: gb.Dataset) -> list:
    """The graybox constraint objects of canonical constraint tables, an equality's curve resolved
    against the structure and the data set ("fit", "dataset" or given coefficients)."""
    out = []
    for c in specs:
        curve = None
        if c["type"] == "equality":
            if c["curve"] == "fit":
                curve = _numerator_fit(st, data.static)
            elif c["curve"] == "dataset":
                curve = data.extra["static_curve"]
            else:
                curve = gb.StaticCurve.polynomial(list(c["curve"]), name="given static curve")
        out.append(build_constraint(c, curve=curve))
    return out


def _estimate(cell: Cell, st: gb.Structure, data: gb.Dataset):
    """(model, Pareto set or None, row fields the estimator sets itself)."""
    v = cell.variant_spec
    est = v["estimator"]
    opts = dict(v["options"])
    name = f"{cell.variant} / {cell.structure}"
    lam = None if v["lambdas"] is None else np.array(v["lambdas"])
    if est == "ls":
        return gb.els(st, data.ident, noise=0, name=name).model, None, {}
    if est == "els":
        return gb.els(st, data.ident, name=name, **opts).model, None, {}
    if est == "neural":
        # the network sees the structure's lags: of y, and the largest of any input (1 with none)
        kw = {"ny": st.input_lag("y"), "nu": max((st.input_lag(n) for n in st.input_names), default=1), **opts}
        return gb.neural_narx(data.ident, seed=cell.seed or 0, name=name, **kw).model, None, {}
    cons = cell_constraints(v["constraints"], st, data)
    if est == "cls":
        # the variant's constraints are what it imposes; the data set's points are their context
        return gb.cls(st, data, constraints=cons, name=name, **{"how": "context", **opts}).model, None, {}
    if est == "pe":
        return None, gb.pe_pareto(st, data, lambdas=lam, constraints=cons, **opts), {}
    if "margin" in opts and opts["margin"] == "none":  # the paper's problem: TOML has no null
        opts["margin"] = None
    if est == "se-ga":
        theta0 = opts.pop("theta0", "ls")
        margin = opts.pop("margin", "auto")
        ga = gb.GAOptions(**opts)
        return None, gb.se_pareto(st, data, lambdas=lam, method="ga", seed=cell.seed or 0, progress=False,
                                  options=ga, theta0=None if theta0 == "none" else "ls", margin=margin), {}
    if est == "se-gradient":
        return None, gb.se_pareto(st, data, lambdas=lam, method="gradient", progress=False, **opts), {}
    if est == "se-dsf":
        band = opts.pop("band", None) or cell.band
        if band is None:
            raise ValueError("se-dsf needs a band: give the data set a band or the variant options = {band = ...}")
        res = gb.se_dsf(st, data, band=band, lambdas=lam, **opts)
        # a band the structure cannot reach gives the model with the smallest J_SF (and a warning), as
        # D_SF with fallback "min_jsf" does
        return res.model.with_theta(res.model.theta, name=name), None, \
            {"rule": "D_SF (direct)" if res.in_band else "min J_SF (band infeasible)", "in_band": int(res.in_band)}
    raise ValueError(f"unknown estimator {est!r}")  # pragma: no cover - the spec refuses it


def _decide(cell: Cell, pareto: gb.ParetoSet, data: gb.Dataset) -> tuple[int, str, bool | None]:
    """(member index, rule, in band: None for the rules that decide by no band) or ``InfeasibleError`` when D_SF
    finds no member in its band."""
    d = cell.variant_spec["decision"]
    if d["rule"] == "dsf":
        # no member in the band and no fallback: InfeasibleError naming the smallest J_SF reached
        dec = gb.decide_dsf(pareto, band=d["band"] if d["band"] is not None else cell.band, fallback=d["fallback"])
        return dec.index, dec.rule, bool(dec.in_band)
    if d["rule"] == "min_correlation":
        dec = gb.decide_min_correlation(pareto, data.ident, output=d["output"])
        return dec.index, dec.rule, None
    # no band read (the cell is keyed without it): whether its member lies in the data set's band is not decided here
    return min_jsf_index(pareto), "min J_SF", None


def _members(pareto: gb.ParetoSet, data: gb.Dataset) -> dict[str, Any]:
    """Every member's figures (identification J's from the set, J_S on the validation record).

    Arrays, not lists: a Dask task returns them, and a worker pickles and frees arrays of floats
    faster than lists of Python floats (BENCHMARKS.md, grids).
    """
    K = len(pareto)
    ok = np.array([i not in pareto.failures for i in range(K)], bool)
    # on the validation output over the power of two above its largest |y| (exact): there J_S is a float however
    # large or small y is, and fit % (a ratio) is read from it (at y × 2^-600 J_S read 0 and fit % 100, at
    # y × 2^600 inf and -inf); J_S is mapped back to output units² (inf or 0 only where it is no float)
    e = binary_exponent(np.max(np.abs(data.valid.y), initial=0.0))
    valid = replace(data.valid, y=np.ldexp(data.valid.y, -e))
    js_unit = np.full(K, np.inf)
    if ok.any():
        th = scaled_theta(pareto.thetas[ok], pareto.structure, {"y": e, "e": e})
        js_unit[ok] = gb.evaluate_thetas(pareto.structure, th, valid, one_step=False)["JS"]
    with np.errstate(over="ignore", under="ignore"):
        js_valid = np.ldexp(js_unit, 2 * e)
    # fit % from J_S as gb.fit_percent defines it: 100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖) from sample L on;
    # NaN where a held (constant) validation output leaves it undefined
    y = valid.y[pareto.structure.max_lag:]
    spread = output_spread(y)
    with np.errstate(invalid="ignore"):
        fit = 100.0 * (1.0 - np.sqrt(js_unit * y.size) / spread) if spread > 0 else np.full(K, np.nan)
    figures = {"lambda1": pareto.lambdas, "J1": pareto.J1, "JS": pareto.JS, "JSF": pareto.JSF, "JS_valid": js_valid,
               "fit_valid": fit}
    out: dict[str, Any] = {k: np.array(v, dtype=np.float64) for k, v in figures.items()}  # copies, own memory
    out["failure"] = [pareto.failures.get(i, "") for i in range(K)]
    return out


def _figures(m, data: gb.Dataset) -> tuple[dict[str, float], dict[str, tuple[int, int]]]:
    """The shared evaluator's figures of one model on both records and the static points, and
    where a free run diverged: record -> (first sample that is not finite, samples)."""
    L = m.max_lag
    out: dict[str, float] = {}
    diverged: dict[str, tuple[int, int]] = {}
    for tag, rec in (("ident", data.ident), ("valid", data.valid)):
        out[f"J1_{tag}"] = gb.j1(m, rec)
        sim = m.simulate(rec, on_diverge="nan")
        out[f"JS_{tag}"] = gb.mse(rec.y, sim, start=L)
        out[f"fit_{tag}"] = fit_or_nan(rec.y, sim, L)
        bad = np.flatnonzero(~np.isfinite(np.asarray(sim, float)[L:]))
        if bad.size:
            diverged[tag] = (int(bad[0]) + L, len(rec))
    out["JSF"] = gb.jsf(m, data.static)
    yb = np.asarray(m.static_curve(data.static.ubar, y0=data.static.ybar, strict=False), float)
    miss = np.abs(yb - data.static.ybar)
    out["static_miss"] = float(miss.max()) if np.all(np.isfinite(miss)) else float("inf")
    return out, diverged


def warning_texts(caught: Iterable[warnings.WarningMessage]) -> list[str]:
    """What a fit warned of, as text a row keeps: ``"Category: message"``, each once, sorted."""
    return sorted({f"{w.category.__name__}: {w.message}" for w in caught})


def run_cell(cell: Cell, data: gb.Dataset, *, threads: int = 1) -> dict[str, Any]:
    """Run one cell and return its row (see :data:`COLUMNS`); never raises for the cell's own problems.

    Parameters
    ----------
    cell : Cell
        What to run.
    data : Dataset
        The cell's data set (identification, validation, static points).
    threads : int
        Threads for BLAS and numba inside the cell (1: the same numbers on every executor).

    Returns
    -------
    dict of str to Any
        The cell's row, one entry per column of :data:`COLUMNS` (``status`` says whether it fitted).
    """
    threads = check_int(threads, "threads", low=1)  # the caller's mistake, not the cell's: raised
    row = _row(cell)
    t0 = time.perf_counter()
    numba_before = numba.get_num_threads()
    caught: list[warnings.WarningMessage] = []
    try:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        with thread_pools().limit(limits=threads), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            st = make_structure(cell.structure_spec, data, cell.data_hash)
            row["terms"] = [str(t) for t in st]
            if cell.variant_spec["estimator"] != "neural":  # one rule: N_p is known once the terms are,
                row["n_params"] = len(st)                    # whatever becomes of the fit (a network's: once fitted)
            model, pareto, fields = _estimate(cell, st, data)
            row.update(fields)
            if pareto is not None:
                row["members"] = _members(pareto, data)
                i, rule, in_band = _decide(cell, pareto, data)
                row["members"]["chosen"] = (np.arange(len(pareto)) == i).astype(np.float64)  # the report's mark
                model = pareto.member_model(i, name=f"{cell.variant} / {cell.structure}")
                row.update(lambda1=float(pareto.lambdas[i]), rule=rule,
                           in_band=None if in_band is None else int(in_band))
            row["n_params"] = int(model.n_params)
            if isinstance(model, gb.Model):
                row["theta"] = model.theta.tolist()
            figures, diverged = _figures(model, data)
            row.update(figures)
        bad = [tag for tag in ("ident", "valid") if not np.isfinite(row[f"JS_{tag}"])]
        if bad:
            where = [f"the {'identification' if t == 'ident' else 'validation'} record at sample {diverged[t][0]} of "
                     f"{diverged[t][1]}" if t in diverged else f"the {t} record" for t in bad]
            row.update(status="diverged", message=f"the free run of the chosen model diverges on "
                                                  f"{' and on '.join(where)} (J_S = inf)")
        else:
            row["status"] = "ok"
    except gb.InfeasibleError as exc:
        row.update(status="infeasible", message=str(exc))
    except gb.DivergenceError as exc:
        row.update(status="diverged", message=str(exc))
    except Exception as exc:  # a cell's failure is data, not a crash of the grid
        if interrupted_by_user(exc):  # Ctrl-C, not the cell's failure: the grid stops and the cell stays to run
            raise KeyboardInterrupt from exc
        row.update(status="failed", message=f"{type(exc).__name__}: {exc}")
    finally:
        numba.set_num_threads(numba_before)
    row["warnings"] = warning_texts(caught)
    row["wall_time"] = time.perf_counter() - t0
    row["finished_at"] = _now()
    return row
