"""hunt50c: reproducing the paper and the bundled data (graybox.reproduce, graybox.datasets)."""

import numpy as np
import pytest

from graybox.datasets.pumping import PumpingPlant


@pytest.mark.parametrize("kw,error,match", [
    ({"surge_time": True}, TypeError, "surge_time"),         # a surge decaying in 1 s, silently
    ({"air_vent_time": True}, TypeError, "air_vent_time"),   # air venting in 1 s, silently
    ({"surge_time": "6"}, TypeError, "surge_time"),          # text is a wrong type, not a wrong value
    ({"dead_time": "0.02"}, TypeError, "dead_time"),         # "unsupported operand type(s) for /: 'str' and 'float'"
    ({"dead_time": None}, TypeError, "dead_time"),
])
def test_pumping_plant_times_are_numbers(kw, error, match):
    with pytest.raises(error, match=f"PumpingPlant: {match}"):
        PumpingPlant(**kw)


def test_pumping_plant_takes_numpy_times():
    # np.float32(6.0) was refused as 'surge_time must be a positive finite number', as inertia's was before hunt49b
    plant = PumpingPlant(surge_time=np.float32(6.0), air_vent_time=np.float32(30.0), dead_time=np.float64(0.02))
    u = np.r_[np.full(40, 1000.0), np.full(40, 1300.0)]
    assert plant.simulate(u, seed=3).y == pytest.approx(PumpingPlant().simulate(u, seed=3).y, rel=1e-6)


def test_reproduce_refuses_an_unreadable_checkpoint_before_any_section(tmp_path, monkeypatch):
    # a checkpoint no graybox wrote (a torn copy, another file under its name) was announced as "resuming from 1
    # checkpoint(s)", and three sections ran and drew their figures before Table I's sweep refused it
    import io

    import graybox.reproduce as rp
    from graybox.estimation._simulation_error import CheckpointError
    from graybox.reproduce._table1 import checkpoint_paths

    ran = []
    monkeypatch.setattr(rp, "SECTIONS", (lambda quick, out: ran.append(1) or "a section",))
    bad = checkpoint_paths(tmp_path, quick=True)[1]
    bad.write_bytes(b"no checkpoint")
    out = io.StringIO()
    with pytest.raises(CheckpointError, match=f"{bad.name}.*not a readable SE checkpoint.*no .npz archive"):
        rp.run(quick=True, out=tmp_path, stream=out)
    np.savez(bad, kind="select_graybox")  # another function's archive under the name
    with pytest.raises(CheckpointError, match="not a readable SE checkpoint.*no SE sweep's metadata"):
        rp.run(quick=True, out=tmp_path, stream=out)
    assert not ran and "resuming" not in out.getvalue()
    rp.run(quick=True, out=tmp_path, stream=out, fresh=True)  # --fresh deletes it and runs
    assert ran and not bad.exists()


def test_speed_reference_steps_and_holds_are_as_documented_but_at_the_forced_ends():
    # the docstring promised steps of 40-900 rpm every 4-9 s; the holds forced to the ends of the range break both
    # (1 part in 8 over seeds 0-199: steps of 10 rpm, or a level repeated into a hold of 15.8 s), which it now says
    from graybox.datasets import pumping

    assert "whatever step" in pumping.speed_reference.__doc__
    low, high = 750.0, 1650.0
    for seed in range(40):
        u = pumping.speed_reference(seed=seed)
        for part in (u[:pumping.N_IDENT], u[pumping.N_IDENT:]):
            starts = np.r_[0, np.flatnonzero(np.diff(part)) + 1]
            levels, lengths = part[starts], np.diff(np.r_[starts, part.size])
            near_end = (levels <= low + 30) | (levels >= high - 30)
            steps = np.abs(np.diff(levels))
            assert np.all((steps >= 40) | near_end[:-1] | near_end[1:])
            assert np.all((lengths[:-1] <= 180) | near_end[:-1])  # the last hold is cut where the part ends
            assert np.all(lengths[:-1] >= 80) and np.all(levels % 10 == 0)
            assert levels.min() <= low + 30 and levels.max() >= high - 30


@pytest.mark.parametrize("section", ["section_table1", "section_neural"])
def test_reproduce_sections_check_quick_and_out_before_any_work(section, monkeypatch):
    # quick="no" is truthy: section_table1 ran the full sweeps (100 λ1 values, hours); out=5 failed inside pathlib
    # ("argument should be a str or an os.PathLike object ..., not 'int'") after the data were loaded and fitted
    import graybox.reproduce as rp
    from graybox.reproduce import _neural, _table1

    def no_data():
        raise AssertionError("the section started its work")

    for mod in (_neural, _table1):
        monkeypatch.setattr(mod, "load_pumping", no_data)
    with pytest.raises(TypeError, match="quick must be True or False"):
        getattr(rp, section)(quick="no")
    with pytest.raises(TypeError, match="out must be a file or folder name"):
        getattr(rp, section)(quick=True, out=5)
    if section == "section_table1":  # threads was checked by the first SE sweep, after ELS, CLS and PE
        with pytest.raises(ValueError, match="threads must be an integer >= 1"):
            rp.section_table1(quick=True, threads=0)


def test_reproduce_run_names_an_out_that_is_no_folder_name(monkeypatch):
    import graybox.reproduce as rp

    monkeypatch.setattr(rp, "SECTIONS", ())
    with pytest.raises(TypeError, match="out must be a file or folder name"):
        rp.run(out=5)


@pytest.mark.parametrize("section", ["section_black_box", "section_neural"])
@pytest.mark.parametrize("data", ["record", "pumping"])
def test_reproduce_sections_name_data_that_is_no_dataset(section, data):
    # a Record (or a name) failed with a bare AttributeError: "'Record' object has no attribute 'ident'"
    import graybox as gb
    import graybox.reproduce as rp

    bad = gb.Record(np.arange(50.0) % 7, np.arange(50.0) % 5, Ts=1.0) if data == "record" else data
    with pytest.raises(TypeError, match="data must be a Dataset"):
        getattr(rp, section)(data=bad)


@pytest.mark.parametrize("sizes,error,match", [
    ([(2, 17), (2, 10)], ValueError, "degree 2 twice"),         # the second overwrote the first under "ELS ℓ=2"
    ((2, 17), TypeError, r"sizes\[0\] must be a pair"),        # "cannot unpack non-iterable int object"
    ([(2,)], ValueError, r"sizes\[0\] must be a pair"),        # "not enough values to unpack (expected 2, got 1)"
    ({(2, 17), (3, 23)}, TypeError, "no order"),                # the models' order changed from run to run
])
def test_black_box_models_gives_one_model_per_size(sizes, error, match):
    from graybox.reproduce import black_box_models

    rec = _small_record()
    with pytest.raises(error, match=match):
        black_box_models(rec, ny=1, nu=1, ne=0, sizes=sizes)


def test_black_box_models_keys_follow_sizes():
    from graybox.reproduce import black_box_models

    out = black_box_models(_small_record(), ny=1, nu=1, ne=0, sizes=[(2, 3), (1, 2)])
    assert list(out) == ["ELS ℓ=2", "ELS ℓ=1"] and [len(sel.structure) for sel, _ in out.values()] == [3, 2]
    rows = black_box_models(_small_record(), ny=1, nu=1, ne=0, sizes=np.array([[2, 3], [1, 2]]))  # rows of an array
    assert list(rows) == list(out)


def _small_record():
    import graybox as gb

    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 200)
    y = np.zeros(200)
    for k in range(1, 200):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.3 * u[k - 1] ** 2 + 0.01 * rng.standard_normal()
    return gb.Record(u, y, Ts=1.0)


def test_static_tests_name_the_level_outside_the_calibrated_range():
    # the levels became a run's reference first: "speed reference must stay within 500–1800 rpm …; sample 3720 is
    # 2000 rpm", a sample of a run the caller never made, for speeds=[750, 2000]
    from graybox.datasets import TwoSpeedPumpingPlant, static_experiment, static_grid_experiment

    with pytest.raises(ValueError, match=r"speeds\[1\] is 2000 rpm, outside .*500–1800 rpm") as exc:
        static_experiment(PumpingPlant(), speeds=[750.0, 2000.0], seed=1)
    assert "sample" not in str(exc.value)
    with pytest.raises(ValueError, match=r"speeds\[1\] is \[1200.0, 2000.0\] rpm, outside .*500–1800 rpm"):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[[1200.0, 1200.0], [1200.0, 2000.0]], seed=1)


@pytest.mark.parametrize("folder", ["pumping", "pumping_miso"])
def test_regenerating_another_seed_needs_its_own_folder(folder, capsys):
    # `python -m graybox.datasets.pumping --seed 7` rewrote the bundled files with seed 7's draw, and load_pumping
    # went on saying extra["seed"] = 2011 (and the docstrings' and BENCHMARKS' numbers, all of seed 2011's files)
    from graybox.datasets.pumping import regenerate_main

    calls = []
    with pytest.raises(SystemExit) as exc:
        regenerate_main(["--seed", "7"], module="m", folder=folder, write=lambda out, seed: calls.append(seed))
    assert exc.value.code == 2 and not calls
    assert "--out" in capsys.readouterr().err


def test_regenerating_another_seed_into_a_folder_of_its_own_works(tmp_path):
    from graybox.datasets.pumping import regenerate_main

    calls = []

    def write(out, seed):
        calls.append((out, seed))
        return out / "dynamic.csv", out / "static.csv"

    assert regenerate_main(["--seed", "7", "--out", str(tmp_path)], module="m", folder="pumping", write=write) == 0
    assert calls == [(tmp_path, 7)]


def test_static_grid_experiment_reads_a_frame_of_speeds_by_its_columns():
    # simulate and the static surface read a DataFrame's columns u1, u2 by name; the static test read them by
    # position, so a frame with u2 first put each speed on the other pump set and labelled its points so
    import pandas as pd

    from graybox.datasets import TwoSpeedPumpingPlant, static_grid_experiment

    frame = pd.DataFrame({"u2": [1650.0, 1400.0], "u1": [1150.0, 1300.0]})
    quiet = dict(settle=1.0, average=0.5, seed=1)
    sp = static_grid_experiment(TwoSpeedPumpingPlant(), speeds=frame, **quiet)
    np.testing.assert_array_equal(sp.ubar, [[1150.0, 1650.0], [1300.0, 1400.0]])
    same = static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[[1150.0, 1650.0], [1300.0, 1400.0]], **quiet)
    np.testing.assert_array_equal(sp.ybar, same.ybar)
    with pytest.raises(ValueError, match="speeds"):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=frame.rename(columns={"u2": "n2"}), **quiet)


def test_load_record_csv_reads_ts_as_record_does(tmp_path):
    # Ts=10**400 escaped as a bare OverflowError from math.isfinite; a 0-d array, one number to Record, was refused
    import graybox as gb

    p = tmp_path / "r.csv"
    p.write_text("u,y\n1,2\n2,3\n3,4\n")
    assert gb.load_record_csv(p, u="u", y="y", Ts=np.array(0.1)).Ts == gb.Record([1, 2], [1, 2], Ts=np.array(0.1)).Ts
    with pytest.raises(ValueError, match="Ts.*beyond the float range"):
        gb.load_record_csv(p, u="u", y="y", Ts=10**400)
    with pytest.raises(TypeError, match="Ts must be a positive number of seconds"):
        gb.load_record_csv(p, u="u", y="y", Ts=np.array([0.1]))
    with pytest.raises(ValueError, match="Ts must be a positive number of seconds"):
        gb.load_record_csv(p, u="u", y="y", Ts=0)


def test_pumping_plant_ramp_beyond_the_float_range_is_a_value_error():
    # math.isnan(10**400) raised a bare OverflowError
    with pytest.raises(ValueError, match="ramp_up must be a positive number of rpm/s.*beyond the float range"):
        PumpingPlant(ramp_up=10**400)
    assert PumpingPlant(ramp_down=np.int64(150)).ramp_down == 150 and PumpingPlant(ramp_up=np.inf).ramp_up == np.inf
    for bad in (np.nan, -1.0, 0, True, "fast"):
        with pytest.raises(ValueError, match="ramp_up"):
            PumpingPlant(ramp_up=bad)


def test_reproduce_refuses_an_empty_out_folder_name(monkeypatch, capsys, tmp_path):
    # Path("") is the current folder: `graybox reproduce --out "$UNSET"` wrote its figures and checkpoints there
    import graybox.reproduce as rp
    from graybox._cli import main

    monkeypatch.setattr(rp, "SECTIONS", ())
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="out is empty"):
        rp.run(out="")
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "--quick", "--out", ""])
    assert exc.value.code == 2 and "--out" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())
    rp.run(out=".")  # the current folder, named


def test_regenerating_into_an_empty_out_name_is_refused(monkeypatch, tmp_path, capsys):
    # --out "" was Path("") = the current folder: the CSVs were written wherever the command ran
    from graybox.datasets.pumping import regenerate_main

    monkeypatch.chdir(tmp_path)
    calls = []
    with pytest.raises(SystemExit) as exc:
        regenerate_main(["--out", ""], module="m", folder="pumping", write=lambda out, seed: calls.append(out))
    assert exc.value.code == 2 and not calls and "--out" in capsys.readouterr().err


def test_the_papers_neural_row_is_read_only():
    # a plain dict copy of the read-only TABLE_I: an edit changed the "paper" row section_neural prints after it
    from graybox.reference import TABLE_I
    from graybox.reproduce import PAPER_NEURAL_ROW

    with pytest.raises(TypeError):
        PAPER_NEURAL_ROW["JS_valid"] = 0.1  # type: ignore[index]
    assert dict(PAPER_NEURAL_ROW) == dict(TABLE_I["Neural"])


@pytest.mark.parametrize("make,error", [
    (lambda tmp: open(tmp / "t.bin", "wb"), TypeError),   # a binary file: "a bytes-like object is required, not 'str'"
    (lambda tmp: _closed_text(tmp), ValueError),           # "I/O operation on closed file"
])
def test_reproduce_run_refuses_a_stream_that_takes_no_text_before_any_section(make, error, monkeypatch, tmp_path):
    # the stream's write method was enough: a binary or closed file failed at the first print, after a section's work
    import graybox.reproduce as rp

    ran = []
    monkeypatch.setattr(rp, "SECTIONS", (lambda quick, out: ran.append(1) or "text",))
    stream = make(tmp_path)
    try:
        with pytest.raises(error, match="stream"):
            rp.run(stream=stream)
    finally:
        stream.close()
    assert ran == []


def _closed_text(tmp):
    f = open(tmp / "t.txt", "w")
    f.close()
    return f


def test_writing_the_bundled_pair_leaves_the_old_pair_whole_when_it_fails(tmp_path):
    # dynamic.csv was written (replaced) before static.csv's text was even made: a failure there left a new
    # dynamic record beside the old static points, a pair of two draws; and a kill mid-write left a torn file
    from graybox.datasets.pumping import write_csv_pair

    old = write_csv_pair(tmp_path, ("t", "u", "y"), ["0,1,2"], ("u", "y"), ["1,2"])
    before = [p.read_bytes() for p in old]

    class Failing:
        def __iter__(self):
            yield "5,6"
            raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space left"):
        write_csv_pair(tmp_path, ("t", "u", "y"), ["0,3,4"], ("u", "y"), Failing())
    assert [p.read_bytes() for p in old] == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dynamic.csv", "static.csv"]
    new = write_csv_pair(tmp_path, ("t", "u", "y"), ["0,3,4"], ("u", "y"), ["5,6"])
    assert [p.read_text() for p in new] == ["t,u,y\n0,3,4\n", "u,y\n5,6\n"]


def test_static_tests_name_a_repeated_level_before_the_run(monkeypatch):
    # a way up and a way down (speeds=[1000, 1200, 1000]) ran the whole test, then StaticPoints refused it with
    # "duplicated ubar value(s) [1000.0]; … use StaticPoints.from_repeats", which no caller of the test can use
    from graybox.datasets import TwoSpeedPumpingPlant, static_experiment, static_grid_experiment

    def no_run(*args, **kwargs):
        raise AssertionError("the test ran")

    monkeypatch.setattr(PumpingPlant, "simulate", no_run)
    monkeypatch.setattr(TwoSpeedPumpingPlant, "simulate", no_run)
    with pytest.raises(ValueError, match=r"speeds\[2\] repeats speeds\[0\] \(1000 rpm\).*two tests"):
        static_experiment(PumpingPlant(), speeds=[1000.0, 1200.0, 1000.0], seed=1)
    with pytest.raises(ValueError, match=r"speeds\[2\] repeats speeds\[0\] \(\[1200.0, 1300.0\] rpm\)"):
        static_grid_experiment(TwoSpeedPumpingPlant(), speeds=[[1200.0, 1300.0], [1300.0, 1300.0], [1200.0, 1300.0]],
                               seed=1)
