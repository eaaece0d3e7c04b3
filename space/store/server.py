"""The store process's Zenoh side: one worker thread serving every space.

Zenoh callbacks only enqueue; one worker thread owns the state and the
database, so changesets are applied in one order, acknowledged only once
committed (and, with replicas, once every follower has them), and published
after, as whole changesets and as per-triple keys.

Several stores may hold the same spaces: `roles.py` decides which one leads
(and serves them) and which follow; this module says what each role declares.
"""

from __future__ import annotations

import gc
import logging
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import zenoh

from space import keys
from space.changeset import Changeset, pack, unpack
from space.errors import MalformedPayload, QueryError, SpaceError
from space.store.acks import AckGate
from space.store.db import Commit, StoreDB
from space.store.guard import WriteGuard, writer_of
from space.store.queries import answer_key_get, answer_query
from space.store.replica import Replica
from space.store.roles import Roles
from space.store.state import SpaceState

log = logging.getLogger("tspace.store")

_BATCH = 256
HEARTBEAT = 0.5  # seconds between publications of each space's sequence number
_SERVICES = ("write", "query", "log", "keys")


@dataclass
class _Request:
    kind: str  # a service, or "replica", "ack", "peer", "spaces", "state"
    space: str
    payload: bytes | None
    query: zenoh.Query | None = None
    key: str = ""
    writer: str | None = None  # the CN a secure router let write on this key


class StoreServer:
    """Serve every space of a database on a Zenoh session.

    Construct, then `start()`; `close()` undeclares everything and closes the
    database. The session belongs to the caller.
    """

    def __init__(
        self,
        session: zenoh.Session,
        data_dir: Path,
        *,
        durable: bool = False,
        log_keep: int = 100_000,
        root: str = keys.ROOT,
        look_for_leader: float = 0.0,
        guard: WriteGuard | None = None,
    ) -> None:
        self.session = session
        self.guard = guard
        self.log_keep = log_keep
        self.data_dir = data_dir
        self.durable = durable
        self.root = root
        self._queue: queue.SimpleQueue[_Request | None] = queue.SimpleQueue()
        self._spaces: dict[str, SpaceState] = {}
        self._acks = AckGate()
        self._roles = Roles(
            session,
            root,
            self._acks,
            look_for_leader=look_for_leader,
            leading=self._serve_leading,
            following=self._serve_following,
            seqs=self._seqs,
        )
        self._graph_publishers: dict[tuple[str, str], zenoh.Publisher] = {}
        self._db: StoreDB | None = None
        self._worker: threading.Thread | None = None

    def start(self, timeout: float = 10.0) -> None:
        """Load every space from the database, find the leader or lead, then serve.

        Blocks until this store leads or has caught up with the leader, or for
        `timeout` seconds (a follower behind goes on trying in the background).
        """
        self._db = StoreDB(self.data_dir, durable=self.durable, log_keep=self.log_keep)
        replica = Replica(self.session, self.root, self._db, self._space, self._forget)
        for name in self._db.spaces():
            self._space(name)
        self._roles.open(replica, self._on_peer)
        self._worker = threading.Thread(target=self._run, name="tspace-store", daemon=True)
        self._worker.start()
        if not self._roles.ready.wait(timeout):
            log.warning("store not ready after %g s (still catching up)", timeout)
        log.info(
            "store %s %s: %d space(s) from %s",
            self._roles.zid,
            self._roles.role,
            len(self._spaces),
            self._db.path,
        )

    def close(self) -> None:
        """Stop serving, finish queued work and close the database (no-op if not started)."""
        self._roles.close()
        if self._worker is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        for publisher in self._graph_publishers.values():
            publisher.undeclare()
        self._graph_publishers = {}
        if self._db is not None:
            self._db.close()
            self._db = None

    # Zenoh callbacks: parse the key, enqueue, return.

    def _on_query(self, kind: str) -> Callable[[zenoh.Query], None]:
        def callback(query: zenoh.Query) -> None:
            key = str(query.key_expr)
            space = key.split("/")[1]
            payload = query.payload.to_bytes() if query.payload is not None else None
            self._queue.put(_Request(kind, space, payload, query, key, writer_of(key)))

        return callback

    def _on_sample(self, kind: str) -> Callable[[zenoh.Sample], None]:
        def callback(sample: zenoh.Sample) -> None:
            key = str(sample.key_expr)
            space = key.split("/")[1]
            payload = sample.payload.to_bytes()
            self._queue.put(_Request(kind, space, payload, key=key, writer=writer_of(key)))

        return callback

    def _on_peer(self, what: str) -> Callable[[zenoh.Sample], None]:
        def callback(sample: zenoh.Sample) -> None:
            zid = str(sample.key_expr).rsplit("/", 1)[1]
            alive = sample.kind == zenoh.SampleKind.PUT
            self._queue.put(_Request("peer", what, pack([zid, alive])))

        return callback

    # The worker: the only thread that touches state and database.

    def _run(self) -> None:
        self._roles.decide()
        next_beat = time.monotonic()
        while True:
            self._roles.retry()
            if time.monotonic() >= next_beat:
                self._heartbeat()
                next_beat = time.monotonic() + HEARTBEAT
            batch: list[_Request] = []
            wait = next_beat - time.monotonic()
            held = self._acks.wait_time()
            try:
                item = self._queue.get(timeout=max(0.0, wait if held is None else min(wait, held)))
            except queue.Empty:
                item = _Request("tick", "", None)
            while item is not None:
                batch.append(item)
                if len(batch) >= _BATCH:
                    break
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
            try:
                self._handle(batch)
                self._acks.release()
            except Exception:  # a bug must not stop the store; the requests time out
                log.exception("store worker failed on a batch of %d request(s)", len(batch))
            if item is None:
                return

    def _handle(self, batch: list[_Request]) -> None:
        pending: list[tuple[_Request, Changeset | None, SpaceState]] = []
        commits: list[Commit] = []
        replicas: list[_Request] = []
        for req in batch:
            if req.kind == "replica":
                replicas.append(req)
                continue
            if req.kind != "write":
                self._flush(pending, commits)
                pending, commits = [], []
                self._other(req)
                continue
            try:
                keys.check_space(req.space)
                cs = Changeset.decode(req.payload or b"")
            except (MalformedPayload, ValueError) as exc:
                self._reject(req, exc)
                continue
            state = self._space(req.space)
            if self.guard is not None and (why := self.guard.refusal(req.writer, state, cs)):
                self._reject(req, QueryError(why))
                continue
            if not cs.timestamp:
                cs.timestamp = str(self.session.new_timestamp())
            result = state.apply(cs)
            pending.append((req, result[0] if result else None, state))
            if result is not None:
                commits.append(result[1])
        self._flush(pending, commits)
        if replicas:
            self._roles.follow([(r.space, r.payload or b"") for r in replicas])

    def _flush(self, pending: list, commits: list[Commit]) -> None:
        if not pending:
            return
        assert self._db is not None
        self._db.commit(commits)
        for req, net, state in pending:
            if req.query is not None:
                seq = net.seq if net else state.seq
                ack = pack({"id": net.id if net else "", "seq": seq})
                if not self._acks.hold(state.name, seq, req.query, req.key, ack):
                    req.query.reply(req.key, ack)
                    req.query.drop()
        published = [(net, state) for _req, net, state in pending if net is not None]
        block = zenoh.CongestionControl.BLOCK
        # The whole changesets first (every agent waits for them), then their triples' keys.
        for (_net, state), commit in zip(published, commits, strict=True):
            key = keys.service_key(state.name, "changes", self.root)
            self.session.put(key, commit.payload, congestion_control=block)
        for net, state in published:
            self._publish_triples(state, net)

    def _publish_triples(self, state: SpaceState, net: Changeset) -> None:
        """Publish each triple of a net changeset on its key, for plain Zenoh subscribers.

        A graph nobody subscribes to is skipped without making its keys (Zenoh
        would drop the samples anyway): a 600-triple answer then costs nothing here.
        """
        s = self.session
        block = zenoh.CongestionControl.BLOCK
        meta = pack({"id": net.id, "seq": net.seq})
        for graph, removed, added in (
            (keys.ASSERTED, net.removed, net.added),
            (keys.INFERRED, net.inferred_removed, net.inferred_added),
        ):
            if not (removed or added) or not self._watched(state.name, graph):
                continue
            for t in removed:
                key = keys.triple_key(state.name, graph, t, state.prefixes, self.root)
                s.delete(key, attachment=meta, congestion_control=block)
            for t in added:
                key = keys.triple_key(state.name, graph, t, state.prefixes, self.root)
                s.put(key, meta, congestion_control=block)

    def _watched(self, space: str, graph: str) -> bool:
        """Return whether any subscriber matches a graph's triple keys (Zenoh's matching status)."""
        publisher = self._graph_publishers.get((space, graph))
        if publisher is None:
            key = f"{self.root}/{space}/{graph}/**"
            publisher = self._graph_publishers[(space, graph)] = self.session.declare_publisher(key)
        return publisher.matching_status.matching

    def _heartbeat(self) -> None:
        """Publish each space's sequence number, so subscribers learn of changes they missed."""
        if self._roles.role != "leading":
            return
        for name, state in self._spaces.items():
            if state.seq:
                self.session.put(keys.service_key(name, "seq", self.root), pack({"seq": state.seq}))

    def _other(self, req: _Request) -> None:
        if req.kind == "peer":
            self._roles.peer(req.space, *unpack(req.payload or b""))  # type: ignore[misc]
        elif req.kind == "ack":
            self._ack(req.payload or b"")
        elif req.kind == "spaces":
            reply = pack(self._seqs())
            self._answer(req, lambda: reply)
        elif req.kind == "state":
            self._answer(req, lambda: self._copy(unpack(req.payload or b"")))
        elif req.kind in _SERVICES:
            self._answer(req, lambda: self._service(req))

    def _service(self, req: _Request) -> bytes:
        keys.check_space(req.space)
        state = self._space(req.space)
        if req.kind == "keys":
            assert req.query is not None
            answer_key_get(state, req.query, self.root)
            return b""
        if req.kind == "log":
            return self._log(state, unpack(req.payload or b""))
        reply, take = answer_query(state, unpack(req.payload or b""))
        if take is not None and not take.is_empty():
            if self.guard is not None and (
                why := self.guard.refusal(req.writer, state, take, take=True)
            ):
                raise QueryError(why)
            result = state.apply(take)
            if result is not None:
                self._flush([(_Request("write", req.space, None), result[0], state)], [result[1]])
                reply["seq"] = result[0].seq
        return pack(reply)

    def _answer(self, req: _Request, produce: Callable[[], bytes]) -> None:
        try:
            payload = produce()
            if payload and req.query is not None:
                req.query.reply(req.key, payload)
        except (SpaceError, ValueError) as exc:
            self._reject(req, exc)
            return
        if req.query is not None:
            req.query.drop()

    def _log(self, state: SpaceState, request: object) -> bytes:
        if not isinstance(request, dict):
            raise MalformedPayload("a log request is a map {from, to}")
        first, last = int(request.get("from", 1)), int(request.get("to", state.seq))
        assert self._db is not None
        rows = self._db.log(state.name, first, last)
        return pack({"seq": state.seq, "changes": [payload for _seq, payload in rows]})

    def _copy(self, request: object) -> bytes:
        """Return a space whole, for a follower whose own copy cannot be continued."""
        if not isinstance(request, dict) or not isinstance(request.get("space"), str):
            raise MalformedPayload("a state request is a map {space}")
        state = self._space(request["space"])
        assert self._db is not None
        last = self._db.log(state.name, state.seq, state.seq)
        return pack(
            {
                "seq": state.seq,
                "last": last[0][1] if last else b"",
                "prefixes": self._db.prefixes(state.name),
                "rows": list(self._db.triples(state.name)),
            }
        )

    def _forget(self, name: str) -> None:
        """Drop a space's state from memory (its database was replaced: `_space` reloads it)."""
        self._spaces.pop(name, None)
        gc.unfreeze()  # frozen at start (space.heap), the old state could never be freed

    def _reject(self, req: _Request, exc: Exception) -> None:
        what = "rejected" if isinstance(exc, QueryError) else "malformed, skipped:"
        log.warning("%s %s on space %r: %s", what, req.kind, req.space, exc)
        if req.query is not None:
            req.query.reply_err(str(exc).encode())
            req.query.drop()

    def _space(self, name: str) -> SpaceState:
        state = self._spaces.get(name)
        if state is None:
            state = SpaceState(name)
            assert self._db is not None
            state.prefixes.update(self._db.prefixes(name))
            state.load(self._db.triples(name))
            state.seq = self._db.last_seq(name)
            self._spaces[name] = state
        return state

    # What this store serves in each role (declared by `Roles`, on the worker).

    def _serve_leading(self) -> list:
        root, s = self.root, self.session
        on_query = self._on_query
        return [
            s.declare_queryable(f"{root}/*/@/write", on_query("write")),
            s.declare_subscriber(f"{root}/*/@/write", self._on_sample("write")),
            s.declare_queryable(f"{root}/*/@/query", on_query("query")),
            # The same services, under the name of the writer (see space.store.guard).
            s.declare_queryable(f"{root}/*/@/write/*", on_query("write")),
            s.declare_subscriber(f"{root}/*/@/write/*", self._on_sample("write")),
            s.declare_queryable(f"{root}/*/@/query/*", on_query("query")),
            s.declare_queryable(f"{root}/*/@/log", on_query("log")),
            s.declare_queryable(f"{root}/*/{keys.ASSERTED}/**", on_query("keys")),
            s.declare_queryable(f"{root}/*/{keys.INFERRED}/**", on_query("keys")),
            s.declare_queryable(f"{root}/@repl/spaces", on_query("spaces")),
            s.declare_queryable(f"{root}/@repl/state", on_query("state")),
            s.declare_subscriber(f"{root}/@repl/ack", self._on_sample("ack")),
        ]

    def _serve_following(self) -> list:
        changes = f"{self.root}/*/@/changes"
        return [self.session.declare_subscriber(changes, self._on_sample("replica"))]

    def _seqs(self) -> dict[str, int]:
        return {name: state.seq for name, state in self._spaces.items()}

    def _ack(self, payload: bytes) -> None:
        message = unpack(payload)
        if isinstance(message, dict) and isinstance(message.get("seqs"), dict):
            self._acks.acked(str(message.get("store")), message["seqs"])
