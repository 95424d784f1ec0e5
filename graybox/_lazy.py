"""Lazy re-export of public names, as SciPy does with a module ``__getattr__``.

A package lists which private module holds each public name; the module is imported on the
first access of one of its names, so ``import graybox`` loads neither numba, cvxpy, pandas nor
matplotlib.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any


def attach(package: str, exports: Mapping[str, Sequence[str]]) -> tuple[Callable[[str], Any], Callable[[], list[str]],
                                                                          list[str]]:
    """``__getattr__``, ``__dir__`` and ``__all__`` for a package that re-exports lazily.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : mapping of str to sequence of str
        Each private module (relative to the package, e.g. ``"_terms"``, or a subpackage) and
        the public names it holds.
    """
    where = {name: module for module, names in exports.items() for name in names}
    if len(where) != sum(len(v) for v in exports.values()):
        raise RuntimeError(f"{package}: a public name is exported twice")

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(importlib.import_module(package), name, value)  # later accesses skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(where)

    return __getattr__, __dir__, sorted(where)
