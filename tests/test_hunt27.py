"""Bugs found by a bug hunt from model to controller (graybox.control) and in growing grids
(graybox.experiments): each test fails without its fix."""

import warnings

import numpy as np
import pytest

import graybox as gb

#: y(k) = 0.5 y(k-1) + s(k-1): one input named "speed", gain 2.
SPEED = gb.Model(["y(k-1)", "speed(k-1)"], [0.5, 1.0], input_names=("speed",))


def two_input_record(n: int = 200) -> gb.Record:
    """A record of two inputs, "valve" in [0, 1] and "speed" in [5, 10], whose output SPEED explains."""
    rng = np.random.default_rng(0)
    valve, speed = rng.uniform(0.0, 1.0, n), rng.uniform(5.0, 10.0, n)
    return gb.Record(np.column_stack([valve, speed]), SPEED.simulate(speed, np.zeros(1)), 1.0,
                     input_names=("valve", "speed"))


def test_range_of_a_one_input_model_is_read_from_its_own_input_of_the_record():
    # the range check took a one-input model's range from every column of the record: a record with a
    # second input was refused, and a record whose one input has another name gave that input's range
    rec = two_input_record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lm = gb.local_model(SPEED, 7.0, data=rec)  # inside the speed's range [5, 10]: no warning
    assert lm.reached and lm.dc_gain[0] == pytest.approx(2.0)
    with pytest.warns(gb.StaticRangeWarning, match="outside the input range"):
        gb.local_model(SPEED, 0.5, data=rec)  # inside the valve's range, outside the speed's
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        oc = gb.operating_curve(SPEED, [6.0, 8.0], data=rec)
    assert np.allclose(oc.gain, 2.0)
    other = gb.Record(rec.input("valve"), rec.y, 1.0, input_names=("valve",))
    with pytest.raises(ValueError, match="speed"):
        gb.local_model(SPEED, 0.5, data=other)


def test_two_input_operating_curve_frame_keeps_the_gain_bands():
    # to_frame kept only one-dimensional bands: a two-input curve's gain bands were silently left out
    two = gb.Model(["1", "y(k-1)", "u1(k-1)", "u2(k-1)", "u1(k-1)u2(k-1)"], [0.2, 0.5, 0.3, -0.2, 0.05],
                   input_names=("u1", "u2"))
    rng = np.random.default_rng(1)
    U = np.column_stack([rng.uniform(0.5, 1.5, 400), rng.uniform(0.2, 0.8, 400)])
    rec = gb.Record(U, two.simulate(U, np.zeros(1)) + 0.01 * rng.standard_normal(400), 0.1,
                    input_names=("u1", "u2"))
    model = gb.els(two.structure, rec, noise=0).model
    oc = gb.operating_curve(model, [[1.0, 0.5], [1.2, 0.4]], data=rec,
                            uncertainty=gb.ls_uncertainty(model, rec), n_samples=50)
    frame = oc.to_frame()
    for i, name in enumerate(("u1", "u2")):
        assert np.array_equal(frame[f"gain low {name}"], oc.gain_low[:, i])
        assert np.array_equal(frame[f"gain high {name}"], oc.gain_high[:, i])
    assert np.array_equal(frame["time constant low"], oc.time_constant_low)


def saturated_record(seed: int, n: int = 400) -> gb.Record:
    """An unstable first-order system held by a saturation: y(k) = clip(1.5 y(k-1) + u(k-1), ±3)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-0.1, 0.1, n)
    y = np.zeros(n)
    y[0] = 1.0
    for k in range(1, n):
        y[k] = np.clip(1.5 * y[k - 1] + u[k - 1], -3.0, 3.0)
    return gb.Record(u, y + 0.001 * rng.standard_normal(n), 1.0)


def test_leaderboard_says_why_when_a_pareto_member_failed(tmp_path):
    # a member whose fit failed was counted as a model "with an undefined static curve", and the
    # reason its fit failed, kept in the store, was said nowhere
    from graybox import experiments as gx

    data = gb.Dataset(saturated_record(0), saturated_record(1),
                      gb.StaticPoints([-0.1, 0.0, 0.1], [-2.0, 0.0, 2.0], uncertainty=0.1))
    ga = gx.Variant("GA", "se-ga", lambdas=[0.1, 1.0],
                    options={"population": 6, "generations": 1, "theta0": "none", "margin": "none"})
    grid = gx.Grid([gx.DataSpec("saturated", dataset=data)],
                   [gx.StructureSpec("cubic", terms=["y(k-1)", "u(k-1)", "y(k-1)^3"])], [ga], name="g")
    gx.run_grid(grid, tmp_path / "s.sqlite")
    df = gb.load_results(tmp_path / "s.sqlite")
    failure = [f for f in df["members"].iloc[0]["failure"] if f]
    assert len(failure) == 1  # the set-up: one of the two members failed
    row = gx.leaderboard(df).iloc[0]
    assert row["candidates"] == 1  # the one model that was fitted
    assert "1 member fit(s) failed" in row["reason"] and failure[0][:60] in row["reason"]
    assert "every one of the 2 model(s)" not in row["reason"]


def test_local_models_of_different_sampling_periods_are_drawn_on_their_own_time_and_frequency_axes():
    # every response was drawn on the first model's time grid and its frequencies up to the first
    # model's Nyquist frequency: a slower-sampled model's step was squeezed in time and its Bode
    # diagram aliased beyond its own Nyquist frequency
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    fast, slow = gb.local_model(model, 1.0, Ts=0.1), gb.local_model(model, 1.0, Ts=1.0)
    fig = gb.plots.plot_local_models([fast, slow], duration=5.0)
    steps, bode = fig.axes[0].get_lines(), fig.axes[1].get_lines()
    for lm, step, mag in zip((fast, slow), steps, bode):
        t = np.asarray(step.get_xdata())
        assert np.allclose(np.diff(t), lm.Ts) and t[-1] == pytest.approx(5.0)
        assert np.allclose(step.get_ydata(), lm.step(t.size))
        w = np.asarray(mag.get_xdata())
        assert w.max() == pytest.approx(np.pi / lm.Ts)
        assert np.allclose(mag.get_ydata(), np.abs(lm.frequency_response(w)))


def test_a_cell_another_run_wrote_meanwhile_is_kept_and_the_run_goes_on(tmp_path):
    # two runs into one store (a resume started while the first still runs, or two grids sharing
    # cells): the second to finish a cell crashed with sqlite3.IntegrityError and ran no further
    from graybox import experiments as gx

    structures = [gx.StructureSpec("first", terms=["y(k-1)", "u(k-1)", "1"]),
                  gx.StructureSpec("second", terms=["y(k-1)", "y(k-2)", "u(k-1)", "1"])]
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structures, [gx.Variant("LS", "ls")], name="g")
    store = tmp_path / "s.sqlite"
    other: list = []

    def meanwhile(line: str) -> None:  # called once the run knows which cells to run, before any runs
        if not other:
            other.append(gx.run_grid(grid, store))

    run = gx.run_grid(grid, store, log=meanwhile)
    assert other[0].ran == 2 and run.counts["ok"] == 2
    assert any("another run" in n for n in run.notes)
    df = gb.load_results(store)
    assert len(df) == 2 and (df["status"] == "ok").all()


def _scaled_theta(structure: gb.Structure, theta: np.ndarray, cu: float, cy: float) -> np.ndarray:
    """θ of the same model with u in units cu times smaller and y in units cy times smaller."""
    out = []
    for t, v in zip(structure, theta):
        py = sum(p for s, _, p in t.factors if s == "y")
        pu = sum(p for s, _, p in t.factors if s != "y")
        out.append(v * cy / (cy**py * cu**pu))
    return np.array(out)


@pytest.mark.parametrize("cy", [1e-3, 1e3])
def test_pe_with_inequality_constraints_does_not_depend_on_the_output_units(cy):
    # Clarabel's tolerances and starting point are absolute, and its QP was in output units: with the
    # output in mV instead of V the front moved (J_S of the λ1 = 1e-3 member 25 % off)
    d = gb.load_pumping()
    cu = 1e3

    def scaled(r: gb.Record) -> gb.Record:
        return gb.Record(r.u * cu, r.y * cy, r.Ts, r.name)

    other = gb.Dataset(scaled(d.ident), scaled(d.valid),
                       gb.StaticPoints(d.static.ubar * cu, d.static.ybar * cy, uncertainty=d.static.uncertainty * cy))
    st = gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)y(k-1)", "1"])
    lam = [1e-3, 1e-2, 1e-1, 1.0]
    a = gb.pe_pareto(st, d, lambdas=lam, constraints=gb.GainBounds(lower=0))
    b = gb.pe_pareto(st, other, lambdas=lam, constraints=gb.GainBounds(lower=0))
    assert np.allclose(b.JS, a.JS * cy**2, rtol=1e-6)
    assert np.allclose(b.JSF, a.JSF * cy**2, rtol=1e-6)
    for ta, tb in zip(a.thetas, b.thetas):
        assert np.allclose(_scaled_theta(st, ta, cu, cy), tb, rtol=1e-5)


def test_monte_carlo_bands_do_not_depend_on_the_units():
    # the draws θ ~ N(θ̂, cov) came from the eigenvectors of cov itself, whose entries span decades in
    # engineering units: the eigensolver's round-off, of the size of the largest entry, swamped the
    # small-scale parameters, and the bands changed with the units (the gain's lower bound 3-7x)
    d = gb.load_pumping()
    cu, cy = 1e3, 1e-3
    st = gb.parse_structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"])
    other = gb.Record(d.ident.u * cu, d.ident.y * cy, d.ident.Ts)
    a, b = gb.els(st, d.ident, noise=0).model, gb.els(st, other, noise=0).model
    ua, ub = gb.ls_uncertainty(a, d.ident), gb.ls_uncertainty(b, other)
    grid = np.linspace(900.0, 1500.0, 4)
    oa = gb.operating_curve(a, grid, Ts=d.Ts, uncertainty=ua, n_samples=200)
    ob = gb.operating_curve(b, grid * cu, Ts=d.Ts, uncertainty=ub, n_samples=200)
    for lo_hi in ("gain_low", "gain_high"):
        assert np.allclose(getattr(ob, lo_hi), getattr(oa, lo_hi) * cy / cu, rtol=1e-6)
    for lo_hi in ("time_constant_low", "time_constant_high"):
        assert np.allclose(getattr(ob, lo_hi), getattr(oa, lo_hi), rtol=1e-6)
    sa = gb.static_curve_band(ua, grid, method="monte-carlo", n_samples=200)
    sb = gb.static_curve_band(ub, grid * cu, method="monte-carlo", n_samples=200)
    assert np.allclose(sb.ybar_low, sa.ybar_low * cy, rtol=1e-6)
    assert np.allclose(sb.gain_low, sa.gain_low * cy / cu, rtol=1e-6)
