"""Bug hunt 38c: a newcomer's first hour and long experiments (CLI, CSV loaders, grids, stores)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import graybox as gb
from graybox import experiments as gx
from graybox._cli import main


def _tiny_files(folder: Path) -> Path:
    """Three small CSV files and a one-cell spec reading them; returns the spec's path."""
    rng = np.random.default_rng(3)
    for name, n in (("ident.csv", 120), ("valid.csv", 60)):
        u = np.repeat(rng.uniform(1.0, 2.0, n // 10), 10)
        y = np.zeros(n)
        for k in range(1, n):
            y[k] = 0.5 * y[k - 1] + u[k - 1]
        (folder / name).write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(u, y)))
    (folder / "static.csv").write_text("u,y\n1.0,2.0\n1.5,3.0\n2.0,4.0\n")
    spec = folder / "spec.toml"
    spec.write_text('name = "tiny"\n[[data]]\nname = "d"\n'
                    'ident = {path = "ident.csv", u = "u", y = "y", Ts = 1.0}\n'
                    'valid = {path = "valid.csv", u = "u", y = "y", Ts = 1.0}\n'
                    'static = {path = "static.csv", u = "u", y = "y", uncertainty = 0.1}\n'
                    '[[structures]]\nname = "fo"\nterms = ["y(k-1)", "u(k-1)"]\n'
                    '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    return spec


# --- a scheduler address that is no Dask scheduler's address -----------------------------------------------------
@pytest.mark.parametrize("address, said", [
    ("localhost:notaport", "port"),                       # was: invalid literal for int() with base 10: 'notaport'
    ("http://127.0.0.1:8787/status", "dashboard"),        # the dashboard's URL pasted: was 'unknown address scheme'
    ("foo://host:8786", "scheme"),
])
def test_a_malformed_scheduler_address_is_refused_naming_it_before_the_store_is_written(tmp_path, capsys, address,
                                                                                          said):
    with pytest.raises(ValueError, match="scheduler") as err:
        with gx.parallel_map(scheduler=address):
            pass
    assert address in str(err.value) and said in str(err.value)
    spec = _tiny_files(tmp_path)
    store = tmp_path / "r.sqlite"
    assert main(["grid", "run", str(spec), "--store", str(store), "--scheduler", address]) == 2
    text = capsys.readouterr().err
    assert "scheduler" in text and address in text and said in text
    assert not store.exists()  # refused before anything was written


def test_a_tls_scheduler_without_security_settings_is_an_error_naming_it_not_a_traceback(tmp_path, capsys):
    # distributed raises a TypeError (no ssl_context) from Client(): the command crashed with a traceback
    spec = _tiny_files(tmp_path)
    assert main(["grid", "run", str(spec), "--store", str(tmp_path / "r.sqlite"), "--scheduler",
                 "tls://127.0.0.1:1"]) == 2
    text = capsys.readouterr().err
    assert "tls://127.0.0.1:1" in text and "client=" in text


# --- names from a spec drawn as text, not as matplotlib's mathtext or hidden legend labels -------------------------
def _named_store(tmp_path: Path) -> Path:
    spec = _tiny_files(tmp_path)
    text = spec.read_text().replace('name = "d"', 'name = "rig $x^$"').replace('name = "fo"', 'name = "fo $\\\\x$"')
    text += ('[[variants]]\nname = "_base"\nestimator = "els"\n'
             '[[variants]]\nname = "cost $5 or $10"\nestimator = "pe"\nlambdas = [0.5, 1.0]\n'
             'decision = {rule = "dsf", fallback = "min_jsf"}\n')
    spec.write_text(text)
    store = tmp_path / "names.sqlite"
    gx.run_grid(spec, store)
    return store


def test_grid_report_figures_show_the_names_of_the_spec_as_written(tmp_path):
    # a structure named 'fo $\x$' crashed graybox grid report with matplotlib's 'ParseFatalException: Unknown
    # symbol: \x'; '$5 or $10' was typeset as math, and the variant '_base' left out of every legend
    store = _named_store(tmp_path)
    written = gx.write_report(store, tmp_path / "report", html=True)
    assert {"report.html", "scatter.png"} <= {p.name for p in written}
    for fig in (gx.plot_scatter(store), gx.plot_fronts(store), gx.plot_heatmap(store)):
        fig.canvas.draw()  # the figure renders
        texts = set()
        for ax in fig.axes:
            texts |= {t.get_text() for t in ax.texts + ax.get_xticklabels() + ax.get_yticklabels()}
            texts.add(ax.get_title())
            if ax.get_legend() is not None:
                texts |= {t.get_text() for t in ax.get_legend().get_texts()}
        if fig._suptitle is not None:
            texts.add(fig._suptitle.get_text())
        shown = " | ".join(texts).replace("\\$", "$")  # an escaped dollar is drawn as a dollar
        for n in ("rig $x^$", "fo $\\x$", "_base", "cost $5 or $10", "LS"):
            assert n in shown, (n, shown)
        legend = [t.get_text() for ax in fig.axes if ax.get_legend() is not None for t in ax.get_legend().get_texts()]
        assert not legend or "_base" in [t.strip() for t in legend], legend


# --- pandas columns of text or dates are no numbers ---------------------------------------------------------------
@pytest.mark.parametrize("column", [
    pd.Series(["1.5", "2.5", "3.5"]),                        # object dtype: parsed silently
    pd.Series(["1.5", "2.5", "3.5"], dtype="string"),
    pd.Series(pd.date_range("2026-11-26", periods=3, freq="s")),   # read as µs since 1970: u ≈ 1.8e15
    pd.Series(pd.to_timedelta([0, 1, 2], unit="s")),
])
def test_a_column_of_text_or_dates_is_refused_as_a_wrong_type(column):
    with pytest.raises(TypeError, match="must be numbers"):
        gb.Record(column, [1.0, 2.0, 3.0], Ts=1.0)
    with pytest.raises(TypeError, match="must be numbers"):
        gb.Record([1.0, 2.0, 3.0], column, Ts=1.0)
    with pytest.raises(TypeError, match="must be numbers"):
        gb.StaticPoints(column, [1.0, 2.0, 3.0])
    # numbers held in an object array are numbers
    rec = gb.Record(pd.Series([1.5, 2.5, 3.5], dtype=object), [1.0, 2.0, 3.0], Ts=1.0)
    assert rec.u.tolist() == [1.5, 2.5, 3.5]


def test_a_dataframe_of_inputs_holding_the_output_column_is_refused():
    # Record(df, df["y"]) read the frame by position: two inputs u1 = u, u2 = y, the output fed in as an input
    df = pd.DataFrame({"u": [1.0, 2.0, 3.0, 4.0], "y": [0.5, 1.0, 1.5, 2.0]})
    with pytest.raises(ValueError, match="'y'.*the output") as err:
        gb.Record(df, df["y"], Ts=1.0)
    assert "drop(columns='y')" in str(err.value)
    with pytest.raises(ValueError, match="the output"):
        gb.StaticPoints(df, df["y"])
    # a Series is a signal whose labels may be anything, 'y' among them
    assert gb.Record(pd.Series([1.0, 2.0], index=["x", "y"]), [1.0, 2.0]).u.tolist() == [1.0, 2.0]
    assert gb.Record(df[["u"]], df["y"], Ts=1.0).u.tolist() == [1.0, 2.0, 3.0, 4.0]
    assert gb.Record(df.drop(columns="y"), df["y"], Ts=1.0).n_inputs == 1
