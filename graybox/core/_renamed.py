"""Names that changed: the old spelling still works for a while and says the new one (``DeprecationWarning``)."""

from __future__ import annotations

import warnings
from typing import Any

__all__ = ["RenamedAttribute", "renamed_keyword"]


def _say(old: str, new: str, stacklevel: int) -> None:
    warnings.warn(f"{old} is now {new}; the old name will be removed in graybox 0.5", DeprecationWarning,
                  stacklevel=stacklevel + 1)


class RenamedAttribute:
    """A class attribute ``old`` that reads attribute ``new`` and warns: ``inputs = RenamedAttribute("input_names")``."""

    def __init__(self, new: str):
        self.new = new
        self.old = ""
        # what the API pages and help() show for the old name (else this class's docstring, of its mechanics);
        # no colon: the docs read "type: text" from an attribute's first line
        self.__doc__ = f"The old name of ``{new}``, deprecated (reading it warns) and removed in graybox 0.5."

    def __set_name__(self, owner: type, name: str) -> None:
        self.old = name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        _say(f"{type(obj).__name__}.{self.old}", f"{type(obj).__name__}.{self.new}", 2)
        return getattr(obj, self.new)

    def __set__(self, obj: Any, value: Any) -> None:  # read-only (and so a data descriptor, not a method's)
        raise AttributeError(f"{type(obj).__name__}.{self.old} is read-only (and now named {self.new})")


def renamed_keyword(function: str, old: str, new: str, old_value: Any, new_value: Any) -> Any:
    """The value of keyword ``new`` of ``function`` when it may also be given by its old name ``old`` (warned);
    ``TypeError`` when both are given."""
    if old_value is None:
        return new_value
    if new_value is not None:
        raise TypeError(f"{function}: give {new}= only ({old}= is its old name)")
    _say(f"{function}({old}=)", f"{function}({new}=)", 3)
    return old_value
