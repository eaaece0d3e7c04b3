"""The behaviour machine: the robot's task automaton, connected to the space.

It reads the task the rules or a user set (`ac:current_task`,
`ac:requested_task`), and writes what follows from it: where the robot must go
(`ac:target_place`, which the nav monitor obeys), whom it serves
(`ac:interacting_with`, which interaction rules adapt to), the power cycle
(GoingToDock -> Docking -> Charging -> back to work, `ac:resume_task`), how
long the task has run (`ac:task_started`, `ac:task_elapsed`, which the "task
takes too long" rule watches), and re-planning: a task that rule postponed
(`P ac:waiting_for T ; ac:postponed_by R`) is taken up again, for its person,
once the robot is free. See `agents.automaton` for the decisions.
"""

from __future__ import annotations

import argparse
import sys
import time
from datetime import UTC, datetime
from decimal import Decimal

from rdflib import Literal, URIRef
from rdflib.term import Node

from agents.automaton import DOCKING_TIME, RETRY_AFTER, Plan, Situation, TaskAutomaton
from agents.base import Agent, run_agent
from agents.vocabulary import AC, local_name


class Behavior(Agent):
    """Run the task automaton of a robot: targets, power cycle and task durations."""

    kind = "behavior"
    # Besides its robot: who waits for a task it postponed, in which room, and the task types.
    shared = (AC.postponed_by, AC.waiting_for, AC.room, AC.type)
    ticks_on_reads = True

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.automaton = TaskAutomaton(args.docking_time, args.retry_after)
        self._task: str | None = None
        self._serving: tuple[str, Node] | None = None  # the task and the person it is for
        self._elapsed_written = 0.0

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the automaton's options."""
        parser.add_argument(
            "--docking-time",
            type=float,
            default=DOCKING_TIME,
            metavar="SECONDS",
            help=f"simulated seconds docking takes (default {DOCKING_TIME:g})",
        )
        parser.add_argument(
            "--elapsed-step",
            type=float,
            default=5.0,
            metavar="SECONDS",
            help="granularity of ac:task_elapsed, simulated seconds (default 5)",
        )
        parser.add_argument(
            "--retry-after",
            type=float,
            default=RETRY_AFTER,
            metavar="SECONDS",
            help="simulated seconds idle before a postponed task is taken up again "
            f"(default {RETRY_AFTER:g})",
        )

    def tick(self) -> None:
        """Step the automaton on the current view and write what it decided."""
        waiting = self._waiting()
        plan = self.automaton.step(self._situation(waiting))
        self.set_values(self._values(plan, waiting))

    def _waiting(self) -> URIRef | None:
        """Return a person waiting for a task this robot postponed (the first by name)."""
        people = self.view.subjects(AC.postponed_by, self.robot)
        return next((p for p in people if isinstance(p, URIRef)), None)

    def _situation(self, waiting: URIRef | None) -> Situation:
        v, robot = self.view, self.robot
        person = v.value(robot, AC.attended_person)
        return Situation(
            now=self.clock.now(),
            task=v.task_type(v.value(robot, AC.current_task)),
            # No battery reading (its monitor is gone, rules say so): take no new task.
            requested=None
            if v.value(robot, AC.battery_unknown) is not None
            else v.task_type(v.value(robot, AC.requested_task)),
            location=_name(v.value(robot, AC.location)),
            navigation=v.text(robot, AC.navigation_status),
            battery=v.text(v.device(robot, AC.Battery), AC.battery_level),
            dock=_name(v.value(robot, AC.dock)),
            person_room=_name(v.value(person, AC.room)),
            guide_destination=_name(v.value(robot, AC.guide_destination)),
            elapsed=v.number(robot, AC.task_elapsed),
            resume=v.task_type(v.value(robot, AC.resume_task)),
            postponed=v.task_type(v.value(waiting, AC.waiting_for)),
            postponed_room=_name(v.value(waiting, AC.room)),
        )

    def _values(self, plan: Plan, waiting: URIRef | None) -> dict[tuple[Node, Node], Node | None]:
        robot = self.robot
        task = self.view.task_of_type(plan.task)
        resume = self.view.task_of_type(plan.resume) if plan.resume else None
        person = self.view.value(robot, AC.attended_person) if plan.interacting else None
        values: dict[tuple[Node, Node], Node | None]
        if plan.take_postponed and waiting is not None:
            values = self._take_postponed(plan, waiting)
            person = values.get((robot, AC.attended_person), person)
        elif (
            person is not None
            and (plan.task, person) != self._serving
            and (person, AC.postponed_by, robot) in self.view
        ):
            # Served again, so no longer waiting; only when the service begins: this scoped
            # agent receives a postponement in parts, the person's maybe a tick before the
            # robot's idle task, and that tick must not take the old service for a new one.
            values = self._settled(person)
        else:
            values = {}
        self._serving = None if person is None else (plan.task, person)
        values |= {
            (robot, AC.target_place): URIRef(plan.target) if plan.target else None,
            (robot, AC.interacting_with): person,
            (robot, AC.resume_task): resume,
        }
        if task is not None:
            values[(robot, AC.current_task)] = task
        if plan.take_request:
            values[(robot, AC.requested_task)] = None
        if plan.task != self._task:
            if self._task is not None:
                self.log.info("task %s -> %s", self._task, plan.task)
                values[(robot, AC.task_started)] = Literal(datetime.now(UTC))
            self._task = plan.task
            values.update(self._elapsed(plan.elapsed))
        elif time.monotonic() - self._elapsed_written >= 1.0:
            values.update(self._elapsed(plan.elapsed))
        return values

    def _take_postponed(self, plan: Plan, waiting: URIRef) -> dict[tuple[Node, Node], Node | None]:
        """Return what taking a postponed task up (or giving it up) writes, and log it."""
        postponed = self.view.task_type(self.view.value(waiting, AC.waiting_for))
        values = self._settled(waiting)
        if plan.task == postponed:
            self.log.info("taking up the postponed %s for %s", postponed, local_name(waiting))
            values[(self.robot, AC.attended_person)] = waiting
        else:
            self.log.info(
                "giving up the postponed %s for %s: it cannot be resumed",
                postponed,
                local_name(waiting),
            )
        return values

    def _settled(self, person: Node) -> dict[tuple[Node, Node], Node | None]:
        """Return the removal of a person's postponed task, and of the robot's record of it."""
        v, robot = self.view, self.robot
        others = {
            t
            for p in v.subjects(AC.postponed_by, robot)
            if p != person
            for t in v.objects(p, AC.waiting_for)
        }
        values: dict[tuple[Node, Node], Node | None] = {
            (person, AC.waiting_for): None,
            (person, AC.postponed_by): None,
        }
        if len(others) <= 1:  # the robot's record can only be set to one value or none
            values[(robot, AC.postponed_task)] = next(iter(others), None)
        return values

    def _elapsed(self, elapsed: float) -> dict[tuple[Node, Node], Node | None]:
        """Return the elapsed time on a coarse grid (rules re-run on every write of it)."""
        self._elapsed_written = time.monotonic()
        step = self.args.elapsed_step
        return {(self.robot, AC.task_elapsed): Literal(Decimal(int(elapsed // step * step)))}


def _name(node: Node | None) -> str | None:
    return None if node is None else str(node)


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the behaviour machine (see `--help`)."""
    return run_agent(Behavior, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
