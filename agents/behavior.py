"""The behaviour machine: the robot's task automaton, connected to the space.

It reads the task the rules or a user set (`ac:current_task`,
`ac:requested_task`), and writes what follows from it: where the robot must go
(`ac:target_place`, which the nav monitor obeys), whom it serves
(`ac:interacting_with`, which interaction rules adapt to), the power cycle
(GoingToDock -> Docking -> Charging -> back to work, `ac:resume_task`), and how
long the task has run (`ac:task_started`, `ac:task_elapsed`, which the "task
takes too long" rule watches). See `agents.automaton` for the decisions.
"""

from __future__ import annotations

import argparse
import sys
import time
from datetime import UTC, datetime
from decimal import Decimal

from rdflib import Literal, URIRef
from rdflib.term import Node

from agents.automaton import DOCKING_TIME, Plan, Situation, TaskAutomaton
from agents.base import Agent, run_agent
from agents.view import AC


class Behavior(Agent):
    """Run the task automaton of a robot: targets, power cycle and task durations."""

    kind = "behavior"

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.automaton = TaskAutomaton(args.docking_time)
        self._task: str | None = None
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

    def tick(self) -> None:
        """Step the automaton on the current view and write what it decided."""
        plan = self.automaton.step(self._situation())
        self.set_values(self._values(plan))

    def _situation(self) -> Situation:
        v, robot = self.view, self.robot
        person = v.value(robot, AC.attended_person)
        return Situation(
            now=self.clock.now(),
            task=v.task_type(v.value(robot, AC.current_task)),
            requested=v.task_type(v.value(robot, AC.requested_task)),
            location=_name(v.value(robot, AC.location)),
            navigation=v.text(robot, AC.navigation_status),
            battery=v.text(v.device(robot, AC.Battery), AC.battery_level),
            dock=_name(v.value(robot, AC.dock)),
            person_room=_name(v.value(person, AC.room)),
            guide_destination=_name(v.value(robot, AC.guide_destination)),
            elapsed=v.number(robot, AC.task_elapsed),
            resume=v.task_type(v.value(robot, AC.resume_task)),
        )

    def _values(self, plan: Plan) -> dict[tuple[Node, Node], Node | None]:
        robot = self.robot
        task = self.view.task_of_type(plan.task)
        resume = self.view.task_of_type(plan.resume) if plan.resume else None
        person = self.view.value(robot, AC.attended_person) if plan.interacting else None
        values: dict[tuple[Node, Node], Node | None] = {
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

    def _elapsed(self, elapsed: float) -> dict[tuple[Node, Node], Node | None]:
        """Return the elapsed time on a coarse grid (rules re-run on every write of it)."""
        self._elapsed_written = time.monotonic()
        step = self.args.elapsed_step
        return {(self.robot, AC.task_elapsed): Literal(Decimal(int(elapsed // step * step)))}


def _name(node: Node | None) -> str | None:
    return None if node is None else str(node)


def main(argv: list[str] | None = None) -> int:
    """Run the behaviour machine (see `--help`)."""
    return run_agent(Behavior, argv)


if __name__ == "__main__":
    sys.exit(main())
