"""A store replica's link to etcd, for a threaded store: one asyncio loop in its own thread.

The store's worker thread owns Oxigraph; etcd's client is asyncio. A
`ClusterNode` runs the client, the log (group commit) and the applier on one
event loop in a daemon thread and offers the worker thread plain calls:

- `append(entry)` returns a `concurrent.futures.Future` of the entry's
  position: the worker goes on deciding while 64 changesets are in flight;
  `append_all(entries, done)` hands a whole batch over at once (one wake-up
  of the loop, not one task and one wake-up per changeset);
- `apply(revision, batches)` and `relist(listing)`, given at
  construction, are called in the loop thread for each committed revision:
  they must only hand the work to the worker (a queue), never block;
- `read_barrier()` returns the revision etcd has committed now (a
  linearizable read, refused with `NoQuorum` on a minority side): a replica
  that has applied that revision answers a read as the majority would;
- `members()` says how many members are reachable, for `tspace up`'s view.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Callable, Coroutine, Sequence
from typing import Any, TypeVar

from aetcd import rpc

from space.store.cluster_keys import ROOT, prefix_end
from space.store.etcd_applier import Applier, Apply, Relist
from space.store.etcd_client import EtcdClient
from space.store.etcd_log import ClusterLog, Entry, Position

T = TypeVar("T")
Done = asyncio.Future[Position]
# Transactions in flight at once: etcd batches concurrent proposals into one Raft round, so a
# changeset arriving while others commit is sent at once instead of waiting a round.
INFLIGHT = 8
# ... but while one is in flight, another starts only once this many changesets wait: fewer
# wait for its reply and go together in the next one. Measured through three replicas, 64 in
# flight, 6 pairs of runs: 5.5 changesets per transaction instead of 4, CPU per changeset -6 %
# in the replicas and -10 % in etcd, in every pair (docs/performance.md).
PIPELINE = 32
# ... and while the log is busy (8 changesets or more in its last transaction, committed less
# than 50 ms ago: `ClusterLog.busy_for`), a transaction waits 8 ms before it starts, for the
# writers of the last one on their way back: a transaction costs etcd's three members ~2.7 ms
# of CPU whatever it carries, and each replica a gRPC call and a watch message. Measured
# through three replicas, 64 in flight, 2 pairs of runs: 17 changesets a transaction instead
# of 10, CPU per changeset -12 to -26 % over every process (docs/performance.md). With a few
# writers (less than 8 a transaction), or one alone after a burst, no wait.
LINGER, LINGER_FROM = 0.008, 8


class ClusterNode:
    """The etcd client, log and applier of one replica, on a loop thread.

    Construct (no side effects), `start()`, then call from any thread;
    `close()` stops the thread (queued appends fail).
    """

    def __init__(
        self,
        endpoints: Sequence[str],
        *,
        node: str,
        revision: int,
        apply: Apply,
        relist: Relist,
        seqs: dict[str, int] | None = None,
        root: bytes = ROOT,
    ) -> None:
        self.endpoints = list(endpoints)
        self.node = node
        self.root = root
        self._start_revision, self._start_seqs = revision, dict(seqs or {})
        self._apply, self._relist = apply, relist
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="tspace-etcd")
        self._thread.daemon = True
        self.client: EtcdClient | None = None
        self.log: ClusterLog | None = None
        self.applier: Applier | None = None

    def start(self) -> None:
        """Start the loop thread, the committers and the applier (does not wait for etcd)."""
        self._thread.start()
        self._call(self._open(), timeout=10)

    async def _open(self) -> None:
        self.client = EtcdClient(self.endpoints)
        await self.client.open()
        self.log = ClusterLog(
            self.client,
            root=self.root,
            node=self.node,
            inflight=INFLIGHT,
            pipeline=PIPELINE,
            linger=LINGER,
            linger_from=LINGER_FROM,
        )
        await self.log.start()
        self.applier = Applier(
            self.client,
            node=self.node,
            revision=self._start_revision,
            apply=self._apply,
            relist=self._relist,
            seqs=self._start_seqs,
            root=self.root,
        )
        await self.applier.start()

    def close(self) -> None:
        """Stop applying and committing, close the client and end the thread."""
        if not self._thread.is_alive():
            return
        self._call(self._close(), timeout=10)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join()
        self._loop.close()

    async def _close(self) -> None:
        for part in (self.applier, self.log):
            if part is not None:
                await part.close()
        if self.client is not None:
            await self.client.close()

    def append(self, entry: Entry) -> concurrent.futures.Future[Position]:
        """Commit an entry; the future's result is its position (see `ClusterLog.append`)."""
        assert self.log is not None, "start() first"
        return asyncio.run_coroutine_threadsafe(self.log.append(entry), self._loop)

    def append_all(self, entries: list[Entry], done: Callable[[int, Done], None]) -> None:
        """Commit entries; `done(i, future)` runs in the loop's thread once entry i's is done.

        The future is an `asyncio.Future` of the entry's position, done (read
        it from any thread), failed as `append`'s fails.
        """
        log = self.log
        assert log is not None, "start() first"

        def submit() -> None:
            for i, entry in enumerate(entries):
                log.submit(entry).add_done_callback(lambda f, i=i: done(i, f))

        self._loop.call_soon_threadsafe(submit)

    def read_barrier(self, timeout: float = 5.0) -> int:
        """Return the revision etcd has committed now; raise `NoQuorum` on a minority side."""
        client = self.client
        assert client is not None, "start() first"
        request = rpc.RangeRequest(key=self.root, count_only=True)
        reply = self._call(client.range(request), timeout)
        return reply.header.revision

    def barrier(self) -> concurrent.futures.Future[int]:
        """Return a future of the last revision that logged a changeset (or of `NoQuorum`).

        A linearizable read: once the replica applied that revision, it holds
        every changeset acknowledged before the barrier was asked for, on any
        replica. (etcd's own revision also counts puts outside the log, such
        as the replicas' reports, which a replica never sees applied.)
        """
        client = self.client
        assert client is not None, "start() first"
        prefix = self.root + b"log/"
        request = rpc.RangeRequest(
            key=prefix,
            range_end=prefix_end(prefix),
            limit=1,
            keys_only=True,
            sort_order=rpc.RangeRequest.DESCEND,
            sort_target=rpc.RangeRequest.MOD,
        )

        async def revision() -> int:
            reply = await client.range(request)
            return reply.kvs[0].mod_revision if reply.kvs else 0

        return asyncio.run_coroutine_threadsafe(revision(), self._loop)

    def reachable(self) -> concurrent.futures.Future[int]:
        """`members` without waiting: a future of how many members answer now."""
        assert self.client is not None, "start() first"
        return asyncio.run_coroutine_threadsafe(self.client.reachable(), self._loop)

    def members(self, timeout: float = 2.0) -> tuple[int, int]:
        """Return (members reachable, members) now."""
        assert self.client is not None, "start() first"
        return self._call(self.client.reachable(), timeout), len(self.endpoints)

    def _call(self, coro: Coroutine[Any, Any, T], timeout: float) -> T:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(timeout)
