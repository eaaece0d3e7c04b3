"""One space's state on a cluster replica: decide on what is applied plus what is in flight.

An embedded store decides, commits and settles within one batch. A replica
decides on its database at the etcd revision it applied, but its own
changesets take a round trip through etcd before they come back to be
applied, and 64 may be in flight. So this state keeps, beside what is applied,
the changesets it decided that are not applied yet (`inflight`): the next
decision sees them (the overlay of `SpaceState`, rebuilt from them whenever
one is applied or fails), and the guards of the entries chained on them
(`cluster_writer`) make that safe.

Sequence numbers are not decided here: a changeset's seq is its place in
etcd's order, given when it is applied (`install_at`). Functional stamps
are kept apart too: what is applied (true in the database) and what the
changesets in flight wrote, so applying a changeset removes exactly the
stamp the database holds.
"""

from __future__ import annotations

from collections import ChainMap

from space.changeset import pack, unpack
from space.errors import MalformedPayload
from space.prefixes import PrefixMap
from space.store.cluster_entries import DROPPED, ORIGIN
from space.store.db import StoreDB
from space.store.db_layout import Entry
from space.store.intake import WriteRequest
from space.store.state import Net, SpaceState


class ClusterSpace(SpaceState):
    """`SpaceState` for a replica: decisions do not take a seq; applying does."""

    def __init__(self, name: str, db: StoreDB) -> None:
        super().__init__(name, db)
        self._applied_stamps = self._stamps
        self._flying_stamps: dict = {}
        self._stamps = ChainMap(self._flying_stamps, self._applied_stamps)  # type: ignore[assignment]
        self._applied_prefixes: dict[str, str] = self.prefixes.as_dict()
        self.inflight: list[Entry] = []

    def decide(self, req: WriteRequest, stamp: str) -> tuple[Net | None, list[dict]]:
        """Decide as `SpaceState` does, on the applied state and what is in flight; no seq."""
        seq = self.seq
        net, dropped = super().decide(req, stamp)
        self.seq = seq
        if net is not None:
            self.inflight.append(net.entry)
        return net, dropped

    def functional_properties(self) -> set:
        """Return the properties declared functional in this space (as it is decided on)."""
        return self._functional

    def install_at(self, payload: bytes, seq: int) -> Net:
        """Apply a committed changeset as number `seq` of the space; return it to commit.

        The entry keeps what its writer was told was not applied (`logged_payload`), on
        every replica: a retry sent to any of them is told the same.

        Raises:
            MalformedPayload: not a changeset (the log holds only what replicas decided).
        """
        wire = unpack(payload)
        if not isinstance(wire, dict):
            raise MalformedPayload("a logged changeset is a map")
        dropped = wire.pop(DROPPED, None)  # for the log entry, not the changeset published
        wire.pop(ORIGIN, None)  # for the replica that decided it
        wire["seq"] = seq
        bindings = wire.get("prefixes") or {}
        # New to the database, also when our own decision already taught them to `prefixes`.
        new = {k: v for k, v in bindings.items() if self._applied_prefixes.get(k) != v}
        self._stamps = self._applied_stamps  # type: ignore[assignment]
        try:
            net = self.install(wire, pack(wire))
        finally:
            self._stamps = ChainMap(self._flying_stamps, self._applied_stamps)  # type: ignore[assignment]
        net.entry.prefixes = new
        if dropped:
            net.entry.dropped = pack(dropped)
        self._applied_prefixes.update(new)
        return net

    def settle(self) -> None:
        """Forget what is applied; keep (rebuild) the overlay of what is still in flight."""
        super().settle()
        self._flying_stamps.clear()
        for e in self.inflight:
            # No lookups: an entry's net lists say what it leaves, whatever the database holds.
            self._intend("t", e.removed, e.added)
            self._intend("i", e.inferred_removed, e.inferred_added)
            for s, p, lit in e.stamps_added:
                self._flying_stamps[(s, p)] = lit.value

    def landed(self, entry: Entry) -> None:
        """Forget an entry of ours once applied (settle afterwards)."""
        self._drop(entry)

    def failed(self, entry: Entry) -> None:
        """Forget an entry etcd did not commit: its prefixes and stamps were never true."""
        self._drop(entry)
        self.prefixes = PrefixMap(self._applied_prefixes)
        for e in self.inflight:
            self.prefixes.update(e.prefixes)
        self._functional = self.db.functional(self.name)
        self.settle()

    def _drop(self, entry: Entry) -> None:
        self.inflight = [e for e in self.inflight if e is not entry]
