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
