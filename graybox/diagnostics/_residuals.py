"""Residual validation: the higher-order correlation tests of Billings & Voon (1986).

A model whose one-step residuals ξ are unpredictable from past data has captured everything the
data can say. Billings & Voon ("Structure detection and model validity tests in the
identification of nonlinear systems", IEE Proc. D 130(4), 1983; "Correlation based model
validity tests for non-linear models", Int. J. Control 44(1), 1986) showed that for a NARMAX
model the linear tests (residual autocorrelation, input/residual cross-correlation) are not
enough: a missing term in u² leaves them clean. Their five tests, as Billings & Zhu (1994) and
Billings's book (2013, Section 5.2) collect them, with ξ' = ξ − mean(ξ) etc.:

====================  ========================================  ===================
test                  correlation of                            lags (default)
====================  ========================================  ===================
φ_ξξ(τ)               ξ(k−τ) and ξ(k)                           τ = 1 … 20
φ_uξ(τ)               u(k−τ) and ξ(k)                           τ = −20 … 20
φ_ξ(ξu)(τ)            ξ(k−1−τ)u(k−1−τ) and ξ(k)                 τ = 0 … 20
φ_(u²)'ξ(τ)           u²(k−τ) and ξ(k)                          τ = −20 … 20
φ_(u²)'ξ²(τ)          u²(k−τ) and ξ²(k)                         τ = −20 … 20
====================  ========================================  ===================

Products with u use the input centred and scaled to unit spread (u' = (u − mean u)/std u): with
an engineering offset (u ≈ 1000 ± 400 rpm) the raw u² would be almost a linear function of u and
ξu almost a multiple of ξ, and the higher-order tests would repeat the linear ones. Each φ is a
normalised sample correlation (means removed, divided by the product of the two
sequences' norms over all samples, as Box & Jenkins' biased estimator), so it lies in [−1, 1] and
does not depend on units. For a model that explains the data, each is zero at every lag up to
sampling error, which for N residuals is approximately normal with standard deviation 1/√N:
the 95 % band is ±1.96/√N.

Pass or fail
------------
Twenty to forty-one lags are looked at per test. Read lag by lag, even a correct model has about
5 % of them outside the 95 % band (with 41 lags it leaves the band somewhere in 88 % of records),
so "no lag outside ±1.96/√N" (``rule="pointwise"``, the literature's reading taken literally)
fails correct models most of the time. The default, ``rule="simultaneous"``, asks the question
at the 95 % level for the test as a whole: a test fails when its largest |φ| over the lags exceeds
a limit set by permutation. The residuals are shuffled within each record B times (199 at 95 %, 999 at
99 %: ``(B + 1)(1 − level) = 10``, seeded by ``seed``), each test's φ recomputed on every shuffle, and
the limit is the smallest of the 10 largest of the B shuffles' max |φ|: the test fails when the record's own
max |φ| exceeds it, i.e. is among the 10 largest of the B + 1 (a p-value of at most 10/(B + 1)). For a model
that explains the data, ξ is white noise independent of u, every order of its samples is as likely as
the recorded one, and the test fails a correct model with probability at most 1 − level, exactly, whatever
the tails of u and ξ and however the lags correlate (a held input). Shuffling keeps the residuals' own
tails, so a skewed, heavy-tailed input and noise widen the limit as much as they widen φ, and a slow
input's correlated lags narrow it.

Normal limits do not: a sum of products of skewed, heavy-tailed factors is far from normal out in the tail
where a lag's share of the 5 % lies (0.12 % for 41 lags). A Bonferroni limit ±z/√N (z = 3.23 for 41 lags),
and the same with an Edgeworth term in the products' kurtosis and skewness (the limit of graybox until
2026-11-29, which files written then keep, ``permutations = 0``), failed a correct model's φ_(u²)'ξ² in
13–20 % of records with a chi-square input and noise and in 18–23 % with Student-t input and noise of 3
degrees of freedom (N = 200–2000, 300 records each, ``benchmarks/bench_residual_tests.py --families``); the
permutation limit fails it in 2.7–6 % of those records, and every test in 1.7–8 % of the records of every input
and noise tried (Gaussian, uniform, chi-square, Student t, a held input; 5 % up to the sampling error, ±1.3 %).
Where the normal limit held its size it is as sharp or sharper (a missing u² under a held input, N = 2000:
φ_(u²)'ξ fails 65 % of records, against 53 %); where it did not, its rejections were partly false alarms. The price: a test can fail only where its φ stands out from what the record's own
residuals give in another order. With an impulse input, φ_uξ(τ) is one residual per lag, and a model with
the wrong gain fails only if the residual after the impulse is among the largest of the record's: with 41
lags and fewer than 820 samples it never fails (41 of N is more than 5 % of the draws; a normal limit would
fail it, by assuming normal noise). The pointwise band stays the literature's ±1.96/√N.

:attr:`CorrelationTest.excess_kurtosis` and :attr:`CorrelationTest.skewness` say how heavy-tailed the products
are: N times the excess kurtosis, and √N times the skewness, of a sum of products normalised by both
sequences' norms, (κ_a − 3)(κ_b − 3) − 6 and γ_a γ_b from the two sequences' own (−6 where either is
Gaussian: b / ‖b‖ is then uniform on the sphere). Only a file of an older graybox's limit depends on them.

What the 95 % promises, measured (``benchmarks/bench_residual_tests.py``, BENCHMARKS.md: a NARX
system with white equation noise, N = 1000, 200 records). With the system's own parameters, each
test fails 3–7 % of records under the simultaneous rule (5 % by construction; ±1.5 % is the sampling
error of 200 records), and 47–88 % under the pointwise one (1 − 0.95^K for K independent lags: 64 % for
20, 88 % for 41; less when a slow input correlates the lags). :attr:`ResidualTests.passed` asks all five
tests (and each input's), each at 95 % on its own: a correct model fails at least one in up to
5 × 5 % = 25 % of records (measured 19–21 %), not 5 %. On fresh data a fitted model fails more
often than its true-parameter twin, mostly φ_uξ (10–18 % with a fit on as many samples as the
test record): its parameter error, of order 1/√N of the fit's record, correlates its residuals
with the input, which a new record with independent noise shows. That is the model's error, not
the test's (a fit on ten times as many samples brings φ_uξ back to 4–6.5 %); on the
identification record least squares makes ξ orthogonal to the regressors, and the tests fail no more often
than the true parameters'. A shuffled record's verdict is the seed's only where max |φ| lies within the limit's
own sampling error (a few % of it with 199 shuffles): ``seed`` fixes it.

Residuals
---------
ξ(k) is the model's one-step prediction error on measured data, counted from sample L on (L the
largest lag, process and noise terms). For a model with an MA part (ELS), ξ includes it:
ξ(k) = y(k) − ψ(k)ᵀθ − Σ_j c_j ν_j(k), with the noise terms ν_j evaluated on the residuals
themselves (zero before sample L), the recursion whose fixed point ELS converges to. That is the
model the tests judge: its MA part is meant to whiten the equation error, and the tests ask whether
it did. ``moving_average=False`` judges the process part alone (ξ = y − ψᵀθ, the equation error,
coloured whenever the noise is). A neural model's residuals are those of its training predictor
(:meth:`graybox.NeuralModel.predict_narmax`), or of its deterministic predictor without the MA part.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from ..models._coerce import MODEL_ACCEPTED, as_model, records_of
from ..models._model import Model
from ..estimation._neural import NeuralModel
from ..core._records import Dataset, Record
from ..core._regressors import record_signals, regressor_matrix
from ..core._simulation_kernels import inverse_ma_filter
from ..core._reprs import percent_text
from ..estimation._extended_least_squares import _ma_invertible, _ma_text
from ..core._least_squares import binary_scaled, scaled_theta
from ..core._validation import (Relocked, FrozenMap, check_agrees, check_bool, check_choice, check_fields, check_int,
                                check_level, check_real, check_seed, frozen, warn)

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

#: What a model argument of the residual tests may be, in words.
_ACCEPTED = MODEL_ACCEPTED.replace("a Model or", "a Model, a NeuralModel or").replace(")", ", NeuralFit)")

__all__ = ["CorrelationTest", "ResidualTests", "residual_tests", "one_step_residuals", "TESTS"]

#: The five tests: key -> (label, kind, lag side). Side "both": τ = −L … L; "positive": 1 … L
#: (φ_ξξ is symmetric and 1 at τ = 0); "nonnegative": 0 … L.
TESTS: Mapping[str, tuple[str, str, str]] = MappingProxyType({
    "xi_xi": ("φ_ξξ(τ)", "linear", "positive"),
    "u_xi": ("φ_uξ(τ)", "linear", "both"),
    "xi_xiu": ("φ_ξ(ξu)(τ)", "nonlinear", "nonnegative"),
    "u2_xi": ("φ_(u²)'ξ(τ)", "nonlinear", "both"),
    "u2_xi2": ("φ_(u²)'ξ²(τ)", "nonlinear", "both"),
})

#: The tests made once per input, and of them those of u'² (undefined where u'² is constant).
INPUT_TESTS = tuple(k for k in TESTS if k != "xi_xi")
U2_TESTS = tuple(k for k in INPUT_TESTS if k.startswith("u2_"))

RULES = ("simultaneous", "pointwise")


def _label_of(name: str) -> str:
    """The label of the test keyed ``name`` in ``TESTS`` (``"u_xi:rpm"``: the input's name for u, ``"φ_rpmξ(τ)"``)."""
    base, _, nm = name.partition(":")
    label = TESTS[base][0]
    return label.replace("u", nm) if nm else label


@dataclass(frozen=True, eq=False)
class CorrelationTest(Relocked):
    """One correlation test over its lags.

    Attributes
    ----------
    name : str
        Key in ``TESTS`` (``"xi_xi"``, ``"u_xi"``, ``"xi_xiu"``, ``"u2_xi"``, ``"u2_xi2"``); with
        several inputs each input test once per input, keyed ``"u_xi:u1"`` and so on.
    label : str
        As the literature prints it, e.g. ``"φ_(u²)'ξ(τ)"`` (``"φ_(rpm²)'ξ(τ)"`` for the input ``rpm`` of
        several); held to the name's.
    kind : str
        ``"linear"`` or ``"nonlinear"``.
    lags : ndarray of int, shape (m,)
        τ, in samples.
    phi : ndarray, shape (m,)
        The normalised correlation at each lag, in [−1, 1] (NaN at every lag in a file of an older graybox: a
        test the data could not make, 0/0, kept as failed).
    band : float
        The pointwise confidence half-width z_{(1+level)/2}/√N (1.96/√N at 95 %).
    limit : float
        The half-width the pass/fail rule uses, in φ's units (at most 1): ``band`` for the pointwise rule; for
        the simultaneous one the largest |φ| over the lags that the residuals in shuffled order reach in
        (1 − level) of ``permutations`` + 1 draws (see the module docstring).
    outside : ndarray of int
        Lags where |φ| > ``band``.
    passed : bool
        Every |φ| <= ``limit`` (a tie with a limit set on permutations, within round-off, passes).
    excess_kurtosis, skewness : float
        N times the excess kurtosis, and √N times the skewness, of φ at a lag were the test's two sequences a
        and b independent: (κ_a − 3)(κ_b − 3) − 6 and γ_a γ_b from their own kurtosis and skewness (−6 where
        either is Gaussian; 0 in a file of an older graybox): how heavy-tailed the products are. They set the
        limit only of a simultaneous test with ``permutations = 0``, from a file of an older graybox (the
        Bonferroni half-width with an Edgeworth term in them).
    permutations : int
        The shuffles of the residuals the simultaneous limit was set on (199 at 95 %, 999 at 99 %); 0 for the
        pointwise rule and in a file of an older graybox.
    """

    name: str
    label: str
    kind: str
    lags: np.ndarray
    phi: np.ndarray
    band: float
    limit: float
    outside: np.ndarray
    passed: bool
    excess_kurtosis: float = 0.0
    skewness: float = 0.0
    permutations: int = 0

    def __post_init__(self) -> None:
        check_fields(self)
        # read-only, and held to what residual_tests makes (one built by hand or read from an edited file too)
        lags, phi, outside = (frozen(self.lags, np.int64), frozen(self.phi), frozen(self.outside, np.int64))
        check_choice(self.kind, "kind", ("linear", "nonlinear"))
        base = self.name.split(":")[0]
        if base in TESTS and self.kind != TESTS[base][1]:  # linear_passed / nonlinear_passed count it by its kind
            raise ValueError(f"kind of test {self.name!r} is {TESTS[base][1]!r}, got {self.kind!r}")
        if base in TESTS and self.label != _label_of(self.name):  # reports and plots print the label as the test's
            raise ValueError(f"label of test {self.name!r} is {_label_of(self.name)!r}, got {self.label!r}")
        if lags.ndim != 1 or lags.size == 0 or phi.shape != lags.shape:
            raise ValueError(f"lags and phi must be 1-D, one φ per lag, got shapes {lags.shape} and {phi.shape}")
        # NaN at every lag: a 0/0 test as graybox made it before such tests were left out (its files load, failed)
        undone = bool(np.all(np.isnan(phi)))
        if not undone and not np.all(np.isfinite(phi) & (np.abs(phi) <= 1 + 1e-12)):
            raise ValueError("phi must hold correlations, finite and in [-1, 1] (or NaN at every lag: a 0/0 test "
                             "an older graybox kept, failed)")
        if base in TESTS:  # a u-ξ cross-correlation over an autocorrelation's lags 1 … L is no test residual_tests makes
            side = TESTS[base][2]
            top = int(np.max(np.abs(lags)))
            if top < 1 or not np.array_equal(lags, _lags(side, top)):
                span = {"both": "-L … L", "positive": "1 … L", "nonnegative": "0 … L"}[side]
                raise ValueError(f"lags of test {self.name!r} must be τ = {span} (every lag, in order, some L >= 1), "
                                 f"got {_lag_text(lags)}")
        check_real(self.band, "band", low=0, low_open=True)
        check_real(self.limit, "limit", low=0, low_open=True)
        check_real(self.excess_kurtosis, "excess_kurtosis")
        check_real(self.skewness, "skewness")
        check_int(self.permutations, "permutations", low=0)
        if self.permutations and self.limit > 1:  # a limit on |φ| ≤ 1 set by permuted correlations
            raise ValueError(f"limit = {self.limit:g} of a permutation test must be at most 1 (|phi| <= 1)")
        if outside.ndim != 1 or not np.array_equal(outside, lags[np.abs(phi) > self.band]):
            raise ValueError(f"outside must list the lags where |phi| > band ({lags[np.abs(phi) > self.band].tolist()}), "
                             f"got {outside.tolist()}")
        # a tie with a permutation limit passes (_TIE); a file written before kept such a tie as failed, and loads
        if self.passed not in (bool(np.all(np.abs(phi) <= verdict_limit(self.limit, self.permutations))),
                               bool(np.all(np.abs(phi) <= self.limit))):
            raise ValueError(f"passed is {self.passed} but {'every' if not self.passed else 'not every'} |phi| is "
                             f"within limit = {self.limit:g}")
        object.__setattr__(self, "lags", lags)
        object.__setattr__(self, "phi", phi)
        object.__setattr__(self, "outside", outside)

    @property
    def worst_lag(self) -> int:
        """The lag with the largest |φ|."""
        return int(self.lags[int(np.argmax(np.abs(self.phi)))])

    def __repr__(self) -> str:
        verdict = "pass" if self.passed else f"FAIL (max |φ| = {np.max(np.abs(self.phi)):.3f} at τ = {self.worst_lag})"
        return f"CorrelationTest({self.label}: {verdict}; {self.outside.size} of {self.lags.size} lags outside ±{self.band:.3g})"


@dataclass(frozen=True, eq=False)
class ResidualTests(Relocked):
    """The result of :func:`residual_tests`: five correlation tests of one model's residuals.

    Attributes
    ----------
    tests : mapping str -> CorrelationTest
        In the order of ``TESTS``.
    n : int
        Residuals used (samples from the max lag on, summed over records).
    level : float
        Confidence level of the bands (0.95).
    rule : str
        ``"simultaneous"`` or ``"pointwise"`` (see the module docstring).
    model_name : str
        Name of the model tested.
    residuals : tuple of ndarray
        ξ per record, shape (N_r − L,) (samples L … N_r − 1).
    undefined : mapping str -> str
        The tests these data cannot make, keyed as ``tests`` would be, with why: an input held
        constant (its four input tests), one taking two levels equally often (u'² constant: its
        two u² tests), residuals of one magnitude ±c (ξ² constant: φ_(u²)'ξ²), or residuals c·u'
        of such an input (ξu' constant: its φ_ξ(ξu)). They are not in ``tests`` and take no part
        in :attr:`passed`.
    seed : int or None
        The seed of the permutations that set the simultaneous limits (``residual_tests(seed=)``): with the
        same data, level and seed they are the same limits. None where nothing was drawn (the pointwise rule, a
        file of the Bonferroni limits) or where it is unknown (a file of a graybox that did not keep it).
    """

    tests: Mapping[str, CorrelationTest]
    n: int
    level: float
    rule: str
    model_name: str
    residuals: tuple[np.ndarray, ...]
    undefined: Mapping[str, str] = field(default_factory=FrozenMap)
    seed: int | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        check_int(self.n, "n", low=1)
        check_level(self.level)
        check_choice(self.rule, "rule", RULES)
        if self.seed is not None:
            check_seed(self.seed, "seed")
            if not any(getattr(t, "permutations", 0) for t in self.tests.values()):
                raise ValueError(f"seed = {self.seed!r} of tests whose limits no permutation set (the pointwise "
                                 "rule's band, or Bonferroni limits): nothing was drawn, the seed is None")
        for k, t in self.tests.items():
            if not isinstance(t, CorrelationTest) or t.name != k or k.split(":")[0] not in TESTS:
                raise ValueError(f"tests[{k!r}] must be the CorrelationTest named {k!r}, one of {list(TESTS)} "
                                 "(with ':input' for one input's test of several)")
        if not self.tests:  # xi_xi is always made: no test at all would read 'all passed'
            raise ValueError("tests must hold at least one CorrelationTest (residual_tests always makes φ_ξξ)")
        for k, why in self.undefined.items():
            if not isinstance(k, str) or k.split(":")[0] not in INPUT_TESTS or not isinstance(why, str):
                raise ValueError(f"undefined must map an input test's key (one of {list(INPUT_TESTS)}, with ':input' "
                                 f"for one input's of several) to why it was not made, in words; got {k!r}: {why!r}")
            if k in self.tests:
                raise ValueError(f"undefined names {k!r}, a test that was made (it is in tests)")
        residuals = tuple(frozen(e) for e in self.residuals)
        if not residuals or any(e.ndim != 1 or not np.all(np.isfinite(e)) for e in residuals):
            raise ValueError("residuals must hold each record's residuals, 1-D and finite (at least one record)")
        if sum(e.size for e in residuals) != self.n:
            raise ValueError(f"n must be the number of residuals, {sum(e.size for e in residuals)} over "
                             f"{len(residuals)} record(s), got {self.n}")
        # the bands and limits are those of n, level and rule (a hand-built or edited one said 'passed' with a band
        # its n would not give), and the tests of one call share its max_lag
        tops = {k: int(np.max(np.abs(t.lags))) for k, t in self.tests.items()}
        if len(set(tops.values())) > 1:
            raise ValueError(f"lags of the tests must reach one max_lag, as residual_tests makes them; got {tops}")
        from scipy import stats  # slow to import: loaded where used
        band = float(stats.norm.ppf(0.5 + self.level / 2) / np.sqrt(self.n))
        for k, t in self.tests.items():
            check_agrees(t.band, band, f"band of tests[{k!r}]", f"level = {self.level!r} and n = {self.n} (z/√n)")
            if self.rule == "pointwise":
                check_agrees(t.limit, band, f"limit of tests[{k!r}]", "the pointwise rule's band and its level and n")
                if t.permutations:
                    raise ValueError(f"tests[{k!r}] says its limit was set on {t.permutations} permutations, but the "
                                     "pointwise rule's is the band (permutations = 0)")
            elif t.permutations:
                # the permutations' maxima need the inputs, which a result does not keep: their count is checked
                if t.permutations != _permutations(self.level):
                    raise ValueError(f"permutations of tests[{k!r}] is {t.permutations}, but residual_tests sets the "
                                     f"limit at level = {self.level!r} on {_permutations(self.level)}")
            else:  # a file of an older graybox: the Bonferroni limit, its tails corrected by an Edgeworth term
                limit = _simultaneous_limit(self.level, t.lags.size, self.n, t.excess_kurtosis, t.skewness)
                check_agrees(t.limit, limit, f"limit of tests[{k!r}]", f"the simultaneous rule over its {t.lags.size} "
                             f"lags at level = {self.level!r}, n = {self.n}, excess_kurtosis = "
                             f"{t.excess_kurtosis!r} and skewness {t.skewness!r} (Bonferroni, Edgeworth tails)")
        object.__setattr__(self, "tests", FrozenMap(self.tests))  # not the caller's dict
        object.__setattr__(self, "undefined", FrozenMap(self.undefined))
        object.__setattr__(self, "residuals", residuals)

    @property
    def passed(self) -> bool:
        """Every test passed. Each is a test at ``level`` of its own; together a correct model fails
        at least one in up to (number of tests) × (1 − level) of records (25 % for five tests at 95 %;
        see the module docstring for measured rates)."""
        return all(t.passed for t in self.tests.values())

    @property
    def linear_passed(self) -> bool:
        """φ_ξξ and φ_uξ passed."""
        return all(t.passed for t in self.tests.values() if t.kind == "linear")

    @property
    def nonlinear_passed(self) -> bool:
        """The three higher-order tests passed."""
        return all(t.passed for t in self.tests.values() if t.kind == "nonlinear")

    @property
    def failed(self) -> list[str]:
        """Names of the tests that failed."""
        return [k for k, t in self.tests.items() if not t.passed]

    def __getitem__(self, name: str) -> CorrelationTest:
        """The test ``name`` (a key of :attr:`tests`); ``KeyError`` saying why for one left out or unknown."""
        if name in self.tests:
            return self.tests[name]
        if name in self.undefined:
            raise KeyError(f"test {name!r} was not made on these data: {self.undefined[name]}")
        raise KeyError(f"no test {name!r}; the tests made are {list(self.tests)}"
                       + (f", those left out {list(self.undefined)}" if self.undefined else ""))

    def to_frame(self) -> pd.DataFrame:
        """The tests as a table.

        Returns
        -------
        pandas.DataFrame
            One row per test (indexed by its name): ``test`` (its label), ``kind``, ``passed``, ``max |phi|``,
            ``worst lag``, ``limit``, ``band`` (dimensionless correlations) and ``lags outside band``; a test not
            made on these data has ``passed`` None and ``undefined`` (why).
        """
        import pandas as pd

        rows = {
            k: {"test": t.label, "kind": t.kind, "passed": t.passed, "max |phi|": float(np.max(np.abs(t.phi))),
                "worst lag": t.worst_lag, "limit": t.limit, "band": t.band,
                "lags outside band": t.outside.tolist()}
            for k, t in self.tests.items()
        }
        rows.update({k: {"test": k, "passed": None, "undefined": why} for k, why in self.undefined.items()})
        return pd.DataFrame.from_dict(rows, orient="index")

    def __repr__(self) -> str:
        verdict = "all passed" if self.passed else f"failed: {', '.join(self.tests[k].label for k in self.failed)}"
        if self.undefined:
            verdict += f"; {len(self.undefined)} undefined on these data ({', '.join(self.undefined)})"
        drawn = any(t.permutations for t in self.tests.values())
        seed = "" if not drawn else f"; seed {self.seed}" if self.seed is not None else "; seed unknown"
        return (f"ResidualTests({self.model_name or 'model'}: N = {self.n}, {self.rule} {percent_text(self.level)}; "
                f"{verdict}{seed})")


# --------------------------------------------------------------------------------------------
# residuals
# --------------------------------------------------------------------------------------------
def _model_residuals(model: Model | NeuralModel, rec: Record, moving_average: bool) -> tuple[np.ndarray, int]:
    """ξ(k) for k = L … N−1 of one record, and L."""
    if isinstance(model, NeuralModel):
        L = model.max_lag
        if moving_average and model.ne:
            _, e = model.predict_narmax(rec)
            return e[L:].copy(), L
        return (rec.y - model.predict(rec))[L:], L
    model.check_record(rec)  # a discrete-time model holds at the period (and in the units) it was identified at
    ns = model.noise_structure if moving_average else model.noise_structure[:0]
    L = max(model.max_lag, ns.max_lag)
    rec.require_length(L)
    psi = regressor_matrix(model.structure, rec.u, rec.y, start=L, input_names=rec.input_names)  # refuses overflow
    # on u and y times powers of two where a column nears the float range's ends (exact, as the estimators fit and
    # Model.predict predicts): y(k-1)² of y ≈ 1e-200 (1e-400, no float) was dropped, the residuals 20 times too large
    (scaled,), exps = binary_scaled([rec], model.structure)
    if exps:
        psi = regressor_matrix(model.structure, scaled.u, scaled.y, start=L, input_names=rec.input_names)
        v = np.ldexp(scaled.y[L:] - psi @ scaled_theta(model.theta, model.structure, exps), exps["y"])
    else:
        v = rec.y[L:] - psi @ model.theta
    if len(ns) == 0:
        return v, L
    c = model.noise_theta
    if all(len(t.factors) == 1 and t.factors[0][2] == 1 for t in ns):
        # linear MA part: ξ(k) + Σ c_l ξ(k−l) = v(k) with ξ = 0 before sample L, a linear filter
        a = np.zeros(ns.max_lag + 1)
        a[0] = 1.0
        for cj, t in zip(c, ns):
            a[t.factors[0][1]] += cj
        if not _ma_invertible(a):
            raise ValueError(f"the model's MA part C(q) = {_ma_text(a)} is not invertible (a root on or outside the "
                             "unit circle): its one-step residuals grow without bound, and say nothing of the model")
        return inverse_ma_filter(v[:, None], a, np.array([0, v.size]))[:, 0], L
    # products of residuals with u, y or each other: the recursion sample by sample
    N = len(rec)
    e = np.zeros(N)
    sig = record_signals(rec) | {"e": e}
    with np.errstate(over="ignore", invalid="ignore"):  # residuals that overflow are refused below, by name
        for k in range(L, N):
            acc = 0.0
            for cj, t in zip(c, ns):
                val = cj
                for s, lag, pw in t.factors:
                    val *= sig[s][k - lag] ** pw
                acc += val
            e[k] = v[k - L] - acc
    if not np.all(np.isfinite(e)):
        raise ValueError(f"the model's one-step residuals overflow (its MA part {', '.join(map(str, ns))} feeds them "
                         "back without damping them): they say nothing of the model")
    return e[L:], L


def one_step_residuals(
    model: Model | NeuralModel,
    data: Record | Sequence[Record] | Dataset,
    *,
    moving_average: bool = True,
) -> list[np.ndarray]:
    """The model's one-step prediction errors ξ on measured data, per record.

    Parameters
    ----------
    model : Model, NeuralModel, or a result that carries one in ``.model``
        A polynomial model (with or without an MA part) or a neural one (an ELSResult,
        NeuralFit, Decision … stands for its model).
    data : Record, sequence of Record, or Dataset
        Measured data (a Dataset stands for its validation record, as in :func:`residual_tests`;
        pass ``data.ident`` for the identification record).
    moving_average : bool
        Include the model's MA part (default; see the module docstring). False: the process
        part's equation error y − ψᵀθ.

    Returns
    -------
    list of ndarray
        ξ(k) for k = L … N_r − 1 of each record, shape (N_r − L,), output units; L is the largest
        lag of the terms used (process and, with ``moving_average``, noise terms).

    Raises
    ------
    ValueError
        With ``moving_average``, an MA part that is not invertible (its residuals grow without bound).
    """
    model = as_model(model, kinds=(Model, NeuralModel), accepted=_ACCEPTED)
    moving_average = check_bool(moving_average, "moving_average")
    return [_model_residuals(model, r, moving_average)[0] for r in records_of(data, "valid")]


# --------------------------------------------------------------------------------------------
# correlations
# --------------------------------------------------------------------------------------------
def _lags(side: str, max_lag: int) -> np.ndarray:
    if side == "both":
        return np.arange(-max_lag, max_lag + 1)
    if side == "positive":
        return np.arange(1, max_lag + 1)
    return np.arange(0, max_lag + 1)


def _lag_text(lags: np.ndarray) -> str:
    """Lags in a message: all of a few, the ends of many."""
    return str(lags.tolist()) if lags.size <= 8 else f"[{lags[0]}, {lags[1]}, …, {lags[-1]}] ({lags.size} lags)"


def _xcorr(a: list[np.ndarray], b: list[np.ndarray], lags: np.ndarray) -> np.ndarray:
    """Σ_r Σ_k a_r(k−τ) b_r(k) / sqrt(Σ a² Σ b²) with a, b mean-removed over all records.

    Products never pair samples of two records.
    """
    ma = np.mean(np.concatenate(a))
    mb = np.mean(np.concatenate(b))
    a = [x - ma for x in a]
    b = [x - mb for x in b]
    den = np.sqrt(sum(float(x @ x) for x in a)) * np.sqrt(sum(float(x @ x) for x in b))
    num = np.zeros(lags.size)
    for x, y in zip(a, b):
        n = x.size
        for i, t in enumerate(lags):
            t = int(t)
            if abs(t) >= n:
                continue
            num[i] += float(x[: n - t] @ y[t:]) if t >= 0 else float(x[-t:] @ y[: n + t])
    if den == 0.0:
        return np.full(lags.size, np.nan)
    return num / den


def residual_tests(
    model: Model | NeuralModel,
    data: Record | Sequence[Record] | Dataset,
    *,
    max_lag: int = 20,
    level: float = 0.95,
    rule: str = "simultaneous",
    moving_average: bool = True,
    seed: int = 0,
) -> ResidualTests:
    """The five correlation tests of Billings & Voon on a model's one-step residuals.

    Parameters
    ----------
    model : Model, NeuralModel, or a result that carries one in ``.model``
        The model to validate (an ELSResult, NeuralFit, Decision … stands for its model).
    data : Record, sequence of Record, or Dataset
        Measured data: a validation record the model has not seen (a Dataset stands for its
        ``valid`` record), or the identification record (``data.ident``). With several records, lagged products never pair samples of two records.
    max_lag : int
        Largest |τ| in samples (default 20).
    level : float
        Confidence level in (0, 1) of the band (0.95: ±1.96/√N).
    rule : {"simultaneous", "pointwise"}
        How a test passes: every lag within a limit at ``level`` for the test as a whole, set by
        shuffling the residuals (default: exact for a correct model whatever the tails of u and ξ), or
        every lag within the pointwise ±1.96/√N band (see the module docstring for why the pointwise rule
        fails correct models).
    moving_average : bool
        Include the model's MA part in the residuals (default; see :func:`one_step_residuals`).
    seed : int
        Seed of the shuffles that set the simultaneous limit (default 0: the same verdict on every call).

    Returns
    -------
    ResidualTests
        Per test: φ at each lag, the band, the lags outside it, pass or fail; ``.passed``,
        ``.linear_passed``, ``.nonlinear_passed``; draw with :func:`graybox.plots.plot_residual_tests`.

    Raises
    ------
    ValueError
        A record shorter than the model's lags plus ``max_lag`` + 2, constant residuals (within
        1e-10 of the largest |y|, round-off: a model that reproduces the data exactly has nothing
        to test), every input constant, a record sampled at another period than the model was identified
        at, an MA part whose residual recursion grows without bound (not invertible), a level above
        0.9999 under the simultaneous rule (more than 9999 shuffles), bad options.

    Notes
    -----
    With several inputs the four input tests are made for each input (keys ``"u_xi:u1"`` …, labels
    with the input's name); the model is adequate when every one of them passes.
    """
    model = as_model(model, kinds=(Model, NeuralModel), accepted=_ACCEPTED)
    max_lag = check_int(max_lag, "max_lag", low=1)
    moving_average = check_bool(moving_average, "moving_average")
    level = check_level(level)
    check_choice(rule, "rule", RULES)
    seed = check_seed(seed)
    recs = records_of(data, "valid")
    names = recs[0].input_names
    xi, us = [], []
    for r in recs:
        e, L = _model_residuals(model, r, bool(moving_average))
        if e.size < max_lag + 2:
            raise ValueError(f"{r.name}: {e.size} residuals (after the model's max lag {L}) are too few for "
                             f"max_lag = {max_lag}")
        xi.append(e)
        us.append(r.inputs[L:])
    n = sum(e.size for e in xi)
    allxi = np.concatenate(xi)
    # "constant" in the output's units: an exact model of data near 2e5 Pa leaves round-off of 1e-11 Pa
    ymax = max(float(np.max(np.abs(r.y))) for r in recs)
    if np.ptp(allxi) <= 1e-10 * ymax:
        raise ValueError("the residuals are constant to round-off: the model reproduces the data exactly, there is "
                         "nothing to test")
    allu = np.concatenate(us)
    # tests these data cannot make: left out and named (a held input, a balanced PRBS), not NaN verdicts
    undefined: dict[str, str] = {}
    std: dict[str, np.ndarray] = {}  # u' of each input that moves, over every record
    for j, nm in enumerate(names):
        tag = "" if len(names) == 1 else f":{nm}"
        if np.ptp(allu[:, j]) == 0.0:
            for key in INPUT_TESTS:
                undefined[key + tag] = f"input {nm!r} is constant on these data"
            continue
        std[nm] = _standardised(allu[:, j], allu[:, j])
        u2 = std[nm] ** 2
        if np.ptp(u2) <= 1e-9 * np.max(u2):  # round-off of ±1: its correlations would be noise
            for key in U2_TESTS:
                undefined[key + tag] = (f"input {nm!r} takes two levels equally often: u'² is constant (for any "
                                        "two-level input these tests repeat φ_uξ)")
    # residuals of one magnitude (±c, an output quantised to two levels about the model): ξ² is constant and
    # φ_(u²)'ξ² is 0/0 (to round-off), for every input
    if _flat(np.abs(allxi), ymax):
        for nm in names:
            undefined.setdefault("u2_xi2" + ("" if len(names) == 1 else f":{nm}"),
                                 "the residuals have one magnitude (ξ = ±c): ξ² is constant")
    # residuals c·u' of a two-level input taken equally often (u' = ±1): ξu' is constant and φ_ξ(ξu) 0/0
    for nm in names:
        key = "xi_xiu" + ("" if len(names) == 1 else f":{nm}")
        if key not in undefined:  # (a held input's tests are, so its u' was made above)
            uj = std[nm]
            if _flat(allxi * uj, ymax * float(np.max(np.abs(uj)))):
                undefined[key] = f"the residuals are c·u' of input {nm!r} (u' = ±1): ξu' is constant"
    if len(undefined) == len(INPUT_TESTS) * len(names):
        raise ValueError(("the input is constant" if len(names) == 1 else "every input is constant")
                         + ": the input correlation tests are undefined")
    if undefined:
        warn(f"residual_tests: {len(undefined)} test(s) undefined on these data, left out: "
             + "; ".join(f"{k} ({why})" for k, why in undefined.items()), UserWarning)
    from scipy import stats  # slow to import: loaded where used
    z = stats.norm.ppf(0.5 + level / 2)
    if rule == "simultaneous" and level > _max_level():
        raise ValueError(f"level = {level!r} is too close to 1 for the simultaneous rule: its limit is set on at most "
                         f"{_MAX_PERMUTATIONS} permutations of the residuals, which hold no test beyond level = "
                         f"{_max_level():.6g} (rule='pointwise' takes it)")
    band = float(z / np.sqrt(n))
    # φ is the same for ξ in any units: in units of its largest magnitude, its squares and products neither
    # underflow nor overflow (y in units of 1e-100 made Σξ²·Σξ² 0, φ_ξξ NaN)
    xmax = float(np.max(np.abs(allxi)))
    xs = [e / xmax for e in xi]
    # with several inputs every input test is made for each input (keys "u_xi:u1", …); the tests to make as
    # (key, test, input column; −1 for φ_ξξ), and u in units of its own spread for each input they use (u² of
    # 1e3 rpm would otherwise lose digits to the mean removal)
    keys = [(key + ("" if len(names) == 1 or key == "xi_xi" else f":{nm}"), key, -1 if key == "xi_xi" else j)
            for key in TESTS for j, nm in (enumerate(names[:1]) if key == "xi_xi" else enumerate(names))]
    keys = [(k, key, j) for k, key, j in keys if k not in undefined]
    uc = {j: [_standardised(u[:, j], allu[:, j]) for u in us] for j in {j for _, _, j in keys if j >= 0}}
    limits = _permutation_limits(xs, uc, keys, max_lag, level, seed) if rule == "simultaneous" else {}
    permutations = _permutations(level) if rule == "simultaneous" else 0
    out = {}
    for k, key, j in keys:
        _, kind, side = TESTS[key]
        lags = _lags(side, max_lag)
        if key == "xi_xi":
            a, b, shift = xs, xs, 0
        elif key == "u_xi":
            a, b, shift = uc[j], xs, 0
        elif key == "xi_xiu":
            a, b, shift = [e * u for e, u in zip(xs, uc[j])], xs, 1
        elif key == "u2_xi":
            a, b, shift = [u**2 for u in uc[j]], xs, 0
        else:
            a, b, shift = [u**2 for u in uc[j]], [e**2 for e in xs], 0
        phi = _xcorr(a, b, lags + shift)
        kurt, skew = _product_shape(a, b)
        limit = limits.get(k, band)
        outside = lags[np.abs(phi) > band]
        out[k] = CorrelationTest(k, _label_of(k), kind, _ro(lags), _ro(phi), band, limit, _ro(outside),
                                 bool(np.all(np.abs(phi) <= verdict_limit(limit, permutations))), kurt, skew,
                                 permutations)
    return ResidualTests(FrozenMap(out), n, level, rule, getattr(model, "name", ""),
                         tuple(_ro(e) for e in xi), FrozenMap(undefined), seed if permutations else None)

#: |φ| within this of a limit set on permutations ties it: no exceedance. The limit is a shuffled order's max |φ|
#: (by FFT), the record's own is summed directly, and an order whose φ equals the record's in exact arithmetic (its
#: own order drawn again, or reversed: three residuals have six orders) came out an ulp below it, failing a correct
#: model by round-off (φ_ξξ of 39 in 300 such records). Far below any φ's sampling error (1/√N).
_TIE = 1e-12


def verdict_limit(limit: float, permutations: int) -> float:
    """The largest |φ| a test with this ``limit`` passes: the limit, and a tie with one set on ``permutations``
    (``_TIE``)."""
    return limit + _TIE if permutations else limit


#: Exceedances of the permutation limit at ``level``: (B + 1)(1 − level) permuted maxima lie at or above it, 10
#: where the cap allows (B = 199 at 95 %, 999 at 99 %), at least 1 (an exact test needs one), B at most 9999.
_EXCEED, _MAX_PERMUTATIONS = 10, 9999


def _permutations(level: float) -> int:
    """B, the permutations the simultaneous limit at ``level`` is set on (see ``_EXCEED``)."""
    return int(min(max(np.ceil(_EXCEED / (1 - level) - 1e-9) - 1, 99), _MAX_PERMUTATIONS))


def _max_level() -> float:
    """The largest level whose permutation limit _MAX_PERMUTATIONS permutations can set (one maximum above it)."""
    return 1 - 1 / (_MAX_PERMUTATIONS + 1)


def _permutation_limits(xs: list[np.ndarray], uc: dict[int, list[np.ndarray]], keys: list[tuple[str, str, int]],
                        max_lag: int, level: float, seed: int) -> dict[str, float]:
    """Per test, the limit on max_τ |φ(τ)| that a level-``level`` permutation test sets: the residuals permuted
    within each record B times (``_permutations``), every test's φ recomputed on each permutation (as ``_xcorr``:
    means removed over all records, products within records), and the limit the order statistic of the B maxima
    above which (B + 1)(1 − level) − 1 of them lie. Exact under the null (ξ independent and identically
    distributed within each record, independent of u), whatever the tails of u and ξ and the correlation between
    lags (a held input), as a Bonferroni limit is not.

    ``keys`` holds (key, test, input column; −1 for φ_ξξ) of the tests to make, ``uc`` each input column's u' per
    record."""
    from scipy import fft  # slow to import: loaded where used

    B = _permutations(level)
    rng = np.random.default_rng(seed)
    sizes = [x.size for x in xs]
    gap = max_lag + 2  # zeros between records: no lag up to max_lag + 1 (φ_ξ(ξu)'s shift) pairs two records
    starts = np.cumsum([0] + [n + gap for n in sizes[:-1]]).astype(int)
    width = int(starts[-1] + sizes[-1])
    where = np.concatenate([s0 + np.arange(n) for s0, n in zip(starts, sizes)])  # the samples' places in a row
    nfft = fft.next_fast_len(width + max_lag + 2, real=True)

    def laid(parts: list[np.ndarray]) -> np.ndarray:
        out = np.zeros(width)
        out[where] = np.concatenate(parts)
        return out

    def centred(x: np.ndarray) -> np.ndarray:  # means over the samples only, the gaps kept zero
        return np.where(np.isin(np.arange(width), where), x - np.mean(x[where]), 0.0)

    xi = laid(xs)
    # permuting ξ moves neither its mean nor its norm, nor ξ²'s: only φ_ξ(ξu)'s product ξu' changes its own
    xic, xi2c = centred(xi), centred(xi**2)
    norm = {"xi": np.sqrt(xic @ xic), "xi2": np.sqrt(xi2c @ xi2c)}
    fixed = {}  # per input: u', and the conjugate transforms of u' and u'² over their norms where a test uses them
    made = {(t, j) for _, t, j in keys}
    for j in {j for _, _, j in keys if j >= 0}:
        u, u2 = centred(laid(uc[j])), centred(laid([x**2 for x in uc[j]]))
        fixed[j] = (laid(uc[j]), np.conj(fft.rfft(u, nfft)) / np.sqrt(u @ u) if ("u_xi", j) in made else None,
                    # (u'² of a balanced two-level input is constant: its tests are not made, nor divided by 0)
                    np.conj(fft.rfft(u2, nfft)) / np.sqrt(u2 @ u2) if {("u2_xi", j), ("u2_xi2", j)} & made else None)
    maxima = {k: np.empty(B) for k, _, _ in keys}
    chunk = max(1, 2**20 // nfft)
    # the lags of φ_ξξ, φ_ξ(ξu) (shifted) and the input tests as places in a cross-correlation (τ < 0 at its end)
    pos, pos1, both = _lags("positive", max_lag), _lags("nonnegative", max_lag) + 1, _lags("both", max_lag) % nfft
    for lo in range(0, B, chunk):
        m = min(chunk, B - lo)
        idx = np.empty((m, where.size), dtype=np.intp)  # each row a permutation within each record
        for s0, n, c0 in zip(starts, sizes, np.cumsum([0] + sizes[:-1])):
            idx[:, c0:c0 + n] = rng.permuted(np.broadcast_to(where[c0:c0 + n], (m, n)), axis=1)
        # Σ_k a(k−τ) b(k) at every τ: the cross-correlation of the zero-padded rows, by FFT
        f_xi = fft.rfft(_placed(xic, idx, where, width), nfft, axis=1)
        f_xi2 = None
        for k, t, j in keys:
            if t in ("u_xi", "u2_xi"):
                phi = fft.irfft(fixed[j][1 if t == "u_xi" else 2] * f_xi, nfft, axis=1)[:, both] / norm["xi"]
            elif t == "u2_xi2":
                if f_xi2 is None:
                    f_xi2 = fft.rfft(_placed(xi2c, idx, where, width), nfft, axis=1)
                phi = fft.irfft(fixed[j][2] * f_xi2, nfft, axis=1)[:, both] / norm["xi2"]
            else:
                if t == "xi_xi":
                    c = fft.irfft(np.abs(f_xi) ** 2, nfft, axis=1)[:, pos] / norm["xi"] ** 2
                else:
                    a = xi[idx] * fixed[j][0][where]
                    a = _placed(a - np.mean(a, axis=1, keepdims=True), slice(None), where, width)
                    na = np.sqrt(np.einsum("ij,ij->i", a, a))[:, None]
                    c = fft.irfft(np.conj(fft.rfft(a, nfft, axis=1)) * f_xi, nfft, axis=1)[:, pos1]
                    c = np.divide(c, na * norm["xi"], out=np.zeros_like(c), where=na > 0)
                phi = c
            maxima[k][lo:lo + m] = np.max(np.abs(phi), axis=1)
    rank = B - int(np.floor((B + 1) * (1 - level) + 1e-9))  # (B + 1)(1 − level) − 1 maxima lie above it
    # (|φ| <= 1: FFT round-off of a degenerate record's could exceed it by an ulp)
    return {k: min(float(np.sort(v)[rank]), 1.0) for k, v in maxima.items()}


def _placed(x: np.ndarray, idx: np.ndarray | slice, where: np.ndarray, width: int) -> np.ndarray:
    """Rows x[idx] laid at the places ``where`` of rows of ``width`` (zero in the gaps between records)."""
    if where.size == width:  # one record: no gaps
        return x[idx]
    out = np.zeros((*np.shape(x[idx])[:-1], width))
    out[..., where] = x[idx]
    return out


def _product_shape(a: list[np.ndarray], b: list[np.ndarray]) -> tuple[float, float]:
    """N times the excess kurtosis, √N times the skewness, of the normalised correlation of independent a and b:
    (κ_a − 3)(κ_b − 3) − 6 and γ_a γ_b from the two sequences' own (means removed over every record, as in the
    correlation). Not κ_a κ_b − 3, the unnormalised sum's: dividing by ‖a‖‖b‖ takes out the spread of Σa² and Σb²
    (a Gaussian b over its norm is a point of the sphere, whatever a), and an impulse input's κ_u ≈ N widened the
    limit of a test whose φ is a normal residual. The −6 is the normalisation's own: with b Gaussian, b / ‖b‖ is
    uniform on the sphere and φ is exactly (2 Beta((N − 1)/2, (N − 1)/2) − 1), of excess kurtosis −6 / (N + 2)
    whatever a (review59h: a Monte Carlo of N = 200 gave about −3, +1.3 and −7 ± 1.6 for normal × normal, Laplace
    × Laplace and normal × Laplace, against −6, 3 and −6 with it and 0, 9 and 0 without)."""
    shape = []
    for x in (a, b):
        c = np.concatenate(x)
        c = c - np.mean(c)
        c = c / np.max(np.abs(c))  # moments of order 4 of ξ² in units of its largest: no overflow, no underflow
        m2 = float(np.mean(c**2))
        shape.append((float(np.mean(c**4)) / m2**2, float(np.mean(c**3)) / m2**1.5))
    (ka, ga), (kb, gb) = shape
    return (ka - 3) * (kb - 3) - 6, ga * gb


def _simultaneous_limit(level: float, n_lags: int, n: int, excess_kurtosis: float, skewness: float) -> float:
    """The simultaneous limit of a file of an older graybox (``permutations = 0``), which its tests are held to.

    The half-width c/√n that each of ``n_lags`` lags exceeds with probability (1 − level)/n_lags: c from the
    Edgeworth expansion of the two-sided tail of Z = √n φ of excess kurtosis κ/n and skewness γ/√n,

        P(|Z| > c) = 2(1 − Φ(c)) + 2φ(c) [κ He₃(c) / (24 n) + γ² He₅(c) / (72 n)],

    its largest root, never below the normal (Bonferroni) quantile and at most √n (|φ| ≤ 1: a limit of 1 rejects
    nothing, which is what the expansion says of a few products this heavy-tailed)."""
    from scipy import optimize, special  # slow to import: loaded where used

    alpha = (1 - level) / n_lags
    z0 = float(-special.ndtri(alpha / 2))
    top = float(np.sqrt(n))

    def excess(c: np.ndarray | float) -> np.ndarray | float:
        # (scipy.special, not scipy.stats.norm: its checks made this 20 times slower, and it runs per test)
        c2 = np.multiply(c, c)
        he3, he5 = c * (c2 - 3), c * (c2 * (c2 - 10) + 15)
        pdf = np.exp(-c2 / 2) / np.sqrt(2 * np.pi)
        return (special.erfc(c / np.sqrt(2)) + 2 * pdf * (excess_kurtosis * he3 / (24 * n)
                                                          + skewness**2 * he5 / (72 * n)) - alpha)

    if z0 >= top:
        return z0 / top
    if excess(top) >= 0:
        return 1.0
    # beyond c = 3.33 (He₆'s largest root) both terms fall with c, the tail is monotone there; below, a grid finds
    # the largest c at which the tail still exceeds alpha
    knee = min(max(z0, 3.33), top)
    grid = np.linspace(z0, knee, 64)
    ex = excess(grid)
    if excess(knee) >= 0:
        lo, hi = knee, top
    elif np.any(ex >= 0):
        i = int(np.flatnonzero(ex >= 0)[-1])
        lo, hi = float(grid[i]), float(grid[i + 1])
    else:
        return z0 / top
    return float(optimize.brentq(excess, lo, hi, xtol=1e-12, rtol=1e-14)) / top


def _standardised(x: np.ndarray, col: np.ndarray) -> np.ndarray:
    """(x − mean(col)) / std(col) for u in any units: the deviations taken in units of the largest before
    squaring (std of u ~ 1e160 overflowed to inf, of u ~ 1e-300 underflowed to 0); the mean of u itself, lest an
    offset lose digits (a balanced two-level input about 1e5 must stay u'² = 1 to round-off)."""
    m = float(np.mean(col))
    if not np.isfinite(m):  # Σu overflowed (u near the largest float)
        a = float(np.max(np.abs(col)))
        m = float(np.mean(col / a)) * a
    s = float(np.max(np.abs(col - m)))
    return ((x - m) / s) / float(np.std((col - m) / s))


def _flat(x: np.ndarray, scale: float) -> bool:
    """x is constant to round-off: of itself, or of the output (residuals carry round-off of y's size, 1e-10 of
    it as for constant residuals, whatever their own size) about a level clear of that round-off (x = ±c, c·u'²
    with c beyond it: residuals small beside y that come near 0 are not of one magnitude, they are tested)."""
    tol = 1e-10 * scale
    ax = np.abs(x)
    return bool(np.ptp(x) <= 1e-9 * float(np.max(ax)) or (np.ptp(x) <= tol and float(np.min(ax)) > tol))


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a
