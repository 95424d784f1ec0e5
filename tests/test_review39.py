"""Review of the session's eq. (22) (Σ*_y estimated), leaderboard and report changes."""

import pytest

from graybox.experiments._spec import Variant


def test_a_spec_s_cls_and_pe_take_reference_free_as_the_estimators_do():
    """reference = "free" is cls's and pe_pareto's default and the spec's equality takes sigma_y = "free", but
    the variant option was refused ('must be one of ls, els')."""
    for est in ("cls", "pe"):
        v = Variant("v", est, constraints=[{"type": "equality", "curve": "fit"}], options={"reference": "free"})
        assert v.options["reference"] == "free"
    with pytest.raises(ValueError, match="reference"):
        Variant("v", "cls", constraints=[{"type": "equality", "curve": "fit"}], options={"reference": "loose"})


def test_leaderboard_judges_each_group_by_its_own_cells_band(tmp_path):
    """Read with spec="all", a store run by two specs that give a data set different bands holds that data set's
    cells with each spec's band. The old leaderboard judged each (data, structure, variant) by its cells' band;
    the vectorised one took the data set's first row's band for every group (a spec-2 group judged by spec 1's
    B = 0.5 instead of its own 0.05 picked models with J_SF far outside its band)."""
    import warnings

    import numpy as np

    import graybox as gb
    from graybox import experiments as gx

    def grid(b, name, structures):
        s = [gx.StructureSpec(f"s{i}", terms=t) for i, t in enumerate(structures)]
        v = [gx.Variant("CLS", "cls", constraints=[{"type": "equality"}]),
             gx.Variant("PE", "pe", lambdas={"logspace": [-4, 0, 5]}, options={"solver": "closed"})]
        return gx.Grid([gx.DataSpec("pumping", bundled="pumping", band=b)], s, v, name=name)

    structures = [["1", "y(k-1)", "u(k-1)"], ["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-1)u(k-1)"],
                  ["y(k-1)", "y(k-1)^2", "u(k-1)", "1"]]
    store = tmp_path / "two.sqlite"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the estimators' notes are not under test
        gx.run_grid(grid(0.5, "g1", structures), store, progress=False)
        gx.run_grid(grid(0.05, "g2", structures[1:] + [["1", "y(k-1)", "y(k-2)", "u(k-1)"]]), store, progress=False)
    df = gb.load_results(store, spec="all")
    assert set(df["band"]) == {0.5, 0.05}  # the premise: one data set, two bands
    lb = gx.leaderboard(df).reset_index()
    own = df.groupby(["data", "structure", "variant"])["band"].first()
    checked = 0
    for r in lb.itertuples(index=False):
        if r.in_band is True or r.in_band == 1:
            assert r.JSF <= own[(r.data, r.structure, r.variant)], (r.structure, r.variant, r.JSF)
            checked += 1
    assert checked >= 4
    # the spec-2 groups rank as leaderboard(spec=2) ranks them
    two = gx.leaderboard(gb.load_results(store, spec=2)).reset_index().set_index("variant")
    for r in lb[lb["structure"].str.endswith("(spec 2)")].itertuples(index=False):
        want = two[two["structure"] == r.structure.replace(" (spec 2)", "")].loc[r.variant]
        assert r.JS_valid == want["JS_valid"] or (np.isnan(r.JS_valid) and np.isnan(want["JS_valid"]))


def test_a_variant_s_key_says_where_sigma_y_comes_from():
    """cls's and pe_pareto's default changed from reference='ls' to 'free' within graybox 0.2.6, and a cell's key
    hashes the variant's content with the version: a store grown before the change held cells of an equality
    variant without a reference option, estimated with the least-squares Σ*_y, that a run now reused as if they
    were estimated with Σ_y free. The key now names the default it was run with (the same as an explicit
    reference = "free"), so those cells are not reused; an explicit "ls" or a given sigma_y keep their own."""
    eq = [{"type": "equality", "curve": "fit"}]
    for est in ("cls", "pe"):
        default = Variant("v", est, constraints=eq).content()
        assert default == Variant("v", est, constraints=eq, options={"reference": "free"}).content()
        assert default != Variant("v", est, constraints=eq, options={"reference": "ls"}).content()
    given = [{"type": "equality", "curve": "fit", "sigma_y": 0.9}]
    assert "reference" not in Variant("v", "cls", constraints=given).content()["options"]
    assert "reference" not in Variant("v", "pe").content()["options"]  # no equality: no Σ*_y at all


def test_pe_keeps_a_member_whose_free_sigma_y_reaches_one_as_a_failed_member():
    """With Σ_y estimated, PE's static objective (the points' linear residual, (1 − Σ_y)(ȳ − H(ū)) under eq. (22))
    shrinks as Σ_y → 1, so the members of small λ1 approach the degenerate Σ_y = 1. One such member refused the
    whole sweep ('the estimated Σ_y = 1 leaves the model no stable equilibrium'): pe_pareto lost its λ1 = 0.5
    member too. A sweep keeps a failed member with its reason and goes on."""
    import numpy as np

    import graybox as gb

    true = gb.Structure(["y(k-1)", "y(k-1)u(k-1)", "u(k-1)", "u(k-1)^2", "1"])
    theta = np.array([0.5, 0.15, 0.3, -0.05, 0.2])
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(0.0, 2.0, 21), 20)[:400]
    rec = gb.Record(u, gb.Model(true, theta).simulate(u, np.zeros(1)) + 0.02 * rng.standard_normal(400))
    ub = np.linspace(0.25, 1.75, 7)
    pts = gb.StaticPoints(ub, gb.Model(true, theta).static_curve(ub) + 0.05 * rng.standard_normal(ub.size))
    eq = gb.CurveEquality(gb.StaticCurve.fit(pts, degree=2))
    from graybox.estimation._prediction_error import pe_members

    thetas, failures = pe_members(true, rec, pts, lambdas=[1e-14, 0.5], constraints=eq, solver="closed")
    assert list(failures) == [0] and "λ1 = 1e-14" in failures[0] and "Σ_y" in failures[0]
    assert np.isnan(thetas[0]).all()
    sy = gb.Model(true, thetas[1]).clusters()["Σy"]
    assert 0.0 < sy < 1.0
    ps = gb.pe_pareto(true, rec, pts, lambdas=[1e-14, 0.5], constraints=eq, solver="closed")
    assert ps.to_frame()["failure"].iloc[0] != "" and ps.to_frame()["failure"].iloc[1] == ""
    with pytest.raises(ValueError, match="Σ_y"):  # every member failed: nothing to return
        gb.pe_thetas(true, rec, pts, lambdas=[1e-14], constraints=eq, solver="closed")
