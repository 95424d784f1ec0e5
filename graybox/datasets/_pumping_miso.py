r"""The two-pump rig with the pump sets at independent speeds: a MISO benchmark plant.

The bundled rig (:mod:`graybox.datasets.pumping`) runs both pump sets at one speed. Here each set
has its own drive and speed reference, r₁ and r₂ (rpm), and the pressure at the turbine is the one
output (mlc). Everything else is the bundled rig's, taken from a :class:`~graybox.datasets.PumpingPlant`
(``rig``): the same motors, pumps, pipe, turbine characteristic, transmitter noise and process
disturbances. With r₁ = r₂ it *is* the bundled rig: the same equations, the same static curve
eq. (1), the same response to the same noise (tests/test_pumping_miso.py checks all three).

Physical model
--------------
State x = (n_c1, n_1, n_c2, n_2, Q). Units as in :mod:`graybox.datasets.pumping`.

1. **Two drives and two rotors**, each the bundled rig's equations with its own reference:
   ``dn_ci/dt = (r_i(t − θ) − n_ci) / τ_v`` and ``J' dn_i/dt = k_s (n_ci − n_i) + c (n_ci² − n_i²)``.
2. **Two pumps in parallel into one header**, each behind a non-return valve: pump i delivers
   q_i ≥ 0 against the header head H_h with ``H_h = A_i − h_2 q_i²``, A_i = (1 − a) h_0 n_i²
   (the air loss a is common: one sump), while its valve is open; its valve closes (q_i = 0)
   when ``A_i ≤ H_h``. The pump branches are short next to the pipe, so their water is taken as
   massless: given the total flow Q = q_1 + q_2 the split and H_h follow algebraically. With
   s = √h_2 Q and d = A_1 − A_2, both valves are open when s² ≥ |d|, and then
   √h_2 q_1 = (s + d/s)/2, √h_2 q_2 = (s − d/s)/2, H_h = A_1 − (s + d/s)²/4; otherwise only the
   faster pump delivers, H_h = max(A_1, A_2) − s². At n_1 = n_2 this is the bundled rig's
   H_h = (1 − a) h_0 n² − h_2 (Q/2)². No square root of a negative number appears anywhere.
3. **One water column** as in the bundled rig: ``I dQ/dt = H_h − R_f Q² − H_t(Q) + w + s``,
   with the bundled rig's turbine characteristic H_t (calibrated to eq. (1) at equal speeds, with
   its low-flow branch) and its non-return behaviour at Q = 0 (the column stops, never reverses).
4. **Disturbances**: the bundled rig's fast head disturbance w, surge s and air loss a. The slow
   two are driven by the mean shaft-speed change of the two sets, (|Δn_1| + |Δn_2|)/2 per sample
   (the change of flow pattern in the shared sump), which is the bundled rig's |Δn| at equal speeds.
   The noise sequences are drawn in the bundled rig's order, so one seed gives both plants the
   same disturbances.

Static surface
--------------
At constant references the equilibrium flow solves H_h(Q; n̄_1, n̄_2) − R_f Q² = H_t(Q): the left
side falls and the right side rises with Q, so the root is unique, and p̄ = H_t(Q̄)
(:meth:`TwoSpeedPumpingPlant.static_pressure`). p̄ rises with each speed while both valves are
open. When one pump is much slower than the other its valve stays shut: its shut-off head
h_0 n̄_i² is below the header head the faster pump holds, and p̄ then depends on the faster speed
alone (flat in the slower one). For the default rig the slower pump's valve shuts below about
0.64 times the faster speed (1062 rpm against 1650 rpm, 740 against 1200).

Operating range
---------------
The simulator accepts references in the rig's ``speed_range`` (500–1800 rpm) for each set, in any
combination, and never fails there (flows go to zero, never negative; tests/test_pumping_miso.py
checks random staircases with hypothesis). The benchmark data keep each reference within
``OPERATING_RANGE`` = 1150–1650 rpm, where both valves are open at every steady state (the corner
(1150, 1650) keeps 5.4 L/s through the slower pump): the static surface is smooth there, and a
quadratic in (n̄_1, n̄_2) fits it to within 0.1 mlc (about 0.013 mlc rms), against a static-point
noise of about 0.03 mlc. (Over 750–1650 rpm the shut-valve regions make the surface kinked, and no
low-degree polynomial fits it to better than 2 mlc.)

Run ``python -m graybox.datasets._pumping_miso`` to regenerate the bundled CSVs in
``data/pumping_miso`` (see :func:`main`).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

from ..core._jit import nb
import numpy as np

from ..core._records import Record, StaticPoints, frame_inputs
from ..core._validation import Relocked, as_1d_finite, check_real, locked, real_array
from .pumping import (DEFAULT_SEED, PumpingPlant, _staircase, check_plant, check_static_levels, initial_state,
                      reference_lengths, regenerate_main, static_samples, static_speeds, write_csv_pair)
from ..core._reprs import short_repr

#: The plant's inputs, as its records and static points name them: speed references of sets 1 and 2.
_INPUTS = ("u1", "u2")

__all__ = [
    "TwoSpeedPumpingPlant",
    "TwoSpeedRun",
    "PlantSurface",
    "two_speed_reference",
    "static_grid",
    "static_grid_experiment",
    "generate_miso",
    "write_miso_csvs",
    "main",
    "OPERATING_RANGE",
    "STATIC_SPEEDS_MISO",
    "N_SAMPLES_MISO",
    "N_IDENT_MISO",
]

#: Range of each speed reference in the benchmark data (rpm): both valves open at every steady state.
OPERATING_RANGE = (1150.0, 1650.0)
#: Speeds of each set in the static grid (rpm): 1150, 1250, …, 1650 (36 points).
STATIC_SPEEDS_MISO = tuple(float(s) for s in range(1150, 1651, 100))
#: Samples in the dynamic record; the first N_IDENT_MISO identify, the rest validate.
N_SAMPLES_MISO = 6000
N_IDENT_MISO = 4800

#: CSV column names of the bundled files.
DYNAMIC_COLUMNS_MISO = ("time_s", "speed1_ref_rpm", "speed2_ref_rpm", "pressure_mlc")
STATIC_COLUMNS_MISO = ("speed1_rpm", "speed2_rpm", "pressure_mlc")


@dataclass(frozen=True, eq=False)
class TwoSpeedRun(Relocked):
    """The result of one simulation of :class:`TwoSpeedPumpingPlant`, sampled at t = k Ts.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Time stamps (s), starting at 0.
    u : ndarray, shape (N, 2)
        Speed references r₁, r₂ (rpm) applied over [t_k, t_k + Ts).
    y : ndarray, shape (N,)
        Measured pressure (mlc): true pressure + transmitter noise.
    pressure : ndarray, shape (N,)
        True pressure H_t(Q) (mlc).
    speed : ndarray, shape (N, 2)
        Shaft speeds n₁, n₂ (rpm).
    flow : ndarray, shape (N,)
        Total flow Q (L/s).
    pump_flow : ndarray, shape (N, 2)
        Flow through each pump (L/s), >= 0; they add up to ``flow``.
    Ts : float
        Sampling period (s).
    surge : ndarray, shape (N,)
        Transient head disturbance over [t_k, t_k + Ts) (mlc of head).
    air_loss : ndarray, shape (N,)
        Fraction of the pumps' head lost to air over [t_k, t_k + Ts).
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    pressure: np.ndarray
    speed: np.ndarray
    flow: np.ndarray
    pump_flow: np.ndarray
    Ts: float
    surge: np.ndarray
    air_loss: np.ndarray

    def __post_init__(self) -> None:
        for name in ("t", "u", "y", "pressure", "speed", "flow", "pump_flow", "surge", "air_loss"):
            a = np.array(getattr(self, name), dtype=float, copy=True)
            object.__setattr__(self, name, locked(a))  # a run is a value

    def record(self, name: str = "pumping_miso") -> Record:
        """The measured inputs/output as a two-input :class:`~graybox.Record` (inputs ``u1``, ``u2`` in rpm; mlc).

        Parameters
        ----------
        name : str
            The record's name.

        Returns
        -------
        Record
            N samples at ``Ts``, inputs ``u1``, ``u2`` (rpm), output the pressure (mlc).
        """
        return Record(self.u, self.y, Ts=self.Ts, name=name, units=("rpm", "mlc"), input_names=("u1", "u2"))

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


@dataclass(frozen=True)
class TwoSpeedPumpingPlant:
    """The bundled rig with its two pump sets at independent speeds (see the module docs).

    Parameters
    ----------
    rig : PumpingPlant
        Every physical constant, the noise and the disturbances (default: the bundled rig). Its
        ``speed_range`` bounds each reference. The two drives have no ramps: a rig with a finite
        ``ramp_up`` or ``ramp_down`` is refused rather than run without them.
    """

    rig: PumpingPlant = field(default_factory=PumpingPlant)

    def __post_init__(self) -> None:
        if not isinstance(self.rig, PumpingPlant):
            raise TypeError(f"TwoSpeedPumpingPlant: rig must be a PumpingPlant, got {type(self.rig).__name__}")
        if math.isfinite(self.rig.ramp_up) or math.isfinite(self.rig.ramp_down):
            raise ValueError("TwoSpeedPumpingPlant: the two-speed rig has no drive ramps; pass a rig with "
                             f"ramp_up = ramp_down = inf, got {self.rig.ramp_up!r} and {self.rig.ramp_down!r}")

    @property
    def Ts(self) -> float:
        """Sampling period (s)."""
        return self.rig.Ts

    # -- statics ------------------------------------------------------------
    def _consts(self) -> np.ndarray:
        rig = self.rig
        k0, a0, b0 = (float(c) for c in rig.static_coefficients)
        qj, hj, m = rig._low_flow
        return np.array([k0, a0, rig.shutoff_head - b0, rig.drive_lag, rig.inertia * math.pi / 30.0,
                         rig.speed_stiffness, rig.pump_torque, rig.shutoff_head, rig.pump_drop, rig.pipe_loss,
                         rig.inertance, qj, hj, m])

    def _check_speeds(self, speed1: np.ndarray | float, speed2: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        # text and bools are no speeds (a float conversion parsed '1200' and read True as 1 rpm)
        n1, n2 = np.broadcast_arrays(real_array(speed1, "speed1"), real_array(speed2, "speed2"))
        lo, hi = self.rig.speed_range
        for i, n in ((1, n1), (2, n2)):
            if not np.all(np.isfinite(n)):
                raise ValueError(f"speed{i} must be finite")
            if np.any((n < lo) | (n > hi)):
                raise ValueError(f"speed{i} must stay within {lo:g}–{hi:g} rpm (the rig's speed_range), "
                                 f"got {float(n[(n < lo) | (n > hi)].flat[0]):g} rpm")
        return n1, n2

    def steady_flows(self, speed1: np.ndarray | float, speed2: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Equilibrium flow through each pump set at constant speeds.

        Solved by bisection on the total flow to the last bit (the balance falls strictly with Q);
        a pump whose valve stays shut delivers 0.

        Parameters
        ----------
        speed1, speed2 : float or array_like, shapes that broadcast together
            Constant speed references of the two pump sets (rpm), within the rig's ``speed_range``.

        Returns
        -------
        q1, q2 : ndarray, the broadcast shape
            Flows (L/s).
        """
        n1, n2 = self._check_speeds(speed1, speed2)
        c = self._consts()
        q1 = np.empty(n1.shape)
        q2 = np.empty(n1.shape)
        for idx in np.ndindex(n1.shape):
            q1[idx], q2[idx] = _steady_split(float(n1[idx]), float(n2[idx]), c)
        return q1, q2

    def steady_flow(self, speed1: np.ndarray | float, speed2: np.ndarray | float) -> np.ndarray:
        """Equilibrium total flow Q̄ at constant speeds.

        Parameters
        ----------
        speed1, speed2 : float or array_like, shapes that broadcast together
            Constant speed references of the two pump sets (rpm), within the rig's ``speed_range``.

        Returns
        -------
        ndarray, the broadcast shape
            Flow (L/s).
        """
        q1, q2 = self.steady_flows(speed1, speed2)
        return q1 + q2

    def static_pressure(self, speed1: np.ndarray | float, speed2: np.ndarray | float) -> np.ndarray:
        """The theoretical static surface p̄(n̄₁, n̄₂) = H_t(Q̄), noise-free.

        Equals eq. (1) at n̄₁ = n̄₂; see the module docs ("Static surface").

        Parameters
        ----------
        speed1, speed2 : float or array_like, shapes that broadcast together
            Constant speed references of the two pump sets (rpm), within the rig's ``speed_range``.

        Returns
        -------
        ndarray, the broadcast shape
            Pressure (mlc).
        """
        q = self.steady_flow(speed1, speed2)
        c = self._consts()
        return np.vectorize(lambda x: _turbine_head(float(x), c), otypes=[float])(q)

    def surface(self, *, domain: tuple[tuple[float, float], tuple[float, float]] | None = None) -> "PlantSurface":
        """The theoretical static surface as a callable on ū of shape (K, 2) (for plots and errors).

        Parameters
        ----------
        domain : ((float, float), (float, float)), optional
            Box of (n̄₁, n̄₂) the surface is drawn over (rpm); default ``OPERATING_RANGE`` for both.

        Returns
        -------
        PlantSurface
            Called on ū of shape (K, 2) (rpm), it gives p̄ of shape (K,) (mlc).
        """
        box = (OPERATING_RANGE, OPERATING_RANGE) if domain is None else self._check_domain(domain)
        return PlantSurface(self, tuple((float(lo), float(hi)) for lo, hi in box))

    def _check_domain(self, domain: object) -> tuple[tuple[float, float], tuple[float, float]]:
        """``domain`` as two (low, high) speed ranges inside the rig's ``speed_range`` (rpm), low < high."""
        form = "domain must be ((low1, high1), (low2, high2)) in rpm"
        if not isinstance(domain, (tuple, list, np.ndarray)) or not all(
                isinstance(p, (tuple, list, np.ndarray)) for p in domain):
            raise TypeError(f"{form}, got {domain!r}")
        if len(domain) != 2 or any(len(p) != 2 for p in domain):
            raise ValueError(f"{form} (one range per pump set), got {domain!r}")
        lo_rig, hi_rig = self.rig.speed_range
        out = []
        for i, (lo, hi) in enumerate(domain, start=1):
            lo = check_real(lo, f"domain[{i - 1}][0] (low{i}, rpm)", low=lo_rig)
            hi = check_real(hi, f"domain[{i - 1}][1] (high{i}, rpm)", high=hi_rig)
            if not lo < hi:
                raise ValueError(f"{form} with low < high, got {domain!r}")
            out.append((lo, hi))
        return tuple(out)  # type: ignore[return-value]

    def steady_state(self, speed1: float, speed2: float) -> tuple[float, float, float, float, float]:
        """Equilibrium state at constant references.

        Parameters
        ----------
        speed1, speed2 : float
            One speed reference of each pump set (rpm), within the rig's ``speed_range``.

        Returns
        -------
        (float, float, float, float, float)
            (n_c1, n_1, n_c2, n_2, Q): each set's drive and rotor speeds (rpm), each the reference, and the total
            flow (L/s).
        """
        n1, n2 = self._check_speeds(speed1, speed2)
        if n1.size != 1:  # (arrays of speeds failed in numpy's words: 'only length-1 arrays can be converted')
            raise ValueError(f"steady_state takes one speed of each pump set (rpm), got speeds of shape {n1.shape}; "
                             "steady_flow takes arrays")
        n1, n2 = float(n1.reshape(-1)[0]), float(n2.reshape(-1)[0])
        return (n1, n1, n2, n2, float(self.steady_flow(n1, n2)[()]))

    # -- dynamics -----------------------------------------------------------
    def simulate(
        self,
        u: np.ndarray | Sequence[Sequence[float]],
        *,
        seed: int | np.random.Generator | None = None,
        noise: bool = True,
        process_noise: bool = True,
        x0: tuple[float, float, float, float, float] | None = None,
    ) -> TwoSpeedRun:
        """Simulate the rig for two sampled speed references.

        Parameters
        ----------
        u : array_like or pandas.DataFrame, shape (N, 2)
            Speed references r₁, r₂ (rpm), held over each sample, each within the rig's
            ``speed_range``. A DataFrame with columns ``u1`` and ``u2`` (the rig's records' input
            names) is read by name, in any order.
        seed : int or numpy Generator, optional
            Source of noise (an int seeds ``np.random.default_rng``); required when any noise is on.
            The draws are the bundled rig's, in its order.
        noise : bool
            Add transmitter noise to the measured pressure.
        process_noise : bool
            Add the process disturbances w, s and a; False gives the noise-free physics.
        x0 : (n_c1, n_1, n_c2, n_2, Q), optional
            Initial state; default the equilibrium at ``u[0]``.

        Returns
        -------
        TwoSpeedRun
        """
        uu = real_array(frame_inputs(u, _INPUTS, "u"), "u")  # a DataFrame by its columns u1, u2; no masked entry
        if uu.ndim != 2 or uu.shape[1] != 2 or uu.shape[0] == 0:
            raise ValueError(f"u must have shape (N, 2): one column per pump set, got shape {uu.shape}")
        r1 = as_1d_finite(uu[:, 0], "speed reference 1")
        r2 = as_1d_finite(uu[:, 1], "speed reference 2")
        rig = self.rig
        rig._check_reference(r1, "speed reference 1")
        rig._check_reference(r2, "speed reference 2")
        N = r1.size
        eps_w, eps_s, eps_a, v, (phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain) = rig._disturbances(
            N, seed, noise=noise, process_noise=process_noise)
        if x0 is None:
            state = self.steady_state(r1[0], r2[0])
        else:
            state = initial_state(x0, ("n_c1", "n_1", "n_c2", "n_2", "Q"))  # text or bools are no state
        S = int(rig.substeps)
        dt = rig.Ts / S
        delay = int(round(rig.dead_time / dt))
        out = _integrate2(r1, r2, eps_w, eps_s, eps_a, float(phi), float(w_gain), float(w0), float(s_phi),
                          float(s_gain), float(a_phi), float(a_gain), *state, S, delay, dt, self._consts())
        p, n1, n2, q, q1, surge, air = out
        return TwoSpeedRun(t=np.arange(N) * rig.Ts, u=np.column_stack([r1, r2]), y=p + v, pressure=p,
                           speed=np.column_stack([n1, n2]), flow=q, pump_flow=np.column_stack([q1, q - q1]),
                           Ts=rig.Ts, surge=surge, air_loss=air)


@dataclass(frozen=True)
class PlantSurface:
    """p̄(n̄₁, n̄₂) of a :class:`TwoSpeedPumpingPlant` as a function of ū of shape (K, 2) (mlc).

    Attributes
    ----------
    plant : TwoSpeedPumpingPlant
    domain : ((float, float), (float, float))
        Box of speeds (rpm) it is meant for (plots use it as their default range).
    name : str
    """

    plant: TwoSpeedPumpingPlant
    domain: tuple[tuple[float, float], tuple[float, float]]
    name: str = "theoretical static surface"

    def __call__(self, ubar: np.ndarray) -> np.ndarray:
        """p̄ at ``ubar`` of shape (K, 2) (rpm; a DataFrame with columns ``u1``, ``u2`` read by name); returns shape (K,)."""
        # a DataFrame by its columns u1, u2; text, bools and None are no speeds (np.asarray parsed '1200')
        u = real_array(frame_inputs(ubar, _INPUTS, "ubar"), "ubar", "speed pairs (rpm)")
        if u.ndim == 1 and u.size == 2:
            u = u[None, :]
        if u.ndim != 2 or u.shape[1] != 2:
            raise ValueError(f"ū must have shape (K, 2), got {np.shape(ubar)}")
        return self.plant.static_pressure(u[:, 0], u[:, 1])


# ---------------------------------------------------------------------------
# Compiled physics. c = (κ, α, h_0 − β, τ_v, J', k_s, c_p, h_0, h_2, R_f, I, Q_j, H_j, m)
# ---------------------------------------------------------------------------

@nb.njit(cache=True, nogil=True)
def _turbine_head(q, c):  # pragma: no cover - compiled
    """H_t(Q) (mlc): the bundled rig's calibrated characteristic and its low-flow branch."""
    k0, a0, g, h0, h2, rf, qj, hj, m = c[0], c[1], c[2], c[7], c[8], c[9], c[11], c[12], c[13]
    if q >= qj:
        rq2 = (h2 / 4 + rf) * q * q
        n_star = (a0 + math.sqrt(a0 * a0 + 4 * g * (k0 + rq2))) / (2 * g)
        return h0 * n_star * n_star - rq2
    if q > 0.0:
        return hj * (q / qj) ** m
    return 0.0


@nb.njit(cache=True, nogil=True)
def _header(q, A1, A2, sh2):  # pragma: no cover - compiled
    """(H_h, √h_2 q_1): header head and pump 1's scaled flow for total flow q (module docs, item 2)."""
    s = sh2 * q
    d = A1 - A2
    if s > 0.0 and s * s >= abs(d):
        x = 0.5 * (s + d / s)
        return A1 - x * x, x
    if A1 >= A2:
        return A1 - s * s, s
    return A2 - s * s, 0.0


@nb.njit(cache=True, nogil=True)
def _balance(q, A1, A2, c):  # pragma: no cover - compiled
    """I dQ/dt without disturbances: header head − pipe friction − turbine head (mlc)."""
    hh, _ = _header(q, A1, A2, math.sqrt(c[8]))
    return hh - c[9] * q * q - _turbine_head(q, c)


@nb.njit(cache=True, nogil=True)
def _steady_split(n1, n2, c):  # pragma: no cover - compiled
    """Equilibrium (q_1, q_2) at constant speeds: bisection on Q to the last bit."""
    h0 = c[7]
    A1 = h0 * n1 * n1
    A2 = h0 * n2 * n2
    lo = 0.0
    # the header head is at most max(A) − h_2 Q²/4, so the balance is negative beyond this flow
    hi = math.sqrt(max(A1, A2) / (c[8] / 4 + c[9])) + 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if _balance(mid, A1, A2, c) > 0.0:
            lo = mid
        else:
            hi = mid
    q = 0.5 * (lo + hi)
    _, x = _header(q, A1, A2, math.sqrt(c[8]))
    q1 = min(q, x / math.sqrt(c[8]))
    return q1, q - q1


@nb.njit(cache=True, nogil=True)
def _rhs2(nc1, n1, nc2, n2, q, r1, r2, w, air, c):  # pragma: no cover - compiled
    tv, jp, ks, cp, h0, rf, inert = c[3], c[4], c[5], c[6], c[7], c[9], c[10]
    hh, _ = _header(q, h0 * (1.0 - air) * n1 * n1, h0 * (1.0 - air) * n2 * n2, math.sqrt(c[8]))
    dq = (hh - rf * q * q - _turbine_head(q, c) + w) / inert
    if q <= 0.0 and dq < 0.0:
        dq = 0.0  # the non-return valves hold the column: the flow stops, it does not reverse
    return ((r1 - nc1) / tv, (ks * (nc1 - n1) + cp * (nc1 * nc1 - n1 * n1)) / jp,
            (r2 - nc2) / tv, (ks * (nc2 - n2) + cp * (nc2 * nc2 - n2 * n2)) / jp, dq)


@nb.njit(cache=True, nogil=True)
def _integrate2(r1, r2, eps_w, eps_s, eps_a, phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain,
                nc1, n1, nc2, n2, q, S, delay, dt, c):  # pragma: no cover - compiled
    """RK4 over the whole record; returns (pressure, n_1, n_2, Q, q_1, surge, air), each shape (N,)."""
    N = r1.shape[0]
    p = np.empty(N)
    s1 = np.empty(N)
    s2 = np.empty(N)
    flow = np.empty(N)
    flow1 = np.empty(N)
    surge_out = np.empty(N)
    air_out = np.empty(N)
    h0, sh2 = c[7], math.sqrt(c[8])
    prev1 = r1[0]
    prev2 = r2[0]
    surge = 0.0
    air = 0.0
    w = w0
    for k in range(N):
        if k > 0:
            w = phi * w + w_gain * eps_w[k]
        p[k] = _turbine_head(q, c)
        s1[k] = n1
        s2[k] = n2
        flow[k] = q
        _, x = _header(q, h0 * (1.0 - air) * n1 * n1, h0 * (1.0 - air) * n2 * n2, sh2)
        flow1[k] = min(q, x / sh2)  # rounding must not push the other pump's share below 0
        surge_out[k] = surge
        air_out[k] = air
        wk = w + surge
        n1_old = n1
        n2_old = n2
        h = 0.5 * dt
        s6 = dt / 6.0
        for j in range(S):
            a = r1[k] if j >= delay else prev1
            b = r2[k] if j >= delay else prev2
            k1 = _rhs2(nc1, n1, nc2, n2, q, a, b, wk, air, c)
            k2 = _rhs2(nc1 + h * k1[0], n1 + h * k1[1], nc2 + h * k1[2], n2 + h * k1[3], q + h * k1[4],
                       a, b, wk, air, c)
            k3 = _rhs2(nc1 + h * k2[0], n1 + h * k2[1], nc2 + h * k2[2], n2 + h * k2[3], q + h * k2[4],
                       a, b, wk, air, c)
            k4 = _rhs2(nc1 + dt * k3[0], n1 + dt * k3[1], nc2 + dt * k3[2], n2 + dt * k3[3], q + dt * k3[4],
                       a, b, wk, air, c)
            nc1 += s6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            n1 += s6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            nc2 += s6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
            n2 += s6 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3])
            q += s6 * (k1[4] + 2 * k2[4] + 2 * k3[4] + k4[4])
            if q < 0.0:
                q = 0.0  # the valves close within the substep (RK4 overshoots the stop)
        prev1 = r1[k]
        prev2 = r2[k]
        dn = 0.5 * (abs(n1 - n1_old) + abs(n2 - n2_old))
        surge = s_phi * surge + s_gain * dn * eps_s[k]
        air = min(1.0, a_phi * air + a_gain * dn * eps_a[k] * eps_a[k])
    return p, s1, s2, flow, flow1, surge_out, air_out


# ---------------------------------------------------------------------------
# The experiment: input design, static grid, files
# ---------------------------------------------------------------------------

def two_speed_reference(*, n_samples: int = N_SAMPLES_MISO, n_ident: int = N_IDENT_MISO, seed: int = DEFAULT_SEED,
                        low: float = OPERATING_RANGE[0], high: float = OPERATING_RANGE[1]) -> np.ndarray:
    """Two independent staircase speed references (rpm), shape (n_samples, 2).

    Each column is designed like the bundled rig's reference (:func:`graybox.datasets.speed_reference`:
    holds of 4–9 s, or longer where a hold forced to an end merges with a neighbour, steps of several sizes,
    levels on whole multiples of 10 rpm, both ends of
    [``low``, ``high``] visited in the identification part ``:n_ident`` and in the validation
    part ``n_ident:``), from its own random stream (``[seed, 11]`` and ``[seed, 12]``), so the two
    references change at unrelated instants and to unrelated levels.

    Parameters
    ----------
    n_samples : int
        Length of both references, samples of Ts = 0.05 s (default 6000: the records of
        :func:`graybox.load_pumping_miso`).
    n_ident : int
        Samples of the identification part, the first (default 4800); the rest is the validation part.
    seed : int
        Seed of both columns' streams (default 2011, the bundled records').
    low, high : float
        The speed range of each pump set (rpm), 0 < low < high; default 1150–1650.

    Returns
    -------
    ndarray, shape (n_samples, 2)
        One speed reference (rpm) per pump set.
    """
    n_samples, n_ident, seed = reference_lengths(n_samples, n_ident, seed)
    low, high = check_real(low, "low (rpm)", low=0, low_open=True), check_real(high, "high (rpm)")
    if not low < high:
        raise ValueError(f"need 0 < low < high, got {low} and {high}")
    cols = []
    for i in (1, 2):
        rng = np.random.default_rng([seed, 10 + i])
        cols.append(np.concatenate([_staircase(n_ident, rng, low, high),
                                    _staircase(n_samples - n_ident, rng, low, high)]))
    return np.column_stack(cols)


def static_grid(*, speeds1: Sequence[float] = STATIC_SPEEDS_MISO,
                speeds2: Sequence[float] | None = None) -> np.ndarray:
    """The grid of speed pairs (rpm) in the order the static test visits them, shape (K, 2).

    Row by row in ``speeds1`` (rpm of set 1), with ``speeds2`` (rpm of set 2; default the same
    levels) alternately up and down (a serpentine), so each move changes one reference by one
    grid step.
    """
    s1 = static_speeds(speeds1, "speeds1")
    s2 = s1 if speeds2 is None else static_speeds(speeds2, "speeds2")
    rows = [np.column_stack([np.full(s2.size, a), s2 if i % 2 == 0 else s2[::-1]]) for i, a in enumerate(s1)]
    return np.vstack(rows)


def static_grid_experiment(
    plant: TwoSpeedPumpingPlant,
    *,
    speeds: np.ndarray | None = None,
    seed: int | np.random.Generator | None = None,
    settle: float = 180.0,
    average: float = 6.0,
) -> StaticPoints:
    """The static test over (n₁, n₂): hold each pair, wait out the transients, average the pressure.

    As :func:`graybox.datasets.static_experiment`, one continuous run visiting ``speeds``
    in order (default ``static_grid``), discarding ``settle`` seconds and averaging the next
    ``average`` seconds of noisy measurements at each pair (``speeds``: shape (K, 2), a DataFrame with
    columns ``u1`` and ``u2`` read by name, as :meth:`TwoSpeedPumpingPlant.simulate` reads ``u``); ``seed`` (an int
    or a numpy Generator) is the source of noise.

    Parameters
    ----------
    plant : TwoSpeedPumpingPlant
        The simulated two-speed rig.
    speeds : ndarray of shape (K, 2) or DataFrame with columns u1, u2, optional
        The speed pairs held, in the order visited (rpm; default a 6 × 6 serpentine over 1150, 1250, …, 1650), finite
        and within the rig's speed range.
    seed : int or numpy Generator, optional
        Source of noise; required while the plant's noise is on.
    settle : float
        Seconds discarded at each pair (default 180).
    average : float
        Seconds averaged after them (default 6).

    Returns
    -------
    StaticPoints
        ū = the speed pairs (rpm), shape (K, 2), inputs named ``u1``, ``u2``; ȳ = mean measured
        pressure (mlc), shape (K,).
    """
    check_plant(plant, TwoSpeedPumpingPlant)
    # a DataFrame by its columns u1, u2, as simulate reads u (by position it put u2 first on pump set 1)
    sp = static_grid() if speeds is None else real_array(frame_inputs(speeds, _INPUTS, "speeds"), "speeds",
                                                         "speed pairs (rpm)")
    if sp.ndim != 2 or sp.shape[1] != 2 or sp.shape[0] == 0:
        raise ValueError(f"speeds must have shape (K, 2), got {sp.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(sp), axis=1))
    if bad.size:  # said of the pairs given, not of the run's samples they become
        raise ValueError(f"speeds must be finite (rpm): row {bad[0]} is {sp[bad[0]].tolist()}")
    check_static_levels(sp, plant.rig.speed_range, "speeds")
    n_settle, n_avg = static_samples(plant.Ts, settle, average, sp.shape[0])
    u = np.repeat(sp, n_settle + n_avg, axis=0)
    run = plant.simulate(u, seed=seed)
    y = run.y.reshape(sp.shape[0], n_settle + n_avg)[:, n_settle:]
    return StaticPoints(sp, y.mean(axis=1), name="pumping_miso static points", input_names=("u1", "u2"),
                        units=("rpm", "mlc"))


def generate_miso(*, seed: int = DEFAULT_SEED, plant: TwoSpeedPumpingPlant | None = None
                  ) -> tuple[TwoSpeedRun, StaticPoints]:
    """The bundled MISO experiment: the dynamic run and the 36-point static grid.

    ``plant`` defaults to :class:`TwoSpeedPumpingPlant` (the bundled rig). Deterministic for a given
    ``seed``: the references use streams ``[seed, 11]``, ``[seed, 12]``,
    the dynamic run ``[seed, 13]`` and the static test ``[seed, 14]``.

    Returns
    -------
    (TwoSpeedRun, StaticPoints)
        The run and the 36 static points (ū in rpm, shape (36, 2); ȳ in mlc).
    """
    plant = TwoSpeedPumpingPlant() if plant is None else check_plant(plant, TwoSpeedPumpingPlant)
    run = plant.simulate(two_speed_reference(seed=seed), seed=np.random.default_rng([seed, 13]))
    static = static_grid_experiment(plant, seed=np.random.default_rng([seed, 14]))
    return run, static


def write_miso_csvs(out_dir: str | Path, *, seed: int = DEFAULT_SEED) -> tuple[Path, Path]:
    """Write ``dynamic.csv`` and ``static.csv`` of :func:`generate_miso` into ``out_dir``.

    ``seed`` as in :func:`generate_miso`. Formatting as the bundled rig's files: time with 2 decimals, speeds with 1, pressure with 4.

    Returns
    -------
    (Path, Path)
        The dynamic and static files.
    """
    run, static = generate_miso(seed=seed)
    return write_csv_pair(out_dir, DYNAMIC_COLUMNS_MISO,
                          [f"{t:.2f},{u[0]:.1f},{u[1]:.1f},{y:.4f}" for t, u, y in zip(run.t, run.u, run.y)],
                          STATIC_COLUMNS_MISO, [f"{u[0]:.1f},{u[1]:.1f},{y:.4f}" for u, y in zip(static.ubar, static.ybar)])


def main(argv: list[str] | None = None) -> int:
    """``python -m graybox.datasets._pumping_miso [--out DIR] [--seed N]``: regenerate the bundled MISO CSVs."""
    return regenerate_main(argv, module="graybox.datasets._pumping_miso", folder="pumping_miso",
                           write=lambda out, seed: write_miso_csvs(out, seed=seed))


if __name__ == "__main__":
    sys.exit(main())
