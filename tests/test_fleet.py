"""A fleet in one space, as processes: a real store, reasoners and simulated robots.

Two hospital robots share two docks (one out of service) and a supermarket
guide robot works in the same space. The robots' agents run in crews
(`agents.crew`): the robots that must charge fast, the others ten times
slower so that they do not run low themselves during a test. Each test runs with one
reasoner for the fleet and with one reasoner per robot: both must give the
same fleet. (At that pace a task's `ac:max_duration` passes in seconds, so the
tests look at what happens before the rules postpone a task.)
"""

import threading
from dataclasses import dataclass

import pytest
from agentprocs import REPO, value
from rdflib import Graph, Literal, Namespace
from rdflib.term import Node

from conftest import AC_NS, wait_for

AC = Namespace(AC_NS)
ROBOTS = REPO / "ontology" / "robots"
WAITING = Literal("All docks are taken: I am waiting for one to be free.")
FAST = ("--time-scale", "300")  # a charge takes about three seconds
SLOW = ("--time-scale", "30")  # 80 % of charge lasts a minute and a half


@dataclass(frozen=True)
class Record:
    """One changeset seen in the space."""

    id: str
    agent: str
    cause: str | None
    added: tuple
    removed: tuple


class Recorder:
    """Every changeset of the space, in order, to check what caused what."""

    def __init__(self, ts) -> None:
        self._lock = threading.Lock()
        self._records: list[Record] = []
        ts.subscribe(None, self._on_change)

    def _on_change(self, change) -> None:
        record = Record(change.id, change.agent, change.cause, change.added, change.removed)
        with self._lock:
            self._records.append(record)

    @property
    def records(self) -> list[Record]:
        with self._lock:
            return list(self._records)

    def added(self, s: Node | None, p: Node, o: Node | None = None) -> list[Record]:
        """Return the changesets that added a matching triple."""
        return [
            r
            for r in self.records
            if any(
                (s is None or t[0] == s) and t[1] == p and (o is None or t[2] == o) for t in r.added
            )
        ]

    def commands_from_other_robots(self, robot: str, devices: list[Node]) -> list[str]:
        """Return the conclusions about `robot`'s devices caused by another robot's agents."""
        by_id = {r.id: r for r in self.records}
        wrong = []
        for record in self.records:
            cause = by_id.get(record.cause or "")
            if cause is None or cause.agent == "test" or cause.agent.endswith(f".{robot}"):
                continue
            wrong += [f"{t} <- {cause.agent}" for t in record.added if t[0] in devices]
        return wrong


@pytest.fixture(params=["one reasoner", "a reasoner per robot"])
def reasoners(request) -> str:
    return request.param


def start_fleet(
    ts, launch, reasoners: str, situation: list, fast: str = "robot1,robot2"
) -> Recorder:
    """Write the fleet and a situation into the space, start reasoners and crews.

    The robots in `fast` live 300 times faster than real time, the others 30 times.
    """
    knowledge = Graph().parse(REPO / "ontology" / "selfconfig.ttl")
    for name in ("common.ttl", "hospital_fleet.ttl", "supermarket.ttl"):
        knowledge.parse(ROBOTS / name)
    ts.write(knowledge)
    ts.write(situation)  # after the ontology: the store knows what is single-valued
    recorder = Recorder(ts)
    rules = ("--rules", str(REPO / "rules" / "fleet.rules"))
    if reasoners == "one reasoner":
        launch.start("reasoner", *rules)
    else:
        for robot in ("robot1", "robot2", "guide1"):
            launch.start("reasoner", *rules, "--robot", robot, "--per-robot")
    launch.start("crew", "--robots", fast, *FAST)
    others = [r for r in ("robot1", "robot2", "guide1") if r not in fast.split(",")]
    launch.start("crew", "--robots", ",".join(others), *SLOW)
    return recorder


def devices(ts, robot: str) -> list[Node]:
    return sorted(ts.query((AC[robot], AC.has_device, None)).objects())


def test_one_dock_free_two_robots_to_charge_one_charges_the_other_waits(ts, launch, reasoners):
    recorder = start_fleet(
        ts,
        launch,
        reasoners,
        [
            (AC.dock2, AC.dock_status, Literal("out of service")),
            (AC.robot1_battery, AC.charge_percent, Literal(11)),
            (AC.robot2_battery, AC.charge_percent, Literal(11)),
        ],
    )
    # Both drain to "very low" within a second; whoever is second must wait.
    waited = wait_for(lambda: recorder.added(None, AC.announcement, WAITING), 30, "a robot waits")
    second = next(t[0] for t in waited[0].added if t[1:] == (AC.announcement, WAITING))
    first = AC.robot2 if second == AC.robot1 else AC.robot1
    # With a reasoner per robot, the first's claim may be written after the second's wait.
    wait_for(lambda: recorder.added(first, AC.dock, AC.dock1), 10, "the first robot's claim")

    # The first charges and leaves; in the same changeset the second gets the dock.
    handed = wait_for(lambda: recorder.added(second, AC.dock, AC.dock1), 30, "the dock freed")[0]
    assert (first, AC.dock, AC.dock1) in handed.removed
    wait_for(lambda: value(ts, second, AC.current_task) == AC.task_charging, 20)
    wait_for(lambda: value(ts, second, AC.current_task) == AC.task_idle, 30)
    wait_for(lambda: value(ts, AC.dock1, AC.dock_status) == Literal("free"))
    assert value(ts, AC.dock2, AC.dock_status) == Literal("out of service")
    assert not recorder.added(None, AC.dock, AC.dock2)

    # The supermarket robot in the same space was never commanded by them.
    assert value(ts, AC.guide1, AC.current_task) == AC.task_idle
    assert value(ts, AC.guide1, AC.dock) is None
    for device in (AC.guide1_screen, AC.guide1_speakers, AC.guide1_barcode):
        assert value(ts, device, AC.running_mode) == Literal("active")
    for robot in ("robot1", "robot2", "guide1"):
        assert recorder.commands_from_other_robots(robot, devices(ts, robot)) == []


def test_a_patient_is_handed_over_when_its_robot_leaves_to_charge(ts, launch, reasoners):
    recorder = start_fleet(
        ts,
        launch,
        reasoners,
        [
            (AC.robot1, AC.current_task, AC.task_attending_patient),
            (AC.robot1, AC.attended_person, AC.patient_ane),
            (AC.robot1, AC.location, AC.room_101),
            (AC.robot1, AC.position_x, Literal(2.0)),
            (AC.robot1, AC.position_y, Literal(12.0)),
            (AC.robot1_battery, AC.charge_percent, Literal(11)),
        ],
        fast="robot1",  # robot2 must not run low itself before the test is over
    )
    # robot1 runs low beside Ane: robot2, idle in the therapy room, comes to her.
    wait_for(lambda: value(ts, AC.robot2, AC.attended_person) == AC.patient_ane, 30)
    wait_for(lambda: value(ts, AC.robot2, AC.current_task) == AC.task_attending_patient, 10)
    wait_for(lambda: value(ts, AC.robot2, AC.location) == AC.room_101, 10)
    told = recorder.added(AC.robot1, AC.announcement)
    assert any("another robot will look after you" in str(t[2]) for r in told for t in r.added)
    assert value(ts, AC.patient_ane, AC.handed_over_by) is None
    # Charged, robot1 does not go back to a patient who is looked after.
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle, 30)
    assert value(ts, AC.robot1, AC.attended_person) is None
    assert not recorder.added(AC.robot1, AC.current_task, AC.task_attending_patient)
    wait_for(lambda: value(ts, AC.dock1, AC.dock_status) == Literal("free"))
    for robot in ("robot1", "robot2", "guide1"):
        assert recorder.commands_from_other_robots(robot, devices(ts, robot)) == []
