"""The nav monitor and the behaviour machine as processes: trips, speed, power cycle, restarts."""

import signal

import pytest
from agentprocs import AgentProcess, Launcher, knowledge, value
from rdflib import XSD, Literal, Namespace

from conftest import AC_NS, Server, tspace_cmd, wait_for
from space import TripleSpace

AC = Namespace(AC_NS)


@pytest.fixture
def robot(ts):
    ts.write(knowledge())
    return ts


def state(ts, predicate, subject=AC.robot1):
    return value(ts, subject, predicate)


def test_a_user_request_takes_the_robot_to_the_patient(robot, launch):
    launch.start("nav_monitor", "--time-scale", "20")
    launch.start("behavior", "--time-scale", "20")
    robot.write(
        [
            (AC.robot1, AC.attended_person, AC.patient_ane),
            (AC.robot1, AC.requested_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: state(robot, AC.current_task) == AC.task_attending_patient)
    wait_for(lambda: state(robot, AC.location) == AC.room_101)
    wait_for(lambda: state(robot, AC.navigation_status) == Literal("reached"))
    assert state(robot, AC.interacting_with) == AC.patient_ane
    assert state(robot, AC.requested_task) is None
    # the space holds XSD numbers by value, in canonical form ("2.0"^^xsd:decimal is "2")
    x, y = state(robot, AC.position_x), state(robot, AC.position_y)
    assert x.datatype == y.datatype == XSD.decimal
    assert (x.toPython(), y.toPython()) == (2, 12)


def test_speed_limit_and_disabled_navigation_act_on_the_base(robot, launch):
    launch.start("nav_monitor", "--time-scale", "2")
    robot.write([(AC.robot1, AC.target_place, AC.therapy_room)])
    wait_for(lambda: state(robot, AC.navigation_status) == Literal("navigating"))
    wait_for(lambda: float(state(robot, AC.actual_speed, AC.robot1_base) or 0) == 0.7)
    robot.write([(AC.robot1_base, AC.motion_speed, Literal("low"))])
    wait_for(lambda: float(state(robot, AC.actual_speed, AC.robot1_base) or 0) == 0.3)

    robot.write([(AC.robot1_navigation, AC.skill_status, Literal("disabled"))])
    wait_for(lambda: state(robot, AC.navigation_status) == Literal("aborted"))
    assert float(state(robot, AC.actual_speed, AC.robot1_base)) == 0.0
    stopped_at = state(robot, AC.position_x)
    robot.write([(AC.robot1_base, AC.motion_speed, Literal("high"))])
    wait_for(lambda: state(robot, AC.navigation_status) == Literal("aborted"))
    assert state(robot, AC.position_x) == stopped_at

    robot.write([(AC.robot1_navigation, AC.skill_status, Literal("enabled"))])
    wait_for(lambda: state(robot, AC.location) == AC.therapy_room, 20)
    wait_for(lambda: state(robot, AC.navigation_status) == Literal("reached"))


def test_going_to_dock_docks_charges_and_resumes_the_patient(robot, launch):
    for agent in ("hw_monitor", "nav_monitor", "behavior"):
        launch.start(agent, "--time-scale", "50")
    robot.write(
        [
            (AC.robot1, AC.attended_person, AC.patient_ane),
            (AC.robot1, AC.requested_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: state(robot, AC.location) == AC.room_101)
    # What the paper's rule does on a very low battery.
    robot.write([(AC.robot1, AC.current_task, AC.task_going_to_dock)])
    wait_for(lambda: state(robot, AC.current_task) == AC.task_charging, 15)
    assert state(robot, AC.location) == AC.dock1
    assert state(robot, AC.resume_task) == AC.task_attending_patient
    wait_for(lambda: state(robot, AC.current_task) == AC.task_attending_patient, 20)
    wait_for(lambda: state(robot, AC.location) == AC.room_101)
    # It went back to work charged (full at 95 %; it drains again on the way).
    assert int(state(robot, AC.charge_percent, AC.robot1_battery)) >= 85


def test_kill_9_behavior_keeps_counting_the_task_time(robot, launch):
    behavior = launch.start("behavior", "--time-scale", "20")
    robot.write([(AC.robot1, AC.requested_task, AC.task_guiding)])
    wait_for(lambda: state(robot, AC.current_task) == AC.task_guiding)
    wait_for(lambda: float(state(robot, AC.task_elapsed) or 0) >= 40, 15)
    behavior.stop(signal.SIGKILL)
    before = float(state(robot, AC.task_elapsed))
    behavior.start()
    wait_for(lambda: "view rebuilt" in behavior.logs().split("connected to space")[-1])
    wait_for(lambda: float(state(robot, AC.task_elapsed)) > before)
    assert state(robot, AC.current_task) == AC.task_guiding


def test_a_visit_postponed_for_taking_too_long_is_taken_up_again_for_the_same_patient(
    robot, launch
):
    reasoner = launch.start("reasoner")
    wait_for(lambda: "loaded" in reasoner.logs(), 30, "the reasoner", reasoner.logs)
    behavior = launch.start("behavior", "--time-scale", "100", "--retry-after", "60")
    robot.write(
        [
            (AC.robot1_battery, AC.battery_level, Literal("low")),
            (AC.robot1, AC.attended_person, AC.patient_ane),
            (AC.robot1, AC.requested_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: state(robot, AC.interacting_with) == AC.patient_ane, 15)
    visit_started = state(robot, AC.task_started)
    # 600 simulated seconds (6 s here) later the visit is overdue: the rules postpone it.
    wait_for(lambda: state(robot, AC.waiting_for, AC.patient_ane) is not None, 30)
    assert state(robot, AC.waiting_for, AC.patient_ane) == AC.task_attending_patient
    assert state(robot, AC.postponed_by, AC.patient_ane) == AC.robot1
    assert "took too long" in str(state(robot, AC.announcement))
    assert state(robot, AC.current_task) == AC.task_idle
    # Meanwhile someone else asks for the robot: Ane's attended_person is overwritten.
    robot.write([(AC.robot1, AC.attended_person, AC.visitor_miren)])
    # Idle for longer than --retry-after, but the battery is low: the visit waits.
    # The idle count is the one after a new task_started (the count under 100 lasts 1 s).
    wait_for(
        lambda: (
            state(robot, AC.task_started) != visit_started
            and float(state(robot, AC.task_elapsed) or 0) >= 100
        ),
        15,
        "the idle count",
    )
    assert state(robot, AC.current_task) == AC.task_idle
    assert "taking up" not in behavior.logs()
    robot.write([(AC.robot1_battery, AC.battery_level, Literal("normal"))])
    wait_for(lambda: state(robot, AC.current_task) == AC.task_attending_patient, 15)
    assert state(robot, AC.attended_person) == AC.patient_ane
    assert state(robot, AC.target_place) == AC.room_101
    assert state(robot, AC.waiting_for, AC.patient_ane) is None
    assert state(robot, AC.postponed_task) is None
    taking_up = "taking up the postponed AttendingPatient for patient_ane"
    wait_for(lambda: taking_up in behavior.logs(), 10, "the behaviour's line")


def test_a_postponement_whose_parts_arrive_apart_is_kept(robot, launch):
    """The behaviour follows its robot's scope: a changeset reaches it in parts, one per key.

    The rule's answer postpones the visit on the patient (`waiting_for`, `postponed_by`)
    and makes the robot idle (`current_task`): on a busy computer the patient's parts
    come first, and a tick sees the robot still with its patient. That is not the
    patient being served again: the postponement must stay.
    """
    launch.start("behavior", "--time-scale", "100")
    robot.write(
        [
            (AC.robot1, AC.attended_person, AC.patient_ane),
            (AC.robot1, AC.requested_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: state(robot, AC.interacting_with) == AC.patient_ane, 15)
    # The patient's half first, as the parts arrive under load.
    robot.write(
        [
            (AC.patient_ane, AC.waiting_for, AC.task_attending_patient),
            (AC.patient_ane, AC.postponed_by, AC.robot1),
        ]
    )
    # Two writes of the count later, the behaviour has ticked with that half in its view.
    counted = float(state(robot, AC.task_elapsed) or 0)
    wait_for(lambda: float(state(robot, AC.task_elapsed) or 0) >= counted + 200, 15)
    assert state(robot, AC.waiting_for, AC.patient_ane) == AC.task_attending_patient
    robot.write(
        [
            (AC.robot1, AC.current_task, AC.task_idle),
            (AC.robot1, AC.postponed_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: state(robot, AC.interacting_with) is None)
    assert state(robot, AC.waiting_for, AC.patient_ane) == AC.task_attending_patient
    assert state(robot, AC.postponed_by, AC.patient_ane) == AC.robot1


def test_tspace_agent_runs_an_agent(robot, server, space_name, tmp_path):
    launcher = Launcher(server.endpoint, space_name, tmp_path)
    proc = AgentProcess("nav_monitor", server.endpoint, space_name, tmp_path)
    proc.argv = tspace_cmd("agent", "nav_monitor", *proc.argv[3:])
    launcher.procs.append(proc.start())
    try:
        robot.write([(AC.robot1, AC.target_place, AC.hall)])
        wait_for(lambda: state(robot, AC.navigation_status) == Literal("navigating"))
        assert proc.stop(signal.SIGINT) == 0
    finally:
        launcher.close()


def test_agents_started_before_the_store_and_the_robot_wait_for_them(tmp_path, space_name):
    """`tspace up` may start agents first: they wait for the store, then for the robot."""
    late = Server(tmp_path / "data")
    launcher = Launcher(late.endpoint, space_name, tmp_path)
    try:
        launcher.start("hw_monitor", "--time-scale", "20")
        launcher.start("nav_monitor", "--time-scale", "20")
        wait_for(lambda: "waiting for the space" in launcher.procs[1].logs())
        late.start()
        with TripleSpace.open(late.endpoint, space=space_name) as ts:
            wait_for(lambda: "connected to space" in launcher.procs[1].logs())
            ts.write(knowledge())
            ts.write([(AC.robot1, AC.target_place, AC.corridor)])
            wait_for(lambda: state(ts, AC.location) == AC.corridor)
            wait_for(lambda: state(ts, AC.actual_mode, AC.robot1_laser) == Literal("active"))
    finally:
        launcher.close()
        late.stop()
