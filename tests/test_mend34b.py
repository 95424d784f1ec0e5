"""Mends of batch 34b: CSV files as spreadsheets in other locales write them (thousands separators,
UTF-16 and cp1252 text), SE checkpoints keyed by the graybox version as well as the problem, and
what the residual tests' 95 % bands promise on fresh data."""

from __future__ import annotations

import re

import numpy as np
import pytest

from graybox.datasets import load_record_csv, load_static_csv


# -- 1. CSV files in other locales ---------------------------------------------------------------

@pytest.mark.parametrize("text, line", [
    ("u;y\n1;2.5\n2;1,234.5\n3;4.5\n", 3),             # English grouping, ';' between columns
    ('u,y\n1,2.5\n2,"1,234.5"\n3,4.5\n', 3),           # English Excel's CSV quotes grouped numbers
    ("u;y\n1;2,5\n2;1.234,5\n3;4,5\n", 3),             # German grouping with decimal commas
    ("u;y\n1;1.234,5\n2;2,5\n", 2),
    ("u;y\n1;2,5\n2;1 234,5\n3;4,5\n", 3),             # a space, as French writes it
    ("u;y\n1;2,5\n2;1\u202f234,5\n3;4,5\n", 3),        # a narrow no-break space (French Excel)
    ("u\ty\n1\t2,5\n2\t1\u00a0234,5\n", 3),            # a no-break space
    ("u,y\n1,2.5\n2,1'234.5\n", 3),                    # Swiss grouping
])
def test_a_thousands_separator_is_refused_naming_the_file_column_and_line(tmp_path, text, line):
    # was: refused as "is not a number" without saying why; the message now names the separator
    p = tmp_path / "grouped.csv"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=rf"grouped.csv: line {line}, column 'y': .* is not a number.*thousands "
                                         "separator"):
        load_static_csv(p, u="u", y="y")


@pytest.mark.parametrize("text, mark, as_decimal", [
    ("u;y\n1;1,234\n2;2,345\n3;14,567\n", ",", [1.234, 2.345, 14.567]),
    ('u,y\n1,"1,234"\n2,"2,345"\n', ",", [1.234, 2.345]),  # English Excel's CSV, thousands format
    ("u;y\n1;1.234\n2;-2.345\n", ".", [1.234, -2.345]),    # German Excel, integers with grouping
    ("u\ty\n1\t1.234\n2\t2.345\n", ".", [1.234, 2.345]),
])
def test_decimals_that_may_be_thousands_groups_are_refused_unless_the_mark_is_given(tmp_path, text, mark,
                                                                                      as_decimal):
    # was: read silently as decimals (1,234 -> 1.234), a thousand times too small if the comma
    # grouped thousands, as English Excel writes quoted "1,234"
    p = tmp_path / "groups.csv"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=r"groups.csv: the decimal mark is ambiguous.*line 2, column 'y': '-?1[.,]234'.*"
                                         rf"pass decimal='\{mark}'"):
        load_static_csv(p, u="u", y="y")
    np.testing.assert_array_equal(load_static_csv(p, u="u", y="y", decimal=mark).ybar, as_decimal)
    with pytest.raises(ValueError, match=r"line 2, column 'y'.*thousands separator"):
        load_static_csv(p, u="u", y="y", decimal="." if mark == "," else ",")


def test_one_decimal_that_cannot_be_a_thousands_group_settles_the_mark(tmp_path):
    # 0,125 and 2,5 are decimals in any locale, so 1,234 beside them is one too
    p = tmp_path / "settled.csv"
    p.write_text("u;y\n1;1,234\n2;0,125\n3;2,5\n", encoding="utf-8")
    np.testing.assert_array_equal(load_static_csv(p, u="u", y="y").ybar, [1.234, 0.125, 2.5])


def _table(n: int = 80) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(5)
    return np.arange(n) * 0.5, rng.uniform(30, 60, n).round(2), rng.uniform(20, 90, n).round(4)


def _text(header: str, delimiter: str, decimal: str) -> str:
    t, u, y = _table()
    rows = [delimiter.join(repr(float(v)).replace(".", decimal) for v in row) for row in zip(t, u, y)]
    return "\n".join([delimiter.join(["time", "Leistung %", header])] + rows) + "\n"


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-be", "utf-32"])
def test_unicode_text_with_a_byte_order_mark_is_read(tmp_path, codec):
    # was: "line 1 is not UTF-8 text (byte 0xff)"; Excel's "Unicode text" is UTF-16 with a byte-order
    # mark, tab-separated
    t, u, y = _table()
    p = tmp_path / "unicode.txt"
    bom = {"utf-16-be": b"\xfe\xff"}.get(codec, b"")
    p.write_bytes(bom + _text("Temperatur °C", "\t", ",").encode(codec))
    r = load_record_csv(p, u="Leistung %", y="Temperatur °C", time="time")
    np.testing.assert_array_equal(r.u, u)
    np.testing.assert_array_equal(r.y, y)
    assert r.Ts == 0.5
    s = load_static_csv(p, u="Leistung %", y="Temperatur °C", repeats="mean")
    np.testing.assert_array_equal(np.sort(s.ybar), np.sort(y))


@pytest.mark.parametrize("header", ["Temperatur °C", "Druck µbar"])
@pytest.mark.parametrize("delimiter, decimal", [(";", ","), (",", ".")])
def test_a_cp1252_file_is_named_as_such_and_read_with_its_encoding(tmp_path, header, delimiter, decimal):
    # was: only "save the file as UTF-8"; encoding= now reads Excel's Windows "CSV" as it is
    t, u, y = _table()
    p = tmp_path / "ansi.csv"
    p.write_bytes(_text(header, delimiter, decimal).encode("cp1252"))
    with pytest.raises(ValueError, match=r"ansi.csv: line 1 is not UTF-8 text.*encoding='cp1252'") as info:
        load_record_csv(p, u="Leistung %", y=header, time="time")
    assert info.type is ValueError  # never a UnicodeDecodeError traceback
    r = load_record_csv(p, u="Leistung %", y=header, time="time", encoding="cp1252")
    np.testing.assert_array_equal(r.u, u)
    np.testing.assert_array_equal(r.y, y)
    pts = load_static_csv(p, u="time", y=header, encoding="cp1252")
    np.testing.assert_array_equal(pts.ybar, y)


def test_encoding_faults_are_value_errors_naming_the_encoding(tmp_path):
    p = tmp_path / "late.csv"
    p.write_bytes(("u;y;note\n" + "1;2,5;-\n" * 60 + "2;3,5;20 °C\n").encode("cp1252"))
    with pytest.raises(ValueError, match=r"late.csv: line 62 is not UTF-8 text") as info:
        load_static_csv(p, u="u", y="y", repeats="mean")
    assert info.type is ValueError
    np.testing.assert_array_equal(load_static_csv(p, u="u", y="y", repeats="mean", encoding="cp1252").ybar, [2.5, 3.5])
    with pytest.raises(ValueError, match=r"late.csv: line 62 is not ascii text") as info:
        load_static_csv(p, u="u", y="y", repeats="mean", encoding="ascii")
    assert info.type is ValueError
    with pytest.raises(ValueError, match=r"late.csv: encoding 'klingon' is not a text encoding"):
        load_static_csv(p, u="u", y="y", encoding="klingon")
    with pytest.raises(TypeError, match=r"encoding must name a text encoding"):
        load_static_csv(p, u="u", y="y", encoding=1252)
    q = tmp_path / "bomless.txt"
    q.write_bytes("u\ty\n1\t2,5\n2\t3,5\n".encode("utf-16-le"))
    with pytest.raises(ValueError, match=r"bomless.txt: the file holds NUL bytes.*encoding='utf-16-le'"):
        load_static_csv(q, u="u", y="y")
    np.testing.assert_array_equal(load_static_csv(q, u="u", y="y", encoding="utf-16-le").ybar, [2.5, 3.5])


# -- 2. SE checkpoints of another graybox version ----------------------------------------------

def _se_problem():
    from graybox import Record, StaticPoints
    from graybox.estimation._simulation_error import SEProblem

    rng = np.random.default_rng(3)
    n = 300
    u = np.repeat(rng.uniform(0.0, 2.0, n // 20 + 1), 20)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + 0.1 * u[k - 1] ** 2
    y += 0.01 * rng.standard_normal(n)
    ub = np.array([0.25, 1.0, 1.75])
    static = StaticPoints(ub, (0.3 * ub + 0.1 * ub ** 2) / 0.5 + 0.02)  # a static bias the fit must trade
    return SEProblem(["y(k-1)", "u(k-1)", "u(k-1)^2"], [Record(u, y, Ts=1.0)], static)


def _sweep(method, problem, checkpoint=None):
    from graybox.estimation._simulation_error import GAOptions, ga_front, gradient_front

    lam = [1.0, 0.5, 0.1]
    if method == "ga":
        return ga_front(problem, lam, options=GAOptions(population=20, generations=4), seed=2, checkpoint=checkpoint,
                        progress=False)
    return gradient_front(problem, lam, checkpoint=checkpoint, progress=False)


@pytest.mark.parametrize("method", ["ga", "gradient"])
def test_a_checkpoint_of_another_graybox_version_is_started_over_with_a_warning(tmp_path, monkeypatch, method):
    # was: resumed as if this version had written it, so a front mixed the members of two
    # algorithms; the version now keys the checkpoint as it keys the grid store's cells
    import graybox.estimation._simulation_error as se

    problem = _se_problem()
    fresh = _sweep(method, problem)
    this = se.graybox_version()
    ck = tmp_path / "front.npz"
    # another version whose algorithm differed: its members are not this version's
    inner = "_ga_run" if method == "ga" else "_multistart"
    real = getattr(se, inner)

    def older_algorithm(*args, **kw):
        th, cost, n = real(*args, **kw)
        return th * 1.5, cost, n

    with monkeypatch.context() as m:
        m.setattr(se, "graybox_version", lambda: "0.0.1")
        m.setattr(se, inner, older_algorithm)
        old = _sweep(method, problem, ck)
    assert se.checkpoint_version(ck) == "0.0.1"
    assert not np.array_equal(old.thetas, fresh.thetas)
    with pytest.warns(UserWarning, match=rf"front.npz was written by graybox 0\.0\.1, this is graybox "
                                         rf"{re.escape(this)}.*starts over"):
        again = _sweep(method, problem, ck)
    np.testing.assert_array_equal(again.thetas, fresh.thetas)
    assert se.checkpoint_version(ck) == this
    resumed = _sweep(method, problem, ck)  # this version's own checkpoint resumes, silently
    np.testing.assert_array_equal(resumed.thetas, fresh.thetas)


def test_a_checkpoint_that_records_no_version_is_started_over(tmp_path):
    # checkpoints written before versions were recorded hold no version: they start over too
    import json

    import graybox.estimation._simulation_error as se

    problem = _se_problem()
    ck = tmp_path / "front.npz"
    fresh = _sweep("gradient", problem, ck)
    with np.load(ck) as z:
        kept = {k: z[k] for k in z.files}
    meta = json.loads(str(kept["meta"]))
    del meta["graybox"]
    np.savez(ck, **(kept | {"meta": json.dumps(meta)}))
    assert se.checkpoint_version(ck) == ""
    with pytest.warns(UserWarning, match="written by a graybox that did not record its version"):
        again = _sweep("gradient", problem, ck)
    np.testing.assert_array_equal(again.thetas, fresh.thetas)


def test_reproduce_says_which_checkpoints_it_resumes_and_which_start_over(tmp_path, monkeypatch):
    # was: "resuming from 2 checkpoint(s)" also for checkpoints another graybox version wrote
    import io

    import graybox.estimation._simulation_error as se
    import graybox.reproduce as rp
    from graybox.reproduce._table1 import checkpoint_paths

    monkeypatch.setattr(rp, "SECTIONS", ())
    problem = _se_problem()
    mine, theirs = checkpoint_paths(tmp_path, quick=True)[:2]
    _sweep("gradient", problem, mine)
    with monkeypatch.context() as m:
        m.setattr(se, "graybox_version", lambda: "0.0.1")
        _sweep("gradient", problem, theirs)
    out = io.StringIO()
    rp.run(quick=True, out=tmp_path, stream=out)
    text = out.getvalue()
    assert f"resuming from 1 checkpoint(s) in {tmp_path}: {mine.name} " in text
    assert (f"starting over 1 checkpoint(s) of another graybox version (this is {se.graybox_version()}): "
            f"{theirs.name} (0.0.1)") in text


# -- 3. what the residual tests' 95 % promises --------------------------------------------------

def test_each_residual_test_has_its_stated_size_for_the_true_model():
    # the coordinator saw correct models rejected too often; with the system's own parameters each
    # test fails at most 5 % of records (simultaneous rule), the pointwise rule about 1 − 0.95^K,
    # and .passed, asking all five, up to 25 %: the module docstring now says so (not a bug)
    import graybox as gb

    theta = np.array([0.6, 0.2, 0.3, 0.05, 0.4])
    structure = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]

    def record(seed, n=600):
        rng = np.random.default_rng(seed)
        u, e = rng.uniform(0.0, 2.0, n + 100), 0.03 * rng.standard_normal(n + 100)
        y = np.zeros(n + 100)
        for k in range(2, n + 100):
            y[k] = theta[0] * y[k - 1] + theta[1] * y[k - 2] + theta[2] * u[k - 1] + theta[3] * u[k - 2] ** 2 \
                + theta[4] + e[k]
        return gb.Record(u[100:], y[100:], Ts=1.0)

    truth = gb.els(structure, record(0), noise=0).model.with_theta(theta)
    R = 120
    fails = {rule: np.array([[not t.passed for t in gb.residual_tests(truth, record(s), rule=rule).tests.values()]
                             for s in range(1, R + 1)]) for rule in ("simultaneous", "pointwise")}
    simultaneous = fails["simultaneous"].mean(axis=0)
    se = np.sqrt(0.05 * 0.95 / R)
    assert np.all(simultaneous <= 0.05 + 3 * se), simultaneous
    assert fails["simultaneous"].any(axis=1).mean() <= 0.25 + 3 * np.sqrt(0.25 * 0.75 / R)
    # pointwise: any of K nearly independent lags (white input) outside ±1.96/√N
    K = np.array([t.lags.size for t in gb.residual_tests(truth, record(1)).tests.values()])
    expected = 1 - 0.95 ** K
    pointwise = fails["pointwise"].mean(axis=0)
    assert np.all(np.abs(pointwise - expected) <= 3 * np.sqrt(expected * (1 - expected) / R) + 0.05), (pointwise,
                                                                                                       expected)


def test_a_checkpoint_of_another_problem_is_refused_whichever_version_wrote_it(tmp_path, monkeypatch):
    # was: the version was checked first, so another problem's checkpoint written by another graybox (or
    # by one that did not record its version) was overwritten with a warning, the other run's work lost
    import graybox.estimation._simulation_error as se
    from graybox.estimation._simulation_error import CheckpointError

    problem = _se_problem()
    ck = tmp_path / "front.npz"
    with monkeypatch.context() as m:
        m.setattr(se, "graybox_version", lambda: "0.0.1")
        _sweep("gradient", problem, ck)
    before = ck.read_bytes()
    other = se.SEProblem(problem.structure[:-1], problem.records, problem.static)  # another structure
    with pytest.raises(CheckpointError, match="another problem"):
        _sweep("gradient", other, ck)
    assert ck.read_bytes() == before  # not overwritten
