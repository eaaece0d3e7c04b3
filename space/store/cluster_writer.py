"""A cluster replica's writer: decide on its state, commit through etcd, ack once applied.

Worker thread only (as `writer.py` is for the embedded store). A write or
take is decided on the replica's state (`ClusterSpace`: what it applied plus
its changesets in flight) into a guarded entry (`entry_for`) that
`ClusterNode.append` commits. The entry's guards say "unchanged since the
revision I applied"; an entry decided on a changeset of ours still in flight
(it replaces the value that one wrote, or takes what it added) is chained: it
is appended once that one committed, its guard on those keys raised to that
revision, and fails with it if it fails.

Nothing is acknowledged before the replica itself applied the revision the
changeset committed at (`cluster_apply`): the ack carries the seq every replica gives it, and
the writer reads its own write from the replica that answered. A guard that
no longer holds (`WriteConflict`) sends the request back to be decided again
once the replica caught up with etcd; a request id committed by another
replica conflicts on its `req/` key, and once caught up the replica finds it in
its own log and answers with the first outcome (exactly once).
"""

from __future__ import annotations

import concurrent.futures
import logging
import queue
import secrets
import uuid
from collections.abc import Callable

import zenoh

from space import keys
from space.changeset import unpack
from space.errors import SpaceError, WriteConflict
from space.store import intake
from space.store.cluster_apply import acknowledge, install
from space.store.cluster_expiry import ClusterExpiry
from space.store.cluster_flights import Flight, chain, committed, guarded_entry
from space.store.cluster_node import ClusterNode, Done
from space.store.cluster_state import ClusterSpace
from space.store.db import CommitFailed, StoreDB
from space.store.etcd_applier import Batch
from space.store.guard import Refused, WriteGuard
from space.store.publish import Publisher
from space.store.state import Net
from space.store.writer import Request, SpaceLimit, answer, decide, reject

log = logging.getLogger("tspace.store")

MAX_ATTEMPTS = 20  # decisions of one request before its writer is told it kept conflicting


class ClusterWriter:
    """Decide, commit through etcd, apply, acknowledge and publish, for one replica.

    `events` is the worker's queue: etcd's callbacks put `("done", flight,
    future)`, `("barrier", item, future)` there; the server hands them back
    to `event`.
    """

    def __init__(
        self,
        session: zenoh.Session,
        db: StoreDB,
        node: ClusterNode,
        *,
        root: bytes,
        events: queue.SimpleQueue,
        spaces: dict[str, ClusterSpace],
        space: Callable[[str], ClusterSpace],
        publisher: Publisher,
        max_spaces: int,
        expiry: ClusterExpiry,
        guard: WriteGuard | None = None,
    ) -> None:
        self.session, self.db, self.node, self.root = session, db, node, root
        self.expiry = expiry
        self.guard = guard
        self.max_spaces = max_spaces
        self.revision = 0  # the etcd revision applied into the database
        self.failed = ""  # why this replica cannot apply (a failed commit): restart it
        self._events = events
        self._spaces, self._space, self._publisher = spaces, space, publisher
        self._staged: list[Flight] = []
        self._writers: dict[bytes, Flight] = {}  # key -> our latest flight writing it
        # Our flights by logged payload, which names this writer (`logged_payload`): a retry
        # another replica decided alike, on the same state, is not taken for ours.
        self._by_payload: dict[bytes, Flight] = {}
        self._origin = secrets.token_hex(8)
        self._by_request: dict[tuple[str, str], Flight] = {}
        self._parked: list[tuple[int, Callable[[], None]]] = []  # (revision, what then)
        self._applied: list[tuple[int, list[Batch]]] = []

    # Deciding.

    def write(self, req: Request, attempt: int = 1) -> None:
        write = intake.write_request(req.payload or b"")
        write.parse_plain()  # decided term by term: in-flight decisions overlay in terms
        state = self._writable(req.space)
        if self._again(req, state.name, write.id):
            return
        self._check(req, write, state)
        stamp = write.ts or str(self.session.new_timestamp())
        plan = self.expiry.plan(state, write)  # before deciding: what it finds held
        net, dropped = decide(state, write, stamp)
        net = self.expiry.decided(plan, state, write, net, stamp)

        def reply(n: Net | None) -> dict:
            ack: dict = {"id": write.id, "seq": n.entry.seq if n else state.seq}
            if dropped:
                ack["dropped"] = dropped
            return ack

        if net is None:
            answer(req, reply(None))
            return
        self._stage(req, state, net, reply, stamp, write.id, attempt, taken=False)
        self.expiry.amend(self._staged[-1].entry, state.name, net, write, plan, stamp)

    def take(self, req: Request, attempt: int = 1) -> None:
        take = intake.query_request(req.payload or b"")
        keys.check_space(req.space)
        if req.space not in self._spaces:
            answer(req, {"seq": 0, keys.ASSERTED: []})
            return
        state = self._writable(req.space)
        ident = take.id or uuid.uuid4().hex
        if self._again(req, state.name, ident, take=True):
            return
        found = list(self.db.match(state.name, "t", take.template))
        write = intake.WriteRequest(id=ident, agent=take.agent, removed=found)
        if found:
            self._check(req, write, state, take=True)
        stamp = take.ts or str(self.session.new_timestamp())
        net, _ = state.decide(write, stamp)
        if net is None:
            answer(req, {"seq": state.seq, keys.ASSERTED: []})
            return
        reply = lambda n: {"seq": n.entry.seq, keys.ASSERTED: n.texts[1]}  # noqa: E731
        self._stage(req, state, net, reply, stamp, ident, attempt, taken=True)
        self.expiry.amend(self._staged[-1].entry, state.name, net)

    def _again(self, req: Request, space: str, ident: str, *, take: bool = False) -> bool:
        """Answer a request id already applied (the first outcome), or join one in flight."""
        if not ident:
            return False
        flying = self._by_request.get((space, ident))
        if flying is not None:
            flying.followers.append(req)
            return True
        done = self.db.outcome(space, ident)
        if done is None:
            return False
        if take:
            removed = unpack(done[1]).get("del") or []  # type: ignore[union-attr]
            answer(req, {"seq": done[0], keys.ASSERTED: removed, "again": True})
        else:
            again: dict = {"id": ident, "seq": done[0], "again": True}
            if done[2]:
                again["dropped"] = unpack(done[2])
            answer(req, again)
        return True

    def _writable(self, name: str) -> ClusterSpace:
        keys.check_space(name)
        if self.failed:
            raise CommitFailed(f"not applied: this replica cannot apply the log ({self.failed})")
        if name not in self._spaces and len(self._spaces) >= self.max_spaces:
            raise SpaceLimit(
                f"not applied: this store holds at most {self.max_spaces} spaces "
                "(tspace serve --max-spaces)"
            )
        return self._space(name)

    def _check(
        self, req: Request, write: intake.WriteRequest, state: ClusterSpace, *, take: bool = False
    ) -> None:
        if self.guard is None:
            return
        why = self.guard.refusal(req.writer, write, state.holds, state.prefixes.compact, take=take)
        if why:
            raise Refused(why)

    def _stage(
        self,
        req: Request,
        state: ClusterSpace,
        net: Net,
        reply: Callable[[Net], dict],
        stamp: str,
        ident: str,
        attempt: int,
        *,
        taken: bool,
    ) -> None:
        entry = guarded_entry(
            self.root, state, net, self.revision, stamp, ident, taken=taken, origin=self._origin
        )
        flight = Flight(req, state, net, reply, entry, attempt, ident)
        self._by_payload[entry.payload] = flight
        self._by_request[(state.name, ident)] = flight
        self._staged.append(flight)

    def sweep(self) -> None:
        """Decide and send the expiries due (`cluster_expiry`); worker thread, between batches."""
        if self.failed:
            return
        stamp = lambda: str(self.session.new_timestamp())  # noqa: E731
        flying = lambda key: key in self._writers  # noqa: E731
        try:
            for x in self.expiry.due(self._space, stamp, flying):
                ask = Request("expire", x.state.name, None)
                self._stage(ask, x.state, x.net, lambda _n: {}, x.stamp, x.request, 1, taken=False)
                self.expiry.guard(self._staged[-1].entry, x, self.revision)
        except Exception:  # a bug must not stop the replica: its writes go on
            log.exception("replica failed sweeping expired writes")
        self.flush()

    # Committing.

    def flush(self) -> None:
        """Send what was decided, chained on our flights it read (before anything is applied)."""
        staged, self._staged = self._staged, []
        self._send([flight for flight in staged if chain(flight, self._writers)])

    def _send(self, flights: list[Flight]) -> None:
        """Hand flights to etcd's thread at once; each one's outcome comes back as an event."""
        if flights:
            put = self._events.put
            self.node.append_all(
                [f.entry for f in flights], lambda i, f: put(("done", flights[i], f))
            )

    def event(self, item: tuple) -> None:
        """Handle what etcd's thread reported (worker thread)."""
        kind = item[0]
        if kind == "done":
            self._done(item[1], item[2])
        elif kind == "apply":
            self._applied.append((item[1], item[2]))
        elif kind == "relist":
            self.apply_pending()
            self._relist(item[1])
        elif kind == "barrier":
            self._barrier(item[1], item[2])

    def _done(self, flight: Flight, future: Done) -> None:
        if future.cancelled():
            self._fail(flight, SpaceError("not applied: the replica is stopping"))
            return
        error = future.exception()
        if error is None:
            self._send(committed(flight, future.result()))
            return
        if isinstance(error, WriteConflict):
            self._conflict(flight)
        else:
            self._fail(flight, error)

    def _end(self, flight: Flight) -> None:
        flight.over = True
        self._by_payload.pop(flight.entry.payload, None)
        self._by_request.pop((flight.state.name, flight.request), None)
        for key in flight.writes:
            if self._writers.get(key) is flight:
                del self._writers[key]

    def _fail(self, flight: Flight, error: BaseException) -> None:
        """Tell the writer (and those chained on it) why it was not committed."""
        if flight.over:
            return
        self._end(flight)
        flight.state.failed(flight.net.entry)
        if not self._expiry_again(flight):
            for req in (flight.req, *flight.followers):
                reject(req, error if isinstance(error, Exception) else SpaceError(str(error)))
        for w in flight.waiting:
            self._conflict(w)

    def _conflict(self, flight: Flight) -> None:
        """Decide a request again once this replica applied what etcd committed by now."""
        if flight.over:
            return
        self._end(flight)
        flight.state.failed(flight.net.entry)
        for w in flight.waiting:
            self._conflict(w)
        if self._expiry_again(flight):
            return
        if flight.attempt >= MAX_ATTEMPTS:
            error = SpaceError(
                f"not applied: {MAX_ATTEMPTS} decisions in a row conflicted; try again"
            )
            for req in (flight.req, *flight.followers):
                reject(req, error)
            return
        retry = (flight.req, flight.attempt + 1, flight.followers)
        self.ask_barrier(("redecide", retry))

    def _expiry_again(self, flight: Flight) -> bool:
        """Leave an expiry not committed to the next sweep; return whether it was one."""
        return flight.req.kind == "expire" and self.expiry.retry(flight.request)

    def ask_barrier(self, item: tuple) -> None:
        """Put `item` back on the worker's queue once this replica applied etcd's revision now.

        `("reads", [requests])` or `("redecide", (request, attempt, followers))`;
        on a minority side their requests are refused with `NoQuorum`.
        """
        future = self.node.barrier()
        future.add_done_callback(lambda f: self._events.put(("barrier", item, f)))

    def _barrier(self, item: tuple, future: concurrent.futures.Future) -> None:
        error = None if future.cancelled() else future.exception()
        what, arg = item
        if future.cancelled() or error is not None:
            reqs = [arg[0], *arg[2]] if what == "redecide" else list(arg)
            for req in reqs:
                reject(req, error if isinstance(error, Exception) else SpaceError("stopping"))
            return
        revision = future.result()
        self.when_applied(revision, lambda: self._events.put((what, arg)))

    def when_applied(self, revision: int, then: Callable[[], None]) -> None:
        """Run `then` once this replica applied `revision` (at once if it has)."""
        if revision <= self.revision:
            then()
        else:
            self._parked.append((revision, then))

    # Applying.

    def apply_pending(self) -> None:
        """Apply every revision handed over, in one database update; ack and publish ours.

        What was decided before is sent first: its guards are at the revision it saw.
        """
        self.flush()
        if not self._applied:
            return
        applied, self._applied = self._applied, []
        if self.failed:
            return
        nets, ours = install(applied, self._space, self._by_payload, self.expiry)
        last = applied[-1][0]
        try:
            self.db.commit([n.entry for _, n in nets], self.expiry.changes(), revision=last)
        except CommitFailed as exc:
            self.failed = str(exc)
            log.error("cannot apply revision %d: %s; restart this replica to resume", last, exc)
            return
        self.revision = last
        for flight, _ in ours:
            self._end(flight)
            flight.state.landed(flight.net.entry)
        for state in {id(s): s for s, _ in nets}.values():
            state.settle()
        acknowledge(nets, ours, self._publisher)
        self._release()

    def _release(self) -> None:
        ready = [then for revision, then in self._parked if revision <= self.revision]
        self._parked = [(r, t) for r, t in self._parked if r > self.revision]
        for then in ready:
            then()

    def _relist(self, listing: object) -> None:
        from space.store.cluster_db import replace_all
        from space.store.cluster_entries import read_state

        revision, pairs, seqs = listing.revision, listing.pairs, listing.seqs  # type: ignore[attr-defined]
        self.expiry.forget(self.db)
        try:
            replace_all(self.db, read_state(self.root, pairs), seqs, revision)
        except CommitFailed as exc:
            self.failed = str(exc)
            log.error("cannot install the re-listed state: %s; restart this replica", exc)
            return
        log.warning("re-listed every space at revision %d", revision)
        self.revision = revision
        self._spaces.clear()
        for flight in list(self._by_payload.values()):
            if flight.position is not None and flight.position.revision <= revision:
                self._end(flight)
                answer(flight.req, {"id": flight.request, "seq": seqs.get(flight.state.name, 0)})
        self._release()
