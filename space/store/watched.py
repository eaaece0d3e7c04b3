"""Whether anyone subscribes to a key expression, told by Zenoh when it changes.

The store publishes a changeset's parts, and its triples on their keys, only
while some subscriber selects them. Asking a publisher's `matching_status` for
each changeset made Zenoh walk every remote subscription each time: 12.7 % of
the store process's CPU in `bench/end_to_end.py` (perf, DWARF stacks), where
every agent's scoped subscription is on the store's router. A matching listener
is told of a change instead, and each changeset reads a boolean.

The listener may hear of a new subscriber a little after the router did: what
the store publishes meanwhile is in its log, which a subscriber that may have
missed it reads (`space._scoped`), as it did when the store asked.
"""

from __future__ import annotations

import threading

import zenoh


class Watched:
    """A publisher on a key expression, and whether any subscriber matches it.

    Not for putting: it is declared only to hear of matching subscribers.
    """

    def __init__(self, session: zenoh.Session, key: str) -> None:
        self._lock = threading.Lock()
        self._heard = False
        self.matching = False
        self._publisher = session.declare_publisher(key)
        self._listener = self._publisher.declare_matching_listener(self._changed)
        now = self._publisher.matching_status.matching
        with self._lock:
            if not self._heard:  # a notice that came meanwhile is newer than `now`
                self.matching = now

    def _changed(self, status: zenoh.MatchingStatus) -> None:
        """Zenoh's callback: note the new status (a lock held for an assignment, no more)."""
        with self._lock:
            self._heard = True
            self.matching = status.matching

    def close(self) -> None:
        """Undeclare the listener and the publisher."""
        self._listener.undeclare()
        self._publisher.undeclare()
