"""Confidence band of a model's free run from its parameters' covariance (MATLAB's ``simsd``).

The band answers "how far could the model's simulated output be from this one, given how well the
record determined θ?": the free run ŷ(k; θ) is a nonlinear function of θ through the output
feedback, so the band is taken either to first order through the forward sensitivities ∂ŷ(k)/∂θ
(the SE estimators' own Jacobian) or from free runs of θ drawn around θ̂. It is not a prediction
interval for a new measurement: the measurement noise and the structure's own error are not in it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core._gram import require_memory
from ..core._records import check_units, said_units
from ..core._simulation import simulate_many
from ..core._simulation_kernels import encode, free_run_sensitivity_blocks, input_products, record_inputs
from ..core._reprs import share_text
from ..core._terms import check_input_names
from ..core._validation import (Relocked, check_count, check_band_finite, check_band_values, check_choice, check_fields,
                                check_level, check_real, check_seed, frozen, warn)
from ..models._coerce import as_record
from ._uncertainty import (BAND_METHODS, MIN_DRAWS, ParameterUncertainty, UncertaintyWarning, check_band_draws,
                           theta_draws)

if TYPE_CHECKING:  # pandas takes ~0.4 s to import: loaded where a table is made
    import pandas as pd

__all__ = ["SimulationBand", "simulation_band"]


@dataclass(frozen=True, eq=False)
class SimulationBand(Relocked):
    """Confidence band of a model's free run over one record.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time, s (sample index × the record's period).
    y : ndarray, shape (N,)
        The record's measured output, output units.
    yhat : ndarray, shape (N,)
        The estimate's free run from the record's first max-lag outputs (those samples are the
        record's, with no spread).
    low, high : ndarray, shape (N,)
        The band at :attr:`level`.
    std : ndarray, shape (N,)
        Standard deviation of ŷ(k) (delta method, or of the Monte Carlo runs' deviations from the estimate's,
        each brought back to the normal draw it came from: the multivariate t's own has none at dof <= 2).
    level : float
    method : str
        ``"delta"`` or ``"monte-carlo"``.
    n_samples : int
        Monte Carlo draws (0 for the delta method).
    diverged : float
        Fraction of the Monte Carlo draws whose free run diverged on the record (left out of the
        band, and said by an :class:`UncertaintyWarning`); 0 for the delta method.
    model_name, record_name : str
    units : tuple of str
        The (input, output) units: the record's, the model's where the record names none. Inputs in units of their
        own give one unit per input, of :attr:`input_names`.
    input_names : tuple of str, optional
        The record's inputs, which per-input units are of (:func:`simulation_band` gives them; None: not known, as
        in a file written before they were kept, and then per-input units are not counted).
    """

    t: np.ndarray
    y: np.ndarray
    yhat: np.ndarray
    low: np.ndarray
    high: np.ndarray
    std: np.ndarray
    level: float
    method: str
    n_samples: int
    diverged: float
    model_name: str = ""
    record_name: str = ""
    units: tuple[str | tuple[str, ...], str] = ("", "")
    input_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        N = np.shape(self.t)[0]
        for f in ("t", "y", "yhat", "low", "high", "std"):
            a = frozen(getattr(self, f))
            if a.shape != (N,):
                raise ValueError(f"{f} must have shape ({N},), got {a.shape}")
            object.__setattr__(self, f, a)
        if self.input_names is not None:
            object.__setattr__(self, "input_names", check_input_names(self.input_names, what="input_names"))
        m = None if self.input_names is None else len(self.input_names)
        object.__setattr__(self, "units", check_units(self.units, "SimulationBand", m))  # ("rpm", 3) is no unit
        # a value read from a hand-edited file is held to what the band can be
        check_level(self.level)
        check_real(self.diverged, "diverged", low=0, high=1)
        check_band_draws(self.method, self.n_samples, self.diverged, "diverged")
        if self.method == "monte-carlo" and round((1 - self.diverged) * self.n_samples) < 2:
            # simulation_band refuses a band of fewer than two bounded runs: one that says so is no band
            raise ValueError(f"diverged = {self.diverged:g} of {self.n_samples} draws leaves "
                             f"{round((1 - self.diverged) * self.n_samples)} bounded run(s): a Monte Carlo band needs "
                             "at least two")
        # the samples' times, the record, the estimate's run (refused where it diverges) and the band of at least
        # two bounded runs: all numbers, at one sample or more
        if N == 0:
            raise ValueError("a simulation band needs at least one sample, got none")
        if not (np.all(np.isfinite(self.t)) and np.all(np.diff(self.t) > 0)):
            raise ValueError("t must increase strictly through finite times (s), one per sample")
        check_band_finite(self, ("y", "yhat", "low", "high", "std"))
        check_band_values(self.std, self.low, self.high, "std", "low", "high")

    @property
    def coverage(self) -> float:
        """Fraction of the measured samples after the initial ones that lie inside the band.

        Not a test of the band (it is a band of the model's output, not of a measurement): a
        coverage far below :attr:`level` says the record's error is mostly the noise's or the
        structure's, not the parameters' uncertainty. Counted over the samples where the band has
        a width (std > 0; the initial samples have none); NaN where it has none at all (every
        parameter fixed, e.g. by constraints): a band of zero width covers nothing to speak of."""
        k = self.std > 0
        if not k.any():
            return float("nan")
        return float(np.mean((self.y[k] >= self.low[k]) & (self.y[k] <= self.high[k])))

    def to_frame(self) -> pd.DataFrame:
        """The band as a table.

        Returns
        -------
        pandas.DataFrame
            One row per sample (index ``t``, s): ``y`` (measured), ``yhat`` (the free run), ``low``, ``high`` and
            ``std``, output units.
        """
        import pandas as pd

        return pd.DataFrame({"y": self.y, "yhat": self.yhat, "low": self.low, "high": self.high, "std": self.std},
                            index=pd.Index(self.t, name="t"))

    def __repr__(self) -> str:
        return (f"SimulationBand({self.model_name or 'model'} on {self.record_name or 'record'}: {self.t.size} samples, "
                f"{self.method}, level={self.level:g}, max ±{np.max((self.high - self.low) / 2):.4g})")


def simulation_band(
    uncertainty: ParameterUncertainty,
    record: object,
    *,
    method: str = "delta",
    n_samples: int = 1000,
    seed: int = 0,
) -> SimulationBand:
    """Confidence band of the model's free run over a record, from its parameters' covariance.

    Parameters
    ----------
    uncertainty : ParameterUncertainty
        From :func:`ls_uncertainty`, :func:`cls_uncertainty`, :func:`pe_uncertainty` or
        :func:`se_uncertainty`; its model is run.
    record : Record or Dataset
        Inputs (by name, any units) and the first max-lag outputs the free run starts from,
        shape (N,); a Dataset stands for its validation record.
    method : {"delta", "monte-carlo"}
        ``"delta"``: first order, ŷ(k) ± t·std with std² = gₖᵀ cov gₖ, gₖ = ∂ŷ(k)/∂θ by the forward
        sensitivity recursion (streamed in blocks: memory does not grow with the record), t the
        parameters' Student's quantile (:attr:`ParameterUncertainty.quantile`). ``"monte-carlo"``:
        θ drawn from the multivariate t around θ̂ with scale ``cov`` and the same degrees of
        freedom, each run freely, the band from the runs' quantiles at each sample (honest where
        the free run is far from linear in θ, e.g. near a stability limit).
    n_samples : int
        Monte Carlo draws (at least 10; checked for either method).
    seed : int
        Seed of the Monte Carlo draws.

    Returns
    -------
    SimulationBand
        Draw it with :func:`graybox.plots.plot_simulation_band`.

    Raises
    ------
    TypeError
        ``uncertainty`` is not a :class:`ParameterUncertainty`; ``record`` is not a Record or Dataset.
    ValueError
        The estimate's own free run diverges on the record (there is nothing to put a band
        around); fewer than two Monte Carlo runs stay bounded; a record not longer than the lags; an
        ``n_samples`` whose runs (3 × N floats each) this machine's memory could never hold.
    MemoryError
        The Monte Carlo runs (about 3 × 8 × ``n_samples`` × N bytes) would not fit in the memory available,
        naming the bytes; nothing is allocated.

    Warns
    -----
    UncertaintyWarning
        Some Monte Carlo runs diverged: the band is of the bounded ones (their fraction is
        :attr:`SimulationBand.diverged`).
    """
    if not isinstance(uncertainty, ParameterUncertainty):
        raise TypeError(f"uncertainty must be a ParameterUncertainty (from ls_uncertainty, cls_uncertainty, "
                        f"pe_uncertainty or se_uncertainty), got {type(uncertainty).__name__}")
    rec = as_record(record, "valid", "record")
    check_choice(method, "method", BAND_METHODS)
    n_samples = check_count(n_samples, "n_samples", low=MIN_DRAWS)
    seed = check_seed(seed)
    m = uncertainty.model
    st, th = m.structure, m.theta
    L = st.max_lag
    rec.require_length(L)
    if method == "monte-carlo":  # the runs, their bounded copy and the quantiles' working copy: 3 × N floats a draw
        check_count(n_samples, "n_samples", each=((3, "copies"), (len(rec), "samples")))
    yhat = m.simulate(rec, on_diverge="nan")  # refuses a record at another period or in other units
    # the band is in the model's units where the record names none (where it names one, they agree)
    units = said_units([rec, m])
    if not np.all(np.isfinite(yhat)):
        k = int(np.flatnonzero(~np.isfinite(yhat))[0])
        raise ValueError(f"simulation_band: the estimate's free run diverges on {rec.name} at sample {k}; there is no "
                         "run to put a band around")
    N = len(rec)
    if method == "delta":
        code = encode(st)
        U = input_products(code.fptr, code.fsig, code.flag, code.fpow, record_inputs(rec, code.input_names), L)
        var = np.zeros(N)
        for k0, k1, _, S in free_run_sensitivity_blocks(code, th, U, rec.y[:L], L):
            var[k0:k1] = uncertainty.contract(S)
        std = np.sqrt(var)
        h = uncertainty.quantile * std  # Student's t, as the parameters' intervals: σ² is estimated
        return SimulationBand(rec.t, rec.y, yhat, yhat - h, yhat + h, std, uncertainty.level, "delta", 0, 0.0,
                              m.name, rec.name, units, rec.input_names)
    # the runs (n_samples × N), the bounded ones' copy and the quantiles' and spread's working copies: refused
    # before allocation where they would not fit (a long record's band by draws), as the long-record paths refuse
    require_memory(3 * 8 * n_samples * N, f"simulation_band's {n_samples} Monte Carlo free runs of {N} samples",
                   hint="use fewer n_samples, or method='delta' (streamed: its memory does not grow with the draws)")
    rng = np.random.default_rng(seed)
    thetas, w = theta_draws(th, uncertainty.cov, n_samples, rng, dof=uncertainty.dof, factor=uncertainty.cov_factor,
                            weights=True)
    # the estimate's run first, by the same kernel: a draw equal to θ̂ then deviates by exactly 0
    Y = simulate_many(st, np.vstack([th, thetas]), rec)
    own = np.where(np.isfinite(Y[0]), Y[0], yhat)
    Y = Y[1:]
    ok = np.all(np.isfinite(Y), axis=1)
    diverged = 1.0 - float(ok.mean())
    if ok.sum() < 2:
        raise ValueError(f"simulation_band: {n_samples - int(ok.sum())} of the {n_samples} Monte Carlo runs diverged on "
                         f"{rec.name}: the parameters' uncertainty reaches unstable models along this record; use "
                         "method='delta' for the first-order band, or a longer identification record")
    if diverged > 0:
        warn(f"simulation_band: {share_text(diverged)} of the Monte Carlo runs diverged on {rec.name} "
             f"({n_samples - int(ok.sum())} of {n_samples}) and are left out of the "
             "band, which is therefore narrower than the parameters' uncertainty (SimulationBand.diverged)",
             UncertaintyWarning)
    a = (1 - uncertainty.level) / 2
    low, high = np.quantile(Y[ok], [a, 1 - a], axis=0)
    # spread about the estimate's run: runs that agree give exactly 0, not the round-off of a mean at 2e5 Pa; each
    # deviation times its draw's weight, the normal draw's (the multivariate t has no variance at dof <= 2)
    std = (w[ok, None] * (Y[ok] - own)).std(axis=0)
    return SimulationBand(rec.t, rec.y, yhat, low, high, std, uncertainty.level, "monte-carlo",
                          n_samples, diverged, m.name, rec.name, units, rec.input_names)
