"""Reproduce the paper's results (Table I, the static analysis, the figures): ``graybox reproduce``.

Each section is a function returning text (and, where it makes pictures, writing them
under ``out``); :func:`run` strings them together. The CLI's ``graybox reproduce``
calls :func:`run`. ``quick`` mode shortens only the expensive searches, never the
definitions of the numbers. Everything that exists only to reproduce the paper lives in this
package; the estimators never import it.
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path
from typing import Callable, TextIO

from ..core._files import folder_now
from ._black_box import PAPER_BLACK_BOX, black_box_models, section_black_box
from ._neural import PAPER_NEURAL_ROW, section_neural
from ._paper_models import section_reference_models
from ._table1 import section_table1

__all__ = ["run", "SECTIONS", "section_reference_models", "section_black_box", "section_neural",
           "section_table1", "black_box_models", "PAPER_BLACK_BOX", "PAPER_NEURAL_ROW"]

#: The sections of ``graybox reproduce``, in order.
SECTIONS: tuple[Callable[..., str], ...] = (section_reference_models, section_black_box, section_neural,
                                            section_table1)


def _writable_folder(out: Path) -> None:
    """Create ``out`` if missing and check that files can be written in it, before any section runs (a
    section would otherwise fail at its first figure)."""
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out} is a file, not a folder for the figures and checkpoints")
    try:
        out.mkdir(parents=True, exist_ok=True)
        folder_now(out)  # a file made and gone there: what the figures and checkpoints will do
    except OSError as exc:
        raise type(exc)(f"cannot write in the folder {out}: {exc.strerror or exc}") from None


def _unreadable_because(path: Path) -> str:
    """Why a file under a checkpoint's name is no checkpoint: what reading it raised (its mode, a torn or foreign
    file), or that it holds no sweep's metadata (another function's archive)."""
    from ..estimation._simulation_error import NPZ_ERRORS, read_npz

    try:
        read_npz(path)
    except NPZ_ERRORS as exc:
        return str(exc)
    return "it holds no SE sweep's metadata"


def run(quick: bool = True, out: Path | None = None, stream: TextIO | None = None, fresh: bool = False) -> None:
    """Run every section in order, printing each as it finishes.

    The SE sweeps of Table I keep checkpoints under ``out`` (``se_<method>_l<degree>_margin<margin>[_<starts>][_quick].npz``, e.g. ``se_ga_l2_margin0.01_pe.npz``)
    and resume from them: a second run in the same folder, or a run after a kill, skips the λ1
    values already done. Each checkpoint resumed is named in the output; one written by another
    graybox version is named too, and its sweep starts over (its algorithm may have changed).

    Parameters
    ----------
    quick : bool
        Shorter searches (10 λ for the SE fronts instead of 100).
    out : path, optional
        Folder for the figures and the SE checkpoints (created if missing).
    stream : text file, optional
        Where the text goes (default: the standard output at the time of the call, ``sys.stdout``).
    fresh : bool
        Delete this mode's checkpoints under ``out`` first, so every sweep starts over.
    """
    from ..core._validation import check_bool, check_path
    from ..core._version import graybox_version
    from ..estimation._simulation_error import CheckpointError, checkpoint_version
    from ._table1 import checkpoint_paths

    # flags checked first: "no" is truthy, and fresh deletes checkpoints of hours of sweeps
    quick, fresh = check_bool(quick, "quick"), check_bool(fresh, "fresh")
    if stream is None:  # looked up now, not at import: redirect_stdout and notebooks replace it
        stream = sys.stdout
    elif not callable(getattr(stream, "write", None)):  # said now, not after the first section's minutes
        raise TypeError(f"stream must be a text file (with a write method), e.g. sys.stdout or open(path, 'w'), got "
                        f"{stream!r} ({type(stream).__name__})")
    try:  # a binary or closed file has a write method too, and failed at the first print, after a section's work
        stream.write("")
    except TypeError as exc:
        raise TypeError(f"stream must be a text file, e.g. sys.stdout or open(path, 'w'), got one that takes no str "
                        f"({exc})") from None
    except ValueError as exc:
        raise ValueError(f"stream cannot be written ({exc}); pass an open text file") from None

    if out is not None:
        out = check_path(out, "out")  # '~/figs' the home folder's, as check_path reads it
        if not os.fspath(out):  # Path("") is the current folder, a folder nobody named
            raise ValueError("out is empty: give the folder's name ('.' for the current folder)")
        _writable_folder(Path(out))
        found = [c for c in checkpoint_paths(out, quick) if c.exists()]
        if fresh:
            for c in found:
                c.unlink()
            if found:
                print(f"--fresh: deleted {len(found)} checkpoint(s): {', '.join(c.name for c in found)}",
                      file=stream, flush=True)
        elif found:
            this = graybox_version()
            versions = {c: checkpoint_version(c) for c in found}
            unreadable = [c for c, v in versions.items() if v is None]
            if unreadable:  # said now: Table I's sweep refuses it, after the other sections have run and drawn
                raise CheckpointError(f"checkpoint {unreadable[0]} is not a readable SE checkpoint "
                                      f"({_unreadable_because(unreadable[0])}); delete it or choose another out folder")
            stale = {c: v for c, v in versions.items() if v is not None and v != this}
            if len(stale) < len(found):
                print(f"resuming from {len(found) - len(stale)} checkpoint(s) in {out}: "
                      f"{', '.join(c.name for c in found if c not in stale)} (--fresh starts over)", file=stream,
                      flush=True)
            if stale:
                print(f"starting over {len(stale)} checkpoint(s) of another graybox version (this is {this}): "
                      + ", ".join(f"{c.name} ({v or 'no version recorded'})" for c, v in stale.items()), file=stream,
                      flush=True)
    said: set[str] = set()
    for sec in SECTIONS:
        # warnings raised inside a section are facts about the bundled data (e.g. static points
        # beyond the records' range), not something the reader can act on: each is said once,
        # as a note under the section that first met it
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            text = sec(quick=quick, out=out)
        notes = []
        for w in caught:
            msg = f"{w.category.__name__}: {w.message}"
            if msg not in said:
                said.add(msg)
                notes.append(f"note: {msg}")
        print("\n".join([text] + notes), file=stream, flush=True)
        print(file=stream)
