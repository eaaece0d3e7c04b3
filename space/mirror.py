"""A local copy of a space, kept current by one subscription with snapshot.

The live view, the scenario checker and the HMI all need the whole robot state
at once and a way to wait for it to change; they read this copy instead of
querying the store on every refresh. Changes arrive on the client library's
dispatcher thread (never a Zenoh callback); `watch` reacts to each one.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from rdflib import Graph

from space.terms import Triple

if TYPE_CHECKING:
    from space import Change, Subscription, TripleSpace


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


class SpaceMirror:
    """Keep the asserted and inferred graphs of a space in memory.

    Args:
        history: how many recent changesets to remember for `recent`.
    """

    def __init__(self, history: int = 200) -> None:
        self._asserted = Graph()
        self._inferred = Graph()
        self._snapshot = Graph()
        self._recent: deque[ChangeRecord] = deque(maxlen=history)
        self._version = 0
        self._lock = threading.Lock()
        self._subscription: Subscription | None = None
        self._space: TripleSpace | None = None
        self._watchers: list[Callable[[], None]] = []

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
        with self._lock:
            # Removals first, as the store applies them.
            for triple in (*change.removed, *change.inferred_removed):
                self._snapshot.remove(triple)
            for triple in change.removed:
                self._asserted.remove(triple)
            for triple in change.inferred_removed:
                self._inferred.remove(triple)
            # The snapshot merges both graphs: keep its triples apart until a later
            # change removes them from whichever graph they were in.
            for triple in change.added:
                (self._snapshot if self._version == 0 else self._asserted).add(triple)
            for triple in change.inferred_added:
                self._inferred.add(triple)
            self._recent.append(ChangeRecord.of(change))
            self._version += 1
        for watcher in self._watchers:
            watcher()

    @property
    def version(self) -> int:
        """Return how many changesets (the snapshot included) have been applied."""
        with self._lock:
            return self._version

    def graph(self) -> Graph:
        """Return a copy of the union of asserted and inferred triples."""
        union = Graph()
        with self._lock:
            for triple in self._asserted:
                union.add(triple)
            for triple in self._inferred:
                union.add(triple)
            for triple in self._snapshot:
                union.add(triple)
        return union

    def recent(self) -> list[ChangeRecord]:
        """Return the remembered changesets, oldest first."""
        with self._lock:
            return list(self._recent)
