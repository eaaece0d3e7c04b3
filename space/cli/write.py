"""`tspace write`: write (and/or remove) the triples of Turtle documents as one changeset."""

from __future__ import annotations

import argparse
import sys

from space.cli.options import add_connect, open_space
from space.errors import UsageError

ORDER = 30


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `write` sub-command."""
    p = sub.add_parser(
        "write",
        help="write a Turtle document into the space",
        description="Write the triples of a Turtle document (- for stdin) as one changeset; "
        "with --remove, remove those of another in the same changeset. Prints the changeset id.",
    )
    p.add_argument("file", nargs="?", metavar="FILE|-", help="Turtle document to add")
    p.add_argument("--remove", metavar="FILE|-", help="Turtle document whose triples to remove")
    add_connect(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Parse the documents, then send one changeset and wait for the store."""
    from space._turtle import read_turtle

    if args.file is None and args.remove is None:
        raise UsageError("give a FILE to add and/or --remove FILE")
    added = read_turtle(args.file) if args.file else None
    removed = read_turtle(args.remove) if args.remove else None
    with open_space(args, agent="tspace-write") as ts:
        cs = ts.changeset(
            added if added is not None else (), removed if removed is not None else ()
        )
        print(ts.send(cs, timeout=args.timeout), file=sys.stdout)
    return 0
