"""The replicated log: changesets group-committed into etcd transactions.

`append(entry)` resolves once etcd has committed the entry, that is once a
majority of members have it on disk; its `Position` (revision, index) is its
place in the space's order. Entries waiting while a transaction is in flight
go together into the next one (group commit: one Raft round for many
changesets), which is how a 2-core host reaches thousands of changesets a
second with 64 in flight.

An entry carries the keys it writes and the guards its decision rests on:
take and the replacement of a functional value are decided by
compare-and-swap inside the same transaction as the write. A replica decides
on its state at the revision R it has applied, so a guard says "this key is
unchanged since R" (etcd: mod_revision < R + 1; a key absent then and now
passes) and, for what a take removes, "and it is present" (version > 0):
present now and untouched since R means present all along, so nobody else
took it. When a guard fails only that entry fails (`WriteConflict`: catch up
and decide again); the rest of its batch is sent again at once. An entry
whose guard covers a key an earlier entry of the batch writes waits for the
next batch, where etcd judges it against that write.

Each transaction also creates a marker key, and only if it is absent, so the
client's retry of a transaction that timed out after committing is a no-op
that reports the revision of the first commit: a changeset is never logged
twice.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import uuid
from collections import Counter
from dataclasses import dataclass, field

import msgpack
from aetcd import rpc

from space.errors import ClusterError, WriteConflict
from space.store.cluster_keys import ROOT, batch_key, count_keys, log_key
from space.store.etcd_client import EtcdClient

log = logging.getLogger("tspace.etcd")

MAX_OPS = 4096  # below etcd's --max-txn-ops that etcd_member sets
MAX_BYTES = 2 * 1024 * 1024  # below its --max-request-bytes
MARKER_TTL = 60  # seconds a batch marker outlives its transaction (a retry comes sooner)


@dataclass(frozen=True)
class Position:
    """Where a committed entry sits in its space's order: etcd revision, then index."""

    revision: int
    index: int


@dataclass
class Entry:
    """One changeset to commit: its payload for the log, its writes and its guards."""

    space: str
    payload: bytes
    puts: dict[bytes, bytes] = field(default_factory=dict)
    deletes: list[bytes] = field(default_factory=list)
    guards: dict[bytes, int] = field(default_factory=dict)  # key -> unchanged since this revision
    present: list[bytes] = field(default_factory=list)  # guarded keys that must also exist
    leased: list[bytes] = field(default_factory=list)  # empty keys put with a 60 s lease

    def ops(self) -> int:
        """Return how many transaction operations this entry costs."""
        puts = len(self.puts) + len(self.leased)
        return 1 + puts + len(self.deletes) + len(self.guards) + len(self.present)

    def size(self) -> int:
        """Return roughly how many bytes this entry adds to a transaction."""
        return (
            len(self.payload)
            + sum(len(k) + len(v) for k, v in self.puts.items())
            + sum(len(k) for k in self.deletes)
            + sum(len(k) + 8 for k in self.guards)
        )


_Waiting = tuple[Entry, "asyncio.Future[Position]"]


class ClusterLog:
    """Group-commit entries into etcd; one per replica process.

    `await start()`, then `await append(entry)` from any task of the same
    loop; `await close()` fails what is still queued. Raises `NoQuorum` (via
    the client) when this side of a partition cannot commit.
    """

    def __init__(
        self,
        client: EtcdClient,
        *,
        root: bytes = ROOT,
        node: str | None = None,
        inflight: int = 2,
        batch: int = 256,
        pipeline: int = 1,
        linger: float = 0.0,
        linger_from: int = 8,
        busy_for: float = 0.05,
    ) -> None:
        self.client = client
        self.root = root
        # Markers must never repeat, also across restarts of a node of the same name: a
        # marker left by an earlier process would make a new transaction look committed.
        self.node = f"{node or 'log'}-{uuid.uuid4().hex}"
        self.inflight = inflight
        self.batch = batch  # entries per transaction at most
        # With fewer than this many entries queued, no transaction starts while one is in
        # flight: they wait for its reply and go together in the next one.
        self.pipeline = pipeline
        # While the log is busy (its last transaction carried `linger_from` entries or more,
        # and committed less than `busy_for` seconds ago), a transaction waits `linger`
        # seconds before it starts, unless `pipeline` entries wait: the writers of the last
        # one are on their way back, and go in this one. `busy_for` is about an ack's p50
        # with 64 writers on two loaded cores (docs/performance.md): a writer that comes
        # back later than that is not one of them, and a lone one after a burst waits not.
        self.linger, self.linger_from, self.busy_for = linger, linger_from, busy_for
        self._last = 0  # entries in the last transaction committed
        self._last_at = 0.0  # when (the loop's clock)
        self.flying = 0  # transactions in flight now
        self.transactions = 0  # committed transactions, for the benchmark's batch size
        self._queue: list[_Waiting] = []
        self._busy: Counter[bytes] = Counter()  # keys written by transactions in flight
        self._wake = asyncio.Event()
        self._numbers = itertools.count(1)
        self._lease = 0
        self._lease_at = 0.0
        self._tasks: list[asyncio.Task[None]] = []

    async def start(self) -> None:
        """Start the committers."""
        self._tasks = [asyncio.create_task(self._commit_loop()) for _ in range(self.inflight)]

    async def close(self) -> None:
        """Stop committing; entries still queued fail with CancelledError."""
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks = []
        for _, future in self._queue:
            future.cancel()
        self._queue = []

    async def append(self, entry: Entry) -> Position:
        """Commit one entry; return its position once a majority has it.

        Raises `WriteConflict` when one of its guards failed (nothing of it
        was written), `NoQuorum` or `ClusterError` when etcd could not commit
        (it may still have: only a timeout is ambiguous, as with any store).
        """
        return await self.submit(entry)

    def submit(self, entry: Entry) -> asyncio.Future[Position]:
        """Queue one entry (from the loop's thread); return the future `append` awaits."""
        future: asyncio.Future[Position] = asyncio.get_running_loop().create_future()
        if entry.size() > MAX_BYTES or entry.ops() > MAX_OPS:
            future.set_exception(
                ClusterError(
                    f"a changeset of {entry.size()} bytes and {entry.ops()} keys is over one "
                    f"transaction's limits ({MAX_BYTES} bytes, {MAX_OPS} keys)"
                )
            )
            return future
        self._queue.append((entry, future))
        self._wake.set()
        return future

    async def _commit_loop(self) -> None:
        while True:
            # A fuller transaction costs etcd and every replica less CPU per changeset
            # than several small ones, so a few entries wait for the one in flight.
            wait = self.flying and len(self._queue) < self.pipeline
            if not wait and self._busy_log():
                await asyncio.sleep(self.linger)
                wait = self.flying and len(self._queue) < self.pipeline  # another one started
            batch, written = ([], set()) if wait else self._take_batch()
            if not batch:  # nothing queued, too few, or all of it waits for a batch in flight
                self._wake.clear()
                await self._wake.wait()
                continue
            self.flying += 1
            try:
                await self._commit(batch)
            except asyncio.CancelledError:
                for _, future in batch:
                    future.cancel()
                raise
            except Exception as error:  # every waiter learns why its batch failed
                for _, future in batch:
                    if not future.done():
                        future.set_exception(error)
            finally:
                self.flying -= 1
                self._busy.subtract(written)
                self._busy = +self._busy  # drop the keys no batch holds any more
                self._wake.set()

    def _busy_log(self) -> bool:
        """Return whether the next transaction should linger (see `linger`)."""
        queued = len(self._queue)
        return bool(self.linger and queued and queued < self.pipeline) and (
            self._last >= self.linger_from
            and asyncio.get_running_loop().time() - self._last_at < self.busy_for
        )

    def _take_batch(self) -> tuple[list[_Waiting], set[bytes]]:
        """Take queued entries up to the transaction's limits; return them and the keys written.

        Per key, entries commit in the order they were appended: an entry that
        touches a key a transaction in flight writes, or that an entry left
        for later touches, waits; one whose guard covers a key an earlier entry
        of this batch writes waits too (etcd checks guards before any write).
        """
        batch: list[_Waiting] = []
        later: list[_Waiting] = []
        written: set[bytes] = set()
        blocked: set[bytes] = set(self._busy)
        ops = size = 0
        for item in self._queue:
            entry = item[0]
            writes = {*entry.puts, *entry.deletes, *entry.leased}
            guards = {*entry.guards, *entry.present}
            full = batch and (
                len(batch) >= self.batch
                or ops + entry.ops() > MAX_OPS
                or size + entry.size() > MAX_BYTES
            )
            if full or guards & (written | blocked) or writes & blocked:
                later.append(item)
                blocked |= writes | guards
                continue
            batch.append(item)
            ops += entry.ops()
            size += entry.size()
            written |= writes
        self._queue = later
        self._busy.update(written)
        return batch, written

    async def _commit(self, batch: list[_Waiting]) -> None:
        while batch:
            marker = batch_key(self.root, self.node, next(self._numbers))
            request = await self._request(batch, marker)
            reply = await self.client.txn(request)
            if reply.succeeded:
                self._resolve(batch, reply.header.revision)
                return
            first = reply.responses[0].response_range.kvs
            if first:  # our own earlier attempt committed; this retry changed nothing
                self._resolve(batch, first[0].mod_revision)
                return
            current = {
                r.response_range.kvs[0].key: r.response_range.kvs[0].mod_revision
                for r in reply.responses[1:]
                if r.response_range.kvs
            }
            kept = self._fail_conflicts(batch, current)
            if len(kept) == len(batch):
                raise ClusterError("a transaction failed although every guard holds")
            batch = kept

    def _resolve(self, batch: list[_Waiting], revision: int) -> None:
        self.transactions += 1
        self._last, self._last_at = len(batch), asyncio.get_running_loop().time()
        counters: dict[str, int] = {}
        for entry, future in batch:
            index = counters.get(entry.space, 0)
            counters[entry.space] = index + 1
            if not future.done():
                future.set_result(Position(revision, index))

    @staticmethod
    def _fail_conflicts(batch: list[_Waiting], current: dict[bytes, int]) -> list[_Waiting]:
        """Fail the entries whose guards no longer hold; return the others."""
        kept = []
        for entry, future in batch:
            changed = [k for k, since in entry.guards.items() if current.get(k, 0) > since]
            changed += [k for k in entry.present if k not in current]
            if changed:
                if not future.done():
                    future.set_exception(WriteConflict(changed))
            else:
                kept.append((entry, future))
        return kept

    async def _request(self, batch: list[_Waiting], marker: bytes) -> rpc.TxnRequest:
        compare = [
            rpc.Compare(
                key=marker,
                result=rpc.Compare.EQUAL,
                target=rpc.Compare.CREATE,
                create_revision=0,
            )
        ]
        guarded: dict[bytes, int] = {}
        present: set[bytes] = set()
        logs: dict[str, list[bytes]] = {}
        # etcd refuses a key twice in one transaction: the batch's writes of one key
        # merge into the last, which is what applying them one after another gives.
        writes: dict[bytes, rpc.RequestOp] = {}
        for entry, _ in batch:
            for key, since in entry.guards.items():
                guarded[key] = min(since, guarded.get(key, since))
            present.update(entry.present)
            logs.setdefault(entry.space, []).append(entry.payload)
            for key in entry.deletes:
                writes.pop(key, None)
                writes[key] = _delete(key)
            for key, value in entry.puts.items():
                writes.pop(key, None)
                writes[key] = _put(key, value)
        lease = await self._marker_lease()
        for entry, _ in batch:
            for key in entry.leased:
                writes.pop(key, None)
                writes[key] = _put(key, b"", lease=lease)
        success = list(writes.values())
        for key, since in guarded.items():
            compare.append(
                rpc.Compare(
                    key=key, result=rpc.Compare.LESS, target=rpc.Compare.MOD, mod_revision=since + 1
                )
            )
        for key in present:
            compare.append(
                rpc.Compare(
                    key=key, result=rpc.Compare.GREATER, target=rpc.Compare.VERSION, version=0
                )
            )
            guarded.setdefault(key, 0)
        for space, payloads in logs.items():
            success.append(_put(log_key(self.root, space), msgpack.packb(payloads)))
            success += [_put(k, b"") for k in count_keys(self.root, space, len(payloads))]
        success.append(_put(marker, b"", lease=lease))
        failure = [_get(marker)] + [_get(key) for key in guarded]
        return rpc.TxnRequest(compare=compare, success=success, failure=failure)

    async def _marker_lease(self) -> int:
        """Return a lease that expires the markers (a fresh one every half TTL)."""
        now = asyncio.get_running_loop().time()
        if not self._lease or now - self._lease_at > MARKER_TTL / 2:
            self._lease = await self.client.grant(MARKER_TTL)
            self._lease_at = now
        return self._lease


def _put(key: bytes, value: bytes, lease: int = 0) -> rpc.RequestOp:
    return rpc.RequestOp(request_put=rpc.PutRequest(key=key, value=value, lease=lease))


def _delete(key: bytes) -> rpc.RequestOp:
    return rpc.RequestOp(request_delete_range=rpc.DeleteRangeRequest(key=key))


def _get(key: bytes) -> rpc.RequestOp:
    return rpc.RequestOp(request_range=rpc.RangeRequest(key=key))
