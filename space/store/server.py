"""The store process's Zenoh side: queryables and subscribers of every space.

Zenoh callbacks only enqueue; one worker thread owns the state and the
database, so changesets are applied in one order, acknowledged only once
committed, and published (as whole changesets and as per-triple keys) after.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import zenoh

from space import keys
from space.changeset import Changeset, pack, unpack
from space.errors import MalformedPayload, QueryError, SpaceError
from space.store.db import Commit, StoreDB
from space.store.queries import answer_key_get, answer_query
from space.store.state import SpaceState

log = logging.getLogger("tspace.store")

_BATCH = 256


@dataclass
class _Request:
    kind: str  # "write", "query", "log", "keys"
    space: str
    payload: bytes | None
    query: zenoh.Query | None = None
    key: str = ""


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
        root: str = keys.ROOT,
    ) -> None:
        self.session = session
        self.data_dir = data_dir
        self.durable = durable
        self.root = root
        self._queue: queue.SimpleQueue[_Request | None] = queue.SimpleQueue()
        self._spaces: dict[str, SpaceState] = {}
        self._entities: list = []
        self._db: StoreDB | None = None
        self._worker: threading.Thread | None = None

    def start(self) -> None:
        """Load every space from the database, then start serving."""
        self._db = StoreDB(self.data_dir, durable=self.durable)
        for name in self._db.spaces():
            self._space(name)
        root = self.root
        s = self.session
        self._entities = [
            s.declare_queryable(f"{root}/*/@/write", self._on_query("write")),
            s.declare_subscriber(f"{root}/*/@/write", self._on_put),
            s.declare_queryable(f"{root}/*/@/query", self._on_query("query")),
            s.declare_queryable(f"{root}/*/@/log", self._on_query("log")),
            s.declare_queryable(f"{root}/*/{keys.ASSERTED}/**", self._on_query("keys")),
            s.declare_queryable(f"{root}/*/{keys.INFERRED}/**", self._on_query("keys")),
            s.liveliness().declare_token(f"{root}/@stores/{s.zid()}"),
        ]
        self._worker = threading.Thread(target=self._run, name="tspace-store", daemon=True)
        self._worker.start()
        log.info("store ready: %d space(s) from %s", len(self._spaces), self._db.path)

    def close(self) -> None:
        """Stop serving, finish queued work and close the database (no-op if not started)."""
        for entity in reversed(self._entities):
            entity.undeclare()
        self._entities = []
        if self._worker is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        if self._db is not None:
            self._db.close()
            self._db = None

    # Zenoh callbacks: parse the key, enqueue, return.

    def _on_query(self, kind: str) -> Callable[[zenoh.Query], None]:
        def callback(query: zenoh.Query) -> None:
            key = str(query.key_expr)
            space = key.split("/")[1]
            payload = query.payload.to_bytes() if query.payload is not None else None
            self._queue.put(_Request(kind, space, payload, query, key))

        return callback

    def _on_put(self, sample: zenoh.Sample) -> None:
        space = str(sample.key_expr).split("/")[1]
        self._queue.put(_Request("write", space, sample.payload.to_bytes()))

    # The worker: the only thread that touches state and database.

    def _run(self) -> None:
        while True:
            batch: list[_Request] = []
            item = self._queue.get()
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
            except Exception:  # a bug must not stop the store; the requests time out
                log.exception("store worker failed on a batch of %d request(s)", len(batch))
            if item is None:
                return

    def _handle(self, batch: list[_Request]) -> None:
        pending: list[tuple[_Request, Changeset | None, SpaceState]] = []
        commits: list[Commit] = []
        for req in batch:
            if req.kind != "write":
                self._flush(pending, commits)
                pending, commits = [], []
                self._answer(req)
                continue
            try:
                keys.check_space(req.space)
                cs = Changeset.decode(req.payload or b"")
            except (MalformedPayload, ValueError) as exc:
                self._reject(req, exc)
                if req.query is not None:
                    req.query.drop()
                continue
            state = self._space(req.space)
            if not cs.timestamp:
                cs.timestamp = str(self.session.new_timestamp())
            result = state.apply(cs)
            if result is None:
                pending.append((req, None, state))
            else:
                pending.append((req, result[0], state))
                commits.append(result[1])
        self._flush(pending, commits)

    def _flush(self, pending: list, commits: list[Commit]) -> None:
        if not pending:
            return
        assert self._db is not None
        self._db.commit(commits)
        for req, net, state in pending:
            if req.query is not None:
                ack = {"id": net.id if net else "", "seq": net.seq if net else state.seq}
                _reply(req, pack(ack))
                req.query.drop()
        payloads = iter(c.payload for c in commits)
        for _req, net, state in pending:
            if net is not None:
                self._publish(state, net, next(payloads))

    def _publish(self, state: SpaceState, net: Changeset, payload: bytes) -> None:
        s = self.session
        block = zenoh.CongestionControl.BLOCK
        s.put(keys.service_key(state.name, "changes", self.root), payload, congestion_control=block)
        meta = pack({"id": net.id, "seq": net.seq})
        for graph, removed, added in (
            (keys.ASSERTED, net.removed, net.added),
            (keys.INFERRED, net.inferred_removed, net.inferred_added),
        ):
            for t in removed:
                key = keys.triple_key(state.name, graph, t, state.prefixes, self.root)
                s.delete(key, attachment=meta, congestion_control=block)
            for t in added:
                key = keys.triple_key(state.name, graph, t, state.prefixes, self.root)
                s.put(key, meta, congestion_control=block)

    def _answer(self, req: _Request) -> None:
        try:
            keys.check_space(req.space)
            state = self._space(req.space)
            if req.kind == "keys":
                answer_key_get(state, req.query, self.root)
                return
            if req.kind == "log":
                _reply(req, self._log(state, unpack(req.payload or b"")))
                return
            reply, take = answer_query(state, unpack(req.payload or b""))
            if take is not None and not take.is_empty():
                result = state.apply(take)
                if result is not None:
                    self._flush(
                        [(_Request("write", req.space, None), result[0], state)], [result[1]]
                    )
                    reply["seq"] = result[0].seq
            _reply(req, pack(reply))
        except (SpaceError, ValueError) as exc:
            self._reject(req, exc)
        finally:
            if req.query is not None:
                req.query.drop()

    def _log(self, state: SpaceState, request: object) -> bytes:
        if not isinstance(request, dict):
            raise MalformedPayload("a log request is a map {from, to}")
        first, last = int(request.get("from", 1)), int(request.get("to", state.seq))
        assert self._db is not None
        rows = self._db.log(state.name, first, last)
        return pack({"seq": state.seq, "changes": [payload for _seq, payload in rows]})

    def _reject(self, req: _Request, exc: Exception) -> None:
        what = "rejected" if isinstance(exc, QueryError) else "malformed, skipped:"
        log.warning("%s %s on space %r: %s", what, req.kind, req.space, exc)
        if req.query is not None:
            req.query.reply_err(str(exc).encode())

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


def _reply(req: _Request, payload: bytes) -> None:
    if req.query is not None:
        req.query.reply(req.key, payload)
