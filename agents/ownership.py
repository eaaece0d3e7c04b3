"""Which robot a change is about, so that a reasoner per robot answers for its own robot.

A robot owns itself, its devices and its skills. Every per-robot reasoner
applies every changeset, so all of them hold the same state and draw the same
conclusions; ownership only decides who writes them. A changeset about one
robot's things is answered whole by that robot's reasoner: a dock it releases
and another robot claims in the same breath is then written in one changeset,
never as two halves racing each other. A changeset about no robot (a place, a
person, a dock) or about several is shared: each reasoner writes the firings
and inferred triples about its own robot, and those about no robot (the same
for all, so writing them twice changes nothing).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from rdflib import RDF
from rdflib.term import Node

from agents.view import AC
from space.reasoning import Delta, Firing, RuleEngine
from space.terms import Triple


def owner(engine: RuleEngine, subject: Node) -> Node | None:
    """Return the robot `subject` is or belongs to (as a device or skill), or None."""
    if (subject, RDF.type, AC.Robot) in engine:
        return subject
    for predicate in (AC.has_device, AC.has_skill):
        for robot, _p, _o in engine.match(None, predicate, subject):
            return robot
    return None


def concerned_robot(engine: RuleEngine, triples: Iterable[Triple]) -> Node | None:
    """Return the one robot whose things a change touches; None if it touches none or several."""
    robots = {owner(engine, s) for s, _p, _o in triples} - {None}
    return robots.pop() if len(robots) == 1 else None


def firing_robot(engine: RuleEngine, firing: Firing) -> Node | None:
    """Return the robot a firing concerned: the first robot among its premises, or None."""
    for s, _p, _o in firing.triggers:
        if (s, RDF.type, AC.Robot) in engine:
            return s
    return None


@dataclass(frozen=True)
class Answer:
    """What a reasoner writes back for one change: asserted and inferred changes, firings."""

    added: tuple[Triple, ...]
    removed: tuple[Triple, ...]
    inferred_added: tuple[Triple, ...]
    inferred_removed: tuple[Triple, ...]
    firings: tuple[Firing, ...]

    @classmethod
    def of(cls, delta: Delta) -> Answer:
        """Return the whole answer to a delta."""
        return cls(
            delta.asserted_added,
            delta.asserted_removed,
            delta.inferred_added,
            delta.inferred_removed,
            delta.firings,
        )

    def share(self, engine: RuleEngine, robot: Node) -> Answer:
        """Return the part of this answer a reasoner for `robot` writes for a shared change.

        Firings count for the robot among their premises; their asserted changes
        are composed in firing order. Inferred triples go with their subject's robot.
        """
        firings = tuple(f for f in self.firings if firing_robot(engine, f) in (robot, None))
        added: dict[Triple, None] = {}
        removed: dict[Triple, None] = {}
        for firing in firings:
            for triple in firing.retracted:
                if triple in added:
                    del added[triple]
                else:
                    removed[triple] = None
            for triple in firing.asserted:
                if triple in removed:
                    del removed[triple]
                else:
                    added[triple] = None

        def mine(triples: tuple[Triple, ...]) -> tuple[Triple, ...]:
            return tuple(t for t in triples if owner(engine, t[0]) in (robot, None))

        return Answer(
            tuple(added),
            tuple(removed),
            mine(self.inferred_added),
            mine(self.inferred_removed),
            firings,
        )
