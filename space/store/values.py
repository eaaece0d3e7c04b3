"""The objects of (subject, functional property) pairs, remembered between decisions.

Deciding a functional write reads the value it replaces (`StoreDB.objects`).
A value rewritten at every reading leaves RocksDB a tombstone for each old
value under that pair until a compaction reaches them, and a scan of the pair
steps over all of them: 9 us for a fresh pair, 30-1,250 us (often ~250) once
64 robots had rewritten theirs a few thousand times, with the store's flushes
running. So the pairs read are kept here, and each commit updates the ones it
changes: a decision reads the database once per pair, not once per reading.
"""

from __future__ import annotations

from space.store import oxterms
from space.store.db_layout import Entry
from space.store.oxterms import OxTerm

LIMIT = 100_000  # pairs remembered at most (then forgotten all at once, and read again)

Pair = tuple[OxTerm, OxTerm]


class Values:
    """Per space, the asserted objects of the (s, p) pairs read; writer thread only."""

    def __init__(self) -> None:
        self._spaces: dict[str, dict[Pair, tuple[OxTerm, ...]]] = {}
        self._predicates: dict[str, set[str]] = {}  # N-Triples of the predicates remembered
        self._size = 0

    def get(self, space: str, s: OxTerm, p: OxTerm) -> tuple[OxTerm, ...] | None:
        """Return the objects remembered for (s, p), or None if not remembered."""
        pairs = self._spaces.get(space)
        return None if pairs is None else pairs.get((s, p))

    def put(self, space: str, s: OxTerm, p: OxTerm, objects: tuple[OxTerm, ...]) -> None:
        """Remember what the database holds for (s, p) now."""
        if self._size >= LIMIT:
            self.clear()
        self._spaces.setdefault(space, {})[(s, p)] = objects
        self._predicates.setdefault(space, set()).add(oxterms.text(p))
        self._size += 1

    def committed(self, entries: list[Entry]) -> None:
        """Apply what a successful commit changed to the pairs remembered."""
        for e in entries:
            pairs = self._spaces.get(e.space)
            if not pairs:
                continue
            if e.plain:  # texts: a plain write names no functional property, but be sure
                remembered = self._predicates[e.space]
                if any(row[1] in remembered for row in e.plain):
                    self._forget(e.space)
                    continue
            for s, p, o in e.removed:
                held = pairs.get((s, p))
                if held is not None:
                    pairs[(s, p)] = tuple(x for x in held if x != o)
            for s, p, o in e.added:
                held = pairs.get((s, p))
                if held is not None and o not in held:
                    pairs[(s, p)] = (*held, o)

    def clear(self) -> None:
        """Forget every pair (the database was changed otherwise than by `committed`)."""
        self._spaces.clear()
        self._predicates.clear()
        self._size = 0

    def _forget(self, space: str) -> None:
        self._size -= len(self._spaces.pop(space, {}))
        self._predicates.pop(space, None)
