"""Bugs found by a bug hunt from model to controller (graybox.control), in growing grids and their
reports (graybox.experiments, select_graybox's result) and on the command line, used as a control
engineer would on a plant of their own (Pa and rpm, inputs not named "u", two inputs): each test
fails without its fix."""

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from _reports import undrawn_figures
from graybox import plots

#: p(k) = 0.5 p(k-1) + 2e-5 n(k-1) + 3 (a pressure in bar against a speed in rpm).
RPM = gb.Model(["1", "y(k-1)", "n(k-1)"], [3.0, 0.5, 2e-5], input_names=("n",))
#: Two inputs, "n" (rpm) and "valve" (0-1).
TWO = gb.Model(["1", "y(k-1)", "n(k-1)", "valve(k-1)"], [3.0, 0.5, 2e-5, 1.0], input_names=("n", "valve"))


@pytest.mark.parametrize("bad", ["3000", None, [1.0, "a"], True, [[1.0, 2.0], [3.0]], object()])
@pytest.mark.parametrize("call", [
    lambda bad: gb.local_model(RPM, bad, Ts=0.1),
    lambda bad: gb.operating_curve(RPM, bad, Ts=0.1),
    lambda bad: gb.local_model(TWO, bad, Ts=0.1),
    lambda bad: gb.narx_steady_state(RPM, bad, 9.0),
])
def test_operating_points_that_are_not_numbers_are_a_type_error_naming_ubar(call, bad):
    # ubar went through numpy's float conversion: a string was "ValueError: could not convert string to float"
    # (naming no argument), None became NaN ("ubar has non-finite values"), True became the level 1.0
    with pytest.raises(TypeError, match="ubar"):
        call(bad)


SLOW_SPEC = """name = "slow"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "s1"
terms = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)"]
[[structures]]
name = "s2"
terms = ["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)^2", "u(k-2)y(k-1)"]
[[variants]]
name = "LS"
estimator = "ls"
[[variants]]
name = "SE"
estimator = "se-gradient"
lambdas = {logspace = [-3, 0, 8]}
decision = {rule = "dsf", fallback = "min_jsf"}
"""


def _cells_in(store) -> int:
    import sqlite3

    try:
        con = sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=0.1)
        try:
            return con.execute("SELECT COUNT(*) FROM cells").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error:
        return 0


@pytest.mark.parametrize("where", [["--processes", "1"], ["--workers", "1"]], ids=["processes", "dask"])
def test_ctrl_c_during_grid_run_says_what_is_kept_instead_of_tracebacks(tmp_path, where):
    # Ctrl-C (SIGINT to the terminal's whole process group) during `graybox grid run` ended in a KeyboardInterrupt
    # traceback from the driver and one from every worker process (local pool or Dask LocalCluster), and did not
    # say that the finished cells are kept and the same command resumes; `graybox reproduce` did
    import os
    import signal
    import subprocess
    import sys
    import time

    from graybox import experiments as gx

    spec, store = tmp_path / "spec.toml", tmp_path / "s.sqlite"
    spec.write_text(SLOW_SPEC)
    # the command as a terminal starts it: SIGINT not ignored, though a test runner started in the background (a
    # shell's `&`) hands its children an ignored SIGINT, which the driver would keep, finishing the grid
    proc = subprocess.Popen([sys.executable, "-m", "graybox", "grid", "run", str(spec), "--store", str(store), *where],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 120
        while _cells_in(store) < 1:  # the first cell (LS) is in; an SE cell runs
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the grid did not start"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the driver and its workers
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    done = _cells_in(store)
    assert done < 4, "the grid finished before it was interrupted"
    assert proc.returncode == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err and "leaked" not in err, err
    assert err.startswith("graybox grid run: interrupted") and str(store) in err and "cells left" in err
    again = gx.run_grid(spec, store)
    assert again.skipped == done and again.ran == 4 - done


@pytest.mark.parametrize("call", [
    lambda: plots.plot_operating_curve(gb.local_model(RPM, 3000.0, Ts=0.1)),
    lambda: plots.plot_local_models(gb.local_model(RPM, 3000.0, Ts=0.1)),
    lambda: plots.plot_local_models(3000.0),
    lambda: plots.plot_local_models([RPM]),
])
def test_the_control_pictures_refuse_a_wrong_type_with_a_type_error(call):
    # plot_operating_curve and plot_local_models raised ValueError for an object of the wrong type (a LocalModel
    # for the curve, a Model in the list), and plot_local_models(3000.0) Python's "'float' object is
    # not iterable", naming no argument
    with pytest.raises(TypeError, match="curve must be an OperatingCurve|models must be an OperatingCurve"):
        call()


@pytest.mark.parametrize("call", [gb.local_model, gb.operating_curve])
def test_a_list_of_records_at_another_period_is_refused_as_one_record_is(call):
    # the local models' period check read only a Record or a Dataset: data=[record] at 0.2 s gave a 0.1 s model's
    # local model without a word, and a model without a period was told "Ts is needed" though its docstring takes
    # the period of data's records
    rec = gb.Record(np.linspace(2000.0, 4000.0, 50), np.full(50, 9.0), 0.2, input_names=("n",))
    with pytest.raises(ValueError, match="every 0.1 s but 'record' every 0.2 s"):
        call(gb.Model(RPM.structure, RPM.theta, input_names=("n",), Ts=0.1), [3000.0], data=[rec])
    lm = gb.local_model(RPM, 3000.0, data=[rec])  # RPM has no period: the records' own
    assert lm.Ts == 0.2 and lm.time_constant == pytest.approx(-0.2 / np.log(0.5))


def test_graybox_grid_without_a_command_names_what_is_missing_in_the_help_s_words(capsys):
    # `graybox grid` alone said "the following arguments are required: grid_command", the name of an internal
    # variable that the help shows nowhere
    from graybox._cli import main

    with pytest.raises(SystemExit) as exc:
        main(["grid"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "grid_command" not in err and "required: COMMAND" in err and "usage: graybox grid [-h] COMMAND" in err


def _rpm_dataset(seed: int, n: int = 300) -> gb.Dataset:
    """A plant in rpm and bar (RPM's dynamics), noisy, with its static points at ±0.05 bar."""
    rng = np.random.default_rng(seed)
    recs = []
    for part in range(2):
        n_ = np.repeat(rng.uniform(2500.0, 3500.0, n // 20 + 1), 20)[:n]
        y = RPM.simulate(n_, np.full(1, 9.0)) + 0.01 * rng.standard_normal(n)
        recs.append(gb.Record(n_, y, 0.1, input_names=("n",), name=f"run {seed}.{part}"))
    levels = np.linspace(2600.0, 3400.0, 5)
    return gb.Dataset(*recs, gb.StaticPoints(levels, RPM.static_curve(levels), input_names=("n",), uncertainty=0.05))


def test_data_set_names_that_differ_only_in_other_characters_keep_their_own_report_files(tmp_path, monkeypatch):
    # the report's file names kept only ASCII letters, digits and ._- of a data set's name: "plant A" and "plant_A"
    # (or "Kessel ü" and "Kessel ö", or two names in another script, both "data") wrote the same heatmap and fronts files, the second data set's
    # overwriting the first's, while write_report listed both and the HTML page showed one
    from graybox import experiments as gx

    names = ("plant A", "plant_A", "Kessel ü", "Kessel ö")
    grid = gx.Grid([gx.DataSpec(nm, dataset=_rpm_dataset(i)) for i, nm in enumerate(names)],
                   [gx.StructureSpec("first order", terms=["1", "y(k-1)", "n(k-1)"])], [gx.Variant("LS", "ls")])
    gx.run_grid(grid, tmp_path / "s.sqlite")
    undrawn_figures(monkeypatch)  # the files' names and tables are asserted: nine figures not drawn
    written = gx.write_report(tmp_path / "s.sqlite", tmp_path / "report", html=True)
    assert len(set(written)) == len(written) and all(p.exists() for p in written)
    tables = sorted(p for p in written if p.name.startswith("heatmap_") and p.suffix == ".csv")
    assert len(tables) == len(names)
    df = gx.load_results(tmp_path / "s.sqlite")
    for nm, p in zip(names, [p for p in written if p in tables]):
        js = pd.read_csv(p, index_col=0).loc["first order", "LS"]
        assert js == pytest.approx(gx.heatmap_table(df, data=nm).loc["first order", "LS"], rel=1e-12)


def test_graybox_grid_run_says_when_another_run_wrote_its_cells_meanwhile(tmp_path, monkeypatch, capsys):
    # run_grid adds a note when cells it ran were meanwhile written by another run on the store (their rows kept,
    # its own dropped), but the command printed only the summary's first line ("its notes were printed at the
    # start"), and that note comes at the end: the command never said it
    from graybox import experiments as gx
    from graybox._cli import main
    from graybox.experiments import _run

    spec, store = tmp_path / "spec.toml", tmp_path / "s.sqlite"
    spec.write_text('name = "g"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\nname = "first"\n'
                    'terms = ["y(k-1)", "u(k-1)", "1"]\n[[variants]]\nname = "LS"\nestimator = "ls"\n')
    notes, other = _run._notes, []

    def meanwhile(*args, **kwargs):  # once the command's run knows its cells, another run does them first
        if not other:
            other.append(None)  # the other run passes here too
            other[0] = gx.run_grid(spec, store)
        return notes(*args, **kwargs)

    monkeypatch.setattr(_run, "_notes", meanwhile)
    assert main(["grid", "run", str(spec), "--store", str(store)]) == 0
    assert other[0].ran == 1
    # since claims (this session), the command's run does not run the cell again; its note says so, at the end
    assert "1 cell(s) were run meanwhile by another run on this store" in capsys.readouterr().out


def test_the_status_of_all_specs_says_all_instead_of_a_spec_zero(tmp_path):
    # grid_status(store, spec="all") (graybox grid status --spec all) printed "spec 0 of 2": a spec number the
    # store does not have
    from graybox import experiments as gx

    data = [gx.DataSpec("plant", dataset=_rpm_dataset(0))]
    variants = [gx.Variant("LS", "ls")]
    store = tmp_path / "s.sqlite"
    for terms in (["1", "y(k-1)", "n(k-1)"], ["1", "y(k-1)", "n(k-1)", "n(k-1)^2"]):
        gx.run_grid(gx.Grid(data, [gx.StructureSpec("s", terms=terms)], variants), store)
    status = gx.grid_status(store, spec="all")
    assert status.done == 2 and status.summary().startswith(f"{store}: all 2 specs (")
    assert gx.grid_status(store, spec=1).summary().startswith(f"{store}: spec 1 of 2 (")


def test_operating_curve_bands_are_nan_where_the_model_has_no_equilibrium_not_an_error():
    # the Monte Carlo bands refused the whole curve ("the gain and time-constant bands need an equilibrium at
    # every operating point") when one ū lay past the model's fold, where the same call without uncertainty
    # gives NaN and says "no equilibrium"
    true = gb.Model(["y(k-1)", "y(k-1)^2", "p(k-1)"], [0.5, 0.1, 1e-5], input_names=("p",))  # fold at ū = 62 500
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0.0, 5e4, 40), 10)
    rec = gb.Record(u, true.simulate(u, [0.0]) + 1e-3 * rng.standard_normal(u.size), 0.5, input_names=("p",))
    model = gb.els(true.structure, rec, noise=0).model
    unc = gb.ls_uncertainty(model, rec)
    levels = np.array([1e4, 3e4, 7e4])
    oc = gb.operating_curve(model, levels, uncertainty=unc, n_samples=100)
    assert oc.status[-1] == "no equilibrium"
    for band in (oc.gain_low, oc.gain_high, oc.time_constant_low, oc.time_constant_high, oc.undefined):
        assert np.isnan(band[-1]) and np.all(np.isfinite(band[:-1]))
    assert np.all(oc.gain_low[:-1] <= oc.gain[:-1]) and np.all(oc.gain[:-1] <= oc.gain_high[:-1])
    # the defined points' bands are those of the curve without the point past the fold
    inside = gb.operating_curve(model, levels[:-1], uncertainty=unc, n_samples=100)
    assert np.array_equal(inside.gain_low, oc.gain_low[:-1]) and np.array_equal(inside.undefined, oc.undefined[:-1])


SMALL_SPEC = """name = "g"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first"
terms = ["y(k-1)", "u(k-1)", "1"]
[[variants]]
name = "LS"
estimator = "ls"
"""


def test_a_spec_an_editor_saved_with_a_byte_order_mark_reads(tmp_path):
    # a spec saved as "UTF-8 with BOM" (Notepad) was refused as "line 1: invalid TOML: Invalid statement", while the
    # JSON files and the CSV loaders skip the mark
    from graybox import experiments as gx

    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    plain.write_text(SMALL_SPEC, encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    a, b = gx.Grid.from_toml(plain), gx.Grid.from_toml(marked)
    assert [c.key for c in b.cells()] == [c.key for c in a.cells()]


def test_a_spec_that_is_not_text_is_refused_naming_the_file_and_what_it_is(tmp_path, capsys):
    # the store given as the spec (`graybox grid run results.sqlite --store spec.toml`, arguments swapped), or any
    # binary file, gave "graybox grid run: 'utf-8' codec can't decode byte 0xf8 in position 102": neither the
    # file nor what was wrong with it
    from graybox import experiments as gx
    from graybox._cli import main

    spec, store = tmp_path / "spec.toml", tmp_path / "results.sqlite"
    spec.write_text(SMALL_SPEC)
    gx.run_grid(spec, store)
    before = spec.read_bytes()
    assert main(["grid", "run", str(store), "--store", str(spec)]) == 2
    err = capsys.readouterr().err
    assert str(store) in err and "grid store (SQLite), not a spec" in err
    assert spec.read_bytes() == before
    binary = tmp_path / "image.toml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(gx.SpecError, match=r"image.toml.*not UTF-8 text \(byte 0\)"):
        gx.Grid.from_toml(binary)


def test_a_grid_whose_cells_are_all_reused_starts_no_worker_process(tmp_path, monkeypatch):
    # the local process pool started a worker (a Python start-up and graybox's imports, about a second) when every
    # cell was reused and there was nothing to run; the Dask executor starts no cluster then
    from graybox import experiments as gx
    from graybox.experiments._executors import ProcessPool

    spec, store = tmp_path / "spec.toml", tmp_path / "s.sqlite"
    spec.write_text(SMALL_SPEC)
    gx.run_grid(spec, store)
    started = []
    monkeypatch.setattr(ProcessPool, "_start", lambda self: started.append(1) or pytest.fail("a worker started"))
    again = gx.run_grid(spec, store, executor="processes", workers=2)
    assert again.ran == 0 and again.skipped == 1 and not started


def _delta_dataset(delta) -> gb.Dataset:
    """_rpm_dataset(0) with static points off the model's curve by ±0.02 bar, of uncertainty δ (bar): a band
    constraint binds where δ is small."""
    d = _rpm_dataset(0)
    sp = d.static
    ybar = sp.ybar + 0.02 * np.array([1.0, -1.0, 1.0, -1.0, 1.0])
    return gb.Dataset(d.ident, d.valid, gb.StaticPoints(sp.ubar, ybar, input_names=("n",), uncertainty=delta))


def test_a_band_constraint_that_takes_the_points_uncertainty_is_a_new_cell_when_that_uncertainty_changes(tmp_path):
    # a cell's key held the data (records and points) and the band, not the points' uncertainty δ, which a band
    # constraint without b takes point by point: the same points with δ = 0.01, 0.07, … and 0.07, 0.01, … under
    # one band had the same key, and the store gave the second grid the first grid's stale result
    from graybox import experiments as gx

    structure = [gx.StructureSpec("quadratic", terms=["1", "y(k-1)", "n(k-1)", "n(k-1)^2"])]
    variants = [gx.Variant("PE band", "pe", lambdas=[1e-3, 1.0], constraints=[{"type": "band"}]), gx.Variant("LS", "ls")]
    store = tmp_path / "s.sqlite"
    runs, thetas = [], []
    for delta in ([0.01, 0.07, 0.04, 0.07, 0.01], [0.07, 0.01, 0.04, 0.01, 0.07]):
        data = _delta_dataset(delta)
        runs.append(gx.run_grid(gx.Grid([gx.DataSpec("plant", dataset=data, band=0.003)], structure, variants), store))
        row = gb.load_results(store).set_index("variant").loc["PE band"]
        front = gb.pe_pareto(structure[0].terms, data, lambdas=[1e-3, 1.0], constraints=gb.StaticBand())
        thetas.append(gb.decide_dsf(front, band=0.003).model.theta)
        assert np.allclose(row["theta"], thetas[-1], rtol=1e-9)
    assert not np.allclose(thetas[0], thetas[1], rtol=0.01)  # δ decides the fit
    assert runs[1].ran == 1 and runs[1].skipped == 1  # LS does not read δ: reused
    # one δ whose square is the band (the bundled sets, a CSV file's uncertainty) keeps the key it had
    structure = [gx.StructureSpec("quadratic", terms=["1", "y(k-1)", "u(k-1)", "u(k-1)^2"])]  # the plant's input u
    grid = gx.Grid([gx.DataSpec("pumping", bundled="pumping")], structure, variants[:1])
    from graybox.experiments._spec import _hash

    (cell,) = grid.cells()
    assert cell.key == _hash({"data": cell.data_hash, "band": cell.band, "structure": structure[0].content(),
                              "variant": variants[0].content(), "seed": None, "version": gb.__version__}, 32)


def test_two_data_sets_of_the_same_points_with_other_uncertainties_in_one_grid_are_refused(tmp_path):
    # workers find a cell's data by its content hash, which leaves δ out: the cells of the first data set ran on
    # the second's δ
    from graybox import experiments as gx

    data = [gx.DataSpec("a", dataset=_delta_dataset([0.01, 0.07, 0.04, 0.07, 0.01]), band=0.003),
            gx.DataSpec("b", dataset=_delta_dataset([0.07, 0.01, 0.04, 0.01, 0.07]), band=0.003)]
    structure = [gx.StructureSpec("quadratic", terms=["1", "y(k-1)", "n(k-1)", "n(k-1)^2"])]
    band = gx.Variant("PE band", "pe", lambdas=[1e-3, 1.0], constraints=[{"type": "band"}])
    with pytest.raises(gx.SpecError, match="'a' and 'b' hold the same records and static points"):
        gx.run_grid(gx.Grid(data, structure, [band]), tmp_path / "s.sqlite")
    # the band-free cells of the two share one key: one fit, counted for both grid cells it stands for (9700d10),
    # and read with spec="all" as the spec reads it, one row under each data set (mend56c)
    run = gx.run_grid(gx.Grid(data, structure, [gx.Variant("LS", "ls")]), tmp_path / "t.sqlite")
    every = gx.load_results(tmp_path / "t.sqlite", spec="all")
    assert run.ran == 2 and list(every["data"]) == ["a", "b"] and every["key"].nunique() == 1


def test_plot_fronts_refuses_an_empty_list_of_structures_with_a_value_error(tmp_path):
    # plot_fronts(results, structures=[]) failed with "ZeroDivisionError: integer division or modulo by zero"
    # while laying out its panels
    from graybox import experiments as gx

    spec, store = tmp_path / "spec.toml", tmp_path / "s.sqlite"
    spec.write_text(SMALL_SPEC)
    gx.run_grid(spec, store)
    with pytest.raises(ValueError, match="structures must name at least one structure"):
        gx.plot_fronts(store, structures=[])
    assert gx.plot_fronts(store, structures=["first"]).axes


def test_plot_heatmap_of_a_text_column_says_it_cannot_colour_text(tmp_path):
    # plot_heatmap(results, value="reason"), a leaderboard column as its docstring asks, failed with numpy's
    # "could not convert string to float: ''"
    from graybox import experiments as gx

    spec, store = tmp_path / "spec.toml", tmp_path / "s.sqlite"
    spec.write_text(SMALL_SPEC)
    gx.run_grid(spec, store)
    with pytest.raises(ValueError, match="numeric leaderboard column.*'reason'"):
        gx.plot_heatmap(store, value="reason")
    assert gx.heatmap_table(store, value="reason").loc["first", "LS"].startswith("no model has J_SF")


def test_parallel_map_on_a_scheduler_without_workers_says_so_instead_of_waiting_for_ever(monkeypatch):
    # parallel_map(scheduler=…) (select_graybox's and bootstrap_decision's Dask path) sent its jobs to a scheduler
    # that had no worker and waited for them for ever; run_grid waited a minute, then raised distributed's
    # "Only 0/1 workers arrived after 60"
    from distributed import LocalCluster

    from graybox import experiments as gx
    from graybox.experiments import _executors

    monkeypatch.setattr(_executors, "WORKER_TIMEOUT", 1)
    with LocalCluster(n_workers=0, dashboard_address=":0") as cluster:
        with pytest.raises(ConnectionError, match=f"scheduler at {cluster.scheduler_address} has no worker"):
            with gx.parallel_map(scheduler=cluster.scheduler_address) as pmap:
                pmap(abs, [1.0, -2.0])


def test_narx_iosystem_takes_the_model_s_own_period_as_local_model_does():
    # was: narx_iosystem(model, Ts) needed Ts even from a model that knows the period it was identified at
    pytest.importorskip("control")
    m = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.2, 1.0], Ts=0.1)
    assert gb.narx_iosystem(m).dt == 0.1 == gb.local_model(m, 1.0).Ts
    with pytest.raises(ValueError, match=r"Ts = 0.2 s, but model .* was identified at Ts = 0.1 s"):
        gb.narx_iosystem(m, Ts=0.2)  # its coefficients hold per step of 0.1 s, as for local_model
    assert gb.narx_iosystem(gb.Model(m.structure, m.theta, Ts=1.0), Ts=0.2).dt == 0.2  # a record's default 1 s
    with pytest.raises(ValueError, match="Ts .*is needed"):
        gb.narx_iosystem(gb.Model(m.structure, m.theta))
