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
    with pytest.raises(ValueError, match="units must be a pair of strings"):
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

def _buck_dir() -> Path:
    try:
        return find_buck_dir()
    except FileNotFoundError as exc:
        pytest.skip(f"buck converter data (../shared/data/buck) not available here: {exc}")


def test_load_buck():
    d = _buck_dir()
    ds = load_buck(d)
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
    assert load_buck().extra["folder"] == str(d)  # the default search finds the same folder


def test_buck_env_var(monkeypatch, tmp_path):
    d = _buck_dir()
    monkeypatch.setenv("GRAYBOX_BUCK_DIR", str(d))
    monkeypatch.chdir(tmp_path)
    assert find_buck_dir() == d


def test_buck_wrong_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match=re.escape(str(tmp_path)) + ".*buck_id.csv"):
        load_buck(tmp_path)


def test_buck_files_are_not_in_the_project():
    # The licence and the shared folder's README ask that the project never carries copies.
    hits = [p for d in ("data", "tests", "graybox", "notebooks") if (REPO / d).is_dir()
            for p in (REPO / d).rglob("buck_*.csv")]
    assert not hits, hits


# -- the fast reader gives what the careful reader gives -------------------------------------

_FORMATS = (repr, "{:.3f}".format, "{:.6e}".format, lambda v: f"  {v!r} ", lambda v: f"{v:+.17g}")


@settings(max_examples=80, deadline=None)
@given(values=st.lists(st.tuples(st.floats(-1e300, 1e300, allow_nan=False), st.floats(-1e6, 1e6, allow_nan=False)),
                       min_size=1, max_size=30),
       fmt=st.integers(0, len(_FORMATS) - 1), crlf=st.booleans(), bom=st.booleans(),
       blank=st.integers(-1, 30), quote=st.booleans(), text_col=st.booleans(), trailing_newline=st.booleans())
def test_fast_and_careful_csv_readers_agree(values, fmt, crlf, bom, blank, quote, text_col, trailing_newline):
    """numpy's reader, used where it can be, gives the careful reader's floats bit for bit and its line
    numbers; files it cannot read exactly (quotes, blank lines) go to the careful reader."""
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
        fast = _loaders._fast_columns(p, index)
        careful_reader = _loaders._fast_columns
        try:
            _loaders._fast_columns = lambda p, index: None
            careful = _loaders._read_columns(p, {"u": "a", "y": "b"})
        finally:
            _loaders._fast_columns = careful_reader
        got = _loaders._read_columns(p, {"u": "a", "y": "b"})
    simple = not quote and not (0 <= blank < len(values))
    assert (fast is not None) == simple
    for k in ("u", "y", "_lines"):
        assert np.array_equal(got[k], careful[k])
        assert np.array_equal(np.signbit(got[k]), np.signbit(careful[k]))
    assume(simple)
    assert np.array_equal(fast["u"], careful["u"]) and np.array_equal(fast["_lines"], careful["_lines"])
