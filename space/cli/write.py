"""`tspace write`: write (and/or remove) the triples of Turtle documents as one changeset.

A big document (1 MB and more) is streamed as several changesets instead (`bulk.py`).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import TYPE_CHECKING

from space.cli.options import add_connect, open_space
from space.errors import InputError, UsageError

if TYPE_CHECKING:
    from rdflib import Graph

ORDER = 30
PROGRESS_BYTES = 1_000_000  # documents from this size on are streamed, with progress lines
PROGRESS_TRIPLES = 10_000  # changesets from this size on: the store takes seconds; say so
CHUNK = 10_000  # triples per changeset of a streamed document (bulk.py)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `write` sub-command."""
    p = sub.add_parser(
        "write",
        help="write a Turtle document into the space",
        description="Write the triples of a Turtle document (- for stdin) as one changeset; "
        "with --remove, remove those of another in the same changeset. Prints the changeset id; "
        "each added triple the store did not apply (a functional property holding a newer value) "
        "is printed on stderr with its reason, and with --strict makes the exit code 1. "
        "A document with no triples is an error (nothing is written). A document of 1 MB and "
        "more (without --remove) is checked whole, then sent as changesets of "
        f"{CHUNK:,} triples, several in flight, with progress lines on stderr, and one id per "
        "changeset on stdout: each changeset is applied whole, the document is not (--atomic). "
        "One changeset of 10,000 triples and more gets progress lines too.",
    )
    p.add_argument("file", nargs="?", metavar="FILE|-", help="Turtle document to add")
    p.add_argument("--remove", metavar="FILE|-", help="Turtle document whose triples to remove")
    p.add_argument("--strict", action="store_true", help="exit 1 when some triple was not applied")
    p.add_argument(
        "--atomic",
        action="store_true",
        help="send a big document as one changeset too: all of it or nothing "
        "(at most 100,000 triples, the store's limit)",
    )
    p.add_argument(
        "--lifespan",
        type=_lifespan,
        metavar="DURATION",
        help="retract the added triples after DURATION (500ms, 5s, 2m, 1h) unless written "
        "again; default: permanent",
    )
    add_connect(p, space=None)
    p.set_defaults(func=run)


def _lifespan(text: str) -> float:
    from space.lifespan import check_lifespan

    try:
        return check_lifespan(text) or 0.0
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def run(args: argparse.Namespace) -> int:
    """Parse the documents, then send one changeset and wait for the store."""
    from space.zconfig import make_config

    if args.file is None and args.remove is None:
        raise UsageError("give a FILE to add and/or --remove FILE")
    make_config(connect=args.connect, config_file=args.config)  # a bad endpoint: say it first
    if args.file and args.remove is None and _size(args.file) >= PROGRESS_BYTES:
        if not args.atomic:
            return _stream(args)
        _fits(args.file)
    added = _read(args.file) if args.file else None
    removed = _read(args.remove) if args.remove else None
    for source, graph in ((args.file, added), (args.remove, removed)):
        if graph is not None and not len(graph):
            name = "<stdin>" if source == "-" else source
            raise InputError(f"{name}: no triples in it; nothing written")
    with open_space(args, agent="tspace-write", create=True) as ts:
        cs = ts.changeset(
            added if added is not None else (),
            removed if removed is not None else (),
            lifespan=args.lifespan or 0,
        )
        count = len(cs.added) + len(cs.removed)
        big = count >= PROGRESS_TRIPLES or any(
            _size(source) >= PROGRESS_BYTES for source in (args.file, args.remove)
        )
        started = time.monotonic()
        if big:
            _say(f"sending one changeset of {count} triples…")
        ack = ts.send(cs, timeout=args.timeout, strict=False)
        print(ack, file=sys.stdout)
        if big:
            _say(f"written in {time.monotonic() - started:.1f} s")
    for dropped in ack.dropped:
        s, p, o = (term.n3() for term in dropped.triple)
        print(f"tspace: not applied: {s} {p} {o} .: {dropped.reason}", file=sys.stderr)
    return 1 if ack.dropped and args.strict else 0


def _fits(source: str) -> None:
    """Refuse, before anything is sent, a document too big for one changeset.

    Raises:
        InputError: more triples than a changeset holds, or not Turtle.
    """
    from space.cli import bulk
    from space.errors import InputError
    from space.store.intake import MAX_TRIPLES

    total, _ = bulk.check(source)
    if total > MAX_TRIPLES:
        raise InputError(
            f"{source}: {total:,} triples, and a changeset holds at most {MAX_TRIPLES:,}: "
            "nothing written (without --atomic it is sent as several changesets)"
        )


def _stream(args: argparse.Namespace) -> int:
    """Check a big document whole, then send it as several changesets (`bulk.py`)."""
    from space.cli import bulk
    from space.errors import InputError

    _say(f"checking {args.file} ({_size(args.file) / 1e6:.1f} MB)…")
    started = time.monotonic()
    total, prefixes = bulk.check(args.file)
    if not total:
        raise InputError(f"{args.file}: no triples in it; nothing written")
    _say(f"{total:,} triples in {time.monotonic() - started:.1f} s; sending…")
    with open_space(args, agent="tspace-write", create=True) as ts:
        acks = bulk.send(
            ts,
            args.file,
            total,
            prefixes,
            lifespan=args.lifespan or 0,
            timeout=args.timeout,
            say=_say,
        )
    for ack in acks:
        print(ack, file=sys.stdout)
    dropped = [d for ack in acks for d in ack.dropped]
    for d in dropped:
        s, p, o = (term.n3() for term in d.triple)
        print(f"tspace: not applied: {s} {p} {o} .: {d.reason}", file=sys.stderr)
    return 1 if dropped and args.strict else 0


def _read(source: str) -> Graph:
    """Parse a document, saying what it does on stderr when it is big."""
    from space._turtle import read_turtle

    size = _size(source)
    if size < PROGRESS_BYTES:
        return read_turtle(source)
    _say(f"reading {source} ({size / 1e6:.1f} MB)…")
    started = time.monotonic()
    graph = read_turtle(source)
    _say(f"{len(graph)} triples read in {time.monotonic() - started:.1f} s")
    return graph


def _size(source: str | None) -> int:
    """Return a document's size in bytes (0 for stdin or nothing)."""
    return os.path.getsize(source) if source and source != "-" and os.path.isfile(source) else 0


def _say(line: str) -> None:
    print(f"tspace write: {line}", file=sys.stderr, flush=True)
