"""Progress bars that appear on a terminal and stay out of piped logs."""

from __future__ import annotations

import sys

from tqdm import tqdm

from ._validation import _is_bool

__all__ = ["progress_bar", "show_progress"]


def show_progress(progress: bool | None) -> bool:
    """Whether to draw a bar: ``True``/``False`` as asked; ``None`` (the default) on a terminal only.

    ``graybox reproduce > log.txt`` then writes no carriage-return lines into the log.
    """
    if progress is None:
        try:
            return bool(sys.stderr.isatty())
        except (AttributeError, ValueError):
            return False
    if not _is_bool(progress):  # a wrong type, as check_bool says it
        raise TypeError(f"progress must be True, False or None (on a terminal), got {progress!r} "
                        f"({type(progress).__name__})")
    return bool(progress)


def progress_bar(total: int, desc: str, progress: bool | None, initial: int = 0) -> tqdm:
    """A tqdm bar on standard error, disabled unless :func:`show_progress` says so."""
    return tqdm(total=total, initial=initial, desc=desc, disable=not show_progress(progress), leave=False,
                file=sys.stderr)
