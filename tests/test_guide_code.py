"""The user guide's code blocks run as written (docs/guide/*.md, and the site's front page docs/index.md): a line that
cannot run is caught here."""

import re
import warnings
from pathlib import Path

import pytest
from _once import keep_selections

import graybox as gb

GUIDE = Path(__file__).resolve().parent.parent / "docs" / "guide"
# the front page's example (FROLS, ELS, the evaluation table) was run by no test: 1.4 s of CPU
PAGES = [*sorted(p for p in GUIDE.glob("*.md") if "```python" in p.read_text(encoding="utf-8")),
         GUIDE.parent / "index.md"]


def test_the_guide_has_code_to_run():
    assert {p.name for p in PAGES} >= {"black_box.md", "gray_box.md", "selection.md", "index.md"}


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_python_block_of_a_page_runs(page, monkeypatch):
    keep_selections(monkeypatch)  # selection.md's first calls are the README's: test_readme_api takes their results
    blocks = re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"), flags=re.S | re.M)
    assert blocks
    namespace: dict = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for i, code in enumerate(blocks):
            exec(compile(code, f"{page.name} block {i + 1}", "exec"), namespace)
    # the only warnings a page may raise are the ones it explains: the selection call's summary
    # of a row whose fit warned (selection.md says so)
    explained = "structure × estimator rows warned"
    assert all(w.category is gb.SelectionWarning and explained in str(w.message) for w in caught), \
        [str(w.message) for w in caught]
