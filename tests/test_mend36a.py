"""Mends of batch 36a: items earlier bug hunts left open — the delta-method static band at an
input offset, PE's QP scaling at an output offset, a NaN θ scored as a model, unchecked ``name=``
arguments, and SEMP's unbounded pruning scores."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


# -- 3. evaluate_thetas and a parameter vector that is not a model ------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_evaluate_thetas_refuses_a_non_finite_theta_row_naming_it(bad):
    # was: a NaN (or inf) θ row scored J1 = JS = JSF = inf with no word, as if it were a diverging model
    data = gb.load_pumping()
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)"])
    th = np.array([[0.1, 0.9, 1e-3], [0.1, 0.9, 1e-3], [bad, 0.9, 1e-3]])
    with pytest.raises(ValueError, match=r"thetas.*row.*\[2\]"):
        gb.evaluate_thetas(st, th, data.valid, data.static)
    with pytest.raises(ValueError, match=r"thetas.*row.*\[2\]"):
        gb.evaluate_thetas(st, th, None, data.static)
    ok = gb.evaluate_thetas(st, th[:2], data.valid, data.static)
    assert np.all(np.isfinite(ok["JS"])) and np.all(np.isfinite(ok["JSF"]))


# -- 4. name= arguments ---------------------------------------------------------------------------

def _named(kind, name):
    data = gb.load_pumping()
    u, y = data.ident.u[:100], data.ident.y[:100]
    if kind == "Record":
        return gb.Record(u, y, name=name)
    if kind == "Record.slice":
        return data.ident.slice(0, 100, name=name)
    if kind == "DaskRecord":
        import dask.array as da
        return gb.DaskRecord(da.from_array(u), da.from_array(y), name=name)
    if kind == "StaticPoints":
        return gb.StaticPoints([1.0, 2.0], [1.0, 2.0], name=name)
    if kind == "StaticPoints.from_repeats":
        return gb.StaticPoints.from_repeats([1.0, 1.0, 2.0], [1.0, 1.2, 2.0], name=name)
    if kind == "StaticCurve":
        return gb.StaticCurve(np.array([1.0, 2.0, 3.0]), name=name)
    if kind == "StaticCurve.fit":
        return gb.StaticCurve.fit(data.static, name=name)
    if kind == "StaticSurface.polynomial":
        return gb.StaticSurface.polynomial({(0, 0): 1.0, (1, 0): 2.0}, name=name)
    if kind == "UserConstraint":
        return gb.UserConstraint(lambda theta, ctx: [], name=name)
    if kind == "narx_iosystem":
        pytest.importorskip("control")
        m = gb.Model(gb.parse_structure(["1", "y(k-1)", "u(k-1)"]), np.array([0.1, 0.5, 1e-3]))
        return gb.narx_iosystem(m, 1.0, name=name)
    raise AssertionError(kind)


@pytest.mark.parametrize("kind", ["Record", "Record.slice", "DaskRecord", "StaticPoints", "StaticPoints.from_repeats",
                                  "StaticCurve", "StaticCurve.fit", "StaticSurface.polynomial", "UserConstraint",
                                  "narx_iosystem"])
def test_a_name_that_is_not_a_string_is_a_type_error(kind):
    # was: records, static points, curves, surfaces and user constraints kept name=5 (or a list) as their label,
    # which then failed far away (a message, a saved file); narx_iosystem refused it in words of its own
    for bad in (5, ["a"], b"a"):
        with pytest.raises(TypeError, match=r"name must be a str, got"):
            _named(kind, bad)
    assert _named(kind, "label") is not None
