"""Publish each committed changeset cut by (subject, predicate), chained by `prev`.

A robot's agents select their robot's keys (`@/changes/<...%23robot7_$*>/*`) and
Zenoh delivers them nothing else. Each part names the seq of the previous
changeset with a part on its key (`prev`), so a subscriber tells a missed part
from a key that was quiet. After the parts of a changeset of `BURST` parts or
more it publishes the changeset's end (`space._parts.end`) on `keys.end_key`, from the
same session: Zenoh keeps one session's messages of one priority and
reliability in order, so a subscriber that hears the end has heard every part
before it (see `space._scoped`). The store keeps the last seq of each key in memory;
a key it does not know (after a start, a failover, or forgotten to bound
memory, or while nobody selected parts) gets the `floor`: a seq no lower than
its real previous part, which makes a subscriber not sure to have it fetch
from the log (see `space._scoped`).
"""

from __future__ import annotations

import logging

import zenoh

from space import keys
from space._parts import BURST, end, split
from space.changeset import pack, unpack
from space.errors import MalformedPayload
from space.store.state import Net, SpaceState

log = logging.getLogger("tspace.store")

MAX_KEYS = 200_000  # last seqs remembered per space; the oldest half is forgotten beyond
MAX_KEY = 60_000  # bytes: a longer key is not published (Zenoh refuses ~64 KiB keys)


class PartPublisher:
    """Publish the parts of net changesets; writer thread only."""

    def __init__(self, session: zenoh.Session, root: str) -> None:
        self.session = session
        self.root = root
        self._last: dict[str, dict[str, int]] = {}  # space -> part key -> seq of its last part
        self._floor: dict[str, int] = {}
        self._watchers: dict[str, zenoh.Publisher] = {}
        self._ends: dict[str, zenoh.Publisher] = {}

    def close(self) -> None:
        """Undeclare the publishers of ends and those used to learn whether anyone selects parts."""
        for publisher in [*self._watchers.values(), *self._ends.values()]:
            publisher.undeclare()
        self._watchers, self._ends = {}, {}

    def publish(self, state: SpaceState, net: Net) -> None:
        """Publish the parts of one net changeset, if anyone selects parts of its space.

        While nobody does, nothing is cut: the floor follows the seq instead, so the
        first part on any key names it, and a subscriber that came in between (before
        the store heard of it) fetches what it may have missed from the log.
        """
        self._chain(state, net, send=True)

    def note(self, state: SpaceState, net: Net) -> None:
        """Record a changeset another cluster replica publishes: the `prev` of its keys moves.

        So the next part this replica publishes on such a key names that
        changeset, and a subscriber that missed it fetches it from the log.
        """
        self._chain(state, net, send=False)

    def _chain(self, state: SpaceState, net: Net, *, send: bool) -> None:
        space, seq = state.name, net.entry.seq
        if not self._watched(space):
            self._last[space] = {}
            self._floor[space] = seq
            return
        last = self._last.setdefault(space, {})
        floor = self._floor.setdefault(space, seq - 1)
        try:
            parts = split(unpack(net.entry.payload))  # type: ignore[arg-type]
        except MalformedPayload as exc:  # the store made it: a bug, but parts are an extra
            log.error("changeset %d of %r not cut into parts: %s", seq, space, exc)
            return
        block = zenoh.CongestionControl.BLOCK
        for (s, p), part in parts.items():
            key = keys.part_key(space, s, p, self.root)
            prev = last.pop(key, floor)
            last[key] = seq
            if send and len(key) <= MAX_KEY:
                part["prev"] = prev
                part["n"] = len(parts)
                self.session.put(key, pack(part), congestion_control=block)
        if send and len(parts) >= BURST:
            self._end(space).put(pack(end(seq, parts)))
        if len(last) > MAX_KEYS:
            self._forget(space, last)

    def _end(self, space: str) -> zenoh.Publisher:
        """Return the publisher of a space's ends, declared on first use (as its parts: BLOCK)."""
        publisher = self._ends.get(space)
        if publisher is None:
            publisher = self._ends[space] = self.session.declare_publisher(
                keys.end_key(space, self.root), congestion_control=zenoh.CongestionControl.BLOCK
            )
        return publisher

    def _forget(self, space: str, last: dict[str, int]) -> None:
        """Forget the oldest half of a space's keys; their next part names the floor."""
        old = list(last)[: len(last) // 2]
        self._floor[space] = max(self._floor[space], *(last.pop(k) for k in old))

    def _watched(self, space: str) -> bool:
        """Return whether any subscriber selects parts of a space (Zenoh's matching status)."""
        publisher = self._watchers.get(space)
        if publisher is None:
            key = keys.part_key(space, "*", "*", self.root)
            publisher = self._watchers[space] = self.session.declare_publisher(key)
        return publisher.matching_status.matching
