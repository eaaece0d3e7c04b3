"""The TSC operations of TripleSpace against a real router + store process."""

import os
import signal
import threading
import time
from itertools import pairwise
from pathlib import Path

import pytest
import zenoh
from rdflib import Graph, Literal, Namespace, URIRef
from rdflib.namespace import OWL, RDF

from conftest import AC_NS, wait_for
from space import (
    Change,
    InputError,
    SpaceTimeout,
    SpaceUnavailable,
    Template,
    TemplateError,
    TripleSpace,
)
from space.zconfig import make_config

AC = Namespace(AC_NS)
ROBOT = [
    (AC.robot1, RDF.type, AC.Robot),
    (AC.robot1, AC.has_device, AC.robot1_battery),
    (AC.robot1_battery, RDF.type, AC.Battery),
    (AC.robot1_battery, AC.battery_level, Literal("normal")),
]


def test_write_then_query_sees_exactly_what_was_written(ts):
    cs_id = ts.write(ROBOT)
    assert isinstance(cs_id, str) and cs_id
    assert set(ts.query(None)) == set(ROBOT)
    assert set(ts.query("?r ac:has_device ?d")) == {ROBOT[1]}


def test_write_accepts_an_rdflib_graph(ts):
    g = Graph()
    for t in ROBOT:
        g.add(t)
    ts.write(g)
    assert len(ts.query(None)) == len(ROBOT)


def test_read_returns_one_subject(ts):
    ts.write(ROBOT)
    g = ts.read("?s rdf:type ?c")
    assert {s for s in g.subjects()} == {AC.robot1}


def test_functional_property_write_replaces_old_value(ts):
    ts.write([(AC.battery_level, RDF.type, OWL.FunctionalProperty), *ROBOT])
    ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
    levels = set(ts.query((AC.robot1_battery, AC.battery_level, None)).objects())
    assert levels == {Literal("very low")}


def test_non_functional_property_accumulates(ts):
    ts.write([(AC.robot1, AC.has_device, AC.a)])
    ts.write([(AC.robot1, AC.has_device, AC.b)])
    assert len(ts.query((AC.robot1, AC.has_device, None))) == 2


def test_older_hlc_write_of_functional_property_loses(ts):
    ts.write([(AC.level, RDF.type, OWL.FunctionalProperty)])
    older = ts.changeset([(AC.x, AC.level, Literal("old"))])
    newer = ts.changeset([(AC.x, AC.level, Literal("new"))])
    ts.send(newer)
    ts.send(older)  # arrives later, but its timestamp is earlier
    assert set(ts.query((AC.x, AC.level, None)).objects()) == {Literal("new")}


def test_transaction_applies_removals_and_additions_atomically(ts):
    ts.write(ROBOT)
    seen = []
    ts.subscribe(None, seen.append)
    with ts.transaction() as tx:
        tx.remove(ROBOT[3])
        tx.add((AC.robot1_battery, AC.battery_level, Literal("low")))
    assert tx.id
    wait_for(lambda: seen, what="the transaction's change")
    assert len(seen) == 1
    assert seen[0].removed == [ROBOT[3]]
    assert seen[0].added == [(AC.robot1_battery, AC.battery_level, Literal("low"))]


def test_take_removes_what_it_returns(ts):
    ts.write(ROBOT)
    taken = ts.take("?d ac:battery_level ?l")
    assert set(taken) == {ROBOT[3]}
    assert len(ts.query("?d ac:battery_level ?l")) == 0
    assert len(ts.query(None)) == 3


def test_concurrent_takes_never_return_the_same_triple(server, ts, space_name):
    ts.write([(AC.job, AC.item, Literal(i)) for i in range(40)])
    results: list[set] = []

    def taker() -> None:
        with TripleSpace.open(server.endpoint, space=space_name) as other:
            got: set = set()
            for _ in range(20):
                got |= set(other.take((None, AC.item, None)))
            results.append(got)

    threads = [threading.Thread(target=taker) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not (results[0] & results[1])
    assert len(results[0] | results[1]) == 40


def test_sparql_select_ask_construct(ts):
    ts.write(ROBOT)
    rows = list(ts.query_sparql("SELECT ?d WHERE { ?r ac:has_device ?d }"))
    assert [r[0] for r in rows] == [AC.robot1_battery]
    assert ts.query_sparql("ASK { ?b ac:battery_level 'normal' }").askAnswer is True
    built = ts.query_sparql("CONSTRUCT { ?d ac:of ?r } WHERE { ?r ac:has_device ?d }")
    assert set(built.graph) == {(AC.robot1_battery, AC.of, AC.robot1)}


def test_inferred_graph_is_kept_apart(ts):
    ts.apply(added=ROBOT[:1], inferred_added=[(AC.robot1, RDF.type, AC.Agent)])
    assert set(ts.query(None, graph="asserted")) == set(ROBOT[:1])
    assert set(ts.query(None, graph="inferred")) == {(AC.robot1, RDF.type, AC.Agent)}
    assert len(ts.query(None)) == 2
    asserted, inferred, seq = ts.graphs()
    assert (asserted, inferred) == (list(ROBOT[:1]), [(AC.robot1, RDF.type, AC.Agent)])
    assert seq == ts.snapshot()[1] > 0


def test_spaces_do_not_see_each_other(server, ts, space_name):
    ts.write(ROBOT)
    with TripleSpace.open(server.endpoint, space=space_name + "x") as other:
        assert len(other.query(None)) == 0


def test_subscribe_gives_matching_triples_with_bindings(ts):
    seen = []
    ts.subscribe("?b ac:battery_level ?l", seen.append)
    ts.write(ROBOT)
    wait_for(lambda: seen, what="the change")
    assert seen[0].added == [ROBOT[3]]
    assert seen[0].bindings == [{"b": AC.robot1_battery, "l": Literal("normal")}]
    assert seen[0].agent == "test"


def test_subscribe_in_texts_gives_the_terms_as_the_wire_has_them(ts):
    seen = []
    ts.subscribe(None, seen.append, texts=True)
    ts.write(ROBOT[3:])
    wait_for(lambda: seen, what="the change")
    assert seen[0].added == [(f"<{AC_NS}robot1_battery>", f"<{AC_NS}battery_level>", '"normal"')]
    assert seen[0].texts
    for wrong in ({"template": "?b ac:battery_level ?l"}, {"snapshot": True}, {"scope": []}):
        with pytest.raises(InputError, match="whole changesets"):
            ts.subscribe(wrong.pop("template", None), seen.append, texts=True, **wrong)


def test_unsubscribe_stops_callbacks(ts):
    seen = []
    sub = ts.subscribe(None, seen.append)
    ts.write(ROBOT[:1])
    wait_for(lambda: seen, what="first change")
    ts.unsubscribe(sub)
    ts.write(ROBOT[1:2])
    marker = []
    ts.subscribe(None, marker.append)
    ts.write(ROBOT[2:3])
    wait_for(lambda: marker, what="the marker change")
    assert len(seen) == 1


def test_subscribe_with_snapshot_starts_from_current_state(ts):
    ts.write(ROBOT)
    seen = []
    ts.subscribe("?d ac:battery_level ?l", seen.append, snapshot=True)
    ts.write([(AC.robot2_battery, AC.battery_level, Literal("full"))])
    wait_for(lambda: len(seen) >= 2, what="snapshot and change")
    assert seen[0].added == [ROBOT[3]]
    assert seen[1].added == [(AC.robot2_battery, AC.battery_level, Literal("full"))]


def test_subscribe_can_skip_its_own_changes(server, ts, space_name):
    ts.write([ROBOT[0]])
    seen = []
    ts.subscribe(None, seen.append, snapshot=True, skip_own=True)
    ts.write([ROBOT[1]])  # our own: skipped whole
    with TripleSpace.open(server.endpoint, space=space_name, agent="other") as other:
        other.write([ROBOT[2]])
        other.write([ROBOT[3]])
    wait_for(lambda: len(seen) >= 3, what="snapshot and two changes")
    assert seen[0].added == [ROBOT[0]]
    assert [(c.agent, c.added) for c in seen[1:]] == [("other", [ROBOT[2]]), ("other", [ROBOT[3]])]
    assert seen[1].seq == seen[0].seq + 2  # after the one skipped, no gap to fill


def test_without_a_dispatch_thread_changes_and_posted_work_run_where_deliver_is_called(
    server, space_name
):
    with TripleSpace.open(server.endpoint, space=space_name, dispatch_thread=False) as ts:
        seen: list[tuple[str, object]] = []
        ts.subscribe(None, lambda c: seen.append((threading.current_thread().name, c.added)))
        ts.write(ROBOT[:1])
        wait_for(lambda: ts.deliver(0.05) and seen, what="the change")
        ts.post(lambda: seen.append((threading.current_thread().name, "work")))
        wait_for(lambda: ts.deliver(0.05) and len(seen) >= 2, what="the work")
        me = threading.current_thread().name
        assert seen == [(me, ROBOT[:1]), (me, "work")]  # on this thread
    assert not ts.deliver(0)  # closed


def test_no_store_means_space_unavailable_within_timeout(tmp_path):
    from conftest import free_port

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with zenoh.open(make_config(mode="router", listen=[endpoint])):
        with TripleSpace.open(endpoint, space="nostore") as ts:
            with pytest.raises(SpaceUnavailable, match="no store answered"):
                ts.write(ROBOT, timeout=0.5)
            with pytest.raises(SpaceUnavailable):
                ts.query(None, timeout=0.5)


def test_no_router_means_space_unavailable():
    from conftest import free_port

    with pytest.raises(SpaceUnavailable, match="no Zenoh router reachable"):
        TripleSpace.open(f"tcp/127.0.0.1:{free_port()}")


def test_write_nowait_arrives(ts):
    seen = []
    ts.subscribe(None, seen.append)
    ts.write_nowait([(AC.s, AC.p, Literal(i)) for i in range(3)])
    wait_for(lambda: seen, what="fire-and-forget change")
    assert len(ts.query(None)) == 3


def test_changesets_sent_later_are_applied_in_order_and_acknowledged(ts):
    level = AC.robot1_battery, AC.battery_level
    ts.write(ROBOT)
    levels = ["normal", "low", "very low", "low", "normal", "very low"]
    pending = [
        ts.send_later(ts.changeset([(*level, Literal(new))], [(*level, Literal(old))]))
        for old, new in pairwise(levels)
    ]
    seqs = [p.result()["seq"] for p in pending]
    assert seqs == list(range(seqs[0], seqs[0] + len(pending)))  # each applied, in order
    assert set(ts.query((*level, None))) == {(*level, Literal("very low"))}


def test_a_changeset_sent_later_is_ready_once_the_store_acknowledged_it(server, ts):
    ts.write(ROBOT)
    os.kill(server.proc.pid, signal.SIGSTOP)  # the router and the store: no reply can come
    try:
        pending = ts.send_later(
            ts.changeset([(AC.robot1_battery, AC.charge_percent, Literal(7))]), timeout=10
        )
        time.sleep(0.3)
        assert not pending.ready(), "ready before the store answered"
    finally:
        os.kill(server.proc.pid, signal.SIGCONT)
    wait_for(pending.ready, 5, "the acknowledgement")
    assert pending.ready(), "stays ready"
    assert pending.result()["seq"] == ts.seq()
    assert ts.query((AC.robot1_battery, AC.charge_percent, None))


def test_send_later_without_a_store_fails_at_result(tmp_path):
    from conftest import free_port

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with zenoh.open(make_config(mode="router", listen=[endpoint])):
        with TripleSpace.open(endpoint, space="nostore") as ts:
            pending = ts.send_later(ts.changeset(ROBOT, []), timeout=0.5)
            with pytest.raises(SpaceUnavailable, match="no store answered"):
                pending.result()


def test_iri_unaffected_by_unregistered_prefix(ts):
    ts.write([(URIRef("http://other.org/a/b"), URIRef("http://other.org/p#q"), Literal("x"))])
    assert len(ts.query("<http://other.org/a/b> ?p ?o")) == 1


def test_open_checks_the_space_name_before_connecting():
    from conftest import free_port

    nowhere = f"tcp/127.0.0.1:{free_port()}"  # no router: a session would fail differently
    with pytest.raises(InputError, match="space name 'bad/name'"):
        TripleSpace.open(nowhere, space="bad/name")
    assert issubclass(InputError, ValueError)


def test_tuple_templates_take_question_mark_names_as_variables(ts):
    ts.write(ROBOT)
    assert set(ts.read(("?s", AC.battery_level, None))) == {ROBOT[3]}
    assert set(ts.query(("?d", RDF.type, "?c"))) == {ROBOT[0], ROBOT[2]}
    assert Template("?s", "?p", "?o").variables() == ["s", "p", "o"]
    seen: list[Change] = []
    ts.subscribe(("?b", AC.battery_level, "?l"), seen.append)
    ts.write([(AC.robot1_battery, AC.battery_level, Literal("low"))])
    wait_for(lambda: seen, what="the change")
    assert seen[0].bindings == [{"b": AC.robot1_battery, "l": Literal("low")}]


@pytest.mark.parametrize("position", ["robot1", "ac:robot1", "?", 42])
def test_a_tuple_template_refuses_what_is_not_a_term_or_a_variable(ts, position):
    with pytest.raises(TemplateError, match="template position"):
        ts.read((position, AC.battery_level, None))


def test_a_store_too_busy_to_answer_in_time_raises_space_timeout(ts):
    big = [(AC[f"s{i}"], AC.n, Literal(i)) for i in range(20_000)]  # ~0.5 s of the store's time
    with pytest.raises(SpaceTimeout, match=r"0\.05 s \(the changeset may still be applied\)"):
        ts.write(big, timeout=0.05)
    with pytest.raises(SpaceTimeout, match=r"no answer from the store to the query within 0\.05 s"):
        ts.query((AC.s0, None, None), timeout=0.05)  # queued behind that write
    # the query waits behind the late write: give it the deadline, not the 5 s default
    everything = (None, AC.n, None)
    wait_for(lambda: len(ts.query(everything, timeout=30)) == len(big), 30, "the late write")


def test_the_readme_python_example_runs_on_a_fresh_space(server, space_name):
    import subprocess
    import sys

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    example = readme.split("## From Python", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    assert 'space="hospital"' in example and '"tcp/127.0.0.1:7447"' in example
    example = example.replace('space="hospital"', f'space="{space_name}"')
    # Its last lines ask a reasoner `why`: test_readme runs them against `tspace up`.
    example, why = example.split("    for tree in ts.why(", 1)
    assert "tree.rule" in why
    example = example.replace('"tcp/127.0.0.1:7447"', f'"{server.endpoint}"')
    out = subprocess.run(
        [sys.executable, "-c", example], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr
    assert 'ac:battery_level "very low"' in out.stdout
