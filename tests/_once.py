"""A selection two tests make with equal arguments, made once in a pytest process.

The selection guide's first block (test_guide_code, selection.md) and the README's selection example
(test_readme_api) both call ``select_graybox(Candidates(ny=6, nu=6, degree=2), load_pumping())`` and again with
``band=np.inf``: the gray-box call alone is ~12 s of CPU, and both tests run in one pytest (tests/conftest.py,
BESIDE), the guide's first. The guide's test makes its calls as before (:func:`keep_selections`: its warnings are
checked as they come); the README's test (:func:`reuse_selections`) takes the result of a kept call whose arguments
are equal by content (the call is deterministic, its result immutable) and makes any other call itself. Its
assertions read the choice and the table's size, not the table's warnings column (the guide's call kept its rows'
warnings, under the README test's "ignore" they would be empty). Run alone, or in another order, it calls as before."""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Mapping

import numpy as np

#: Each kept result by its arguments' key, beside the arguments: held, no id hashed in a key is another object's later
_KEPT: dict[str, tuple[object, object]] = {}


def _fingerprint(obj, h) -> None:
    """Feed ``obj``'s content to the hash ``h``: arrays by dtype, shape and bytes, dataclasses field by field."""
    if isinstance(obj, np.ndarray):
        h.update(f"array {obj.dtype.str} {obj.shape}".encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(type(obj).__qualname__.encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _fingerprint(getattr(obj, f.name), h)
    elif isinstance(obj, (list, tuple)):
        h.update(f"{type(obj).__name__} {len(obj)}".encode())
        for x in obj:
            _fingerprint(x, h)
    elif isinstance(obj, Mapping):  # a dict, or a FrozenMap (a Dataset's extra): by content, as a dict
        h.update(f"mapping {len(obj)}".encode())
        for k in sorted(obj, key=repr):
            h.update(repr(k).encode())
            _fingerprint(obj[k], h)
    elif obj is None or isinstance(obj, (bool, int, float, complex, str, bytes)):
        h.update(f"{type(obj).__name__} {obj!r}".encode())
    else:  # anything else is not known to be equal by content: never shared (its id, the object held in _KEPT)
        h.update(f"{type(obj).__qualname__} {id(obj)}".encode())


def _key(args, kwargs) -> str:
    h = hashlib.sha256()
    _fingerprint((args, kwargs), h)
    return h.hexdigest()


def keep_selections(monkeypatch) -> None:
    """Have ``graybox.select_graybox`` run as always and keep each result by its arguments' content."""
    import graybox as gb

    real = gb.select_graybox

    def keep(*args, **kwargs):
        result = real(*args, **kwargs)
        _KEPT[_key(args, kwargs)] = (result, (args, kwargs))
        return result

    monkeypatch.setattr(gb, "select_graybox", keep)


def reuse_selections(monkeypatch) -> None:
    """Have ``graybox.select_graybox`` return a kept result of equal arguments, or run as always."""
    import graybox as gb

    real = gb.select_graybox

    def reuse(*args, **kwargs):
        key = _key(args, kwargs)
        return _KEPT[key][0] if key in _KEPT else real(*args, **kwargs)

    monkeypatch.setattr(gb, "select_graybox", reuse)
