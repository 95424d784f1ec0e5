"""CSV loaders and the buck-converter loader (issue 3, items 4 and 6)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from graybox import Dataset, Record, StaticPoints
from graybox.datasets import BUCK_STATIC_CURVE, find_buck_dir, load_buck, load_record_csv, load_static_csv

REPO = Path(__file__).resolve().parents[1]


def write(tmp_path: Path, text: str, name: str = "data.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


GOOD = "t,speed,pressure,other\n0.00,1000,8.1,x\n0.05,1000,8.2,y\n0.10,1100,8.3,z\n0.15,1100,8.9,w\n"


# -- records -----------------------------------------------------------------

def test_record_with_time_column(tmp_path):
    p = write(tmp_path, GOOD, "run1.csv")
    r = load_record_csv(p, u="speed", y="pressure", time="t", units=("rpm", "mlc"))
    assert isinstance(r, Record)
    np.testing.assert_array_equal(r.u, [1000, 1000, 1100, 1100])
    np.testing.assert_array_equal(r.y, [8.1, 8.2, 8.3, 8.9])
    assert r.Ts == 0.05  # the mean step, without float noise
    assert r.name == "run1" and r.units == ("rpm", "mlc")


def test_record_with_given_Ts_and_no_time(tmp_path):
    p = write(tmp_path, "u,y\n1,2\n3,4\n\n")  # a trailing blank line is not a sample
    r = load_record_csv(p, u="u", y="y", Ts=0.5, name="mine")
    assert len(r) == 2 and r.Ts == 0.5 and r.name == "mine"


def test_time_stamps_may_start_anywhere(tmp_path):
    p = write(tmp_path, "t,u,y\n10.0,1,2\n10.5,1,2\n11.0,1,3\n")
    r = load_record_csv(p, u="u", y="y", time="t", Ts=0.5)
    assert r.Ts == 0.5 and r.t[0] == 0.0


@pytest.mark.parametrize("col, seconds", [("t [ms]", 0.5), ("time (min)", 30_000.0), ("t_ms", 0.5), ("Zeit/h", 1.8e6),
                                          ("t [µs]", 5e-4), ("t_millis", 0.5), ("T (Days)", 4.32e7),
                                          # the table's nsec and nanoseconds: their stamps were read as seconds
                                          ("t_nsec", 5e-7), ("time [nanoseconds]", 5e-7)])
def test_a_time_column_named_in_another_unit_is_converted_as_a_units_rows(tmp_path, col, seconds):
    # was: stamps 0, 500, 1000 ms read as seconds, Ts = 500 s without a word (local models' time constants and every
    # controller designed on them off by 1000); then refused, where a units row's 'ms' converted (mend61e's 1ad8ce0d)
    p = write(tmp_path, f"{col},u,y\n0,1,2\n500,1,2\n1000,1,3\n")
    assert load_record_csv(p, u="u", y="y", time=col).Ts == seconds  # 500 of the unit, in seconds by hand
    unit = "ms" if "ms" in col else "s"
    q = write(tmp_path, f"{col},u,y\n[{unit}],,\n0,1,2\n500,1,2\n1000,1,3\n", "row.csv")
    if unit == "ms":  # the same unit in both: converted once
        assert load_record_csv(q, u="u", y="y", time=col, units_row=True).Ts == 0.5
    else:
        with pytest.raises(ValueError, match=re.escape(repr(col)) + r" names its unit .*the units row gives it 's'"):
            load_record_csv(q, u="u", y="y", time=col, units_row=True)
    with pytest.raises(ValueError, match=re.escape(repr(col)) + r" names the unit .*holds dates or clock times"):
        load_record_csv(write(tmp_path, f"{col},u,y\n2026-11-20 09:14:03,1,2\n2026-11-20 09:14:04,1,2\n", "d.csv"),
                        u="u", y="y", time=col)
    for ok in ("t [s]", "time_s", "Zeit (s)", "timestamp"):  # seconds, or no unit named: read as before
        q = write(tmp_path, f"{ok},u,y\n0,1,2\n0.5,1,2\n1.0,1,3\n", "ok.csv")
        assert load_record_csv(q, u="u", y="y", time=ok).Ts == 0.5


def test_excel_s_delimiter_hint_line_is_read_as_what_it_is(tmp_path):
    # was: "line 2 names the columns ... (a data logger's header block?)", then "delete line 1":
    # Excel's "sep=;" first line names the delimiter (tests/test_loaders36.py has the rest)
    p = write(tmp_path, "sep=;\nt;u;y\n0;1;2\n0,5;1;2\n")
    assert load_record_csv(p, u="u", y="y", time="t").Ts == 0.5


def test_needs_time_or_Ts(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(ValueError, match=re.escape(str(p)) + ".*time=.*Ts="):
        load_record_csv(p, u="speed", y="pressure")


def test_nan_row_names_file_line_and_column(tmp_path):
    p = write(tmp_path, "t,speed,pressure\n0,1,2\n0.1,1,nan\n0.2,1,2\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 3, column 'pressure'") + ".*not a finite number"):
        load_record_csv(p, u="speed", y="pressure", time="t")


def test_empty_cell(tmp_path):
    p = write(tmp_path, "t,speed,pressure\n0,1,2\n0.1,,2\n0.2,1,2\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 3, column 'speed': empty cell")):
        load_record_csv(p, u="speed", y="pressure", time="t")


def test_text_where_a_number_belongs(tmp_path):
    p = write(tmp_path, "t,speed,pressure\n0,1,2\n0.1,1,2\n0.2,1,high\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 4, column 'pressure': 'high' is not a number")):
        load_record_csv(p, u="speed", y="pressure", time="t")


def test_short_row(tmp_path):
    p = write(tmp_path, "t,speed,pressure\n0,1,2\n0.1,1\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 3 has 2 field(s)") + ".*'pressure'"):
        load_record_csv(p, u="speed", y="pressure", time="t")


def test_misspelled_column_suggests_close_names(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(ValueError) as err:
        load_record_csv(p, u="speed", y="presure", time="t")
    msg = str(err.value)
    assert str(p) in msg and "no column 'presure' (asked for as y)" in msg
    assert "Did you mean 'pressure'" in msg and "'other'" in msg  # suggestion, then all columns


def test_missing_column_case_suggestion(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(ValueError, match="no column 'T'.*Did you mean 't'"):
        load_record_csv(p, u="speed", y="pressure", time="T")


def test_same_column_twice(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(ValueError, match="u, y all name the column 'speed'"):
        load_record_csv(p, u="speed", y="speed", Ts=1.0)


def test_non_increasing_time(tmp_path):
    p = write(tmp_path, "t,u,y\n0,1,2\n0.1,1,2\n0.1,1,2\n0.3,1,2\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: column 't': time does not increase from line 3") + ".*line 4"):
        load_record_csv(p, u="u", y="y", time="t")
    p = write(tmp_path, "t,u,y\n0,1,2\n0.2,1,2\n0.1,1,2\n", "back.csv")
    with pytest.raises(ValueError, match="does not increase from line 3"):
        load_record_csv(p, u="u", y="y", time="t")


def test_uneven_time(tmp_path):
    p = write(tmp_path, "t,u,y\n0,1,2\n0.1,1,2\n0.2,1,2\n0.4,1,2\n0.5,1,2\n")  # a missing sample
    with pytest.raises(ValueError, match=re.escape(f"{p}: column 't': uneven time stamps") + ".*line 4 to line 5"):
        load_record_csv(p, u="u", y="y", time="t")


def test_time_disagrees_with_Ts(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(ValueError, match="Ts = 0.1 s disagrees with column 't'"):
        load_record_csv(p, u="speed", y="pressure", time="t", Ts=0.1)


def test_empty_and_header_only_files(tmp_path):
    with pytest.raises(ValueError, match="the file is empty"):
        load_record_csv(write(tmp_path, ""), u="u", y="y", Ts=1.0)
    with pytest.raises(ValueError, match="no data rows"):
        load_record_csv(write(tmp_path, "u,y\n", "h.csv"), u="u", y="y", Ts=1.0)


def test_bad_Ts(tmp_path):
    with pytest.raises(ValueError, match="Ts must be a positive number"):
        load_record_csv(write(tmp_path, GOOD), u="speed", y="pressure", Ts=-1)


def test_bad_units(tmp_path):
    # a TypeError, as Record's and StaticPoints' own check (was a ValueError here alone)
    with pytest.raises(TypeError, match="units must be a pair of strings"):
        load_record_csv(write(tmp_path, GOOD), u="speed", y="pressure", Ts=1.0, units="rpm")


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_record_csv(tmp_path / "nope.csv", u="u", y="y", Ts=1.0)


# -- static points -------------------------------------------------------------

def test_static_points(tmp_path):
    p = write(tmp_path, "rpm,mlc\n750,3.9\n850,5.2\n950,6.6\n", "static.csv")
    s = load_static_csv(p, u="rpm", y="mlc")
    assert isinstance(s, StaticPoints) and s.name == "static"
    np.testing.assert_array_equal(s.ubar, [750, 850, 950])


def test_static_duplicated_ubar_names_both_lines(tmp_path):
    p = write(tmp_path, "rpm,mlc\n750,3.9\n850,5.2\n750.0,4.0\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: column 'rpm': lines 2 and 4 have the same input level 750")
                       + ".*repeats=\"mean\""):
        load_static_csv(p, u="rpm", y="mlc")
    # repeated measurements averaged: one point per level
    s = load_static_csv(p, u="rpm", y="mlc", repeats="mean")
    np.testing.assert_array_equal(s.ubar, [750, 850])
    np.testing.assert_allclose(s.ybar, [3.95, 5.2])
    with pytest.raises(ValueError, match="repeats"):
        load_static_csv(p, u="rpm", y="mlc", repeats="median")


def test_static_nan_and_missing_column(tmp_path):
    p = write(tmp_path, "rpm,mlc\n750,3.9\n850,NaN\n")
    with pytest.raises(ValueError, match=re.escape(f"{p}: line 3, column 'mlc'")):
        load_static_csv(p, u="rpm", y="mlc")
    with pytest.raises(ValueError, match="no column 'rmp'.*Did you mean 'rpm'"):
        load_static_csv(p, u="rmp", y="mlc")


# -- buck converter -------------------------------------------------------------

BUCK = REPO / "data" / "buck"


def test_load_buck():
    ds = load_buck()
    assert isinstance(ds, Dataset)
    assert (len(ds.ident), len(ds.valid)) == (1001, 999)
    assert ds.Ts == pytest.approx(1e-5, rel=1e-9) and ds.valid.Ts == ds.Ts
    assert ds.ident.units == ("", "V")
    assert 2.1 < ds.ident.u.min() and ds.ident.u.max() < 2.6
    assert 10.9 < ds.ident.y.min() and ds.ident.y.max() < 16.7
    curve = ds.extra["static_curve"]
    assert curve is BUCK_STATIC_CURVE
    np.testing.assert_allclose(curve(np.array([1.0, 2.203, 4.0])), [24.0, 14.376, 0.0])
    np.testing.assert_allclose(curve.gain(np.array([2.5])), [-8.0])
    np.testing.assert_allclose(ds.static.ybar, (4 - ds.static.ubar) * 8)
    assert "theoretical" in ds.description and "no static points were measured" in ds.description.lower()
    assert Path(ds.extra["folder"]).resolve() == BUCK.resolve()  # the bundled copy


def test_bundled_buck_files_are_the_published_ones_with_their_licence():
    import hashlib

    sha = {"buck_id.csv": "d244920026305463079732a91f62968bc30121f651a5699279b42b7ee637c3e7",
           "buck_valid.csv": "adaaa29d0b677eaf7a3b36267f7fd8dc0afd6e9c1d7d054547a0e3f945e0c685"}
    for name, digest in sha.items():
        assert hashlib.sha256((BUCK / name).read_bytes()).hexdigest() == digest, name
    licence = (BUCK / "LICENSE").read_text()
    assert "MIT License" in licence and "Copyright (c) 2024 Wilson Rocha" in licence
    assert "LICENSE" in (BUCK / "README.md").read_text()


def test_buck_ships_as_package_data():
    import tomllib

    conf = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "graybox.data.buck" in conf["packages"]
    assert {"*.csv", "LICENSE"} <= set(conf["package-data"]["graybox.data.buck"])


def test_buck_env_var(monkeypatch, tmp_path):
    other = tmp_path / "copy"
    other.mkdir()
    for f in ("buck_id.csv", "buck_valid.csv"):
        (other / f).write_bytes((BUCK / f).read_bytes())
    monkeypatch.setenv("GRAYBOX_BUCK_DIR", str(other))
    assert find_buck_dir() == other
    assert load_buck().extra["folder"] == str(other)


def test_buck_env_var_naming_a_wrong_folder_is_an_error(monkeypatch, tmp_path):
    # never a silent fall-back to the bundled copy when the user pointed elsewhere
    monkeypatch.setenv("GRAYBOX_BUCK_DIR", str(tmp_path))
    with pytest.raises(FileNotFoundError, match=re.escape(str(tmp_path)) + ".*GRAYBOX_BUCK_DIR.*buck_id.csv"):
        load_buck()


def test_buck_wrong_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match=re.escape(str(tmp_path)) + ".*buck_id.csv"):
        load_buck(tmp_path)


# -- the fast reader gives what the careful reader gives -------------------------------------

_FORMATS = (repr, "{:.3f}".format, "{:.6e}".format, lambda v: f"  {v!r} ", lambda v: f"{v:+.17g}")


@settings(max_examples=80, deadline=None)
@given(values=st.lists(st.tuples(st.floats(-1e300, 1e300, allow_nan=False), st.floats(-1e6, 1e6, allow_nan=False)),
                       min_size=1, max_size=30),
       fmt=st.integers(0, len(_FORMATS) - 1), crlf=st.booleans(), bom=st.booleans(),
       blank=st.integers(-1, 30), quote=st.booleans(), text_col=st.booleans(), trailing_newline=st.booleans())
def test_fast_and_careful_csv_readers_agree(values, fmt, crlf, bom, blank, quote, text_col, trailing_newline):
    """numpy's reader, used where it can be, gives the careful reader's floats bit for bit and its line
    numbers; files it cannot read exactly (blank lines) go to the careful reader, and quotes round whole fields are
    dropped first."""
    import tempfile

    from graybox.datasets import _loaders

    f = _FORMATS[fmt]
    lines = ["a,b" + (",note" if text_col else "")]
    for i, (a, b) in enumerate(values):
        row = f"{f(a)},{f(b)}" + (f",row {i}" if text_col else "")
        lines.append(row.replace(f(a), f'"{f(a)}"', 1) if quote and i == 0 else row)
    if 0 <= blank < len(values):
        lines.insert(blank + 1, "")
    nl = "\r\n" if crlf else "\n"
    text = nl.join(lines) + (nl if trailing_newline else "")
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "x.csv"
        p.write_bytes((b"\xef\xbb\xbf" if bom else b"") + text.encode())
        index = {"u": 0, "y": 1}
        raw = p.read_bytes()
        fast = _loaders._fast_columns(p, index, raw=raw, text=lambda: raw.decode("utf-8-sig"), delimiter=",", decimal=".",
                                      n_fields=len(lines[0].split(",")))
        careful_reader = _loaders._fast_columns
        try:
            _loaders._fast_columns = lambda *a, **k: None
            careful = _loaders._read_columns(p, {"u": "a", "y": "b"})
        finally:
            _loaders._fast_columns = careful_reader
        got = _loaders._read_columns(p, {"u": "a", "y": "b"})
    simple = not (0 <= blank < len(values))
    assert (fast is not None) == simple
    for k in ("u", "y", "_lines"):
        assert np.array_equal(got[k], careful[k])
        assert np.array_equal(np.signbit(got[k]), np.signbit(careful[k]))
    assume(simple)
    assert np.array_equal(fast["u"], careful["u"]) and np.array_equal(fast["_lines"], careful["_lines"])


# -- CSV dialects as spreadsheets export them ------------------------------------------------

# (delimiter, decimal mark, quote every field): the dialects spreadsheets write in common locales
_DIALECTS = ((",", ".", False), (";", ".", False), (";", ",", False), ("\t", ".", False), ("\t", ",", False),
             (",", ",", True), (",", ".", True))


def _write_dialect(path: Path, header, rows, delimiter, decimal, quote, bom=False, crlf=False) -> Path:
    def cell(v):
        text = repr(v) if isinstance(v, float) else str(v)
        text = text.replace(".", decimal)
        return f'"{text}"' if quote else text

    nl = "\r\n" if crlf else "\n"
    lines = [delimiter.join(f'"{h}"' if quote else h for h in header)]
    lines += [delimiter.join(cell(v) for v in row) for row in rows]
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + (nl.join(lines) + nl).encode())
    return path


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.tuples(st.floats(-1e12, 1e12, allow_nan=False), st.floats(-1e6, 1e6, allow_nan=False),
                               st.integers(-5, 5)), min_size=1, max_size=20),
       dialect=st.integers(0, len(_DIALECTS) - 1), bom=st.booleans(), crlf=st.booleans())
def test_every_dialect_loads_the_same_floats(rows, dialect, bom, crlf):
    """The same table written with each delimiter and decimal mark (BOM, CRLF or not) loads bit for
    bit as the plain comma-and-point file, detected and with the dialect passed explicitly."""
    import tempfile

    delimiter, decimal, quote = _DIALECTS[dialect]
    header = ("speed", "pressure", "count")
    with tempfile.TemporaryDirectory() as d:
        plain = _write_dialect(Path(d) / "plain.csv", header, rows, ",", ".", False)
        other = _write_dialect(Path(d) / "other.csv", header, rows, delimiter, decimal, quote, bom, crlf)
        want = load_record_csv(plain, u=["speed", "count"], y="pressure", Ts=1.0)
        # every decimal of the form 1.234 (it may be 1234 with a thousands separator): refused unless
        # decimal= is given, but where a comma separates the columns a point decimal is plain
        decimals = [repr(v) for row in rows for v in row[:2] if re.fullmatch(r"-?\d*\.\d+(e[+-]\d+)?", repr(v))]
        ambiguous = (delimiter, decimal) != (",", ".") and decimals and all(
            re.fullmatch(r"-?[1-9]\d{0,2}\.\d{3}", c) for c in decimals)
        if ambiguous:
            with pytest.raises(ValueError, match="the decimal mark is ambiguous"):
                load_record_csv(other, u=["speed", "count"], y="pressure", Ts=1.0)
        given_ = {"delimiter": delimiter, "decimal": decimal}
        for kw in ([given_] if ambiguous else [{}, given_]):
            got = load_record_csv(other, u=["speed", "count"], y="pressure", Ts=1.0, **kw)
            assert got.u.tobytes() == want.u.tobytes() and got.y.tobytes() == want.y.tobytes()
        pts = load_static_csv(other, u="speed", y="pressure", repeats="mean", **(given_ if ambiguous else {}))
        assert pts.ubar.tobytes() == load_static_csv(plain, u="speed", y="pressure", repeats="mean").ubar.tobytes()


def test_semicolon_file_with_decimal_commas(tmp_path):
    # the file of the issue: 't;valve;flow' was read as one column
    p = write(tmp_path, "t;valve;flow\n0,0;10;1,5\n0,5;20;2,25\n1,0;30;3,125\n")
    r = load_record_csv(p, u="valve", y="flow", time="t")
    np.testing.assert_array_equal(r.u, [10, 20, 30])
    np.testing.assert_array_equal(r.y, [1.5, 2.25, 3.125])
    assert r.Ts == 0.5


def test_the_fast_reader_serves_semicolon_and_decimal_comma_files(tmp_path):
    from graybox.datasets import _loaders

    p = write(tmp_path, "a;b\n1,5;2\n3,25;4\n")
    raw = p.read_bytes()
    fast = _loaders._fast_columns(p, {"u": 0, "y": 1}, raw=raw, text=lambda: raw.decode(), delimiter=";", decimal=",",
                                  n_fields=2)
    assert fast is not None and fast["u"].tolist() == [1.5, 3.25]


def test_delimiter_and_decimal_can_be_given(tmp_path):
    # a one-column-looking header: detection cannot tell, the caller can
    p = write(tmp_path, "a|b\n1,5|2\n2,5|3\n")
    with pytest.raises(ValueError, match="no column 'a'.*one column.*pass delimiter="):
        load_static_csv(p, u="a", y="b")
    pts = load_static_csv(p, u="a", y="b", delimiter="|", decimal=",")
    np.testing.assert_array_equal(pts.ubar, [1.5, 2.5])


@pytest.mark.parametrize("kw, match", [
    ({"delimiter": ";;"}, "delimiter must be one character"),
    ({"delimiter": "1"}, "delimiter must be one character"),
    ({"decimal": ";"}, "decimal must be '.' or ','"),
    ({"delimiter": ",", "decimal": ","}, "the delimiter is ',' and so is the decimal mark, but no field is quoted"),
])
def test_bad_dialect_arguments(tmp_path, kw, match):
    p = write(tmp_path, "a,b\n1,2\n")
    with pytest.raises(ValueError, match=match):
        load_static_csv(p, u="a", y="b", **kw)


@pytest.mark.parametrize("text, match", [
    # mixed delimiters: the header and line 2 by ';', line 3 by ','
    ("t;valve;flow\n0;1;2\n1,2,3\n", r"data.csv: mixed delimiters: the header \(line 1\) is separated by ';' but "
                                    r"line 3 by ','.*pass delimiter=';'"),
    # a decimal comma with a comma delimiter and no quotes
    ("t,valve,flow\n0,1,2,5,3\n", r"data.csv: line 2 has 5 comma-separated fields but the header \(line 1\) has 3.*"
                                  r"decimal comma.*';' as the delimiter"),
    # every line splits evenly on two delimiters
    ("a,b;c\n1,2;3\n", r"data.csv: the delimiter is ambiguous: on the first 2 lines ',' gives 2 columns and ';' gives 2 "
                       r"columns; pass delimiter= \(',' or ';'\)"),
    # both decimal marks among the numbers
    ("a;b\n1,5;2\n2.5;3\n", r"data.csv: the decimal mark is ambiguous: line 3 has '2.5' and line 2 has '1,5'; "
                            r"pass decimal="),
    ("", r"data.csv: line 1: the file is empty; expected a header line"),
    ("\n", r"data.csv: line 1 is blank; expected a header line"),
    ("a,b\n", r"data.csv: line 2: no data rows after the header"),
    ("a,b\n\n\n", r"data.csv: line 2: no data rows after the header"),
])
def test_unreadable_files_name_the_file_the_line_and_what_to_do(tmp_path, text, match):
    p = write(tmp_path, text)
    with pytest.raises(ValueError, match=match):
        load_static_csv(p, u="a" if text.startswith(("a", "\n")) or not text else "valve",
                        y="b" if text.startswith(("a", "\n")) or not text else "flow")


def test_a_point_in_a_decimal_comma_file_is_never_a_thousands_separator(tmp_path):
    p = write(tmp_path, "a;b\n1,5;2\n3;4\n1.500;5\n")
    with pytest.raises(ValueError, match=r"line 4, column 'a': '1.500' is not a number; the decimal mark of this "
                                         r"file is ','"):
        load_static_csv(p, u="a", y="b", decimal=",")


def test_a_decimal_comma_past_the_sniffed_lines_says_what_to_pass(tmp_path):
    from graybox.datasets import _loaders

    rows = "".join(f"{i};{i}\n" for i in range(_loaders._SNIFF_LINES + 5)) + "7,5;1\n"
    p = write(tmp_path, "a;b\n" + rows)
    with pytest.raises(ValueError, match=r"'7,5' is not a number; it has a decimal comma: pass decimal=','"):
        load_static_csv(p, u="a", y="b")


def test_a_line_with_more_fields_than_the_header_is_refused(tmp_path):
    # numpy's reader with usecols would take it, shifted: the fast reader declines, the careful one
    # refuses it (past the lines the detection reads)
    from graybox.datasets import _loaders

    rows = "".join(f"{i},{i},{i}\n" for i in range(_loaders._SNIFF_LINES + 5))
    p = write(tmp_path, "a,b,c\n" + rows + "4,5,6,7\n")
    with pytest.raises(ValueError, match=rf"line {_loaders._SNIFF_LINES + 7} has 4 fields but the header names 3 "
                                         "columns: a decimal comma with a comma delimiter"):
        load_static_csv(p, u="a", y="b")
    raw = p.read_bytes()
    assert _loaders._fast_columns(p, {"u": 0, "y": 1}, raw=raw, text=lambda: raw.decode(), delimiter=",", decimal=".",
                                  n_fields=3) is None
    q = write(tmp_path, "a,b,c\n1,2,3\n4,5,6,7\n", "early.csv")  # within them: the detection says it
    with pytest.raises(ValueError, match=r"early.csv: line 3 has 4 comma-separated fields but the header \(line 1\) "
                                         r"has 3.*otherwise correct line 3"):
        load_static_csv(q, u="a", y="b")
    r = write(tmp_path, "a,b,c\n1,2,3\n4,5,6,\n", "trailing.csv")  # an empty trailing field is harmless
    np.testing.assert_array_equal(load_static_csv(r, u="a", y="b").ubar, [1, 4])


def test_a_file_that_is_not_utf8_names_the_line(tmp_path):
    p = tmp_path / "latin.csv"
    p.write_bytes("a,b\n1,2\n3,4 \xb0C\n".encode("latin-1"))
    with pytest.raises(ValueError, match=r"latin.csv: line 3 is not UTF-8 text.*save the file as UTF-8"):
        load_static_csv(p, u="a", y="b")


def test_a_period_given_beside_the_stamps_is_the_records_period(tmp_path):
    # two runs of one logger at 20 Hz whose stamps jitter: with Ts=0.05 given, each record took its stamps' mean
    # step (0.0500004 s, 0.04999975 s), not the period the user said (checked against the stamps all the same)
    rng = np.random.default_rng(3)
    periods = []
    for i in range(2):
        t = 0.05 * np.arange(400) + rng.uniform(-2e-5, 2e-5, 400)
        lines = "t,u,y\n" + "".join(f"{a:.6f},{b:.3f},{c:.3f}\n" for a, b, c in
                                      zip(t, rng.uniform(0, 1, 400), rng.uniform(0, 1, 400)))
        path = write(tmp_path, lines, f"run{i}.csv")
        assert load_record_csv(path, "u", "y", time="t").Ts != 0.05  # the stamps' own mean step
        periods.append(load_record_csv(path, "u", "y", time="t", Ts=0.05).Ts)
        with pytest.raises(ValueError, match="disagrees with column 't'"):
            load_record_csv(path, "u", "y", time="t", Ts=0.06)
    assert periods == [0.05, 0.05]


def test_columns_shorter_than_the_file_end_where_their_cells_do(tmp_path):
    """Two runs exported side by side (Vernier, pandas' to_csv of unequal columns): the second run's columns end
    before the file does, in empty cells or cut-off lines; they were refused as 'empty cell'."""
    f = tmp_path / "runs.csv"
    f.write_text("Run 1: Time (s),Run 1: Temp (C),Run 2: Time (s),Run 2: Temp (C),Run 2: Power (W)\n"
                 "0,20,0,21,1\n0.5,20.1,0.5,21.2,1\n1,20.3,1,21.5,2\n1.5,20.6,,,\n2,21\n", encoding="utf-8")
    two = load_record_csv(f, u="Run 2: Power (W)", y="Run 2: Temp (C)", time="Run 2: Time (s)")
    np.testing.assert_array_equal(two.y, [21.0, 21.2, 21.5])
    np.testing.assert_array_equal(two.u, [1.0, 1.0, 2.0])
    assert two.Ts == 0.5
    one = load_record_csv(f, u="Run 1: Time (s)", y="Run 1: Temp (C)", Ts=0.5)
    np.testing.assert_array_equal(one.y, [20.0, 20.1, 20.3, 20.6, 21.0])
    # empty in the middle and samples again after: a gap, refused
    f.write_text("t,u,y,v\n0,1,2,3\n,,,4\n1,1,2,5\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 3: the columns read \('u', 'y', 't'\) are empty there but hold "
                                         r"samples again from line 4: a gap"):
        load_record_csv(f, u="u", y="y", time="t")
    with pytest.raises(ValueError, match=r"line 3, column 'y': empty cell"):  # one column of several empty
        load_record_csv(f, u="v", y="y", Ts=0.5)


def test_a_short_line_whose_quote_took_in_its_fields_says_so(tmp_path):
    """A line starting with a quote no quote closes read as one field: 'line 4 has 1 field(s)', no word of the quote
    (review55a)."""
    f = tmp_path / "q.csv"
    f.write_text('t,u,y,note\n0,1,2,ok\n1,2,3,ok\n"2,3,4,x\n', encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 4 has 1 field\(s\).*one field, '2,3,4,x', is quoted and holds ','"):
        load_record_csv(f, u="u", y="y", time="t")


def test_a_note_over_lines_in_the_first_column_is_a_cell_not_a_quote_left_open(tmp_path):
    """csv.writer and pandas.to_csv quote a note holding a line break; in the first column its last line runs on into
    the sample's numbers ('break",3.5,0.56'), which read as a sample quotes removed and were refused as a quote left
    open (the file is valid CSV: pandas reads it)."""
    import csv

    f = tmp_path / "notes.csv"
    rows = [("note", "t", "u", "y"), ("line\nbreak", 3.0, 0.5, -1.0), ("", 3.5, 0.25, 2.0),
            ("ends\n", 4.0, 1.0, 4.0), ('two\n"quoted"\nlines', 4.5, 2.0, 8.0), ("a", 5.0, 3.0, 16.0)]
    for terminator in ("\n", "\r\n"):
        with open(f, "w", newline="", encoding="utf-8") as out:
            csv.writer(out, lineterminator=terminator).writerows(rows)
        r = load_record_csv(f, "u", "y", time="t")
        assert r.u.tolist() == [0.5, 0.25, 1.0, 2.0, 3.0] and r.y.tolist() == [-1.0, 2.0, 4.0, 8.0, 16.0]
        assert r.Ts == 0.5
    # a date's closing quote missing, closed by the next line's opening quote, is refused as before
    f.write_text('"date",u,y\n"2026-01-01 00:00:00",1,2\n"2026-01-01 00:00:01,2,3\n"2026-01-01 00:00:02",3,4\n',
                 encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 3.*closes only on line 4"):
        load_record_csv(f, "u", "y", Ts=1.0)


def test_a_quoted_file_is_read_in_memory_of_a_few_times_its_size(tmp_path):
    """Quotes round whole fields (pandas.to_csv(quoting=QUOTE_ALL), every TOA5 file's text fields) are checked before
    numpy reads the file: that check held a running count of 8 bytes per byte of the file for each of the delimiter,
    LF and CR (a 33 MB file of 10^6 rows peaked at 0.9 GB, this one at 28 times its size; the same rows unquoted at 3
    times theirs)."""
    from conftest import traced_peak

    rng = np.random.default_rng(0)
    u, y = rng.normal(size=(2, 30000))
    rows = [(str(k), f"{a:.6f}", f"{b:.6f}") for k, (a, b) in enumerate(zip(u, y))]
    quoted = write(tmp_path, '"t","u","y"\n' + "".join(",".join(f'"{c}"' for c in r) + "\n" for r in rows), "q.csv")
    a = load_record_csv(quoted, "u", "y", time="t")  # imports done before the peak is traced
    assert a.u.tolist() == [float(r[1]) for r in rows] and a.y.tolist() == [float(r[2]) for r in rows] and a.Ts == 1.0
    assert traced_peak(lambda: load_record_csv(quoted, "u", "y", time="t")) < 12 * quoted.stat().st_size


def test_a_digit_group_separator_underscore_is_not_read(tmp_path):
    """Python's float reads '1_000' as 1000 and '1_0.5' as 10.5, and the careful reader took them so (numpy's refuses
    them): a grouped number read where every other thousands separator is refused, and a made-up one."""
    for cell, kw in (("1_000", {}), ("1_0.5", {}), ("1_000,5", {"delimiter": ";", "decimal": ","})):
        sep = kw.get("delimiter", ",")
        f = write(tmp_path, sep.join("tuy") + "\n" + "".join(f"{k}{sep}{cell if k == 1 else k}{sep}2\n"
                                                            for k in range(3)))
        with pytest.raises(ValueError, match=rf"line 3, column 'u': '{cell}' is not a number.*thousands separator"):
            load_record_csv(f, "u", "y", time="t", **kw)
    f = write(tmp_path, "u,y\n1,2\n1_5,3\n")
    with pytest.raises(ValueError, match=r"line 3, column 'u': '1_5' is not a number"):
        load_static_csv(f, "u", "y")


def test_a_column_name_is_found_whatever_unicode_form_composes_its_accents(tmp_path):
    """'Düse' typed (NFC: ü one character) against a header written decomposed (NFD: u and U+0308, as macOS file
    tools and some exports write it) was refused as 'no column 'Drehzahl Düse'. Did you mean 'Drehzahl Düse'?', two
    names that print alike and are the same text by Unicode's canonical equivalence. Either form now finds the
    other; a lookalike that is another character (µ MICRO SIGN for μ) is still refused, named even for a name of
    one character, which no close match found."""
    import unicodedata

    for written, asked in (("NFD", "NFC"), ("NFC", "NFD")):
        col = unicodedata.normalize(written, "Drehzahl Düse")
        f = write(tmp_path, f"t;{col};Druck\n0;1;2\n1;2;3\n2;3;5\n")
        r = load_record_csv(f, unicodedata.normalize(asked, "Drehzahl Düse"), "Druck", time="t")
        assert r.u.tolist() == [1.0, 2.0, 3.0] and r.y.tolist() == [2.0, 3.0, 5.0]
        s = load_static_csv(f, ["t", unicodedata.normalize(asked, "Drehzahl Düse")], "Druck",
                            input_names=["a", "b"])
        assert s.ubar.tolist() == [[0.0, 1.0], [1.0, 2.0], [2.0, 3.0]]
    f = write(tmp_path, "t,\u00b5,y\n0,1,2\n1,2,3\n2,3,5\n")
    with pytest.raises(ValueError, match=r"no column '\u03bc'.*Did you mean '\u00b5'\? \(the file's '\u00b5' is "
                                         r"U\+00B5 MICRO SIGN"):
        load_record_csv(f, "\u03bc", "y", time="t")


@pytest.mark.parametrize("tail, said", [("3,4", r"line 5 has 2 field\(s\), but column 'y' is field 3"),
                                        ("3,4,", r"line 5, column 'y': empty cell")])
def test_a_file_cut_off_in_its_last_line_says_so(tmp_path, tail, said):
    """A file cut off mid-line (a copy or download interrupted, a logger still writing it) ends in a short line with no
    line end: it was refused as a short line or an empty cell, no word of the cut; the same line ended is refused as
    before, with no such word."""
    f = write(tmp_path, "t,u,y\n0,1,2\n1,2,3\n2,3,4\n" + tail)
    with pytest.raises(ValueError, match=said + r".*the file's last line, which has no line end: the file was cut off"):
        load_record_csv(f, "u", "y", time="t")
    f = write(tmp_path, "t,u,y\n0,1,2\n1,2,3\n2,3,4\n" + tail + "\n")
    with pytest.raises(ValueError, match=said) as info:
        load_record_csv(f, "u", "y", time="t")
    assert "cut off" not in str(info.value)


@pytest.mark.parametrize("sep", [";", "\t"])
@pytest.mark.parametrize("blank", [False, True])  # a blank line sends the file to the careful reader
def test_a_grouped_number_past_the_sniffed_lines_of_whole_numbers_is_ambiguous(tmp_path, sep, blank):
    """A ';' or tab file (a decimal-comma locale's) whose first 50 lines hold whole numbers only says nothing of its
    decimal mark; a speed of 1.050 further on (Excel's '#.##0' format: 1050 rpm) was read as 1.05 without a word,
    where the same number in the first lines is refused as ambiguous."""
    speeds = [750 + 10 * (k % 20) for k in range(60)] + ["1.050", "1.100"]
    lines = [sep.join(["t", "speed", "p"])] + [sep.join([str(k), str(s), str(k % 7)]) for k, s in enumerate(speeds)]
    if blank:
        lines.insert(30, "")
    f = write(tmp_path, "\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=rf"line {62 + blank}, column 'speed': '1\.050' reads as 1\.050 or as 1050 "
                                         r".*lines 1 to 50, whole numbers.*decimal='\.'"):
        load_record_csv(f, "speed", "p", time="t")
    r = load_record_csv(f, "speed", "p", time="t", decimal=".")
    assert r.u[-2:].tolist() == [1.05, 1.1]
    # a file whose first lines show the point as its decimal mark reads it so, as before
    f = write(tmp_path, "\n".join(lines).replace(f"{sep}750{sep}", f"{sep}750.5{sep}", 1) + "\n")
    assert load_record_csv(f, "speed", "p", time="t").u[-2:].tolist() == [1.05, 1.1]
    # and so does a file that shows it past the first lines, before or after the cell that alone would be ambiguous: a
    # point before other than three digits (1.25, 0.500) groups no thousands (was: refused at 1.050 all the same)
    for tail in (["1.25", "1.050", "1.100"], ["1.050", "1.100", "0.500"]):
        rows = [sep.join([str(k), str(s), str(k % 7)]) for k, s in enumerate(speeds[:60] + tail)]
        f = write(tmp_path, "\n".join([lines[0], *rows]) + "\n")
        assert load_record_csv(f, "speed", "p", time="t").u[-3:].tolist() == [float(c) for c in tail]


def test_the_header_again_in_the_file_is_named_as_two_files_joined(tmp_path):
    """A logger that writes its header again after a restart, or two exports joined (cat run1.csv run2.csv), put the
    column names again mid-file: refused as "line 5, column 'u': 'u' is not a number", no word of the header."""
    f = write(tmp_path, "t;u;y\n0;1;2\n1;2;3\n2;3;4\nt;u;y\n0;4;5\n1;5;6\n")
    with pytest.raises(ValueError, match=r"line 5 repeats the header \(line 1\): two files joined into one, or a "
                                         r"logger restarted\?.*Cut the file there into two"):
        load_record_csv(f, "u", "y", time="t")
    with pytest.raises(ValueError, match=r"line 5 repeats the header \(line 1\)"):
        load_static_csv(f, "u", "y")
