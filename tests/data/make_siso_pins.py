"""Generator of ``siso_pins.json``: the single-input results pinned bit for bit.

Run ONCE, from the code as it was before several inputs were added, with
``python tests/data/make_siso_pins.py``; the JSON file it writes is the reference that
``tests/test_siso_pins.py`` compares today's code against. Do not re-run it to make a failing
pin pass: a changed pin means a single-input result changed.

The file was first written from commit 2ebc567. Issue 14's ELS (a rearranged iteration and a
direct solve when the relaxed one stalls) landed on main before the several-inputs branch, and it
changes ELS's θ in the last bits (Table I's figures by about 1e-12 relative), and with it CLS (22), whose reference Σ*_y comes from ELS. The
file was therefore written again from 3a0f02a, main with issue 14's changes and without several
inputs; the several-inputs merge reproduces it bit for bit (both files were compared).

What is pinned (each float array as the sha256 of its float64 bytes, scalars as float hex):
Table I's rows built as ``graybox reproduce`` builds them (FROLS structures, ELS, CLS (22),
PE with D_SF, SE-GA and SE-gradient with D_SF) at reduced settings so that the test is fast
(3 λ1 values, a GA of 40 individuals × 5 generations, 20 PE λ1 values), the evaluate() table;
the paper's printed models (Tables II, III): θ, clusters, free runs on the bundled validation
record, static curves, gains and equilibria; the bundled records themselves.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np


def _h(a) -> str:
    a = np.ascontiguousarray(np.asarray(a, dtype=np.float64))
    return hashlib.sha256(a.tobytes()).hexdigest() + f":{a.shape}"


def _f(x) -> str:
    return float(x).hex()


def compute_pins() -> dict:
    """Every pinned single-input result, as a JSON-able dict of strings."""
    from graybox import reference
    from graybox.estimation._prediction_error import cls as cls_fit, pe_pareto
    from graybox.static._curves import StaticCurve
    from graybox.estimation._decisions import decide_dsf
    from graybox.estimation._extended_least_squares import els
    from graybox.models._evaluate import evaluate
    from graybox.estimation._simulation_error import GAOptions, se_pareto
    from graybox.selection._forward_regression import frols
    from graybox.core._simulation_kernels import batch_sse, encode, free_run_sensitivity
    from graybox.core._simulation import simulate_many
    from graybox.static._analysis import equilibria
    from graybox.core._terms import Candidates
    from graybox.datasets import load_pumping

    out: dict = {}
    data = load_pumping()
    out["records"] = {k: [_h(r.u), _h(r.y)] for k, r in (("ident", data.ident), ("valid", data.valid))}
    out["static_points"] = [_h(data.static.ubar), _h(data.static.ybar)]
    curve = StaticCurve.fit(data.static, 2, name="eq. (1) form")
    out["curve"] = [_f(c) for c in curve.coefficients]
    models = {}
    for degree, n_terms, eq in ((2, 17, "15"), (3, 23, "17")):
        cand = Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
        out[f"candidates_l{degree}"] = str(cand)
        sel = frols(cand, data.ident, n_terms=n_terms, include=["1"])
        out[f"frols_l{degree}"] = str(sel)
        m_els = els(sel, data.ident, name=f"ELS ({eq})").model
        models[f"ELS ({eq})"] = m_els
        st = m_els.structure
        if degree == 2:
            models["CLS (22)"] = cls_fit(st, data.ident, curve, reference=m_els, name="CLS (22)").model
        pe = pe_pareto(st, data.ident, data.static, lambdas=np.logspace(-6, 0, 20))
        models[f"PE (D_SF) l={degree}"] = decide_dsf(pe, band=0.031, fallback="min_jsf").model
        for method in ("ga", "gradient"):
            se = se_pareto(st, data, lambdas=np.logspace(-2, 0, 3), method=method, seed=0, threads=1, margin=None,
                           options=GAOptions(population=40, generations=5) if method == "ga" else None)
            models[f"SE-{method} (D_SF) l={degree}"] = decide_dsf(se, band=0.031, fallback="min_jsf").model
    out["table1_models"] = {k: {"structure": str(m.structure), "theta": _h(m.theta),
                                "noise_theta": _h(m.noise_theta), "name": m.name} for k, m in models.items()}
    tab = evaluate(models, data)
    out["table1"] = {str(idx): {str(c): (_f(v) if isinstance(v, (float, np.floating)) else str(v))
                                for c, v in row.items()} for idx, row in tab.iterrows()}
    paper = {}
    ub = np.arange(750.0, 1651.0, 100.0)
    for eq, table in ((15, reference.TABLE_II), (17, reference.TABLE_III)):
        for col in table:
            m = reference.paper_model(eq, col, allow_misprinted=True)
            d = {"theta": _h(m.theta), "clusters": {k: _f(v) for k, v in m.clusters().items()},
                 "free_run_valid": _h(m.simulate(data.valid, on_diverge="nan")),
                 "predict_valid": _h(m.predict(data.valid))}
            try:
                d["static_curve"] = _h(m.static_curve(ub))
                d["static_gain"] = _h(m.static_gain(ub))
            except ValueError as exc:
                d["static_curve"] = f"error: {exc}"
            d["equilibria_750"] = [[_f(e.ybar), bool(e.stable), _f(e.spectral_radius)]
                                   for e in equilibria(m.structure, m.theta, 750.0)]
            # the population kernels and the sensitivities, on the model and two perturbations
            thetas = m.theta[None, :] * np.array([[1.0], [0.999], [1.001]])
            d["simulate_many_valid"] = _h(simulate_many(m.structure, thetas, data.valid))
            d["batch_sse_valid"] = _h(batch_sse(encode(m.structure), thetas, data.valid.u, data.valid.y, m.max_lag))
            yh, S = free_run_sensitivity(encode(m.structure), m.theta, data.valid.u, data.valid.y[:m.max_lag],
                                         m.max_lag)
            d["sensitivity_valid"] = [_h(yh), _h(S)]
            paper[f"{eq} {col}"] = d
    out["paper_models"] = paper
    for k, m in models.items():
        out["table1_models"][k]["free_run_valid"] = _h(m.simulate(data.valid, on_diverge="nan"))
        out["table1_models"][k]["static_curve"] = _h(m.static_curve(ub, y0=None, strict=False))
    return out


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    path = Path(__file__).with_name("siso_pins.json")
    path.write_text(json.dumps(compute_pins(), indent=1, sort_keys=True, ensure_ascii=False) + "\n")
    print(f"wrote {path}")
