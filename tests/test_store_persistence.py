"""The store keeps every acknowledged change across `kill -9` and restarts."""

import signal

from rdflib import Literal, Namespace
from rdflib.namespace import OWL, RDF

from conftest import AC_NS, Server, wait_for
from space import TripleSpace

AC = Namespace(AC_NS)


def test_acknowledged_changes_survive_kill_9(tmp_path):
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="robots", prefixes={"ac": AC_NS}) as ts:
            ts.write([(AC.battery_level, RDF.type, OWL.FunctionalProperty)])
            for i in range(200):
                ts.write([(AC.robot1_battery, AC.reading, Literal(i))])
            ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
            ts.apply(inferred_added=[(AC.robot1_battery, RDF.type, AC.Device)])
            before, seq_before = ts.snapshot()
        assert srv.stop(signal.SIGKILL) == -signal.SIGKILL
        srv.start()
        with TripleSpace.open(srv.endpoint, space="robots") as ts:
            after, seq_after = ts.snapshot()
            assert set(after) == set(before)
            assert seq_after == seq_before == 203
            assert len(ts.query(None, graph="inferred")) == 1
            # prefixes registered before the crash still compact keys and templates
            assert len(ts.query("?b ac:battery_level 'very low'")) == 1
            # functional properties are still known after the restart
            ts.write([(AC.robot1_battery, AC.battery_level, Literal("low"))])
            assert set(ts.query("?b ac:battery_level ?l").objects()) == {Literal("low")}
    finally:
        srv.stop()


def test_subscriber_fills_the_gap_while_its_router_was_down(tmp_path):
    store = Server(tmp_path / "data")
    store.start()
    edge = Server(tmp_path / "unused", "--no-store", "--connect", store.endpoint)
    edge.start()
    try:
        seen = []
        with (
            TripleSpace.open(edge.endpoint, space="gap") as sub_side,
            TripleSpace.open(store.endpoint, space="gap") as writer,
        ):
            sub_side.subscribe(None, seen.append)
            writer.write([(AC.a, AC.n, Literal(0))])
            wait_for(lambda: seen, 10, "the first change")
            edge.stop(signal.SIGKILL)
            for i in range(1, 6):
                writer.write([(AC.a, AC.n, Literal(i))])
            edge.start()
            # on reconnecting, the subscription fetches what was written meanwhile
            wait_for(lambda: len(seen) >= 6, 20, "the changes written while the router was down")
            writer.write([(AC.a, AC.n, Literal(6))])
            wait_for(lambda: len(seen) >= 7, 10, "every change")
            assert [c.seq for c in seen] == list(range(1, 8))
            assert [int(c.added[0][2]) for c in seen] == list(range(7))
    finally:
        edge.stop()
        store.stop()


def test_sigterm_stops_the_server_cleanly(tmp_path):
    srv = Server(tmp_path / "data")
    srv.start()
    assert srv.stop(signal.SIGTERM) == 0
    assert "stopping" in srv.logs()


def test_serve_logs_one_line_per_client_that_comes_and_goes(tmp_path):
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="clients") as ts:
            zid = str(ts.session.zid())
            ts.write([(AC.robot1, AC.charge_percent, Literal(50))])
            wait_for(lambda: f"client {zid} connected" in srv.logs(), 10, "the arrival line")
        wait_for(lambda: f"client {zid} disconnected" in srv.logs(), 10, "the departure line")
        lines = [line for line in srv.logs().splitlines() if zid in line]
        assert len(lines) == 2, lines
    finally:
        srv.stop()
