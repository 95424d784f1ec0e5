"""A newcomer's own logger files: Campbell Scientific's TOA5 (LoggerNet, CardConvert) read without options, its
binary TOB1/2/3 refused as what they are, and the other loggers' ASCII exports a lab hands round."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb

#: The four header lines of a TOA5 file as a CR1000 writes them: every text field quoted.
TOA5_HEAD = ('"TOA5","CR1000","CR1000","1234","CR1000.Std.32","CPU:x.CR1","1","Table1"\n'
             '"TIMESTAMP","RECORD","Power","Temp"\n'
             '"TS","RN","W","degC"\n'
             '"","","Smp","Avg"\n')
TOA5_ROWS = ('"2026-01-01 00:00:00",0,10.0,20.1\n'
             '"2026-01-01 00:00:01",1,10.0,20.2\n'
             '"2026-01-01 00:00:02",2,12.0,20.4\n'
             '"2026-01-01 00:00:03",3,12.0,20.7\n')


def _write(path, text: str, newline: str = "\r\n"):
    path.write_bytes(text.replace("\n", newline).encode("utf-8"))
    return path


@pytest.mark.parametrize("newline", ["\r\n", "\n"])
def test_a_toa5_file_is_read_without_options(tmp_path, newline):
    f = _write(tmp_path / "CR1000_Table1.dat", TOA5_HEAD + TOA5_ROWS, newline)
    r = gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    np.testing.assert_array_equal(r.u, [10.0, 10.0, 12.0, 12.0])
    np.testing.assert_array_equal(r.y, [20.1, 20.2, 20.4, 20.7])
    assert r.units == ("W", "degC") and r.Ts == 1.0
    # the explicit options that say what the format says are accepted, with the same record
    same = gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0, skiprows=1, units_row=True)
    np.testing.assert_array_equal(same.y, r.y)
    assert same.units == r.units
    # static points too, and a units= that agrees with the units row
    pts = gb.load_static_csv(f, u="RECORD", y="Temp", units=("", "degC"))
    np.testing.assert_array_equal(pts.ybar, r.y)
    assert pts.units == ("RN", "degC")


def test_a_toa5_file_unquoted_or_with_a_byte_order_mark_is_recognised(tmp_path):
    text = (TOA5_HEAD + TOA5_ROWS).replace('"', "")
    f = tmp_path / "bare.dat"
    f.write_bytes(b"\xef\xbb\xbf" + text.encode())
    r = gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    assert r.units == ("W", "degC") and len(r) == 4


def test_a_toa5_files_messages_name_its_own_lines(tmp_path):
    bad = TOA5_ROWS.replace("20.4", "abc")
    f = _write(tmp_path / "t.dat", TOA5_HEAD + bad)
    with pytest.raises(ValueError, match=r"line 7, column 'Temp': 'abc' is not a number"):
        gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    nan = _write(tmp_path / "nan.dat", TOA5_HEAD + TOA5_ROWS.replace("20.2", '"NAN"'))
    with pytest.raises(ValueError, match=r"line 6, column 'Temp': 'NAN' is not a finite number"):
        gb.load_record_csv(nan, u="Power", y="Temp", Ts=1.0)
    empty = _write(tmp_path / "empty.dat", TOA5_HEAD)
    with pytest.raises(ValueError, match=r"line 5: no data rows"):
        gb.load_record_csv(empty, u="Power", y="Temp", Ts=1.0)
    with pytest.raises(ValueError, match=r"no column 'Pow' .*Did you mean 'Power'"):
        gb.load_record_csv(f, u="Pow", y="Temp", Ts=1.0)


def test_options_that_contradict_the_toa5_format_are_refused(tmp_path):
    f = _write(tmp_path / "t.dat", TOA5_HEAD + TOA5_ROWS)
    for kw, said in ((dict(skiprows=0), "skiprows=0"), (dict(skiprows=2), "skiprows=2"),
                     (dict(units_row=False), "units_row=False")):
        with pytest.raises(ValueError, match=rf"TOA5.*{said}.*omit"):
            gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0, **kw)
        with pytest.raises(ValueError, match=rf"TOA5.*{said}.*omit"):
            gb.load_static_csv(f, u="Power", y="Temp", **kw)


def test_a_damaged_toa5_header_is_refused_with_its_line(tmp_path):
    no_codes = _write(tmp_path / "a.dat", TOA5_HEAD.replace('"","","Smp","Avg"\n', "") + TOA5_ROWS)
    with pytest.raises(ValueError, match=r"line 4 holds numbers .*processing codes"):
        gb.load_record_csv(no_codes, u="Power", y="Temp", Ts=1.0)
    no_units = _write(tmp_path / "b.dat", TOA5_HEAD.replace('"TS","RN","W","degC"\n', "")
                      .replace('"","","Smp","Avg"\n', "") + TOA5_ROWS)
    with pytest.raises(ValueError, match=r"line 3 holds numbers .*TOA5"):
        gb.load_record_csv(no_units, u="Power", y="Temp", Ts=1.0)
    lines = TOA5_HEAD.splitlines(keepends=True)
    for n, said in ((1, r"line 2: the TOA5 file ends after line 1"),
                     (2, r"line 3: the TOA5 file ends after its column"),
                    (3, r"line 4: the TOA5 file ends after its units")):
        short = _write(tmp_path / "c.dat", "".join(lines[:n]))
        with pytest.raises(ValueError, match=said):
            gb.load_record_csv(short, u="Power", y="Temp", Ts=1.0)


@pytest.mark.parametrize("kind", ["TOB1", "TOB2", "TOB3"])
def test_a_binary_campbell_file_is_refused_as_what_it_is(tmp_path, kind):
    f = tmp_path / "CR1000_Table1.dat"
    f.write_bytes(f'"{kind}","CR1000","CR1000","1234","CR1000.Std.32","CPU:x.CR1","1","Table1"\r\n'.encode()
                  + b'"TIMESTAMP","RECORD","Power"\r\n"TS","RN","W"\r\n"","","Smp"\r\n"ULONG","ULONG","IEEE4"\r\n'
                  + bytes([0, 0, 0x12, 0x9f, 0xff, 0x80, 0x3f, 0x00]) * 8)
    with pytest.raises(ValueError, match=rf"{kind}.*binary.*CardConvert.*TOA5"):
        gb.load_record_csv(f, u="Power", y="RECORD", Ts=1.0)
    with pytest.raises(ValueError, match=rf"{kind}.*binary.*CardConvert.*TOA5"):
        gb.load_static_csv(f, u="Power", y="RECORD", encoding="cp1252")
    # a text file whose first column is named TOB1 (a boiler's temperature) is no logger file
    ok = _write(tmp_path / "boiler.csv", f"{kind},power\n20.5,1\n21.0,2\n")
    assert gb.load_static_csv(ok, u="power", y=kind).ybar.tolist() == [20.5, 21.0]


def test_a_labview_tdms_file_is_refused_as_what_it_is(tmp_path):
    # NI's binary TDMS (LabVIEW's logging format): lead-in "TDSm", table-of-contents mask, version 4713, offsets
    import struct

    f = tmp_path / "run.tdms"
    f.write_bytes(b"TDSm" + struct.pack("<iIqq", 0x0E, 4713, 1000, 500) + b"\x00" * 40 + b"/'Group'/'Power'")
    with pytest.raises(ValueError, match=r"TDMS.*not CSV text.*nptdms"):
        gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    index = tmp_path / "run.tdms_index"
    index.write_bytes(b"TDSh" + struct.pack("<iIqq", 0x0E, 4712, 1000, 500))
    with pytest.raises(ValueError, match=r"TDMS.*not CSV text"):
        gb.load_static_csv(index, u="Power", y="Temp")


def test_a_gap_in_a_toa5_files_record_numbers_is_refused_with_its_lines(tmp_path):
    # records overwritten before collection, or a collection appended twice: with Ts= the samples
    # on both sides of the gap were glued into one record without a word
    gap = TOA5_ROWS.replace('"2026-01-01 00:00:02",2,', '"2026-01-01 00:00:09",9,').replace(
        '"2026-01-01 00:00:03",3,', '"2026-01-01 00:00:10",10,')
    f = _write(tmp_path / "gap.dat", TOA5_HEAD + gap)
    with pytest.raises(ValueError, match=r"column 'RECORD'.*from 1 \(line 6\) to 9 \(line 7\).*7 record"):
        gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    twice = _write(tmp_path / "twice.dat", TOA5_HEAD + TOA5_ROWS + TOA5_ROWS.splitlines(keepends=True)[-1])
    with pytest.raises(ValueError, match=r"column 'RECORD'.*from 3 \(line 8\) to 3 \(line 9\)"):
        gb.load_record_csv(twice, u="Power", y="Temp", Ts=1.0)
    # static points need no contiguous samples
    assert len(gb.load_static_csv(f, u="Power", y="Temp", repeats="mean")) == 2
    with pytest.raises(ValueError, match=r"column 'RECORD'.*from 1 \(line 6\) to 9 \(line 7\)"):
        gb.load_record_csv(f, u="RECORD", y="Temp", Ts=1.0)


def test_a_units_row_after_a_blank_line_is_read_as_the_refusal_advises(tmp_path):
    # without units_row the loader names line 3 as units and advises units_row=True, which then read the blank
    # line 2 as the units row and failed on line 3: "'rpm' is not a number"
    f = _write(tmp_path / "run.csv", "t,u,y\n\ns,rpm,Pa\n0,1,2\n1,2,3\n2,2,4\n")
    with pytest.raises(ValueError, match=r"line 3 holds text in every column read .*pass units_row=True"):
        gb.load_record_csv(f, "u", "y", time="t")
    r = gb.load_record_csv(f, "u", "y", time="t", units_row=True)
    assert r.units == ("rpm", "Pa") and r.u.tolist() == [1, 2, 2] and r.Ts == 1.0
    bad = _write(tmp_path / "bad.csv", "t,u,y\n\ns,rpm,Pa\n0,1,2\n1,x,3\n")
    with pytest.raises(ValueError, match=r"line 5, column 'u': 'x' is not a number"):
        gb.load_record_csv(bad, "u", "y", time="t", units_row=True)
    numbers = _write(tmp_path / "numbers.csv", "t,u,y\n\n0,1,2\n1,2,3\n")
    with pytest.raises(ValueError, match=r"line 3 holds numbers .*drop units_row=True"):
        gb.load_record_csv(numbers, "u", "y", time="t", units_row=True)
    only = _write(tmp_path / "only.csv", "t,u,y\n\ns,rpm,Pa\n\n")
    with pytest.raises(ValueError, match=r"line 4: no data rows"):
        gb.load_static_csv(only, "u", "y", units_row=True)


def test_a_toa5_file_resaved_by_a_european_excel_is_still_a_toa5_file(tmp_path):
    # opened in Excel and saved as "CSV" in a decimal-comma locale: ';' between the fields, quotes dropped; it was
    # refused as before TOA5 was read ("line 4, column 'Power': 'Smp' is not a number", no option to skip line 4)
    text = (TOA5_HEAD + TOA5_ROWS).replace('"', "").replace(",", ";").replace(".", ",")
    f = _write(tmp_path / "resaved.csv", text)
    r = gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    assert r.units == ("W", "degC") and r.y.tolist() == [20.1, 20.2, 20.4, 20.7]
    tabs = _write(tmp_path / "tabs.txt", (TOA5_HEAD + TOA5_ROWS).replace(",", "\t"))
    assert gb.load_record_csv(tabs, u="Power", y="Temp", Ts=1.0).u.tolist() == [10, 10, 12, 12]


def test_two_toa5_files_joined_into_one_are_refused_where_the_second_starts(tmp_path):
    f = _write(tmp_path / "joined.dat", TOA5_HEAD + TOA5_ROWS + TOA5_HEAD + TOA5_ROWS)
    with pytest.raises(ValueError, match=r"line 9 starts a TOA5 file's header again .*two files joined"):
        gb.load_record_csv(f, u="Power", y="Temp", Ts=1.0)
    bare = _write(tmp_path / "bare.dat", (TOA5_HEAD + TOA5_ROWS + TOA5_HEAD + TOA5_ROWS).replace('"', ""))
    with pytest.raises(ValueError, match=r"line 9 starts a TOA5 file's header again"):
        gb.load_static_csv(bare, u="Power", y="Temp", repeats="mean")


def test_column_names_commented_out_below_a_header_block_are_named_not_blamed_on_the_delimiter(tmp_path):
    # np.savetxt(path, data, delimiter=",", header="logger v1\nrate: 10 Hz\nt,u,y") writes every header line behind
    # '# ', as many loggers' ASCII exports do: the refusal said "the header was read as one column, split at ',':
    # pass delimiter=", which no delimiter cures
    import io

    buf = io.StringIO()
    np.savetxt(buf, np.array([[0.0, 1, 2], [0.1, 2, 3], [0.2, 3, 4]]), delimiter=",",
               header="logger v1\nrate: 10 Hz\nt,u,y")
    f = _write(tmp_path / "log.csv", buf.getvalue(), "\n")
    with pytest.raises(ValueError, match=r"line 3 names the columns behind the comment marker '#' .*skiprows=2") as e:
        gb.load_record_csv(f, "u", "y", time="t")
    assert "pass delimiter=" not in str(e.value)
    # the advice followed: the '# ' deleted, skiprows=2
    f.write_text(buf.getvalue().replace("# t,u,y", "t,u,y"))
    assert gb.load_record_csv(f, "u", "y", time="t", skiprows=2).y.tolist() == [2, 3, 4]
    spaces = io.StringIO()
    np.savetxt(spaces, np.array([[0.0, 1, 2], [0.1, 2, 3]]), header="logger v1\nt u y")
    g = _write(tmp_path / "log.txt", spaces.getvalue(), "\n")
    with pytest.raises(ValueError, match=r"line 2 names the columns behind the comment marker '#' .*skiprows=1.*"
                                         r"delimiter=' '"):
        gb.load_static_csv(g, "u", "y")


def test_a_header_block_longer_than_the_sniffed_lines_is_found(tmp_path):
    # a logger's block of one line per channel (HBM catman, Yokogawa, Dewesoft exports run past 50 lines): the
    # names below line 50 went unseen, and the refusal blamed the delimiter ("pass delimiter=")
    block = "".join(f"Channel {i}: gain 1\n" for i in range(60))
    f = _write(tmp_path / "long.csv", block + "t;u;y\n0;1;2\n1;2;3\n2;3;4\n", "\n")
    with pytest.raises(ValueError, match=r"line 61 names the columns .*pass skiprows=60") as e:
        gb.load_record_csv(f, "u", "y", time="t")
    assert "delimiter=" not in str(e.value)
    assert gb.load_record_csv(f, "u", "y", time="t", skiprows=60).y.tolist() == [2, 3, 4]


def test_a_quote_left_open_on_a_date_does_not_lose_the_sample_silently(tmp_path):
    # the date's closing quote missing on line 3: the reader took line 3's cells and line 4's opening quote into one
    # cell, so lines 3 and 4 read as one sample (line 4's values) and line 3's sample was lost without a word
    f = _write(tmp_path / "dates.csv", '"date",u,y\n"2026-01-01 00:00:00",1,2\n"2026-01-01 00:00:01,2,3\n'
               '"2026-01-01 00:00:02",3,4\n"2026-01-01 00:00:03",4,5\n', "\n")
    with pytest.raises(ValueError, match=r"line 3.*a quote \(\"\) opens a field that closes only on line 4.*line 4"):
        gb.load_record_csv(f, "u", "y", Ts=1.0)
    with pytest.raises(ValueError, match=r"line 3.*a quote"):
        gb.load_static_csv(f, "u", "y")
    # a note over two lines is a cell, as before
    note = _write(tmp_path / "note.csv", 't,u,y,note\n0,1,2,"first line\nsecond line"\n1,2,3,""\n', "\n")
    assert gb.load_record_csv(note, "u", "y", time="t").u.tolist() == [1, 2]
    # in a TOA5 file (its TIMESTAMP read as text) a note's stray quote that takes in whole samples is refused too
    head = TOA5_HEAD.replace('"Temp"\n', '"Temp","Note"\n').replace('"degC"\n', '"degC",""\n').replace(
        '"Avg"\n', '"Avg","Smp"\n')
    rows = ('"2026-01-01 00:00:00",0,10.0,20.1,"ok"\n"2026-01-01 00:00:01",1,10.0,20.2,"oops\n'
            '2026-01-01 00:00:02,2,12.0,20.4,fine"\n')
    toa5 = _write(tmp_path / "note.dat", head + rows)
    with pytest.raises(ValueError, match=r"line 6, column 'Note': a quote"):
        gb.load_record_csv(toa5, "Power", "Temp", Ts=1.0)


_FINITE = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12, max_value=1e12)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(_FINITE, _FINITE), min_size=2, max_size=12), st.sampled_from(["\r\n", "\n"]),
       st.booleans())
def test_a_toa5_file_reads_as_the_same_samples_written_as_plain_csv_with_a_units_row(samples, newline, quoted):
    # the law: TOA5's header lines change how a file is read, never what its samples are
    q = '"' if quoted else ""
    rows = "".join(f'{q}2026-01-01 00:{k // 60:02d}:{k % 60:02d}{q},{k},{u!r},{y!r}\n'
                   for k, (u, y) in enumerate(samples))
    head = TOA5_HEAD if quoted else TOA5_HEAD.replace('"', "")
    with tempfile.TemporaryDirectory() as d:
        toa5 = _write(Path(d) / "t.dat", head + rows, newline)
        plain = _write(Path(d) / "p.csv", "TIMESTAMP,RECORD,Power,Temp\nTS,RN,W,degC\n" + rows, newline)
        r = gb.load_record_csv(toa5, u="Power", y="Temp", Ts=1.0)
        c = gb.load_record_csv(plain, u="Power", y="Temp", Ts=1.0, units_row=True)
    np.testing.assert_array_equal(r.u, [u for u, _ in samples])
    np.testing.assert_array_equal(r.y, [y for _, y in samples])
    np.testing.assert_array_equal(r.u, c.u)
    np.testing.assert_array_equal(r.y, c.y)
    assert r.units == c.units == ("W", "degC")
