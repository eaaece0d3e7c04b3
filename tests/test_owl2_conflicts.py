"""Inconsistencies end to end: the reasoner writes a conflict resource and takes it back."""

from agentprocs import HOSPITAL, value
from rdflib import RDF, Literal, Namespace

from agents.conflicts import TR
from conftest import AC_NS, wait_for

AC = Namespace(AC_NS)


def conflicts_about(ts, subject):
    """Return the conflict resources in the space that involve `subject`."""
    return set(ts.query((None, TR.involves, subject), graph="inferred").subjects())


def test_a_device_put_on_stand_by_while_in_use_is_a_conflict_until_its_user_leaves(ts, launch):
    """A visitor uses the screen; the battery goes low and the rules put it on stand-by."""
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle)
    screen = AC.robot1_screen
    ts.write([(screen, AC.used_by, AC.patient_jon)])
    wait_for(lambda: len(ts.query((screen, RDF.type, AC.DeviceInUse), graph="inferred")))
    assert not conflicts_about(ts, screen)

    ts.write([(AC.robot1_battery, AC.battery_level, Literal("low"))])
    wait_for(lambda: value(ts, screen, AC.running_mode) == Literal("stand-by"))
    (conflict,) = wait_for(lambda: conflicts_about(ts, screen), what="a conflict on the screen")
    assert value(ts, conflict, TR.rule) == Literal("cax-dw")
    clashing = set()
    for statement in ts.query((conflict, TR.clash, None), graph="inferred").objects():
        s, p, o = (value(ts, statement, x) for x in (RDF.subject, RDF.predicate, RDF.object))
        clashing.add((s, p, o))
    assert (screen, RDF.type, AC.StandbyDevice) in clashing
    assert (screen, RDF.type, AC.DeviceInUse) in clashing
    wait_for(lambda: "conflict" in agent.logs() and "cax-dw" in agent.logs(), 10, "the log line")
    # Nothing was lost, and the reasoner goes on answering.
    assert value(ts, screen, AC.running_mode) == Literal("stand-by")
    ts.write([(AC.robot1_laser, AC.obstacles, Literal("surrounded"))])
    wait_for(lambda: value(ts, AC.robot1_base, AC.obstacle_avoidance) == Literal("cautious"))

    # The patient is done with the screen: the conflict goes, statements and all.
    ts.remove([(screen, AC.used_by, AC.patient_jon)])
    wait_for(lambda: not conflicts_about(ts, screen), what="the conflict to go")
    assert not len(ts.query((conflict, None, None), graph="inferred"))
    assert not len(ts.query((None, RDF.type, TR.Conflict), graph="inferred"))
    assert agent.alive()
