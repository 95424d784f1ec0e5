"""hunt50b: saving and loading (graybox.io and every result's JSON), and the files they write."""

import os
import stat
import sys

import numpy as np
import pytest

import graybox as gb


def _model():
    return gb.Model(structure=["y(k-1)", "u(k-1)"], theta=[0.5, 0.1], name="m", units=("rpm", "mlc"))


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_save_to_a_pipe_writes_into_it_and_keeps_it_a_pipe(tmp_path):
    # write_atomically moved a file of its own over whatever the path named: a named pipe (or, for root, the
    # character device os.devnull itself: gb.save(m, os.devnull) left /dev/null a regular file holding the model)
    fifo = tmp_path / "out.json"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # a reader waiting on the pipe, as a shell's would
    try:
        gb.save(_model(), fifo)
        assert stat.S_ISFIFO(os.stat(fifo).st_mode)
        got = os.read(reader, 1 << 16).decode("utf-8")
    finally:
        os.close(reader)
    assert gb.from_json(got).theta.tolist() == [0.5, 0.1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]  # nothing of the write left beside it


@pytest.mark.parametrize("number", ["1e400", "-1e400", "1.5e309"])
def test_a_float_beyond_the_float_range_is_refused_as_an_integer_is(number):
    # JSON's 1e400 was read as inf: a hand-written finite number loaded as an infinite one (a modulus of inf, a
    # diverged member's J_S), where the integer 10**400 was refused as "a number beyond the float range"
    text = gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=True, spectral_radius=0.5))
    assert '"spectral_radius": 0.5' in text
    with pytest.raises(gb.GrayboxFileError, match="beyond the float range"):
        gb.from_json(text.replace('"spectral_radius": 0.5', f'"spectral_radius": {number}'), source="eq.json")
    with pytest.raises(gb.GrayboxFileError, match="beyond the float range"):
        gb.from_json(text.replace('"ybar": 2.0', f'"ybar": {number}'))


def test_numbers_at_the_float_range_still_load():
    text = gb.to_json(gb.Equilibrium(ubar=1.0, ybar=2.0, stable=True, spectral_radius=0.5))
    big = gb.from_json(text.replace('"ybar": 2.0', '"ybar": 1.7976931348623157e308'))
    assert big.ybar == sys.float_info.max
    tiny = gb.from_json(text.replace('"ybar": 2.0', '"ybar": 1e-400'))  # below the subnormals: zero, as written
    assert tiny.ybar == 0.0
