"""One record only: a held-out tail used as the validation record, against the folds of select_graybox.

    .venv/bin/python benchmarks/bench_record_only.py

For four of bench_honest.py's cases: the identification record cut into a head (67, 75, 80 %) and a
tail; the gray box (the case's band) and the black box (no band) chosen on the tail's blocks, fitted
on the head, scored on the case's test record. Compare with ``bench_honest.py --record-only``.
"""
import sys, warnings, numpy as np, graybox as gb
sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
warnings.simplefilter("ignore")
from bench_honest import cases
def main():
    cs = cases()
    for name in ("two-speed rig", "buck", "plant", "slow disturbance"):
        data, test, cand, band = cs[name]
        rec = data.ident
        out = []
        for frac in (0.67, 0.75, 0.8):
            n = int(frac * len(rec))
            a, b = rec.slice(0, n, name="head"), rec.slice(n, None, name="tail")
            g = gb.select_graybox(cand, a, data.static, validation=b, band=band, test=test, executor="processes", workers=2)
            k = gb.select_graybox(cand, a, data.static, validation=b, band=np.inf, test=test, executor="processes", workers=2)
            print(name, frac, "gray", len(g.structure), g.chosen["estimator"], f"{g.chosen['JS_test']:.4g}", "black", len(k.structure), k.chosen["estimator"], f"{k.chosen['JS_test']:.4g}",
                  "ratio", f"{g.chosen['JS_test']/k.chosen['JS_test']:.3f}", "regret", f"{g.chosen['JS_test']/g.table['JS_test'].min():.3f}", "jsf", f"{g.chosen['JSF_test']:.4g}", flush=True)
if __name__ == "__main__":
    main()
