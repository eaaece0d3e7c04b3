"""The request ids a space's log holds, in memory: a write never seen is known so at once.

Exactly-once writes make the store look every request id up in its log before
deciding (`StoreDB.outcome`). Nearly every id is new, and a lookup that finds
nothing still builds a RocksDB iterator over the memory table and every level:
~40 us a write, 11 % of the store thread's time with the GIL held at 2,000
writes a second (py-spy, `bench/fleet.py`). This keeps, per space, the hash of
every logged request id's IRI, in seq order, so that a new id is answered
"never logged" from a set, and only an id that may be logged (a retry, or a
hash collision) is looked up. It follows the log: ids are added when their
batch commits and forgotten when compaction cuts their entries, so it holds
at most the `log_keep` entries the log does.

A space's ids are read from its log at its first write after the store starts,
on a thread of their own (~1 s at 100,000 entries): until they are, its ids are
looked up in the log as before, and the ids committed meanwhile are kept aside.
A read that fails is tried again `RETRY` seconds later. Memory: ~17 MB per
100,000 ids; past `LIMIT` ids in all, a space's are dropped and it goes back to
lookups until the database is reopened.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterable

from space.store.db_layout import Entry, request_iri

log = logging.getLogger("tspace.store")

Loader = Callable[[str], Iterable[tuple[int, str]]]
Ids = OrderedDict[int, int]  # hash of a request id's IRI -> seq, in seq order

LIMIT = 1_000_000  # ids kept in all spaces (~170 MB); a space beyond it is looked up
RETRY = 10.0  # seconds before a failed read of a space's ids is tried again


class _Reading:
    """A space's ids being read from its log, and those committed since it began."""

    def __init__(self, space: str, load: Loader) -> None:
        self.since: list[tuple[int, int]] = []  # (seq, hash) committed meanwhile
        self.cut = 0  # the highest cut made meanwhile
        self.ids: Ids | None = None  # None: not read (yet, or it failed)
        self.error = ""  # why it failed
        self.thread = threading.Thread(
            target=self._read, args=(space, load), name="tspace-request-ids", daemon=True
        )
        self.thread.start()

    def _read(self, space: str, load: Loader) -> None:
        try:
            rows = sorted((seq, hash(iri)) for seq, iri in load(space))
        except Exception as exc:  # the database went away (closed, reopened): tried again later
            self.error = f"{type(exc).__name__}: {exc}"
            return
        self.ids = OrderedDict((h, seq) for seq, h in rows)

    @property
    def done(self) -> bool:
        """Return whether the read is over (`ids` says how it went)."""
        return not self.thread.is_alive()

    def result(self) -> Ids:
        """Return the space's ids read, with those committed since, without those cut since."""
        assert self.ids is not None
        held = self.ids
        for seq, h in self.since:  # later than every id read: they go at the end
            held[h] = seq
        _cut(held, self.cut)
        return held


def _cut(held: Ids, cut: int) -> None:
    while held and next(iter(held.values())) <= cut:
        held.popitem(last=False)


class RequestIds:
    """Per space, the hashes of the request-id IRIs its log holds; the writer's thread only.

    Args:
        load: yields a space's logged `(seq, request-id IRI)` pairs, read from the database
            (on another thread).
    """

    def __init__(self, load: Loader) -> None:
        self._load = load
        self._spaces: dict[str, Ids] = {}
        self._reading: dict[str, _Reading] = {}
        self._later: dict[str, float] = {}  # space -> when its ids may be read (again)
        self._size = 0  # ids held in all spaces

    def may_hold(self, space: str, request: str) -> bool:
        """Return False if the space's log surely does not hold `request` (True: look it up)."""
        held = self._spaces.get(space)
        if held is None:
            held = self._read(space)
            if held is None:
                return True
        return hash(request_iri(request)) in held

    def known(self, space: str) -> bool:
        """Return whether the space's ids are read, so that a new id skips the log."""
        return space in self._spaces or self._read(space) is not None

    def committed(self, entries: list[Entry]) -> None:
        """Add the request ids of a batch just committed."""
        for e in entries:
            if not e.request:
                continue
            held = self._spaces.get(e.space)
            if held is not None:
                before = len(held)
                held[hash(request_iri(e.request))] = e.seq
                self._size += len(held) - before
                if self._size > LIMIT:
                    self._drop(e.space)
            elif (reading := self._reading.get(e.space)) is not None:
                reading.since.append((e.seq, hash(request_iri(e.request))))

    def cut(self, space: str, cut: int) -> None:
        """Forget the ids of the entries compaction removed (seq <= `cut`)."""
        if (reading := self._reading.get(space)) is not None:
            reading.cut = max(reading.cut, cut)
        held = self._spaces.get(space)
        if held:
            before = len(held)
            _cut(held, cut)
            self._size -= before - len(held)

    def clear(self) -> None:
        """Forget every space (the log was changed otherwise than by commits and cuts).

        Waits for the reads under way: they hold the database open.
        """
        for reading in self._reading.values():
            reading.thread.join()
        self._reading.clear()
        self._spaces.clear()
        self._later.clear()
        self._size = 0

    def _read(self, space: str) -> Ids | None:
        """Start reading a space's ids, or take them once read; None until then."""
        reading = self._reading.get(space)
        if reading is None:
            if time.monotonic() < self._later.get(space, 0.0):
                return None
            self._reading[space] = _Reading(space, self._load)
            return None
        if not reading.done:
            return None
        del self._reading[space]
        if reading.ids is None:
            self._later[space] = time.monotonic() + RETRY
            log.warning(
                "could not read the request ids of %s (%s): looked up, read again in %g s",
                space,
                reading.error,
                RETRY,
            )
            return None
        held = self._spaces[space] = reading.result()
        self._size += len(held)
        if self._size > LIMIT:
            self._drop(space)
            return None
        return held

    def _drop(self, space: str) -> None:
        """Forget a space's ids past `LIMIT` in all: looked up in its log until `clear`."""
        self._size -= len(self._spaces.pop(space))
        self._later[space] = float("inf")
        log.info("request ids of %s looked up in its log: more than %d in all", space, LIMIT)
