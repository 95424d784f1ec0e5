"""select_graybox: gray-box structure selection through the experiment layer."""

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.static._form_check import static_degree

TRUE = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])


def plant(seed, n=1200, noise=0.02):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
    m = gb.Model(TRUE, THETA)
    y = m.simulate(u, np.zeros(2)) + noise * rng.standard_normal(n)
    return gb.Record(u, y, name=f"r{seed}")


@pytest.fixture(scope="module")
def data():
    m = gb.Model(TRUE, THETA)
    ub = np.linspace(-0.5, 3.5, 7)  # beyond the records' range on both sides: that is the point
    static = gb.StaticPoints(ub, m.static_curve(ub))
    return gb.Dataset(plant(1), plant(2), static)


def test_selects_a_structure_in_the_band_and_reports_everything(data, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[3, 5], store=tmp_path / "s.sqlite")
    assert res.decision.in_band and res.decision.JSF <= 1e-3
    assert res.degree == 2  # a quadratic static curve: the points ask for degree 2
    # every structure tried is a row; the chosen one is rank 1 and carries Σ0, Σu, Σu², Σy
    assert len(res.table) >= 2 and res.table.iloc[0]["rank"] == 1
    keys = {gb.cluster_map(res.structure).keys[i] for i in range(len(gb.cluster_map(res.structure).keys))}
    assert {(0, 0), (0, 1), (0, 2), (1, 0)} <= keys
    # the decision was made on the validation record: the chosen member's validation J_S is the
    # smallest among the in-band members of the refitted front
    ev = gb.evaluate({"m": res.model}, data)
    assert ev.loc["m", "JS_valid"] == pytest.approx(res.decision.JS, rel=1e-9)
    assert ev.loc["m", "JS_valid"] < 10 * 0.02**2 * 10  # near the noise level
    # the cells are in a real store, one per structure
    df = gb.load_results(res.store)
    assert len(df) == len(res.table) and set(df["status"]) == {"ok"}


def test_folds_when_there_is_one_record(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data.ident, data.static, band=1e-3, sizes=[5], folds=3)
    df = gb.load_results(res.store)
    assert set(df["data"]) == {"fold1", "fold2", "fold3"}
    assert res.decision.JSF <= 1e-3


def test_band_no_structure_reaches_is_an_error_or_an_explicit_fallback(data):
    far = gb.StaticPoints(data.static.ubar, data.static.ybar + np.array([0.5, -0.5, 0.5, -0.5, 0.5, -0.5, 0.5]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match="no structure meets the band.*smallest J_SF reached"):
            gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, far, band=1e-6, sizes=[5])
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, far, band=1e-6, sizes=[5], fallback="min_jsf")
    assert not res.in_band and not res.decision.in_band


def test_bad_input(data):
    with pytest.raises(ValueError, match="cannot represent a degree-2 static curve"):
        gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=1), data, band=1e-3, sizes=[3])
    short = gb.Dataset(data.ident, data.valid.slice(0, 3), data.static)
    with pytest.raises(ValueError, match="fewer than max lag|shorter"):
        gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), short, band=1e-3, sizes=[3])
    with pytest.raises(ValueError, match="estimator"):
        gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, estimator="ls")


def test_several_estimators_score_every_structure_and_the_best_pair_wins(data, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[3, 5],
                                estimator=("pe", "se-gradient"), store=tmp_path / "s.sqlite")
        single = {e: gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[3, 5],
                                       estimator=e, store=tmp_path / f"{e}.sqlite") for e in ("pe", "se-gradient")}
    # one row per structure and estimator, each structure scored by both
    assert set(res.table["estimator"]) == {"pe", "se-gradient"}
    assert res.table.groupby(level=0).size().eq(2).all()
    # the winner is the better of the two single-estimator selections, by validation J_S in the band
    best = min(single.values(), key=lambda r: r.table["JS_valid"].iloc[0])
    assert res.table["JS_valid"].iloc[0] == pytest.approx(best.table["JS_valid"].iloc[0], rel=1e-9)
    assert res.decision.in_band
    with pytest.raises(ValueError, match="distinct"):
        gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, estimator=("pe", "pe"))


def test_constraints_are_imposed_by_pe_and_refused_for_se(data, tmp_path):
    """With constraints the default scores with PE alone (the estimator that imposes them); naming an
    SE estimator with them is an error, not a silent unconstrained model."""
    gain = gb.GainBounds(lower=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[5],
                                constraints=[gain], store=tmp_path / "c.sqlite")
    assert set(res.table["estimator"]) == {"pe"} and res.decision.in_band
    df = gb.load_results(res.store)
    assert set(df["estimator"]) == {"pe"} and set(df["status"]) == {"ok"}
    assert [c["type"] for c in df.attrs["spec"]["variants"][0]["constraints"]] == ["gain"]  # the cells imposed it
    with pytest.raises(ValueError, match="constraints are imposed by PE only; se-gradient"):
        gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[5], constraints=[gain],
                          estimator=("pe", "se-gradient"))


@pytest.mark.parametrize("constraints", [
    [{"type": "equality"}], [{"type": "points"}], [{"type": "band", "b": 0.05}], [{"type": "gain", "lower": 0.0}],
    [{"type": "clusters", "bounds": {"Sy": {"upper": 0.999}}}], gb.StaticBand(0.05) & gb.GainBounds(lower=0.0),
], ids=["equality", "points", "band", "gain", "clusters", "object"])
def test_every_constraint_variant(data, constraints):
    """Every constraint variant runs in the cells and in the refit of the chosen structure (an
    equality's curve is fitted to the static points there too; one object needs no list)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[5],
                                constraints=constraints)
    assert res.decision.in_band and res.decision.JSF <= 1e-3
    assert set(gb.load_results(res.store)["status"]) == {"ok"}
    if isinstance(constraints, list) and constraints[0]["type"] in ("equality", "points"):
        # the static curve passes through the points' curve: J_SF far inside the band
        assert res.decision.JSF < 1e-6


TWO = gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)u2(k-1)", "1"])
THETA2 = np.array([0.5, 0.3, 0.2, 0.05, 0.1])


def _two_input_record(seed, n=1500):
    rng = np.random.default_rng(seed)
    u = np.column_stack([np.repeat(rng.uniform(0.0, 2.0, n // 30 + 1), 30)[:n],
                         np.repeat(rng.uniform(0.0, 2.0, n // 45 + 1), 45)[:n]])  # (N, m)
    y = gb.Model(TWO, THETA2).simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(n)
    return gb.Record(u, y, name=f"two{seed}", input_names=("u1", "u2"))


def test_two_inputs_the_static_surface_asks_for_its_clusters():
    """Several inputs: the static points make a surface; its degree (2: the ū1ū2 monomial) asks for
    every cluster Σ0, Σu1, Σu2, Σu1², Σu1u2, Σu2² and Σy, and the selected model meets the band."""
    g = np.linspace(-0.5, 2.5, 4)  # beyond the records' range [0, 2] in both inputs
    ub = np.array([(a, b) for a in g for b in g])
    yb = (0.3 * ub[:, 0] + 0.2 * ub[:, 1] + 0.05 * ub[:, 0] * ub[:, 1] + 0.1) / 0.5
    static = gb.StaticPoints(ub, yb, input_names=("u1", "u2"))
    assert static_degree(static, band=1e-6) == 2
    data = gb.Dataset(_two_input_record(1), _two_input_record(2), static)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(1, 1, degree=2, input_names=("u1", "u2")), data, band=1e-3, sizes=[4])
    assert res.degree == 2 and res.decision.in_band and res.decision.JSF <= 1e-3
    keys = set(gb.surface_cluster_map(res.structure, input_names=("u1", "u2")).keys)
    assert {(0, 0, 0), (0, 1, 0), (0, 0, 1), (0, 2, 0), (0, 1, 1), (0, 0, 2), (1, 0, 0)} <= keys


def test_two_inputs_candidates_that_cannot_carry_the_surface_are_named():
    from graybox.static._form_check import static_terms

    st = gb.Structure(["y(k-1)", "u1(k-1)"])
    added = static_terms(st, gb.Candidates(1, 1, degree=2, input_names=("u1", "u2")), 1)
    assert sorted(map(str, added)) == ["1", "u2(k-1)"]  # Σ0 and Σu2 were missing; Σu1 and Σy are there
    with pytest.raises(ValueError, match=r"static surface.*Σu1².*Σu1u2.*Σu2²"):
        static_terms(st, gb.Candidates(1, 1, degree=1, input_names=("u1", "u2")), 2)


def test_one_static_point_and_repeated_measurements(data):
    """One static point asks for a constant (degree 0) and is met; repeated measurements at the same
    levels, averaged by StaticPoints.from_repeats, work like any points."""
    m = gb.Model(TRUE, THETA)
    one = gb.StaticPoints([1.5], m.static_curve(np.array([1.5])))
    assert static_degree(one, band=1e-3) == 0
    rng = np.random.default_rng(3)
    ub = np.tile(np.linspace(-0.5, 3.5, 7), 3)
    rep = gb.StaticPoints.from_repeats(ub, m.static_curve(ub) + 0.01 * rng.standard_normal(ub.size))
    assert len(rep) == 7
    for sp in (one, rep):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), gb.Dataset(data.ident, data.valid, sp),
                                    band=1e-3, sizes=[5])
        assert res.decision.in_band and res.decision.JSF <= 1e-3


def test_static_points_that_leave_a_direction_unvaried_ask_only_what_they_determine():
    """Two inputs that always move together (or one held) cannot determine a full surface: the
    degree stops where the fit is still determined, instead of a rank error."""
    from graybox.static._form_check import static_fit_mse

    s = np.linspace(1.0, 3.0, 6)
    together = gb.StaticPoints(np.column_stack([s, s]), 1.0 + 0.5 * s + 0.1 * s**2, input_names=("u1", "u2"))
    assert static_fit_mse(together, 1) is None  # ū1 and ū2 are collinear: a plane is not determined
    assert static_fit_mse(together, 0) is not None
    assert static_degree(together, band=1e-9) == 0


def test_constraints_given_as_a_generator_reach_the_refit(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = gb.select_graybox(gb.Candidates(3, 3, ne=0, degree=2), data, band=1e-3, sizes=[5],
                                constraints=(c for c in [{"type": "points"}]))
    assert res.decision.JSF < 1e-6  # the refit passes through the points: the constraint was imposed
