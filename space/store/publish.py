"""Publish committed changesets: whole on `@/changes`, in parts by subject and predicate
(`space.store.parts`), then triple by triple on their keys."""

from __future__ import annotations

import logging
import threading

import zenoh
from zenoh import ext

from space import keys
from space.changeset import pack
from space.store.parts import PartPublisher
from space.store.state import Net, SpaceState
from space.store.watched import Watched
from space.terms import triple_from_nt

log = logging.getLogger("tspace.store")

MAX_KEY = 60_000  # bytes: a longer triple key is not published (Zenoh refuses ~64 KiB keys)
CACHE = 128  # whole changesets each space's advanced publisher keeps to repair short gaps
MISS_BEAT = 0.5  # seconds: its sporadic heartbeat (the last sample's number, if it moved)


class Publisher:
    """Publish on a session; writer thread only (`heartbeat` from any thread).

    Each space's whole changesets and heartbeat go out on publishers declared once
    (as Zenoh means a stream of puts on one key). Not `express`: at 2,000 changesets/s
    a message per write cost the store a third of its rate (bench/fleet.py), and alone
    it gained nothing measurable. The whole changesets' is a `zenoh.ext` advanced
    publisher: it numbers its samples and keeps the last `CACHE`, so a subscriber's
    Zenoh repairs a short gap from it without asking our log (see `space._watching`).
    `close` undeclares them all.
    """

    def __init__(self, session: zenoh.Session, root: str) -> None:
        self.session = session
        self.root = root
        self._graphs: dict[tuple[str, str], Watched] = {}
        # (space, service) -> its publisher
        self._streams: dict[tuple[str, str], zenoh.Publisher | ext.AdvancedPublisher] = {}
        self._lock = threading.Lock()
        self._parts = PartPublisher(session, root)

    def close(self) -> None:
        """Undeclare every publisher declared."""
        with self._lock:
            streams, self._streams = list(self._streams.values()), {}
        for watched in self._graphs.values():
            watched.close()
        for publisher in streams:
            publisher.undeclare()
        self._graphs = {}
        self._parts.close()

    def publish(self, committed: list[tuple[SpaceState, Net]]) -> None:
        """Publish committed changesets, whole first (every agent waits for them), then triples."""
        for state, net in committed:
            self._stream(state.name, "changes").put(net.entry.payload)
        for state, net in committed:
            self._parts.publish(state, net)
        for state, net in committed:
            self._triples(state, net)

    def heartbeat(self, space: str, seq: int) -> None:
        """Publish a space's sequence number on its `@/seq` key."""
        self._stream(space, "seq").put(pack({"seq": seq}))

    def _stream(self, space: str, service: str) -> zenoh.Publisher | ext.AdvancedPublisher:
        """Return the publisher of a space's service key, declaring it on first use."""
        with self._lock:
            publisher = self._streams.get((space, service))
            if publisher is None:
                key = keys.service_key(space, service, self.root)
                block = zenoh.CongestionControl.BLOCK
                publisher = self._streams[(space, service)] = (
                    ext.declare_advanced_publisher(
                        self.session,
                        key,
                        congestion_control=block,
                        cache=ext.CacheConfig(CACHE),
                        sample_miss_detection=ext.MissDetectionConfig(
                            heartbeat=None, sporadic_heartbeat=MISS_BEAT
                        ),
                    )
                    if service == "changes"
                    else self.session.declare_publisher(key, congestion_control=block)
                )
            return publisher

    def note(self, state: SpaceState, net: Net) -> None:
        """Record a changeset another cluster replica publishes (its parts' `prev` chain)."""
        self._parts.note(state, net)

    def _triples(self, state: SpaceState, net: Net) -> None:
        """Publish each triple of a net changeset on its key, for plain Zenoh subscribers.

        A graph nobody subscribes to is skipped without making its keys (Zenoh
        would drop the samples anyway): a 600-triple answer then costs nothing here.
        """
        s = self.session
        block = zenoh.CongestionControl.BLOCK
        meta = pack({"id": net.entry.request, "seq": net.entry.seq})
        added, removed, i_added, i_removed = net.texts
        for graph, gone, new in (
            (keys.ASSERTED, removed, added),
            (keys.INFERRED, i_removed, i_added),
        ):
            if not (gone or new) or not self._watched(state.name, graph):
                continue
            for texts, put in ((gone, False), (new, True)):
                for text in texts:
                    key = keys.triple_key(
                        state.name, graph, triple_from_nt(text), state.prefixes, self.root
                    )
                    if len(key) > MAX_KEY:
                        log.info(
                            "triple key of %d bytes not published (limit %d)", len(key), MAX_KEY
                        )
                    elif put:
                        s.put(key, meta, congestion_control=block)
                    else:
                        s.delete(key, attachment=meta, congestion_control=block)

    def _watched(self, space: str, graph: str) -> bool:
        """Return whether any subscriber matches a graph's triple keys."""
        watched = self._graphs.get((space, graph))
        if watched is None:
            key = f"{self.root}/{space}/{graph}/**"
            watched = self._graphs[(space, graph)] = Watched(self.session, key)
        return watched.matching
