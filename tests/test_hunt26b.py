"""Bugs found by a second bug hunt on one's own data (a two-input NARX system, inputs "valve" and
"speed", an output in Pa near 2e5 or in tiny units): each test fails without its fix."""

import warnings

import numpy as np
import pytest

import graybox as gb

#: y(k) = 3e4 + 100 valve(k-1) + 1e-3 speed(k-1)² + 0.05 valve(k-1) speed(k-1) + 0.6 y(k-1) + 0.2 y(k-2), in Pa
TRUE = gb.Structure(["1", "valve(k-1)", "speed(k-1)^2", "valve(k-1)speed(k-1)", "y(k-1)", "y(k-2)"])
THETA = np.array([3e4, 100.0, 1e-3, 0.05, 0.6, 0.2])
INPUTS = ("valve", "speed")


def record(seed: int, n: int, noise: float = 0.02, scale: float = 1.0, name: str | None = None) -> gb.Record:
    """The system on a staircase (valve in [20, 80] %, speed in [1000, 3000] rpm), output noise of
    ``noise`` × std y, the output in Pa × ``scale``."""
    rng = np.random.default_rng(seed)
    u = np.column_stack([np.repeat(rng.uniform(20, 80, n // 15 + 1), 15)[:n],
                         np.repeat(rng.uniform(1000, 3000, n // 15 + 1), 18)[:n]])
    y = gb.Model(TRUE, THETA, input_names=INPUTS).simulate(u, np.full(2, 2e5))
    y = y + noise * np.std(y) * rng.standard_normal(n)
    return gb.Record(u, y * scale, 0.1, name=name or f"r{seed}", input_names=INPUTS, units=("", "Pa"))


def static(ub: np.ndarray, scale: float = 1.0, uncertainty: float | None = None) -> gb.StaticPoints:
    yb = (THETA[0] + THETA[1] * ub[:, 0] + THETA[2] * ub[:, 1] ** 2 + THETA[3] * ub[:, 0] * ub[:, 1]) / 0.2
    return gb.StaticPoints(ub, yb * scale, input_names=INPUTS,
                           uncertainty=None if uncertainty is None else uncertainty * scale)


def grid(valve, speed) -> np.ndarray:
    vv, ss = np.meshgrid(valve, speed)
    return np.column_stack([vv.ravel(), ss.ravel()])


CAND = gb.Candidates(2, 2, degree=2, input_names=INPUTS, max_y_power=1)


def test_select_graybox_says_when_static_points_lie_outside_the_records():
    # every fit inside select_graybox silences StaticRangeWarning and nothing said it once: speeds
    # given in rad/s instead of rpm (or any units mix-up) went unsaid, as pe_thetas and se_dsf say it
    data = gb.Dataset(record(0, 400), record(1, 300), static(grid([30, 50, 70], [1200, 2000, 2800]), uncertainty=500.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # inside the records' range: nothing to say
        gb.select_graybox(CAND, data, sizes=[6], estimator="pe")
    far = static(grid([30, 50, 70], [1200, 2000, 2800]) * [1, 3], uncertainty=500.0)
    with pytest.warns(gb.StaticRangeWarning, match="outside the input box") as caught:
        gb.select_graybox(CAND, gb.Dataset(data.ident, data.valid, far), sizes=[6], estimator="pe",
                          fallback="min_jsf")
    assert sum(issubclass(w.category, gb.StaticRangeWarning) for w in caught) == 1  # once per call


def test_records_at_another_sampling_period_are_refused_where_they_meet():
    # a validation, test or choosing record sampled at 0.2 s beside a 0.1 s identification record was
    # scored as if sampled at 0.1 s: a discrete-time model's J_S on it is silent nonsense
    ident, other = record(0, 400, name="ident"), record(1, 300)
    slow = gb.Record(other.u, other.y, 0.2, name="slow", input_names=INPUTS)
    with pytest.raises(ValueError, match="'ident' is sampled every 0.1 s but 'slow' every 0.2 s"):
        gb.Dataset(ident, slow)
    with pytest.raises(ValueError, match="sampled every"):
        gb.output_error(TRUE, ident, choose_on=slow, n_starts=0)
    with pytest.raises(ValueError, match="sampled every"):
        gb.output_error(TRUE, [ident, slow], n_starts=0)
    for where in ("test", "validation"):
        with pytest.raises(ValueError, match="sampled every"):
            gb.select_graybox(CAND, ident, sizes=[6], **{where: slow})
    # a period read from printed stamps may differ in its last digits: the same period
    near = gb.Record(other.u, other.y, 0.1 * (1 + 1e-9), name="near", input_names=INPUTS)
    assert gb.Dataset(ident, near).Ts == 0.1


def test_select_graybox_says_at_once_when_a_choosing_or_test_record_lacks_a_candidate_input(monkeypatch):
    # a validation or test record without an input the candidates use (e.g. a transient input added to
    # the data set but not to the test record) failed only after the structure search and the fits
    # (minutes with SE fronts), from inside a job; with a test record it failed or not by the chance
    # of which structures the search found
    data = gb.transient_inputs(gb.Dataset(record(0, 400), record(1, 300)), taus=(1.0,), input_names=["speed"])
    cand = gb.Candidates(2, {"valve": 2, "speed": 2, "speed_tau1": 1}, degree=2, input_names=data.input_names,
                         max_y_power=1)
    import graybox._api as api

    def no_search(*args, **kwargs):
        raise AssertionError("the structure search ran")

    monkeypatch.setattr(api, "semp", no_search)
    monkeypatch.setattr(api, "frols", no_search)
    with pytest.raises(ValueError, match="the test record 'r2': the structure uses input 'speed_tau1'.*transient_inputs"):
        gb.select_graybox(cand, data, test=record(2, 300), sizes=[6])
    with pytest.raises(ValueError, match="the validation record 'r2': the structure uses input 'speed_tau1'"):
        gb.select_graybox(cand, data.ident, validation=record(2, 300), sizes=[6])


def test_slow_mode_warning_says_why_the_slow_model_was_kept():
    # margin="auto" kept a slow in-band fit because its refit inside the margin missed the band, and the
    # warning said "no fit inside that factor (margin='auto') was found": one was found, and missed the band
    from types import SimpleNamespace

    from graybox.estimation._simulation_error import SEProblem, refit_if_slow

    problem = SEProblem(TRUE, [record(0, 400)], None)
    slow = SimpleNamespace(model=gb.Model(TRUE, THETA * [1, 1, 1, 1, 1.333, 1], input_names=INPUTS), in_band=True)
    assert problem.slow_modes(slow.model.theta[None])[1][0]
    inside = SimpleNamespace(model=gb.Model(TRUE, THETA, input_names=INPUTS), in_band=False)

    def misses_the_band(p):
        return slow if p.margin is None else inside

    def finds_none(p):
        if p.margin is None:
            return slow
        raise ValueError("no start inside the margin")

    with pytest.warns(gb.SlowModeWarning, match="misses the band this one meets") as caught:
        assert refit_if_slow(problem, misses_the_band, "the fit", auto=True) is slow
    assert "was found" not in str(caught[0].message)
    with pytest.warns(gb.SlowModeWarning, match=r"no fit inside that factor \(margin='auto'\) was found"):
        assert refit_if_slow(problem, finds_none, "the fit", auto=True) is slow


def test_select_graybox_keeps_every_included_term_in_every_frols_structure():
    # with 4 included terms and sizes=[2, 6], the FROLS row of size 2 was its path's first 2 terms:
    # "1 + y(k-1)", without the included y(k-2) and valve(k-1) ("include: terms in every structure")
    include = ["1", "y(k-1)", "y(k-2)", "valve(k-1)"]
    data = gb.Dataset(record(0, 400), record(1, 300))
    with pytest.warns(gb.SelectionWarning, match=r"semp: \[2\]; frols: \[2\]"):
        res = gb.select_graybox(CAND, data, include=include, sizes=[2, 6], estimator="ls")
    assert (res.table["size"] == 6).all()
    assert set(gb.Structure(include)) <= set(res.structure)


def test_select_graybox_and_se_dsf_models_take_the_records_input_order(tmp_path):
    # their models' inputs were the structure's, in name order ("speed", "valve"): an input array or
    # static ū given in the records' column order (valve, speed) was read the other way round, silently
    # (the chosen model's static curve at valve 50 %, 2000 rpm read 1.2e6 Pa for the true 2.2e5)
    data = gb.Dataset(record(0, 400), record(1, 300), static(grid([30, 50, 70], [1200, 2000, 2800]), uncertainty=500.0))
    test = record(2, 300)
    u = np.array([[50.0, 2000.0]])
    true = (THETA[0] + THETA[1] * 50 + THETA[2] * 2000**2 + THETA[3] * 50 * 2000) / 0.2
    for estimator in ("pe", "ls"):
        res = gb.select_graybox(CAND, data, sizes=[6], estimator=estimator, band=None if estimator == "pe" else np.inf)
        assert res.model.input_names == INPUTS
        np.testing.assert_allclose(res.model.simulate(test.u, test.y[:2]), res.model.simulate(test), rtol=1e-12)
        assert res.model.static_curve(u)[0] == pytest.approx(true, rel=0.01)
    gb.save(res, tmp_path / "sel.json")
    assert gb.load(tmp_path / "sel.json").model.input_names == INPUTS
    dsf = gb.se_dsf(TRUE, data)
    assert dsf.model.input_names == INPUTS
    assert dsf.model.static_curve(u)[0] == pytest.approx(true, rel=0.01)


def test_a_test_record_with_its_columns_in_another_order_is_still_the_fitting_record():
    # the overlap checks compared (u, y) column by column: the identification record loaded again with
    # its inputs in another order (or with a transient input added) passed as new data
    ident, valid = record(0, 400, name="ident"), record(1, 300, name="valid")
    swapped = gb.Record(ident.u[:, ::-1], ident.y, 0.1, name="again", input_names=INPUTS[::-1])
    part = swapped.slice(100, 300, name="part")
    with pytest.raises(ValueError, match="the test record is the identification record"):
        gb.select_graybox(CAND, gb.Dataset(ident, valid), test=swapped, sizes=[6])
    with pytest.raises(ValueError, match="shares 200 samples with the identification record"):
        gb.select_graybox(CAND, gb.Dataset(ident, valid), test=part, sizes=[6])
    with pytest.raises(ValueError, match="a choosing record is a fitting record"):
        gb.output_error(TRUE, ident, choose_on=swapped, n_starts=0)
    extended = gb.transient_inputs(ident, taus=(1.0,), input_names=["speed"])
    with pytest.raises(ValueError, match="a choosing record is a fitting record"):
        gb.output_error(TRUE, ident, choose_on=extended, n_starts=0)
    # new data in another column order is new data
    other = record(2, 300)
    reordered = gb.Record(other.u[:, ::-1], other.y, 0.1, name="new", input_names=INPUTS[::-1])
    assert gb.output_error(TRUE, ident, choose_on=reordered, n_starts=0).chosen_on == "new"


@pytest.mark.parametrize("estimator", ["se-gradient", "pe"])
def test_a_shortlist_that_cannot_act_is_refused(estimator):
    # with the SE estimators alone nothing ranks the structures first, and with PE alone there is no slow
    # fit to spare: shortlist=1 was ignored, silently, and every structure fitted (hours with SE fronts)
    data = gb.Dataset(record(0, 300), record(1, 200), static(grid([30, 50, 70], [1200, 2000, 2800]), uncertainty=500.0))
    with pytest.raises(ValueError, match="shortlist has nothing to do"):
        gb.select_graybox(CAND, data, sizes=[4, 6], estimator=estimator, shortlist=1)


def test_gray_box_options_given_to_a_black_box_search_are_refused():
    # without a band (none given, static points without uncertainty) the search is a black box: the
    # lambdas and fallback given with it were ignored, silently (lambda1 NaN in every row)
    data = gb.Dataset(record(0, 300), record(1, 200), static(grid([30, 50, 70], [1200, 2000, 2800])))
    with pytest.raises(ValueError, match="lambdas applies to a gray box .* black box \\(ls, els, oe\\)"):
        gb.select_graybox(CAND, data, sizes=[6], lambdas=[0.5, 1.0])
    with pytest.raises(ValueError, match="fallback applies to a gray box"):
        gb.select_graybox(CAND, data, sizes=[6], fallback="min_jsf")
    with pytest.raises(ValueError, match="lambdas applies to a gray box"):
        gb.select_graybox(CAND, data, band=np.inf, sizes=[6], lambdas=[0.5])
    res = gb.select_graybox(CAND, data, band=1e6, sizes=[6], lambdas=[0.5, 1.0], estimator="pe")
    assert set(res.table["lambda1"]) <= {0.5, 1.0}


def test_select_graybox_checks_its_executor_and_workers_before_the_search(monkeypatch):
    # executor="threads" (or workers with executor="inprocess") was refused only after the structure
    # search, and workers=0 ran on 2 processes, silently, where workers=-1 was refused
    data = gb.Dataset(record(0, 300), record(1, 200))
    import graybox._api as api

    def no_search(*args, **kwargs):
        raise AssertionError("the structure search ran")

    monkeypatch.setattr(api, "semp", no_search)
    monkeypatch.setattr(api, "frols", no_search)
    with pytest.raises(ValueError, match="executor must be one of"):
        gb.select_graybox(CAND, data, sizes=[6], executor="threads")
    with pytest.raises(ValueError, match="workers must be an integer >= 1, got 0"):
        gb.select_graybox(CAND, data, sizes=[6], executor="processes", workers=0)
    with pytest.raises(ValueError, match="workers, client and scheduler need"):
        gb.select_graybox(CAND, data, sizes=[6], executor="inprocess", workers=2)


def test_estimators_and_fronts_give_models_in_the_records_input_order(tmp_path):
    # ELS, CLS and every member of a PE or SE front (hence decide_dsf's model) named their inputs in
    # the structure's name order ("speed", "valve"): a static ū or input array in the records' order
    # (valve, speed) was read the other way round, silently
    data = gb.Dataset(record(0, 400), record(1, 300), static(grid([30, 50, 70], [1200, 2000, 2800]), uncertainty=500.0))
    u = np.array([[50.0, 2000.0]])
    true = (THETA[0] + THETA[1] * 50 + THETA[2] * 2000**2 + THETA[3] * 50 * 2000) / 0.2
    front = gb.se_pareto(TRUE, data, method="gradient", lambdas=[1.0, 0.5])
    sel, semp = gb.frols(CAND, data, n_terms=8), gb.semp(CAND, data, n_terms=8)
    models = [gb.els(TRUE, data).model, gb.cls(TRUE, data).model, front.member_model(0),
              gb.decide_dsf(gb.pe_pareto(TRUE, data), band=data.static.band).model, sel.model, semp.model]
    for m in models[:4]:
        assert m.input_names == INPUTS
        assert m.static_curve(u)[0] == pytest.approx(true, rel=0.01)
    for m in models[4:]:  # least squares of the selected structures: ū read in the records' order
        assert m.input_names == INPUTS
        other = gb.Model(m.structure, m.theta, input_names=INPUTS[::-1])
        np.testing.assert_allclose(m.static_curve(u), other.static_curve(u[:, ::-1]), rtol=1e-9)
    for res in (sel, semp):
        gb.save(res, tmp_path / "res.json")
        assert gb.load(tmp_path / "res.json").model.input_names == INPUTS
    assert front.subset([1]).member_model(0).input_names == INPUTS
    gb.save(front, tmp_path / "front.json")
    assert gb.load(tmp_path / "front.json").input_names == INPUTS
    # a set built without records keeps a Model's default
    assert gb.ParetoSet(TRUE, front.thetas, front.lambdas, front.J1, front.JS, front.JSF).input_names == ("speed", "valve")


def test_a_grid_cell_reads_the_static_points_in_the_records_input_order(tmp_path):
    # a grid cell's static_miss evaluated the model's static curve at the static points' ū (the records'
    # column order: valve, speed) with a model that named its inputs in name order (speed, valve)
    from graybox import experiments as gx

    data = gb.Dataset(record(0, 400), record(1, 300), static(grid([30, 50, 70], [1200, 2000, 2800]), uncertainty=500.0))
    g = gx.Grid([gx.DataSpec("mine", dataset=data)], [gx.StructureSpec("true", terms=[str(t) for t in TRUE])],
                [gx.Variant("pe", "pe", lambdas=[1e-3, 0.5]), gx.Variant("dsf", "se-dsf", lambdas=[0.5, 1.0])],
                name="order")
    gx.run_grid(g, tmp_path / "order.sqlite")
    df = gx.load_results(tmp_path / "order.sqlite").set_index("variant")
    for v in ("pe", "dsf"):
        r = df.loc[v]
        assert r["status"] == "ok"
        m = gb.Model(TRUE, r["theta"], input_names=INPUTS)
        miss = np.abs(m.static_curve(data.static.ubar, y0=data.static.ybar) - data.static.ybar).max()
        assert r["static_miss"] == pytest.approx(miss, rel=1e-9)
        assert r["static_miss"] < 1e3  # the model is near the true one: a few hundred Pa at most


def test_periods_from_rounded_time_stamps_are_one_period(tmp_path):
    # two files of one 30 Hz logger, stamps printed to 5 decimals: their mean steps differ by about 1e-6
    # relative, which is rounding, not another period; 0.1 s against 0.2 s still is
    for name, n in (("a", 200), ("b", 150)):
        t = np.arange(n) / 30.0
        (tmp_path / f"{name}.csv").write_text("t,u,y\n" + "".join(f"{x:.5f},{i % 7},{i % 5}\n"
                                                                   for i, x in enumerate(t)))
    a = gb.load_record_csv(tmp_path / "a.csv", u="u", y="y", time="t", name="a")
    b = gb.load_record_csv(tmp_path / "b.csv", u="u", y="y", time="t", name="b")
    assert a.Ts != b.Ts
    gb.Dataset(a, b)
    with pytest.raises(ValueError, match="sampled every 0.1 s but .* every 0.2 s"):
        gb.Dataset(gb.Record(np.ones(50), np.ones(50), 0.1, name="x"), gb.Record(np.ones(50), np.ones(50), 0.2))


def test_local_model_checks_the_data_range_by_input_name():
    # a model whose inputs are in another order than the data's columns: the range check reads them by name
    valve, speed = np.repeat([20.0, 50.0, 80.0], 40), np.repeat([1000.0, 2000.0, 3000.0], 40)[::-1]
    rec = gb.Record(np.column_stack([valve, speed]), np.linspace(1, 2, 120), 1.0, input_names=("valve", "speed"))
    m = gb.Model(gb.Structure(["y(k-1)", "valve(k-1)", "speed(k-1)"]), np.array([0.5, 0.01, 0.001]),
                 input_names=("speed", "valve"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", gb.StaticRangeWarning)
        gb.local_model(m, [2000.0, 50.0], data=rec)  # speed 2000, valve 50: inside
    with pytest.warns(gb.StaticRangeWarning, match="outside the input range"):
        gb.local_model(m, [50.0, 2000.0], data=rec)  # speed 50: outside
