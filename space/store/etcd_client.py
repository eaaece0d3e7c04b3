"""The etcd client tspace uses: aetcd's gRPC stubs, one channel per member, fast failover.

aetcd (docs/cluster.md says why this client) is used for its generated
protocol and asyncio gRPC stubs, not its `Client` class: that one dials one
target (given several addresses it fails over badly), has no per-call deadline
and no range limit/revision. Here every call has a short deadline (0.5 s) and
is retried on the next member until an overall deadline; after a failure the
members are probed, and when fewer than a majority answer the call fails at
once with `NoQuorum` ("no quorum: 1 of 3 members reachable") instead of
waiting: that side of a partition can commit nothing.

Retrying is safe only for idempotent requests: a transaction that timed out
may have committed. `etcd_log` makes its transactions idempotent (batch keys).
All methods are coroutines of the loop that called `open()`.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from typing import TypeVar

import grpc
from aetcd import rpc

from space.errors import ClusterError, NoQuorum

log = logging.getLogger("tspace.etcd")

CALL_TIMEOUT = 0.5  # one attempt on one member
DEADLINE = 3.0  # every attempt of one call together
PROBE_TIMEOUT = 0.3  # one status request
PROBE_WINDOW = 1.0  # every status request to one member in one probe
# etcd answers a proposal it cannot make now (no leader, leader changed, overloaded,
# stopping) with these; the next member or the next attempt may succeed.
_RETRY = {
    grpc.StatusCode.UNAVAILABLE,
    grpc.StatusCode.DEADLINE_EXCEEDED,
    grpc.StatusCode.CANCELLED,
    grpc.StatusCode.RESOURCE_EXHAUSTED,
}
_CHANNEL_OPTIONS = [
    ("grpc.initial_reconnect_backoff_ms", 100),
    ("grpc.min_reconnect_backoff_ms", 100),
    ("grpc.max_reconnect_backoff_ms", 500),
    ("grpc.keepalive_time_ms", 2000),
    ("grpc.keepalive_timeout_ms", 1000),
    ("grpc.max_receive_message_length", 64 * 1024 * 1024),
]
# A watch on a member that lost its leader is cancelled instead of going silent.
_REQUIRE_LEADER = (("hasleader", "true"),)

T = TypeVar("T")


def _retryable(error: grpc.aio.AioRpcError) -> bool:
    details = error.details() or ""
    if "space exceeded" in details:
        return False  # the quota is full: retrying cannot help
    # etcd's own deadline on a proposal it could not commit in time comes as UNKNOWN
    return error.code() in _RETRY or "deadline exceeded" in details or "timed out" in details


class EtcdClient:
    """A client of every member of one etcd cluster.

    Construct with the members' `host:port` targets, then `await open()`;
    `await close()` closes every channel. Raises `NoQuorum` when a majority is
    unreachable, `ClusterError` for what a retry cannot fix.
    """

    def __init__(
        self,
        endpoints: Sequence[str],
        *,
        call_timeout: float = CALL_TIMEOUT,
        deadline: float = DEADLINE,
    ) -> None:
        if not endpoints:
            raise ValueError("an etcd cluster needs at least one member endpoint")
        self.endpoints = list(endpoints)
        self.call_timeout = call_timeout
        self.deadline = deadline
        self._channels: list[grpc.aio.Channel] = []
        self._kv: list[rpc.KVStub] = []
        self._maint: list[rpc.MaintenanceStub] = []
        self._watch: list[rpc.WatchStub] = []
        self._lease: list[rpc.LeaseStub] = []
        self._current = 0

    @property
    def majority(self) -> int:
        """Return how many members make a quorum."""
        return len(self.endpoints) // 2 + 1

    async def open(self) -> None:
        """Create one channel per member (connects lazily; never blocks on the network)."""
        for target in self.endpoints:
            channel = grpc.aio.insecure_channel(target, options=_CHANNEL_OPTIONS)
            self._channels.append(channel)
            self._kv.append(rpc.KVStub(channel))
            self._maint.append(rpc.MaintenanceStub(channel))
            self._watch.append(rpc.WatchStub(channel))
            self._lease.append(rpc.LeaseStub(channel))

    async def close(self) -> None:
        """Close every channel; calls in flight fail."""
        for channel in self._channels:
            await channel.close()
        self._channels = []

    async def txn(self, request: rpc.TxnRequest) -> rpc.TxnResponse:
        """Run a transaction (retried: make it idempotent)."""
        return await self._retrying(lambda i, t: self._kv[i].Txn(request, timeout=t))

    async def range(self, request: rpc.RangeRequest) -> rpc.RangeResponse:
        """Run a (linearizable unless `request.serializable`) range read."""
        return await self._retrying(lambda i, t: self._kv[i].Range(request, timeout=t))

    async def compact(self, revision: int) -> None:
        """Compact etcd's history up to `revision`; already compacted is not an error."""
        request = rpc.CompactionRequest(revision=revision)
        try:
            await self._retrying(lambda i, t: self._kv[i].Compact(request, timeout=t))
        except ClusterError as error:
            if "compacted" not in str(error):
                raise

    async def grant(self, ttl: int) -> int:
        """Grant a lease of `ttl` seconds and return its id."""
        request = rpc.LeaseGrantRequest(TTL=ttl)
        reply = await self._retrying(lambda i, t: self._lease[i].LeaseGrant(request, timeout=t))
        return reply.ID

    async def reachable(self, enough: int | None = None) -> int:
        """Return how many members answer a status request, probing for up to PROBE_WINDOW.

        A member that refuses (nothing listens, or its channel is failing) is
        asked once more after a pause and then counted gone; one that is only
        slow is asked again until the window closes: on a loaded host a live
        member, or the first call on an idle channel, can miss one short probe,
        and a live member must not be reported gone. With `enough`, returns as
        soon as that many answered (the count is then at least `enough`).
        """
        loop = asyncio.get_running_loop()
        end = loop.time() + PROBE_WINDOW

        async def probe(i: int) -> bool:
            refusals = 0
            while True:
                timeout = max(0.05, min(PROBE_TIMEOUT, end - loop.time()))
                try:
                    await self._maint[i].Status(rpc.StatusRequest(), timeout=timeout)
                    return True
                except grpc.aio.AioRpcError as error:
                    log.debug("probe of etcd %s: %s", self.endpoints[i], error.details())
                    if error.code() != grpc.StatusCode.DEADLINE_EXCEEDED:
                        refusals += 1
                        if refusals == 2:
                            return False
                        await asyncio.sleep(0.1)
                if loop.time() >= end:
                    return False

        probes = [asyncio.ensure_future(probe(i)) for i in range(len(self.endpoints))]
        answered = 0
        try:
            for done in asyncio.as_completed(probes):
                answered += await done
                if enough is not None and answered >= enough:
                    break
        finally:
            for task in probes:
                task.cancel()
        return answered

    async def leader(self) -> int | None:
        """Return the index of the member that leads now, or None if none answers as leader."""
        for i in range(len(self.endpoints)):
            try:
                status = await self._maint[i].Status(rpc.StatusRequest(), timeout=PROBE_TIMEOUT)
            except grpc.aio.AioRpcError:
                continue
            if status.leader and status.leader == status.header.member_id:
                return i
        return None

    async def watch(
        self, key: bytes, range_end: bytes, start_revision: int
    ) -> AsyncIterator[rpc.WatchResponse]:
        """Yield watch responses for `[key, range_end)` from `start_revision` on one member.

        Raises the gRPC error when the stream breaks (member gone, no leader):
        the caller resumes from the revision it reached, on another member
        (`rotate()`). Never relied on across a compaction: a response with
        `compact_revision` set tells the caller to re-list.
        """
        i = self._current
        create = rpc.WatchCreateRequest(key=key, range_end=range_end, start_revision=start_revision)
        call = self._watch[i].Watch(metadata=_REQUIRE_LEADER)
        try:
            await call.write(rpc.WatchRequest(create_request=create))
            async for response in call:
                yield response
        finally:
            call.cancel()

    def rotate(self) -> None:
        """Use the next member from now on (after its stream or call failed)."""
        self._current = (self._current + 1) % len(self.endpoints)

    async def _retrying(self, call: Callable[[int, float], Awaitable[T]]) -> T:
        loop = asyncio.get_running_loop()
        end = loop.time() + self.deadline
        failures = 0
        while True:
            i = self._current
            timeout = max(0.05, min(self.call_timeout, end - loop.time()))
            try:
                return await call(i, timeout)
            except grpc.aio.AioRpcError as error:
                if not _retryable(error):
                    raise ClusterError(f"etcd refused: {error.details()}") from error
                failures += 1
                log.debug("etcd %s: %s", self.endpoints[i], error.details())
                if self._current == i:
                    self.rotate()
                if failures == 1 or loop.time() >= end:
                    # the first failure only asks whether a quorum is there; the last one counts
                    reachable = await self.reachable(self.majority if loop.time() < end else None)
                    if reachable < self.majority:
                        raise NoQuorum(reachable, len(self.endpoints)) from error
                    if loop.time() >= end:
                        raise NoQuorum(
                            reachable,
                            len(self.endpoints),
                            f"no leader elected within {self.deadline:g} s",
                        ) from error
                await asyncio.sleep(min(0.05 * failures, 0.2))
