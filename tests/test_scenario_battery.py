"""The paper's battery example, end to end across real processes, through `tspace up`."""

from __future__ import annotations

import os
import re
import signal

import pytest
from uprun import Up

from conftest import REPO, wait_for

HOSPITAL = REPO / "deploy" / "hospital.toml"
STEPS = [
    "robot attends a patient (task AttendingPatient)",
    "battery drains to very low",
    "robot heads to the dock (task GoingToDock)",
    "mobile base slows to low speed",
    "screen, speakers, microphone stand-by; wheels, laser stay active",
    "robot reaches the dock and docks (location dock, task Docking)",
    "robot charges (task Charging)",
    "battery charged (level normal or full)",
    "robot back to work (task AttendingPatient)",
]

needs_reasoner = pytest.mark.skipif(
    not (REPO / "agents" / "reasoner.py").is_file(), reason="the reasoner agent is not built yet"
)
# The hospital without its reasoner: nothing concludes that the robot must go to its dock.
NO_REASONER = """
space = "hospital"
robots = ["robot1"]
load = ["{repo}/ontology/selfconfig.ttl", "{repo}/ontology/robots/hospital.ttl"]

[[agent]]
name = "hw_monitor"
per_robot = true

[[agent]]
name = "nav_monitor"
per_robot = true

[[agent]]
name = "behavior"
per_robot = true
"""


def completed_steps(up: Up) -> list[str]:
    found = [re.search(r"step \d+/\d+ done: (.*) \(", line) for line in up.err]
    return [m.group(1) for m in found if m]


def assert_the_robot_behaved(up: Up) -> None:
    assert completed_steps(up) == STEPS, up.logs()
    assert up.stdout_has("scenario battery: completed")
    log = "\n".join(up.out)
    # The reasoner's conclusions, each caused by the very low battery, said as sentences
    # ("battery very low → robot1 goes to the dock at low speed; microphone, ... stand-by").
    because = "firing: .*battery very low → .*"
    for conclusion in (
        "robot1 goes to the dock",
        "at low speed",
        "microphone[^;]* stand-by",
        "screen[^;]* stand-by",
        "speakers[^;]* stand-by",
    ):
        assert re.search(because + conclusion, log), f"{conclusion} in {up.logs()}"
    assert not re.search(r"firing: .*(wheels|laser)[^;]* stand-by", log)
    # The robot's resulting behaviour, as the live view logged it, in order.
    story = [
        "task AttendingPatient",
        "battery very low",
        "task GoingToDock",
        "at dock1",
        "task Docking",
        "task Charging",
        "task AttendingPatient",
    ]
    robot_lines = [line for line in up.out if line.startswith("robot1: ")]
    position = 0
    for line in robot_lines:
        if position < len(story) and story[position] in line:
            position += 1
    assert position == len(story), f"missing {story[position:]} in {robot_lines}"
    # Charging with a very low battery does not send the robot to its dock again.
    charging = next(i for i, line in enumerate(robot_lines) if "task Charging" in line)
    assert not [line for line in robot_lines[charging:] if "task GoingToDock" in line]
    assert len(re.findall(r"firing: .*verylow_battery_causes_going_to_dock_task", log)) == 1


@needs_reasoner
def test_the_battery_scenario_completes(tmp_path):
    with Up(tmp_path, HOSPITAL, "--scenario", "battery", "--once") as up:
        assert up.proc.wait(timeout=9 * 90) == 0, up.logs()
        wait_for(lambda: up.stdout_has("scenario battery: completed"), 5, "the last line")
        assert_the_robot_behaved(up)


# Each agent is killed after the step that leaves it work to do: the reasoner before the
# battery is very low, the HMI while it drains, the nav monitor on the way to the dock, the
# behaviour machine and the hw_monitor at the dock (the charge, and going back to the
# patient, must survive).
KILLED_AFTER_STEP = {"reasoner": 1, "hmi": 2, "nav_monitor": 3, "behavior": 6, "hw_monitor": 7}


@needs_reasoner
@pytest.mark.parametrize("agent", sorted(KILLED_AFTER_STEP))
def test_the_scenario_survives_an_agent_killed_with_sigkill(tmp_path, agent):
    step = KILLED_AFTER_STEP[agent]
    with Up(tmp_path, HOSPITAL, "--scenario", "battery", "--once") as up:
        wait_for(lambda: len(completed_steps(up)) >= step, 90, f"step {step}")
        victim = up.pid_of(f"agents.{agent}")
        assert victim is not None
        os.kill(victim, signal.SIGKILL)
        wait_for(lambda: up.stderr_has(f"{agent}: restarted (pid "), 15, "the restart")
        assert up.stderr_has(f"{agent}: crashed (killed by SIGKILL)")
        assert up.proc.wait(timeout=9 * 90) == 0, up.logs()
        assert_the_robot_behaved(up)


def test_a_step_that_does_not_happen_is_named(tmp_path):
    launch = tmp_path / "no_reasoner.toml"
    launch.write_text(NO_REASONER.format(repo=REPO))
    with Up(tmp_path, launch, "--scenario", "battery", "--once", "--step-timeout", "15") as up:
        assert up.proc.wait(timeout=120) == 1, up.logs()
        assert up.stderr_has(
            "scenario battery failed: step 3/9 did not happen within 15 s: "
            "robot heads to the dock (task GoingToDock)"
        ), up.logs()
