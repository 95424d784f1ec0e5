import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from graybox import Model, Structure, reference
from graybox._static import cluster_map, rational_static_curve


def test_eq16_clusters_from_table_ii():
    c = reference.paper_model(15).clusters()
    # eq. (16) as printed, to the table's 4-digit rounding (design.md)
    assert c["Σ0"] == pytest.approx(-0.4770, abs=5e-5)
    assert c["Σy"] == pytest.approx(0.9264, abs=5e-5)
    assert c["Σu"] == pytest.approx(8.925e-4, rel=2e-4)
    assert c["Σu²"] == pytest.approx(-1.2727e-7, rel=1e-3)
    assert c["Σyu"] == pytest.approx(2.7797e-5, rel=1e-3)


def test_eq20_clusters_from_table_iii():
    c = reference.paper_model(17).clusters()
    printed = {"Σy": 1.0299, "Σu": -1.4475e-3, "Σy²": 2.6151e-2, "Σu²": 5.6331e-6, "Σy³": 4.3873e-4,
               "Σu³": -3.4869e-9, "Σyu": -7.4151e-4, "Σy²u": -3.4620e-5, "Σyu²": 6.5291e-7}
    for k, v in printed.items():
        assert c[k] == pytest.approx(v, rel=6e-3), k   # Σyu² 6.526e-7 vs printed 6.5291e-7
    assert set(c) == set(printed)


def test_jsf_of_els15_against_eq1():
    from graybox import jsf

    assert jsf(reference.paper_model(15), reference.eq1_points()) == pytest.approx(1.618, abs=1e-3)


def test_model17_three_equilibria_at_750():
    eqs = reference.paper_model(17).equilibria(750.0)
    assert len(eqs) == 3
    stable = [e for e in eqs if e.stable]
    assert len(stable) == 1 and stable[0].ybar == pytest.approx(4.04, abs=0.01)
    assert eqs[1] is stable[0]  # the middle root
    assert reference.paper_model(17).static_curve([1650.0])[0] == pytest.approx(20.49, abs=0.01)


@pytest.mark.parametrize("eq,ubar", [(15, 750.0), (15, 1650.0), (17, 750.0), (17, 1200.0), (17, 1650.0)])
def test_static_curve_is_end_of_long_constant_input_run(eq, ubar):
    m = reference.paper_model(eq)
    ys = m.static_curve([ubar])[0]
    y = m.simulate(np.full(4000, ubar), np.full(m.max_lag, ys + 0.5))
    assert y[-1] == pytest.approx(ys, abs=1e-8)


def test_rational_form_equals_roots():
    m = reference.paper_model(15)
    u = np.linspace(750, 1650, 7)
    np.testing.assert_allclose(rational_static_curve(m.structure, m.theta, u), m.static_curve(u), rtol=1e-12)
    with pytest.raises(ValueError, match="not rational"):
        rational_static_curve(reference.STRUCTURE_17, reference.TABLE_III["ELS"], u)


def test_static_gain_matches_finite_difference():
    for eq in (15, 17):
        m = reference.paper_model(eq)
        u = np.array([800.0, 1200.0, 1600.0])
        h = 1e-3
        fd = (m.static_curve(u + h) - m.static_curve(u - h)) / (2 * h)
        np.testing.assert_allclose(m.static_gain(u), fd, rtol=1e-6)


def test_cluster_map_R():
    cm = cluster_map(reference.STRUCTURE_15)
    assert cm.R.shape == (5, 17) and np.all(cm.R.sum(axis=0) == 1)
    assert cm.names == ["Σ0", "Σu", "Σu²", "Σy", "Σyu"]
    assert cm.index("Syu") == cm.index("Σyu") == cm.index((1, 1))


@st.composite
def stable_models(draw):
    """Random rational/cubic-free structures with a contracting y part."""
    a = draw(st.lists(st.floats(-0.3, 0.3), min_size=2, max_size=2))
    b = draw(st.floats(0.001, 0.01))
    c = draw(st.floats(-1e-6, 1e-6))
    d = draw(st.floats(-2e-4, 2e-4))
    e0 = draw(st.floats(-1, 1))
    s = Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-2)", "1"])
    return Model(s, [a[0], a[1], b, c, d, e0])


@given(stable_models(), st.floats(750, 1650))
@settings(max_examples=40, deadline=None)
def test_property_static_curve_equals_simulated_steady_state(m, ubar):
    stable = [e for e in m.equilibria(ubar) if e.stable]
    if len(stable) != 1:
        return
    ys = stable[0].ybar
    y = m.simulate(np.full(3000, ubar), np.full(m.max_lag, ys * 1.01 + 0.1), on_diverge="nan")
    assert y[-1] == pytest.approx(ys, rel=1e-6, abs=1e-6)


@given(st.lists(st.floats(-10, 10), min_size=2, max_size=4).filter(lambda c: abs(c[-1]) > 1e-3),
       st.floats(1e-3, 1e3))
@settings(max_examples=80, deadline=None)
def test_property_closed_form_roots_equal_numpy_roots(coef, scale):
    from graybox._static_kernels import real_roots_upto_cubic

    c = np.array(coef) * scale
    got = real_roots_upto_cubic(c[:, None, None])[0, 0]
    got = np.sort(got[np.isfinite(got)])
    ref = np.roots(c[::-1])
    # well-separated real roots only: near-double roots are ill-conditioned for any method
    real = np.sort(ref[np.abs(ref.imag) < 1e-9].real)
    if len(ref) > 1 and np.min(np.abs(np.subtract.outer(ref, ref))[~np.eye(len(ref), dtype=bool)]) < 1e-3:
        return
    assert got.size == real.size
    np.testing.assert_allclose(got, real, rtol=1e-7, atol=1e-9)
