"""An agent's view of the space: the library's local copy, read in the robot vocabulary.

The copy itself (functional replacement, asserted and inferred kept apart) is
`space.SpaceMirror`; this adds the readings agents share (a robot's devices,
tasks by type, the integrator's levels).
"""

from __future__ import annotations

from collections.abc import Iterable

from rdflib import RDF, Literal, URIRef
from rdflib.term import Node

from agents.firings import without_records
from agents.vocabulary import AC
from space import SpaceMirror, Triple


class View(SpaceMirror):
    """The triples an agent knows, with the lookups agents need (owner thread only)."""

    @staticmethod
    def concerning(triples: Iterable[Triple], robot: URIRef) -> list[Triple]:
        """Return the triples but other robots' and their parts' (`ac:robot2_battery`), and records.

        What a robot's agent keeps of a snapshot: it follows only its own robot's
        changes, so another robot's state, or the reasoner's firing records, would
        go stale in its view.
        """
        triples = without_records(triples)
        others = {s for s, p, o in triples if p == RDF.type and o == AC.Robot and s != robot}
        stems = tuple(f"{r}_" for r in others)
        return [t for t in triples if t[0] not in others and not str(t[0]).startswith(stems)]

    def strays(self, robot: URIRef) -> list[Node]:
        """Return the robot's devices and skills not named after it (`ac:robot7_...`).

        A robot's agent hears only of the subjects named after its robot: it would
        never see these change.
        """
        parts = {*self.objects(robot, AC.has_device), *self.objects(robot, AC.has_skill)}
        return sorted(p for p in parts if not str(p).startswith(f"{robot}_"))

    def devices(self, robot: URIRef, cls: Node) -> list[URIRef]:
        """Return the robot's devices of class `cls`."""
        return [
            d
            for d in self.objects(robot, AC.has_device)
            if isinstance(d, URIRef) and self.has_type(d, cls)
        ]

    def device(self, robot: URIRef, cls: Node) -> URIRef | None:
        """Return the robot's first device of class `cls`, or None."""
        return next(iter(self.devices(robot, cls)), None)

    def task_type(self, task: Node | None) -> str | None:
        """Return the `ac:type` of a task individual, or None."""
        return self.text(task, AC.type)

    def task_of_type(self, task_type: str) -> URIRef | None:
        """Return the task individual whose `ac:type` is `task_type`, or None."""
        for task in self.subjects(AC.type, Literal(task_type)):
            if isinstance(task, URIRef):
                return task
        return None

    def levels(self, cls: Node, measure: Node) -> dict[str, float]:
        """Return the integrator's levels of a class: level literal -> its measure."""
        found = {}
        for level in self.subjects(RDF.type, cls):
            name, amount = self.text(level, AC.level), self.number(level, measure)
            if name is not None and amount is not None:
                found[name] = amount
        return found
