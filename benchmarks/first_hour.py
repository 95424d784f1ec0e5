"""A newcomer's first hour with graybox, on a lab's own files (a synthetic pressurised tank).

The plant: a tank pressurised by a pump, input the pump speed n (rpm, 1000–3000), output the
tank pressure p (Pa, about 2·10⁵), sampled every 0.5 s; a polynomial NARX system whose time
constant falls with the speed and whose static curve is rational in n:

    p(k) = (1.4 − 1e-5 n(k−1)) p(k−1) − 0.45 p(k−2) + 7333 + 1.667e-3 n(k−1)²  (+ equation noise)

measured with a 500 Pa sensor noise. The identification and validation runs stay within
1700–2300 rpm; the test run and the steady states cover 1000–3000 rpm, where only a model that
knows the static curve stays right. The files are written as a lab writes them:

- ``ident.csv``: an Excel export (Windows, German locale): ``;`` between columns, decimal commas,
  cp1252, the units in the column names;
- ``valid.log``: a data logger's file: a header block of ``#`` lines, then a time column in seconds;
- ``test.txt``: tab-separated, units in the column names;
- ``steady.csv``: ten steady states with their uncertainty (standard error of each mean, Pa).

Then, using what the README and the docs site say: a Dataset, a black box, a gray box chosen by
``select_graybox`` with the test record, its static curve against the points, a residual check,
a local linear model and a PI for it (``graybox.control``), and the model saved and loaded.

    python benchmarks/first_hour.py [--seed 0] [--keep DIR]
"""

from __future__ import annotations

import argparse
import datetime
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402

TS = 0.5  # s


def tank_static(n: np.ndarray) -> np.ndarray:
    """The plant's steady-state pressure (Pa) at pump speed n (rpm)."""
    n = np.asarray(n, dtype=float)
    return (7333.0 + 1.667e-3 * n**2) / (0.05 + 1e-5 * n)


def tank_step(p1: float, p2: float, n1: float, rng: np.random.Generator) -> float:
    """p(k) from p(k−1), p(k−2) (Pa) and n(k−1) (rpm), with 30 Pa of equation noise."""
    return (1.4 - 1e-5 * n1) * p1 - 0.45 * p2 + 7333.0 + 1.667e-3 * n1**2 + 30.0 * rng.standard_normal()


def tank_run(n: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Measured pressure (Pa) of a run at the speeds n (rpm), from the steady state at n[0]."""
    p = np.full(n.size, tank_static(n[0]))
    for k in range(2, n.size):
        p[k] = tank_step(p[k - 1], p[k - 2], n[k - 1], rng)
    return p + 500.0 * rng.standard_normal(n.size)  # sensor noise (Pa)


def staircase(rng: np.random.Generator, n: int, low: float, high: float) -> np.ndarray:
    """Speed steps (rpm) held 10–60 samples each."""
    out = []
    while len(out) < n:
        out += [round(rng.uniform(low, high))] * int(rng.integers(10, 61))
    return np.asarray(out[:n], dtype=float)


def write_lab_files(folder: Path, seed: int = 0) -> dict[str, Path]:
    """The four files a lab would have, in the dialects it would have them."""
    rng = np.random.default_rng(seed)
    files = {}
    # An Excel export (German locale): ';', decimal comma, cp1252, units in the names.
    n = staircase(rng, 2000, 1700, 2300)
    files["ident"] = folder / "ident.csv"
    pd.DataFrame({"Zeit [s]": np.arange(n.size) * TS, "Drehzahl [U/min]": n,
                  "Behälterdruck [Pa]": tank_run(n, rng).round(1)}).to_csv(
        files["ident"], sep=";", decimal=",", index=False, encoding="cp1252")
    # A data logger: a header block, then time in seconds, comma-separated.
    n = staircase(rng, 1000, 1700, 2300)
    files["valid"] = folder / "valid.log"
    body = pd.DataFrame({"time_s": np.arange(n.size) * TS, "speed": n,
                         "pressure": tank_run(n, rng).round(1)}).to_csv(index=False)
    files["valid"].write_text("# Logger TL-400 serial 0412\n# started 2026-11-20 09:14:03\n"
                              f"# channels: speed (rpm), pressure (Pa); period {TS} s\n" + body,
                              encoding="utf-8")
    # Tab-separated, units in the column names, a wider range of speeds.
    n = staircase(rng, 1000, 1000, 3000)
    files["test"] = folder / "test.txt"
    pd.DataFrame({"t [s]": np.arange(n.size) * TS, "n [rpm]": n, "p [Pa]": tank_run(n, rng).round(1)}).to_csv(
        files["test"], sep="\t", index=False)
    # Steady states: ten levels, each the mean of a settled stretch, with its standard error.
    levels = np.linspace(1000, 3000, 10).round()
    sem = np.full(levels.size, 150.0)
    files["static"] = folder / "steady.csv"
    pd.DataFrame({"speed_rpm": levels, "pressure_Pa": (tank_static(levels) + sem * rng.standard_normal(10)).round(1),
                  "sem_Pa": sem}).to_csv(files["static"], index=False)
    return files


def closed_loop_step(kp: float, ki: float, n0: float, p_ref: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """The plant's pressure (Pa) under a PI (speed = PI of the pressure error) from the steady state at n0 (rpm)."""
    p = np.full(n, tank_static(n0))
    speed = np.full(n, n0)
    integ = n0
    for k in range(2, n):
        p[k] = tank_step(p[k - 1], p[k - 2], speed[k - 1], rng)
        e = p_ref - p[k]
        integ += ki * TS * e
        speed[k] = integ + kp * e
    return p


def rise_time(p: np.ndarray, start: float, target: float) -> float:
    """10–90 % rise time (s) of a step response from ``start`` to ``target``."""
    frac = (p - start) / (target - start)
    return (np.argmax(frac >= 0.9) - np.argmax(frac >= 0.1)) * TS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--keep", type=Path, help="write the files and figures here (default: a temporary folder)")
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {machine()}, git {git_rev()}")
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        files = write_lab_files(folder, args.seed)
        first_hour(files, folder)
    print(f"whole first hour: {time.perf_counter() - t_start:.0f} s")


def first_hour(files: dict[str, Path], folder: Path) -> None:
    units = ("rpm", "Pa")
    # 1. The files. The Excel export is cp1252 (the loader says so and names the encoding to pass).
    ident = gb.load_record_csv(files["ident"], u="Drehzahl [U/min]", y="Behälterdruck [Pa]", time="Zeit [s]",
                               units=units, encoding="cp1252")
    try:  # the logger's header block is refused with the line that names the columns and skiprows=
        gb.load_record_csv(files["valid"], u="speed", y="pressure", time="time_s")
    except ValueError as err:
        print("logger file refused:", str(err).split(": ", 1)[1][:160], "…")
    valid = gb.load_record_csv(files["valid"], u="speed", y="pressure", time="time_s", name="valid", units=units,
                               skiprows=3)  # as the message says
    test = gb.load_record_csv(files["test"], u="n [rpm]", y="p [Pa]", time="t [s]", units=units)
    steady = gb.load_static_csv(files["static"], u="speed_rpm", y="pressure_Pa", uncertainty="sem_Pa", units=units)
    data = gb.Dataset(ident, valid, steady, description="a pressurised tank (synthetic)")
    print(data)
    print(f"band B = mean δ² = {steady.band:.4g} Pa²")

    # 2. Black and gray boxes, chosen the same honest way: fitted on ident, chosen on blocks of
    #    valid, reported on test (which no step of the choice reads).
    cand = gb.Candidates(ny=3, nu=3, degree=2)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        black = gb.select_graybox(cand, data, band=np.inf, test=test)
        t_black = time.perf_counter() - t0
        t0 = time.perf_counter()
        gray = gb.select_graybox(cand, data, test=test)
        t_gray = time.perf_counter() - t0
    for w in said:
        print(f"  warned: {w.category.__name__}: {str(w.message)[:150]} …")
    print(f"black box ({t_black:.0f} s): {black}\n  {black.model}")
    print(f"gray box ({t_gray:.0f} s): {gray}\n  {gray.model}")
    rows = {"black box": black.chosen, "gray box": gray.chosen}
    print("\n| model | terms | estimator | J_S valid (Pa²) | J_S test (Pa²) | J_SF (Pa²) | in band | regret |")
    print("| --- | ---: | --- | ---: | ---: | ---: | --- | ---: |")
    for (name, row), sel in zip(rows.items(), (black, gray)):
        print(f"| {name} | {row['n_terms']} | {row['estimator']} | {row['JS_valid']:.4g} | {row['JS_test']:.4g} | "
              f"{row['JSF']:.4g} | {row['JSF'] <= steady.band} | {sel.regret:.2f} |")
    print(f"gray / black test J_S: {gray.chosen['JS_test'] / black.chosen['JS_test']:.2f}; "
          f"J_SF black / gray: {black.chosen['JSF'] / gray.chosen['JSF']:.1f}\n")

    # 3. The static curves against the points.
    from graybox import plots

    models = {"black box": black.model, "gray box": gray.model}
    print("static error ȳ_model − ȳ_i (Pa) at each point:")
    print(pd.DataFrame({name: m.static_curve(steady.ubar, strict=False) - steady.ybar for name, m in models.items()},
                       index=pd.Index(steady.ubar, name="speed (rpm)")).round(0).T.to_string())
    fig = plots.plot_static_curve(steady, xlabel="Speed (rpm)", ylabel="Pressure (Pa)")
    grid = np.linspace(1000, 3000, 81)
    for name, m in models.items():
        fig.axes[0].plot(grid, m.static_curve(grid, strict=False), label=name)
    fig.axes[0].legend()
    fig.savefig(folder / "static.png")
    plots.plot_free_run(test, models, ylabel="Pressure (Pa)").savefig(folder / "test.png")

    # 4. Residual check on the validation record.
    for name, m in models.items():
        tests = gb.residual_tests(m, data.valid)
        print(f"residual tests, {name}: passed {tests.passed}; failed {list(tests.failed)}")

    # 5. Local model at 2000 rpm and a PI for it.
    import control as ct

    lm = gb.local_model(gray.model, 2000.0, data=data)
    print(f"\n{lm}\n  poles {np.round(lm.poles.real, 3)}, zeros {np.round(lm.zeros().real, 3)}, "
          f"damping {lm.damping:.3f}, 2 % settling {lm.settling_time():.1f} s")
    K = lm.dc_gain[0]

    def pi_loop(tau: float, lam: float) -> Any:
        kp = tau / (K * lam)  # IMC PI for a first-order plant K/(τs+1) and a closed loop of time constant λ
        pi = ct.ss([[1.0]], [[kp / tau * TS]], [[1.0]], [[kp * (1 + TS / tau)]], dt=TS, inputs="e", outputs="u",
                   name="pi")
        loop = ct.interconnect([gb.narx_iosystem(gray.model, Ts=TS, name="tank model"), pi,
                                ct.summing_junction(["r", "-y"], "e", dt=TS)], inputs="r", outputs=["y", "u"])
        x0 = np.r_[gb.narx_steady_state(gray.model, 2000.0, lm.ybar), 2000.0]
        return kp, ct.input_output_response(loop, TS * np.arange(120), np.full(120, lm.ybar + 5000.0), x0)

    try:  # the README's recipe as it stands: τ = lm.time_constant, λ = 1 s
        pi_loop(lm.time_constant, 1.0)
        print("README recipe (τ = time_constant, λ = 1 s): the loop holds")
    except gb.DivergenceError as err:
        print(f"README recipe (τ = time_constant = {lm.time_constant:.1f} s, λ = 1 s): {str(err)[:110]} …")
    tau = lm.settling_time() / 4  # a first-order lag settles within 2 % in about 4 τ
    kp, resp = pi_loop(tau, tau)
    model_p = resp.outputs[0]
    ki = kp / tau
    plant_p = closed_loop_step(kp, ki, 2000.0, tank_static(2000.0) + 5000.0, 120, np.random.default_rng(1))
    print(f"PI from τ = settling/4 = {tau:.2f} s, λ = τ: kp = {kp:.4g} rpm/Pa, ki = {ki:.4g} rpm/(Pa·s); "
          f"5000 Pa step: rise time on the model {rise_time(model_p, lm.ybar, lm.ybar + 5000):.1f} s, "
          f"on the plant {rise_time(plant_p, tank_static(2000.0), tank_static(2000.0) + 5000):.1f} s; "
          f"final error on the plant {np.mean(plant_p[-20:]) - tank_static(2000.0) - 5000:.0f} Pa")

    # 6. Keep the model.
    path = gb.save(gray.model, folder / "tank.json", units=units)
    again = gb.load(path, expect=gb.Model)
    same = np.array_equal(again.simulate(test.u, test.y[:again.max_lag]), gray.model.simulate(test.u, test.y[:3]))
    print(f"saved {path.name} ({path.stat().st_size} bytes), loaded: same free run on test {same}")


if __name__ == "__main__":
    main()
