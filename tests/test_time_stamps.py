"""Time columns of dates and times: ISO 8601 stamps, clock times, a TOA5 file's TIMESTAMP (load_record_csv)."""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb

TOA5_HEAD = ('"TOA5","CR1000","CR1000","1234","CR1000.Std.32","CPU:x.CR1","1","Table1"\n'
             '"TIMESTAMP","RECORD","Power","Temp"\n"TS","RN","W","degC"\n"","","Smp","Avg"\n')


def _csv(path, stamps, sep=","):
    path.write_text(f"t{sep}u{sep}y\n" + "".join(f"{s}{sep}{k % 3}{sep}{0.5 * k}\n" for k, s in enumerate(stamps)),
                    encoding="utf-8")
    return path


@settings(max_examples=25, deadline=None)
@given(start=st.datetimes(min_value=datetime(1990, 1, 1), max_value=datetime(2090, 1, 1)),
       ms=st.integers(1, 5000), n=st.integers(2, 30), sep=st.sampled_from(["T", " "]))
def test_iso_stamps_give_the_period_and_samples_of_the_same_stamps_in_seconds(tmp_path_factory, start, ms, n, sep):
    """The law: a record read from ISO 8601 stamps is the record read from the same instants as seconds."""
    d = tmp_path_factory.mktemp("iso")
    start = start.replace(microsecond=start.microsecond // 1000 * 1000)  # stamps written to the millisecond
    instants = [start + timedelta(milliseconds=ms * k) for k in range(n)]
    iso = gb.load_record_csv(_csv(d / "iso.csv", [t.isoformat(sep=sep, timespec="milliseconds") for t in instants]),
                             u="u", y="y", time="t")
    secs = gb.load_record_csv(_csv(d / "s.csv", [f"{ms * k / 1000:.3f}" for k in range(n)]), u="u", y="y", time="t")
    assert iso.Ts == secs.Ts == pytest.approx(ms / 1000, rel=1e-12)
    np.testing.assert_array_equal(iso.u, secs.u)
    np.testing.assert_array_equal(iso.y, secs.y)


def test_every_fraction_digit_counts_and_utc_offsets_give_elapsed_time(tmp_path):
    # 100 ns steps: a datetime keeps 6 digits, which would make the steps 0 and 1 µs
    ns = gb.load_record_csv(_csv(tmp_path / "ns.csv", [f"2026-11-20 09:14:00.{100 * k:09d}" for k in range(8)]),
                            u="u", y="y", time="t")
    assert ns.Ts == pytest.approx(1e-7, rel=1e-9)
    # the spring clock change written with offsets: 01:59:59+01:00 to 03:00:00+02:00 is one second
    cet, cest = timezone(timedelta(hours=1)), timezone(timedelta(hours=2))
    instants = [datetime(2026, 3, 29, 0, 59, 58, tzinfo=timezone.utc) + timedelta(seconds=k) for k in range(5)]
    stamps = [t.astimezone(cest if t.hour >= 1 else cet).isoformat(sep=" ") for t in instants]
    assert stamps[2].endswith("+01:00") is False and "03:00:00" in stamps[2]
    rec = gb.load_record_csv(_csv(tmp_path / "dst.csv", stamps), u="u", y="y", time="t")
    assert rec.Ts == 1.0 and rec.y.size == 5
    z = gb.load_record_csv(_csv(tmp_path / "z.csv", [t.strftime("%Y-%m-%dT%H:%M:%SZ") for t in instants]),
                           u="u", y="y", time="t")
    assert z.Ts == 1.0


def test_local_times_over_a_clock_change_are_refused_as_one(tmp_path):
    spring = ["2026-03-29 01:59:58", "2026-03-29 01:59:59", "2026-03-29 03:00:00", "2026-03-29 03:00:01"]
    with pytest.raises(ValueError, match=r"line 3 to line 4 \('2026-03-29 01:59:59' to '2026-03-29 03:00:00'\).*"
                                         r"plus an hour: a clock change \(daylight saving time\).*UTC offset"):
        gb.load_record_csv(_csv(tmp_path / "spring.csv", spring), u="u", y="y", time="t")
    autumn = ["2026-10-25 02:59:58", "2026-10-25 02:59:59", "2026-10-25 02:00:00", "2026-10-25 02:00:01"]
    with pytest.raises(ValueError, match=r"does not increase from line 3.*an hour back, a clock change"):
        gb.load_record_csv(_csv(tmp_path / "autumn.csv", autumn), u="u", y="y", time="t")
    with pytest.raises(ValueError, match=r"line 3, column 't': '2026-03-29 01:59:59' has no UTC offset but line "
                                         r"2's '2026-03-29 01:59:58\+01:00' has one"):
        gb.load_record_csv(_csv(tmp_path / "mixed.csv", ["2026-03-29 01:59:58+01:00", "2026-03-29 01:59:59"]),
                           u="u", y="y", time="t")
    with pytest.raises(ValueError, match=r"line 3, column 't': '2026-03-29T01:59:59Z' has a UTC offset but the "
                                         "stamps before it have none"):
        gb.load_record_csv(_csv(tmp_path / "mixed2.csv", ["2026-03-29T01:59:58", "2026-03-29T01:59:59Z"]),
                           u="u", y="y", time="t")


def test_clock_times_pass_midnight_and_need_their_seconds(tmp_path):
    stamps = ["23:59:58.5", "23:59:59.0", "23:59:59.5", "00:00:00.0", "00:00:00.5"]
    rec = gb.load_record_csv(_csv(tmp_path / "clock.csv", stamps, sep=";"), u="u", y="y", time="t")
    assert rec.Ts == 0.5 and rec.y.size == 5
    # 00:01, 00:02 … may be a stopwatch's minutes and seconds: read as hours and minutes, 60 times too long
    with pytest.raises(ValueError, match=r"line 2, column 't': '00:01' is not a number.*clock times \(09:14:03.5\)"):
        gb.load_record_csv(_csv(tmp_path / "mmss.csv", ["00:01", "00:02", "00:03"]), u="u", y="y", time="t")
    # 25:00:00 is no clock time but an elapsed 25 h (a spreadsheet's [h]:mm:ss duration): after 23:59:59 in a clock
    # column, a typo for 00:00:00, it is a step of an hour, refused as uneven; a minute out of range is no time at all
    with pytest.raises(ValueError, match=r"uneven time stamps: step 3601 s from line 4 to line 5"):
        gb.load_record_csv(_csv(tmp_path / "bad.csv", ["23:59:57", "23:59:58", "23:59:59", "25:00:00"]), u="u", y="y",
                           time="t")
    with pytest.raises(ValueError, match=r"line 3, column 't': '23:60:00' is not a clock time.*'23:59:59' \(line 2\)"):
        gb.load_record_csv(_csv(tmp_path / "bad.csv", ["23:59:59", "23:60:00"]), u="u", y="y", time="t")


@pytest.mark.parametrize("stamp", ["20.11.2026 09:14:{:02d}", "11/20/2026 09:14:{:02d}"])
def test_dates_in_another_order_are_refused_saying_what_is_read(tmp_path, stamp):
    f = _csv(tmp_path / "d.csv", [stamp.format(k) for k in range(4)])
    with pytest.raises(ValueError, match=r"line 2, column 't'.*not a number.*ISO 8601.*which number is the day.*Ts="):
        gb.load_record_csv(f, u="u", y="y", time="t")
    assert gb.load_record_csv(f, u="u", y="y", Ts=1.0).y.size == 4


def test_a_toa5_timestamp_gives_the_period_and_shows_a_pause_of_the_logger(tmp_path):
    rows = "".join(f'"2026-01-01 00:00:{2 * k:02d}",{k},10.0,20.{k}\n' for k in range(5))
    f = tmp_path / "t.dat"
    f.write_bytes((TOA5_HEAD + rows).replace("\n", "\r\n").encode())
    rec = gb.load_record_csv(f, u="Power", y="Temp", time="TIMESTAMP")
    assert rec.Ts == 2.0 and rec.units == ("W", "degC") and rec.y.size == 5
    with pytest.raises(ValueError, match=r"Ts = 1 s disagrees with column 'TIMESTAMP'"):
        gb.load_record_csv(f, u="Power", y="Temp", time="TIMESTAMP", Ts=1.0)
    paused = rows.replace('"2026-01-01 00:00:06",3', '"2026-01-01 00:05:06",3').replace(
        '"2026-01-01 00:00:08",4', '"2026-01-01 00:05:08",4')  # record numbers run on over the pause
    f.write_bytes((TOA5_HEAD + paused).replace("\n", "\r\n").encode())
    with pytest.raises(ValueError, match=r"line 7 to line 8 \('2026-01-01 00:00:04' to '2026-01-01 00:05:06'\)"):
        gb.load_record_csv(f, u="Power", y="Temp", time="TIMESTAMP")
    assert gb.load_record_csv(f, u="Power", y="Temp", Ts=2.0).y.size == 5  # Ts alone: the stamps unread, as said


# written to every digit, or as Excel shows a General cell (11 digits: 1e-6 of a day, so 0.01 s steps print as 0)
@pytest.mark.parametrize("seconds, digits", [(1.0, 15), (1.0, 11), (0.1, 15), (0.1, 11), (0.01, 15), (60.0, 11)])
def test_a_spreadsheets_serial_dates_are_refused_not_read_as_seconds(tmp_path, digits, seconds):
    """Days since 1899-12-30 read as seconds gave a sampling period 86,400 times too short, without a word."""
    first = (datetime(2025, 12, 9, 12) - datetime(1899, 12, 30)) / timedelta(days=1)
    f = _csv(tmp_path / "xl.csv", [f"{first + k * seconds / 86400:.{digits}g}" for k in range(20)])
    said = rf"serial dates.*2025-12-09 12:00:00 in the 1900 system.*a step of {seconds:g} s.*Ts="
    with pytest.raises(ValueError, match=said):
        gb.load_record_csv(f, u="u", y="y", time="t")


def test_serial_dates_of_a_1904_workbook_are_named_as_such_not_only_as_1900_dates(tmp_path):
    """A workbook of the 1904 date system (Mac Excel) counts days from 1904-01-01: the message named its
    2025-12-09 12:00 as 2021-12-08 12:00 (days since 1899-12-30) alone; the file cannot tell which system wrote it."""
    first = (datetime(2025, 12, 9, 12) - datetime(1904, 1, 1)) / timedelta(days=1)
    f = _csv(tmp_path / "mac.csv", [f"{first + k / 86400:.15g}" for k in range(20)])
    with pytest.raises(ValueError, match=r"serial dates.*2021-12-08 12:00:00 in the 1900 system.*"
                                         r"2025-12-09 12:00:00 in the 1904 system.*a step of 1 s"):
        gb.load_record_csv(f, u="u", y="y", time="t")


@pytest.mark.parametrize("rate", [1e3, 1e4, 5e4, 1e5, 2e5, 1e6])
def test_seconds_at_the_usual_sampling_rates_are_never_taken_for_serial_dates(tmp_path, rate):
    f = _csv(tmp_path / "s.csv", [f"{30000 + k / rate:.12f}" for k in range(20)])  # 8 h 20 min into a run
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(1 / rate, rel=1e-9)


# 44.1 and 88.2 kHz (audio) step by 1.96 s and 0.98 s of a day, and 1/0.0007 s by 60.5 s: within 5 % of 2 s, 1 s and
# 60 s, they were refused as serial dates; the stamps' 12 decimals leave their step known far closer than that. (The
# period is rounded to the 7 digits float stamps near 30000 s resolve of it, as documented.)
@pytest.mark.parametrize("rate", [44100.0, 88200.0, 1 / 0.0007])
def test_seconds_at_rates_near_a_round_fraction_of_a_day_are_not_taken_for_serial_dates(tmp_path, rate):
    f = _csv(tmp_path / "s.csv", [f"{30000 + k / rate:.12f}" for k in range(20)])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(1 / rate, rel=1e-6)
    # the same stamps as serial dates written to 11 digits, 1e-6 of a day, still refused at 2 s, 1 s and 60 s
    near = {44100.0: 2.0, 88200.0: 1.0}.get(rate, 60.0)
    f = _csv(tmp_path / "d.csv", [f"{46000.5 + k * near / 86400:.11g}" for k in range(20)])
    with pytest.raises(ValueError, match=rf"serial dates.*a step of {near:g} s"):
        gb.load_record_csv(f, u="u", y="y", time="t")


# Seconds at 25 or 40 Hz 10 h into a run lie within what a short record's decimals leave unknown of 1 h or 2000 s
# of a day: they were refused as a spreadsheet's serial dates. Seconds at a usual acquisition rate that fits better
# than a round period are seconds (mend61e).
@pytest.mark.parametrize("rate, start, decimals, n", [(25, 36000, 6, 5), (25, 46000, 2, 3), (40, 36000, 3, 3),
                                                      (48, 30000, 6, 20), (50, 36000, 2, 4), (60, 36000, 6, 20),
                                                      (100, 100000, 2, 3), (400, 36000, 4, 5)])
def test_seconds_at_usual_rates_are_not_taken_for_serial_dates_of_a_round_period(tmp_path, rate, start, decimals, n):
    f = _csv(tmp_path / "s.csv", [f"{start + k / rate:.{decimals}f}" for k in range(n)])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(1 / rate, rel=10.0**-decimals * rate)


# 24 Hz is 1 h of a day exactly: the numbers cannot tell such seconds from hourly serial dates, far more common in a
# plant's logs, which read as seconds would give a period 86,400 times off; refused, saying how to read seconds
@pytest.mark.parametrize("start, decimals, n", [(36000, 6, 20), (20000, 6, 200), (100000, 9, 5), (46000, 6, 48)])
def test_stamps_one_hour_of_a_day_apart_stay_refused_saying_how_to_read_24_hz_seconds(tmp_path, start, decimals, n):
    f = _csv(tmp_path / "s.csv", [f"{start + k / 24:.{decimals}f}" for k in range(n)])
    with pytest.raises(ValueError, match=r"serial dates .*seconds at 24 Hz, whose steps are 3600 s of a day exactly: "
                                         r"leave time= out and give Ts=1/24"):
        gb.load_record_csv(f, u="u", y="y", time="t")
    assert gb.load_record_csv(f, u="u", y="y", Ts=1 / 24).Ts == pytest.approx(1 / 24)


def test_hourly_serial_dates_are_named_whatever_ts_says(tmp_path):
    # hourly serial dates have the numbers of seconds at 24 Hz: refused as dates with Ts= given too (Ts=3600 said
    # only "disagrees with the stamps' mean step 0.0416667 s")
    f = _csv(tmp_path / "h.csv", [f"{46000 + k / 24:.10f}" for k in range(30)])
    for Ts in (3600.0, 1.0):
        with pytest.raises(ValueError, match=r"serial dates .* a step of 3600 s\), not seconds"):
            gb.load_record_csv(f, u="u", y="y", time="t", Ts=Ts)


@pytest.mark.parametrize("year", [1600, 2026, 2300, 9999])
def test_stamps_of_any_year_are_read_alike(tmp_path, year):
    """numpy's nanosecond dates hold the years 1678-2261 and wrap others silently (2300 read as 1715)."""
    f = _csv(tmp_path / "y.csv", [f"{year}-12-31 23:59:{57 + k}.25" for k in range(3)])
    rec = gb.load_record_csv(f, u="u", y="y", time="t")
    assert rec.Ts == 1.0 and rec.y.size == 3


def test_stamps_written_unalike_are_read_cell_by_cell_and_named(tmp_path):
    stamps = ["2026-11-20 09:14:00.5", "2026-11-20 09:14:01", "2026-11-20 09:14:01.5", "NaT", "2026-11-20 09:14:02.5"]
    with pytest.raises(ValueError, match=r"line 5, column 't': 'NaT' is not an ISO 8601 date and time"):
        gb.load_record_csv(_csv(tmp_path / "a.csv", stamps), u="u", y="y", time="t")
    stamps[3] = "2026-11-20 09:14:02"
    assert gb.load_record_csv(_csv(tmp_path / "b.csv", stamps), u="u", y="y", time="t").Ts == 0.5


def test_a_quoted_file_reads_as_the_same_file_unquoted(tmp_path):
    rows = [f'"2026-01-01 00:00:{k:02d}",{k},"{k % 3}.5",{0.25 * k}' for k in range(6)]
    quoted, plain = tmp_path / "q.csv", tmp_path / "p.csv"
    quoted.write_text('"t","n","u","y"\n' + "\n".join(rows) + "\n", encoding="utf-8")
    plain.write_text("t,n,u,y\n" + "\n".join(r.replace('"', "") for r in rows) + "\n", encoding="utf-8")
    a, b = (gb.load_record_csv(f, u="u", y="y", time="t") for f in (quoted, plain))
    assert a.Ts == b.Ts == 1.0
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.y, b.y)
    quoted.write_text('"t","n","u","y"\n' + "\n".join(rows).replace('"2.5"', '2"5') + "\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"column 'u'"):  # a quote inside a number is no quoting: never dropped
        gb.load_record_csv(quoted, u="u", y="y", time="t")


def test_a_toa5_file_thinned_to_every_kth_record_reads_and_its_gaps_are_still_named(tmp_path):
    """RECORD stepping by 2 throughout (every second sample kept) was refused as records missing at its first line."""
    f = tmp_path / "thin.dat"

    def write(records):
        f.write_text(TOA5_HEAD + "".join(f'"2026-01-01 00:00:{2 * k:02d}",{r},1.0,2.{k}\n'
                                         for k, r in enumerate(records)), encoding="utf-8")
        return f

    assert gb.load_record_csv(write([10, 12, 14, 16, 18]), u="Power", y="Temp", time="TIMESTAMP").Ts == 2.0
    with pytest.raises(ValueError, match=r"jumps from 14 \(line 7\) to 18 \(line 8\): 3 record\(s\) missing from the "
                                         r"file \(it holds one record in 2: 1 of those\)"):
        gb.load_record_csv(write([10, 12, 14, 18, 20]), u="Power", y="Temp", Ts=2.0)
    with pytest.raises(ValueError, match=r"jumps from 11 \(line 6\) to 13 \(line 7\): 1 record\(s\) missing"):
        gb.load_record_csv(write([10, 11, 13, 14, 15]), u="Power", y="Temp", Ts=1.0)


def test_a_thinned_toa5_files_step_off_its_thinning_is_said_as_such_not_as_a_fraction_of_records(tmp_path):
    """A step of a thinned file that is no multiple of its usual step read '0 record(s) missing (it holds one record
    in 2: -0.5 of those)' (16 to 17) and '14 record(s) missing (… one record in 10: 0.5 of those)' (30 to 45)."""
    f = tmp_path / "thin.dat"

    def write(records):
        f.write_text(TOA5_HEAD + "".join(f'"2026-01-01 00:00:{2 * k:02d}",{r},1.0,2.{k}\n'
                                         for k, r in enumerate(records)), encoding="utf-8")
        return f

    for records, where, step, usual in (([10, 12, 14, 16, 17, 19, 21], r"from 16 \(line 8\) to 17 \(line 9\)", 1, 2),
                                        ([10, 20, 30, 45, 55, 65], r"from 30 \(line 7\) to 45 \(line 8\)", 15, 10)):
        with pytest.raises(ValueError, match=rf"steps {where}, by {step}, where the file's other lines step by "
                                             rf"{usual} \(one record in {usual} kept\)") as info:
            gb.load_record_csv(write(records), u="Power", y="Temp", Ts=2.0)
        assert "of those" not in str(info.value) and "0 record(s)" not in str(info.value)


def test_a_toa5_file_with_its_units_and_processing_codes_swapped_is_refused_not_read_as_units(tmp_path):
    """Lines 3 and 4 swapped (the codes first) read the processing codes as the record's units, ('Smp', 'Avg')."""
    f = tmp_path / "swapped.dat"
    head = TOA5_HEAD.splitlines(keepends=True)
    rows = "".join(f'"2026-01-01 00:00:{k:02d}",{k},1.{k},2.{k}\n' for k in range(5))
    f.write_text(head[0] + head[1] + head[3] + head[2] + rows, encoding="utf-8")
    with pytest.raises(ValueError, match=r"line 3 gives column 'Power' the unit 'Smp', one of a TOA5 file's "
                                         r"processing codes"):
        gb.load_record_csv(f, u="Power", y="Temp", time="TIMESTAMP")
    f.write_text("".join(head) + rows, encoding="utf-8")  # in order: the units
    assert gb.load_record_csv(f, u="Power", y="Temp", time="TIMESTAMP").units == ("W", "degC")


def test_iso_end_of_day_24_00_reads_as_the_next_midnight_and_a_leap_second_is_named(tmp_path):
    """ISO 8601's 24:00:00 (the day's end) and UTC's leap second 23:59:60 were refused as 'not an ISO 8601 date and
    time', which both are."""
    f = _csv(tmp_path / "end.csv", ["2016-12-31 23:59:58", "2016-12-31 23:59:59", "2016-12-31 24:00:00",
                                    "2017-01-01 00:00:01"])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == 1.0
    f = _csv(tmp_path / "clock.csv", ["23:59:58", "23:59:59", "24:00:00", "00:00:01"])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == 1.0
    f = _csv(tmp_path / "leap.csv", ["2016-12-31 23:59:59", "2016-12-31 23:59:60", "2017-01-01 00:00:00"])
    with pytest.raises(ValueError, match=r"line 3, column 't': '2016-12-31 23:59:60' is a leap second"):
        gb.load_record_csv(f, u="u", y="y", time="t")
    f = _csv(tmp_path / "bad.csv", ["2016-12-31 23:59:59", "2016-12-31 24:00:01"])
    with pytest.raises(ValueError, match=r"'2016-12-31 24:00:01' is not an ISO 8601 date and time"):
        gb.load_record_csv(f, u="u", y="y", time="t")


def test_a_quoted_file_with_a_byte_order_mark_keeps_numpys_reader(tmp_path, monkeypatch):
    """pandas.to_csv(encoding='utf-8-sig', quoting=QUOTE_ALL) starts with a BOM, then the header's opening quote: the
    quotes were kept (a BOM is no line start) and the file went to the careful reader, ten times slower."""
    from graybox.datasets import _loaders

    fast = []
    real = _loaders._fast_columns
    monkeypatch.setattr(_loaders, "_fast_columns", lambda *a, **k: fast.append(real(*a, **k)) or fast[-1])
    rows = [f'"2026-01-01 00:00:{k:02d}","{k}","{k % 3}.5","{0.25 * k}"' for k in range(6)]
    f = tmp_path / "bom.csv"
    for nl in ("\n", "\r\n"):
        f.write_bytes(("\ufeff" + nl.join(['"t","n","u","y"'] + rows) + nl).encode())
        rec = gb.load_record_csv(f, u="u", y="y", time="t")
        assert fast[-1] is not None and rec.Ts == 1.0 and rec.y.tolist() == [0.25 * k for k in range(6)]


def _frame_with_time():
    import pandas as pd
    t = 100.0 + 0.1 * np.arange(40)  # seconds of a logger's clock
    u = np.sin(np.arange(40.0)) + 0.1 * np.arange(40) % 3
    return pd.DataFrame({"t": t, "u": u, "y": 0.5 * u + 1.0})


@pytest.mark.parametrize("make", [
    lambda df: gb.Record(df[["t", "u"]], df["y"]),
    lambda df: gb.Record(df.drop(columns="y"), df["y"].to_numpy()),
    lambda df: gb.Record(df[["t", "u"]], df["y"], input_names=("u", "v")),
    lambda df: gb.simulate(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, 1.0], df[["t", "u"]], y0=[0.0]),
])
def test_a_frames_time_column_is_refused_at_once_naming_it_and_its_step(make):
    """A float time column beside one input was read as a second input (u1 = t, u2 = u), and the record failed only
    at the fit, on the inputs' default names (mend60g): now refused where it is read, naming the column, its step
    as Ts= and the loader's time= option."""
    with pytest.raises(ValueError, match=r"column 't' .*looks like time.*Ts=0\.1\b.*time='t'"):
        make(_frame_with_time())


def test_a_ramp_named_as_an_input_is_an_input_and_static_levels_are_no_time():
    import pandas as pd
    df = _frame_with_time()
    rec = gb.Record(df[["t", "u"]], df["y"], input_names=("t", "u"))  # named so: the user's own ramp input
    np.testing.assert_array_equal(rec.input("t"), df["t"].to_numpy())
    points = gb.StaticPoints(pd.DataFrame({"a": [1.0, 2.0, 3.0], "b": [5.0, 1.0, 4.0]}), [1.0, 2.0, 3.0])
    assert points.input_names == ("a", "b")  # designed levels in even steps: points, not samples in time


def test_a_ramp_input_of_a_frame_by_position_is_told_a_way_to_be_read():
    # a model's free run over pd.DataFrame(np.column_stack([ramp, valve])) (columns 0, 1) was told "if it is an input
    # that ramps, name the columns as the inputs, input_names=['0', '1']": no identifiers, and Model.simulate takes no
    # input_names. The hint now names the columns as the inputs the call reads, which every entry takes
    import pandas as pd
    model = gb.Model(gb.Structure(["y(k-1)", "a(k-1)", "b(k-1)"]), [0.5, 1.0, 2.0], input_names=("a", "b"))
    u = np.column_stack([np.linspace(1.0, 2.0, 6), [0.5, 0.1, 0.7, 0.2, 0.9, 0.3]])
    frame = pd.DataFrame(u)
    with pytest.raises(ValueError, match=r"looks like time.*if it is an input that ramps, name the columns as the "
                                         r"inputs: df\.set_axis\(\['a', 'b'\], axis=1\)$"):
        model.simulate(frame, y0=[0.0])
    np.testing.assert_array_equal(model.simulate(frame.set_axis(["a", "b"], axis=1), y0=[0.0]),
                                  model.simulate(u, y0=[0.0]))


def test_a_saved_index_beside_an_input_is_refused_without_taking_its_step_for_seconds():
    import pandas as pd
    df = pd.DataFrame({"Unnamed: 0": np.arange(20), "u": np.sin(np.arange(20.0))})  # read_csv of a saved index
    with pytest.raises(ValueError, match=r"column 'Unnamed: 0' .*looks like time or a count of samples.*df\[\['u'\]\], "
                                         r"with the sampling period \(s\) as Ts="):
        gb.Record(df, np.cos(np.arange(20.0)))


# Unix time counted in ms (JavaScript's Date.now(), many IoT and logger exports), µs or ns, read as seconds, gave a
# sampling period 1000, 10^6 or 10^9 times too long without a word: 1764000000000, 1764000000010, … read Ts = 10 s
@pytest.mark.parametrize("unit, per_second", [("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9)])
def test_unix_time_counted_in_a_fraction_of_a_second_is_refused_not_read_as_seconds(tmp_path, unit, per_second):
    start = datetime(2025, 11, 24, 15, 0, tzinfo=timezone.utc).timestamp()
    f = _csv(tmp_path / "ms.csv", [f"{round((start + k * 0.01) * per_second)}" for k in range(20)])
    with pytest.raises(ValueError, match=rf"column 't'.*Unix time in {unit}.*2025-11-24 15:00:00 UTC.*"
                                         r"step of 0\.01 s.*Ts="):
        gb.load_record_csv(f, u="u", y="y", time="t")
    # Unix time in seconds (to the 10 ms here), and seconds since LabVIEW's 1904 or NTP's 1900, are seconds
    for offset in (0.0, 2082844800.0, 2208988800.0):
        f = _csv(tmp_path / "s.csv", [f"{start + offset + k * 0.01:.2f}" for k in range(20)])
        assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(0.01)


# A short record of seconds at 100 kHz, 27.8 h into a run (100000, 100000.00001, … : 0.864 s of a day, 14 % off 1 s),
# or at 10 Hz (100000.1 …: 8640 s of a day, 2.4 times 3600 s), was refused as a spreadsheet's serial dates: the window
# of what the stamps' decimals leave unknown of the mean step (last decimal / (N − 1)) passed 14 % below 8 samples
# and 140 % at 2. Stamps that increase strictly are taken for serial dates only within 10 % of a round period.
@pytest.mark.parametrize("rate, n", [(1e5, 5), (1e5, 3), (10.0, 2), (20.0, 3)])
def test_a_short_record_of_seconds_far_from_zero_is_not_taken_for_serial_dates(tmp_path, rate, n):
    f = _csv(tmp_path / "s.csv", [f"{100000 + k / rate:.5f}" for k in range(n)])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(1 / rate, rel=1e-9)


# MATLAB's datenum (days since year 0: 739960.5 is 2025-12-09 12:00), as writematrix([datenum(t), u, y]) writes it,
# read as seconds gave a period 86,400 times too short, as Excel's serial dates did before they were refused
@pytest.mark.parametrize("seconds", [1.0, 0.1, 60.0])
def test_matlab_datenums_are_refused_not_read_as_seconds(tmp_path, seconds):
    first = datetime(2025, 12, 9, 12).toordinal() + 366 + 0.5
    f = _csv(tmp_path / "dn.csv", [f"{first + k * seconds / 86400:.15g}" for k in range(20)])
    with pytest.raises(ValueError, match=rf"MATLAB's datenum.*2025-12-09 12:00:00.*a step of {seconds:g} s.*Ts="):
        gb.load_record_csv(f, u="u", y="y", time="t")
    # seconds there, 205 h into a run, at the usual rates are seconds
    f = _csv(tmp_path / "s.csv", [f"{740000 + k / 1000:.3f}" for k in range(20)])
    assert gb.load_record_csv(f, u="u", y="y", time="t").Ts == pytest.approx(1e-3)


# An elapsed time past a day, as a spreadsheet's [h]:mm:ss duration writes it (a test stand's 'Elapsed' column:
# 23:59:59, 24:00:00, 24:00:01 …, 100:00:00), was refused as 'not a clock time' at its first hour past 24, and a
# first stamp of 99:59:58 as "'99:59:58' is not a clock time, as the column's first stamp '99:59:58' (line 2) is";
# and the end of a 1000-hour endurance run, 999:59:58 then 1000:00:00, as "'1000:00:00' is not a clock time, as the
# column's first stamp '999:59:58' (line 2) is" (hours of four digits and more were not read)
@pytest.mark.parametrize("start_hour", [23, 99, 0, 999])
def test_elapsed_hours_past_a_day_are_read_as_a_duration(tmp_path, start_hour):
    stamps = [start_hour * 3600 + 3597 + 1.5 * k for k in range(8)]  # across the next whole hour, 1.5 s apart
    cells = [f"{int(s // 3600)}:{int(s // 60) % 60:02d}:{s % 60:04.1f}" for s in stamps]
    f = _csv(tmp_path / "e.csv", cells)
    r = gb.load_record_csv(f, u="u", y="y", time="t")
    assert r.Ts == 1.5 and r.y.size == 8
    f = _csv(tmp_path / "b.csv", ["09:61:00", "09:61:01"])  # a minute out of range, in the first stamp
    with pytest.raises(ValueError, match=r"line 2, column 't': '09:61:00' is not a clock time \(09:14:03\.5\): its "
                                         r"minute or second is out of range$"):
        gb.load_record_csv(f, u="u", y="y", time="t")
