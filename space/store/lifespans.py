"""Leases: when each leased triple expires, kept on disk with it, and the sweep that retracts it.

A write with a lifespan leases the asserted triples it asserts (those already
held too: a sensor's periodic reading renews its lease). The latest write of a
triple decides: with a lifespan it (re)leases it, without one it makes it
permanent; a triple removed (by a write, a take, a functional replacement or
its expiry) loses its lease.

On disk a lease is the triple itself in the graph
`urn:tspace:lease:<space>:<expiry in ms>:<write id, percent-encoded>`, committed in
the same SPARQL update as the changeset that decided it. A lease quad counts
only while its triple is asserted: an expiry leaves its lease quads behind
(`garbage`, deleted later by `collect`: with the retraction they tripled its
commit), and a triple asserted again has its old one deleted in that commit.
After `kill -9`, `load` finds the leases of the triples held (those whose
time passed during the outage are due at once).

In memory, one group per leasing write (its triples still leased by it) in a
heap by expiry time, each triple kept as the texts the database writes: str
tuples, which the garbage collector leaves out of its walks (it walks
pyoxigraph terms one by one: with 100,000 leases a full collection took
0.2-4 s of the writer thread on a loaded machine, the tail of the writes
during a mass expiry). `due` hands the writer thread the groups whose time
has come, a bounded cost per turn (one write while requests come in), so a
mass expiry is spread over turns and never holds the writes queued behind it.
Each group becomes one changeset retracting its triples, attributed to the
store, naming the write that expired (`cause`). A cluster replica orders its
expiries through the replicated log instead (`cluster_expiry.py`).

Writer thread only, except `remaining` (any reader thread).
"""

from __future__ import annotations

import heapq
import itertools
import logging
import time
import uuid
from collections.abc import Callable
from functools import lru_cache
from typing import TYPE_CHECKING
from urllib.parse import quote, unquote

import pyoxigraph as ox

from space.lifespan import EXPIRY_AGENT
from space.store.db import StoreDB
from space.store.intake import WriteRequest
from space.store.oxterms import OxTriple, term

if TYPE_CHECKING:
    from space.store.state import Net, SpaceState

log = logging.getLogger("tspace.store")

LEASE = "urn:tspace:lease:"
# A writer turn of expiries retracts about BUDGET triples' worth of commit, a changeset
# (its log entry, seq, publication) costing as much as CHANGESET triples. While writes
# come in, a turn is one expired write (BUSY), so a write waits for one at most. The
# first write of a turn expires whole, whatever its size.
BUDGET = 64
BUSY = 1
CHANGESET = 16
# Lease quads left behind by expiries, deleted a few at a time between writes (see `collect`).
GARBAGE = 256  # a turn of them when no request comes in
GARBAGE_BUSY = 16  # while requests come in

_Group = tuple[str, float, str]  # space, expiry (unix seconds), write id
_Text = str  # a triple as the database writes it: `str` of each term, joined by spaces


def _text(t: OxTriple) -> _Text:
    return f"{t[0]} {t[1]} {t[2]}"


def _triple(k: _Text) -> OxTriple:
    s, p, o = k.split(" ", 2)  # a subject and a predicate are IRIs: no space in them
    return (term(s), term(p), term(o))


@lru_cache(maxsize=4096)
def lease_graph(group: _Group) -> ox.NamedNode:
    """Return the graph holding the triples a write leased until its expiry."""
    space, expires, request = group
    return ox.NamedNode(f"{LEASE}{space}:{round(expires * 1000)}:{quote(request, safe='')}")


def parse_graph(name: str) -> _Group | None:
    """Return `(space, expires, write id)` of a lease graph's IRI (None if it is not one)."""
    if not name.startswith(LEASE):
        return None
    space, ms, request = name[len(LEASE) :].rsplit(":", 2)
    return space, int(ms) / 1000, unquote(request)


class Leases:
    """Every lease of every space, and the lease quads the next commit must write."""

    def __init__(self) -> None:
        self._held: dict[str, dict[_Text, _Group]] = {}  # space -> triple -> its write
        self._groups: dict[_Group, set[_Text]] = {}
        self._heap: list[tuple[float, int, _Group]] = []
        self._order = itertools.count()
        self._changes: dict[tuple[_Group, _Text], bool] = {}  # lease quads: insert (True)
        # Lease quads of triples retracted on expiry, still on disk: deleting them with the
        # retraction would triple its commit, so `collect` deletes them later. A lease quad
        # whose triple is not asserted means nothing (`load` skips it).
        self.garbage: dict[tuple[str, _Text], _Group] = {}
        self._garbage_in: dict[str, int] = {}  # space -> how many of `garbage` are its

    def has_garbage(self, space: str) -> bool:
        """Return whether a space has lease quads left to collect.

        Any way of asserting triples other than `decide` (a fast path for plain
        writes) must not be taken then: a triple asserted again must have its old
        lease quad deleted in the same commit (`decide` does it).
        """
        return self._garbage_in.get(space, 0) > 0

    def _discard(self, space: str, t: _Text, group: _Group) -> None:
        """Make a lease quad garbage: its triple is retracted, the quad is still on disk."""
        self.garbage[(space, t)] = group
        self._garbage_in[space] = self._garbage_in.get(space, 0) + 1

    def _collected(self, space: str) -> None:
        self._garbage_in[space] -= 1

    def __len__(self) -> int:
        return sum(map(len, self._held.values()))

    def holds(self, space: str) -> bool:
        """Return whether any triple of a space is leased."""
        return bool(self._held.get(space))

    def load(self, db: StoreDB) -> None:
        """Forget everything and read the leases from the database (at start, after a failure)."""
        self.__init__()  # type: ignore[misc]
        for g in db.store.named_graphs():
            if not isinstance(g, ox.NamedNode):
                continue
            group = parse_graph(g.value)
            if group is None:
                continue
            for q in db.store.quads_for_pattern(None, None, None, g):
                t = (q.subject, q.predicate, q.object)
                if db.has(group[0], "t", t):
                    self._lease(group, _text(t))
                else:  # retracted on expiry, its lease quad not collected yet
                    self._discard(group[0], _text(t), group)
        if self._groups:
            log.info("%d leased triple(s) in %d write(s)", len(self), len(self._groups))

    def decide(
        self,
        space: str,
        request: str,
        lifespan: float | None,
        asserted: list[OxTriple],
        removed: list[OxTriple],
        expires: float | None = None,
    ) -> None:
        """Note what a changeset does to leases: `removed` lose theirs, `asserted` get the write's.

        `asserted` are the additions applied (held already or not), `removed`
        the asserted triples it really removes. The lease runs until `expires`
        (unix seconds), by default `lifespan` from now.
        """
        if not lifespan and not self.holds(space) and not self.has_garbage(space):
            return  # nothing leased to release, nothing to lease
        for t in removed:
            self._release(space, _text(t))
        if lifespan and expires is None:
            expires = time.time() + lifespan
        group = (space, expires, request) if expires is not None else None
        for t in map(_text, asserted):
            self._release(space, t)
            stale = self.garbage.pop((space, t), None)
            if stale is not None:  # asserted again: its old lease quad goes in this commit
                self._changes[(stale, t)] = False
                self._collected(space)
            if group is not None:
                self._lease(group, t)
                self._changes[(group, t)] = True

    def take_changes(self) -> tuple[list[ox.Quad], list[ox.Quad]]:
        """Return the lease quads to delete and to insert with the next commit, and forget them."""
        changes, self._changes = self._changes, {}
        return [_quad(*k) for k, v in changes.items() if not v], [
            _quad(*k) for k, v in changes.items() if v
        ]

    def next_due(self) -> float | None:
        """Return the earliest expiry time still to sweep (unix seconds), if any."""
        while self._heap and self._heap[0][2] not in self._groups:
            heapq.heappop(self._heap)
        return self._heap[0][0] if self._heap else None

    def due(self, now: float, budget: int = BUDGET) -> list[tuple[_Group, list[OxTriple]]]:
        """Return the writes expired by `now` with their leased triples, about `budget` in cost.

        Each write costs its triples plus `CHANGESET`; the first is returned whatever its size.

        Their leases are released here; their lease quads become `garbage`,
        deleted later by `collect` (not with the retraction: that is its cost).
        """
        found = self.pop_due(now, budget)
        for group, _triples in found:
            for t in self._groups.pop(group):
                del self._held[group[0]][t]
                self._discard(group[0], t, group)
        return found

    def pop_due(self, now: float, budget: int = BUDGET) -> list[tuple[_Group, list[OxTriple]]]:
        """Return the writes expired by `now` with their triples, leases kept (about `budget`).

        For a cluster replica, where an expiry holds only once the log applied
        it: until then each is out of the heap; `requeue` puts it back.
        """
        found: list[tuple[_Group, list[OxTriple]]] = []
        count = 0
        while count < budget and self.next_due() is not None and self._heap[0][0] <= now:
            group = heapq.heappop(self._heap)[2]
            if any(group == g for g, _ in found):
                continue
            triples = [_triple(t) for t in self._groups[group]]
            found.append((group, triples))
            count += len(triples) + CHANGESET
        return found

    def requeue(self, group: _Group, when: float) -> None:
        """Sweep a write's leases again at `when` (unix seconds), if it still leases any."""
        if group in self._groups:
            heapq.heappush(self._heap, (when, next(self._order), group))

    def live(self, group: _Group) -> bool:
        """Return whether a write still leases any triple."""
        return group in self._groups

    def leased(self, space: str, t: OxTriple) -> bool:
        """Return whether a triple of a space is leased."""
        return _text(t) in self._held.get(space, ())

    def collect(self, count: int) -> int:
        """Queue the deletion of up to `count` garbage lease quads with the next commit.

        Returns how many were queued.
        """
        taken = 0
        while self.garbage and taken < count:
            (space, t), group = self.garbage.popitem()
            self._changes[(group, t)] = False
            self._collected(space)
            taken += 1
        return taken

    def _lease(self, group: _Group, t: _Text) -> None:
        self._held.setdefault(group[0], {})[t] = group
        held = self._groups.get(group)
        if held is None:
            held = self._groups[group] = set()
            heapq.heappush(self._heap, (group[1], next(self._order), group))
        held.add(t)

    def _release(self, space: str, t: _Text) -> None:
        group = self._held.get(space, {}).pop(t, None)
        if group is None:
            return
        held = self._groups[group]
        held.discard(t)
        if not held:
            del self._groups[group]
        self._changes[(group, t)] = False


def retractions(
    leases: Leases,
    space: Callable[[str], SpaceState],
    stamp: Callable[[], str],
    now: float,
    budget: int = BUDGET,
) -> list[tuple[SpaceState, Net | None]]:
    """Decide one changeset per write expired by `now` (about `budget` in cost, see `due`).

    Each retracts what its write still leased.

    Each is attributed to the store (`EXPIRY_AGENT`) and names the expired
    write as its `cause`. Writer thread only; the caller commits them.
    """
    decided = []
    for (name, _expires, request), triples in leases.due(now, budget):
        state = space(name)
        write = WriteRequest(
            id=uuid.uuid4().hex, agent=EXPIRY_AGENT, cause=request, removed=triples
        )
        net, _ = state.decide(write, stamp())
        decided.append((state, net))
    return decided


def _quad(group: _Group, t: _Text) -> ox.Quad:
    return ox.Quad(*_triple(t), lease_graph(group))


def remaining(db: StoreDB, space: str, t: OxTriple, now: float) -> float | None:
    """Return the seconds a triple of a space has left to live (None: permanent)."""
    for q in db.store.quads_for_pattern(t[0], t[1], t[2], None):
        g = q.graph_name
        group = parse_graph(g.value) if isinstance(g, ox.NamedNode) else None
        if group is not None and group[0] == space:
            return max(0.0, group[1] - now)
    return None
