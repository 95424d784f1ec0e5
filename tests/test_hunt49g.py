"""hunt49g: several inputs and long records."""

import numpy as np
import pytest

import graybox as gb


def first_order(n: int, delay: int = 1, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """u uniform on [0, 1] and y(k) = 0.5 y(k-1) + u(k-delay), noise-free, y zero before its first update."""
    u = np.random.default_rng(seed).uniform(0, 1, n)
    y = np.zeros(n)
    for k in range(delay, n):
        y[k] = 0.5 * y[k - 1] + u[k - delay]
    return u, y


def test_regressor_matrix_one_column_with_two_input_names_is_refused():
    # a 1-D u with input_names of two inputs was silently read as the first input alone
    rng = np.random.default_rng(0)
    u, y = rng.uniform(size=20), rng.uniform(size=20)
    st = gb.Structure(["a(k-1)", "y(k-1)"])
    with pytest.raises(ValueError, match="one input column.*2 input names"):
        gb.regressor_matrix(st, u, y, input_names=("a", "b"))
    with pytest.raises(ValueError, match="one input column.*2 input names"):
        gb.regressor_matrix(st, u.tolist(), y, input_names=("a", "b"))
    # one input, one name: as before
    psi = gb.regressor_matrix(st, u, y, input_names=("a",))
    assert np.array_equal(psi[:, 0], u[:-1])


def test_dask_record_inf_is_refused_without_numpy_warnings():
    # the clear ValueError naming the sample came after numpy's RuntimeWarnings (invalid value in multiply, matmul)
    da = pytest.importorskip("dask.array")
    import warnings

    u, y = first_order(300)
    y[0] = np.inf
    rec = gb.DaskRecord(da.from_array(u, chunks=100), da.from_array(y, chunks=100), name="long")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="long: y has 1 non-finite value.*index 0"):
            gb.frols(gb.Candidates(2, 2, degree=2), rec, n_terms=2)
        with pytest.raises(ValueError, match="overflow"):
            big = gb.DaskRecord(da.from_array(u * 1e160, chunks=100), da.from_array(u, chunks=100))
            gb.frols(gb.Candidates(2, 2, degree=2), big, n_terms=2)


def test_dask_records_without_a_name_are_named_in_messages():
    # two DaskRecords made without name= were both '' in every message: "'' is sampled every 1 s but '' every 2 s"
    da = pytest.importorskip("dask.array")
    u = np.random.default_rng(0).uniform(size=100)
    a = gb.DaskRecord(da.from_array(u, chunks=50), da.from_array(u, chunks=50))
    b = gb.DaskRecord(da.from_array(u, chunks=50), da.from_array(u, chunks=50), Ts=2.0)
    with pytest.raises(ValueError) as info:
        gb.frols(gb.Candidates(1, 1, degree=1), [a, b], n_terms=1)
    assert "''" not in str(info.value) and "'record' is sampled every 1 s" in str(info.value)
    with pytest.raises(ValueError) as info:
        gb.frols(gb.Candidates(1, {"speed": 1}, degree=1), a, n_terms=1)
    assert str(info.value).startswith("record: the terms use input 'speed'")
    # the hint is a DaskRecord's: it has no input_names to give (Record(..., input_names=...) was the advice)
    assert "input_names=" not in str(info.value) and "one input, named 'u'" in str(info.value)
    assert "'record'" in repr(a)


def test_dask_record_neither_aliases_nor_takes_item_assignment():
    # DaskRecord held the caller's own dask arrays (astype/rechunk return them unchanged) and dask assigns items in
    # place: u[0] = -99 after construction changed the "frozen" record, and so did record.u[1] = ...
    da = pytest.importorskip("dask.array")
    u = da.from_array(np.arange(10.0), chunks=5)
    y = da.from_array(np.arange(10.0), chunks=5)
    rec = gb.DaskRecord(u, y, name="long")
    u[0] = -99.0
    y[0] = -99.0
    assert rec.u[0].compute() == 0.0 and rec.y[0].compute() == 0.0
    with pytest.raises(TypeError, match="read-only"):
        rec.u[1] = 1234.0
    with pytest.raises(TypeError, match="read-only"):
        rec.y[1] = 1234.0
    assert rec.u[1].compute() == 1.0 and rec.y[1].compute() == 1.0


def test_dask_record_where_records_in_memory_are_meant_says_where_it_is_taken():
    # frols([Record, DaskRecord]) said "data must be a Record, a sequence of Records or a Dataset; got a sequence
    # holding a DaskRecord", as if frols took no DaskRecord; els(DaskRecord) said "got DaskRecord" and no more
    da = pytest.importorskip("dask.array")
    u = np.random.default_rng(0).uniform(size=100)
    d = gb.DaskRecord(da.from_array(u, chunks=50), da.from_array(u, chunks=50), name="long")
    r = gb.Record(u, u)
    st = gb.Structure(["y(k-1)", "u(k-1)"])
    with pytest.raises(TypeError, match="not among Records: give them all as DaskRecords, or all as Records"):
        gb.frols(st, [r, d], n_terms=1)
    with pytest.raises(TypeError, match=r"taken by frols, pe_thetas and cls only.*Record\(r\.u\.compute\(\)"):
        gb.els(st, d)
    with pytest.raises(TypeError, match=r"taken by frols, pe_thetas and cls only.*Record\(r\.u\.compute\(\)"):
        gb.els(st, [d, d])


def test_dask_record_of_a_wrong_type_is_a_type_error():
    # an array in memory, a list or complex samples were a ValueError ("must be a dask array, got ndarray")
    da = pytest.importorskip("dask.array")
    x = np.arange(10.0)
    d = da.from_array(x, chunks=5)
    with pytest.raises(TypeError, match=r"DaskRecord.u must be a dask array, got ndarray.*from_array"):
        gb.DaskRecord(x, d)
    with pytest.raises(TypeError, match="DaskRecord.y must be a dask array, got list"):
        gb.DaskRecord(d, x.tolist())
    with pytest.raises(TypeError, match="DaskRecord.u must hold real numbers, got dtype complex128"):
        gb.DaskRecord(d.astype(complex), d)
    with pytest.raises(ValueError, match="holds one input"):
        gb.DaskRecord(da.from_array(np.ones((10, 2)), chunks=5), d)


def test_dask_record_nan_where_no_row_reads_is_refused_as_a_records():
    # u's last sample is read by no regression row (lags >= 1): a NaN there was taken silently from a DaskRecord,
    # while the same samples as a Record are refused at construction
    da = pytest.importorskip("dask.array")
    u, y = first_order(400, delay=2)
    u[-1] = np.nan
    with pytest.raises(ValueError, match="u has 1 non-finite value.*index 399"):
        gb.Record(u, y)
    rec = gb.DaskRecord(da.from_array(u, chunks=100), da.from_array(y, chunks=100), name="long")
    with pytest.raises(ValueError, match="long: u has 1 non-finite value.*index 399"):
        gb.frols(gb.Candidates(2, 2, degree=2), rec, n_terms=2)
    points = gb.StaticPoints([0.2, 0.5, 0.8], [0.4, 1.0, 1.6])
    with pytest.raises(ValueError, match="long: u has 1 non-finite value.*index 399"):
        gb.pe_thetas(gb.Structure(["y(k-1)", "u(k-2)"]), rec, points)


def test_dask_record_takes_one_input_as_a_column_as_a_record_does():
    """(N, 1) u was refused with 'holds one input: several are a Record of shape (N, m)', wrong for one input
    (review49i)."""
    da = pytest.importorskip("dask.array")
    u, y = first_order(200, seed=1)
    col = gb.DaskRecord(da.from_array(u[:, None], chunks=50), da.from_array(y, chunks=50), name="c")
    flat = gb.DaskRecord(da.from_array(u, chunks=50), da.from_array(y, chunks=50), name="c")
    assert col.u.shape == (200,)
    cand = gb.Candidates(2, 2, degree=2)
    a, b = gb.frols(cand, col, n_terms=3), gb.frols(cand, flat, n_terms=3)
    assert list(a.structure) == list(b.structure) and np.array_equal(a.theta, b.theta)
    with pytest.raises(ValueError, match="holds one input"):
        gb.DaskRecord(da.from_array(np.ones((10, 2)), chunks=5), da.from_array(np.ones(10), chunks=5))
