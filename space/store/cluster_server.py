"""A store replica on an etcd cluster (`tspace serve --cluster`): the Zenoh side of it.

Every replica serves writes, takes and reads of every space; there is no
leader of ours (etcd's is the only one). Zenoh callbacks only enqueue; one
worker thread decides, applies and answers (`cluster_writer`), reads run on
reader threads once the replica applied what etcd had committed when they
arrived (`ClusterNode.barrier`), so a read sees every acknowledged write, on
any replica. On a minority side the barrier fails and the read is refused
with "no quorum: ...", unless the request asks for possibly stale answers
(`"stale": true`, `tspace query --stale`).

Each replica publishes each space's sequence number (the heartbeat, as the
embedded store does) and its view of the cluster on `@cluster/NODE`
(members reachable, revision applied), for `tspace up`'s view and the HMI.
"""

from __future__ import annotations

import hashlib
import logging
import queue
import socket
import time
from collections.abc import Sequence
from pathlib import Path

import zenoh

from space import keys
from space.changeset import pack, unpack
from space.errors import MalformedPayload, QueryError, SpaceError
from space.store.cluster_db import applied_revision, space_seqs
from space.store.cluster_expiry import ClusterExpiry
from space.store.cluster_keys import ROOT as ETCD_ROOT
from space.store.cluster_node import ClusterNode
from space.store.cluster_state import ClusterSpace
from space.store.cluster_writer import ClusterWriter
from space.store.db import StoreDB
from space.store.guard import WriteGuard
from space.store.serving import Serving, request_op
from space.store.writer import Request, answer, reject

log = logging.getLogger("tspace.store")

HEARTBEAT = 0.5  # seconds between publications of each space's seq and of the quorum
_BATCH = 256


def node_name(data_dir: Path) -> str:
    """Return a replica's stable name: its host and a digest of its data directory."""
    where = hashlib.blake2b(str(data_dir.resolve()).encode(), digest_size=4).hexdigest()
    return f"{socket.gethostname()}-{where}"


def cluster_key(root: str, node: str = "*") -> str:
    """Return the Zenoh key where replica `node` publishes its view of the cluster."""
    return f"{root}/@cluster/{node}"


class ClusterStoreServer(Serving):
    """Serve every space as one replica of an etcd cluster.

    Construct, `start()`, `close()`; the Zenoh session belongs to the caller.

    Raises (from `start`):
        DataDirInUse: another store has the data directory open.
    """

    def __init__(
        self,
        session: zenoh.Session,
        data_dir: Path,
        endpoints: Sequence[str],
        *,
        durable: bool = False,
        log_keep: int = 100_000,
        root: str = keys.ROOT,
        etcd_root: bytes = ETCD_ROOT,
        query_timeout: float = 10.0,
        query_slots: int = 16,
        max_spaces: int = 10_000,
        guard: WriteGuard | None = None,
        name: str | None = None,
    ) -> None:
        self.session, self.data_dir, self.root = session, data_dir, root
        self.endpoints = list(endpoints)
        self.name = name or node_name(data_dir)
        self.durable, self.log_keep, self.max_spaces = durable, log_keep, max_spaces
        self.etcd_root, self.guard = etcd_root, guard
        self.quorum = (0, len(self.endpoints))  # (members reachable, members), last probe
        self._spaces: dict[str, ClusterSpace] = {}
        super().__init__(query_timeout, query_slots)
        self._node: ClusterNode | None = None
        self._writer: ClusterWriter | None = None
        self._probing = False

    def start(self) -> None:
        """Open the database, connect to etcd (resuming at the revision applied), serve."""
        db = self._db = StoreDB(self.data_dir, durable=self.durable, log_keep=self.log_keep)
        revision = applied_revision(db)
        put = self._queue.put
        self._node = ClusterNode(
            self.endpoints,
            node=self.name,
            revision=revision,
            apply=lambda r, batches: put(("apply", r, batches)),
            relist=lambda listing: put(("relist", listing)),
            seqs=space_seqs(db),
            root=self.etcd_root,
        )
        self._writer = ClusterWriter(
            self.session,
            db,
            self._node,
            root=self.etcd_root,
            events=self._queue,
            spaces=self._spaces,
            space=self._space,
            publisher=self._publisher,
            max_spaces=self.max_spaces,
            expiry=ClusterExpiry(self.etcd_root, db),
            guard=self.guard,
        )
        self._writer.revision = revision
        for name in db.spaces():
            self._space(name)
        self._node.start()
        self._start_worker(self._run, "tspace-replica")
        # complete=True: a client's request goes to one replica (the nearest), not to all.
        self._declared = self._declare_services(complete=True)
        log.info(
            "replica %s of etcd %s: %d space(s) from %s, at revision %d",
            self.name,
            ",".join(self.endpoints),
            len(self._spaces),
            db.path,
            revision,
        )

    def _stop(self) -> None:
        if self._node is not None:
            self._node.close()
            self._node = None

    # The worker.

    def _run(self) -> None:
        next_beat = time.monotonic()
        writer = self._writer
        assert writer is not None
        while True:
            self._beat()
            if time.monotonic() >= next_beat:
                self._heartbeat()
                next_beat = time.monotonic() + HEARTBEAT
            writer.sweep()
            wait = next_beat - time.monotonic()
            due = writer.expiry.next_due()
            if due is not None and not writer.failed:
                wait = min(wait, due - time.time())
            try:
                item = self._queue.get(timeout=max(0.0, wait))
            except queue.Empty:
                continue
            batch = [item]
            while item is not None and len(batch) < _BATCH:
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
                batch.append(item)
            if not self._handle(batch):
                return

    def _handle(self, batch: list) -> bool:
        writer = self._writer
        assert writer is not None
        reads: list[Request] = []
        going = None not in batch
        # What etcd committed first: its writers are answered before new requests are
        # decided, and those are decided on the state it makes.
        for item in batch:
            if isinstance(item, tuple):
                self._event(item)
        self._apply()
        for item in batch:
            if item is None or isinstance(item, tuple):
                continue
            if item.kind == "write" or (
                item.kind == "query" and request_op(item.payload) == "take"
            ):
                self._decide(item, 1)
            elif item.kind == "spaces":
                answer(item, {n: s.seq for n, s in self._spaces.items() if s.seq})
            elif item.kind in ("query", "log", "keys"):
                if item.kind == "query" and _stale(item):
                    self._read(item)
                else:
                    reads.append(item)
        self._apply()
        if reads:
            writer.ask_barrier(("reads", reads))
        return going

    def _apply(self) -> None:
        """Send what was decided, then apply what etcd committed (`apply_pending`)."""
        writer = self._writer
        assert writer is not None
        try:
            writer.apply_pending()
        except Exception as exc:  # a bug: stop taking writes rather than diverge silently
            log.exception("replica failed to apply the log: refusing writes; restart it")
            writer.failed = f"internal error while applying: {type(exc).__name__}: {exc}"

    def _event(self, item: tuple) -> None:
        """Handle what etcd's thread or a barrier put on the queue."""
        writer = self._writer
        assert writer is not None
        kind = item[0]
        if kind == "redecide":
            req, attempt, followers = item[1]
            for r in (req, *followers):
                self._decide(r, attempt)
        elif kind == "reads":
            for r in item[1]:
                self._read(r)
        else:
            try:
                writer.event(item)
            except Exception as exc:  # a bug: stop taking writes rather than diverge silently
                log.exception("replica failed on a %s event: refusing writes; restart it", kind)
                writer.failed = f"internal error: {type(exc).__name__}: {exc}"

    def _decide(self, req: Request, attempt: int) -> None:
        writer = self._writer
        assert writer is not None
        try:
            if req.kind == "write":
                writer.write(req, attempt)
            else:
                writer.take(req, attempt)
        except (SpaceError, ValueError) as exc:
            reject(req, exc)
        except Exception as exc:  # a bug must not stop the replica nor leave a caller waiting
            log.exception("replica failed on a %s request for %r", req.kind, req.space)
            reject(req, QueryError(f"internal error: {type(exc).__name__}: {exc}"))

    def _read(self, req: Request) -> None:
        """Hand a read to a reader thread (the replica applied what etcd had committed)."""
        try:
            self._submit_read(req)
        except (SpaceError, ValueError) as exc:
            reject(req, exc)

    def _space(self, name: str) -> ClusterSpace:
        state = self._spaces.get(name)
        if state is None:
            assert self._db is not None
            state = self._spaces[name] = ClusterSpace(name, self._db)
        return state

    def _heartbeat(self) -> None:
        """Publish each space's seq and this replica's view of the cluster; probe the members."""
        self._publish_seqs()
        reachable, members = self.quorum
        writer = self._writer
        status = {
            "node": self.name,
            "members": members,
            "reachable": reachable,
            "quorum": reachable > members // 2,
            "revision": writer.revision if writer else 0,
        }
        self.session.put(cluster_key(self.root, self.name), pack(status))
        if not self._probing and self._node is not None:
            self._probing = True
            self._node.reachable().add_done_callback(self._probed)

    def _probed(self, future) -> None:  # noqa: ANN001 (a concurrent future, etcd's thread)
        self._probing = False
        if future.cancelled() or future.exception() is not None:
            return
        before = self.quorum
        self.quorum = (future.result(), len(self.endpoints))
        had, has = before[0] > before[1] // 2, self.quorum[0] > self.quorum[1] // 2
        if had != has:
            level = logging.INFO if has else logging.WARNING
            log.log(
                level,
                "%s quorum: %d of %d members reachable",
                "back in" if has else "no",
                *self.quorum,
            )


def _stale(req: Request) -> bool:
    """Return whether a read asks for possibly stale answers (no barrier: works without quorum)."""
    try:
        wire = unpack(req.payload or b"")
    except MalformedPayload:
        return False
    return isinstance(wire, dict) and wire.get("stale") is True
