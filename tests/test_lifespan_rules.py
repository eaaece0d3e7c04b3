"""Rules see expiry as retraction: a silent battery monitor stops the robot taking tasks."""

from __future__ import annotations

import json
import re
import signal
import time

from agentprocs import HOSPITAL, value
from rdflib import Literal, Namespace

from conftest import AC_NS, wait_for

AC = Namespace(AC_NS)
LIFE = 2.0  # the monitor's lifespan here (10 s in deploy/hospital.toml)


def _reading_leased(ts) -> bool:
    lives = dict(ts.lifespans((AC.robot1_battery, AC.battery_level, None)))
    return any(left is not None for left in lives.values())


def _stays(condition, seconds: float) -> bool:
    """Return True if `condition` holds all along the next `seconds` (checked as it goes)."""
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        if not condition():
            return False
        time.sleep(0.05)
    return True


def test_the_robot_stops_taking_tasks_when_its_battery_monitor_dies(ts, launch) -> None:
    launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle, 20, "the robot")
    monitor = launch.start("hw_monitor", "--lifespan", f"{LIFE}s")
    launch.start("behavior")
    wait_for(lambda: _reading_leased(ts), 20, "the monitor's leased battery reading")
    assert value(ts, AC.robot1, AC.battery_unknown) is None

    ts.write([(AC.robot1, AC.requested_task, AC.task_attending_patient)])
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_attending_patient, 15)

    monitor.stop(signal.SIGKILL)
    killed = time.monotonic()
    wait_for(
        lambda: value(ts, AC.robot1, AC.battery_unknown) == AC.robot1_battery,
        LIFE + 1.0,
        "battery unknown within the lifespan plus 1 s of the kill",
    )
    assert value(ts, AC.robot1_battery, AC.battery_level) is None
    assert time.monotonic() - killed >= LIFE / 2  # not before its last renewal ran out

    ts.write([(AC.robot1, AC.requested_task, AC.task_guiding)])
    assert _stays(
        lambda: value(ts, AC.robot1, AC.current_task) == AC.task_attending_patient, 1.5
    ), "a task was taken while the battery was unknown"
    assert value(ts, AC.robot1, AC.requested_task) == AC.task_guiding  # waiting, not lost

    monitor.start()
    wait_for(lambda: value(ts, AC.robot1, AC.battery_unknown) is None, 20, "the battery known")
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_guiding, 15, "the task")


def test_why_with_lifespan_shows_what_each_fact_has_left(ts, launch, run_tspace) -> None:
    launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle, 30, "the robot")
    ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))], lifespan=60)
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == Literal("low"), 20)
    ts.load_prefixes()

    done = run_tspace("why", "--with-lifespan", "ac:robot1_base ac:motion_speed ?speed")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    at = next(i for i, line in enumerate(lines) if 'battery_level "very low"' in line)
    left = re.search(r"expires in ([0-9.]+) s unless written again", "\n".join(lines[at : at + 3]))
    assert left is not None and 50 < float(left[1]) <= 60, done.stdout
    robot = next(i for i, line in enumerate(lines) if line.endswith("ac:robot1 rdf:type ac:Robot"))
    assert "permanent" in "\n".join(lines[robot : robot + 3]), done.stdout
    first = re.search(
        r"concluded from a fact that expires in ([0-9.]+) s; stays until changed", done.stdout
    )
    assert first is not None and 50 < float(first[1]) <= 60, done.stdout

    done = run_tspace(
        "why", "--with-lifespan", "--format", "json", "ac:robot1_base ac:motion_speed ?speed"
    )
    assert done.returncode == 0, done.stderr
    [tree] = json.loads(done.stdout)
    level = next(p for p in tree["premises"] if p["text"].endswith('battery_level "very low"'))
    assert 50 < level["lifespan"] <= 60
    robot = next(p for p in tree["premises"] if p["text"] == "ac:robot1 rdf:type ac:Robot")
    assert robot["lifespan"] is None  # permanent
    assert tree["lifespan"] is None  # a production rule's conclusion is written permanent
