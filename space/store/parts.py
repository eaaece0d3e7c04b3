"""Publish each committed changeset cut by subject, each part naming its predicates and `prev`s.

A robot's agents select their robot's keys (`@/changes/<...%23robot7_$*>/*/**`) and
Zenoh delivers them nothing else. A part's key is its subject and its predicates
(`space._parts.grouped`); for each of those pairs it names the seq of the previous
changeset with triples on it (`prev`), so a subscriber tells a missed part from a
pair that was quiet. After the parts of a changeset of `BURST` pairs or more it
publishes the changeset's end (`space._parts.end`) on `keys.end_key`, from the
same session: Zenoh keeps one session's messages of one priority and
reliability in order, so a subscriber that hears the end has heard every part
before it (see `space._scoped`). The store keeps the last seq of each pair in memory;
a pair it does not know (after a start, a failover, or forgotten to bound
memory, or while nobody selected parts) gets the `floor`: a seq no lower than
its real previous part, which makes a subscriber not sure to have it fetch
from the log (see `space._scoped`).
"""

from __future__ import annotations

import logging

import msgpack
import zenoh

from space import keys
from space._parts import BURST, PartKey, cut, end, grouped, made_chunks
from space.changeset import LISTS, pack
from space.store.state import Net, SpaceState
from space.store.watched import Watched

log = logging.getLogger("tspace.store")

MAX_KEYS = 200_000  # pairs whose last seq is kept per space; the oldest half is forgotten beyond
OFTEN = 32  # puts on a key before it gets a declared publisher
MAX_OFTEN = 4096  # keys whose puts are counted; the least recently put half is forgotten beyond
MAX_KEY = 60_000  # bytes: a longer key is not published (Zenoh refuses ~64 KiB keys)


class PartPublisher:
    """Publish the parts of net changesets; writer thread only."""

    def __init__(self, session: zenoh.Session, root: str) -> None:
        self.session = session
        self.root = root
        self._last: dict[str, dict[PartKey, int]] = {}  # space -> pair -> seq of its last part
        self._floor: dict[str, int] = {}
        self._watchers: dict[str, Watched] = {}
        self._ends: dict[str, zenoh.Publisher] = {}
        self._often = _Often(session)
        self._packer = msgpack.Packer(use_bin_type=True)  # as `space.changeset.pack`, made once

    def close(self) -> None:
        """Undeclare the publishers of ends and those used to learn whether anyone selects parts."""
        for watched in self._watchers.values():
            watched.close()
        for publisher in self._ends.values():
            publisher.undeclare()
        self._watchers, self._ends = {}, {}
        self._often.close()

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
        pairs = cut(zip(LISTS, net.texts, strict=True), made_chunks)
        parts = grouped(pairs)
        head = self._packer.pack(net.header)[1:]  # its pairs, packed once for every part
        for s, predicates, part in parts:
            prevs = []
            for p in predicates:
                prevs.append(last.pop((s, p), floor))
                last[(s, p)] = seq
            key = keys.part_key(space, s, "/".join(predicates), self.root)
            if send and len(key) <= MAX_KEY:
                part["prev"] = prevs[0] if len(prevs) == 1 else prevs
                part["n"] = len(pairs)
                self._often.put(
                    key, self._map(head, len(net.header), part), often=len(predicates) > 1
                )
        if send and len(pairs) >= BURST:
            self._end(space).put(pack(end(seq, pairs)))
        if len(last) > MAX_KEYS:
            self._forget(space, last)

    def _map(self, head: bytes, count: int, rest: dict) -> bytes:
        """Return the msgpack map of `count` packed pairs `head` followed by those of `rest`.

        What `pack` makes of the two maps merged, byte for byte: a part's header is
        packed once for all the parts of its changeset. Both are fixmaps (a header
        of at most 7 pairs, a part's 4 lists, `prev` and `n`: under 16 in all).
        """
        body = self._packer.pack(rest)
        return bytes((0x80 | (count + len(rest)),)) + head + body[1:]

    def _end(self, space: str) -> zenoh.Publisher:
        """Return the publisher of a space's ends, declared on first use (as its parts: BLOCK)."""
        publisher = self._ends.get(space)
        if publisher is None:
            publisher = self._ends[space] = self.session.declare_publisher(
                keys.end_key(space, self.root), congestion_control=zenoh.CongestionControl.BLOCK
            )
        return publisher

    def _forget(self, space: str, last: dict[PartKey, int]) -> None:
        """Forget the oldest half of a space's pairs; their next part names the floor."""
        old = list(last)[: len(last) // 2]
        self._floor[space] = max(self._floor[space], *(last.pop(k) for k in old))

    def _watched(self, space: str) -> bool:
        """Return whether any subscriber selects parts of a space."""
        watched = self._watchers.get(space)
        if watched is None:
            key = keys.part_key(space, "*", "*/**", self.root)
            watched = self._watchers[space] = Watched(self.session, key)
        return watched.matching


class _Often:
    """Put parts, on a declared publisher for a key put `OFTEN` times (the last `MAX_OFTEN` keys).

    A put on a declared publisher costs half a put on the session (~1 us less), but
    declaring one costs ~80: a key that comes back (a robot's, the reasoner's answer's)
    earns one, a bulk write's keys (seen once) do not. A key of several predicates
    gets one at its second put: Zenoh matches it against every subscriber's expression
    chunk by chunk, ~3 us a chunk with 20 of them, for a put on the session as for a
    declaration, and a put on a declared publisher pays that once (`docs/performance.md`).
    Not at its first: a key seen once (a firing record's, a new subject each time) then
    cost a declaration sent to every client of the store's router, and later its
    undeclaration, for one put (6.3 % of the store's CPU in `bench/end_to_end.py`).
    """

    def __init__(self, session: zenoh.Session) -> None:
        self.session = session
        self._keys: dict[str, int | zenoh.Publisher] = {}  # key -> its puts, or its publisher

    def put(self, key: str, payload: bytes, *, often: bool = False) -> None:
        """Put a part on its key (BLOCK, as every part: none is dropped when a link is slow).

        `often`: declare its publisher at its second put (a key of several predicates).
        """
        seen = self._keys.pop(key, 0)  # put back last: the least recently put are forgotten
        if isinstance(seen, int) and seen + 1 < (2 if often else OFTEN):
            self._keys[key] = seen + 1
            self.session.put(key, payload, congestion_control=zenoh.CongestionControl.BLOCK)
        else:
            if isinstance(seen, int):
                seen = self.session.declare_publisher(
                    key, congestion_control=zenoh.CongestionControl.BLOCK
                )
            self._keys[key] = seen
            seen.put(payload)
        if len(self._keys) > MAX_OFTEN:
            old = list(self._keys)[: len(self._keys) // 2]
            self._undeclare([self._keys.pop(k) for k in old])

    def close(self) -> None:
        """Undeclare every publisher."""
        self._undeclare(list(self._keys.values()))
        self._keys = {}

    @staticmethod
    def _undeclare(seen: list[int | zenoh.Publisher]) -> None:
        for publisher in seen:
            if not isinstance(publisher, int):
                publisher.undeclare()
