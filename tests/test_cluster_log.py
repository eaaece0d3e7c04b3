"""The replicated log on a real 3-member etcd cluster on loopback ports.

Group commit, etcd's order as the space's order, compare-and-swap for take,
a replica resuming from its revision or re-listing after a compaction, a
minority refusing at once, and a leader's kill -9.
"""

from __future__ import annotations

import asyncio
import time

import msgpack
import pytest
from aetcd import rpc

from space.errors import NoQuorum, WriteConflict
from space.store.cluster_keys import ROOT, log_key, state_prefix, triple_key
from space.store.etcd_applier import Applier, Batch, Listing, compact_behind_replicas
from space.store.etcd_client import EtcdClient
from space.store.etcd_log import ClusterLog, Entry


@pytest.fixture
def cluster(etcd_cluster):
    return etcd_cluster


class Replica:
    """What a store replica keeps: the payloads applied, in order, and the re-listed state."""

    def __init__(self, revision: int = 0) -> None:
        self.applied: list[bytes] = []
        self.seq_of: dict[bytes, int] = {}
        self.revisions: list[int] = []
        self.seqs: dict[str, int] = {}
        self.state: dict[bytes, bytes] = {}
        self.start = revision

    def apply(self, revision: int, batches: list[Batch]) -> None:
        self.revisions.append(revision)
        for batch in batches:
            self.applied.extend(batch.payloads)
            for i, p in enumerate(batch.payloads):
                self.seq_of[p] = batch.first_seq + i

    def relist(self, listing: Listing) -> None:
        self.state = dict(listing.pairs)
        self.seqs = listing.seqs


async def _open(endpoints: list[str], **kw: object) -> tuple[EtcdClient, ClusterLog]:
    client = EtcdClient(endpoints, **kw)  # type: ignore[arg-type]
    await client.open()
    cluster_log = ClusterLog(client)
    await cluster_log.start()
    return client, cluster_log


async def _close(client: EtcdClient, *logs: ClusterLog | Applier) -> None:
    for x in logs:
        await x.close()
    await client.close()


def test_group_commit_orders_every_changeset_once_on_every_replica(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        replicas = [Replica(), Replica()]
        appliers = [
            Applier(client, node=f"r{i}", revision=0, apply=r.apply, relist=r.relist)
            for i, r in enumerate(replicas)
        ]
        for a in appliers:
            await a.start()
        sent = [f"cs-{i}".encode() for i in range(640)]
        limit = asyncio.Semaphore(64)

        async def write(payload: bytes) -> tuple[int, int]:
            async with limit:
                pos = await clog.append(Entry("s", payload))
                return pos.revision, pos.index

        positions = await asyncio.gather(*(write(p) for p in sent))
        assert len(set(positions)) == len(sent), "two changesets share a place in the order"
        assert clog.transactions < len(sent) / 4, "changesets were not grouped"
        in_order = [p for _, p in sorted(zip(positions, sent, strict=True))]
        last = max(r for r, _ in positions)
        for a in appliers:
            assert await a.wait_applied(last, 10), f"replica at {a.revision}, log at {last}"
        for r in replicas:
            assert r.applied == in_order
            assert [r.seq_of[p] for p in in_order] == list(range(1, len(sent) + 1))
        await _close(client, clog, *appliers)

    asyncio.run(main())


def test_changesets_arriving_one_by_one_during_a_transaction_go_together_in_the_next(cluster):
    """Below `pipeline` waiting, no second transaction starts beside the one in flight."""

    async def main() -> None:
        client = EtcdClient(cluster.endpoints)
        await client.open()
        clog = ClusterLog(client, inflight=8, pipeline=32)
        await clog.start()
        first = asyncio.ensure_future(clog.append(Entry("s", b"first")))
        deadline = time.monotonic() + 5
        while not clog.flying:  # until the first transaction is on its way to etcd
            assert time.monotonic() < deadline, "the first transaction never started"
            await asyncio.sleep(0)
        later = []
        for i in range(20):  # each one alone, with idle committers given their turn
            later.append(asyncio.ensure_future(clog.append(Entry("s", b"%d" % i))))
            await asyncio.sleep(0)
        positions = await asyncio.gather(*later)
        assert {p.revision for p in positions} == {positions[0].revision}
        assert positions[0].revision > (await first).revision
        assert clog.transactions == 2
        await _close(client, clog)

    asyncio.run(main())


async def _lingering(
    cluster, linger: float, busy_for: float = 0.05
) -> tuple[EtcdClient, ClusterLog]:
    """A log as a replica runs it, busy after 8 changesets in a transaction."""
    client = EtcdClient(cluster.endpoints)
    await client.open()
    clog = ClusterLog(
        client, inflight=8, pipeline=32, linger=linger, linger_from=8, busy_for=busy_for
    )
    await clog.start()
    return client, clog


async def _burst(clog: ClusterLog) -> None:
    """Append 8 changesets at once (one transaction: the log is busy after it)."""
    await asyncio.gather(*(clog.append(Entry("s", b"busy%d" % i)) for i in range(8)))


def test_a_busy_log_waits_for_the_writers_on_their_way_an_idle_one_sends_at_once(cluster):
    """After a transaction of `linger_from` entries the next waits `linger`; not after less."""
    linger = 2.0

    async def main() -> None:
        # busy for as long as it waits: a loaded machine may run this test's next line late
        client, clog = await _lingering(cluster, linger, busy_for=linger)
        began = time.monotonic()
        await clog.append(Entry("s", b"alone"))
        assert time.monotonic() - began < linger  # idle: sent at once
        await _burst(clog)
        assert clog.transactions == 2  # the eight went together: the log is busy
        one = asyncio.ensure_future(clog.append(Entry("s", b"one")))
        await asyncio.sleep(0.2)  # a writer of the last transaction, on its way back
        two = asyncio.ensure_future(clog.append(Entry("s", b"two")))
        assert (await one).revision == (await two).revision
        began = time.monotonic()
        await clog.append(Entry("s", b"alone again"))  # the last carried two: idle again
        assert time.monotonic() - began < linger
        await _close(client, clog)

    asyncio.run(main())


def test_a_lone_writer_long_after_a_busy_transaction_is_sent_at_once(cluster):
    """The log is busy only while the writers of its last transaction can be on their way
    back: one writing alone a while after a burst is not held `linger` for them."""
    linger = 2.0

    async def main() -> None:
        client, clog = await _lingering(cluster, linger)
        await _burst(clog)
        assert clog.transactions == 1  # the burst went together: its transaction was busy
        await asyncio.sleep(clog.busy_for * 2)  # then nobody writes for a while
        began = time.monotonic()
        await clog.append(Entry("s", b"alone"))
        assert time.monotonic() - began < linger
        await _close(client, clog)

    asyncio.run(main())


def test_a_busy_log_does_not_wait_when_a_full_pipeline_of_changesets_waits(cluster):
    """The wait is for a few changesets to become many: once `pipeline` wait, they go."""
    linger = 5.0

    async def main() -> None:
        client, clog = await _lingering(cluster, linger)
        await _burst(clog)
        began = time.monotonic()
        await asyncio.gather(*(clog.append(Entry("s", b"many%d" % i)) for i in range(40)))
        assert time.monotonic() - began < linger
        await _close(client, clog)

    asyncio.run(main())


def test_writes_of_one_key_commit_in_the_order_they_were_appended(cluster):
    """Two transactions are in flight at once; per key, the later append never overtakes."""

    async def main() -> None:
        client = EtcdClient(cluster.endpoints)
        await client.open()
        clog = ClusterLog(client, batch=8)  # many small transactions, two in flight
        await clog.start()
        key = triple_key(ROOT, "s", "t", "<door1>", "<ac:state>", "<open>")
        other = [triple_key(ROOT, "s", "t", f"<x{i}>", "<a>", "<b>") for i in range(200)]

        def entry(i: int) -> Entry:
            if i % 3 == 0:
                return Entry("s", b"%d" % i, puts={key: b"%d" % i})
            if i % 3 == 1:
                return Entry("s", b"%d" % i, deletes=[key])
            return Entry("s", b"%d" % i, puts={other[i]: b"x"})

        positions = await asyncio.gather(*(clog.append(entry(i)) for i in range(199)))
        touching = [(p.revision, p.index, i) for i, p in enumerate(positions) if i % 3 != 2]
        assert [i for *_, i in sorted(touching)] == [i for *_, i in touching]
        reply = await client.range(rpc.RangeRequest(key=key))
        assert [kv.value for kv in reply.kvs] == [b"198"]
        await _close(client, clog)

    asyncio.run(main())


def test_two_takers_on_two_members_never_take_the_same_item(cluster):
    """Each taker read the items at one revision and deletes one, guarded: present, unchanged."""

    async def main() -> None:
        a_client, a_log = await _open(cluster.endpoints)
        b_client, b_log = await _open(cluster.endpoints[1:] + cluster.endpoints[:1])
        items = [triple_key(ROOT, "s", "t", f"<dock{i}>", "<a>", "<Free>") for i in range(30)]
        put = await a_log.append(Entry("s", b"docks", puts={k: b"free" for k in items}))

        async def take(clog: ClusterLog, who: str, key: bytes) -> str | None:
            entry = Entry(
                "s",
                f"{who} takes".encode(),
                deletes=[key],
                guards={key: put.revision},
                present=[key],
            )
            try:
                await clog.append(entry)
                return who
            except WriteConflict:
                return None

        winners = await asyncio.gather(
            *(asyncio.gather(take(a_log, "a", k), take(b_log, "b", k)) for k in items)
        )
        for pair in winners:
            assert sorted(w for w in pair if w) in (["a"], ["b"]), pair
        left = await a_client.range(
            rpc.RangeRequest(key=state_prefix(ROOT, "s"), range_end=state_prefix(ROOT, "t"))
        )
        assert left.count == 0
        await _close(a_client, a_log)
        await _close(b_client, b_log)

    asyncio.run(main())


def test_a_take_fails_when_the_item_went_or_came_back_since_the_read(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        key = triple_key(ROOT, "s", "t", "<patient1>", "<ac:waiting_for>", "<task1>")
        read = await clog.append(Entry("s", b"add", puts={key: b"x"}))
        await clog.append(Entry("s", b"other takes", deletes=[key]))

        def take() -> Entry:
            return Entry("s", b"take", deletes=[key], guards={key: read.revision}, present=[key])

        with pytest.raises(WriteConflict):  # gone
            await clog.append(take())
        await clog.append(Entry("s", b"put back", puts={key: b"x"}))
        with pytest.raises(WriteConflict):  # there again, but not the item that was read
            await clog.append(take())
        await _close(client, clog)

    asyncio.run(main())


def test_a_guard_on_a_key_the_same_batch_writes_fails(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        key = triple_key(ROOT, "s", "t", "<robot1>", "<ac:task>", "<t1>")
        first = await clog.append(Entry("s", b"init", puts={key: b"v0"}))
        both = [
            Entry("s", f"w{i}".encode(), puts={key: f"v{i}".encode()}, guards={key: first.revision})
            for i in (1, 2)
        ]
        results = await asyncio.gather(*(clog.append(e) for e in both), return_exceptions=True)
        assert sum(isinstance(r, WriteConflict) for r in results) == 1, results
        await _close(client, clog)

    asyncio.run(main())


def test_a_retried_transaction_is_logged_once(cluster):
    """A retry after a timeout that had committed must not log its changesets again."""

    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        waiting = [(Entry("s", b"once"), asyncio.get_running_loop().create_future())]
        request = await clog._request(waiting, b"tspace/batch/test-1")
        first = await client.txn(request)
        again = await client.txn(request)
        assert first.succeeded and not again.succeeded
        assert again.responses[0].response_range.kvs[0].mod_revision == first.header.revision
        history = await client.range(rpc.RangeRequest(key=log_key(ROOT, "s")))
        assert history.kvs[0].version == 1
        await _close(client, clog)

    asyncio.run(main())


def test_a_log_restarted_under_its_name_commits_its_first_changesets(cluster):
    """The markers of a node's earlier life (leased 60 s) are not taken for its own."""

    async def main() -> None:
        client = EtcdClient(cluster.endpoints)
        await client.open()
        for life in (b"first life", b"second life"):
            clog = ClusterLog(client, node="store-a")
            await clog.start()
            pos = await clog.append(Entry("s", life))
            reply = await client.range(rpc.RangeRequest(key=log_key(ROOT, "s")))
            assert msgpack.unpackb(reply.kvs[0].value) == [life]
            assert reply.kvs[0].mod_revision == pos.revision
            await clog.close()
        await client.close()

    asyncio.run(main())


def test_a_replica_resumes_from_its_revision(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        replica = Replica()
        first = Applier(client, node="r", revision=0, apply=replica.apply, relist=replica.relist)
        await first.start()
        pos = None
        for i in range(5):
            pos = await clog.append(Entry("s", f"before-{i}".encode()))
        assert await first.wait_applied(pos.revision, 10)
        await first.close()
        for i in range(5):
            pos = await clog.append(Entry("s", f"after-{i}".encode()))
        again = Replica()
        second = Applier(
            client,
            node="r",
            revision=first.revision,
            seqs=first.seqs,
            apply=again.apply,
            relist=again.relist,
        )
        await second.start()
        assert await second.wait_applied(pos.revision, 10)
        assert again.applied == [f"after-{i}".encode() for i in range(5)]
        assert [again.seq_of[p] for p in again.applied] == [6, 7, 8, 9, 10]
        assert second.relists == 0
        await _close(client, clog, second)

    asyncio.run(main())


def test_a_replica_behind_a_compaction_relists_then_follows(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        key = triple_key(ROOT, "s", "t", "<robot1>", "<ac:at>", "<kitchen>")
        start = await clog.append(Entry("s", b"first", puts={key: b"kitchen"}))
        # grouped: the space's counter keys count several changesets per transaction
        await asyncio.gather(*(clog.append(Entry("s", f"missed-{i}".encode())) for i in range(10)))
        last = await clog.append(Entry("s", b"last"))
        await client.compact(last.revision)
        replica = Replica()
        applier = Applier(
            client, node="r", revision=start.revision, apply=replica.apply, relist=replica.relist
        )
        await applier.start()
        assert await applier.wait_applied(last.revision, 10)
        assert applier.relists == 1
        assert replica.state == {key: b"kitchen"}
        assert replica.seqs == {"s": 12}  # the space's 12 changesets, none of them replayed
        assert replica.applied == []  # nothing replayed: the state came whole
        after = await clog.append(Entry("s", b"after"))
        assert await applier.wait_applied(after.revision, 10)
        assert replica.applied == [b"after"]
        assert replica.seq_of[b"after"] == 13
        await _close(client, clog, applier)

    asyncio.run(main())


def test_compaction_stops_at_the_slowest_live_replica(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        positions = [await clog.append(Entry("s", f"{i}".encode())) for i in range(6)]
        slow, fast = positions[2].revision, positions[5].revision
        for node, rev in (("slow", slow), ("fast", fast)):
            put = rpc.PutRequest(key=ROOT + b"replicas/" + node.encode(), value=b"%d" % rev)
            await client.txn(rpc.TxnRequest(success=[rpc.RequestOp(request_put=put)]))
        assert await compact_behind_replicas(client, ROOT, 0) == slow
        replica = Replica()
        applier = Applier(
            client, node="slow", revision=slow, apply=replica.apply, relist=replica.relist
        )
        await applier.start()
        assert await applier.wait_applied(fast, 10)
        assert applier.relists == 0, "the slow replica's history was compacted away"
        assert replica.applied == [b"3", b"4", b"5"]
        await _close(client, clog, applier)

    asyncio.run(main())


def test_a_minority_refuses_writes_at_once(cluster):
    cluster.kill("m1")
    cluster.kill("m2")

    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        began = time.monotonic()
        with pytest.raises(NoQuorum, match=r"^no quorum: 1 of 3 members reachable$"):
            await clog.append(Entry("s", b"lost?"))
        assert time.monotonic() - began < 1.5
        await _close(client, clog)

    asyncio.run(main())


def test_after_the_leader_is_killed_the_next_write_is_acknowledged_within_3s(cluster):
    async def main() -> None:
        client, clog = await _open(cluster.endpoints)
        await clog.append(Entry("s", b"before"))
        leader = await client.leader()
        assert leader is not None
        cluster.kill(cluster.members[leader].name)
        began = time.monotonic()
        pos = await clog.append(Entry("s", b"after"))
        assert time.monotonic() - began <= 3.0
        reply = await client.range(rpc.RangeRequest(key=log_key(ROOT, "s")))
        assert msgpack.unpackb(reply.kvs[0].value) == [b"after"]
        assert reply.kvs[0].mod_revision == pos.revision
        await _close(client, clog)

    asyncio.run(main())
