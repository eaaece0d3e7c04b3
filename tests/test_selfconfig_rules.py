"""The self-configuration rules, run by the engine on the ontology and the hospital robot.

Each test sets a situation the way the agents would write it and checks the
conclusion a user would notice on the robot.
"""

from pathlib import Path

import pytest
from rdflib import RDF, Literal, Namespace
from rdflib.term import Node
from rulestate import RuledState

from space.reasoning import read_graph

REPO = Path(__file__).resolve().parents[1]
AC = Namespace("https://w3id.org/tspace/selfconfig#")


class Robot(RuledState):
    """The engine loaded with ac:robot1 (`set`, `get`, `fired`: see `RuledState`)."""

    def __init__(self) -> None:
        super().__init__(
            "selfconfig.rules", read_graph([REPO / "ontology" / "robots" / "hospital.ttl"])
        )


@pytest.fixture
def robot() -> Robot:
    return Robot()


def volume(robot: Robot) -> str:
    return str(robot.get(AC.robot1_speakers, AC.volume))


def modes(robot: Robot, *devices: Node) -> list[str]:
    return [str(robot.get(d, AC.running_mode)) for d in devices]


INTERACTION = (AC.robot1_screen, AC.robot1_speakers, AC.robot1_microphone)
NAVIGATION_ACTUATORS = (AC.robot1_base, AC.robot1_wheels)

# 1. Interaction


def test_volume_follows_the_noise_of_the_place(robot):
    assert volume(robot) == "normal"
    robot.set(AC.robot1, AC.location, AC.hall)
    assert volume(robot) == "high"
    assert "loud_voice_in_noisy_place" in robot.fired
    robot.set(AC.robot1, AC.location, AC.room_102)
    assert volume(robot) == "low"
    robot.set(AC.robot1, AC.location, AC.corridor)
    assert volume(robot) == "normal"


def test_a_hearing_impaired_patient_is_spoken_to_loudly_even_in_a_quiet_room(robot):
    robot.set(AC.robot1, AC.location, AC.room_101)
    assert volume(robot) == "low"
    robot.set(AC.robot1, AC.interacting_with, AC.patient_ane)
    assert volume(robot) == "high"
    robot.set(AC.robot1, AC.interacting_with, None)
    assert volume(robot) == "low"


def test_screen_adapts_to_the_patient_profile_and_back(robot):
    robot.set(AC.robot1, AC.interacting_with, AC.patient_jon)
    assert robot.get(AC.robot1_screen, AC.font_size) == Literal("large")
    assert robot.get(AC.robot1_screen, AC.button_press_time) == Literal("normal")
    robot.set(AC.robot1, AC.interacting_with, AC.patient_ane)
    assert robot.get(AC.robot1_screen, AC.font_size) == Literal("normal")
    assert robot.get(AC.robot1_screen, AC.button_press_time) == Literal("long")
    robot.set(AC.robot1, AC.interacting_with, None)
    assert robot.get(AC.robot1_screen, AC.button_press_time) == Literal("normal")


# 2. Tasks


def test_guiding_is_aborted_on_low_battery_and_the_robot_says_why(robot):
    robot.set(AC.robot1, AC.current_task, AC.task_guiding)
    robot.set(AC.robot1_battery, AC.battery_level, Literal("low"))
    assert robot.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert "stop guiding" in str(robot.get(AC.robot1, AC.announcement))


def test_other_work_goes_on_with_a_low_battery(robot):
    robot.set(AC.robot1, AC.current_task, AC.task_attending_patient)
    robot.set(AC.robot1_battery, AC.battery_level, Literal("low"))
    assert robot.get(AC.robot1, AC.current_task) == AC.task_attending_patient


def test_a_task_taking_too_long_is_postponed_for_its_person_and_announced(robot):
    robot.set(AC.robot1, AC.current_task, AC.task_attending_patient)
    robot.set(AC.robot1, AC.interacting_with, AC.patient_ane)
    robot.set(AC.robot1, AC.task_elapsed, Literal(595))
    assert robot.get(AC.robot1, AC.current_task) == AC.task_attending_patient
    robot.set(AC.robot1, AC.task_elapsed, Literal(605))
    assert robot.get(AC.robot1, AC.current_task) == AC.task_idle
    assert robot.get(AC.robot1, AC.postponed_task) == AC.task_attending_patient
    # Kept with the patient, not only on the task every robot shares: whoever the robot
    # serves next, this visit is still Ane's.
    assert robot.get(AC.patient_ane, AC.waiting_for) == AC.task_attending_patient
    assert robot.get(AC.patient_ane, AC.postponed_by) == AC.robot1
    assert "AttendingPatient took too long" in str(robot.get(AC.robot1, AC.announcement))
    robot.set(AC.robot1, AC.interacting_with, AC.patient_jon)
    assert robot.get(AC.patient_ane, AC.waiting_for) == AC.task_attending_patient
    assert robot.get(AC.patient_jon, AC.waiting_for) is None


def test_going_to_the_dock_is_never_postponed(robot):
    robot.set(AC.robot1, AC.current_task, AC.task_going_to_dock)
    robot.set(AC.robot1, AC.task_elapsed, Literal(1000))
    assert robot.get(AC.robot1, AC.current_task) == AC.task_going_to_dock


# 3. Resources


def test_low_battery_puts_unneeded_interaction_devices_on_stand_by(robot):
    robot.set(AC.robot1_battery, AC.battery_level, Literal("low"))
    assert modes(robot, *INTERACTION) == ["stand-by"] * 3
    assert modes(robot, *NAVIGATION_ACTUATORS, AC.robot1_laser) == ["active"] * 3
    robot.set(AC.robot1, AC.interacting_with, AC.visitor_miren)
    assert modes(robot, *INTERACTION) == ["active"] * 3
    robot.set(AC.robot1, AC.interacting_with, None)
    assert modes(robot, *INTERACTION) == ["stand-by"] * 3
    robot.set(AC.robot1_battery, AC.battery_level, Literal("normal"))
    assert modes(robot, *INTERACTION) == ["active"] * 3


def test_very_low_battery_keeps_interaction_on_stand_by_even_with_someone_there(robot):
    robot.set(AC.robot1, AC.interacting_with, AC.visitor_miren)
    robot.set(AC.robot1_battery, AC.battery_level, Literal("very low"))
    assert modes(robot, *INTERACTION) == ["stand-by"] * 3
    assert robot.get(AC.robot1_base, AC.motion_speed) == Literal("low")
    assert robot.get(AC.robot1, AC.current_task) == AC.task_going_to_dock


def test_a_motor_error_disables_navigation_until_it_is_repaired(robot):
    robot.set(AC.robot1_wheels, AC.fault, Literal("error"))
    assert robot.get(AC.robot1_navigation, AC.skill_status) == Literal("disabled")
    assert modes(robot, *NAVIGATION_ACTUATORS) == ["disabled"] * 2
    assert modes(robot, AC.robot1_laser) == ["active"]
    assert "wheel motor failed" in str(robot.get(AC.robot1, AC.announcement))
    assert (AC.robot1_wheels, RDF.type, AC.FaultyDevice) in robot.engine.graph
    assert (AC.robot1_base, RDF.type, AC.UnavailableDevice) in robot.engine.graph
    robot.set(AC.robot1_wheels, AC.fault, Literal("none"))
    assert robot.get(AC.robot1_navigation, AC.skill_status) == Literal("enabled")
    assert modes(robot, *NAVIGATION_ACTUATORS) == ["active"] * 2
    assert (AC.robot1_wheels, RDF.type, AC.FaultyDevice) not in robot.engine.graph
    said = str(robot.get(AC.robot1, AC.announcement))
    assert "cannot move" not in said
    assert said == "My wheel motors work again: I can move."


def test_a_newer_announcement_is_not_replaced_when_the_motor_is_repaired(robot):
    robot.set(AC.robot1_wheels, AC.fault, Literal("error"))
    robot.set(AC.robot1, AC.announcement, Literal("Visiting hours are over."))
    robot.set(AC.robot1_wheels, AC.fault, Literal("none"))
    assert robot.get(AC.robot1, AC.announcement) == Literal("Visiting hours are over.")


# 4. Software


def test_navigation_slows_down_for_a_wheelchair_user_and_speeds_up_after(robot):
    robot.set(AC.robot1, AC.interacting_with, AC.patient_jon)
    assert robot.get(AC.robot1_base, AC.motion_speed) == Literal("low")
    robot.set(AC.robot1, AC.interacting_with, None)
    assert robot.get(AC.robot1_base, AC.motion_speed) == Literal("normal")


def test_speed_stays_low_while_the_battery_is_very_low(robot):
    robot.set(AC.robot1, AC.interacting_with, AC.patient_jon)
    robot.set(AC.robot1_battery, AC.battery_level, Literal("very low"))
    robot.set(AC.robot1, AC.interacting_with, None)
    assert robot.get(AC.robot1_base, AC.motion_speed) == Literal("low")
    robot.set(AC.robot1_battery, AC.battery_level, Literal("low"))
    assert robot.get(AC.robot1_base, AC.motion_speed) == Literal("normal")


def test_obstacle_avoidance_is_cautious_when_surrounded(robot):
    robot.set(AC.robot1_laser, AC.obstacles, Literal("surrounded"))
    assert robot.get(AC.robot1_base, AC.obstacle_avoidance) == Literal("cautious")
    robot.set(AC.robot1_laser, AC.obstacles, Literal("clear"))
    assert robot.get(AC.robot1_base, AC.obstacle_avoidance) == Literal("normal")


def test_why_names_the_rule_and_its_premises(robot):
    robot.set(AC.robot1, AC.interacting_with, AC.patient_jon)
    why = robot.engine.why((AC.robot1, AC.audience_profile, AC.profile_wheelchair))
    assert why is not None and why.rule == "audience_profile"
    assert (AC.robot1, AC.interacting_with, AC.patient_jon) in why.premises
