"""How fresh the readings the HMI shows are: the life each has left, and since when one is stale.

A reading written with a lifespan (the hardware monitor's, `lifespan = "10s"` in
a launch file) lives while its writer renews it, every third of its lifespan.
The HMI asks the store once a second how long each reading it shows has left
(a renewal that changes nothing is not published, so a change stream cannot
tell). The page greys out a reading with less than a third of its lifespan
left: its writer missed its renewals and it is about to expire. When the store
retracts a reading on expiry, the page says since when there has been none and
what it last said, until a reading comes back.
"""

from __future__ import annotations

import time

from rdflib.term import Node

from agents.vocabulary import AC
from space import EXPIRY_AGENT, Change, TripleSpace

WATCHED = (AC.battery_level, AC.actual_mode)  # the readings the page shows
POLL = 1.0  # seconds between two questions to the store
MOVED = 0.5  # seconds an expiry must move (a renewal) for the page to be told

Key = tuple[Node, Node]


class Freshness:
    """The remaining life and staleness of the watched readings; the HMI agent's thread only."""

    def __init__(self) -> None:
        self.expires: dict[Key, float] = {}  # unix time the reading expires unless renewed
        self.life: dict[Key, float] = {}  # the longest remaining life seen: about its lifespan
        self.stale: dict[Key, tuple[float, str]] = {}  # since when, and its last value
        self._next = 0.0

    def poll(self, ts: TripleSpace, timeout: float) -> bool:
        """Ask the store, at most every `POLL` s, the remaining life of the readings.

        Returns True when the page should be told (a reading renewed, leased or made
        permanent since the last time).

        Raises:
            SpaceError: the store did not answer.
        """
        now = time.time()
        if now < self._next:
            return False
        self._next = now + POLL
        expires: dict[Key, float] = {}
        for predicate in WATCHED:
            for (s, p, _o), left in ts.lifespans((None, predicate, None), timeout=timeout):
                if left is not None:
                    expires[(s, p)] = now + left
                    self.life[(s, p)] = max(self.life.get((s, p), 0.0), left)
        moved = expires.keys() != self.expires.keys() or any(
            abs(at - self.expires[key]) > MOVED for key, at in expires.items()
        )
        self.expires = expires
        return moved

    def note(self, change: Change) -> None:
        """Mark the readings the store retracted on expiry stale, and a new reading fresh."""
        if change.agent == EXPIRY_AGENT:
            for s, p, o in change.removed:
                if p in WATCHED:
                    self.stale[(s, p)] = (time.time(), str(o))
                    self.expires.pop((s, p), None)
        for s, p, _o in change.added:
            if p in WATCHED:
                self.stale.pop((s, p), None)

    def of(self, subject: Node | None, predicate: Node) -> dict | None:
        """Return what the page shows of a reading's freshness (None: permanent or unknown).

        `{"expires": unix ms, "life": s}` for a leased reading, `{"stale_since": unix ms,
        "last": value}` for one the store retracted on expiry.
        """
        key = (subject, predicate)
        if key in self.stale:
            since, last = self.stale[key]
            return {"stale_since": round(since * 1000), "last": last}
        if key in self.expires:
            return {"expires": round(self.expires[key] * 1000), "life": self.life[key]}
        return None
