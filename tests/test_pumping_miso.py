"""The MISO benchmark plant: two pump sets at independent speeds (issue 15)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from graybox.datasets.pumping import PumpingPlant, speed_reference
from graybox.datasets._pumping_miso import (
    N_IDENT_MISO,
    N_SAMPLES_MISO,
    OPERATING_RANGE,
    STATIC_SPEEDS_MISO,
    TwoSpeedPumpingPlant,
    main,
    static_grid,
    static_grid_experiment,
    two_speed_reference,
    write_miso_csvs,
)

REPO = Path(__file__).resolve().parents[1]
PLANT = TwoSpeedPumpingPlant()
LO, HI = PLANT.rig.speed_range


# -- equal speeds: the bundled rig ---------------------------------------------

def test_equal_speeds_give_the_siso_static_curve():
    n = np.linspace(LO, HI, 27)
    np.testing.assert_allclose(PLANT.static_pressure(n, n), PLANT.rig.static_pressure(n), rtol=0, atol=1e-10)
    np.testing.assert_allclose(PLANT.steady_flow(n, n), PLANT.rig.steady_flow(n), rtol=1e-12)
    q1, q2 = PLANT.steady_flows(n, n)
    np.testing.assert_allclose(q1, q2, rtol=1e-12)


def test_equal_speeds_give_the_siso_run_with_the_same_noise():
    u = speed_reference()[:1500]
    siso = PLANT.rig.simulate(u, seed=7)
    miso = PLANT.simulate(np.column_stack([u, u]), seed=7)
    np.testing.assert_allclose(miso.y, siso.y, rtol=0, atol=1e-9)
    np.testing.assert_allclose(miso.flow, siso.flow, rtol=0, atol=1e-9)
    np.testing.assert_allclose(miso.speed[:, 0], siso.speed, rtol=0, atol=1e-9)
    np.testing.assert_allclose(miso.air_loss, siso.air_loss, rtol=0, atol=1e-12)
    np.testing.assert_allclose(miso.pump_flow, np.column_stack([siso.flow, siso.flow]) / 2, rtol=0, atol=1e-9)


# -- the static surface ----------------------------------------------------------

@settings(max_examples=25, deadline=None)
@given(st.floats(LO, HI), st.floats(LO, HI), st.floats(LO, HI), st.floats(LO, HI))
def test_static_surface_is_the_long_simulated_steady_state(n1, n2, m1, m2):
    # start at the equilibrium of another pair of speeds, step both references, wait 90 s
    # (about 70 of the slowest time constants) without noise
    assume(abs(n1 - m1) + abs(n2 - m2) > 1.0)
    u = np.column_stack([np.full(1800, n1), np.full(1800, n2)])
    run = PLANT.simulate(u, noise=False, process_noise=False, x0=PLANT.steady_state(m1, m2))
    assert run.pressure[-1] == pytest.approx(float(PLANT.static_pressure(n1, n2)), abs=1e-7)
    q1, q2 = PLANT.steady_flows(n1, n2)
    np.testing.assert_allclose(run.pump_flow[-1], [q1, q2], rtol=0, atol=1e-6)


def test_surface_callable():
    surf = PLANT.surface()
    U = static_grid()
    np.testing.assert_array_equal(surf(U), PLANT.static_pressure(U[:, 0], U[:, 1]))
    assert surf.domain == (OPERATING_RANGE, OPERATING_RANGE) and surf(np.array([1200.0, 1300.0])).shape == (1,)
    with pytest.raises(ValueError, match=r"shape \(K, 2\)"):
        surf(np.ones((2, 3)))


def test_static_surface_rises_with_each_speed_in_the_operating_range():
    g = np.linspace(*OPERATING_RANGE, 41)
    P = PLANT.static_pressure(g[:, None], g[None, :])
    assert P.shape == (41, 41)
    assert np.all(np.diff(P, axis=0) > 0) and np.all(np.diff(P, axis=1) > 0)
    np.testing.assert_allclose(P, P.T, rtol=1e-13)  # identical pump sets
    q1, q2 = PLANT.steady_flows(g[:, None], g[None, :])
    assert q1.min() > 5.0 and q2.min() > 5.0  # both valves open everywhere in the operating range


def test_static_surface_is_flat_in_the_slower_speed_while_its_valve_is_shut():
    g = np.linspace(LO, HI, 53)
    P = PLANT.static_pressure(g[:, None], g[None, :])
    assert np.all(np.diff(P, axis=0) >= -1e-12) and np.all(np.diff(P, axis=1) >= -1e-12)
    q1, _ = PLANT.steady_flows(800.0, 1650.0)
    assert q1 == 0.0  # the 800 rpm pump cannot lift water against the 1650 rpm pump's header
    P_alone = PLANT.static_pressure(np.array([600.0, 700.0, 800.0]), 1650.0)
    np.testing.assert_allclose(P_alone, P_alone[0], rtol=0, atol=1e-12)
    assert PLANT.static_pressure(1300.0, 1650.0) > P_alone[0] + 1.0


def test_static_grid_experiment_scatters_around_the_surface():
    pts = static_grid_experiment(PLANT, seed=3)
    ubar, ybar = pts.ubar, pts.ybar
    assert ubar.shape == (36, 2) and ybar.shape == (36,) and pts.input_names == ("u1", "u2")
    assert {tuple(p) for p in ubar} == {(a, b) for a in STATIC_SPEEDS_MISO for b in STATIC_SPEEDS_MISO}
    assert np.all(np.abs(np.diff(ubar, axis=0)).sum(axis=1) == 100.0)  # one grid step per move
    err = ybar - PLANT.static_pressure(ubar[:, 0], ubar[:, 1])
    std = PLANT.rig.static_point_std(1400.0, 120)  # the SISO rig's, same noise at a similar flow
    assert np.abs(err).max() < 5 * std
    assert 0.5 * std < err.std() < 2 * std


# -- never fails in the operating range -------------------------------------------

def _staircase_from(levels, holds):
    return np.repeat(np.asarray(levels, dtype=float), holds)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    levels1=st.lists(st.floats(LO, HI), min_size=2, max_size=8),
    levels2=st.lists(st.floats(LO, HI), min_size=2, max_size=8),
    hold=st.integers(5, 120),
    seed=st.integers(0, 2**32 - 1),
    harsh=st.booleans(),
)
def test_simulator_never_fails_within_its_speed_range(levels1, levels2, hold, seed, harsh):
    u1 = _staircase_from(levels1, hold)
    u2 = _staircase_from(levels2, hold + 7)
    n = min(u1.size, u2.size)
    assume(n >= 10)
    # harsh: a surge ten times stronger and 5x the air, so valves shut and the column stops
    rig = PumpingPlant(surge_intensity=0.055, air_loss_per_rpm=4e-4) if harsh else PumpingPlant()
    run = TwoSpeedPumpingPlant(rig=rig).simulate(np.column_stack([u1[:n], u2[:n]]), seed=seed)
    for a in (run.y, run.pressure, run.flow, run.pump_flow, run.speed, run.air_loss, run.surge):
        assert np.all(np.isfinite(a))
    assert run.flow.min() >= 0.0 and run.pump_flow.min() >= 0.0 and run.pressure.min() >= 0.0
    np.testing.assert_allclose(run.pump_flow.sum(axis=1), run.flow, rtol=1e-12, atol=1e-12)
    assert run.air_loss.max() <= 1.0


def test_valves_shut_and_the_column_stops_under_harsh_disturbances():
    # a surge ten times stronger and 5x the air: the slower pump's valve shuts, now and then the
    # whole column stops (p = 0), and it restarts; nothing is NaN and no flow is negative
    rig = PumpingPlant(surge_intensity=0.055, air_loss_per_rpm=4e-4)
    rng = np.random.default_rng(0)
    u = np.column_stack([np.repeat(rng.uniform(LO, HI, 12), 60), np.repeat(rng.uniform(LO, HI, 12), 60)])
    run = TwoSpeedPumpingPlant(rig=rig).simulate(u, seed=0)
    assert np.all(np.isfinite(run.y)) and run.pump_flow.min() >= 0.0
    shut = (run.pump_flow == 0.0).any(axis=1)
    assert shut.any() and not shut.all()
    stopped = np.flatnonzero(run.flow == 0.0)
    assert stopped.size and np.all(run.pressure[stopped] == 0.0) and run.flow[stopped[-1]:].max() > 10.0


def test_a_stopped_column_restarts():
    # from rest (no flow) at full speed the column accelerates to the steady state
    u = np.full((600, 2), 1400.0)
    run = PLANT.simulate(u, noise=False, process_noise=False, x0=(1400.0, 1400.0, 1400.0, 1400.0, 0.0))
    assert run.flow[0] == 0.0
    assert run.pressure[-1] == pytest.approx(float(PLANT.static_pressure(1400.0, 1400.0)), abs=1e-6)


# -- input design and files -----------------------------------------------------

def _change_instants(x):
    return set(np.flatnonzero(np.diff(x)) + 1)


def test_two_speed_reference():
    u = two_speed_reference()
    assert u.shape == (N_SAMPLES_MISO, 2)
    assert np.all((u >= OPERATING_RANGE[0]) & (u <= OPERATING_RANGE[1])) and np.all(u % 10 == 0)
    for part in (u[:N_IDENT_MISO], u[N_IDENT_MISO:]):
        for i in (0, 1):  # both parts visit both ends of the range with both references
            assert part[:, i].min() <= OPERATING_RANGE[0] + 30 and part[:, i].max() >= OPERATING_RANGE[1] - 30
    c1, c2 = _change_instants(u[:, 0]), _change_instants(u[:, 1])
    assert len(c1) >= 30 and len(c2) >= 30 and len(c1 & c2) <= 2  # independent staircases
    assert abs(np.corrcoef(u[:, 0], u[:, 1])[0, 1]) < 0.3
    np.testing.assert_array_equal(u, two_speed_reference())
    assert not np.array_equal(u, two_speed_reference(seed=3))


def test_static_grid_is_a_serpentine():
    g = static_grid(speeds1=[1.0, 2.0, 3.0], speeds2=[10.0, 20.0])
    np.testing.assert_array_equal(g, [[1, 10], [1, 20], [2, 20], [2, 10], [3, 10], [3, 20]])


def test_regenerated_files_match_the_committed_ones(tmp_path):
    # as for the SISO files: exact speeds and times, pressures to one unit of the 4th decimal
    from conftest import assert_csv_pair_matches

    dyn, sta = write_miso_csvs(tmp_path)
    assert_csv_pair_matches(dyn, sta, REPO / "data" / "pumping_miso", (4, 3))


def test_main_writes_to_out(tmp_path, capsys):
    assert main(["--out", str(tmp_path / "x"), "--seed", "3"]) == 0
    assert (tmp_path / "x" / "dynamic.csv").is_file() and (tmp_path / "x" / "static.csv").is_file()
    assert "wrote" in capsys.readouterr().out


# -- bad input -----------------------------------------------------------------

@pytest.mark.parametrize("u, match", [
    (np.full(10, 1200.0), r"shape \(N, 2\)"),
    (np.full((10, 3), 1200.0), r"shape \(N, 2\)"),
    (np.c_[np.full(10, 1200.0), np.full(10, 1900.0)], "speed reference 2 must stay within"),
    (np.c_[np.full(10, np.nan), np.full(10, 1200.0)], "speed reference 1"),
])
def test_bad_references(u, match):
    with pytest.raises(ValueError, match=match):
        PLANT.simulate(u, noise=False, process_noise=False)


def test_bad_calls():
    u = np.full((10, 2), 1200.0)
    with pytest.raises(ValueError, match="pass seed"):
        PLANT.simulate(u)
    with pytest.raises(ValueError, match="x0 must be 5 finite numbers"):
        PLANT.simulate(u, noise=False, process_noise=False, x0=(1200.0, 1200.0, 40.0))
    with pytest.raises(ValueError, match="speed2 must stay within"):
        PLANT.static_pressure(1200.0, 100.0)
    with pytest.raises(TypeError, match="rig must be a PumpingPlant"):
        TwoSpeedPumpingPlant(rig="rig")
    with pytest.raises(ValueError, match=r"shape \(K, 2\)"):
        static_grid_experiment(PLANT, speeds=[1200.0, 1300.0], seed=1)


# -- the bundled data set ---------------------------------------------------------

def test_load_pumping_miso():
    import graybox as gb

    ds = gb.load_pumping_miso()
    assert ds.input_names == ("u1", "u2") and ds.Ts == 0.05
    assert ds.ident.u.shape == (N_IDENT_MISO, 2) and ds.valid.u.shape == (N_SAMPLES_MISO - N_IDENT_MISO, 2)
    assert ds.static.ubar.shape == (36, 2) and ds.ident.units == ("rpm", "mlc")
    run = PLANT.simulate(two_speed_reference(), seed=np.random.default_rng([2011, 13]))
    np.testing.assert_array_equal(ds.ident.u, run.u[:N_IDENT_MISO])
    np.testing.assert_allclose(ds.valid.y, run.y[N_IDENT_MISO:], rtol=0, atol=5.01e-5)  # 4 decimals in the file
    rec = run.record()
    assert rec.input_names == ("u1", "u2") and rec.u.shape == (N_SAMPLES_MISO, 2)
    surf = ds.extra["static_surface"]
    err = ds.static.ybar - surf(ds.static.ubar)
    assert np.abs(err).max() < 0.15 and ds.extra["plant"] == PLANT
    assert "not a measured plant" in ds.description
