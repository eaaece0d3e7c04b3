"""An agent's view of the space: the library's local copy, read in the robot vocabulary.

The copy itself (functional replacement, asserted and inferred kept apart) is
`space.SpaceMirror`; this adds the readings agents share (a robot's devices,
tasks by type, the integrator's levels) and leaves out the reasoner's firing
records: no agent decides from them (the HMI reads them from the changes), and
a change that fires many rules would cost every agent their triples.
"""

from __future__ import annotations

from collections.abc import Iterable

from rdflib import RDF, Literal, URIRef
from rdflib.term import Node

from agents.vocabulary import AC, RECORD_PREFIX
from space import SpaceMirror, Triple


class View(SpaceMirror):
    """The triples an agent knows, with the lookups agents need (owner thread only)."""

    def __init__(self, triples: Iterable[Triple] = ()) -> None:
        super().__init__(triples, skip_subjects=RECORD_PREFIX)

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
        for task in sorted(self.graph.subjects(AC.type, Literal(task_type))):
            if isinstance(task, URIRef):
                return task
        return None

    def levels(self, cls: Node, measure: Node) -> dict[str, float]:
        """Return the integrator's levels of a class: level literal -> its measure."""
        found = {}
        for level in self.graph.subjects(RDF.type, cls):
            name, amount = self.text(level, AC.level), self.number(level, measure)
            if name is not None and amount is not None:
                found[name] = amount
        return found
