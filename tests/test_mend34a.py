"""Mends of batch 34a, left open by the coordinator: the stationarity checks of cls_uncertainty and
pe_uncertainty in any output units, static curves and gains of inputs far from zero, bootstrap
options that make every replicate fail, and SE costs of diverging members. Each test fails
without its fix."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from test_bootstrap import STRUCT as BOOT_STRUCT
from test_bootstrap import data  # noqa: F401 (the fixture)
from test_hunt30c import SPEED_TERMS, speed_record, speed_ybar

UBAR = np.array([2500.0, 2800.0, 3100.0, 3400.0])


def _verdict(call):
    try:
        return call().std
    except ValueError as exc:
        assert "not the optimum" in str(exc)
        return None


def test_cls_and_pe_uncertainty_verdicts_do_not_depend_on_the_output_units():
    # cls_uncertainty and pe_uncertainty check that θ is the optimum of the problem they are given, but
    # measured the gradient against |Aᵀy|, which grows with the output's offset, at a tolerance of 1e-5:
    # the CLS estimate of another record was accepted in any units, and a PE member of another record
    # was refused in gauge pressure (near 0 Pa) but accepted in absolute pressure (near 2e5 Pa).
    rng = np.random.default_rng(0)
    a, b = speed_record(rng, 300, hold=5), speed_record(rng, 300, hold=5)
    seen = []
    for offset, scale in [(-2e5, 1.0), (0.0, 1.0), (2e5, 1.0), (0.0, 1e-3)]:  # gauge Pa, absolute Pa, ×2, kPa
        ra, rb = (gb.Record(r.u, (r.y + offset) * scale, Ts=0.1, input_names=("speed",)) for r in (a, b))
        pts = gb.StaticPoints(UBAR, (speed_ybar(UBAR) + offset) * scale, input_names=("speed",))
        two = gb.StaticPoints(UBAR[:2], pts.ybar[:2], input_names=("speed",))
        c = gb.cls(SPEED_TERMS, ra, two, how="points").model
        member = gb.pe_pareto(SPEED_TERMS, ra, pts, lambdas=[0.5, 1.0]).member_model(0)
        stds = [_verdict(lambda: gb.cls_uncertainty(c, ra, two, how="points")),
                _verdict(lambda: gb.cls_uncertainty(c, rb, two, how="points")),
                _verdict(lambda: gb.pe_uncertainty(member, ra, pts, lambda1=0.5, static_sigma=50 * scale)),
                _verdict(lambda: gb.pe_uncertainty(member, rb, pts, lambda1=0.5, static_sigma=50 * scale)),
                _verdict(lambda: gb.pe_uncertainty(member, ra, pts, lambda1=0.45, static_sigma=50 * scale))]
        assert [s is not None for s in stds] == [True, False, True, False, False], (offset, scale)
        # relative stds of the terms the offset does not move (the constant term absorbs it)
        seen.append([np.asarray(s)[:3] / np.abs(m.theta[:3]) for s, m in ((stds[0], c), (stds[2], member))])
    for other in seen[1:]:
        for x, y in zip(seen[0], other):
            np.testing.assert_allclose(x, y, rtol=1e-6)



@pytest.mark.parametrize("solver", ["clarabel", "osqp", "closed"])
def test_cls_uncertainty_takes_a_qp_estimate_whose_constrained_cluster_is_round_off_from_zero(solver):
    # Eq. (22) sets a cluster Σ_yu of one term to 0; a QP leaves it at round-off (2e-17), and
    # cls_uncertainty measured the constraint's residual against |A||θ|, i.e. against that residual
    # itself: the CLS estimate on its own data was refused as "does not satisfy (22)" (the closed
    # form's exact 0 passed). The residual is now measured in the solver's scaled coordinates.
    rng = np.random.default_rng(0)
    terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-1)u(k-1)", "1", "y(k-2)"]
    v = np.repeat(rng.uniform(-50, 50, 101), 30)[:3000]
    y = np.zeros(3000)
    for k in range(1, 3000):
        y[k] = (0.8 + 2e-4 * v[k - 1]) * y[k - 1] + v[k - 1] + 4e-3 * v[k - 1] ** 2 + 20 + 0.02 * rng.standard_normal()
    rec = gb.Record(v, y, Ts=1.0)
    vb = np.linspace(-50, 50, 7)
    pts = gb.StaticPoints(vb, (20 + vb + 4e-3 * vb**2) / (0.2 - 2e-4 * vb))
    curve = gb.StaticCurve.fit(pts, 2)
    model = gb.cls(terms, rec, curve, solver=solver, reference="ls").model
    unc = gb.cls_uncertainty(model, rec, curve, reference="ls")
    # Σ_yu = 0, Σ_y = Σ*_y, Σ_0, Σ_u, Σ_u² fixed: y(k-1) and y(k-2) share the one free direction
    assert unc.constraints.shape[0] == 5 and unc.std[0] > 0 and unc.std[5] == pytest.approx(unc.std[0])
    other = gb.Model(model.structure, model.theta + np.array([0, 0, 0, 1e-6, 0, 0]))  # (22) broken by 1e-6
    with pytest.raises(ValueError, match="does not satisfy static curve equality"):
        gb.cls_uncertainty(other, rec, curve, reference="ls")
    # Σ_y estimated (the default): Σ_yu = 0 and Σ_{u^m} + c_m Σ_y = c_m, one row fewer, the same round-off
    free = gb.cls(terms, rec, curve, solver=solver).model
    unc = gb.cls_uncertainty(free, rec, curve)
    assert unc.constraints.shape[0] == 4 and unc.std[3] == 0 and np.all(np.delete(unc.std, 3) > 0)  # Σ_yu alone fixed


# --------------------------------------------------------------------------------------------
# bootstrap_decision when replicates fail
# --------------------------------------------------------------------------------------------
def _boot(data, **kw):
    args = dict(estimator="pe", lambdas=np.logspace(-4, 0, 8), n_boot=6, band=0.05,
                options={"solver": "closed"}, progress=False)
    args.update(kw)
    return gb.bootstrap_decision(BOOT_STRUCT, data, **args)


def test_bootstrap_with_every_replicate_failing_raises_the_first_reason(data):
    # A band no member reaches (and no fallback) made every replicate fail, and the user got a
    # DecisionBootstrap full of NaN (agreement NaN, an empty summary) instead of an error.
    with pytest.raises(ValueError, match=r"every one of the 6 replicates failed.*replicate 0.*no member of the Pareto "
                                         r"set") as info:
        _boot(data, band=1e-12)
    assert "InfeasibleError" in str(info.value)  # decide_dsf's own reason, with its type


@pytest.mark.parametrize("estimator, options, error, says", [
    ("pe", {"solver": "bogus"}, ValueError, "solver must be one of"),
    ("pe", {"solver": "closed", "weights": "bogus"}, ValueError, "weights must be one of"),
    ("se", {"method": "bogus"}, ValueError, "method must be one of"),
    ("se", {"method": "gradient", "max_nfev": 0}, ValueError, "max_nfev must be an integer >= 1"),
    ("se", {"method": "gradient", "max_nfev": "ten"}, TypeError, "max_nfev must be an integer"),
    ("se", {"max_nfev": 3}, ValueError, "applies to method='gradient' only"),
])
def test_bootstrap_refuses_an_option_the_sweep_refuses_before_any_replicate_runs(data, estimator, options, error,
                                                                                  says):
    # An option value the sweep refuses made every replicate fail with the same reason (a result full
    # of NaN), or, for a wrong type, raised a TypeError out of the first job on the executor.
    ran = []

    def spy_map(job, ids):
        ran.extend(ids)
        return [job(i) for i in ids]

    with pytest.raises(error, match=says):
        _boot(data, estimator=estimator, lambdas=[1.0, 0.1], options=options, map=spy_map)
    assert ran == []


def test_bootstrap_counts_and_says_a_few_failing_replicates(data):
    # A few failing replicates were kept in .failures without a word: the summary, frequencies and
    # agreement silently described the replicates that succeeded only.
    smallest = _boot(data, band=1e-12, fallback="min_jsf").JSF  # each replicate's smallest J_SF
    band = float(np.median(smallest))
    expected = int(np.sum(smallest > band))
    assert 0 < expected < smallest.size
    with pytest.warns(gb.UncertaintyWarning, match=rf"{expected} of 6 replicates failed.*no member of the Pareto set"):
        boot = _boot(data, band=band)
    assert len(boot.failures) == expected and int(np.sum(~boot.ok)) == expected


# --------------------------------------------------------------------------------------------
# SE costs of diverging members
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def growing_record():
    # A record that grows as 1.01^k over 3000 samples (to ~5e14, no overflow): its own model
    # y(k) = 1.01 y(k-1) + u(k-1) leaves simulate's default bound (10⁶ × the run's own scale), so
    # gb.js calls it diverging (inf).
    rng = np.random.default_rng(0)
    u = rng.uniform(0, 1, 3000)
    y = np.zeros(3000)
    for k in range(1, 3000):
        y[k] = 1.01 * y[k - 1] + u[k - 1]
    return gb.Record(u, y, Ts=1.0)


def test_se_sweeps_never_return_a_member_whose_free_run_leaves_the_bound(growing_record):
    # The GA's and the gradient sweep's costs used an unbounded J_S (inf only on overflow), while the
    # front's reported J_S is bounded as gb.js: a run that leaves the bound was fitted with a finite
    # cost (0 for the gradient, 1e14 for the GA) and returned as a member of the front, its reported
    # J_S inf (nondominated all the same) against the optimiser's finite cost. Now the costs are
    # bounded too: the GA keeps a member whose run stays bounded, at the cost it reports; the
    # gradient sweep, whose every start leaves the bound, has no member.
    structure = ["y(k-1)", "u(k-1)"]
    assert not np.isfinite(gb.js(gb.Model(structure, [1.01, 1.0]), growing_record))
    pts = gb.StaticPoints([0.2, 0.8], [1.0, 4.0])
    kw = dict(lambdas=[1.0], margin=None, progress=False)
    ga = gb.se_pareto(structure, growing_record, pts, method="ga", options=gb.GAOptions(population=20, generations=3),
                      **kw)
    assert np.all(np.isfinite(ga.JS)) and not ga.failures
    np.testing.assert_allclose(ga.JS, ga.extra["cost"], rtol=1e-9)  # λ1 = 1: the cost is J_S
    with pytest.raises(ValueError, match="every member of the SE sweep.*free run diverges"):
        gb.se_pareto(structure, growing_record, pts, method="gradient", **kw)
