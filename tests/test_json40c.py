"""gb.save / gb.load for the public values it refused: DecimationAdvice, ResidualTests and CorrelationTest,
DecisionBootstrap (and the GAOptions its options may hold), StaticSurfaceBand, Equilibrium, Structure, Record and Dataset.

Each round-trips field for field (floats bit for bit, NaN and ±inf kept, dtypes kept), a hand-edited file is
refused with a GrayboxFileError naming the field, ``expect=`` holds, and what JSON cannot carry (a function, a
static constraint, a plant simulator, Dask's lazy arrays) is refused when saving, naming why.
"""

import dataclasses
import json
import math
import re
import struct
import subprocess
import sys
import warnings
from collections.abc import Mapping

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import graybox as gb
from graybox.io import _json as _io


def same(a, b, path="value"):
    """Deep equality: the same types all the way down, floats bit for bit, arrays by dtype, shape and bits."""
    assert type(a) is type(b) or (isinstance(a, Mapping) and isinstance(b, Mapping)), \
        f"{path}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, f"{path}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"
        if a.dtype.kind == "f":
            ab, bb = (np.where(np.isnan(x), np.nan, x).astype(np.float64).view(np.int64) for x in (a, b))
            np.testing.assert_array_equal(ab, bb, err_msg=path)
        else:
            np.testing.assert_array_equal(a, b, err_msg=path)
        assert not b.flags.writeable, f"{path}: a loaded array must be read-only"
    elif type(a) in _io._TYPES:
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, np.floating):  # NumPy's own (np.float64 is a float too): its bits at its width
        assert a.tobytes() == b.tobytes() or (np.isnan(a) and np.isnan(b)), path
    elif isinstance(a, float):
        assert struct.pack("<d", a) == struct.pack("<d", b) or (math.isnan(a) and math.isnan(b)), path
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{path}[{i}]")
    elif isinstance(a, Mapping):
        assert list(a) == list(b), path  # the same keys in the same order
        for k in a:
            same(a[k], b[k], f"{path}[{k!r}]")
    else:
        assert a == b, path


def siso(seed=0, N=400):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(750, 1650, N // 10 + 1), 10)[:N]
    m = gb.Model(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"], [0.6, 5e-3, 1e-6, 0.3])
    y = m.simulate(u, np.full(1, 8.0)) + 0.05 * rng.standard_normal(N)
    return gb.Record(u, y, Ts=0.05, name=f"run {seed}", units=("rpm", "mlc")), m


@pytest.fixture(scope="module")
def values():
    rec, m = siso(0)
    valid, _ = siso(1)
    static = gb.StaticPoints(np.linspace(800, 1600, 5), m.static_curve(np.linspace(800, 1600, 5)), uncertainty=0.2,
                             units=("rpm", "mlc"))
    # two inputs, the second held: its four input tests are left out ("undefined"), with a UserWarning
    rng = np.random.default_rng(2)
    u2 = np.column_stack([rng.uniform(0, 1, 300), np.full(300, 2.0)])
    m2 = gb.Model(gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)"]), [0.5, 1.0, 0.1])
    y2 = m2.simulate(u2, np.zeros(1)) + 0.01 * rng.standard_normal(300)
    rec2 = gb.Record(u2, y2, name="two inputs", input_names=("u1", "u2"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tests = gb.residual_tests(m, valid)
        tests_undefined = gb.residual_tests(m2, rec2, rule="pointwise", max_lag=5)
        fit2 = gb.cls(m2.structure, rec2).model  # least squares: ls_uncertainty asks for its optimum
        surface_band = gb.static_surface_band(gb.ls_uncertainty(fit2, rec2), [[0.2, 2.0], [0.8, 2.0]],
                                              method="monte-carlo", n_samples=50)
        boot = gb.bootstrap_decision(m.structure, rec, static, lambdas=[1.0, 0.1, 1e-3], n_boot=3,
                                     options={"solver": "closed", "weights": "sum"})
    ga = gb.GAOptions(population=10, generations=3, stall=2, mutation_scale=1e-3)
    # every kind of plain value an option or a decision may hold, and a failed replicate
    exotic = gb.DecisionBootstrap(
        m.structure, "se", np.array([1.0, 0.5, 5e-324]), (0.0, 0.25), 40, 10, 7, np.array([1.0, np.nan, 0.5]),
        np.array([np.inf, np.nan, 1e-310]), np.array([0.1, np.nan, 5e300]), np.array([True, False, False]),
        np.vstack([[0.6, 5e-3, 1e-6, 0.3], np.full(4, np.nan), [0.5, 4e-3, -0.0, 0.1]]), ("D_SF", "", "min J_SF"),
        {"failure": "ValueError: no member in the band"}, {1: "DivergenceError: the free run diverged"},
        {"options": ga, "starts": (np.array([0.6, 5e-3, 1e-6, 0.3]), np.array([0.5, 0.0, 0.0, 0.0])),
         "margin": float("nan"), "tol": 1e-8, "max_nfev": 20, "method": "gradient", "solver": "inf",
         "theta0": np.arange(4, dtype=np.int32), "flags": np.array([[True, False]]), "empty": np.zeros((0, 3)),
         "progress": None, "solver_options": {"eps": 1e-9, "nested": [1, 2.0, "3", None, -np.inf]},
         "reference": m, "eval_static": static, "warm": np.bool_(True), "count": np.int64(3)},
        static_sigma=0.05)
    eq = gb.equilibria(m.structure, m.theta, 1200.0)[0]
    eq2 = gb.surface_equilibria(m2.structure, m2.theta, [0.3, 2.0])[0]
    data = gb.Dataset(rec, valid, static, "a bench run", {"seed": 2011, "curve": gb.StaticCurve.polynomial([1.0, 2.0]),
                                                          "note": "nan", "level": float("inf"), "repeats": (1, 2)})
    return {"advice": gb.decimation_advice(rec),
            "no advice": gb.DecimationAdvice(None, None, None, None, None, 0.05, "no minimum within a quarter"),
            "residual tests": tests, "residual tests, some undefined": tests_undefined,
            "correlation test": tests["u_xi"], "bootstrap": boot, "bootstrap, exotic": exotic, "ga options": ga,
            "equilibrium": eq, "equilibrium of two inputs": eq2, "structure": gb.Candidates(ny=2, nu=1, degree=2),
            "record": rec, "record of two inputs": rec2, "dataset": data,
            "dataset without static": gb.Dataset(rec2, rec2), "static surface band": surface_band}


NAMES = ["advice", "no advice", "residual tests", "residual tests, some undefined", "correlation test", "bootstrap",
         "bootstrap, exotic", "ga options", "equilibrium", "equilibrium of two inputs", "structure", "record",
         "record of two inputs", "dataset", "dataset without static", "static surface band"]


@pytest.mark.parametrize("name", NAMES)
def test_round_trip(values, name, tmp_path):
    v = values[name]
    p = gb.save(v, tmp_path / "v.json")
    back = gb.load(p)
    same(v, back)
    assert gb.to_json(back) == p.read_text(encoding="utf-8")  # the loaded value writes the same file
    assert gb.read_header(p)["type"] == type(v).__name__
    json.loads(p.read_text(encoding="utf-8"))  # strict JSON: no NaN or Infinity literals


def test_the_fixture_holds_what_the_round_trips_are_meant_to_cover(values):
    # guards against a fixture that silently stops exercising a case
    assert values["advice"].q is not None and values["no advice"].q is None
    assert values["residual tests, some undefined"].undefined and ":" in next(iter(values["residual tests, some undefined"].tests.keys() - {"xi_xi"}))
    assert values["residual tests"].tests["u_xi"].outside.dtype == np.int64
    assert isinstance(values["bootstrap"].band, float) and isinstance(values["bootstrap, exotic"].band, tuple)
    assert values["bootstrap"].reference["theta"].dtype == np.float64
    assert isinstance(values["equilibrium of two inputs"].ubar, tuple)
    assert values["record of two inputs"].u.ndim == 2
    assert values["static surface band"].gain.shape == (2, 2) and values["static surface band"].n_samples == 50


def test_the_header_carries_a_records_units(values, tmp_path):
    assert gb.read_header(gb.save(values["record"], tmp_path / "r.json"))["units"] == ("rpm", "mlc")
    assert gb.read_header(gb.save(values["dataset"], tmp_path / "d.json"))["units"] == ("rpm", "mlc")
    # units= that contradict the record's own would make the header lie about the numbers (hunt 43c): refused
    with pytest.raises(ValueError, match="contradicts the units the Record carries"):
        gb.save(values["record"], tmp_path / "r2.json", units=("%", "bar"))


def test_plain_values_keep_their_type(values):
    back = gb.from_json(gb.to_json(values["bootstrap, exotic"]))
    opts = back.options
    assert isinstance(opts["options"], gb.GAOptions) and opts["options"] == values["ga options"]
    assert opts["solver"] == "inf" and isinstance(opts["solver"], str)  # text is never read as a number
    assert math.isnan(opts["margin"]) and type(opts["max_nfev"]) is int and type(opts["tol"]) is float
    assert opts["theta0"].dtype == np.int32 and opts["flags"].dtype == np.bool_ and opts["empty"].shape == (0, 3)
    assert isinstance(opts["reference"], gb.Model) and isinstance(opts["eval_static"], gb.StaticPoints)
    assert isinstance(opts["starts"], tuple) and opts["starts"][1].tolist() == [0.5, 0.0, 0.0, 0.0]
    assert back.reference == {"failure": "ValueError: no member in the band"} and back.failures == {1: values[
        "bootstrap, exotic"].failures[1]}
    # what the result computes from them agrees
    assert back.agreement == values["bootstrap"].agreement or np.isnan(back.agreement)
    assert back.to_frame().equals(values["bootstrap, exotic"].to_frame())


def test_derived_results_of_a_loaded_value_agree(values):
    for name in ("residual tests", "residual tests, some undefined"):
        t, back = values[name], gb.from_json(gb.to_json(values[name]))
        assert back.passed == t.passed and back.failed == t.failed and back.to_frame().equals(t.to_frame())
    b = gb.from_json(gb.to_json(values["bootstrap"]))
    assert b.frequencies().equals(values["bootstrap"].frequencies()) and b.agreement == values["bootstrap"].agreement
    a = gb.from_json(gb.to_json(values["advice"]))
    assert a.Ts_new == values["advice"].Ts_new and repr(a) == repr(values["advice"])


@pytest.mark.parametrize("name", NAMES)
def test_expect(values, name, tmp_path):
    v = values[name]
    p = gb.save(v, tmp_path / "v.json")
    assert type(gb.load(p, expect=type(v))) is type(v)
    assert type(gb.load(p, expect=(gb.Model, type(v)))) is type(v)
    other = gb.GAOptions if type(v) is not gb.GAOptions else gb.Model
    with pytest.raises(gb.GrayboxFileError, match=f"holds a {type(v).__name__}, expected {other.__name__}"):
        gb.load(p, expect=other)


def _edit(text, path, value):
    doc = json.loads(text)
    node = doc["object"]
    for key in path[:-1]:
        node = node[key]
    if value is _DROP:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return json.dumps(doc)


_DROP = object()

# (value, where in the object, the edited value, what the error must name)
CORRUPT = [
    ("advice", ["q"], "5", r"object\.q: expected an integer"),
    ("advice", ["q_range"], [4], r"object: not a valid DecimationAdvice: .*q_range"),
    ("advice", ["q_range", 0], 4.5, r"object\.q_range\[0\]: expected an integer"),
    ("no advice", ["reason"], _DROP, r"missing field\(s\) \['reason'\] for a DecimationAdvice"),
    ("correlation test", ["lags", 0], 1.5, r"object\.lags\[0\]: expected an integer"),
    ("correlation test", ["passed"], "yes", r"object\.passed: expected true or false"),
    ("residual tests", ["tests", "u_xi", "phi"], "0.1", r"object\.tests\.u_xi\.phi: expected a list"),
    ("residual tests", ["tests", "xi_xi", "extra"], 1, r"object\.tests\.xi_xi: unknown field\(s\) \['extra'\]"),
    ("residual tests, some undefined", ["undefined", "u_xi:u2"], 3, r"object\.undefined\.u_xi:u2: expected a string"),
    ("residual tests", ["residuals", 0, 3], "x", r"object\.residuals\[0\]\[3\]: expected a number"),
    ("bootstrap", ["in_band", 1], 1, r"object\.in_band\[1\]: expected true or false"),
    ("bootstrap", ["band"], [0.1, 0.2, 0.3], r"object\.band: expected a number or a pair"),
    ("bootstrap", ["reference", "theta", "array", "shape"], [7], r"object\.reference\.theta\.array\.shape: shape \[7\]"),
    ("bootstrap", ["reference", "theta", "array", "dtype"], "object", r"object\.reference\.theta\.array\.dtype: unknown dtype"),
    ("bootstrap", ["options", "solver"], ["closed"], r"object\.options\.solver: a bare list"),
    ("bootstrap", ["options", "solver"], {"pickle": "x"}, r"object\.options\.solver: expected a value or an object of one key"),
    ("bootstrap", ["failures", "x"], "why", r"object\.failures\.x: a member index must be an integer"),
    ("bootstrap, exotic", ["options", "options", "type", "object", "population"], 2,
     r"object\.options\.options\.type\.object: not a valid GAOptions: .*population"),
    ("bootstrap, exotic", ["options", "margin", "float"], 1.5, r"object\.options\.margin\.float: a finite number"),
    ("bootstrap, exotic", ["thetas", 0], [1.0], r"object\.thetas: rows of different lengths"),
    ("ga options", ["stall"], "2", r"object\.stall: expected an integer"),
    ("equilibrium", ["ubar"], "1200", r"object\.ubar: expected a number, got the string '1200'"),
    ("equilibrium of two inputs", ["ubar", 1], None, r"object\.ubar\[1\]: expected a number"),
    ("structure", ["terms", 1], "y(k-1", r"object\.terms: cannot parse term 'y\(k-1'"),
    ("record", ["units", 0], 1, r"object\.units\[0\]: expected a string"),
    ("record", ["y"], [1.0, 2.0], r"object: not a valid Record: .*same length"),
    ("dataset", ["extra", "repeats"], [1, 2], r"object\.extra\.repeats: a bare list"),
    ("dataset", ["valid", "Ts"], "0.05", r"object\.valid\.Ts: expected a number"),
    ("static surface band", ["gain", 1], [0.1], r"object\.gain: rows of different lengths"),
    ("static surface band", ["input_names"], ["u1"], r"object: not a valid StaticSurfaceBand: ubar must have shape"),
]


@pytest.mark.parametrize("name, path, value, message", CORRUPT, ids=[f"{c[0]}-{'.'.join(map(str, c[1]))}" for c in CORRUPT])
def test_a_hand_edited_file_is_refused_naming_the_field(values, name, path, value, message, tmp_path):
    p = tmp_path / "edited.json"
    p.write_text(_edit(gb.to_json(values[name]), path, value), encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match=message) as info:
        gb.load(p)
    assert str(p) in str(info.value)


def test_what_json_cannot_carry_is_refused_when_saving_saying_why(values, tmp_path):
    boot = values["bootstrap"]
    with pytest.raises(ValueError, match=r"DecisionBootstrap\.options\['constraints'\]\[0\]: a PassesThrough, a static "
                                         r"constraint.*Python function"):
        gb.to_json(dataclasses.replace(boot, options={"constraints": [gb.PassesThrough()]}))
    with pytest.raises(ValueError, match=r"DecisionBootstrap\.options\['callback'\]: a function \(.*lambda.*\), which "
                                         r"JSON cannot carry"):
        gb.to_json(dataclasses.replace(boot, options={"callback": lambda k: k}))
    with pytest.raises(ValueError, match=r"Dataset\.extra\['plant'\]: a PumpingPlant, which graybox does not save"):
        gb.save(gb.load_pumping(), tmp_path / "pumping.json")
    assert not (tmp_path / "pumping.json").exists()  # nothing half-written
    data = values["dataset"]
    with pytest.raises(ValueError, match=r"Dataset\.extra\['big'\]: the integer 18446744073709551616 is beyond the 64-bit"):
        gb.to_json(dataclasses.replace(data, extra={"big": 2**64}))
    with pytest.raises(ValueError, match=r"Dataset\.extra\['nested'\]: its keys must be text, got 1"):
        gb.to_json(dataclasses.replace(data, extra={"nested": {1: "one"}}))
    with pytest.raises(ValueError, match=r"Dataset\.extra\['c'\]: an array of dtype complex128"):
        gb.to_json(dataclasses.replace(data, extra={"c": np.ones(2, complex)}))
    with pytest.raises(ValueError, match=r"cannot save a UserConstraint, a static constraint.*UserConstraint's fn"):
        gb.to_json(gb.UserConstraint(lambda theta: theta[0], name="mine"))
    with pytest.raises(ValueError, match=r"cannot save a function"):
        gb.to_json(np.sin)


def test_a_dask_record_is_refused_saying_its_arrays_are_lazy():
    da = pytest.importorskip("dask.array")
    with pytest.raises(ValueError, match=r"cannot save a DaskRecord, whose u and y are lazy Dask arrays"):
        gb.to_json(gb.DaskRecord(da.ones(20, chunks=10), da.ones(20, chunks=10), Ts=0.1))


def test_a_saved_decimation_advice_loads_in_a_new_session(values, tmp_path):
    # DecimationAdvice registers itself from the datasets layer (above io): a fresh session that has not
    # imported it yet must still find it from the file's type
    p = gb.save(values["advice"], tmp_path / "advice.json")
    code = "import sys, graybox as gb; a = gb.load(sys.argv[1]); print(type(a).__name__, a.q, a.q_range)"
    out = subprocess.run([sys.executable, "-c", code, str(p)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    a = values["advice"]
    assert out.stdout.split() == ["DecimationAdvice", str(a.q), f"({a.q_range[0]},", f"{a.q_range[1]})"]


def test_every_saved_type_is_listed_in_the_docs():
    import graybox.datasets._decimation  # noqa: F401  (registers DecimationAdvice)
    import graybox.experiments._select  # noqa: F401  (registers GrayboxSelection)
    from pathlib import Path

    module_doc = " ".join(_io.__doc__.split())
    for name in _io._CODECS:
        assert f"graybox.{name}`" in module_doc, name
        for f in (gb.save, gb.to_json):
            obj_line = next(line for line in f.__doc__.splitlines() if line.strip().startswith("obj :"))
            assert re.search(rf"\b{name}\b", obj_line), (f.__name__, name)
    guide = " ".join((Path(__file__).parents[1] / "docs" / "guide" / "trust.md").read_text(encoding="utf-8").split())
    for name in _io._CODECS:
        assert f"`{name}`" in guide, name


_SHORT = gb.Record([1.0, 2.0, 3.0], [0.5, 0.25, 0.125], name="short")

# plain values: what a bootstrap's options and a Dataset's extra may hold, each read back as the type it was
_scalars = (st.none() | st.booleans() | st.integers(-2**63, 2**63 - 1) | st.floats(width=64) | st.text(max_size=5)
            | st.sampled_from(["nan", "inf", "-inf", "1.0"]) | st.floats(width=64).map(np.float64)
            | st.floats(width=32).map(np.float32) | st.integers(-2**63, 2**63 - 1).map(np.int64)
            | st.booleans().map(np.bool_))
_arrays = st.builds(lambda xs, dt: np.array(xs, dtype=dt), st.lists(st.floats(width=32), max_size=4),
                    st.sampled_from(["float64", "float32"])) | \
    st.builds(lambda xs: np.array(xs, dtype=np.int64), st.lists(st.integers(-2**63, 2**63 - 1), max_size=4))
_plain = st.recursive(_scalars | _arrays, lambda inner: st.lists(inner, max_size=3) | st.tuples(inner, inner)
                      | st.dictionaries(st.text(max_size=4), inner, max_size=3), max_leaves=10)


@settings(max_examples=150, deadline=None)
@given(extra=st.dictionaries(st.text(max_size=6), _plain, max_size=4))
def test_plain_values_round_trip(extra):
    data = gb.Dataset(_SHORT, _SHORT, extra=extra)
    back = gb.from_json(gb.to_json(data))
    same(data.extra, back.extra, "extra")

