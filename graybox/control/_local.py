"""Local linear models of a polynomial NARX model at its operating points, and along the static curve.

At a constant input ū the model reaches an equilibrium ȳ (the definition J_SF uses:
:func:`graybox.static._analysis.reached_equilibria`). Around it, in deviation variables
Δy = y − ȳ, Δu_i = u_i − ū_i, the model is to first order

    A(q⁻¹) Δy(k) = Σ_i B_i(q⁻¹) Δu_i(k),   A = 1 − Σ_l a_l q⁻ˡ,   B_i = Σ_l b_il q⁻ˡ,

with a_l = ∂F/∂y(k−l) and b_il = ∂F/∂u_i(k−l) of the one-step map F at the equilibrium. They are
exact, read from the term structure (:mod:`graybox.static._linearisation`, the package's one
derivative map): a factor s(k−l)^p of a term θ ∏ s^P contributes
θ p x̄_s^(P_s − 1) ∏_(s' ≠ s) x̄_s'^P_s' (at steady state every lag of a signal has the same value).
Then

- the poles are the roots of z^L − a_1 z^(L−1) − … − a_L (L the largest output lag), the
  polynomial the Schur–Cohn stability test works on;
- the DC gain Σ_l b_il / (1 − Σ_l a_l) is the static gain ∂ȳ/∂ū_i (implicit differentiation of the
  static equation gives the same quotient);
- the dominant time constant is −Ts / ln|p| of the pole p of largest modulus, its damping that of
  the continuous pole s = ln(p)/Ts, ζ = −Re s / |s|.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from typing import Any, ClassVar, Sequence

import numpy as np

from ..core._records import (Dataset, Record, StaticPoints, StaticRangeWarning, as_records, check_period,
                              check_same_units, check_units, frame_inputs, labelled_point, outside_range,
                              rounded_levels, static_point_inputs)
from ..core._terms import Structure, check_input_names, require_inputs, transient_source
from ..core._transient import _tau_of, refuse_transient_levels, steady_levels
from ..core._reprs import exact_text, listed
from ..core._validation import (Relocked, check_count, check_band_finite, check_band_values, check_choice, check_fields,
                                check_int, check_per_point, check_real, check_seed, frozen, real_array, warn)
from ..models._coerce import as_model
from ..models._model import Model
from ..static._analysis import (CONTINUUM_WHY, NO_EQUILIBRIUM_WHY, REACHED, Equilibrium, Reached, continuum,
                                equilibria_at_levels, multiple_root, reached_equilibria, schur_stable, several_stable,
                                verdict_radius)
from ..static._linearisation import characteristic_roots, local_coefficients
from ..static._surface_analysis import _folded, reached_surface
from ..core._simulation_kernels import kernel_array
from ..static._equilibrium_kernels import unit_pole

__all__ = ["LocalModel", "OperatingCurve", "local_model", "operating_curve", "jacobian_rows", "check_polynomial",
           "require_control", "local_statespace", "local_transfer_function", "system_name", "CONTROL_EXTRA",
           "input_levels", "transient_sources"]

#: The status of a point where the model has several stable equilibria and no ``y0`` picks one: ū sets no ȳ there.
SEVERAL_STABLE = "several stable equilibria"
#: Every status a local model can have: the statuses of the equilibrium reached, and that one.
LOCAL_STATUS = (*Reached.FULL_STATUS, SEVERAL_STABLE)

#: Settling band of :attr:`LocalModel.settling_time`: the step response stays within this fraction
#: of its final value (dimensionless).
SETTLING_BAND = 0.02
#: Longest settling time (samples); a slower equilibrium gets inf.
MAX_SETTLING_SAMPLES = 10_000_000
#: Longest step response run to find it (samples, in blocks: memory does not grow with it): a response that
#: settles near the limit is confirmed over a window about three times as long.
SETTLING_WINDOW_SAMPLES = 4 * MAX_SETTLING_SAMPLES


def _step_error(num: np.ndarray, den: np.ndarray, g: float, band: float, n: int, tail: int
                ) -> tuple[int, float, float, float]:
    """Over a unit step response of n samples (the filter num/den from rest, run in blocks): the number of
    samples after which it stays within ``band`` of g (the last sample outside it, plus one), the largest error
    |s − g| over the first and over the second half of the last ``tail`` samples, and over all.

    The error s − g is run itself, as the response to the input stepping off from its steady state (at 1): the
    response run to its final value and compared with g settles on the recursion's round-off, eps / (1 − Σa) of g,
    and a band under a thousand times that never settled; the error's own recursion decays to 0."""
    block = 1 << 20
    from scipy.signal import lfilter, lfilter_zi  # slow to import: loaded where used
    zi = -lfilter_zi(num, den)  # s(k) − g = −(the response to 1 for k < 0, off from k = 0)
    last, early, late, peak = 0, 0.0, 0.0, 0.0
    mid = n - tail // 2
    for k0 in range(0, n, block):
        k1 = min(n, k0 + block)
        e, zi = lfilter(num, den, np.zeros(k1 - k0), zi=zi)
        err = np.abs(e)
        out = np.flatnonzero(err > band * abs(g))
        if out.size:
            last = k0 + int(out[-1]) + 1
        peak = max(peak, float(err.max()))
        for lo, hi, which in ((n - tail, mid, 0), (mid, n, 1)):
            a, b = max(k0, lo), min(k1, hi)
            if a < b:
                v = float(err[a - k0:b - k0].max())
                early, late = (max(early, v), late) if which == 0 else (early, max(late, v))
    return last, early, late, peak


def check_polynomial(model: object, what: str) -> Model:
    """``model`` if it is a polynomial :class:`Model`; a clear ``TypeError`` otherwise (a neural model included)."""
    try:  # a Model, or a result that carries one (ELSResult, CLSResult, Decision, …): the one coercion
        return as_model(model, "model")  # type: ignore[return-value]
    except TypeError as exc:
        said = str(exc)
    carried = getattr(model, "model", None)
    kind = type(carried if carried is not None and not callable(carried) else model).__name__
    hint = (" A NeuralModel's equilibria and their stability are given by its equilibria() method; its local "
            "linear model is not built here." if kind == "NeuralModel" else "")
    # a set of models (a ParetoSet) is told how to pick one, as everywhere else a model is meant
    many = said[said.rfind("; a ", 0, said.index("holds many models")):] if "holds many models" in said else ""
    raise TypeError(f"{what} needs a polynomial NARX Model, got {kind}{many}.{hint}")


# -- exact partial derivatives from the term structure (graybox.static._linearisation) -----------
def jacobian_rows(structure: Structure, inputs: tuple[str, ...], thetas: np.ndarray, ybar: np.ndarray,
                  ubar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """a_l and b_il at many steady states, from the term structure (no finite differences).

    Parameters
    ----------
    structure : Structure
        Process terms.
    inputs : tuple of str
        The inputs, in the column order of ``ubar``.
    thetas : ndarray, shape (K, n_terms)
        One parameter vector per steady state.
    ybar : ndarray, shape (K,)
        Output levels.
    ubar : ndarray, shape (K, m)
        Input levels.

    Returns
    -------
    a : ndarray, shape (K, L_y)
        ∂F/∂y(k−l), l = 1 … L_y (dimensionless).
    b : ndarray, shape (K, m, L_u)
        ∂F/∂u_i(k−l) (output units per unit of input i; L_u the largest input lag over the inputs).
    """
    return local_coefficients(structure, tuple(inputs), thetas, ybar, ubar)  # type: ignore[return-value]


def _unit_pole(a: np.ndarray) -> bool:
    """Whether z = 1 is a pole of z^L − a_1 z^(L−1) − … − a_L to rounding (a fold's: 1 − Σ a_l = −∂F/∂ȳ = 0): the
    rule the one stability test applies (:func:`graybox.static._equilibrium_kernels.unit_pole`), so that the local
    model and the static analysis never disagree on a stable equilibrium."""
    return bool(unit_pole(kernel_array(a)))


#: Relative rounding of pole moduli from the eigensolver: moduli within it of one another are one modulus, and within
#: it of 1 on the unit circle (z⁵ + 1's roots come out 1 − 6e-16 … 1 + 4e-16).
MODULUS_ROUNDING = 1e-12


def _dominant(poles: np.ndarray, Ts: float, unit: bool = False, stable: bool = True) -> tuple[complex, float, float]:
    """(dominant pole, its time constant (s), its damping) of one set of poles (``unit``: one is z = 1 to rounding,
    :func:`_unit_pole`; the slowest mode then never decays; ``stable``: the one stability test's verdict, False when
    a mode never decays though rounding put every modulus below 1)."""
    if poles.size == 0 or not np.any(poles):
        return 0j, 0.0, 1.0  # a finite impulse response: no recursion, nothing to wait for
    if unit and np.abs(poles).max() <= 1.0:
        return 1 + 0j, float("inf"), 0.0
    mods = np.abs(poles)
    rho = float(mods.max())  # the spectral radius, as LocalModel.spectral_radius and the bands take it
    cand = poles[mods >= rho * (1 - MODULUS_ROUNDING)]
    # of poles of one modulus the least damped, whatever order the eigensolver gave them in: of a conjugate
    # pair the one with arg > 0, of ±p (a model in y(k-2) alone) −p, whose mode alternates as slowly as +p's decays
    p = complex(cand[np.argmax(np.angle(cand))])
    r = rho  # not abs(p): Python's modulus of a pole on the unit circle came out 1 − 1e-16 where numpy's is 1
    if r >= 1.0 or not stable:
        # on the unit circle to rounding (the test says not inside; z² − z + 1's roots came out of modulus 1 − 1e-16,
        # a τ of 9e15 s) its mode never decays, ζ = 0; outside it grows, ζ undefined
        return p, float("inf"), 0.0 if r <= 1.0 + MODULUS_ROUNDING else float("nan")
    s = complex(np.log(r), np.angle(p))
    return p, float(-Ts / np.log(r)), float(-s.real / abs(s))


@dataclass(frozen=True, eq=False)
class LocalModel(Relocked):
    """The linearisation of a NARX model around the equilibrium it reaches at a constant input.

    Attributes
    ----------
    ubar : ndarray, shape (m,)
        The operating input (input units), in ``input_names`` order.
    ybar : float or None
        The equilibrium output (output units); None when the model has no equilibrium at ū.
    status : str
        ``"reached"`` (a stable equilibrium, reached from y0 as J_SF defines it), or why not:
        ``"no equilibrium"``, ``"no stable equilibrium"`` (the linearisation is then at the
        unstable equilibrium nearest y0, or with the smallest spectral radius), ``"diverged"`` or
        ``"did not settle"`` (the free run from y0 settles on none; the linearisation is at the
        real equilibrium nearest y0), ``"continuum of equilibria"`` (every ȳ is an equilibrium at ū, as
        for an integrator at its balancing input: ū sets no ȳ; the linearisation is at ȳ = y0 when y0 is
        given, where the model stays, and there is none without it), ``"several stable equilibria"`` (no ``y0``
        picks one of them: no linearisation; :func:`operating_curve` marks such a point and goes on,
        :func:`local_model` raises).
    reason : str
        The status in words, naming ū (empty when reached).
    a : ndarray, shape (L_y,)
        a_l = ∂F/∂y(k−l) (dimensionless): A(q⁻¹) = 1 − Σ a_l q⁻ˡ.
    b : ndarray, shape (m, L_u)
        b_il = ∂F/∂u_i(k−l) (output units per unit of input i): B_i(q⁻¹) = Σ b_il q⁻ˡ.
    Ts : float
        Sampling period (s).
    input_names : tuple of str
    name : str
        Label (the model's name).
    units : tuple
        The model's units of (u, y) (:attr:`graybox.Model.units`; the input's one str, or one per input): ``b``
        and the gains hold in them. Empty: not said.
    """

    ubar: np.ndarray
    ybar: float | None
    status: str
    reason: str
    a: np.ndarray
    b: np.ndarray
    Ts: float
    input_names: tuple[str, ...]
    name: str = ""
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        # types, then what the fields say of each other (a file loads through here: graybox.io)
        check_fields(self)
        m = len(check_input_names(self.input_names, what="LocalModel: input_names"))
        object.__setattr__(self, "units", check_units(self.units, "LocalModel", m))
        # numbers only: numpy's conversion parsed text, read True as 1 and None as NaN (a file's or a caller's fields)
        ubar = np.ravel(real_array(self.ubar, "LocalModel: ubar"))
        a, b = real_array(self.a, "LocalModel: a"), real_array(self.b, "LocalModel: b")
        if ubar.size != m:
            raise ValueError(f"ubar has {ubar.size} values for {m} input(s) {self.input_names}")
        if a.ndim != 1:
            raise ValueError(f"a must have shape (L_y,), got {a.shape}")
        if b.ndim == 1 and m == 1:
            b = b[None, :]
        if b.ndim != 2 or b.shape[0] != m:
            raise ValueError(f"b must have shape ({m}, L_u), one row per input, got {b.shape}")
        for name, v in (("ubar", ubar), ("a", a), ("b", b)):
            if not np.isfinite(v).all():
                raise ValueError(f"{name} has non-finite values")
        # the gains Σ_l b_il / (1 − Σ_l a_l) are the model's figures: coefficients whose sums or gain overflow (a
        # hand-edited file) are no local model; an integrator's 1 − Σa = 0 is its infinite gain, not an overflow
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            den, sb = 1.0 - a.sum(), b.sum(axis=1)
            gain = sb / den
        if not np.isfinite(den) or not np.isfinite(sb).all() or (den != 0 and not np.isfinite(gain).all()):
            raise ValueError(f"a and b overflow: 1 − Σa = {den:g}, Σb = {sb.tolist()} and the DC gain Σb / (1 − Σa) "
                             "must be finite (an integrator's 1 − Σa = 0 excepted)")
        if self.ybar is not None:  # a float, as typed (an int beyond int64 failed numpy's isfinite)
            try:
                object.__setattr__(self, "ybar", float(self.ybar))
            except OverflowError:
                raise ValueError("ybar must be finite or None (no equilibrium), got an integer beyond the float "
                                 "range") from None
            if not np.isfinite(self.ybar):
                raise ValueError(f"ybar must be finite or None (no equilibrium), got {self.ybar}")
        check_choice(self.status, "status", LOCAL_STATUS)  # a local model evaluates its point
        if self.status == "reached" and self.ybar is None:
            raise ValueError("status 'reached' needs the equilibrium ybar")
        if self.ybar is not None and self.status in ("reached", "no stable equilibrium"):
            # the one says the equilibrium is stable, the other that none is: the poles must agree
            stable = bool(schur_stable(a)) if a.size else True
            if stable != (self.status == "reached"):
                said = "a stable equilibrium" if self.status == "reached" else "an unstable equilibrium"
                poles = "every pole inside the unit circle" if stable else "poles on or outside the unit circle"
                raise ValueError(f"status {self.status!r} linearises at {said}, but a = {a.tolist()} has {poles}")
        # what a hand-edited file could say and the statuses cannot (hunt37e's note)
        if self.status in ("no equilibrium", SEVERAL_STABLE) and self.ybar is not None:
            raise ValueError(f"status {self.status!r} has no ybar, got {self.ybar}")
        if self.status != "reached" and not self.reason.strip():
            raise ValueError(f"status {self.status!r} needs its reason (the status in words, naming ū)")
        if self.status == "reached" and self.reason.strip():
            raise ValueError(f"status 'reached' has no reason (it is empty when the equilibrium is reached), got "
                             f"{self.reason!r}")
        object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        if self.ybar is not None and a.size:  # τ = −Ts / ln ρ is a figure too: a period that overflows it is none
            poles = characteristic_roots(a[None, :])[0]
            stable = bool(schur_stable(a))  # a mode that never decays has τ = inf of its own, whatever Ts
            with np.errstate(over="ignore", divide="ignore"):
                _, tau, _ = _dominant(poles, self.Ts, stable=stable)
            rho = float(np.abs(poles).max())
            if stable and rho < 1.0 and not np.isfinite(tau):
                raise ValueError(f"Ts = {self.Ts:g} s makes the time constant −Ts / ln ρ (ρ = {rho:.6g}) overflow")
        object.__setattr__(self, "ubar", frozen(ubar))
        object.__setattr__(self, "a", frozen(a))
        object.__setattr__(self, "b", frozen(b))

    # -- facts --------------------------------------------------------------------------------
    @property
    def exists(self) -> bool:
        """True when there is an equilibrium to linearise around (stable or not)."""
        return self.ybar is not None

    @property
    def reached(self) -> bool:
        """True when the equilibrium is stable and reached (the J_SF definition)."""
        return self.status == "reached"

    def _need(self) -> None:
        if self.ybar is None:
            raise ValueError(f"no local model: {self.reason}")

    @property
    def poles(self) -> np.ndarray:
        """Roots of z^L − a_1 z^(L−1) − … − a_L, shape (L_y,) complex: the stability test's eigenvalues."""
        self._need()
        return characteristic_roots(self.a[None, :])[0]

    @property
    def stable(self) -> bool:
        """Every pole strictly inside the unit circle (the package's Schur–Cohn test; a pole at z = 1 to rounding, as
        at a fold of the static curve, is not inside)."""
        self._need()
        return bool(schur_stable(self.a)) if self.a.size else True

    @property
    def spectral_radius(self) -> float:
        """Largest pole modulus (0 without output lags), on the side of the unit circle :attr:`stable` says (at least 1
        where not stable), as :attr:`graybox.Equilibrium.spectral_radius` reports it."""
        p = self.poles
        rho = float(np.abs(p).max()) if p.size else 0.0
        # on the stability verdict's side of the unit circle, as the static analysis's Equilibrium reports it: a pole at
        # z = 1 to rounding (a fold's), or z² − 2cos(0.3)z + 1's pair whose moduli rounding put at 1 − 1e-16, is ρ >= 1
        return verdict_radius(self.stable, rho)

    def zeros(self, input: int | str = 0) -> np.ndarray:
        """Zeros of B_i away from z = 0: roots of Σ_l b_il z^(L_u − l) other than 0, complex (input ``input``).

        A zero at z = 0 is a delay, as the poles at 0 of a common order are (:meth:`to_transfer_function` carries both,
        so its ``zeros()`` can list some at 0 beside these): an input whose lags end before L_u, the largest input
        lag over the inputs, would show them only because another input reaches further back.

        Parameters
        ----------
        input : int or str
            The input, by position in ``input_names`` or by name.

        Returns
        -------
        ndarray of complex, shape (<= L_u − 1,)
            The zeros (none for an input that no term moves).
        """
        self._need()
        row = self.b[self._input_index(input)]
        nz = np.flatnonzero(row)
        if nz.size == 0:
            return np.zeros(0, complex)
        return np.roots(row[nz[0]: nz[-1] + 1]).astype(complex)

    def _input_index(self, input: int | str) -> int:
        if isinstance(input, str):
            if input not in self.input_names:
                raise ValueError(f"no input named {input!r}; the inputs are {self.input_names}")
            return self.input_names.index(input)
        i = check_int(input, "input")
        if not 0 <= i < len(self.input_names):
            raise ValueError(f"input {i} is out of range: the local model has {len(self.input_names)} input(s), "
                             f"{', '.join(f'{k} ({n})' for k, n in enumerate(self.input_names))}")
        return i

    @property
    def dc_gain(self) -> np.ndarray:
        """Σ_l b_il / (1 − Σ_l a_l), shape (m,): output units per unit of each input (= the static gain)."""
        self._need()
        with np.errstate(divide="ignore", invalid="ignore"):  # a pole at z = 1 to rounding: the gain is infinite
            return self.b.sum(axis=1) / (0.0 if _unit_pole(self.a) else 1.0 - self.a.sum())

    @property
    def dominant_pole(self) -> complex:
        """The pole of largest modulus (of several of that modulus the least damped: of a complex pair the one
        with positive angle, of ±p the negative one)."""
        return self._mode()[0]

    @property
    def time_constant(self) -> float:
        """−Ts / ln|p| of the dominant pole (s); 0 without recursion; inf when |p| >= 1 or the equilibrium is not
        :attr:`stable` (nothing settles: a pole on the unit circle whose modulus rounding put at 1 − 1e-16 included).

        The decay of the slowest mode's envelope, a first-order time constant only for a positive
        real dominant pole (:attr:`damping` 1). A negative or complex one oscillates, and a pole
        nearly cancelled by a zero (:meth:`zeros`) barely shows in the step response: a fitted
        model can carry a pole near −1 with a zero beside it, a τ longer than the time its step
        takes to settle. Read :meth:`settling_time` and :meth:`step` before tuning on it.
        """
        return self._mode()[1]

    @property
    def damping(self) -> float:
        """ζ of the dominant pole's continuous equivalent s = ln(p)/Ts (1 for a positive real pole,
        below 1 for a complex or negative one; 0 on the unit circle (to a modulus rounding of 1e-12, where the
        equilibrium is not :attr:`stable`), NaN outside it)."""
        return self._mode()[2]

    def _mode(self) -> tuple[complex, float, float]:
        """(dominant pole, τ (s), ζ): :func:`_dominant` of the poles, told the stability test's verdict."""
        return _dominant(self.poles, self.Ts, _unit_pole(self.a), self.stable)

    def step(self, n_samples: int, input: int | str = 0) -> np.ndarray:
        """Response Δy(k), k = 0 … n−1, to a unit step of input ``input`` applied from k = 0, shape (n,).

        Parameters
        ----------
        n_samples : int
            Length of the response.
        input : int or str
            The input stepped, by position or name.

        Returns
        -------
        ndarray, shape (n_samples,)
            Δy(k) in output units for a step of one input unit (deviation from ȳ).
        """
        self._need()
        n = check_count(n_samples, "n_samples", low=1)
        b = np.concatenate([[0.0], self.b[self._input_index(input)]])
        from scipy.signal import lfilter  # slow to import: loaded where used
        return lfilter(b, np.concatenate([[1.0], -self.a]), np.ones(n))

    def frequency_response(self, omega: np.ndarray, input: int | str = 0) -> np.ndarray:
        """G_i(e^{jωTs}) = B_i / A on the unit circle at the angular frequencies ``omega`` (rad/s), complex, shape (K,);
        of infinite modulus at a pole on the unit circle (an integrator's at ω = 0).

        Parameters
        ----------
        omega : array_like, shape (K,)
            Angular frequencies (rad/s), up to the Nyquist frequency π/Ts.
        input : int or str
            The input, by position or name.

        Returns
        -------
        ndarray of complex, shape (K,)
            Output units per input unit.
        """
        self._need()
        w = np.atleast_1d(real_array(omega, "omega", "angular frequencies (numbers, rad/s)"))
        if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)):
            raise ValueError(f"omega must be finite angular frequencies (rad/s) of shape (K,), K >= 1, got shape "
                             f"{w.shape}" + ("" if np.all(np.isfinite(w)) else " with non-finite values"))
        nyquist = np.pi / self.Ts
        if np.abs(w).max() > nyquist * (1 + 1e-9):  # above it e^{jωTs} comes round again: an alias, not a response
            raise ValueError(f"omega must be at most the Nyquist frequency π/Ts = {nyquist:.6g} rad/s (Ts = "
                             f"{self.Ts:g} s), got {np.abs(w).max():.6g} rad/s")
        zi = np.exp(-1j * w * self.Ts)  # z⁻¹ on the unit circle
        b = self.b[self._input_index(input)]
        num = np.polynomial.polynomial.polyval(zi, np.concatenate([[0.0], b]))
        den = np.polynomial.polynomial.polyval(zi, np.concatenate([[1.0], -self.a]))
        with np.errstate(divide="ignore", invalid="ignore"):  # at a pole on the unit circle: infinite, as dc_gain
            return num / den

    def settling_time(self, input: int | str = 0, band: float = SETTLING_BAND) -> float:
        """Time (s) after which the step response stays within ``band`` of its final value.

        Counted from the step instant. inf when the equilibrium is not stable (or settles beyond
        10⁷ samples); NaN when the DC gain is zero (no final value to settle on).

        Parameters
        ----------
        input : int or str
            The input stepped.
        band : float
            Fraction of the final value (dimensionless, default 0.02).

        Returns
        -------
        float
            Seconds; inf or NaN as said above.
        """
        band = check_real(band, "band", low=0, low_open=True, high=1, high_open=True)
        i = self._input_index(input)
        g = float(self.dc_gain[i])
        rho = self.spectral_radius
        # not stable (the one test): a mode never decays, even where rounding put its modulus at 1 − 1e-16 (its step
        # response was run over the longest window, 3 s, to find that out)
        if rho >= 1.0 or not np.isfinite(g) or not self.stable:
            return float("inf")
        if g == 0.0:
            return float("nan")
        lags = self.a.size + self.b.shape[1] + 2
        # a window over which the slowest mode's envelope ρ^k falls to 1e-3 of the band, then as long as the
        # response still has not come that close at the window's end: the envelope starts at the transient's
        # own size, which a zero near z = 1 makes thousands of times the final value
        n = lags if rho == 0.0 else lags + int(np.ceil(np.log(band * 1e-3) / np.log(rho)))
        num, den = np.concatenate([[0.0], self.b[i]]), np.concatenate([[1.0], -self.a])
        n = min(n, SETTLING_WINDOW_SAMPLES)
        while True:
            # the tail: the error recursion's whole state, and a quarter of the window so that a slow oscillation
            # passing zero is no settled tail; round-off of the response is no transient
            last, early, late, peak = _step_error(num, den, g, band, n, max(lags, n // 4))
            settled = max(early, late) <= max(1e-3 * band * abs(g), 64 * np.finfo(float).eps * (peak + abs(g)))
            if not settled and n >= SETTLING_WINDOW_SAMPLES:
                # the window can grow no further: settled when the tail stays in the band and still falls there
                settled = max(early, late) <= band * abs(g) and late < early
                if not settled:
                    return float("inf")
            if settled:
                return float("inf") if last > MAX_SETTLING_SAMPLES else float(last * self.Ts)
            n = min(2 * n, SETTLING_WINDOW_SAMPLES)

    # -- python-control ------------------------------------------------------------------------
    def to_statespace(self) -> Any:
        """The local model as a discrete ``control.StateSpace`` (dt = Ts) in deviation variables.

        Observer canonical form of order n = max(L_y, L_u): x_1 = Δy, A's first column holds the
        a_l, B's rows the b_il, C = [1, 0, …], D = 0. Its eigenvalues are :attr:`poles` and
        n − L_y poles at z = 0 (input lags beyond the output lags). Inputs are named after
        ``input_names`` but the transient inputs (``u_tau30`` …: moving with Δu², they stay at 0 to first order,
        and :func:`graybox.narx_iosystem` computes them), the output ``"y"``. Needs python-control
        (``pip install graybox[control]``).

        Returns
        -------
        control.StateSpace
            n states, one input per input but the transient ones, 1 output; Δu in input units, Δy in output units.
        """
        self._need()
        return local_statespace(self)

    def to_transfer_function(self) -> Any:
        """The local model as a discrete ``control.TransferFunction`` (dt = Ts), one column per input (but the
        transient inputs, as in :meth:`to_statespace`).

        G_i(z) = Σ_l b_il z^(n−l) / (z^n − Σ_l a_l z^(n−l)), n = max(L_y, L_u), in deviation
        variables. Needs python-control (``pip install graybox[control]``).

        Returns
        -------
        control.TransferFunction
            1 output × one input per input but the transient ones, output units per input unit.
        """
        self._need()
        return local_transfer_function(self)

    def __repr__(self) -> str:
        u = ", ".join(exact_text(v) for v in self.ubar)  # ū 10000.01 and 10000.02 printed alike with %g
        if self.ybar is None:
            return f"LocalModel(ū = ({u}): {self.reason})"
        g = ", ".join(f"{v + 0.0:.4g}" for v in self.dc_gain)  # + 0.0: -0.0 is 0, not "-0"
        return (f"LocalModel(ū = ({u}), ȳ = {self.ybar + 0.0:.6g}, {self.status}, gain = ({g}), "
                f"ρ = {self.spectral_radius:.4g}, τ = {self.time_constant:.4g} s)")


# -- python-control ------------------------------------------------------------------------------
#: How to install the optional dependency.
#: How to get python-control: the package itself, or graybox's extra (quoted: zsh reads bare brackets as a glob;
#: from a clone, the editable install the README uses)
CONTROL_EXTRA = ("pip install graybox[control] (quoted in zsh: 'graybox[control]'), from a clone pip install -e "
                 "'.[control]', or the package itself: pip install control")


#: The oldest python-control the bridge runs on (the extra's pin): 0.10 brought ``control.nlsys``.
CONTROL_MIN = (0, 10)


def require_control() -> Any:
    """python-control, or an ``ImportError`` naming the extra to install (or to upgrade, for one older than
    :data:`CONTROL_MIN`)."""
    try:
        import control
    except ImportError as exc:
        raise ImportError(f"this needs python-control (the 'control' extra): {CONTROL_EXTRA}") from exc
    # an older one (a distribution's package, 0.9) failed later with "module 'control' has no attribute 'nlsys'"
    version = str(getattr(control, "__version__", ""))
    parts = tuple(int(p) for p in re.findall(r"\d+", version)[:2])
    if len(parts) == 2 and parts < CONTROL_MIN:
        raise ImportError(f"this needs python-control {CONTROL_MIN[0]}.{CONTROL_MIN[1]} or later (the 'control' "
                          f"extra), found {version}: upgrade it, "
                          f"{CONTROL_EXTRA.replace('pip install', 'pip install -U')}")
    return control


def transient_sources(inputs: tuple[str, ...]) -> dict[int, tuple[int, float]]:
    """Transient input j → (its source input i, τ (s)), read from their names as
    :func:`graybox.core._transient.recomputed_transients` reads them: the inputs no python-control system takes
    (:func:`graybox.narx_iosystem` computes them from their sources)."""
    out = {}
    for j, n in enumerate(inputs):
        source = transient_source(n, inputs)
        tau = None if source is None else _tau_of(n, source)
        if tau is not None:
            out[j] = (inputs.index(source), tau)
    return out


def _padded(lm: LocalModel) -> tuple[np.ndarray, np.ndarray, int, list[str]]:
    """(a, b, n, names) padded to the common order n = max(L_y, L_u): a (n,), b (m', n) of the inputs a system
    takes, named ``names``. A transient input is none: z(k) = ρ z(k−1) + (1 − ρ)(u(k) − u(k−1))² moves with Δu
    squared, so to first order it stays at its z̄ = 0 and the linear system from u is B_u / A alone (as
    ``control.linearize`` of :func:`graybox.narx_iosystem`'s system, which computes z, finds it)."""
    transient = transient_sources(lm.input_names)
    fed = [i for i in range(len(lm.input_names)) if i not in transient]
    n = max(lm.a.size, lm.b.shape[1], 1)
    a = np.zeros(n)
    a[: lm.a.size] = lm.a
    b = np.zeros((len(fed), n))
    b[:, : lm.b.shape[1]] = lm.b[fed]
    return a, b, n, [lm.input_names[i] for i in fed]


def local_statespace(lm: LocalModel) -> Any:
    """See :meth:`graybox.control._local.LocalModel.to_statespace`."""
    ct = require_control()
    a, b, n, names = _padded(lm)
    A = np.zeros((n, n))
    A[:, 0] = a
    A[np.arange(n - 1), np.arange(1, n)] = 1.0
    C = np.zeros((1, n))
    C[0, 0] = 1.0
    return ct.ss(A, b.T, C, np.zeros((1, b.shape[0])), dt=lm.Ts, inputs=names, outputs=["y"],
                 states=[f"x{i + 1}" for i in range(n)], name=system_name(lm.name, "local"))


def local_transfer_function(lm: LocalModel) -> Any:
    """See :meth:`graybox.control._local.LocalModel.to_transfer_function`."""
    ct = require_control()
    a, b, n, names = _padded(lm)
    den = np.concatenate([[1.0], -a])
    nums = [[np.trim_zeros(np.concatenate([[0.0], row]), "f") if np.any(row) else np.array([0.0]) for row in b]]
    return ct.tf(nums, [[den] * b.shape[0]], dt=lm.Ts, inputs=names, outputs=["y"],
                 name=system_name(lm.name, "local"))


def system_name(name: str, what: str) -> str | None:
    """A python-control system name from a model name (None lets python-control number it)."""
    clean = "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in name).strip("_")
    return f"{clean}_{what}" if clean else None


# -- the equilibrium and the linearisation --------------------------------------------------------
def input_levels(ubar: object, name: str = "ubar") -> np.ndarray:
    """``ubar`` as a float array, or a ``TypeError`` naming it for strings, complex values, None or booleans
    (numpy's own conversion names neither the argument nor the problem, and takes None for NaN)."""
    return real_array(ubar, name, "input levels (numbers)")


def _as_points(model: Model, ubar: object, one_point: bool = False) -> np.ndarray:
    """ū as points of shape (M, m) in the model's input order (``one_point``: the caller takes one)."""
    m = model.n_inputs
    ub = input_levels(frame_inputs(ubar, model.input_names, "ubar", steady=True))  # by column name
    one_point = one_point or labelled_point(ubar, model.input_names)  # a Series labelled by the inputs: one ū
    ub = steady_levels(ub, model.input_names, one_point=one_point)  # transient inputs left out: z̄ = 0
    if m == 1:
        ub = np.atleast_1d(ub).reshape(-1, 1) if ub.ndim <= 1 else ub
    elif ub.ndim == 1 and ub.size == m:
        ub = ub[None, :]
    if ub.size == 0:  # shape (0,) is (M,) with M = 0: the fault is the missing levels, not the shape
        raise ValueError(f"ubar holds no input level: give one ū or more (of the inputs {model.input_names})")
    if ub.ndim != 2 or ub.shape[1] != m or ub.shape[0] == 0:
        raise ValueError(f"ubar must have shape (M,) for one input or (M, {m}) for {m} inputs "
                         f"{model.input_names}, got shape {np.shape(ubar)}")
    if not np.all(np.isfinite(ub)):
        raise ValueError("ubar has non-finite values")
    refuse_transient_levels(ub, model.input_names)  # no equilibrium there: narx_steady_state refuses it alike
    return ub


def _reached(model: Model, thetas: np.ndarray, ub: np.ndarray, y0: np.ndarray):
    """:class:`~graybox.static._analysis.Reached` of many members at the points ``ub`` (M, m)."""
    if model.n_inputs > 1:
        return reached_surface(model.structure, thetas, ub, y0, inputs=model.input_names)
    return reached_equilibria(model.structure, thetas, ub[:, 0], y0)


def _continuum_at(model: Model, u: np.ndarray) -> bool:
    """Whether every ȳ is an equilibrium at the point u (m,) (:func:`graybox.static._analysis.continuum`)."""
    if model.n_inputs > 1:
        sk, th = _folded(model.structure, model.theta, u[None, :], model.input_names)
        return bool(continuum(sk, th[0], np.ones(1))[0, 0])
    return bool(continuum(model.structure, model.theta[None, :], u[:1])[0, 0])


def _fold_at(model: Model, u: np.ndarray, ybar: float) -> bool:
    """Is ȳ a multiple root of the static equation at the point u (m,) (a fold: Σ a_l = 1 there)?"""
    if model.n_inputs > 1:  # the surface's equilibria are those of the folded model at ū' = 1
        sk, th = _folded(model.structure, model.theta, u[None, :], model.input_names)
        return multiple_root(sk, th[0, 0], 1.0, ybar)
    return multiple_root(model.structure, model.theta, float(u[0]), ybar)


def _equilibrium(model: Model, u: np.ndarray, y0: float | None, eqs: list[Equilibrium] | None = None
                 ) -> tuple[float | None, str, str, bool]:
    """(ȳ, status, reason, fold) at one point u (m,): the reached equilibrium, else the one to linearise around;
    ``fold``: that equilibrium is a multiple root of the static equation, or every ȳ is one (its pole is at z = 1).
    ``eqs``: the model's equilibria at u, when the caller found them (:func:`_equilibria_at`)."""
    label = exact_text(u[0]) if u.size == 1 else "(" + ", ".join(exact_text(v) for v in u) + ")"
    if _continuum_at(model, u):
        # every ȳ is an equilibrium: ū sets none, the output stays where it starts; y0 is then the one to take
        why = f"ū = {label}: {CONTINUUM_WHY}"
        if y0 is None:
            return None, "continuum of equilibria", why + ("; give y0 (the output level ȳ to linearise at, where the "
                                                           "model stays) for the local model there"), False
        # every ȳ solves the static equation, so its slope 1 − Σ a_l is 0 there: the pole is at z = 1 (True: as at a
        # fold), whatever rounding left of the vanishing coefficients (Σa = 1 − 2e-13 at y0 = 1e4 was stable, τ 4e12 s)
        return float(y0), "continuum of equilibria", why + f"; linearised at ȳ = y0 = {exact_text(y0)}", True
    if eqs is None:
        eqs = model.equilibria(u if model.n_inputs > 1 else float(u[0]))
    if y0 is None:
        stable = [e for e in eqs if e.stable]
        if len(stable) == 1:
            return stable[0].ybar, "reached", "", False
        if len(stable) > 1:  # ū sets no one ȳ: the point's status (local_model raises it; a curve goes on)
            return None, SEVERAL_STABLE, "the model has " + several_stable(np.array([e.ybar for e in stable]),
                                                                            f"ū = {label}"), False
        if not eqs:
            return None, "no equilibrium", f"ū = {label}: {NO_EQUILIBRIUM_WHY}", False
        e = min(eqs, key=lambda e: e.spectral_radius)
        why = (f"ū = {label}: no stable equilibrium; linearised at the unstable ȳ = {exact_text(e.ybar)} (spectral "
               f"radius {e.spectral_radius:.4g})")
        return e.ybar, "no stable equilibrium", why, _fold_at(model, u, e.ybar)
    r = _reached(model, model.theta[None, :], u[None, :], np.array([y0]))
    if r.ok[0, 0]:
        return float(r.ybar[0, 0]), "reached", "", False
    status = r.STATUS[int(r.status[0, 0])]
    reason = r.explain(0)[0]
    if not eqs:
        return None, status, reason, False
    e = min(eqs, key=lambda e: abs(e.ybar - y0))
    return (e.ybar, status, reason + f"; linearised at the equilibrium ȳ = {exact_text(e.ybar)} nearest y0",
            not e.stable and _fold_at(model, u, e.ybar))


def _range_warning(model: Model, ub: np.ndarray, data: object) -> None:
    """StaticRangeWarning naming the ū outside the input range of ``data``'s records and static points."""
    if data is None:
        return
    if isinstance(data, Dataset):
        recs = [data.ident, data.valid]
        static = data.static
    elif isinstance(data, StaticPoints):
        recs, static = [], data
    else:
        recs, static = as_records(data), None
    # the range is read in the data's units: data in others than the model's say nothing of its range (the
    # period is checked by check_Ts, and only when the model's own is taken)
    for r in [*recs, *([] if static is None else [static])]:
        check_same_units(model.units, f"model {model.name!r} was identified with", r,
                         "its parameters hold in those units only; convert the data", model.input_names)
    # each input by name, in the model's order (the data's columns may be in another, and a record
    # may hold inputs the model does not use, one input included)
    names = model.input_names
    for r in recs:  # an input the model uses and a record lacks (a transient one: how to add it), as Model.simulate
        require_inputs(names, r.input_names, "but the record's inputs are", prefix=f"{r.name}: ")
    cols = [np.column_stack([r.input(n) for n in names]) for r in recs]
    if static is not None:
        cols.append(static_point_inputs(static, names).reshape(len(static), -1))
    lo = np.min([c.min(axis=0) for c in cols], axis=0)
    hi = np.max([c.max(axis=0) for c in cols], axis=0)
    out = ub[outside_range(ub, lo, hi).any(axis=1)]
    if out.size:
        box = " × ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi))
        pts = rounded_levels(out[:, 0] if out.shape[1] == 1 else out)
        warn(f"operating points ū = {listed(pts)} lie outside the input range {box} of the records and static points: "
             "the local models there are extrapolations of the model", StaticRangeWarning)


def check_Ts(Ts: float | None, data: object, model: Model, takes_data: bool = True) -> float:
    """The sampling period of a model's linear or nonlinear systems: ``Ts``, else the one the model was identified
    at (``data`` at another period is refused: its coefficients hold at its own), else ``data``'s; ``data`` at another
    period than a ``Ts`` given is refused too, but records made without ``Ts=`` (1 s). ``takes_data``: whether the
    caller has a ``data=`` to suggest."""
    # records (a Dataset's, or a sequence of them, which share one period); static points have none
    recs = None if data is None or isinstance(data, StaticPoints) else as_records(data)
    if Ts is None:
        if model.Ts is not None:
            if recs is not None:
                model.check_period(recs[0])
            return float(model.Ts)
        if recs is not None:
            return float(recs[0].Ts)
        raise ValueError("Ts (the sampling period, s) is needed: pass Ts=" + (" or data= (records)" if takes_data else "")
                         + ", or use a model an estimator made (it knows the period it was identified at)")
    # given, it is the user's word over a model's 1 s, the period of a record made without Ts= (its model's local
    # models are then asked for at the real one); a model identified at another period is refused: its coefficients
    # hold per step of that period (Ts=50 meant as 50 ms beside a 0.05 s model gave τ 1000 times too long)
    Ts = check_real(Ts, "Ts", low=0, low_open=True)
    known = model.Ts is not None and model.Ts != 1.0
    if known and abs(Ts - model.Ts) > 1e-9 * model.Ts:
        raise ValueError(f"Ts = {Ts:g} s, but model {model.name!r} was identified at Ts = {model.Ts:g} s, the period its "
                         "coefficients hold per step of: leave Ts= out (seconds, the model's own is taken), or, if the "
                         "model's period is wrong, give the model its own: dataclasses.replace(model, Ts=...)")
    # the data the model was identified on say its period too: a Ts= they contradict (50 meant as ms beside records
    # at 0.05 s) is refused as the model's own is; records made without Ts= (1 s) are relabelled by it, as its 1 s is
    # (beside a model of known period too: Ts= given its own, records without Ts= were refused by the model's check)
    if recs is not None and recs[0].Ts != 1.0:
        if known:
            model.check_period(recs[0])
        else:
            check_period(Ts, f"Ts = {Ts:.9g} s was given: the model runs", recs[0],
                         "; leave Ts= out to take the data's period")
    return Ts


def _y0s(y0: object, M: int) -> list[float | None]:
    if y0 is None:
        return [None] * M
    return [float(v) for v in check_per_point(y0, M, "y0 (one per operating point)")]


def _equilibria_at(model: Model, ub: np.ndarray) -> list[list[Equilibrium] | None]:
    """The equilibria of a one-input model at each point of ``ub`` (M, 1), every level's static equation solved
    together; None where every ȳ is one (:func:`_equilibrium` says so) and for a model of several inputs."""
    if model.n_inputs > 1:
        return [None] * ub.shape[0]
    levels = ub[:, 0]
    free = ~continuum(model.structure, model.theta[None, :], levels)[0]
    out: list[list[Equilibrium] | None] = [None] * levels.size
    if not free.any():
        return out
    for j, eqs in zip(np.flatnonzero(free), equilibria_at_levels(model.structure, model.theta, levels[free])):
        out[j] = eqs
    return out


def _linearise(model: Model, u: np.ndarray, y0: float | None, Ts: float,
               eqs: list[Equilibrium] | None = None) -> LocalModel:
    ybar, status, reason, fold = _equilibrium(model, u, y0, eqs)
    if ybar is None:
        a, b = np.zeros(0), np.zeros((model.n_inputs, 0))
    else:
        a2, b3 = jacobian_rows(model.structure, model.input_names, model.theta[None, :], np.array([ybar]), u[None, :])
        a, b = a2[0], b3[0]
        if fold and a.size:
            # a multiple root (a fold, an inflection): there Σ a_l = 1 exactly, but the root is known only to
            # eps^(1/m) and its a_l sum to 1 ± 4e-10 (a triple root), either side of 1 as rounding went: the
            # linearisation at the root itself has its pole at z = 1 (so has a continuum's, every ȳ a root)
            a = a.copy()
            a[0] += 1.0 - a.sum()
    return LocalModel(u, ybar, status, reason, a, b, Ts, model.input_names, model.name, model.units)


def local_model(model: Model, ubar: float | Sequence[float] | np.ndarray, *, Ts: float | None = None,
                y0: float | None = None, data: Record | Dataset | Sequence[Record] | StaticPoints | None = None
                ) -> LocalModel:
    """The local linear model of a polynomial NARX model at the constant input ``ubar``.

    The equilibrium is the one the model reaches there (``reached_equilibria``,
    the definition J_SF uses): from ``y0`` when given, else the only stable one. The linearisation
    around it is exact (partial derivatives read from the term structure).

    Parameters
    ----------
    model : Model
        A polynomial NARX model (a ``NeuralModel`` gets a ``TypeError``).
    ubar : float or array_like, shape (m,)
        The operating input (input units); one value per input, in ``model.input_names`` order, or
        a dict or pandas Series by input name (``{"flow": 7.0, "inlet": 20.0}``; transient inputs left
        out are 0, their level at every steady state).
    Ts : float, optional
        Sampling period (s); default the model's own (``model.Ts``, the period it was identified at;
        ``data`` at another period is refused, and so is a ``Ts`` other than a model's own but for its 1 s, the
        period of records made without ``Ts=``), else ``data``'s. ``data`` at another period than a ``Ts`` given is
        refused too, but for records made without ``Ts=`` (1 s).
    y0 : float, optional
        Initial output of the settling run that picks the equilibrium (output units), e.g. the
        measured ȳ; needed when several equilibria are stable, and where every ȳ is an equilibrium
        (status ``"continuum of equilibria"``) the output level to linearise at.
    data : Record, Dataset, sequence of Record or StaticPoints, optional
        The data the model was identified on: a ū outside their input range (records and static
        points) gets a :class:`~graybox.StaticRangeWarning`.

    Returns
    -------
    LocalModel
        ``status`` says whether the equilibrium is reached; without any equilibrium its
        properties raise ``ValueError`` saying so.
    """
    model = check_polynomial(model, "local_model")
    ub = _as_points(model, ubar, one_point=True)
    if ub.shape[0] != 1:
        raise ValueError(f"ubar: local_model takes one operating point, got {ub.shape[0]} (use operating_curve)")
    Ts_ = check_Ts(Ts, data, model)
    _range_warning(model, ub, data)
    lm = _linearise(model, ub[0], _y0s(y0, 1)[0], Ts_)
    if lm.status == SEVERAL_STABLE:  # one point asked for: y0 is what it needs
        raise ValueError(lm.reason)
    return lm


@dataclass(frozen=True, eq=False)
class OperatingCurve(Relocked):
    """Local models along the static curve: gain, time constant and damping against ū.

    Attributes
    ----------
    local_models : tuple of LocalModel
        One per operating point.
    ubar : ndarray, shape (M,) or (M, m)
        Operating points (input units).
    ybar, time_constant, damping, spectral_radius, settling_time : ndarray, shape (M,)
        Equilibrium (output units), dominant time constant (s), its damping, largest pole
        modulus, 2 % settling time of a step of the first input (s; :meth:`to_frame` names that input
        when there are several); NaN where there is no equilibrium (``status`` says why).
    gain : ndarray, shape (M,) or (M, m)
        DC gain = static gain (output units per input unit).
    status : tuple of str
        Each point's :attr:`LocalModel.status`.
    level : float
        Confidence level of the bands (NaN without bands).
    gain_low, gain_high, time_constant_low, time_constant_high : ndarray or None
        Monte Carlo band from the parameter covariance (None when none was given).
    undefined : ndarray, shape (M,) or None
        Fraction of draws that reach no stable equilibrium at each ū (left out of the band); NaN,
        with NaN bands, where the model itself reaches none (``status`` not ``"reached"``: no
        draws are made there).
    model_name : str
        Name of the model the curve is of (its :attr:`Model.name`; shown by ``repr`` and the plots).
    """

    local_models: tuple[LocalModel, ...]
    ubar: np.ndarray
    ybar: np.ndarray
    gain: np.ndarray
    time_constant: np.ndarray
    damping: np.ndarray
    spectral_radius: np.ndarray
    settling_time: np.ndarray
    status: tuple[str, ...]
    level: float = float("nan")
    gain_low: np.ndarray | None = None
    gain_high: np.ndarray | None = None
    time_constant_low: np.ndarray | None = None
    time_constant_high: np.ndarray | None = None
    undefined: np.ndarray | None = None
    model_name: str = ""

    BANDS: ClassVar[tuple[str, ...]] = ("gain_low", "gain_high", "time_constant_low", "time_constant_high", "undefined")

    @property
    def units(self) -> tuple[str, str]:
        """The model's units of (u, y), as its local models carry them (empty: not said)."""
        return self.local_models[0].units

    def __post_init__(self) -> None:
        check_fields(self)
        for f in ("ubar", "ybar", "gain", "time_constant", "damping", "spectral_radius", "settling_time", *self.BANDS):
            v = getattr(self, f)
            if v is not None:  # numbers only: numpy's conversion parsed text and read None as NaN
                object.__setattr__(self, f, frozen(real_array(v, f"OperatingCurve: {f}")))
        # what the fields say of each other (a file loads through here: graybox.io)
        M = len(self.ubar)
        if not all(isinstance(lm, LocalModel) for lm in self.local_models):
            raise TypeError("local_models must hold LocalModel values")
        if len(self.local_models) != M or M == 0:
            raise ValueError(f"{len(self.local_models)} local models for {M} operating points; one each, at least one")
        if len(self.status) != M:
            raise ValueError(f"status has {len(self.status)} entries for {M} operating points")
        if tuple(self.status) != tuple(lm.status for lm in self.local_models):
            raise ValueError(f"status {self.status} disagrees with the local models' own")
        # one model's local models: one set of inputs, one sampling period, one set of units
        first = self.local_models[0]
        for i, lm in enumerate(self.local_models[1:], 1):
            if lm.input_names != first.input_names or lm.Ts != first.Ts or lm.units != first.units:
                raise ValueError(f"the local models are not of one model: local model {i} has the inputs "
                                 f"{lm.input_names}, Ts = {lm.Ts:g} s and units {lm.units}, local model 0 "
                                 f"{first.input_names}, Ts = {first.Ts:g} s and units {first.units}")
        points = np.vstack([lm.ubar for lm in self.local_models])
        if self.ubar.shape != ((M,) if points.shape[1] == 1 else points.shape) \
                or not np.array_equal(self.ubar.reshape(points.shape), points):
            raise ValueError("ubar disagrees with the local models' operating points")
        for f in ("ybar", "time_constant", "damping", "spectral_radius", "settling_time", "gain", *self.BANDS):
            v = getattr(self, f)
            want = self.ubar.shape if f.startswith("gain") else (M,)
            if v is not None and v.shape != want:
                each = "operating point and input" if len(want) > 1 else "operating point"
                raise ValueError(f"{f} must have shape {want}, one value per {each}, got {v.shape}")
        # the columns are the local models' own figures (the plots and tables read the columns, a user the models);
        # the settling time is not recomputed (it costs a step response per point), only held to what it can be
        rows = [_summary(lm, settling=False) for lm in self.local_models]
        own = {"ybar": np.array([r[0] for r in rows]), "gain": np.array([r[1] for r in rows]).reshape(self.ubar.shape),
               "time_constant": np.array([r[2] for r in rows]), "damping": np.array([r[3] for r in rows]),
               "spectral_radius": np.array([r[4] for r in rows])}
        for f, v in own.items():
            if not np.allclose(getattr(self, f), v, rtol=1e-9, atol=0.0, equal_nan=True):
                i = int(np.flatnonzero(~np.isclose(getattr(self, f), v, rtol=1e-9, atol=0.0, equal_nan=True)
                                       .reshape(M, -1).any(axis=1))[0])
                raise ValueError(f"{f} disagrees with the local models' own at operating point {i} "
                                 f"({getattr(self, f).reshape(M, -1)[i].tolist()} against {v.reshape(M, -1)[i].tolist()})")
        exists = np.array([lm.exists for lm in self.local_models])
        st = self.settling_time
        if np.any(st < 0) or np.any(~np.isnan(st[~exists])):
            i = int(np.flatnonzero((st < 0) | (~exists & ~np.isnan(st)))[0])
            raise ValueError(f"settling_time must be >= 0 seconds (inf: never), NaN where there is no equilibrium; got "
                             f"{st[i]:g} at operating point {i}")
        self._check_bands()

    def _check_bands(self) -> None:
        """The Monte Carlo bands as :func:`operating_curve` makes them (a file loads through here): all or none, at a
        level in (0, 1) (NaN without), low ends at most high ones, τ >= 0, undefined shares in [0, 1] (NaN where the
        model itself reaches no equilibrium)."""
        given = [f for f in self.BANDS if getattr(self, f) is not None]
        if not given:
            if not np.isnan(self.level):
                raise ValueError(f"level must be NaN without bands (it is the bands' confidence level), got {self.level}")
            return
        if len(given) != len(self.BANDS):
            raise ValueError(f"the bands are all given or none: {', '.join(given)} given, "
                             f"{', '.join(f for f in self.BANDS if f not in given)} not")
        check_real(self.level, "level (of the bands)", low=0, high=1, low_open=True, high_open=True)
        for lo, hi in (("gain_low", "gain_high"), ("time_constant_low", "time_constant_high")):
            a, b = getattr(self, lo), getattr(self, hi)
            check_band_values(np.zeros(a.shape), a, b, "", lo, hi)
        tlo = self.time_constant_low
        if np.any(tlo < 0):
            raise ValueError(f"time_constant_low must be >= 0 seconds, got {tlo[tlo < 0][0]:g}")
        u = self.undefined
        reached = np.array([lm.reached for lm in self.local_models])
        if np.any((u < 0) | (u > 1)) or np.any(np.isnan(u[reached])):
            raise ValueError("undefined must hold shares of the draws, in [0, 1] (NaN only where the model reaches no "
                             f"equilibrium), got {u.tolist()}")
        # numbers wherever a draw was kept: NaN where the model reaches no equilibrium (no draws) or none was kept
        check_band_finite(self, ("gain_low", "gain_high", "time_constant_low", "time_constant_high"),
                          np.isnan(u) | (u == 1))

    @property
    def has_band(self) -> bool:
        """True when the parameter uncertainty gave bands."""
        return self.gain_low is not None

    def to_frame(self) -> Any:
        """The operating curve as a table.

        Returns
        -------
        pandas.DataFrame
            One row per operating point (index ``ubar``, or a MultiIndex by input with several inputs; input
            units): ``ybar`` (output units), ``gain`` (output units per input unit; ``gain <input>`` per input with
            several), ``time constant`` and ``settling time`` (s; with several inputs ``settling time (<first
            input> step)``), ``damping``, ``spectral radius``, ``status``, and the bands' columns (``gain low``,
            ``gain high``, ``time constant low``, ``time constant high``, ``undefined``) when there are bands.
        """
        import pandas as pd

        single = self.ubar.ndim == 1
        names = self.local_models[0].input_names

        def per_input(label: str, v: np.ndarray) -> dict[str, np.ndarray]:  # one column per input when (M, m)
            return {label: v} if v.ndim == 1 else {f"{label} {n}": v[:, i] for i, n in enumerate(names)}

        cols: dict[str, Any] = {"ybar": self.ybar, **per_input("gain", self.gain)}
        # a step of the first input: named with several inputs, or the same model with its inputs listed in
        # another order would put another input's settling time under the same column
        settling = "settling time" if single else f"settling time ({names[0]} step)"
        cols.update({"time constant": self.time_constant, "damping": self.damping,
                     "spectral radius": self.spectral_radius, settling: self.settling_time,
                     "status": list(self.status)})
        if self.has_band:
            for f in self.BANDS:
                cols.update(per_input(f.replace("_", " "), getattr(self, f)))
        index = pd.Index(self.ubar, name="ubar") if single else pd.MultiIndex.from_arrays(
            self.ubar.T, names=list(self.local_models[0].input_names))
        return pd.DataFrame(cols, index=index)

    def __repr__(self) -> str:
        ok = sum(s == "reached" for s in self.status)
        tau = self.time_constant[np.isfinite(self.time_constant)]
        span = f", τ in [{tau.min():.4g}, {tau.max():.4g}] s" if tau.size else ""
        return (f"OperatingCurve({self.model_name or 'model'}: {len(self.local_models)} points, {ok} reached{span}"
                + (f", band at {self.level:g}" if self.has_band else "") + ")")


def _summary(lm: LocalModel, settling: bool = True) -> tuple[float, np.ndarray, float, float, float, float]:
    """(ȳ, gain, τ, ζ, ρ, settling time) of one local model; NaN where it has no equilibrium (and for the settling
    time without ``settling``)."""
    m = len(lm.input_names)
    if not lm.exists:
        return np.nan, np.full(m, np.nan), np.nan, np.nan, np.nan, np.nan
    _, tau, zeta = lm._mode()
    return float(lm.ybar), lm.dc_gain, tau, zeta, lm.spectral_radius, lm.settling_time(0) if settling else np.nan


def operating_curve(model: Model, ubar: Sequence[float] | np.ndarray, *, Ts: float | None = None,
                    y0: float | Sequence[float] | np.ndarray | None = None,
                    data: Record | Dataset | Sequence[Record] | StaticPoints | None = None,
                    uncertainty: Any = None, n_samples: int = 500, seed: int = 0) -> OperatingCurve:
    """Local models over a grid of operating inputs: the model's gain, time constant and damping against ū.

    Parameters
    ----------
    model : Model
        A polynomial NARX model.
    ubar : array_like, shape (M,) or (M, m)
        Operating inputs (input units), columns in ``model.input_names`` order, or a dict or pandas
        DataFrame by input name (``{"flow": [2.0, 7.0], "inlet": [20.0, 20.0]}``); transient inputs left
        out are 0, their level at every steady state (levels of shape (M, 1), or (M,) for M ≠ m, for a
        one-input plant's model with them: m values could be one point as well, and are refused).
    Ts : float, optional
        Sampling period (s); default the model's own (``model.Ts``, the period it was identified at;
        ``data`` at another period is refused, and so is a ``Ts`` other than a model's own but for its 1 s, the
        period of records made without ``Ts=``), else ``data``'s. ``data`` at another period than a ``Ts`` given is
        refused too, but for records made without ``Ts=`` (1 s).
    y0 : float or array_like of shape (M,), optional
        Initial output of each point's settling run (see :func:`local_model`). Without it a point
        where the model has several stable equilibria gets the status ``"several stable equilibria"``
        (no local model there; its reason names them), and the curve goes on.
    data : Record, Dataset, sequence of Record or StaticPoints, optional
        The identification data: ū outside their range gets a :class:`~graybox.StaticRangeWarning`.
    uncertainty : ParameterUncertainty, optional
        The model's parameter covariance (:func:`graybox.ls_uncertainty` and the others): the
        gain and time-constant bands at its level are the quantiles of ``n_samples`` draws of θ
        around θ̂ with scale ``cov`` (multivariate t with its degrees of freedom, as its intervals),
        each at the equilibrium it reaches from the estimate's ȳ (NaN bands where the estimate
        itself reaches none). Draws that reach none are left out, and said with an
        :class:`~graybox.UncertaintyWarning` (the curve's ``undefined`` counts them).
    n_samples : int
        Monte Carlo draws for the bands.
    seed : int
        Seed of the draws.

    Returns
    -------
    OperatingCurve
        Draw it with :func:`graybox.plots.plot_operating_curve`.
    """
    model = check_polynomial(model, "operating_curve")
    n_samples, seed = check_count(n_samples, "n_samples", low=10), check_seed(seed)
    ub = _as_points(model, ubar)
    if uncertainty is not None:  # each draw's rows are M points × n_terms floats (_band): counted before any work
        check_count(n_samples, "n_samples", each=((ub.shape[0], "points"), (model.theta.size, "terms")))
    Ts_ = check_Ts(Ts, data, model)
    _range_warning(model, ub, data)
    lms = tuple(_linearise(model, u, y, Ts_, e) for u, y, e in zip(ub, _y0s(y0, ub.shape[0]), _equilibria_at(model, ub)))
    rows = [_summary(lm) for lm in lms]
    single = model.n_inputs == 1
    gain = np.array([r[1] for r in rows])
    fields: dict[str, Any] = {}
    if uncertainty is not None:
        # draws only where the estimate reaches its equilibrium: from an unstable one they run off to another
        ybar = np.array([r[0] if lm.reached else np.nan for r, lm in zip(rows, lms)])
        fields = _band(model, uncertainty, ub, ybar, Ts_, n_samples, seed, single)
    return OperatingCurve(lms, ub[:, 0] if single else ub, np.array([r[0] for r in rows]),
                          gain[:, 0] if single else gain, np.array([r[2] for r in rows]),
                          np.array([r[3] for r in rows]), np.array([r[4] for r in rows]),
                          np.array([r[5] for r in rows]), tuple(lm.status for lm in lms), model_name=model.name,
                          **fields)


def _band(model: Model, uncertainty: Any, ub: np.ndarray, ybar: np.ndarray, Ts: float, n: int, seed: int,
          single: bool) -> dict[str, Any]:
    """Monte Carlo quantiles of the gain and the time constant under θ drawn around θ̂ (multivariate t)."""
    # here: the estimators it loads cost a local model nothing
    from ..diagnostics._uncertainty import ParameterUncertainty, theta_draws, warn_dropped_draws

    if not isinstance(uncertainty, ParameterUncertainty):  # a wrong type, as everywhere: TypeError
        raise TypeError(f"uncertainty must be a ParameterUncertainty (e.g. graybox.ls_uncertainty(model, data)), got "
                        f"{type(uncertainty).__name__}")
    cov, um = uncertainty.cov, uncertainty.model
    if um.structure != model.structure:
        raise ValueError("uncertainty must be the ParameterUncertainty of this model (same structure), e.g. "
                         "graybox.ls_uncertainty(model, data)")
    if not np.array_equal(um.theta, model.theta):  # another estimate's covariance says nothing of this one's
        raise ValueError(f"uncertainty is that of the model {um.name!r}, whose θ differs from this model's "
                         f"({model.name!r}): give the ParameterUncertainty of this model (e.g. cls_uncertainty for "
                         "a CLS model, pe_uncertainty for a PE member)")
    th = model.theta
    rng = np.random.default_rng(seed)
    thetas = theta_draws(th, cov, n, rng, dof=uncertainty.dof, factor=uncertainty.cov_factor)  # t, as the intervals
    # the draws start from the estimate's equilibrium: where it has none, none is drawn and the band is NaN
    has = np.isfinite(ybar)
    M, full = int(has.sum()), ub.shape[0]
    glo, ghi = np.full((full, model.n_inputs), np.nan), np.full((full, model.n_inputs), np.nan)
    tlo, thi, undefined = np.full(full, np.nan), np.full(full, np.nan), np.full(full, np.nan)
    if M:
        sub = ub[has]
        r = _reached(model, thetas, sub, ybar[has])
        ok = r.status == REACHED  # (n, M)
        Y = np.where(ok, r.ybar, 0.0)
        a, b = jacobian_rows(model.structure, model.input_names, np.repeat(thetas, M, axis=0), Y.ravel(),
                             np.tile(sub, (n, 1)))
        rho = np.abs(characteristic_roots(a)).max(axis=1, initial=0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            tau = np.where(rho > 0, -Ts / np.log(rho), 0.0).reshape(n, M)
            gain = (b.sum(axis=2) / (1.0 - a.sum(axis=1))[:, None]).reshape(n, M, -1)
        tau = np.where(ok, tau, np.nan)
        gain = np.where(ok[:, :, None], gain, np.nan)
        q = (1 - uncertainty.level) / 2
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a point no draw reaches has an all-NaN column
            glo[has], ghi[has] = np.nanquantile(gain, [q, 1 - q], axis=0)
            tlo[has], thi[has] = np.nanquantile(tau, [q, 1 - q], axis=0)
        undefined[has] = 1.0 - ok.mean(axis=0)
        warn_dropped_draws("operating_curve", undefined)
    if single:
        glo, ghi = glo[:, 0], ghi[:, 0]
    return {"level": float(uncertainty.level), "gain_low": glo, "gain_high": ghi, "time_constant_low": tlo,
            "time_constant_high": thi, "undefined": undefined}
