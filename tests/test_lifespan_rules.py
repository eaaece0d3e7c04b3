"""Rules see expiry as retraction: a silent battery monitor stops the robot taking tasks."""

from __future__ import annotations

import signal
import time

from agentprocs import HOSPITAL, value
from rdflib import Namespace

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
