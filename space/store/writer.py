"""The store's writer: decide writes and takes, commit them in batches, answer, publish.

Writer thread only. A write or take is decided (`state.py`) into a `Pending`;
a batch of them is committed at once (`db.py`), then each is answered and
published. A commit that
fails makes the store fail-stop: every write is refused until `probe` finds
the database committing again (docs/store.md).
"""

from __future__ import annotations

import logging
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from space import keys
from space.changeset import pack, unpack
from space.errors import QueryError, SpaceError
from space.store import intake
from space.store.db import CommitFailed, NotFlushed, StoreDB
from space.store.guard import Refused, WriteGuard
from space.store.lifespans import Leases, retractions
from space.store.publish import Publisher
from space.store.state import Net, SpaceState

log = logging.getLogger("tspace.store")

PROBE = 2.0  # seconds between attempts to commit again after a failed commit


class SpaceLimit(SpaceError):
    """A write would create a space beyond the store's `--max-spaces`."""


@dataclass
class Request:
    kind: str  # a service ("write", "query", "log", "keys") or "spaces"
    space: str
    payload: bytes | None
    query: zenoh.Query | None = None
    key: str = ""
    writer: str | None = None  # the CN a secure router let write on this key


@dataclass
class Pending:
    """A write or take decided, waiting for its batch's commit to be answered."""

    req: Request
    state: SpaceState
    net: Net | None
    reply: Callable[[Net | None], dict]


class Writer:
    """Decide, commit, answer and publish writes and takes; refuse them after a failed commit.

    Args:
        spaces: the server's loaded spaces, name -> state (read to check the limit).
        space: returns a space's state, loading or creating it.
        guard: in a secure space, what each identity may write; a write or take
            it forbids is refused (and logged, naming the identity) before anything
            is decided.
    """

    def __init__(
        self,
        session: zenoh.Session,
        db: StoreDB,
        *,
        spaces: dict[str, SpaceState],
        space: Callable[[str], SpaceState],
        publisher: Publisher,
        max_spaces: int,
        guard: WriteGuard | None = None,
        leases: Leases | None = None,
    ) -> None:
        self.session = session
        self.guard = guard
        self.db = db
        self.failed = db.open_error  # why writes are refused ("": they are not)
        self.max_spaces = max_spaces
        self._spaces = spaces
        self._space = space
        self._publisher = publisher
        self._next_probe = 0.0
        self._leases = leases
        # The batch's decided changesets by (state, request id), until `commit`: a request sent
        # twice in a batch is found at once (a scan of the batch cost 10 % at 2,000 writes/s).
        self._batch: dict[tuple[int, str], Pending] = {}

    def _pend(self, pending: list[Pending], p: Pending) -> None:
        """Add a decided write, take or expiry to the batch (every batch ends in `commit`)."""
        pending.append(p)
        if p.net is not None:
            self._batch.setdefault((id(p.state), p.net.entry.request), p)

    def _writable(self, name: str) -> SpaceState:
        """Return the state of a space about to be written, creating it within the limit."""
        keys.check_space(name)
        if self.failed:
            raise CommitFailed(
                f"not applied: the store refuses writes since a commit failed ({self.failed}); "
                "it retries every few seconds"
            )
        if name not in self._spaces and len(self._spaces) >= self.max_spaces:
            raise SpaceLimit(
                f"not applied: this store holds at most {self.max_spaces} spaces "
                "(tspace serve --max-spaces)"
            )
        return self._space(name)

    def write(self, req: Request, pending: list[Pending]) -> None:
        write = intake.write_request(req.payload or b"")
        if self.failed and write.id:  # a retry is told its outcome even while writes are refused
            keys.check_space(req.space)
            done = self.db.outcome(req.space, write.id)
            if done is not None:
                _again(req, write.id, done)
                return
        state = self._writable(req.space)
        if self.guard is not None or not state.takes_plain(write):
            write.parse_plain()
            if state.pending_plain:  # decided on texts: commit them before deciding in terms
                self.commit(pending)
                pending.clear()
                state = self._writable(req.space)
        first = self._batch.get((id(state), write.id))
        if first is not None:
            self._reply_later(req, state, pending, first)
            return
        done = self.db.outcome(state.name, write.id) if write.id else None
        if done is not None:
            _again(req, write.id, done)
            return
        self._check(req, write)
        net, dropped = decide(state, write, write.ts or str(self.session.new_timestamp()))

        def reply(net: Net | None) -> dict:
            ack: dict = {"id": write.id, "seq": net.entry.seq if net else state.seq}
            if dropped:
                ack["dropped"] = dropped
            return ack

        self._pend(pending, Pending(req, state, net, reply))

    def _reply_later(
        self, req: Request, state: SpaceState, pending: list[Pending], first: Pending
    ) -> None:
        """Answer a request sent twice within one batch with the first one's outcome."""
        pending.append(
            Pending(req, state, None, lambda _n: {**first.reply(first.net), "again": True})
        )

    def take(self, req: Request, pending: list[Pending]) -> None:
        take = intake.query_request(req.payload or b"")
        keys.check_space(req.space)
        if req.space not in self._spaces:
            answer(req, {"seq": 0, keys.ASSERTED: []})  # nothing to take; create nothing
            return
        state = self._writable(req.space)
        if take.id:
            done = self.db.outcome(state.name, take.id)
            if done is not None:
                removed = unpack(done[1]).get("del") or []  # type: ignore[union-attr]
                answer(req, {"seq": done[0], keys.ASSERTED: removed, "again": True})
                return
        found = list(self.db.match(state.name, "t", take.template))
        write = intake.WriteRequest(id=take.id or uuid.uuid4().hex, agent=take.agent, removed=found)
        if found:
            self._check(req, write, take=True)
        net, _ = state.decide(write, take.ts or str(self.session.new_timestamp()))

        def reply(net: Net | None) -> dict:
            if net is None:
                return {"seq": state.seq, keys.ASSERTED: []}
            return {"seq": net.entry.seq, keys.ASSERTED: net.texts[1]}

        self._pend(pending, Pending(req, state, net, reply))

    def _check(self, req: Request, write: intake.WriteRequest, *, take: bool = False) -> None:
        """Refuse what the policy forbids its writer (no-op outside a secure space).

        Raises:
            Refused: naming the identity and the first triple it may not write.
        """
        if self.guard is None:
            return
        state = self._spaces[req.space]
        why = self.guard.refusal(req.writer, write, state.holds, state.prefixes.compact, take=take)
        if why:
            raise Refused(why)

    def commit(self, pending: list[Pending]) -> None:
        """Commit a batch's changesets at once; then answer and publish, or fail every one."""
        self._batch.clear()
        if not pending:
            return
        decided = [p for p in pending if p.net is not None]
        unflushed: NotFlushed | None = None
        try:
            entries = [p.net.entry for p in decided]  # type: ignore[union-attr]
            self.db.commit(
                entries, self._leases.take_changes() if self._leases is not None else ([], [])
            )
        except NotFlushed as exc:  # `--fsync`: in the database and served, not flushed
            unflushed = exc
        except CommitFailed as exc:
            self._fail(exc, pending)
            return
        for p in pending:
            p.state.settle()
        # Published before answered: watchers hear of a change as soon as it is durable.
        self._publisher.publish([(p.state, p.net) for p in decided])  # type: ignore[misc]
        if unflushed is not None:  # its writers are told just that; writes are refused
            self._refuse(unflushed)
            for p in pending:
                reject(
                    p.req,
                    NotFlushed(f"{unflushed}; a retry of this request is answered as applied"),
                )
            return
        for p in pending:
            if p.req.query is None:
                continue
            p.req.query.reply(p.req.key, pack(p.reply(p.net)))
            p.req.query.drop()

    def _refuse(self, exc: CommitFailed) -> None:
        self.failed = str(exc)
        self._next_probe = time.monotonic() + PROBE
        log.error("%s: refusing writes until a commit works again", exc)

    def _fail(self, exc: CommitFailed, pending: list[Pending]) -> None:
        """Refuse writes from now on; forget what the batch decided; tell every writer."""
        self._refuse(exc)
        for name in {p.state.name for p in pending}:
            self._spaces.pop(name, None)
        for name in {p.state.name for p in pending}:
            self._space(name)  # as the database has it, not as the failed batch would have
        if self._leases is not None:
            self._leases.load(self.db)
        for p in pending:
            reject(p.req, CommitFailed(f"not applied: {exc}"))

    def expire(self, pending: list[Pending], budget: int) -> None:
        """Decide the retraction of writes whose lifespan ran out, about `budget` in cost.

        See `lifespans.py`.
        """
        if self.failed or self._leases is None:
            return
        stamp = lambda: str(self.session.new_timestamp())  # noqa: E731
        for state, net in retractions(self._leases, self._space, stamp, time.time(), budget):
            self._pend(pending, Pending(Request("expire", state.name, None), state, net, _no_reply))

    def collect(self, count: int) -> None:
        """Delete up to `count` lease quads left by expiries, in a commit of their own."""
        if self.failed or self._leases is None or not self._leases.collect(count):
            return
        try:
            self.db.commit([], self._leases.take_changes())
        except CommitFailed as exc:
            self._fail(exc, [])

    def probe(self, busy: int) -> None:
        """After a failed commit, try an empty one now and then; writes resume once one works.

        `busy`: reads running; the database is reopened only while there are none.
        """
        if not self.failed or time.monotonic() < self._next_probe or busy:
            return
        try:
            self.db.probe()
        except CommitFailed as exc:
            self._next_probe = time.monotonic() + PROBE
            log.debug("commit still failing: %s", exc)
            return
        log.warning("the database commits again: writes are accepted again")
        self.failed = ""


def decide(state: SpaceState, write: intake.WriteRequest, stamp: str) -> tuple[Net | None, list]:
    """Decide a write on a space's state; note what it does not apply, in the log and its entry.

    The entry keeps the dropped triples so that a retry is told the same.
    """
    net, dropped = state.decide(write, stamp)
    if dropped:
        log.info(
            "%s on %s: %d triple(s) not applied: %s", write.id, state.name, len(dropped), dropped
        )
        if net is not None:
            net.entry.dropped = pack(dropped)
    return net, dropped


def _no_reply(_net: Net | None) -> dict:
    return {}


def _again(req: Request, ident: str, done: tuple[int, bytes, bytes]) -> None:
    """Answer a write already applied with its first outcome (`StoreDB.outcome`)."""
    again: dict = {"id": ident, "seq": done[0], "again": True}
    if done[2]:
        again["dropped"] = unpack(done[2])
    answer(req, again)


def answer(req: Request, reply: dict) -> None:
    """Reply to a request with a msgpack map (no-op for a fire-and-forget one)."""
    if req.query is not None:
        req.query.reply(req.key, pack(reply))
        req.query.drop()


def reject(req: Request, exc: Exception) -> None:
    """Log a refused request and answer it with the error's sentence."""
    what = (
        "rejected"
        if isinstance(exc, QueryError | CommitFailed | SpaceLimit)
        else "malformed, skipped:"
    )
    log.warning("%s %s on space %r: %s", what, req.kind, req.space[:80], exc)
    if req.query is not None:
        req.query.reply_err(str(exc).encode())
        req.query.drop()
