"""Block bootstrap of a D_SF decision: resampling, reproducibility, pluggable maps, failures, figure."""

import pickle
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb
from graybox.diagnostics._bootstrap import BootstrapJob, block_resample

STRUCT = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "1"])
TRUE = gb.Model(STRUCT, [0.6, 0.2, 2e-3, 1e-3, -5e-7, 0.3])
LAMBDAS = np.logspace(-4, 0, 12)


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(750, 1650, 61), 10)[:600]
    y = TRUE.simulate(u, np.full(2, TRUE.static_curve([u[0]])[0])) + 0.05 * rng.standard_normal(600)
    ub = np.linspace(750, 1650, 8)
    static = gb.StaticPoints(ub, TRUE.static_curve(ub) + 0.05 * rng.standard_normal(8))
    return gb.Dataset(gb.Record(u, y, name="ident"), gb.Record(u, y, name="valid"), static)


def run(data, **kw):
    args = dict(estimator="pe", lambdas=LAMBDAS, n_boot=8, band=0.05, options={"solver": "closed"}, fallback="min_jsf")
    args.update(kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        return gb.bootstrap_decision(STRUCT, data, **args)


@settings(max_examples=30, deadline=None)
@given(lengths=st.lists(st.integers(5, 80), min_size=1, max_size=4), b=st.integers(5, 40), seed=st.integers(0, 1000))
def test_blocks_are_slices_of_one_record(lengths, b, seed):
    recs = [gb.Record(np.arange(n) + 1000.0 * i, -np.arange(n) - 1000.0 * i, name=f"r{i}") for i, n in enumerate(lengths)]
    if max(lengths) < b:
        with pytest.raises(ValueError, match="no record has"):
            block_resample(recs, b, np.random.default_rng(seed))
    else:
        blocks = block_resample(recs, b, np.random.default_rng(seed))
        assert len(blocks) == max(1, round(sum(lengths) / b))
        for blk in blocks:
            assert len(blk) == b
            i, s = int(blk.u[0] // 1000), int(blk.u[0] % 1000)
            np.testing.assert_array_equal(blk.u, np.arange(s, s + b) + 1000.0 * i)  # contiguous, one record
            np.testing.assert_array_equal(blk.y, -blk.u)
            assert blk.name == f"r{i}[{s}:{s + b}]"


def test_replicates_match_a_direct_rerun(data):
    boot = run(data)
    assert boot.n_replicates == 8 and not boot.failures
    assert boot.block_length == 60 and boot.n_blocks == 10  # max(10·(L+1), N/10) = 60
    job = BootstrapJob(STRUCT, (data.ident,), data.static, "pe", LAMBDAS, 0.05, "min_jsf", 60, 0, None,
                          {"solver": "closed"})
    for i in (0, 5):
        recs, sp = job.data(i)
        assert len(recs) == 10 and all(len(r) == 60 for r in recs)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gb.StaticRangeWarning)
            d = gb.decide_dsf(gb.pe_pareto(STRUCT, recs, sp, lambdas=LAMBDAS, solver="closed"), band=0.05, fallback="min_jsf")
        assert boot.lambda1[i] == d.lambda1 and boot.JS[i] == d.JS and boot.JSF[i] == d.JSF
        np.testing.assert_array_equal(boot.thetas[i], d.model.theta)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.StaticRangeWarning)
        ref = gb.decide_dsf(gb.pe_pareto(STRUCT, data.ident, data.static, lambdas=LAMBDAS, solver="closed"), band=0.05,
                            fallback="min_jsf")
    assert boot.reference["lambda1"] == ref.lambda1 and boot.reference["JS"] == ref.JS
    freq = boot.frequencies()
    assert freq["count"].sum() == 8 and freq["fraction"].sum() == pytest.approx(1.0)
    assert freq.loc[ref.lambda1, "reference"]
    assert boot.agreement == pytest.approx(np.mean(boot.lambda1 == ref.lambda1))
    s = boot.summary()
    assert s.loc["JS", "median"] == pytest.approx(np.median(boot.JS))
    assert s.loc["JS", "q05"] <= s.loc["JS", "median"] <= s.loc["JS", "q95"]


def test_seeded_and_independent_of_where_replicates_run(data):
    a = run(data, seed=3)
    b = run(data, seed=3)
    np.testing.assert_array_equal(a.lambda1, b.lambda1)
    np.testing.assert_array_equal(a.thetas, b.thetas)
    c = run(data, seed=4)
    assert not np.array_equal(a.thetas, c.thetas)
    with ThreadPoolExecutor(2) as ex:
        t = run(data, seed=3, map=ex.map)
    np.testing.assert_array_equal(t.thetas, a.thetas)
    # the job and its results travel by pickle (processes, Dask workers)
    job = BootstrapJob(STRUCT, (data.ident,), data.static, "pe", LAMBDAS, 0.05, "min_jsf", 60, 3, None,
                          {"solver": "closed"})
    again = pickle.loads(pickle.dumps(job))
    assert again(2) == job(2) == pickle.loads(pickle.dumps(job(2)))
    assert again(2)["theta"] == list(a.thetas[2])


def test_a_real_process_pool_through_the_experiment_layer(data):
    with gb.experiments.parallel_map(executor="processes", workers=2) as pmap:
        p = run(data, seed=3, n_boot=3, map=pmap)
    a = run(data, seed=3, n_boot=3)
    np.testing.assert_array_equal(p.thetas, a.thetas)
    np.testing.assert_array_equal(p.JS, a.JS)


def test_a_real_dask_cluster_through_the_experiment_layer(data):
    with gb.experiments.parallel_map(workers=2) as pmap:
        d = run(data, seed=3, n_boot=3, map=pmap)
    a = run(data, seed=3, n_boot=3)
    np.testing.assert_array_equal(d.thetas, a.thetas)
    with pytest.raises(ValueError, match="exactly one"):
        with gb.experiments.parallel_map():
            pass


def test_static_noise_and_se(data):
    boot = run(data, static_sigma=0.05, n_boot=3)
    job = BootstrapJob(STRUCT, (data.ident,), data.static, "pe", LAMBDAS, 0.05, None, 60, 0, 0.05, {})
    _, sp = job.data(1)
    assert np.all(sp.ybar != data.static.ybar) and np.array_equal(sp.ubar, data.static.ubar)
    assert boot.static_sigma == 0.05
    se = run(data, estimator="se", lambdas=[1.0, 0.3, 0.1], n_boot=2, options={"method": "gradient", "max_nfev": 10})
    assert se.estimator == "se" and se.n_replicates == 2
    assert set(se.lambda1[se.ok]) <= {1.0, 0.3, 0.1}


def test_failures_are_kept_with_their_reason(data):
    fb = run(data, band=1e-9, fallback="min_jsf", n_boot=4)  # each replicate's smallest J_SF, none in the band
    assert not fb.failures and fb.rules == ("min J_SF",) * 4 and not fb.in_band.any()
    band = float(np.median(fb.JSF))  # about half the replicates reach it
    failed = [int(i) for i in np.flatnonzero(fb.JSF > band)]
    with pytest.warns(gb.UncertaintyWarning, match=f"{len(failed)} of 4 replicates failed"):
        boot = run(data, band=band, fallback=None, n_boot=4)
    assert sorted(boot.failures) == failed and 0 < len(failed) < 4
    assert all("no member of the Pareto set" in why for why in boot.failures.values())
    assert ("failure" in boot.reference) == (fb.reference["JSF"] > band)
    assert np.all(np.isnan(boot.lambda1[failed])) and not boot.in_band[failed].any()
    assert [boot.rules[i] for i in failed] == [""] * len(failed)
    assert list(boot.to_frame()["failure"][failed].str.startswith("InfeasibleError")) == [True] * len(failed)
    with pytest.raises(ValueError, match="every one of the 3 replicates failed"):  # nothing left to summarise
        run(data, band=1e-9, fallback=None, n_boot=3)


def test_bad_options(data):
    with pytest.raises(ValueError, match="not keyword options of pe_pareto"):
        run(data, options={"solver": "closed", "max_nfev": 3})
    with pytest.raises(ValueError, match="not keyword options of se_pareto"):
        run(data, estimator="se", options={"checkpoint": "x.npz"})
    with pytest.raises(ValueError, match="block_length"):
        run(data, block_length=3)
    with pytest.raises(ValueError, match="longer than every record"):
        run(data, block_length=601)
    with pytest.raises(ValueError, match="estimator"):
        run(data, estimator="ga")
    with pytest.raises(ValueError, match="static points"):
        gb.bootstrap_decision(STRUCT, data.ident)
    with pytest.raises(ValueError, match="map returned"):
        run(data, n_boot=2, map=lambda f, xs: [f(x) for x in list(xs)[:1]])


def test_figure(data, tmp_path):
    from matplotlib.figure import Figure

    from graybox.plots import plot_decision_bootstrap

    boot = run(data)
    fig = plot_decision_bootstrap(boot)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    left, right = fig.axes
    assert left.get_xscale() == "log"
    assert sum(len(c.get_segments()) for c in left.collections) == len(boot.frequencies())
    pts = right.lines[0]
    np.testing.assert_array_equal(pts.get_xdata(), boot.JS)
    assert right.lines[1].get_marker() == "*"
    fig.savefig(tmp_path / "boot.png", dpi=50)
    with pytest.raises(TypeError, match="DecisionBootstrap"):
        plot_decision_bootstrap(boot.to_frame())
