"""Facts that expire: a write's lifespan, renewal, permanence, the expiry changeset, restarts."""

from __future__ import annotations

import signal
import time

import pytest
from rdflib import Literal, Namespace
from rdflib.namespace import OWL, RDF

from conftest import AC_NS, Server, wait_for
from space import TripleSpace
from space.errors import ChangesetRejected, InputError
from space.lifespan import check_lifespan

AC = Namespace(AC_NS)
LONG = 15.0  # seconds: outlives a restart on a loaded machine


def _held(ts: TripleSpace, s, p) -> set:
    return set(ts.query((s, p, None), graph="asserted").objects())


def test_a_leased_fact_is_retracted_in_one_changeset_naming_its_write(ts: TripleSpace) -> None:
    seen = []
    ts.subscribe(None, seen.append)
    ack = ts.write([(AC.r1, AC.battery, Literal(80)), (AC.r1, AC.seen, AC.kitchen)], lifespan=0.5)
    ts.write([(AC.r1, AC.name, Literal("r1"))])  # permanent
    started = time.monotonic()
    assert _held(ts, AC.r1, AC.battery) == {Literal(80)}
    wait_for(lambda: not _held(ts, AC.r1, AC.battery), 5, "the expiry")
    assert time.monotonic() - started >= 0.4
    assert _held(ts, AC.r1, AC.name) == {Literal("r1")}
    expired = wait_for(lambda: [c for c in seen if c.removed], 5, "the expiry changeset")
    assert len(expired) == 1
    change = expired[0]
    assert change.agent == "tspace-store"
    assert change.cause == str(ack)
    assert set(change.removed) == {
        (AC.r1, AC.battery, Literal(80)),
        (AC.r1, AC.seen, AC.kitchen),
    }


def test_rewriting_renews_and_a_write_without_lifespan_makes_permanent(ts: TripleSpace) -> None:
    ts.write([(AC.r2, AC.seen, AC.hall), (AC.r2, AC.mode, AC.idle)], lifespan=0.6)
    for _ in range(4):  # renewed every 0.3 s for 1.2 s: lives past its first lifespan
        time.sleep(0.3)
        ts.write([(AC.r2, AC.seen, AC.hall)], lifespan=0.6)
        assert _held(ts, AC.r2, AC.seen) == {AC.hall}
    ts.write([(AC.r2, AC.seen, AC.hall)])  # now permanent
    wait_for(lambda: not _held(ts, AC.r2, AC.mode), 5, "the unrenewed triple's expiry")
    time.sleep(1.0)  # well past the last lease: it must still be there
    assert _held(ts, AC.r2, AC.seen) == {AC.hall}
    lives = dict(ts.lifespans((AC.r2, None, None)))
    assert lives == {(AC.r2, AC.seen, AC.hall): None}


def test_remaining_life_is_shown(ts: TripleSpace) -> None:
    ts.write([(AC.r3, AC.battery, Literal(50))], lifespan=30)
    ts.write([(AC.r3, AC.name, Literal("r3"))])
    lives = dict(ts.lifespans((AC.r3, None, None)))
    assert lives[(AC.r3, AC.name, Literal("r3"))] is None
    assert 25 < lives[(AC.r3, AC.battery, Literal(50))] <= 30


def test_a_functional_reading_renews_its_lease_with_each_value(ts: TripleSpace) -> None:
    ts.write([(AC.level, RDF.type, OWL.FunctionalProperty)])
    for i in range(3):
        ts.write([(AC.r4, AC.level, Literal(i))], lifespan=0.5)
    assert _held(ts, AC.r4, AC.level) == {Literal(2)}
    wait_for(lambda: not _held(ts, AC.r4, AC.level), 5, "the last reading's expiry")
    assert _held(ts, AC.level, RDF.type) == {OWL.FunctionalProperty}


def test_a_removed_leased_fact_is_not_retracted_again(ts: TripleSpace) -> None:
    seen = []
    ts.subscribe(None, seen.append)
    ts.write([(AC.r5, AC.seen, AC.lab)], lifespan=0.4)
    ts.remove([(AC.r5, AC.seen, AC.lab)])
    ts.write([(AC.r5, AC.seen, AC.lab)])  # written again, permanent: must survive
    time.sleep(0.8)
    assert _held(ts, AC.r5, AC.seen) == {AC.lab}
    assert not [c for c in seen if c.agent == "tspace-store"]


def test_bad_lifespans_are_refused_with_a_clear_error(ts: TripleSpace) -> None:
    assert check_lifespan("500ms") == 0.5
    assert check_lifespan("2m") == 120
    assert check_lifespan(0) is None
    for bad in (-1, float("nan"), float("inf"), "5 parsecs", True):
        with pytest.raises(InputError, match="lifespan"):
            ts.write([(AC.r6, AC.x, AC.y)], lifespan=bad)
    cs = ts.changeset([(AC.r6, AC.x, AC.y)])
    wire = cs.to_wire()
    wire["lifespan"] = -3
    import msgpack

    from space._request import ask_store

    with pytest.raises(ChangesetRejected, match="lifespan"):
        ask_store(ts.session, ts._key("write"), msgpack.packb(wire), 5.0, what="write")
    assert not _held(ts, AC.r6, AC.x)


def test_expiry_survives_kill_9(tmp_path) -> None:
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="leases") as ts:
            ts.write([(AC.a, AC.p, Literal("short"))], lifespan=1.0)
            sent = time.monotonic()
            ts.write([(AC.a, AC.q, Literal("long"))], lifespan=LONG)
            ts.write([(AC.a, AC.r, Literal("forever"))])
            written = time.monotonic()
        assert srv.stop(signal.SIGKILL) == -signal.SIGKILL
        wait_for(lambda: time.monotonic() - written > 1.2, 3, "the short lease to pass")
        srv.start()
        with TripleSpace.open(srv.endpoint, space="leases") as ts:
            # passed during the outage: gone at restart
            wait_for(lambda: not _held(ts, AC.a, AC.p), 3, "the outage's expiry")
            assert _held(ts, AC.a, AC.q) == {Literal("long")}
            left = dict(ts.lifespans((AC.a, AC.q, None)))[(AC.a, AC.q, Literal("long"))]
            assert left is not None and left < LONG - (time.monotonic() - sent) + 0.5
            wait_for(lambda: not _held(ts, AC.a, AC.q), LONG + 2, "the long lease on time")
            assert time.monotonic() - sent >= LONG - 0.05  # on time, not at restart
            assert _held(ts, AC.a, AC.r) == {Literal("forever")}
    finally:
        srv.stop()


def test_the_command_line_writes_with_a_lifespan_and_shows_it(ts, run_tspace, tmp_path) -> None:
    doc = tmp_path / "reading.ttl"
    doc.write_text(f"@prefix ac: <{AC_NS}> .\nac:r7 ac:battery 42 .\nac:r7 ac:name 'r7' .\n")
    assert run_tspace("write", "--lifespan", "30s", str(doc)).returncode == 0
    shown = run_tspace("query", "-t", "ac:r7 ?p ?o", "--with-lifespan")
    assert shown.returncode == 0, shown.stderr
    rows = [line.split() for line in shown.stdout.splitlines()[2:]]
    assert len(rows) == 2 and all(25 < float(r[-1]) <= 30 for r in rows), shown.stdout
    bad = run_tspace("write", "--lifespan", "soon", str(doc))
    assert bad.returncode == 2 and "lifespan" in bad.stderr
    assert run_tspace("write", "--lifespan", "0", str(doc)).returncode == 0  # permanent again
    assert dict(ts.lifespans((AC.r7, None, None))) == {
        (AC.r7, AC.battery, Literal(42)): None,
        (AC.r7, AC.name, Literal("r7")): None,
    }


def test_a_launch_file_gives_an_agent_its_lifespan(tmp_path) -> None:
    from agents.runtime.launch import read_launch

    path = tmp_path / "robot.toml"
    path.write_text('[[agent]]\nname = "hw_monitor"\nlifespan = "10s"\n[[agent]]\nname = "hmi"\n')
    hw, hmi = read_launch(path).agents
    assert hw.option("--lifespan") == "10s"
    assert hmi.option("--lifespan") is None
    path.write_text('[[agent]]\nname = "hw_monitor"\nlifespan = "-1s"\n')
    with pytest.raises(InputError, match="agent hw_monitor: a lifespan"):
        read_launch(path)


def test_an_expired_lease_left_on_disk_never_leases_its_triple_again(tmp_path) -> None:
    """The retraction leaves its lease quads to collect later; they must mean nothing."""
    import pyoxigraph as ox

    from space.store.db import StoreDB
    from space.store.intake import WriteRequest
    from space.store.lifespans import Leases, remaining, retractions
    from space.store.state import SpaceState

    db = StoreDB(tmp_path / "data")
    leases = Leases()
    state = SpaceState("s", db)
    state.leases = leases
    t = (ox.NamedNode(str(AC.a)), ox.NamedNode(str(AC.p)), ox.Literal("x"))
    u = (ox.NamedNode(str(AC.a)), ox.NamedNode(str(AC.q)), ox.Literal("y"))

    def commit(write: WriteRequest | None = None, net=None) -> None:
        if write is not None:
            net, _ = state.decide(write, f"stamp-{write.id}")
        db.commit([net.entry] if net else [], leases.take_changes())
        state.settle()

    def reloaded() -> Leases:
        again = Leases()
        again.load(db)
        return again

    try:
        commit(WriteRequest(id="w1", agent="a", added=[t, u], lifespan=0.01))
        [(_state, net)] = retractions(leases, lambda _n: state, lambda: "stamp-x", time.time() + 1)
        commit(net=net)
        assert not db.has("s", "t", t) and not db.has("s", "t", u)
        assert len(leases) == 0 and len(leases.garbage) == 2  # lease quads still on disk
        assert leases.has_garbage("s") and not leases.has_garbage("other")
        after_restart = reloaded()
        assert len(after_restart) == 0 and len(after_restart.garbage) == 2
        assert after_restart.next_due() is None  # nothing to expire again

        commit(WriteRequest(id="w2", agent="a", added=[t]))  # asserted again, permanent
        assert remaining(db, "s", t, time.time()) is None
        after_restart = reloaded()
        assert len(after_restart) == 0
        assert list(after_restart.garbage) == [("s", " ".join(map(str, u)))]

        assert leases.collect(10) == 1  # the last one, deleted in a commit of its own
        commit()
        assert not leases.garbage and not reloaded().garbage and not leases.has_garbage("s")
    finally:
        db.close()
