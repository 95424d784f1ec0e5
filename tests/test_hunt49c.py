"""hunt49c: the command line and the public surface (graybox._cli, graybox, graybox._api) against their promises."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


@pytest.fixture
def csv_files(tmp_path):
    rec = tmp_path / "run.csv"
    rec.write_text("t,u,y\n0,1,2\n1,2,3\n2,3,4\n3,4,5\n", encoding="utf-8")
    static = tmp_path / "points.csv"
    static.write_text("u,y\n1,2\n2,3\n3,4\n", encoding="utf-8")
    return rec, static


@pytest.mark.parametrize("name", [0, {}, [], False, np.ones((2, 2)), 5])
def test_the_csv_loaders_refuse_a_name_that_is_not_text(csv_files, name):
    """A falsy name (0, {}, []) fell back to the file's stem without a word, and an array raised numpy's
    "truth value of an array is ambiguous"; a name is a str, as Record's own."""
    rec, static = csv_files
    with pytest.raises(TypeError, match="name"):
        gb.load_record_csv(rec, u="u", y="y", time="t", name=name)
    with pytest.raises(TypeError, match="name"):
        gb.load_static_csv(static, u="u", y="y", name=name)


def test_the_csv_loaders_name_by_the_file_without_a_name(csv_files):
    rec, static = csv_files
    assert gb.load_record_csv(rec, u="u", y="y", time="t").name == "run"
    assert gb.load_static_csv(static, u="u", y="y").name == "points"
    assert gb.load_record_csv(rec, u="u", y="y", time="t", name="a").name == "a"
    assert gb.load_static_csv(static, u="u", y="y", name="b").name == "b"


SHARED_SPEC = """\
name = "shared"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "a"
terms = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-1)", "1"]
[[structures]]
name = "b"
terms = ["y(k-1)", "u(k-1)", "u(k-2)", "u(k-1)^2", "1"]
[[structures]]
name = "c"
terms = ["y(k-1)", "u(k-1)", "y(k-1)^2", "1"]
[[variants]]
name = "LS"
estimator = "ls"
"""


def test_a_run_that_waits_counts_only_the_cells_another_run_still_holds(tmp_path, monkeypatch):
    """Two in-process runs on one store leapfrog: each skips the cell the other is running and goes on, and
    at its end said "10 of the cells to run are being run by another run on this store: this one waits for
    them" when the other had finished nine of those long before and was running one. The line counts the
    cells still held when it is said."""
    from concurrent.futures import ThreadPoolExecutor

    from graybox import experiments as gx
    from graybox.experiments import _run
    from graybox.experiments._cell import run_cell
    from graybox.experiments._store import ResultStore

    spec = tmp_path / "spec.toml"
    spec.write_text(SHARED_SPEC, encoding="utf-8")
    store = tmp_path / "s.sqlite"
    g = gx.Grid.from_toml(spec)
    data = g.load_data()
    cells = g.cells(data)
    keys = [c.key for c in cells]
    with ThreadPoolExecutor(1) as pool:  # the other run's connection lives in its own thread
        def in_other(fn, *args):
            return pool.submit(fn, *args).result()

        other = in_other(lambda: ResultStore.open(store, grid_name=g.name, fingerprint=g.fingerprint(cells),
                                                  spec=g.to_dict(), cells=cells, version=gb.__version__))
        try:
            assert in_other(other.claim, keys) == {}
            take = _run._Share.take
            finished = []

            def take_then_the_other_finishes_two(share, batch):
                mine = take(share, batch)
                if not finished and len(share.waiting) == len(cells):  # every cell skipped: the other holds them
                    for c in cells[:2]:
                        in_other(other.write, run_cell(c, data[c.data]))
                    finished.extend(cells[:2])
                return mine

            monkeypatch.setattr(_run._Share, "take", take_then_the_other_finishes_two)
            lines = []

            def log(line: str) -> None:
                lines.append(line)
                if "waits for them" in line:
                    in_other(other.close)  # the other run stops: its last cell is free

            run = gx.run_grid(spec, store, log=log)
        finally:
            in_other(other.close)
    said = [x for x in lines if "waits for them" in x]
    assert finished and len(said) == 1, lines
    assert said[0].strip().startswith("1 of the cells to run are being run by another run"), said
    assert run.ran == 1 and any("2 cell(s) were run meanwhile by another run" in n for n in run.notes), run
    assert len(gx.load_results(store)) == len(cells)


def test_what_the_readme_and_the_package_say_is_exported_at_the_top_is():
    """The README's layout and graybox's docstring said "every public name is exported from graybox", and the
    API reference that only the plots', the experiments' and the simulators' are not: gb.run_grid,
    gb.plot_pareto, gb.TABLE_I, gb.BUCK_STATIC_CURVE and gb.find_buck_dir raise AttributeError, while four of
    the experiments' names are at the top. They now say which are, and these hold them to it."""
    import importlib
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    layout = readme.split("## Layout", 1)[1].split("| package |", 1)[0]
    top = set(gb.__all__)
    for unit in ("core", "static", "models", "selection", "estimation", "diagnostics", "control", "io"):
        names = importlib.import_module(f"graybox.{unit}").__all__
        assert set(names) <= top, (unit, sorted(set(names) - top))
    datasets = importlib.import_module("graybox.datasets")
    said_there = {"design_input", "decimate", "decimation_advice", "DecimationAdvice"}
    for name in datasets.__all__:
        assert (name in top) == (name.startswith("load_") or name in said_there), name
    for shown in ("gb.datasets.PumpingPlant", "gb.datasets.BUCK_STATIC_CURVE", "gb.reference.TABLE_I",
                  "gb.plots.plot_pareto", "gb.experiments.run_grid"):
        assert f"`{shown}`" in layout
        mod, name = shown.split(".")[1:]
        assert name not in top and hasattr(importlib.import_module(f"graybox.{mod}"), name), shown
    for unit in ("reference", "plots"):
        assert not set(importlib.import_module(f"graybox.{unit}").__all__) & top, unit
    at_top = {n for n in importlib.import_module("graybox.experiments").__all__ if n in top}
    assert at_top == {"select_graybox", "GrayboxSelection", "SelectionWarning", "load_results"}
    for text in (layout, gb.__doc__):
        assert "every public name is exported" not in text
        assert all(f"`{n}`" in text for n in at_top), text


ONE_CELL_SPEC = """\
name = "one"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order NARX"
terms = ["y(k-1)", "u(k-1)", "1"]
[[variants]]
name = "least squares fit"
estimator = "ls"
"""


def test_a_heatmap_of_one_structure_and_one_variant_has_room_for_its_names(tmp_path):
    """The heat map's size counted cells only (2.3 x 1.9 in for one cell): with a structure named in ten
    characters or more the labels, the colour bar and the title left the axes no room, matplotlib said
    "constrained_layout not applied because axes sizes collapsed to zero" (graybox grid report printed it)
    and the figure came out cramped. The figure now makes room for its labels."""
    import io
    import warnings

    from graybox import experiments as gx

    spec = tmp_path / "spec.toml"
    spec.write_text(ONE_CELL_SPEC, encoding="utf-8")
    store = tmp_path / "s.sqlite"
    gx.run_grid(spec, store)
    df = gx.load_results(store)
    for name in ("first-order NARX", "a structure with a rather long name, as grids of many have"):
        fig = gx.plot_heatmap(df.assign(structure=name), data="pumping")
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            fig.savefig(io.BytesIO(), format="png", dpi=110)
        fig.draw_without_rendering()  # laid out at the figure's own dpi, as measured below
        ax = fig.axes[0]
        box = ax.get_position()
        assert box.width > 0.05 and box.height > 0.05, box
        renderer = fig._get_renderer()
        page = fig.bbox
        for label in [*ax.get_xticklabels(), *ax.get_yticklabels()]:
            extent = label.get_window_extent(renderer)
            assert extent.x0 >= page.x0 - 1 and extent.y0 >= page.y0 - 1, (label.get_text(), extent, page)


def test_grid_status_of_cells_stopped_at_their_time_limit_does_not_say_none_finished(tmp_path):
    """A cell stopped at --cell-time-limit (or whose worker died twice) is stored as failed without a run time:
    with only such cells done, graybox grid status said "2 of 2 cells done ..., 0 left; no cell finished yet;
    last finished 2026-…", contradicting itself."""
    import sqlite3

    from graybox import experiments as gx

    spec = tmp_path / "spec.toml"
    spec.write_text(ONE_CELL_SPEC.replace('name = "least squares fit"\nestimator = "ls"',
                                          'name = "LS"\nestimator = "ls"\n[[variants]]\nname = "ELS"\n'
                                          'estimator = "els"'), encoding="utf-8")
    store = tmp_path / "s.sqlite"
    gx.run_grid(spec, store)
    with sqlite3.connect(store) as con:  # as the executors write a cell stopped at its time limit
        con.execute("UPDATE cells SET status = 'failed', wall_time = NULL, message = 'stopped after the cell "
                    "time limit of 0.5 s (its worker was stopped)'")
    con.close()
    status = gx.grid_status(store)
    assert status.done == 2 and status.left == 0 and np.isnan(status.time_per_cell)
    text = status.summary()
    assert "no cell finished yet" not in text and "last finished" in text, text
    assert "2 of 2 cells done" in text and "no run time" in text, text


def test_every_field_of_a_public_value_is_in_its_docstring():
    """The API reference documents a value's fields from its docstring: OperatingCurve.model_name was in
    none (test_api checks the functions' arguments, not the values' fields)."""
    import dataclasses
    import inspect

    from graybox import experiments as gx

    missing = {}
    for mod in (gb, gx):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isclass(obj) and dataclasses.is_dataclass(obj):
                doc = inspect.getdoc(obj) or ""
                gone = [f.name for f in dataclasses.fields(obj) if f.name not in doc]
                if gone:
                    missing[f"{mod.__name__}.{name}"] = gone
    assert not missing, missing


@pytest.mark.parametrize("argv", [["reproduce", "--quick"], ["grid", "status", "s.sqlite"]])
def test_ctrl_c_while_the_command_loads_is_a_line_not_a_traceback(monkeypatch, capsys, argv):
    """Ctrl-C in the first second of graybox reproduce (or grid ...), while the command imports numpy, scipy and
    matplotlib before its own handlers are in place, printed a KeyboardInterrupt traceback through importlib
    and ended the process by the signal; it now says it was interrupted and exits 130, as later."""
    from graybox import _cli

    def interrupted(*args, **kwargs):  # Ctrl-C as the command starts
        raise KeyboardInterrupt

    monkeypatch.setattr("argparse.ArgumentParser.parse_args", interrupted)
    assert _cli.main(argv) == 130
    captured = capsys.readouterr()
    assert captured.err.strip() == "graybox: interrupted" and not captured.out, captured


def test_grid_run_help_names_the_values_its_texts_speak_of(capsys):
    """graybox grid run --help said "start a Dask LocalCluster of N worker processes" and "run in N local worker
    processes" beside a usage of --workers WORKERS and --processes PROCESSES (and --scheduler SCHEDULER for "this
    address"), while the spec that grid init prints and the README write [--workers N | --scheduler ADDRESS]."""
    from graybox import _cli

    with pytest.raises(SystemExit):
        _cli.main(["grid", "run", "--help"])
    text = capsys.readouterr().out
    assert "[--workers N | --scheduler ADDRESS | --processes N]" in " ".join(text.split()), text
    for word in ("WORKERS", "PROCESSES", "SCHEDULER"):
        assert word not in text, text
    from graybox.experiments import EXAMPLE_SPEC

    assert "[--workers N | --scheduler ADDRESS]" in EXAMPLE_SPEC


@pytest.mark.parametrize("labels, error", [([1, 2], TypeError), ([None, "b"], TypeError), (["", "b"], ValueError),
                                           (["a", "  "], ValueError)])
def test_compare_results_refuses_labels_that_are_not_names(tmp_path, labels, error):
    """labels=[1, 2] were turned into '1' and '2' without a word (the docstring: a sequence of str), None into
    'None', and an empty label made the variants ': LS', a store called nothing in every table and figure."""
    from graybox import experiments as gx

    stores = []
    for name in ("a", "b"):
        spec = tmp_path / f"{name}.toml"
        spec.write_text(ONE_CELL_SPEC, encoding="utf-8")
        stores.append(tmp_path / f"{name}.sqlite")
        gx.run_grid(spec, stores[-1])
    with pytest.raises(error, match="labels"):
        gx.compare_results(stores, labels=labels)
    assert sorted(set(gx.compare_results(stores, labels=["x", "y"])["store"])) == ["x", "y"]


def test_a_count_of_worker_processes_no_machine_could_hold_is_refused_naming_it(tmp_path, capsys):
    """10**20 worker processes was handed to the pool or to Dask's LocalCluster (hunt49c's note)."""
    from graybox import experiments as gx
    from graybox._cli import main
    from graybox.experiments._executors import make_executor
    from graybox.experiments._map import parallel_map

    huge = 10**20
    with pytest.raises(ValueError, match=r"workers=100000000000000000000 is too large"):
        make_executor("processes", workers=huge)
    with pytest.raises(ValueError, match="workers=.* is too large"):
        make_executor("dask", workers=huge)
    with pytest.raises(ValueError, match="workers=.* is too large"):
        with parallel_map(executor="processes", workers=huge):
            pass
    spec = tmp_path / "spec.toml"
    spec.write_text(gx.EXAMPLE_SPEC, encoding="utf-8")
    for flag in ("--processes", "--workers"):  # the command's main here: a new process would add 1 s of imports
        capsys.readouterr()
        assert main(["grid", "run", str(spec), "--store", str(tmp_path / "s.sqlite"), flag, str(huge)]) == 2
        err = capsys.readouterr().err
        assert f"{flag}={huge} is too large" in err and "Traceback" not in err
        assert not (tmp_path / "s.sqlite").exists()
