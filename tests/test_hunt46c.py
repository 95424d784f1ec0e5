"""Bugs found by the hunt of session 46 (c): simulation-error estimation as a researcher drives it."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _set(lambdas, J1=(0.0, 0.0), JS=(0.0, 0.0), JSF=(0.0, 0.0)):
    st = gb.parse_structure(["1", "y(k-1)"])
    return gb.ParetoSet(st, np.zeros((2, 2)), np.asarray(lambdas, float), np.asarray(J1, float),
                        np.asarray(JS, float), np.asarray(JSF, float))


@pytest.mark.parametrize("lam", [(1.5, 0.5), (0.5, 0.0), (-0.2, 1.0), (np.inf, 1.0)])
def test_pareto_set_refuses_a_weight_outside_0_1(lam):
    with pytest.raises(ValueError, match="lambdas"):
        _set(lam)


@pytest.mark.parametrize("field", ["J1", "JS", "JSF"])
def test_pareto_set_refuses_a_negative_mean_square(field):
    with pytest.raises(ValueError, match=field):
        _set((0.5, 1.0), **{field: (-1.0, 0.0)})


def test_pareto_set_keeps_nan_weights_and_inf_errors():
    p = _set((np.nan, 1.0), JS=(np.inf, 0.0), JSF=(np.nan, 0.0))
    assert np.isnan(p.lambdas[0]) and p.JS[0] == np.inf


@pytest.fixture(scope="module")
def pumping():
    return gb.load_pumping()


@pytest.fixture(scope="module")
def small_front(pumping):
    st = gb.parse_structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-2)y(k-1)"])
    return gb.se_pareto(st, pumping, lambdas=[1.0, 0.3], method="gradient")


def _in_units(record, units, Ts=None, factor=1.0):
    return gb.Record(record.u * factor, record.y, Ts=record.Ts if Ts is None else Ts, units=units, name="other")


@pytest.mark.parametrize("carrier", ["set", "model", "decision"])
def test_evaluate_thetas_refuses_data_in_other_units_than_the_front(pumping, small_front, carrier):
    obj = {"set": small_front, "model": small_front.member_model(0),
           "decision": gb.decide_dsf(small_front, band=10.0)}[carrier]
    rad = _in_units(pumping.valid, ("rad/s", "mlc"), factor=2 * np.pi / 60)
    with pytest.raises(ValueError, match="rad/s"):
        gb.evaluate_thetas(obj, small_front.thetas, rad)
    fast = _in_units(pumping.valid, ("rpm", "mlc"), Ts=0.01)
    with pytest.raises(ValueError, match="sampled"):
        gb.evaluate_thetas(obj, small_front.thetas, fast)
    s = pumping.static
    pts = gb.StaticPoints(s.ubar * 2 * np.pi / 60, s.ybar, units=("rad/s", "mlc"))
    with pytest.raises(ValueError, match="rad/s"):
        gb.evaluate_thetas(obj, small_front.thetas, None, pts)
    # the data it was fitted on are scored as before, and a bare structure checks nothing
    ok = gb.evaluate_thetas(obj, small_front.thetas, pumping)
    assert np.allclose(ok["JS"], gb.evaluate_thetas(small_front.structure, small_front.thetas, pumping)["JS"])
    assert np.all(np.isfinite(gb.evaluate_thetas(small_front.structure, small_front.thetas, rad)["JS"]))


_ST = ["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-2)y(k-1)"]
_GA = dict(lambdas=[1.0, 0.3], method="ga", options=gb.GAOptions(population=10, generations=2))


@pytest.fixture(scope="module")
def checkpoint_arrays(pumping, tmp_path_factory):
    path = tmp_path_factory.mktemp("ck") / "front.npz"
    gb.se_pareto(_ST, pumping, checkpoint=path, **_GA)
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize("change", [
    {"costs": np.array([np.nan, np.nan])},          # a NaN cost taken for a fitted member's
    {"costs": np.array([0.5])},                     # one cost broadcast over both members
    {"nfev": np.array([3])},                        # one count broadcast over both members
    {"done": np.array(1.5)},                        # truncated to 1 member done
    {"thetas": None},                               # a fitted member's θ not finite
    {"thetas": np.array(["a", "b"])},               # text: a broadcasting error, not a corrupt file
    {"costs": np.array([-1.0, 2.0])},
])
def test_a_corrupt_se_checkpoint_is_refused_naming_the_file(pumping, checkpoint_arrays, tmp_path, change):
    arrays = dict(checkpoint_arrays)
    for k, v in change.items():
        arrays[k] = np.full_like(arrays["thetas"], np.inf) if v is None else v
    path = tmp_path / "front.npz"
    np.savez(path, **arrays)
    with pytest.raises(gb.estimation._simulation_error.CheckpointError, match="corrupt"):
        gb.se_pareto(_ST, pumping, checkpoint=path, **_GA)


def test_a_whole_se_checkpoint_still_resumes(pumping, checkpoint_arrays, tmp_path):
    path = tmp_path / "front.npz"
    np.savez(path, **checkpoint_arrays)
    again = gb.se_pareto(_ST, pumping, checkpoint=path, **_GA)
    assert np.array_equal(again.extra["cost"], checkpoint_arrays["costs"])


def _moved(data, y_offset=0.0, u_offset=0.0):
    rec = lambda r: gb.Record(r.u + u_offset, r.y + y_offset, Ts=r.Ts, name=r.name)
    s = data.static
    return gb.Dataset(rec(data.ident), rec(data.valid), gb.StaticPoints(s.ubar + u_offset, s.ybar + y_offset,
                                                                       uncertainty=s.uncertainty))


@pytest.mark.parametrize("y_offset", [1e4, -1e4])
def test_the_ga_front_of_a_closed_structure_does_not_depend_on_the_outputs_zero(pumping, y_offset):
    # the GA's individuals whose free runs left the default bound (10⁶ times the run's own size) got an infinite cost
    # on y in mlc but a finite one on y + 1e4 (a bound 500 times wider): other individuals were ranked and bred, and
    # the front differed (J_SF up to 15 times); the free runs are now made on the centred signals
    kw = dict(lambdas=[1.0, 0.5, 0.1, 0.01], method="ga", options=gb.GAOptions(population=30, generations=10), seed=1)
    ref = gb.se_pareto(_ST, pumping, **kw)
    moved = gb.se_pareto(_ST, _moved(pumping, y_offset=y_offset), **kw)
    np.testing.assert_allclose(moved.JS, ref.JS, rtol=1e-6)
    np.testing.assert_allclose(moved.JSF, ref.JSF, rtol=1e-6)


def test_the_se_problem_judges_divergence_alike_at_every_offset(pumping):
    from graybox.estimation._simulation_error import SEProblem

    P0 = SEProblem(_ST, [pumping.ident], pumping.static)
    P1 = SEProblem(_ST, [_moved(pumping, y_offset=1e4).ident], _moved(pumping, y_offset=1e4).static)
    pop0 = P0.random_ls(np.random.default_rng(0), 200, 30)
    pop1 = P1.from_z(P0.to_z(pop0))  # the same models at the other offset
    c0, c1 = P0.cost(pop0, 1.0), P1.cost(pop1, 1.0)
    assert not np.all(np.isfinite(c0))  # some individuals diverge: the case at stake
    np.testing.assert_array_equal(np.isfinite(c0), np.isfinite(c1))
    np.testing.assert_allclose(c1[np.isfinite(c1)], c0[np.isfinite(c0)], rtol=1e-6)


def test_evaluate_of_no_model_says_so(pumping):
    # a bare KeyError: 'n_params' from building the empty table
    with pytest.raises(ValueError, match="empty"):
        gb.evaluate({}, pumping)


def test_an_empty_ubar_is_named(pumping):
    # said 'fit to pumping static points: no static points', of the curve's source and not of the argument
    curve = gb.StaticCurve.fit(pumping.static, degree=2)
    with pytest.raises(ValueError, match="ubar is empty"):
        gb.se_pareto(_ST, pumping.ident, curve, lambdas=[1.0, 0.3], method="gradient", ubar=[])


def test_bootstrap_refuses_a_parallel_map_not_entered(pumping):
    # README: parallel_map(workers=2) 'as a map (e.g. for bootstrap_decision(..., map=pmap))'; given without `with`,
    # the bootstrap ran the sweep on the original data and then failed with 'ContextDecorator.__call__() takes 2
    # positional arguments but 3 were given'
    pmap = gb.experiments.parallel_map(executor="inprocess")
    with pytest.raises(TypeError, match="with graybox.experiments.parallel_map"):
        gb.bootstrap_decision(_ST, pumping, estimator="pe", lambdas=[1.0, 0.1], n_boot=2, map=pmap,
                              options={"solver": "closed"}, fallback="min_jsf")
    with gb.experiments.parallel_map(executor="inprocess") as entered:  # the map it makes is taken
        boot = gb.bootstrap_decision(_ST, pumping, estimator="pe", lambdas=[1.0, 0.1], n_boot=2, map=entered,
                                     options={"solver": "closed"}, fallback="min_jsf")
    assert len(boot.frequencies()) >= 1


@pytest.mark.parametrize("stall", [1, 3])
def test_the_ga_stops_after_stall_generations_without_improvement(stall):
    # GAOptions: 'stops ... when the best cost has not improved by a relative 1e-9 for stall generations'; it ran
    # stall + 1 (the first window, from the initial population, was never looked at)
    from graybox.estimation._simulation_error import _ga_run

    class Flat:  # every individual costs the same: no generation ever improves
        z_map = None

        def cost(self, pop, lam1, threads=1):
            return np.ones(len(pop))

    init = np.random.default_rng(0).standard_normal((10, 3))
    _, _, g = _ga_run(Flat(), 1.0, init, gb.GAOptions(population=10, generations=20, stall=stall),
                      np.random.default_rng(1), 1)
    assert g == stall


def test_a_checkpoint_of_inputs_named_in_another_order_is_not_resumed(tmp_path):
    # the same arrays with the inputs' names swapped (a file's columns mislabelled, then put right) had the same
    # fingerprint: the corrected call resumed the mislabelled sweep's members, silently
    data = gb.load_pumping_miso()
    st = ["1", "y(k-1)", "y(k-2)", "u1(k-2)", "u2(k-2)", "u1(k-2)^2", "u1(k-2)u2(k-2)", "u2(k-2)^2", "u1(k-2)y(k-1)"]
    kw = dict(lambdas=[1.0, 0.1], method="ga", margin=None, options=gb.GAOptions(population=10, generations=2),
              theta0=None)
    swapped = lambda r: gb.Record(r.u, r.y, Ts=r.Ts, input_names=("u2", "u1"), units=r.units, name=r.name)
    s = data.static
    wrong = gb.Dataset(swapped(data.ident), swapped(data.valid),
                       gb.StaticPoints(s.ubar, s.ybar, uncertainty=s.uncertainty, input_names=("u2", "u1"),
                                       units=s.units))
    ck = tmp_path / "front.npz"
    gb.se_pareto(st, wrong, checkpoint=ck, **kw)
    with pytest.raises(ValueError, match="another problem"):
        gb.se_pareto(st, data, checkpoint=ck, **kw)
    again = tmp_path / "again.npz"  # the default names' checkpoint resumes as before
    first = gb.se_pareto(st, data, checkpoint=again, **kw)
    assert np.array_equal(gb.se_pareto(st, data, checkpoint=again, **kw).thetas, first.thetas)


def test_a_failed_ga_member_says_its_individuals_lay_outside_the_margin(pumping):
    # said 'every free run diverged' of individuals whose free runs were bounded but outside the stability margin
    with pytest.raises(ValueError, match="outside the stability margin") as err:
        gb.se_pareto(_ST, pumping, lambdas=[1.0, 0.3], method="ga", margin=0.3, theta0=None,
                     options=gb.GAOptions(population=10, generations=2))
    assert "every free run diverged" not in str(err.value)
