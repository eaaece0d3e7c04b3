"""`tspace write`: write (and/or remove) the triples of Turtle documents as one changeset."""

from __future__ import annotations

import argparse
import sys

from space.cli.options import add_connect, open_space
from space.errors import InputError, UsageError

ORDER = 30


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `write` sub-command."""
    p = sub.add_parser(
        "write",
        help="write a Turtle document into the space",
        description="Write the triples of a Turtle document (- for stdin) as one changeset; "
        "with --remove, remove those of another in the same changeset. Prints the changeset id; "
        "each added triple the store did not apply (a functional property holding a newer value) "
        "is printed on stderr with its reason, and with --strict makes the exit code 1.",
    )
    p.add_argument("file", nargs="?", metavar="FILE|-", help="Turtle document to add")
    p.add_argument("--remove", metavar="FILE|-", help="Turtle document whose triples to remove")
    p.add_argument("--strict", action="store_true", help="exit 1 when some triple was not applied")
    p.add_argument(
        "--lifespan",
        type=_lifespan,
        metavar="DURATION",
        help="retract the added triples after DURATION (500ms, 5s, 2m, 1h) unless written "
        "again; default: permanent",
    )
    add_connect(p)
    p.set_defaults(func=run)


def _lifespan(text: str) -> float:
    from space.lifespan import check_lifespan

    try:
        return check_lifespan(text) or 0.0
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def run(args: argparse.Namespace) -> int:
    """Parse the documents, then send one changeset and wait for the store."""
    from space.turtle import read_turtle

    if args.file is None and args.remove is None:
        raise UsageError("give a FILE to add and/or --remove FILE")
    added = read_turtle(args.file) if args.file else None
    removed = read_turtle(args.remove) if args.remove else None
    with open_space(args, agent="tspace-write") as ts:
        cs = ts.changeset(
            added if added is not None else (),
            removed if removed is not None else (),
            lifespan=args.lifespan or 0,
        )
        ack = ts.send(cs, timeout=args.timeout, strict=False)
        print(ack, file=sys.stdout)
    for dropped in ack.dropped:
        s, p, o = (term.n3() for term in dropped.triple)
        print(f"tspace: not applied: {s} {p} {o} .: {dropped.reason}", file=sys.stderr)
    return 1 if ack.dropped and args.strict else 0
