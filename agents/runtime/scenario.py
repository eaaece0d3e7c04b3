"""Scenarios: a story the robots must act out, checked step by step against the space.

A scenario is a list of steps, each a condition on one robot's state that must
become true, in order, within a time limit after the previous one. A step may
first act on the space (assign a task). `tspace up --scenario NAME` runs one;
the paper's example is `battery`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from rdflib import Literal

from agents.runtime.robotview import RobotState, battery_of, read_robots, task_named
from agents.vocabulary import AC

if TYPE_CHECKING:
    from space import SpaceMirror, TripleSpace

STEP_TIMEOUT = 90.0
INTERACTION = ("TouchScreen", "Speaker", "Microphone")
NAVIGATION = ("WheelMotor", "LaserScanner")


@dataclass(frozen=True)
class Step:
    """One thing that must happen.

    Attributes:
        name: what a person should see happen, used in reports.
        check: true once the step has happened.
        act: run once (on the caller's thread of `ScenarioRun.tick`) when the
            step becomes the one awaited, with the space and the robot's name.
    """

    name: str
    check: Callable[[RobotState], bool]
    act: Callable[[TripleSpace, str], None] | None = None


@dataclass(frozen=True)
class Scenario:
    """A named story.

    Attributes:
        name: what `--scenario` calls it.
        steps: what must happen, in order.
        agent_args: options appended per agent name (e.g. a faster clock).
        prepare: run once the space is loaded and before any agent starts, to set
            the stage (with the space and the robot's name).
        finish: run once after the last step, to leave the robot in a state that
            lasts (the battery scenario ends the visit: the robot idles).
    """

    name: str
    steps: tuple[Step, ...]
    agent_args: dict[str, list[str]] = field(default_factory=dict)
    prepare: Callable[[TripleSpace, str], None] | None = None
    finish: Callable[[TripleSpace, str], None] | None = None


def _request(task_type: str, person: str | None = None) -> Callable[[TripleSpace, str], None]:
    """Return an action that requests a task (for a person, if given), as the HMI does."""

    def act(ts: TripleSpace, robot: str) -> None:
        task = task_named(ts.query((None, AC.type, None)), task_type)
        if task is None:
            raise LookupError(f"the space has no task of type {task_type!r}")
        wanted = [(AC[robot], AC.requested_task, task)]
        if person is not None:
            wanted.append((AC[robot], AC.attended_person, AC[person]))
        ts.write(wanted)

    return act


def _battery_at(percent: int, level: str) -> Callable[[TripleSpace, str], None]:
    """Return an action that sets the battery's charge, read by hw_monitor when it starts."""

    def prepare(ts: TripleSpace, robot: str) -> None:
        battery = battery_of(ts.query(None), robot)
        if battery is None:
            raise LookupError(f"robot {robot} has no battery in the space")
        ts.write(
            [
                (battery, AC.charge_percent, Literal(percent)),
                (battery, AC.battery_level, Literal(level)),
            ]
        )

    return prepare


def _devices_saving(robot: RobotState) -> bool:
    kinds = {d.kind for d in robot.devices}
    if not set(INTERACTION + NAVIGATION) <= kinds:
        return False
    return all(d.mode == "stand-by" for d in robot.devices if d.kind in INTERACTION) and all(
        d.mode == "active" for d in robot.devices if d.kind in NAVIGATION
    )


BATTERY = Scenario(
    name="battery",
    steps=(
        Step(
            "robot attends a patient (task AttendingPatient)",
            lambda r: r.task_type == "AttendingPatient",
            _request("AttendingPatient", "patient_ane"),
        ),
        Step("battery drains to very low", lambda r: r.battery == "very low"),
        Step("robot heads to the dock (task GoingToDock)", lambda r: r.task_type == "GoingToDock"),
        Step("mobile base slows to low speed", lambda r: r.speed == "low"),
        Step("screen, speakers, microphone stand-by; wheels, laser stay active", _devices_saving),
        Step(
            "robot reaches the dock and docks (location dock, task Docking)",
            lambda r: r.task_type == "Docking" and r.at_dock,
        ),
        Step("robot charges (task Charging)", lambda r: r.task_type == "Charging"),
        Step("battery charged (level normal or full)", lambda r: r.battery in ("normal", "full")),
        Step(
            "robot back to work (task AttendingPatient)",
            lambda r: r.task_type == "AttendingPatient",
        ),
    ),
    # A simulated minute every two real seconds; the battery starts a little above
    # "very low" so the drain is over before the patient's visit takes too long
    # (AttendingPatient's max_duration), and charges in seconds, not a quarter of an hour.
    agent_args={
        "hw_monitor": ["--time-scale", "30", "--charge-rate", "0.5"],
        "nav_monitor": ["--time-scale", "30"],
        "behavior": ["--time-scale", "30"],
    },
    prepare=_battery_at(13, "low"),
    # The patient's visit never ends by itself: left on, it would overrun, be postponed,
    # taken up again, and so on. The story over, the visit is done and the robot idles.
    finish=_request("Idle"),
)

SCENARIOS = {s.name: s for s in (BATTERY,)}


class ScenarioRun:
    """Follow one robot through a scenario.

    `observe` is called after every changeset (on the mirror's thread) so that a
    state that lasts a single changeset, like Docking, is not missed; `tick` is
    called periodically from the owner's thread to run actions and check time.

    Args:
        scenario: the story.
        robot: the robot's local name.
        on_event: gets one line per completed or failed step (from either thread).
        step_timeout: seconds each step may take after the previous one.
    """

    def __init__(
        self,
        scenario: Scenario,
        robot: str,
        on_event: Callable[[str], None],
        step_timeout: float = STEP_TIMEOUT,
    ) -> None:
        self.scenario = scenario
        self.robot = robot
        self._on_event = on_event
        self._timeout = step_timeout
        self._lock = threading.Lock()
        self._index = 0
        self._acted = -1
        self._finished = False
        self._since = time.monotonic()
        self._started = self._since
        self.failure: str | None = None

    @property
    def finished(self) -> bool:
        """Return whether every step has happened."""
        with self._lock:
            return self._index == len(self.scenario.steps)

    @property
    def finishing(self) -> bool:
        """Return whether every step has happened and the finishing action has not run yet."""
        with self._lock:
            return self._index == len(self.scenario.steps) and not self._finished

    @property
    def progress(self) -> str:
        """Return "step i/n: name" of the step awaited, for the live view."""
        with self._lock:
            steps = self.scenario.steps
            if self._index == len(steps):
                return f"scenario {self.scenario.name}: completed"
            return (
                f"scenario {self.scenario.name}: waiting for step {self._index + 1}/{len(steps)}: "
                f"{steps[self._index].name}"
            )

    def observe(self, robots: list[RobotState]) -> None:
        """Advance past every step that the robots' current states (read off the space) satisfy."""
        robot = next((r for r in robots if r.name == self.robot), None)
        if robot is None:
            return
        with self._lock:
            steps = self.scenario.steps
            # A step's action must have run before the step can count as done.
            while self._index < len(steps) and (
                steps[self._index].act is None or self._acted == self._index
            ):
                if not steps[self._index].check(robot):
                    break
                now = time.monotonic()
                self._index += 1
                self._on_event(
                    f"scenario {self.scenario.name}: step {self._index}/{len(steps)} done: "
                    f"{steps[self._index - 1].name} ({now - self._started:.1f} s)"
                )
                self._since = now

    def tick(self, ts: TripleSpace, mirror: SpaceMirror) -> None:
        """Run the awaited step's action once, then fail it if it is overdue.

        Blocks while the action writes to the space. Sets `failure` (and reports
        it) when the awaited step did not happen within the step timeout.
        """
        with self._lock:
            index = self._index
            finish = index == len(self.scenario.steps) and not self._finished
            if finish:
                self._finished = True
        if finish and self.scenario.finish is not None:
            self.scenario.finish(ts, self.robot)
            self._on_event(f"scenario {self.scenario.name}: over, the robot carries on")
        with self._lock:
            if index == len(self.scenario.steps) or self.failure is not None:
                return
            step = self.scenario.steps[index]
            pending = step.act is not None and self._acted < index
            overdue = time.monotonic() - self._since > self._timeout
        if pending:
            assert step.act is not None
            step.act(ts, self.robot)
            with self._lock:
                self._acted = index
                self._since = time.monotonic()
            self.observe(read_robots(mirror.copy()))
        elif overdue:
            self.failure = (
                f"step {index + 1}/{len(self.scenario.steps)} did not happen within "
                f"{self._timeout:.0f} s: {step.name}"
            )
            self._on_event(f"scenario {self.scenario.name}: FAILED: {self.failure}")
