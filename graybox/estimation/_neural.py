"""The neural NARMAX model of Section IV-A: a one-hidden-layer perceptron trained by Levenberg–Marquardt.

The paper identifies a neural NARMAX model with Norgaard's ``nnnarmax2`` (NNSYSID toolbox):
ny = nu = 6, ne = 2, seven tanh hidden nodes, one linear output node, 60 epochs of
Levenberg–Marquardt, and reports N_p = 99 in Table I, where it is the best dynamic model. This
module rebuilds that network. Its default training differs from the paper's, for the reasons
given under "Training".

Model
-----
In normalised units (see below) the network is

    ŷ(k) = w2ᵀ tanh(W1 x(k) + b1) + b2,
    x(k) = [y(k-1) … y(k-ny), u(k-1) … u(k-nu), e(k-1) … e(k-ne)],

with W1 of shape (hidden, ny + nu + ne). The residual inputs e(k-l) = y(k-l) − ŷ(k-l) are the
*current network's* one-step prediction errors, as in ``nnnarmax2``: they are fed back while the
network is trained and then dropped. Free run, the one-step :meth:`NeuralModel.predict`, the
static curve and the gain all use e ≡ 0, i.e. only the weights of the y and u inputs. This
mirrors the polynomial models, whose MA part helps estimation only and is not used in
simulation (Section IV-A).

Parameter count
---------------
N_p counts the weights the deterministic (e ≡ 0) model uses:

    N_p = hidden · (ny + nu)   input weights of y and u
        + hidden               hidden biases b1
        + hidden               output weights w2
        + 1                    output bias b2

For the paper's sizes 7 · 12 + 7 + 7 + 1 = 99, Table I's number. The hidden · ne residual
weights (14 here; 113 trained weights in all) are estimated but not counted, exactly as the MA
parameters of the polynomial models are not counted (17 and 23 in Table I). The normalisation
constants are fixed from the data, not estimated, and are not counted either.

Normalisation
-------------
Inputs and output are normalised internally to zero mean and unit standard deviation over the
training data, a held-out part excluded (u ≈ 10³ rpm would saturate every tanh node otherwise);
residuals are normalised with the output's scale. Every public method takes and returns engineering units.

Training (:func:`neural_narx`)
------------------------------
Three stages, each Levenberg–Marquardt on ½ Σ r² + ½ D ‖θ‖² (normalised units, D the weight
decay of Norgaard's toolbox) over the weights it trains:

1. *Prediction error*, as ``nnnarmax2``: r(k) = ŷ(k) − y(k) with the residuals of the current
   weights fed back (e = 0 before the first predicted sample of each record), all weights
   (``epochs``, default 10). The exact gradient obeys the time-varying recursion
   ψ(k) = ∂f/∂θ(k) − Σ_l c_l(k) ψ(k-l), c_l(k) = ∂f/∂e(k-l), because de(k-l)/dθ = −ψ(k-l)
   (the "filtering through C" of Norgaard's toolbox).
2. *Simulation error* (output error, Norgaard's ``nnoe``; the combined scheme of Connally et al.
   2007, the paper's ref. [21]): r(k) = ŷ_s(k) − y(k) with ŷ_s the free run from each record's
   first max(ny, nu) measured outputs, over the 99 weights a free run uses (``sim_epochs``,
   default 60). Its gradient obeys ψ(k) = ∂f/∂θ(k) + Σ_i a_i(k) ψ(k-i), a_i(k) = ∂f/∂y(k-i).
3. The residual-input weights re-fitted by prediction error to the final network (20 epochs),
   so that :meth:`NeuralModel.predict_narmax` belongs to it; they never enter a free run.

One epoch is one trial step (JᵀJ + (λ + D) I) h = −Jᵀr − Dθ (Norgaard's ``marq``): the step is
kept when the cost falls, λ (from 1) is halved when the actual reduction exceeds 3/4 of the
predicted one and doubled below 1/4; a stage has converged when the decrease a step predicts is the
cost's rounding (10⁻¹⁴ of it: whether such a step is kept would depend on the units). The normal
equations and their Cholesky solve are numba loops in a fixed order, with no BLAS call, so the
BLAS thread count cannot change a result; a seed (initial weights uniform in [−0.5, 0.5], Norgaard's choice, from
``numpy.random.default_rng(seed)``) gives the same network on every machine with the same numpy.
``scipy.optimize.least_squares`` with the same Jacobians was slower and reached higher costs
(BENCHMARKS.md, "Neural NARMAX training").

With ``holdout`` the last fraction of each record is kept out of training (and out of the
normalisation) and the last stage returns the weights with the lowest free-run MSE on it (early
stopping, optionally after ``patience`` steps without improvement). The default does not use it.

Why this default. On the bundled plant (``benchmarks/bench_neural.py``; validation record only
evaluated, never trained or stopped on; J in mlc², median [min–max] over seeds 0–4, ELS (15):
J_S valid 0.824):

- the paper's training (60 epochs of stage 1, D = 0) gives J_S valid 3.36 [0.79–5.14]. Epoch by
  epoch (seed 0) the one-step error J_1 ident is already 0.02 at epoch 15 while J_S valid is
  lowest there (0.63) and climbs to 5.14 by epoch 60: the one-step criterion, dominated by
  y(k-1), keeps fitting what a free run does not use (the transmitter noise and the fast head
  disturbance), and the free run drifts;
- early stopping on the last 20 % of the identification record helps (1.15 [0.86–1.91]) but
  cannot be trusted there: that part spans 950–1260 rpm only, and over 20 seeds its held-out
  cost ranks the networks' validation J_S poorly (Spearman 0.31). Weight decay in stage 1 does
  not help (D = 0.01: 2.96; D = 1: 3.47, the one-step fit itself fails);
- stage 2 without weight decay overfits the 99 weights to this record's realisation of the
  random slow disturbances: after 200 epochs J_S ident 0.37 (ELS (15): 0.876) and J_S valid 10.4;
- stage 2 with weight decay fixes it. D = 30 is the one-standard-error choice of 5-fold
  cross-validation over contiguous blocks of the identification record (D in 0 … 1000; the
  lowest CV error at D = 10, 1.94 ± 0.80 mlc², D = 30: 2.20). The default gives J_S ident 0.727
  [0.726–1.017], J_S valid 0.697 [0.605–0.698], J_SF 0.963 [0.959–1.214]: on validation, at most
  ELS (15)'s 0.824 for every seed; statically about as good as ELS (15) (J_SF 0.944), far from
  the paper's 0.0496, because the static points lie outside what the disturbed dynamic record
  shows (see :mod:`graybox.datasets.pumping`). Four seeds reach the same minimum, seed 0 a
  second one (J_S ident 1.02, J_S valid 0.60).

The price: the default network is a free-run model. Its one-step prediction with e ≡ 0 (J_1
ident 0.11–0.17) is worse than that of the paper's training (0.02–0.05). The paper's training
remains available as ``neural_narx(data, epochs=60, sim_epochs=0, weight_decay=0)``. These
choices were checked on the bundled stand-in plant only; a user's record may want another D
(cross-validate it as ``bench_neural.py --part cv`` does).

Static analysis
---------------
At constant input the deterministic model's steady state solves the scalar equation
ȳ = g(ȳ, ū) := f(ȳ … ȳ, ū … ū, 0 … 0). Because the output node is linear over bounded tanh
units, every real root lies in |ȳ − b2| ≤ Σ|w2| (normalised units): that interval is scanned on
a fine grid and each sign change is refined with Brent's method, so no equilibrium outside a
guessed bracket is missed. Local stability comes from the linearisation
y(k) = Σ_i a_i y(k-i), a_i = ∂f/∂y(k-i), decided by the package's one stability test (the
Schur–Cohn recursion, :func:`graybox.static._analysis.schur_stable`). A stable equilibrium always has
∂g/∂ȳ < 1, i.e. F = g − ȳ crosses zero downwards, so a tangent (double) root — which the grid can
miss — is never a stable one. Two distinct roots closer together than the grid spacing (2·10⁻³
normalised output units, i.e. 2·10⁻³ standard deviations of the training output, or finer; coarser
for an output range Σ|w2| beyond 200, where the scan stops at 200 001 points) can still be missed. The static output at a static point is, as for every model of the package, the
equilibrium a free run at constant ū from y0 settles on (:func:`graybox.static._analysis.settle`, the one
checked settling routine; tolerances in normalised units).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal, Sequence

from ..core._jit import nb
import numpy as np

from ..core._least_squares import output_spread
from ..core._records import (Dataset, Record, as_records, carried_from, check_fitted_on, check_units, require_lengths,
                             require_record)
from ..core._validation import (Relocked, check_bool, check_choice, check_int, check_per_point, check_real, check_seed,
                                check_str, frozen, check_fields, real_array, short_value)
from ..core._simulation import DivergenceError, default_bound, free_run_inputs
from ..core._simulation_kernels import kernel_array, record_inputs
from ..core._terms import check_input_names
from ..static._analysis import (NET, Equilibrium, Reached, one_input_levels, only_stable, point_phrases, schur_stable,
                                settle, spectral_radius, verdict_radius)
from ..core._reprs import point_texts, short_repr

__all__ = ["NeuralModel", "NeuralFit", "neural_narx"]

#: The paper's sizes (Section IV-A) and training length.
PAPER_NY, PAPER_NU, PAPER_NE, PAPER_HIDDEN, PAPER_EPOCHS = 6, 6, 2, 7, 60
#: Default training (module docstring, "Training"): prediction-error epochs, simulation-error
#: epochs, weight decay D (normalised units, on the sum of squares).
DEFAULT_EPOCHS, DEFAULT_SIM_EPOCHS, DEFAULT_WEIGHT_DECAY = 10, 60, 30.0
#: Trial steps of the final re-fit of the residual-input weights (a small, well-posed problem).
_RESIDUAL_EPOCHS = 20



def _frozen(a: np.ndarray, name: str, shape: tuple[int, ...]) -> np.ndarray:
    # the shared coercion: numpy's would parse text, drop an imaginary part and read True as 1 and None as NaN
    a = frozen(real_array(a, name))
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has non-finite values")
    return a


# ---------------------------------------------------------------------------
# Compiled kernels (normalised units, no validation: the Python layer validates)
# ---------------------------------------------------------------------------

@nb.njit(cache=True, nogil=True, inline="always")
def _net_output(W1, b1, w2, b2, y, un, e, k, ny, nu, ne, e_from):  # pragma: no cover - compiled
    """The network at sample k: past outputs y, inputs un, and residuals e(k-1-i) from e_from on."""
    s = b2
    for j in range(b1.size):
        a = b1[j]
        for i in range(ny):
            a += W1[j, i] * y[k - 1 - i]
        for i in range(nu):
            a += W1[j, ny + i] * un[k - 1 - i]
        for i in range(ne):
            if k - 1 - i >= e_from:
                a += W1[j, ny + nu + i] * e[k - 1 - i]
        s += w2[j] * np.tanh(a)
    return s


@nb.njit(cache=True, nogil=True)
def _free_run_kernel(W1, b1, w2, b2, un, y0n, ny, nu):  # pragma: no cover - compiled
    """Free run with e ≡ 0: the first L = max(ny, nu) outputs are y0n, shape (N,)."""
    N = un.size
    L = max(ny, nu)
    y = np.empty(N)
    for k in range(L):
        y[k] = y0n[k]
    for k in range(L, N):
        y[k] = _net_output(W1, b1, w2, b2, y, un, y, k, ny, nu, 0, 0)
    return y


@nb.njit(cache=True, nogil=True)
def _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne):  # pragma: no cover - compiled
    """NARMAX one-step prediction with residual feedback over records seg[r]:seg[r+1].

    Returns ŷ (NaN on each record's first L samples) and e = y − ŷ (0 there), shape (N,).
    """
    N = un.size
    L = max(ny, nu)
    yhat = np.full(N, np.nan)
    e = np.zeros(N)
    for r in range(seg.size - 1):
        a0 = seg[r] + L
        for k in range(a0, seg[r + 1]):
            s = _net_output(W1, b1, w2, b2, yn, un, e, k, ny, nu, ne, a0)
            yhat[k] = s
            e[k] = yn[k] - s
    return yhat, e


@nb.njit(cache=True, nogil=True)
def _pe_jacobian_kernel(W1, b1, w2, un, yn, e, seg, ny, nu, ne):  # pragma: no cover - compiled
    """ψ(k) = dŷ(k)/dθ on the training rows (each record's samples L …), shape (rows, P).

    θ = [W1 row-major, b1, w2, b2]; the residual feedback enters through
    ψ(k) −= c_l(k) ψ(k-l) with c_l(k) = ∂f/∂e(k-l).
    """
    H = b1.size
    n_in = ny + nu + ne
    P = H * n_in + 2 * H + 1
    L = max(ny, nu)
    rows = 0
    for r in range(seg.size - 1):
        rows += seg[r + 1] - seg[r] - L
    psi = np.zeros((rows, P))
    x = np.empty(n_in)
    d = np.empty(H)
    row = 0
    for r in range(seg.size - 1):
        a0 = seg[r] + L
        first = row
        for k in range(a0, seg[r + 1]):
            for i in range(ny):
                x[i] = yn[k - 1 - i]
            for i in range(nu):
                x[ny + i] = un[k - 1 - i]
            for i in range(ne):
                x[ny + nu + i] = e[k - 1 - i] if k - 1 - i >= a0 else 0.0
            for j in range(H):
                a = b1[j]
                for i in range(n_in):
                    a += W1[j, i] * x[i]
                h = np.tanh(a)
                d[j] = w2[j] * (1.0 - h * h)
                for i in range(n_in):
                    psi[row, j * n_in + i] = d[j] * x[i]
                psi[row, H * n_in + j] = d[j]
                psi[row, H * n_in + H + j] = h
            psi[row, P - 1] = 1.0
            for i in range(ne):
                prev = row - 1 - i
                if prev >= first:
                    c = 0.0
                    for j in range(H):
                        c += d[j] * W1[j, ny + nu + i]
                    for p in range(P):
                        psi[row, p] -= c * psi[prev, p]
            row += 1
    return psi


@nb.njit(cache=True, nogil=True)
def _sim_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, want_jac):  # pragma: no cover - compiled
    """Free run (e ≡ 0) of each record seg[r]:seg[r+1] from its first L = max(ny, nu) measured outputs.

    Returns the run ŷ, shape (N,) (the measured yn on each record's first L samples), and with
    ``want_jac`` ψ = dŷ/dθ_d on the rows k >= seg[r] + L, shape (rows, P_d), else shape (0, P_d).
    θ_d = [W1[:, :ny+nu] row-major, b1, w2, b2] are the weights the free run uses; ψ obeys
    ψ(k) = ∂f/∂θ_d(k) + Σ_i a_i(k) ψ(k-i) with a_i(k) = ∂f/∂y(k-i), restarting in each record.
    """
    H = b1.size
    n_d = ny + nu
    Pd = H * n_d + 2 * H + 1
    L = max(ny, nu)
    rows = 0
    for r in range(seg.size - 1):
        rows += seg[r + 1] - seg[r] - L
    ys = yn.copy()
    psi = np.zeros((rows if want_jac else 0, Pd))
    x = np.empty(n_d)
    d = np.empty(H)
    row = 0
    for r in range(seg.size - 1):
        first = row
        for k in range(seg[r] + L, seg[r + 1]):
            for i in range(ny):
                x[i] = ys[k - 1 - i]
            for i in range(nu):
                x[ny + i] = un[k - 1 - i]
            s = b2
            for j in range(H):
                a = b1[j]
                for i in range(n_d):
                    a += W1[j, i] * x[i]
                h = np.tanh(a)
                s += w2[j] * h
                if want_jac:
                    d[j] = w2[j] * (1.0 - h * h)
                    for i in range(n_d):
                        psi[row, j * n_d + i] = d[j] * x[i]
                    psi[row, H * n_d + j] = d[j]
                    psi[row, H * n_d + H + j] = h
            ys[k] = s
            if want_jac:
                psi[row, Pd - 1] = 1.0
                for i in range(ny):
                    prev = row - 1 - i
                    if prev >= first:
                        c = 0.0
                        for j in range(H):
                            c += d[j] * W1[j, i]
                        for p in range(Pd):
                            psi[row, p] += c * psi[prev, p]
            row += 1
    return ys, psi


@nb.njit(cache=True, nogil=True)
def _normal_equations(J, r):  # pragma: no cover - compiled
    """JᵀJ, shape (P, P), and −Jᵀr, shape (P,), accumulated row by row in a fixed order.

    No BLAS: the result cannot depend on the BLAS thread count or build, so a seed gives the
    same network on any machine.
    """
    n, P = J.shape
    R = np.zeros((P, P))
    G = np.zeros(P)
    for k in range(n):
        for p in range(P):
            v = J[k, p]
            G[p] -= v * r[k]
            for q in range(p + 1):
                R[p, q] += v * J[k, q]
    for p in range(P):
        for q in range(p):
            R[q, p] = R[p, q]
    return R, G


@nb.njit(cache=True, nogil=True)
def _damped_solve(R, G, mu):  # pragma: no cover - compiled
    """Solve (R + mu I) h = G by Cholesky (R symmetric positive semi-definite, mu > 0); NaN if rounding broke definiteness."""
    P = G.size
    C = np.zeros((P, P))
    for i in range(P):
        for j in range(i + 1):
            s = R[i, j] + (mu if i == j else 0.0)
            for k in range(j):
                s -= C[i, k] * C[j, k]
            if i == j:
                C[i, i] = np.sqrt(s) if s > 0.0 else np.nan
            else:
                C[i, j] = s / C[j, j]
    z = np.empty(P)
    for i in range(P):
        s = G[i]
        for k in range(i):
            s -= C[i, k] * z[k]
        z[i] = s / C[i, i]
    h = np.empty(P)
    for i in range(P - 1, -1, -1):
        s = z[i]
        for k in range(i + 1, P):
            s -= C[k, i] * h[k]
        h[i] = s / C[i, i]
    return h


# ---------------------------------------------------------------------------
# The model
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class NeuralModel(Relocked):
    """A one-hidden-layer tanh perceptron NAR(MA)X model as an immutable value.

    All weights act on normalised signals (see the module docstring); every method takes and
    returns engineering units. Arrays are read-only copies.

    Parameters
    ----------
    W1 : array_like, shape (hidden, ny + nu + ne)
        Hidden-layer weights; columns ordered y(k-1) … y(k-ny), u(k-1) … u(k-nu),
        e(k-1) … e(k-ne). The e columns are used in training only.
    b1 : array_like, shape (hidden,)
        Hidden-layer biases.
    w2 : array_like, shape (hidden,)
        Output weights (linear output node).
    b2 : float
        Output bias.
    ny, nu, ne : int
        Output, input and residual lags (ny >= 0, nu >= 1, ne >= 0).
    u_offset, u_scale : float
        Input normalisation: u_n = (u − u_offset) / u_scale (input units).
    y_offset, y_scale : float
        Output normalisation: y_n = (y − y_offset) / y_scale (output units); residuals use
        y_scale too.
    name : str
        Label for tables and plots.
    input_names : sequence of str
        The one input's name, as one name in a tuple (as :class:`~graybox.Model`'s): given a
        Record, the network reads that input of it, by name (default ``("u",)``).
    Ts : float, optional
        The sampling period (s) of the training records (:func:`neural_narx` sets it); a Record at
        another period is refused. None: unknown, not checked.
    units : (str, str), optional
        The units of (u, y) in the training records (:func:`neural_narx` sets them); a Record in other
        units is refused. Empty: unknown, not checked.
    """

    W1: np.ndarray
    b1: np.ndarray
    w2: np.ndarray
    b2: float
    ny: int
    nu: int
    ne: int = 0
    u_offset: float = 0.0
    u_scale: float = 1.0
    y_offset: float = 0.0
    y_scale: float = 1.0
    name: str = "Neural"
    input_names: tuple[str, ...] = ("u",)
    Ts: float | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_str(self.name, "name")
        if self.Ts is not None:
            object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        names = check_input_names(self.input_names)
        if len(names) != 1:
            raise ValueError(f"input_names: a network has one input, got {len(names)} names {names}")
        object.__setattr__(self, "input_names", names)
        object.__setattr__(self, "units", check_units(self.units, f"network {self.name!r}", 1))  # its one input's
        ny = check_int(self.ny, "ny", low=0)
        nu = check_int(self.nu, "nu", low=1)
        ne = check_int(self.ne, "ne", low=0)
        b1 = real_array(self.b1, "b1")
        if b1.ndim != 1 or b1.size == 0:
            raise ValueError(f"b1 must be 1-D with one bias per hidden node, got shape {b1.shape}")
        H = b1.size
        object.__setattr__(self, "ny", ny)
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "ne", ne)
        object.__setattr__(self, "W1", _frozen(self.W1, "W1", (H, ny + nu + ne)))
        object.__setattr__(self, "b1", _frozen(b1, "b1", (H,)))
        object.__setattr__(self, "w2", _frozen(self.w2, "w2", (H,)))
        object.__setattr__(self, "b2", check_real(self.b2, "b2"))
        for off in ("u_offset", "y_offset"):  # any level in the signal's units
            object.__setattr__(self, off, check_real(getattr(self, off), off))
        object.__setattr__(self, "u_scale", check_real(self.u_scale, "u_scale", low=0, low_open=True))
        object.__setattr__(self, "y_scale", check_real(self.y_scale, "y_scale", low=0, low_open=True))

    # -- basic facts --------------------------------------------------------
    @property
    def hidden(self) -> int:
        """Number of tanh hidden nodes."""
        return int(self.b1.size)

    @property
    def n_params(self) -> int:
        """N_p: weights used by the deterministic model, hidden·(ny+nu) + 2·hidden + 1.

        The hidden·ne residual-input weights are not counted (they are not used in simulation),
        as the MA parameters of the polynomial models are not: 99 for the paper's sizes.
        """
        return self.hidden * (self.ny + self.nu) + 2 * self.hidden + 1

    @property
    def n_trained(self) -> int:
        """All weights estimated in training, residual inputs included: hidden·(ny+nu+ne+2) + 1."""
        return self.hidden * (self.ny + self.nu + self.ne) + 2 * self.hidden + 1

    @property
    def max_lag(self) -> int:
        """max(ny, nu): the number of initial conditions of a free run."""
        return max(self.ny, self.nu)

    def with_name(self, name: str) -> "NeuralModel":
        """The same network under another label.

        Parameters
        ----------
        name : str
            The new label.

        Returns
        -------
        NeuralModel
        """
        return NeuralModel(self.W1, self.b1, self.w2, self.b2, self.ny, self.nu, self.ne,
                           self.u_offset, self.u_scale, self.y_offset, self.y_scale, name, self.input_names,
                           self.Ts, self.units)

    def check_record(self, record: Record) -> None:
        """``ValueError`` when ``record`` (or static points) was sampled at another period than the network was
        trained at, or is in other units where both name them (as :meth:`graybox.Model.check_record`).

        Parameters
        ----------
        record : Record or StaticPoints
            Its ``Ts`` (s) and units are compared with the network's.
        """
        check_fitted_on(self.Ts, self.units, f"network {self.name!r} was trained", record,
                        "its weights hold in those units only; convert the data", self.input_names)

    def _input(self, record: Record) -> np.ndarray:
        """The record's input the network reads, by name, shape (N,) (ValueError naming both when it lacks it, or
        when the record is sampled at another period or in other units than the network was trained on)."""
        self.check_record(record)
        return record_inputs(record, self.input_names)

    # -- normalisation ------------------------------------------------------
    def _un(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, float)
        if u.ndim > 1:  # several inputs: the compiled kernels would fail on them with a typing error
            raise ValueError(f"the network has one input; got {u.shape[1]} inputs (shape {u.shape}): pass a record "
                             "or an array of the one input it was trained on")
        return (u - self.u_offset) / self.u_scale

    def _yn(self, y: np.ndarray) -> np.ndarray:
        return (np.asarray(y, float) - self.y_offset) / self.y_scale

    def _y(self, yn: np.ndarray) -> np.ndarray:
        return self.y_offset + self.y_scale * np.asarray(yn, float)

    @property
    def _W1c(self) -> np.ndarray:
        return np.ascontiguousarray(self.W1)

    # -- dynamics -----------------------------------------------------------
    def predict(self, record: Record, *, horizon: int = 1) -> np.ndarray:
        """Prediction ``horizon`` samples ahead from measured data with e ≡ 0, shape (N,).

        One step (the default): ŷ(k) = f(y(k-1) … y(k-ny), u(k-1) … u(k-nu), 0 … 0), the
        deterministic model, as :meth:`graybox.Model.predict` uses only the process terms. A
        longer horizon runs the network freely from the outputs measured up to k − horizon, as
        :func:`graybox.predict` does for polynomial models: the samples before max_lag + horizon − 1
        are one free run from the first max_lag, and a horizon of the record's length is the free
        run. The first ``max_lag`` samples are the measured ones.

        Parameters
        ----------
        record : Record
            Measured data (input and output units), more than ``max_lag`` samples (``ValueError`` otherwise).
        horizon : int >= 1, keyword-only
            Samples ahead (default 1).

        Returns
        -------
        ndarray, shape (N,)
            Predicted output, output units.
        """
        require_record(record, call="model.predict(r)")  # a Dataset: told to pass data.ident or data.valid
        horizon = check_int(horizon, "horizon", low=1)
        L = self.max_lag
        record.require_length(L)
        N = len(record)
        first = L + horizon - 1  # samples before this have too few measured outputs behind them
        if first > L:
            free = self.simulate(record, on_diverge="nan")  # one free run from the first max_lag
            if first >= N:
                return free
        un, yn = self._un(self._input(record)), self._yn(record.y)
        Wd = self.W1[:, : self.ny + self.nu]
        # P[j][t]: the j-step prediction of y(t), normalised (P[0] the measured output). Each step is
        # one vectorised pass over the record: P[j][t] reads P[j - 1 - i][t - 1 - i] (the measured y
        # when j - 1 - i <= 0); only the last ny passes are kept.
        P = [yn]
        for j in range(1, (horizon if self.ny else 1) + 1):  # without output lags every horizon is one step
            X = np.empty((N - L, self.ny + self.nu))
            for i in range(self.ny):
                X[:, i] = (P[-1 - i] if j - 1 - i > 0 else yn)[L - 1 - i:N - 1 - i]
            for i in range(self.nu):
                X[:, self.ny + i] = un[L - 1 - i:N - 1 - i]
            step = yn.copy()
            step[L:] = np.tanh(X @ Wd.T + self.b1) @ self.w2 + self.b2
            P = (P + [step])[-max(self.ny, 1):]
        out = record.y.copy()
        out[L:] = self._y(P[-1][L:])
        if first > L:
            out[L:first] = free[L:first]
        return out

    def predict_narmax(self, record: Record) -> tuple[np.ndarray, np.ndarray]:
        """The training predictor over ``record``: one step ahead with the residuals fed back (``nnnarmax2``).

        Parameters
        ----------
        record : Record
            Measured data (input and output units), more than ``max_lag`` samples (``ValueError`` otherwise).

        Returns
        -------
        yhat : ndarray, shape (N,)
            One-step prediction; the first ``max_lag`` samples are the measured ones.
        e : ndarray, shape (N,)
            Residuals y − ŷ in output units (0 on the first ``max_lag`` samples).
        """
        require_record(record, call="model.predict_narmax(r)")  # a Dataset: told to pass data.ident or data.valid
        record.require_length(self.max_lag)
        un, yn = self._un(self._input(record)), self._yn(record.y)
        seg = np.array([0, len(record)], dtype=np.int64)
        yh, e = _pe_kernel(self._W1c, self.b1, self.w2, self.b2, un, yn, seg, self.ny, self.nu, self.ne)
        out = record.y.copy()
        L = self.max_lag
        out[L:] = self._y(yh[L:])
        return out, e * self.y_scale

    def simulate(
        self,
        u: np.ndarray | Record,
        y0: np.ndarray | None = None,
        *,
        on_diverge: Literal["raise", "nan"] = "raise",
        bound: float | None = None,
    ) -> np.ndarray:
        """Free run (e ≡ 0): the network feeds back its own past outputs.

        Same conventions as :func:`graybox.simulate`. The output of a tanh network
        with a linear output node is bounded (|ŷ_n − b2| ≤ Σ|w2|), so it never runs off to
        infinity; the bound check is kept for the shared contract (and for a small ``bound``).
        An oscillating (limit-cycle) free run is not reported as divergence: J_S measures it.

        Parameters
        ----------
        u : ndarray or pandas.DataFrame, shape (N,), or Record
            Input (input units). With a Record, ``y0`` defaults to its first ``max_lag`` outputs. A
            one-column DataFrame is read as :func:`graybox.simulate` reads one (its column named
            as the input, or not named as any).
        y0 : ndarray, shape (>= max_lag,), optional
            Initial outputs y(0) … y(L-1) (output units); only the first L = max_lag are used.
        on_diverge : {"raise", "nan"}
            When |y| exceeds ``bound``: raise :class:`~graybox.DivergenceError`
            naming the sample, or return NaN from that sample on.
        bound : float, optional
            Divergence bound on |y|, output units (default 1e6 × the larger of max|y0| and the
            network's output range |offset| + scale (|b2| + Σ|w2|), in the output's units as for
            polynomial models).

        Returns
        -------
        ndarray, shape (N,)
            Output units; the first ``max_lag`` samples are ``y0``.
        """
        check_choice(on_diverge, "on_diverge", ("raise", "nan"))
        L = self.max_lag
        if isinstance(u, Record):
            u, y0 = self._input(u), u.y[:L] if y0 is None else y0
        u, y0, b = free_run_inputs(u, y0, L, bound, what="network", names=self.input_names)
        if b is None:  # the default: from the network's output range, |offset| + scale (|b2| + Σ|w2|)
            reach = abs(self.y_offset) + abs(self.y_scale) * (abs(self.b2) + float(np.sum(np.abs(self.w2))))
            b = default_bound(y0, reach)
        yn = _free_run_kernel(self._W1c, self.b1, self.w2, self.b2, np.ascontiguousarray(self._un(u)),
                              np.ascontiguousarray(self._yn(y0)), self.ny, self.nu)
        y = self._y(yn)
        y[:L] = y0  # exact copy (no round trip through the normalisation)
        out = ~(np.abs(y[L:]) <= b)
        if out.any():
            k = L + int(np.flatnonzero(out)[0])
            if on_diverge == "raise":
                raise DivergenceError(f"free run diverged at sample {k} (|y| > {b:g}): the network is unstable along this input")
            y[k:] = np.nan
        return y

    # -- statics ------------------------------------------------------------
    def _static_parts(self, un: float) -> tuple[np.ndarray, np.ndarray]:
        """(a, c) with g(ȳ_n) = Σ_j w2_j tanh(a_j ȳ_n + c_j) + b2 at normalised input ``un``."""
        a = self.W1[:, : self.ny].sum(axis=1)
        c = self.b1 + un * self.W1[:, self.ny: self.ny + self.nu].sum(axis=1)
        return a, c

    def _equilibria_n(self, un: float) -> list[tuple[float, bool, float]]:
        """All real equilibria (ȳ_n, stable, spectral radius) at normalised input ``un``, sorted."""
        a, c = self._static_parts(un)
        if self.ny == 0:
            return [(float(np.tanh(c) @ self.w2 + self.b2), True, 0.0)]

        def F(y: np.ndarray | float) -> np.ndarray | float:
            return np.tanh(np.multiply.outer(y, a) + c) @ self.w2 + self.b2 - y

        if not np.any(a):  # ȳ cancels from the static equation (the lags' weights sum to 0): one root, whose local
            roots = [float(np.tanh(c) @ self.w2 + self.b2)]  # model may still be unstable (its a_i need not be 0)
        else:
            # every root lies where |ȳ_n - b2| <= Σ|w2| (bounded tanh units); the margin keeps the
            # end points strictly on the right sides
            r = float(np.abs(self.w2).sum())
            lo, hi = self.b2 - r - 1e-6 * (1 + r), self.b2 + r + 1e-6 * (1 + r)
            n = int(np.clip((hi - lo) / 2e-3, 2001, 200001))
            grid = np.linspace(lo, hi, n)
            f = F(grid)
            roots = [float(v) for v in grid[f == 0.0]]
            idx = np.flatnonzero((f[:-1] * f[1:]) < 0)
            from scipy.optimize import brentq  # slow to import: loaded where used
            for i in idx:
                roots.append(float(brentq(F, grid[i], grid[i + 1], xtol=1e-13, rtol=1e-13, maxiter=200)))
            roots.sort()
        lin = np.array([self._linearisation_n(yb, un) for yb in roots]).reshape(len(roots), self.ny)
        stable = schur_stable(lin)  # the package's one stability test
        return [(yb, bool(s), verdict_radius(bool(s), spectral_radius(ai))) for yb, s, ai in zip(roots, stable, lin)]

    def _linearisation_n(self, ybn: float, un: float) -> np.ndarray:
        """a_i = ∂f/∂y(k-i) at the equilibrium ȳ_n, i = 1..ny (dimensionless)."""
        a, c = self._static_parts(un)
        d = self.w2 * (1.0 - np.tanh(a * ybn + c) ** 2)
        return d @ self.W1[:, : self.ny]

    def equilibria(self, ubar: float) -> list[Equilibrium]:
        """Every real equilibrium at constant input ``ubar``, sorted by ȳ, with stability.

        Stability is decided by ``schur_stable`` on the linearisation (the test
        every model of the package uses); the spectral radius is given for information.

        Parameters
        ----------
        ubar : float
            One input level, input units.

        Returns
        -------
        list of Equilibrium
            Each real equilibrium ȳ (output units) with its stability and spectral radius.
        """
        ub = check_real(ubar, "ubar (one input level)")  # as Model.equilibria: a bool or a list is no level
        return [Equilibrium(ub, float(self._y(yb)), s, rho) for yb, s, rho in self._equilibria_n(self._un(ub))]

    def _settle_params(self, un: float) -> np.ndarray:
        """One row of coefficients of the free run at constant normalised input (see :func:`settle`)."""
        c = self.b1 + un * self.W1[:, self.ny: self.ny + self.nu].sum(axis=1)
        return np.concatenate([[self.b2], self.w2, c, self.W1[:, : self.ny].ravel()])

    def static_curve(self, ubar: np.ndarray, y0: float | np.ndarray | None = None, *, strict: bool = True) -> np.ndarray:
        """The steady state the network reaches at each constant input, shape (M,).

        Conventions of :func:`graybox.static_curve`. With ``y0``: the equilibrium a free run at
        constant ū, with every initial output equal to ``y0``, settles on (the package's one
        settling routine, ``settle``, checks that it does). Without it: the
        stable equilibrium when there is exactly one.

        Parameters
        ----------
        ubar : array_like, shape (M,)
            Constant input levels (input units).
        y0 : float or array_like of shape (M,), optional
            Initial output (output units), one for all ū or one per ū.
        strict : bool
            True: a ū where no equilibrium is reached (none is stable, the run does not settle;
            or several are stable and no ``y0``) raises ``ValueError`` naming ū. False: NaN there.

        Returns
        -------
        ndarray, shape (M,)
            Output units.
        """
        strict = check_bool(strict, "strict")
        ub = one_input_levels(ubar)
        y0s = None
        if y0 is not None:
            y0s = check_per_point(y0, ub.size, "y0")
        eqs = [self._equilibria_n(self._un(u_)) for u_ in ub]
        D = max((len(e) for e in eqs), default=0)
        roots = np.full((ub.size, D), np.nan)  # normalised
        stable = np.zeros((ub.size, D), bool)
        for i, e in enumerate(eqs):
            roots[i, : len(e)] = [yb for yb, _, _ in e]
            stable[i, : len(e)] = [s for _, s, _ in e]
        if y0s is not None:
            fp = np.array([self._settle_params(self._un(u_)) for u_ in ub])
            ip = np.array([self.hidden, self.ny], dtype=np.int64)
            yn, status = settle(NET, ip, fp, self._yn(y0s), roots, stable, self.ny, floor=1.0)
            out = np.where(status == 0, self._y(yn), np.nan)
            if strict and np.any(status != 0):
                res = Reached(ub, np.asarray(y0s, float), out[None, :], status[None, :])
                raise ValueError("the network reaches no equilibrium at " + point_phrases(res.explain(0)))
            return out
        # the polynomial model's rule and phrases (each ū named, equilibria to 6 significant digits)
        out, problems = only_stable(self._y(roots), stable, [f"ū = {u_}" for u_ in point_texts(ub)])
        if strict and problems:
            raise ValueError("the network has " + point_phrases(problems))
        return out

    def static_gain(self, ubar: np.ndarray, y0: float | np.ndarray | None = None, *, strict: bool = True) -> np.ndarray:
        """dȳ/dū along the static curve at each ū of ``ubar``.

        Implicit differentiation of ȳ = g(ȳ, ū): dȳ/dū = g_ū / (1 − g_ȳ).

        Parameters
        ----------
        ubar : array_like, shape (M,)
            Constant input levels (input units).
        y0 : float or array_like of shape (M,), optional
            As for :meth:`static_curve` (output units).
        strict : bool
            As for :meth:`static_curve` (False: NaN where no equilibrium is reached).

        Returns
        -------
        ndarray, shape (M,)
            Output units per input unit.
        """
        ub = one_input_levels(ubar)
        yb = self.static_curve(ub, y0=y0, strict=strict)
        out = np.full(ub.size, np.nan)
        wu = self.W1[:, self.ny: self.ny + self.nu].sum(axis=1)
        for i, (u_, y_) in enumerate(zip(ub, yb)):
            if not np.isfinite(y_):
                continue
            un, ybn = self._un(u_), self._yn(y_)
            a, c = self._static_parts(un)
            d = self.w2 * (1.0 - np.tanh(a * ybn + c) ** 2)
            out[i] = (self.y_scale / self.u_scale) * float(d @ wu) / (1.0 - float(d @ a))
        return out

    # -- printing -----------------------------------------------------------
    def __str__(self) -> str:
        head = f"{self.name}: " if self.name else ""
        kind = "NARMAX" if self.ne else "NARX"
        inputs = ([f"y(k-1..{self.ny})"] if self.ny else []) + [f"u(k-1..{self.nu})"] + (
            [f"e(k-1..{self.ne})"] if self.ne else [])  # no y(k-1..0) for a network without output lags
        return (f"{head}neural {kind} MLP, y(k) = w2ᵀ tanh(W1 [{', '.join(inputs)}] + b1) + b2, "
                f"{self.hidden} tanh hidden nodes, 1 linear output; N_p = {self.n_params}"
                + (f" (+{self.hidden * self.ne} residual-input weights used in training only)" if self.ne else "")
                + f"; normalisation u: ({self.u_offset:.6g}, {self.u_scale:.6g}), y: ({self.y_offset:.6g}, {self.y_scale:.6g})")

    def __repr__(self) -> str:
        period = "" if self.Ts is None else f", Ts={self.Ts:g} s"
        return (f"NeuralModel(name={self.name!r}, input={self.input_names[0]!r}, ny={self.ny}, nu={self.nu}, "
                f"ne={self.ne}, hidden={self.hidden}, n_params={self.n_params}{period})")


# ---------------------------------------------------------------------------
# Training
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class NeuralFit(Relocked):
    """The result of :func:`neural_narx`: the trained network and how the training went.

    Costs are in normalised units (output divided by its standard deviation over the training
    data); held-out costs are free-run mean square errors in output units², as J_S.

    Attributes
    ----------
    model : NeuralModel
        The trained network.
    prediction_cost : tuple of float
        Stage 1 (one-step NARMAX prediction error): ½ Σ e_n² + ½ D ‖θ‖² at the initial weights
        and after each accepted step.
    simulation_cost : tuple of float
        Stage 2 (free-run simulation error): ½ Σ (ŷ_n − y_n)² + ½ D ‖θ_d‖² at its start and after
        each accepted step; empty when ``sim_epochs = 0``.
    holdout_cost : tuple of float
        Free-run MSE of the held-out data (output units²) at the start of the last stage and after
        each of its accepted steps; empty without ``holdout``.
    best_step : int or None
        Index into ``holdout_cost`` of the weights returned (early stopping); None without
        ``holdout``.
    epochs : int
        Levenberg–Marquardt trial steps (Norgaard's epochs) over all stages.
    stopped : str
        Why the last training stage ended (stage 2, or stage 1 when ``sim_epochs = 0``; the refit of the
        residual-input weights that follows stage 2 when ``ne > 0`` is not one): "epochs" (its budget), "converged" (a vanishing gradient, a
        step that predicts a decrease within the cost's rounding, or a damping so large that no step
        lowers the cost), "patience" (early stopping: ``patience`` accepted steps without a lower
        held-out cost) or "unstable" (the sensitivity recursion overflowed; the weights reached before are kept).
    rmse_train : float
        Root mean square one-step residual of the NARMAX predictor on the training rows, output units.
    rmse_sim : float
        Root mean square free-run error on the training rows (from each record's first
        max(ny, nu) measured outputs), output units.
    seconds : float
        Wall-clock training time.
    """

    model: NeuralModel
    prediction_cost: tuple[float, ...]
    simulation_cost: tuple[float, ...]
    holdout_cost: tuple[float, ...]
    best_step: int | None
    epochs: int
    stopped: str
    rmse_train: float
    rmse_sim: float
    seconds: float

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape

    def __post_init__(self) -> None:
        check_fields(self)
        # what a training can report (a file edited by hand, a result built wrong is refused, as OEResult's)
        check_int(self.epochs, "NeuralFit: epochs", low=0)
        check_choice(self.stopped, "NeuralFit: stopped", STOP_REASONS)
        if not self.prediction_cost:
            raise ValueError("NeuralFit: prediction_cost holds at least stage 1's cost at the initial weights")
        for name in ("prediction_cost", "simulation_cost", "holdout_cost", "rmse_train", "rmse_sim"):
            v = np.asarray(getattr(self, name), dtype=float)
            if np.any(np.isnan(v)) or np.any(v < 0):  # inf: a figure beyond the float range in huge output units
                raise ValueError(f"NeuralFit: {name} holds sums or means of squares, never negative or NaN; got "
                                 f"{short_value(getattr(self, name))}")
        accepted = len(self.prediction_cost) - 1 + max(len(self.simulation_cost) - 1, 0)
        if self.epochs < accepted:  # each accepted step is a trial step
            raise ValueError(f"NeuralFit: epochs counts the trial steps of every stage, at least the {accepted} "
                             f"accepted ones its costs record; got {self.epochs}")
        last = self.simulation_cost or self.prediction_cost  # the stage the held-out costs were taken along
        if self.holdout_cost and len(self.holdout_cost) != len(last):
            raise ValueError(f"NeuralFit: holdout_cost holds one held-out cost per cost of the last stage "
                             f"({len(last)}, {'simulation' if self.simulation_cost else 'prediction'}_cost); got "
                             f"{len(self.holdout_cost)}")
        if self.holdout_cost:
            if self.best_step is None or not 0 <= self.best_step < len(self.holdout_cost):
                raise ValueError(f"NeuralFit: best_step indexes holdout_cost ({len(self.holdout_cost)} values); got "
                                 f"{self.best_step!r}")
        elif self.best_step is not None or self.stopped == "patience":
            raise ValueError(f"NeuralFit: without holdout_cost there is no early stopping (best_step None, stopped "
                             f"not 'patience'); got best_step={self.best_step!r}, stopped={self.stopped!r}")
        if not (self.seconds >= 0 and np.isfinite(self.seconds)):
            raise ValueError(f"NeuralFit: seconds is a training time, finite and >= 0; got {self.seconds!r}")


#: Why a training stage ended (NeuralFit.stopped).
STOP_REASONS = ("epochs", "converged", "patience", "unstable")


def _unpack(theta: np.ndarray, H: int, n_in: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    W1 = theta[: H * n_in].reshape(H, n_in)
    b1 = theta[H * n_in: H * n_in + H]
    w2 = theta[H * n_in + H: H * n_in + 2 * H]
    # read-only, as a fitted model's weights are: the kernels then compile once for both (kernel_array)
    return kernel_array(W1), kernel_array(b1.copy()), kernel_array(w2.copy()), float(theta[-1])


def _deterministic(H: int, ny: int, nu: int, ne: int) -> np.ndarray:
    """Mask over θ = [W1 row-major, b1, w2, b2] of the weights a free run uses (all but the e inputs)."""
    n_in = ny + nu + ne
    det = np.ones(H * (n_in + 2) + 1, bool)
    for j in range(H):
        det[j * n_in + ny + nu: (j + 1) * n_in] = False
    return det


@dataclass(frozen=True, eq=False)
class _Signals:
    """Records concatenated in normalised units, with the training-row mask (each record's samples L …)."""

    un: np.ndarray
    yn: np.ndarray
    seg: np.ndarray
    rows: np.ndarray

    @classmethod
    def of(cls, recs: list[Record], L: int, u_off: float, u_sc: float, y_off: float, y_sc: float) -> "_Signals":
        un = np.ascontiguousarray((np.concatenate([r.u for r in recs]) - u_off) / u_sc)
        yn = np.ascontiguousarray((np.concatenate([r.y for r in recs]) - y_off) / y_sc)
        seg = np.cumsum([0] + [len(r) for r in recs]).astype(np.int64)
        rows = np.ones(yn.size, bool)
        for a in seg[:-1]:
            rows[a: a + L] = False
        return cls(un, yn, seg, rows)


@dataclass
class _Stage:
    """What one training stage did."""

    x: np.ndarray
    epochs: int
    cost: list[float]
    holdout: list[float]
    best: int | None
    stopped: str


def _sumsq(r: np.ndarray) -> float:
    """Σ r² by numpy's pairwise summation (no BLAS: independent of the thread count)."""
    return float(np.sum(r * r))


#: Levenberg–Marquardt damping: Norgaard's start, and the λ beyond which no step can lower the cost.
_LAMBDA0, _LAMBDA_MAX = 1.0, 1e12
#: A predicted decrease below this fraction of the cost is rounding (a few ulps of V): the stage has converged.
_ROUNDING = 1e-14


def _run_stage(residual, jacobian, x0: np.ndarray, *, max_epochs: int, decay: float,
               heldout=None, patience: int | None = None) -> _Stage:
    """Levenberg–Marquardt on ½ ‖r(x)‖² + ½ decay ‖x‖², as Norgaard's ``marq``.

    ``residual(x)`` gives r, shape (rows,); ``jacobian(x)`` gives dr/dx, shape (rows, x.size). One
    epoch is one trial step (JᵀJ + (λ + decay) I) h = −Jᵀr − decay·x; the step is kept when the
    cost falls, and λ is halved when the actual reduction exceeds 3/4 of the predicted one and
    doubled below 1/4; a step whose predicted decrease is within ``_ROUNDING`` of the cost ends the
    stage (converged) without counting as an epoch. ``heldout(x)`` (optional) is the held-out cost,
    taken at the start and after each kept step: the stage then returns the point where it was lowest and stops after
    ``patience`` kept steps without a new lowest.
    """
    x = np.array(x0, dtype=float)
    lam = _LAMBDA0
    r = residual(x)
    V = 0.5 * _sumsq(r) + 0.5 * decay * _sumsq(x)
    cost = [V]
    held: list[float] = []
    best: tuple[float, np.ndarray, int] = (np.inf, x, 0)
    if heldout is not None:
        held.append(float(heldout(x)))
        best = (held[0], x, 0)
    stopped = "epochs"
    need_jac = True
    epochs = 0
    while epochs < max_epochs:
        if need_jac:
            J = jacobian(x)
            if not np.all(np.isfinite(J)):  # the sensitivity recursion blew up along the data
                stopped = "unstable"
                break
            R, G = _normal_equations(np.ascontiguousarray(J), np.ascontiguousarray(r))
            G -= decay * x  # G = −∇V
            need_jac = False
            if np.sqrt(_sumsq(G)) <= 1e-12 * (1.0 + np.sqrt(2.0 * V)):
                stopped = "converged"
                break
        h = _damped_solve(R, G, lam + decay)
        predicted = 0.5 * (float(np.sum(h * G)) + lam * _sumsq(h))  # decrease of the quadratic model
        if predicted <= _ROUNDING * V:
            # no step can lower V by more than its rounding: converged. Trial steps on would be kept or refused by
            # the rounding alone, which differs with the signals' units (their count, epochs, did)
            stopped = "converged"
            break
        epochs += 1
        if not np.all(np.isfinite(h)):  # R + (λ + D) I lost positive definiteness to rounding
            lam *= 2.0
            continue
        x_new = x + h
        r_new = residual(x_new)
        V_new = 0.5 * _sumsq(r_new) + 0.5 * decay * _sumsq(x_new)
        actual = V - V_new
        if actual > 0.75 * predicted:
            lam /= 2.0
        elif actual <= 0.25 * predicted:
            lam *= 2.0
        if V_new < V:
            x, r, V = x_new, r_new, V_new
            cost.append(V)
            need_jac = True
            if heldout is not None:
                held.append(float(heldout(x)))
                if held[-1] < best[0]:
                    best = (held[-1], x, len(held) - 1)
                elif patience is not None and len(held) - 1 - best[2] >= patience:
                    stopped = "patience"
                    break
        if lam > _LAMBDA_MAX:
            stopped = "converged"
            break
    if heldout is not None:
        return _Stage(best[1], epochs, cost, held, best[2], stopped)
    return _Stage(x, epochs, cost, held, None, stopped)


def _level_and_scale(x: np.ndarray, what: str) -> tuple[float, float]:
    """Mean and standard deviation of a training signal (its units), for the normalisation; ``ValueError`` when it is
    constant to round-off (not std > 0: the mean of a held 1000.1 is not 1000.1, and its std, 2e-13, is no scale).
    Computed in units of max|x|: the squares of values near 1e200 overflowed (std inf: a network blind to its
    input), those of values near 1e-200 underflowed (std 0)."""
    top = float(np.max(np.abs(x)))
    z = x / top if top > 0 else x
    if top == 0 or output_spread(z) == 0:
        raise ValueError(f"the {what} is constant over the training data: nothing to identify (and no scale to "
                         "normalise with)")
    return float(z.mean()) * top, float(z.std()) * top


def _split_holdout(recs: list[Record], holdout: float, L: int) -> tuple[list[Record], list[Record]]:
    """Each record's last ``holdout`` fraction held out (contiguous), the rest for training."""
    if holdout == 0.0:
        return recs, []
    train, held = [], []
    for i, r in enumerate(recs):
        n = len(r)
        h = int(round(holdout * n))
        if h <= L or n - h <= L:
            # of several, by position too: records made or loaded without a name are all called "record"
            which = f"record {i + 1} of {len(recs)} ({r.name!r}, {n} samples)" if len(recs) > 1 else \
                f"record {r.name!r} ({n} samples)"
            raise ValueError(f"holdout = {holdout:g} of {which} leaves {n - h} training and {h} held-out samples; "
                             f"each part needs more than max(ny, nu) = {L}")
        train.append(r.slice(0, n - h))
        held.append(r.slice(n - h, n))
    return train, held


def neural_narx(
    data: Record | Dataset | Sequence[Record],
    *,
    ny: int = PAPER_NY,
    nu: int = PAPER_NU,
    ne: int = PAPER_NE,
    hidden: int = PAPER_HIDDEN,
    epochs: int = DEFAULT_EPOCHS,
    sim_epochs: int = DEFAULT_SIM_EPOCHS,
    weight_decay: float = DEFAULT_WEIGHT_DECAY,
    holdout: float = 0.0,
    patience: int | None = None,
    seed: int = 0,
    name: str = "Neural",
) -> NeuralFit:
    """Train the neural NARMAX model: prediction error (``nnnarmax2``), then simulation error.

    Stage 1 minimises the one-step NARMAX prediction error as Norgaard's ``nnnarmax2`` does
    (residual inputs fed back, all weights trained); stage 2 minimises the free-run simulation
    error of the weights the free run uses; stage 3 re-fits the residual-input weights to the
    final network by prediction error. Every stage adds the weight decay ½ D ‖θ‖² and runs
    Levenberg–Marquardt (Norgaard's ``marq``) with the exact Jacobian. The module docstring
    says why this is the default and how to get the paper's training (``epochs=60,
    sim_epochs=0, weight_decay=0``).

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        Training data (a Dataset contributes its identification record). With several records
        no regressor straddles two of them and the residual feedback and the free run restart in
        each.
    ny, nu : int
        Output and input lags (ny >= 0, nu >= 1); the input enters as u(k-1) … u(k-nu).
    ne : int
        Residual inputs e(k-1) … e(k-ne) (NARMAX, training only); 0 trains a NARX network.
    hidden : int
        Tanh hidden nodes (>= 1).
    epochs : int
        Stage 1 trial steps (Norgaard's epochs, >= 1; the paper used 60).
    sim_epochs : int
        Stage 2 trial steps (>= 0; 0 skips stages 2 and 3: the paper's training).
    weight_decay : float
        D >= 0 of the cost ½ Σ r² + ½ D ‖θ‖², r and θ in normalised units (Norgaard's ``D``,
        on the sum of squares over the training rows, not their mean).
    holdout : float
        Fraction in [0, 0.5) of each record, at its end, held out of training for early
        stopping: the last stage returns the weights with the lowest free-run MSE on the held-out
        parts (default 0: no early stopping, every sample trains).
    patience : int, optional
        With ``holdout``: stop the last stage after this many accepted steps (>= 1) without a
        lower held-out cost (default: run its whole budget and keep the best).
    seed : int
        Seed of ``numpy.random.default_rng`` for the initial weights (uniform in [−0.5, 0.5]).
    name : str
        Label of the returned model.

    Returns
    -------
    NeuralFit
        ``.model`` is the trained network; the other fields say how the training went.

    Raises
    ------
    ValueError
        Bad sizes or options, a record not longer than max(ny, nu) (or a holdout that leaves
        either part that short), fewer training rows than weights, or a constant input or
        output (no scale to normalise with).

    Notes
    -----
    On the bundled plant data (``graybox.load_pumping()``, seeds 0–4) the paper's training gives
    a validation free-run J_S of 3.36 mlc² (median; 0.79–5.14), against 0.82 for ELS (15): the
    one-step criterion keeps improving while the free run drifts. The default gives 0.70
    (0.61–0.70). D = 30 was chosen by cross-validation on the identification record. Evidence:
    BENCHMARKS.md, "Neural NARMAX training" (``benchmarks/bench_neural.py``).
    """
    recs = as_records(data)
    several = [r for r in recs if r.n_inputs > 1]
    if several:
        raise ValueError(f"neural_narx takes one input; the record {several[0].name!r} has the inputs "
                         f"{several[0].input_names} (the neural baseline is single-input)")
    ny = check_int(ny, "ny", low=0)
    nu = check_int(nu, "nu", low=1)
    ne = check_int(ne, "ne", low=0)
    hidden = check_int(hidden, "hidden", low=1)
    epochs = check_int(epochs, "epochs", low=1)
    sim_epochs = check_int(sim_epochs, "sim_epochs", low=0)
    D = check_real(weight_decay, "weight_decay", low=0)
    holdout = check_real(holdout, "holdout", low=0, high=0.5, high_open=True)
    if patience is not None:
        if holdout == 0.0:
            raise ValueError("patience applies to early stopping only: pass holdout > 0 with it")
        patience = check_int(patience, "patience", low=1)
    seed = check_seed(seed)
    name = check_str(name, "name")
    L = max(ny, nu)
    require_lengths(recs, L)
    train, held = _split_holdout(recs, holdout, L)
    n_in = ny + nu + ne
    P = hidden * (n_in + 2) + 1
    n_rows = sum(len(r) - L for r in train)
    if n_rows < P:
        raise ValueError(f"{n_rows} training samples (after the first max(ny, nu) = {L} of each record"
                         + (" and the held-out parts" if held else "") + f") are fewer than the {P} weights "
                         "to estimate; use more data or a smaller network")
    u = np.concatenate([r.u for r in train])
    y = np.concatenate([r.y for r in train])
    u_off, u_sc = _level_and_scale(u, "input")
    y_off, y_sc = _level_and_scale(y, "output")
    sig = _Signals.of(train, L, u_off, u_sc, y_off, y_sc)
    hsig = _Signals.of(held, L, u_off, u_sc, y_off, y_sc) if held else None
    det = _deterministic(hidden, ny, nu, ne)
    t0 = time.perf_counter()

    def with_(theta: np.ndarray, mask: np.ndarray, x: np.ndarray) -> np.ndarray:
        t = theta.copy()
        t[mask] = x
        return t

    def pe_residual(theta: np.ndarray) -> np.ndarray:
        W1, b1, w2, b2 = _unpack(theta, hidden, n_in)
        e = _pe_kernel(W1, b1, w2, b2, sig.un, sig.yn, sig.seg, ny, nu, ne)[1]
        return -e[sig.rows]

    def pe_jacobian(theta: np.ndarray) -> np.ndarray:
        W1, b1, w2, b2 = _unpack(theta, hidden, n_in)
        e = _pe_kernel(W1, b1, w2, b2, sig.un, sig.yn, sig.seg, ny, nu, ne)[1]
        return _pe_jacobian_kernel(W1, b1, w2, sig.un, sig.yn, e, sig.seg, ny, nu, ne)

    def sim(theta: np.ndarray, s: _Signals, want_jac: bool) -> tuple[np.ndarray, np.ndarray]:
        W1, b1, w2, b2 = _unpack(theta, hidden, n_in)
        ys, psi = _sim_kernel(W1, b1, w2, b2, s.un, s.yn, s.seg, ny, nu, want_jac)
        return (ys - s.yn)[s.rows], psi

    def heldout(theta: np.ndarray) -> float:  # normalised: in output units² it under- or overflows in tiny or huge units
        assert hsig is not None
        r = sim(theta, hsig, False)[0]
        return _sumsq(r) / r.size

    theta = np.random.default_rng(seed).uniform(-0.5, 0.5, P)  # Norgaard's initialisation: rand − 0.5
    last_pe = sim_epochs == 0
    s1 = _run_stage(pe_residual, pe_jacobian, theta, max_epochs=epochs, decay=D,
                    heldout=heldout if (held and last_pe) else None, patience=patience)
    theta, n_epochs, stages = s1.x, s1.epochs, [s1]
    if sim_epochs:
        th1 = theta  # the residual-input weights stay as stage 1 left them
        s2 = _run_stage(lambda x: sim(with_(th1, det, x), sig, False)[0],
                        lambda x: sim(with_(th1, det, x), sig, True)[1],
                        th1[det], max_epochs=sim_epochs, decay=D,
                        heldout=(lambda x: heldout(with_(th1, det, x))) if held else None, patience=patience)
        theta = with_(th1, det, s2.x)
        stages.append(s2)
        n_epochs += s2.epochs
        if ne:
            # the residual-input weights, trained in stage 1 alongside other weights, re-fitted
            # to the final network (they never enter a free run)
            th2 = theta
            s3 = _run_stage(lambda x: pe_residual(with_(th2, ~det, x)),
                            lambda x: pe_jacobian(with_(th2, ~det, x))[:, ~det],
                            th2[~det], max_epochs=_RESIDUAL_EPOCHS, decay=D)
            theta = with_(th2, ~det, s3.x)
            n_epochs += s3.epochs
    last = stages[-1]
    W1, b1, w2, b2 = _unpack(theta, hidden, n_in)
    model = NeuralModel(W1, b1, w2, b2, ny, nu, ne, u_off, u_sc, y_off, y_sc, name,
                        **carried_from(recs))
    r_pe = pe_residual(theta)
    r_sim = sim(theta, sig, False)[0]
    return NeuralFit(
        model=model,
        prediction_cost=tuple(s1.cost),
        simulation_cost=tuple(stages[1].cost) if sim_epochs else (),
        holdout_cost=tuple(c * y_sc * y_sc for c in last.holdout),  # not y_sc ** 2: a float power raises on overflow
        best_step=last.best,
        epochs=n_epochs,
        stopped=last.stopped,
        rmse_train=float(np.sqrt(np.mean(r_pe ** 2)) * y_sc),
        rmse_sim=float(np.sqrt(np.mean(r_sim ** 2)) * y_sc),
        seconds=time.perf_counter() - t0,
    )
