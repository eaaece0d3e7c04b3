"""The robot's task automaton (the paper's behavior machine), free of any I/O.

Tasks come from two sources: users (`ac:requested_task`, through the HMI) and
the reasoner (`ac:current_task` written by rules). As in the paper, the task in
the space wins: whatever the automaton was doing, a task the rules set becomes
its task. The automaton adds what rules do not say: where each task goes, the
power cycle GoingToDock -> Docking -> Charging -> back to the interrupted work,
taking a postponed task up again once the robot is free, and how long the
current task has run.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

POWER_TASKS = ("GoingToDock", "Docking", "Charging")
WORK_TASKS = ("AttendingPatient", "Guiding")
# Work that makes sense to resume after charging; a guided person will not have waited.
RESUMABLE = ("AttendingPatient",)
LOW_BATTERY = ("low", "very low")
DOCKING_TIME = 5.0
# Idle this long before a postponed task is taken up again: not at once, or a task
# postponed for taking too long would start over in the same breath.
RETRY_AFTER = 300.0


@dataclass(frozen=True)
class Situation:
    """What the automaton observes, as read from the space (places by name).

    Attributes:
        now: simulated seconds.
        task: type of `ac:current_task`.
        requested: type of `ac:requested_task`, if a user asked for one.
        location: `ac:location` of the robot.
        navigation: `ac:navigation_status`.
        battery: `ac:battery_level`.
        dock: the robot's dock.
        person_room: room of `ac:attended_person`.
        guide_destination: `ac:guide_destination`.
        elapsed: `ac:task_elapsed` in the space (to resume the count after a restart).
        resume: type of `ac:resume_task` in the space (the work to resume after
            charging, for an automaton that restarted meanwhile).
        postponed: type of a task the robot postponed, that a person waits for.
        postponed_room: room of that person.
    """

    now: float
    task: str | None = None
    requested: str | None = None
    location: str | None = None
    navigation: str | None = None
    battery: str | None = None
    dock: str | None = None
    person_room: str | None = None
    guide_destination: str | None = None
    elapsed: float | None = None
    resume: str | None = None
    postponed: str | None = None
    postponed_room: str | None = None


@dataclass(frozen=True)
class Plan:
    """What the automaton wants in the space after a step.

    Attributes:
        task: type of the task the robot performs.
        target: place the robot must drive to, None to stay.
        interacting: whether the robot serves the attended person.
        resume: type of the work task to resume after charging, if any.
        elapsed: simulated seconds the task has run.
        take_request: whether the user's request was handled (remove it).
        take_postponed: whether the postponed task was handled: taken up again (it is
            `task`) or, if it cannot be resumed, given up.
    """

    task: str
    target: str | None
    interacting: bool
    resume: str | None
    elapsed: float
    take_request: bool
    take_postponed: bool = False


class TaskAutomaton:
    """Follows the task in the space and drives the power cycle; see the module docstring."""

    def __init__(
        self, docking_time: float = DOCKING_TIME, retry_after: float = RETRY_AFTER
    ) -> None:
        self.docking_time = docking_time
        self.retry_after = retry_after
        self.task: str | None = None
        self.started = 0.0
        self.resume: str | None = None

    def step(self, s: Situation) -> Plan:
        """Observe the situation and return the plan; never blocks."""
        outside = s.task or "Idle"
        if self.task is None:
            self._enter(outside, s.now - (s.elapsed or 0.0))
            if outside in POWER_TASKS:
                self.resume = s.resume
        elif outside != self.task:
            self._enter(outside, s.now)
        if s.requested is not None:
            if self.task in POWER_TASKS and s.requested in WORK_TASKS:
                self.resume = s.requested
            elif s.requested != self.task:
                self._enter(s.requested, s.now)
        take_postponed = self._free_for_postponed(s)
        if take_postponed and s.postponed in RESUMABLE:
            self._enter(s.postponed, s.now)
            s = replace(s, person_room=s.postponed_room)
        self._advance(s)
        return Plan(
            task=self.task or "Idle",
            target=self._target(s),
            interacting=self.task in WORK_TASKS,
            resume=self.resume,
            elapsed=max(0.0, s.now - self.started),
            take_request=s.requested is not None,
            take_postponed=take_postponed,
        )

    def _free_for_postponed(self, s: Situation) -> bool:
        """Return True if a postponed task can be handled: idle a while, nothing asked, charged."""
        return (
            s.postponed is not None
            and self.task == "Idle"
            and s.requested is None
            and s.battery not in LOW_BATTERY
            and s.now - self.started >= self.retry_after
        )

    def _enter(self, task: str, since: float) -> None:
        if self.task in RESUMABLE and task in POWER_TASKS:
            self.resume = self.task
        elif task in WORK_TASKS:
            self.resume = None
        self.task, self.started = task, since

    def _advance(self, s: Situation) -> None:
        stopped = s.navigation != "navigating"
        if self.task == "GoingToDock" and s.dock is not None and s.location == s.dock and stopped:
            self._enter("Docking", s.now)
        elif self.task == "Docking" and s.now - self.started >= self.docking_time:
            self._enter("Charging", s.now)
        elif self.task == "Charging" and s.battery == "full":
            resume, self.resume = self.resume, None
            if resume == "AttendingPatient" and s.person_room is None:
                resume = None  # the patient was handed over to another robot meanwhile
            self._enter(resume or "Idle", s.now)
        elif self.task == "Guiding" and s.guide_destination is not None:
            if s.location == s.guide_destination and stopped:
                self._enter("Idle", s.now)

    def _target(self, s: Situation) -> str | None:
        if self.task in POWER_TASKS:
            return s.dock
        if self.task == "AttendingPatient":
            return s.person_room
        if self.task == "Guiding":
            return s.guide_destination
        return None
