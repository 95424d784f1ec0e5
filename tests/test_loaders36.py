"""A lab's own files as they come (loaders36): a data logger's header block read with ``skiprows=``,
Excel's ``sep=;`` first line used as the delimiter it names, δ read from a column, units carried
on static points. Every message names the file's own line numbers (line 1 = its first line), on
the fast reader (numpy's) and on the careful one (Python's csv, taken for quoted fields)."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graybox.datasets import load_record_csv, load_static_csv

BLOCK = "# Logger TL-400 serial 0412\n# started 2026-11-20 09:14:03\nchannels: speed, pressure; 0.5 s\n"


def write(tmp_path: Path, text: str, name: str = "data.csv") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def quoted(text: str) -> str:
    """The same rows with every field of the data lines quoted: numpy's reader is then not taken."""
    head, *rows = text.split("\n")
    return "\n".join([head] + [",".join(f'"{c}"' for c in r.split(",")) if r else r for r in rows])


ROWS = "t,speed,pressure\n0.0,1000,8.1\n0.5,1000,8.2\n1.0,1100,8.3\n1.5,1100,8.9\n"


# -- skiprows: a data logger's header block ------------------------------------------------------

@pytest.mark.parametrize("form", [str, quoted], ids=["fast", "careful"])
def test_skiprows_reads_the_file_below_a_header_block(tmp_path, form):
    plain = load_record_csv(write(tmp_path, form(ROWS), "plain.csv"), u="speed", y="pressure", time="t")
    logged = load_record_csv(write(tmp_path, BLOCK + form(ROWS)), u="speed", y="pressure", time="t", skiprows=3)
    np.testing.assert_array_equal(logged.u, plain.u)
    np.testing.assert_array_equal(logged.y, plain.y)
    assert logged.Ts == plain.Ts == 0.5
    steady = write(tmp_path, BLOCK + form("speed,pressure\n1000,1.5\n2000,2.5\n"), "steady.csv")
    points = load_static_csv(steady, u="speed", y="pressure", skiprows=3)
    np.testing.assert_array_equal(points.ubar, [1000, 2000])


@pytest.mark.parametrize("form", [str, quoted], ids=["fast", "careful"])
def test_lines_named_below_a_skipped_block_are_the_file_s_own(tmp_path, form):
    # a missing sample between file lines 7 and 8 (lines 4 and 5 of the file without its block)
    uneven = BLOCK + form("t,u,y\n0,1,2\n0.1,1,2\n0.2,1,2\n0.4,1,2\n0.5,1,2\n")
    p = write(tmp_path, uneven)
    with pytest.raises(ValueError, match=re.escape(f"{p}: column 't': uneven time stamps") + ".*line 7 to line 8"):
        load_record_csv(p, u="u", y="y", time="t", skiprows=3)
    p = write(tmp_path, BLOCK + form("rpm,mlc\n750,3.9\n850,5.2\n750.0,4.0\n"), "static.csv")
    with pytest.raises(ValueError, match=re.escape(f"{p}: column 'rpm': lines 5 and 7 have the same input level")):
        load_static_csv(p, u="rpm", y="mlc", skiprows=3)
    p = write(tmp_path, BLOCK + form("t,u,y\n0,1,2\n0.1,1,nan\n"), "nan.csv")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 6, column 'y'")):
        load_record_csv(p, u="u", y="y", time="t", skiprows=3)


def test_dialect_messages_below_a_skipped_block_name_the_file_s_lines(tmp_path):
    p = write(tmp_path, BLOCK + "t;u;y\n0;1;2\n0,5;1;2\n1.0;1;2\n")
    with pytest.raises(ValueError, match=r"decimal mark is ambiguous: line 7 has '1\.0' and line 6 has '0,5'"):
        load_record_csv(p, u="u", y="y", time="t", skiprows=3)
    p = write(tmp_path, BLOCK + "t,u,y\n0,1,2\n1;1;2\n", "mixed.csv")
    with pytest.raises(ValueError, match=r"the header \(line 4\) is separated by ',' but line 6 by ';'"):
        load_record_csv(p, u="u", y="y", time="t", skiprows=3)
    with pytest.raises(ValueError, match=r"line 5: no data rows after the header"):
        load_record_csv(write(tmp_path, BLOCK + "u,y\n", "h.csv"), u="u", y="y", Ts=1.0, skiprows=3)
    with pytest.raises(ValueError, match=r"line 5 names the columns.*pass skiprows=4"):  # a blank line left
        load_record_csv(write(tmp_path, BLOCK + "\nu,y\n1,2\n", "b.csv"), u="u", y="y", Ts=1.0, skiprows=3)
    with pytest.raises(ValueError, match=r"line 4: the file is empty after the 3 line\(s\) skipped"):
        load_record_csv(write(tmp_path, BLOCK, "e.csv"), u="u", y="y", Ts=1.0, skiprows=3)


def test_a_bad_byte_below_a_skipped_block_names_its_own_line(tmp_path):
    p = tmp_path / "latin.csv"
    p.write_bytes(BLOCK.encode() + "u,y\n1,2\n3,4\n5,\xb0\n".encode("cp1252"))
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 7 is not UTF-8 text")):
        load_record_csv(p, u="u", y="y", Ts=1.0, skiprows=3)


def test_an_unskipped_header_block_is_refused_naming_skiprows(tmp_path):
    p = write(tmp_path, BLOCK + ROWS)
    with pytest.raises(ValueError, match=r"line 4 names the columns.*3 line\(s\) before.*pass skiprows=3") as err:
        load_record_csv(p, u="speed", y="pressure", time="t")
    assert "pandas" not in str(err.value)  # the loader itself does it now
    with pytest.raises(ValueError, match=r"line 4 names the columns.*pass skiprows=3"):
        load_record_csv(p, u="speed", y="pressure", time="t", skiprows=1)  # too few: still the file's own count
    with pytest.raises(ValueError, match=r"line 4 names the columns.*pass skiprows=3"):
        load_static_csv(p, u="speed", y="pressure")


def test_skipping_the_column_names_themselves_is_named(tmp_path):
    p = write(tmp_path, BLOCK + ROWS)
    with pytest.raises(ValueError, match=r"skiprows=4 skips line 4, which names the columns: pass skiprows=3"):
        load_record_csv(p, u="speed", y="pressure", time="t", skiprows=4)


@pytest.mark.parametrize("bad, exc", [(-1, ValueError), (1.5, TypeError), ("3", TypeError), (True, TypeError)])
def test_skiprows_is_a_count(tmp_path, bad, exc):
    with pytest.raises(exc, match="skiprows"):
        load_record_csv(write(tmp_path, ROWS), u="speed", y="pressure", time="t", skiprows=bad)
    with pytest.raises(exc, match="skiprows"):
        load_static_csv(write(tmp_path, ROWS), u="speed", y="pressure", skiprows=bad)


@settings(max_examples=30, deadline=None)
@given(block=st.lists(st.sampled_from(["# logger", "serial;0412", "a,b", "", "date\t2026-11-20", '"x, y"']),
                      max_size=6),
       bad=st.integers(0, 5), careful=st.booleans())
def test_a_block_shifts_every_line_named_by_its_length(block, bad, careful):
    # law: the line a message names in a file with a skipped block of k lines is the line it names
    # in the same file without the block, plus k
    rows = [f"{0.5 * i},{i},{i * 2}" for i in range(6)]
    rows[bad] = rows[bad].rsplit(",", 1)[0] + ",oops"
    body = "t,u,y\n" + "\n".join(rows) + "\n"
    if careful:
        body = quoted(body)
    with tempfile.TemporaryDirectory() as d:
        lines = []
        for k, text in ((0, body), (len(block), "".join(b + "\n" for b in block) + body)):
            p = Path(d) / f"f{k}.csv"
            p.write_text(text, encoding="utf-8")
            with pytest.raises(ValueError) as err:
                load_record_csv(p, u="u", y="y", time="t", skiprows=k)
            lines.append(int(re.search(r"line (\d+)", str(err.value)).group(1)))
    assert lines[1] == lines[0] + len(block)
    assert lines[0] == bad + 2


# -- Excel's sep= first line -------------------------------------------------------------------

def test_excel_s_delimiter_hint_is_used(tmp_path):
    p = write(tmp_path, "sep=;\nt;u;y\n0;1;2\n0,5;1;2\n")
    r = load_record_csv(p, u="u", y="y", time="t")
    assert r.Ts == 0.5 and len(r) == 2
    assert load_record_csv(p, u="u", y="y", time="t", delimiter=";").Ts == 0.5  # agrees: fine
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 1 is 'sep=;'") + ".*delimiter=','"):
        load_record_csv(p, u="u", y="y", time="t", delimiter=",")
    tab = write(tmp_path, "sep=\t\nu\ty\n1\t2\n3\t4\n", "tab.csv")
    np.testing.assert_array_equal(load_static_csv(tab, u="u", y="y").ybar, [2, 4])
    # a letter is no delimiter: not Excel's hint, and the line is named as one to skip
    odd = write(tmp_path, "sep=a\nu,y\n1,2\n3,4\n", "odd.csv")
    with pytest.raises(ValueError, match=r"line 2 names the columns.*pass skiprows=1"):
        load_static_csv(odd, u="u", y="y")


@pytest.mark.parametrize("form", [str, quoted], ids=["fast", "careful"])
def test_lines_below_a_sep_line_are_the_file_s_own(tmp_path, form):
    p = write(tmp_path, "sep=,\n" + form("t,u,y\n0,1,2\n0.1,1,2\n0.2,1,2\n0.4,1,2\n"))
    with pytest.raises(ValueError, match=r"uneven time stamps.*line 5 to line 6"):
        load_record_csv(p, u="u", y="y", time="t")
    p = write(tmp_path, "sep=,\n" + form("u,y\n1,2\n3,x\n"), "x.csv")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 4, column 'y': 'x' is not a number")):
        load_record_csv(p, u="u", y="y", Ts=1.0)
    # a sep= line below a skipped block is the delimiter hint too
    p = write(tmp_path, BLOCK + "sep=;\n" + "u;y\n1;2\n3;x\n", "both.csv")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 7, column 'y'")):
        load_record_csv(p, u="u", y="y", Ts=1.0, skiprows=3)


# -- uncertainty="column" --------------------------------------------------------------------

STEADY = "speed,pressure,sem\n1000,1.5,0.02\n1500,2.0,0.03\n2000,2.5,0.05\n"


@pytest.mark.parametrize("form", [str, quoted], ids=["fast", "careful"])
def test_uncertainty_read_from_a_column(tmp_path, form):
    p = write(tmp_path, form(STEADY))
    points = load_static_csv(p, u="speed", y="pressure", uncertainty="sem")
    np.testing.assert_array_equal(points.uncertainty, [0.02, 0.03, 0.05])
    same = load_static_csv(p, u="speed", y="pressure", uncertainty=[0.02, 0.03, 0.05])
    assert points.band == same.band
    # the column's numbers follow the file's decimal mark, as the other columns do
    semi = write(tmp_path, BLOCK + STEADY.replace(",", ";").replace(".", ","), "semi.csv")
    np.testing.assert_array_equal(load_static_csv(semi, u="speed", y="pressure", uncertainty="sem",
                                                  skiprows=3).uncertainty, [0.02, 0.03, 0.05])


def test_uncertainty_column_with_repeats_is_averaged_per_level_as_ybar(tmp_path):
    p = write(tmp_path, "u1,u2,p,sem\n1,1,2.0,0.1\n2,1,3.0,0.2\n1,1,2.2,0.3\n")
    points = load_static_csv(p, u=["u1", "u2"], y="p", uncertainty="sem", repeats="mean")
    given_ = load_static_csv(p, u=["u1", "u2"], y="p", uncertainty=[0.1, 0.2, 0.3], repeats="mean")
    np.testing.assert_allclose(points.uncertainty, given_.uncertainty)
    np.testing.assert_allclose(points.uncertainty, [0.2, 0.2])


@pytest.mark.parametrize("form", [str, quoted], ids=["fast", "careful"])
@pytest.mark.parametrize("cell, what", [("nan", "not a finite number"), ("", "empty cell"), ("-0.03", "> 0"),
                                        ("0", "> 0"), ("n/a", "'n/a' is not a number")])
def test_a_bad_uncertainty_cell_names_file_line_and_column(tmp_path, form, cell, what):
    p = write(tmp_path, BLOCK + form(STEADY.replace("0.03", cell)))
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 6, column 'sem'") + ".*" + re.escape(what)):
        load_static_csv(p, u="speed", y="pressure", uncertainty="sem", skiprows=3)


def test_an_uncertainty_column_is_named_like_the_others(tmp_path):
    p = write(tmp_path, STEADY)
    with pytest.raises(ValueError, match=r"no column 'SEM' \(asked for as uncertainty\).*Did you mean 'sem'"):
        load_static_csv(p, u="speed", y="pressure", uncertainty="SEM")
    with pytest.raises(ValueError, match=r"y, uncertainty all name the column 'pressure'"):
        load_static_csv(p, u="speed", y="pressure", uncertainty="pressure")


# -- units on static points ------------------------------------------------------------------

def test_static_points_carry_units_as_a_record_does():
    import graybox as gb

    plain = gb.StaticPoints([1.0, 2.0], [3.0, 4.0])
    assert plain.units == ("", "") == gb.Record([1.0, 2.0], [3.0, 4.0]).units  # same default
    sp = gb.StaticPoints([1.0, 2.0], [3.0, 4.0], units=["rpm", "mlc"])
    assert sp.units == ("rpm", "mlc") and isinstance(sp.units, tuple)
    assert "rpm" in repr(sp) and "mlc" in repr(sp) and "rpm" not in repr(plain)
    for bad in ("rpm", ("rpm",), ("rpm", 1), None):
        with pytest.raises(TypeError, match=r"units must be a pair of strings \(input unit, output unit\)"):
            gb.StaticPoints([1.0, 2.0], [3.0, 4.0], units=bad)
        with pytest.raises(TypeError, match=r"units must be a pair of strings \(input unit, output unit\)"):
            gb.Record([1.0, 2.0], [3.0, 4.0], units=bad)  # the same check


def test_every_static_points_made_from_others_keeps_their_units():
    import graybox as gb
    from graybox.diagnostics._bootstrap import BootstrapJob

    sp = gb.StaticPoints([1.0, 2.0, 3.0], [3.0, 4.0, 6.0], units=("rpm", "mlc"))
    assert sp.with_uncertainty(0.1).units == ("rpm", "mlc")
    assert gb.StaticPoints.from_repeats([1.0, 1.0, 2.0], [3.0, 3.2, 4.0], units=("rpm", "mlc")).units == ("rpm", "mlc")
    assert gb.transient_inputs(sp, [1.0]).units == ("rpm", "mlc")
    rec = gb.Record(np.sin(np.arange(40.0)), np.cos(np.arange(40.0)), units=("rpm", "mlc"))
    job = BootstrapJob(gb.Structure(["y(k-1)"]), (rec,), sp, "pe", np.array([0.5]), 1.0, None, 10, 0, 0.1)
    assert job.data(0)[1].units == ("rpm", "mlc")


def test_load_static_csv_carries_units(tmp_path):
    p = write(tmp_path, STEADY)
    assert load_static_csv(p, u="speed", y="pressure").units == ("", "")
    assert load_static_csv(p, u="speed", y="pressure", units=("rpm", "bar")).units == ("rpm", "bar")
    assert load_static_csv(p, u="speed", y="pressure", units=("rpm", "bar"), repeats="mean").units == ("rpm", "bar")
    with pytest.raises(TypeError, match=r"units must be a pair of strings"):
        load_static_csv(p, u="speed", y="pressure", units="rpm")


def test_the_bundled_static_points_carry_their_records_units():
    import graybox as gb

    for data in (gb.load_pumping(), gb.load_buck(), gb.load_pumping_miso()):
        assert data.static.units == data.ident.units


def test_plots_of_static_points_label_axes_with_their_units():
    import matplotlib

    matplotlib.use("Agg")
    import graybox as gb
    from graybox import plots

    sp = gb.StaticPoints([1.0, 2.0, 3.0], [3.0, 4.0, 6.0], units=("rpm", "mlc"))
    ax = plots.plot_static_curve(sp).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("input ū (rpm)", "output ȳ (mlc)")
    ax = plots.plot_static_curve(sp, xlabel="Speed (rpm)", ylabel="Pressure").axes[0]  # a unit given is not doubled
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("Speed (rpm)", "Pressure (mlc)")
    ax = plots.plot_static_curve(gb.StaticPoints([1.0, 2.0], [3.0, 4.0])).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("input ū", "output ȳ")
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    u = np.random.default_rng(0).uniform(1, 3, 200)
    y = np.zeros(200)
    for k in range(1, 200):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.01 * np.sin(k)
    rec = gb.Record(u, y)
    band = gb.static_curve_band(gb.ls_uncertainty(gb.els(model.structure, rec).model, rec), np.linspace(1, 3, 5))
    fig = plots.plot_static_band(band, sp)
    assert [a.get_xlabel() for a in fig.axes] == ["input ū (rpm)"] * 2
    assert fig.axes[0].get_ylabel() == "output ȳ (mlc)" and fig.axes[1].get_ylabel() == "static gain dȳ/dū (mlc/rpm)"
    two = gb.StaticPoints([[1.0, 1.0], [2.0, 1.0], [1.0, 2.0], [2.0, 2.0]], [1.0, 2.0, 3.0, 4.0], units=("rpm", "mlc"))
    ax = plots.plot_surface_slices(None, two).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("input u1 (rpm)", "output ȳ (mlc)")
    fig = plots.plot_surface_contours(lambda U: U[:, 0] + U[:, 1], two)
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("input u1 (rpm)", "input u2 (rpm)")
    assert fig.axes[1].get_ylabel() == "output ȳ (mlc)"  # the colour bar


def test_data_of_one_identification_in_other_units_are_refused():
    # was: records in rpm and static points in rad/s (each labelled) made one Dataset without a word,
    # the units mix-up the library's static range warning exists to catch
    import graybox as gb

    r = gb.Record(np.arange(10.0), np.arange(10.0), units=("rpm", "mlc"), name="ident")
    with pytest.raises(ValueError, match="'ident' has input unit 'rpm' but 'static points' has 'rad/s'"):
        gb.Dataset(r, r, gb.StaticPoints([1.0, 2.0], [3.0, 4.0], units=("rad/s", "mlc")))
    with pytest.raises(ValueError, match="output unit 'mlc' but 'valid' has 'Pa'"):
        gb.Dataset(r, gb.Record(np.arange(10.0), np.arange(10.0), units=("rpm", "Pa"), name="valid"))
    # a unit left empty says nothing: accepted
    assert gb.Dataset(r, r, gb.StaticPoints([1.0, 2.0], [3.0, 4.0], units=("", "mlc"))).static is not None


def test_saved_static_points_say_their_own_units_in_the_file_header(tmp_path):
    # was: gb.save(points) wrote a header without units although the points carry them
    import graybox as gb

    pts = gb.StaticPoints([1000.0, 2000.0], [3.0, 4.0], units=("rpm", "mlc"))
    p = gb.save(pts, tmp_path / "p.json")
    assert gb.read_header(p)["units"] == ("rpm", "mlc")
    # units= that contradict the points' own would make the header lie about the numbers (hunt 43c): refused
    with pytest.raises(ValueError, match="contradicts the units the StaticPoints carries"):
        gb.save(pts, tmp_path / "q.json", units=("rad/s", "Pa"))
    assert gb.read_header(gb.save(gb.StaticPoints([1.0, 2.0], [3.0, 4.0]), tmp_path / "r.json"))["units"] is None
