"""The simulation-error (SE) bi-objective, eq. (13): min λ1 J_S(θ) + λ2 J_SF(θ).

Two solvers share one problem definition (:class:`SEProblem`):

- :func:`ga_front` — the paper's genetic algorithm, faithfully: real-coded, stochastic
  universal sampling, heuristic crossover (ratio 1.2, probability 0.9), Gaussian mutation
  (probability 0.1, standard deviation 5 % of the gene), population 200, elitism; one run per
  λ1 from λ1 = 1 down, each seeded with the previous run's best plus random individuals whose
  θ is least squares on 30 randomly chosen samples.
- :func:`gradient_front` — beyond the paper: ``scipy.optimize.least_squares`` on the stacked
  residuals [√(λ1/N) e_sim, √(λ2/N_SF) e_SF] with the Jacobian from the forward sensitivity
  recursion of the compiled kernel, warm-started along the λ sweep.

:func:`se_pareto` runs either and returns a :class:`graybox.ParetoSet` whose J's come
from the shared evaluator. Long sweeps show a progress bar, write a checkpoint after each λ and
resume from it; a checkpoint written for another problem is refused.

Inside the optimisers J_S is computed by the fused batch kernel (same definition as
:func:`graybox.js`) and J_SF by the package's one static definition
(:func:`graybox._static.reached_equilibria`): at each static point the equilibrium a free run at
constant ū_i from the measured ȳ_i settles on; where it settles on none the cost is infinite — a
model does not settle on an unstable equilibrium, nor on a stable one whose basin does not hold
ȳ_i, so matching the static points there would be a false gain. The reported front is
re-evaluated by the shared evaluator, which uses the same definition.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal, Sequence

import numpy as np
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from ._convex import pe_thetas
from ._kernels import batch_sse, encode, free_run_sensitivity, input_products, simulate_one
from ._ls import column_scales, scaled_lstsq
from ._pareto import ParetoSet
from ._progress import progress_bar
from ._records import Dataset, Record, StaticPoints, StaticRangeWarning, as_records, warn_static_range
from ._regressors import stacked_regressors
from ._static import reached_equilibria, static_theta_gradient
from ._terms import Structure
from ._validation import check_choice, check_lambdas, check_theta

__all__ = ["SEProblem", "GAOptions", "ga_front", "gradient_front", "se_pareto", "SE_LAMBDAS"]

#: The paper's SE sweep (Section IV-C), the default ``lambdas``: 100 λ1 in logspace(−2, 0).
SE_LAMBDAS = np.logspace(-2, 0, 100)
SE_LAMBDAS.setflags(write=False)


class SEProblem:
    """The data of one SE problem: structure, identification record(s), static points.

    Parameters
    ----------
    structure : Structure
        Process terms.
    records : Record or sequence of Record
        Identification data. Each record is run freely from its own first max-lag samples (a
        free run never straddles two experiments) and J_S is the mean over all their samples.
    static : StaticPoints
        Measured steady states.
    """

    def __init__(self, structure: Structure, records: Record | Sequence[Record], static: StaticPoints):
        self.records = as_records(records)
        if not isinstance(static, StaticPoints):
            raise ValueError(f"static must be StaticPoints, got {type(static).__name__}")
        structure = structure if isinstance(structure, Structure) else Structure(structure)
        if any(t.is_noise for t in structure):
            structure = structure.process
        self.structure = structure
        self.record = self.records[0]
        self.static = static
        self.L = structure.max_lag
        self.code = c = encode(structure)
        # input products are fixed across the whole sweep: computed once per record
        self.U = [input_products(c.fptr, c.fsig, c.flag, c.fpow, r.u, self.L) for r in self.records]
        self.psi, self.target = stacked_regressors(structure, self.records)
        self.n_dyn = self.target.size
        self.scale = column_scales(self.psi)  # θ = z / scale keeps the optimisers well conditioned

    def fingerprint(self) -> str:
        """A hash of everything that defines the problem (for checkpoints)."""
        h = hashlib.sha256()
        h.update(str(self.structure).encode())
        for a in [x for r in self.records for x in (r.u, r.y)] + [self.static.ubar, self.static.ybar]:
            h.update(np.ascontiguousarray(a).tobytes())
        return h.hexdigest()[:16]

    # -- objectives -------------------------------------------------------------------
    def js(self, thetas: np.ndarray, threads: int = 1) -> np.ndarray:
        """J_S of each row of ``thetas`` (inf where a free run diverges), shape (P,)."""
        sse = sum(batch_sse(self.code, thetas, r.u, r.y, self.L, threads, U) for r, U in zip(self.records, self.U))
        js = sse / self.n_dyn
        return np.where(np.isfinite(js), js, np.inf)

    def static_outputs(self, thetas: np.ndarray) -> np.ndarray:
        """The equilibrium each row reaches from each measured ȳ_i (NaN where none), shape (P, M).

        :func:`graybox._static.reached_equilibria` with y0 = ȳ_i: the definition of J_SF.
        """
        return reached_equilibria(self.structure, np.atleast_2d(thetas), self.static.ubar, self.static.ybar).ybar

    def jsf(self, thetas: np.ndarray) -> np.ndarray:
        """J_SF of each row (the equilibrium reached from the measured ȳ; inf where none), shape (P,)."""
        yb = self.static_outputs(thetas)
        with np.errstate(all="ignore"):
            v = np.mean((yb - self.static.ybar) ** 2, axis=1)
        return np.where(np.isfinite(v), v, np.inf)

    def cost(self, thetas: np.ndarray, lam1: float, threads: int = 1) -> np.ndarray:
        """λ1 J_S + λ2 J_SF with λ2 = 1 − λ1, shape (P,); inf for a diverging member."""
        js = self.js(thetas, threads)
        c = lam1 * js
        if lam1 < 1.0:
            c = c + (1.0 - lam1) * self.jsf(thetas)
        return np.where(np.isfinite(c), c, np.inf)

    def ls_theta(self) -> np.ndarray:
        """Least-squares (one-step) estimate on all samples."""
        return scaled_lstsq(self.psi, self.target)

    def random_ls(self, rng: np.random.Generator, count: int, samples: int = 30) -> np.ndarray:
        """``count`` θ's, each least squares on ``samples`` randomly chosen rows (the paper's seeds)."""
        n = self.psi.shape[0]
        if samples > n:
            raise ValueError(f"cannot draw {samples} samples from {n} rows")
        A = self.psi / self.scale
        b = self.target
        out = np.empty((count, self.psi.shape[1]))
        for i in range(count):
            rows = rng.choice(n, size=samples, replace=False)
            z = np.linalg.lstsq(A[rows], b[rows], rcond=None)[0]
            out[i] = z / self.scale
        return out


@dataclass(frozen=True)
class GAOptions:
    """Settings of the paper's genetic algorithm (defaults: the paper's, 50 generations).

    Attributes
    ----------
    population : int
        Individuals per generation (paper: 200).
    generations : int
        Generations per λ (the paper does not state it; 50 here). The run stops after this many
        generations, or earlier when the best cost has not improved by a relative 1e-9 for
        ``stall`` generations (``stall=None``: never early).
    crossover_prob, crossover_ratio : float
        Heuristic crossover: with probability 0.9 a pair (better p1, worse p2) gives the children
        p2 + 1.2 (p1 − p2) and p2 + r (p1 − p2) with r ~ U(0, 1); otherwise the parents pass on.
    mutation_prob, mutation_scale : float
        Each gene mutates with probability 0.1 by adding N(0, (0.05 |gene|)²).
    elite : int
        Best individuals copied unchanged into the next generation.
    random_samples : int
        Samples of the identification record in each random individual's least squares (30).
    selective_pressure : float
        Linear ranking pressure in [1, 2] for the fitness that stochastic universal sampling uses.
    """

    population: int = 200
    generations: int = 50
    stall: int | None = None
    crossover_prob: float = 0.9
    crossover_ratio: float = 1.2
    mutation_prob: float = 0.1
    mutation_scale: float = 0.05
    elite: int = 1
    random_samples: int = 30
    selective_pressure: float = 2.0

    def __post_init__(self) -> None:
        if self.population < 4 or self.generations < 1:
            raise ValueError("population must be >= 4 and generations >= 1")
        for name in ("crossover_prob", "mutation_prob"):
            v = getattr(self, name)
            if not 0 <= v <= 1:
                raise ValueError(f"{name} must lie in [0, 1], got {v}")
        if not 0 <= self.elite < self.population:
            raise ValueError("elite must lie in [0, population)")
        if not 1 <= self.selective_pressure <= 2:
            raise ValueError("selective_pressure must lie in [1, 2]")


def _sus(fitness: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Stochastic universal sampling (Baker 1987): n equally spaced pointers, one spin."""
    cum = np.cumsum(fitness)
    step = cum[-1] / n
    pointers = rng.uniform(0, step) + step * np.arange(n)
    idx = np.searchsorted(cum, pointers, side="right")
    return np.minimum(idx, fitness.size - 1)


def _ranking_fitness(cost: np.ndarray, sp: float) -> np.ndarray:
    """Linear ranking: best gets sp, worst 2 − sp (infinite costs rank last)."""
    n = cost.size
    order = np.argsort(cost, kind="stable")
    rank = np.empty(n)
    rank[order] = np.arange(n)[::-1]  # best → n−1
    return 2 - sp + 2 * (sp - 1) * rank / max(n - 1, 1)


def _ga_run(problem: SEProblem, lam1: float, init: np.ndarray, opts: GAOptions, rng: np.random.Generator,
            threads: int) -> tuple[np.ndarray, float, int]:
    """One GA run for one λ1; returns (best θ, its cost, generations run)."""
    pop = init
    cost = problem.cost(pop, lam1, threads)
    best_hist = [np.min(cost)]
    n = opts.population
    g = 0
    for g in range(1, opts.generations + 1):
        order = np.argsort(cost, kind="stable")
        elite = pop[order[: opts.elite]]
        fit = _ranking_fitness(cost, opts.selective_pressure)
        nsel = n - opts.elite
        nsel += nsel % 2
        parents = _sus(fit, nsel, rng)
        rng.shuffle(parents)
        a, b = parents[0::2], parents[1::2]
        better = np.where((cost[a] <= cost[b])[:, None], pop[a], pop[b])
        worse = np.where((cost[a] <= cost[b])[:, None], pop[b], pop[a])
        cross = rng.random(a.size) < opts.crossover_prob
        r = rng.random((a.size, 1))
        c1 = np.where(cross[:, None], worse + opts.crossover_ratio * (better - worse), pop[a])
        c2 = np.where(cross[:, None], worse + r * (better - worse), pop[b])
        kids = np.vstack([c1, c2])[: n - opts.elite]
        mut = rng.random(kids.shape) < opts.mutation_prob
        kids = kids + mut * rng.standard_normal(kids.shape) * opts.mutation_scale * np.abs(kids)
        pop = np.vstack([elite, kids])
        cost = problem.cost(pop, lam1, threads)
        best_hist.append(np.min(cost))
        if opts.stall and g > opts.stall:
            old = best_hist[-opts.stall - 1]
            if old - best_hist[-1] <= 1e-9 * abs(old):
                break
    i = int(np.argmin(cost))
    return pop[i].copy(), float(cost[i]), g


# -- checkpoints ------------------------------------------------------------------------
def _load_checkpoint(path: Path, meta: dict) -> dict:
    with np.load(path, allow_pickle=False) as z:
        stored = json.loads(str(z["meta"]))
        if stored != meta:
            diff = sorted(k for k in set(stored) | set(meta) if stored.get(k) != meta.get(k))
            raise ValueError(
                f"checkpoint {path} was written for another problem or settings (differs in: {', '.join(diff)}); "
                "delete it or choose another checkpoint path"
            )
        return {"thetas": z["thetas"], "costs": z["costs"], "done": int(z["done"])}


def _save_checkpoint(path: Path, meta: dict, thetas: np.ndarray, costs: np.ndarray, done: int) -> None:
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, meta=json.dumps(meta), thetas=thetas, costs=costs, done=done)
    os.replace(tmp, path)  # atomic: a kill during the write never leaves a torn checkpoint


def _sweep(problem: SEProblem, lam: np.ndarray, method: str, settings: dict, seed: int | None,
           checkpoint: str | os.PathLike | None, progress: bool, step) -> tuple[np.ndarray, np.ndarray]:
    """Run ``step(i, lam1, previous θ, rng)`` over the λ's with checkpoints and a progress bar."""
    K = lam.size
    n = len(problem.structure)
    thetas = np.full((K, n), np.nan)
    costs = np.full(K, np.nan)
    done = 0
    meta = {"problem": problem.fingerprint(), "method": method, "lambdas": lam.tolist(), "seed": seed,
            "settings": settings}
    path = Path(checkpoint) if checkpoint is not None else None
    if path is not None and path.exists():
        ck = _load_checkpoint(path, meta)
        done = ck["done"]
        thetas[:done], costs[:done] = ck["thetas"][:done], ck["costs"][:done]
    prev = thetas[done - 1] if done else None
    bar = progress_bar(K, f"SE front ({method})", progress, initial=done)
    # The sweeps make thousands of small BLAS calls (a 3200 × n Jacobian's SVD, 30-row least
    # squares): a multi-threaded BLAS only adds synchronisation, and on a loaded 2-core machine
    # it measured 30x slower than one thread. Our own parallelism is the population threads.
    limits = threadpool_limits(limits=1, user_api="blas")
    try:
        for i in range(done, K):
            # one generator per λ index: a resumed sweep draws exactly what an uninterrupted one does
            rng = np.random.default_rng([0 if seed is None else seed, i])
            th, c = step(i, float(lam[i]), prev, rng)
            thetas[i], costs[i] = th, c
            prev = th
            if path is not None:
                _save_checkpoint(path, meta, thetas, costs, i + 1)
            bar.update(1)
    finally:
        bar.close()
        limits.restore_original_limits()
    return thetas, costs


def ga_front(
    problem: SEProblem,
    lambdas: Sequence[float] | np.ndarray = SE_LAMBDAS,
    *,
    options: GAOptions = GAOptions(),
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    threads: int = 1,
    theta0: np.ndarray | Literal["ls"] | None = "ls",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's GA over a λ1 sweep (run from λ1 = 1 down, whatever order is given).

    Parameters
    ----------
    problem : SEProblem
    lambdas : sequence of float in (0, 1]
    options : GAOptions
    seed : int
        Seeds every random draw; with a checkpoint, a resumed sweep equals an uninterrupted one.
    checkpoint : path, optional
    progress : bool
    threads : int
    theta0 : ndarray, "ls" or None
        An individual added to the first run's initial population. The paper seeds its first
        run with random individuals only (least squares on 30 samples); for structures with
        cubic terms those almost never give a free run that stays bounded, and the run then has
        nothing to select from. The default, ``"ls"``, adds the least-squares estimate on all
        samples — one individual, in the spirit of the paper's seeds. ``None`` is the paper's
        choice exactly.

    Returns
    -------
    lambdas : ndarray, shape (K,)
        λ1 in the order the runs were made (descending).
    thetas : ndarray, shape (K, n_terms)
    costs : ndarray, shape (K,)
        The optimised weighted cost of each run's best individual.
    """
    lam = np.sort(check_lambdas(lambdas))[::-1]
    if isinstance(theta0, str):
        if theta0 != "ls":
            raise ValueError(f"theta0 must be an array, 'ls' or None, got {theta0!r}")
        first = problem.ls_theta()
    else:
        first = None if theta0 is None else check_theta(len(problem.structure), theta0, "theta0")

    def step(i, lam1, prev, rng):
        carry = prev if prev is not None else first
        nrand = options.population - (carry is not None)
        init = problem.random_ls(rng, nrand, options.random_samples)
        if carry is not None:
            init = np.vstack([carry[None, :], init])
        th, c, _ = _ga_run(problem, lam1, init, options, rng, threads)
        return th, c

    settings = dict(asdict(options), theta0=None if first is None else [float(v) for v in first])
    thetas, costs = _sweep(problem, lam, "ga", settings, seed, checkpoint, progress, step)
    return lam, thetas, costs


def _residuals_and_jac(problem: SEProblem, z: np.ndarray, lam1: float, want_jac: bool):
    th = z / problem.scale
    L = problem.L
    w1 = np.sqrt(lam1 / problem.n_dyn)
    r, J = [], []
    for rec, U in zip(problem.records, problem.U):
        if want_jac:
            y, S = free_run_sensitivity(problem.code, th, rec.u, rec.y[:L], L, U)
            J.append(w1 * S[L:] / problem.scale)
        else:
            y = simulate_one(problem.code, th, rec.u, rec.y[:L], L, 1e300)
        r.append(w1 * (y[L:] - rec.y[L:]))
    lam2 = 1.0 - lam1
    if lam2 > 0:
        sp = problem.static
        w2 = np.sqrt(lam2 / len(sp))
        # an unstable equilibrium gives NaN here, hence inf residuals: least_squares treats the
        # region as infeasible and shrinks its step, so the front never trades J_SF for stability
        yb = problem.static_outputs(th)[0]
        r.append(w2 * (yb - sp.ybar))
        if want_jac:
            J.append(w2 * static_theta_gradient(problem.structure, th, sp.ubar, yb) / problem.scale)
    r = np.concatenate(r)
    if not np.all(np.isfinite(r)):
        r = np.full_like(r, np.inf)  # diverged: least_squares shrinks its trust region
    return r, (np.vstack(J) if want_jac else None)


def gradient_front(
    problem: SEProblem,
    lambdas: Sequence[float] | np.ndarray = SE_LAMBDAS,
    *,
    theta0: np.ndarray | None = None,
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    max_nfev: int = 50,
    tol: float = 1e-8,
    starts: Sequence[np.ndarray] = (),
    solver: Literal["trf", "dogbox", "lm"] = "trf",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gradient SE front: ``scipy.optimize.least_squares`` per λ1, warm-started.

    Parameters
    ----------
    problem : SEProblem
    lambdas : sequence of float in (0, 1]
        Run from λ1 = 1 down.
    theta0 : ndarray, optional
        Start of the first run (default: least squares on all samples).
    max_nfev, tol : int, float
        Per-λ limits passed to ``least_squares`` (``ftol = xtol = gtol = tol``).
    solver : {"trf", "dogbox", "lm"}
        ``least_squares`` method. On the plant's ℓ = 2 problem "dogbox" reached the lowest pure
        simulation error (λ1 = 1: J_S 0.158 in 65 evaluations; "trf" 0.442 and "lm" 0.464 in
        300), but along the sweep, where unstable equilibria are walls, it stalled in poorer
        minima (J_SF 0.08–0.27 where "trf" reached 0.001–0.003): "trf" is the default.
    starts : sequence of ndarray
        Further starting points tried, in order, when neither the previous λ's solution nor
        ``theta0`` gives a finite cost (e.g. their static equilibria are unstable).
        :func:`se_pareto` passes PE solutions (convex, with the static points weighted in).

    Returns
    -------
    lambdas, thetas, costs : as :func:`ga_front`
    """
    lam = np.sort(check_lambdas(lambdas))[::-1]
    start = problem.ls_theta() if theta0 is None else check_theta(len(problem.structure), theta0, "theta0")

    def step(i, lam1, prev, rng):
        cache: dict = {}

        def fun(z):
            r, J = _residuals_and_jac(problem, z, lam1, True)
            cache["J"] = J
            return r

        def jac(z):
            return cache["J"]

        # warm start from the previous λ; if its static equilibria are unstable (the λ1 = 1 run
        # ignores statics) start again from theta0
        for th0 in ([prev] if prev is not None else []) + [start] + [np.asarray(s, float) for s in starts]:
            z0 = th0 * problem.scale
            if np.all(np.isfinite(fun(z0))):
                break
        else:
            why = ("its free run diverges" if not np.isfinite(problem.js(start[None]))[0]
                   else "its equilibrium at some static point is unstable or undefined")
            raise ValueError(f"cannot start the gradient SE fit at λ1 = {lam1:g}: theta0 fails ({why}) and so "
                             f"do the {len(starts)} further start(s); give another theta0")
        with np.errstate(over="ignore", invalid="ignore"):  # inf residuals mark rejected steps
            res = least_squares(fun, z0, jac=jac, method=solver, x_scale="jac", max_nfev=max_nfev,
                                ftol=tol, xtol=tol, gtol=tol)
        th = res.x / problem.scale
        return th, float(2 * res.cost)

    check_choice(solver, "solver", ("trf", "dogbox", "lm"))
    thetas, costs = _sweep(problem, lam, "gradient", {"max_nfev": max_nfev, "tol": tol, "solver": solver,
                                                     "theta0": None if theta0 is None else list(map(float, start)),
                                                     "starts": [list(map(float, s_)) for s_ in starts]},
                           seed, checkpoint, progress, step)
    return lam, thetas, costs


def _pe_starts(problem: SEProblem) -> list[np.ndarray]:
    """PE solutions (closed form) leaning more and more on the static points: fallback starts."""
    try:
        with threadpool_limits(limits=1, user_api="blas"), warnings.catch_warnings():
            warnings.simplefilter("ignore", StaticRangeWarning)  # se_pareto has said it already
            return list(pe_thetas(problem.structure, problem.records, problem.static, [1e-1, 1e-2, 1e-3, 1e-4],
                                  solver="closed"))
    except ValueError:  # e.g. not identifiable with the static rows: no fallback, theta0 only
        return []


#: Options of :func:`se_pareto` that apply to one method only.
_METHOD_ONLY = {"ga": ("options",), "gradient": ("max_nfev", "tol", "solver", "starts")}


def se_pareto(
    structure: Structure,
    data: Record | Dataset | Sequence[Record],
    static: StaticPoints | None = None,
    lambdas: Sequence[float] | np.ndarray | None = None,
    *,
    method: Literal["ga", "gradient"] = "ga",
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    threads: int = 1,
    theta0: np.ndarray | Literal["ls"] | None = "ls",
    options: GAOptions | None = None,
    max_nfev: int | None = None,
    tol: float | None = None,
    solver: Literal["trf", "dogbox", "lm"] | None = None,
    starts: Sequence[np.ndarray] | None = None,
) -> ParetoSet:
    """SE Pareto set of eq. (13) by the paper's GA or the gradient method.

    Parameters
    ----------
    structure : Structure
        Process terms (noise terms are dropped: the SE problem has no MA part).
    data : Record, Dataset or sequence of Record
        Identification data (a Dataset's ``ident``); with several records each is run freely
        on its own and J_S is the mean over all their samples.
    static : StaticPoints, optional
        Static points (default: the Dataset's). Points outside the records' input range are
        welcome (a :class:`StaticRangeWarning` names them once).
    lambdas : sequence of float in (0, 1], optional
        λ1 values; default: the paper's logspace(-2, 0, 100). Runs go from λ1 = 1 down.
    method : {"ga", "gradient"}
        The paper's genetic algorithm, or ``scipy.optimize.least_squares`` with the analytic
        Jacobian of the free run.
    seed : int
        Makes the GA (and its random initial individuals) reproducible.
    checkpoint : path, optional
        Written after each λ; an existing one for the same problem resumes the sweep.
    progress : bool, optional
        Show a progress bar; default: only on a terminal.
    threads : int
        Threads for the GA's population runs and the evaluation of the members.
    theta0 : ndarray, "ls" or None
        Start. GA: an individual added to the first run's population (``"ls"``, the default: the
        least-squares estimate; ``None``: the paper's random individuals only). Gradient: the
        first run's start (``"ls"`` or ``None``: least squares).
    options : GAOptions, optional
        GA settings (GA only).
    max_nfev, tol, solver, starts : optional
        Gradient only: evaluations per λ (default 50), ``least_squares`` tolerances (1e-8), its
        method (``"trf"``), and further starting points (default: PE solutions).

    Returns
    -------
    ParetoSet
        All members (one per λ) with J_1, J_S and J_SF from the shared evaluator; the optimised
        cost is in ``extra["cost"]``. Use ``.nondominated()`` for the front proper.

    Raises
    ------
    ValueError
        An option of the other method is given, an unknown method, no static points.
    """
    check_choice(method, "method", ("ga", "gradient"))
    given = {"options": options, "max_nfev": max_nfev, "tol": tol, "solver": solver, "starts": starts}
    other = "gradient" if method == "ga" else "ga"
    wrong = [k for k in _METHOD_ONLY[other] if given[k] is not None]
    if wrong:
        raise ValueError(f"{', '.join(wrong)} appl{'y' if len(wrong) > 1 else 'ies'} to method={other!r} only, "
                         f"not to method={method!r}")
    rec = as_records(data)
    sp = static if static is not None else (data.static if isinstance(data, Dataset) else None)
    if sp is None:
        raise ValueError("the SE problem needs static points: pass static= or a Dataset with static points")
    warn_static_range(sp.ubar, rec)
    problem = SEProblem(structure, rec, sp)
    lam_in = SE_LAMBDAS if lambdas is None else lambdas
    if method == "ga":
        lam, th, cost = ga_front(problem, lam_in, options=options or GAOptions(), seed=seed, checkpoint=checkpoint,
                                 progress=progress, threads=threads, theta0=theta0)
    else:
        t0 = None if (isinstance(theta0, str) and theta0 == "ls") else theta0
        if isinstance(theta0, str) and theta0 != "ls":
            raise ValueError(f"theta0 must be an array, 'ls' or None, got {theta0!r}")
        lam, th, cost = gradient_front(
            problem, lam_in, theta0=t0, seed=seed, checkpoint=checkpoint, progress=progress,
            max_nfev=50 if max_nfev is None else max_nfev, tol=1e-8 if tol is None else tol,
            solver="trf" if solver is None else solver,
            starts=_pe_starts(problem) if starts is None else starts)
    finite = np.all(np.isfinite(th), axis=1) & np.isfinite(cost)
    if not finite.any():
        raise ValueError(
            f"the SE sweep ({method}) produced no member with a finite cost: every candidate's free run "
            "diverged or its static curve was undefined; try another structure, theta0 or more generations"
        )
    return ParetoSet.from_thetas(problem.structure, th[finite], lam[finite], rec, sp,
                                 method=f"SE ({method})", extra={"cost": cost[finite]}, threads=threads)
