"""Hunt 54f: saving, loading and the command line (graybox.io, graybox._cli)."""

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import graybox as gb
from graybox.io import _json as _io


def _record(n=200):
    t = np.arange(n)
    return gb.Record(np.sin(0.05 * t), np.cos(0.03 * t), Ts=0.1, name="run", units=("V", "m"))


def test_a_saved_type_of_a_layer_above_inside_a_plain_map_loads_in_a_fresh_session(tmp_path, monkeypatch):
    # the header's type was imported by name when a fresh session had not registered it yet, but a saved value inside
    # a Dataset's extra (or a bootstrap's options) was not: a Dataset saved with a DecimationAdvice in its extra
    # failed to load in a new session ('expected {"type": one of [...]}'), and loaded in the session that saved it
    from graybox.datasets._decimation import DecimationAdvice

    rec = _record()
    text = gb.to_json(gb.Dataset(rec, rec, None, "bench", {"advice": gb.decimation_advice(rec)}))
    # a fresh session: the type not registered, its module (here a stand-in) registering it when imported
    (tmp_path / "hunt54f_registers_advice.py").write_text(
        "from graybox.io._json import register_type\n"
        "from graybox.datasets._decimation import DecimationAdvice\n"
        f"register_type('DecimationAdvice', DecimationAdvice, {_io._CODECS['DecimationAdvice'][1]!r})\n",
        encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(_io, "_CODECS", {k: v for k, v in _io._CODECS.items() if k != "DecimationAdvice"})
    monkeypatch.setattr(_io, "_TYPES", {k: v for k, v in _io._TYPES.items() if v != "DecimationAdvice"})
    monkeypatch.setitem(_io._REGISTERED_ABOVE, "DecimationAdvice", "hunt54f_registers_advice")
    back = gb.from_json(text)
    assert isinstance(back.extra["advice"], DecimationAdvice)


def test_a_pareto_set_without_members_loads_as_it_was_saved():
    # a set filtered to no member (ps.subset(ps.JSF <= B) when none is in the band) saved, and loading it failed:
    # JSON gives back [] for its (0, n) thetas, read as (0, 0) and refused ('thetas must have shape (K, 2)')
    ps = gb.ParetoSet(gb.Structure(["y(k-1)", "u(k-1)"]), [[0.5, 1.0], [0.4, 1.1]], [1.0, 0.1], [0.1, 0.2],
                      [0.3, 0.2], [0.0, 0.1], "PE", {"radius": [1.0, 2.0]})
    empty = ps.subset(ps.JSF < 0)
    back = gb.from_json(gb.to_json(empty))
    assert len(back) == 0 and back.thetas.shape == (0, 2) and back.extra["radius"].shape == (0,)
    assert gb.to_json(back) == gb.to_json(empty)


@pytest.mark.parametrize("shape", [[0, 2**62], [2**40, 2**40, 0], [1] * 65])
def test_a_hand_edited_shape_numpy_cannot_make_is_a_file_error_naming_the_field(shape):
    # a plain array's shape holding its (zero or one) values, but beyond what NumPy makes: a bare ValueError of
    # NumPy's ('array is too big', 'maximum supported dimension'), neither the file nor the field named
    rec = _record()
    doc = json.loads(gb.to_json(gb.Dataset(rec, rec, None, "", {"empty": np.zeros((0, 3)), "one": np.ones(1)})))
    key = "one" if math.prod(shape) else "empty"
    doc["object"]["extra"][key]["array"]["shape"] = shape
    with pytest.raises(gb.GrayboxFileError, match=rf"edited\.json: object\.extra\.{key}\.array\.shape: "):
        gb.from_json(json.dumps(doc), source="edited.json")


def test_an_empty_tuple_of_expected_types_is_refused_as_a_bad_argument(tmp_path):
    # expect=() was taken for "any of no type": every file refused with 'holds a Model, expected ' (no type named),
    # as though the file were wrong, not the call
    m = gb.Model(gb.Structure(["y(k-1)"]), [0.5])
    p = gb.save(m, tmp_path / "m.json")
    for call in (lambda: gb.load(p, expect=()), lambda: gb.from_json(gb.to_json(m), expect=())):
        with pytest.raises(ValueError, match=r"expect=\(\) names no type") as info:
            call()
        assert not isinstance(info.value, gb.GrayboxFileError)


def test_a_result_seeded_beyond_64_bits_loads_as_it_was_saved():
    # NumPy takes a seed of any size (SeedSequence().entropy is 128 bits), and so do output_error and
    # bootstrap_decision (check_seed: an integer >= 0); the file held it, but loading refused it as 'an integer
    # beyond the 64-bit range'
    import pandas as pd

    seed = 2**100 + 3
    starts = pd.DataFrame({"start": ["least squares"], "solver": ["trf"], "status": ["fitted"], "message": [""],
                           "JS_start": [0.2], "JS": [0.1], "JS_choose": [np.nan], "nfev": [3]})
    oe = gb.OEResult(gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, 1.0]), 0.1, np.nan, "", "least squares",
                     starts, np.nan, 0.5, seed)
    back = gb.from_json(gb.to_json(oe))
    assert back.seed == seed and gb.to_json(back) == gb.to_json(oe)
    doc = json.loads(gb.to_json(oe))
    doc["object"]["seed"] = -1
    with pytest.raises(gb.GrayboxFileError, match=r"object\.seed: a seed is an integer >= 0"):
        gb.from_json(json.dumps(doc))


@pytest.mark.parametrize("stem", ["a" * 240, "é" * 120])
def test_a_file_name_open_writes_is_one_save_writes(tmp_path, monkeypatch, stem):
    # a name of 245 bytes (a file system takes 255) was refused: the write's own file beside it, the name with
    # ".host-pid-0badc0de.tmp" added, was too long, and save said 'cannot write in the folder …: File name too long'
    from graybox.core import _files

    target = tmp_path / f"{stem}.json"
    m = gb.Model(gb.Structure(["y(k-1)"]), [0.5])
    gb.save(m, target)
    assert gb.load(target).theta.tolist() == [0.5]
    # what a killed write of it left beside it is swept by the next, as beside any other target
    written = []
    monkeypatch.setattr(_files.os, "replace", lambda a, b: (written.append(Path(a)), (_ for _ in ()).throw(OSError())))
    with pytest.raises(OSError):
        gb.save(m, target)
    left = written[0].with_name(written[0].name.replace(_files.writer_tag(), "otherhost-1"))
    left.write_bytes(b"half")
    monkeypatch.undo()
    os.utime(left, (0, 0))  # long past the age at which another host's leftover is swept
    gb.save(m, target)
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def test_a_subclass_of_a_saved_type_inside_a_value_is_refused_naming_the_field():
    # a value holding a user's subclass of Model or Record (a field the class takes, isinstance) crashed to_json with
    # a bare KeyError of the subclass; at the top a subclass was refused with a ValueError ('cannot save a MyModel')
    class MyModel(gb.Model):
        pass

    class MyRecord(gb.Record):
        pass

    m = MyModel(gb.Structure(["y(k-1)"]), [0.5])
    r = MyRecord(np.ones(20), np.ones(20))
    for value, field in ((gb.CLSResult(m, None, (), "closed"), "CLSResult.model"),
                         (gb.Dataset(r, gb.Record(np.ones(20), np.ones(20))), "Dataset.ident")):
        with pytest.raises(ValueError, match=rf"cannot save {field}: a My\w+, a subclass of (Model|Record)"):
            gb.to_json(value)


def test_grid_init_into_a_full_disk_is_a_line_not_a_traceback(monkeypatch, capsys):
    # graybox grid init > spec.toml on a full disk (or > /dev/full) ended in a traceback of the OSError, where every
    # other command says its OSError in one line with exit status 2
    import errno
    import io

    from graybox._cli import main

    class Full(io.StringIO):
        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        def flush(self):
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("sys.stdout", Full())
    assert main(["grid", "init"]) == 2
    assert capsys.readouterr().err == "graybox grid init: [Errno 28] No space left on device\n"


@pytest.mark.parametrize("call", [
    lambda folder: gb.save(gb.Model(gb.Structure(["y(k-1)"]), [0.5]), folder),
    lambda folder: gb.load(folder),
    lambda folder: gb.read_header(folder),
    lambda folder: gb.load_results(folder),
    lambda folder: gb.experiments.run_grid("spec.toml", folder),  # the store checked before the spec is read
])
def test_a_path_ending_in_a_folder_separator_is_no_file_name(tmp_path, monkeypatch, call):
    # gb.save(m, "results/") wrote a FILE named results (Path drops the '/'), where open("results/", "w") refuses;
    # graybox grid run --store out/ made an SQLite file named out; load("m.json/") read m.json
    monkeypatch.chdir(tmp_path)
    gb.save(gb.Model(gb.Structure(["y(k-1)"]), [0.5]), "results")  # a file the name without '/' would reach
    with pytest.raises(ValueError, match=r"'results/' ends in a folder separator, so it names a folder"):
        call("results/")
    assert [p.name for p in tmp_path.iterdir()] == ["results"]


def test_grid_run_into_a_store_named_as_a_folder_is_refused_before_any_cell(tmp_path, monkeypatch, capsys):
    from graybox._cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "spec.toml").write_text(gb.experiments.EXAMPLE_SPEC, encoding="utf-8")
    with pytest.raises(SystemExit) as exc:  # argparse's: the spec is not read, no cell runs
        main(["grid", "run", "spec.toml", "--store", "out/"])
    assert exc.value.code == 2
    assert "argument --store: the store 'out/' ends in a folder separator" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.toml"]
