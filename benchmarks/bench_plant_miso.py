"""Speed of the two-input benchmark plant against the bundled one (``python benchmarks/bench_plant_miso.py``).

Prints the median time of one 6000-sample simulation of each plant (with all noise on), its
throughput in samples per second, and the time to generate the bundled two-input data set.
"""

from __future__ import annotations

import argparse

import numpy as np

from _common import machine, timeit
from graybox.datasets._pumping_miso import TwoSpeedPumpingPlant, generate_miso, two_speed_reference
from graybox.datasets.pumping import PumpingPlant


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(machine())
    u2 = two_speed_reference()
    siso, miso = PumpingPlant(), TwoSpeedPumpingPlant()
    t_siso = timeit(lambda: siso.simulate(u2[:, 0], seed=1), repeat=args.repeat)
    t_miso = timeit(lambda: miso.simulate(u2, seed=1), repeat=args.repeat)
    n = u2.shape[0]
    print(f"{'plant':<28}{'ms / 6000 samples':>20}{'samples/s':>14}")
    for name, t in (("PumpingPlant (one speed)", t_siso), ("TwoSpeedPumpingPlant", t_miso)):
        print(f"{name:<28}{1e3 * t:>20.2f}{n / t:>14.3g}")
    t_gen = timeit(lambda: generate_miso(), repeat=max(1, args.repeat // 3))
    print(f"generate_miso (6000 samples + 36 static points of 186 s each): {t_gen:.2f} s")


if __name__ == "__main__":
    main()
