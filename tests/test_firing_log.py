"""The reasoner's firing records: one per answer and robot, the last few kept."""

from rdflib import Literal, Namespace

from agents.firings import FiringLog, rule_names
from conftest import AC_NS

AC = Namespace(AC_NS)


def test_the_rules_that_answer_one_change_share_one_record():
    log = FiringLog()
    first, _ = log.record(["low_speed", "low_speed"], "change-1", AC.robot1)  # two bindings
    more, replaced = log.record(["go_to_dock"], "change-1", AC.robot1)  # a later answer to it
    again, _ = log.record(["go_to_dock"], "change-1", AC.robot1)  # another binding, same rule
    assert {s for s, _p, _o in first + more} == {AC.firing_1}
    assert rule_names(first) == ["low_speed"]
    assert rule_names(more) == ["low_speed", "go_to_dock"] and rule_names(replaced) == ["low_speed"]
    assert again == []
    other_robot, _ = log.record(["go_to_dock"], "change-1", AC.robot2)
    next_change, _ = log.record(["low_speed"], "change-2", AC.robot1)
    assert {s for s, _p, _o in other_robot} == {AC.firing_2}
    assert (AC.firing_3, AC.cause, Literal("change-2")) in next_change


def test_a_record_is_six_triples_however_many_rules_fired():
    added, _ = FiringLog().record([f"rule_{i}" for i in range(200)], "change-1", AC.robot1)
    assert len(added) == 6
    assert rule_names(added) == [f"rule_{i}" for i in range(200)]


def test_only_the_last_records_stay():
    log = FiringLog(keep=2)
    for i in range(3):
        _added, dropped = log.record(["rule"], f"change-{i}", AC.robot1)
    assert {s for s, _p, _o in dropped} == {AC.firing_1}
