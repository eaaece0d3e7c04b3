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
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable

from space.store.db_layout import Entry, request_iri

Loader = Callable[[str], Iterable[tuple[int, str]]]
Ids = OrderedDict[int, int]  # hash of a request id's IRI -> seq, in seq order


class _Reading:
    """A space's ids being read from its log, and those committed since it began."""

    def __init__(self, space: str, load: Loader) -> None:
        self.since: list[tuple[int, int]] = []  # (seq, hash) committed meanwhile
        self.cut = 0  # the highest cut made meanwhile
        self.rows: list[tuple[int, int]] | None = None  # None: not read (yet, or it failed)
        self.thread = threading.Thread(
            target=self._read, args=(space, load), name="tspace-request-ids", daemon=True
        )
        self.thread.start()

    def _read(self, space: str, load: Loader) -> None:
        try:
            self.rows = [(seq, hash(iri)) for seq, iri in load(space)]
        except Exception:  # the database went away (closed, reopened): ids stay looked up
            self.rows = None

    def ids(self) -> Ids | None:
        """Return the space's ids once read (None: still reading, or it failed)."""
        if self.thread.is_alive() or self.rows is None:
            return None
        rows = sorted(r for r in (*self.rows, *self.since) if r[0] > self.cut)
        return OrderedDict((h, seq) for seq, h in rows)


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

    def may_hold(self, space: str, request: str) -> bool:
        """Return False if the space's log surely does not hold `request` (True: look it up)."""
        held = self._spaces.get(space)
        if held is None:
            reading = self._reading.get(space)
            if reading is None:
                self._reading[space] = _Reading(space, self._load)
                return True
            held = reading.ids()
            if held is None:
                return True
            self._spaces[space] = held
            del self._reading[space]
        return hash(request_iri(request)) in held

    def known(self, space: str) -> bool:
        """Return whether the space's ids are read, so that a new id skips the log."""
        self.may_hold(space, "")
        return space in self._spaces

    def committed(self, entries: list[Entry]) -> None:
        """Add the request ids of a batch just committed."""
        for e in entries:
            if not e.request:
                continue
            held = self._spaces.get(e.space)
            if held is not None:
                held[hash(request_iri(e.request))] = e.seq
            elif (reading := self._reading.get(e.space)) is not None:
                reading.since.append((e.seq, hash(request_iri(e.request))))

    def cut(self, space: str, cut: int) -> None:
        """Forget the ids of the entries compaction removed (seq <= `cut`)."""
        if (reading := self._reading.get(space)) is not None:
            reading.cut = max(reading.cut, cut)
        held = self._spaces.get(space)
        while held:
            if next(iter(held.values())) > cut:
                return
            held.popitem(last=False)

    def clear(self) -> None:
        """Forget every space (the log was changed otherwise than by commits and cuts).

        Waits for the reads under way: they hold the database open.
        """
        for reading in self._reading.values():
            reading.thread.join()
        self._reading.clear()
        self._spaces.clear()
