"""The reasoner's firing records: one per answer and robot, the last few kept."""

from datetime import UTC, datetime

from rdflib import RDF, Literal, Namespace

from agents.firings import FiringLog
from agents.firings import rule_names as names_in
from conftest import AC_NS
from space import triple_from_nt

AC = Namespace(AC_NS)


def rule_names(texts):
    """`rule_names` of records written as N-Triples texts, as the reasoner writes them."""
    return names_in(terms(texts))


def terms(texts):
    return [triple_from_nt(t) for t in texts]


def test_the_rules_that_answer_one_change_share_one_record():
    log = FiringLog()
    first, _ = log.record(["low_speed", "low_speed"], "change-1", AC.robot1)  # two bindings
    more, replaced = log.record(["go_to_dock"], "change-1", AC.robot1)  # a later answer to it
    again, _ = log.record(["go_to_dock"], "change-1", AC.robot1)  # another binding, same rule
    assert {s for s, _p, _o in terms(first + more)} == {AC.firing_1}
    assert rule_names(first) == ["low_speed"]
    assert rule_names(more) == ["low_speed", "go_to_dock"] and rule_names(replaced) == ["low_speed"]
    assert again == []
    other_robot, _ = log.record(["go_to_dock"], "change-1", AC.robot2)
    next_change, _ = log.record(["low_speed"], "change-2", AC.robot1)
    assert {s for s, _p, _o in terms(other_robot)} == {AC.firing_2}
    assert (AC.firing_3, AC.cause, Literal("change-2")) in terms(next_change)


def test_a_record_is_six_triples_however_many_rules_fired():
    added, _ = FiringLog().record([f"rule_{i}" for i in range(200)], "change-1", AC.robot1)
    assert len(added) == 6
    assert rule_names(added) == [f"rule_{i}" for i in range(200)]


def test_only_the_last_records_stay():
    log = FiringLog(keep=2)
    for i in range(3):
        _added, dropped = log.record(["rule"], f"change-{i}", AC.robot1)
    assert {s for s, _p, _o in terms(dropped)} == {AC.firing_1}


def test_a_record_reads_as_the_rdflib_terms_it_stands_for():
    """Written as texts with no rdflib term made, a record parses to what rdflib would write."""
    when = datetime(2026, 11, 28, 15, 0, 1, 250000, tzinfo=UTC)
    added, _ = FiringLog().record(['a "quoted"\nrule'], "change\t1", AC.robot1, when)
    assert set(terms(added)) == {
        (AC.firing_1, AC.rule_names, Literal('a "quoted"\nrule')),
        (AC.firing_1, AC.robot, AC.robot1),
        (AC.firing_1, AC.fired_at, Literal(when)),
        (AC.firing_1, AC.firing_seq, Literal(1)),
        (AC.firing_1, AC.cause, Literal("change\t1")),
        (AC.firing_1, RDF.type, AC.RuleFiring),
    }


def test_records_restored_after_a_restart_are_numbered_after_and_dropped_in_turn():
    first = FiringLog(keep=2)
    kept = [first.record(["rule"], f"change-{i}", AC.robot1)[0] for i in range(2)]
    again = FiringLog(keep=2)
    again.restore(terms(kept[0] + kept[1]))
    added, dropped = again.record(["rule"], "change-9", AC.robot1)
    assert {s for s, _p, _o in terms(added)} == {AC.firing_3}
    assert sorted(dropped) == sorted(kept[0])
