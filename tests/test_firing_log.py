"""The reasoner's firing records: one per answer and robot, the last few kept."""

from rdflib import Literal, Namespace

from agents.firings import FiringLog
from conftest import AC_NS

AC = Namespace(AC_NS)


def names(triples):
    return {str(o) for _s, p, o in triples if p == AC.rule_name}


def test_the_rules_that_answer_one_change_share_one_record():
    log = FiringLog()
    first, _ = log.record("low_speed", "change-1", AC.robot1)
    more, _ = log.record("go_to_dock", "change-1", AC.robot1)
    again, _ = log.record("go_to_dock", "change-1", AC.robot1)  # another binding, same rule
    assert {s for s, _p, _o in first + more} == {AC.firing_1}
    assert names(first + more) == {"low_speed", "go_to_dock"}
    assert again == []
    other_robot, _ = log.record("go_to_dock", "change-1", AC.robot2)
    next_change, _ = log.record("low_speed", "change-2", AC.robot1)
    assert {s for s, _p, _o in other_robot} == {AC.firing_2}
    assert (AC.firing_3, AC.cause, Literal("change-2")) in next_change


def test_only_the_last_records_stay():
    log = FiringLog(keep=2)
    for i in range(3):
        _added, dropped = log.record("rule", f"change-{i}", AC.robot1)
    assert {s for s, _p, _o in dropped} == {AC.firing_1}
