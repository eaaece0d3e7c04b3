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
at most the `log_keep` entries the log does. A space's ids are read from the
log the first time they are asked for (~0.1 s at 100,000 entries).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Iterable

from space.store.db_layout import Entry, request_iri

Loader = Callable[[str], Iterable[tuple[int, str]]]


class RequestIds:
    """Per space, the hashes of the request-id IRIs its log holds; the writer's thread only.

    Args:
        load: returns a space's logged `(seq, request-id IRI)` pairs, read from the database.
    """

    def __init__(self, load: Loader) -> None:
        self._load = load
        self._spaces: dict[str, OrderedDict[int, int]] = {}  # hash -> seq, in seq order

    def may_hold(self, space: str, request: str) -> bool:
        """Return False if the space's log surely does not hold `request` (True: look it up)."""
        held = self._spaces.get(space)
        if held is None:
            rows = sorted((seq, hash(iri)) for seq, iri in self._load(space))
            held = self._spaces[space] = OrderedDict((h, seq) for seq, h in rows)
        return hash(request_iri(request)) in held

    def committed(self, entries: list[Entry]) -> None:
        """Add the request ids of a batch just committed (to the spaces already read)."""
        for e in entries:
            held = self._spaces.get(e.space)
            if held is not None and e.request:
                held[hash(request_iri(e.request))] = e.seq

    def cut(self, space: str, cut: int) -> None:
        """Forget the ids of the entries compaction removed (seq <= `cut`)."""
        held = self._spaces.get(space)
        while held:
            seq = next(iter(held.values()))
            if seq > cut:
                return
            held.popitem(last=False)

    def clear(self) -> None:
        """Forget every space (the log was changed otherwise than by commits and cuts)."""
        self._spaces.clear()
