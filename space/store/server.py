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
import time
from pathlib import Path

import zenoh

from space import keys
from space.errors import QueryError, SpaceError
from space.store import lifespans
from space.store.db import StoreDB
from space.store.guard import WriteGuard
from space.store.lifespans import Leases
from space.store.serving import Serving, request_op
from space.store.state import SpaceState
from space.store.writer import Pending, Request, Writer, answer, reject

log = logging.getLogger("tspace.store")

_BATCH = 256
HEARTBEAT = 0.5  # seconds between publications of each space's sequence number
OVERDUE = 0.02  # seconds late from which an expiry turn runs even while requests wait
BUSY = 0.05  # seconds after a request during which expiry turns are one write each
_READS = ("query", "log", "keys")


class StoreServer(Serving):
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
        self._spaces: dict[str, SpaceState] = {}
        super().__init__(query_timeout, query_slots)
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
        self._start_worker(self._run, "tspace-store")
        self._declared = self._declare_services(complete=False)
        log.info("store: %d space(s) from %s", len(self._spaces), self._db.path)

    # The writer: the only thread that decides and commits.

    def _run(self) -> None:
        next_beat = time.monotonic()
        while True:
            self._beat()
            if time.monotonic() >= next_beat:
                self._publish_seqs()
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
                if req.kind == "query" and request_op(req.payload) == "take":
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

    def _other(self, req: Request) -> None:
        if req.kind == "spaces":
            answer(req, self._seqs())
        elif req.kind in _READS:
            self._submit_read(req)

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

    def _seqs(self) -> dict[str, int]:
        return {name: state.seq for name, state in self._spaces.items()}
