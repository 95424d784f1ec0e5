"""A data logger's row of units under the column names (``t;speed;p`` then ``s;rpm;Pa``): read into
the record's or the points' units with ``units_row=True``, named in the refusal without it, and
checked against ``units=`` and against the seconds time stamps are read in."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


def _write(path, text: str, newline: str = "\n"):
    path.write_bytes(text.replace("\n", newline).encode("utf-8"))
    return path


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_a_units_row_becomes_the_records_units(tmp_path, newline):
    f = _write(tmp_path / "run.csv", "t;speed;p\ns;rpm;Pa\n0,0;1000;2,0e5\n0,1;1010;2,01e5\n0,2;1020;2,02e5\n", newline)
    r = gb.load_record_csv(f, "speed", "p", time="t", units_row=True)
    assert r.units == ("rpm", "Pa") and r.Ts == 0.1
    np.testing.assert_array_equal(r.y, [2.0e5, 2.01e5, 2.02e5])
    np.testing.assert_array_equal(r.u, [1000, 1010, 1020])


def test_without_the_option_the_row_is_named_and_the_option_too(tmp_path):
    f = _write(tmp_path / "run.csv", "t,speed,p\n[s],[rpm],[Pa]\n0.0,1000,200000\n0.1,1010,201000\n")
    with pytest.raises(ValueError, match=r"line 2 holds text in every column read .*pass units_row=True"):
        gb.load_record_csv(f, "speed", "p", time="t")
    assert gb.load_record_csv(f, "speed", "p", time="t", units_row=True).units == ("rpm", "Pa")  # brackets dropped
    pts = _write(tmp_path / "steady.csv", "speed,p\nrpm,Pa\n1000,200000\n1500,250000\n")
    with pytest.raises(ValueError, match="pass units_row=True"):
        gb.load_static_csv(pts, "speed", "p")
    assert gb.load_static_csv(pts, "speed", "p", units_row=True).units == ("rpm", "Pa")


def test_later_lines_keep_the_files_own_numbers(tmp_path):
    f = _write(tmp_path / "run.csv", "t,speed,p\ns,rpm,Pa\n0.0,1000,200000\n0.1,,201000\n")
    with pytest.raises(ValueError, match=r"line 4, column 'speed': empty cell"):
        gb.load_record_csv(f, "speed", "p", time="t", units_row=True)


def test_the_units_row_is_checked(tmp_path):
    two = _write(tmp_path / "two.csv", "t,n1,n2,p\ns,rpm,V,Pa\n0.0,1000,1,2e5\n0.1,1010,2,2.01e5\n0.2,1020,3,2.02e5\n")
    # inputs in units of their own keep one each; a units= of one unit for both contradicts the row
    assert gb.load_record_csv(two, ["n1", "n2"], "p", time="t", units_row=True).units == (("rpm", "V"), "Pa")
    with pytest.raises(ValueError, match=r"says the input 'n2' is in 'rpm', but the units row says 'V'"):
        gb.load_record_csv(two, ["n1", "n2"], "p", time="t", units_row=True, units=("rpm", "Pa"))
    assert gb.load_record_csv(two, ["n1", "n2"], "p", time="t", units_row=True,
                              units=(("rpm", "V"), "Pa")).units == (("rpm", "V"), "Pa")
    furlongs = _write(tmp_path / "ms.csv", "t,speed,p\nfortnights,rpm,Pa\n0,1000,2e5\n100,1010,2.01e5\n")
    with pytest.raises(ValueError, match="time column the unit 'fortnights', but graybox converts the units of "
                                         "elapsed time s, ms, µs"):
        gb.load_record_csv(furlongs, "speed", "p", time="t", units_row=True)
    ok = _write(tmp_path / "ok.csv", "t,speed,p\ns,rpm,Pa\n0,1000,2e5\n0.1,1010,2.01e5\n")
    with pytest.raises(ValueError, match=r"units=.*says the input is in 'rad/s', but the units row says 'rpm'"):
        gb.load_record_csv(ok, "speed", "p", time="t", units_row=True, units=("rad/s", "Pa"))
    assert gb.load_record_csv(ok, "speed", "p", time="t", units_row=True, units=("rpm", "")).units == ("rpm", "Pa")
    plain = _write(tmp_path / "plain.csv", "t,speed,p\n0,1000,2e5\n0.1,1010,2.01e5\n0.2,1020,2.02e5\n")
    with pytest.raises(ValueError, match=r"line 2 holds numbers .* not a row of units: drop units_row=True"):
        gb.load_record_csv(plain, "speed", "p", time="t", units_row=True)
    with pytest.raises(TypeError, match="units_row"):
        gb.load_record_csv(plain, "speed", "p", time="t", units_row="yes")
    head = _write(tmp_path / "head.csv", "t,speed,p\n")
    with pytest.raises(ValueError, match="no line after the header"):
        gb.load_record_csv(head, "speed", "p", time="t", units_row=True)


def test_a_units_row_that_leaves_an_input_blank_says_nothing_of_it(tmp_path):
    # a row naming 'l/min' for q and nothing for T gave both inputs 'l/min' (the record then clashed with one whose
    # T is in °C), and units= naming q's unit beside a row naming T's only was refused as contradicting it
    q_only = _write(tmp_path / "q.csv", "t,q,T,h\ns,l/min,,m\n0,1.0,20.0,1\n1,1.5,21.0,2\n2,2.0,22.0,3\n")
    rec = gb.load_record_csv(q_only, ["q", "T"], "h", time="t", units_row=True)
    assert rec.units == (("l/min", ""), "m")
    full = _write(tmp_path / "full.csv", "t,q,T,h\ns,l/min,°C,m\n0,1.0,20.0,1\n1,1.5,21.0,2\n2,2.0,22.0,3\n")
    gb.Dataset(rec, gb.load_record_csv(full, ["q", "T"], "h", time="t", units_row=True))
    t_only = _write(tmp_path / "T.csv", "t,q,T,h\ns,,°C,m\n0,1.0,20.0,1\n1,1.5,21.0,2\n2,2.0,22.0,3\n")
    assert gb.load_record_csv(t_only, ["q", "T"], "h", time="t", units_row=True,
                              units=(("l/min", ""), "")).units == (("l/min", "°C"), "m")
    pts = _write(tmp_path / "pts.csv", "q,T,h\nl/min,,m\n1.0,20.0,1\n2.0,21.0,2\n")
    assert gb.load_static_csv(pts, ["q", "T"], "h", units_row=True).units == (("l/min", ""), "m")


def test_a_grid_spec_takes_units_row(tmp_path):
    from graybox.experiments import Grid, SpecError

    for name, n in (("ident", 60), ("valid", 40)):
        rows = "".join(f"{k * 0.1:.1f},{1000 + 10 * (k // 5 % 4)},{2e5 + 50 * (k // 5 % 4) + k % 3}\n" for k in range(n))
        _write(tmp_path / f"{name}.csv", "t,speed,p\ns,rpm,Pa\n" + rows)
    _write(tmp_path / "static.csv", "speed,p\nrpm,Pa\n1000,200000\n1030,200150\n")
    spec = ('name = "own"\n[[data]]\nname = "rig"\n'
            + "".join(f'{k} = {{path = "{k}.csv", u = "speed", y = "p", time = "t", units_row = true}}\n'
                      for k in ("ident", "valid"))
            + 'static = {path = "static.csv", u = "speed", y = "p", units_row = true}\nband = 100.0\n'
            + '[[structures]]\nname = "given"\nterms = ["y(k-1)", "u(k-1)", "1"]\n'
              '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    data = Grid.from_toml_text(spec, base_dir=str(tmp_path)).data[0].load(tmp_path)
    assert data.ident.units == data.valid.units == data.static.units == ("rpm", "Pa")
    with pytest.raises(SpecError, match="units_row"):
        Grid.from_toml_text(spec.replace("units_row = true", 'units_row = "yes"'))


# A units row giving a time column of numbers the unit ms (a logger's elapsed milliseconds) was refused ("time stamps
# are read as seconds"), though the row says how to read them: now converted, per unit, to the seconds of Ts (mend61e)
@pytest.mark.parametrize("unit, stamps, Ts", [
    ("ms", ["0", "10", "20", "30"], 0.01), ("[ms]", ["1000", "1100", "1200", "1300"], 0.1),
    ("µs", ["0", "250", "500", "750"], 250e-6), ("μs", ["0", "250", "500", "750"], 250e-6),
    ("us", ["5000000", "5001000", "5002000", "5003000"], 1e-3), ("ns", ["0", "500", "1000", "1500"], 5e-7),
    ("min", ["0", "0.5", "1", "1.5"], 30.0), ("h", ["2", "2.25", "2.5", "2.75"], 900.0),
    ("d", ["0", "1", "2", "3"], 86400.0),
    ("s", ["0", "0.5", "1", "1.5"], 0.5),
])
def test_a_units_rows_unit_of_elapsed_time_is_converted_to_seconds(tmp_path, unit, stamps, Ts):
    rows = "".join(f"{t},{1000 + k},{2e5 + k}\n" for k, t in enumerate(stamps))
    f = _write(tmp_path / "run.csv", f"t,speed,p\n{unit},rpm,Pa\n{rows}")
    r = gb.load_record_csv(f, "speed", "p", time="t", units_row=True)
    assert r.Ts == pytest.approx(Ts, rel=1e-12) and r.units == ("rpm", "Pa")
    # and checked against a Ts given in seconds, as stamps in seconds are
    assert gb.load_record_csv(f, "speed", "p", time="t", units_row=True, Ts=Ts).Ts == Ts
    with pytest.raises(ValueError, match="disagrees"):
        gb.load_record_csv(f, "speed", "p", time="t", units_row=True, Ts=Ts * 1000)


def test_dates_given_a_unit_of_elapsed_time_in_the_units_row_are_refused(tmp_path):
    f = _write(tmp_path / "run.csv",
               "t,speed,p\nms,rpm,Pa\n2026-11-20 09:14:03,1000,2e5\n2026-11-20 09:14:04,1010,2e5\n")
    with pytest.raises(ValueError, match=r"unit 'ms', but the time column holds dates or clock times"):
        gb.load_record_csv(f, "speed", "p", time="t", units_row=True)


# A units row (or a time column's name) was read whatever its case: 'Ms' (megaseconds) and 'MS' read as ms,
# milliseconds, a period off by 10⁹. A symbol whose case names another unit is now read as written only, and refused,
# naming the column, in another case; a word (Sec, MIN) names no other unit in any case and is read in any.
@pytest.mark.parametrize("unit", ["Ms", "MS", "mS", "S", "H", "US"])
def test_a_time_unit_in_another_case_is_refused_as_ambiguous_naming_the_column(tmp_path, unit):
    rows = "t,speed,p\n{},rpm,Pa\n0,1000,2e5\n10,1010,2.01e5\n20,1020,2.02e5\n"
    f = _write(tmp_path / "run.csv", rows.format(unit))
    with pytest.raises(ValueError, match=rf"time column 't' is given the unit '{unit}', which differs from "
                                         rf"'{unit.lower()}' only by case: ambiguous"):
        gb.load_record_csv(f, "speed", "p", time="t", units_row=True)
    named = _write(tmp_path / "named.csv", f"t [{unit}],speed,p\n0,1000,2e5\n10,1010,2.01e5\n")
    if unit.lower() != "s":  # 't [s]' names seconds, which the stamps are read in without a unit
        with pytest.raises(ValueError, match=rf"time column 't \[{unit}\]' is given the unit '{unit}'.*only by case"):
            gb.load_record_csv(named, "speed", "p", time=f"t [{unit}]")


@pytest.mark.parametrize("unit, Ts", [("ms", 0.01), ("Sec", 10.0), ("MIN", 600.0), ("Hours", 36000.0), ("s", 10.0)])
def test_a_time_unit_as_written_or_a_word_in_any_case_is_read(tmp_path, unit, Ts):
    f = _write(tmp_path / "run.csv", f"t,speed,p\n{unit},rpm,Pa\n0,1000,2e5\n10,1010,2.01e5\n20,1020,2.02e5\n")
    assert gb.load_record_csv(f, "speed", "p", time="t", units_row=True).Ts == pytest.approx(Ts, rel=1e-12)


# 'mSec', 'uSEC' (a lower-case prefix, the word 'sec' in any case, as DAQ exports write it) were refused as ambiguous,
# though their prefix is as written and the word names no other unit; a capital prefix ('Msec', 'MSEC': mega) still is.
@pytest.mark.parametrize("unit, Ts", [("mSec", 0.01), ("mSEC", 0.01), ("uSec", 1e-5), ("nSEC", 1e-8)])
def test_a_prefixed_sec_with_its_prefix_as_written_is_read(tmp_path, unit, Ts):
    f = _write(tmp_path / "run.csv", f"t,speed,p\n{unit},rpm,Pa\n0,1000,2e5\n10,1010,2.01e5\n20,1020,2.02e5\n")
    assert gb.load_record_csv(f, "speed", "p", time="t", units_row=True).Ts == pytest.approx(Ts, rel=1e-12)
    for capital in (unit[0].upper() + unit[1:], unit.upper()):
        g = _write(tmp_path / "cap.csv", f"t,speed,p\n{capital},rpm,Pa\n0,1000,2e5\n10,1010,2.01e5\n")
        with pytest.raises(ValueError, match="only by case: ambiguous"):
            gb.load_record_csv(g, "speed", "p", time="t", units_row=True)
