"""Regression tests for the items mended by mend51f."""
from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest


def test_check_lambdas_beyond_float_range_is_named():
    from graybox.core._validation import check_lambdas
    with pytest.raises(ValueError, match="beyond the float range"):
        check_lambdas([Decimal("1e400")])
    with pytest.raises(ValueError, match="beyond the float range"):
        check_lambdas([0.5, 10**400])
    assert check_lambdas([Decimal("0.5")]).tolist() == [0.5]


def test_section_docstrings_say_out_is_created():
    from graybox.reproduce import section_neural, section_table1
    for fn in (section_table1, section_neural):
        assert "created if missing" in " ".join(fn.__doc__.split()), fn.__name__


@pytest.mark.parametrize("path", ["graybox/plots/_control.py", "graybox/diagnostics/_simulation_band.py"])
def test_no_unused_validation_imports(path):
    import ast
    from pathlib import Path
    src = (Path(__file__).resolve().parents[1] / path).read_text(encoding="utf-8")
    tree = ast.parse(src)
    imported = {a.asname or a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                and (n.module or "").endswith("_validation") for a in n.names}
    used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    assert imported - used == set()


def test_local_model_repr_tells_close_points_apart():
    import graybox as gb
    from graybox.core._reprs import exact_text
    assert exact_text(10000.01) == "10000.01" and exact_text(1000.0) == "1000" and exact_text(0.5) == "0.5"
    model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.4, 0.05])
    a, b = gb.local_model(model, 10000.01, Ts=1.0), gb.local_model(model, 10000.02, Ts=1.0)
    assert "10000.01" in repr(a) and "10000.02" in repr(b)
    assert repr(a) != repr(b)
