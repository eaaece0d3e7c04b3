"""The crew: the simulated agents of many robots in one process.

A fleet of fifty simulated robots as one process per agent would be 150 Python
interpreters on a laptop's two cores. The crew runs a hardware monitor, a
navigation monitor and a behaviour machine per robot in one process, over one
Zenoh session, one subscription and one view of the space. The members are the
classes `agents.hw_monitor` & co. run alone, so they decide exactly as they do
there; each writes under its own name and holds its own liveliness token
(`hw_monitor.robot7`), so the space cannot tell the crew from separate processes.

Run: `python -m agents.crew --robots robot1,robot2,guide1 --connect ... --space ...`.
"""

from __future__ import annotations

import argparse
import sys
import time

import zenoh
from rdflib import RDF
from rdflib.term import Node

from agents.base import Agent, run_agent
from agents.behavior import Behavior
from agents.hw_monitor import HwMonitor
from agents.nav_monitor import NavMonitor
from agents.vocabulary import AC
from space import Change, TripleSpace, declare_agent

KINDS: dict[str, type[Agent]] = {
    "hw_monitor": HwMonitor,
    "nav_monitor": NavMonitor,
    "behavior": Behavior,
}


def _names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError("give at least one name")
    return names


def _kinds(text: str) -> list[str]:
    kinds = _names(text)
    unknown = [k for k in kinds if k not in KINDS]
    if unknown:
        raise argparse.ArgumentTypeError(f"unknown {unknown}; known: {', '.join(KINDS)}")
    return kinds


class Crew(Agent):
    """Run the simulated agents of several robots in one process."""

    kind = "crew"

    def __init__(self, args: argparse.Namespace) -> None:
        robots = [r for group in args.robots for r in group]
        args.robot = robots[0]  # the crew is named after its first robot: crew.robot1
        super().__init__(args)
        kinds = args.kinds or list(KINDS)
        self.members: list[Agent] = [
            KINDS[kind](argparse.Namespace(**{**vars(args), "robot": robot, "name": None}))
            for robot in robots
            for kind in kinds
        ]
        for member in self.members:
            member.view = self.view  # one view for all: the space is the same
            member.writes = self.writes  # one thread settles all their writes
        self._tokens: list[zenoh.LivelinessToken] = []
        self._touched: set[Node] = set()
        self._full_tick_at = 0.0

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add `--robots`, `--kinds` and every member's options."""
        parser.add_argument(
            "--robots",
            type=_names,
            action="append",
            required=True,
            metavar="NAMES",
            help="comma-separated robots to simulate (repeatable); --robot is ignored",
        )
        parser.add_argument(
            "--kinds",
            type=_kinds,
            metavar="KINDS",
            help=f"agents per robot (default {','.join(KINDS)})",
        )
        for member in KINDS.values():
            member.add_arguments(parser)

    def setup(self) -> None:
        """Open the space as `Agent.setup` does, then give every member its handle and token.

        Raises:
            SpaceUnavailable: see `Agent.setup`.
        """
        super().setup()
        assert self.ts is not None
        for member in self.members:
            member.ts = TripleSpace(
                self.ts.session, self.ts.space, agent=member.name, writer=self.ts.writer
            )
            self._tokens.append(declare_agent(self.ts.session, self.ts.space, member.name))
        self.log.info("crew of %d agents for %d robots", len(self.members), len(self.robots))

    @property
    def robots(self) -> list[Node]:
        """Return the robots the crew simulates, in order."""
        return list(dict.fromkeys(m.robot for m in self.members))

    def shutdown(self) -> None:
        """Undeclare the members' tokens and handles, then leave the space."""
        try:
            for token in self._tokens:
                token.undeclare()
            for member in self.members:
                if member.ts is not None:
                    member.ts.close()
                member.ts = None
        finally:
            self._tokens.clear()
            super().shutdown()

    def on_start(self) -> None:
        """Start every member on the rebuilt view."""
        for member in self.members:
            member.started = True
            self._guarded(member.on_start, f"{member.name} start")

    def on_change(self, change: Change) -> None:
        """Hand a change to the members of the robots it is about; they tick next.

        A change about no robot (a firing record, a place) waits for the
        periodic tick: the members read it from the shared view then.
        """
        subjects = {s for s, _p, _o in (*change.added, *change.removed)}
        touched = {self._robot_of(s) for s in subjects}
        touched.discard(None)
        for member in self.members:
            if member.robot in touched:
                self._guarded(lambda m=member: m.on_change(change), f"{member.name} change")
        self._touched |= touched  # type: ignore[arg-type]

    def _robot_of(self, subject: Node) -> Node | None:
        """Return the robot `subject` is, or whose device or skill it is, per the view."""
        graph = self.view.graph
        if (subject, RDF.type, AC.Robot) in graph:
            return subject
        return graph.value(None, AC.has_device, subject) or graph.value(None, AC.has_skill, subject)

    def tick(self) -> None:
        """Tick every member each `--tick`; between, only those of robots a change was about."""
        now = time.monotonic()
        full = now >= self._full_tick_at
        if full:
            self._full_tick_at = now + self.args.tick
        for member in self.members:
            if full or member.robot in self._touched:
                self._guarded(member.tick, f"{member.name} tick")
        self._touched.clear()


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run a crew (see `--help`)."""
    return run_agent(Crew, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
