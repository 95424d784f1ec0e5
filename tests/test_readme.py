"""The README's Python example runs as written."""

import re
from pathlib import Path

import matplotlib
import pytest

import graybox as gb

matplotlib.use("Agg")


def test_readme_example_runs():
    text = (Path(__file__).parents[1] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "README has no python example"
    ns: dict = {}
    # the bundled plant's static points (750 and 1650 rpm) lie just beyond its identification record,
    # within 5 % of its span: no StaticRangeWarning (warnings are errors in the tests)
    exec(compile(blocks[0], "README.md", "exec"), ns)
    table = ns["table"]
    assert list(table.index) == ["ELS", "CLS", "PE", "SE"]
    assert table.loc["SE", "JSF"] <= 0.031 + 1e-12
