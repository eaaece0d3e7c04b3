"""The store process's Zenoh side: one writer thread for every space, reads beside it.

Zenoh callbacks only enqueue. The writer thread takes requests in arrival
order: writes and takes are decided (`state.py`), committed as one batch
with their log entries (`db.py`), acknowledged only once committed, then
published. A read is handed, in its turn, to a reader thread (`readers.py`):
it sees every write acknowledged before it was sent, and a slow one never
holds up the writer.

One store holds its spaces; a fleet that must survive the loss of a store host
runs replicas on etcd instead (`cluster_server.py`, `tspace serve --cluster`).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from pathlib import Path

import zenoh

from space import keys
from space.changeset import pack, unpack
from space.errors import MalformedPayload, QueryError, SpaceError
from space.store import intake, lifespans, queries
from space.store.db import StoreDB
from space.store.guard import WriteGuard, writer_of
from space.store.lifespans import Leases
from space.store.publish import Publisher
from space.store.readers import Readers
from space.store.state import SpaceState
from space.store.writer import Pending, Request, Writer, answer, reject

log = logging.getLogger("tspace.store")

_BATCH = 256
HEARTBEAT = 0.5  # seconds between publications of each space's sequence number
OVERDUE = 0.02  # seconds late from which an expiry turn runs even while requests wait
BUSY = 0.05  # seconds after a request during which expiry turns are one write each
_READS = ("query", "log", "keys")


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
        query_timeout: float = 10.0,
        query_slots: int = 16,
        max_spaces: int = 10_000,
        guard: WriteGuard | None = None,
    ) -> None:
        self.session = session
        self.guard = guard
        self.log_keep = log_keep
        self.data_dir = data_dir
        self.durable = durable
        self.root = root
        self.max_spaces = max_spaces
        self._queue: queue.SimpleQueue[Request | None] = queue.SimpleQueue()
        self._spaces: dict[str, SpaceState] = {}
        self._declared: list = []
        self._readers = Readers(limit=query_timeout, slots=query_slots)
        self._publisher = Publisher(session, root)
        self._db: StoreDB | None = None
        self._worker: threading.Thread | None = None
        self._writer: Writer | None = None
        self._leases = Leases()
        self._busy_until = 0.0  # monotonic time until which requests are coming in

    def start(self) -> None:
        """Open the database, then serve.

        Raises:
            DataDirInUse: another store has the data directory open.
            OldDataDir: an old data directory could not be migrated.
        """
        self._db = StoreDB(self.data_dir, durable=self.durable, log_keep=self.log_keep)
        if self._db.open_error:
            log.error("%s: serving reads, refusing writes until it commits", self._db.open_error)
        self._writer = Writer(
            self.session,
            self._db,
            spaces=self._spaces,
            space=self._space,
            publisher=self._publisher,
            max_spaces=self.max_spaces,
            guard=self.guard,
            leases=self._leases,
        )
        self._leases.load(self._db)
        for name in self._db.spaces():
            self._space(name)
        self._worker = threading.Thread(target=self._run, name="tspace-store", daemon=True)
        self._worker.start()
        self._declared = self._serve()
        log.info("store: %d space(s) from %s", len(self._spaces), self._db.path)

    def close(self) -> None:
        """Stop serving, finish queued work and close the database (no-op if not started)."""
        for declared in self._declared:
            declared.undeclare()
        self._declared = []
        if self._worker is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        self._readers.close()
        self._publisher.close()
        if self._db is not None:
            self._db.close()
            self._db = None

    # Zenoh callbacks: parse the key, enqueue, return.

    def _on_query(self, kind: str) -> Callable[[zenoh.Query], None]:
        def callback(query: zenoh.Query) -> None:
            key = str(query.key_expr)
            space = key.split("/")[1]
            payload = query.payload.to_bytes() if query.payload is not None else None
            self._queue.put(Request(kind, space, payload, query, key, writer_of(key)))

        return callback

    def _on_sample(self, kind: str) -> Callable[[zenoh.Sample], None]:
        def callback(sample: zenoh.Sample) -> None:
            key = str(sample.key_expr)
            space = key.split("/")[1]
            payload = sample.payload.to_bytes()
            self._queue.put(Request(kind, space, payload, key=key, writer=writer_of(key)))

        return callback

    # The writer: the only thread that decides and commits.

    def _run(self) -> None:
        next_beat = time.monotonic()
        while True:
            if time.monotonic() >= next_beat:
                self._heartbeat()
                self._writer.probe(self._readers.running)
                next_beat = time.monotonic() + HEARTBEAT
            batch: list[Request] = []
            wait = min(next_beat - time.monotonic(), self._expiry_wait())
            try:
                item = self._queue.get(timeout=max(0.0, wait))
            except queue.Empty:
                item = Request("tick", "", None)
            while item is not None:
                batch.append(item)
                if len(batch) >= _BATCH:
                    break
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
            self._handle(batch)
            if item is None:
                return
            if batch[0].kind != "tick":
                self._busy_until = time.monotonic() + BUSY
            if self._queue.empty() or self._expiry_overdue():
                self._sweep()

    def _handle(self, batch: list[Request]) -> None:
        pending: list[Pending] = []
        for req in batch:
            try:
                if req.kind == "write":
                    self._writer.write(req, pending)
                    continue
                self._writer.commit(pending)
                pending = []
                if req.kind == "query" and _op(req.payload) == "take":
                    self._writer.take(req, pending)
                    self._writer.commit(pending)
                    pending = []
                else:
                    self._other(req)
            except (SpaceError, ValueError) as exc:
                reject(req, exc)
            except Exception as exc:  # a bug must not stop the store nor leave a caller waiting
                log.exception("store failed on a %s request for %r", req.kind, req.space)
                reject(req, QueryError(f"internal error: {type(exc).__name__}: {exc}"))
        self._writer.commit(pending)

    def _heartbeat(self) -> None:
        """Publish each space's sequence number, so subscribers learn of changes they missed."""
        for name, state in self._spaces.items():
            if state.seq:
                self.session.put(keys.service_key(name, "seq", self.root), pack({"seq": state.seq}))

    def _other(self, req: Request) -> None:
        if req.kind == "spaces":
            answer(req, self._seqs())
        elif req.kind in _READS:
            self._read(req)

    def _read(self, req: Request) -> None:
        """Hand a read to a reader thread: it starts after every write queued before it."""
        assert req.query is not None
        db, root = self._db_(), self.root
        if req.kind == "keys":
            spaces = self._key_spaces(req.key)
            self._readers.submit(
                req.query, req.key, lambda _d: queries.key_get(db, spaces, req.query, root)
            )
            return
        space = keys.check_space(req.space)
        if req.kind == "log":
            first, last = intake.log_request(req.payload or b"", 2**62)
            self._readers.submit(
                req.query, req.key, lambda _d: queries.log_entries(db, space, first, last)
            )
            return
        read = intake.query_request(req.payload or b"")
        if read.op == "sparql":
            job = lambda d: queries.sparql(db, space, read.text, d)  # noqa: E731
        else:
            job = lambda d: queries.read(db, space, read, d)  # noqa: E731
        self._readers.submit(req.query, req.key, job, read.limit)

    def _key_spaces(self, key: str) -> list[str]:
        """Return the known spaces a GET on triple keys may name (none is created)."""
        chunk = key.split("/")[1]
        if "*" not in chunk and "$" not in chunk:
            return [keys.check_space(chunk)]  # read from the database as it is: nothing created
        selector = zenoh.KeyExpr(key)
        return [
            n for n in self._spaces if selector.intersects(zenoh.KeyExpr(f"{self.root}/{n}/**"))
        ]

    def _db_(self) -> StoreDB:
        assert self._db is not None
        return self._db

    def _space(self, name: str) -> SpaceState:
        state = self._spaces.get(name)
        if state is None:
            state = self._spaces[name] = SpaceState(name, self._db_())
            state.leases = self._leases
        return state

    def _sweep(self) -> None:
        """Commit one turn of expiries on its own, between batches (writes never wait for more).

        It runs when no request waits, or when expiries are late by `OVERDUE` (so a
        steady stream of writes cannot hold them back for ever). While requests come
        in (one within `BUSY` s), a turn is one expired write, so a write arriving
        meanwhile waits for that one's commit at most; else about `lifespans.BUDGET`
        triples' worth, to sweep a mass expiry fast.
        """
        pending: list[Pending] = []
        busy = time.monotonic() < self._busy_until
        try:
            self._writer.expire(pending, lifespans.BUSY if busy else lifespans.BUDGET)
            self._writer.commit(pending)  # a failed commit: the writer refuses writes, says why
            if not pending:  # nothing due: delete a few lease quads left by expiries
                self._writer.collect(lifespans.GARBAGE_BUSY if busy else lifespans.GARBAGE)
        except Exception:  # a bug must not stop the store
            log.exception("store failed sweeping expired writes")

    def _expiry_overdue(self) -> bool:
        due = self._leases.next_due()
        return due is not None and due < time.time() - OVERDUE

    def _expiry_wait(self) -> float:
        """Return the seconds until the next lease expires (a heartbeat if none).

        No wait while lease quads left by expiries remain to delete (a turn of them each).
        """
        if self._leases.garbage and not self._writer.failed:
            return 0.0
        due = self._leases.next_due()
        if due is None:
            return HEARTBEAT
        return max(0.0, due - time.time())

    def _serve(self) -> list:
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
            # A subscriber that sees this token come back (a cut between us healed)
            # fetches what it missed from the log (space.client, `_watch_store`).
            s.liveliness().declare_token(f"{root}/@leader/{s.zid()}"),
        ]

    def _seqs(self) -> dict[str, int]:
        return {name: state.seq for name, state in self._spaces.items()}


def _op(payload: bytes | None) -> object:
    """Return a query request's op without checking the rest (takes go to the writer)."""
    try:
        wire = unpack(payload or b"")
    except MalformedPayload:
        return None
    return wire.get("op") if isinstance(wire, dict) else None
