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


# Data may be positional (the structure, the records, the static information); every option is
# keyword-only, so a call never depends on the order of options.
_DATA_ARGS = {"curve", "static", "data", "record", "records", "u", "y0", "ubar", "structure", "thetas", "theta", "model",
              "candidates", "points", "pareto", "path", "obj", "text", "terms", "surface"}


def _all_public_functions():
    mods = [gb, gb.experiments, gb.plots, gb.datasets]
    for mod in mods:
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if inspect.isfunction(obj):
                yield f"{mod.__name__}.{name}", obj


@pytest.mark.parametrize("name,fn", list(_all_public_functions()))
def test_options_are_keyword_only(name, fn):
    bad = [p.name for p in inspect.signature(fn).parameters.values()
           if p.kind == p.POSITIONAL_OR_KEYWORD and p.default is not p.empty and p.name not in _DATA_ARGS]
    assert not bad, f"{name}: options {bad} can be given by position; make them keyword-only"
