"""hunt54c: several inputs, long records and the statics of several inputs."""

import numpy as np
import pytest

import graybox as gb


def test_regressor_matrix_reads_one_input_column_as_a_record_does_whatever_its_container():
    # an (N, 1) float64 array skipped the coercion and was read as input 'u1', while the same samples as a list (or in
    # a Record) are the one input 'u': u(k-1) was refused for the array and u1(k-1) for the list
    rng = np.random.default_rng(0)
    u, y = rng.uniform(size=20), rng.uniform(size=20)
    st = gb.Structure(["u(k-1)", "y(k-1)"])
    flat = gb.regressor_matrix(st, u, y)
    for col in (u[:, None], u[:, None].tolist(), np.asfortranarray(u[:, None])):
        assert np.array_equal(gb.regressor_matrix(st, col, y), flat)
    assert np.array_equal(gb.stacked_regressors(st, gb.Record(u[:, None], y))[0], flat)
    named = gb.Structure(["u1(k-1)", "y(k-1)"])
    assert np.array_equal(gb.regressor_matrix(named, u[:, None], y, input_names=("u1",)), flat)
    for col in (u[:, None], u[:, None].tolist()):
        with pytest.raises(ValueError, match="needs input 'u1'"):
            gb.regressor_matrix(named, col, y)


def test_static_values_and_cached_cluster_maps_cannot_be_made_writeable_again():
    # read-only arrays that own their memory take a.flags.writeable = True (4a5f8bb fixed records, models and static
    # points only): a StaticSurface's or StaticCurve's coefficients could then be edited in place, and cluster_map's
    # R, cached and shared by every static analysis of the structure, changed what every later call saw
    surface = gb.StaticSurface.polynomial({(0, 0): 1.0, (1, 0): 2.0, (0, 1): 3.0})
    curve = gb.StaticCurve.polynomial([1.0, 2.0])
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    arrays = {"StaticSurface.coefficients": surface.coefficients, "StaticCurve.coefficients": curve.coefficients,
              "cluster_map(st).R": gb.cluster_map(st).R,
              "surface_cluster_map(st).R": gb.surface_cluster_map(gb.parse_structure(["y(k-1)", "a(k-1)", "b(k-1)"])).R}
    for name, a in arrays.items():
        with pytest.raises(ValueError, match="WRITEABLE"):
            a.flags.writeable = True
        assert not a.flags.writeable, name
    assert surface([[0.0, 0.0]])[0] == 1.0 and curve(0.0) == 1.0
    assert gb.cluster_map(st).R[0].tolist() == [1.0, 0.0, 0.0, 0.0]


def test_frols_selection_arrays_and_pe_lambdas_cannot_be_made_writeable_again():
    # a Selection's err, theta, rss … and the public default sweep PE_LAMBDAS were read-only arrays owning their
    # memory: a.flags.writeable = True, then sel.theta[0] = 5 changed the selection (and its model), and
    # gb.PE_LAMBDAS[:] = 1 every later pe_pareto's default λ1
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, (200, 2))
    y = 0.3 * u[:, 0] + 0.1 * rng.standard_normal(200)
    sel = gb.frols(gb.Candidates(1, {"a": 1, "b": 1}, degree=1), gb.Record(u, y, input_names=("a", "b")), n_terms=2)
    arrays = {name: getattr(sel, name) for name in ("err", "theta", "err_evaluated", "rss", "criterion_curve")}
    arrays["PE_LAMBDAS"] = gb.PE_LAMBDAS
    for name, a in arrays.items():
        for target in (a, a.base):
            if isinstance(target, np.ndarray):
                with pytest.raises(ValueError, match="WRITEABLE"):
                    target.flags.writeable = True
        assert not a.flags.writeable, name
    assert gb.PE_LAMBDAS[0] == pytest.approx(1e-6) and gb.PE_LAMBDAS[-1] == 1.0 and gb.PE_LAMBDAS.size == 100


def test_plant_runs_cannot_be_made_writeable_again():
    # a run of the bundled plants ("a run is a value") held read-only arrays owning their memory: flags.writeable =
    # True, then run.u[0] = … edited it, and the Record made of it later
    one = gb.datasets.PumpingPlant().simulate(np.full(40, 1200.0), seed=0)
    two = gb.datasets.TwoSpeedPumpingPlant().simulate(np.full((40, 2), 1200.0), seed=0)
    for run in (one, two):
        for name in ("u", "y", "speed", "flow", "surge"):
            with pytest.raises(ValueError, match="WRITEABLE"):
                getattr(run, name).flags.writeable = True


@pytest.mark.parametrize("fn, twin", [("static_curve", "static_surface"), ("static_gain", "static_surface_gain")])
def test_the_one_input_static_functions_send_a_structure_of_several_inputs_to_the_surface_functions(fn, twin):
    # gb.static_curve(structure of u1, u2, θ, points of shape (M, 2)) said "ubar must be levels of the one input …:
    # a model of several inputs takes points of shape (M, m)", which is what it was given
    st = gb.parse_structure(["1", "y(k-1)", "u1(k-1)", "u2(k-2)"])
    theta = [0.1, 0.5, 1.0, 1.0]
    for ubar in ([[1.0, 2.0], [3.0, 4.0]], [1.0, 2.0], 1.0):
        with pytest.raises(ValueError, match=rf"2 inputs \('u1', 'u2'\).*graybox\.{twin}\(structure, theta, ubar\)"):
            getattr(gb, fn)(st, theta, ubar)
    assert getattr(gb, twin)(st, theta, [[1.0, 2.0]]).shape[0] == 1


def test_pe_and_cls_of_a_closed_structure_on_a_dask_record_at_an_offset_are_the_in_memory_fit():
    # CLS and PE fit a structure closed under shifts on the centred signals (the raw regressors of y + 1e7 carry the
    # offset's powers, whose round-off is what the data say), but a DaskRecord was fitted raw: at y + 1e7 pe_thetas
    # and cls refused it ("θ is not identifiable ... rank 6 for 7 terms") where the same samples in memory fit
    da = pytest.importorskip("dask.array")
    from graybox.selection._centring import closure

    data = gb.load_pumping()
    r = gb.Record(data.ident.u[:1200], data.ident.y[:1200] + 1e7, Ts=data.ident.Ts, name="ident")
    points = gb.StaticPoints(data.static.ubar, data.static.ybar + 1e7, uncertainty=0.175)
    big = gb.DaskRecord(da.from_array(r.u, chunks=300), da.from_array(r.y, chunks=300), Ts=r.Ts, name="ident")
    st = closure(gb.parse_structure(["y(k-1)", "y(k-2)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-1)^2"]))
    lambdas = [1e-6, 1e-4, 0.5]
    mem = gb.pe_thetas(st, r, points, lambdas=lambdas)
    lazy = gb.pe_thetas(st, big, points, lambdas=lambdas)
    # θ to the data's own conditioning (one ulp of one sample of y moves the in-memory θ by 6e-9); their static
    # curves, evaluated on raw θ at y + 1e7, would differ by the evaluation's round-off alone
    np.testing.assert_allclose(lazy, mem, rtol=1e-7)
    a = gb.cls(st, r, points, how="context", constraints=gb.StaticBand()).model
    b = gb.cls(st, big, points, how="context", constraints=gb.StaticBand()).model
    np.testing.assert_allclose(b.theta, a.theta, rtol=1e-7)


def test_a_free_run_of_a_dask_record_says_where_one_is_taken():
    # model.simulate(DaskRecord) and simulate(structure, θ, DaskRecord) said "u must be an array of numbers, got
    # DaskRecord", where every other entry says which take one and how to make a Record of its samples (7baa7e9)
    da = pytest.importorskip("dask.array")
    u = np.random.default_rng(0).uniform(size=100)
    d = gb.DaskRecord(da.from_array(u, chunks=50), da.from_array(u, chunks=50), name="long")
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    for run in (lambda: m.simulate(d), lambda: gb.simulate(m.structure, m.theta, d)):
        with pytest.raises(TypeError, match=r"got DaskRecord; .*taken by frols, pe_thetas and cls only.*Record\(r\.u"):
            run()
