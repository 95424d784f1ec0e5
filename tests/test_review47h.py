"""Review 47h: the bug hunts 47a (plots and reports) and 47c (a newcomer's first hour)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import graybox as gb


def _front(jsf) -> gb.ParetoSet:
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    return gb.ParetoSet(s, np.array([[0.9, 0.01, 0.1]] * 3), np.array([0.01, 0.1, 1.0]), np.ones(3),
                        np.array([1.0, 2.0, 3.0]), np.asarray(jsf, float), method="PE")


@pytest.mark.parametrize("log", [True, False])
def test_plot_pareto_keeps_its_range_for_a_band_among_the_members(log):
    # a302fff brought a band below every member into the panel, but also zoomed out for a band already inside it:
    # J_SF 100.2 … 100.8 and B = 100.4 drew the members in a sliver of a panel from 0 (linear) or 33 (log)
    from graybox.plots import plot_pareto

    ps = _front([100.8, 100.5, 100.2])
    bare = plot_pareto(ps, log=log).axes[0].get_ylim()
    lo, hi = plot_pareto(ps, band=100.4, log=log).axes[0].get_ylim()
    assert lo == pytest.approx(bare[0]) and hi == pytest.approx(bare[1])
    lo, hi = plot_pareto(ps, band=10.0, log=log).axes[0].get_ylim()  # below every member: still brought in
    assert lo < 10.0 and hi >= 100.8


@pytest.fixture(scope="module")
def boot():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.bootstrap_decision(gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]),
                                     gb.load_pumping(), n_boot=4, lambdas=np.logspace(-3, 0, 4))


def test_plot_decision_bootstrap_keeps_its_range_for_a_band_among_the_replicates(boot):
    # 4f68da7 lowered the panel's bottom to B/3 for any band from 0, also one whose top lies among the replicates
    from graybox.plots import plot_decision_bootstrap

    jsf = boot.JSF[boot.ok]
    top = float(np.max(jsf)) * 10  # above every replicate: the range the replicates give
    bare = plot_decision_bootstrap(dataclasses.replace(boot, band=top)).axes[1].get_ylim()
    inside = float(np.median(jsf))
    lo, _ = plot_decision_bootstrap(dataclasses.replace(boot, band=inside)).axes[1].get_ylim()
    assert lo == pytest.approx(bare[0])
    low = float(np.min(jsf)) / 100  # below every replicate: still brought in
    assert plot_decision_bootstrap(dataclasses.replace(boot, band=low)).axes[1].get_ylim()[0] < low


def _refused_write(tmp_path, monkeypatch, *, owner_writes: bool, other_user: bool) -> str:
    # tests run as root, which may write anything: os.access is answered as for a user without write permission,
    # and os.geteuid as for another user than the file's owner where asked
    import os
    import stat

    path = gb.save(gb.Structure(["y(k-1)"]), tmp_path / "m.json")
    path.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH | (stat.S_IWUSR if owner_writes else 0))
    real_access, owner = os.access, os.stat(path).st_uid
    monkeypatch.setattr(os, "access", lambda p, mode, *a, **k: False if (os.fspath(p) == os.fspath(path)
                                                                         and mode & os.W_OK) else real_access(p, mode))
    if other_user:
        monkeypatch.setattr(os, "geteuid", lambda: owner + 1)
    with pytest.raises(PermissionError) as exc:
        gb.save(gb.Structure(["y(k-2)"]), path)
    assert str(gb.load(path)) == str(gb.Structure(["y(k-1)"]))
    return str(exc.value)


@pytest.mark.skipif(not hasattr(__import__("os"), "geteuid"), reason="POSIX owners")
def test_a_file_of_another_user_is_not_called_read_only(tmp_path, monkeypatch):
    # f2d9c69 said of every file it may not write "the file is read-only (its mode forbids writing): make it writable
    # (chmod u+w)": of a colleague's file (mode 0644, theirs) that is false, and chmod u+w fails for the caller
    said = _refused_write(tmp_path, monkeypatch, owner_writes=True, other_user=True)
    assert "another user" in said and "chmod" not in said
    monkeypatch.undo()
    said = _refused_write(tmp_path, monkeypatch, owner_writes=False, other_user=False)  # the caller's own, 0444
    assert "read-only" in said and "chmod u+w" in said


def test_a_writable_mode_refused_is_not_called_read_only(tmp_path, monkeypatch):
    # the caller's own file, mode 0644, that os.access still refuses (a read-only mount, an ACL, an immutable flag):
    # "its mode forbids writing" and chmod u+w were both wrong
    said = _refused_write(tmp_path, monkeypatch, owner_writes=True, other_user=False)
    assert "its mode forbids" not in said and "chmod" not in said


@pytest.mark.parametrize("order", ["le", "be"])
def test_utf16_without_a_mark_read_as_utf8_is_said_utf16(tmp_path, order):
    # 9aaa5cf guessed UTF-16 only without encoding=: with encoding='utf-8' given, a UTF-16 file without its
    # byte-order mark was "line 1 holds NUL bytes ... a data logger's file padded with zeros ... cut the file before
    # line 1", advice for another file
    t = np.arange(30) * 0.1
    text = "t,u,y\n" + "".join(f"{a:.1f},{np.sin(a):.6f},{np.cos(a):.6f}\n" for a in t)
    path = tmp_path / "run.csv"
    path.write_bytes(text.encode(f"utf-16-{order}"))
    with pytest.raises(ValueError, match=f"UTF-16 .*encoding='utf-16-{order}'"):
        gb.load_record_csv(path, time="t", u="u", y="y", encoding="utf-8")


def test_a_dataset_without_static_points_is_not_said_to_carry_them(tmp_path):
    # 64cb215's hint for load(path, expect=StaticPoints) of a saved Dataset was "a Dataset carries a StaticPoints:
    # ... take its .static" also for a Dataset without static points, whose .static is None
    rec = gb.Record(np.arange(10.0), np.arange(10.0), Ts=0.1)
    path = gb.save(gb.Dataset(rec, rec), tmp_path / "d.json")
    with pytest.raises(gb.GrayboxFileError) as exc:
        gb.load(path, expect=gb.StaticPoints)
    assert "holds a Dataset, expected StaticPoints" in str(exc.value) and ".static" not in str(exc.value)
    sp = gb.StaticPoints([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    path = gb.save(gb.Dataset(rec, rec, sp), tmp_path / "s.json")
    with pytest.raises(gb.GrayboxFileError, match=r"take its \.static"):
        gb.load(path, expect=gb.StaticPoints)


def test_many_repeated_static_measurements_keep_the_repeats_advice(tmp_path):
    # 2cc141b told a file with 20 or more lines at one level only that it "looks like a dynamic record" and to read it
    # with load_record_csv: a static test logging 25 settled readings per level was steered away from repeats="mean",
    # which reads it
    rng = np.random.default_rng(1)
    levels = np.repeat([800.0, 1000.0, 1200.0], 25)
    lines = "".join(f"{u:g},{1e-4 * u ** 2 + rng.normal(0, 0.01):.5f}\n" for u in levels)
    path = tmp_path / "static.csv"
    path.write_text("u,y\n" + lines, encoding="utf-8")
    with pytest.raises(ValueError, match=r"dynamic record.*repeats=\"mean\""):
        gb.load_static_csv(path, u="u", y="y")
    assert gb.load_static_csv(path, u="u", y="y", repeats="mean").ubar.tolist() == [800.0, 1000.0, 1200.0]


@pytest.mark.parametrize("Ts", [np.array([0.05]), np.array([[0.05]]), [0.05]])
def test_a_one_element_ts_is_not_called_a_time_column(Ts):
    # 1985832 said of any Ts with a dimension "got 1 values (ndarray): a time column? Pass its step, e.g.
    # Ts=float(np.median(np.diff(t)))": scipy.io.loadmat gives a saved scalar as array([[0.05]]), whose diff is empty
    # (the median of nothing is NaN); one value in an array is taken out with float(Ts)
    with pytest.raises(TypeError, match=r"Ts .*one value.*float\(Ts\)") as exc:
        gb.Record(np.arange(10.0), np.arange(10.0), Ts=Ts)
    assert "time column" not in str(exc.value)


@pytest.mark.parametrize("eol", ["\n", "\r\n"])
def test_a_file_padded_with_zeros_after_whole_lines_reads_its_lines(tmp_path, eol):
    # 9aaa5cf refused every NUL byte, "a data logger's file padded with zeros ... Delete them": a logger's preallocated
    # file whose written part ends with a whole line holds all its samples, and the zeros after it no text to read.
    # A file cut off inside a line (a torn last sample before the zeros) is still refused.
    t = np.arange(300) * 0.1
    text = "t,u,y" + eol + "".join(f"{a:.1f},{np.sin(a):.6f},{np.cos(a):.6f}{eol}" for a in t)
    plain, padded, torn = tmp_path / "plain.csv", tmp_path / "padded.csv", tmp_path / "torn.csv"
    plain.write_bytes(text.encode())
    padded.write_bytes(text.encode() + b"\x00" * 8192)
    torn.write_bytes(text.encode()[:-7] + b"\x00" * 8192)
    ref = gb.load_record_csv(plain, time="t", u="u", y="y")
    rec = gb.load_record_csv(padded, time="t", u="u", y="y")
    assert rec.Ts == ref.Ts and np.array_equal(rec.u, ref.u) and np.array_equal(rec.y, ref.y)
    with pytest.raises(ValueError, match="NUL bytes"):
        gb.load_record_csv(torn, time="t", u="u", y="y")
    static = tmp_path / "static.csv"
    static.write_bytes(b"u,y\n800,1.1\n1000,1.6\n1200,2.3\n" + b"\x00" * 100)
    assert gb.load_static_csv(static, u="u", y="y").ubar.tolist() == [800.0, 1000.0, 1200.0]


@pytest.mark.parametrize("text", [
    "1.0e+00,2.0e+00,3.0e+00\n4.0e+00,5.0e+00,6.0e+00\n",  # np.savetxt's default: no header, a number first
    '"t","u","y"\n0,1,2\n1,1,3\n',  # R's write.csv: the header's names quoted
    "-1,2\n3,4\n",
])
def test_load_of_a_csv_that_starts_like_a_json_value_is_not_a_corrupt_file(tmp_path, text):
    # cd87d7d named a CSV given to load only when JSON could read nothing of it: a file starting with a number or a
    # quoted name is read by json as a value followed by "Extra data", and was still 'JSON: corrupt file (Extra data
    # at line 1, column 25)'. A graybox file is a JSON object: a text not starting with '{' is none.
    path = tmp_path / "run.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(gb.GrayboxFileError, match="not a graybox file.*load_record_csv"):
        gb.load(path)
    path.write_text('{"format": "graybox", "format_version": 1,\n', encoding="utf-8")  # a torn graybox file
    with pytest.raises(gb.GrayboxFileError, match="corrupt file"):
        gb.load(path)
