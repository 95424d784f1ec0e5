"""Bugs found by a bug hunt in saving and loading, the command line, neural NARMAX and ELS: each test
fails without its fix."""

import json
import os
import stat

import numpy as np
import pytest

import graybox as gb

#: y(k) = 0.5 y(k-1) + u(k-1), with an MA part
MODEL = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], noise_structure=["e(k-1)"], noise_theta=[0.2])


@pytest.mark.parametrize("typ", [["Model"], {"name": "Model"}])
def test_a_file_whose_type_is_not_text_is_refused_as_a_graybox_file_error(typ):
    # a hand-edited "type" that is a list or an object raised TypeError (unhashable) from the lookup
    doc = json.loads(gb.to_json(MODEL))
    doc["type"] = typ
    with pytest.raises(gb.GrayboxFileError, match="unknown type"):
        gb.from_json(json.dumps(doc), source="edited.json")


def test_save_gives_the_file_the_permissions_a_plain_write_would(tmp_path):
    # the atomic write went through mkstemp, whose file is private (0600): a saved model was unreadable
    # by the group and others whatever the umask, and re-saving made a shared file private
    old = os.umask(0o022)
    try:
        p = gb.save(MODEL, tmp_path / "m.json")
        assert stat.S_IMODE(p.stat().st_mode) == 0o644
        p.chmod(0o664)
        gb.save(MODEL, p)  # an existing file keeps its mode, as open(path, "w") keeps it
        assert stat.S_IMODE(p.stat().st_mode) == 0o664
    finally:
        os.umask(old)
    assert gb.load(p).name == MODEL.name and sorted(x.name for x in tmp_path.iterdir()) == ["m.json"]


def siso_record(seed: int = 0, n: int = 300, su: float = 1.0, sy: float = 1.0, name: str = "u") -> gb.Record:
    """A staircase input in [1, 3] through y(k) = 0.6 y(k-1) + 0.5 u(k-1) − 0.1 u(k-1)², small noise."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(1.0, 3.0, n // 10 + 1), 10)[:n]
    y = gb.Model(["y(k-1)", "u(k-1)", "u(k-1)^2"], [0.6, 0.5, -0.1]).simulate(u, np.zeros(1))
    return gb.Record(u * su, (y + 0.01 * rng.standard_normal(n)) * sy, 0.1, input_names=(name,))


def test_a_neural_model_refuses_several_inputs_clearly():
    # the network has one input: a record of two inputs (or an (N, 2) array) reached the compiled kernels and
    # failed there with a numba TypingError or a broadcasting error that named neither the inputs nor the cause
    net = gb.neural_narx(siso_record(), ny=2, nu=2, ne=1, hidden=2, epochs=3, sim_epochs=3, seed=0).model
    rec = siso_record()
    two = gb.Record(np.column_stack([rec.u, rec.u[::-1]]), rec.y, rec.Ts, input_names=("u", "v"))
    with pytest.raises(ValueError, match=r"one input.*2"):  # an array has no names: two columns are refused
        net.simulate(two.u, rec.y[:2])
    assert np.array_equal(net.simulate(rec.u[:, None], rec.y[:2]), net.simulate(rec))  # (N, 1) is one input
    # a record's input is read by name, as a polynomial model reads it (the network's is "u")
    assert np.array_equal(net.predict(two), net.predict(rec))
    assert np.array_equal(net.predict(two, horizon=3), net.predict(rec, horizon=3))
    assert np.array_equal(net.predict_narmax(two)[0], net.predict_narmax(rec)[0])
    assert np.array_equal(net.simulate(two), net.simulate(rec))
    other = gb.Record(rec.u[:, None], rec.y, rec.Ts, input_names=("v",))
    for call in (lambda: net.predict(other), lambda: net.predict_narmax(other), lambda: net.simulate(other)):
        with pytest.raises(ValueError, match=r"'u'.*\('v',\)|\('v',\).*'u'|u.*v"):
            call()


def _cli(*argv: str):
    """The graybox command on ARGV, its main in this process: (exit status, stdout, stderr). (`python -m graybox`
    in a new process cost a second or two of imports a call; the pipe test below, which needs one, starts one.)"""
    import contextlib
    import io

    from graybox._cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(argv))
        except SystemExit as exc:  # argparse's refusals, as the process would exit
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def test_reproduce_refuses_an_out_that_is_not_a_folder_in_one_line(tmp_path):
    # --out naming a file (or a path under one) ended in a FileExistsError / NotADirectoryError traceback
    afile = tmp_path / "afile"
    afile.write_text("mine")
    for out in (afile, afile / "sub"):
        code, stdout, stderr = _cli("reproduce", "--quick", "--out", str(out))
        assert code == 2 and "Traceback" not in stderr and stdout == "", stderr
        assert stderr.startswith("graybox reproduce: ") and str(afile) in stderr and "folder" in stderr
    assert afile.read_text() == "mine"


def test_reproduce_says_in_one_line_which_checkpoint_is_corrupt_and_how_to_start_over(tmp_path, monkeypatch, capsys):
    # a corrupt checkpoint in --out ended the run in a ValueError traceback (after the sections before Table I)
    # that told to "choose another checkpoint path", which the command has no option for
    import graybox.reproduce as rp
    from graybox._cli import main
    from graybox.reproduce._table1 import checkpoint_path

    ck = checkpoint_path(tmp_path, "gradient", 2, quick=True)
    ck.write_bytes(b"half a checkpoint")
    rec = siso_record()

    def section(quick, out):  # Table I's sweep meeting its checkpoint, without the plant-sized work
        static = gb.StaticPoints([1.0, 2.0, 3.0], [1.0, 1.5, 1.5])
        gb.se_pareto(["y(k-1)", "u(k-1)", "u(k-1)^2"], rec, static, lambdas=[1.0], method="gradient", checkpoint=ck)
        return "unreachable"

    monkeypatch.setattr(rp, "SECTIONS", (section,))
    assert main(["reproduce", "--quick", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("graybox reproduce: ") and ck.name in err and "--fresh" in err
    assert ck.exists()  # nothing deleted behind the user's back


def test_grid_commands_refuse_unusable_paths_in_one_line(tmp_path):
    # grid report --out naming a file ended in a FileExistsError traceback; grid run --store in a folder that
    # cannot hold a file ended in sqlite3.OperationalError "unable to open database file"
    afile = tmp_path / "afile"
    afile.write_text("mine")
    spec = tmp_path / "spec.toml"
    spec.write_text('name = "tiny"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\n'
                    'name = "first-order"\nterms = ["y(k-1)", "u(k-1)", "1"]\n[[variants]]\nname = "LS"\n'
                    'estimator = "ls"\n')
    code, _, stderr = _cli("grid", "run", str(spec), "--store", str(afile / "s.sqlite"))
    assert code == 2 and "Traceback" not in stderr and str(afile) in stderr, stderr
    store = tmp_path / "s.sqlite"
    assert _cli("grid", "run", str(spec), "--store", str(store))[0] == 0
    code, _, stderr = _cli("grid", "report", str(store), "--out", str(afile))
    assert code == 2 and "Traceback" not in stderr and str(afile) in stderr, stderr
    assert afile.read_text() == "mine"


@pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")
def test_a_torn_or_foreign_checkpoint_is_refused_without_leaving_it_open(tmp_path):
    # np.load(path) left the file open when a torn zip (a checkpoint cut short) failed to read (a ResourceWarning);
    # a plain .npy array under the checkpoint's name raised TypeError (an array is no context manager)
    import gc

    from graybox.estimation._simulation_error import _load_checkpoint

    torn, npy = tmp_path / "torn.npz", tmp_path / "array.npz"
    np.savez(torn, meta="{}", thetas=np.zeros((1, 2)))
    torn.write_bytes(torn.read_bytes()[:40])
    with open(npy, "wb") as f:
        np.save(f, np.zeros(3))
    for path in (torn, npy):
        with pytest.raises(ValueError, match="not a readable SE checkpoint"):
            _load_checkpoint(path, {})
        gc.collect()  # an unclosed file says so when collected


@pytest.mark.parametrize("edit", ["theta", "err", "evaluated", "err_evaluated", "rss", "criterion_curve"])
def test_a_hand_edited_selection_file_whose_arrays_disagree_is_refused(edit):
    # a Selection took arrays of any length: a file with one θ (or one evaluated term, one ERR …) fewer or more
    # loaded, and the value then failed in str(), .model or to_frame() with an IndexError or a broadcasting error
    sel = gb.frols(gb.Candidates(ny=2, nu=2, degree=2), siso_record(), n_terms=3)
    doc = json.loads(gb.to_json(sel))
    for change in (lambda v: v[:-1], lambda v: v + v[-1:]):
        d = json.loads(json.dumps(doc))
        d["object"][edit] = change(d["object"][edit])
        with pytest.raises(gb.GrayboxFileError, match="not a valid Selection|duplicated term"):
            gb.from_json(json.dumps(d))
    back = gb.from_json(json.dumps(doc))  # the file as written still loads
    assert str(back) and back.model.n_params == 3 and len(back.to_frame()) == len(sel.evaluated)


def test_a_one_input_static_curve_refuses_points_of_several_inputs():
    # ū of shape (M, 2) given to a one-input model was flattened: static_curve answered 2M levels (the two
    # columns read as more levels of the one input), static_gain failed to broadcast or, for (1, 2), gave a
    # 2-D gain; a polynomial model and a neural network alike
    net = gb.neural_narx(siso_record(), ny=1, nu=1, ne=0, hidden=2, epochs=3, sim_epochs=3, seed=0).model
    for model in (gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]), net):
        for ub in ([[1.5, 2.0], [2.5, 2.2]], [[1.5, 2.5]]):
            for f in (model.static_curve, model.static_gain):
                with pytest.raises(ValueError, match=r"ubar.*one input.*shape \(\d, 2\)"):
                    f(ub)
        column = np.array([[1.5], [2.5]])  # a column of levels is one input's
        assert np.array_equal(model.static_curve(column), model.static_curve([1.5, 2.5]))
        assert np.array_equal(model.static_gain(column), model.static_gain([1.5, 2.5]))


@pytest.mark.parametrize("argv", [("grid", "init"), ("reproduce", "--help"), ("grid", "status", "STORE")])
def test_a_reader_that_leaves_the_pipe_early_ends_the_command_quietly(argv, tmp_path):
    # graybox grid init | head -3: the reader closing the pipe ended in a BrokenPipeError traceback (grid init)
    # or an "[Errno 32] Broken pipe" error line (commands that print as they go)
    import subprocess
    import sys

    store = tmp_path / "s.sqlite"
    if "STORE" in argv:
        spec = tmp_path / "spec.toml"
        spec.write_text('name = "tiny"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\n'
                        'name = "first-order"\nterms = ["y(k-1)", "u(k-1)", "1"]\n[[variants]]\nname = "LS"\n'
                        'estimator = "ls"\n')
        assert _cli("grid", "run", str(spec), "--store", str(store))[0] == 0
    p = subprocess.Popen([sys.executable, "-m", "graybox", *[str(store) if a == "STORE" else a for a in argv]],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()  # the reader is gone before the command writes (it is still importing)
    err = p.stderr.read().decode()
    p.stderr.close()
    assert p.wait(timeout=120) in (0, 1) and err == "", err


def test_the_command_says_its_version(capsys):
    # graybox --version answered "the following arguments are required: COMMAND"
    from graybox._cli import main

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"graybox {gb.__version__}"


@pytest.mark.parametrize("name", [None, 3, 2.5])
def test_a_model_name_that_is_not_text_is_refused_where_it_is_given(name):
    # a Model or NeuralModel took any name (e.g. els(..., name=None)): the file saved from it could not be loaded
    # ("object.name: expected a string"), so a fit was lost on the way to disk
    rec = siso_record()
    with pytest.raises(TypeError, match="name"):
        gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0], name=name)
    with pytest.raises(TypeError, match="name"):
        gb.els(["y(k-1)", "u(k-1)", "u(k-1)^2"], rec, name=name)
    with pytest.raises(TypeError, match="name"):
        gb.NeuralModel(np.zeros((1, 2)), [0.0], [1.0], 0.0, 1, 1, name=name)
    with pytest.raises(TypeError, match="name"):
        gb.neural_narx(rec, ny=1, nu=1, ne=0, hidden=1, epochs=1, sim_epochs=0, name=name)


def test_a_report_of_a_store_without_finished_cells_says_so(tmp_path):
    # a store whose run was stopped before its first cell finished (Ctrl-C, a closed pipe) made grid report fail
    # in matplotlib: "Number of columns must be a positive integer, not 0"
    import graybox.experiments as gx

    spec = tmp_path / "spec.toml"
    spec.write_text('name = "tiny"\n[[data]]\nname = "pumping"\nbundled = "pumping"\n[[structures]]\n'
                    'name = "first-order"\nterms = ["y(k-1)", "u(k-1)", "1"]\n[[variants]]\nname = "LS"\n'
                    'estimator = "ls"\n')
    store = tmp_path / "s.sqlite"

    def interrupt(line):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gx.run_grid(spec, store, log=interrupt)
    assert gx.grid_status(store).summary()  # the store is there, its spec registered, no cell done
    with pytest.raises(ValueError, match=r"no finished cell.*grid status"):
        gx.write_report(store, tmp_path / "report")
    assert not (tmp_path / "report").exists()


def test_a_file_an_editor_saved_with_a_byte_order_mark_loads(tmp_path):
    # a graybox file opened and saved again in an editor that writes "UTF-8 with BOM" (Notepad) was refused as
    # "corrupt file (Unexpected UTF-8 BOM …)"; the text is the same JSON
    p = gb.save(MODEL, tmp_path / "m.json", units=("rpm", "mlc"))
    p.write_bytes(b"\xef\xbb\xbf" + p.read_bytes())
    back = gb.load(p)
    assert np.array_equal(back.theta, MODEL.theta) and gb.read_header(p)["units"] == ("rpm", "mlc")


@pytest.mark.parametrize("direct", ["yes", 1, None])
def test_els_refuses_a_direct_flag_of_another_type_as_a_type_error(direct):
    # every flag of the library refuses a wrong type with TypeError (check_bool); els's direct raised ValueError
    with pytest.raises(TypeError, match="direct must be True or False"):
        gb.els(["y(k-1)", "u(k-1)", "u(k-1)^2"], siso_record(), direct=direct)


def test_from_json_refuses_bytes_as_a_type_error():
    # from_json(b"…") (a file read in binary mode) raised ValueError; a wrong type is a TypeError everywhere else
    with pytest.raises(TypeError, match="text must be a str"):
        gb.from_json(gb.to_json(MODEL).encode())


@pytest.mark.parametrize("term, why", [("y(k-99999999999999999999)", "64-bit"),
                                       ("u(k-1)^99999999999999999999", "power above 1023"),
                                       ("u(k-1)^9223372036854775807u(k-1)", "power above 1023"),
                                       ("u(k-1)^9223372036854775807", "power above 1023"),
                                       ("u(k-1)^1000u(k-1)^24", "power above 1023")])
def test_a_lag_beyond_64_bits_or_a_power_beyond_a_float_is_refused_where_the_term_is_read(term, why):
    # such a term (a typo in a hand-edited file) was accepted: the file loaded, and simulate and static_curve then
    # failed with OverflowError ("Python int too large to convert to C long"), or (a power near 2^63) never finished
    with pytest.raises(ValueError, match=why):
        gb.Structure([term])
    doc = json.loads(gb.to_json(MODEL))
    doc["object"]["structure"][1] = term
    with pytest.raises(gb.GrayboxFileError, match=why):
        gb.from_json(json.dumps(doc))


def test_the_largest_power_a_float_can_carry_is_a_term():
    # x^1023 is finite for x in (1/2, 2): the largest power kept, and it simulates
    st_ = gb.Structure(["y(k-1)", "u(k-1)^1023"])
    y = gb.simulate(st_, np.array([0.5, 1.0]), np.full(20, 1.0005), np.zeros(1))
    assert np.all(np.isfinite(y)) and y[-1] == pytest.approx(1.0005**1023 * 2 * (1 - 0.5**19), rel=1e-9)


def test_an_interrupted_reproduce_says_it_resumes_instead_of_a_traceback(tmp_path, monkeypatch, capsys):
    # Ctrl-C during graybox reproduce (hours in full mode) ended in a KeyboardInterrupt traceback through numba
    # and scipy frames, and did not say that the checkpoints are kept and a second run resumes
    import graybox.reproduce as rp
    from graybox._cli import main

    def section(quick, out):
        raise KeyboardInterrupt

    monkeypatch.setattr(rp, "SECTIONS", (section,))
    assert main(["reproduce", "--quick", "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err
    assert err.startswith("graybox reproduce: interrupted") and "resume" in err and str(tmp_path) in err


def test_a_saved_graybox_selection_loads_in_a_new_session(tmp_path):
    # GrayboxSelection is registered with the file format by the experiment layer when it is imported: a fresh
    # Python session that only did `import graybox` refused the file as "unknown type 'GrayboxSelection'"
    import subprocess
    import sys
    import warnings

    rec = siso_record(seed=3, n=400)
    static = gb.StaticPoints([1.2, 2.0, 2.8], gb.Model(["y(k-1)", "u(k-1)", "u(k-1)^2"], [0.6, 0.5, -0.1])
                             .static_curve([1.2, 2.0, 2.8]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sel = gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=2), rec, static, band=1.0, sizes=[3],
                                estimator="pe", folds=2)
    p = gb.save(sel, tmp_path / "sel.json")
    code = ("import sys, graybox as gb\n"
            "print(gb.read_header(sys.argv[1])['type'], type(gb.load(sys.argv[1])).__name__, "
            "gb.load(sys.argv[1]).model.n_params)")
    out = subprocess.run([sys.executable, "-c", code, str(p)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["GrayboxSelection", "GrayboxSelection", str(sel.model.n_params)]
    from graybox.io import _json as io

    from graybox._layers import LAYERS

    import graybox.datasets._decimation  # noqa: F401  (registers DecimationAdvice, as gb.decimation_advice would)

    units = [u for u, _, _ in LAYERS]
    above_io = set(units[units.index("io") + 1:])
    above = {name for name in io._CODECS if io._cls(name).__module__.split(".")[1] in above_io}
    assert above == set(io._REGISTERED_ABOVE)  # every type a layer above registers is found from its name
    assert all(io._REGISTERED_ABOVE[name] == io._cls(name).__module__ for name in above)


def test_a_file_a_newer_graybox_wrote_with_a_field_this_one_lacks_says_to_upgrade():
    # a file of the same format version written by a newer graybox with a field added since was refused as
    # "unknown field(s) ['…'] for a Model", which reads as a corrupt file rather than as version skew
    doc = json.loads(gb.to_json(MODEL))
    doc["object"]["sampling_period"] = 0.1
    doc["graybox_version"] = "99.0.0"
    with pytest.raises(gb.GrayboxFileError, match=r"unknown field.*sampling_period.*graybox 99\.0\.0.*upgrade"):
        gb.from_json(json.dumps(doc))
    doc["graybox_version"] = gb.__version__  # same version: a hand-edited file, no advice to upgrade
    with pytest.raises(gb.GrayboxFileError, match="unknown field") as exc:
        gb.from_json(json.dumps(doc))
    assert "upgrade" not in str(exc.value)


def test_a_network_keeps_the_name_of_the_input_it_was_trained_on():
    # a network trained on "speed" read whatever one input a record had ("valve" included); a polynomial model
    # reads its inputs by name and refuses a record without them: the network now does the same, and the name
    # is saved (a file written before it existed reads as "u")
    rec = siso_record()
    speed = gb.Record(rec.u, rec.y, rec.Ts, input_names=("speed",))
    net = gb.neural_narx(speed, ny=2, nu=2, ne=0, hidden=2, epochs=3, sim_epochs=3, seed=0).model
    assert net.input_names == ("speed",)
    valve = gb.Record(rec.u, rec.y, rec.Ts, input_names=("valve",))
    with pytest.raises(ValueError, match="speed"):
        net.simulate(valve)
    with pytest.raises(ValueError, match="speed"):
        gb.js(net, valve)
    both = gb.Record(np.column_stack([rec.u[::-1], rec.u]), rec.y, rec.Ts, input_names=("valve", "speed"))
    assert np.array_equal(net.simulate(both), net.simulate(speed))
    back = gb.from_json(gb.to_json(net))
    assert back.input_names == ("speed",) and np.array_equal(back.simulate(speed), net.simulate(speed))
    doc = json.loads(gb.to_json(net))
    del doc["object"]["input_names"]
    assert gb.from_json(json.dumps(doc)).input_names == ("u",)
    with pytest.raises(ValueError, match="one input"):
        gb.NeuralModel(net.W1, net.b1, net.w2, net.b2, net.ny, net.nu, net.ne, input_names=("a", "b"))
