"""An agent's local copy of the space: the triples it has seen, kept current by changes.

Agents decide from this view instead of asking the store on every tick, so a
slow or absent store never stalls a control loop. The view is the union of the
asserted and inferred graphs, as a snapshot reports it, without the reasoner's
firing records: no agent decides from them (the HMI reads them from the
changes), and a change that fires many rules would cost every agent their
triples on its way to the robot.
"""

from __future__ import annotations

from collections.abc import Iterable

from rdflib import OWL, RDF, Graph, Literal, Namespace, URIRef
from rdflib.term import Node

from space import Changeset, Triple
from space.memory import BulkMemory

AC = Namespace("https://w3id.org/tspace/selfconfig#")
RECORD_PREFIX = str(AC) + "firing_"


class View:
    """The triples an agent knows, with the lookups agents need.

    The graph has no named graphs and changes go to its store's indexes
    directly (`space.memory.BulkMemory`), and the functional properties are
    kept in a set so that each triple added costs one lookup, not a graph query.
    """

    def __init__(self, triples: Iterable[Triple] = ()) -> None:
        self._store = BulkMemory()
        self.graph = Graph(store=self._store)
        self._functional: set[Node] = set()
        self.add(triples)

    def apply(self, change: Changeset) -> None:
        """Apply a changeset: removals first, then additions."""
        self.remove([*change.removed, *change.inferred_removed])
        self.add([*change.added, *change.inferred_added])

    def add(self, triples: Iterable[Triple]) -> None:
        """Add triples; a functional property's new value replaces the old one.

        The store already replaces functional values, but a change may reach us
        before the removal it implies, so the view enforces it too. Firing
        records are left out.
        """
        store, functional = self._store, self._functional
        for t in triples:
            s, p, o = t
            if s.startswith(RECORD_PREFIX):
                continue
            if p in functional:
                for old in store.objects_of(s, p):
                    if old != o:
                        store.discard((s, p, old))
            elif p == RDF.type and o == OWL.FunctionalProperty:
                functional.add(s)
            store.put(t)

    def remove(self, triples: Iterable[Triple]) -> None:
        """Remove triples (absent ones are ignored)."""
        store = self._store
        for triple in triples:
            if triple[1] == RDF.type and triple[2] == OWL.FunctionalProperty:
                self._functional.discard(triple[0])
            store.discard(triple)

    def is_functional(self, predicate: Node) -> bool:
        """Return True if the view declares `predicate` an owl:FunctionalProperty."""
        return predicate in self._functional

    def value(self, subject: Node | None, predicate: Node) -> Node | None:
        """Return one object of (subject, predicate), or None."""
        if subject is None:
            return None
        return next(iter(sorted(self.graph.objects(subject, predicate))), None)

    def text(self, subject: Node | None, predicate: Node) -> str | None:
        """Return the lexical form of one object of (subject, predicate), or None."""
        found = self.value(subject, predicate)
        return None if found is None else str(found)

    def number(self, subject: Node | None, predicate: Node) -> float | None:
        """Return one numeric object of (subject, predicate), or None if absent or not a number."""
        found = self.value(subject, predicate)
        if not isinstance(found, Literal):
            return None
        try:
            return float(found)
        except ValueError:
            return None

    def objects(self, subject: Node, predicate: Node) -> list[Node]:
        """Return the objects of (subject, predicate), sorted for determinism."""
        return sorted(self.graph.objects(subject, predicate))

    def has_type(self, subject: Node, cls: Node) -> bool:
        """Return True if `subject rdf:type cls` is in the view."""
        return (subject, RDF.type, cls) in self.graph

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
