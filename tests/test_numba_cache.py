"""Every compiled kernel is cached on disk (issue 25): a new process loads it instead of compiling."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "graybox"
_COMPILERS = {"njit", "jit", "vectorize", "guvectorize", "cfunc", "generated_jit"}


def _compiled_functions():
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if not any(name in text for name in _COMPILERS):  # a decorator's name is in its file's text: no need to parse
            continue
        for node in ast.walk(ast.parse(text)):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for deco in node.decorator_list:
                call = deco if isinstance(deco, ast.Call) else None
                target = call.func if call else deco
                name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
                if name in _COMPILERS:
                    yield f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {node.name}", call


def test_every_numba_kernel_is_cached():
    found = list(_compiled_functions())
    assert len(found) > 30  # the kernels are where they were looked for
    uncached = [where for where, call in found
                if call is None or not any(k.arg == "cache" and isinstance(k.value, ast.Constant) and k.value.value is True
                                           for k in call.keywords)]
    assert not uncached, f"compiled without cache=True (each new process would compile them again): {uncached}"

