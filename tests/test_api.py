"""Conformance of the public API: every exported name is documented, every argument too."""

import inspect

import pytest

import graybox as gb


def _public():
    for name in gb.__all__:
        obj = getattr(gb, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield name, obj


@pytest.mark.parametrize("name,obj", list(_public()))
def test_documented(name, obj):
    assert obj.__doc__ and obj.__doc__.strip(), f"{name} has no docstring"


@pytest.mark.parametrize("name,obj", [(n, o) for n, o in _public() if inspect.isfunction(o)])
def test_every_argument_documented(name, obj):
    doc = obj.__doc__ or ""
    missing = [
        p for p in inspect.signature(obj).parameters.values()
        if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name not in doc
    ]
    assert not missing, f"{name}: arguments not in the docstring: {[p.name for p in missing]}"


def test_all_names_exist():
    for name in gb.__all__:
        assert hasattr(gb, name), name
