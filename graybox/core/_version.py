"""This graybox's version: what files, checkpoints and grid stores record of who wrote them."""

from __future__ import annotations

__all__ = ["graybox_version"]


def graybox_version() -> str:
    """The installed package's version (``"0+unknown"`` for a source tree that was never installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("graybox")
    except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
        return "0+unknown"
