"""Claims of the docs, notebooks and docstrings that had stopped holding (hunt39c)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _code(path: Path) -> str:
    nb = json.loads(path.read_text(encoding="utf-8"))
    return "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")


def _variant_calls(code: str) -> list[str]:
    """The source of every ``gx.Variant(...)`` call, parentheses balanced."""
    calls = []
    for m in re.finditer(r"gx\.Variant\(", code):
        depth, i = 0, m.end() - 1
        while True:
            depth += {"(": 1, ")": -1}.get(code[i], 0)
            i += 1
            if depth == 0:
                break
        calls.append(code[m.start():i])
    return calls


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_a_variant_named_for_its_reference_model_uses_it(path):
    # Notebook 5's buck grid had a variant "CLS eq.(22), Σ*y from LS" with no reference option: once cls's
    # default became reference="free" it estimated Σy instead, and the prose's figures (2.24 V² on the
    # six-term structure, from the LS reference) no longer described the cells it ran.
    for call in _variant_calls(_code(path)):
        named = re.search(r"Σ\*y from (LS|ELS)\b", call)
        if named:
            ref = {"LS": "ls", "ELS": "els"}[named.group(1)]
            assert re.search(rf"[\"']reference[\"']\s*:\s*[\"']{ref}[\"']", call), call
