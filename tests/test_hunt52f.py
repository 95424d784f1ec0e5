"""hunt52f: users' own files (CSV loaders, grid specs that read them)."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.experiments import DataSpec


def _miso_files(tmp_path):
    """A logger's two-input files with a units row whose inputs have different units (rpm and %)."""
    rows = ["t;speed;valve;p", "s;rpm;%;Pa"]
    rows += [f"{k * 0.1:.1f};{1000 + 100 * (k // 5 % 4)};{20 + 10 * (k // 7 % 3)};{0.5 * k}".replace(".", ",")
             for k in range(40)]
    for name in ("id.csv", "va.csv"):
        (tmp_path / name).write_text("\n".join(rows) + "\n", encoding="utf-8")
    (tmp_path / "st.csv").write_text("speed;valve;p\nrpm;%;Pa\n1000;20;6\n1500;80;11,5\n1200;50;8,5\n",
                                     encoding="utf-8")


def test_spec_file_tables_read_inputs_in_units_of_their_own(tmp_path):
    # a units row of mixed inputs gives each input its own unit; a spec's table may say them too, one per input,
    # and one unit for both contradicts the row
    _miso_files(tmp_path)
    rec = dict(u=["speed", "valve"], y="p", time="t", units_row=True)
    each = [["rpm", "%"], "Pa"]
    d = DataSpec("m", ident=dict(path="id.csv", **rec, units=each), valid=dict(path="va.csv", **rec, units=each),
                 static=dict(path="st.csv", u=["speed", "valve"], y="p", units_row=True, units=each))
    ds = d.load(tmp_path)
    assert ds.ident.units == ds.valid.units == ds.static.units == (("rpm", "%"), "Pa")
    assert d.to_dict()["ident"]["units"] == each
    bare = DataSpec("m", ident=dict(path="id.csv", **rec), valid=dict(path="va.csv", **rec),
                    static=dict(path="st.csv", u=["speed", "valve"], y="p", units_row=True))
    assert "units" not in bare.to_dict()["ident"]  # the canonical form of a spec without it is as before
    assert bare.load(tmp_path).ident.units == (("rpm", "%"), "Pa")
    one = DataSpec("m", ident=dict(path="id.csv", **rec, units=["rpm", "Pa"]), valid=dict(path="va.csv", **rec),
                   static=dict(path="st.csv", u=["speed", "valve"], y="p", units_row=True))
    with pytest.raises(ValueError, match=r"input 'valve' is in 'rpm', but the units row says '%'"):
        one.load(tmp_path)
    with pytest.raises(gb.experiments.SpecError, match="units"):
        DataSpec("m", ident=dict(path="id.csv", **rec, units="rpm"), valid=dict(path="va.csv", **rec),
                 static=dict(path="st.csv", u=["speed", "valve"], y="p"))


def _noted(tmp_path, rows):
    """A ';' file with a notes column whose quoted cells hold a line break (Alt+Enter in Excel)."""
    text = "t;u;y;note\r\n" + "".join(f'{t};{u};{y};"checked\nby JS"\r\n' for t, u, y in rows)
    p = tmp_path / "noted.csv"
    p.write_bytes(text.encode("utf-8"))
    return p


def test_a_bad_cell_is_named_at_the_line_its_sample_starts_on(tmp_path):
    # each sample spans two lines (2-3, 4-5, 6-7, 8-9 …): the 'x' of the fourth sample is on line 8, and the
    # message named line 9, the line its record ends on (csv's line_num), where no 'x' is
    rows = [(f"{k / 10:.1f}".replace(".", ","), "x" if k == 3 else str(k), str(2 * k)) for k in range(6)]
    with pytest.raises(ValueError, match=r"line 8, column 'u': 'x' is not a number"):
        gb.load_record_csv(_noted(tmp_path, rows), u="u", y="y", time="t")
    rec = gb.load_record_csv(_noted(tmp_path, [(r[0], "1", r[2]) for r in rows]), u="u", y="y", time="t")
    assert rec.y.tolist() == [0.0, 2.0, 4.0, 6.0, 8.0, 10.0] and rec.Ts == 0.1
    # the time check names the samples' lines likewise: the uneven step is from line 6 to line 8
    uneven = [("0", "1", "1"), ("0,1", "1", "1"), ("0,2", "1", "1"), ("0,35", "1", "1"), ("0,4", "1", "1")]
    with pytest.raises(ValueError, match=r"from line 6 to line 8"):
        gb.load_record_csv(_noted(tmp_path, uneven), u="u", y="y", time="t")


@pytest.mark.parametrize("cell, char", [("\u22121.5", r"U\+2212"), ("\u20131.5", r"U\+2013"), ("\uff0d1", r"U\+FF0D")])
def test_a_number_with_a_typographic_minus_names_the_character(tmp_path, cell, char):
    # '−1.5' with U+2212 MINUS SIGN (what word processors, web pages and some exports write) looks like a number, and
    # the message said only "'−1.5' is not a number": the character that is not ASCII '-' is now named
    p = tmp_path / "m.csv"
    p.write_text(f"t,u,y\n0,1,1\n1,{cell},2\n2,3,3\n", encoding="utf-8")
    with pytest.raises(ValueError, match=rf"line 3, column 'u': .* is not a number; it holds .*{char}.*'-'"):
        gb.load_record_csv(p, u="u", y="y", time="t")


def test_a_mapping_is_no_list_of_input_columns_nor_of_input_names(tmp_path):
    # u={"a": "rpm", "b": "%"} (columns with their units, say) was read as its keys, the units dropped without a
    # word; likewise input_names={"n1": ..., "n2": ...}
    p = tmp_path / "m.csv"
    p.write_text("t,a,b,y\n0,1,1,1\n1,2,2,2\n2,3,3,3\n", encoding="utf-8")
    for load, kw in ((gb.load_record_csv, dict(time="t")), (gb.load_static_csv, {})):
        with pytest.raises(TypeError, match=r"m\.csv: u must .* got a dict"):
            load(p, u={"a": "rpm", "b": "%"}, y="y", **kw)
        with pytest.raises(TypeError, match="input_names must be a sequence of names"):
            load(p, u=["a", "b"], y="y", input_names={"n1": 0, "n2": 1}, **kw)
    with pytest.raises(TypeError, match="input_names must be a sequence of names"):
        gb.Record([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]], [1.0, 2.0, 3.0], Ts=1.0, input_names={"n1": 0, "n2": 1})
    assert gb.load_record_csv(p, u=("b", "a"), y="y", time="t").input_names == ("b", "a")


@pytest.mark.parametrize("repeats", ["error", "mean"])
def test_a_static_files_uncertainty_of_the_wrong_length_names_the_file(tmp_path, repeats):
    # one δ per line of the file, two given for three lines: the message named only the points ('rig A: uncertainty
    # must be ...'), not the file whose lines they were to match
    p = tmp_path / "steady.csv"
    p.write_text("u,y\n1,2\n2,3\n3,4\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"steady\.csv: .*uncertainty"):
        gb.load_static_csv(p, u="u", y="y", name="rig A", uncertainty=[0.1, 0.2], repeats=repeats)
    with pytest.raises(ValueError, match=r"steady\.csv: .*uncertainty"):
        gb.load_static_csv(p, u="u", y="y", uncertainty=[0.1, 0.2, float("nan")], repeats=repeats)
    with pytest.raises(TypeError, match=r"steady\.csv: .*uncertainty"):
        gb.load_static_csv(p, u="u", y="y", uncertainty=[0.1, "x", 0.2], repeats=repeats)
    pts = gb.load_static_csv(p, u="u", y="y", uncertainty=[0.1, 0.2, 0.3], repeats=repeats)
    assert pts.uncertainty.tolist() == [0.1, 0.2, 0.3]


def test_a_spec_not_in_utf8_is_named_by_its_line_or_its_encoding(tmp_path):
    # a spec saved by Windows Notepad as "Unicode" (UTF-16) or "ANSI" (cp1252: 'Wärme' in a name) read
    # "cannot read the spec: it is not UTF-8 text (byte 0)": an offset into the file, which no editor shows
    from graybox.experiments import Grid, SpecError

    text = 'name = "heater"\n\n[[data]]\nname = "Wärme"\nbundled = "pumping"\n'
    ansi = tmp_path / "ansi.toml"
    ansi.write_bytes(text.encode("cp1252"))
    with pytest.raises(SpecError, match=r"ansi\.toml, line 4: .*not UTF-8 text"):
        Grid.from_toml(ansi)
    wide = tmp_path / "wide.toml"
    wide.write_bytes(text.encode("utf-16"))
    with pytest.raises(SpecError, match=r"wide\.toml: .*UTF-16 text.*save it as UTF-8"):
        Grid.from_toml(wide)


def test_a_missing_column_that_differs_by_a_lookalike_character_names_it(tmp_path):
    # 'Druck μbar' (GREEK SMALL LETTER MU, typed) against the file's 'Druck µbar' (MICRO SIGN, what cp1252 and Excel
    # write) read "no column 'Druck μbar' ... Did you mean 'Druck µbar'?": two names that print alike
    p = tmp_path / "mu.csv"
    p.write_text("t;Druck \u00b5bar;T \u00baC\n0;1;1\n1;2;2\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"Did you mean 'Druck \u00b5bar'\? \(the file's '\u00b5' is U\+00B5 MICRO SIGN, "
                                         r"the name asked for has '\u03bc', U\+03BC GREEK SMALL LETTER MU"):
        gb.load_record_csv(p, u="Druck \u03bcbar", y="T \u00baC", Ts=1.0)
    with pytest.raises(ValueError, match=r"U\+00BA MASCULINE ORDINAL INDICATOR.*U\+00B0 DEGREE SIGN"):
        gb.load_static_csv(p, u="Druck \u00b5bar", y="T \u00b0C")
    with pytest.raises(ValueError, match=r"Did you mean 'T \u00baC'\? The columns"):  # an ASCII typo: no such note
        gb.load_static_csv(p, u="Druck \u00b5bar", y="T \u00baF")


def test_a_mac_csv_not_in_utf8_is_sent_to_mac_roman_not_cp1252(tmp_path):
    # Excel's "CSV (Macintosh)" ends its lines in CR alone and writes Mac Roman: its '°' (0xa1) was refused with the
    # hint encoding='cp1252', which reads 0xa1 as '¡', so the units row gave the record the unit '¡C' without a word
    p = tmp_path / "mac.csv"
    p.write_bytes("t;P;Temp\rs;W;\u00b0C\r0;1,5;2\r0,5;2,5;3\r1;3,5;4\r".encode("mac_roman"))
    with pytest.raises(ValueError, match=r"mac\.csv: line 2 is not UTF-8 .*encoding='mac_roman'") as info:
        gb.load_record_csv(p, u="P", y="Temp", time="t", units_row=True)
    assert "cp1252" not in str(info.value)
    rec = gb.load_record_csv(p, u="P", y="Temp", time="t", units_row=True, encoding="mac_roman")
    assert rec.units == ("W", "\u00b0C") and rec.y.tolist() == [2.0, 3.0, 4.0] and rec.Ts == 0.5


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(breaks=st.lists(st.integers(0, 2), min_size=3, max_size=8), data=st.data(), eol=st.sampled_from(["\n", "\r\n"]),
       skip=st.integers(0, 2), units=st.booleans(), delim=st.sampled_from([",", ";", "\t"]))
def test_the_line_named_is_the_one_the_bad_sample_starts_on(tmp_path, breaks, data, eol, skip, units, delim):
    # samples whose notes hold 0-2 line breaks, a header block skipped, a units row or not: the bad cell's line is
    # the file's line where its sample starts
    bad = data.draw(st.integers(0, len(breaks) - 1))
    lines = [f"logger {i}" for i in range(skip)] + [delim.join(["t", "note", "u", "y"])]
    if units:
        lines.append(delim.join(["s", "", "rpm", "Pa"]))
    line, expected = len(lines) + 1, None
    for k, b in enumerate(breaks):
        if k == bad:
            expected = line
        lines.append(delim.join([str(k), '"' + "\n".join(["n"] * (b + 1)) + '"', "x" if k == bad else str(k), str(k)]))
        line += 1 + b
    p = tmp_path / "f.csv"
    p.write_bytes((eol.join(lines) + eol).encode())
    with pytest.raises(ValueError, match=rf"f\.csv: line {expected}, column 'u': 'x' is not a number"):
        gb.load_record_csv(p, u="u", y="y", time="t", skiprows=skip, units_row=units)


@pytest.mark.parametrize("kw", [dict(u="", y="y", Ts=1.0), dict(u="u", y="", Ts=1.0), dict(u="u", y="y", time=""),
                                dict(u="u", y="y", time="  "),
                                dict(u=["u", " "], y="y", Ts=1.0, input_names=["a", "b"])])
def test_an_empty_column_name_is_refused_not_read_as_the_unnamed_column(tmp_path, kw):
    # pandas' to_csv writes its index as a first column with no name: u="" (or y, time) read it without a word,
    # time="" taking the index 0, 1, 2 ... for stamps (Ts = 1 s); a spec refuses an empty name already
    p = tmp_path / "pandas.csv"
    p.write_text(",u,y\n0,1.5,2\n1,3.5,4\n2,5.5,6\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"pandas\.csv: .*names no column.*empty"):
        gb.load_record_csv(p, **kw)
    rec = gb.load_record_csv(p, u="u", y="y", Ts=0.5)
    assert rec.u.tolist() == [1.5, 3.5, 5.5] and rec.Ts == 0.5


@pytest.mark.parametrize("kw", [dict(u="", y="y"), dict(u="u", y=""), dict(u="u", y="y", uncertainty="")])
def test_an_empty_column_name_is_refused_by_the_static_loader(tmp_path, kw):
    p = tmp_path / "pandas.csv"
    p.write_text(",u,y\n1,1.5,2\n2,3.5,4\n3,5.5,6\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"pandas\.csv: .*names no column.*empty"):
        gb.load_static_csv(p, **kw)
    assert gb.load_static_csv(p, u="u", y="y").ybar.tolist() == [2.0, 4.0, 6.0]


@pytest.mark.parametrize("col, unit", [("Zeit [10ms]", "10ms"), ("t (0.1 s)", "0.1 s"), ("time [100 \u00b5s]", "100 \u00b5s")])
def test_a_time_column_in_ticks_of_a_unit_is_not_read_as_seconds(tmp_path, col, unit):
    # a PLC's 'Zeit [10ms]' counts ticks of 10 ms: its stamps 0, 1, 2 … were read as seconds, Ts = 1 s for 0.01 s
    # without a word ('t [ms]' and 't_ms' were refused, a tick with a number was not)
    p = tmp_path / "plc.csv"
    p.write_text(f"{col};u;y\n" + "".join(f"{k};{k % 3};{k}\n" for k in range(6)), encoding="utf-8")
    with pytest.raises(ValueError, match=rf"names its unit '{unit}', but time stamps are read as seconds"):
        gb.load_record_csv(p, u="u", y="y", time=col)
    for ok in ("t [1 s]", "t [1.0 s]", "time (s)", "Time [sec]"):
        q = tmp_path / "s.csv"
        q.write_text(f"{ok};u;y\n" + "".join(f"{k / 2};{k % 3};{k}\n" for k in range(6)), encoding="utf-8")
        assert gb.load_record_csv(q, u="u", y="y", time=ok).Ts == 0.5


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "UTF-16BE", "utf_32_le"])
def test_a_utf16_encoding_given_for_a_file_that_is_not_names_the_encoding(tmp_path, encoding):
    # encoding='utf-16' (Excel's "Unicode text", say) for a file saved as UTF-8 decoded its bytes in pairs into CJK
    # characters, and the error blamed the delimiter: "no column 'u' ... The header was read as one column, split at
    # ',': pass delimiter= ... The columns are ['ⱴⱵ...']"
    p = tmp_path / "run.csv"
    p.write_text("t,u,y\n0,1,2\n1,3,4\n2,5,6\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"run\.csv: .*encoding=.* no NUL bytes.*not UTF-(16|32)") as info:
        gb.load_record_csv(p, u="u", y="y", time="t", encoding=encoding)
    assert "delimiter" not in str(info.value)
    q = tmp_path / "wide.csv"
    q.write_bytes("t,u,y\n0,1,2\n1,3,4\n2,5,6\n".encode(encoding.replace("_", "-").lower()))
    assert gb.load_record_csv(q, u="u", y="y", time="t", encoding=encoding).u.tolist() == [1.0, 3.0, 5.0]


def test_a_quote_no_quote_closes_is_refused_not_read_as_the_rest_of_the_file(tmp_path):
    # an operator's note opening a quote it never closes ('"pump off') made the csv reader take every later line into
    # that one cell: a record of 10 samples was read as 4, without a word
    rows = ["t,u,y,note"] + [f"{k},{k % 3},{2 * k}," + ('"pump off' if k == 3 else "ok") for k in range(10)]
    p = tmp_path / "notes.csv"
    p.write_text("\n".join(rows) + "\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"notes\.csv: line 5, column 'note': a quote .* no quote closes.*"
                                         r"lines 5 to 11, the rest"):
        gb.load_record_csv(p, u="u", y="y", time="t")
    with pytest.raises(ValueError, match=r"notes\.csv: line 5, column 'note': a quote"):
        gb.load_static_csv(p, u="t", y="y")
    # a note spanning lines in a closed quote, and a quote inside a note, are read as before
    rows[4] = '3,0,6,"pump off\nfor a minute"'
    rows[6] = '5,2,10,12" pipe'
    p.write_text("\n".join(rows) + "\n\n", encoding="utf-8")
    assert gb.load_record_csv(p, u="u", y="y", time="t").y.tolist() == [2.0 * k for k in range(10)]


def test_a_quote_closed_lines_later_is_refused_not_read_as_one_sample(tmp_path):
    # a note's stray '"' opened a field that a '"' three lines on closed ('12" pipe'): with Ts given (no time column
    # to show the gap) a record of 10 samples was read as 7, lines 6 to 8 taken into the note without a word
    rows = ["u,y,note"] + [f"{k % 3},{2 * k}," + ('"pump off' if k == 3 else '12" pipe' if k == 6 else "ok")
                           for k in range(10)]
    p = tmp_path / "notes.csv"
    p.write_text("\n".join(rows) + "\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"notes\.csv: line 5, column 'note': a quote .* closes only on line 8, so "
                                         r"lines 6 to 8, which read as samples \('1,8,ok'\)"):
        gb.load_record_csv(p, u="u", y="y", Ts=0.1)
    with pytest.raises(ValueError, match=r"notes\.csv: line 5, column 'note': a quote"):
        gb.load_static_csv(p, u="y", y="u")


def test_a_note_spanning_lines_of_numbers_is_still_read(tmp_path):
    # a closed note whose second line holds numbers with commas ('3,5\n4,2') is no swallowed sample of a 4-column file
    p = tmp_path / "notes.csv"
    p.write_text('u,y,z,note\n1,2,0,"set to\n4,2"\n3,4,0,ok\n5,6,0,"a\n1,2,3"\n', encoding="utf-8")
    assert gb.load_record_csv(p, u="u", y="y", Ts=1.0).y.tolist() == [2.0, 4.0, 6.0]


@pytest.mark.parametrize("col, refused", [("t [1/10 s]", True), ("t [1e-3 s]", True), ("t (2.5e-2 s)", True),
                                          ("t [1 s]", False), ("Time (s)", False), ("t [1.0 s]", False)])
def test_a_time_column_in_ticks_written_as_a_fraction_or_a_power_is_refused(tmp_path, col, refused):
    # 't [1/10 s]' and 't [1e-3 s]' were read as seconds: a sampling period off by 10 or 1000 without a word
    p = tmp_path / "r.csv"
    p.write_text(f"{col},u,y\n" + "".join(f"{k},{k % 3},{0.5 * k}\n" for k in range(20)), encoding="utf-8")
    if refused:
        with pytest.raises(ValueError, match="time stamps are read as seconds"):
            gb.load_record_csv(p, u="u", y="y", time=col)
    else:
        assert gb.load_record_csv(p, u="u", y="y", time=col).Ts == 1.0
