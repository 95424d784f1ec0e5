"""Robustness of a decision: a block bootstrap of the identification records that reruns a sweep and D_SF.

D_SF (eq. (14)) picks one member of a Pareto set. Would it pick the same member from another
record of the same plant? :func:`bootstrap_decision` answers by resampling: each replicate draws
blocks of the identification record(s) (a moving-block bootstrap, which keeps the dynamics inside
each block), reruns the PE or SE sweep on them, applies D_SF, and records the chosen λ1 and that
member's J_S and J_SF.

Blocks as records
-----------------
The blocks of a replicate are *separate records*, not glued together: graybox's regressors and free
runs never straddle two records, so a replicate has no artificial jumps at the seams, and each
block's free run starts from its own first measured samples (as every record's does). Blocks are
drawn from every record of the data (every start position equally likely) until the replicate has
about as many samples as the original; a record shorter than a block holds no block, and is said
(an :class:`~graybox.UncertaintyWarning`) to be in the reference decision only.

The static points are kept as measured, or, with ``static_sigma``, perturbed by Gaussian noise of
that standard deviation in each replicate (a parametric bootstrap of the transmitter's error).

Running replicates elsewhere
----------------------------
Replicates are independent jobs: replicate ``i`` draws from ``numpy.random.default_rng([seed, i])``,
so the result does not depend on where or in which order they run. ``map`` is any callable with
the signature of the built-in ``map`` that returns the results in order:

- ``map=None``: in this process, one after the other (with a progress bar on a terminal);
- ``concurrent.futures.ProcessPoolExecutor().map``: local processes;
- on the experiment layer's executors: ``with graybox.experiments.parallel_map(workers=2) as pmap: … map=pmap`` (Dask or local processes).

The job object (:class:`BootstrapJob`) is a frozen dataclass of plain values and records, so it
pickles for processes and Dask workers alike (these are graybox's own objects in transit, never a
user's file). A replicate that fails (no member in the band without a fallback, a sweep with no
finite member, …) is kept with its reason and the bootstrap goes on; the failures are counted in
one :class:`~graybox.UncertaintyWarning` (the summary describes the replicates that succeeded), and
when every replicate fails the bootstrap is a ValueError naming the first one's reason. The sweep
on the original data (the reference decision) runs first, in this process: an option the sweep
refuses raises there, before any replicate runs.
"""

from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Iterable, Mapping, Sequence

import numpy as np

from ..estimation._prediction_error import PE_LAMBDAS, pe_pareto
from ..estimation._decisions import FALLBACKS, decide_dsf, resolve_band
from ..estimation._pareto import ParetoSet
from ..core._progress import progress_bar
from ..models._coerce import as_structure, records_of, static_points
from ..core._records import Dataset, Record, StaticPoints, StaticRangeWarning
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface
from ..estimation._simulation_error import SE_LAMBDAS, se_pareto
from ..core._terms import Structure
from ..core._validation import (Relocked, FrozenMap, check_band, check_choice, check_count, check_fields, check_int,
                                check_lambdas, check_mean_square, check_real, check_seed, frozen, frozen_value, warn)
from ..core._reprs import listed, share_text, short_repr
from ._uncertainty import UncertaintyWarning

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["BootstrapJob", "DecisionBootstrap", "bootstrap_decision", "block_resample"]

ESTIMATORS = ("pe", "se")
#: What a replicate may fail with and go on (InfeasibleError, DivergenceError are ValueErrors); anything else is a bug
_FAILURES = (ValueError, ArithmeticError, np.linalg.LinAlgError)


def block_resample(
    records: Sequence[Record],
    block_length: int,
    rng: np.random.Generator,
) -> list[Record]:
    """One moving-block bootstrap replicate: blocks of ``block_length`` samples, each a Record.

    Parameters
    ----------
    records : sequence of Record
        The original records; a block lies inside one record.
    block_length : int
        Samples per block.
    rng : numpy.random.Generator
        Source of the block starts.

    Returns
    -------
    list of Record
        round(Σ N_r / block_length) blocks (at least one), each named after its record and range.
    """
    starts = [(i, s) for i, r in enumerate(records) for s in range(len(r) - block_length + 1)]
    if not starts:
        raise ValueError(f"no record has {block_length} samples: use a shorter block_length")
    total = sum(len(r) for r in records)
    count = max(1, int(round(total / block_length)))
    pick = rng.integers(0, len(starts), size=count)
    out = []
    for j in pick:
        i, s = starts[int(j)]
        r = records[i]
        out.append(r.slice(s, s + block_length, name=f"{r.name}[{s}:{s + block_length}]"))
    return out


@dataclass(frozen=True, eq=False)
class BootstrapJob:
    """One bootstrap's settings; calling it with a replicate index runs that replicate.

    ``job(-1)`` runs the sweep and D_SF on the original data (the reference decision);
    ``job(i)`` for i >= 0 on replicate i. Returns a dict of plain values (picklable):
    ``lambda1, index, JS, JSF, in_band, rule, theta`` or ``failure`` (the reason, in words).

    Attributes
    ----------
    structure : Structure
    records : tuple of Record
    static : StaticPoints
    estimator : str
        ``"pe"`` or ``"se"``.
    lambdas : ndarray
        λ1 values of the sweep.
    band : float or (float, float)
        D_SF's band B.
    fallback : str or None
        As for :func:`graybox.decide_dsf`.
    block_length : int
    seed : int
    static_sigma : float or None
    options : mapping
        Keyword options of :func:`graybox.pe_pareto` or :func:`graybox.se_pareto`.
    """

    structure: Structure
    records: tuple[Record, ...]
    static: StaticPoints
    estimator: str
    lambdas: np.ndarray
    band: float | tuple[float, float]
    fallback: str | None
    block_length: int
    seed: int
    static_sigma: float | None
    options: Mapping = field(default_factory=dict)

    def data(self, i: int) -> tuple[list[Record], StaticPoints]:
        """The records and static points of replicate ``i`` (the original ones for i = −1)."""
        if i < 0:
            return list(self.records), self.static
        rng = np.random.default_rng([self.seed, i])
        recs = block_resample(self.records, self.block_length, rng)
        sp = self.static
        if self.static_sigma is not None:
            sp = StaticPoints(sp.ubar, sp.ybar + self.static_sigma * rng.standard_normal(len(sp)), sp.name,
                              sp.input_names, sp.uncertainty, sp.units)
        return recs, sp

    def _sweep(self, recs: list[Record], sp: StaticPoints) -> ParetoSet:
        with warnings.catch_warnings():
            # said once by bootstrap_decision; block records cover a narrower input range than the whole
            warnings.simplefilter("ignore", StaticRangeWarning)
            if self.estimator == "pe":
                return pe_pareto(self.structure, recs, sp, lambdas=self.lambdas, **dict(self.options))
            return se_pareto(self.structure, recs, sp, lambdas=self.lambdas, progress=False, **dict(self.options))

    def _decide(self, front: ParetoSet) -> dict:
        try:
            d = decide_dsf(front, band=self.band, fallback=self.fallback)
        except _FAILURES as exc:
            return {"failure": f"{type(exc).__name__}: {exc}"}
        return {"lambda1": d.lambda1, "index": d.index, "JS": d.JS, "JSF": d.JSF, "in_band": d.in_band,
                "rule": d.rule, "theta": [float(v) for v in d.model.theta]}

    def __call__(self, i: int) -> dict:
        try:
            front = self._sweep(*self.data(int(i)))
        except _FAILURES as exc:
            return {"failure": f"{type(exc).__name__}: {exc}"}
        return self._decide(front)

    def reference(self) -> dict:
        """The decision on the original data, as ``job(-1)``, except that the sweep's own errors raise:
        an option it refuses (or a sweep with no member on the original data) fails here, before any
        replicate runs, instead of failing every replicate alike."""
        return self._decide(self._sweep(*self.data(-1)))

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


@dataclass(frozen=True, eq=False)
class DecisionBootstrap(Relocked):
    """The result of :func:`bootstrap_decision`.

    Attributes
    ----------
    structure : Structure
    estimator : str
        ``"pe"`` or ``"se"`` (with the estimator options in :attr:`options`).
    lambdas : ndarray, shape (K,)
        The sweep's λ1 values.
    band : float or (float, float)
        D_SF's band.
    block_length, n_blocks : int
        Samples per block and blocks per replicate.
    seed : int
    lambda1 : ndarray, shape (B,)
        λ1 chosen in each replicate (NaN where it failed).
    JS, JSF : ndarray, shape (B,)
        The chosen member's J_S and J_SF on its replicate's data (NaN where it failed).
    in_band : ndarray of bool, shape (B,)
        Whether the chosen member's J_SF lies in B (False for a fallback choice or a failure).
    thetas : ndarray, shape (B, n_terms)
        The chosen members' θ (NaN rows where it failed).
    rules : tuple of str
        The decision rule of each replicate (``"D_SF"``, ``"min J_SF"``, or ``""`` where it failed).
    reference : mapping
        The decision on the original data (``lambda1``, ``JS``, ``JSF``, ``in_band``, ``rule``,
        ``theta``), or ``{"failure": reason}``.
    failures : mapping int -> str
        Replicates that failed, with the reason.
    options : mapping
        The estimator options used.
    static_sigma : float or None
    """

    structure: Structure
    estimator: str
    lambdas: np.ndarray
    band: float | tuple[float, float]
    block_length: int
    n_blocks: int
    seed: int
    lambda1: np.ndarray
    JS: np.ndarray
    JSF: np.ndarray
    in_band: np.ndarray
    thetas: np.ndarray
    rules: tuple[str, ...]
    reference: Mapping
    failures: Mapping[int, str]
    options: Mapping = field(default_factory=dict)
    static_sigma: float | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        B = np.shape(self.lambda1)[0]
        for f in ("lambdas", "lambda1", "JS", "JSF"):
            object.__setattr__(self, f, frozen(getattr(self, f)))
        object.__setattr__(self, "in_band", frozen(self.in_band, bool))
        th = frozen(np.reshape(self.thetas, (B, len(self.structure))))
        object.__setattr__(self, "thetas", th)
        for f in ("JS", "JSF", "in_band"):
            if getattr(self, f).shape != (B,):
                raise ValueError(f"{f} must have shape ({B},), got {getattr(self, f).shape}")
        if len(self.rules) != B:
            raise ValueError(f"rules must have {B} entries, got {len(self.rules)}")
        object.__setattr__(self, "rules", tuple(self.rules))
        # immutable all the way down: the reference's θ (a list in the job's plain result) and the options as given
        object.__setattr__(self, "reference", frozen_value(dict(self.reference), "reference", numbers_as_arrays=True))
        object.__setattr__(self, "failures", FrozenMap({int(k): str(v) for k, v in dict(self.failures).items()}))
        object.__setattr__(self, "options", frozen_value(dict(self.options), "options", numbers_as_arrays=True))
        self._check_values()

    def _check_values(self) -> None:
        """What :func:`bootstrap_decision` makes, held to a bootstrap built by hand or read from an edited file: the
        settings in range, each replicate a decision by D_SF or its fallback at one of the sweep's λ1, or a failure
        with its reason."""
        check_choice(self.estimator, "estimator", ESTIMATORS)
        check_lambdas(self.lambdas, "lambdas")  # the sweep's λ1, as bootstrap_decision takes them
        check_seed(self.seed)
        check_int(self.block_length, "block_length", low=1)
        check_int(self.n_blocks, "n_blocks", low=1)
        check_band(self.band, "band")
        if self.static_sigma is not None:
            check_real(self.static_sigma, "static_sigma", low=0, low_open=True)
        B = self.lambda1.size
        failed = np.zeros(B, bool)
        for i in self.failures:
            if not 0 <= i < B:
                raise ValueError(f"failures: no replicate {i} of {B}")
            failed[i] = True
        if not np.array_equal(failed, np.isnan(self.lambda1)):
            raise ValueError("failures must name exactly the replicates without a decision (lambda1 NaN)")
        if not np.all(np.isin(self.lambda1[~failed], self.lambdas)):
            raise ValueError(f"lambda1: each replicate's choice is one of the sweep's lambdas, got "
                             f"{sorted(set(self.lambda1[~failed]) - set(self.lambdas))[:3]}")
        check_mean_square(self.JS, "JS")
        check_mean_square(self.JSF, "JSF")
        for i, (rule, inb) in enumerate(zip(self.rules, self.in_band)):
            want = ("",) if failed[i] else ("D_SF", "min J_SF")
            if rule not in want:
                raise ValueError(f"rules[{i}] must be one of {want} for {'a failed' if failed[i] else 'a'} replicate, "
                                 f"got {rule!r}")
            if bool(inb) != (rule == "D_SF"):
                raise ValueError(f"in_band[{i}] is {bool(inb)} but replicate {i}'s rule is {rule or 'none (failed)'!r}")

    @property
    def n_replicates(self) -> int:
        """B, replicates run (failed ones included)."""
        return int(self.lambda1.size)

    @property
    def ok(self) -> np.ndarray:
        """Replicates that produced a decision, shape (B,) bool."""
        return np.isfinite(self.lambda1)

    @property
    def agreement(self) -> float:
        """Fraction of the successful replicates that chose the reference λ1 (NaN without one)."""
        ref = self.reference.get("lambda1")
        if ref is None or not self.ok.any():
            return float("nan")
        return float(np.mean(self.lambda1[self.ok] == ref))

    def frequencies(self) -> pd.DataFrame:
        """How often each λ1 was chosen.

        Returns
        -------
        pandas.DataFrame
            One row per λ1 (index ``lambda1``, ascending): ``count`` and ``fraction`` of the successful replicates
            that chose it, and ``reference`` (True for the reference decision's λ1, listed even when no replicate
            chose it).
        """
        import pandas as pd

        lam = self.lambda1[self.ok]
        vals, counts = np.unique(lam, return_counts=True)
        ref = self.reference.get("lambda1")
        if ref is not None and ref not in vals:  # the reference's λ1 is listed even if no replicate chose it
            vals, counts = np.append(vals, ref), np.append(counts, 0)
            order = np.argsort(vals)
            vals, counts = vals[order], counts[order]
        df = pd.DataFrame({"count": counts, "fraction": counts / max(lam.size, 1)}, index=pd.Index(vals, name="lambda1"))
        df["reference"] = df.index == ref if ref is not None else False
        return df

    def summary(self) -> pd.DataFrame:
        """The spread of the chosen member's J_S and J_SF.

        Returns
        -------
        pandas.DataFrame
            Rows ``JS`` and ``JSF``; columns ``reference``, ``median``, ``q05``, ``q95`` (5 % and 95 % quantiles)
            and ``std`` over the replicates whose J is finite (all in output units²), ``infinite``:
            how many replicates' chosen member has an infinite J (a free run that diverged, a static curve with no
            equilibrium: ``fallback="min_jsf"`` can choose such a member), left out of the others, and
            ``in band``: the fraction of the successful replicates whose choice is in the band.
        """
        import pandas as pd

        rows = {}
        for name in ("JS", "JSF"):
            v = getattr(self, name)[self.ok]
            finite = v[np.isfinite(v)]
            q = np.quantile(finite, [0.05, 0.5, 0.95]) if finite.size else [np.nan] * 3
            rows[name] = {"reference": self.reference.get(name, np.nan), "median": q[1], "q05": q[0], "q95": q[2],
                          "std": float(np.std(finite)) if finite.size else np.nan,
                          "infinite": int(np.sum(np.isinf(v)))}
        rows_df = pd.DataFrame.from_dict(rows, orient="index")
        rows_df["in band"] = float(np.mean(self.in_band[self.ok])) if self.ok.any() else np.nan
        return rows_df

    def to_frame(self) -> pd.DataFrame:
        """The replicates as a table.

        Returns
        -------
        pandas.DataFrame
            One row per replicate (index ``replicate``): ``lambda1``, ``JS``, ``JSF`` (output units²), ``in band``,
            ``rule`` (``"D_SF"`` or ``"min J_SF"``, the rule that chose; ``""`` when it failed) and ``failure``
            (the reason, ``""`` for a replicate that did not fail).
        """
        import pandas as pd

        return pd.DataFrame({"lambda1": self.lambda1, "JS": self.JS, "JSF": self.JSF, "in band": self.in_band,
                             "rule": self.rules, "failure": [self.failures.get(i, "") for i in range(self.n_replicates)]},
                            index=pd.RangeIndex(self.n_replicates, name="replicate"))

    def __repr__(self) -> str:
        # the share with the digits it needs: ':.2f' read 999 of 1000 replicates agreeing as 'agreement=1.00'
        agree = "nan" if np.isnan(self.agreement) else share_text(self.agreement)
        return (f"DecisionBootstrap({self.estimator.upper()}, replicates={self.n_replicates}, failed={len(self.failures)}, "
                f"blocks={self.n_blocks} × {self.block_length}, agreement={agree})")


def _estimator_options(estimator: str, options: Mapping | None) -> dict:
    if options is not None and not isinstance(options, Mapping):
        raise TypeError(f"options must be a mapping of the sweep's keyword options, got {options!r}")
    opts = dict(options or {})
    fn = pe_pareto if estimator == "pe" else se_pareto
    allowed = [p.name for p in inspect.signature(fn).parameters.values() if p.kind == p.KEYWORD_ONLY]
    taken = {"lambdas"} | ({"progress", "checkpoint"} if estimator == "se" else set())  # the bootstrap's own
    bad = [k for k in opts if k not in allowed or k in taken]
    if bad:
        own = " (pass lambdas= to bootstrap_decision itself)" if "lambdas" in bad else ""
        raise ValueError(f"options {bad} are not keyword options of {fn.__name__} the bootstrap can pass{own} "
                         f"(allowed: {sorted(set(allowed) - taken)})")
    return opts


def bootstrap_decision(
    structure: Structure,
    data: Record | Sequence[Record] | Dataset,
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    estimator: str = "pe",
    lambdas: Sequence[float] | np.ndarray | None = None,
    n_boot: int = 50,
    block_length: int | None = None,
    band: float | tuple[float, float] | None = None,
    fallback: str | None = None,
    static_sigma: float | None = None,
    seed: int = 0,
    options: Mapping | None = None,
    map: Callable[[Callable[[int], dict], Iterable[int]], Iterable[dict]] | None = None,
    progress: bool | None = None,
) -> DecisionBootstrap:
    """Block bootstrap of the identification data: rerun the PE or SE sweep and D_SF per replicate.

    Parameters
    ----------
    structure : Structure, sequence of str, Model, or a result that carries one
        Process terms (a Selection, ELSResult, Decision … gives its own).
    data : Record, sequence of Record, or Dataset
        Identification data (a Dataset's ``ident``, and its static points by default).
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static points (default: the Dataset's); a curve or surface is sampled over its domain as
        every estimator samples it, or at the ``ubar`` of ``options`` (sampled points carry no
        uncertainty: give ``band``).
    estimator : {"pe", "se"}
        The sweep: :func:`graybox.pe_pareto` or :func:`graybox.se_pareto`.
    lambdas : array_like of shape (P,), optional
        λ1 values in (0, 1] (default: the estimator's paper sweep; a short one keeps the bootstrap fast).
    n_boot : int
        Replicates B.
    block_length : int, optional
        Samples per block (default: the larger of 10·(max lag + 1) and a tenth of the data);
        at least 2·(max lag + 1) so that a block has rows to fit.
    band : float or (float, float), optional
        As for :func:`graybox.decide_dsf`; default: the static points' own band
        (:attr:`~graybox.StaticPoints.band`), required when they carry no uncertainty.
    fallback : {None, "min_jsf"}
        As for :func:`graybox.decide_dsf`.
    static_sigma : float, optional
        Standard deviation of Gaussian noise added to the static ȳ_i in each replicate (output
        units); default: the static points are kept as measured.
    seed : int
        Replicate i draws from ``default_rng([seed, i])``: the result is reproducible and does not
        depend on where replicates run.
    options : mapping, optional
        Keyword options of the sweep (e.g. ``{"solver": "closed"}`` for PE,
        ``{"method": "gradient", "max_nfev": 20}`` for SE). The SE GA's own ``seed`` (default 0) is
        the same in every replicate: replicates differ by their data only.
    map : callable, optional
        ``map(job, range(B))`` returning results in order: ``None`` runs in this process; pass an
        executor's ``.map`` or a Dask wrapper to run elsewhere (see the module docstring).
    progress : bool, optional
        Progress bar (default: on a terminal only; in-process runs).

    Returns
    -------
    DecisionBootstrap
        Chosen λ1, J_S, J_SF per replicate; ``frequencies()``, ``summary()``, ``agreement``; the
        reference decision on the original data; failures with their reasons. Draw it with
        :func:`graybox.plots.plot_decision_bootstrap`.

    Raises
    ------
    ValueError
        Bad options (an unknown estimator option or a value the sweep refuses, a block too short
        for the lags or longer than every record, no static points); the sweep on the original
        data fails; every replicate fails (the first one's reason is named).
    TypeError
        An option of a type the sweep refuses.

    Warns
    -----
    UncertaintyWarning
        Some replicates failed: they are counted and the first one's reason is named (all reasons
        in ``failures``). Some records are shorter than ``block_length``: no replicate draws from them
        (they are named).
    """
    structure = as_structure(structure)
    estimator = check_choice(estimator, "estimator", ESTIMATORS)
    recs = records_of(data)
    opts = _estimator_options(estimator, options)
    # a curve or surface is sampled here, at the sweep's own ubar when the options give one (the sweep is handed
    # the points, which carry their ū)
    sp = static_points(static, data, ubar=opts.get("ubar"), needed_by="bootstrap_decision",
                       takes_ubar="ubar" in opts)
    lam = check_lambdas((PE_LAMBDAS if estimator == "pe" else SE_LAMBDAS) if lambdas is None else lambdas)
    n_boot = check_count(n_boot, "n_boot", low=1)
    seed = check_seed(seed)
    L = structure.process.max_lag
    total = sum(len(r) for r in recs)
    if block_length is None:
        block_length = min(max(10 * (L + 1), total // 10), max(len(r) for r in recs))
        if block_length < 2 * (L + 1):  # the default, not the user, would be named by the check below
            raise ValueError(f"bootstrap_decision: the records ({[len(r) for r in recs]} samples) are too short for "
                             f"blocks of this structure (largest lag {L}): a block needs at least {2 * (L + 1)} "
                             "samples to leave rows to fit")
    block_length = check_int(block_length, "block_length", low=2 * (L + 1))
    if static_sigma is not None:
        static_sigma = check_real(static_sigma, "static_sigma", low=0, low_open=True)
    lo, hi = resolve_band(band, sp, "bootstrap_decision")
    band = hi if lo == 0 and (band is None or np.ndim(band) == 0) else (lo, hi)
    if fallback is not None:
        check_choice(fallback, "fallback", FALLBACKS)
    if map is not None and not callable(map):
        raise TypeError(f"map must be a callable map(job, ids) (e.g. an executor's .map), got {map!r}")
    if hasattr(map, "__enter__") and hasattr(map, "__exit__") and not hasattr(map, "__self__"):
        # parallel_map(...) not entered: callable as a decorator, it failed only after the sweep on the original
        # data, with "ContextDecorator.__call__() takes 2 positional arguments but 3 were given"
        raise TypeError(f"map is a context manager ({type(map).__name__}), not the map it makes: run the bootstrap "
                        "inside it, e.g. `with graybox.experiments.parallel_map(workers=2) as pmap: "
                        "bootstrap_decision(..., map=pmap)`")
    if not any(len(r) >= block_length for r in recs):
        raise ValueError(f"block_length {block_length} is longer than every record ({[len(r) for r in recs]} samples)")
    short = [f"{r.name or 'record'} ({len(r)} samples)" for r in recs if len(r) < block_length]
    if short:  # no block lies inside them: the replicates are drawn from the other records alone
        warn(f"bootstrap_decision: {len(short)} record(s) shorter than block_length = {block_length} are in the "
             f"reference decision but in no replicate (no block fits inside them): {listed(short)}; give a "
             "shorter block_length to draw from them too", UncertaintyWarning)
    job = BootstrapJob(structure.process, tuple(recs), sp, estimator, lam, band, fallback, block_length, seed,
                       static_sigma, {k: v for k, v in opts.items() if k != "ubar"})
    ids = list(range(n_boot))
    reps: list[dict] = []
    bar = progress_bar(len(ids) + 1, f"bootstrap of D_SF ({estimator.upper()})", progress if map is None else False)
    try:
        ref = job.reference()  # the sweep's own checks of the options, before any replicate runs
        bar.update(1)
        if map is None:
            for i in ids:
                reps.append(job(i))
                bar.update(1)
        else:
            reps = list(map(job, ids))
            if len(reps) != len(ids):
                raise ValueError(f"map returned {len(reps)} results for {len(ids)} jobs")
            bad = next((i for i, r in enumerate(reps) if not isinstance(r, dict)), None)
            if bad is not None:  # e.g. a Dask client's map, which returns futures, not the jobs' results
                raise TypeError(f"map must return the jobs' results in order (each a dict, as job(i) returns it); "
                                f"result {bad} is a {type(reps[bad]).__name__} (a Dask client's map returns futures: "
                                "gather them, or use graybox.experiments.parallel_map)")
    finally:
        bar.close()
    n = len(structure.process)
    lam1 = np.full(n_boot, np.nan)
    js, jsf = np.full(n_boot, np.nan), np.full(n_boot, np.nan)
    inb = np.zeros(n_boot, bool)
    th = np.full((n_boot, n), np.nan)
    rules, fails = [], {}
    for i, r in enumerate(reps):
        if "failure" in r:
            fails[i] = r["failure"]
            rules.append("")
            continue
        lam1[i], js[i], jsf[i], inb[i] = r["lambda1"], r["JS"], r["JSF"], r["in_band"]
        th[i] = r["theta"]
        rules.append(r["rule"])
    if len(fails) == n_boot:
        raise ValueError(f"bootstrap_decision: every one of the {n_boot} replicates failed, so there is no "
                         f"decision to summarise; the first, replicate 0: {fails[0]}")
    if fails:
        first = min(fails)
        warn(f"bootstrap_decision: {len(fails)} of {n_boot} replicates failed and are left out of the frequencies, "
             f"agreement and summary (the first, replicate {first}: {fails[first]}); their reasons are in .failures",
             UncertaintyWarning)
    n_blocks = max(1, int(round(total / block_length)))
    return DecisionBootstrap(structure.process, estimator, lam, band, block_length, n_blocks, seed, lam1, js, jsf, inb, th,
                             tuple(rules), ref, fails, opts, static_sigma)
