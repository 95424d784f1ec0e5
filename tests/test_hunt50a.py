"""hunt50a: a newcomer's first hour (README, docs, notebooks) and one's own CSV files."""

from __future__ import annotations

import codecs

import numpy as np
import pytest

import graybox as gb

TEXT = "t;u;y\n0;1,5;2\n0,5;2;3\n1;2;4\n"


@pytest.mark.parametrize("bom, codec, wrong", [
    (codecs.BOM_UTF16_LE, "utf-16-le", "utf-16-be"),
    (codecs.BOM_UTF16_BE, "utf-16-be", "utf-16-le"),
    (codecs.BOM_UTF32_LE, "utf-32-le", "utf-32-be"),
    (codecs.BOM_UTF32_BE, "utf-32-be", "utf-32-le"),
])
def test_encoding_of_the_other_byte_order_than_the_mark_is_refused(tmp_path, bom, codec, wrong):
    # the docstring: "an encoding that contradicts the file's byte-order mark is an error"; a UTF-16 file with a
    # little-endian mark read as encoding='utf-16-be' was decoded as mojibake ("no column 'u' … ['\ufffe琀㬀…']")
    path = tmp_path / "run.csv"
    path.write_bytes(bom + TEXT.encode(codec))
    with pytest.raises(ValueError, match="byte-order mark") as err:
        gb.load_record_csv(path, u="u", y="y", time="t", encoding=wrong)
    assert ("little-endian" if codec.endswith("le") else "big-endian") in str(err.value)
    # the encoding the mark says, with or without its byte order, reads the file
    for enc in (codec, codec.rsplit("-", 1)[0], None):
        rec = gb.load_record_csv(path, u="u", y="y", time="t", encoding=enc)
        np.testing.assert_array_equal(rec.u, [1.5, 2.0, 2.0])


def test_notebook_06_states_the_input_lags_its_candidates_have():
    # notebook 06 said "Candidates with both inputs (lags 2–3 each, delay=2 …)" above
    # Candidates(ny=2, nu={"u1": 2, "u2": 2}, delay=2, …), whose input lags run from the delay to nu: lag 2 only
    import json
    import re
    from pathlib import Path

    cells = json.loads((Path(__file__).parents[1] / "notebooks" / "06_miso.ipynb").read_text("utf-8"))["cells"]
    i = next(i for i, c in enumerate(cells) if c["cell_type"] == "markdown"
             and "Candidates with both inputs" in "".join(c["source"]))
    text = "".join(cells[i]["source"])
    code = next(c for c in cells[i + 1:] if c["cell_type"] == "code")
    call = next(line for line in code["source"] if line.startswith("candidates = gb.Candidates("))
    space = {}
    exec(call, {"gb": gb}, space)
    lags = sorted({lag for t in space["candidates"].process for name, lag in
                   re.findall(r"(u\d)\(k-(\d+)\)", str(t))})
    said = re.search(r"\(lags? (\d)(?:–(\d))? each", text)
    assert said is not None, text
    claimed = [str(k) for k in range(int(said.group(1)), int(said.group(2) or said.group(1)) + 1)]
    assert claimed == lags, (text, lags)
