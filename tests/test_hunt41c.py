"""hunt41c: bugs found in static_surface_band, plot_static_band, the QP's equality elimination, static settling,
decimation_advice, design_input and gb.save/gb.load; each test failed before its fix."""

from __future__ import annotations

import json

import numpy as np
import pytest

import graybox as gb

MISO = ["y(k-1)", "y(k-2)", "u1(k-1)", "u2(k-1)", "u1(k-1)y(k-1)", "u1(k-1)u2(k-1)", "u2(k-1)^2", "1"]


@pytest.fixture(scope="module")
def surface_band():
    d = gb.load_pumping_miso()
    unc = gb.ls_uncertainty(gb.els(MISO, d.ident, noise=0).model, d.ident)
    return gb.static_surface_band(unc, np.array([[1250.0, 1300.0], [1400.0, 1400.0]]))


def test_a_surface_band_refuses_an_input_named_twice(surface_band, tmp_path):
    # to_frame's columns 'gain u1 …' of the first input were overwritten by the second's without a word
    b = surface_band
    with pytest.raises(ValueError, match="named twice"):
        type(b)(b.ubar, ("u1", "u1"), b.ybar, b.ybar_low, b.ybar_high, b.ybar_std, b.gain, b.gain_low,
                b.gain_high, b.gain_std, b.level, b.method, b.n_samples, b.undefined)
    p = tmp_path / "band.json"
    gb.save(b, p)
    j = json.loads(p.read_text())
    for bad in (["u1", "u1"], ["", "u2"]):
        j["object"]["input_names"] = bad
        p.write_text(json.dumps(j))
        with pytest.raises(gb.GrayboxFileError, match="input_names"):
            gb.load(p)


def test_plot_static_band_puts_points_on_their_slice_whatever_each_input_unit():
    # the slice tolerance took 1e-9 of the largest held input's size: with u2 in a unit 1e3 smaller and u3 in one
    # 1e6 larger, the tolerance in u3 (levels 5e-7 and 1.5e-6) was 1.5e-6 and every point lay on every slice
    from graybox import plots

    rng = np.random.default_rng(0)
    st, names = ["y(k-1)", "u1(k-1)", "u2(k-1)", "u3(k-1)", "1"], ("u1", "u2", "u3")
    k = np.array([1.0, 1e3, 1e-6])
    U = np.column_stack([np.repeat(rng.uniform(0, 2, 30), 20) for _ in range(3)])
    y = gb.Model(st, [0.5, 0.2, 0.3, 0.1, 1.0], input_names=names).simulate(U, np.zeros(1))
    rec = gb.Record(U * k, y + 0.01 * rng.standard_normal(y.size), Ts=1.0, input_names=names)
    unc = gb.ls_uncertainty(gb.els(st, rec, noise=0).model, rec)
    lv = np.array([[a, b, c] for c in (0.5, 1.5) for b in (0.5, 1.5) for a in np.linspace(0, 2, 5)]) * k
    band = gb.static_surface_band(unc, lv)
    pu = np.array([[a, b, c] for c in (0.5, 1.5) for b in (0.5, 1.5) for a in (0.5, 1.0)]) * k
    pts = gb.StaticPoints(pu, np.arange(8.0), input_names=names)
    ax = plots.plot_static_band(band, pts, against="u1", gain=False).axes[0]
    stars = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
    assert len(stars) == 4 and [len(s.get_xdata()) for s in stars] == [2, 2, 2, 2]
    for s in stars:  # each slice's points are the two at its levels of u2 and u3, in the band's order
        assert len({float(v) for v in s.get_ydata() // 2}) == 1
