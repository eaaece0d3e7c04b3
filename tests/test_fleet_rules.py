"""The fleet rules on the engine: docks shared by a fleet, patients handed over.

The space holds two hospital robots (two docks) and a supermarket guide robot
(one dock). Each test sets a situation the way the agents would write it and
checks what a user would notice: where each robot goes, who looks after whom.
The last tests add rules/presence.rules, as deployed: a robot whose agents are
all gone (`ac:presence "gone"`, the fleet monitor's fact) and back.
"""

from pathlib import Path

import pytest
from rdflib import RDF, Graph, Literal, Namespace
from rdflib.term import Node
from rulestate import RuledState

from agents.sim.fleet import clone_robot, fleet_description
from space.reasoning import read_graph

REPO = Path(__file__).resolve().parents[1]
ROBOTS = REPO / "ontology" / "robots"
AC = Namespace("https://w3id.org/tspace/selfconfig#")
WAITING = Literal("All docks are taken: I am waiting for one to be free.")
DOCK_FREE = Literal("A dock is free now: I am going to charge.")
INTERACTION = ("screen", "speakers", "microphone")


class Fleet(RuledState):
    """The engine with the fleet rules (`set`, `get`, `fired`: see `RuledState`).

    With `presence`, also rules/presence.rules, as the fleet's reasoner runs them.
    """

    def __init__(
        self,
        *extra: Graph,
        files: tuple[str, ...] = ("hospital_fleet.ttl",),
        presence: bool = False,
    ) -> None:
        data = read_graph([ROBOTS / "common.ttl", *(ROBOTS / f for f in files)])
        for graph in extra:
            data += graph
        super().__init__(("fleet.rules", *(["presence.rules"] if presence else [])), data)

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

    def presence(self, robot: str, value: str) -> None:
        """Mark a robot "gone" or "present", as the fleet monitor does."""
        self.set(AC[robot], AC.presence, Literal(value))

    def available(self) -> set[str]:
        """Return the robots the rules would send to a waiting patient."""
        robots = self.engine.graph.subjects(RDF.type, AC.AvailableRobot)
        return {str(r).removeprefix(str(AC)) for r in robots}


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


def fleet_with_robot3(*, presence: bool = True) -> Fleet:
    """Return the fleet with a third hospital robot in room 102, next to Ane's room 101."""
    hospital = Graph().parse(ROBOTS / "hospital_fleet.ttl")
    robot3 = clone_robot(hospital, AC.robot1, "robot3", place=AC.room_102)
    return Fleet(robot3, files=("hospital_fleet.ttl", "supermarket.ttl"), presence=presence)


def test_a_gone_robot_is_never_sent_to_a_patient_and_is_again_once_back():
    fleet = fleet_with_robot3()
    assert fleet.available() == {"robot1", "robot2", "robot3", "guide1"}
    fleet.presence("robot3", "gone")  # the nearest to Ane's room
    assert fleet.available() == {"robot1", "robot2", "guide1"}
    fleet.at("robot1", AC.room_101)
    fleet.attend("robot1", AC.patient_ane)

    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot3, AC.attended_person) is None
    assert fleet.get(AC.robot3, AC.requested_task) is None
    assert fleet.get(AC.robot2, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot2, AC.requested_task) == AC.task_attending_patient

    # Back, it is counted on again: the next patient handed over is its.
    fleet.presence("robot3", "present")
    assert "robot3" in fleet.available()
    fleet.task("robot2", "attending_patient")
    fleet.battery("robot2", "very low")
    assert fleet.get(AC.robot3, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot3, AC.requested_task) == AC.task_attending_patient


def test_a_robot_gone_before_taking_a_patient_over_hands_them_on():
    fleet = fleet_with_robot3()
    fleet.at("robot1", AC.room_101)
    fleet.attend("robot1", AC.patient_ane)
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot3, AC.requested_task) == AC.task_attending_patient

    # robot3 vanishes before its behaviour agent took the request.
    fleet.presence("robot3", "gone")
    assert fleet.get(AC.robot2, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot2, AC.requested_task) == AC.task_attending_patient
    assert fleet.get(AC.robot3, AC.attended_person) is None
    assert fleet.get(AC.robot3, AC.requested_task) is None  # nothing to take when back
    assert fleet.get(AC.patient_ane, AC.handed_over_by) is None


def test_a_robot_gone_while_attending_a_patient_is_idle_and_available_when_back():
    fleet = Fleet(files=("hospital_fleet.ttl", "supermarket.ttl"), presence=True)
    fleet.attend("robot1", AC.patient_ane)
    fleet.presence("robot1", "gone")
    assert fleet.get(AC.robot2, AC.attended_person) == AC.patient_ane
    assert fleet.get(AC.robot1, AC.attended_person) is None
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_idle
    assert "robot1" not in fleet.available()

    fleet.presence("robot1", "present")
    assert "robot1" in fleet.available()
    assert fleet.get(AC.robot2, AC.attended_person) == AC.patient_ane


def test_a_gone_robots_dock_is_freed_and_it_waits_for_one_when_back():
    fleet = Fleet(presence=True)
    fleet.set(AC.dock2, AC.dock_status, Literal("out of service"))
    fleet.battery("robot1", "very low")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1
    fleet.battery("robot2", "very low")
    assert fleet.get(AC.robot2, AC.announcement) == WAITING

    fleet.presence("robot1", "gone")  # on its way to dock 1
    assert fleet.get(AC.robot1, AC.dock) is None
    assert fleet.get(AC.robot2, AC.dock) == AC.dock1
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("occupied")
    assert fleet.get(AC.robot2, AC.announcement) == DOCK_FREE

    # Back, it still has to charge: it waits for the dock robot2 took.
    fleet.presence("robot1", "present")
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock
    assert fleet.get(AC.robot1, AC.dock) is None
    assert fleet.get(AC.robot1, AC.announcement) == WAITING
    fleet.task("robot2", "docking")
    fleet.charge_and_leave("robot2")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1
    assert fleet.get(AC.dock2, AC.dock_status) == Literal("out of service")


def test_a_robot_gone_while_charging_gets_no_dock_until_it_is_back():
    fleet = Fleet(presence=True)
    fleet.battery("robot1", "very low")
    fleet.task("robot1", "docking")
    fleet.task("robot1", "charging")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1

    fleet.presence("robot1", "gone")
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("free")
    assert fleet.get(AC.robot1, AC.dock) is None  # a free dock, but not for a gone robot
    # It lost its dock: when back it must go and get one, not charge nowhere.
    assert fleet.get(AC.robot1, AC.current_task) == AC.task_going_to_dock

    fleet.presence("robot1", "present")
    assert fleet.get(AC.robot1, AC.dock) == AC.dock1
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("occupied")


def test_a_gone_robots_dock_taken_out_of_service_stays_out_of_service():
    fleet = Fleet(presence=True)
    fleet.battery("robot1", "very low")
    fleet.set(AC.dock1, AC.dock_status, Literal("out of service"))
    fleet.presence("robot1", "gone")
    assert fleet.get(AC.robot1, AC.dock) is None
    assert fleet.get(AC.dock1, AC.dock_status) == Literal("out of service")
