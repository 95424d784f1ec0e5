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
