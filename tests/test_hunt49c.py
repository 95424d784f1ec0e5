"""hunt49c: the command line and the public surface (graybox._cli, graybox, graybox._api) against their promises."""

from __future__ import annotations

import numpy as np
import pytest

import graybox as gb


@pytest.fixture
def csv_files(tmp_path):
    rec = tmp_path / "run.csv"
    rec.write_text("t,u,y\n0,1,2\n1,2,3\n2,3,4\n3,4,5\n", encoding="utf-8")
    static = tmp_path / "points.csv"
    static.write_text("u,y\n1,2\n2,3\n3,4\n", encoding="utf-8")
    return rec, static


@pytest.mark.parametrize("name", [0, {}, [], False, np.ones((2, 2)), 5])
def test_the_csv_loaders_refuse_a_name_that_is_not_text(csv_files, name):
    """A falsy name (0, {}, []) fell back to the file's stem without a word, and an array raised numpy's
    "truth value of an array is ambiguous"; a name is a str, as Record's own."""
    rec, static = csv_files
    with pytest.raises(TypeError, match="name"):
        gb.load_record_csv(rec, u="u", y="y", time="t", name=name)
    with pytest.raises(TypeError, match="name"):
        gb.load_static_csv(static, u="u", y="y", name=name)


def test_the_csv_loaders_name_by_the_file_without_a_name(csv_files):
    rec, static = csv_files
    assert gb.load_record_csv(rec, u="u", y="y", time="t").name == "run"
    assert gb.load_static_csv(static, u="u", y="y").name == "points"
    assert gb.load_record_csv(rec, u="u", y="y", time="t", name="a").name == "a"
    assert gb.load_static_csv(static, u="u", y="y", name="b").name == "b"
