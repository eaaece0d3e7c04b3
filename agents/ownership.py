"""Which per-robot reasoner answers a change, so that each change gets one whole answer.

With `--per-robot`, every robot has a reasoner named `reasoner.ROBOT`. All of
them apply every changeset in the store's order, so all hold the same state
and draw the same conclusions; one writes them, whole, in one changeset.
Writing whole keeps every engine equal to the space: split by robot, a dock
released by one robot and claimed by another would arrive as two halves, in
either order.

A reasoner subscribes to the changes, reads the space (the state after change
`start`), then joins with a liveliness token
`tspace/<space>/@reasoners/<join time>-<start>-<name>`: it answers the changes
after `start`, and those up to it are answered by the reasoners before it. A
robot owns itself, its devices and its skills: a change about one robot's
things is answered by that robot's reasoner if it had joined by then. Any
other change (about no robot or several, or about a robot without a reasoner)
is answered by the leader: the reasoner that joined first. The leader also
writes what loading the space concluded. Engines load in a canonical order, so
the same state gives the same conclusions in every one. A change may be
answered twice (by a reasoner that did not see a newcomer's token yet; the
second answer changes nothing), never not at all.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable

import zenoh
from rdflib.term import Node

from agents.vocabulary import AC, RDF_TYPE, local_name
from space import KEY_ROOT, Triple, escape_key_chunk, unescape_key_chunk
from space.reasoning import Engine, Firing

PREFIX = "reasoner."


# Looked up once: these run per triple.
_ROBOT, _BELONGS = AC.Robot, (AC.has_device, AC.has_skill)


def reasoner_name(robot: Node) -> str:
    """Return the name of a robot's own reasoner."""
    return PREFIX + local_name(robot)  # type: ignore[arg-type]


def owner(engine: Engine, subject: Node) -> Node | None:
    """Return the robot `subject` is or belongs to (as a device or skill), or None."""
    if (subject, RDF_TYPE, _ROBOT) in engine:
        return subject
    for predicate in _BELONGS:
        for robot, _p, _o in engine.match(None, predicate, subject):
            return robot
    return None


def concerned_robot(engine: Engine, triples: Iterable[Triple]) -> Node | None:
    """Return the one robot whose things a change touches; None if it touches none or several."""
    robots = {owner(engine, s) for s in {t[0] for t in triples}} - {None}  # a subject once
    return robots.pop() if len(robots) == 1 else None


def firing_robot(engine: Engine, firing: Firing, robots: dict[Node, bool], default: Node) -> Node:
    """Return the robot a firing concerned: the first robot among its premises, else `default`.

    `robots` remembers which subjects are robots for one answer: its
    firings share their premises' subjects, so the engine is asked once each.
    """
    for s, _p, _o in firing.triggers:
        is_robot = robots.get(s)
        if is_robot is None:
            is_robot = robots[s] = (s, RDF_TYPE, _ROBOT) in engine
        if is_robot:
            return s
    return default


def _roster_key(space: str, entry: str = "*") -> str:
    return f"{KEY_ROOT}/{space}/@reasoners/{entry}"


class Roster:
    """The per-robot reasoners of a space: when each joined, and from which change on it answers.

    A reasoner answers the changes after the sequence number of the state it
    loaded (`start`); the changes up to it are in what it loaded, and the
    reasoners before it answer them. Every reasoner decides by the changes'
    sequence numbers, so who answers a change does not depend on when each
    learns of a newcomer, only (for a change after `start` that another reads
    before the newcomer's token arrives) may two answer it.

    `watch` feeds it from a liveliness subscriber (on a Zenoh thread); the
    agent's thread reads it. Every method takes a lock and never blocks otherwise.

    Args:
        me: this reasoner's name.
    """

    def __init__(self, me: str) -> None:
        self.me = me
        self._joined: dict[str, tuple[int, int]] = {}  # name -> (join time, start)
        self._lock = threading.Lock()

    def watch(self, session: zenoh.Session, space: str) -> zenoh.Subscriber:
        """Follow the reasoners' tokens (those present now first); the caller owns it."""

        def on_sample(sample: zenoh.Sample) -> None:
            entry = str(sample.key_expr).rsplit("/", 1)[1].split("-", 2)
            if len(entry) != 3 or not (entry[0].isdigit() and entry[1].isdigit()):
                return  # not a reasoner's token of this version
            name = unescape_key_chunk(entry[2])
            with self._lock:
                if sample.kind == zenoh.SampleKind.PUT:
                    self._joined[name] = (int(entry[0]), int(entry[1]))
                else:
                    self._joined.pop(name, None)

        return session.liveliness().declare_subscriber(_roster_key(space), on_sample, history=True)

    def join(self, session: zenoh.Session, space: str, start: int) -> zenoh.LivelinessToken:
        """Declare that this reasoner answers the changes after `start`; the caller owns it."""
        stamp = time.time_ns()
        with self._lock:
            self._joined[self.me] = (stamp, start)
        return session.liveliness().declare_token(
            _roster_key(space, f"{stamp}-{start}-{escape_key_chunk(self.me)}")
        )

    def answers(self, robot: Node | None, seq: int | None = None) -> bool:
        """Return True if this reasoner answers change `seq` about `robot` (None: shared).

        A robot's own reasoner answers for it; the leader (the first to join)
        answers the rest. Without `seq`, every reasoner present counts.
        """
        with self._lock:
            joined = {
                name: stamp
                for name, (stamp, start) in self._joined.items()
                if seq is None or start < seq
            }
        if robot is not None and reasoner_name(robot) in joined:
            return reasoner_name(robot) == self.me
        leader = min(joined, key=lambda name: (joined[name], name), default=None)
        return leader == self.me
