"""The ``graybox`` command."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``graybox`` command; returns the exit status."""
    parser = argparse.ArgumentParser(prog="graybox", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    rp = sub.add_parser("reproduce", help="reproduce the paper's Table I and figures on the bundled plant data")
    rp.add_argument("--quick", action="store_true", help="short searches (minutes, not hours)")
    rp.add_argument("--out", type=Path, default=Path("reproduce-out"), help="folder for figures and tables")
    args = parser.parse_args(argv)
    if args.command == "reproduce":
        from .reproduce import run

        run(quick=args.quick, out=args.out)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
