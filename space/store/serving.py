"""What the embedded store and a cluster replica serve alike: Zenoh's side of a store.

Both enqueue every request from Zenoh's callbacks and handle it on one worker
thread; both hand reads to reader threads and publish each space's sequence
number. They differ in how a write is decided and committed (`server.py`
commits to its own database, `cluster_server.py` through etcd's log).
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable

import zenoh

from space import keys
from space.changeset import unpack
from space.errors import MalformedPayload
from space.store import intake, queries
from space.store.db import StoreDB
from space.store.guard import writer_of
from space.store.publish import Publisher
from space.store.readers import Readers
from space.store.watchdog import Watchdog
from space.store.writer import Request


class Serving:
    """The Zenoh side shared by `StoreServer` and `ClusterStoreServer`."""

    session: zenoh.Session
    root: str
    _spaces: dict

    def __init__(self, query_timeout: float, query_slots: int) -> None:
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._readers = Readers(limit=query_timeout, slots=query_slots)
        self._publisher = Publisher(self.session, self.root)
        self._db: StoreDB | None = None
        self._worker: threading.Thread | None = None
        self._watchdog: Watchdog | None = None
        self._declared: list = []

    def close(self) -> None:
        """Stop serving, finish queued work and close the database (no-op if not started)."""
        for declared in self._declared:
            declared.undeclare()
        self._declared = []
        if self._worker is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        if self._watchdog is not None:
            self._watchdog.close()
            self._watchdog = None
        self._stop()
        self._readers.close()
        self._publisher.close()
        if self._db is not None:
            self._db.close()
            self._db = None

    def _start_worker(self, run: Callable[[], None], name: str) -> None:
        """Start the thread that decides and commits, and a watchdog that says when it is stuck."""
        self._worker = threading.Thread(target=run, name=name, daemon=True)
        self._watchdog = Watchdog(self._worker, f"the store's {name} thread")
        self._worker.start()
        self._watchdog.start()

    def _beat(self) -> None:
        """Tell the watchdog the worker finished a turn (from the worker)."""
        assert self._watchdog is not None
        self._watchdog.beat()

    def _stop(self) -> None:
        """Close what the worker fed once it has stopped (a subclass's own parts)."""

    # Zenoh callbacks: parse the key, enqueue, return.

    def _on_query(self, kind: str) -> Callable[[zenoh.Query], None]:
        def callback(query: zenoh.Query) -> None:
            key = str(query.key_expr)
            payload = query.payload.to_bytes() if query.payload is not None else None
            self._queue.put(Request(kind, key.split("/")[1], payload, query, key, writer_of(key)))

        return callback

    def _on_sample(self, kind: str) -> Callable[[zenoh.Sample], None]:
        def callback(sample: zenoh.Sample) -> None:
            key = str(sample.key_expr)
            payload = sample.payload.to_bytes()
            self._queue.put(
                Request(kind, key.split("/")[1], payload, key=key, writer=writer_of(key))
            )

        return callback

    def _declare_services(self, complete: bool) -> list:
        """Declare the store's services; `complete`: a request goes to one store, the nearest."""
        root, s = self.root, self.session

        def q(key: str, kind: str) -> zenoh.Queryable:
            return s.declare_queryable(key, self._on_query(kind), complete=complete)

        return [
            q(f"{root}/*/@/write", "write"),
            s.declare_subscriber(f"{root}/*/@/write", self._on_sample("write")),
            q(f"{root}/*/@/query", "query"),
            # The same services, under the name of the writer (see space.store.guard).
            q(f"{root}/*/@/write/*", "write"),
            s.declare_subscriber(f"{root}/*/@/write/*", self._on_sample("write")),
            q(f"{root}/*/@/query/*", "query"),
            q(f"{root}/*/@/log", "log"),
            q(f"{root}/*/{keys.ASSERTED}/**", "keys"),
            q(f"{root}/*/{keys.INFERRED}/**", "keys"),
            q(f"{root}/@repl/spaces", "spaces"),
            # A subscriber that sees this token come back (a cut between us healed)
            # fetches what it missed from the log (space.client, `_watch_store`).
            s.liveliness().declare_token(f"{root}/@leader/{s.zid()}"),
        ]

    # Reads and the heartbeat.

    def _submit_read(self, req: Request) -> None:
        """Hand a read to a reader thread: it starts after every write queued before it.

        Raises:
            SpaceError, ValueError: a malformed request (the caller rejects it).
        """
        assert req.query is not None and self._db is not None
        db, root, query = self._db, self.root, req.query
        if req.kind == "keys":
            spaces = self._key_spaces(req.key)
            self._readers.submit(
                query, req.key, lambda _d: queries.key_get(db, spaces, query, root)
            )
            return
        space = keys.check_space(req.space)
        if req.kind == "log":
            first, last = intake.log_request(req.payload or b"", 2**62)
            self._readers.submit(
                query, req.key, lambda _d: queries.log_entries(db, space, first, last)
            )
            return
        read = intake.query_request(req.payload or b"")
        if read.op == "sparql":
            job = lambda d: queries.sparql(db, space, read.text, d)  # noqa: E731
        else:
            job = lambda d: queries.read(db, space, read, d)  # noqa: E731
        self._readers.submit(query, req.key, job, read.limit)

    def _key_spaces(self, key: str) -> list[str]:
        """Return the known spaces a GET on triple keys may name (none is created)."""
        chunk = key.split("/")[1]
        if "*" not in chunk and "$" not in chunk:
            return [keys.check_space(chunk)]  # read from the database as it is: nothing created
        selector = zenoh.KeyExpr(key)
        return [
            n for n in self._spaces if selector.intersects(zenoh.KeyExpr(f"{self.root}/{n}/**"))
        ]

    def _publish_seqs(self) -> None:
        """Publish each space's sequence number, so subscribers learn of changes they missed."""
        for name, state in list(self._spaces.items()):
            if state.seq:
                self._publisher.heartbeat(name, state.seq)


def request_op(payload: bytes | None) -> object:
    """Return a query request's op without checking the rest (takes go to the writer)."""
    try:
        wire = unpack(payload or b"")
    except MalformedPayload:
        return None
    return wire.get("op") if isinstance(wire, dict) else None
