"""What the database holds, remembered between decisions: the objects of (subject,
functional property) pairs, and the triples the latest commits added or removed.

Deciding a functional write reads the value it replaces (`StoreDB.objects`).
A value rewritten at every reading leaves RocksDB a tombstone for each old
value under that pair until a compaction reaches them, and a scan of the pair
steps over all of them: 9 us for a fresh pair, 30-1,250 us (often ~250) once
64 robots had rewritten theirs a few thousand times, with the store's flushes
running. So the pairs read are kept here, and each commit updates the ones it
changes: a decision reads the database once per pair, not once per reading.

A decision also looks up each triple it removes or adds (`StoreDB.has`): a
reasoner's answer replacing 200 settings, 400 lookups, ~12 % of the store
thread's time. The triple it removes is mostly one a recent commit added, and the
one it adds one a recent commit removed (a setting going back and forth), so each
commit's triples are remembered as present or absent (`SETTLED` at most) and a
lookup goes to the database only for the others: a reasoner's answer of 200
settings, 9.7 -> 8.4-9.6 ms of the store's CPU in-process. A bulk write's are not: they
would cost it ~10 % more CPU and are rarely written again soon.
"""

from __future__ import annotations

from space.store import oxterms
from space.store.db_layout import Entry
from space.store.oxterms import OxTerm

LIMIT = 100_000  # pairs remembered at most (then forgotten all at once, and read again)
SETTLED = 10_000  # triples remembered as present or absent at most (then forgotten at once)
BULK = 2_000  # a changeset of more triples is not remembered (its space's are forgotten)

Pair = tuple[OxTerm, OxTerm]
Triple = tuple[OxTerm, OxTerm, OxTerm]


class Values:
    """Per space, the asserted objects of the (s, p) pairs read; writer thread only."""

    def __init__(self) -> None:
        self._spaces: dict[str, dict[Pair, tuple[OxTerm, ...]]] = {}
        self._predicates: dict[str, set[str]] = {}  # N-Triples of the predicates remembered
        self._size = 0
        # Per space, (graph `t` or `i`, triple) -> whether a recent commit left it there; read
        # straight by `StoreDB.has`, every triple a decision removes or adds.
        self.settled: dict[str, dict[tuple[str, Triple], bool]] = {}
        self._settled_size = 0

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
        """Apply what a successful commit changed to the pairs and triples remembered."""
        self._settle(entries)
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

    def _settle(self, entries: list[Entry]) -> None:
        if self._settled_size >= SETTLED:
            self.settled.clear()
            self._settled_size = 0
        for e in entries:
            if e.plain or e.size() > BULK:  # texts, or a bulk write: forget the space's
                self._settled_size -= len(self.settled.pop(e.space, {}))
                continue
            settled = self.settled.setdefault(e.space, {})
            before = len(settled)
            for which, gone, new in (
                ("t", e.removed, e.added),
                ("i", e.inferred_removed, e.inferred_added),
            ):
                for t in gone:
                    settled[(which, t)] = False
                for t in new:
                    settled[(which, t)] = True
            self._settled_size += len(settled) - before

    def clear(self) -> None:
        """Forget everything (the database was changed otherwise than by `committed`)."""
        self._spaces.clear()
        self._predicates.clear()
        self._size = 0
        self.settled.clear()
        self._settled_size = 0

    def _forget(self, space: str) -> None:
        self._size -= len(self._spaces.pop(space, {}))
        self._predicates.pop(space, None)
