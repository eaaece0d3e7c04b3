"""The fleet monitor as a process: a robot is present while one of its agents is alive."""

from agentprocs import knowledge
from rdflib import RDF, Literal, Namespace

from conftest import AC_NS, wait_for
from space import Change
from space.presence import declare_agent

AC = Namespace(AC_NS)
PRESENCE = (None, AC.presence, None)


def presence(ts, robot):
    """Return the robot's `ac:presence` in the space, None if it has none."""
    found = list(ts.query((robot, AC.presence, None)).objects())
    return found[0] if len(found) == 1 else None


def test_a_robot_is_gone_when_its_last_agent_is(ts, space_name, launch):
    ts.write(knowledge())
    ts.write([(AC.robot2, RDF.type, AC.Robot)])  # described, never started
    written: list[Change] = []
    ts.subscribe(PRESENCE, written.append)
    hw = declare_agent(ts.session, space_name, "hw_monitor.robot1")
    monitor = launch.start("fleet_monitor")
    wait_for(lambda: presence(ts, AC.robot1) == Literal("present"), 30, "robot1 present")

    behavior = declare_agent(ts.session, space_name, "behavior.robot1")
    hw.undeclare()
    wait_for(lambda: "agent hw_monitor.robot1 gone" in monitor.logs(), 10, "hw_monitor gone")
    nav = declare_agent(ts.session, space_name, "nav_monitor.robot1")
    # the monitor handles events in order: once it saw nav_monitor arrive, it has
    # written whatever hw_monitor's departure made it write
    wait_for(lambda: "agent nav_monitor.robot1 arrived" in monitor.logs(), 10, "nav_monitor")
    assert presence(ts, AC.robot1) == Literal("present")
    behavior.undeclare()
    nav.undeclare()
    wait_for(lambda: presence(ts, AC.robot1) == Literal("gone"), 10, "robot1 gone")

    again = declare_agent(ts.session, space_name, "hw_monitor.robot1")
    wait_for(lambda: presence(ts, AC.robot1) == Literal("present"), 10, "robot1 back")
    again.undeclare()
    wait_for(lambda: presence(ts, AC.robot1) == Literal("gone"), 10, "robot1 gone again")

    assert [str(o) for ch in written for _s, _p, o in ch.added] == [
        "present",
        "gone",
        "present",
        "gone",
    ]
    assert presence(ts, AC.robot2) is None
    assert monitor.stop() == 0
    assert "Traceback" not in monitor.logs()
