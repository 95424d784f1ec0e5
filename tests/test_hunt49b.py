"""hunt49b: from model to controller and the signals (control, inputs, decimation, plants, reference)."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb
from graybox.datasets import TwoSpeedPumpingPlant
from graybox.datasets.pumping import PumpingPlant

QUIET = {"noise": False, "process_noise": False}


@pytest.mark.parametrize("x0,error,match", [
    ((1200.0, 1200.0), ValueError, "x0 must be 3"),                    # numpy's 'not enough values to unpack'
    ((1200.0, 1200.0, 40.0, 1.0), ValueError, "x0 must be 3"),         # 'too many values to unpack (expected 3)'
    (1200.0, ValueError, "x0 must be 3"),                               # "'float' object is not iterable"
    ("123", TypeError, "x0"),                                           # read as the state (1, 2, 3)
    ((1200.0, 1200.0, "40"), TypeError, "x0"),                          # the flow parsed from text
    ((1200.0, 1200.0, True), TypeError, "x0"),                          # a flow of 1 L/s
    ({"a": 1, "b": 2, "c": 3}, TypeError, "x0"),                         # 'could not convert string to float'
    ((1200.0, np.nan, 40.0), ValueError, "x0 must be 3 finite"),
    ((1200.0, 1200.0, -1.0), ValueError, "Q >= 0"),
])
def test_plant_initial_state_is_three_numbers(x0, error, match):
    # simulate and closed_loop unpacked x0 with (float(x) for x in x0): a wrong length failed in Python's words
    # naming nothing, text was parsed and a bool taken for a number; the two-speed rig took text and bools too
    plant = PumpingPlant()
    with pytest.raises(error, match=match):
        plant.simulate(np.full(5, 1200.0), x0=x0, **QUIET)
    with pytest.raises(error, match=match):
        plant.closed_loop(lambda k, y: 1200.0, 5, u0=1200.0, x0=x0, **QUIET)
    run = plant.simulate(np.full(5, 1200.0), x0=np.array(plant.steady_state(1200.0)), **QUIET)
    assert run.y == pytest.approx(plant.simulate(np.full(5, 1200.0), **QUIET).y)


@pytest.mark.parametrize("x0,error", [((1200.0, 1200.0, 1100.0, 1100.0, "40"), TypeError),
                                      ((1200.0, 1200.0, 1100.0, 1100.0, True), TypeError),
                                      ("12345", TypeError), (1200.0, ValueError)])
def test_two_speed_initial_state_is_five_numbers(x0, error):
    with pytest.raises(error, match="x0"):
        TwoSpeedPumpingPlant().simulate(np.full((5, 2), 1200.0), x0=x0, **QUIET)


def test_reference_tables_are_read_only():
    # TABLE_II's and TABLE_III's arrays were writeable and the tables plain dicts: `th = TABLE_II["ELS"]; th *= 2`
    # doubled every θ of every later paper_model(15), and TABLE_I's rows could be edited, changing what
    # graybox reproduce compares against
    from graybox import reference

    before = reference.paper_model(15).theta.copy()
    for table in (reference.TABLE_II, reference.TABLE_III):
        with pytest.raises(ValueError, match="read-only"):
            table["ELS"] *= 2
        with pytest.raises(ValueError, match="read-only"):
            table["ELS"][0] = 1.0
        with pytest.raises(TypeError):
            table["ELS"] = np.zeros(3)
    with pytest.raises(TypeError):
        reference.TABLE_I["ELS (15)"]["JSF"] = 0.0
    with pytest.raises(TypeError):
        reference.TABLE_I["mine"] = {}
    assert np.array_equal(reference.paper_model(15).theta, before)
    assert reference.TABLE_I["ELS (15)"]["JSF"] == 1.604
    assert dict(reference.TABLE_I["Neural"])["n_params"] == 99


def test_paper_model_checks_its_arguments():
    from graybox import reference

    # a switch that is no bool ('no' is truthy) gave the misprinted column the caller meant to refuse
    with pytest.raises(TypeError, match="allow_misprinted"):
        reference.paper_model(15, "SE", allow_misprinted="no")
    with pytest.raises(TypeError, match="column"):  # was 'unhashable type: list'
        reference.paper_model(15, ["ELS"])
    with pytest.raises(ValueError, match="Table II has columns"):
        reference.paper_model(15, "GA")
    with pytest.raises(ValueError, match="eq. 15 and eq. 17"):
        reference.paper_model(16)
    with pytest.raises(TypeError, match="equation"):
        reference.paper_model("15")
    assert reference.paper_model(np.int64(17), "PE").name == "PE (17) [paper]"
    assert reference.paper_model(15.0).name == "ELS (15) [paper]"  # was 'ELS (15.0) [paper]'
    assert reference.paper_model(15, "SE", allow_misprinted=True).n_params == 17


def test_plant_steady_state_is_inside_the_calibrated_range():
    # steady_state(100) returned a flow from the calibrated formula R Q² = (h0 − β) n² − α n − κ at a speed the rig
    # refuses (below speed_range[0] its turbine follows the low-flow branch, so that is no equilibrium), and
    # steady_state('1200') parsed text
    plant = PumpingPlant()
    with pytest.raises(ValueError, match="500–1800 rpm"):
        plant.steady_state(100.0)
    with pytest.raises(ValueError, match="non-finite"):
        plant.steady_state(np.nan)
    with pytest.raises(TypeError, match="speed"):
        plant.steady_state("1200")
    with pytest.raises(TypeError, match="speed"):
        TwoSpeedPumpingPlant().steady_state("1200", 1100.0)
    with pytest.raises(TypeError, match="speed1"):
        TwoSpeedPumpingPlant().static_pressure(True, 1100.0)
    assert plant.steady_state(1200.0)[:2] == (1200.0, 1200.0)
    run = plant.simulate(np.full(400, 1200.0), **QUIET)
    assert run.flow[-1] == pytest.approx(plant.steady_state(1200.0)[2], rel=1e-9)


def test_step_time_constant_checks_speed_and_horizon():
    plant = PumpingPlant()
    with pytest.raises(TypeError, match="speed"):  # was "can only concatenate str (not 'float') to str"
        plant.step_time_constant("1200")
    with pytest.raises(ValueError, match="500–1800 rpm"):
        plant.step_time_constant(100.0)
    with pytest.raises(ValueError, match="horizon"):  # was numpy's MemoryError for 149 GiB
        plant.step_time_constant(1200.0, horizon=1e9)
    assert 0.3 < plant.step_time_constant(1200.0) < 2.0


@pytest.mark.parametrize("fields", [
    (2, (1, 3), 30, 30, 30),        # τ_m = 30 allows 2..3 and advises 2
    (3, (2, 3), 30, 30, 30),        # the rule's q for τ_m = 30 is round(30 / 15) = 2
    (1, (1, 1), 30, 30, 30),
    (5, (4, 7), 90, 90, 90),        # the bundled plant's range and q with another τ_m (90: 5..9, q 6)
])
def test_decimation_advice_holds_q_to_the_rule(fields):
    # DecimationAdvice checked tau_m = min(tau_y, tau_y2) and q inside q_range, but not that q_range and q are the
    # rule's for tau_m: a hand-edited file (q = 3 where τ_m = 30 gives 2; q_range = (1, 3) for (2, 3)) loaded
    # as advice the rule never gives
    q, q_range, ty, ty2, tm = fields
    with pytest.raises(ValueError, match="rule"):
        gb.DecimationAdvice(q, q_range, ty, ty2, tm, 0.05)


def test_decimation_advice_without_minimum_has_no_tau():
    with pytest.raises(ValueError, match="rule"):
        gb.DecimationAdvice(None, None, 30, 30, 30, 0.05, "no minimum")
    gb.DecimationAdvice(None, None, None, None, None, 0.05, "no minimum")
    adv = gb.decimation_advice(gb.load_pumping())
    assert (adv.q, adv.q_range) == (5, (4, 7))
    assert gb.DecimationAdvice(adv.q, adv.q_range, adv.tau_y, adv.tau_y2, adv.tau_m, adv.Ts) == adv


def test_speed_reference_draws_its_holds_with_a_running_total(monkeypatch):
    # _staircase summed the growing list of holds at each draw, quadratic in their number: 4·10⁶ samples took 4.7 s
    # and 4·10⁷ (23 days at 0.05 s) about 8 minutes; the same draws, so every seed gives the reference it gave
    from graybox.datasets import pumping

    ref = pumping.speed_reference(n_samples=3000, n_ident=2000, seed=7)
    assert ref.shape == (3000,) and np.all(ref % 10 == 0)
    assert np.array_equal(ref, pumping.speed_reference(n_samples=3000, n_ident=2000, seed=7))
    summed = []

    def counted_sum(*args, **kwargs):  # the module's sum, before the builtin
        summed.append(1)
        return sum(*args, **kwargs)

    monkeypatch.setattr(pumping, "sum", counted_sum, raising=False)
    assert np.array_equal(ref, pumping.speed_reference(n_samples=3000, n_ident=2000, seed=7))
    assert len(summed) <= 2  # not once per hold (37 holds here)


def test_bundled_plant_run_is_the_committed_one():
    # the bundled dynamic record is speed_reference(seed=2011) run on the plant: the running total draws the same
    from graybox.datasets import pumping

    data = gb.load_pumping()
    u = pumping.speed_reference()
    assert np.array_equal(u, np.concatenate([data.ident.u, data.valid.u]))


@pytest.mark.parametrize("call", ["static_experiment", "generate", "static_grid_experiment", "generate_miso"])
def test_static_experiment_and_generate_name_a_plant_that_is_none(call):
    # each failed on the object's first missing attribute: AttributeError "'str' object has no attribute 'Ts'"
    from graybox.datasets import _pumping_miso, pumping

    calls = {"static_experiment": lambda p: pumping.static_experiment(p, seed=1),
             "generate": lambda p: pumping.generate(plant=p),
             "static_grid_experiment": lambda p: _pumping_miso.static_grid_experiment(p, seed=1),
             "generate_miso": lambda p: _pumping_miso.generate_miso(plant=p)}
    kind = "TwoSpeedPumpingPlant" if "miso" in call or "grid" in call else "PumpingPlant"
    with pytest.raises(TypeError, match=f"plant must be a {kind}, got str"):
        calls[call]("rig")
    other = PumpingPlant() if kind == "TwoSpeedPumpingPlant" else TwoSpeedPumpingPlant()
    with pytest.raises(TypeError, match=f"plant must be a {kind}"):
        calls[call](other)


@pytest.mark.parametrize("seed,error", [(True, TypeError), (-1, ValueError), (1.5, TypeError), ("3", TypeError),
                                        ([1, 2], TypeError)])
def test_plant_seed_is_an_int_or_a_generator(seed, error):
    # the rigs handed seed straight to numpy's default_rng: True ran as seed 1 (and [1, 2] as a seed sequence), and
    # -1, 1.5 and '3' failed in numpy's words ('expected non-negative integer', 'SeedSequence expects int or
    # sequence of ints for entropy not 3'), naming no argument
    from graybox.datasets import pumping

    plant = PumpingPlant()
    u = np.full(5, 1200.0)
    with pytest.raises(error, match="seed"):
        plant.simulate(u, seed=seed)
    with pytest.raises(error, match="seed"):
        plant.closed_loop(lambda k, y: 1200.0, 5, u0=1200.0, seed=seed)
    with pytest.raises(error, match="seed"):
        TwoSpeedPumpingPlant().simulate(np.full((5, 2), 1200.0), seed=seed)
    with pytest.raises(error, match="seed"):
        pumping.static_experiment(plant, seed=seed, settle=1.0, average=1.0)


def test_plant_seed_reproduces():
    plant = PumpingPlant()
    u = gb.design_input("aprbs", 300, low=800.0, high=1600.0, hold=(10, 40), seed=3)
    a = plant.simulate(u, seed=5)
    assert np.array_equal(a.y, plant.simulate(u, seed=np.int64(5)).y)
    assert np.array_equal(a.y, plant.simulate(u, seed=np.random.default_rng(5)).y)
    assert np.array_equal(a.y, plant.closed_loop(lambda k, y: u[k], 300, u0=u[0], seed=5).y)
    assert not np.array_equal(a.y, plant.simulate(u, seed=6).y)


def test_frequency_response_at_a_pole_on_the_unit_circle_is_infinite_without_a_warning():
    # an integrator's response at ω = 0 (its pole at z = 1) divided by zero with numpy's RuntimeWarning, where
    # dc_gain says inf quietly
    import warnings

    integ = gb.Model(["1", "y(k-1)", "u(k-1)"], [-0.5, 1.0, 0.5], name="integ")
    lm = gb.local_model(integ, 1.0, Ts=0.1, y0=3.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g = lm.frequency_response([0.0, 1.0])
        assert lm.dc_gain[0] == np.inf
    assert np.abs(g[0]) == np.inf
    assert np.isfinite(g[1]) and abs(g[1]) == pytest.approx(abs(0.5 / (np.exp(0.1j) - 1.0)))


@pytest.mark.parametrize("kw,error,match", [
    ({"Ts": True, "dead_time": 0.0}, TypeError, "Ts"),             # a 1 s period, silently
    ({"substeps": True, "dead_time": 0.0}, TypeError, "substeps"),
    ({"inertia": True}, TypeError, "inertia"),
    ({"ramp_up": True}, ValueError, "ramp_up"),                     # a ramp of 1 rpm/s (a ValueError, as for 'fast')
    ({"process_noise_pole": True}, TypeError, "process_noise_pole"),
    ({"static_coefficients": (1.0, 2.0)}, ValueError, "static_coefficients"),  # 'not enough values to unpack'
    ({"static_coefficients": "abc"}, TypeError, "static_coefficients"),        # 'could not convert string to float'
    ({"speed_range": (500.0,)}, ValueError, "speed_range"),                    # 'not enough values to unpack'
    ({"speed_range": ("500", "1800")}, TypeError, "speed_range"),              # "'<' not supported …"
    ({"speed_range": (500.0, np.inf)}, ValueError, "speed_range"),            # references of any speed above 500 rpm
])
def test_pumping_plant_refuses_constants_that_are_no_numbers(kw, error, match):
    with pytest.raises(error, match=f"PumpingPlant: {match}"):
        PumpingPlant(**kw)


def test_pumping_plant_takes_numpy_numbers():
    # np.float32(0.15) was refused as 'inertia must be a positive finite number'
    plant = PumpingPlant(inertia=np.float32(0.15), substeps=np.int64(10), static_coefficients=np.array(PumpingPlant().
                         static_coefficients), speed_range=[500, 1800])
    assert plant.speed_range == (500.0, 1800.0) and isinstance(plant.static_coefficients, tuple)
    hash(plant)
    u = np.full(20, 1200.0)
    assert plant.simulate(u, **QUIET).y == pytest.approx(PumpingPlant().simulate(u, **QUIET).y, rel=1e-6)


@pytest.mark.parametrize("bad", [["1200", "1100"], [[True, 1200.0]], None, {"a": 1}])
def test_plant_surface_refuses_what_is_no_speeds(bad):
    # PlantSurface read ū with np.asarray(dtype=float): text was parsed (['1200', '1100'] gave 9.94 mlc), True was 1 rpm,
    # None 'must have shape (K, 2), got ()' and a dict numpy's "float() argument must be …"
    surface = TwoSpeedPumpingPlant().surface()
    with pytest.raises(TypeError, match="ubar"):
        surface(bad)
    assert surface([1200.0, 1100.0]) == pytest.approx(TwoSpeedPumpingPlant().static_pressure([1200.0], [1100.0]))


@pytest.mark.parametrize("kw", [{"settle": 1e9}, {"average": 1e9}, {"average": 1e300}])
def test_static_experiment_refuses_a_run_no_memory_holds(kw):
    # settle=1e9 s ended in numpy's MemoryError (1.46 TiB; 10.5 TiB on the two-speed rig) and average=1e300 in
    # "OverflowError: Python int too large to convert to C long", after the other checks
    from graybox.datasets import pumping
    from graybox.datasets._pumping_miso import static_grid_experiment

    with pytest.raises(ValueError, match="settle|average"):
        pumping.static_experiment(PumpingPlant(), seed=1, **kw)
    with pytest.raises(ValueError, match="settle|average"):
        static_grid_experiment(TwoSpeedPumpingPlant(), seed=1, **kw)


@pytest.mark.parametrize("kw", [{"seed": 1}, QUIET, {"x0": (1200.0, 1200.0, 40.0), **QUIET}])
def test_plant_refuses_an_empty_reference(kw):
    # simulate([]) failed with a bare 'IndexError: index 0 is out of bounds for axis 0 with size 0' (reading u[0] for
    # the initial equilibrium), and with x0 returned a run of no samples; the two-speed rig refuses N = 0 by name
    with pytest.raises(ValueError, match="speed reference"):
        PumpingPlant().simulate([], **kw)


def test_plant_statics_read_speeds_as_simulate_does():
    # static_pressure and steady_flow read speed with np.asarray(dtype=float): '1200' was parsed, True was 1 rpm, NaN
    # gave NaN, and steady_flow below speed_range[0] gave the calibrated formula's flow (no equilibrium there: the
    # low-flow branch holds) or, lower still, NaN with numpy's 'invalid value encountered in sqrt'
    import warnings

    plant = PumpingPlant()
    for f in (plant.static_pressure, plant.steady_flow):
        with pytest.raises(TypeError, match="speed"):
            f("1200")
        with pytest.raises(TypeError, match="speed"):
            f(True)
        with pytest.raises(ValueError, match="non-finite"):
            f([1200.0, np.nan])
        with pytest.raises(ValueError, match="500–1800 rpm"):
            f([1200.0, 100.0])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ValueError, match="500–1800 rpm"):
                f(10.0)
        grid = np.array([[800.0, 1200.0], [1400.0, 1600.0]])
        assert f(grid).shape == (2, 2) and np.ndim(f(1200.0)) == 0
    assert plant.static_pressure(1200.0) == pytest.approx(gb.reference.eq1(1200.0))


@pytest.mark.parametrize("flow,error", [("3", TypeError), (True, TypeError), (None, TypeError), ({}, TypeError),
                                        (np.inf, ValueError), (np.nan, ValueError), (-1.0, ValueError)])
def test_turbine_head_takes_a_flow(flow, error):
    # float(flow) parsed '3' and read True as 1 L/s (None: "float() argument must be …"), and inf returned inf
    with pytest.raises(error, match="flow"):
        PumpingPlant().turbine_head(flow)


def test_eq1_points_reads_speeds():
    # eq1_points([[750, 850]]) said 'eq. (1): ybar must be 1-D, got shape (1, 2)', naming the curve's values for the
    # speeds given, and one speed (1200.0) was refused as '0-D'
    from graybox import reference

    with pytest.raises(ValueError, match="ubar must be 1-D"):
        reference.eq1_points([[750.0, 850.0]])
    with pytest.raises(ValueError, match="ubar must be 1-D"):
        reference.eq1_points([[750.0], [850.0]])
    pts = reference.eq1_points(1200.0)
    assert pts.ubar.ravel().tolist() == [1200.0] and pts.ybar[0] == pytest.approx(reference.eq1(1200.0))
    assert len(reference.eq1_points()) == 10


@pytest.mark.parametrize("rel_step", [1.0, 10.0])
def test_linearize_refuses_a_step_of_the_whole_level(rel_step):
    # rel_step=10 stepped the flow to −9 Q̄: C came back NaN and A with a spectral radius of 1.13 (the rig is stable,
    # 0.89), without a word; a relative step of 1 or more crosses zero
    with pytest.raises(ValueError, match="rel_step"):
        PumpingPlant().linearize(1200.0, rel_step=rel_step)
    A, _, C = PumpingPlant().linearize(1200.0)
    assert np.isfinite(C).all() and np.max(np.abs(np.linalg.eigvals(A))) < 1.0


def _multisine_by_sum(n, lines, phase):
    k = np.arange(n)[:, None]
    return np.cos(2 * np.pi * k * lines[None, :] / n + phase[None, :]).sum(axis=1)


def test_multisine_is_computed_in_time_and_memory_linear_in_the_record(monkeypatch):
    # the multisine summed a cosine per line over an (n × lines) matrix: 20 000 samples took 6 s and 630 MB, 10⁵
    # samples would take 15 GB (quadratic in n); one inverse FFT gives the same signal in O(n log n)
    from graybox.datasets import _inputs

    for n in (64, 101, 1024):
        for band in ((0.05, 0.4), (0.5, 1.0), (0.01, 1.0)):
            got = _inputs._multisine(n, 1, band, 0)[:, 0]
            lines = np.arange(1, n // 2 + 1)
            lines = lines[(lines * 2 / n >= band[0]) & (lines * 2 / n <= band[1])]
            K = np.arange(1, lines.size + 1)
            want = _multisine_by_sum(n, lines, -np.pi * K * (K - 1) / lines.size)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * lines.size)
    big = []
    real_cos = np.cos

    def watched_cos(x, *args, **kwargs):  # no (n × lines) array of phases
        big.append(np.size(x))
        return real_cos(x, *args, **kwargs)

    monkeypatch.setattr(_inputs.np, "cos", watched_cos)
    x = gb.design_input("multisine", 20_000, low=0.0, high=1.0, frequencies=(0.005, 0.2), n_inputs=2, seed=1)
    assert x.shape == (20_000, 2) and x.min() == 0.0 and x.max() == 1.0
    assert max(big, default=0) <= 20_000


@given(st.lists(st.integers(min_value=0, max_value=300), min_size=1, max_size=6), st.integers(1, 80))
@settings(max_examples=60, deadline=None)
def test_record_points_are_at_most_count_over_any_records(lengths, count):
    """record_points' docstring says up to count points (the README's 64): one stride per record took up to one
    more per record (hunt49b's note)."""
    from graybox.estimation._local_models import record_points

    structure = gb.Structure(["y(k-1)", "u(k-2)"])
    records = [gb.Record(np.arange(n + 2.0), np.arange(n + 2.0) * 0.5) for n in lengths]
    total = sum(lengths)
    ubar, ybar = record_points(structure, records, count)
    assert ubar.shape == ybar.shape and len(ubar) <= count
    assert len(ubar) == min(total, -(-total // max(1, -(-total // count))))  # evenly spaced over all rows


def test_a_step_beyond_the_calibrated_range_names_the_step():
    """step_time_constant(1750, step=100) said 'speed reference … sample 10 is 1850 rpm', naming neither (hunt49b)."""
    from graybox.datasets.pumping import PumpingPlant

    with pytest.raises(ValueError, match=r"speed \+ step \(1750 \+ 100 rpm\) must stay within 500–1800 rpm"):
        PumpingPlant().step_time_constant(1750, step=100)
    with pytest.raises(ValueError, match=r"speed \+ step \(600 - 200 rpm\)"):
        PumpingPlant().step_time_constant(600, step=-200)


def test_the_two_speed_rig_steady_state_takes_one_speed_of_each_set():
    from graybox.datasets._pumping_miso import TwoSpeedPumpingPlant

    rig = TwoSpeedPumpingPlant()
    with pytest.raises(ValueError, match=r"one speed of each pump set .* shape \(2,\)"):
        rig.steady_state(np.array([1200.0, 1100.0]), np.array([1000.0, 1100.0]))
    x = rig.steady_state(np.array([1200.0]), 1000)
    assert x[:4] == (1200.0, 1200.0, 1000.0, 1000.0) and x[4] == float(rig.steady_flow(1200.0, 1000.0))
