"""The neural NARMAX baseline of Section IV-A: a one-hidden-layer perceptron trained by Levenberg–Marquardt.

The paper identifies a neural NARMAX model with Norgaard's ``nnnarmax2`` (NNSYSID toolbox):
ny = nu = 6, ne = 2, seven tanh hidden nodes, one linear output node, 60 epochs of
Levenberg–Marquardt, and reports N_p = 99 in Table I. This module rebuilds that model.

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
training data (u ≈ 10³ rpm would saturate every tanh node otherwise); residuals are normalised
with the output's scale. Every public method takes and returns engineering units.

Training (:func:`neural_narx`)
------------------------------
Prediction-error training as ``nnnarmax2`` does it: minimise ½ Σ_k e(k)² (+ ½ D ‖θ‖² with the
optional weight decay D) over all 113 weights, where e(k) is computed recursively with the
residuals of the current weights fed back (e = 0 before the first predicted sample of each
record). The gradient is exact: the derivative of ŷ(k) with respect to the weights obeys the
time-varying recursion

    ψ(k) = ∂f/∂θ(k) − Σ_l c_l(k) ψ(k-l),   c_l(k) = ∂f/∂e(k-l),

because de(k-l)/dθ = −ψ(k-l) (the "filtering through C" of Norgaard's toolbox). The
Levenberg–Marquardt loop follows Norgaard's ``marq``: one epoch is one trial step
(JᵀJ + (λ + D) I) h = Jᵀe − Dθ; the step is kept when the cost falls, and λ is halved when the
actual reduction exceeds 3/4 of the predicted one and doubled below 1/4. With ne = 0 the same
code trains a plain NARX network (series-parallel, one-step prediction error). Initial weights
are uniform in [−0.5, 0.5] (Norgaard's choice), drawn from ``numpy.random.default_rng(seed)``:
a seed gives the same network on every machine with the same numpy.

Static analysis
---------------
At constant input the deterministic model's steady state solves the scalar equation
ȳ = g(ȳ, ū) := f(ȳ … ȳ, ū … ū, 0 … 0). Because the output node is linear over bounded tanh
units, every real root lies in |ȳ − b2| ≤ Σ|w2| (normalised units): that interval is scanned on
a fine grid and each sign change is refined with Brent's method, so no equilibrium outside a
guessed bracket is missed. Local stability comes from the linearisation
y(k) = Σ_i a_i y(k-i), a_i = ∂f/∂y(k-i), decided by the package's one stability test (the
Schur–Cohn recursion, :func:`graybox._static.schur_stable`). A stable equilibrium always has
∂g/∂ȳ < 1, i.e. F = g − ȳ crosses zero downwards, so a tangent (double) root — which the grid can
miss — is never a stable one. Two distinct roots closer together than the grid spacing (2·10⁻³
normalised output units, i.e. 2·10⁻³ standard deviations of the training output, or finer) can
still be missed. The static output at a static point is, as for every model of the package, the
equilibrium a free run at constant ū from y0 settles on (:func:`graybox._static.settle`, the one
checked settling routine; tolerances in normalised units).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal, Sequence

import numba as nb
import numpy as np
from scipy.optimize import brentq

from ._records import Dataset, Record, as_records
from ._validation import as_1d_finite, check_choice, check_int, check_per_point, check_real, frozen
from ._simulation import DivergenceError, free_run_inputs
from ._static import NET, Equilibrium, Reached, schur_stable, settle, spectral_radius

__all__ = ["NeuralModel", "NeuralFit", "neural_narx"]

#: The paper's sizes (Section IV-A) and training length.
PAPER_NY, PAPER_NU, PAPER_NE, PAPER_HIDDEN, PAPER_EPOCHS = 6, 6, 2, 7, 60



def _frozen(a: np.ndarray, name: str, shape: tuple[int, ...]) -> np.ndarray:
    a = frozen(a)
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
def _normal_equations(psi, r):  # pragma: no cover - compiled
    """ψᵀψ, shape (P, P), and ψᵀr, shape (P,), accumulated row by row in a fixed order.

    Done here rather than with BLAS: the result does not depend on the BLAS thread count (a
    seed gives the same network on any machine), and a multi-threaded BLAS on a busy shared
    machine was slower than this loop for P ≈ 100.
    """
    n, P = psi.shape
    R = np.zeros((P, P))
    G = np.zeros(P)
    for k in range(n):
        for p in range(P):
            v = psi[k, p]
            G[p] += v * r[k]
            for q in range(p + 1):
                R[p, q] += v * psi[k, q]
    for p in range(P):
        for q in range(p):
            R[q, p] = R[p, q]
    return R, G


@nb.njit(cache=True, nogil=True)
def _damped_solve(R, G, mu):  # pragma: no cover - compiled
    """Solve (R + mu I) h = G by Cholesky (R symmetric positive semi-definite, mu > 0)."""
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
class NeuralModel:
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

    def __post_init__(self) -> None:
        ny = check_int(self.ny, "ny", low=0)
        nu = check_int(self.nu, "nu", low=1)
        ne = check_int(self.ne, "ne", low=0)
        b1 = np.asarray(self.b1, dtype=float)
        if b1.ndim != 1 or b1.size == 0:
            raise ValueError(f"b1 must be 1-D with one bias per hidden node, got shape {b1.shape}")
        H = b1.size
        object.__setattr__(self, "ny", ny)
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "ne", ne)
        object.__setattr__(self, "W1", _frozen(self.W1, "W1", (H, ny + nu + ne)))
        object.__setattr__(self, "b1", _frozen(b1, "b1", (H,)))
        object.__setattr__(self, "w2", _frozen(self.w2, "w2", (H,)))
        b2 = float(self.b2)
        if not np.isfinite(b2):
            raise ValueError(f"b2 must be finite, got {self.b2!r}")
        object.__setattr__(self, "b2", b2)
        for off in ("u_offset", "y_offset"):
            v = float(getattr(self, off))
            if not np.isfinite(v):
                raise ValueError(f"{off} must be finite, got {v!r}")
            object.__setattr__(self, off, v)
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
        """The same network under another label."""
        return NeuralModel(self.W1, self.b1, self.w2, self.b2, self.ny, self.nu, self.ne,
                           self.u_offset, self.u_scale, self.y_offset, self.y_scale, name)

    # -- normalisation ------------------------------------------------------
    def _un(self, u: np.ndarray) -> np.ndarray:
        return (np.asarray(u, float) - self.u_offset) / self.u_scale

    def _yn(self, y: np.ndarray) -> np.ndarray:
        return (np.asarray(y, float) - self.y_offset) / self.y_scale

    def _y(self, yn: np.ndarray) -> np.ndarray:
        return self.y_offset + self.y_scale * np.asarray(yn, float)

    @property
    def _W1c(self) -> np.ndarray:
        return np.ascontiguousarray(self.W1)

    # -- dynamics -----------------------------------------------------------
    def predict(self, record: Record) -> np.ndarray:
        """One-step-ahead prediction from measured data with e ≡ 0, shape (N,).

        ŷ(k) = f(y(k-1) … y(k-ny), u(k-1) … u(k-nu), 0 … 0): the deterministic model, as
        :meth:`graybox.Model.predict` uses only the process terms. The first ``max_lag``
        samples are the measured ones.
        """
        if not isinstance(record, Record):
            raise ValueError(f"record must be a Record, got {type(record).__name__}")
        L = self.max_lag
        record.require_length(L)
        N = len(record)
        un, yn = self._un(record.u), self._yn(record.y)
        # lagged inputs, shape (N-L, ny+nu): column i of the y block is y(k-1-i)
        X = np.empty((N - L, self.ny + self.nu))
        for i in range(self.ny):
            X[:, i] = yn[L - 1 - i:N - 1 - i]
        for i in range(self.nu):
            X[:, self.ny + i] = un[L - 1 - i:N - 1 - i]
        Wd = self.W1[:, : self.ny + self.nu]
        out = record.y.copy()
        out[L:] = self._y(np.tanh(X @ Wd.T + self.b1) @ self.w2 + self.b2)
        return out

    def predict_narmax(self, record: Record) -> tuple[np.ndarray, np.ndarray]:
        """The training predictor: one step ahead with the residuals fed back (``nnnarmax2``).

        Returns
        -------
        yhat : ndarray, shape (N,)
            One-step prediction; the first ``max_lag`` samples are the measured ones.
        e : ndarray, shape (N,)
            Residuals y − ŷ in output units (0 on the first ``max_lag`` samples).
        """
        if not isinstance(record, Record):
            raise ValueError(f"record must be a Record, got {type(record).__name__}")
        record.require_length(self.max_lag)
        un, yn = self._un(record.u), self._yn(record.y)
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
        u : ndarray, shape (N,), or Record
            Input (input units). With a Record, ``y0`` defaults to its first ``max_lag`` outputs.
        y0 : ndarray, shape (>= max_lag,), optional
            Initial outputs y(0) … y(L-1) (output units); only the first L = max_lag are used.
        on_diverge : {"raise", "nan"}
            When |y| exceeds ``bound``: raise :class:`~graybox.DivergenceError`
            naming the sample, or return NaN from that sample on.
        bound : float, optional
            Divergence bound on |y| (default 1e6 · (1 + max|y0|), as for polynomial models).

        Returns
        -------
        ndarray, shape (N,)
            Output units; the first ``max_lag`` samples are ``y0``.
        """
        check_choice(on_diverge, "on_diverge", ("raise", "nan"))
        L = self.max_lag
        u, y0, b = free_run_inputs(u, y0, L, bound, what="network")
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
        if self.ny == 0 or not np.any(a):
            yb = float(np.tanh(c) @ self.w2 + self.b2)
            return [(yb, True, 0.0)]

        def F(y: np.ndarray | float) -> np.ndarray | float:
            return np.tanh(np.multiply.outer(y, a) + c) @ self.w2 + self.b2 - y

        # every root lies where |ȳ_n - b2| <= Σ|w2| (bounded tanh units); the margin keeps the
        # end points strictly on the right sides
        r = float(np.abs(self.w2).sum())
        lo, hi = self.b2 - r - 1e-6 * (1 + r), self.b2 + r + 1e-6 * (1 + r)
        n = int(np.clip((hi - lo) / 2e-3, 2001, 200001))
        grid = np.linspace(lo, hi, n)
        f = F(grid)
        roots: list[float] = [float(v) for v in grid[f == 0.0]]
        idx = np.flatnonzero((f[:-1] * f[1:]) < 0)
        for i in idx:
            roots.append(float(brentq(F, grid[i], grid[i + 1], xtol=1e-13, rtol=1e-13, maxiter=200)))
        roots.sort()
        lin = np.array([self._linearisation_n(yb, un) for yb in roots]).reshape(len(roots), self.ny)
        stable = schur_stable(lin)  # the package's one stability test
        return [(yb, bool(s), spectral_radius(ai)) for yb, s, ai in zip(roots, stable, lin)]

    def _linearisation_n(self, ybn: float, un: float) -> np.ndarray:
        """a_i = ∂f/∂y(k-i) at the equilibrium ȳ_n, i = 1..ny (dimensionless)."""
        a, c = self._static_parts(un)
        d = self.w2 * (1.0 - np.tanh(a * ybn + c) ** 2)
        return d @ self.W1[:, : self.ny]

    def equilibria(self, ubar: float) -> list[Equilibrium]:
        """Every real equilibrium at constant input ``ubar`` (input units), sorted by ȳ, with stability.

        Stability is decided by :func:`graybox._static.schur_stable` on the linearisation (the test
        every model of the package uses); the spectral radius is given for information.
        """
        ub = float(as_1d_finite([ubar], "ubar")[0])
        return [Equilibrium(ub, float(self._y(yb)), s, rho) for yb, s, rho in self._equilibria_n(self._un(ub))]

    def _settle_params(self, un: float) -> np.ndarray:
        """One row of coefficients of the free run at constant normalised input (see :func:`settle`)."""
        c = self.b1 + un * self.W1[:, self.ny: self.ny + self.nu].sum(axis=1)
        return np.concatenate([[self.b2], self.w2, c, self.W1[:, : self.ny].ravel()])

    def static_curve(self, ubar: np.ndarray, y0: float | np.ndarray | None = None, strict: bool = True) -> np.ndarray:
        """The steady state the network reaches at each constant input, shape (M,).

        Conventions of :func:`graybox.static_curve`. With ``y0``: the equilibrium a free run at
        constant ū, with every initial output equal to ``y0``, settles on (the package's one
        settling routine, :func:`graybox._static.settle`, checks that it does). Without it: the
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
        ub = np.atleast_1d(as_1d_finite(np.ravel(ubar), "ubar"))
        y0s = None
        if y0 is not None:
            y0s = check_per_point(y0, ub.size, "y0")
        out = np.full(ub.size, np.nan)
        eqs = [self._equilibria_n(self._un(u_)) for u_ in ub]
        if y0s is not None:
            D = max(len(e) for e in eqs)
            roots = np.full((ub.size, D), np.nan)
            stable = np.zeros((ub.size, D), bool)
            for i, e in enumerate(eqs):
                roots[i, : len(e)] = [yb for yb, _, _ in e]
                stable[i, : len(e)] = [s for _, s, _ in e]
            fp = np.array([self._settle_params(self._un(u_)) for u_ in ub])
            ip = np.array([self.hidden, self.ny], dtype=np.int64)
            yn, status = settle(NET, ip, fp, self._yn(y0s), roots, stable, self.ny, floor=1.0)
            out = np.where(status == 0, self._y(yn), np.nan)
            if strict and np.any(status != 0):
                res = Reached(ub, np.asarray(y0s, float), out[None, :], status[None, :])
                raise ValueError("the network reaches no equilibrium at " + "; ".join(res.explain(0)))
            return out
        for i, u_ in enumerate(ub):
            stable_n = [yb for yb, s, _ in eqs[i] if s]
            if len(stable_n) == 1:
                out[i] = self._y(stable_n[0])
            elif strict and not stable_n:
                raise ValueError(f"the network has no stable equilibrium at ū = {u_:g}")
            elif strict:
                raise ValueError(
                    f"the network has {len(stable_n)} stable equilibria at ū = {u_:g} "
                    f"({[round(float(self._y(s)), 6) for s in stable_n]}); pass y0 to choose the one reached from it")
        return out

    def static_gain(self, ubar: np.ndarray, y0: float | np.ndarray | None = None, strict: bool = True) -> np.ndarray:
        """dȳ/dū along the static curve, shape (M,), output units per input unit.

        Implicit differentiation of ȳ = g(ȳ, ū): dȳ/dū = g_ū / (1 − g_ȳ).
        """
        ub = np.atleast_1d(as_1d_finite(np.ravel(ubar), "ubar"))
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
        return (f"{head}neural {kind} MLP, y(k) = w2ᵀ tanh(W1 [y(k-1..{self.ny}), u(k-1..{self.nu})"
                + (f", e(k-1..{self.ne})" if self.ne else "") + f"] + b1) + b2, "
                f"{self.hidden} tanh hidden nodes, 1 linear output; N_p = {self.n_params}"
                + (f" (+{self.hidden * self.ne} residual-input weights used in training only)" if self.ne else "")
                + f"; normalisation u: ({self.u_offset:.6g}, {self.u_scale:.6g}), y: ({self.y_offset:.6g}, {self.y_scale:.6g})")

    def __repr__(self) -> str:
        return (f"NeuralModel(name={self.name!r}, ny={self.ny}, nu={self.nu}, ne={self.ne}, "
                f"hidden={self.hidden}, n_params={self.n_params})")


# ---------------------------------------------------------------------------
# Training
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class NeuralFit:
    """The result of :func:`neural_narx`: the trained network and how the training went.

    Attributes
    ----------
    model : NeuralModel
        The trained network.
    epochs : int
        Trial steps taken (each is one epoch, accepted or not).
    cost : tuple of float
        Training cost ½ Σ e_n² + ½ D ‖θ‖² (normalised units) after each epoch (the kept value).
    lam : tuple of float
        λ after each epoch.
    accepted : int
        Steps that lowered the cost.
    stopped : str
        Why the loop ended ("epochs", "gradient", "lambda").
    rmse_train : float
        Root mean square one-step residual of the NARMAX predictor at the end, output units.
    seconds : float
        Wall-clock training time.
    """

    model: NeuralModel
    epochs: int
    cost: tuple[float, ...]
    lam: tuple[float, ...]
    accepted: int
    stopped: str
    rmse_train: float
    seconds: float


def _unpack(theta: np.ndarray, H: int, n_in: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    W1 = theta[: H * n_in].reshape(H, n_in)
    b1 = theta[H * n_in: H * n_in + H]
    w2 = theta[H * n_in + H: H * n_in + 2 * H]
    return np.ascontiguousarray(W1), b1.copy(), w2.copy(), float(theta[-1])


def neural_narx(
    data: Record | Dataset | Sequence[Record],
    *,
    ny: int = PAPER_NY,
    nu: int = PAPER_NU,
    ne: int = PAPER_NE,
    hidden: int = PAPER_HIDDEN,
    epochs: int = PAPER_EPOCHS,
    seed: int = 0,
    weight_decay: float = 0.0,
    lam0: float = 1.0,
    name: str = "Neural",
) -> NeuralFit:
    """Train the neural NARMAX baseline (Norgaard's ``nnnarmax2``) by Levenberg–Marquardt.

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        Training data (a Dataset contributes its identification record). With several records
        no regressor straddles two of them and the residual feedback restarts in each.
    ny, nu : int
        Output and input lags (ny >= 0, nu >= 1); the input enters as u(k-1) … u(k-nu).
    ne : int
        Residual inputs e(k-1) … e(k-ne) (NARMAX, training only); 0 trains a NARX network.
    hidden : int
        Tanh hidden nodes (>= 1).
    epochs : int
        Levenberg–Marquardt trial steps (Norgaard's iterations; >= 1).
    seed : int
        Seed of ``numpy.random.default_rng`` for the initial weights (uniform in [−0.5, 0.5]).
    weight_decay : float
        D >= 0 of the cost ½ Σ e_n² + ½ D ‖θ‖² (normalised units; Norgaard's ``D``, default 0).
    lam0 : float
        Initial Levenberg–Marquardt λ (> 0; Norgaard's default 1).
    name : str
        Label of the returned model.

    Returns
    -------
    NeuralFit
        ``.model`` is the trained network; the other fields say how the training went.

    Raises
    ------
    ValueError
        Bad sizes, a record not longer than max(ny, nu), fewer training rows than weights,
        a constant input or output (no scale to normalise with), or training that produced
        non-finite weights.
    """
    recs = as_records(data)
    ny = check_int(ny, "ny", low=0)
    nu = check_int(nu, "nu", low=1)
    ne = check_int(ne, "ne", low=0)
    hidden = check_int(hidden, "hidden", low=1)
    epochs = check_int(epochs, "epochs", low=1)
    seed = check_int(seed, "seed", low=0)
    D = float(weight_decay)
    if not (np.isfinite(D) and D >= 0):
        raise ValueError(f"weight_decay must be a finite number >= 0, got {weight_decay!r}")
    lam = check_real(lam0, "lam0", low=0, low_open=True)
    L = max(ny, nu)
    for r in recs:
        r.require_length(L)
    n_in = ny + nu + ne
    P = hidden * (n_in + 2) + 1
    rows = sum(len(r) - L for r in recs)
    if rows < P:
        raise ValueError(f"{rows} training samples (after the first max(ny, nu) = {L} of each record) "
                         f"are fewer than the {P} weights to estimate; use more data or a smaller network")
    u = np.concatenate([r.u for r in recs])
    y = np.concatenate([r.y for r in recs])
    u_off, u_sc = float(u.mean()), float(u.std())
    y_off, y_sc = float(y.mean()), float(y.std())
    if not u_sc > 0:
        raise ValueError("the input is constant over the training data: nothing to identify (and no scale to normalise with)")
    if not y_sc > 0:
        raise ValueError("the output is constant over the training data: nothing to identify (and no scale to normalise with)")
    un = np.ascontiguousarray((u - u_off) / u_sc)
    yn = np.ascontiguousarray((y - y_off) / y_sc)
    seg = np.cumsum([0] + [len(r) for r in recs]).astype(np.int64)
    mask = np.ones(y.size, bool)
    for a in seg[:-1]:
        mask[a: a + L] = False
    t0 = time.perf_counter()

    rng = np.random.default_rng(seed)
    theta = rng.uniform(-0.5, 0.5, P)  # Norgaard's initialisation: rand − 0.5 for every weight

    def residuals(th: np.ndarray) -> tuple[np.ndarray, float]:
        W1, b1, w2, b2 = _unpack(th, hidden, n_in)
        _, e = _pe_kernel(W1, b1, w2, b2, un, yn, seg, ny, nu, ne)
        r = e[mask]
        with np.errstate(over="ignore", invalid="ignore"):
            V = 0.5 * float(r @ r) + 0.5 * D * float(th @ th)
        return e, (V if np.isfinite(V) else np.inf)

    e, V = residuals(theta)
    if not np.isfinite(V):
        raise ValueError("the initial network gives non-finite residuals (check the data)")
    costs: list[float] = []
    lams: list[float] = []
    accepted = 0
    stopped = "epochs"
    need_jac = True
    for _ in range(epochs):
        if need_jac:
            W1, b1, w2, _b2 = _unpack(theta, hidden, n_in)
            psi = _pe_jacobian_kernel(W1, b1, w2, un, yn, e, seg, ny, nu, ne)
            if not np.all(np.isfinite(psi)):
                # the residual feedback (the "C filter") became unstable along the data
                stopped = "gradient"
                break
            R, G = _normal_equations(psi, np.ascontiguousarray(e[mask]))
            G -= D * theta  # G = −∇V
            need_jac = False
            if np.linalg.norm(G) <= 1e-12 * (1.0 + np.sqrt(2.0 * V)):
                stopped = "gradient"
                break
        h = _damped_solve(R, G, lam + D)
        if not np.all(np.isfinite(h)):  # R + (λ+D)I lost positive definiteness to rounding
            lam *= 2.0
            costs.append(V)
            lams.append(lam)
            continue
        theta_new = theta + h
        e_new, V_new = residuals(theta_new)
        predicted = 0.5 * (float(h @ G) + lam * float(h @ h))  # decrease of the quadratic model
        actual = V - V_new
        if actual > 0.75 * predicted:
            lam /= 2.0
        elif actual <= 0.25 * predicted:
            lam *= 2.0
        if V_new < V:
            theta, e, V = theta_new, e_new, V_new
            accepted += 1
            need_jac = True
        costs.append(V)
        lams.append(lam)
        if lam > 1e12:
            stopped = "lambda"
            break
    if not np.all(np.isfinite(theta)):
        raise ValueError("training produced non-finite weights")
    W1, b1, w2, b2 = _unpack(theta, hidden, n_in)
    model = NeuralModel(W1, b1, w2, b2, ny, nu, ne, u_off, u_sc, y_off, y_sc, name)
    return NeuralFit(model, len(costs), tuple(costs), tuple(lams), accepted, stopped,
                           float(np.sqrt(np.mean(e[mask] ** 2)) * y_sc), time.perf_counter() - t0)
