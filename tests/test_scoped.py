"""Scoped subscriptions: a robot's agent receives only its robot's part of the traffic.

Against a real router and store: Zenoh filters the parts by key, and the chain of
`prev` seqs still finds what a subscriber missed, from the store's log.
"""

import logging
import signal

import pytest
import zenoh
from rdflib import Literal, Namespace
from rdflib.namespace import RDF

from conftest import AC_NS, Server, wait_for
from space import InputError, TripleSpace, escape_key_chunk, make_config
from space._parts import term_chunk
from space.changeset import pack, unpack
from space.keys import part_key
from space.store.parts import OFTEN
from space.terms import to_nt, triple_from_nt

AC = Namespace(AC_NS)
SCOPE = [(AC.robot1, None), ("ac:robot1_*", None)]


def level(robot: int, value: str) -> tuple:
    return (AC[f"robot{robot}_battery"], AC.battery_level, Literal(value))


def test_a_scoped_subscriber_receives_only_its_robots_parts(ts):
    ts.write([(AC.robot1, RDF.type, AC.Robot)])
    seen = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    ts.write([level(2, "low")])  # robot2's only: not even received
    ts.write([level(12, "low")])  # robot12 starts with "robot1": not robot1's either
    mixed = ts.write([level(2, "full"), level(1, "low")])
    ts.write([(AC.robot1, AC.location, AC.hall)])
    wait_for(lambda: len(seen) >= 2, what="robot1's two parts")
    assert [c.added for c in seen] == [[level(1, "low")], [(AC.robot1, AC.location, AC.hall)]]
    assert seen[0].id == mixed and seen[0].seq == mixed.seq  # the part of the mixed changeset


def test_a_scoped_snapshot_holds_only_the_scope(ts):
    ts.write([level(1, "normal"), level(2, "low"), (AC.robot1, RDF.type, AC.Robot)])
    seen = []
    ts.subscribe(None, seen.append, snapshot=True, scope=SCOPE)
    ts.write([level(1, "low")])
    wait_for(lambda: len(seen) >= 2, what="snapshot and change")
    assert set(seen[0].added) == {level(1, "normal"), (AC.robot1, RDF.type, AC.Robot)}
    assert seen[1].added == [level(1, "low")]


def test_a_template_and_a_scope_both_filter(ts):
    seen = []
    ts.subscribe((None, AC.battery_level, None), seen.append, scope=[(None, AC.battery_level)])
    ts.write([level(1, "low"), (AC.robot1, AC.location, AC.hall)])
    ts.write([level(3, "full")])
    wait_for(lambda: len(seen) >= 2, what="two battery levels")
    assert [c.added for c in seen] == [[level(1, "low")], [level(3, "full")]]
    assert seen[0].bindings == []  # a template without variables binds nothing


def _cut(ts, sub):
    """Lose every part sent to `sub` until `_mend` (as a link cut does)."""
    for subscriber in sub._subscribers:
        subscriber.undeclare()
    sub._subscribers = []


def _mend(ts, sub):
    for key in sub.keys:
        sub.attach(ts.session.declare_subscriber(key, ts._dispatcher.feed(sub)))


def test_a_missed_part_is_fetched_from_the_log_before_the_next_one(ts):
    seen = []
    sub = ts.subscribe(None, seen.append, scope=SCOPE)
    ts.write([level(1, "normal")])
    wait_for(lambda: seen, what="the first part")
    _cut(ts, sub)
    ts.write([level(1, "low"), level(2, "low")])  # lost
    ts.write([level(2, "full")])  # not robot1's
    _mend(ts, sub)
    ts.write([level(1, "very low")])  # its prev names the lost one
    wait_for(lambda: len(seen) >= 3, what="the lost part, then the new one")
    assert [c.added for c in seen] == [
        [level(1, "normal")],
        [level(1, "low")],  # from the log, robot2's triple left out
        [level(1, "very low")],
    ]
    assert seen[1].seq < seen[2].seq


def test_a_lost_last_part_comes_back_when_the_link_does(ts):
    seen = []
    sub = ts.subscribe(None, seen.append, scope=SCOPE)
    _cut(ts, sub)
    ts.write([level(1, "low")])  # lost, and nothing follows it on robot1's keys
    _mend(ts, sub)
    ts.write([level(2, "low")])
    ts._dispatcher.catch_up()  # what a reconnection or the leader's token coming back does
    wait_for(lambda: seen, what="the lost part")
    assert [c.added for c in seen] == [[level(1, "low")]]


def test_a_forged_or_malformed_part_is_skipped_and_delivery_goes_on(server, ts, caplog):
    seen = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    s, p = (escape_key_chunk(f"<{AC_NS}{name}>") for name in ("robot1_battery", "battery_level"))
    key = f"tspace/{ts.space}/@/changes/{s}/{p}"
    forged = {"id": "x", "seq": 10**9, "prev": 0, "add": [[f"<{AC_NS}robot1_battery>"] * 3]}
    with caplog.at_level(logging.WARNING, logger="tspace.subscription"):
        with zenoh.open(make_config(mode="client", connect=[server.endpoint])) as plain:
            plain.put(key, pack(forged))
            plain.put(key, b"\xc1 not msgpack")
            plain.put(key, b"\x81\x90\x00")  # a map keyed by a list: msgpack, no Python dict
        ts.write([level(1, "low")])
        wait_for(lambda: seen, what="the real part")
        # Zenoh orders puts per session only: the forged ones may land after the real part.
        wait_for(lambda: "past the store's seq" in caplog.text, what="the forged part's warning")
        wait_for(lambda: caplog.text.count("malformed change skipped") >= 2, what="both malformed")
    assert [c.added for c in seen] == [[level(1, "low")]]


@pytest.mark.parametrize(
    ("scope", "message"),
    [
        ([("ac:robot1_", None)], "ends with"),
        ([("zz:robot1_*", None)], "unknown prefix"),
        ([AC.robot1], "pairs"),
        ([(42, None)], "None, an RDF term"),
    ],
)
def test_a_malformed_scope_is_refused_with_what_is_wrong(ts, scope, message):
    with pytest.raises(InputError, match=message):
        ts.subscribe(None, lambda change: None, scope=scope)


def test_a_part_key_does_not_change_when_the_space_learns_a_prefix(server, space_name):
    ns = AC_NS + "robot1_"
    with TripleSpace.open(server.endpoint, space=space_name, prefixes={"ac": AC_NS}) as ts:
        ts.write([(AC.robot1, RDF.type, AC.Robot)])
        with TripleSpace.open(server.endpoint, space=space_name, prefixes={"r1": ns}) as other:
            other.write([(AC.robot1_base, RDF.type, AC.MobileBase)])  # r1:base in triple keys
        seen = []
        ts.subscribe(None, seen.append, scope=SCOPE)
        ts.write([(AC.robot1_base, AC.motion_speed, Literal("low"))])
        wait_for(lambda: seen, what="the part keyed with the longer namespace")
        assert seen[0].added == [(AC.robot1_base, AC.motion_speed, Literal("low"))]


def test_a_key_written_often_keeps_every_part_in_order(ts, space_name):
    """Past `OFTEN` puts the store puts a key's parts on a declared publisher: none is lost."""
    key = part_key(space_name, *(term_chunk(t) for t in level(1, "x")[:2]))
    heard: list[bytes] = []
    raw = ts.session.declare_subscriber(key, lambda sample: heard.append(sample.payload))
    seen = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    values = [str(i) for i in range(OFTEN + 8)]
    for value in values:
        ts.write([level(1, value), level(2, value)])
    wait_for(lambda: len(seen) >= len(values), what="robot1's every level")
    assert [c.added for c in seen] == [[level(1, v)] for v in values]
    wait_for(lambda: len(heard) >= len(values), what="every part on robot1's key")
    parts = [unpack(bytes(payload)) for payload in heard]
    assert [p["add"] for p in parts] == [[[to_nt(t) for t in level(1, v)]] for v in values]
    assert [p["prev"] for p in parts[1:]] == [p["seq"] for p in parts[:-1]]
    raw.undeclare()


def test_a_scoped_subscription_may_start_from_the_whole_state(ts):
    ts.write([level(1, "normal"), level(2, "low")])
    seen = []
    ts.subscribe(None, seen.append, snapshot="all", scope=SCOPE)
    ts.write([level(2, "full")])
    ts.write([level(1, "low")])
    wait_for(lambda: len(seen) >= 2, what="snapshot and robot1's change")
    assert set(seen[0].added) == {level(1, "normal"), level(2, "low")}
    assert [c.added for c in seen[1:]] == [[level(1, "low")]]


def test_parts_missed_while_the_subscribers_router_was_down_come_back(tmp_path):
    store = Server(tmp_path / "data")
    store.start()
    edge = Server(tmp_path / "unused", "--no-store", "--connect", store.endpoint)
    edge.start()
    try:
        seen = []
        with (
            TripleSpace.open(edge.endpoint, space="gap", prefixes={"ac": AC_NS}) as sub_side,
            TripleSpace.open(store.endpoint, space="gap") as writer,
        ):
            sub_side.subscribe(None, seen.append, scope=SCOPE)
            writer.write([level(1, "normal")])
            wait_for(lambda: seen, 10, "the first part")
            edge.stop(signal.SIGKILL)
            for value in ("low", "very low"):
                writer.write([level(1, value), level(2, value)])
            edge.start()
            # on reconnecting, the subscription fetches what was written meanwhile
            wait_for(lambda: len(seen) >= 3, 20, "the parts written while the router was down")
            writer.write([level(1, "full")])
            wait_for(lambda: len(seen) >= 4, 10, "every part")
        assert [c.added for c in seen] == [
            [level(1, v)] for v in ("normal", "low", "very low", "full")
        ]
    finally:
        edge.stop()
        store.stop()


def test_parts_go_on_after_the_store_restarts(tmp_path):
    store = Server(tmp_path / "data")
    store.start()
    edge = Server(tmp_path / "unused", "--no-store", "--connect", store.endpoint)
    edge.start()
    try:
        seen = []
        with TripleSpace.open(edge.endpoint, space="again", prefixes={"ac": AC_NS}) as sub_side:
            sub_side.subscribe(None, seen.append, scope=SCOPE)
            with TripleSpace.open(store.endpoint, space="again") as writer:
                writer.write([level(1, "normal")])
            wait_for(lambda: seen, 10, "the first part")
            store.stop(signal.SIGKILL)
            store.start()  # knows no key's last part: its first parts name its floor
            with TripleSpace.open(store.endpoint, space="again") as writer:
                writer.write([level(2, "low")])
                writer.write([level(1, "low")])
            wait_for(lambda: len(seen) >= 2, 20, "the part after the restart")
        assert [c.added for c in seen] == [[level(1, "normal")], [level(1, "low")]]
        assert [c.seq for c in seen] == [1, 3]
    finally:
        edge.stop()
        store.stop()


def test_a_changeset_on_several_selected_keys_arrives_whole_with_one_id_and_seq(ts):
    seen = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    triples = [level(1, "low"), (AC.robot1, AC.location, AC.hall), level(2, "low")]
    written = ts.write(triples)
    wait_for(lambda: sum(len(c.added) for c in seen) >= 2, what="both of robot1's parts")
    assert {(c.id, c.seq) for c in seen} == {(written, written.seq)}
    assert sorted(t for c in seen for t in c.added) == sorted(triples[:2])


def test_a_changeset_of_many_parts_is_delivered_in_few_changes(ts):
    # A robot's 200 settings turned from one value to another, 200 keys: delivered a
    # handful of parts at a time, an agent would act on a dozen partial changes; the
    # parts' `n` has the library wait for the rest.
    def settings(value: str) -> list:
        return [(AC.robot1_base, AC[f"setting_{i}"], Literal(value)) for i in range(200)]

    ts.write(settings("normal"))
    seen = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    acks = [
        ts.apply(settings("low"), settings("normal")),
        ts.apply(settings("normal"), settings("low")),
        ts.apply(settings("low"), settings("normal")),
    ]
    wait_for(lambda: sum(len(c.added) for c in seen) >= 600, what="all 600 parts")
    assert [c.seq for c in seen] == sorted(c.seq for c in seen)
    assert {c.seq for c in seen} == {ack.seq for ack in acks}
    assert len(seen) <= 15, f"3 changesets delivered in {len(seen)} changes"  # 55-91 without `n`


@pytest.mark.parametrize("settings", [20, 300])  # the end names its predicates, or not
def test_a_changeset_of_many_parts_is_delivered_at_its_end_not_after_a_hold(
    ts, monkeypatch, settings
):
    # The store publishes a changeset's end after its parts: each subscriber of a scope
    # delivers the parts it has heard as soon as the end came back through it. With
    # holds far longer than the test's deadline, only the end can make the delivery.
    import space._dispatch

    monkeypatch.setattr(space._dispatch, "IDLE", 60.0)
    monkeypatch.setattr(space._dispatch, "HOLD_MAX", 60.0)
    robot1 = [(AC.robot1_base, AC[f"setting_{i}"], Literal("low")) for i in range(settings)]
    robot1 += [(AC.robot1, AC[f"status_{i}"], Literal("ok")) for i in range(20)]
    hall = (AC.hall, AC.crowd_level, Literal("high"))
    robot2 = [(AC.robot2_base, AC[f"setting_{i}"], Literal("low")) for i in range(20)]
    seen: list = []
    others: list = []
    ts.subscribe(None, seen.append, scope=[*SCOPE, (None, AC.crowd_level)])
    ts.subscribe(None, others.append, scope=[("ac:robot3_*", None)])  # none of it
    ts.write(robot2)  # not robot1's: its end is heard, and ignored
    ack = ts.write([*robot1, hall])
    expected = len(robot1) + 1
    wait_for(lambda: sum(len(c.added) for c in seen) >= expected, what="robot1's parts", timeout=10)
    assert len(seen) == 1 and seen[0].seq == ack.seq
    assert set(seen[0].added) == {*robot1, hall}
    assert others == []


def test_an_end_comes_back_only_through_the_subscribers_that_may_have_its_parts():
    # An agent's scope is its robot, its robot's parts and a few shared predicates: an
    # answer that sets its base's settings goes back through the base's subscriber only
    # (each sample of it back costs a thread wake-up), one naming no predicate through
    # those of the subjects that match, one naming nothing through all.
    from space._dispatch import Dispatcher
    from space._scope import selectors
    from space._scoped import ScopedSubscription
    from space.prefixes import PrefixMap
    from space.template import Template

    scope = [(AC.robot1, None), ("ac:robot1_*", None), (None, AC.crowd_level)]
    sub = ScopedSubscription(
        Dispatcher(lambda first, last: ([], 0)),
        Template.of(None),
        lambda change: None,
        space="s",
        selectors=selectors(scope, PrefixMap({"ac": AC_NS})),
    )
    base, setting = term_chunk(AC.robot1_base), term_chunk(AC.setting_1)
    through = [key for key, _n in sub._echoes({"seq": 9, "s": [base], "p": [setting]})]
    assert through == [sub._through[1][0]]
    assert len(sub._echoes({"seq": 9, "s": [base]})) == 2  # the predicate's may have it
    assert sub._echoes({"seq": 9, "s": [term_chunk(AC.robot2_base)], "p": [setting]}) == []
    assert len(sub._echoes({"seq": 9})) == 3


@pytest.mark.parametrize("reconnected", [True, False])
def test_a_lost_end_costs_a_hold_not_the_parts(monkeypatch, reconnected):
    # No end comes (a cut): the parts of a changeset of many are delivered as one change
    # when the link comes back (`catch_up`), or, as a last resort, when no more came for IDLE.
    import space._dispatch
    from space._dispatch import Dispatcher
    from space._parts import split
    from space._scoped import ScopedSubscription
    from space.template import Template

    if reconnected:
        monkeypatch.setattr(space._dispatch, "IDLE", 60.0)
        monkeypatch.setattr(space._dispatch, "HOLD_MAX", 60.0)
    triples = [[f"<{AC_NS}robot1_base>", f"<{AC_NS}setting_{i}>", '"low"'] for i in range(20)]
    wire = {"v": 1, "id": "c1", "agent": "w", "ts": "1/x", "seq": 1, "add": triples}
    seen: list = []
    dispatcher = Dispatcher(lambda first, last: ([], 0))
    sub = ScopedSubscription(
        dispatcher, Template.of(None), seen.append, space="s", selectors=["*/*"]
    )
    sub.start(1)
    dispatcher.add(sub)
    dispatcher.mark_ready(sub, 0)
    for (s, p), part in split(wire).items():
        part |= {"prev": 0, "n": 20}
        dispatcher._queue.put((sub, (f"tspace/s/@/changes/{s}/{p}", pack(part))))
    if reconnected:
        dispatcher.catch_up()
    wait_for(lambda: seen, what="the parts, without their end", timeout=10)
    dispatcher.close()
    assert len(seen) == 1 and len(seen[0].added) == 20


def test_a_robots_hw_monitor_hears_its_robot_and_the_site_not_the_fleet_nor_records(ts):
    from agents.base import robot_scope
    from agents.firings import FiringLog
    from agents.hw_monitor import HwMonitor

    seen = []
    ts.subscribe(None, seen.append, scope=robot_scope(AC.robot1, HwMonitor.shared))
    texts, _dropped = FiringLog().record(["some_rule"], "cause-1", AC.robot1)
    record = [triple_from_nt(t) for t in texts]
    ts.write(record)  # the reasoner's record about robot1: not for its agents
    ts.write([level(2, "low"), (AC.robot2, AC.location, AC.hall)])  # another robot's
    ts.write([(AC.hall, AC.crowd_level, Literal("high"))])  # the site: its lasers see it
    ts.write([level(1, "low")])
    wait_for(lambda: len(seen) >= 2, what="the site's and robot1's changes")
    assert [c.added for c in seen] == [
        [(AC.hall, AC.crowd_level, Literal("high"))],
        [level(1, "low")],
    ]


def test_a_malformed_part_costs_only_itself_not_the_parts_delivered_with_it(caplog):
    # The parts of one changeset received together are parsed once, at delivery: a bad
    # term in one of them must still leave the others' triples delivered.
    from space._dispatch import Dispatcher
    from space._parts import split
    from space._scoped import ScopedSubscription
    from space.template import Template

    good = [[f"<{AC_NS}robot1_battery>", f"<{AC_NS}battery_level>", '"low"']]
    bad = [[f"<{AC_NS}robot1>", f"<{AC_NS}location>", '"unterminated']]
    wire = {"v": 1, "id": "c1", "agent": "w", "ts": "1/x", "seq": 1, "add": good + bad}
    sub = ScopedSubscription(
        Dispatcher(lambda first, last: ([], 0)),
        Template.of(None),
        lambda change: None,
        space="s",
        selectors=["*/*"],
    )
    sub.start(1)
    queued: list = []
    for (s, p), part in split(wire).items():
        part |= {"prev": 0, "n": 2}
        for item in sub.receive((f"tspace/s/@/changes/{s}/{p}", pack(part)), None):
            if not (queued and sub.merge(queued[-1], item)):
                queued.append(item)
    assert len(queued) == 1  # one delivery for both parts
    with caplog.at_level(logging.WARNING, logger="tspace.subscription"):
        change = sub.change(queued[0])
    assert change is not None and change.added == [level(1, "low")]
    assert "malformed change skipped" in caplog.text


def settings(robot: int, value: str, count: int = 200) -> list:
    return [(AC[f"robot{robot}_base"], AC[f"setting_{i}"], Literal(value)) for i in range(count)]


def test_a_subjects_many_predicates_travel_in_a_few_parts_a_predicate_scope_gets_its_own(ts):
    # One part a subject, its predicates in its key: 200 settings of one base are a few
    # puts, not 200; a subscriber of one predicate gets that predicate's triple only.
    heard: list = []
    raw = ts.session.declare_subscriber(  # the store's parts: no attachment (ends sent back have)
        f"tspace/{ts.space}/@/changes/*/*/**",
        lambda sample: sample.attachment is None and heard.append(sample),
    )
    seen: list = []
    ts.subscribe(None, seen.append, scope=[(None, AC.setting_7)])
    ack = ts.write([*settings(1, "low"), (AC.robot1, AC.location, AC.hall)])
    wait_for(lambda: seen, what="setting_7's triple")
    wait_for(lambda: len(heard) >= 4, what="the parts")
    raw.undeclare()
    parts = [unpack(bytes(sample.payload)) for sample in heard]
    assert {p["seq"] for p in parts} == {ack.seq}
    assert len(parts) == 4  # the base's 200 predicates in 3 keys of at most 4 KB, robot1's 1
    assert sum(len(p["add"]) for p in parts) == 201
    assert all(p["n"] == 201 for p in parts)  # n counts the changeset's pairs
    assert all(len(str(s.key_expr)) < 4200 for s in heard)
    assert [c.added for c in seen] == [[(AC.robot1_base, AC.setting_7, Literal("low"))]]


def test_a_lost_part_of_many_predicates_is_fetched_by_the_prev_of_a_selected_one(ts):
    seen: list = []
    sub = ts.subscribe(None, seen.append, scope=[(None, AC.setting_7)])
    ts.write([(AC.robot1_base, AC.setting_7, Literal("normal"))])
    wait_for(lambda: seen, what="the first part")
    _cut(ts, sub)
    ts.write(settings(1, "low", 20))  # lost: one part, setting_7 one of its 20 predicates
    ts.write(settings(1, "high", 20)[8:])  # not setting_7: its prevs name the lost one
    _mend(ts, sub)
    ts.write(settings(1, "x", 20))  # one part again: its prev for setting_7 names the lost one
    wait_for(lambda: len(seen) >= 3, what="the lost part, then the new one")
    assert [c.added for c in seen] == [
        [(AC.robot1_base, AC.setting_7, Literal(v))] for v in ("normal", "low", "x")
    ]


def test_a_part_whose_prev_does_not_fit_its_predicates_is_skipped(server, ts, caplog):
    seen: list = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    s = escape_key_chunk(f"<{AC_NS}robot1_base>")
    p1, p2 = (escape_key_chunk(f"<{AC_NS}setting_{i}>") for i in (1, 2))
    forged = {"v": 1, "id": "x", "agent": "f", "ts": "1/x", "seq": 1, "prev": [0]}
    with caplog.at_level(logging.WARNING, logger="tspace.subscription"):
        with zenoh.open(make_config(mode="client", connect=[server.endpoint])) as plain:
            plain.put(f"tspace/{ts.space}/@/changes/{s}/{p1}/{p2}", pack(forged))
        ts.write([level(1, "low")])
        wait_for(lambda: seen, what="the real part")
    assert [c.added for c in seen] == [[level(1, "low")]]
    assert "for each pair" in caplog.text


def test_a_malformed_end_is_skipped_and_a_real_one_still_ends_the_wait(
    server, ts, monkeypatch, caplog
):
    # Anyone can put on the ends' key: garbage there is logged and skipped, and the
    # real end of a changeset of many parts still delivers them (the holds are far
    # longer than the test's deadline: only the end can).
    import space._dispatch

    monkeypatch.setattr(space._dispatch, "IDLE", 60.0)
    monkeypatch.setattr(space._dispatch, "HOLD_MAX", 60.0)
    seen: list = []
    ts.subscribe(None, seen.append, scope=SCOPE)
    forged = [
        b"\xc1 not msgpack",
        b"\x81\x90\x00",  # a map keyed by a list
        pack([1, 2]),
        pack({"s": []}),  # no seq
        pack({"seq": "7"}),
        pack({"seq": True}),
        pack({"seq": 10**9, "s": [1, None], "p": "x"}),  # names nothing usable: heard by all
    ]
    with caplog.at_level(logging.WARNING, logger="tspace.subscription"):
        with zenoh.open(make_config(mode="client", connect=[server.endpoint])) as plain:
            for payload in forged:
                plain.put(f"tspace/{ts.space}/@/changes/end", payload)
        ack = ts.write(settings(1, "low", 20))
        wait_for(lambda: sum(len(c.added) for c in seen) >= 20, what="the parts", timeout=10)
        wait_for(
            lambda: (
                caplog.text.count("malformed end of changeset skipped") == 4
                and caplog.text.count("not an integer skipped") == 2
            ),
            what="a line for each malformed end",
        )
    assert [c.seq for c in seen] == [ack.seq]
