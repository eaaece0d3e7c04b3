"""A store's decisions as etcd entries: functional replacement and take by compare-and-swap.

Against 3 real etcd members: two replicas on two members that both replace a
robot's dock from the same state cannot both win; what etcd holds re-lists
as the state the decisions made.
"""

from __future__ import annotations

import asyncio

import msgpack
import pytest
from aetcd import rpc

from space.errors import WriteConflict
from space.store.cluster_entries import Decision, entry_for, read_state
from space.store.cluster_keys import ROOT, prefix_end
from space.store.etcd_client import EtcdClient
from space.store.etcd_log import ClusterLog

AT = "<https://w3id.org/tspace/selfconfig#at>"
DOCK = "<https://w3id.org/tspace/selfconfig#dockedAt>"
FUNCTIONAL = frozenset({AT, DOCK})
R1, R2 = "<http://ex.org/robot1>", "<http://ex.org/robot2>"


async def _log(endpoints: list[str]) -> tuple[EtcdClient, ClusterLog]:
    client = EtcdClient(endpoints)
    await client.open()
    clog = ClusterLog(client)
    await clog.start()
    return client, clog


async def _relist(client: EtcdClient) -> dict:
    pairs = []
    for prefix in (ROOT + b"state/", ROOT + b"fn/", ROOT + b"prefix/"):
        reply = await client.range(rpc.RangeRequest(key=prefix, range_end=prefix_end(prefix)))
        pairs += [(kv.key, kv.value) for kv in reply.kvs]
    return read_state(ROOT, pairs)


def test_two_replicas_replacing_one_functional_value_from_one_state_cannot_both_win(
    etcd_cluster,
):
    async def main() -> None:
        a_client, a = await _log(etcd_cluster.endpoints)
        b_client, b = await _log(etcd_cluster.endpoints[::-1])
        first = Decision(
            "s", b"cs0", 0, "0001", FUNCTIONAL, added=[(R1, AT, "<kitchen>")], replaced=[(R1, AT)]
        )
        read = (await a.append(entry_for(ROOT, first))).revision

        def move(to: str, stamp: str) -> Decision:  # decided on the state at `read`
            return Decision(
                "s",
                to.encode(),
                read,
                stamp,
                FUNCTIONAL,
                added=[(R1, AT, to)],
                removed=[(R1, AT, "<kitchen>")],
                replaced=[(R1, AT)],
            )

        results = await asyncio.gather(
            a.append(entry_for(ROOT, move("<hall>", "0002"))),
            b.append(entry_for(ROOT, move("<lab>", "0003"))),
            return_exceptions=True,
        )
        assert sum(isinstance(r, WriteConflict) for r in results) == 1, results
        image = (await _relist(a_client))["s"]
        assert len(image.asserted) == 1, "a functional property holds two values"
        assert image.asserted[0] in (f"{R1} {AT} <hall> .\n", f"{R1} {AT} <lab> .\n")
        for c, clog in ((a_client, a), (b_client, b)):
            await clog.close()
            await c.close()

    asyncio.run(main())


def test_a_relisted_state_is_what_the_decisions_made(etcd_cluster):
    async def main() -> None:
        client, clog = await _log(etcd_cluster.endpoints)
        patient = ("<http://ex.org/p1>", "<http://ex.org/waitingFor>", "<http://ex.org/t1>")
        inferred = (R2, "<http://www.w3.org/1999/02/22-rdf-syntax-ns#type>", "<http://ex.org/R>")
        made = Decision(
            "s",
            b"cs1",
            0,
            "0001",
            FUNCTIONAL,
            added=[patient, (R2, DOCK, "<dock1>")],
            inferred_added=[inferred],
            replaced=[(R2, DOCK)],
            prefixes={"ac": "https://w3id.org/tspace/selfconfig#"},
        )
        pos = await clog.append(entry_for(ROOT, made))
        take = Decision("s", b"take", pos.revision, removed=[patient], taken=[patient])
        await clog.append(entry_for(ROOT, take))
        with pytest.raises(WriteConflict):  # the same item, read at the same revision
            await clog.append(entry_for(ROOT, take))
        image = (await _relist(client))["s"]
        assert image.asserted == [f"{R2} {DOCK} <dock1> .\n"]
        assert image.stamps == [(f"{R2} {DOCK} <dock1> .\n", "0001")]
        assert image.inferred == [" ".join(inferred) + " .\n"]
        assert image.prefixes == {"ac": "https://w3id.org/tspace/selfconfig#"}
        history = await client.range(rpc.RangeRequest(key=ROOT + b"log/s"))
        assert msgpack.unpackb(history.kvs[0].value) == [b"take"]
        await clog.close()
        await client.close()

    asyncio.run(main())


def test_one_request_decided_on_two_replicas_is_committed_once(etcd_cluster):
    """A writer's retry reached another replica before that one applied the first attempt."""

    async def main() -> None:
        a_client, a = await _log(etcd_cluster.endpoints)
        b_client, b = await _log(etcd_cluster.endpoints[::-1])

        def attempt(payload: bytes) -> Decision:
            return Decision("s", payload, 0, "0001", added=[(R1, "<p>", "<o>")], request="req-42")

        results = await asyncio.gather(
            a.append(entry_for(ROOT, attempt(b"first"))),
            b.append(entry_for(ROOT, attempt(b"retry"))),
            return_exceptions=True,
        )
        assert sum(isinstance(r, WriteConflict) for r in results) == 1, results
        other = await a.append(entry_for(ROOT, Decision("s", b"other", 0, request="req-43")))
        assert other.revision > 0
        for c, clog in ((a_client, a), (b_client, b)):
            await clog.close()
            await c.close()

    asyncio.run(main())
