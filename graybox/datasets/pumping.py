r"""A simulated two-pump hydraulic rig: the benchmark plant that stands in for the paper's data.

The measured data of Barbosa et al. (2011) are not public. This module simulates a rig with the
layout of their Section II and calibrates it to every fact the paper publishes:

- static curve: the noise-free steady-state pressure equals eq. (1),
  H(u) = β u² + α u + κ (β = 7.2652e-6, α = 1.4933e-3, κ = −1.3312), over 750–1650 rpm;
- sampling time Ts = 0.05 s, 3200 identification + 800 validation samples, speed-reference steps
  at several operating points and of several sizes (their Fig. 3);
- a time constant that varies with the operating point (their ref. [5]);
- pressure transmitter error ±0.175 mlc (read here as the 95 % band of Gaussian noise);
- black-box models whose free-run errors are of the order of 1 mlc² and whose static curve
  misses the measured one by far more than the transmitter band (their Table I): slow,
  transient-excited disturbances that the careful static test waits out (see "Disturbances").

Everything else (inertias, pipe length, pump curve, …) is a plausible choice for a 2 × 7.5 kW rig,
not a measurement. The data it generates are a stand-in, not the paper's plant.

Physical model
--------------
Units: speed n in rpm, flow Q in L/s, head and pressure in mlc (metres of liquid column), time in s.
Both pump sets run at the same instantaneous speed (as in the paper), so one motor equation and
one pump curve with Q/2 per pump describe both. State x = (n_c, n, Q):

1. **Drive (VFD) reference path.** The speed reference r (the input u, held constant over each
   sample) reaches the drive after a scan/fieldbus dead time θ and is smoothed by the drive's
   reference filter: ``dn_c/dt = (r(t − θ) − n_c) / τ_v``.
2. **Induction motor + pump rotor.** The drive's speed loop gives a torque proportional to the
   speed error plus a feed-forward of the pump load torque at the commanded speed (slip
   compensation, so the shaft settles exactly on the command); the pump absorbs T_p = c n²
   (affinity law). With J' = J π/30 (N·m·s per rpm):
   ``J' dn/dt = k_s (n_c − n) + c (n_c² − n²)``, i.e. a mechanical time constant
   J' / (k_s + 2 c n) that *falls* as the speed rises.
3. **Two centrifugal pumps in parallel** (affinity laws; a non-return valve on each, item 6):
   each delivers Q/2 against the head
   ``H_p(n, Q) = h_0 n² − h_2 (Q/2)²``.
4. **Water column inertia** (rigid column of length L and area A, inertance I = L / (g A)):
   ``I dQ/dt = H_p(n, Q) − R_f Q² − H_t(Q) + w(t)``, with R_f the pipe friction and w a head
   disturbance (see "Disturbances": turbulence, pulsation and the slow surge; the air
   disturbance scales the pump head instead).
5. **Francis turbine load.** At fixed distributor opening (50 %, as in the paper) and synchronous
   runner speed the turbine imposes a head–flow characteristic H_t(Q), which is also the measured
   pressure p = H_t(Q). We do not know the real turbine's characteristic, so it is *defined* as the
   one that makes the rig's steady state equal eq. (1): at equilibrium H_p(n, Q) − R_f Q² = H_t(Q)
   and H_t(Q) = H(n), hence R Q² = (h_0 − β) n² − α n − κ with R = h_2/4 + R_f; inverting gives
   n*(Q) (positive root) and ``H_t(Q) = H(n*(Q))``. The resulting characteristic rises with flow,
   more steeply than Q², and is smooth over the operating range. The hydraulic time constant
   I / (H_t'(Q) + 2 R Q) falls as the flow rises.

6. **Low flow.** The calibrated characteristic exists only above 21.4 L/s (below, n*(Q) is
   imaginary) and turns negative below 22.0 L/s, both far below the operating range (30 L/s at
   750 rpm). Under the flow Q_j of the lowest accepted reference (``speed_range[0]``, 500 rpm:
   24.2 L/s, H_j = 1.23 mlc) it continues as ``H_t(Q) = H_j (Q/Q_j)^m`` (m = 9.6 makes the slope
   continuous) down to H_t(0) = 0: a turbine passing little water holds little head. Each pump's
   discharge has a non-return valve (standard for pumps in parallel), so the flow never reverses:
   when the pumps cannot push water against the head, ``(1 − a) h_0 n² + w ≤ 0``, the flow falls
   to zero, stays there (p = 0) while the disturbance lasts, and restarts when it subsides.
   This happens on long records: a large step down (e.g. 1630 → 780 rpm) now and then sets off a
   surge of −6 to −15 mlc of head while the air costs 14–17 % of the pump head, against a shut-off
   head (1 − a) h_0 n² of about 6–8 mlc at 800–900 rpm. The air loss is capped at 1 (a pump full
   of air delivers no head). None of this touches the bundled records, whose flow stays above
   28 L/s.

7. **Drive ramps** (off by default). A drive may limit how fast its commanded speed moves:
   ``dn_c/dt`` is clipped to [−``ramp_down``, ``ramp_up``] rpm/s (a drive without a braking
   resistor decelerates on a ramp, so as not to trip on DC-bus overvoltage). A ramp makes the
   response to a step depend on its size (a 900 rpm step at 150 rpm/s takes 6 s, a 50 rpm one is
   over in about a second), a dynamic that polynomial NARX models of low degree represent poorly.
   It delays the steady state and does not move it. The bundled stand-in has no ramp (both
   default to ``math.inf``); BENCHMARKS.md, "A stand-in calibrated to Table I's other facts",
   tries ramps among other variants.

Integration: classical RK4 with ``substeps`` steps per sample (default 10, i.e. 5 ms, against a
fastest time constant of 80 ms), compiled with numba (about 1 s per 10⁶ samples). Sampling: y(k) is read at t = k Ts, then u(k) is applied over
[k Ts, (k+1) Ts), so y(k) depends on u(k−1), u(k−2), …

Measured dynamics of the default plant (noise-free 63.2 % rise after a ±20 rpm step, measured from
the step instant; :meth:`PumpingPlant.step_time_constant`):

- at  750 rpm: 1.26 s (about 25 samples),
- at 1200 rpm: 0.97 s,
- at 1650 rpm: 0.78 s (about 16 samples): the plant is about 1.6 times faster at high speed
  Both lags speed up with the operating point: the water column's I / (H_t'(Q) + 2 R Q) from
  0.56 s (Q = 30 L/s) to 0.34 s (Q = 59 L/s), the rotor's J' / (k_s + 2 c n) from 0.52 s to 0.29 s.

Fastest effect of the reference: one sample after a step the pressure has moved by less than
0.1 % of its final change, after two samples by 0.3–0.8 %, after four by 2–6 %: u(k−1) alone has
almost no effect on y(k), as in the paper, whose ERR never selected a lag below 2. (ERR on these
data may still take a u(k−1) term late, with a small ERR, because under a staircase input u(k−1)
is nearly collinear with u(k−2); a candidate set with delay 2 excludes such terms.)

Disturbances
------------
Transmitter noise: white Gaussian, std 0.175/1.96 = 0.0893 mlc (95 % band ±0.175 mlc), added to
the pressure. Three process disturbances act on the water column; ``simulate(process_noise=False)``
switches all three off and leaves the noise-free physics above, and none of them moves the
settled static curve:

1. **Fast head disturbance w** (turbulence, blade-pass pulsation): AR(1) per sample, pole 0.8,
   stationary std 0.15 mlc of head; in the pressure about 0.06 mlc std with lag-1 autocorrelation
   above 0.9. Always present, also at constant speed. It makes the equation error of a NARX model
   coloured, so least squares is biased and extended least squares has something to remove.
2. **Surge s** (zero mean, mlc of head, added to w). The circuit is open at the bottom: the
   turbine discharges into a tail-water channel that feeds the pumps' sump. A change of flow sets
   the free surfaces and the flow pattern at the pump intakes in motion, so the sump level, the
   tail-water level and the inflow to the pumps wander irregularly for several seconds, and with
   them the pumps' suction head and the turbine's back pressure. The net effect is modelled as a
   random head driven by the rate of change of the pump speed:
   ``ds = −s/τ_s dt + σ_s |dn/dt| dW`` (τ_s = 6 s, σ_s = 0.0055 mlc·s^½/rpm); per sample
   ``s ← e^(−Ts/τ_s) s + σ_s |Δn| / √Ts · ε``. Its sign is random, not tied to the direction of
   the step: it is a disturbance, not a missing deterministic mode. Its std 2.5 s after a step is
   about 0.37 mlc (head) for a 100 rpm step and 2.0 mlc for a 500 rpm step.
3. **Air head loss a** (one-signed). Fast speed changes draw air into the suction (free-surface
   vortices in the sump) and release dissolved air where the pressure drops; the bubbles cut the
   pumps' head (a few percent of void fraction costs a centrifugal pump several percent of its
   head) until they vent, in τ_a = 30 s. The pumps deliver ``(1 − a) h_0 n² − h_2 (Q/2)²`` with
   ``a ← e^(−Ts/τ_a) a + γ_a |Δn| χ²`` per sample, χ² with one degree of freedom (mean 1: how
   much air a transient brings varies a lot) and γ_a = 8e-5 per rpm: a 100 rpm step costs on
   average 0.7 % of the pump head, a 500 rpm step 3.6 %.

Both slow disturbances start at rest (the rig has been settled at the first reference) and are
excited only by changes of the shaft speed, which does not depend on them, so they are exogenous.
Their size is chosen, not measured: it calibrates the stand-in to the paper's Table I, where the
black-box models have free-run errors of 1–3 mlc² and the ELS model (15) misses the measured static
curve (J_SF = 1.6 mlc², against the 0.031 mlc² uncertainty band): the dynamic data alone do not
pin the static curve. On the bundled dynamic record (default seed) the disturbances change the
pressure by −0.90 mlc on average (the air: −0.7 mlc below 1000 rpm, −1.4 mlc above 1400 rpm, as
the staircase never rests long enough for the air to vent: 9 % of pump head lost on average,
15 % at most) with a std of 0.95 mlc (surge alone 0.79 mlc, air alone 0.54 mlc).

The static test waits them out (:func:`static_experiment`): after each speed change it waits
180 s (6 τ_a, 30 τ_s), the paper's "after transients died out", before averaging; the slow
disturbances then move the averaged pressure by under 0.001 mlc (measured on the bundled test:
at most 4e-4 mlc), so the static points carry only w and the transmitter noise, whose effect on
a 6 s mean is :meth:`PumpingPlant.static_point_std` (about 0.03 mlc).

What the bundled data give (identification part: 3200 samples; validation: the last 800; J in
mlc², the static error against the 10 bundled static points; FROLS over every candidate of the degree,
the constant not forced: ``graybox reproduce`` selects Table I's (15) and (17) with the constant and, at
degree 2, at most one power of y, and gets 0.88, 0.82, 0.94 and 0.84, 0.68, inf):

=========================================================  =========  =========  ======
model                                                      J_S ident  J_S valid  J_SF
=========================================================  =========  =========  ======
FROLS 17 terms, degree 2, ny = nu = 6, + ELS with ne = 2     0.86       0.75     0.87
FROLS 23 terms, degree 3, ny = nu = 6, + ELS with ne = 2     0.88       0.83     1.34
the paper's structure (15) by plain least squares            0.86       0.68      —
=========================================================  =========  =========  ======

Both black-box models run free stably on the validation record. With other seeds of the
generator (7, 1–6) the degree-2 model's J_S ident ranges 0.3–1.9 mlc² and its J_SF 0.7–2.6 mlc²,
and both models stay stable on the validation record (one seed in eight gives the degree-3 model
a static point without a stable equilibrium; a stronger or slower surge makes the degree-3 model
unstable for some seeds). The paper's ELS models reach J_S 1.1–2.6 mlc² and J_SF 1.6
(ELS (15)); the stand-in is a little easier dynamically and of the same kind statically.

What the stand-in does not reproduce (BENCHMARKS.md, "Table I over many draws of the stand-in"):

- In Table I the SE (D_SF) model beats ELS on the validation record at ℓ = 2 (1.751 against 2.116
  mlc²) and loses to it at ℓ = 3 (1.306 against 1.104). Over 30 draws of this stand-in (seeds 1–30
  of :func:`generate`) the gradient SE model's validation J_S is a median 1.66 times ELS's at ℓ = 2,
  where the paper has 0.83; at ℓ = 3 it is 1.21 times (the paper: 1.18), a median over a wide
  spread (1.01 over the first ten).
- The paper's ℓ = 3 black box nearly meets the static points (J_SF 0.060 mlc², twice the band).
  Here the ℓ = 2 black box misses them by 0.94 mlc² and the ℓ = 3 one has no equilibrium at one of
  them, *because* the air loss lowers every dynamic record by about 0.9 mlc, which the static test
  waits out. Transient inputs (:func:`graybox.transient_inputs`) let a gray box carry the air loss
  without moving its static curve (BENCHMARKS.md, "Transient inputs").
- The air loss is not what makes the ℓ = 2 SE model lose. On the bundled stand-in it loses on both
  records; without the air loss, and even without the surge, it beats ELS on the identification
  record and loses on the validation record (overfitting): on the stand-in with neither slow
  disturbance the loss is all start-up, from the validation record's first samples (the rig
  mid-staircase; the identification record starts at rest). On the bundled stand-in it is not the
  start: with the validation record's first outputs estimated, or its first 200 samples left out,
  SE still loses in 8 and 10 draws of 10.
- Read from Table I, the paper's plant differs in two ways: its records and static points barely
  conflict (the ℓ = 3 black box and the network nearly meet the static points), and its
  polynomial models leave 2–3 times this stand-in's free-run error while its network does not: a
  plant whose dynamics degree-2 and -3 polynomials miss.
- Stand-ins calibrated to Table I's ELS facts alone (BENCHMARKS.md, "A stand-in calibrated to
  Table I's other facts": a weaker, faster-venting air loss and a stronger, shorter surge) meet them
  only in part, and there the GA's ℓ = 2 SE model draws level with ELS (median 0.95–1.03 over 30
  draws) while the gradient's still loses; an uncalibrated stand-in without air loss does the same.
  The drive ramps (``ramp_up``, ``ramp_down``) give Table I's contrast between the ℓ = 2 and ℓ = 3
  ELS static errors but make the degree-3 model diverge on validation records.

Run ``python -m graybox.datasets.pumping`` to regenerate the bundled CSVs (see :func:`main`).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from functools import cached_property
from typing import Callable, Sequence

from ..core._jit import nb
import numpy as np

from ..core._files import write_atomically
from ..core._records import Record, StaticPoints
from ..core._validation import (Relocked, as_1d_finite, check_bool, check_count, check_int, check_real, check_seed,
                                locked, real_array)
from ..reference import EQ1_COEFFICIENTS, TS
from ..core._reprs import short_repr

__all__ = [
    "PumpingPlant",
    "PlantRun",
    "speed_reference",
    "static_experiment",
    "generate",
    "write_csvs",
    "main",
    "TS",
    "N_SAMPLES",
    "N_IDENT",
    "STATIC_SPEEDS",
    "DEFAULT_SEED",
    "NOISE_STD",
]

#: Samples in the dynamic record; the first N_IDENT identify, the rest validate.
N_SAMPLES = 4000
N_IDENT = 3200
#: Speeds of the static experiment (rpm): 750, 850, …, 1650.
STATIC_SPEEDS = tuple(float(s) for s in range(750, 1651, 100))
#: Seed of the bundled data.
DEFAULT_SEED = 2011
#: Transmitter noise std (mlc): the ±0.175 mlc error read as a 95 % band of Gaussian noise.
NOISE_STD = 0.175 / 1.96
#: The state of a one-speed run, as x0 gives it.
_STATE = ("n_c", "n", "Q")


def _reference(out: object, k: int) -> float:
    """A controller's reference at sample k as a float: a number, or an array of one (a python-control system's
    output); anything else is an error naming the controller and the sample."""
    what = f"the controller's reference at sample {k}"
    v = real_array(out, what, "a number (rpm)")
    if v.size != 1:
        raise ValueError(f"{what} must be one number (rpm), got {v.size} values of shape {v.shape}")
    return float(v.ravel()[0])


def initial_state(x0: object, names: tuple[str, ...]) -> tuple[float, ...]:
    """A rig's initial state ``x0`` as floats, one per state variable ``names`` (the flow last, >= 0 L/s): a
    ``TypeError`` naming x0 for text, booleans or what is no numbers (a float conversion parsed "40" and read True
    as a flow of 1 L/s), a ``ValueError`` for another count, a non-finite value or a negative flow (unpacking
    said only 'too many values to unpack')."""
    v = real_array(x0, "x0", f"{len(names)} numbers ({', '.join(names)})")
    if v.shape != (len(names),) or not np.all(np.isfinite(v)) or v[-1] < 0.0:
        raise ValueError(f"x0 must be {len(names)} finite numbers ({', '.join(names)}) with Q >= 0 L/s, got {x0!r}")
    return tuple(float(x) for x in v)


@dataclass(frozen=True, eq=False)
class PlantRun(Relocked):
    """The result of one simulation, all arrays of shape (N,) sampled at t = k Ts.

    Attributes
    ----------
    t : ndarray
        Time stamps (s), starting at 0.
    u : ndarray
        Speed reference (rpm) applied over [t_k, t_k + Ts).
    y : ndarray
        Measured pressure (mlc): true pressure + transmitter noise.
    pressure : ndarray
        True pressure H_t(Q) (mlc), including the effect of process noise.
    speed : ndarray
        Shaft speed n (rpm).
    flow : ndarray
        Total flow Q (L/s).
    Ts : float
        Sampling period (s).
    surge : ndarray
        Transient head disturbance s acting on the water column over [t_k, t_k + Ts) (mlc of head).
    air_loss : ndarray
        Fraction of the pumps' head lost to air over [t_k, t_k + Ts) (dimensionless, >= 0).
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    pressure: np.ndarray
    speed: np.ndarray
    flow: np.ndarray
    Ts: float
    surge: np.ndarray
    air_loss: np.ndarray

    def __post_init__(self) -> None:
        for name in ("t", "u", "y", "pressure", "speed", "flow", "surge", "air_loss"):
            a = np.array(getattr(self, name), dtype=float, copy=True)
            object.__setattr__(self, name, locked(a))  # a run is a value: nobody edits it in place

    def record(self, name: str = "pumping") -> Record:
        """The measured input/output pair as a :class:`~graybox.Record`.

        Parameters
        ----------
        name : str, optional
            The record's name (default ``"pumping"``).

        Returns
        -------
        Record
            u the speed reference (rpm), y the pressure (mlc), N samples at ``Ts``.
        """
        return Record(self.u, self.y, Ts=self.Ts, name=name, units=("rpm", "mlc"))

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


@dataclass(frozen=True)
class PumpingPlant:
    """Lumped physical model of the two-pump rig feeding a Francis turbine (see the module docs).

    Parameters
    ----------
    Ts : float
        Sampling period (s).
    substeps : int
        RK4 steps per sample.
    dead_time : float
        Reference scan / fieldbus delay θ (s); a multiple of ``Ts / substeps``, below ``Ts``.
    drive_lag : float
        Drive reference filter τ_v (s).
    inertia : float
        Moment of inertia J of one motor + pump set (kg·m²).
    speed_stiffness : float
        Drive speed-loop gain k_s (N·m per rpm of speed error).
    pump_torque : float
        Pump load-torque coefficient c in T_p = c n² (N·m/rpm²).
    shutoff_head : float
        Pump head coefficient h_0 in H_p = h_0 n² − h_2 q² (mlc/rpm²); must exceed β of eq. (1).
    pump_drop : float
        Pump head-drop coefficient h_2 (mlc/(L/s)², q = flow through one pump).
    pipe_loss : float
        Pipe friction R_f (mlc/(L/s)², total flow).
    pipe_length, pipe_diameter : float
        Water column length and diameter (m), giving the inertance I = L / (g A).
    static_coefficients : tuple of float
        (κ, α, β) of the static curve the rig is calibrated to (default: eq. (1)).
    noise_std : float
        Transmitter noise std (mlc); default 0.175/1.96 (95 % band ±0.175 mlc).
    process_noise_std : float
        Stationary std of the AR(1) head disturbance w (mlc); 0 switches it off.
    process_noise_pole : float
        AR(1) pole of w per sample, in [0, 1).
    surge_intensity : float
        σ_s of the transient head disturbance s (mlc·s^½ per rpm): a speed change at rate ṅ adds
        variance σ_s² ṅ² per second to s; 0 switches it off.
    surge_time : float
        Decay time τ_s of s (s).
    air_loss_per_rpm : float
        γ_a: mean fraction of the pumps' head lost to air per rpm of speed change; 0 switches it off.
    air_vent_time : float
        Time τ_a in which the air vents, i.e. the decay time of the head loss (s).
    ramp_up, ramp_down : float
        The drive's acceleration and deceleration ramps (rpm/s): the commanded speed n_c rises at
        most ``ramp_up`` and falls at most ``ramp_down`` rpm per second (module docs, "Drive
        ramps"); default ``math.inf``, no ramp (the bundled stand-in).
    speed_range : tuple of float
        References accepted by :meth:`simulate` (rpm); the turbine characteristic is calibrated
        for the rig's 750–1650 rpm and extrapolates smoothly a little beyond, down to the flow at
        ``speed_range[0]``, under which the low-flow branch takes over (module docs, item 6).
    """

    Ts: float = TS
    substeps: int = 10
    dead_time: float = 0.02
    drive_lag: float = 0.08
    inertia: float = 0.15
    speed_stiffness: float = 0.01
    pump_torque: float = 1.34e-5
    shutoff_head: float = 1.1e-5
    pump_drop: float = 8.76e-3
    pipe_loss: float = 4.0e-4
    pipe_length: float = 60.0
    pipe_diameter: float = 0.15
    static_coefficients: tuple[float, float, float] = EQ1_COEFFICIENTS
    noise_std: float = NOISE_STD
    process_noise_std: float = 0.15
    process_noise_pole: float = 0.8
    surge_intensity: float = 0.0055
    surge_time: float = 6.0
    air_loss_per_rpm: float = 8.0e-5
    air_vent_time: float = 30.0
    ramp_up: float = math.inf
    ramp_down: float = math.inf
    speed_range: tuple[float, float] = (500.0, 1800.0)

    def __post_init__(self) -> None:
        positive = ("Ts", "drive_lag", "inertia", "speed_stiffness", "pump_torque", "shutoff_head",
                    "pump_drop", "pipe_loss", "pipe_length", "pipe_diameter")
        # numbers, not bools (Ts=True ran at 1 s); numpy's float32 is one too
        for name in positive:
            check_real(getattr(self, name), f"PumpingPlant: {name} (a positive finite number)", low=0, low_open=True)
        check_int(self.substeps, "PumpingPlant: substeps", low=1)
        # the curve and the range as tuples of floats (the plant is hashed): their counts and types said, not unpacked
        for name, n in (("static_coefficients", 3), ("speed_range", 2)):
            v = real_array(getattr(self, name), f"PumpingPlant: {name}", f"{n} numbers")
            if v.shape != (n,) or not np.all(np.isfinite(v)):
                raise ValueError(f"PumpingPlant: {name} must be {n} finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in v))
        # a number (text failed in the division below, naming nothing; True was a 1 s dead time, refused as a value)
        check_real(self.dead_time, "PumpingPlant: dead_time (s)", low=0)
        dt = self.Ts / self.substeps
        m = self.dead_time / dt
        if not (0 <= self.dead_time < self.Ts and abs(m - round(m)) < 1e-9):
            raise ValueError(f"PumpingPlant: dead_time must be a multiple of Ts/substeps = {dt:g} s in "
                             f"[0, Ts), got {self.dead_time!r}")
        # finite and >= 0: a NaN passed "< 0" and switched the process noise off (NaN > 0 is false) or made every
        # pressure NaN, silently
        for name in ("noise_std", "process_noise_std", "surge_intensity", "air_loss_per_rpm"):
            check_real(getattr(self, name), f"PumpingPlant: {name}", low=0)
        for name in ("surge_time", "air_vent_time"):
            # as the positive constants above: True was a decay of 1 s, numpy's float32 was refused, text a ValueError
            check_real(getattr(self, name), f"PumpingPlant: {name} (a positive finite number of s)", low=0,
                       low_open=True)
        for name in ("ramp_up", "ramp_down"):
            v = getattr(self, name)
            # a number (numpy's too), not a bool (True was a ramp of 1 rpm/s)
            ok = isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, (bool, np.bool_))
            try:
                ok = ok and float(v) > 0  # NaN fails, inf (no ramp) passes
            except OverflowError:  # an int beyond the float range (10**400): math.isnan raised it, bare
                raise ValueError(f"PumpingPlant: {name} must be a positive number of rpm/s (inf: no ramp), got an "
                                 "integer beyond the float range") from None
            if not ok:
                raise ValueError(f"PumpingPlant: {name} must be a positive number of rpm/s (inf: no ramp), got {v!r}")
        check_real(self.process_noise_pole, "PumpingPlant: process_noise_pole (in [0, 1))", low=0, high=1,
                   high_open=True)
        k, a, b = (float(c) for c in self.static_coefficients)
        if not self.shutoff_head > b:
            raise ValueError(f"PumpingPlant: shutoff_head ({self.shutoff_head:g}) must exceed β = {b:g}, "
                             "or the pumps cannot reach the static curve")
        lo, hi = self.speed_range
        # The calibrated turbine needs R Q² = (h0 − β) n² − α n − κ > 0 and rising in n over the range.
        g = self.shutoff_head - b
        if not (0 < lo < hi and 2 * g * lo - a > 0 and g * lo * lo - a * lo - k > 0):
            raise ValueError(f"PumpingPlant: the static curve cannot be calibrated over speed_range {self.speed_range}")
        if not b * lo * lo + a * lo + k > 0:  # the low-flow branch H_j (Q/Q_j)^m needs H_j > 0
            raise ValueError(f"PumpingPlant: the static pressure at speed_range[0] = {lo:g} rpm must be positive")

    # -- derived constants --------------------------------------------------
    @property
    def inertance(self) -> float:
        """I = L / (g A) in mlc per (L/s²): head needed to accelerate the column by 1 L/s per s."""
        area = math.pi * self.pipe_diameter**2 / 4
        return self.pipe_length / (9.81 * area) / 1000.0  # /1000: Q in L/s, not m³/s

    @property
    def loss(self) -> float:
        """R = h_2/4 + R_f (mlc/(L/s)²): pump drop (Q/2 per pump) plus pipe friction."""
        return self.pump_drop / 4 + self.pipe_loss

    # -- statics ------------------------------------------------------------
    def static_pressure(self, speed: np.ndarray | float) -> np.ndarray:
        """The curve the rig is calibrated to, H(ū) = β ū² + α ū + κ.

        Parameters
        ----------
        speed : float or array_like, any shape
            Constant speed references ū (rpm), finite and within ``speed_range``.

        Returns
        -------
        ndarray, the shape of ``speed``
            Pressure (mlc).
        """
        k, a, b = self.static_coefficients
        n = self._speeds(speed)
        return b * n**2 + a * n + k

    def steady_flow(self, speed: np.ndarray | float) -> np.ndarray:
        """Equilibrium flow Q̄ at constant speed ū: R Q̄² = (h_0 − β) ū² − α ū − κ.

        Parameters
        ----------
        speed : float or array_like, any shape
            Constant speed references ū (rpm), finite and within ``speed_range``.

        Returns
        -------
        ndarray, the shape of ``speed``
            Flow (L/s).
        """
        k, a, b = self.static_coefficients
        n = self._speeds(speed)
        return np.sqrt(((self.shutoff_head - b) * n**2 - a * n - k) / self.loss)

    def _speeds(self, speed: object) -> np.ndarray:
        """Speeds (rpm) of any shape as a float array: numbers (no text, bools or None), finite, within
        ``speed_range`` (below it the calibrated formula is no equilibrium, the low-flow branch holds there)."""
        n = real_array(speed, "speed", "speeds (rpm)")
        bad = ~np.isfinite(n)
        if bad.any():
            raise ValueError(f"speed has {int(bad.sum())} non-finite value(s) (NaN or inf)")
        self._check_reference(n.ravel(), "speed")
        return n

    @cached_property
    def _low_flow(self) -> tuple[float, float, float]:
        """(Q_j, H_j, m) of the low-flow branch of H_t: H_t(Q) = H_j (Q / Q_j)^m below Q_j.

        Q_j is the steady flow at the lowest reference of ``speed_range``, H_j = H_t(Q_j) from the
        calibrated characteristic, and m = Q_j H_t'(Q_j) / H_j makes the slope continuous there.
        """
        k, a, b = (float(c) for c in self.static_coefficients)
        lo = float(self.speed_range[0])
        g = self.shutoff_head - b
        R = self.loss
        qj = float(self.steady_flow(lo))
        hj = self._calibrated_head(qj)
        # dH_t/dQ = H'(n*) / (dQ/dn*) along the calibrated characteristic, at n* = lo
        slope = (2 * b * lo + a) * 2 * R * qj / (2 * g * lo - a)
        return qj, hj, qj * slope / hj

    def _calibrated_head(self, flow: float) -> float:
        k, a, b = self.static_coefficients
        g = self.shutoff_head - b
        R = self.loss
        disc = a * a + 4 * g * (k + R * flow * flow)
        n_star = (a + math.sqrt(disc)) / (2 * g)
        return self.shutoff_head * n_star * n_star - R * flow * flow

    def turbine_head(self, flow: float) -> float:
        """H_t(Q) (mlc), the turbine characteristic calibrated so that the steady state is eq. (1).

        Below the flow Q_j of the lowest reference of ``speed_range`` (24.2 L/s for the default
        plant) it continues as H_j (Q/Q_j)^m down to H_t(0) = 0 (module docs, "Low flow").

        Parameters
        ----------
        flow : float
            Q (L/s), >= 0.

        Returns
        -------
        float
            Head (mlc).
        """
        # float() parsed '3' and took True; a 0-d array is one number, as check_real (and steady_state) take it
        q = check_real(flow, "flow (L/s)")
        if q < 0.0:
            raise ValueError(f"flow must be >= 0 L/s (the non-return valves stop a reverse flow), got {flow!r}")
        qj, hj, m = self._low_flow
        if q < qj:
            return hj * (q / qj) ** m
        return self._calibrated_head(q)

    def steady_state(self, speed: float) -> tuple[float, float, float]:
        """Equilibrium state at a constant reference.

        Parameters
        ----------
        speed : float
            The speed reference (rpm), within ``speed_range``.

        Returns
        -------
        (float, float, float)
            (n_c, n, Q): the drive's and the rotor's speeds (rpm), both the reference, and the flow (L/s).
        """
        # the calibrated formula of steady_flow is no equilibrium below speed_range[0] (the turbine's low-flow branch
        # takes over there), and text is no speed: one speed as simulate takes it
        s = self._one_speed(speed, "speed")
        return (s, s, float(self.steady_flow(s)))

    # -- dynamics -----------------------------------------------------------
    def _one_speed(self, value: object, what: str) -> float:
        """One speed (rpm): a finite number inside the calibrated range, or the reference check's error."""
        s = float(as_1d_finite([value], what)[0])
        self._check_reference(np.array([s]), what)
        return s

    def _check_reference(self, u: np.ndarray, what: str = "speed reference") -> None:
        lo, hi = self.speed_range
        bad = np.flatnonzero((u < lo) | (u > hi))
        if bad.size:
            raise ValueError(f"{what} must stay within {lo:g}–{hi:g} rpm (the calibrated range); "
                             f"sample {bad[0]} is {u[bad[0]]:g} rpm")

    def _disturbances(self, N: int, rng, *, noise: bool, process_noise: bool, who: str = "simulate"):
        """The noise sequences and disturbance constants of a run of N samples (one- and two-speed rigs; ``who``:
        the method run, which a message names).

        Returns ``eps_w, eps_s, eps_a`` (unit normals for the process noise, surge and air),
        ``v`` (the transmitter noise, mlc) and ``(phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain)``.
        """
        # a switch that is no bool ('no' is truthy) would draw noise the caller meant off
        noise, process_noise = check_bool(noise, "noise"), check_bool(process_noise, "process_noise")
        slow = self.surge_intensity > 0 or self.air_loss_per_rpm > 0
        need_rng = (noise and self.noise_std > 0) or (process_noise and (self.process_noise_std > 0 or slow))
        if need_rng and rng is None:
            raise ValueError(f"{who}: pass seed (an int or a numpy Generator) or switch the noise off; "
                             "the plant never draws unseeded noise")
        if rng is not None and not isinstance(rng, np.random.Generator):
            # numpy takes True for the seed 1 and a list for a seed sequence, and names no argument for -1 or '3'
            if not isinstance(rng, (int, np.integer)) or isinstance(rng, (bool, np.bool_)):
                raise TypeError(f"seed must be an int or a numpy Generator, got {rng!r} ({type(rng).__name__})")
            rng = check_seed(rng)
        gen = np.random.default_rng(rng) if not isinstance(rng, np.random.Generator) else rng
        # Draw all four noise sequences up front, always in this order, so a seed fixes the run
        # whichever disturbances are switched on.
        eps_w, eps_v, eps_s, eps_a = (gen.standard_normal((4, N)) if need_rng else np.zeros((4, N)))
        phi = self.process_noise_pole
        w_on = process_noise and self.process_noise_std > 0
        w_gain = self.process_noise_std * math.sqrt(1 - phi * phi) if w_on else 0.0
        w0 = self.process_noise_std * eps_w[0] if w_on else 0.0  # w starts stationary
        v = self.noise_std * eps_v if noise else np.zeros(N)
        # Transient-excited slow disturbances (module docs, "Disturbances"): both start at rest
        # (the rig has been settled at u[0]) and are driven by the shaft-speed change of each sample.
        s_phi = math.exp(-self.Ts / self.surge_time)
        s_gain = self.surge_intensity / math.sqrt(self.Ts) if process_noise else 0.0
        a_phi = math.exp(-self.Ts / self.air_vent_time)
        a_gain = self.air_loss_per_rpm if process_noise else 0.0
        return eps_w, eps_s, eps_a, v, (phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain)

    def simulate(
        self,
        u: np.ndarray | Sequence[float],
        seed: int | np.random.Generator | None = None,
        noise: bool = True,
        process_noise: bool = True,
        x0: tuple[float, float, float] | None = None,
    ) -> PlantRun:
        """Simulate the rig for a sampled speed reference.

        Parameters
        ----------
        u : array_like, shape (N,)
            Speed reference (rpm), held constant over each sample.
        seed : int or numpy Generator, optional
            Source of noise (an int seeds ``np.random.default_rng``). Required when any noise is on.
        noise : bool
            Add transmitter noise (std ``noise_std``) to the measured pressure.
        process_noise : bool
            Add the process disturbances (module docs, "Disturbances"): the AR(1) head disturbance
            w, the transient surge s and the air head loss a. False gives the noise-free physics.
        x0 : (n_c, n, Q), optional
            Initial state; default the equilibrium at ``u[0]``.

        Returns
        -------
        PlantRun
        """
        u = as_1d_finite(u, "speed reference")
        if u.size == 0:  # u[0] gives the initial equilibrium: an IndexError named nothing
            raise ValueError("speed reference must hold at least one sample (rpm), got none")
        self._check_reference(u)
        N = u.size
        eps_w, eps_s, eps_a, v, (phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain) = self._disturbances(
            N, seed, noise=noise, process_noise=process_noise)

        nc, n, q = self.steady_state(u[0]) if x0 is None else initial_state(x0, _STATE)
        S, delay, dt, consts = self._kernel_constants
        out = _integrate(u, eps_w, eps_s, eps_a, float(phi), float(w_gain), float(w0), float(s_phi), float(s_gain),
                         float(a_phi), float(a_gain), nc, n, q, S, delay, dt, consts)
        p, speed, flow, surge_out, air_out = out
        t = np.arange(N) * self.Ts
        return PlantRun(t=t, u=np.array(u), y=p + v, pressure=p, speed=speed, flow=flow, Ts=self.Ts,
                        surge=surge_out, air_loss=air_out)

    @cached_property
    def _kernel_constants(self) -> tuple[int, int, float, np.ndarray]:
        """(substeps S, dead-time substeps, substep length dt (s), the constants of ``_rhs``)."""
        S = int(self.substeps)
        dt = self.Ts / S
        delay = int(round(self.dead_time / dt))  # substeps during which the previous reference still acts
        k0, a0, b0 = (float(c) for c in self.static_coefficients)
        qj, hj, m = self._low_flow
        consts = np.array([k0, a0, self.shutoff_head - b0, self.drive_lag, self.inertia * math.pi / 30.0,
                           self.speed_stiffness, self.pump_torque, self.shutoff_head, self.loss, self.inertance,
                           qj, hj, m, float(self.ramp_up), float(self.ramp_down)])
        consts.setflags(write=False)
        return S, delay, dt, consts

    # -- closed loop --------------------------------------------------------
    def closed_loop(
        self,
        controller: Callable[[int, float], float],
        n_samples: int,
        *,
        u0: float,
        seed: np.random.Generator | int | None = None,
        noise: bool = True,
        process_noise: bool = True,
        x0: tuple[float, float, float] | None = None,
    ) -> PlantRun:
        """Run the rig under feedback: at each sample a controller reads the measured pressure and sets the reference.

        At t_k = k Ts the pressure y(k) is measured (with transmitter noise when ``noise``), the
        controller returns the speed reference u(k), which is held over [t_k, t_k + Ts) (and, for
        the dead time, the previous reference still acts at the start of the sample: ``u0`` before
        the first). The physics, the noise and the disturbances are those of :meth:`simulate`,
        sample for sample: a controller that returns a fixed sequence u with u(0) = ``u0`` gives
        exactly ``simulate(u)`` with the same ``seed``.

        Parameters
        ----------
        controller : callable (k, y) -> float
            Called once per sample, in order, with the sample index k and the measured pressure
            y(k) (mlc); returns the speed reference u(k) (rpm), which must lie in ``speed_range``.
            It may keep its own state (an integrator).
        n_samples : int
            Number of samples N.
        u0 : float
            The reference the rig has been settled at before the loop starts (rpm).
        seed : numpy Generator or int, optional
            Source of noise, as for :meth:`simulate`; required when any noise is on.
        noise : bool
            Add transmitter noise to the pressure the controller reads.
        process_noise : bool
            Add the process disturbances (module docs, "Disturbances").
        x0 : (n_c, n, Q), optional
            Initial state; default the equilibrium at ``u0``.

        Returns
        -------
        PlantRun
            ``u`` the references the controller set, ``y`` the pressures it read.
        """
        N = check_count(n_samples, "n_samples", low=1)
        if not callable(controller):
            raise TypeError(f"controller must be callable as controller(k, y) -> u, got {type(controller).__name__}")
        prev = self._one_speed(u0, "u0")
        eps_w, eps_s, eps_a, v, (phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain) = self._disturbances(
            N, seed, noise=noise, process_noise=process_noise, who="closed_loop")
        nc, n, q = self.steady_state(prev) if x0 is None else initial_state(x0, _STATE)
        S, delay, dt, consts = self._kernel_constants
        out = np.empty((7, N))  # u, y, pressure, speed, flow, surge, air
        w, surge, air = float(w0), 0.0, 0.0
        for k in range(N):
            p_k = _pressure(q, consts)
            y_k = p_k + v[k]
            u_k = _reference(controller(k, float(y_k)), k)
            if not math.isfinite(u_k):
                raise ValueError(f"the controller returned {u_k!r} at sample {k}")
            self._check_reference(np.array([u_k]), f"the controller's reference at sample {k}")
            out[:, k] = (u_k, y_k, p_k, n, q, surge, air)
            _, w, nc, n, q, surge, air = _sample(u_k, prev, k, w, surge, air, nc, n, q, eps_w[k], eps_s[k], eps_a[k],
                                                 float(phi), float(w_gain), float(s_phi), float(s_gain), float(a_phi),
                                                 float(a_gain), S, delay, dt, consts)
            prev = u_k
        return PlantRun(t=np.arange(N) * self.Ts, u=out[0], y=out[1], pressure=out[2], speed=out[3], flow=out[4],
                        Ts=self.Ts, surge=out[5], air_loss=out[6])

    def linearize(self, speed: float, rel_step: float = 1e-5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The noise-free sampled rig linearised at the steady state of ``speed``, numerically.

        State x(k) = (n_c, n, Q, r(k−1)) at t_k (the previous reference acts during the dead time),
        input the reference r(k), output the pressure y(k) = H_t(Q(k)):
        Δx(k+1) = A Δx(k) + B Δr(k), Δy(k) = C Δx(k). A and B are central differences of the
        compiled one-sample map (the RK4 of :meth:`simulate`), C of H_t, each with a step of
        ``rel_step`` times the variable's level.

        Parameters
        ----------
        speed : float
            Operating reference (rpm), within ``speed_range``.
        rel_step : float
            Relative finite-difference step (dimensionless), in (0, 1).

        Returns
        -------
        A : ndarray, shape (4, 4)
        B : ndarray, shape (4, 1)
            Per rpm.
        C : ndarray, shape (1, 4)
            mlc per unit of each state.
        """
        s = self._one_speed(speed, "speed")
        # below 1: a step of the whole level crosses zero (a negative flow: C was NaN, A's radius 1.13 at 10)
        rel_step = check_real(rel_step, "rel_step", low=0, low_open=True, high=1, high_open=True)
        S, delay, dt, consts = self._kernel_constants
        x_bar = np.array([*self.steady_state(s), s])

        def step(x: np.ndarray, r: float) -> np.ndarray:
            nc, n, q = _advance(r, x[3], 0.0, 0.0, x[0], x[1], x[2], S, delay, dt, consts)
            return np.array([nc, n, q, r])

        J = np.zeros((4, 5))
        for j in range(5):
            h = rel_step * (abs(x_bar[j]) if j < 4 else abs(s))
            e = np.zeros(5)
            e[j] = h
            J[:, j] = (step(x_bar + e[:4], s + e[4]) - step(x_bar - e[:4], s - e[4])) / (2 * h)
        hq = rel_step * x_bar[2]
        C = np.zeros((1, 4))
        C[0, 2] = (_pressure(x_bar[2] + hq, consts) - _pressure(x_bar[2] - hq, consts)) / (2 * hq)
        return J[:, :4], J[:, 4:], C

    def local_time_constant(self, speed: float) -> float:
        """−Ts / ln|p| of the dominant pole of :meth:`linearize` at ``speed`` (s): the rig's own local time constant.

        Parameters
        ----------
        speed : float
            Operating reference (rpm).

        Returns
        -------
        float
            Seconds.
        """
        A, _, _ = self.linearize(speed)
        return float(-self.Ts / np.log(np.max(np.abs(np.linalg.eigvals(A)))))

    # -- measured facts -----------------------------------------------------
    def step_time_constant(self, speed: float, step: float = 20.0, horizon: float = 15.0) -> float:
        """Time (s) for the noise-free pressure to cover 63.2 % of its change after a reference step.

        The step of ``step`` rpm is applied at a settled ``speed``; the time is counted from the
        step instant (so it includes the dead time and the drive and rotor lags), over a run of
        ``horizon`` seconds after it.

        Parameters
        ----------
        speed : float
            The settled reference before the step (rpm), within ``speed_range``.
        step : float, optional
            The step (rpm), nonzero, ``speed + step`` within ``speed_range`` too (default 20).
        horizon : float, optional
            Seconds simulated after the step, > 0 (default 15); a response that does not settle within it is
            refused (``ValueError``).

        Returns
        -------
        float
            Seconds.
        """
        speed = self._one_speed(speed, "speed")  # text was concatenated with the step ('can only concatenate str')
        step = check_real(step, "step (rpm)")
        if step == 0:
            raise ValueError("step (rpm) must not be 0: a time constant is read off the response to a step")
        self._one_speed(speed + step, f"speed + step ({speed:g} {'+' if step > 0 else '-'} {abs(step):g} rpm)")
        horizon = check_real(horizon, "horizon (s)", low=0, low_open=True)
        n_hold = 10
        # the run's arrays, about 15 floats a sample: a horizon no memory holds is said, not numpy's MemoryError
        n_total = n_hold + max(1, check_count(int(round(horizon / self.Ts)), "horizon (in samples of Ts)",
                                              item_bytes=15 * 8))
        u = np.r_[np.full(n_hold, speed), np.full(n_total - n_hold, speed + step)]
        y = self.simulate(u, noise=False, process_noise=False).pressure
        frac = (y[n_hold:] - y[n_hold - 1]) / (y[-1] - y[n_hold - 1])
        if abs(frac[-1] - 1) > 1e-6 or abs(self.static_pressure(speed + step) - y[-1]) > 1e-6:
            raise ValueError(f"the response did not settle within {horizon} s; increase horizon")
        target = 1 - math.exp(-1)
        i = int(np.argmax(frac >= target))
        # linear interpolation between samples i-1 and i (frac[0] is the step instant, value 0)
        return float((i - 1 + (target - frac[i - 1]) / (frac[i] - frac[i - 1])) * self.Ts)

    def static_point_std(self, speed: float, n_samples: int) -> float:
        """Std (mlc) of the mean of ``n_samples`` settled measurements at ``speed`` (linearised).

        Transmitter noise is white: variance σ_v²/n. The head disturbance w is AR(1) with pole φ and
        stationary std σ_w; the water column passes it to the pressure with static gain
        G = H_t'(Q̄) / (H_t'(Q̄) + 2 R Q̄ ) (low-pass filtering does not change the zero-frequency
        power), so the mean of n samples has variance ≈ G² σ_w² (1 + φ)/(1 − φ) / n. The two add.

        The slow surge and air disturbances are left out: they are excited only by speed changes
        and :func:`static_experiment` waits them out (their effect on a settled mean is under
        0.001 mlc, against about 0.03 mlc from the two terms above).

        Parameters
        ----------
        speed : float
            The settled reference (rpm), within ``speed_range``.
        n_samples : int
            Measurements averaged, >= 1.

        Returns
        -------
        float
            Standard deviation of the mean (mlc).
        """
        n = self._one_speed(speed, "speed")
        n_samples = check_count(n_samples, "n_samples", low=1)
        q = float(self.steady_flow(n))
        dq = 1e-4 * q
        ht_slope = (self.turbine_head(q + dq) - self.turbine_head(q - dq)) / (2 * dq)
        G = ht_slope / (ht_slope + 2 * self.loss * q)
        phi = self.process_noise_pole
        var = self.noise_std**2 + (G * self.process_noise_std) ** 2 * (1 + phi) / (1 - phi)
        return math.sqrt(var / n_samples)


@nb.njit(cache=True, nogil=True)
def _rhs(nc, n, q, r, w, air, c):  # pragma: no cover - compiled
    """The ODE right-hand side (module docs, "Physical model" and "Low flow"); c: the constants."""
    k0, a0, g, tv, jp, ks, cp, h0, R, inert, qj, hj, m = (c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8],
                                                          c[9], c[10], c[11], c[12])
    if q >= qj:
        rq2 = R * q * q
        n_star = (a0 + math.sqrt(a0 * a0 + 4 * g * (k0 + rq2))) / (2 * g)
        ht = h0 * n_star * n_star - rq2  # turbine_head(q), inlined
    elif q > 0.0:
        rq2 = R * q * q
        ht = hj * (q / qj) ** m
    else:
        rq2 = 0.0
        ht = 0.0
    # R Q² lumps pump drop and pipe friction; air costs the fraction `air` of h_0 n²
    dq = (h0 * (1.0 - air) * n * n - rq2 - ht + w) / inert
    if q <= 0.0 and dq < 0.0:
        dq = 0.0  # the non-return valves hold the column: the flow stops, it does not reverse
    # the drive's ramps limit the rate of its commanded speed (inf: no ramp, the rate passes unchanged)
    dnc = min(max((r - nc) / tv, -c[14]), c[13])
    return dnc, (ks * (nc - n) + cp * (nc * nc - n * n)) / jp, dq


@nb.njit(cache=True, nogil=True)
def _pressure(q, c):  # pragma: no cover - compiled
    """H_t(Q) (mlc): the measured pressure at flow q (``turbine_head``, inlined); c: the constants."""
    k0, a0, g, h0, R, qj, hj, m = c[0], c[1], c[2], c[7], c[8], c[10], c[11], c[12]
    if q >= qj:
        n_star = (a0 + math.sqrt(a0 * a0 + 4 * g * (k0 + R * q * q))) / (2 * g)
        return h0 * n_star * n_star - R * q * q
    return hj * (q / qj) ** m


@nb.njit(cache=True, nogil=True)
def _advance(uk, prev, wk, air, nc, n, q, S, delay, dt, c):  # pragma: no cover - compiled
    """One sample of RK4: the state (n_c, n, Q) at t_k + Ts under the reference uk (prev for the dead time)."""
    for j in range(S):
        r = uk if j >= delay else prev
        a1, b1, c1 = _rhs(nc, n, q, r, wk, air, c)
        h = 0.5 * dt
        a2, b2, c2 = _rhs(nc + h * a1, n + h * b1, q + h * c1, r, wk, air, c)
        a3, b3, c3 = _rhs(nc + h * a2, n + h * b2, q + h * c2, r, wk, air, c)
        a4, b4, c4 = _rhs(nc + dt * a3, n + dt * b3, q + dt * c3, r, wk, air, c)
        s6 = dt / 6.0
        nc += s6 * (a1 + 2 * a2 + 2 * a3 + a4)
        n += s6 * (b1 + 2 * b2 + 2 * b3 + b4)
        q += s6 * (c1 + 2 * c2 + 2 * c3 + c4)
        if q < 0.0:
            q = 0.0  # the valves close within the substep (RK4 overshoots the stop)
    return nc, n, q


@nb.njit(cache=True, nogil=True)
def _sample(uk, prev, k, w, surge, air, nc, n, q, eps_w_k, eps_s_k, eps_a_k, phi, w_gain, s_phi, s_gain, a_phi,
            a_gain, S, delay, dt, c):  # pragma: no cover - compiled
    """Sample k of a run: the pressure read at t_k, then the state and disturbances carried to t_k + Ts.

    Returns (p_k, w_k, nc, n, q, surge, air): the pressure at t_k, the fast disturbance over the
    sample, and the state and slow disturbances at t_k + Ts.
    """
    if k > 0:
        w = phi * w + w_gain * eps_w_k
    p = _pressure(q, c)
    n_old = n
    nc, n, q = _advance(uk, prev, w + surge, air, nc, n, q, S, delay, dt, c)
    dn = abs(n - n_old)
    surge_next = s_phi * surge + s_gain * dn * eps_s_k
    # a pump full of air delivers no head: the loss cannot exceed the whole head
    air_next = min(1.0, a_phi * air + a_gain * dn * eps_a_k * eps_a_k)
    return p, w, nc, n, q, surge_next, air_next


@nb.njit(cache=True, nogil=True)
def _integrate(u, eps_w, eps_s, eps_a, phi, w_gain, w0, s_phi, s_gain, a_phi, a_gain, nc, n, q, S, delay, dt,
               c):  # pragma: no cover - compiled
    """RK4 over the whole record; returns (pressure, speed, flow, surge, air loss), each shape (N,)."""
    N = u.shape[0]
    p = np.empty(N)
    speed = np.empty(N)
    flow = np.empty(N)
    surge_out = np.empty(N)
    air_out = np.empty(N)
    prev = u[0]
    surge = 0.0
    air = 0.0
    w = w0
    for k in range(N):
        speed[k] = n
        flow[k] = q
        surge_out[k] = surge
        air_out[k] = air
        p[k], w, nc, n, q, surge, air = _sample(u[k], prev, k, w, surge, air, nc, n, q, eps_w[k], eps_s[k],
                                                eps_a[k], phi, w_gain, s_phi, s_gain, a_phi, a_gain, S, delay, dt, c)
        prev = u[k]
    return p, speed, flow, surge_out, air_out


# ---------------------------------------------------------------------------
# The experiment: input design, static test, files
# ---------------------------------------------------------------------------

#: The narrowest speed range a staircase reference is designed over (rpm): its smallest steps (40 rpm) must fit
#: both ways from its middle.
_MIN_SPAN = 80.0
#: A staircase part's holds last 80–180 samples and it needs at least 4 (the first and two forced to the range's
#: ends among the others): 3 · 180 + 1 samples hold four whatever the seed, 240 or fewer never do, and between
#: the two it depended on the seed. Refused below it for every seed; the draws of every length it keeps are as before.
_MIN_PART = 3 * 180 + 1


def speed_reference(*, n_samples: int = N_SAMPLES, n_ident: int = N_IDENT, seed: int = DEFAULT_SEED,
                    low: float = 750.0, high: float = 1650.0) -> np.ndarray:
    """A staircase speed reference (rpm) like the paper's Fig. 3, shape (n_samples,).

    Levels change every 4–9 s (3 to 11 time constants of the plant), by steps of three sizes
    (small 40–150, medium 150–400, large 400–900 rpm, with probabilities 0.4, 0.35, 0.25), up
    or down at random, turned round (or shortened) where the range [``low``, ``high``] has no room;
    levels are whole multiples of 10 rpm. The identification part
    (``:n_ident``) and the validation part (``n_ident:``) are designed separately and each visits
    both ends of the range (one hold is forced to within 30 rpm of ``low``, another of ``high``),
    so both exercise the whole operating range. A hold forced to an end takes whatever step leads
    there: as little as 10 rpm, or none, when a neighbour holds that very level (the two then
    make one longer hold); over seeds 0–199, 1 part in 8 has such a step. Each part needs at least
    541 samples (27 s: four holds for any seed); a shorter one raises ``ValueError``.

    Parameters
    ----------
    n_samples : int
        Length of the whole reference, samples of Ts = 0.05 s (default 4000: the identification and validation
        records of :func:`graybox.load_pumping`).
    n_ident : int
        Samples of the identification part, the first (default 3200); the rest is the validation part.
    seed : int
        Seed of the random levels and holds (default 2011, the bundled records').
    low, high : float
        The speed range (rpm), 0 < low; default 750–1650.

    Returns
    -------
    ndarray, shape (n_samples,)
        The speed reference (rpm).
    """
    n_samples, n_ident, seed = reference_lengths(n_samples, n_ident, seed)
    rng = np.random.default_rng([seed, 1])
    parts = [_staircase(n_ident, rng, low, high), _staircase(n_samples - n_ident, rng, low, high)]
    return np.concatenate(parts)


def reference_lengths(n_samples: object, n_ident: object, seed: object) -> tuple[int, int, int]:
    """A reference's (n_samples, n_ident, seed) checked: counts with 0 < n_ident < n_samples, each part
    (``n_ident`` and ``n_samples - n_ident``) at least ``_MIN_PART`` (541) samples, a seed >= 0."""
    n_samples = check_count(n_samples, "n_samples", low=2)
    n_ident = check_int(n_ident, "n_ident", low=1)
    if not n_ident < n_samples:
        raise ValueError(f"need 0 < n_ident < n_samples, got {n_ident} and {n_samples}")
    if min(n_ident, n_samples - n_ident) < _MIN_PART:  # said for every seed, not for the seeds that drew long holds
        raise ValueError(f"each part of a staircase reference needs at least {_MIN_PART} samples (4 holds of 80–180 "
                         f"samples for every seed), got n_ident = {n_ident} and n_samples − n_ident = "
                         f"{n_samples - n_ident}; e.g. n_samples = {2 * _MIN_PART}, n_ident = {_MIN_PART}")
    return n_samples, n_ident, check_seed(seed)


def _staircase(n: int, rng: np.random.Generator, low: float, high: float) -> np.ndarray:
    """One part of a speed reference: holds of 80–180 samples at whole multiples of 10 rpm in [low, high]."""
    # a pump's speed is positive (a range from -100 rpm gave negative levels, as two_speed_reference refused)
    low, high = check_real(low, "low (rpm)", low=0, low_open=True), check_real(high, "high (rpm)")
    # the levels are the multiples of 10 rpm inside [low, high] (a low of 755 rpm gave levels of 750 and a high of
    # 1646 rpm levels of 1650, and clipping to 755 levels off the grid): the steps move between lo10 and hi10
    lo10, hi10 = math.ceil(low / 10) * 10.0, math.floor(high / 10) * 10.0
    if not hi10 - lo10 >= _MIN_SPAN:
        raise ValueError(f"the speed range [{low:g}, {high:g}] rpm must span at least {_MIN_SPAN:g} rpm between whole "
                         "multiples of 10 rpm: the steps are 40–900 rpm")
    holds: list[int] = []
    total = 0
    while total < n:  # a running total: summing the list at each draw was quadratic in the holds (the same draws)
        holds.append(int(rng.integers(80, 181)))  # 4–9 s at Ts = 0.05 s
        total += holds[-1]
    if len(holds) < 4:
        raise ValueError(f"a part of {n} samples is too short for a staircase; need at least 4 holds")
    sizes = ((40.0, 150.0), (150.0, 400.0), (400.0, 900.0))  # small, medium, large (rpm)
    levels = [float(rng.integers(int(lo10) // 10, int(hi10) // 10 + 1) * 10)]
    for _ in holds[1:]:
        cur = levels[-1]
        lo_s, hi_s = sizes[int(rng.choice(3, p=[0.4, 0.35, 0.25]))]
        size = rng.uniform(lo_s, hi_s)
        up_room, down_room = hi10 - cur, cur - lo10
        go_up = rng.random() < 0.5
        if size > (up_room if go_up else down_room):
            go_up = not go_up  # no room this way: step the other way
        room = up_room if go_up else down_room
        if size > room:  # no room either way for this size: a step into the larger room
            go_up = up_room >= down_room
            size = rng.uniform(40.0, max(up_room, down_room))
        nxt = cur + size if go_up else cur - size
        levels.append(float(np.clip(round(nxt / 10) * 10, lo10, hi10)))
    # Force both ends of the range into this part, at two distinct holds away from the first.
    i_lo, i_hi = rng.choice(np.arange(1, len(holds)), size=2, replace=False)
    # rounded to the grid, held within 30 rpm of the end: a low of 188 rpm rounded 216 up to 220, 32 rpm above it
    # (the multiples of 10 nearest the ends lie within 30 rpm of them: a range on the grid draws as before)
    near_lo, near_hi = math.floor((low + 30) / 10) * 10.0, math.ceil((high - 30) / 10) * 10.0
    levels[i_lo] = float(np.clip(round(rng.uniform(low, low + 30) / 10) * 10, lo10, min(hi10, near_lo)))
    levels[i_hi] = float(np.clip(round(rng.uniform(high - 30, high) / 10) * 10, max(lo10, near_hi), hi10))
    return np.repeat(levels, holds)[:n]


def static_experiment(
    plant: PumpingPlant,
    *,
    speeds: Sequence[float] = STATIC_SPEEDS,
    seed: int | np.random.Generator | None = None,
    settle: float = 180.0,
    average: float = 6.0,
) -> StaticPoints:
    """The paper's static test: hold each speed, wait for transients to die out, average the pressure.

    The speeds are visited in the given order as one continuous staircase (as on the rig); at each,
    the first ``settle`` seconds are discarded and the next ``average`` seconds of noisy
    measurements are averaged.

    Why the default wait is 180 s: the plant's own transient is over in about 8 s (over 6 time
    constants at 750 rpm), but each speed change also sets off the slow surge and air
    disturbances (module docs, "Disturbances"), which decay in τ_s = 6 s and τ_a = 30 s. After
    180 s (6 τ_a) they move the averaged pressure by under 0.001 mlc, so each point is eq. (1)
    plus the fast disturbance and transmitter noise averaged over ``average`` seconds
    (:meth:`PumpingPlant.static_point_std`, about 0.03 mlc for 6 s). The paper's static curve was
    a separate experiment of this kind ("after transients died out, the output pressure was
    recorded"); the dynamic record, whose levels last 4–9 s, never lets the slow disturbances
    die out, which is why its black-box models miss the static curve. A shorter ``settle`` is
    fine when the speed does not change (nothing excites them). ``seed`` (an int or a numpy
    Generator) is the source of noise, as for :meth:`PumpingPlant.simulate`.

    Parameters
    ----------
    plant : PumpingPlant
        The simulated rig.
    speeds : sequence of float
        The speeds held, in the order visited (rpm; default 750, 850, …, 1650), within the plant's speed range.
    seed : int or numpy Generator, optional
        Source of noise; required while the plant's noise is on (:meth:`PumpingPlant.simulate`).
    settle : float
        Seconds discarded at each speed (default 180).
    average : float
        Seconds averaged after them (default 6).

    Returns
    -------
    StaticPoints
        ū = ``speeds`` (rpm), ȳ = mean measured pressure (mlc).
    """
    check_plant(plant)
    sp = static_speeds(speeds, "speeds")
    check_static_levels(sp, plant.speed_range, "speeds")
    n_settle, n_avg = static_samples(plant.Ts, settle, average, sp.size)
    u = np.repeat(sp, n_settle + n_avg)
    run = plant.simulate(u, seed=seed)
    y = run.y.reshape(sp.size, n_settle + n_avg)[:, n_settle:]
    return StaticPoints(sp, y.mean(axis=1), name="pumping static points", units=("rpm", "mlc"))


def check_plant(plant: object, kind: type = PumpingPlant) -> "PumpingPlant":
    """``plant`` if it is a ``kind`` (a :class:`PumpingPlant`, or the two-speed rig), else a ``TypeError`` naming it
    (another object failed on its first missing attribute, "'str' object has no attribute 'Ts'")."""
    if not isinstance(plant, kind):
        raise TypeError(f"plant must be a {kind.__name__}, got {type(plant).__name__}")
    return plant


def static_speeds(speeds: object, name: str) -> np.ndarray:
    """The levels of a static test (rpm), shape (M,): finite, at least one."""
    sp = as_1d_finite(speeds, name)
    if sp.size == 0:
        raise ValueError(f"{name}: no speed given; a static test needs at least one level (rpm)")
    return sp


def check_static_levels(levels: np.ndarray, speed_range: tuple[float, float], name: str) -> None:
    """``ValueError`` naming the first level (a speed, or a row of speeds) of a static test outside the rig's
    ``speed_range``, or repeated: said of the levels given, before the run, not of the run's reference they become
    ("sample 3720") nor, after it, of the points (StaticPoints holds one point per level)."""
    seen: dict[object, int] = {}
    for j, key in enumerate(levels.tolist() if levels.ndim == 1 else map(tuple, levels.tolist())):
        if key in seen:
            level = f"{key:g}" if levels.ndim == 1 else str(list(key))
            raise ValueError(f"{name}[{j}] repeats {name}[{seen[key]}] ({level} rpm): a static test gives one point per "
                             "level; for a way up and a way down (a hysteresis), run two tests")
        seen[key] = j
    lo, hi = speed_range
    out = (levels < lo) | (levels > hi)
    bad = np.flatnonzero(out if out.ndim == 1 else out.any(axis=1))
    if bad.size:
        i = int(bad[0])
        level = f"{levels[i]:g}" if levels.ndim == 1 else str(levels[i].tolist())
        raise ValueError(f"{name}[{i}] is {level} rpm, outside the rig's calibrated range {lo:g}–{hi:g} rpm "
                         "(speed_range)")


def static_samples(Ts: float, settle: object, average: object, levels: int = 1) -> tuple[int, int]:
    """A static test's samples per level: (discarded while settling, averaged), from ``settle`` >= 0 and
    ``average`` seconds (finite numbers; the average covers at least one sample of ``Ts``). The run over ``levels``
    levels must fit in memory (settle = 1e9 s was numpy's MemoryError, average = 1e300 s an OverflowError)."""
    settle = check_real(settle, "settle (s)", low=0)
    average = check_real(average, "average (s)", low=0, low_open=True)
    n_avg = int(round(average / Ts))
    if n_avg < 1:
        raise ValueError(f"average must cover at least one sample of {Ts:g} s, got {average:g} s")
    n_settle = int(round(settle / Ts))
    # the run's arrays, about 15 floats a sample (two inputs' a few more)
    check_count(levels * (n_settle + n_avg), f"the static test's samples, {levels} level(s) × (settle + average) / Ts",
                item_bytes=20 * 8)
    return n_settle, n_avg


def generate(seed: int = DEFAULT_SEED, plant: PumpingPlant | None = None) -> tuple[PlantRun, StaticPoints]:
    """The bundled experiment: the 4000-sample dynamic run and the 10 static points.

    Deterministic for a given ``seed``: the dynamic run uses stream ``[seed, 2]`` and the static
    test stream ``[seed, 3]`` of ``np.random.default_rng`` (the input design uses ``[seed, 1]``).
    """
    plant = PumpingPlant() if plant is None else check_plant(plant)
    u = speed_reference(seed=seed)
    run = plant.simulate(u, seed=np.random.default_rng([seed, 2]))
    static = static_experiment(plant, seed=np.random.default_rng([seed, 3]))
    return run, static


#: CSV column names of the bundled files.
DYNAMIC_COLUMNS = ("time_s", "speed_ref_rpm", "pressure_mlc")
STATIC_COLUMNS = ("speed_rpm", "pressure_mlc")


def write_csvs(out_dir: str | Path, seed: int = DEFAULT_SEED) -> tuple[Path, Path]:
    """Write ``dynamic.csv`` and ``static.csv`` of :func:`generate` into ``out_dir``.

    Formatting: time with 2 decimals (exact multiples of 0.05 s), speed with 1 decimal (levels are
    whole multiples of 10 rpm), pressure with 4 decimals (0.1 mm, 900 times finer than the
    transmitter noise std), Unix newlines.

    Returns
    -------
    (Path, Path)
        The dynamic and static files.
    """
    run, static = generate(seed)
    return write_csv_pair(out_dir, DYNAMIC_COLUMNS, [f"{t:.2f},{u:.1f},{y:.4f}" for t, u, y in zip(run.t, run.u, run.y)],
                          STATIC_COLUMNS, [f"{u:.1f},{y:.4f}" for u, y in zip(static.ubar, static.ybar)])


def write_csv_pair(out_dir: str | Path, dynamic_columns: Sequence[str], dynamic_lines: Sequence[str],
                   static_columns: Sequence[str], static_lines: Sequence[str]) -> tuple[Path, Path]:
    """Write a bundled data set's ``dynamic.csv`` and ``static.csv`` (header + lines, Unix newlines)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = (out / "dynamic.csv", out / "static.csv")
    # both texts made before either file is touched, and each file written whole or not at all: a failure left a new
    # dynamic record beside the old static points (two draws), or a torn file
    texts = [("\n".join([",".join(cols), *lines]) + "\n").encode("utf-8")
             for cols, lines in ((dynamic_columns, dynamic_lines), (static_columns, static_lines))]
    for path, text in zip(paths, texts):
        write_atomically(path, lambda f, text=text: f.write(text))
    return paths


def regenerate_main(argv: list[str] | None, *, module: str, folder: str, write) -> int:
    """The command line that regenerates a bundled data set: ``python -m MODULE [--out DIR] [--seed N]``.

    Without ``--out`` it writes into the source checkout's ``data/FOLDER`` (the bundled files), only those of the
    default seed (another seed's files need ``--out``); ``write(out_dir, seed)`` writes them.
    """
    ap = argparse.ArgumentParser(prog=f"python -m {module}", description=f"Regenerate the bundled data/{folder} CSVs.")
    ap.add_argument("--out", type=_folder_arg, default=None,
                    help=f"output folder (default: <repo>/data/{folder}, for the default seed only)")
    ap.add_argument("--seed", type=_seed_arg, default=DEFAULT_SEED,
                    help=f"seed, an integer >= 0 (default {DEFAULT_SEED})")
    args = ap.parse_args(argv)
    if args.out is None and args.seed != DEFAULT_SEED:
        # the loaders say the bundled files are seed DEFAULT_SEED's (extra["seed"]), and the docs' numbers are theirs
        ap.error(f"the bundled files are seed {DEFAULT_SEED}'s (the loader's extra['seed'] says so, and the docs' "
                 f"numbers are theirs): give --out DIR for seed {args.seed}'s files")
    root = Path(__file__).resolve().parents[2]
    out = args.out if args.out is not None else (root / "data" / folder if (root / "pyproject.toml").is_file() else None)
    if out is None:
        ap.error("not running from a source checkout: give --out DIR")
    try:
        out.mkdir(parents=True, exist_ok=True)  # before the simulation: an unusable --out is said at once
        dyn, sta = write(out, args.seed)
    except OSError as exc:  # --out a file, a folder that cannot be made, a disk full
        print(f"{ap.prog}: cannot write in {out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    print(f"wrote {dyn} and {sta}")
    return 0


def _folder_arg(text: str) -> Path:
    """``--out``: a folder name, not empty (``Path("")`` is the current folder, which an unset shell variable named)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty folder name; give a folder ('.' for this one)")
    return Path(text)


def _seed_arg(text: str) -> int:
    """``--seed``: an integer >= 0 (numpy's generators take no negative seed)."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"a seed is an integer >= 0, got {n}")
    return n


def main(argv: list[str] | None = None) -> int:
    """``python -m graybox.datasets.pumping [--out DIR] [--seed N]``: regenerate the bundled CSVs."""
    return regenerate_main(argv, module="graybox.datasets.pumping", folder="pumping", write=write_csvs)


if __name__ == "__main__":
    sys.exit(main())
