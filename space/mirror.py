"""A local copy of a space, kept current by one subscription with snapshot.

The live view, the scenario checker and the HMI all need the whole robot state
at once and a way to wait for it to change; they read this copy instead of
querying the store on every refresh. Changes arrive on the client library's
dispatcher thread (never a Zenoh callback); readers wait on `wait_change`.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from rdflib import Graph

from space.terms import Triple

if TYPE_CHECKING:
    from space import Change, TripleSpace


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
        self._changed = threading.Condition()
        self._subscription: object | None = None
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
        arrives on the dispatcher thread (see `wait_change`).
        """
        self._space = ts
        self._subscription = ts.subscribe((None, None, None), self._on_change, snapshot=True)

    def detach(self) -> None:
        """Cancel the subscription; the copy stays readable."""
        if self._space is not None and self._subscription is not None:
            self._space.unsubscribe(self._subscription)
        self._subscription = None
        self._space = None
        with self._changed:
            self._changed.notify_all()

    def _on_change(self, change: Change) -> None:
        with self._changed:
            if self._version == 0:
                # The snapshot merges both graphs: keep its triples apart until a
                # later change says which graph they were in by removing them.
                for triple in change.added:
                    self._snapshot.add(triple)
            else:
                for triple in change.added:
                    self._asserted.add(triple)
            for triple in (*change.removed, *change.inferred_removed):
                self._snapshot.remove(triple)
            for triple in change.removed:
                self._asserted.remove(triple)
            for triple in change.inferred_removed:
                self._inferred.remove(triple)
            for triple in change.inferred_added:
                self._inferred.add(triple)
            self._recent.append(ChangeRecord.of(change))
            self._version += 1
            self._changed.notify_all()
        for watcher in self._watchers:
            watcher()

    @property
    def version(self) -> int:
        """Return how many changesets (the snapshot included) have been applied."""
        with self._changed:
            return self._version

    def wait_change(self, after: int, timeout: float) -> int:
        """Block until the version is above `after` or `timeout` passes; return the version."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while self._version <= after:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self._changed.wait(left)
            return self._version

    def graph(self) -> Graph:
        """Return a copy of the union of asserted and inferred triples."""
        union = Graph()
        with self._changed:
            for triple in self._asserted:
                union.add(triple)
            for triple in self._inferred:
                union.add(triple)
            for triple in self._snapshot:
                union.add(triple)
        return union

    def recent(self) -> list[ChangeRecord]:
        """Return the remembered changesets, oldest first."""
        with self._changed:
            return list(self._recent)
