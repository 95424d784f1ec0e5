"""mend52c: leaderboard across bands, memory of Monte Carlo bands, CorrelationTest labels, stored grid specs,
duplicate variants with defaults spelled differently, plot_pareto of an empty set."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.core import _validation

from test_hunt50l import STRUCT, _record  # the quadratic first-order plant those diagnostics tests use

REC = _record(n=300)
MODEL = gb.els(STRUCT, REC, noise=0).model


# ---- 2. the Monte Carlo bands' memory is counted as the arrays they build ------------------------------------------
def _small_machine(monkeypatch, nbytes):
    monkeypatch.setattr(_validation, "_memory_bytes", lambda: nbytes)


@pytest.mark.parametrize("points", [20, 50])
def test_static_curve_band_counts_points_and_terms(monkeypatch, points):
    # n_samples was counted at 8 bytes a draw, while each draw builds M points × n_terms floats
    unc = gb.ls_uncertainty(MODEL, REC)
    n = 100
    _small_machine(monkeypatch, 8 * n * 10)  # room for the draws alone, not for M × n_terms floats each
    with pytest.raises(ValueError, match=rf"n_samples=100 is too large.*{points} points × 4 terms"):
        gb.static_curve_band(unc, np.linspace(0.2, 1.8, points), method="monte-carlo", n_samples=n)
    # the delta method draws nothing: the count alone is checked
    band = gb.static_curve_band(unc, np.linspace(0.2, 1.8, points), n_samples=n)
    assert band.method == "delta"


def test_static_surface_band_counts_points_terms_and_inputs(monkeypatch):
    unc = gb.ls_uncertainty(MODEL, REC)
    _small_machine(monkeypatch, 8 * 100 * 10)
    with pytest.raises(ValueError, match=r"n_samples=100 is too large.*30 points × 4 terms × 1 inputs"):
        gb.static_surface_band(unc, np.linspace(0.2, 1.8, 30)[:, None], method="monte-carlo", n_samples=100)


def test_operating_curve_band_counts_points_and_terms(monkeypatch):
    unc = gb.ls_uncertainty(MODEL, REC)
    _small_machine(monkeypatch, 8 * 100 * 10)
    with pytest.raises(ValueError, match=r"n_samples=100 is too large.*30 points × 4 terms"):
        gb.operating_curve(MODEL, np.linspace(0.2, 1.8, 30), uncertainty=unc, n_samples=100)
    # without an uncertainty nothing is drawn: the count alone is checked, and the curve is made
    curve = gb.operating_curve(MODEL, np.linspace(0.2, 1.8, 30), n_samples=100)
    assert len(curve.ubar) == 30


def test_simulation_band_counts_the_runs(monkeypatch):
    unc = gb.ls_uncertainty(MODEL, REC)
    _small_machine(monkeypatch, 8 * 100 * 10)
    with pytest.raises(ValueError, match=rf"n_samples=100 is too large.*3 copies × {len(REC)} samples"):
        gb.simulation_band(unc, REC, method="monte-carlo", n_samples=100)


def test_bands_still_made_where_they_fit():
    unc = gb.ls_uncertainty(MODEL, REC)
    band = gb.static_curve_band(unc, np.linspace(0.2, 1.8, 5), method="monte-carlo", n_samples=50)
    assert band.n_samples == 50 and np.all(band.ybar_low <= band.ybar_high)


# ---- 3. a CorrelationTest's label is held to its name ----------------------------------------------------------------
def _two_input_tests():
    rng = np.random.default_rng(1)
    n = 300
    u = rng.uniform(0, 2, (n, 2))
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.5 * u[k - 1, 0] + 0.3 * u[k - 1, 1] ** 2 + 0.05 * rng.standard_normal()
    rec = gb.Record(u, y, name="r", input_names=("rpm", "valve"))
    m = gb.els(["y(k-1)", "rpm(k-1)", "valve(k-1)^2"], rec, noise=0).model
    return gb.residual_tests(m, rec)


@pytest.mark.parametrize("two", [False, True])
def test_correlation_test_label_must_match_its_name(two):
    import dataclasses

    tests = (_two_input_tests() if two else gb.residual_tests(MODEL, REC)).tests
    for name, c in tests.items():
        dataclasses.replace(c)  # as made: accepted
        other = next(v.label for k, v in tests.items() if v.label != c.label)
        with pytest.raises(ValueError, match="label"):
            dataclasses.replace(c, label=other)  # φ_ξξ(τ) said of a u-ξ test
    if two:
        with pytest.raises(ValueError, match="label"):  # the input's name is part of the label
            dataclasses.replace(tests["u_xi:rpm"], label="φ_uξ(τ)")


def test_residual_tests_files_still_load(tmp_path):
    for t in (gb.residual_tests(MODEL, REC), _two_input_tests()):
        gb.save(t, tmp_path / "t.json")
        back = gb.load(tmp_path / "t.json")
        assert {k: v.label for k, v in back.tests.items()} == {k: v.label for k, v in t.tests.items()}


# ---- 6. plot_pareto of a set with no member -------------------------------------------------------------------------
@pytest.mark.parametrize("log", [False, True])
@pytest.mark.parametrize("band", [None, 0.2])
def test_plot_pareto_of_an_empty_set_draws_an_empty_labelled_panel(log, band):
    import warnings

    from graybox.plots import plot_pareto

    s = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    th = np.array([[0.9, 0.01, 0.1]] * 3)
    js = np.array([1.0, 2.0, 3.0])
    ps = gb.ParetoSet(s, th, np.array([0.01, 0.1, 1.0]), js, js, js[::-1] / 10, method="PE",
                      units=("rpm", "mlc")).subset([])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ax = plot_pareto(ps, log=log, band=band).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("J_S (mlc²)", "J_SF (mlc²)")
    assert ax.get_legend().get_texts()[0].get_text() == "PE (no members)"
    assert not any(ln.get_xdata().size for ln in ax.lines)
    # J >= 0: no panel of negative errors (linear axes showed (-0.055, 0.055), the log ones (0.1, 10))
    assert min(ax.get_xlim()) >= 0 and min(ax.get_ylim()) >= 0
    if band is not None:
        assert max(ax.get_ylim()) >= band  # the band's shade is in the panel


# ---- 4. a grid spec stored in a store round-trips through Grid.from_dict ---------------------------------------------
def test_a_stored_spec_is_a_grid_spec_again(tmp_path):
    from graybox import experiments as gx

    g = gx.Grid([gx.DataSpec("pumping", bundled="pumping", band=1e-3)],
                [gx.StructureSpec("one", terms=["y(k-1)", "u(k-1)", "1"])], [gx.Variant("LS", "ls")], name="g")
    store = tmp_path / "s.sqlite"
    first = gx.run_grid(g, store)
    stored = gx.store_specs(store).iloc[-1]["spec"]
    assert stored["data"][0]["y_unit"] == "mlc"  # the data set names its output's unit: the store keeps it
    back = gx.Grid.from_dict(stored)  # was: SpecError "unknown key 'y_unit' in a [[data]] table"
    assert back.to_dict() == g.to_dict()
    again = gx.run_grid(back, store)
    assert again.ran == 0 and again.spec == first.spec
    # the unit is held to the data's, once they are read
    wrong = dict(stored, data=[dict(stored["data"][0], y_unit="rpm")])
    with pytest.raises(gx.SpecError, match=r"y_unit.*'rpm'|'rpm'.*y_unit"):
        gx.Grid.from_dict(wrong).load_data()
    with pytest.raises(gx.SpecError, match="y_unit"):
        gx.Grid.from_dict(dict(stored, data=[dict(stored["data"][0], y_unit=3)]))


# ---- 1. leaderboard over specs whose band differs: each cell judged by its own band ----------------------------------
_RPM = gb.Model(["1", "y(k-1)", "n(k-1)"], [3.0, 0.5, 2e-5], input_names=("n",))


def _rpm_data() -> gb.Dataset:
    rng = np.random.default_rng(0)
    recs = []
    for part in range(2):
        n_ = np.repeat(rng.uniform(2500.0, 3500.0, 16), 20)[:300]
        y = _RPM.simulate(n_, np.full(1, 9.0)) + 0.01 * rng.standard_normal(300)
        recs.append(gb.Record(n_, y, 0.1, input_names=("n",), name=f"run {part}"))
    levels = np.linspace(2600.0, 3400.0, 5)
    ybar = _RPM.static_curve(levels) + 0.02 * np.array([1.0, -1.0, 1.0, -1.0, 1.0])
    return gb.Dataset(*recs, gb.StaticPoints(levels, ybar, input_names=("n",), uncertainty=0.05))


def test_leaderboard_of_every_spec_judges_each_cell_by_its_own_band(tmp_path):
    from graybox import experiments as gx

    data = _rpm_data()
    structure = [gx.StructureSpec("quadratic", terms=["1", "y(k-1)", "n(k-1)", "n(k-1)^2"])]
    lambdas = [1e-4, 1e-3, 1e-2, 0.1, 1.0]
    variants = [gx.Variant("PE D_SF", "pe", lambdas=lambdas, decision={"rule": "dsf", "fallback": "min_jsf"})]
    front = gb.pe_pareto(structure[0].terms, data, lambdas=lambdas)
    store = tmp_path / "s.sqlite"
    # the small band first: its cell is stored first, and its band was the group's, the wide band's cell judged by it
    small, wide = 1e-5, 1e-3
    for b in (small, wide):
        gx.run_grid(gx.Grid([gx.DataSpec("plant", dataset=data, band=b)], structure, variants), store)
    every = gb.load_results(store, spec="all")
    assert sorted(every["band"]) == [small, wide]  # one D_SF cell under each band, the same labels
    key = ("plant", "quadratic", "PE D_SF")
    by_wide = gx.leaderboard(every[every["band"] == wide]).loc[key]
    by_small = gx.leaderboard(every[every["band"] == small]).loc[key]
    assert not by_small["JS_valid"] <= by_wide["JS_valid"]  # the wide band lets a better member in (the small none)
    row = gx.leaderboard(every).loc[key]
    # the wide cell's members within its own band: its best is the group's, said with the band it is within
    assert row["JS_valid"] == by_wide["JS_valid"] and row["JSF"] == by_wide["JSF"]
    assert bool(row["in_band"]) and row["band"] == wide and row["JSF"] <= wide and row["reason"] == ""
    assert (by_wide["band"], by_small["band"]) == (wide, small)
    # no member within either cell's band: the reason says each cell's band, and the smallest J_SF's own
    tiny = every.assign(band=[1e-9 if b == small else 1e-8 for b in every["band"]])
    none = gx.leaderboard(tiny).loc[key]
    assert not bool(none["in_band"]) and np.isnan(none["band"]) and np.isnan(none["JS_valid"])
    assert "its cell's band (B = 1e-09, 1e-08)" in none["reason"]
    assert gx.leaderboard(every, rule="chosen")["band"].isna().all()
    # a band given overrides every cell's
    given = gx.leaderboard(every, band=small).loc[("plant", "quadratic", "PE D_SF")]
    assert given["band"] == small and (not bool(given["in_band"]) or given["JSF"] <= small)


# ---- 5. a variant spelling out its estimator's defaults as the cells take them is a duplicate -----------------------
def _two_variants(est, a, b, **kw):
    from graybox import experiments as gx

    return gx.Grid([gx.DataSpec("pumping", bundled="pumping", band=1e-3)],
                   [gx.StructureSpec("one", terms=["y(k-1)", "u(k-1)", "1"])],
                   [gx.Variant("a", est, options=a, **kw), gx.Variant("b", est, options=b, **kw)])


@pytest.mark.parametrize("est, a, b, kw", [
    ("els", {"noise": 2}, {}, {}),                       # noise None: the paper's ne = 2 (grid structures carry none)
    ("els", {"noise": 2.0}, {}, {}),
    ("els", {"noise": 0}, {"noise": 0.0}, {}),
    ("els", {"max_iter": 500.0}, {}, {}),                # a float for an int option
    ("se-gradient", {"max_nfev": 50}, {}, {"lambdas": [0.1, 1.0]}),   # None: gradient_front's 50
    ("se-gradient", {"tol": 1e-8}, {}, {"lambdas": [0.1, 1.0]}),      # None: 1e-8
    ("se-gradient", {"max_nfev": 50.0, "tol": 1e-8}, {"max_nfev": 50}, {"lambdas": [0.1, 1.0]}),
])
def test_defaults_spelled_out_as_the_cells_take_them_are_duplicates(est, a, b, kw):
    from graybox import experiments as gx

    with pytest.raises(gx.SpecError, match="identical"):
        _two_variants(est, a, b, **kw)


@pytest.mark.parametrize("est, a, b, kw", [
    ("els", {"noise": 0}, {}, {}),                       # plain least squares is not the default ne = 2
    ("els", {"noise": 1}, {}, {}),
    ("se-gradient", {"solver": "trf"}, {}, {"lambdas": [0.1, 1.0]}),  # the default "auto" fits trf and dogbox
    ("se-gradient", {"max_nfev": 51}, {}, {"lambdas": [0.1, 1.0]}),
    ("se-gradient", {"tol": 1e-7}, {}, {"lambdas": [0.1, 1.0]}),
    ("els", {"tol": 1e-8}, {}, {}),
])
def test_variants_that_really_differ_are_kept(est, a, b, kw):
    assert len(_two_variants(est, a, b, **kw).variants) == 2


def test_a_stored_unit_the_data_do_not_name_is_said_as_no_unit(tmp_path):
    # the mismatch message quoted its fallback words: "gives its output in 'no unit'"
    from graybox import experiments as gx

    rows = ["t,u,y"] + [f"{k * 0.1:.1f},{1 + k % 3},{0.5 * k}" for k in range(30)]
    for name in ("id.csv", "va.csv"):
        (tmp_path / name).write_text("\n".join(rows) + "\n", encoding="utf-8")
    (tmp_path / "st.csv").write_text("u,y\n1,2\n2,4\n3,6\n", encoding="utf-8")
    rec = dict(u="u", y="y", time="t")
    spec = {"name": "g", "data": [{"name": "m", "ident": dict(path="id.csv", **rec),
                                   "valid": dict(path="va.csv", **rec), "static": dict(path="st.csv", u="u", y="y"),
                                   "y_unit": "mlc"}],
            "structures": [{"name": "one", "terms": ["y(k-1)", "u(k-1)", "1"]}],
            "variants": [{"name": "LS", "estimator": "ls"}]}
    with pytest.raises(gx.SpecError, match=r"gives its output in no unit, but the spec says y_unit = 'mlc'"):
        gx.Grid.from_dict(spec, base_dir=tmp_path).load_data()
