"""What the HMI plots and puts on its timeline: each robot's history, as events from changesets.

The HMI reads the store's changeset log when it starts (the last `LOOKBACK`
changesets), then every change as it comes, and turns each changeset into
events per robot: a battery reading, a speed, a task, a place, a device's
commanded or reported mode, what it says, and rule firings (with their
sentence and the conclusions a `why` can ask about). A page that reloads, or
an HMI that restarts, shows the same history: it comes from the space.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Iterable
from typing import Any

from rdflib import RDF, Graph, Literal
from rdflib.term import Node

from agents.firings import rule_names
from agents.sentences import firing_sentence
from agents.vocabulary import AC
from space import Changeset, Triple, triple_to_nt

LOOKBACK = 3000  # changesets read from the store's log at start
CAUSES_KEPT = 500  # recent changesets remembered to say what caused a firing

Event = dict[str, Any]
# Property -> (event kind, field): the values the page plots or lays on the timeline.
VALUES = {
    AC.charge_percent: ("battery", "charge"),
    AC.battery_level: ("battery", "level"),
    AC.motion_speed: ("speed", "value"),
    AC.location: ("location", "value"),
    AC.announcement: ("says", "value"),
    AC.presence: ("presence", "value"),
    AC.running_mode: ("mode", "commanded"),
    AC.actual_mode: ("mode", "reported"),
}


def _local(term: Node) -> str:
    text = str(term)
    return text if isinstance(term, Literal) else text.rsplit("#", 1)[-1].rsplit("/", 1)[-1]


class History:
    """Turn changesets into per-robot events, each changeset once, in store order."""

    def __init__(self) -> None:
        self.last_seq = 0
        self._causes: OrderedDict[str, Changeset] = OrderedDict()

    def events(self, changes: Iterable[Changeset], graph: Graph) -> list[Event]:
        """Return the events of changesets not seen yet (by seq), in order.

        `graph` is the space now: which robot each device belongs to, each task's kind.
        """
        owner = {d: r for r, d in graph.subject_objects(AC.has_device)}
        robots = {r for r in owner.values()}
        out: list[Event] = []
        for cs in changes:
            if cs.seq and cs.seq <= self.last_seq:
                continue
            self.last_seq = max(self.last_seq, cs.seq)
            self._causes[cs.id] = cs
            while len(self._causes) > CAUSES_KEPT:
                self._causes.popitem(last=False)
            when = cs.time.timestamp() * 1000 if cs.time else time.time() * 1000
            # A space started afresh (`tspace up --fresh`, a scenario) removes its robots:
            # what came before is another story, and the page starts the robot's history again.
            out += [
                {"t": when, "seq": cs.seq, "robot": _local(s), "kind": "reset"}
                for s, p, o in cs.removed
                if p == RDF.type and o == AC.Robot
            ]
            out += self._values(cs, graph, owner, robots, when)
            out += self._firings(cs, graph, owner, when)
        return out

    def _values(
        self, cs: Changeset, graph: Graph, owner: dict, robots: set, when: float
    ) -> list[Event]:
        found: dict[tuple[str, str, str], Event] = {}
        for s, p, o in cs.added:
            robot = s if s in robots else owner.get(s)
            if robot is None:
                continue
            base = {"t": when, "seq": cs.seq, "robot": _local(robot), "agent": cs.agent}
            if p == AC.current_task:
                found[(_local(robot), "task", "")] = {
                    **base,
                    "kind": "task",
                    "value": str(graph.value(o, AC.type) or _local(o)),
                }
                continue
            if p not in VALUES:
                continue
            kind, field = VALUES[p]
            device = _local(s) if kind == "mode" else ""
            event = found.setdefault((_local(robot), kind, device), {**base, "kind": kind})
            if device:
                event["device"] = device
            if field == "charge":
                try:
                    event[field] = float(o)
                except ValueError:
                    continue
            else:
                event[field] = _local(o)
        return list(found.values())

    def _firings(self, cs: Changeset, graph: Graph, owner: dict, when: float) -> list[Event]:
        """Return one firing event per robot a reasoner's firing record in `cs` names."""
        records = {s: o for s, p, o in cs.added if p == AC.robot}
        if not records:
            return []
        rules: dict[Node, list[str]] = {}
        for s, p, o in cs.added:
            if s in records:
                rules.setdefault(records[s], []).extend(rule_names([(s, p, o)]))
        cause = self._causes.get(cs.cause or "")
        out = []
        for robot, names in rules.items():

            def concerns(t: Triple, robot: Node = robot) -> bool:
                return t[0] == robot or owner.get(t[0]) == robot

            added = [t for t in cs.added if concerns(t)]
            removed = [t for t in cs.removed if concerns(t)]
            because = [t for t in cause.added if concerns(t)] if cause else []
            out.append(
                {
                    "t": when,
                    "seq": cs.seq,
                    "robot": _local(robot),
                    "kind": "firing",
                    "rules": sorted(set(names)),
                    "sentence": firing_sentence(because, added, removed, graph, sorted(names)),
                    "cause_agent": cause.agent if cause else None,
                    "added": [triple_to_nt(t) for t in added],
                    "removed": [triple_to_nt(t) for t in removed],
                }
            )
        return out
