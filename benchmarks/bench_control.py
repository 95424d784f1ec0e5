"""From model to controller (issue 23): what the local models say, and what they cost.

    /work/main/.venv/bin/python benchmarks/bench_control.py [--repeat 5]

On the bundled plant: the ELS model and the gray-box CLS model of the README (17 rational terms,
FROLS, ny = nu = 6; CLS imposes the static curve fitted to the 10 static points). Reported:

1. the local gain and dominant time constant of each model along the static curve, beside the
   simulator's own (its physics linearised numerically, ``PumpingPlant.linearize``), and the
   CLS model's 95 % Monte Carlo band of the time constant (1000 draws from its covariance);
2. the 10–90 % rise time of the local models' step responses beside the noise-free simulator's;
3. times (median of ``--repeat``, wall clock, noisy on a shared VM): ``operating_curve`` over
   100 points; its band with 1000 draws over 19 points; the discrete NonlinearIOSystem's free run
   (``control.input_output_response``) against ``Model.simulate`` over the 800-sample validation
   record, and their largest difference.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine, timeit  # noqa: E402

import graybox as gb  # noqa: E402
from graybox.datasets import PumpingPlant  # noqa: E402


def rise_time(step: np.ndarray, Ts: float) -> float:
    """10–90 % rise time (s) of a step response that settles on its last value."""
    f = step / step[-1]
    return float((np.argmax(f >= 0.9) - np.argmax(f >= 0.1)) * Ts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    import control as ct

    warnings.simplefilter("ignore", gb.StaticRangeWarning)
    data = gb.load_pumping()
    Ts = data.Ts
    sel = gb.frols(gb.Candidates(ny=6, nu=6, ne=2, degree=2, max_y_power=1), data, n_terms=17, include=["1"])
    els = gb.els(sel, data).model
    curve = gb.StaticCurve.fit(data.static, degree=2)
    cls = gb.cls(els.structure, data, curve, reference=els).model
    unc = gb.cls_uncertainty(cls, data, curve, reference=els)
    plant = PumpingPlant()
    k, a, b = plant.static_coefficients

    print(f"# bench_control.py, {datetime.date.today()}, git {git_rev()}, {machine()}\n")
    u = np.array([750.0, 900.0, 1050.0, 1200.0, 1350.0, 1500.0, 1650.0])
    oc = gb.operating_curve(cls, u, data=data, uncertainty=unc, n_samples=1000, seed=0)
    oe = gb.operating_curve(els, u, data=data)
    n = 400
    print("| ū (rpm) | gain plant | gain CLS | gain ELS | τ plant (s) | τ CLS (s) [95 % band] | τ ELS (s) "
          "| rise plant (s) | rise CLS (s) | rise ELS (s) |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for i, ui in enumerate(u):
        tau_p = plant.local_time_constant(ui)
        step_u = np.r_[np.full(10, ui), np.full(n, ui + 10.0)]
        yp = plant.simulate(step_u, noise=False, process_noise=False).pressure[9:]
        rise_p = rise_time(yp - yp[0], Ts)
        print(f"| {ui:g} | {2 * b * ui + a:.4f} | {oc.gain[i]:.4f} | {oe.gain[i]:.4f} | {tau_p:.3f} | "
              f"{oc.time_constant[i]:.3f} [{oc.time_constant_low[i]:.3f}, {oc.time_constant_high[i]:.3f}] | "
              f"{oe.time_constant[i]:.3f} | {rise_p:.2f} | {rise_time(oc.local_models[i].step(n), Ts):.2f} | "
              f"{rise_time(oe.local_models[i].step(n), Ts):.2f} |")

    grid = np.linspace(750, 1650, 100)
    t_curve = timeit(lambda: gb.operating_curve(cls, grid, Ts=Ts), repeat=args.repeat)
    g19 = np.linspace(750, 1650, 19)
    t_band = timeit(lambda: gb.operating_curve(cls, g19, Ts=Ts, uncertainty=unc, n_samples=1000), repeat=args.repeat)
    rec = data.valid
    L = cls.max_lag
    sysm = gb.narx_iosystem(cls, Ts=Ts)
    x0 = gb.narx_initial_state(cls, rec)
    T = Ts * np.arange(len(rec) - L)
    t_ct = timeit(lambda: ct.input_output_response(sysm, T, rec.u[L:], x0), repeat=args.repeat)
    t_sim = timeit(lambda: cls.simulate(rec), repeat=args.repeat)
    diff = np.max(np.abs(ct.input_output_response(sysm, T, rec.u[L:], x0).outputs - cls.simulate(rec)[L:]))
    print()
    print("| what | time |")
    print("| --- | ---: |")
    print(f"| operating_curve, 100 points | {t_curve * 1e3:.1f} ms |")
    print(f"| operating_curve with its band, 1000 draws × 19 points | {t_band:.2f} s |")
    print(f"| NonlinearIOSystem free run, {len(T)} samples (input_output_response) | {t_ct * 1e3:.1f} ms |")
    print(f"| Model.simulate, same record | {t_sim * 1e3:.3f} ms |")
    print(f"\nlargest |NonlinearIOSystem − Model.simulate| over the record: {diff:.2e} mlc")


if __name__ == "__main__":
    main()
