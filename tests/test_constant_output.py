"""A validation record whose output is held at one level: fit % is undefined there, J_S is not."""

import numpy as np
import pytest

import graybox as gb
from graybox import experiments as gx

ST = gb.Structure(["y(k-1)", "u(k-1)", "1"])
MODEL = gb.Model(ST, [0.5, 0.3, 0.1])


def test_a_level_held_with_round_off_in_its_mean_is_constant():
    # was: 0.8 held for 40 samples has a mean 1 ulp off 0.8, so ‖y − mean‖ ≈ 1e-16 and fit % came out as
    # −1.9e15 instead of undefined
    y = np.full(40, 0.8)
    with pytest.raises(ValueError, match="constant"):
        gb.fit_percent(y, y + 0.1)
    # a real signal far from zero is no constant: 2e5 Pa ± 1 Pa
    yp = 2e5 + np.sin(np.arange(40.0))
    assert np.isfinite(gb.fit_percent(yp, yp + 0.1))


def test_a_grid_cell_with_a_held_validation_output_is_a_row_with_fit_undefined(tmp_path):
    # was: the one-model cell scored fit % as −1.9e15 (and an exactly constant output failed the cell in
    # gb.fit_percent); the Pareto cell's members divided by zero
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 12), 10)
    y = MODEL.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    ident = gb.Record(u[:80], y[:80], Ts=0.1, name="ident")
    ub = np.linspace(0.2, 1.8, 5)
    sp = gb.StaticPoints(ub, MODEL.static_curve(ub), uncertainty=0.05)
    for level in (0.8, 0.0):  # with round-off in its mean, and exactly constant
        valid = gb.Record(np.full(40, 1.0), np.full(40, level), Ts=0.1, name="held")
        grid = gx.Grid([gx.DataSpec("held", dataset=gb.Dataset(ident, valid, sp))],
                       [gx.StructureSpec("s", terms=[str(t) for t in ST])],
                       [gx.Variant("LS", "ls"), gx.Variant("PE", "pe", lambdas=[1.0, 0.5], options={"solver": "closed"})],
                       name="g")
        path = tmp_path / f"held{level}.sqlite"
        gx.run_grid(grid, path, progress=False)
        df = gx.load_results(path)
        assert (df["status"] == "ok").all()
        assert df["fit_valid"].isna().all() and np.isfinite(df["JS_valid"].astype(float)).all()


@pytest.mark.filterwarnings("ignore::graybox.StaticRangeWarning")  # points beyond 7 samples' range: not the point
@pytest.mark.parametrize("fit", ["se_pareto", "se_dsf", "output_error", "els", "cls", "pe_pareto"])
def test_every_estimator_refuses_as_many_regression_rows_as_parameters(fit):
    # was: the SE estimators (se_pareto, se_dsf, output_error) fitted a record of exactly n rows for n
    # parameters, which the least-squares start interpolates, while els, cls and pe refused it
    st = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "1"])
    rng = np.random.default_rng(1)
    u = rng.uniform(0, 2, 7)  # 7 samples, largest lag 2: 5 rows for 5 parameters
    rec = gb.Record(u, rng.standard_normal(7))
    ub = np.linspace(0.2, 1.8, 5)
    sp = gb.StaticPoints(ub, ub, uncertainty=0.1)
    call = {"se_pareto": lambda: gb.se_pareto(st, rec, sp, lambdas=[1.0, 0.5], progress=False),
            "se_dsf": lambda: gb.se_dsf(st, rec, sp),
            "output_error": lambda: gb.output_error(st, rec, progress=False),
            "els": lambda: gb.els(st, rec, noise=0),
            "cls": lambda: gb.cls(st, rec, sp),
            "pe_pareto": lambda: gb.pe_pareto(st, rec, sp, lambdas=[1.0])}[fit]
    with pytest.raises(ValueError, match="5 regression rows for 5 parameters"):
        call()


def test_the_min_jsf_fallback_with_choosing_records_never_takes_a_member_that_diverges_there():
    # was: fallback='min_jsf' ignored choose_on: it took the smallest J_SF even when that member's free run
    # diverged on the choosing record, and the decision did not say what it was chosen on
    st = gb.Structure(["y(k-1)", "y(k-1)^2", "u(k-1)"])
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(0.0, 0.3, 12), 10)  # small inputs: both members run on the identification data
    rec = gb.Record(u, gb.Model(st, [0.5, 0.0, 0.3]).simulate(u, np.zeros(1)), name="ident")
    choose = gb.Record(np.repeat(rng.uniform(1.5, 2.0, 20), 10), np.zeros(200), name="choose")
    # member 0 (0.2 y²) has a stable equilibrium only for ū < 1.04: its free run diverges on the choosing
    # record; the static points lie on its curve, so its J_SF is the smaller
    thetas = np.array([[0.5, 0.2, 0.3], [0.5, 0.0, 0.3]])
    ub = np.array([0.1, 0.2, 0.3])
    sp = gb.StaticPoints(ub, (0.5 - np.sqrt(0.25 - 0.24 * ub)) / 0.4)
    front = gb.ParetoSet.from_thetas(st, thetas, [1.0, 0.5], gb.Dataset(rec, rec, sp), sp)
    assert np.isfinite(front.JSF).all() and front.JSF[0] < front.JSF[1] and np.isfinite(front.JS).all()
    d = gb.decide_dsf(front, band=1e-40, fallback="min_jsf", choose_on=choose)
    assert d.index == 1 and not d.in_band and d.chosen_on == "choose"
    plain = gb.decide_dsf(front, band=1e-40, fallback="min_jsf")  # on the set's own J_S: as before
    assert plain.index == 0
