"""A replica's side of the log: apply every committed revision, in order, exactly once.

The applier watches the log keys from the revision after the one the replica
has applied (kept in the replica's own store, so a restart or a cut resumes
there). etcd's watch is never trusted across a compaction (Debian's 3.4.23
has a defect there): before each watch the applier reads at its revision,
and when that revision is compacted away, or a watch answers with
`compact_revision`, it re-lists the whole state at the current revision and
hands it to the replica, then watches from there.

A live replica says which revision it applied under `replicas/` (leased:
a replica gone for LIVENESS_TTL seconds stops counting), before it applies
anything and then every second, and every replica compacts etcd's history up
to the lowest of those: etcd keeps a window of the log, the replicas' stores
keep the history.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from dataclasses import dataclass

import grpc
import msgpack
from aetcd import rpc

from space.errors import ClusterError, NoQuorum
from space.store.cluster_keys import ROOT, count_weight, log_space, prefix_end, replica_key
from space.store.etcd_client import EtcdClient

log = logging.getLogger("tspace.etcd")

LIVENESS_TTL = 60  # seconds a silent replica still holds back compaction (a cut, a restart)
REPORT_EVERY = 1.0
COMPACT_EVERY = 10.0
PAGE = 1000


@dataclass
class Batch:
    """What one space committed at one revision: its changesets' payloads, in order.

    `first_seq` is the space's sequence number of the first of them: every
    replica numbers a space's changesets alike, 1, 2, ... in log order.
    """

    space: str
    revision: int
    payloads: list[bytes]
    first_seq: int = 0


@dataclass
class Listing:
    """The whole state at one revision: every state key, and each space's sequence number."""

    revision: int
    pairs: list[tuple[bytes, bytes]]
    seqs: dict[str, int]


Apply = Callable[[int, list[Batch]], None]
Relist = Callable[[Listing], None]


class Applier:
    """Follow the log from `revision` and hand every revision to `apply`, in order.

    `apply(revision, batches)` and `relist(listing)` run in the event loop
    and must not block; once either returns, the replica is at that revision.
    `seqs` are the spaces' sequence numbers at `revision` (the replica's, as
    stored with it). `await start()`, `await close()`.
    """

    def __init__(
        self,
        client: EtcdClient,
        *,
        node: str,
        revision: int,
        apply: Apply,
        relist: Relist,
        seqs: dict[str, int] | None = None,
        root: bytes = ROOT,
    ) -> None:
        self.client = client
        self.node = node
        self.revision = revision
        self.seqs = dict(seqs or {})
        self.root = root
        self._apply = apply
        self._relist = relist
        self._advanced = asyncio.Condition()
        self._registered = asyncio.Event()
        self._tasks: list[asyncio.Task[None]] = []
        self.relists = 0

    async def start(self) -> None:
        """Start following the log, reporting liveness and compacting."""
        self._tasks = [
            asyncio.create_task(self._follow()),
            asyncio.create_task(self._report()),
            asyncio.create_task(self._compact()),
        ]

    async def close(self) -> None:
        """Stop every task (the replica keeps its revision)."""
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks = []

    async def wait_applied(self, revision: int, timeout: float) -> bool:
        """Wait until this replica applied `revision`; return False after `timeout`."""
        async with self._advanced:
            try:
                await asyncio.wait_for(
                    self._advanced.wait_for(lambda: self.revision >= revision), timeout
                )
            except TimeoutError:
                return False
        return True

    async def _advance(self, revision: int) -> None:
        self.revision = revision
        async with self._advanced:
            self._advanced.notify_all()

    async def _follow(self) -> None:
        # Registered first: compaction never passes a replica that applied something.
        await self._registered.wait()
        pause = 0.05
        while True:
            try:
                if not await self._readable(self.revision):
                    log.warning("revision %d was compacted away: re-listing", self.revision)
                    await self._relist_all()
                await self._watch()
            except (grpc.aio.AioRpcError, NoQuorum, ClusterError, _Broken) as error:
                log.info("log watch stopped at revision %d: %s", self.revision, error)
                self.client.rotate()
                await asyncio.sleep(pause)
                pause = min(pause * 2, 1.0)
                continue
            pause = 0.05

    async def _readable(self, revision: int) -> bool:
        """Return True if etcd still holds revision `revision` (not compacted away).

        A new replica (revision 0) replays the log from its start when nothing
        was compacted yet, and re-lists otherwise.
        """
        request = rpc.RangeRequest(key=self.root, revision=max(revision, 1), count_only=True)
        try:
            await self.client.range(request)
        except ClusterError as error:
            if "compacted" in str(error):
                return False
            raise
        return True

    async def _watch(self) -> None:
        start = self.revision + 1
        prefix = self.root + b"log/"
        async for response in self.client.watch(prefix, prefix_end(prefix), start):
            if response.compact_revision:
                log.warning("revision %d compacted: re-listing", self.revision)
                await self._relist_all()
                return
            if response.canceled:
                raise _Broken(response.cancel_reason or "watch cancelled")
            by_revision: dict[int, list[Batch]] = {}
            for event in response.events:
                kv = event.kv
                if event.type != rpc.Event.PUT or kv.mod_revision <= self.revision:
                    continue
                space = log_space(self.root, kv.key)
                batch = Batch(space, kv.mod_revision, msgpack.unpackb(kv.value))
                by_revision.setdefault(kv.mod_revision, []).append(batch)
            for revision in sorted(by_revision):
                for batch in by_revision[revision]:
                    batch.first_seq = self.seqs.get(batch.space, 0) + 1
                    self.seqs[batch.space] = batch.first_seq + len(batch.payloads) - 1
                self._apply(revision, by_revision[revision])
                await self._advance(revision)

    async def _relist_all(self) -> None:
        """Read every state key at one revision, page by page, and hand them over."""
        self.relists += 1
        pairs: list[tuple[bytes, bytes]] = []
        seqs: dict[str, int] = {}
        revision = 0
        counts = self.root + b"count/"
        for prefix in (counts, *(self.root + p for p in (b"state/", b"fn/", b"prefix/"))):
            key = prefix
            while True:
                request = rpc.RangeRequest(
                    key=key, range_end=prefix_end(prefix), limit=PAGE, revision=revision
                )
                reply = await self.client.range(request)
                revision = revision or reply.header.revision
                for kv in reply.kvs:
                    if prefix == counts:
                        space = kv.key[len(counts) :].rsplit(b"/", 1)[0].decode()
                        seqs[space] = seqs.get(space, 0) + kv.version * count_weight(kv.key)
                    else:
                        pairs.append((kv.key, kv.value))
                if not reply.more:
                    break
                key = reply.kvs[-1].key + b"\x00"
        self.seqs = seqs
        self._relist(Listing(revision, pairs, dict(seqs)))
        await self._advance(revision)

    async def _report(self) -> None:
        lease, granted, reported = 0, 0.0, -1
        loop = asyncio.get_running_loop()
        while True:
            if self._registered.is_set():
                await asyncio.sleep(REPORT_EVERY)
            try:
                if not lease or loop.time() - granted > LIVENESS_TTL / 2:
                    lease = await self.client.grant(LIVENESS_TTL)
                    granted, reported = loop.time(), -1
                if self.revision != reported:
                    put = rpc.PutRequest(
                        key=replica_key(self.root, self.node),
                        value=str(self.revision).encode(),
                        lease=lease,
                    )
                    await self.client.txn(rpc.TxnRequest(success=[rpc.RequestOp(request_put=put)]))
                    reported = self.revision
                    self._registered.set()
            except (NoQuorum, ClusterError) as error:
                log.info("cannot report revision %d: %s", self.revision, error)
                lease = 0
                if not self._registered.is_set():
                    await asyncio.sleep(REPORT_EVERY)

    async def _compact(self) -> None:
        compacted = 0
        while True:
            await asyncio.sleep(COMPACT_EVERY)
            try:
                done = await compact_behind_replicas(self.client, self.root, compacted)
                if done != compacted:
                    log.info("compacted etcd's history up to revision %d (%s)", done, self.node)
                compacted = done
            except (NoQuorum, ClusterError) as error:
                log.debug("cannot compact: %s", error)


async def compact_behind_replicas(client: EtcdClient, root: bytes, compacted: int) -> int:
    """Compact etcd's history up to what every live replica applied; return that revision."""
    prefix = root + b"replicas/"
    reply = await client.range(rpc.RangeRequest(key=prefix, range_end=prefix_end(prefix)))
    applied = {kv.key[len(prefix) :].decode(): int(kv.value) for kv in reply.kvs}
    if not applied or min(applied.values()) <= compacted:
        return compacted
    log.debug("replicas at %s: compacting", applied)
    await client.compact(min(applied.values()))
    return min(applied.values())


class _Broken(Exception):
    """A watch was cancelled by etcd (no leader on that member, say)."""
