"""Bugs found by a bug hunt in saving and loading (graybox.io), the CSV loaders and bundled data sets,
transient inputs and the command line, used as a control engineer would on a plant of their own (Pa
near 2e5, rpm near 3000, volts near 1e-3, inputs not named "u", two inputs, hand-edited files): each
test fails without its fix."""

import json

import numpy as np
import pandas as pd
import pytest

import graybox as gb

#: p(k) = 0.5 p(k-1) + 20 n(k-1) + 1e7 v(k-2) + 1e5: a pressure in Pa against a speed in rpm and a voltage.
TWO = gb.Model(["y(k-1)", "speed(k-1)", "volts(k-2)", "1"], [0.5, 20.0, 1e7, 1e5], input_names=("speed", "volts"),
               Ts=0.1)


@pytest.mark.parametrize("units", ["Pa", "ab", b"ab"])
def test_units_given_as_one_text_are_refused_not_split_into_letters(units):
    # to_json / save unpacked units="Pa" (one unit, not a pair) into u = "P" and y = "a" and wrote them in the
    # header without a word (a three-letter unit was refused); bytes were a ValueError, not a TypeError
    with pytest.raises(TypeError, match="units must be a pair of strings"):
        gb.to_json(TWO, units=units)


def test_units_as_a_mapping_name_only_u_and_y():
    # a mapping's other keys were dropped: {"input": "rpm", "output": "Pa"} wrote empty units
    with pytest.raises(ValueError, match=r"units.*'input'.*'u' and 'y'"):
        gb.to_json(TWO, units={"input": "rpm", "output": "Pa"})
    assert json.loads(gb.to_json(TWO, units={"y": "Pa"}))["units"] == {"u": "", "y": "Pa"}
    with pytest.raises(TypeError, match="units must be a pair of strings"):
        gb.to_json(TWO, units=("rpm", 3))


def _record(seed=0, N=300, name="ident"):
    rng = np.random.default_rng(seed)
    u = np.column_stack([np.repeat(rng.uniform(2500, 3500, N // 20 + 1), 20)[:N],
                         np.repeat(rng.uniform(1e-3, 5e-3, N // 15 + 1), 15)[:N]])
    y = TWO.simulate(u, np.full(2, 2e5)) + 50 * rng.standard_normal(N)
    return gb.Record(u, y, Ts=0.1, name=name, units=("rpm", "Pa"), input_names=("speed", "volts"))


@pytest.fixture(scope="module")
def oe():
    return gb.output_error(TWO.structure, _record(), n_starts=1, max_nfev=5, seed=1)


def test_an_output_error_result_without_its_starts_columns_is_refused(oe):
    # OEResult took any table as its starts: a hand-edited file whose starts lacked a column (or one built with an
    # empty table) loaded, and its repr and failures then failed with pandas' KeyError 'status'
    doc = json.loads(gb.to_json(oe))
    doc["object"]["starts"]["columns"][2] = "state"
    with pytest.raises(gb.GrayboxFileError, match=r"starts lacks the column\(s\) \['status'\]"):
        gb.from_json(json.dumps(doc))
    fields = {k: getattr(oe, k) for k in ("model", "JS", "JS_choose", "chosen_on", "start", "margin", "radius", "seed")}
    with pytest.raises(ValueError, match="starts lacks the column"):
        gb.OEResult(starts=pd.DataFrame(), **fields)
    assert gb.OEResult(starts=oe.starts, **fields).failures == oe.failures


@pytest.mark.parametrize("field, value, why", [
    ("input_names", ["speed"], "ubar has 2 values for 1 input"),     # was: gains of a b reshaped to one row
    ("ubar", [3000.0], "ubar has 1 values for 2 input"),
    ("b", [[1.0, 2.0, 3.0, 4.0]], r"b must have shape \(2, L_u\)"),  # was: one row read as two
    ("Ts", -0.1, "Ts"),                                               # was: τ = -0.14 s
    ("status", "weird", "status must be one of"),
    ("a", ["nan"], "a has non-finite values"),                        # was: LinAlgError from repr
    ("ybar", "nan", "ybar must be finite"),
])
def test_a_local_model_that_disagrees_with_itself_is_refused(field, value, why):
    # LocalModel checked its fields' types only: a hand-edited file whose input names, ū and b disagree loaded and
    # gave a gain per misread row of b, a negative Ts a negative time constant, NaN in a numpy's LinAlgError from
    # repr, an unknown status passed as one
    local = gb.local_model(TWO, [3000.0, 3e-3])
    doc = json.loads(gb.to_json(local))
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=f"not a valid LocalModel: .*{why}"):
        gb.from_json(json.dumps(doc))
    back = gb.from_json(gb.to_json(local))
    np.testing.assert_array_equal(back.dc_gain, local.dc_gain)


@pytest.mark.parametrize("field, value, why", [
    ("ybar", [1.0], r"ybar must have shape \(2,\)"),                  # was: to_frame failed in pandas
    ("gain", [1.0, 2.0], r"gain must have shape \(2, 2\)"),
    ("status", ["reached"], "status has 1 entries for 2 operating points"),  # was: "1 reached" of 2
    ("local_models", [], "0 local models for 2 operating points"),    # was: "0 points", IndexError in to_frame
    ("ubar", [[3000.0, 3e-3], [3100.0, 1.0]], "ubar disagrees with the local models"),
])
def test_an_operating_curve_that_disagrees_with_itself_is_refused(field, value, why):
    # OperatingCurve checked its fields' types only: a hand-edited file with arrays of other lengths than its points
    # loaded, printed wrong counts, and its to_frame failed inside pandas
    curve = gb.operating_curve(TWO, [[3000.0, 3e-3], [3100.0, 2e-3]])
    doc = json.loads(gb.to_json(curve))
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=f"not a valid OperatingCurve: .*{why}"):
        gb.from_json(json.dumps(doc))
    pd.testing.assert_frame_equal(gb.from_json(gb.to_json(curve)).to_frame(), curve.to_frame())


@pytest.mark.parametrize("field, value, why", [("level", 2.0, "level"), ("level", 0.0, "level"), ("dof", 0, "dof"),
                                               ("dof", -3, "dof")])
def test_a_parameter_uncertainty_at_an_impossible_level_or_dof_is_refused(field, value, why):
    # ParameterUncertainty checked cov's shape but not its level and degrees of freedom: a hand-edited file with
    # level 2 or dof -3 loaded and gave NaN intervals (Student's t quantile outside its range) without a word
    unc = gb.ls_uncertainty(gb.els(TWO.structure, _record(), noise=0).model, _record())
    doc = json.loads(gb.to_json(unc))
    doc["object"][field] = value
    with pytest.raises(gb.GrayboxFileError, match=f"not a valid ParameterUncertainty: {why}"):
        gb.from_json(json.dumps(doc))
    assert np.isfinite(gb.from_json(gb.to_json(unc)).intervals).all()


def test_reproduce_help_names_the_checkpoint_files_the_run_writes(capsys, tmp_path):
    # `graybox reproduce --help` told to delete "se_ga_l2.npz, se_gradient_l3_quick.npz", names no run writes
    # (they carry the stability margin and the GA's starts: se_ga_l2_margin0.01_pe.npz …)
    import re

    from graybox._cli import main
    from graybox.reproduce._table1 import checkpoint_paths

    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    named = set(re.findall(r"se_[\w.]+?\.npz", capsys.readouterr().out.replace("\n", " ")))
    written = {p.name for quick in (True, False) for p in checkpoint_paths(tmp_path, quick)}
    assert named and named <= written


def _csv_files(folder, speed="speed [rpm]", volts="volts [V]"):
    ident, valid = _record(0), _record(1, name="valid")
    for name, r in (("ident", ident), ("valid", valid)):
        rows = [f"{k * r.Ts:.1f},{float(r.u[k, 0])!r},{float(r.u[k, 1])!r},{float(r.y[k])!r}" for k in range(len(r))]
        (folder / f"{name}.csv").write_text("\n".join([f"t,{speed},{volts},p [Pa]", *rows]) + "\n", encoding="utf-8")
    ub = [[2600.0, 2e-3], [3000.0, 3e-3], [3400.0, 4e-3]]
    rows = [f"{a!r},{b!r},{float(TWO.static_curve([[a, b]])[0])!r}" for a, b in ub]
    (folder / "static.csv").write_text("\n".join([f"{speed},{volts},p [Pa]", *rows]) + "\n", encoding="utf-8")
    return ident, valid


def test_a_grid_reads_csv_inputs_whose_column_names_carry_units(tmp_path):
    # columns named with their units ("speed [rpm]", "volts [V]") are no input names: the loader asks for
    # input_names=[...], which a grid spec's files did not take ("unknown key 'input_names'"), so such files could not
    # be used by `graybox grid run` at all
    from graybox.experiments import Grid

    ident, _ = _csv_files(tmp_path)
    files = {k: f'{{path = "{k}.csv", u = ["speed [rpm]", "volts [V]"], y = "p [Pa]"' for k in ("ident", "valid", "static")}
    names = ', input_names = ["speed", "volts"]'
    spec = (f'name = "own"\n[[data]]\nname = "rig"\nident = {files["ident"]}, time = "t"{names}}}\n'
            f'valid = {files["valid"]}, time = "t"{names}}}\nstatic = {files["static"]}, uncertainty = 50.0{names}}}\n'
            '[[structures]]\nname = "given"\nterms = ["y(k-1)", "speed(k-1)", "volts(k-2)", "1"]\n'
            '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    (tmp_path / "spec.toml").write_text(spec, encoding="utf-8")
    grid = Grid.from_toml(tmp_path / "spec.toml")
    data = grid.data[0].load(tmp_path)
    assert data.input_names == ("speed", "volts") and data.static.input_names == ("speed", "volts")
    np.testing.assert_array_equal(data.ident.u, ident.u)
    assert grid.data[0].to_dict()["ident"]["input_names"] == ["speed", "volts"]
    # a spec without them has the canonical form (and so the cells' keys) it had
    plain = Grid.from_toml_text(spec.replace(names, "").replace('"speed [rpm]", "volts [V]"', '"speed", "volts"'))
    assert "input_names" not in plain.data[0].to_dict()["ident"]
    bad = spec.replace('input_names = ["speed", "volts"]}\nstatic', 'input_names = ["speed"]}\nstatic')
    (tmp_path / "bad.toml").write_text(bad, encoding="utf-8")
    with pytest.raises(gb.experiments.SpecError, match=r"input_names must be a list of 2 name"):
        Grid.from_toml(tmp_path / "bad.toml")
    with pytest.raises(gb.experiments.SpecError, match=r"input_names must be a list of names"):
        Grid.from_toml_text(spec.replace('input_names = ["speed", "volts"]}\nstatic', 'input_names = "speed"}\nstatic'))


def test_a_grid_reads_csv_files_as_a_logger_wrote_them(tmp_path):
    # the loaders' messages ask for skiprows= (a logger's header block), delimiter=, decimal=, encoding= or time_rtol=,
    # but a grid spec's files refused each as an "unknown key": such files could not be used by a grid at all
    from graybox.experiments import Grid

    _csv_files(tmp_path)
    for name in ("ident", "valid"):  # a header block, ';' and a decimal comma, Windows' encoding, stamps of 3 Hz
        lines = (tmp_path / f"{name}.csv").read_text(encoding="utf-8").splitlines()
        body = [";".join([f"{k / 3:.2f}", *row.split(",")[1:]]).replace(".", ",") for k, row in enumerate(lines[1:])]
        text = "\n".join(["Logger 7 (Kessel Süd)", "channels: 3", "", lines[0].replace(",", ";"), *body]) + "\n"
        (tmp_path / f"{name}.csv").write_bytes(text.encode("cp1252"))
    read = 'skiprows = 3, encoding = "cp1252", delimiter = ";", decimal = ",", time_rtol = 0.05'
    spec = ('name = "own"\n[[data]]\nname = "rig"\n'
            + "".join(f'{k} = {{path = "{k}.csv", u = ["speed [rpm]", "volts [V]"], y = "p [Pa]", time = "t", '
                      f'input_names = ["speed", "volts"], {read}}}\n' for k in ("ident", "valid"))
            + 'static = {path = "static.csv", u = ["speed [rpm]", "volts [V]"], y = "p [Pa]", skiprows = 0, '
              'input_names = ["speed", "volts"]}\nband = 100.0\n'
            '[[structures]]\nname = "given"\nterms = ["y(k-1)", "speed(k-1)", "volts(k-2)", "1"]\n'
            '[[variants]]\nname = "LS"\nestimator = "ls"\n')
    data = Grid.from_toml_text(spec, base_dir=str(tmp_path)).data[0].load(tmp_path)
    direct = gb.load_record_csv(tmp_path / "ident.csv", ["speed [rpm]", "volts [V]"], "p [Pa]", time="t",
                                input_names=["speed", "volts"], skiprows=3, encoding="cp1252", time_rtol=0.05)
    np.testing.assert_array_equal(data.ident.u, direct.u)
    assert data.ident.Ts == direct.Ts == pytest.approx(1 / 3, rel=1e-2) and len(data.valid) == len(direct)
    with pytest.raises(gb.experiments.SpecError, match="skiprows"):
        Grid.from_toml_text(spec.replace("skiprows = 3", "skiprows = -1"))


@pytest.mark.parametrize("t0", [0.0, 1.7e9])  # from zero, and Unix time (seconds since 1970) as many loggers write
def test_time_stamps_far_from_zero_give_the_period_they_print(tmp_path, t0):
    # stamps of Unix time at 10 kHz (1700000000.000100, …, printed evenly to the microsecond) were refused as
    # "uneven time stamps …, resample the data": float64 holds 1.7e9 to 2.4e-7 s, so each step read 1e-4 s ± 2.4e-3
    # relative, past the tolerance; at 1 kHz they loaded with Ts = 0.000999999 s where the stamps say 0.001 s
    for Ts, n in ((1e-4, 400), (1e-3, 250)):
        rows = "".join(f"{t0 + k * Ts:.6f},{3000 + k % 7},{2e5 + k}\n" for k in range(n))
        (tmp_path / "r.csv").write_text("t,speed,p\n" + rows, encoding="utf-8")
        assert gb.load_record_csv(tmp_path / "r.csv", "speed", "p", time="t").Ts == Ts
    # a missing sample is still one
    gap = "".join(f"{t0 + k * 1e-4:.6f},3000,2e5\n" for k in range(400) if k != 200)
    (tmp_path / "gap.csv").write_text("t,speed,p\n" + gap, encoding="utf-8")
    with pytest.raises(ValueError, match="uneven time stamps"):
        gb.load_record_csv(tmp_path / "gap.csv", "speed", "p", time="t")


@pytest.mark.parametrize("call", [lambda: gb.save(TWO, 3), lambda: gb.load(3), lambda: gb.read_header(None)])
def test_save_and_load_name_a_path_of_the_wrong_type(call):
    # pathlib's "expected str, bytes or os.PathLike object, not int" named neither the argument nor the function
    with pytest.raises(TypeError, match="path must be a file or folder name"):
        call()


def test_save_names_the_path_given_not_its_temporary_file(tmp_path):
    # the atomic write goes through a temporary file beside the path: a missing folder was "No such file or
    # directory: '…/x.json.63964935.tmp'", and a folder given as the path "Is a directory: '….8f15f5c5.tmp' -> '…'",
    # names the user never gave
    with pytest.raises(FileNotFoundError) as missing:
        gb.save(TWO, tmp_path / "no" / "x.json")
    with pytest.raises(IsADirectoryError) as folder:
        gb.save(TWO, tmp_path)
    for exc, path in ((missing, tmp_path / "no" / "x.json"), (folder, tmp_path)):
        assert ".tmp" not in str(exc.value) and str(path) in str(exc.value)
    assert list(tmp_path.parent.glob("*.tmp")) == []


def test_reproduce_prints_to_the_standard_output_of_the_moment_it_runs(monkeypatch):
    # run(stream=sys.stdout) bound the stream when graybox.reproduce was first imported: under redirect_stdout (a
    # notebook's capture, a log file) the text went to the old stream, or failed on it once closed ("I/O operation on
    # closed file", as when a test that imported the module under pytest's capture was followed by another)
    import contextlib
    import io

    import graybox.reproduce as rp

    monkeypatch.setattr(rp, "SECTIONS", (lambda quick, out: "section text",))
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rp.run(quick=True, out=None)
    assert "section text" in buf.getvalue()


@pytest.mark.parametrize("kw", [{"delimiter": 3}, {"delimiter": b","}, {"decimal": 3}, {"decimal": b"."}])
def test_a_delimiter_or_decimal_mark_of_the_wrong_type_is_a_type_error(tmp_path, kw):
    # delimiter=3 or decimal=b"." raised ValueError; a wrong type is a TypeError everywhere else (encoding= included)
    (tmp_path / "r.csv").write_text("t,speed,p\n0,3000,2e5\n0.1,3100,2.1e5\n", encoding="utf-8")
    with pytest.raises(TypeError, match=f"{next(iter(kw))} must be"):
        gb.load_record_csv(tmp_path / "r.csv", "speed", "p", time="t", **kw)
    with pytest.raises(TypeError, match=f"{next(iter(kw))} must be"):
        gb.load_static_csv(tmp_path / "r.csv", "speed", "p", **kw)


def _pressure(n, *, points=(3.04e5, 3.36e5)):
    """p(k) = 0.5 p(k-1) + 20 n(k-1) + 1e5 Pa (+ 10 Pa noise) against a speed n in rpm: ident and valid of n/2
    samples each, and two static points at 2600 and 3400 rpm (the plant's own: 3.04e5 and 3.36e5 Pa)."""
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(2500, 3500, n // 10), 10)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 20 * u[k - 1] + 1e5 + 10 * rng.standard_normal()
    rec = gb.Record(u, y, Ts=0.1, units=("rpm", "Pa"))
    return gb.Dataset(rec.slice(0, n // 2, name="ident"), rec.slice(n // 2, None, name="valid"),
                      gb.StaticPoints([2600.0, 3400.0], list(points)))


@pytest.fixture(scope="module")
def chosen():
    """A select_graybox result on :func:`_pressure`'s data (least squares, two sizes)."""
    return gb.select_graybox(gb.Candidates(1, 1, degree=1), _pressure(400), sizes=[2, 3], estimator="ls",
                             progress=False)


@pytest.mark.parametrize("ranks, count", [([2, 2, 3], 0), ([1, 1, 3], 2)])
def test_a_graybox_selection_table_without_one_choice_is_refused(chosen, ranks, count):
    # the table's rank 1 row is the choice (chosen, repr): a hand-edited file whose table had no row ranked 1 loaded,
    # and its repr failed with pandas' "IndexError: single positional indexer is out-of-bounds"; with two, chosen
    # gave the first without a word
    doc = json.loads(gb.to_json(chosen))
    table = doc["object"]["table"]
    table["data"][table["columns"].index("rank")] = ranks[:len(table["index"])] + list(range(4, len(table["index"]) + 1))
    with pytest.raises(gb.GrayboxFileError, match=f"{count} rows ranked 1"):
        gb.from_json(json.dumps(doc))


def test_save_through_a_symbolic_link_writes_the_file_it_points_to(tmp_path):
    # the atomic write replaced the path itself: saving to latest.json -> runs/a.json replaced the link with a new
    # file and left runs/a.json, which the link (and everything else reading it) named, as it was
    (tmp_path / "runs").mkdir()
    target = tmp_path / "runs" / "a.json"
    gb.save(gb.Model(["y(k-1)"], [0.5]), target)
    link = tmp_path / "latest.json"
    link.symlink_to(target)
    gb.save(TWO, link)
    assert link.is_symlink() and gb.load(target).theta.tolist() == TWO.theta.tolist()
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a.json", "latest.json", "runs"]  # no temporary left


@pytest.mark.parametrize("module", ["graybox.datasets.pumping", "graybox.datasets._pumping_miso"])
def test_regenerating_the_bundled_data_refuses_bad_arguments_in_one_line(module, tmp_path, capsys):
    # python -m graybox.datasets.pumping --seed -1 ended in numpy's "ValueError: expected non-negative integer"
    # traceback, and an --out that names a file (or a folder that cannot be made) in a FileExistsError /
    # FileNotFoundError traceback, after simulating the whole plant
    import importlib

    main = importlib.import_module(module).main
    with pytest.raises(SystemExit) as exit_:
        main(["--seed", "-1", "--out", str(tmp_path)])
    assert exit_.value.code == 2 and "--seed" in capsys.readouterr().err
    (tmp_path / "afile").write_text("mine")
    assert main(["--out", str(tmp_path / "afile")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "afile" in err and "Traceback" not in err
    assert (tmp_path / "afile").read_text() == "mine"


def test_a_type_a_newer_graybox_saves_says_to_upgrade(tmp_path):
    # saved types are added within one format version (LocalModel and OperatingCurve were): a file of a type this
    # graybox lacks, written by a newer one, was refused as "unknown type 'Future'; graybox loads [...]", which
    # reads as a corrupt file rather than as version skew (a newer field already said to upgrade)
    doc = json.loads(gb.to_json(TWO))
    doc.update(type="Future", graybox_version="99.0")
    (tmp_path / "f.json").write_text(json.dumps(doc), encoding="utf-8")
    for call in (lambda: gb.load(tmp_path / "f.json"), lambda: gb.read_header(tmp_path / "f.json")):
        with pytest.raises(gb.GrayboxFileError, match=r"unknown type 'Future'.*written by graybox 99\.0.*upgrade"):
            call()
    header = json.loads(gb.to_json(TWO)) | {"graybox_version": "99.0", "checksum": "…"}  # a header field added since
    with pytest.raises(gb.GrayboxFileError, match=r"unknown field\(s\) \['checksum'\].*upgrade"):
        gb.from_json(json.dumps(header))
    doc["graybox_version"] = gb.__version__
    with pytest.raises(gb.GrayboxFileError, match="unknown type 'Future'") as exc:
        gb.from_json(json.dumps(doc))
    assert "upgrade" not in str(exc.value)


@pytest.mark.parametrize("command", ["status", "report"])
def test_ctrl_c_during_grid_status_or_report_ends_in_one_line(command, tmp_path, monkeypatch, capsys):
    # Ctrl-C during `graybox grid report` (figures for minutes on a large store) or `grid status` was re-raised: a
    # KeyboardInterrupt traceback through matplotlib or sqlite frames; grid run and reproduce said one line
    from graybox import experiments as gx
    from graybox._cli import main

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(gx, "write_report" if command == "report" else "grid_status", interrupted)
    argv = ["grid", command, str(tmp_path / "r.sqlite")] + (["--out", str(tmp_path / "rep")] if command == "report" else [])
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert err.startswith(f"graybox grid {command}: interrupted") and err.count("\n") == 1


@pytest.fixture(scope="module")
def selections():
    rec = gb.Record(_record().inputs, _record().y, Ts=0.1, input_names=("speed", "volts"))
    cand = gb.Candidates(1, {"speed": 2, "volts": 2}, degree=1)
    return {"Selection": gb.frols(cand, rec, n_terms=3), "SEMPResult": gb.semp(cand, rec, n_terms=3)}


@pytest.mark.parametrize("kind", ["Selection", "SEMPResult"])
def test_a_selection_with_a_non_finite_parameter_is_refused(selections, kind):
    # Selection and SEMPResult checked θ's length, not its values: a hand-edited file with "nan" or "inf" in θ
    # loaded, and the value then failed when its model was asked for ("theta has non-finite values at [0]")
    doc = json.loads(gb.to_json(selections[kind]))
    doc["object"]["theta"][0] = "nan"
    with pytest.raises(gb.GrayboxFileError, match=rf"not a valid {kind}: theta has non-finite values at \[0\]"):
        gb.from_json(json.dumps(doc))
    assert gb.from_json(gb.to_json(selections[kind])).model.theta.tolist() == selections[kind].model.theta.tolist()


def test_from_json_reads_the_text_of_a_file_an_editor_saved_with_a_byte_order_mark(tmp_path):
    # load skips the mark a "UTF-8 with BOM" editor adds (hunt28), but from_json of the same file's text, read with
    # open(..., encoding="utf-8"), was refused as "corrupt file (Unexpected UTF-8 BOM …)"
    p = tmp_path / "m.json"
    p.write_text("\ufeff" + gb.to_json(TWO), encoding="utf-8")
    assert gb.from_json(p.read_text(encoding="utf-8")).theta.tolist() == gb.load(p).theta.tolist()


def test_select_graybox_missing_the_band_names_a_static_error_its_rows_reached():
    # static points 1e5 Pa off the plant's curve: every row misses B = 2500 Pa² (its reason: the smallest J_SF
    # reached is 1e+10), but the refusal said "no structure meets the band B = 2500: the smallest J_SF reached is
    # 1.3e-05", the J_SF of PE members whose free run diverges on the choosing data, which the rows leave out
    data = _pressure(600, points=(2.04e5, 2.36e5))  # 1e5 Pa off the plant's static curve
    kw = dict(sizes=[2, 3], band=2500.0, estimator="pe", progress=False)
    with pytest.raises(ValueError, match="no structure meets the band") as exc:
        gb.select_graybox(gb.Candidates(1, 1, degree=2), data, **kw)
    said = float(str(exc.value).split("the smallest J_SF reached is ")[1].split(" ")[0])
    with pytest.warns(gb.experiments.SelectionWarning, match="no structure meets the band"):
        table = gb.select_graybox(gb.Candidates(1, 1, degree=2), data, fallback="min_jsf", **kw).table
    rows = [float(r.split("the smallest J_SF reached is ")[1]) for r in table["reason"]]
    assert said > 2500.0 and said == pytest.approx(min(rows), rel=1e-3)


def test_a_row_whose_parameters_are_not_numbers_is_named(chosen):
    # model_of read a row's θ text with float(): a hand-edited table with "abc" in it said only "could not convert
    # string to float: 'abc'", naming neither the row nor the column
    doc = json.loads(gb.to_json(chosen))
    table = doc["object"]["table"]
    row = table["index"][0]
    table["data"][table["columns"].index("theta")][0] = "0.5 abc 1e5"
    back = gb.from_json(json.dumps(doc))
    with pytest.raises(ValueError, match=rf"row '{row}' \(ls\): its theta '0.5 abc 1e5' is not numbers"):
        back.model_of(row)
