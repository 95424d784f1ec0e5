"""A validation record whose output is held at one level: fit % is undefined there, J_S is not."""

import numpy as np
import pytest

import graybox as gb
from graybox import experiments as gx

ST = gb.Structure(["y(k-1)", "u(k-1)", "1"])
MODEL = gb.Model(ST, [0.5, 0.3, 0.1])


def test_a_level_held_with_round_off_in_its_mean_is_constant():
    # was: 0.8 held for 40 samples has a mean 1 ulp off 0.8, so ‖y − mean‖ ≈ 1e-16 and fit % came out as
    # −1.9e15 instead of undefined
    y = np.full(40, 0.8)
    with pytest.raises(ValueError, match="constant"):
        gb.fit_percent(y, y + 0.1)
    # a real signal far from zero is no constant: 2e5 Pa ± 1 Pa
    yp = 2e5 + np.sin(np.arange(40.0))
    assert np.isfinite(gb.fit_percent(yp, yp + 0.1))


def test_a_grid_cell_with_a_held_validation_output_is_a_row_with_fit_undefined(tmp_path):
    # was: the one-model cell scored fit % as −1.9e15 (and an exactly constant output failed the cell in
    # gb.fit_percent); the Pareto cell's members divided by zero
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 12), 10)
    y = MODEL.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    ident = gb.Record(u[:80], y[:80], Ts=0.1, name="ident")
    ub = np.linspace(0.2, 1.8, 5)
    sp = gb.StaticPoints(ub, MODEL.static_curve(ub), uncertainty=0.05)
    for level in (0.8, 0.0):  # with round-off in its mean, and exactly constant
        valid = gb.Record(np.full(40, 1.0), np.full(40, level), Ts=0.1, name="held")
        grid = gx.Grid([gx.DataSpec("held", dataset=gb.Dataset(ident, valid, sp))],
                       [gx.StructureSpec("s", terms=[str(t) for t in ST])],
                       [gx.Variant("LS", "ls"), gx.Variant("PE", "pe", lambdas=[1.0, 0.5], options={"solver": "closed"})],
                       name="g")
        path = tmp_path / f"held{level}.sqlite"
        gx.run_grid(grid, path, progress=False)
        df = gx.load_results(path)
        assert (df["status"] == "ok").all()
        assert df["fit_valid"].isna().all() and np.isfinite(df["JS_valid"].astype(float)).all()
