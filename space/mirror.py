"""The one local copy of a space: the triples seen, kept current by changes.

Agents decide from it instead of asking the store on every tick, so a slow or
absent store never stalls a control loop; the live view, the scenario checker
and the HMI read the whole state from it at once. It holds the union of the
asserted and inferred graphs, as a snapshot reports it, and remembers which
graph each triple came from, so a triple both asserted and inferred stays
until both are gone. A functional property's new value replaces the old one
(`space.functional`), even when a change arrives before the removal it implies.

Owned by one thread (an agent's loop: `apply`, then read `graph`), or fed by a
subscription (`attach`: changes arrive on the client's dispatcher thread; read
with `copy()`, `version`, `recent()`, which take the lock).

The owner may note what some code reads (`reading()`): which later changes
could make it decide otherwise (`Reads.touched_by`), so an agent need not
decide again on a change that concerns none of it.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime
from typing import TYPE_CHECKING

from rdflib import RDF, Graph, Literal
from rdflib.term import Node

from space._memory import BulkMemory
from space.functional import declares_functional, replace_functional
from space.terms import Triple

if TYPE_CHECKING:
    from space._subscription import Change, Subscription
    from space.changeset import Changeset
    from space.client import TripleSpace

# Which graph a triple is held for; a snapshot merges both, so its triples are "either".
ASSERTED, INFERRED, EITHER = 1, 2, 4


@dataclass(frozen=True)
class ChangeRecord:
    """What the mirror remembers of a recent changeset, to explain later ones.

    Attributes:
        id: the changeset id.
        seq: its place in the store's order.
        agent: who wrote it.
        timestamp: when, by the Zenoh HLC.
        cause: the id of the changeset it answers, if any.
        added: asserted and inferred triples it added.
        removed: asserted and inferred triples it removed.
    """

    id: str
    seq: int
    agent: str
    timestamp: datetime | None
    cause: str | None
    added: tuple[Triple, ...]
    removed: tuple[Triple, ...]

    @classmethod
    def of(cls, change: Change) -> ChangeRecord:
        """Return the record of a changeset, asserted and inferred triples together."""
        return cls(
            id=change.id,
            seq=change.seq,
            agent=change.agent,
            timestamp=change.time,
            cause=change.cause,
            added=(*change.added, *change.inferred_added),
            removed=(*change.removed, *change.inferred_removed),
        )


@dataclass
class Reads:
    """What some code read from a mirror: the (subject, predicate) pairs it looked up.

    Attributes:
        pairs: (subject, predicate) pairs read; (None, predicate): that predicate's
            triples of any subject (a lookup of subjects).
        everything: it read the rdflib `graph`, where lookups are not noted.
    """

    pairs: set[tuple[Node | None, Node]] = field(default_factory=set)
    everything: bool = False

    def touched_by(self, change: Changeset) -> bool:
        """Return whether `change` adds or removes a triple of what was read."""
        if self.everything:
            return True
        pairs = self.pairs
        for triples in (
            change.added,
            change.removed,
            change.inferred_added,
            change.inferred_removed,
        ):
            for s, p, _o in triples:
                if (s, p) in pairs or (None, p) in pairs:
                    return True
        return False


class SpaceMirror:
    """Keep a space's triples in memory, with the lookups deciding from them needs.

    Args:
        triples: the triples to start from (held as asserted).
        history: how many recent changesets to remember for `recent` (attached only).

    Attributes:
        graph: the live union graph (rdflib, for SPARQL and serialising); read it only
            from the thread that applies changes. The lookups below read the same
            indexes without rdflib's generic pattern search, microseconds each.
    """

    def __init__(
        self,
        triples: Iterable[Triple] = (),
        *,
        history: int = 200,
    ) -> None:
        self._store = BulkMemory()
        self._graph = Graph(store=self._store)
        self._reads: Reads | None = None
        self._origins: dict[Triple, int] = {}
        self._functional: set[Node] = set()
        self._recent: deque[ChangeRecord] = deque(maxlen=history)
        self._version = 0
        self._lock = threading.Lock()
        self._subscription: Subscription | None = None
        self._space: TripleSpace | None = None
        self._watchers: list[Callable[[], None]] = []
        self.add(triples)

    @property
    def graph(self) -> Graph:
        """Return the live union graph (see the class); reading it notes everything read."""
        if self._reads is not None:
            self._reads.everything = True
        return self._graph

    @contextmanager
    def reading(self) -> Iterator[Reads]:
        """Note the lookups made inside the block (owner thread); yield what they read."""
        reads = self._reads = Reads()
        try:
            yield reads
        finally:
            self._reads = None

    def _read(self, subject: Node | None, predicate: Node) -> None:
        if self._reads is not None:
            self._reads.pairs.add((subject, predicate))

    # Keeping it current

    def apply(self, change: Changeset, *, snapshot: bool = False) -> None:
        """Apply a changeset: removals first, as the store applies them, then additions.

        With `snapshot`, the change is a subscription's snapshot: its additions
        merge both graphs, and they leave with the first removal from either.
        """
        with self._lock:
            self._remove(change.removed, ASSERTED)
            self._remove(change.inferred_removed, INFERRED)
            self._add(change.added, EITHER if snapshot else ASSERTED)
            self._add(change.inferred_added, INFERRED)
            self._version += 1

    def add(self, triples: Iterable[Triple]) -> None:
        """Add asserted triples; a functional property's new value replaces the old one."""
        with self._lock:
            self._add(triples, ASSERTED)

    def remove(self, triples: Iterable[Triple]) -> None:
        """Remove asserted triples (absent ones are ignored)."""
        with self._lock:
            self._remove(triples, ASSERTED)

    def _add(self, triples: Iterable[Triple], origin: int) -> None:
        store, origins, functional = self._store, self._origins, self._functional
        triples = list(triples)
        functional.update(t[0] for t in triples if declares_functional(t))
        change = replace_functional(triples, functional.__contains__, store.objects_of)
        for old in change.replaced:
            origins.pop(old, None)
            store.discard(old)
        for triple in change.kept:
            origins[triple] = origins.get(triple, 0) | origin
            store.put(triple)

    def _remove(self, triples: Iterable[Triple], origin: int) -> None:
        store, origins = self._store, self._origins
        for triple in triples:
            left = origins.get(triple, 0) & ~(origin | EITHER)
            if left:
                origins[triple] = left
                continue
            origins.pop(triple, None)
            if declares_functional(triple):
                self._functional.discard(triple[0])
            store.discard(triple)

    # Fed by a subscription

    def watch(self, watcher: Callable[[], None]) -> None:
        """Call `watcher` after each changeset is applied, before the next one.

        It runs on the client's dispatcher thread and must not write to the space.
        Register watchers before `attach`.
        """
        self._watchers.append(watcher)

    def attach(self, ts: TripleSpace) -> None:
        """Subscribe to everything in `ts`, starting from its current state.

        Blocks until the snapshot subscription is declared; the snapshot itself
        arrives on the dispatcher thread, then `version` becomes 1.
        """
        self._space = ts
        self._subscription = ts.subscribe((None, None, None), self._on_change, snapshot=True)

    def detach(self) -> None:
        """Cancel the subscription; the copy stays readable."""
        if self._space is not None and self._subscription is not None:
            self._space.unsubscribe(self._subscription)
        self._subscription = None
        self._space = None

    def _on_change(self, change: Change) -> None:
        self.apply(change, snapshot=self._version == 0)
        with self._lock:
            self._recent.append(ChangeRecord.of(change))
        for watcher in self._watchers:
            watcher()

    @property
    def version(self) -> int:
        """Return how many changesets (a snapshot included) have been applied."""
        with self._lock:
            return self._version

    def copy(self) -> Graph:
        """Return a copy of the union graph; safe from any thread."""
        union = Graph()
        with self._lock:
            for triple in self._origins:
                union.add(triple)
        return union

    def recent(self) -> list[ChangeRecord]:
        """Return the remembered changesets, oldest first."""
        with self._lock:
            return list(self._recent)

    # Lookups (owner thread)

    def __len__(self) -> int:
        return len(self._origins)

    def is_functional(self, predicate: Node) -> bool:
        """Return True if the copy declares `predicate` an owl:FunctionalProperty."""
        self._read(predicate, RDF.type)
        return predicate in self._functional

    def __contains__(self, triple: Triple) -> bool:
        self._read(triple[0], triple[1])
        return self._store.has(triple)

    def value(self, subject: Node | None, predicate: Node) -> Node | None:
        """Return one object of (subject, predicate) (the least, for determinism), or None."""
        if subject is None:
            return None
        self._read(subject, predicate)
        return min(self._store.objects_of(subject, predicate), default=None)

    def text(self, subject: Node | None, predicate: Node) -> str | None:
        """Return the lexical form of one object of (subject, predicate), or None."""
        found = self.value(subject, predicate)
        return None if found is None else str(found)

    def number(self, subject: Node | None, predicate: Node) -> float | None:
        """Return one numeric object of (subject, predicate), or None if absent or not a number."""
        found = self.value(subject, predicate)
        if not isinstance(found, Literal):
            return None
        try:
            return float(found)
        except ValueError:
            return None

    def objects(self, subject: Node, predicate: Node) -> list[Node]:
        """Return the objects of (subject, predicate), sorted for determinism."""
        self._read(subject, predicate)
        return sorted(self._store.objects_of(subject, predicate))

    def subjects(self, predicate: Node, obj: Node | None = None) -> list[Node]:
        """Return the subjects of (predicate, obj), of any object when `obj` is None; sorted."""
        self._read(None, predicate)
        return sorted(self._store.subjects_of(predicate, obj))

    def has_type(self, subject: Node, cls: Node) -> bool:
        """Return True if `subject rdf:type cls` is in the copy."""
        self._read(subject, RDF.type)
        return self._store.has((subject, RDF.type, cls))
