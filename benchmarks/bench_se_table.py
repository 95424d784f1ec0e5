"""Table I's SE D_SF rows against ELS: variants of the SE fits, scored on records they were not fitted or chosen on.

    python benchmarks/bench_se_table.py [--part plant|seeds|draws|variants|windows|startup|scoring|others|all]
                                        [--degrees 2,3] [--draws N]

Issue 26 asks for SE D_SF models (gradient and GA) whose validation J_S is at most ELS's, as in
the paper's Table I, without choosing on the validation record. This script measures the ideas:

- the reproduce settings (stability margin 0.01, 10 λ1 in logspace(-2, 0), GA 50 generations,
  D_SF on the identification record), the GA before and after its PE seeds (``starts="pe"``);
- a ridge towards least squares (γ = 0.1, 1) and larger margins (0.02, 0.05) in the gradient sweep;
- D_SF choosing on a held-out tail: the front fitted on the first 75 % of the identification
  record, D_SF scoring the members on its last 25 % (``decide_dsf(choose_on=tail)``);
- a choice of settings on the tail: each of six SE estimators fitted on the first 75 %, the one
  whose D_SF model has the least J_S on the tail refitted on the whole record;
- ``se_dsf`` (D_SF solved directly) with a margin (0.01, 0.02);
- the GA seeded with PE solutions: ``se_pareto(method="ga", starts="pe")`` (four PE members,
  λ1 = 0.1 … 1e-4), or the PE front's D_SF member and six members along it; or seeded with the
  gradient front's members.

Figures per model: J_S on the identification record, on the validation record (Table I's
score), J_SF, and J_S on three fresh runs of the simulated plant (bench_output_error.py's
``plant_tests``: seeds 7, 8, 9; mean and worst), which nothing saw. Diagnostic bounds,
not estimators (they look at the validation record): the least validation J_S among the in-band
members of a fine gradient front (31 λ1) fitted on the identification record, on identification
+ validation, and ``se_dsf`` fitted on identification + validation.

``--part draws``: Table I's comparison over many draws of the stand-in (``generate(seed)`` for seeds
1 … N: new input design, noise and static test each time, as if the experiment were rerun):
ELS against SE-grad and the GA (reproduce settings) on each draw's own validation record, with
the paper's own ratios beside them (Table I: SE/ELS validation J_S 0.83 at ℓ = 2, 1.18 at ℓ = 3).
``--part variants``: the same for ELS and SE-grad on stand-ins with the slow disturbances changed
(:data:`VARIANTS`): is it the air loss's static–dynamic conflict that makes SE lose?
``--part windows``: SE-grad fitted on windows of the identification record, each run freely from its
measured first samples, against the whole free run (does a restarted fit stop following the drift?).
``--part startup``: where on the validation record the ℓ = 2 models err (J_S per quarter), and their
errors 1, 20 and 100 samples ahead (``Model.predict(record, horizon=k)``).
``--part scoring``: ℓ = 2 SE-grad against ELS with the validation record's first outputs estimated (as
MATLAB's ``compare`` does) or its first 200 samples left out, and on stand-ins whose measured output
carries coloured (AR(1)) noise (:data:`OUT_NOISE`): is the loss how the record is scored or measured?

``--part seeds``: the GA with and without ``starts="pe"`` for seeds 1, 2, 3 (is the gain the
seed's luck?). ``--part others``: the GA seeding and the margin of ``se_dsf`` on the buck converter (test: the
second half of its validation file) and on two synthetic systems with static points
(bench_honest.py's "slow disturbance" and "static points off the records").
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.optimize
import scipy.signal

sys.path.insert(0, str(Path(__file__).parent))
from _common import git_rev, machine  # noqa: E402

import graybox as gb  # noqa: E402
from bench_output_error import plant_tests  # noqa: E402

BAND = 0.031
LAM = np.logspace(-2, 0, 10)
MARGIN = 0.01
GA = gb.GAOptions(generations=50)


def js(st, th, rec):
    return float(gb.evaluate_thetas(st, np.asarray(th)[None], rec, None, one_step=False)["JS"][0])


def fmt(v):
    return "inf" if not np.isfinite(v) else (f"{v:.3g}" if v < 1e4 else f"{v:.2e}")


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **k)


# -- estimators: (records, static, band) -> (θ, λ1 or description) ------------------------------------------

def front_dsf(method, margin=MARGIN, ridge=0.0, starts=None, choose_on=None):
    def fit(recs, static, band):
        kw = {"options": GA} if method == "ga" else {}
        se = quiet(gb.se_pareto, ST[0], recs, static, lambdas=LAM, method=method, seed=0, margin=margin, ridge=ridge,
                   starts=starts(recs, static, band) if callable(starts) else starts, threads=2, **kw)
        d = gb.decide_dsf(se, band=band, fallback="min_jsf", choose_on=choose_on)
        return d.model.theta, f"λ1 {d.lambda1:.3g}" + ("" if d.in_band else " (min J_SF)")
    return fit


def direct_dsf(margin):
    def fit(recs, static, band):
        r = quiet(gb.se_dsf, ST[0], recs, static, band=band, margin=margin)
        return r.model.theta, "direct" + ("" if r.in_band else " (band infeasible)")
    return fit


def pe_seeds(recs, static, band):
    """The PE front's D_SF member (if any member has a static curve) and six members spread along it."""
    pe = quiet(gb.pe_pareto, ST[0], recs, static, lambdas=np.logspace(-6, 0, 100))
    out = [pe.thetas[i] for i in range(0, 100, 20)] + [pe.thetas[-1]]
    if np.isfinite(pe.JSF).any():
        out.insert(0, gb.decide_dsf(pe, band=band, fallback="min_jsf").model.theta)
    return out


def grad_seeds(recs, static, band):
    se = quiet(gb.se_pareto, ST[0], recs, static, lambdas=LAM, method="gradient", seed=0, margin=MARGIN)
    return list(se.thetas[np.all(np.isfinite(se.thetas), axis=1)])


ST: list = [None]  # the structure of the case being run (the estimators read it)


def tail_chosen(candidates):
    """Each candidate fitted on the first 75 % of the identification record; the one whose model has the
    least J_S on the last 25 % (J_SF in the band) refitted on the whole record."""
    def fit(recs, static, band):
        rec = recs if isinstance(recs, gb.Record) else recs[0]
        cut = int(0.75 * len(rec))
        head, tail = rec.slice(0, cut, name="head"), rec.slice(cut, None, name="tail")
        scores = {}
        for name, est in candidates.items():
            th, _ = est(head, static, band)
            ok = gb.jsf(gb.Model(ST[0], th), static) <= band
            scores[name] = js(ST[0], th, tail) if ok else np.inf
        best = min(scores, key=scores.get)
        th, how = candidates[best](rec, static, band)
        return th, f"{best}, {how}"
    return fit


def plant_variants():
    tail = {}
    v = {
        "SE GA (the paper's seeds), reproduce before": front_dsf("ga"),
        "SE GA, starts='pe', reproduce now": front_dsf("ga", starts="pe"),
        "SE GA, PE front seeds": front_dsf("ga", starts=pe_seeds),
        "SE GA, gradient seeds": front_dsf("ga", starts=grad_seeds),
        "SE-grad, reproduce": front_dsf("gradient"),
        "SE-grad margin 0.02": front_dsf("gradient", margin=0.02),
        "SE-grad margin 0.05": front_dsf("gradient", margin=0.05),
        "SE-grad ridge 0.1": front_dsf("gradient", ridge=0.1),
        "SE-grad ridge 1": front_dsf("gradient", ridge=1.0),
        "se_dsf margin 0.01": direct_dsf(0.01),
        "se_dsf margin 0.02": direct_dsf(0.02),
    }
    for k in ("SE-grad, reproduce", "SE-grad margin 0.02", "SE-grad margin 0.05", "se_dsf margin 0.01",
              "se_dsf margin 0.02", "SE GA, starts='pe', reproduce now"):
        tail[k] = v[k]
    v["settings chosen on the tail, refitted"] = tail_chosen(tail)
    return v


def plant(degrees):
    data = gb.load_pumping()
    tests = plant_tests(data.ident.Ts)
    cut = int(0.75 * len(data.ident))
    head, tail = data.ident.slice(0, cut, name="head"), data.ident.slice(cut, None, name="tail")
    print("| ℓ | model | choice | J_S ident | J_S valid | J_SF | J_S test (mean, worst) | s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")

    def row(deg, name, th, how, sec):
        st = ST[0]
        tj = [js(st, th, t) for t in tests]
        print(f"| {deg} | {name} | {how} | {fmt(js(st, th, data.ident))} | {fmt(js(st, th, data.valid))} | "
              f"{fmt(gb.jsf(gb.Model(st, th), data.static))} | {fmt(np.mean(tj))}, {fmt(max(tj))} | {sec:.0f} |",
              flush=True)

    for degree, n_terms in ((2, 17), (3, 23)):
        if degree not in degrees:
            continue
        cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
        sel = quiet(gb.frols, cand, data.ident, n_terms=n_terms, include=["1"])
        e = quiet(gb.els, sel, data.ident)
        ST[0] = e.model.structure.process
        row(degree, "ELS", e.model.theta, "", 0)
        for name, est in plant_variants().items():
            t0 = time.perf_counter()
            th, how = est(data.ident, data.static, BAND)
            row(degree, name, th, how, time.perf_counter() - t0)
        t0 = time.perf_counter()
        th, how = front_dsf("gradient", choose_on=tail)(head, data.static, BAND)
        row(degree, "SE-grad fitted on the first 75 %, D_SF on the tail", th, how, time.perf_counter() - t0)
        # diagnostic bounds: they look at the validation record
        fine = np.r_[1.0, np.logspace(-0.3, -1.5, 30)]
        for label, recs in (("ident", data.ident), ("ident + valid", [data.ident, data.valid])):
            se = quiet(gb.se_pareto, ST[0], recs, data.static, lambdas=fine, method="gradient", seed=0, margin=MARGIN)
            inb = np.flatnonzero(se.JSF <= BAND)
            v = np.array([js(ST[0], se.thetas[i], data.valid) for i in inb])
            if v.size:
                k = inb[np.argmin(v)]
                row(degree, f"bound: fine front on {label}, least valid J_S in the band", se.thetas[k],
                    f"λ1 {se.lambdas[k]:.3g}", 0)
        t0 = time.perf_counter()
        th, how = direct_dsf(MARGIN)([data.ident, data.valid], data.static, BAND)
        row(degree, "bound: se_dsf margin 0.01 on ident + valid", th, how, time.perf_counter() - t0)
        th, how = early_stopping_bound(data)
        row(degree, "bound: early stopping, least valid J_S over the in-band iterates", th, how, 0)


def early_stopping_bound(data):
    """Every iterate of least_squares ("trf" and "dogbox") from the PE member of λ1 = 0.6 … 0.129 (margin
    0.01): the in-band iterate with the least validation J_S (what early stopping could reach at best)."""
    from graybox.estimation._simulation_error import SEProblem, _fit, _pe_members
    p = SEProblem(ST[0], data.ident, data.static, margin=MARGIN)
    lams = np.array([0.6, 0.36, 0.215, 0.129])
    best = (np.inf, None, "")
    for lam, th0 in zip(lams, _pe_members(p, lams)):
        if not np.isfinite(p.cost(th0[None], lam)[0]):
            continue
        its = []
        for solver in ("trf", "dogbox"):
            _fit(p, th0, lam, solver, 50, 1e-8, watch=lambda th: its.append(np.array(th)))
        its = np.array(its)
        for th in its[p.jsf(its) <= BAND]:
            v = js(ST[0], th, data.valid)
            if v < best[0]:
                best = (v, th, f"λ1 {lam:.3g}, from PE")
    return best[1], best[2]


def ga_seeds():
    """The GA with and without PE solutions in its initial populations, over three more seeds."""
    data = gb.load_pumping()
    tests = plant_tests(data.ident.Ts)
    print("| ℓ | seed | starts | λ1 | J_S ident | J_S valid | J_SF | J_S test (mean, worst) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for degree, n_terms in ((2, 17), (3, 23)):
        cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
        st = quiet(gb.els, quiet(gb.frols, cand, data.ident, n_terms=n_terms, include=["1"]),
                   data.ident).model.structure.process
        for seed in (1, 2, 3):
            for starts in (None, "pe"):
                se = quiet(gb.se_pareto, st, data, lambdas=LAM, method="ga", seed=seed, margin=MARGIN, starts=starts,
                           threads=2, options=GA)
                d = gb.decide_dsf(se, band=BAND, fallback="min_jsf")
                tj = [js(st, d.model.theta, t) for t in tests]
                print(f"| {degree} | {seed} | {starts} | {d.lambda1:.3g}{'' if d.in_band else ' (min J_SF)'} | "
                      f"{fmt(d.JS)} | {fmt(js(st, d.model.theta, data.valid))} | {fmt(d.JSF)} | "
                      f"{fmt(np.mean(tj))}, {fmt(max(tj))} |", flush=True)


def _draws(seeds, degrees, estimators, plant=None, show=True):
    """ELS and each SE estimator on draws ``seeds`` of the simulated plant, scored on each draw's own records.

    Returns {degree: array (draws, 2 (1 + len(estimators)), 2)}: per draw and model (ELS first, then the
    estimators in order) two columns, [J_S valid, J_S ident] then [J_SF, NaN] (model k in columns 2k
    and 2k + 1)."""
    from graybox.datasets.pumping import N_IDENT, generate
    rows = {}
    for seed in seeds:
        run, static = generate(seed, plant)
        rec = gb.Record(run.u, run.y, Ts=run.Ts, name=f"draw {seed}")
        ident, valid = rec.slice(0, N_IDENT, name="ident"), rec.slice(N_IDENT, None, name="valid")
        for degree, n_terms in ((2, 17), (3, 23)):
            if degree not in degrees:
                continue
            cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
            e = quiet(gb.els, quiet(gb.frols, cand, ident, n_terms=n_terms, include=["1"]), ident)
            ST[0] = st = e.model.structure.process
            ths = [e.model.theta] + [est(ident, static, BAND)[0] for est in estimators]
            flat = []
            for th in ths:
                flat += [[js(st, th, valid), js(st, th, ident)], [quiet(gb.jsf, gb.Model(st, th), static), np.nan]]
            rows.setdefault(degree, []).append(flat)
            if show:
                print(f"| {seed} | {degree} | " + " | ".join(fmt(f[0]) for f in flat) + " |", flush=True)
    return {d: np.array(r) for d, r in rows.items()}


def _summary(a, c):
    """Figures of estimator ``c`` (0-based) against ELS over the draws of ``a`` (see :func:`_draws`).

    A win is a validation J_S at most ELS's where ELS's stays bounded, or any bounded one where ELS's
    diverges; both diverging is a tie. Medians of the ratios are over the draws where both stay bounded;
    ``els_inf`` counts ELS's divergences, ``se_inf`` the estimator's."""
    els_v, els_i = a[:, 0, 0], a[:, 0, 1]
    v, i, jsf = a[:, 2 + 2 * c, 0], a[:, 2 + 2 * c, 1], a[:, 3 + 2 * c, 0]
    both = np.isfinite(v) & np.isfinite(els_v)
    wins = (both & (v <= els_v)) | (np.isfinite(v) & ~np.isfinite(els_v))
    ratio, ident = v[both] / els_v[both], i[both] / els_i[both]
    return dict(inb=int(np.sum(jsf <= BAND)), wins=int(np.sum(wins)), median=float(np.median(ratio)),
                ident=float(np.median(ident)), bad=int(np.sum(ratio > 5)), els_inf=int(np.sum(~np.isfinite(els_v))),
                se_inf=int(np.sum(~np.isfinite(v))))


def draws(n, degrees):
    """Table I's SE-against-ELS comparison over ``n`` draws of the simulated plant (seeds 1 … n)."""
    print("| draw | ℓ | ELS valid | ELS J_SF | SE-grad valid | SE-grad J_SF | GA valid | GA J_SF |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    rows = _draws(range(1, n + 1), degrees, [front_dsf("gradient"), front_dsf("ga", starts="pe")])
    print()
    summary_table(rows)


def summary_table(rows, label=None, header=True):
    """The SE-grad and GA (estimators 0 and 1 of :func:`_draws`) against ELS summary, one line per degree of
    ``rows``, beside Table I's own ratios; ``label`` (a stand-in's name) adds a first column."""
    from graybox.reference import TABLE_I
    first = "" if label is None else "| stand-in "
    if header:
        print(f"{first}| ℓ | draws | ELS J_SF > B | ELS diverges, SE-grad, GA | SE in B: grad, GA | SE valid ≤ ELS: grad, GA "
              "| median SE/ELS valid: grad, GA | median SE/ELS ident: grad, GA | SE/ELS > 5: grad, GA "
              "| paper SE/ELS valid, ident |")
        print(("| --- " if label is not None else "") + "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for degree, a in rows.items():
        g, ga = _summary(a, 0), _summary(a, 1)
        se, els_ = TABLE_I[f"SE (D_SF) ℓ={degree}"], TABLE_I[f"ELS ({15 if degree == 2 else 17})"]
        print(("" if label is None else f"| {label} ") +
              f"| {degree} | {len(a)} | {int(np.sum(a[:, 1, 0] > BAND))} | {g['els_inf']}, {g['se_inf']}, {ga['se_inf']} | "
              f"{g['inb']}, {ga['inb']} | {g['wins']}, {ga['wins']} | {g['median']:.2f}, {ga['median']:.2f} | "
              f"{g['ident']:.2f}, {ga['ident']:.2f} | {g['bad']}, {ga['bad']} | "
              f"{se['JS_valid'] / els_['JS_valid']:.2f}, {se['JS_ident'] / els_['JS_ident']:.2f} |", flush=True)


#: Stand-in variants (PumpingPlant keywords) for --part variants: which disturbance makes SE lose to ELS?
VARIANTS = {
    "as bundled": {},
    "no air loss": {"air_loss_per_rpm": 0.0},
    "air loss / 4": {"air_loss_per_rpm": 2e-5},
    "air vents in 10 s": {"air_vent_time": 10.0},
    "no air, surge / 2": {"air_loss_per_rpm": 0.0, "surge_intensity": 0.00275},
    "no air, surge decays in 2 s": {"air_loss_per_rpm": 0.0, "surge_time": 2.0},
    "no air, no surge": {"air_loss_per_rpm": 0.0, "surge_intensity": 0.0},
}


def windowed(H, whole=False):
    """SE-grad D_SF fitted on the identification record cut into windows of ``H`` samples, each run freely
    from its own measured first samples (with ``whole``, the whole record's free run as well)."""
    def fit(rec, static, band):
        w = [rec.slice(i, min(i + H, len(rec)), name=f"window {i}") for i in range(0, len(rec) - H // 2, H)]
        return front_dsf("gradient")(([rec] if whole else []) + w, static, band)
    return fit


def windows(n, degrees):
    """SE-grad D_SF fitted on restarted windows, or with a ridge, against the whole free run, over ``n`` draws of three stand-ins."""
    from graybox.datasets.pumping import PumpingPlant
    ests = {"whole record": front_dsf("gradient"), "windows of 200": windowed(200), "windows of 400": windowed(400),
            "whole + windows of 400": windowed(400, whole=True), "whole record, ridge 0.1": front_dsf("gradient", ridge=0.1)}
    print("| plant | ℓ | fit | ELS, SE diverge | SE valid ≤ ELS | median SE/ELS valid | median SE/ELS ident | SE/ELS > 5 |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in ("as bundled", "no air loss", "no air, no surge"):
        rows = _draws(range(1, n + 1), degrees, list(ests.values()), plant=PumpingPlant(**VARIANTS[name]), show=False)
        for degree, a in rows.items():
            for c, label in enumerate(ests):
                g = _summary(a, c)
                print(f"| {name} | {degree} | {label} | {g['els_inf']}, {g['se_inf']} | {g['wins']} | {g['median']:.2f} | "
                      f"{g['ident']:.2f} | {g['bad']} |", flush=True)
    # the same restarts on the buck converter and the synthetic systems with static points (bench_honest's cases)
    from bench_honest import TRUE, cases
    print("\n| case | fit | choice | J_S ident | J_S choose | J_SF | band | J_S test |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    all_cases = cases()
    for name in ("buck", "slow disturbance", "static points off the records"):
        data, test, cand, band = all_cases[name]
        ST[0] = st = (quiet(gb.frols, gb.Candidates(2, 2, degree=2), data.ident, n_terms=6, include=["1"]).structure
                      if name == "buck" else TRUE)
        for label, est in (("whole record", front_dsf("gradient")), ("whole + windows of 100", windowed(100, True)),
                           ("whole + windows of 200", windowed(200, True)), ("whole + windows of 400", windowed(400, True))):
            th, how = est(data.ident, data.static, band)
            print(f"| {name} | {label} | {how} | {fmt(js(st, th, data.ident))} | {fmt(js(st, th, data.valid))} | "
                  f"{fmt(gb.jsf(gb.Model(st, th), data.static))} | {band:g} | {fmt(js(st, th, test))} |", flush=True)


def _fit_draw(seed, plant, degree=2, out_noise=None):
    """Draw ``seed`` of ``plant`` split as reproduce splits it, ELS and SE-grad D_SF fitted on its identification
    record: (structure, ident, valid, static, θ ELS, θ SE-grad). ``out_noise`` = (std, pole): AR(1) noise of that
    std (mlc) added to the measured output (a coloured transmitter error the static test averages out)."""
    from graybox.datasets.pumping import N_IDENT, generate
    run, static = generate(seed, plant)
    y = run.y
    if out_noise is not None:
        std, pole = out_noise
        e = np.random.default_rng(1000 + seed).standard_normal(len(y)) * std * np.sqrt(1 - pole**2)
        y = y + scipy.signal.lfilter([1.0], [1.0, -pole], e)
    rec = gb.Record(run.u, y, Ts=run.Ts, name=f"draw {seed}")
    ident, valid = rec.slice(0, N_IDENT, name="ident"), rec.slice(N_IDENT, None, name="valid")
    cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
    e = quiet(gb.els, quiet(gb.frols, cand, ident, n_terms=17 if degree == 2 else 23, include=["1"]), ident)
    ST[0] = st = e.model.structure.process
    return st, ident, valid, static, e.model.theta, front_dsf("gradient")(ident, static, BAND)[0]


def _js_estimated_start(st, th, rec):
    """J_S with the first max_lag outputs of the free run estimated (least squares on the whole record, from the
    measured ones), as MATLAB's ``compare`` scores by default; a diverging run costs 1e3 mlc per sample."""
    L = st.max_lag

    def res(y0):
        r = (rec.y - gb.simulate(st, th, rec.u, y0, on_diverge="nan"))[L:]
        return np.where(np.isfinite(r), r, 1e3)
    y0 = scipy.optimize.least_squares(res, rec.y[:L].copy(), method="lm", max_nfev=200).x
    return float(np.mean(res(y0) ** 2))


#: Coloured output noise for --part scoring: (std in mlc, AR(1) pole).
OUT_NOISE = ((0.5, 0.9), (1.0, 0.9), (0.7, 0.98), (1.0, 0.5))


def scoring(n):
    """Is SE's ℓ = 2 loss how the validation record is scored (its measured start) or measured (output noise)?
    ELS against SE-grad D_SF over ``n`` draws: J_S from measured and from estimated first outputs, J_S after the
    first 200 samples; and draws of the stand-in with coloured noise added to its measured output."""
    from graybox.datasets.pumping import PumpingPlant
    print("| stand-in | score | median SE/ELS valid | SE valid ≤ ELS | median SE/ELS ident |")
    print("| --- | --- | --- | --- | --- |")

    def line(name, score, els_v, se_v, els_i=None, se_i=None):
        ok = np.isfinite(els_v) & np.isfinite(se_v)
        ident = f"{np.median(se_i[ok] / els_i[ok]):.2f}" if els_i is not None else ""
        print(f"| {name} | {score} | {np.median(se_v[ok] / els_v[ok]):.2f} | {int(np.sum(se_v <= els_v))} of {len(se_v)} "
              f"| {ident} |", flush=True)

    r = []
    for seed in range(1, n + 1):
        st, ident, valid, static, th_e, th_s = _fit_draw(seed, PumpingPlant())
        r.append([f(st, th, valid) for th in (th_e, th_s) for f in (
            js, _js_estimated_start,
            lambda st, th, rec: float(np.mean((rec.y - gb.simulate(st, th, rec, on_diverge="nan"))[200:] ** 2)))]
                 + [js(st, th_e, ident), js(st, th_s, ident)])
    a = np.array(r)
    line("as bundled", "J_S, measured start (Table I's)", a[:, 0], a[:, 3], a[:, 6], a[:, 7])
    line("as bundled", "J_S, estimated start", a[:, 1], a[:, 4])
    line("as bundled", "J_S after the first 200 samples", a[:, 2], a[:, 5])
    for std, pole in OUT_NOISE:
        r = []
        for seed in range(1, n + 1):
            st, ident, valid, static, th_e, th_s = _fit_draw(seed, PumpingPlant(), out_noise=(std, pole))
            r.append([js(st, th_e, valid), js(st, th_s, valid), js(st, th_e, ident), js(st, th_s, ident)])
        a = np.array(r)
        line(f"+ output noise std {std} mlc, pole {pole}", "J_S, measured start", a[:, 0], a[:, 1], a[:, 2], a[:, 3])


def startup(seeds):
    """Where on the validation record the ℓ = 2 SE-grad D_SF model and ELS err: J_S over each quarter (200
    samples), on draws of the stand-in without slow disturbances and of the bundled one."""
    from graybox.datasets.pumping import PumpingPlant
    print("| plant | draw | model | J_S by quarter of the validation record | J_1, J_20, J_100 (k steps ahead) |")
    print("| --- | --- | --- | --- | --- |")
    for name in ("no air, no surge", "as bundled"):
        plant = PumpingPlant(**VARIANTS[name])
        for seed in seeds:
            st, ident, valid, static, th_e, th_s = _fit_draw(seed, plant)
            for label, th in (("ELS", th_e), ("SE-grad", th_s)):
                err = gb.simulate(st, th, valid, on_diverge="nan") - valid.y
                q = [np.mean(err[i * 200:(i + 1) * 200] ** 2) for i in range(len(err) // 200)]
                m = gb.Model(st, th)
                jk = [np.mean((m.predict(valid, horizon=h) - valid.y)[st.max_lag:] ** 2) for h in (1, 20, 100)]
                print(f"| {name} | {seed} | {label} | {', '.join(fmt(v) for v in q)} | {', '.join(fmt(v) for v in jk)} |",
                      flush=True)


def variants(n, degrees):
    """ELS against SE-grad D_SF over ``n`` draws of each stand-in variant of :data:`VARIANTS`."""
    from graybox.datasets.pumping import PumpingPlant
    print("| variant | ℓ | median ELS valid | median ELS J_SF | ELS, SE diverge | SE in B | SE valid ≤ ELS "
          "| median SE/ELS valid | median SE/ELS ident | SE/ELS > 5 |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, kw in VARIANTS.items():
        rows = _draws(range(1, n + 1), degrees, [front_dsf("gradient")], plant=PumpingPlant(**kw), show=False)
        for degree, a in rows.items():
            g = _summary(a, 0)
            print(f"| {name} | {degree} | {np.median(a[:, 0, 0]):.3g} | {np.median(a[:, 1, 0]):.3g} | "
                  f"{g['els_inf']}, {g['se_inf']} | {g['inb']} | {g['wins']} | {g['median']:.2f} | {g['ident']:.2f} | "
                  f"{g['bad']} |", flush=True)


def others():
    from bench_honest import TRUE, cases
    print("| case | model | choice | J_S ident | J_S choose | J_SF | band | J_S test | s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    all_cases = cases()
    for name in ("buck", "slow disturbance", "static points off the records"):
        data, test, cand, band = all_cases[name]
        if name == "buck":
            st = quiet(gb.frols, gb.Candidates(2, 2, degree=2), data.ident, n_terms=6, include=["1"]).structure
        else:
            st = TRUE
        ST[0] = st
        variants = {"SE GA (paper)": front_dsf("ga"), "SE GA, starts='pe'": front_dsf("ga", starts="pe"),
                    "SE GA, PE front seeds": front_dsf("ga", starts=pe_seeds),
                    "SE-grad": front_dsf("gradient"), "se_dsf no margin": direct_dsf(None),
                    "se_dsf margin 0.01": direct_dsf(0.01)}
        for label, est in variants.items():
            t0 = time.perf_counter()
            try:
                th, how = est(data.ident, data.static, band)
            except ValueError as exc:
                print(f"| {name} | {label} | failed: {str(exc)[:90]} | | | | | | |")
                continue
            print(f"| {name} | {label} | {how} | {fmt(js(st, th, data.ident))} | {fmt(js(st, th, data.valid))} | "
                  f"{fmt(gb.jsf(gb.Model(st, th), data.static))} | {band:g} | {fmt(js(st, th, test))} | "
                  f"{time.perf_counter() - t0:.0f} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("plant", "seeds", "draws", "variants", "windows", "startup", "scoring", "others",
                                       "all"), default="all")
    ap.add_argument("--draws", type=int, default=30, help="--part draws, variants, windows: how many draws of the plant")
    ap.add_argument("--degrees", default="2,3", help="plant structures: 2 (17 terms), 3 (23 terms)")
    args = ap.parse_args(argv)
    print(f"# bench_se_table.py --part {args.part}: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} "
          f"UTC, git {git_rev()}, {machine()}")
    if args.part in ("plant", "all"):
        print("\n## bundled plant (band 0.031 mlc², margin 0.01 unless named)\n")
        plant([int(d) for d in args.degrees.split(",")])
    if args.part in ("seeds", "all"):
        print("\n## the GA with and without PE seeds, seeds 1-3 (bundled plant)\n")
        ga_seeds()
    if args.part in ("draws", "all"):
        print(f"\n## Table I over {args.draws} draws of the simulated plant (reproduce settings)\n")
        draws(args.draws, [int(d) for d in args.degrees.split(",")])
    if args.part in ("variants", "all"):
        print(f"\n## ELS against SE-grad D_SF over {args.draws} draws of stand-in variants\n")
        variants(args.draws, [int(d) for d in args.degrees.split(",")])
    if args.part in ("windows", "all"):
        print(f"\n## SE-grad D_SF fitted on restarted windows, {args.draws} draws\n")
        windows(args.draws, [int(d) for d in args.degrees.split(",")])
    if args.part in ("startup", "all"):
        print("\n## where the ℓ = 2 models err on the validation record (draws 1-4)\n")
        startup(range(1, 5))
    if args.part in ("scoring", "all"):
        print(f"\n## ℓ = 2: how the validation record is scored or measured, {args.draws} draws\n")
        scoring(args.draws)
    if args.part in ("others", "all"):
        print("\n## buck converter and synthetic systems with static points (margin 0.01 unless named)\n")
        others()


if __name__ == "__main__":
    main()
