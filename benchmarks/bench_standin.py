"""A stand-in calibrated to Table I's other facts: does SE D_SF then beat ELS at ℓ = 2 as an outcome?

    python benchmarks/bench_standin.py --part calibrate [--draws 10]   # ELS only, every candidate stand-in
    python benchmarks/bench_standin.py --part outcome [--draws 10] [--stand-in calibrated ...]  # SE against ELS

On the bundled stand-in the SE (D_SF) model loses to ELS on validation at ℓ = 2 (median SE/ELS 1.66
over 30 draws, Table I: 0.83). Its ELS models differ from the paper's in two published facts: they
miss the static points (J_SF about 1 mlc² at ℓ = 3; Table I's ELS (17): 0.060) and run freely with
J_S 0.8–0.9 mlc² (Table I's ELS: 1.1–2.6). This script looks for a stand-in (``PumpingPlant``
keywords: the slow disturbances, the fast one, the drive's ramps) whose ELS models show Table I's
ELS facts, using ELS alone, and only then compares SE with ELS on it.

``--part calibrate``: for every candidate of :func:`candidates`, ELS (FROLS 17 / 23 terms, ne = 2, as
``graybox reproduce``) on draws 1 … N (``generate(seed, plant)``): the medians of J_S ident, J_S valid
and J_SF at ℓ = 2 and 3, the draws whose ELS free run diverges on the validation record, and the
score: the mean over those six figures of |ln(median / Table I's ELS figure)| (a diverging run's
figure is infinite: a median over half the draws diverging scores as far off). The rule, fixed
before any SE fit was run: among the candidates whose ELS model stays bounded on the validation
record in at least 80 % of the draws at both degrees (the paper's ELS models ran stably on its
records), the least score wins. Nothing here fits an SE model.

A second rule puts fact (a) first: among the eligible candidates whose four ELS J_S medians are all
at least 1 mlc², the one whose ℓ = 3 ELS J_SF is nearest Table I's 0.0603.

``--part outcome``: SE-grad and the GA (reproduce settings, ``bench_se_table.front_dsf``) against ELS
over draws 1 … N of :data:`CALIBRATED` (the winner of ``--part calibrate``, written into this file
before the outcome was run), :data:`A_FIRST` (the second rule's pick), :data:`RUNNERS_UP` (the next
eligible candidates by score), :data:`CONTROLS` (uncalibrated stand-ins with less air loss) or the
bundled stand-in, in ``bench_se_table.py --part draws``'s tables.
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import bench_se_table as se_table  # noqa: E402
from graybox.datasets.pumping import PumpingPlant  # noqa: E402
from graybox.reference import TABLE_I  # noqa: E402

#: Table I's ELS facts the calibration aims at: (J_S ident, J_S valid, J_SF) of ELS (15), then ELS (17).
PAPER_ELS = tuple(TABLE_I[name][k] for name in ("ELS (15)", "ELS (17)") for k in ("JS_ident", "JS_valid", "JSF"))
#: Least share of draws whose ELS free run stays bounded on the validation record, at each degree.
STABLE_SHARE = 0.8


def candidates() -> dict[str, dict]:
    """The candidate stand-ins (name → ``PumpingPlant`` keywords), in the order they were searched.

    Four families: (1) the drive's symmetric ramp against the bundled slow disturbances (the ramp is
    an amplitude-dependent, non-polynomial dynamic); (2) weaker surge, no air, with ramps up or
    down only (a drive without a braking resistor decelerates on a ramp); (3) the air loss weaker
    and venting faster (for J_SF), the surge stronger and shorter (for J_S), with and without a
    deceleration ramp; (4) around the best of (3), the fast disturbance w doubled; (5) around the
    best of (3) and (4) (a finer search of the air loss, its venting and the surge, no ramp).
    """
    out: dict[str, dict] = {"as bundled": {}}
    for ramp, air, surge in itertools.product([math.inf, 150.0, 80.0, 50.0], [8e-5, 2e-5, 0.0], [0.0055, 0.00275, 0.0]):
        if ramp == math.inf and air == 8e-5 and surge == 0.0055:
            continue  # the bundled stand-in
        out[f"ramp ±{ramp:g}, air {air:g}, surge {surge:g}"] = dict(ramp_up=ramp, ramp_down=ramp, air_loss_per_rpm=air,
                                                                   surge_intensity=surge)
    for up, down in [(400, 400), (250, 250), (math.inf, 200), (math.inf, 100), (math.inf, 50), (200, math.inf),
                     (100, math.inf)]:
        out[f"no air, surge 0.00275, ramp up {up:g} down {down:g}"] = dict(air_loss_per_rpm=0.0, surge_intensity=0.00275,
                                                                           ramp_up=up, ramp_down=down)
    for (air, vent), (si, st), down in itertools.product(
            [(0.0, 30.0), (2e-5, 10.0), (4e-5, 5.0), (8e-5, 3.0)],
            [(0.0055, 1.0), (0.011, 1.0), (0.0165, 1.0), (0.0055, 2.0), (0.011, 2.0), (0.0165, 2.0), (0.0055, 6.0),
             (0.011, 6.0)], [math.inf, 150.0]):
        out[_name(air, vent, si, st, down, 0.15)] = dict(air_loss_per_rpm=air, air_vent_time=vent, surge_intensity=si,
                                                         surge_time=st, ramp_down=down)
    for (air, vent), (si, st), down, w in itertools.product(
            [(4e-5, 5.0), (4e-5, 15.0), (8e-5, 10.0), (8e-5, 30.0)], [(0.0165, 1.0), (0.022, 1.0), (0.0165, 2.0)],
            [math.inf, 300.0], [0.15, 0.3]):
        out.setdefault(_name(air, vent, si, st, down, w), dict(
            air_loss_per_rpm=air, air_vent_time=vent, surge_intensity=si, surge_time=st, ramp_down=down,
            process_noise_std=w))
    for air, vent, (si, st) in itertools.product([4e-5, 6e-5], [10.0, 15.0, 20.0],
                                                 [(0.0165, 1.5), (0.0195, 1.5), (0.0165, 2.0)]):
        out.setdefault(_name(air, vent, si, st, math.inf, 0.15), dict(
            air_loss_per_rpm=air, air_vent_time=vent, surge_intensity=si, surge_time=st))
    return out


def _name(air, vent, si, st, down, w):
    return (f"air {air:g} vents {vent:g} s, surge {si:g} decays {st:g} s, ramp down {down:g}"
            + ("" if w == 0.15 else f", w {w:g}"))


def els_facts(plant: PumpingPlant, n: int) -> np.ndarray:
    """ELS on draws 1 … n of ``plant``: shape (n, 6), J_S ident, J_S valid, J_SF at ℓ = 2, then at ℓ = 3."""
    rows = se_table._draws(range(1, n + 1), (2, 3), [], plant=plant, show=False)
    return np.column_stack([np.column_stack([a[:, 0, 1], a[:, 0, 0], a[:, 1, 0]]) for a in (rows[2], rows[3])])


def score(medians: np.ndarray) -> float:
    """Mean of |ln(median / Table I's ELS figure)| over the six facts (inf where a median is inf)."""
    with np.errstate(divide="ignore"):
        return float(np.mean(np.abs(np.log(np.asarray(medians) / np.array(PAPER_ELS)))))


def calibrate(n: int) -> None:
    print("| stand-in | ℓ=2 J_S ident, valid, J_SF | ℓ=3 J_S ident, valid, J_SF | ELS diverges ℓ=2, ℓ=3 | score | eligible |")
    print("| --- | --- | --- | --- | --- | --- |")
    print(f"| Table I's ELS (15), (17) | {', '.join(f'{v:.3g}' for v in PAPER_ELS[:3])} | "
          f"{', '.join(f'{v:.3g}' for v in PAPER_ELS[3:])} | 0, 0 | 0 | |")
    results, a_first = [], []
    for name, kw in candidates().items():
        f = els_facts(PumpingPlant(**kw), n)
        med = np.median(f, axis=0)
        div = [int(np.sum(~np.isfinite(f[:, c]))) for c in (1, 4)]
        ok = all(n - d >= STABLE_SHARE * n - 1e-9 for d in div)  # 1e-9: (1 - 0.8) * 10 is 1.999…
        s = score(med)
        results.append((s if ok else math.inf, s, name))
        if ok and min(med[[0, 1, 3, 4]]) >= 1.0:
            a_first.append((abs(math.log(med[5] / PAPER_ELS[5])), name))
        print(f"| {name} | {', '.join(se_table.fmt(v) for v in med[:3])} | {', '.join(se_table.fmt(v) for v in med[3:])} "
              f"| {div[0]}, {div[1]} | {s:.2f} | {'yes' if ok else 'no'} |", flush=True)
    print("\nEligible candidates by score (the first is the calibrated stand-in):\n")
    for rank, (_, s, name) in enumerate(sorted(r for r in results if np.isfinite(r[0]))[:5], 1):
        print(f"{rank}. {name}: score {s:.2f}")
    if a_first:
        print(f"\nFact (a) first (every ELS J_S median at least 1 mlc², ℓ = 3 J_SF nearest 0.0603): {min(a_first)[1]}")


#: The winner of ``--part calibrate --draws 10`` (2026-11-26 02:08 UTC, git 9d43704), written here before
#: ``--part outcome`` was first run: ELS medians ℓ = 2 J_S 1.58, 2.46, J_SF 0.719; ℓ = 3 J_S 1.23, 3.04,
#: J_SF 0.399; score 0.76 (the bundled stand-in: 1.07).
CALIBRATED = dict(air_loss_per_rpm=6e-5, air_vent_time=20.0, surge_intensity=0.0195, surge_time=1.5)
#: The second rule, fact (a) first (also fixed before any SE fit): among the eligible candidates whose
#: four ELS J_S medians are all at least 1 mlc² (Table I's ELS: 1.1–2.6), the one whose ℓ = 3 ELS J_SF
#: median is nearest Table I's 0.0603 in ratio: ℓ = 2 1.09, 1.79, 0.0661; ℓ = 3 1.29, 3.69, 0.0525; score 0.95.
A_FIRST = dict(air_loss_per_rpm=4e-5, air_vent_time=5.0, surge_intensity=0.022, surge_time=1.0, ramp_down=300.0)
#: The next eligible candidates by score in the same run (0.78 and 0.82).
RUNNERS_UP: dict[str, dict] = {
    "runner-up 2": dict(air_loss_per_rpm=4e-5, air_vent_time=15.0, surge_intensity=0.0165, surge_time=2.0),
    "runner-up 3": dict(air_loss_per_rpm=4e-5, air_vent_time=15.0, surge_intensity=0.022, surge_time=1.0),
}

#: Controls, not calibrated to anything (bench_se_table.VARIANTS): does SE beat ELS on any stand-in with less air loss?
CONTROLS: dict[str, dict] = {
    "control: no air loss": se_table.VARIANTS["no air loss"],
    "control: no air, no surge": se_table.VARIANTS["no air, no surge"],
}


def outcome(n: int, which: list[str]) -> None:
    """SE-grad and the GA against ELS over draws 1 … n of the stand-ins ``which`` (names of :func:`stand_ins`)."""
    plants = stand_ins()
    estimators = [se_table.front_dsf("gradient"), se_table.front_dsf("ga", starts="pe")]
    for name in which:
        kw = plants[name]
        print(f"{name}, per draw:\n\n| draw | ℓ | ELS valid | ELS J_SF | SE-grad valid | SE-grad J_SF | GA valid | GA J_SF |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        rows = se_table._draws(range(1, n + 1), (2, 3), estimators, plant=PumpingPlant(**kw))
        f = np.column_stack([np.column_stack([a[:, 0, 1], a[:, 0, 0], a[:, 1, 0]]) for a in (rows[2], rows[3])])
        med = np.median(f, axis=0)
        print(f"\n{name} ({kw or 'bundled keywords'}): ELS medians ℓ=2 {', '.join(se_table.fmt(v) for v in med[:3])}; "
              f"ℓ=3 {', '.join(se_table.fmt(v) for v in med[3:])}; score {score(med):.2f}\n")
        se_table.summary_table(rows, label=name)
        print()


def stand_ins() -> dict[str, dict]:
    """The stand-ins ``--part outcome`` can run: the bundled one, the calibrated one and the runners-up."""
    return {"as bundled": {}, "calibrated": CALIBRATED, "fact (a) first": A_FIRST, **RUNNERS_UP, **CONTROLS}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("calibrate", "outcome"), required=True)
    ap.add_argument("--draws", type=int, default=10, help="draws (seeds 1 … N) of each stand-in")
    ap.add_argument("--stand-in", action="append", choices=tuple(stand_ins()),
                    help="--part outcome: the stand-in(s) to run (repeatable; default: calibrated)")
    args = ap.parse_args(argv)
    print(f"# bench_standin.py --part {args.part} --draws {args.draws}: "
          f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, git {git_rev()}, {machine()}\n")
    if args.part == "calibrate":
        calibrate(args.draws)
    else:
        outcome(args.draws, args.stand_in or ["calibrated"])


if __name__ == "__main__":
    main()
