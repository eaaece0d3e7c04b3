"""The fleet rules on the engine: docks shared by a fleet, patients handed over.

The space holds two hospital robots (two docks) and a supermarket guide robot
(one dock). Each test sets a situation the way the agents would write it and
checks what a user would notice: where each robot goes, who looks after whom.
"""

from pathlib import Path

import pytest
from rdflib import Graph, Literal, Namespace
from rdflib.term import Node
from rulestate import RuledState

from agents.sim.fleet import clone_robot, fleet_description
from space.reasoning import read_graph

REPO = Path(__file__).resolve().parents[1]
ROBOTS = REPO / "ontology" / "robots"
AC = Namespace("https://w3id.org/tspace/selfconfig#")
WAITING = Literal("All docks are taken: I am waiting for one to be free.")
INTERACTION = ("screen", "speakers", "microphone")


class Fleet(RuledState):
    """The engine with the fleet rules (`set`, `get`, `fired`: see `RuledState`)."""

    def __init__(self, *extra: Graph, files: tuple[str, ...] = ("hospital_fleet.ttl",)) -> None:
        data = read_graph([ROBOTS / "common.ttl", *(ROBOTS / f for f in files)])
        for graph in extra:
            data += graph
        super().__init__("fleet.rules", data)

    def battery(self, robot: str, level: str) -> None:
        self.set(AC[f"{robot}_battery"], AC.battery_level, Literal(level))

    def task(self, robot: str, task: str) -> None:
        self.set(AC[robot], AC.current_task, AC[f"task_{task}"])

    def at(self, robot: str, place: Node) -> None:
        """Put a robot at a place, as the nav monitor reports it."""
        self.set(AC[robot], AC.location, place)
        self.set(AC[robot], AC.position_x, self.get(place, AC.map_x))
        self.set(AC[robot], AC.position_y, self.get(place, AC.map_y))

    def attend(self, robot: str, patient: Node) -> None:
        """Have a robot attend a patient, as the HMI's request and the behaviour agent do."""
        self.task(robot, "attending_patient")
        self.set(AC[robot], AC.attended_person, patient)
        self.set(AC[robot], AC.interacting_with, patient)

    def charge_and_leave(self, robot: str) -> None:
        """Run the power cycle's end, as the behaviour agent does: charged, then idle."""
        self.battery(robot, "full")
        self.task(robot, "charging")
        self.task(robot, "idle")

    def modes(self, robot: str, *devices: str) -> list[str]:
        return [str(self.get(AC[f"{robot}_{d}"], AC.running_mode)) for d in devices]


@pytest.fixture
def fleet() -> Fleet:
    return Fleet(files=("hospital_fleet.ttl", "supermarket.ttl"))


def test_a_robot_that_must_charge_takes_the_nearest_free_dock_of_its_site(fleet):
    fleet.battery("robot2", "very low")  # in the therapy room, next to dock 2
    assert fleet.get(AC.robot2, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot2, AC.dock) == AC.dock2
    assert fleet.get(AC.dock2, AC.dock_status) == Literal("occupied")
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("free")

    fleet.battery("robot1", "very low")  # in the corridor, nearer to dock 1
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1
    # The supermarket robot charges in the supermarket, whatever the coordinates say.
    fleet.battery("guide1", "very low")
    assert fleet.get(AC.guide1, AC.dock) == AC.market_dock


def test_a_second_robot_goes_to_the_next_free_dock(fleet):
    fleet.at("robot1", AC.therapy_room)
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock2
    fleet.battery("robot2", "very low")  # dock 2 is nearer, but robot1 has it
    assert fleet.get(AC.robot2, AC.dock) == AC.dock1
    assert fleet.fired.count("claim_nearest_free_dock") == 2


def test_with_no_free_dock_the_robot_waits_until_one_is_released(fleet):
    fleet.set(AC.dock2, AC.dock_status, Literal("out of service"))
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1

    fleet.battery("robot2", "very low")
    assert fleet.get(AC.robot2, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot2, AC.dock) is None  # nowhere to drive to: it waits
    assert fleet.get(AC.robot2, AC.announcement) == WAITING

    fleet.task("robot1", "docking")
    fleet.charge_and_leave("robot1")
    assert fleet.get(AC.robot1, AC.dock) is None
    assert fleet.get(AC.robot2, AC.dock) == AC.dock1
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("occupied")
    assert fleet.get(AC.dock2, AC.dock_status) == Literal("out of service")
    assert fleet.get(AC.robot2, AC.announcement) == Literal(
        "A dock is free now: I am going to charge."
    )

    fleet.charge_and_leave("robot2")
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("free")


def test_a_robot_leaves_a_dock_taken_out_of_service_while_it_charged(fleet):
    fleet.battery("robot1", "very low")
    fleet.set(AC.dock1, AC.dock_status, Literal("out of service"))
    fleet.charge_and_leave("robot1")
    assert fleet.get(AC.robot1, AC.dock) is None
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("out of service")
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock2


def test_a_battery_change_on_one_robot_commands_that_robot_only(fleet):
    fleet.battery("robot1", "very low")
    assert fleet.modes("robot1", *INTERACTION) == ["stand-by"] * 3
    assert fleet.get(AC.robot1_base, AC.motion_speed) == Literal("low")
    assert fleet.modes("robot2", *INTERACTION) == ["active"] * 3
    assert fleet.get(AC.robot2_base, AC.motion_speed) == Literal("normal")
    assert fleet.get(AC.robot2, AC.current_task) == AC.task_idle
    assert fleet.modes("guide1", "screen", "speakers", "barcode") == ["active"] * 3


def test_the_guide_robot_with_other_devices_follows_the_same_rules(fleet):
    fleet.battery("guide1", "very low")
    # Its interaction devices, whatever they are, go to stand-by; the shelf scanner does not.
    assert fleet.modes("guide1", "screen", "speakers", "barcode") == ["stand-by"] * 3
    assert fleet.modes("guide1", "shelf_scanner") == ["active"]
    assert fleet.get(AC.guide1_base, AC.motion_speed) == Literal("low")
    assert fleet.modes("robot1", *INTERACTION) == ["active"] * 3


def test_robots_sharing_the_task_individuals_keep_their_own_tasks(fleet):
    fleet.attend("robot2", AC.patient_jon)
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot2, AC.current_task) == AC.task_attending_patient
    # Jon uses a wheelchair: robot2 is slow for him, robot1 for its battery.
    assert fleet.get(AC.robot2_base, AC.motion_speed) == Literal("low")
    fleet.set(AC.robot2, AC.task_elapsed, Literal(700.0))  # over AttendingPatient's 600 s
    assert fleet.get(AC.robot2, AC.current_task) == AC.task_idle
    assert fleet.get(AC.robot2, AC.postponed_task) == AC.task_attending_patient
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot1, AC.postponed_task) is None


def test_a_patient_whose_robot_leaves_for_the_dock_goes_to_the_nearest_free_robot():
    hospital = Graph().parse(ROBOTS / "hospital_fleet.ttl")
    robot3 = clone_robot(hospital, AC.robot1, "robot3", place=AC.room_102)
    fleet = Fleet(robot3, files=("hospital_fleet.ttl", "supermarket.ttl"))
    fleet.at("robot1", AC.room_101)
    fleet.attend("robot1", AC.patient_ane)
    fleet.at("guide1", AC.market_entrance)  # (2, 10): next to room 101 (2, 12) on paper

    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot1, AC.attended_person) is None
    assert "another robot will look after you" in str(fleet.get(AC.robot1, AC.announcement))
    # robot3 in room 102 is nearer to Ane's room 101 than robot2 in the therapy room.
    assert fleet.get(AC.robot3, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot3, AC.requested_task) == AC.task_attending_patient
    assert fleet.get(AC.robot2, AC.requested_task) is None
    assert fleet.get(AC.guide1, AC.requested_task) is None
    assert fleet.get(AC.patient_ane, AC.handed_over_by) is None


def test_a_handed_over_patient_waits_for_a_robot_to_become_free(fleet):
    fleet.attend("robot1", AC.patient_ane)
    fleet.battery("robot2", "low")  # not available: it would soon have to charge too
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.patient_ane, AC.handed_over_by) == AC.robot1
    assert fleet.get(AC.robot2, AC.requested_task) is None

    fleet.battery("robot2", "normal")
    assert fleet.get(AC.robot2, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot2, AC.requested_task) == AC.task_attending_patient
    assert fleet.get(AC.patient_ane, AC.handed_over_by) is None


def test_a_lone_robot_keeps_its_own_dock_under_the_fleet_rules():
    fleet = Fleet(files=("hospital.ttl",))
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1
    assert fleet.get(AC.dock1, AC.dock_status) is None
    assert not {r for r in fleet.fired if "dock" in r and r.startswith(("claim", "wait"))}


def test_fifty_generated_robots_each_answer_for_themselves():
    fleet = Fleet(fleet_description(50), files=())
    fleet.battery("robot37", "very low")
    assert fleet.get(AC.robot37, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot37, AC.dock) in (AC.dock1, AC.dock2)
    assert fleet.modes("robot37", *INTERACTION) == ["stand-by"] * 3
    others = [f"robot{k}" for k in range(1, 51) if k != 37]
    assert {str(fleet.get(AC[r], AC.current_task)) for r in others} == {str(AC.task_idle)}
    assert {m for r in others for m in fleet.modes(r, *INTERACTION)} == {"active"}
