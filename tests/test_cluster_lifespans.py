"""Lifespans on three `tspace serve --cluster` replicas of a real 3-member etcd cluster.

Each replica runs its own Zenoh router: what one learns of another's writes and
expiries came through etcd. A leased write expires on every replica in one
changeset of the log, decided once whichever replicas swept it; a renewal on
another replica keeps it alive; when the replica that committed the write is
killed -9, another expires it, and the killed one agrees once restarted; leases outlive a
kill -9 of every replica (one due during the outage is retracted at restart, once).
"""

from __future__ import annotations

import asyncio
import signal
import time

from rdflib import Literal, URIRef
from test_cluster_store import _compact_all

from conftest import Server, wait_for
from space import TripleSpace
from space.changeset import Changeset

EX = "http://example.org/"
AT = URIRef(EX + "at")


def _open(server: Server, space: str) -> TripleSpace:
    return TripleSpace.open(server.endpoint, space=space, agent="test")


def _holds(server: Server, space: str, triple: tuple) -> bool:
    with _open(server, space) as ts:
        return triple in ts.query((triple[0], None, None), graph="asserted")


def _left(server: Server, space: str, triple: tuple) -> float | None:
    """Return the seconds a triple has left to live on a replica (None: permanent)."""
    with _open(server, space) as ts:
        return dict(ts.lifespans((triple[0], None, None))).get(triple)


def _expiries(server: Server, space: str) -> list[Changeset]:
    with _open(server, space) as ts:
        changes, _ = ts.history(1, 0, timeout=30)
    return [c for c in changes if c.agent == "tspace-store"]


def _logs(replicas: list[Server], space: str) -> list[list[tuple]]:
    logs = []
    for r in replicas:
        with _open(r, space) as ts:
            changes, _ = ts.history(1, 0, timeout=30)
        logs.append([(c.seq, c.id, sorted(c.removed)) for c in changes])
    return logs


def test_a_leased_write_expires_on_every_replica_once(replicas: list[Server]) -> None:
    robot, permanent = (
        (URIRef(EX + "robot1"), AT, URIRef(EX + "dock")),
        (
            URIRef(EX + "robot1"),
            URIRef(EX + "name"),
            Literal("r1"),
        ),
    )
    with _open(replicas[0], "exp") as a:
        ack = a.write([robot], lifespan=2.0)
        written = time.monotonic()
        a.write([permanent])
        lives = dict(a.lifespans((robot[0], None, None)))
        assert 0 < lives[robot] <= 2.0 and lives[permanent] is None
    with _open(replicas[2], "exp") as c:  # leased on every replica, the same life left
        assert 0 < dict(c.lifespans((robot[0], None, None)))[robot] <= 2.0
    for r in replicas:
        wait_for(lambda r=r: not _holds(r, "exp", robot), 10, f"the expiry on {r.endpoint}")
    assert time.monotonic() - written >= 1.8
    for r in replicas:
        assert _holds(r, "exp", permanent)
        expiries = _expiries(r, "exp")
        assert len(expiries) == 1, expiries  # three replicas swept it: one commit
        assert expiries[0].cause == str(ack)
        assert expiries[0].removed == [robot]
    logs = _logs(replicas, "exp")
    assert logs[0] == logs[1] == logs[2]  # the same retraction at the same place everywhere


def test_a_renewal_on_another_replica_keeps_it_alive(replicas: list[Server]) -> None:
    reading = (URIRef(EX + "robot2_battery"), URIRef(EX + "level"), Literal("normal"))
    life = 3.0  # renewed every ~0.4 s: a loaded host's slow write must not outlast it
    with _open(replicas[0], "renew") as a, _open(replicas[1], "renew") as b:
        a.write([reading], lifespan=life)
        until = time.monotonic() + 2.5 * life
        last = None
        while time.monotonic() < until:
            last = b.write([reading], lifespan=life)  # the same reading, on another replica
            renewed = time.monotonic()
            assert _holds(replicas[2], "renew", reading)
            time.sleep(0.4)
    for r in replicas:
        wait_for(lambda r=r: not _holds(r, "renew", reading), 10, f"the expiry on {r.endpoint}")
    assert time.monotonic() - renewed >= 0.8 * life
    for r in replicas:
        expiries = _expiries(r, "renew")
        assert [(e.cause, e.removed) for e in expiries] == [(str(last), [reading])]


def test_another_replica_expires_the_write_of_one_killed(replicas: list[Server]) -> None:
    seen = (URIRef(EX + "person1"), AT, URIRef(EX + "kitchen"))
    with _open(replicas[0], "killed") as a:
        ack = a.write([seen], lifespan=1.0)
    replicas[0].stop(signal.SIGKILL)  # the replica that would have expired it on time
    for r in replicas[1:]:
        wait_for(lambda r=r: not _holds(r, "killed", seen), 15, f"the expiry on {r.endpoint}")
    for r in replicas[1:]:
        assert [e.cause for e in _expiries(r, "killed")] == [str(ack)]
    replicas[0].start()  # resumes from its revision: applies the expiry others decided
    assert not _holds(replicas[0], "killed", seen)
    assert [e.cause for e in _expiries(replicas[0], "killed")] == [str(ack)]
    logs = _logs(replicas, "killed")
    assert logs[0] == logs[1] == logs[2]


def test_leases_outlive_a_kill_of_every_replica(replicas: list[Server]) -> None:
    soon, later = (
        (URIRef(EX + "door1"), URIRef(EX + "state"), Literal("open")),
        (URIRef(EX + "door2"), URIRef(EX + "state"), Literal("open")),
    )
    with _open(replicas[1], "durable") as b:
        b.write([soon], lifespan=1.0)
        b.write([later], lifespan=30.0)
        due = time.monotonic() + 1.0
    for r in replicas:
        r.stop(signal.SIGKILL)
    # The outage must outlast the first lease: on a quiet machine the kills and restarts
    # alone can take less than its second.
    wait_for(lambda: time.monotonic() > due, 5, "the first lease to fall due")
    for r in replicas:
        r.start(wait=False)
    for r in replicas:
        wait_for(r.reachable, 30, f"replica on {r.endpoint}", r.logs)
    assert time.monotonic() > due  # the outage outlasted the first lease
    for r in replicas:  # due during the outage: retracted at restart, once
        wait_for(lambda r=r: not _holds(r, "durable", soon), 15, f"the expiry on {r.endpoint}")
        assert _holds(r, "durable", later)
        assert [e.removed for e in _expiries(r, "durable")] == [[soon]]


def test_a_relisted_replica_never_expires_a_lease_renewed_while_it_was_away(
    replicas: list[Server], etcd_cluster
) -> None:
    reading = (URIRef(EX + "robot3_battery"), URIRef(EX + "level"), Literal("low"))
    with _open(replicas[1], "relist") as b:
        b.write([reading], lifespan=3.0)  # B holds this lease, on disk
    first_due = time.monotonic() + 3.0
    replicas[1].stop(signal.SIGKILL)
    with _open(replicas[0], "relist") as a:
        a.write([reading], lifespan=60.0)  # renewed while B is away
    # C applied the renewal (a replica just started may still be reading the log from its start,
    # and would re-list too at the compaction below, dropping its leases: docs/lifespans.md)
    wait_for(lambda: (_left(replicas[2], "relist", reading) or 0) > 50, 15, "C's renewal")
    # as if B had been away longer than etcd keeps the log: it re-lists, its old lease is stale
    asyncio.run(_compact_all(etcd_cluster.endpoints))
    replicas[1].start()
    wait_for(lambda: "re-listed every space" in replicas[1].logs(), 30, "the re-list")
    wait_for(lambda: time.monotonic() > first_due + 2.0, 10, "the stale lease's time and grace")
    for r in replicas:  # B did not sweep its stale lease: the renewal holds everywhere
        assert _holds(r, "relist", reading)
        assert _expiries(r, "relist") == []
    assert 50 < (_left(replicas[2], "relist", reading) or 0) <= 60
