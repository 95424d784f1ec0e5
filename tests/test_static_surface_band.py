"""static_surface_band: the band of a static surface ȳ(ū1, ū2) and of its gains ∂ȳ/∂ū_i from a parameter
covariance; one input gives static_curve_band's band; the delta method's gradient against finite differences,
against Monte Carlo, and units."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb
from graybox.static._linearisation import static_gain_gradient, static_powers
from graybox.static._surface_analysis import surface_theta_gradient

MISO = ["y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-1)", "u1(k-1)y(k-1)", "u1(k-1)u2(k-1)", "u2(k-1)^2", "1"]


@pytest.fixture(scope="module")
def miso():
    d = gb.load_pumping_miso()
    fit = gb.els(MISO, d.ident, noise=0)
    unc = gb.ls_uncertainty(fit.model, d.ident)
    lo, hi = d.static.ubar.min(axis=0), d.static.ubar.max(axis=0)
    pts = lo + (hi - lo) * np.array([[0.2, 0.3], [0.5, 0.5], [0.8, 0.6], [0.4, 0.9]])
    return d, unc, pts


def test_one_input_gives_the_curve_band(miso):
    d = gb.load_pumping()
    st = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "u(k-1)^2", "1"]
    unc = gb.ls_uncertainty(gb.els(st, d.ident, noise=0).model, d.ident)
    ub = np.linspace(800, 1600, 5)
    for method in ("delta", "monte-carlo"):
        c = gb.static_curve_band(unc, ub, method=method, n_samples=300)
        s = gb.static_surface_band(unc, ub[:, None], method=method, n_samples=300)
        np.testing.assert_allclose(s.ybar, c.ybar, rtol=1e-12)
        for f in ("ybar_low", "ybar_high", "ybar_std"):
            np.testing.assert_allclose(getattr(s, f), getattr(c, f), rtol=1e-9)
        for f in ("gain", "gain_low", "gain_high", "gain_std"):
            np.testing.assert_allclose(getattr(s, f)[:, 0], getattr(c, f), rtol=1e-9)


def test_the_gain_gradient_is_the_finite_difference_of_the_gains(miso):
    _, unc, pts = miso
    m = unc.model
    th = m.theta
    yb = gb.static_surface(m.structure, th, pts, input_names=m.input_names)
    p, A = static_powers(m.structure, m.input_names)
    G = static_gain_gradient(p, A, th, pts, yb, surface_theta_gradient(m.structure, th, pts, yb, inputs=m.input_names))
    for t in range(th.size):
        h = 1e-6 * max(abs(th[t]), 1e-12)
        gains = [gb.static_surface_gain(m.structure, th + s * h * np.eye(th.size)[t], pts, input_names=m.input_names)
                 for s in (1, -1)]
        np.testing.assert_allclose(G[:, :, t], (gains[0] - gains[1]) / (2 * h), rtol=1e-4,
                                   atol=1e-6 * np.abs(G[:, :, t]).max())


def test_delta_and_monte_carlo_agree_where_the_map_is_near_linear(miso):
    _, unc, pts = miso
    dl = gb.static_surface_band(unc, pts)
    mc = gb.static_surface_band(unc, pts, method="monte-carlo", n_samples=4000, seed=3)
    assert dl.ubar.shape == (4, 2) and dl.gain.shape == (4, 2) and dl.input_names == ("u1", "u2")
    assert np.all(dl.ybar_low < dl.ybar) and np.all(dl.ybar < dl.ybar_high)
    np.testing.assert_allclose(mc.ybar_std, dl.ybar_std, rtol=0.15)
    np.testing.assert_allclose(mc.gain_std, dl.gain_std, rtol=0.2)
    assert np.all(mc.undefined == 0)
    again = gb.static_surface_band(unc, pts, method="monte-carlo", n_samples=4000, seed=3)
    np.testing.assert_array_equal(again.ybar_low, mc.ybar_low)


def test_the_band_follows_the_units(miso):
    d, unc, pts = miso
    k_u, k_y = np.array([60 / (2 * np.pi), 1.0]), 1000.0

    def scaled(r):
        return gb.Record(r.u * k_u, r.y * k_y, Ts=r.Ts, input_names=r.input_names)

    unc2 = gb.ls_uncertainty(gb.els(MISO, scaled(d.ident), noise=0).model, scaled(d.ident))
    a = gb.static_surface_band(unc, pts)
    b = gb.static_surface_band(unc2, pts * k_u)
    np.testing.assert_allclose(b.ybar_std, a.ybar_std * k_y, rtol=1e-6)
    np.testing.assert_allclose(b.gain_std, a.gain_std * k_y / k_u, rtol=1e-6)


def test_frame_and_bad_input(miso):
    _, unc, pts = miso
    band = gb.static_surface_band(unc, pts)
    f = band.to_frame()
    assert list(f.index.names) == ["u1", "u2"] and "gain u2 high" in f and len(f) == 4
    one = gb.static_surface_band(unc, pts[0])  # one point as shape (m,)
    assert one.ubar.shape == (1, 2)
    with pytest.raises(ValueError, match=r"shape \(M, 2\)"):
        gb.static_surface_band(unc, pts[:, :1])
    with pytest.raises(ValueError, match="non-finite"):
        gb.static_surface_band(unc, [[np.nan, 1.0]])
    with pytest.raises(TypeError, match="ParameterUncertainty"):
        gb.static_surface_band(unc.model, pts)
    with pytest.raises(ValueError, match="static_surface_band"):
        gb.static_curve_band(unc, pts)
    with pytest.raises(ValueError, match="gain must have shape"):
        type(band)(band.ubar, band.input_names, band.ybar, band.ybar_low, band.ybar_high, band.ybar_std,
                   band.gain[:, 0], band.gain_low, band.gain_high, band.gain_std, 0.95, "delta", 0, band.undefined)


def test_plot_static_band_draws_a_surface_band_as_slices(miso):
    from graybox import plots

    d, unc, _ = miso
    lo, hi = d.static.ubar.min(axis=0), d.static.ubar.max(axis=0)
    levels = np.unique(d.static.ubar[:, 1])[:2]  # two of the points' own levels of u2: their points lie on slices
    u1 = np.linspace(lo[0], hi[0], 7)
    pts = np.array([[a, b] for b in levels for a in u1])
    band = gb.static_surface_band(unc, pts)
    fig = plots.plot_static_band(band, d.static, against="u1")
    ax, gx = fig.axes
    lines = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    assert len(lines) == 2 and all(len(ln.get_xdata()) == 7 for ln in lines)
    np.testing.assert_allclose(lines[0].get_ydata(), band.ybar[:7])
    assert [ln.get_label().split("(")[-1] for ln in lines] == [f"u2 = {v:g})" for v in levels]
    stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
    assert sum(len(ln.get_xdata()) for ln in stars) == int(np.isin(d.static.ubar[:, 1], levels).sum())
    assert ax.get_xlabel().startswith("input u1") and gx.get_ylabel().startswith("static gain ∂ȳ/∂u1")
    np.testing.assert_allclose([ln for ln in gx.get_lines()][0].get_ydata(), band.gain[:7, 0])
    other = plots.plot_static_band(band, against=1, gain=False)  # against u2: 7 slices of 2 points
    assert len([ln for ln in other.axes[0].get_lines()]) == 7
    with pytest.raises(ValueError, match="against"):
        plots.plot_static_band(band, against="u3")
    with pytest.raises(ValueError, match="against"):
        plots.plot_static_band(band, against=2)
