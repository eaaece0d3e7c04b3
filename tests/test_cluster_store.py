"""Three `tspace serve --cluster` replicas on a real 3-member etcd cluster.

Each replica runs its own Zenoh router, not meshed with the others: whatever
one replica learns of another's writes came through etcd. A writer on one
replica reads its write on another; two takers on two replicas race for the
same items and each item is taken once; a replica whose side has lost the
majority refuses writes and reads with "no quorum: 1 of 3 members reachable",
and answers a read that asks for possibly stale answers. Also: one functional
value when two replicas write it at once, exactly once across replicas, a
replica resuming from its revision after kill -9 or re-listing after a
compaction, and the quorum shown by the HMI.
"""

from __future__ import annotations

import asyncio
import json
import signal
import subprocess
import threading
import urllib.request

import pytest
from agentprocs import AgentProcess, knowledge
from rdflib import Literal, URIRef
from rdflib.namespace import OWL, RDF

from conftest import Server, free_port, tspace_cmd, wait_for
from space import Changeset, TripleSpace
from space.cluster_status import ClusterWatch
from space.errors import NoQuorum, SpaceError

EX = "http://example.org/"


def _open(server: Server, space: str) -> TripleSpace:
    return TripleSpace.open(server.endpoint, space=space, agent="test")


def _s(n: int) -> URIRef:
    return URIRef(f"{EX}item{n}")


def test_a_write_on_one_replica_is_read_on_another(replicas: list[Server]) -> None:
    with _open(replicas[0], "fleet") as a, _open(replicas[2], "fleet") as c:
        ack = a.write([(_s(1), URIRef(EX + "at"), Literal("dock"))])
        assert ack.seq == 1
        # acknowledged means committed by a majority: the read on another replica sees it
        assert (_s(1), URIRef(EX + "at"), Literal("dock")) in c.query((None, None, None))
        ack = c.write([(_s(2), URIRef(EX + "at"), Literal("hall"))])
        assert ack.seq == 2  # every replica numbers the space's changesets alike
        assert len(a.query((None, URIRef(EX + "at"), None))) == 2
        assert c.seq() == 2
        # a changeset sent again to another replica (its writer's retry) is applied once
        cs = a.changeset([(_s(4), URIRef(EX + "at"), Literal("ward"))])
        first = a.send(cs)
        again = c.send(cs)
        assert (first.seq, again.seq) == (3, 3)
        assert c.seq() == 3
    # a prefix binding sent with a write is kept by the replica that decided it and the others
    with TripleSpace.open(replicas[0].endpoint, space="fleet", prefixes={"ex": EX}) as named:
        named.write([(_s(5), URIRef(EX + "at"), Literal("lab"))])
    for r in (replicas[0], replicas[2]):
        with _open(r, "fleet") as fresh:
            assert fresh.load_prefixes().as_dict().get("ex") == EX


def test_a_take_raced_on_two_replicas_wins_once(replicas: list[Server]) -> None:
    items = 30
    p = URIRef(EX + "job")
    with _open(replicas[0], "jobs") as seed:
        seed.write([(_s(n), p, Literal(n)) for n in range(items)])
    taken: list[list] = [[], []]

    def taker(k: int) -> None:
        with _open(replicas[k], "jobs") as ts:
            for n in range(items):
                taken[k].extend(ts.take((_s(n), p, None)))

    threads = [threading.Thread(target=taker, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    both = taken[0] + taken[1]
    assert sorted(int(o) for _, _, o in both) == list(range(items)), "each item taken once"
    with _open(replicas[2], "jobs") as third:
        assert len(third.query((None, p, None))) == 0


def test_a_functional_value_written_on_two_replicas_at_once_stays_one(
    replicas: list[Server],
) -> None:
    level, robot = URIRef(EX + "level"), _s(1)
    with _open(replicas[0], "dock") as seed:
        seed.write([(level, RDF.type, OWL.FunctionalProperty)])

    def writer(k: int) -> None:
        with _open(replicas[2 * k], "dock") as ts:
            for n in range(25):
                ts.write([(robot, level, Literal(100 * k + n))])

    threads = [threading.Thread(target=writer, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    values = []
    for r in replicas:
        with _open(r, "dock") as ts:
            values.append({o for _, _, o in ts.query((robot, level, None))})
    assert len(values[0]) == 1, values  # never both values: the replacement was decided once
    assert values[0] == values[1] == values[2]


def test_a_scoped_subscriber_gets_what_another_replica_decided(replicas: list[Server]) -> None:
    """A part published on another (here unreachable) router is found through `prev`."""
    at = URIRef(EX + "at")
    seen: list = []
    with _open(replicas[2], "parts") as c, _open(replicas[0], "parts") as a:
        c.write([(_s(9), at, Literal("start"))])
        c.subscribe(None, seen.append, scope=[(_s(1), None)])
        first = a.write([(_s(1), at, Literal("dock"))])  # decided and published on replica 0
        second = c.write([(_s(1), at, Literal("hall"))])  # its part names the first's seq
        wait_for(lambda: len(seen) >= 2, 10, "both parts")
        assert [x.seq for x in seen] == [first.seq, second.seq]


def test_a_replica_ends_a_changeset_of_many_parts(replicas: list[Server], monkeypatch) -> None:
    """A replica publishes the end after a changeset's parts: one delivery, without a hold."""
    import space._dispatch

    monkeypatch.setattr(space._dispatch, "IDLE", 60.0)
    monkeypatch.setattr(space._dispatch, "HOLD_MAX", 60.0)
    seen: list = []
    with _open(replicas[2], "ends") as c:
        c.subscribe(None, seen.append, scope=[(_s(1), None)])
        ack = c.write([(_s(1), URIRef(f"{EX}p{i}"), Literal(i)) for i in range(50)])
        wait_for(lambda: sum(len(x.added) for x in seen) >= 50, 10, "the 50 parts")
        assert [x.seq for x in seen] == [ack.seq]


def test_a_minority_replica_refuses_writes_and_reads(replicas: list[Server], etcd_cluster) -> None:
    triple = (_s(7), URIRef(EX + "at"), Literal("dock"))
    with _open(replicas[0], "cut") as ts:
        watch = ClusterWatch(ts.session)
        try:
            wait_for(lambda: "3 of 3 reachable" in watch.line(), 10, "the replica's report")
            ts.write([triple])
            etcd_cluster.kill("m1")
            etcd_cluster.kill("m2")
            # what tspace up's view and the HMI show
            wait_for(lambda: "no quorum: 1 of 3 members reachable" in watch.line(), 10, watch.line)
        finally:
            watch.close()
        with pytest.raises(NoQuorum, match="no quorum: 1 of 3 members reachable"):
            ts.write([(_s(8), URIRef(EX + "at"), Literal("hall"))])
        with pytest.raises(NoQuorum, match="no quorum: 1 of 3 members reachable"):
            ts.query((None, None, None))
        assert triple in ts.query((None, None, None), stale=True)
    cli = subprocess.run(
        tspace_cmd("query", "-t", "?s ?p ?o", "--connect", replicas[1].endpoint, "--space", "cut"),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert cli.returncode != 0
    assert "no quorum: 1 of 3 members reachable" in cli.stderr
    stale = subprocess.run(
        tspace_cmd(
            "query",
            "-t",
            "?s ?p ?o",
            "--stale",
            "--connect",
            replicas[1].endpoint,
            "--space",
            "cut",
        ),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert stale.returncode == 0, stale.stderr
    assert "dock" in stale.stdout


def test_replicas_come_back_after_the_majority_does(replicas: list[Server], etcd_cluster) -> None:
    with _open(replicas[0], "heal") as a:
        a.write([(_s(1), URIRef(EX + "at"), Literal("dock"))])
        etcd_cluster.kill("m1")
        etcd_cluster.kill("m2")
        with pytest.raises(SpaceError):
            a.write([(_s(2), URIRef(EX + "at"), Literal("hall"))])
        etcd_cluster.restart("m1")

        def writes() -> bool:
            try:
                a.write([(_s(3), URIRef(EX + "at"), Literal("lab"))], timeout=2)
                return True
            except SpaceError:
                return False

        wait_for(writes, 30, "a write once two members are back")
    with _open(replicas[1], "heal") as b:
        answers: list[set[str]] = []

        def answers_too() -> bool:  # its own probe of the members that came back may lag a's
            try:
                answers.append({str(o) for _, _, o in b.query((None, URIRef(EX + "at"), None))})
                return True
            except SpaceError:
                return False

        wait_for(answers_too, 30, "the other replica answering once two members are back")
        found = answers[-1]
        # every acknowledged write; the refused one only if etcd had it from before the cut
        # (a refusal after the write was sent is not a proof it was not committed)
        assert {"dock", "lab"} <= found <= {"dock", "hall", "lab"}


def test_a_replica_killed_resumes_from_its_revision(replicas: list[Server]) -> None:
    at = URIRef(EX + "at")
    with _open(replicas[0], "resume") as a:
        a.write([(_s(1), at, Literal("dock"))])
        replicas[1].stop(signal.SIGKILL)
        for n in range(2, 12):
            a.write([(_s(n), at, Literal("hall"))])
    replicas[1].start()
    with _open(replicas[1], "resume") as b:
        assert len(b.query((None, at, None))) == 11
        ack = b.write([(_s(12), at, Literal("lab"))])
        assert ack.seq == 12  # numbered after the 11 it applied, none applied twice
        assert b.seq() == 12


def test_a_replica_behind_a_compaction_relists_the_space_whole(
    replicas: list[Server], etcd_cluster
) -> None:
    at, level = URIRef(EX + "at"), URIRef(EX + "level")
    with _open(replicas[0], "relist") as a:
        a.write([(level, RDF.type, OWL.FunctionalProperty)])
        a.write([(_s(1), at, Literal("dock")), (_s(1), level, Literal(10))])
        replicas[1].stop(signal.SIGKILL)
        a.write([(_s(2), at, Literal("hall")), (_s(1), level, Literal(20))])
        a.take((_s(1), at, None))
        seq = a.seq()
    # as if the replica had been away longer than etcd keeps the log: compact it all away
    asyncio.run(_compact_all(etcd_cluster.endpoints))
    replicas[1].start()
    with _open(replicas[1], "relist") as b:
        found = set(b.query((None, None, None), graph="asserted"))
        assert (_s(2), at, Literal("hall")) in found
        assert (_s(1), at, Literal("dock")) not in found  # taken
        assert (_s(1), level, Literal(20)) in found and (_s(1), level, Literal(10)) not in found
        assert b.seq() == seq
        ack = b.write([(_s(1), level, Literal(30))])  # the functional value is still replaced
        assert ack.seq == seq + 1
        assert {o for _, _, o in b.query((_s(1), level, None))} == {Literal(30)}
    with _open(replicas[0], "relist") as a:
        assert {o for _, _, o in a.query((_s(1), level, None))} == {Literal(30)}
    assert "re-listed every space" in replicas[1].logs()


async def _compact_all(endpoints: list[str]) -> None:
    from aetcd import rpc

    from space.store.etcd_client import EtcdClient

    client = EtcdClient(endpoints)
    await client.open()
    try:
        reply = await client.range(rpc.RangeRequest(key=b"tspace/", count_only=True))
        await client.compact(reply.header.revision)
    finally:
        await client.close()


def _quorum_on_page(port: int) -> list[tuple[int, bool]]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=2) as reply:
            return [(c["reachable"], c["quorum"]) for c in json.load(reply).get("cluster", [])]
    except OSError:
        return []


def test_the_hmi_shows_its_replicas_quorum(replicas: list[Server], etcd_cluster, tmp_path) -> None:
    with _open(replicas[0], "ward") as ts:
        ts.write(knowledge())
    port = free_port()
    hmi = AgentProcess("hmi", replicas[0].endpoint, "ward", tmp_path, "--http-port", str(port))
    hmi.start()
    try:
        wait_for(lambda: _quorum_on_page(port) == [(3, True)], 30, "the quorum shown", hmi.logs)
        etcd_cluster.kill("m1")
        etcd_cluster.kill("m2")
        wait_for(lambda: _quorum_on_page(port) == [(1, False)], 30, "no quorum shown", hmi.logs)
    finally:
        hmi.stop()


def test_a_retry_on_another_replica_is_told_what_its_first_outcome_dropped(
    replicas: list[Server],
) -> None:
    """Exactly once means the first outcome, all of it: a changeset whose functional value lost
    to a newer one, sent again to another replica, is told again what was not applied."""
    level = URIRef(EX + "level")
    with _open(replicas[0], "dropped") as a, _open(replicas[2], "dropped") as c:
        a.write([(level, RDF.type, OWL.FunctionalProperty)])
        a.write([(_s(1), level, Literal(20))])
        stale = Changeset(
            id="robot 7/level #1",  # escaped in the log's IRI
            agent="test",
            timestamp="1/0000000000000000",  # older than the value held
            added=[(_s(1), level, Literal(10)), (_s(2), URIRef(EX + "at"), Literal("dock"))],
        )
        first = a.send(stale)
        assert [d.reason for d in first.dropped] and "newer value" in first.dropped[0].reason
        again = c.send(stale)
        assert again.again and again.seq == first.seq, (again, first.seq)
        assert [d.reason for d in again.dropped] == [d.reason for d in first.dropped]
