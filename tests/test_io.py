"""Save and load as JSON: every saved type round-trips bit for bit; bad files are refused clearly; no pickle."""

import ast
import json
import re
import struct
import subprocess
import sys
import warnings
from dataclasses import fields
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, given, settings, strategies as st

import graybox as gb
from graybox.core._records import RecordPrint, record_print
from graybox.io import _json as _io

STRUCT = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-1)y(k-2)", "u(k-1)^2", "1"])


def bits(x):
    """The float64 bit patterns of an array (NaN payloads aside: graybox writes one NaN)."""
    a = np.asarray(x, float)
    return np.where(np.isnan(a), np.nan, a).view(np.int64) if a.size else a


def same(a, b, path="value"):
    """Deep equality of graybox values: floats bit for bit, arrays by shape and bits."""
    if isinstance(a, pd.DataFrame) or isinstance(b, pd.DataFrame):
        pd.testing.assert_frame_equal(a, b, check_exact=True, obj=path)  # dtypes, index and values exactly
    elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a, float), np.asarray(b, float)
        assert a.shape == b.shape, path
        np.testing.assert_array_equal(bits(a), bits(b), err_msg=path)
    elif isinstance(a, gb.Record) and isinstance(b, RecordPrint):  # a Pareto set's fitting record: saved as its print
        same(record_print(a), b, path)
    elif isinstance(a, RecordPrint):
        assert type(b) is RecordPrint, path
        for f in fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif type(a) in _io._TYPES:
        assert type(a) is type(b), path
        for f in fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, float) or isinstance(b, float):
        assert struct.pack("<d", a) == struct.pack("<d", b) or (np.isnan(a) and np.isnan(b)), path
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{path}[{i}]")
    elif hasattr(a, "items"):
        assert dict(a).keys() == dict(b).keys(), path
        for k in dict(a):
            same(a[k], b[k], f"{path}.{k}")
    else:
        assert a == b, path


def record(seed=0, N=300):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(750, 1650, N // 10 + 1), 10)[:N]
    m = gb.Model(STRUCT, [0.6, 0.2, 2e-3, 1e-5, -5e-7, 0.3])
    y = m.simulate(u, np.full(2, 8.0)) + 0.05 * rng.standard_normal(N)
    return gb.Record(u, y, name="ident", units=("rpm", "mlc"))


@pytest.fixture(scope="module")
def values():
    rec = record()
    static = gb.StaticPoints(np.linspace(800, 1600, 5), np.linspace(5, 19, 5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sel = gb.frols(gb.Candidates(ny=2, nu=1, ne=2, degree=2), rec, n_terms=6)
        fit = gb.els(sel, rec)
        pe = gb.pe_pareto(STRUCT, rec, static, lambdas=[1.0, 0.1, 1e-3], solver="closed")
        failed = gb.ParetoSet(STRUCT, np.vstack([pe.thetas[:2], np.full(6, np.nan)]), [1.0, 0.1, np.nan],
                              pe.J1, [0.5, np.inf, np.inf], pe.JSF, "PE with a failure", {"cost": [1.0, -0.0, np.inf]},
                              {2: "no start was feasible"})
        dec = gb.decide_dsf(pe, band=100.0)
        nfit = gb.neural_narx(rec, ny=1, nu=1, ne=1, hidden=2, epochs=3, seed=0)
        unc = gb.pe_uncertainty(dec, rec, static)
        band = gb.static_curve_band(gb.ls_uncertainty(pe.member_model(0), rec), [900.0, 1300.0], method="monte-carlo",
                                    n_samples=200)
        dsf = gb.se_dsf(STRUCT, rec, static, band=1.0, theta0=pe.thetas[1], max_iter=5)
        run_band = gb.simulation_band(gb.ls_uncertainty(pe.member_model(0), rec), rec, method="monte-carlo",
                                      n_samples=50)
        path = gb.semp(gb.Candidates(ny=2, nu=1, degree=2), rec, n_terms=3)
        exact = gb.frols(gb.Candidates(ny=2, nu=1, degree=2), rec, max_terms=4, search="exact")
        oe = gb.output_error(STRUCT, rec, n_starts=1, max_nfev=5, margin=0.05, choose_on=record(seed=1))
        chosen = gb.decide_dsf(pe, band=100.0, choose_on=record(seed=1))
        # the static information a user passes, and the results that keep it
        points = gb.StaticPoints(np.linspace(800, 1600, 5), np.linspace(5, 19, 5), "bench", ("speed",), 0.175,
                                 ("rpm", "mlc"))
        points2 = gb.StaticPoints([[1.0, 2e5], [2.0, 2e5], [1.0, 3e5]], [3.0, 4.0, 5.5], input_names=("valve", "p"))
        curve = gb.StaticCurve.fit(static, degree=2)
        surface = gb.StaticSurface.fit(points2, degree=1)
        cls_points = gb.cls(STRUCT, rec, static=static)
        cls_curve = gb.cls(STRUCT, rec, static=curve)
        local = gb.local_model(fit.model, 1200.0, Ts=0.1)
        no_eq = gb.local_model(gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [1.0, 0.5]), 1.0, Ts=0.1)
        curve_band = gb.operating_curve(pe.member_model(0), [900.0, 1200.0, 1500.0], Ts=0.1,
                                        uncertainty=gb.ls_uncertainty(pe.member_model(0), rec), n_samples=50)
    return {"static points": static, "points with uncertainty": points, "points of two inputs": points2,
            "curve": curve, "curve without domain": gb.StaticCurve.polynomial([1.0, -2.5, 1e-4]),
            "surface": surface, "cls": cls_points, "cls on a curve": cls_curve, "cls without static": gb.cls(STRUCT, rec),
            "local model": local, "no local model": no_eq, "operating curve": curve_band,
            "exact selection": exact, "oe": oe, "chosen decision": chosen, "model": fit.model, "plain model": sel.model, "neural": nfit.model, "pareto": pe, "failed": failed,
            "selection": sel, "els": fit, "neural fit": nfit, "decision": dec, "uncertainty": unc, "band": band,
            "simulation band": run_band, "dsf": dsf, "semp": path}


TYPES = ["static points", "points with uncertainty", "points of two inputs", "curve", "curve without domain", "surface",
         "cls", "cls on a curve", "cls without static", "local model", "no local model", "operating curve", "model", "plain model", "neural", "pareto", "failed", "selection", "exact selection", "els", "neural fit",
         "decision", "uncertainty", "band", "simulation band", "dsf", "semp", "oe", "chosen decision"]


@pytest.mark.parametrize("name", TYPES)
def test_round_trip(values, name, tmp_path):
    v = values[name]
    p = gb.save(v, tmp_path / f"{name}.json", units=("rpm", "mlc"))
    back = gb.load(p)
    same(v, back)
    assert gb.load(p, expect=type(v)) is not None
    head = gb.read_header(p)
    assert head["type"] == type(v).__name__ and head["units"] == ("rpm", "mlc")
    assert head["format_version"] == gb.FORMAT_VERSION and head["graybox_version"] == gb.__version__
    # text round trip too, and writing the loaded value gives the same file
    assert gb.to_json(back, units=("rpm", "mlc")) == p.read_text(encoding="utf-8")


def test_a_selection_saved_before_subset_search_loads_as_greedy(values):
    import json

    d = json.loads(gb.to_json(values["selection"]))
    body = d["object"]
    for k in ("search", "subsets", "subset_rss"):
        del body[k]
    back = gb.from_json(json.dumps(d))
    assert back.search == "greedy" and back.subsets == () and back.subset_rss.size == 0
    assert back.structure == values["selection"].structure


def test_every_constructor_field_is_saved():
    for name in _io._REGISTERED_ABOVE:  # the types above io's layer too, whichever tests ran before
        assert _io._saved_type(name), name
    for name, (_, spec) in _io._CODECS.items():
        assert {f.name for f in fields(_io._cls(name))} == {k for k, _ in spec}, name


def test_the_file_is_readable(values, tmp_path):
    p = gb.save(values["model"], tmp_path / "m.json", units=("rpm", "mlc"))
    doc = json.loads(p.read_text(encoding="utf-8"))
    assert doc["format"] == "graybox" and doc["type"] == "Model" and doc["units"] == {"u": "rpm", "y": "mlc"}
    m = values["model"]
    assert doc["object"]["structure"] == [str(t) for t in m.structure]  # terms as the paper prints them
    assert doc["object"]["noise_structure"] == ["e(k-1)", "e(k-2)"]
    assert doc["object"]["equation"].startswith("y(k) = ")
    assert set(doc["object"]["clusters"]) == set(m.clusters())
    lines = p.read_text(encoding="utf-8").splitlines()
    assert any(line.strip().startswith('"theta": [') and line.rstrip().endswith("],") for line in lines)  # one line
    pareto = gb.to_json(values["failed"])
    assert '"nan"' in pareto and '"inf"' in pareto and "NaN" not in pareto and "Infinity" not in pareto
    json.loads(pareto)  # strict JSON


finite_or_inf = st.floats(allow_nan=False, allow_infinity=False, allow_subnormal=True, width=64)


@settings(max_examples=200, deadline=None)
@given(theta=st.lists(finite_or_inf, min_size=6, max_size=6))
def test_model_floats_round_trip_bit_for_bit(theta):
    m = gb.Model(STRUCT, theta, name="θ")
    back = gb.from_json(gb.to_json(m))
    assert [struct.pack("<d", x) for x in back.theta] == [struct.pack("<d", float(x)) for x in theta]


@settings(max_examples=100, deadline=None)
@given(values=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1, max_size=8))
def test_non_finite_values_round_trip(values):
    K = len(values)
    v = np.array(values)
    # any float goes through extra; lambdas and J_S take the values a set may hold (λ1 in (0, 1] or NaN; J >= 0)
    lam = np.where((v > 0) & (v <= 1) | np.isnan(v), v, np.nan)
    ps = gb.ParetoSet(gb.Structure(["y(k-1)"]), np.ones((K, 1)), lam, np.zeros(K), np.abs(v), np.zeros(K),
                      extra={"values": v})
    back = gb.from_json(gb.to_json(ps))
    same(ps, back)


def _doc(values, **change):
    d = json.loads(gb.to_json(values["model"]))
    for k, v in change.items():
        if v is None:
            d.pop(k)
        else:
            d[k] = v
    return json.dumps(d)


def test_bad_files_are_refused(values, tmp_path):
    ok = gb.to_json(values["model"])
    bad = {
        "not JSON": (ok[:-20], "corrupt file"),
        "a list": ("[1, 2]", "not a graybox file"),
        "another format": (_doc(values, format="other"), "not a graybox file"),
        "newer": (_doc(values, format_version=2), r"newer graybox .*format version 2.*upgrade"),
        "version as text": (_doc(values, format_version="1"), "unknown format_version"),
        "version 0": (_doc(values, format_version=0), "unknown format_version"),
        "unknown type": (_doc(values, type="Pickle"), "unknown type 'Pickle'"),
        "extra header": (_doc(values, comment="hi"), r"unknown field\(s\) \['comment'\]"),
        "bad units": (_doc(values, units={"u": 1}), "units"),
        "no object": (_doc(values, object=None), 'no "object"'),
    }
    for label, (text, msg) in bad.items():
        with pytest.raises(gb.GrayboxFileError, match=msg):
            gb.from_json(text, source=label)
    obj = json.loads(ok)

    def with_object(**change):
        d = json.loads(ok)
        d["object"].update(change)
        return json.dumps(d)

    cases = {
        "object.theta": (with_object(theta="0.5"), "expected a list"),
        "object.theta[1]": (with_object(theta=[0.1, "x"] + obj["object"]["theta"][2:]), "expected a number"),
        "length": (with_object(theta=obj["object"]["theta"][:-1]), r"not a valid Model: theta has \d values"),
        "term": (with_object(structure=["y(k-1)", "k(k-1)"] + obj["object"]["structure"][2:]), "unknown signal"),
        "name": (with_object(name=3), "expected a string"),
        "unknown": (with_object(colour="red"), r"unknown field\(s\) \['colour'\]"),
        "true as number": (with_object(theta=[True] + obj["object"]["theta"][1:]), "expected a number"),
    }
    for label, (text, msg) in cases.items():
        with pytest.raises(gb.GrayboxFileError, match=msg):
            gb.from_json(text)
    d = json.loads(ok)
    del d["object"]["theta"]
    with pytest.raises(gb.GrayboxFileError, match=r"missing field\(s\) \['theta'\]"):
        gb.from_json(json.dumps(d))
    # a file: names itself in the message; binary junk is refused without being interpreted
    junk = tmp_path / "junk.json"
    junk.write_bytes(b"\x80\x04\x95 pickle protocol 4")
    with pytest.raises(gb.GrayboxFileError, match="junk.json: not a graybox file"):
        gb.load(junk)
    with pytest.raises(FileNotFoundError):
        gb.load(tmp_path / "missing.json")


def test_expect_and_unsupported_types(values, tmp_path):
    p = gb.save(values["pareto"], tmp_path / "front.json")
    with pytest.raises(gb.GrayboxFileError, match="holds a ParetoSet, expected Model"):
        gb.load(p, expect=gb.Model)
    assert isinstance(gb.load(p, expect=(gb.Model, gb.ParetoSet)), gb.ParetoSet)
    with pytest.raises(ValueError, match="expect must be one of"):
        gb.load(p, expect=dict)
    with pytest.raises(ValueError, match="cannot save a dict"):
        gb.save({"a": 1}, tmp_path / "x.json")
    with pytest.raises(TypeError, match="units must be a pair"):
        gb.save(values["model"], tmp_path / "x.json", units="rpm")


def test_loaded_values_are_immutable(values):
    back = gb.from_json(gb.to_json(values["els"]))
    with pytest.raises(ValueError):
        back.residuals[0][0] = 1.0
    with pytest.raises(ValueError):
        back.model.theta[0] = 1.0


def test_save_is_atomic(values, tmp_path, monkeypatch):
    p = tmp_path / "m.json"
    gb.save(values["model"], p)
    before = p.read_text(encoding="utf-8")

    def boom(*a, **k):
        raise OSError("disk full (test)")

    monkeypatch.setattr(_io.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        gb.save(values["plain model"], p)
    assert p.read_text(encoding="utf-8") == before
    assert sorted(x.name for x in tmp_path.iterdir()) == ["m.json"]  # no temporary left behind


def test_no_loader_uses_pickle():
    """No module of graybox imports pickle (or its kin) or calls np.load without allow_pickle=False."""
    root = Path(gb.__file__).parent
    for path in root.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [a.name for a in node.names] + ([node.module] if isinstance(node, ast.ImportFrom) else [])
                assert not {"pickle", "cPickle", "dill", "joblib", "shelve", "marshal", "cloudpickle"} & set(names), path
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                if node.func.attr == "read_pickle":
                    raise AssertionError(f"{path}: read_pickle")
                if node.func.attr == "load" and getattr(node.func.value, "id", "") in ("np", "numpy"):
                    kw = {k.arg: k.value for k in node.keywords}
                    assert "allow_pickle" in kw and getattr(kw["allow_pickle"], "value", True) is False, path


def test_latex():
    m = gb.Model(["y(k-1)", "u(k-2)y(k-6)", "u(k-6)^2", "1"], [0.6303, 2.3e-4, -4.134e-7, -0.477],
                 noise_structure=["e(k-1)"], noise_theta=[-0.5])
    tex = m.to_latex()
    assert tex == (r"y(k) = 0.6303\,y(k-1) + 0.00023\,u(k-2)\,y(k-6) - 4.134 \times 10^{-7}\,u(k-6)^{2} - 0.477"
                   r" - 0.5\,\xi(k-1) + \xi(k)")
    block = m.to_latex(terms_per_line=2)
    assert block.startswith("\\begin{aligned}\ny(k) ={}& 0.6303") and block.endswith("\\end{aligned}")
    assert block.count("\\\\\n") == 2
    assert gb.Model(["y(k-1)"], [-2.0]).to_latex(digits=2) == r"y(k) = -2\,y(k-1)"


def test_an_els_file_written_before_n_direct_existed_still_loads(values):
    import json

    text = gb.to_json(values["els"])
    doc = json.loads(text)
    body = doc["object"]
    assert body.pop("n_direct") == values["els"].n_direct
    back = gb.from_json(json.dumps(doc))
    assert back.n_direct == 0 and back.n_iter == values["els"].n_iter


def test_a_decision_file_written_before_chosen_on_existed_still_loads(values):
    import json

    doc = json.loads(gb.to_json(values["chosen decision"]))
    assert doc["object"].pop("chosen_on") == "ident"
    back = gb.from_json(json.dumps(doc))
    assert back.chosen_on == "" and back.index == values["chosen decision"].index


def test_static_points_keep_their_units_and_a_file_written_before_them_still_loads(values):
    import json

    points = values["points with uncertainty"]
    assert gb.from_json(gb.to_json(points)).units == points.units == ("rpm", "mlc")
    doc = json.loads(gb.to_json(points))
    assert doc["object"].pop("units") == ["rpm", "mlc"]
    back = gb.from_json(json.dumps(doc))
    assert back.units == ("", "")  # the default: no unit said
    np.testing.assert_array_equal(back.uncertainty, points.uncertainty)
    doc["object"]["units"] = ["rpm"]
    with pytest.raises(gb.GrayboxFileError, match=r"units must be a pair of strings"):
        gb.from_json(json.dumps(doc))


def test_an_output_error_result_keeps_its_starts(values):
    back = gb.from_json(gb.to_json(values["oe"]))
    assert back.starts.equals(values["oe"].starts) and dict(back.failures) == dict(values["oe"].failures)
    assert back.chosen_on == "ident" and back.JS_choose == values["oe"].JS_choose


def test_a_graybox_selection_round_trips_with_its_table(tmp_path):
    """select_graybox's result (defined in the experiment layer, registered with the file format):
    its table comes back with the same columns, kinds, index and values."""
    rec = record(3, N=600)
    static = gb.StaticPoints(np.linspace(800, 1600, 5), gb.Model(STRUCT, [0.6, 0.2, 2e-3, 1e-5, -5e-7, 0.3])
                             .static_curve(np.linspace(800, 1600, 5)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sel = gb.select_graybox(gb.Candidates(ny=2, nu=1, degree=2), rec, static, band=1.0, sizes=[3, 4],
                                estimator="pe", folds=2)
    assert len(sel.table) >= 2 and {"JS_valid", "in_band", "rank"} <= set(sel.table.columns)
    p = gb.save(sel, tmp_path / "sel.json", units=("rpm", "mlc"))
    back = gb.load(p, expect=gb.GrayboxSelection)
    same(sel, back)
    assert gb.to_json(back, units=("rpm", "mlc")) == p.read_text(encoding="utf-8")


def test_bad_tables_are_refused(values):
    ok = json.loads(gb.to_json(values["semp"]))

    def with_path(**change):
        d = json.loads(json.dumps(ok))
        d["object"]["path"].update(change)
        return json.dumps(d)

    cols = ok["object"]["path"]["columns"]
    data = ok["object"]["path"]["data"]
    cases = {
        "short column": (with_path(data=[data[0][:-1]] + data[1:]), "different lengths"),
        "unknown kind": (with_path(kinds=["complex"] + ok["object"]["path"]["kinds"][1:]), "unknown column kind"),
        "text in a float column": (with_path(data=[c if k != "float" else ["x"] * len(c) for c, k in
                                                   zip(data, ok["object"]["path"]["kinds"])]), "expected a number"),
        "repeated name": (with_path(columns=[cols[0]] * len(cols)), "repeated column names"),
        "too few kinds": (with_path(kinds=ok["object"]["path"]["kinds"][:-1]), "columns, .* kinds"),
        "unknown key": (with_path(colour="red"), "unknown"),
    }
    for label, (text, msg) in cases.items():
        with pytest.raises(gb.GrayboxFileError, match=msg):
            gb.from_json(text, source=label)
    huge = {
        "an int beyond 64 bits": (with_path(data=[[2**64] * len(data[0])] + data[1:]), "beyond the 64-bit range"),
        "a length of a trillion rows": (with_path(index=10**12), r"a table length must be in \[0, "),
        "a float beyond the float range": (with_path(data=data[:4] + [[10**400] * len(data[4])] + data[5:]),
                                           "beyond the float range"),
        "a 5000-digit integer": (re.sub(r'"n_rows": \d+', '"n_rows": ' + "9" * 5000, gb.to_json(values["semp"])),
                                 "corrupt file"),
    }
    for label, (text, msg) in huge.items():
        with pytest.raises(gb.GrayboxFileError, match=msg):
            gb.from_json(text, source=label)
    # a file whose parts do not fit together is refused by the value's own checks
    d = json.loads(gb.to_json(values["semp"]))
    d["object"]["theta"] = d["object"]["theta"][:-1]
    with pytest.raises(gb.GrayboxFileError, match="not a valid SEMPResult: theta has"):
        gb.from_json(json.dumps(d))
    d = json.loads(gb.to_json(values["semp"]))
    d["object"]["criterion"] = "nonsense"
    with pytest.raises(gb.GrayboxFileError, match="not a valid SEMPResult: criterion"):
        gb.from_json(json.dumps(d))
    # what the format cannot carry is refused when saving, not converted
    for frame, what in ((pd.DataFrame({"x": [None, 1.0, "a"]}, dtype=object), "cannot save the table column 'x'"),
                        (pd.DataFrame({"x": pd.array([1, 2], dtype="Int64")}), "dtype Int64"),
                        (pd.DataFrame({"x": np.array([1, 2], dtype=np.int32)}), "dtype int32"),
                        (pd.DataFrame({0: [1.0]}), "text column labels"),
                        (pd.DataFrame([[1.0, 2.0]], columns=["a", "a"]), "distinct")):
        with pytest.raises(ValueError, match=what):
            _io._enc_frame(frame)


def test_registering_a_saved_type_cannot_replace_or_duplicate_one(monkeypatch):
    # run alone (or before any test that imports the experiment layer) it raised KeyError: 'GrayboxSelection', which
    # registers itself when its module is imported; the tables are the test's own copies, so that a registration it
    # makes cannot reach another test
    assert _io._saved_type("GrayboxSelection")  # imports its module, which registers it
    monkeypatch.setattr(_io, "_CODECS", dict(_io._CODECS))
    monkeypatch.setattr(_io, "_TYPES", dict(_io._TYPES))
    spec = _io._CODECS["GrayboxSelection"][1]
    _io.register_type("GrayboxSelection", gb.GrayboxSelection, spec)  # the same again (a module reloaded): fine
    with pytest.raises(ValueError, match="exists already"):
        _io.register_type("Model", gb.Model, (("name", "str"),))
    with pytest.raises(ValueError, match="saved as 'Model' already"):
        _io.register_type("Model2", gb.Model, _io._CODECS["Model"][1])
    with pytest.raises(ValueError, match="unknown field kind"):
        _io.register_type("Thing", type("Thing", (), {}), (("x", "integer"),))
    assert "Model2" not in _io._CODECS and "Thing" not in _io._CODECS



def test_saving_and_loading_a_model_leaves_pandas_unloaded(values, tmp_path):
    # the codec table named OEResult and SEMPResult, whose modules import pandas (~0.3 s) at the top: a first
    # gb.save of a Model in a fresh process loaded it for no table; a result's module is imported where one is met
    code = ("import sys, numpy as np, graybox as gb\n"
            "m = gb.Model(structure=gb.Structure(['y(k-1)', 'u(k-1)']), theta=np.array([0.5, 0.25]))\n"
            "text = gb.to_json(m)\n"
            "gb.save(m, sys.argv[1])\n"
            "back = gb.load(sys.argv[1], expect=gb.Model)\n"
            "assert back.theta.tolist() == [0.5, 0.25] and gb.from_json(text).structure == m.structure\n"
            "assert 'pandas' not in sys.modules, 'pandas imported'\n"
            "assert 'graybox.estimation._output_error' not in sys.modules\n")
    subprocess.run([sys.executable, "-c", code, str(tmp_path / "m.json")], check=True)
    # a file naming a result loads in a fresh process: its module is imported then
    oe = tmp_path / "oe.json"
    gb.save(values["oe"], oe)
    code = ("import sys, graybox as gb\n"
            "r = gb.load(sys.argv[1])\n"
            "assert type(r).__name__ == 'OEResult' and 'pandas' in sys.modules\n")
    subprocess.run([sys.executable, "-c", code, str(oe)], check=True)


@pytest.mark.parametrize("frame", [
    pd.DataFrame(index=pd.RangeIndex(3)),                                   # rows, no columns
    pd.DataFrame({"a": pd.array([], dtype="str"), "b": np.array([], float)}),  # columns, no rows
    pd.DataFrame({"s": ["x", ""], "f": [1.5, np.inf], "i": [1, -2], "b": [True, False]},
                 index=pd.Index(["p", "q"], name="k")),
    pd.DataFrame({"f": [np.nan, -0.0]}, index=pd.Index([2.5, 2.5])),          # a repeated float index
])
def test_tables_round_trip_exactly(frame):
    back = _io._dec_frame(_io._enc_frame(frame), "table", _io._Reader("test"))
    pd.testing.assert_frame_equal(frame, back, check_exact=True)


def test_a_cls_result_keeps_its_static_information_and_refuses_another_type(values):
    # a CLS result could not be saved: its static field (points, a curve or a surface) had no codec
    for name in ("cls", "cls on a curve"):
        back = gb.from_json(gb.to_json(values[name]))
        assert type(back.static) is type(values[name].static)
        assert back.model.theta.tobytes() == values[name].model.theta.tobytes()
    doc = json.loads(gb.to_json(values["cls"]))
    doc["object"]["static"]["type"] = "Model"  # a saved type, but not static information
    with pytest.raises(gb.GrayboxFileError, match=r"object\.static: expected .*StaticPoints"):
        gb.from_json(json.dumps(doc))
    doc["object"]["static"] = [1.0, 2.0]
    with pytest.raises(gb.GrayboxFileError, match="expected an object"):
        gb.from_json(json.dumps(doc))


def test_an_operating_curve_of_two_inputs_round_trips_with_its_shapes():
    st2 = gb.Structure(["1", "a(k-1)", "b(k-1)", "a(k-1)b(k-1)", "y(k-1)"])
    m = gb.Model(st2, [0.5, 1.0, -2.0, 0.1, 0.6], input_names=("a", "b"), Ts=0.5)
    oc = gb.operating_curve(m, [[1.0, 2.0], [2.0, 3.0]])
    back = gb.from_json(gb.to_json(oc))
    assert back.ubar.shape == (2, 2) and back.gain.shape == (2, 2) and back.local_models[1].b.shape == (2, 1)
    same(oc, back)


def test_a_graybox_file_an_editor_saved_in_another_encoding_is_named_so(tmp_path):
    """A saved model renamed 'Kühler' in an editor that saves cp1252 ('ANSI', Windows Notepad before 2019) was refused
    as 'not a graybox file (not UTF-8 text)': it is one, in another encoding, and no line or byte was named."""
    path = tmp_path / "m.json"
    text = gb.to_json(gb.Model(gb.Structure(["y(k-1)"]), [0.5], name="Kühler")).replace("Σ", "S")
    path.write_bytes(text.encode("cp1252"))
    line = 1 + text[:text.index("Kühler")].count("\n")
    with pytest.raises(gb.GrayboxFileError, match=rf"m\.json: line {line} is not UTF-8 text \(byte 0xfc\): a graybox "
                                                  r"file saved again in another encoding.*save it as UTF-8"):
        gb.load(path)
    path.write_bytes(b"\x00\x01\x02\xff\xfe garbage")
    with pytest.raises(gb.GrayboxFileError, match=r"m\.json: not a graybox file: line 1 is not UTF-8 text \(byte "
                                                  r"0xff\)"):
        gb.read_header(path)


def test_a_path_under_the_home_folder_written_with_a_tilde(tmp_path, monkeypatch):
    # gb.save(m, "~/m.json") said "cannot write in the folder ~" (hunt60b): '~' is the home folder, as in a shell
    import graybox as gb

    monkeypatch.setenv("HOME", str(tmp_path))
    m = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    written = gb.save(m, "~/m.json")
    assert (tmp_path / "m.json").is_file() and written == tmp_path / "m.json"
    assert gb.load("~/m.json").theta.tolist() == [0.5, 1.0]


def _counting(monkeypatch, name, owner):
    """Count the calls of owner.name (a per-number reader), keeping what it does."""
    calls = []
    real = getattr(owner, name)

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)
    monkeypatch.setattr(owner, name, counted)
    return calls


def test_a_long_record_is_read_by_one_conversion_not_number_by_number(monkeypatch):
    # 10**6 samples took ~2.4 s of CPU to load: every number went through a Python call while parsing (the check
    # for numbers beyond the float range) and again while reading (a NumPy array of each); now neither, for a
    # record of one input and of two (rows), while the numbers still come back bit for bit
    rng = np.random.default_rng(3)
    n = 10**4
    for u in (rng.standard_normal(n), rng.standard_normal((n, 2))):
        rec = gb.Record(u, rng.standard_normal(n) * 1e-300, Ts=0.25, name="long")
        text = gb.to_json(rec)
        per_number = _counting(monkeypatch, "float", _io._Reader)
        parsed = _counting(monkeypatch, "_finite_float", _io)
        back = gb.from_json(text, expect=gb.Record)
        monkeypatch.undo()
        assert len(per_number) < 10 and not parsed
        np.testing.assert_array_equal(bits(back.u), bits(rec.u))
        np.testing.assert_array_equal(bits(back.y), bits(rec.y))
        assert back.u.shape == rec.u.shape and not back.y.flags.writeable


def test_a_long_record_of_awkward_numbers_round_trips_bit_for_bit():
    # the shortest repr of every kind of float64 (subnormals, -0.0, the largest, integers beyond 2**53) and
    # integers a hand or another tool wrote, read as float() reads them
    rng = np.random.default_rng(4)
    n = 10**5
    y = rng.standard_normal(n) * 10.0 ** rng.integers(-320, 308, n)
    y[:6] = [-0.0, 5e-324, -2.2250738585072014e-308, 1.7976931348623157e308, 2.0**53 + 2, 1e-310]
    rec = gb.Record(rng.standard_normal(n), y)
    back = gb.from_json(gb.to_json(rec))
    np.testing.assert_array_equal(bits(back.y), bits(y))
    text = gb.to_json(gb.Record(np.arange(4.0), np.arange(4.0))).replace("[0.0, 1.0, 2.0, 3.0]",
                                                                        f"[0, {2**53 + 1}, {10**300}, -7]")
    back = gb.from_json(text)
    np.testing.assert_array_equal(bits(back.u), bits([0.0, float(2**53 + 1), float(10**300), -7.0]))


@pytest.mark.parametrize("token, message", [
    ("1e400", r"object\.y\[1\]: the number 1e400 is beyond the float range"),
    ("-1E+999", r"object\.y\[1\]: the number -1E\+999 is beyond the float range"),
    # read as 0.0 by json: a number written not zero loaded as another, refused as an overflow is, where it is
    ("1e-400", r"object\.y\[1\]: the number 1e-400 is not zero but below the smallest float"),
    ("-2.5E-0330", r"object\.y\[1\]: the number -2.5E-0330 is not zero but below the smallest float"),
    ("0." + "0" * 330 + "7", r"object\.y\[1\]: the number 0\.0000.* is not zero but below the smallest float"),
    ("0.0000001e-318", r"object\.y\[1\]: the number 0\.0000001e-318 is not zero but below the smallest float"),
    ("2.4e-324", r"object\.y\[1\]: the number 2\.4e-324 is not zero but below the smallest float"),
    # a long number is shown by its head and its tail, the exponent kept ("0.000…0001" was shown for 1e-340)
    ("0." + "0" * 39 + "1e-300", r"the number 0\.0000000000…0000001e-300 is not zero but below the smallest float"),
    ("1." + "0" * 40 + "e400", r"the number 1\.0000000000…00000000e400 is beyond the float range"),
    ("Infinity", r"y has 1 non-finite value"),  # the literal Python's json writes: the value it names
    ("1" + "0" * 400, r"object\.y\[1\]: a number beyond the float range"),
    ('"x"', r"object\.y\[1\]: expected a number, got the string 'x'"),
    ("true", r"object\.y\[1\]: expected a number, got bool"),
    ("[1.0]", r"object\.y\[1\]: expected a number, got list"),
    ("null", r"object\.y\[1\]: expected a number, got NoneType"),
    ("NaN", r"y has 1 non-finite value"),
    ('"inf"', r"y has 1 non-finite value"),
])
def test_a_bad_number_in_a_long_array_is_refused_where_it_is(token, message):
    y = np.arange(2000) / 8.0  # 0.0, 0.125, …: the second number, y[1], is replaced
    text = gb.to_json(gb.Record(np.ones(2000), y))
    assert text.index("0.125") > text.index('"y"')
    bad = text.replace("0.125", token, 1)
    with pytest.raises(gb.GrayboxFileError, match=message):
        gb.from_json(bad)


def test_a_long_matrix_keeps_its_refusals_and_its_literals():
    # a ParetoSet's thetas: ragged rows refused; "nan"/"inf" strings, NaN and Infinity literals (Python's json writes
    # them) and integers read as the numbers they are
    K = 300
    ps = gb.ParetoSet(gb.Structure(["y(k-1)", "u(k-1)"]), np.ones((K, 2)), np.full(K, 0.5), np.zeros(K), np.zeros(K),
                      np.zeros(K))
    doc = json.loads(gb.to_json(ps))
    obj = doc["object"]
    obj["thetas"][7], obj["thetas"][8], obj["thetas"][9] = ["nan", "nan"], [float("nan"), float("nan")], [3, -0.0]
    obj["JS"][7], obj["JS"][8] = "inf", float("inf")
    obj["failures"] = {"7": "no start was feasible", "8": "the solver failed"}
    back = gb.from_json(json.dumps(doc))
    assert np.isnan(back.thetas[7:9]).all() and (back.JS[7:9] == np.inf).all() and np.isfinite(back.JS[10:]).all()
    assert back.thetas[9, 0] == 3.0 and np.signbit(back.thetas[9, 1]) and back.thetas.shape == (K, 2)
    doc["object"]["thetas"][9] = [1.0]
    with pytest.raises(gb.GrayboxFileError, match=r"object\.thetas: rows of different lengths"):
        gb.from_json(json.dumps(doc))
    doc["object"]["thetas"][9] = 1.0
    with pytest.raises(gb.GrayboxFileError, match=r"object\.thetas\[9\]: expected a list, got float"):
        gb.from_json(json.dumps(doc))


def test_long_arrays_in_a_datasets_extra_are_read_in_one_conversion(monkeypatch):
    # a Dataset's extra holding long arrays (noise samples, counts, a mask) was read number by number
    rng = np.random.default_rng(5)
    n = 10**4
    rec = gb.Record(rng.standard_normal(n), rng.standard_normal(n))
    noise = rng.standard_normal(n)
    noise[:3] = [np.nan, -np.inf, -0.0]
    extra = {"noise": noise, "counts": rng.integers(-2**63, 2**63 - 1, n), "mask": rng.random(n) < 0.5,
             "small": rng.standard_normal((n // 10, 10)).astype(np.float32), "bytes": rng.integers(0, 255, n, np.uint8)}
    text = gb.to_json(gb.Dataset(rec, rec, extra=extra))
    per_number = [_counting(monkeypatch, name, _io._Reader) for name in ("float", "int", "bool")]
    back = gb.from_json(text).extra
    monkeypatch.undo()
    assert sum(map(len, per_number)) < 40
    for k, a in extra.items():
        assert back[k].dtype == a.dtype and back[k].shape == a.shape, k
        want = np.where(np.isnan(a), np.nan, a).astype(a.dtype) if a.dtype.kind == "f" else a  # graybox's one NaN
        assert back[k].tobytes() == want.tobytes(), k


@pytest.mark.parametrize("dtype, data, message", [
    ("float32", [0.5, 1e300], r"extra\.a\.array\.data: a value beyond the range of float32"),
    ("float64", [0.5, "x"], r"extra\.a\.array\.data\[1\]: expected a number, got the string 'x'"),
    ("float64", [0.5, True], r"extra\.a\.array\.data\[1\]: expected a number, got bool"),
    ("int64", [1, 2**63], r"extra\.a\.array\.data\[1\]: an integer beyond the 64-bit range"),
    ("int64", [1, 1.0], r"extra\.a\.array\.data\[1\]: expected an integer, got 1\.0"),
    ("int64", [1, True], r"extra\.a\.array\.data\[1\]: expected an integer, got True"),
    ("uint8", [1, 256], r"extra\.a\.array\.data: a value beyond the range of uint8"),
    ("uint8", [1, -1], r"extra\.a\.array\.data: a value beyond the range of uint8"),
    ("bool", [True, 1], r"extra\.a\.array\.data\[1\]: expected true or false, got 1"),
    ("float64", [0.5], r"extra\.a\.array\.shape: shape \[2\] does not hold the 1 values of data"),
])
def test_a_bad_array_in_a_datasets_extra_is_refused_as_it_was(dtype, data, message):
    rec = gb.Record(np.ones(5), np.ones(5))
    doc = json.loads(gb.to_json(gb.Dataset(rec, rec, extra={"a": np.zeros(2)})))
    doc["object"]["extra"]["a"]["array"].update(dtype=dtype, data=data)
    with pytest.raises(gb.GrayboxFileError, match=message):
        gb.from_json(json.dumps(doc))


def test_a_long_record_is_written_in_one_conversion_and_reads_back_the_same(monkeypatch):
    # saving 10**6 samples took ~2.5 s of CPU, ~1 s of it a Python call per number (_num, and a type check of each
    # while laying the file out); a finite array is now turned into JSON's numbers at once, a non-finite one as before
    rng = np.random.default_rng(6)
    n = 10**4
    u = rng.standard_normal((n, 2))
    u[0] = [-0.0, 5e-324]
    rec = gb.Record(u, rng.standard_normal(n))
    per_number = _counting(monkeypatch, "_num", _io)
    text = gb.to_json(rec)
    monkeypatch.undo()
    assert len(per_number) < 10
    back = gb.from_json(text)
    np.testing.assert_array_equal(bits(back.u), bits(u))
    assert '"u": [\n      [-0.0, 5e-324],\n' in text  # a matrix still a row per line
    cost = np.array([1.0, np.inf, -np.inf, np.nan, -0.0])
    ps = gb.ParetoSet(gb.Structure(["y(k-1)"]), np.ones((5, 1)), np.full(5, 0.5), np.zeros(5), np.zeros(5),
                      np.zeros(5), extra={"cost": cost})
    assert '"cost": [1.0, "inf", "-inf", "nan", -0.0]' in gb.to_json(ps)


_JSON_NUMBER = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),  # every finite float64, subnormals and -0.0 too
    st.integers(-2**1023, 2**1023).map(str),  # integers a hand or another tool wrote, beyond 2**53 too
    st.builds(lambda m, e: f"{m}e{e}", st.integers(-10**20, 10**20), st.integers(-340, 290)))  # other spellings
_JSON_SPACE = st.sampled_from(["", " ", "\n", "\t", "\r\n    "])


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(_JSON_NUMBER, _JSON_NUMBER, _JSON_SPACE), min_size=1, max_size=8), st.booleans())
def test_a_hand_written_array_loads_as_float_reads_each_number(cells, matrix):
    # the one-conversion reader (speed60j) against Python's float() of each number's text, for a vector and a
    # two-column matrix laid out with any white space a hand or another tool puts between the numbers
    u = [float(a) for a, _, _ in cells]
    y = [float(b) for _, b, _ in cells]
    assume(all(map(np.isfinite, u + y)))  # past the float range: refused, held by the tests above
    # below it (a number written non-zero that reads as 0.0): refused as well (mend61e), held by the tests above
    assume(all(v != 0 or float(t.split("e")[0]) == 0 for v, t in zip(u + y, [a for a, _, _ in cells] +
                                                                        [b for _, b, _ in cells])))
    text = gb.to_json(gb.Record(np.zeros((len(cells), 2)) if matrix else np.zeros(len(cells)), np.zeros(len(cells))))
    doc = json.loads(text)
    u_text = ",".join(f"{s}[{a},{s}{a}]" if matrix else f"{s}{a}" for a, _, s in cells)
    y_text = ",".join(f"{s}{b}{s}" for _, b, s in cells)
    obj = json.dumps(dict(doc["object"], u="@U", y="@Y")).replace('"@U"', f"[{u_text}]").replace('"@Y"', f"[{y_text}]")
    back = gb.from_json(json.dumps(dict(doc, object="@O")).replace('"@O"', obj))
    np.testing.assert_array_equal(bits(back.y), bits(y))
    np.testing.assert_array_equal(bits(back.u), bits(np.c_[u, u] if matrix else u))


def _model_text(m):
    doc = json.loads(gb.to_json(m))
    return doc, doc["object"]


def test_a_models_equation_that_disagrees_with_its_terms_and_theta_is_refused_naming_both():
    # the equation was written for the reader and ignored on load: a file whose θ was edited (the equation not) or
    # whose equation was edited loaded silently, the reader of the file seeing one model and graybox loading another
    m = gb.Model(gb.Structure(["y(k-1)", "flow(k-1)", "1"]), [0.5, -2.0e-5, 3.25], input_names=("flow",))
    doc, obj = _model_text(m)
    assert obj["equation"] == "y(k) = 0.5 y(k-1) - 2e-05 flow(k-1) + 3.25"
    obj["theta"][0] = 0.7
    with pytest.raises(gb.GrayboxFileError, match=r"object\.equation: the equation 'y\(k\) = 0\.5 y\(k-1\) .*"
                       r"disagrees with the structure and theta, which say 'y\(k\) = 0\.7 y\(k-1\) .*first at term 1"):
        gb.from_json(json.dumps(doc))
    for said in ("y(k) = 0.5 y(k-1) - 2e-05 flow(k-2) + 3.25",  # another term
                 "y(k) = 0.5 y(k-1) + 2e-05 flow(k-1) + 3.25",  # another sign
                 "y(k) = 0.5 y(k-1) - 2e-05 flow(k-1)",  # a term left out
                 "y(k) = 0.5 y(k-1) - 2.00001e-05 flow(k-1) + 3.25",  # beyond θ at the 6 digits written
                 "y(k) = 0.5 y(k-1) - 2e-05 flow(k-1) + 3.2",  # 3.25 to 2 digits: files write 6 ("1" is 1.00000)
                 "not an equation"):
        doc, obj = _model_text(m)
        obj["equation"] = said
        with pytest.raises(gb.GrayboxFileError, match="disagrees with the structure and theta"):
            gb.from_json(json.dumps(doc))
    for said in ("y(k) = 0.500000 y(k-1) - 2.0e-5 flow(k-1) + 3.250000000",  # θ to 6 digits or more
                 "y(k) =   0.5 y(k-1)\n - 2e-05 flow(k-1) + 3.25"):  # spaces as an editor leaves them
        doc, obj = _model_text(m)
        obj["equation"] = said
        assert gb.from_json(json.dumps(doc)).theta.tolist() == [0.5, -2.0e-5, 3.25]
    doc, obj = _model_text(m)
    del obj["equation"]  # a file without it: the model as its terms and θ say
    assert gb.from_json(json.dumps(doc)).theta.tolist() == [0.5, -2.0e-5, 3.25]


@settings(max_examples=8, deadline=None)
@given(theta=st.lists(st.floats(-1e30, 1e30, allow_subnormal=True), min_size=4, max_size=4),
       noise=st.floats(-1.0, 1.0), nudge=st.integers(0, 3))
def test_a_saved_models_equation_agrees_and_an_edited_theta_does_not(theta, noise, nudge):
    m = gb.Model(gb.Structure(["1", "y(k-1)", "u(k-2)y(k-1)", "u(k-1)^2"]), theta,
                 noise_structure=gb.Structure(["e(k-1)"]), noise_theta=[noise])
    doc, obj = _model_text(m)
    assert gb.from_json(json.dumps(doc)).equation(digits=17) == m.equation(digits=17)
    # a change of θ in its 5th significant digit (θ = 1 edited to 1.0001 too): no longer what the equation says
    th = obj["theta"][nudge]
    assume(abs(th) > 1e-300)
    obj["theta"][nudge] = th * (1 + 1e-4)
    with pytest.raises(gb.GrayboxFileError, match=f"first at term {nudge + 1},"):
        gb.from_json(json.dumps(doc))
