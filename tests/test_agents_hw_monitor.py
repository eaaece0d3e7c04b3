"""The hardware monitor as a process: levels, commands, faults, restarts, malformed input."""

import signal

import pytest
from agentprocs import alive, knowledge, value
from rdflib import Literal, Namespace

from conftest import AC_NS, wait_for

AC = Namespace(AC_NS)


@pytest.fixture
def robot(ts):
    ts.write(knowledge())
    return ts


def charge(ts):
    found = value(ts, AC.robot1_battery, AC.charge_percent)
    return None if found is None else int(found)


def test_battery_level_falls_as_the_battery_drains(robot, launch):
    launch.start("hw_monitor", "--time-scale", "300", "--charge", "30")
    wait_for(lambda: value(robot, AC.robot1_battery, AC.battery_level) == Literal("low"), 15)
    wait_for(lambda: value(robot, AC.robot1_battery, AC.battery_level) == Literal("very low"), 15)
    assert charge(robot) < 10


def test_battery_charges_while_the_task_is_charging(robot, launch):
    robot.apply(
        [(AC.robot1, AC.current_task, AC.task_charging)],
        [(AC.robot1, AC.current_task, AC.task_idle)],
    )
    launch.start("hw_monitor", "--time-scale", "300", "--charge", "50")
    wait_for(lambda: value(robot, AC.robot1_battery, AC.battery_level) == Literal("full"), 15)


def test_a_level_or_charge_set_by_another_agent_holds(robot, launch):
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_screen, AC.actual_mode) == Literal("active"))
    robot.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
    wait_for(lambda: charge(robot) == 5)  # the middle of "very low", adopted by the battery
    robot.write([(AC.robot1_battery, AC.charge_percent, Literal(40))])
    wait_for(lambda: value(robot, AC.robot1_battery, AC.battery_level) == Literal("normal"))
    # The monitor's later reports keep what was set.
    robot.write([(AC.robot1_screen, AC.running_mode, Literal("stand-by"))])
    wait_for(lambda: value(robot, AC.robot1_screen, AC.actual_mode) == Literal("stand-by"))
    assert value(robot, AC.robot1_battery, AC.battery_level) == Literal("normal")
    assert charge(robot) == 40


def test_a_charging_battery_is_not_very_low_so_the_dock_rule_cannot_fire_again(robot, launch):
    robot.apply(
        [
            (AC.robot1, AC.current_task, AC.task_charging),
            (AC.robot1_battery, AC.charge_percent, Literal(3)),
        ],
        [(AC.robot1, AC.current_task, AC.task_idle)],
    )
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_battery, AC.battery_level) == Literal("low"))
    assert charge(robot) < 10


def test_devices_obey_running_modes_and_report_them(robot, launch):
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_screen, AC.actual_mode) == Literal("active"))
    robot.write([(AC.robot1_screen, AC.running_mode, Literal("stand-by"))])
    wait_for(lambda: value(robot, AC.robot1_screen, AC.actual_mode) == Literal("stand-by"))
    assert value(robot, AC.robot1_speakers, AC.actual_mode) == Literal("active")


def test_a_simulated_motor_fault_is_reported_and_cleared(robot, launch):
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_wheels, AC.actual_mode) == Literal("active"))
    robot.write([(AC.robot1_wheels, AC.simulate_fault, Literal("error"))])
    wait_for(lambda: value(robot, AC.robot1_wheels, AC.fault) == Literal("error"))
    robot.write([(AC.robot1_wheels, AC.simulate_fault, Literal("none"))])
    wait_for(lambda: value(robot, AC.robot1_wheels, AC.fault) == Literal("none"))


def test_the_motor_failure_announcement_is_replaced_once_the_motor_works(robot, launch):
    reasoner = launch.start("reasoner")
    wait_for(lambda: "loaded" in reasoner.logs(), 30, "the reasoner", reasoner.logs)
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_wheels, AC.actual_mode) == Literal("active"))
    robot.write([(AC.robot1_wheels, AC.simulate_fault, Literal("error"))])
    wait_for(lambda: "wheel motor failed" in str(value(robot, AC.robot1, AC.announcement)))
    assert value(robot, AC.robot1_navigation, AC.skill_status) == Literal("disabled")
    robot.write([(AC.robot1_wheels, AC.simulate_fault, Literal("none"))])
    wait_for(lambda: value(robot, AC.robot1_navigation, AC.skill_status) == Literal("enabled"))
    wait_for(lambda: value(robot, AC.robot1, AC.announcement) is not None)
    assert value(robot, AC.robot1, AC.announcement) == Literal(
        "My wheel motors work again: I can move."
    )


def test_the_laser_reports_crowds_where_the_robot_is(robot, launch):
    launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_laser, AC.obstacles) == Literal("clear"))
    robot.write([(AC.robot1, AC.location, AC.hall)])
    wait_for(lambda: value(robot, AC.robot1_laser, AC.obstacles) == Literal("surrounded"))


def test_malformed_commands_are_skipped_and_the_agent_keeps_working(robot, launch):
    agent = launch.start("hw_monitor")
    wait_for(lambda: value(robot, AC.robot1_screen, AC.actual_mode) == Literal("active"))
    robot.write(
        [
            (AC.robot1_screen, AC.running_mode, Literal("asleep")),
            (AC.robot1_wheels, AC.simulate_fault, Literal(42)),
            (AC.robot1_battery, AC.charge_percent, Literal("lots")),
        ]
    )
    robot.write([(AC.robot1_speakers, AC.running_mode, Literal("stand-by"))])
    wait_for(lambda: value(robot, AC.robot1_speakers, AC.actual_mode) == Literal("stand-by"))
    assert agent.alive()
    wait_for(lambda: "ignoring unknown mode 'asleep'" in agent.logs(), 10, "the warning")


def test_kill_9_then_restart_rebuilds_the_battery_from_the_space(robot, launch):
    agent = launch.start("hw_monitor", "--time-scale", "100")
    wait_for(lambda: (charge(robot) or 100) <= 70, 20)
    robot.write([(AC.robot1_microphone, AC.running_mode, Literal("stand-by"))])
    wait_for(lambda: value(robot, AC.robot1_microphone, AC.actual_mode) == Literal("stand-by"))
    name = "hw_monitor.robot1"
    wait_for(lambda: alive(robot, name))
    agent.stop(signal.SIGKILL)
    wait_for(lambda: not alive(robot, name), 15)
    before = charge(robot)

    agent.start()
    wait_for(lambda: alive(robot, name))
    # Rebuilt from the space: the charge it had, not the robot file's 80 % nor --charge.
    wait_for(lambda: f"battery at {before} %" in agent.logs())
    assert charge(robot) <= before
    assert value(robot, AC.robot1_microphone, AC.actual_mode) == Literal("stand-by")


def test_sigterm_stops_cleanly_and_withdraws_presence(robot, launch):
    agent = launch.start("hw_monitor")
    name = "hw_monitor.robot1"
    wait_for(lambda: alive(robot, name))
    assert agent.stop(signal.SIGTERM) == 0
    wait_for(lambda: not alive(robot, name))
    assert "stopping" in agent.logs()
