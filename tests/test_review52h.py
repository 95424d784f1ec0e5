"""review52h: mend52c's and hunt52f's changes (stored specs, leaderboard bands, CSV loaders, spec encodings)."""

from __future__ import annotations

import pytest

import graybox as gb
from graybox import experiments as gx


def test_a_utf8_spec_with_a_byte_order_mark_and_a_bad_byte_names_the_line(tmp_path):
    # e79b063 named a spec with a byte-order mark by its mark's encoding: a UTF-8 mark (Notepad's "UTF-8 with BOM")
    # before a cp1252 byte read "it is UTF-8 text (its byte-order mark says so), and TOML is UTF-8: save it as
    # UTF-8", a file said to be what it must be, and no line
    p = tmp_path / "g.toml"
    p.write_bytes(b'\xef\xbb\xbfname = "g"\n# caf\xe9\n[[data]]\nname = "pumping"\nbundled = "pumping"\n')
    with pytest.raises(gx.SpecError) as info:
        gx.Grid.from_toml(p)
    assert "line 2" in str(info.value) and "not UTF-8" in str(info.value) and "byte 19" in str(info.value)
    # the bad byte first on its line: utf-8-sig counts bytes from after the mark, which the line was counted in
    p.write_bytes(b'\xef\xbb\xbfname = "g"\n\xe9\n')
    with pytest.raises(gx.SpecError, match=r"line 2\b.*byte 14\b"):
        gx.Grid.from_toml(p)
    # a UTF-16 spec (Notepad's "Unicode") is still named as such
    p.write_bytes('name = "g"\n'.encode("utf-16"))
    with pytest.raises(gx.SpecError, match="UTF-16"):
        gx.Grid.from_toml(p)


_PUMPING = '''name = "p"
[[data]]
name = "pumping"
bundled = "pumping"
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]
[[variants]]
name = "PE band"
estimator = "pe"
lambdas = {logspace = [-3, 0, 3]}
constraints = [{type = "band"}]
'''


def test_the_html_report_says_the_unit_of_the_leaderboards_band_column(tmp_path):
    # 1435944 gave the leaderboard a 'band' column, B in the output's unit squared as JS_valid, JS_ident and JSF,
    # which the report's page names the unit of: the page said theirs and not the new column's
    gx.run_grid(gx.Grid.from_toml_text(_PUMPING), tmp_path / "r.sqlite")
    written = {p.name: p for p in gx.write_report(tmp_path / "r.sqlite", tmp_path / "rep", html=True)}
    lb = gx.leaderboard(gb.load_results(tmp_path / "r.sqlite"))
    assert "band" in lb.columns and (lb["band"] == 0.175 ** 2).all()
    page = written["report.html"].read_text("utf-8")
    said = page[page.index("are in the output&#x27;s unit squared") - 400:page.index("are in the output&#x27;s unit squared")]
    assert "band" in said
