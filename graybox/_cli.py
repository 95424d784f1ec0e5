"""The graybox command: reproduce the paper on the bundled data, run grids of experiments."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

__all__ = ["main"]


def _count_arg(words: dict[str, object], what: str):
    """An argparse type: one of ``words`` (to its value) or a count >= 1 (``what`` names it in messages)."""
    def parse(text: str):
        if text in words:
            return words[text]
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {', '.join(map(repr, words))} or {what}, got {text!r}") from None
        if n < 1:
            raise argparse.ArgumentTypeError(f"{what} is >= 1, got {n}")
        return n
    return parse


#: ``--spec``: latest, all, or a spec number
_spec_arg = _count_arg({"latest": "latest", "all": "all"}, "a spec number")
#: ``--max-structures``: a count, or all (None: every structure)
_max_structures_arg = _count_arg({"all": None}, "a number of structures")


def _folder_arg(text: str) -> Path:
    """``--out`` of reproduce and grid report: a folder name, not empty (``Path("")`` is the current folder, which an
    unset shell variable, ``--out "$DIR"``, named without a word)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty folder name; give a folder (e.g. reproduce-out or report; '.' for "
                                         "this one)")
    return Path(text)


def _file_arg(text: str) -> Path:
    """``--store`` of grid run: a file's name (``Path("out/")`` is ``out``: the store was made as a file named as the
    folder meant)."""
    from .core._validation import check_path

    try:
        return Path(check_path(text, "the store", file=True))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _band_arg(text: str) -> tuple[str | None, float]:
    """``--band``: ``B`` (every data set) or ``NAME=B`` (that data set; a name may hold '=': the last one splits)."""
    name, eq, value = text.rpartition("=")
    try:
        return (name if eq else None), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected B or NAME=B (a number), got {text!r}") from None


def _bands(given: list[tuple[str | None, float]] | None) -> float | dict[str, float] | None:
    """The ``--band`` options as write_report's band: None, one number, or data set name -> B."""
    if not given:
        return None
    if any(name is None for name, _ in given):
        if len(given) > 1:
            raise ValueError("--band: give one number for every data set (--band B) or one per data set "
                             "(--band NAME=B, repeated), not both nor two numbers")
        return given[0][1]
    names = [name for name, _ in given]
    if len(set(names)) < len(names):
        raise ValueError(f"--band names {sorted({n for n in names if names.count(n) > 1})} more than once")
    return dict(given)


def _grid(args: argparse.Namespace) -> int:
    from . import experiments as gx
    from .core._validation import check_workers

    if args.grid_command == "init":
        try:
            sys.stdout.write(gx.EXAMPLE_SPEC)
            sys.stdout.flush()  # a full disk (grid init > spec.toml) says so here, not in a traceback at exit
        except BrokenPipeError:
            raise
        except OSError as exc:
            print(f"graybox grid init: {exc}", file=sys.stderr)
            return 2
        return 0
    try:
        if args.grid_command == "run":
            for flag, n in (("--workers", args.workers), ("--processes", args.processes)):
                if n is not None:  # >= 1 and no more than the machine's memory holds (10**20 was handed on)
                    check_workers(n, flag)
            processes = args.processes is not None
            said: set[str] = set()

            def log(line: str) -> None:
                said.add(line.strip())
                print(line, flush=True)

            res = gx.run_grid(args.spec, args.store, executor="processes" if processes else None,
                              workers=args.processes if processes else args.workers, scheduler=args.scheduler,
                              retry_failed=args.retry_failed, cell_time_limit=args.cell_time_limit,
                              **({} if args.worker_timeout is None else {"worker_timeout": args.worker_timeout}), log=log)
            head, *notes = res.summary().splitlines()
            # the notes said at the start are not repeated; those of the end (cells another run wrote meanwhile) are
            print("\n".join([head, *(n for n in notes if n.strip() not in said)]))
            return 0
        if args.grid_command == "status":
            print(gx.grid_status(args.store, spec=args.spec).summary())
            return 0
        store = args.store[0] if len(args.store) == 1 else args.store
        if args.rule == "chosen" and args.band:
            # the ranking is each cell's own choice, which no band of the report changes: --band only draws
            print("graybox grid report: note: --band does not change the ranking under --rule chosen (each cell's "
                  "own choice is ranked as its cell decided it); the figures draw it, and --rule dsf_valid ranks by it",
                  file=sys.stderr)
        written = gx.write_report(store, args.out, rule=args.rule, band=_bands(args.band), spec=args.spec, html=args.html,
                                  max_structures=args.max_structures)
        print(f"wrote {len(written)} files to {args.out}: {', '.join(p.name for p in written)}")
        return 0
    except KeyboardInterrupt:
        if args.grid_command == "run":  # Ctrl-C: every cell finished so far was committed as it came
            print(f"graybox grid run: interrupted; the cells finished so far are kept in {args.store}, and the same "
                  "command runs only the cells left", file=sys.stderr)
        elif args.grid_command == "report":  # the files are written one by one: some may be of this run, some older
            print(f"graybox grid report: interrupted; the files in {args.out} may be incomplete: run the same command "
                  "again", file=sys.stderr)
        else:  # status only reads
            print(f"graybox grid {args.grid_command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        raise
    except (gx.SpecError, gx.StoreError, OSError) as exc:  # OSError: ConnectionError, an --out that is a file, …
        print(f"graybox grid {args.grid_command}: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:  # an argument refused (e.g. --workers 0, a spec number the store lacks)
        if args.grid_command == "init":
            raise
        print(f"graybox grid {args.grid_command}: {exc}", file=sys.stderr)
        return 2


_DESCRIPTION = """\
Black- and gray-box identification of nonlinear dynamic systems with polynomial
NARMAX models (Barbosa, Aguirre, Martinez & Braga, IEEE TCST 2011, and beyond).
The library is used from Python (import graybox as gb); this command reproduces
the paper on the bundled data and runs grids of experiments."""

_EPILOG = """\
examples:
  graybox reproduce --quick                    Table I and figures in reproduce-out/
  graybox grid init > spec.toml                a commented example spec
  graybox grid run spec.toml --store r.sqlite --workers 2
  graybox grid report r.sqlite --out report/   leaderboard, heat maps, fronts

'graybox COMMAND --help' describes each command."""

_REPRODUCE = """\
Reproduce the paper on the bundled plant data: the paper's own models as printed,
the black-box models, the neural baseline and Table I re-estimated, with figures
written to --out (fig2_static_curve.png ... fig8_se_free_run_l3.png, neural_free_run.png;
a --quick run's end in _quick.png, so it leaves a full run's figures alone).

Checkpoints: the simulation-error sweeps of Table I save a checkpoint after each
lambda in --out (se_ga_l2_margin0.01_pe.npz, se_gradient_l3_margin0.01_quick.npz,
...) and a later run in the same folder resumes from them, so an interrupted run
loses little; the run says which checkpoints it resumes. Quick and full runs keep separate files. To
start over, pass --fresh (or delete those .npz files, or choose another --out)."""


def _escape_what_streams_cannot_encode() -> None:
    """Let stdout and stderr write a character their encoding lacks as its escape (``\\u0233``), not raise.

    The command prints ȳ, ū, ρ, λ1, ×: a stream in a narrow code page (Windows gives a redirected command its
    locale's, cp1252: ``graybox reproduce --quick > table.txt``) raised UnicodeEncodeError at the first of them,
    a traceback after the first section's work. UTF streams (any terminal today, a notebook) are left as they are.
    """
    import codecs
    import contextlib

    for stream in (sys.stdout, sys.stderr):
        try:
            utf = codecs.lookup(getattr(stream, "encoding", None) or "utf-8").name.startswith("utf")
        except LookupError:
            utf = False
        if not utf and callable(getattr(stream, "reconfigure", None)):
            with contextlib.suppress(Exception):  # a stream that takes no errors= is left as it is
                stream.reconfigure(errors="backslashreplace")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``graybox`` command; returns the exit status."""
    _escape_what_streams_cannot_encode()
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # Ctrl-C before a command's own handler says what it kept: while it loads (numpy, scipy, matplotlib take
        # a second or two), nothing has started
        print("graybox: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader left (graybox grid init | head): stop quietly, as cat does; stdout goes to the null
        # device so that the flush at exit does not fail on the closed pipe again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(prog="graybox", description=_DESCRIPTION, epilog=_EPILOG,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    from ._api import __version__

    parser.add_argument("--version", action="version", version=f"graybox {__version__}")
    sub = parser.add_subparsers(title="commands", dest="command", required=True, metavar="COMMAND")
    rp = sub.add_parser("reproduce", help="reproduce the paper's Table I and figures on the bundled plant data",
                        description=_REPRODUCE, formatter_class=argparse.RawDescriptionHelpFormatter)
    rp.add_argument("--quick", action="store_true", help="short searches (minutes, not hours)")
    rp.add_argument("--out", type=_folder_arg, default=Path("reproduce-out"),
                    help="folder for the figures (PNG) and the checkpoints; the tables are printed (default: "
                         "reproduce-out)")
    rp.add_argument("--fresh", action="store_true",
                    help="delete this mode's checkpoints in --out first and start every sweep over")
    gp = sub.add_parser("grid", help="grids of structures × constraint variants × estimators, kept in SQLite",
                        description="Grids of data sets × structures × constraint variants × estimators, scored "
                                    "on the validation record and kept in a SQLite store (a killed run resumes).")
    gsub = gp.add_subparsers(title="commands", dest="grid_command", required=True, metavar="COMMAND")
    gsub.add_parser("init", help="print a commented example spec for the bundled plant (graybox grid init > spec.toml)")
    run = gsub.add_parser("run", help="run the cells of a spec that are not in the store yet")
    run.add_argument("spec", type=Path, help="the grid's TOML spec")
    run.add_argument("--store", type=_file_arg, required=True, help="SQLite file for the results (created if missing)")
    where = run.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="start a Dask LocalCluster of N worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask scheduler at this address (e.g. tcp://host:8786)")
    where.add_argument("--processes", type=int, metavar="N", help="run in N local worker processes (no Dask)")
    run.add_argument("--retry-failed", action="store_true", help="run the failed cells again")
    run.add_argument("--cell-time-limit", type=float, metavar="S",
                     help="with --processes, --workers or --scheduler: a cell running longer than S seconds is "
                          "stopped and stored as failed")
    run.add_argument("--worker-timeout", type=float, metavar="S",
                     help="with Dask: end the run (its finished cells kept) once the cluster has had no worker for S "
                          "seconds (default 60)")
    which = {"type": _spec_arg, "default": "latest",
             "help": "which cells: of the spec run last (latest, default), all the store holds, or spec number N"}
    stat = gsub.add_parser("status", help="a store's progress, also while a run writes it: cells done, failed, left, "
                                          "time per cell, the best so far")
    stat.add_argument("store", type=Path, help="the SQLite store of a grid")
    stat.add_argument("--spec", **which)
    rep = gsub.add_parser("report", help="write a store's leaderboard, heat maps and figures (several stores: side "
                                         "by side)")
    rep.add_argument("store", type=Path, nargs="+", help="the SQLite store of a grid; two or more are compared")
    rep.add_argument("--out", type=_folder_arg, required=True, help="folder for the tables (CSV) and figures (PNG)")
    rep.add_argument("--rule", default="dsf_valid", choices=("dsf_valid", "chosen"),
                     help="ranking: D_SF on the validation record over all members (default), or each cell's choice")
    rep.add_argument("--band", type=_band_arg, action="append", metavar="B | NAME=B",
                     help="J_SF band for the ranking: B for every data set, or NAME=B for data set NAME (repeat for "
                          "others; those not named keep theirs); default: each data set's, as stored")
    rep.add_argument("--spec", **which)
    rep.add_argument("--html", action="store_true",
                     help="also write report.html: one self-contained page (figures, tables, spec, reasons)")
    rep.add_argument("--max-structures", type=_max_structures_arg, default=12, metavar="N",
                     help="most structures a data set's figures draw, the best by rank (default 12; 'all': every "
                          "one); the tables keep every structure")
    args = parser.parse_args(argv)
    if args.command == "reproduce":
        from .core._processes import interrupted_by_user
        from .estimation._simulation_error import CheckpointError
        from .reproduce import run as reproduce

        try:
            reproduce(quick=args.quick, out=args.out, fresh=args.fresh)
        except CheckpointError as exc:
            print(f"graybox reproduce: {exc}; or run with --fresh, which starts every sweep of this mode over",
                  file=sys.stderr)
            return 2
        except BrokenPipeError:
            raise
        except OSError as exc:  # --out unusable, a disk full: the environment's, not a bug to trace back
            print(f"graybox reproduce: {exc}", file=sys.stderr)
            return 2
        except BaseException as exc:  # Ctrl-C, also inside a numba kernel (a SystemError it caused)
            if not interrupted_by_user(exc):
                raise
            # the sweeps checkpointed what they finished
            print(f"graybox reproduce: interrupted; the checkpoints in {args.out} are kept, and the same command "
                  "resumes from them", file=sys.stderr)
            return 130
        return 0
    return _grid(args)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
