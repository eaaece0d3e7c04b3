"""Stream a big Turtle document into a space: Oxigraph's parser, several changesets in flight.

`tspace write` sends a document under 1 MB, or any with `--atomic`, as ONE
changeset: all of it is applied or none, up to the store's 100,000 triples. A
bigger one goes this way: Oxigraph's streaming Turtle parser reads it once to
check all of it (a malformed document sends nothing) and to count it, then
again to send it as changesets of `CHUNK` triples, `WINDOW` of them in flight,
as N-Triples texts (no rdflib term is made). Each changeset is applied
atomically; the document is not: if the run stops half way (the store refused
a changeset, it could not be reached), the changesets acknowledged before stay
written, and running it again completes it (a triple already there changes
nothing).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterator
from itertools import islice
from pathlib import Path

import pyoxigraph as ox

from space._request import Pending
from space.ack import Ack
from space.cli.write import CHUNK
from space.client import TripleSpace
from space.errors import InputError

WINDOW = 4  # changesets in flight
MAX_PREFIXES = 256  # the store's limit for one changeset
PROGRESS_EVERY = 1.0  # seconds between progress lines


def check(source: str) -> tuple[int, dict[str, str]]:
    """Parse a whole document; return its number of triples and its prefixes.

    Raises:
        InputError: the file cannot be read or is not Turtle (naming line and column).
    """
    parser = _parser(source)
    try:
        count = sum(1 for _ in parser)
    except SyntaxError as exc:
        raise InputError(f"{source}: bad Turtle: {exc}") from exc
    except OSError as exc:
        raise InputError(f"{source}: {exc.strerror or exc}") from exc
    return count, dict(parser.prefixes)


def send(
    ts: TripleSpace,
    source: str,
    total: int,
    prefixes: dict[str, str],
    *,
    lifespan: float | None,
    timeout: float,
    say: Callable[[str], None],
) -> list[Ack]:
    """Send a checked document (`check`) as changesets, pipelined; return their acks in order.

    `lifespan`: of every triple (None: permanent); `timeout` applies to each
    changeset. Says its progress about once a second.

    Raises:
        what `TripleSpace.send` raises, for the first changeset that fails; those
        acknowledged before it are written.
    """
    acks: list[Ack] = []
    in_flight: deque[tuple[str, Pending, int]] = deque()
    written = 0
    started = shown = time.monotonic()
    first = dict(list(prefixes.items())[:MAX_PREFIXES])
    for chunk in _chunks(source):
        ident, pending = ts.send_rows_later(
            chunk, prefixes=first, lifespan=lifespan, timeout=timeout
        )
        first = {}
        in_flight.append((ident, pending, len(chunk)))
        while len(in_flight) >= WINDOW:
            written += _settle(in_flight, acks)
        if time.monotonic() - shown >= PROGRESS_EVERY:
            shown = time.monotonic()
            say(_progress(written, total, shown - started))
    while in_flight:
        written += _settle(in_flight, acks)
    took = time.monotonic() - started
    say(
        f"{_progress(written, total, took)}: {len(acks)} changesets in {took:.1f} s; "
        "each was applied whole, the document as a whole is not atomic (--atomic)"
    )
    return acks


def _settle(in_flight: deque[tuple[str, Pending, int]], acks: list[Ack]) -> int:
    ident, pending, size = in_flight.popleft()
    acks.append(Ack.of(ident, pending.result()))
    return size


def _progress(written: int, total: int, seconds: float) -> str:
    share = f" ({100 * written / total:.0f}%)" if total else ""
    rate = f", {written / seconds:,.0f} triples/s" if seconds > 0 else ""
    return f"{written:,} of {total:,} triples written{share}{rate}"


def _chunks(source: str) -> Iterator[list[list[str]]]:
    """Yield the document's triples as lists of `[s, p, o]` N-Triples texts, CHUNK at a time."""
    parser = _parser(source)
    while True:
        # Subject and predicate hold no space in N-Triples, so two splits find the three.
        chunk = [str(q.triple).split(" ", 2) for q in islice(parser, CHUNK)]
        if not chunk:
            return
        yield chunk


def _parser(source: str) -> ox.QuadParser:
    return ox.parse(
        path=source, format=ox.RdfFormat.TURTLE, base_iri=Path(source).resolve().as_uri()
    )
