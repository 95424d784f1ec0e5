"""Bug hunt 44a: reproducing the paper, the bundled data, decimation, input design, the neural NARMAX model."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._neural import neural_narx


@pytest.mark.parametrize("level", [0.1, 1000.1, 1e4 + 0.3])
def test_neural_refuses_a_held_input_at_any_level(level: float) -> None:
    # the mean of a constant 1000.1 is not exactly 1000.1: its std was 2e-13, taken for a scale, and the
    # network trained on a held input (0.1 was refused)
    rng = np.random.default_rng(0)
    rec = gb.Record(np.full(400, level), rng.standard_normal(400))
    with pytest.raises(ValueError, match="input is constant"):
        neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=2, sim_epochs=0)


@pytest.mark.parametrize("level", [0.1, 1000.1, 1e4 + 0.3])
def test_neural_refuses_a_held_output_at_any_level(level: float) -> None:
    rng = np.random.default_rng(0)
    rec = gb.Record(rng.uniform(0.0, 1.0, 400), np.full(400, level))
    with pytest.raises(ValueError, match="output is constant"):
        neural_narx(rec, ny=2, nu=2, ne=1, hidden=3, epochs=2, sim_epochs=0)


def test_decimate_refuses_only_records_that_keep_fewer_than_two_samples() -> None:
    # samples 0 and q exist once the record has q + 1 samples: 1001 samples by 1000 keep two, yet the check
    # was n < 2q and said they "make fewer than 2"
    rng = np.random.default_rng(1)
    n, q = 1001, 1000
    rec = gb.Record(rng.uniform(0.0, 1.0, (n, 2)), rng.standard_normal(n), Ts=0.01, units=("rpm", "Pa"))
    out = gb.decimate(rec, q, antialias=False)
    assert len(out) == 2
    np.testing.assert_array_equal(out.u, rec.u[[0, q]])
    np.testing.assert_array_equal(out.y, rec.y[[0, q]])
    assert out.Ts == pytest.approx(q * rec.Ts) and out.units == rec.units
    with pytest.raises(ValueError, match="fewer than 2"):
        gb.decimate(rec.slice(0, q), q, antialias=False)


def _y_power(term: str) -> int:
    return sum(int(p or 1) for p in re.findall(r"y\(k-\d+\)(?:\^(\d+))?", term))


def test_black_box_section_models_are_table_one_els_15_and_17() -> None:
    # the black-box section selected its "eq. 15" among candidates with y² (y(k-6)², y(k-1)y(k-6)) and
    # without the constant forced, so `graybox reproduce` printed two different ELS (15): J_S valid 0.749 in
    # that section and 0.824 in Table I. Both are now Table I's selection (the README's recipe)
    from graybox.reproduce import black_box_models

    data = gb.load_pumping()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)  # ℓ = 3: a candidate collinear on these data
        models = black_box_models(data.ident)
        for degree, n_terms in ((2, 17), (3, 23)):
            cand = gb.Candidates(6, 6, ne=2, degree=degree, max_y_power=1 if degree == 2 else None)
            sel = gb.frols(cand, data.ident, n_terms=n_terms, include=["1"])
            assert list(models[f"ELS ℓ={degree}"][1].structure) == list(sel.structure)
    terms = [str(t) for t in models["ELS ℓ=2"][1].structure]
    assert "1" in terms and max(_y_power(t) for t in terms) == 1  # eq. (15)'s rational form


@pytest.mark.parametrize("seed", range(20))
def test_speed_reference_stays_on_multiples_of_10_inside_its_range(seed: int) -> None:
    # a low of 755 rpm gave a first level of 750 (int(low) // 10 · 10) and a high of 1646 forced ends of 1650:
    # outside [low, high], which the docstring promises, and levels off the 10 rpm grid where clipped to 755
    from graybox.datasets import speed_reference

    u = speed_reference(seed=seed, low=755.0, high=1646.0)
    assert u.min() >= 755.0 and u.max() <= 1646.0
    np.testing.assert_array_equal(u % 10, 0.0)
    for part in (u[:3200], u[3200:]):  # each part visits both ends (within 30 rpm)
        assert part.min() <= 755.0 + 30 and part.max() >= 1646.0 - 30


def test_speed_reference_refuses_a_range_its_steps_do_not_fit() -> None:
    # a 60 rpm range failed inside numpy ("high - low < 0"), and low > high was not refused
    from graybox.datasets import speed_reference

    for low, high in ((800.0, 860.0), (1000.0, 800.0)):
        with pytest.raises(ValueError, match="must span at least 80 rpm"):
            speed_reference(seed=0, low=low, high=high)
    with pytest.raises(ValueError, match="high"):
        speed_reference(seed=0, low=750.0, high=float("nan"))


def test_aprbs_of_a_long_record_is_drawn_in_linear_time_and_the_same_as_before(monkeypatch) -> None:
    # the holds were drawn while sum(holds) < n: the sum of a growing list at each draw, quadratic in the number
    # of holds (10⁶ samples with hold=(1, 3): tens of minutes). Now one running total, the same draws
    import builtins

    from graybox.datasets import _inputs

    visited = []

    def counting_sum(values, *args):
        values = list(values)
        visited.append(len(values))
        return builtins.sum(values, *args)

    monkeypatch.setattr(_inputs, "sum", counting_sum, raising=False)  # the module's name lookups find it first
    n = 3000
    u = gb.design_input("aprbs", n, low=0.0, high=1.0, hold=(1, 3), seed=4)
    assert builtins.sum(visited) <= 10 * n
    # the design the seed always gave: holds drawn one by one from default_rng([seed, 0]), then the levels
    rng = np.random.default_rng([4, 0])
    holds: list[int] = []
    while builtins.sum(holds) < n:
        holds.append(int(rng.integers(1, 4)))
    levels = rng.permutation(len(holds)) / (len(holds) - 1)
    np.testing.assert_allclose(u, np.repeat(levels, holds)[:n], rtol=0, atol=1e-15)


def test_aprbs_takes_its_hold_pair_as_an_array_too() -> None:
    # hold=np.array([5, 10]) (holds computed from a settling time) was refused as "hold must be an integer"
    # although a pair is what an APRBS takes; frequencies= already took an array
    a = gb.design_input("aprbs", 400, low=0.0, high=1.0, hold=np.array([5, 10]), seed=2)
    np.testing.assert_array_equal(a, gb.design_input("aprbs", 400, low=0.0, high=1.0, hold=(5, 10), seed=2))
    with pytest.raises(ValueError, match="pair"):
        gb.design_input("aprbs", 400, low=0.0, high=1.0, hold=np.array([5, 10, 20]))
    with pytest.raises(ValueError, match="hold must be an int for kind='staircase'"):
        gb.design_input("staircase", 400, low=0.0, high=1.0, hold=np.array([5, 10]))


def test_reproduce_run_refuses_flags_that_are_not_bools_before_deleting_anything(tmp_path, monkeypatch) -> None:
    # run(fresh="no") read "no" as true and deleted the checkpoints of hours of sweeps; quick="False" ran quick
    import graybox.reproduce as rp
    from graybox.reproduce._table1 import checkpoint_paths

    monkeypatch.setattr(rp, "SECTIONS", ())  # nothing to compute: only the arguments and the checkpoints
    ck = checkpoint_paths(tmp_path, True)[0]
    ck.write_bytes(b"a checkpoint")
    for kwargs in ({"fresh": "no"}, {"quick": "False"}, {"fresh": 1}):
        with pytest.raises(TypeError, match="must be True or False"):
            rp.run(out=tmp_path, **{"quick": True, **kwargs})
        assert ck.read_bytes() == b"a checkpoint"


def test_static_point_std_validates_its_arguments() -> None:
    # n_samples=0 ended in ZeroDivisionError, a speed of 100 rpm (outside the calibrated 500–1800) gave a number
    from graybox.datasets import PumpingPlant

    plant = PumpingPlant()
    assert plant.static_point_std(1000.0, 120) > 0
    with pytest.raises(ValueError, match="n_samples must be an integer >= 1"):
        plant.static_point_std(1000.0, 0)
    with pytest.raises(TypeError, match="n_samples"):
        plant.static_point_std(1000.0, 2.5)
    with pytest.raises(ValueError, match="within 500–1800 rpm"):
        plant.static_point_std(100.0, 120)
    with pytest.raises(ValueError, match="speed"):
        plant.static_point_std(float("nan"), 120)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"settle": -1.0}, ValueError, "settle"),            # averaged the last 20 samples of a 5 s hold, silently
    ({"settle": float("nan")}, ValueError, "settle"),    # "cannot convert float NaN to integer"
    ({"average": float("inf")}, ValueError, "average"),  # OverflowError
    ({"average": 0.01}, ValueError, "at least one sample"),
    ({"settle": "180"}, TypeError, "settle"),            # "unsupported operand type(s) for /"
])
def test_static_experiments_validate_settle_and_average(kwargs, error, match) -> None:
    from graybox.datasets import PumpingPlant, TwoSpeedPumpingPlant, static_experiment, static_grid_experiment

    with pytest.raises(error, match=match):
        static_experiment(PumpingPlant(), speeds=[800.0, 900.0], seed=0, **kwargs)
    with pytest.raises(error, match=match):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[[1200.0, 1300.0]], seed=0, **kwargs)


@pytest.mark.parametrize("m", [2, 3, 4])
@pytest.mark.parametrize("seed", [0, 1])
def test_multisine_columns_keep_schroeders_low_crest_factor(m: int, seed: int) -> None:
    # with several inputs each column took a random share of the lines, on which Schroeder's phases (made for
    # equally spaced lines) gave crest factors of 3.2-3.8: those of random phases. Interleaved lines keep < 2
    n = 2048
    x = gb.design_input("multisine", n, low=-1.0, high=1.0, frequencies=(0.005, 0.2), n_inputs=m, seed=seed)
    assert x.shape == (n, m)
    np.testing.assert_array_equal(x, gb.design_input("multisine", n, low=-1.0, high=1.0, frequencies=(0.005, 0.2),
                                                     n_inputs=m, seed=seed))
    S = np.abs(np.fft.rfft(x - x.mean(axis=0), axis=0))
    owned = S > 1e-6 * S.max(axis=0)
    assert np.all(owned.sum(axis=1) <= 1)  # no line shared: uncorrelated over the period
    band = np.arange(n // 2 + 1) * 2 / n
    assert np.array_equal(owned.any(axis=1), (band >= 0.005) & (band <= 0.2))  # every line of the band is used
    for c in x.T:
        assert np.max(np.abs(c - c.mean())) / np.std(c) < 2.0
        assert c.min() == -1.0 and c.max() == 1.0


def test_reproduce_help_names_what_the_out_folder_receives(capsys) -> None:
    # --out was "folder for figures, tables and checkpoints", but the tables are printed, never written there
    from graybox._cli import main

    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "figures, tables and checkpoints" not in text
    assert "folder for the figures (PNG) and the checkpoints" in text and "tables are printed" in text


@pytest.mark.parametrize("name, value, error", [
    ("noise_std", float("nan"), ValueError),           # every measured pressure NaN
    ("process_noise_std", float("nan"), ValueError),   # NaN > 0 is false: the process noise silently off
    ("surge_intensity", float("inf"), ValueError),     # NaN pressures
    ("air_loss_per_rpm", float("nan"), ValueError),    # pressures near 0 mlc at 1000 rpm, silently
    ("noise_std", "0.1", TypeError),                   # "'<' not supported between 'str' and 'int'"
    ("noise_std", -0.1, ValueError),
])
def test_pumping_plant_refuses_noise_levels_that_are_not_finite_numbers(name, value, error) -> None:
    from graybox.datasets import PumpingPlant

    with pytest.raises(error, match=f"PumpingPlant: {name}"):
        PumpingPlant(**{name: value})


@pytest.mark.parametrize("su, sy", [(1e200, 1.0), (1.0, 1e-200), (1e-300, 1e150), (1.0, 1e200)])
def test_neural_network_is_the_same_in_huge_or_tiny_units(su: float, sy: float) -> None:
    # u near 1e200 overflowed u.std() (inf: every normalised input 0, a network blind to its input, trained silently);
    # y near 1e-200 underflowed it (the output called constant), and the held-out cost (y_scale²) underflowed to 0
    rng = np.random.default_rng(0)
    n = 400
    u = np.repeat(rng.uniform(200.0, 800.0, n // 20 + 1), 20)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.8 * y[k - 1] + 0.001 * u[k - 1] + 1e-6 * u[k - 1] ** 2 + 0.01 * rng.standard_normal()
    kw = dict(ny=2, nu=2, ne=1, hidden=3, epochs=5, sim_epochs=10, holdout=0.25)
    fit = neural_narx(gb.Record(u, y), **kw)
    scaled = neural_narx(gb.Record(u * su, y * sy), **kw)
    assert scaled.best_step == fit.best_step
    if 0 < sy * sy < np.inf:  # in output units² (1e±400 is no float: there only the choice it made can be compared)
        np.testing.assert_allclose(np.array(scaled.holdout_cost) / sy**2, fit.holdout_cost, rtol=1e-9)
    free = fit.model.simulate(gb.Record(u, y))
    np.testing.assert_allclose(scaled.model.simulate(gb.Record(u * su, y * sy)) / sy, free, rtol=1e-9, atol=1e-12)


def test_reproduce_run_refuses_a_stream_that_cannot_be_written_before_any_section(monkeypatch) -> None:
    # stream="out.txt" failed after the first section with "'str' object has no attribute 'write'"
    import graybox.reproduce as rp

    ran = []
    monkeypatch.setattr(rp, "SECTIONS", (lambda quick, out: ran.append(1) or "text",))
    with pytest.raises(TypeError, match="stream must be a text file"):
        rp.run(stream="out.txt")
    assert ran == []


@pytest.mark.parametrize("kwargs, error", [
    ({"n_ident": 3200.5}, TypeError),        # "slice indices must be integers"
    ({"n_samples": "4000"}, TypeError),      # "'<' not supported between 'int' and 'str'"
    ({"seed": -1}, ValueError),              # numpy's "expected non-negative integer"
    ({"n_ident": 0}, ValueError),
    ({"low": "750"}, TypeError),
])
def test_speed_references_check_their_counts_seed_and_range(kwargs, error) -> None:
    from graybox.datasets import speed_reference, two_speed_reference

    name = next(iter(kwargs))
    for design in (speed_reference, two_speed_reference):
        with pytest.raises(error, match=name):
            design(**kwargs)


@pytest.mark.parametrize("domain, error", [
    (((1650.0, 1150.0), (1150.0, 1650.0)), ValueError),       # a reversed box, kept as given
    (((float("nan"), 1650.0), (1150.0, 1650.0)), ValueError),  # NaN kept
    (((1150.0, 1650.0),), ValueError),                       # one input's range for a two-input surface
    (((100.0, 1650.0), (1150.0, 1650.0)), ValueError),        # beyond the rig's speed_range: p̄ refuses it later
    ((1150.0, 1650.0), TypeError),                           # "cannot unpack non-iterable float object"
])
def test_plant_surface_domain_is_a_box_of_the_rigs_speeds(domain, error) -> None:
    from graybox.datasets import TwoSpeedPumpingPlant

    with pytest.raises(error, match="domain"):
        TwoSpeedPumpingPlant().surface(domain=domain)


@pytest.mark.parametrize("rel_step", [0.0, float("nan"), -1e-5])
def test_linearize_refuses_a_step_that_is_no_positive_number(rel_step: float) -> None:
    # 0 divided by zero (NaN matrices with a RuntimeWarning), NaN gave NaN matrices silently
    from graybox.datasets import PumpingPlant

    with pytest.raises(ValueError, match="rel_step"):
        PumpingPlant().linearize(1000.0, rel_step=rel_step)


@pytest.mark.parametrize("kwargs, match", [
    ({"step": 0.0}, "step"),          # 0/0: NaN with a RuntimeWarning
    ({"step": float("nan")}, "step"),
    ({"horizon": 0.0}, "horizon"),    # IndexError
    ({"horizon": -1.0}, "horizon"),   # "negative dimensions are not allowed"
    ({"horizon": float("inf")}, "horizon"),  # OverflowError
])
def test_step_time_constant_refuses_a_step_or_horizon_it_cannot_measure(kwargs, match) -> None:
    from graybox.datasets import PumpingPlant

    with pytest.raises(ValueError, match=match):
        PumpingPlant().step_time_constant(1000.0, **kwargs)


def test_static_tests_refuse_an_empty_list_of_speeds() -> None:
    # static_experiment(speeds=[]) ended in an IndexError, static_grid(speeds1=[]) in numpy's "need at least one array
    # to concatenate", and static_grid(speeds2=[]) returned an empty grid
    from graybox.datasets import PumpingPlant, static_experiment
    from graybox.datasets._pumping_miso import static_grid

    with pytest.raises(ValueError, match="speeds: no speed"):
        static_experiment(PumpingPlant(), speeds=[], seed=0)
    with pytest.raises(ValueError, match="speeds1: no speed"):
        static_grid(speeds1=[])
    with pytest.raises(ValueError, match="speeds2: no speed"):
        static_grid(speeds1=[1200.0], speeds2=[])


def test_static_grid_experiment_names_a_bad_speed_pair_in_its_own_terms() -> None:
    # a NaN pair was said as "speed reference 2 has 3720 non-finite value(s) … first at index 0" (the run's samples),
    # a string pair failed in numpy's float conversion
    from graybox.datasets import TwoSpeedPumpingPlant, static_grid_experiment

    with pytest.raises(ValueError, match=r"speeds.*row 1"):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[[1200.0, 1300.0], [1200.0, float("nan")]], seed=0)
    with pytest.raises(TypeError, match="speeds"):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[["1200", "1300"]], seed=0)
