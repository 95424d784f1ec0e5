"""hunt47c: loaders, Record construction, JSON files, CLI and docs as a newcomer meets them."""

from __future__ import annotations

import io
import json
import re
import sys

import numpy as np
import pytest

import graybox as gb


def _pareto_json(failures: dict) -> str:
    return json.dumps({"format": "graybox", "format_version": 1, "type": "ParetoSet",
                       "object": {"method": "pe", "structure": ["y(k-1)"], "lambdas": [], "thetas": [], "J1": [],
                                  "JS": [], "JSF": [], "extra": {}, "failures": failures}})


@pytest.mark.parametrize("key", ["--1", "\u00b2", "1\u00b2", "-"])
def test_failure_index_not_an_integer_is_a_file_error(key):
    # a hand-edited member index that str.isdigit takes (superscripts) or lstrip('-') hides ('--1') ended in
    # int()'s bare "invalid literal for int()", naming neither the file nor the field
    with pytest.raises(gb.GrayboxFileError, match=r"<json>: object\.failures\..*integer"):
        gb.from_json(_pareto_json({key: "x"}))


def _masked() -> np.ma.MaskedArray:
    # what netCDF4 hands back for a variable with fill values, and np.genfromtxt(usemask=True) for empty cells:
    # the masked entries' data are the fill value (9.97e36) or anything else, never a sample
    return np.ma.masked_array([1.0, 2.0, 9.969209968386869e36, 4.0, 5.0], mask=[0, 0, 1, 0, 0])


@pytest.mark.parametrize("where", ["u", "y"])
def test_record_refuses_masked_samples(where):
    good = np.arange(5.0)
    kw = {"u": good, "y": good} | {where: _masked()}
    with pytest.raises(ValueError, match=rf"record: {where} .*masked.*index 2"):
        gb.Record(kw["u"], kw["y"])


def test_static_points_refuse_masked_levels_and_a_mask_of_nothing_is_the_data():
    with pytest.raises(ValueError, match=r"ybar .*masked.*index 2"):
        gb.StaticPoints([1.0, 2.0, 3.0, 4.0, 5.0], _masked())
    unmasked = np.ma.masked_array([1.0, 2.0, 3.0], mask=False)
    rec = gb.Record(unmasked, unmasked)
    assert np.array_equal(rec.u, [1.0, 2.0, 3.0]) and np.array_equal(rec.y, [1.0, 2.0, 3.0])


def test_static_curve_levels_masked_are_a_value_error():
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    with pytest.raises(ValueError, match=r"ubar .*masked"):
        model.static_curve(_masked())


@pytest.mark.parametrize("description", [None, 3, b"bytes"])
def test_dataset_description_must_be_text(description):
    # accepted as it was, it made a Dataset whose file save wrote (null, 3) and load then refused
    # ("object.description: expected a string"), or that to_json could not write at all (bytes)
    rec = gb.Record(np.arange(10.0), np.arange(10.0), Ts=0.1)
    with pytest.raises(TypeError, match="Dataset: description must be a str"):
        gb.Dataset(rec, rec, description=description)


def test_a_saved_dataset_loads():
    rec = gb.Record(np.arange(10.0), np.arange(10.0), Ts=0.1)
    data = gb.Dataset(rec, rec, description="bench run 3")
    assert gb.from_json(gb.to_json(data)).description == "bench run 3"


@pytest.mark.parametrize("loader", ["load_record_csv", "load_static_csv"])
@pytest.mark.parametrize("columns", [{"a", "b"}, frozenset({"a", "b"})])
def test_csv_loaders_refuse_a_set_of_input_columns(tmp_path, loader, columns):
    # a set's order changes with PYTHONHASHSEED: the same call read the inputs as (a, b) in one process and
    # (b, a) in the next, so that a model identified in one ran on swapped inputs in the other
    path = tmp_path / "miso.csv"
    path.write_text("t,a,b,y\n0,1,2,3\n1,2,3,4\n", encoding="utf-8")
    kw = {"time": "t"} if loader == "load_record_csv" else {}
    with pytest.raises(TypeError, match=r"u: an ordered sequence of .*got a (frozen)?set.*pass a list"):
        getattr(gb, loader)(path, u=columns, y="y", **kw)


def _narrow_stdout(monkeypatch, encoding: str) -> io.TextIOWrapper:
    # what Windows gives a redirected command (graybox reproduce --quick > table.txt): the locale's code page
    stream = io.TextIOWrapper(io.BytesIO(), encoding=encoding, newline="")
    monkeypatch.setattr(sys, "stdout", stream)
    return stream


def test_reproduce_to_a_narrow_code_page_does_not_crash(monkeypatch, tmp_path):
    # the first section prints ȳ, ρ, ū and λ1, which cp1252 lacks: the command died with a UnicodeEncodeError
    # traceback on its first section (the README's first command, its output redirected on Windows)
    import graybox.reproduce as rp
    from graybox._cli import main

    monkeypatch.setattr(rp, "run", lambda **kw: print("ȳ = 51.2 (stable, ρ = 0.62) at ū = 1000, λ1 = 0.1"))
    stream = _narrow_stdout(monkeypatch, "cp1252")
    assert main(["reproduce", "--quick", "--out", str(tmp_path)]) == 0
    stream.flush()
    text = stream.buffer.getvalue().decode("cp1252")
    assert "51.2" in text and "\\u0233" in text and "\\u03c1" in text


def test_help_to_an_ascii_stream_does_not_crash(monkeypatch):
    from graybox._cli import main

    stream = _narrow_stdout(monkeypatch, "ascii")
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    stream.flush()
    assert "usage: graybox" in stream.buffer.getvalue().decode("ascii")


def test_closed_loop_without_a_seed_names_closed_loop():
    # the message said "simulate: pass seed ...", a method the caller had not called
    from graybox.datasets import PumpingPlant

    with pytest.raises(ValueError, match=r"^closed_loop: pass seed"):
        PumpingPlant().closed_loop(lambda k, y: 1000.0, 10, u0=1000.0)


@pytest.mark.parametrize("page", ["docs/guide/control.md", "README.md"])
def test_documented_closed_loop_call_names_what_it_needs(page):
    # the guide's closed_loop(controller, n_samples) failed as written: u0 is required, and a seed with the noise on
    import inspect
    from pathlib import Path

    from graybox.datasets import PumpingPlant

    text = (Path(__file__).resolve().parent.parent / page).read_text(encoding="utf-8")
    calls = re.findall(r"closed_loop\(([^)`]*)\)", text)
    assert calls
    required = [n for n, p in inspect.signature(PumpingPlant.closed_loop).parameters.items()
                if p.kind is p.KEYWORD_ONLY and p.default is p.empty]
    for args in calls:
        for name in [*required, "seed"]:
            assert f"{name}=" in args, (page, args, name)


def _nested_datasets(depth: int) -> str:
    rec = json.dumps(json.loads(gb.to_json(gb.Record(np.arange(5.0), np.arange(5.0), Ts=0.1)))["object"])
    head = f'"ident": {rec}, "valid": {rec}, "static": null, "description": ""'
    extra = '{"k": 1}'
    for _ in range(depth):  # written as text: json.dumps itself recurses
        extra = f'{{"k": {{"type": {{"type": "Dataset", "object": {{{head}, "extra": {extra}}}}}}}}}'
    return f'{{"format": "graybox", "format_version": 1, "type": "Dataset", "object": {{{head}, "extra": {extra}}}}}'



def test_a_file_nesting_datasets_deeply_is_a_file_error():
    # a Dataset's extra holding a Dataset holding ... (crafted or corrupt): each saved type began the nesting count
    # anew, so that a file json.loads read ended in a bare RecursionError instead of the loader's GrayboxFileError
    assert gb.from_json(_nested_datasets(5)).extra["k"].extra["k"].description == ""
    with pytest.raises(gb.GrayboxFileError, match="nested|recursion"):
        gb.from_json(_nested_datasets(220))  # within what json.loads reads


def test_masked_uncertainty_is_a_value_error_naming_the_mask():
    # said "uncertainty must be a number or an array of numbers, got MaskedArray", a TypeError, for numbers
    with pytest.raises(ValueError, match=r"uncertainty has 1 masked .*index 1"):
        gb.StaticPoints([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], uncertainty=np.ma.masked_array([0.1, 0.2, 0.3], [0, 1, 0]))


@pytest.mark.parametrize("where", [gb.Record, gb.StaticPoints, gb.load_record_csv, gb.load_static_csv])
def test_units_are_not_documented_as_display_only(where):
    # "Units of (u, y), for display only", while a model refuses a record in other units and a Dataset data that
    # mix them: a newcomer labelling rad/s data "rpm" to match a plot was told the label changed nothing
    section = re.search(r"\n    units : [^\n]*\n((?:        [^\n]*\n)+)", where.__doc__).group(1)
    assert "display only" not in section and "for display" not in section and "checked" in section, section


def test_units_are_checked_as_documented():
    data = gb.load_pumping()
    model = gb.els(gb.Structure(["y(k-1)", "u(k-1)", "1"]), data).model
    other = gb.Record(data.valid.u * 2 * np.pi / 60, data.valid.y, Ts=data.valid.Ts, units=("rad/s", "mlc"))
    with pytest.raises(ValueError, match="input unit 'rpm' but 'record' has 'rad/s'"):
        gb.js(model, other)


_LOGGED = "t,u,y\n" + "".join(f"{k * 0.5:.1f},{k % 7},{k % 5}\n" for k in range(40))


@pytest.mark.parametrize("data, line", [
    # (zeros after whole lines, a logger's preallocated file, read its lines since review47h: cut inside a line here)
    (_LOGGED.encode()[:-3] + bytes(512), 41),  # one cut off as it was written
    (_LOGGED.encode().replace(b"\n3.0,6,1\n", b"\n3.0,\x006,1\n"), 8),  # a stray NUL in a cell
    ((_LOGGED * 3).encode()[:-3] + bytes(5000), 123),  # past the first 4096 bytes
])
def test_stray_nul_bytes_are_named_by_line_not_taken_for_utf16(tmp_path, data, line):
    # was "the file holds NUL bytes, so it is not UTF-8 text: UTF-16 without a byte-order mark? Pass
    # encoding='utf-16-le'", which reads this UTF-8 text as garbage, or (past 4096 bytes) "line 42 has 1 field(s)"
    p = tmp_path / "logger.csv"
    p.write_bytes(data)
    with pytest.raises(ValueError, match=rf"logger.csv: line {line} holds NUL bytes") as exc:
        gb.load_record_csv(p, u="u", y="y", time="t")
    assert "utf-16" not in str(exc.value).lower()


@pytest.mark.parametrize("codec", ["utf-16-le", "utf-16-be"])
def test_utf16_without_a_mark_is_told_its_byte_order(tmp_path, codec):
    p = tmp_path / "bomless.csv"
    p.write_bytes(_LOGGED.encode(codec))
    with pytest.raises(ValueError, match=rf"the file holds NUL bytes.*encoding='{codec}'"):
        gb.load_record_csv(p, u="u", y="y", time="t")
    assert len(gb.load_record_csv(p, u="u", y="y", time="t", encoding=codec)) == 40


def test_saving_the_bundled_dataset_says_how_to_save_it_without_its_simulator(tmp_path):
    # said only "cannot save Dataset.extra['plant']: a PumpingPlant, which graybox does not save": the first thing
    # a newcomer saves, with no word of how to keep the records and points
    data = gb.load_pumping()
    with pytest.raises(ValueError, match=r"Dataset.extra\['plant'\].*dataclasses.replace\(data, extra=") as exc:
        gb.save(data, tmp_path / "pumping.json")
    import dataclasses

    fix = re.search(r"(dataclasses\.replace\(data, extra=.*\))", str(exc.value)).group(1)
    kept = eval(fix, {"dataclasses": dataclasses, "data": data})  # the fix as the message writes it
    loaded = gb.load(gb.save(kept, tmp_path / "pumping.json"))
    assert np.array_equal(loaded.ident.y, data.ident.y) and "plant" not in loaded.extra


@pytest.mark.parametrize("make", [
    lambda u, y: gb.Record(u, y),
    lambda u, y: gb.StaticPoints(u, y),
    lambda u, y: gb.StaticPoints.from_repeats(u, y),
])
def test_inputs_stacked_as_rows_are_told_to_be_columns(make):
    # np.array([u1, u2]) stacks the inputs as rows: "u and y must have the same length, got 2 and 50" named a
    # length, not the orientation, nor the transpose that fixes it
    u1, u2, y = np.arange(50.0), np.arange(50.0) ** 2, np.arange(50.0)
    with pytest.raises(ValueError, match=r"shape \(2, 50\), one row per input: .*shape \(50, 2\).*\.T"):
        make(np.array([u1, u2]), y)
    assert make(np.array([u1, u2]).T, y).n_inputs == 2


@pytest.mark.parametrize("text, said", [
    ("t,u,y\n0,1,2\n1,2,3\n", r"not a graybox file: no JSON text \(it starts 't,u,y.*load_record_csv"),
    ("", "the file is empty"),
    ("  \n", "the file is empty"),
    ('{"format": "graybox",, }', r"corrupt file \(Expecting property name"),
])
def test_load_of_what_is_no_json_says_what_it_is(tmp_path, text, said):
    # gb.load("run1.csv") (load reads "my data", a newcomer guesses) and an empty file were both a "corrupt file
    # (Expecting value at line 1, column 1)": a CSV is no corrupt JSON, and the reader it needs went unnamed
    p = tmp_path / "run1.csv"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match=said):
        gb.load(p)


@pytest.mark.parametrize("loader", ["load_record_csv", "load_static_csv"])
def test_a_csv_loader_given_a_saved_graybox_file_names_gb_load(tmp_path, loader):
    # was "no column 'u' ... The header was read as one column, split at ',': pass delimiter= ... ['{']"
    rec = gb.Record(np.arange(5.0), np.arange(5.0), Ts=0.1)
    path = gb.save(rec, tmp_path / "run1.json")
    with pytest.raises(ValueError, match=r"run1.json: the file is a graybox JSON file \(a Record.*graybox.load"):
        getattr(gb, loader)(path, u="u", y="y", **({"Ts": 0.1} if loader == "load_record_csv" else {}))


def test_a_header_np_savetxt_wrote_names_its_comment_mark(tmp_path):
    # np.savetxt(..., header="t,u,y") writes "# t,u,y": was "no column 't' ... Did you mean '# t'?", not the cause
    path = tmp_path / "run1.csv"
    t = np.arange(5) * 0.1
    np.savetxt(path, np.c_[t, np.sin(t), np.cos(t)], delimiter=",", header="t,u,y")
    with pytest.raises(ValueError, match=r"starts with '#'.*np.savetxt.*comments=''"):
        gb.load_record_csv(path, u="u", y="y", time="t")
    np.savetxt(path, np.c_[t, np.sin(t), np.cos(t)], delimiter=",", header="t,u,y", comments="")
    assert gb.load_record_csv(path, u="u", y="y", time="t").Ts == 0.1


@pytest.mark.parametrize("make", [lambda u, y: gb.Record(u, y), lambda u, y: gb.StaticPoints(u, y)])
def test_an_output_given_as_a_one_column_frame_is_told_to_be_its_column(make):
    # df[["p"]] (two pairs of brackets) was told "pass a flat array (e.g. x.ravel())": a DataFrame has no ravel
    import pandas as pd

    df = pd.DataFrame({"u": np.arange(5.0), "p": np.arange(5.0) ** 2})
    with pytest.raises(ValueError, match=r"DataFrame of one column.*df\['p'\] \(one pair of brackets\)"):
        make(df["u"], df[["p"]])
    assert len(make(df["u"], df["p"])) == 5


@pytest.mark.parametrize("as_", [lambda t: t, lambda t: t.to_numpy(), lambda t: list(t)])
def test_a_time_column_given_as_ts_is_told_to_give_its_step(as_):
    # was "Ts (seconds) must be a real number, got 0    0.0\n1    0.1\n..." (the whole column), no word of the fix
    import pandas as pd

    df = pd.DataFrame({"t": np.arange(5.0) * 0.1, "u": np.arange(5.0), "y": np.arange(5.0) ** 2})
    with pytest.raises(TypeError, match=r"Ts is the sampling period, one number of seconds, got 5 values.*np\.diff"):
        gb.Record(df["u"], df["y"], Ts=as_(df["t"]))
    assert gb.Record(df["u"], df["y"], Ts=np.array(0.1)).Ts == 0.1  # a 0-d array is one number


@pytest.mark.parametrize("call", [
    lambda: gb.load_record_csv("", u="u", y="y", Ts=1.0),
    lambda: gb.load_static_csv("", u="u", y="y"),
    lambda: gb.load(""),
    lambda: gb.read_header(""),
    lambda: gb.save(gb.Structure(["y(k-1)"]), ""),
])
def test_an_empty_file_name_is_said_so(call):
    # Path("") is the current folder: "[Errno 21] Is a directory: '.'", a folder the caller never named
    with pytest.raises(ValueError, match="path is empty"):
        call()


def test_save_does_not_replace_a_read_only_file(tmp_path, monkeypatch):
    # open(path, "w") refuses a file made read-only (chmod a-w); save moved its own file over it all the same, so a
    # model kept read-only on purpose was silently replaced. Root may write anything: the test asks os.access as a
    # user without write permission would be answered.
    import os
    import stat

    path = gb.save(gb.Structure(["y(k-1)"]), tmp_path / "final.json")
    path.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, *a, **k: False if (os.fspath(p) == os.fspath(path)
                                                                         and mode & os.W_OK) else real(p, mode, *a, **k))
    with pytest.raises(PermissionError, match="read-only"):
        gb.save(gb.Structure(["y(k-2)"]), path)
    assert str(gb.load(path)) == str(gb.Structure(["y(k-1)"]))


def test_load_expecting_a_record_of_a_dataset_file_says_take_ident_or_valid(tmp_path):
    # a Decision's file said how to take its .model; a Dataset's said only "holds a Dataset, expected Record"
    rec = gb.Record(np.arange(5.0), np.arange(5.0), Ts=0.1)
    path = gb.save(gb.Dataset(rec, rec), tmp_path / "data.json")
    with pytest.raises(gb.GrayboxFileError, match=r"holds a Dataset, expected Record \(a Dataset carries a Record: "
                                                  r"load it without expect= and take its \.ident or \.valid\)"):
        gb.load(path, expect=gb.Record)
    # (a Dataset with static points: one without has .static None, and is not said to carry them, review47h)
    path = gb.save(gb.Dataset(rec, rec, gb.StaticPoints([1.0, 2.0], [1.0, 2.0])), tmp_path / "data_static.json")
    with pytest.raises(gb.GrayboxFileError, match=r"take its \.static\)"):
        gb.load(path, expect=gb.StaticPoints)


def test_a_dynamic_record_given_to_load_static_csv_is_said_so():
    # the bundled dynamic file read as static points was told to average its repeated levels (repeats="mean"),
    # which makes "static points" of whole holds, transients included
    from graybox.datasets import pumping_data_dir

    with pytest.raises(ValueError, match=r"lines have the input level .*looks like a dynamic record.*load_record_csv"):
        gb.load_static_csv(pumping_data_dir() / "dynamic.csv", u="speed_ref_rpm", y="pressure_mlc")


def test_a_few_repeated_static_measurements_still_point_to_repeats_mean(tmp_path):
    p = tmp_path / "steady.csv"
    p.write_text("u,y\n1000,5.1\n1000,5.3\n1100,6.0\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"lines 2 and 3 have the same input level 1000.*repeats=\"mean\""):
        gb.load_static_csv(p, u="u", y="y")
