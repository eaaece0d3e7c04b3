"""Lifespans on a cluster replica: each expiry decided once, in the replicated log.

Every replica builds the same lease index (`Leases`) from the log it applies,
never from its own clock: a leasing write's entry carries its `lifespan` and
HLC stamp `ts`, and its triples expire at the stamp's wall time plus the
lifespan. A write that asserts triples already held names them in its entry
(`held`): with a lifespan it renews their lease, without one it makes them
permanent. So a renewal is an entry of the log too, published as a changeset
with no triples.

Any replica may sweep. An expiry is decided like a write (a changeset removing
what the write still leases, by `tspace-store`, `cause` = the write's id) and
committed through etcd with a fixed request id, `expire:<write id>:<expiry
ms>`, and guards on the expired triples' lease keys (`ROOT lease/SPACE/ID`,
put by each leasing write, deleted when a lease ends): present and unchanged
since the revision the replica decided at. So of several replicas sweeping
the same write, one commits (the others conflict on the request key), and an
expiry racing a renewal on another replica fails if the renewal committed
first. A replica sweeps the writes it committed on time, the others' `GRACE`
later (when their replica died, say); an expiry that conflicted or failed is
decided again `RETRY` later, on the state caught up by then.

The leases live in the replica's database (lease graphs, `lifespans.py`),
committed with the revision that decided them: a replica killed -9 resumes
with the leases of what it applied.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import msgpack

from space._parts import header
from space.changeset import WIRE_VERSION, hlc_key, pack, unpack
from space.lifespan import EXPIRY_AGENT
from space.store import oxterms
from space.store.cluster_keys import digest
from space.store.cluster_state import ClusterSpace
from space.store.db import StoreDB
from space.store.db_layout import Entry
from space.store.etcd_log import Entry as LogEntry
from space.store.intake import WriteRequest
from space.store.lifespans import BUDGET, LEASE, Leases
from space.store.oxterms import OxTriple
from space.store.state import Net

GRACE = 1.0  # seconds a replica leaves the replica that committed a write to expire it
RETRY = 0.2  # seconds before an expiry that conflicted or failed is decided again
PREFIX = "expire:"  # an expiry's request id: expire:<write id>:<expiry, unix ms>

_Group = tuple[str, float, str]


def expires_at(stamp: str, lifespan: float) -> float:
    """Return when a write stamped `stamp` with `lifespan` expires (unix seconds)."""
    ntp64 = hlc_key(stamp)[0]
    return (ntp64 >> 32) + (ntp64 & 0xFFFFFFFF) / 2**32 + lifespan


def lease_key(root: bytes, space: str, t: list[str]) -> bytes:
    """Return the etcd key of the lease of asserted triple `t` (N-Triples texts) of a space."""
    return root + b"lease/" + space.encode() + b"/" + digest(*t).encode()


@dataclass
class Plan:
    """What a write does to leases beyond its net additions: the held triples it asserts."""

    held: list[OxTriple]


@dataclass
class Expiry:
    """An expiry decided, for the writer to send."""

    state: ClusterSpace
    net: Net
    request: str
    stamp: str
    triples: list[OxTriple]


class ClusterExpiry:
    """A replica's lease index, kept from the log, and its sweep."""

    def __init__(self, root: bytes, db: StoreDB) -> None:
        self.root = root
        self.leases = Leases()
        self.leases.load(db)
        self._ours: set[_Group] = set()  # leases of writes this replica committed
        self._flying: dict[str, _Group] = {}  # expiries sent, by request id

    # Deciding a write (before and after `decide`).

    def plan(self, state: ClusterSpace, write: WriteRequest) -> Plan:
        """Return the held triples a write asserts that its entry must name (before deciding).

        With a lifespan: every one (it renews them). Without: the leased ones (it
        makes them permanent).
        """
        if write.lifespan:
            return Plan([t for t in write.added if state.holds(t)])
        if not self.leases.holds(state.name):
            return Plan([])
        leased = self.leases.leased
        return Plan([t for t in write.added if leased(state.name, t) and state.holds(t)])

    def decided(
        self, plan: Plan, state: ClusterSpace, write: WriteRequest, net: Net | None, stamp: str
    ) -> Net | None:
        """Return the changeset to commit, naming `held` (one with no triples for a renewal)."""
        if not plan.held:
            return net
        if net is None:
            wire: dict = {"v": WIRE_VERSION, "id": write.id, "agent": write.agent, "ts": stamp}
            if write.cause:
                wire["cause"] = write.cause
            if write.lifespan:
                wire["lifespan"] = write.lifespan
            entry = Entry(space=state.name, seq=state.seq + 1, request=write.id, payload=b"")
            net = Net(entry, [[], [], [], []], header(wire))
        else:
            wire = unpack(net.entry.payload)  # type: ignore[assignment]
        wire["held"] = [oxterms.triple_text(t) for t in plan.held]
        net.entry.payload = pack(wire)
        return net

    def amend(
        self,
        entry: LogEntry,
        space: str,
        net: Net,
        write: WriteRequest | None = None,
        plan: Plan | None = None,
        stamp: str = "",
    ) -> None:
        """Add the lease keys a changeset writes to its log entry (a take: no `write`)."""
        if self.leases.holds(space):
            for t, text in zip(net.entry.removed, net.texts[1], strict=True):
                if self.leases.leased(space, t):
                    entry.deletes.append(lease_key(self.root, space, text))
        if write is None or plan is None:
            return
        held = [oxterms.triple_text(t) for t in plan.held]
        if write.lifespan:
            expires = expires_at(stamp, write.lifespan)
            value = msgpack.packb([round(expires * 1000), write.id])
            for text in (*net.texts[0], *held):
                entry.puts[lease_key(self.root, space, text)] = value
        else:
            entry.deletes += [lease_key(self.root, space, text) for text in held]
        entry.deletes = [k for k in entry.deletes if k not in entry.puts]

    # Applying the log.

    def applied(self, space: str, payload: bytes, net: Net, *, ours: bool) -> None:
        """Note what an applied changeset does to leases (every replica alike)."""
        if not self.leases.holds(space) and b"lifespan" not in payload and b"held" not in payload:
            return  # a fast filter: a payload naming neither cannot lease nor make permanent
        wire = unpack(payload)
        assert isinstance(wire, dict)
        held = [oxterms.triple(t) for t in wire.get("held") or ()]
        lifespan = float(wire["lifespan"]) if wire.get("lifespan") else None
        expires = expires_at(str(wire.get("ts")), lifespan) if lifespan else None
        request = net.entry.request
        self.leases.decide(
            space, request, lifespan, [*net.entry.added, *held], net.entry.removed, expires
        )
        if ours and expires is not None:
            self._ours.add((space, expires, request))
            if len(self._ours) > 2 * len(self.leases) + 64:  # forget those renewed or removed
                self._ours = {g for g in self._ours if self.leases.live(g)}
        group = self._flying.pop(request, None)
        if group is not None:  # our expiry: what it did not retract is swept again
            self.leases.requeue(group, time.time() + RETRY)

    def changes(self) -> tuple[list, list]:
        """Return the lease quads to delete and insert with the applied revision."""
        return self.leases.take_changes()

    def forget(self, db: StoreDB) -> None:
        """Drop every lease (after a re-list: the others, who have them, sweep them)."""
        for g in list(db.store.named_graphs()):
            if g.value.startswith(LEASE):  # type: ignore[union-attr]
                db.store.remove_graph(g)
        self.leases = Leases()
        self._ours.clear()
        self._flying.clear()

    # Sweeping.

    def next_due(self) -> float | None:
        """Return the next time a lease is due to be swept (unix seconds), if any."""
        return self.leases.next_due()

    def due(
        self,
        space: Callable[[str], ClusterSpace],
        stamp: Callable[[], str],
        flying: Callable[[bytes], bool],
    ) -> list[Expiry]:
        """Decide the expiries due now (about `BUDGET` in cost); the writer sends them.

        `flying(key)`: whether a changeset of ours in flight writes the key (a
        renewal or a removal, say): that write is swept again after it lands.
        """
        now = time.time()
        decided = []
        for group, triples in self.leases.pop_due(now, BUDGET):
            name, expires, write_id = group
            request = f"{PREFIX}{write_id}:{round(expires * 1000)}"
            if request in self._flying:
                continue
            if group not in self._ours and expires + GRACE > now:
                self.leases.requeue(group, expires + GRACE)
                continue
            if any(flying(lease_key(self.root, name, oxterms.triple_text(t))) for t in triples):
                self.leases.requeue(group, now + RETRY)
                continue
            state = space(name)
            write = WriteRequest(id=request, agent=EXPIRY_AGENT, cause=write_id, removed=triples)
            when = stamp()
            net, _ = state.decide(write, when)
            if net is None:  # none held as decided here (our take in flight): later
                self.leases.requeue(group, now + RETRY)
                continue
            self._flying[request] = group
            decided.append(Expiry(state, net, request, when, triples))
        return decided

    def guard(self, entry: LogEntry, expiry: Expiry, revision: int) -> None:
        """Guard an expiry's entry: every lease it ends present and unchanged since `revision`."""
        for t in expiry.triples:
            key = lease_key(self.root, expiry.state.name, oxterms.triple_text(t))
            entry.guards[key] = revision
            entry.present.append(key)
            entry.deletes.append(key)

    def retry(self, request: str) -> bool:
        """Sweep an expiry that was not committed again later; return whether it was one."""
        group = self._flying.pop(request, None)
        if group is None:
            return False
        self.leases.requeue(group, time.time() + RETRY)
        return True
