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
