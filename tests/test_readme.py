"""The README's Python example runs as written."""

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")


def test_readme_example_runs():
    text = (Path(__file__).parents[1] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "README has no python example"
    ns: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), ns)
    table = ns["table"]
    assert list(table.index) == ["ELS", "CLS", "PE", "SE"]
    assert table.loc["SE", "JSF"] <= 0.031 + 1e-12
