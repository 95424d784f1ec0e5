"""Files: save and load graybox values as readable JSON (never pickle)."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_json": ("FORMAT_VERSION", "GrayboxFileError", "from_json", "load", "read_header", "save", "to_json"),
})
