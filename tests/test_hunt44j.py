"""hunt44j: laws of the last sessions' code (design_input's ranges, cluster keys, JSON, fingerprints)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

import graybox as gb

FAST = settings(max_examples=25, deadline=None)


# ---------------------------------------------------------------------------------------------
# design_input: per-input ranges
# ---------------------------------------------------------------------------------------------
@FAST
@given(kind=st.sampled_from(["aprbs", "staircase", "prbs", "multisine"]), m=st.integers(1, 3),
       lows=st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3),
       widths=st.lists(st.floats(1e-3, 1e6), min_size=3, max_size=3))
def test_design_input_columns_in_their_own_range(kind, m, lows, widths):
    lo = np.array(lows[:m])
    hi = lo + np.array(widths[:m])
    assume(np.all(lo < hi))
    opts = {"frequencies": (0.05, 0.5)} if kind == "multisine" else {"hold": (5, 20) if kind == "aprbs" else 5}
    u = gb.design_input(kind, 400, low=list(lo), high=list(hi), n_inputs=m, **opts).reshape(400, m)
    assert np.all(u >= lo) and np.all(u <= hi)
    # one number for every input is the same design as the number repeated
    same = gb.design_input(kind, 400, low=float(lo[0]), high=float(hi[0]), n_inputs=m, **opts)
    again = gb.design_input(kind, 400, low=[float(lo[0])] * m, high=[float(hi[0])] * m, n_inputs=m, **opts)
    np.testing.assert_array_equal(same, again)


def test_design_input_takes_bounds_as_numpy_and_pandas_give_them():
    """A 0-d array is one number (check_real takes it), and per-input bounds read off a table (a Series of
    df.min(), a range) are one per input: both were refused, the first as 'must be one number'."""
    ref = gb.design_input("aprbs", 300, low=0.0, high=1.0, hold=(5, 20))
    np.testing.assert_array_equal(gb.design_input("aprbs", 300, low=np.array(0.0), high=np.array(1.0),
                                                  hold=(5, 20)), ref)
    df = pd.DataFrame({"speed": [750.0, 1650.0], "valve": [20.0, 80.0]})
    ref2 = gb.design_input("aprbs", 300, low=[750.0, 20.0], high=[1650.0, 80.0], hold=(5, 20), n_inputs=2)
    np.testing.assert_array_equal(gb.design_input("aprbs", 300, low=df.min(), high=df.max(), hold=(5, 20),
                                                  n_inputs=2), ref2)
    np.testing.assert_array_equal(gb.design_input("aprbs", 300, low=range(2), high=[5, 5], hold=(5, 20),
                                                  n_inputs=2),
                                  gb.design_input("aprbs", 300, low=[0, 1], high=[5, 5], hold=(5, 20), n_inputs=2))
    with pytest.raises(TypeError, match="low"):
        gb.design_input("aprbs", 300, low="0", high=1.0, hold=(5, 20))


# ---------------------------------------------------------------------------------------------
# ClusterBounds: a key in every form
# ---------------------------------------------------------------------------------------------
@FAST
@given(p=st.integers(0, 3), powers=st.lists(st.integers(0, 3), min_size=1, max_size=3),
       lo=st.floats(-10, 0), hi=st.floats(0, 10))
def test_cluster_bounds_key_forms_agree(p, powers, lo, hi):
    flat = gb.ClusterBounds({(p, *powers): (lo, hi)})
    nested = gb.ClusterBounds({(p, tuple(powers)): (lo, hi)})
    numpy = gb.ClusterBounds({(np.int64(p), *map(np.int64, powers)): (lo, hi)})
    assert dict(flat.bounds) == dict(nested.bounds) == dict(numpy.bounds)


def test_cluster_bounds_refuses_two_forms_of_one_key():
    """(1, (1, 0)) and (1, 1, 0) are one cluster: the dict kept the last one's bounds, the first's lower bound
    silently dropped."""
    with pytest.raises(ValueError, match=r"\(1, 1, 0\)"):
        gb.ClusterBounds({(1, (1, 0)): (0.0, 1.0), (1, 1, 0): (None, 0.5)})


# ---------------------------------------------------------------------------------------------
# operating points of a model with transient inputs: every form of ū gives the same points
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def transient_model():
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(1.0, 3.0, 60), 10)
    y = np.zeros_like(u)
    for k in range(1, len(u)):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1] + 0.05 * u[k - 1] ** 2
    data = gb.transient_inputs(gb.Record(u, y + 0.001 * rng.standard_normal(len(u)), Ts=1.0), [4.0])
    terms = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u_tau4(k-1)", "u_tau4(k-1)u(k-1)"]
    return gb.els(gb.Structure.parse(terms) if hasattr(gb.Structure, "parse") else gb.parse_structure(terms),
                  data).model


def test_transient_model_takes_a_frame_of_its_other_inputs(transient_model):
    """ū given for the other inputs alone is completed with z̄ = 0 (steady_levels): levels as an array were, but
    a DataFrame with a column per other input (the transient ones left out, as in an array) was refused as
    naming 'only some of the inputs'."""
    m = transient_model
    levels = np.array([1.2, 2.0, 2.8])
    ref = m.static_curve(levels)
    frame = pd.DataFrame({"u": levels})
    np.testing.assert_array_equal(m.static_curve(frame), ref)
    np.testing.assert_array_equal(m.static_gain(frame), m.static_gain(levels))
    np.testing.assert_array_equal(gb.operating_curve(m, frame).ybar, gb.operating_curve(m, levels).ybar)
    row = pd.Series({"u": 2.0})
    assert [e.ybar for e in m.equilibria(row)] == [e.ybar for e in m.equilibria(2.0)]
    np.testing.assert_array_equal(gb.local_model(m, row).b, gb.local_model(m, 2.0).b)
    np.testing.assert_array_equal(gb.narx_steady_state(m, row, 1.0), gb.narx_steady_state(m, 2.0, 1.0))
    with pytest.raises(ValueError, match="only some of the inputs"):  # a column that is no input is still refused
        m.static_curve(pd.DataFrame({"u": levels, "v": levels}))


# ---------------------------------------------------------------------------------------------
# the PE closed form over a sweep: a singular weight pair is one failed member, not the whole sweep
# ---------------------------------------------------------------------------------------------
@pytest.mark.filterwarnings("ignore::graybox.StaticRangeWarning")
def test_closed_form_fails_only_the_members_it_cannot_solve():
    """u offset by 1e6 (levels 1e6 + [0, 3]) with a u² term: the closed form judged the λ1 = 0.01 pair singular and
    raised for the whole sweep, so λ1 = 0.1 and 0.5, which it solves alone, were lost with it (select_graybox's PE
    row: 'every member failed'). Each pair is judged on its own: the others keep their θ, the singular one is a
    failed member with its reason."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from conftest import two_level_records

    from graybox.estimation._prediction_error import pe_members

    r1, r2, sp = two_level_records()
    b = 1e6
    ds = gb.Dataset(gb.Record(r1.u + b, r1.y, name="ident"), gb.Record(r2.u + b, r2.y, name="valid"),
                    gb.StaticPoints(sp.ubar + b, sp.ybar))
    S = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])
    lams = [0.01, 0.1, 0.5]
    alone = {}
    for lam in lams:
        try:
            alone[lam] = pe_members(S, ds, lambdas=[lam], solver="closed")[0][0]
        except ValueError:
            alone[lam] = None
    assert any(v is not None for v in alone.values())  # some member is solved alone
    thetas, failures = pe_members(S, ds, lambdas=lams, solver="closed")
    for i, lam in enumerate(lams):
        if alone[lam] is None:
            assert i in failures and np.all(np.isnan(thetas[i]))
        else:
            assert i not in failures
            np.testing.assert_allclose(thetas[i], alone[lam], rtol=1e-9)


def test_transient_model_of_two_inputs_takes_a_frame_of_its_other_inputs_in_any_order():
    rng = np.random.default_rng(3)
    u = np.column_stack([np.repeat(rng.uniform(1.0, 3.0, 60), 10), np.repeat(rng.uniform(0.0, 1.0, 40), 15)])
    y = np.zeros(len(u))
    for k in range(1, len(u)):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1, 0] + 0.05 * u[k - 1, 0] ** 2 + 0.2 * u[k - 1, 1]
    data = gb.transient_inputs(gb.Record(u, y, input_names=("p", "q")), [4.0], input_names=["p"])
    m = gb.els(gb.parse_structure(["1", "y(k-1)", "p(k-1)", "p(k-1)^2", "q(k-1)", "p_tau4(k-1)"]), data).model
    pts = np.array([[1.5, 0.2], [2.5, 0.8]])
    frame = pd.DataFrame({"q": pts[:, 1], "p": pts[:, 0]})  # the other inputs, in another order
    np.testing.assert_array_equal(m.static_curve(frame), m.static_curve(pts))
    np.testing.assert_array_equal(gb.operating_curve(m, frame).ybar, gb.operating_curve(m, pts).ybar)
    assert [e.ybar for e in m.equilibria(frame.iloc[0])] == [e.ybar for e in m.equilibria(pts[0])]


# ---------------------------------------------------------------------------------------------
# squared_unit
# ---------------------------------------------------------------------------------------------
@FAST
@given(unit=st.text(st.sampled_from("ms/()²3 kg·°%µ"), min_size=1, max_size=8))
@example(unit="(m/s)")
@example(unit="(m)(s)")
def test_a_squared_unit_is_the_unit_squared_once(unit):
    from graybox.core._reprs import squared_unit

    said = squared_unit(unit)
    u = unit.strip()
    assume(u)
    # one word takes ² as it is; anything else is in one pair of brackets, never two ("((m/s))²")
    assert said in (f" {u}²", f" ({u})²")
    if u.startswith("(") and u.endswith(")") and _one_group(u):
        assert said == f" {u}²"


def _one_group(u: str) -> bool:
    """Whether the brackets of ``u`` open at its start and close only at its end."""
    depth = 0
    for i, c in enumerate(u):
        depth += (c == "(") - (c == ")")
        if depth < 0 or (depth == 0 and i < len(u) - 1):
            return False
    return depth == 0
