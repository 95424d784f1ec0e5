"""Lazy re-export of public names, as SciPy does with a module ``__getattr__``.

A package lists which private module holds each public name; the module is imported on the
first access of one of its names, so ``import graybox`` loads neither numba, cvxpy, pandas nor
matplotlib.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any


def attach(package: str, exports: Mapping[str, Sequence[str]], *, base: str | None = None,
           modules: Sequence[str] = (), present: Sequence[str] = ()
           ) -> tuple[Callable[[str], Any], Callable[[], list[str]], list[str]]:
    """``__getattr__``, ``__dir__`` and ``__all__`` for a package that re-exports lazily.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : mapping of str to sequence of str
        Each module (relative to ``base``, e.g. ``"_terms"``, or a subpackage) and the public
        names it holds.
    base : str, optional
        The package the modules are relative to (default: ``package`` itself).
    modules : sequence of str
        Modules of ``base`` that are themselves public names (``graybox.plots``), loaded on first use.
    present : sequence of str
        Public names the package sets itself (``__version__``): listed by ``__dir__`` and ``__all__``, not loaded.
    """
    base = package if base is None else base
    where: dict[str, str] = {}
    for module, names_there in exports.items():
        for name in names_there:
            if name in where or name in modules or name in present:
                raise RuntimeError(f"{package}: {name} is exported twice ({where.get(name, name)} and {module})")
            where[name] = module
    names = sorted([*where, *modules, *present])

    def __getattr__(name: str) -> Any:
        if name in modules:
            value = importlib.import_module(f"{base}.{name}")
        elif name in where:
            value = getattr(importlib.import_module(f"{base}.{where[name]}"), name)
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        setattr(importlib.import_module(package), name, value)  # later accesses skip this function
        return value

    def __dir__() -> list[str]:
        return names

    return __getattr__, __dir__, names
