"""Read what a person wants to see of each robot out of the space's triples.

One reading of the vocabulary (docs/vocabulary.md) shared by the live view of
`tspace up`, the scenario checker and the HMI, so they never disagree on what
"the robot's task" or "the battery" is.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from rdflib import RDF, BNode, Graph, Literal, URIRef
from rdflib.term import Node

from agents.firings import rule_names
from agents.sentences import firing_sentence
from agents.vocabulary import AC, FIRING_PROPERTIES, PREFIXES
from space import ChangeRecord, Triple

# Most specific first: a device is shown with the first of its classes listed here.
DEVICE_CLASSES = (
    AC.Battery,
    AC.MobileBase,
    AC.WheelMotor,
    AC.LaserScanner,
    AC.TouchScreen,
    AC.Speaker,
    AC.Microphone,
)


@dataclass(frozen=True)
class DeviceState:
    """One device of a robot: its name, kind and commanded running mode."""

    name: str
    kind: str
    mode: str | None


@dataclass(frozen=True)
class RobotState:
    """What the live view and the HMI show of one robot.

    Attributes are the local names or literal values of the vocabulary's terms,
    None where the space does not say.
    """

    name: str
    task: str | None
    task_type: str | None
    requested: str | None
    location: str | None
    at_dock: bool
    battery: str | None
    charge: int | None
    speed: str | None
    devices: tuple[DeviceState, ...]
    announcement: str | None = None

    def mode(self, kind: str) -> str | None:
        """Return the running mode of the robot's first device of class `kind`."""
        return next((d.mode for d in self.devices if d.kind == kind), None)


@dataclass(frozen=True)
class Answer:
    """A changeset that answered another one (a rule firing or an agent reacting).

    Attributes:
        seq: its place in the store's order.
        agent: who wrote it (the reasoner for rule conclusions).
        time: HH:MM:SS.mmm of its HLC timestamp, or "" if unknown.
        rules: names of the rules that fired (from the `ac:RuleFiring` records it adds).
        added: the conclusions, compacted ("ac:robot1_base ac:motion_speed low").
        removed: what it retracted, compacted.
        cause_agent: who wrote the cause, if the cause is still remembered.
        cause: the cause's triples, compacted (empty if forgotten).
        sentence: the firing said as a sentence (`agents.sentences`), "" if not asked for.
    """

    seq: int
    agent: str
    time: str
    rules: tuple[str, ...]
    added: tuple[str, ...]
    removed: tuple[str, ...]
    cause_agent: str | None
    cause: tuple[str, ...]
    sentence: str = ""


class BadValues:
    """Report each value a view cannot show, once: views re-read every robot on each change.

    Args:
        report: called with one line per bad value (a logger's `warning`, say).
    """

    def __init__(self, report: Callable[[str], None]) -> None:
        self._report = report
        self._seen: set[Triple] = set()
        self._lock = threading.Lock()  # `tspace up` reads robots on two threads

    def __call__(self, triple: Triple, expected: str) -> None:
        """Report `triple` unless it was already; `expected` says what the value should be."""
        with self._lock:
            if triple in self._seen:
                return
            self._seen.add(triple)
        s, p, o = triple
        self._report(f"{short(s)} {short(p)} {str(o)!r} is not {expected}; shown as unknown")


def short(term: Node) -> str:
    """Return a term as a person reads it: prefixed names (`ac:`, `rdf:`...), bare literals."""
    if isinstance(term, Literal):
        return str(term)
    return PREFIXES.compact(str(term)) or str(term)


def local(term: Node | None) -> str | None:
    """Return the local name of an `ac:` IRI (or the literal's value); None stays None."""
    if term is None:
        return None
    text = short(term)
    return text[3:] if text.startswith("ac:") else text


def describe(triple: Triple) -> str:
    """Return one triple as a compact line."""
    return " ".join(short(t) for t in triple)


def _kind(graph: Graph, device: Node) -> str:
    types = set(graph.objects(device, RDF.type))
    found = next((c for c in DEVICE_CLASSES if c in types), None)
    if found is None:
        found = next((t for t in sorted(types) if short(t).startswith("ac:")), None)
    return local(found) or "Device"


def _percent(
    graph: Graph, device: Node | None, predicate: Node, bad: BadValues | None
) -> int | None:
    """Return a whole percentage, None if absent or not a number (reported to `bad`)."""
    value = graph.value(device, predicate) if device is not None else None
    if value is None:
        return None
    try:
        number = float(value) if isinstance(value, Literal) else math.nan
    except ValueError:
        number = math.nan
    if not math.isfinite(number):
        if bad is not None:
            bad((device, predicate, value), "a percentage")
        return None
    return int(number)


def _robot_names(graph: Graph) -> list[Node]:
    robots = set(graph.subjects(RDF.type, AC.Robot)) | set(graph.subjects(AC.has_device, None))
    return sorted(robots)


def read_robots(graph: Graph, bad: BadValues | None = None) -> list[RobotState]:
    """Return the state of every robot in `graph`, sorted by name.

    Anything may be written into a space: a value that cannot be shown (a charge
    of "abc") is shown as unknown and passed to `bad`, never raised.
    """
    states = []
    for robot in _robot_names(graph):
        devices = sorted(graph.objects(robot, AC.has_device))
        kinds = {d: _kind(graph, d) for d in devices}
        battery = next((d for d in devices if kinds[d] == "Battery"), None)
        base = next((d for d in devices if kinds[d] == "MobileBase"), None)
        task = graph.value(robot, AC.current_task)
        requested = graph.value(robot, AC.requested_task)
        place = graph.value(robot, AC.location)
        states.append(
            RobotState(
                name=local(robot) or str(robot),
                task=local(task),
                task_type=local(graph.value(task, AC.type)) if task is not None else None,
                requested=local(graph.value(requested, AC.type)) if requested is not None else None,
                location=local(place),
                at_dock=place is not None
                and (place == graph.value(robot, AC.dock) or (place, RDF.type, AC.Dock) in graph),
                battery=local(graph.value(battery, AC.battery_level)) if battery else None,
                charge=_percent(graph, battery, AC.charge_percent, bad),
                speed=local(graph.value(base, AC.motion_speed)) if base else None,
                devices=tuple(
                    DeviceState(
                        local(d) or str(d), kinds[d], local(graph.value(d, AC.running_mode))
                    )
                    for d in devices
                ),
                announcement=local(graph.value(robot, AC.announcement)),
            )
        )
    return states


def _noise(triple: Triple) -> bool:
    """Return True for triples a firing line leaves out.

    The reasoner's bookkeeping (who fired, when) is shown as rule names, and what
    involves a blank node (membership of an OWL restriction, say) means nothing
    to a reader.
    """
    _, p, o = triple
    if p in FIRING_PROPERTIES or (p == RDF.type and o == AC.RuleFiring):
        return True
    return any(isinstance(t, BNode) for t in triple)


def read_firings(
    records: Iterable[ChangeRecord],
    limit: int = 20,
    graph: Graph | None = None,
    said: dict[str, str] | None = None,
) -> list[Answer]:
    """Return the last `limit` changesets that name a cause, newest first.

    With `graph` (the space now), each is also said as a sentence; `said`
    remembers the sentences by changeset id, so that a view redrawn on every
    change words each firing once.
    """
    said = {} if said is None else said
    if len(said) > 10 * limit:
        said.clear()
    records = list(records)
    by_id = {r.id: r for r in records}
    firings = []
    for record in reversed(records):
        if record.cause is None:
            continue
        cause = by_id.get(record.cause)
        stamp = record.timestamp.strftime("%H:%M:%S.%f")[:-3] if record.timestamp else ""
        names = sorted(set(rule_names(record.added)))
        firings.append(
            Answer(
                seq=record.seq,
                agent=record.agent,
                time=stamp,
                rules=tuple(names),
                added=tuple(describe(t) for t in record.added if not _noise(t)),
                removed=tuple(describe(t) for t in record.removed if not _noise(t)),
                cause_agent=cause.agent if cause else None,
                cause=tuple(describe(t) for t in cause.added if not _noise(t)) if cause else (),
                sentence="" if graph is None else _said(record, cause, graph, names, said),
            )
        )
        if len(firings) == limit:
            break
    return firings


def _said(
    record: ChangeRecord,
    cause: ChangeRecord | None,
    graph: Graph,
    names: list[str],
    said: dict[str, str],
) -> str:
    sentence = said.get(record.id)
    if sentence is None:
        because = cause.added if cause else ()
        sentence = firing_sentence(because, record.added, record.removed, graph, names)
        said[record.id] = sentence
    return sentence


def task_named(graph: Graph, task_type: str) -> URIRef | None:
    """Return the task individual whose `ac:type` is `task_type`, or None."""
    found = next(iter(graph.subjects(AC.type, Literal(task_type))), None)
    return found if isinstance(found, URIRef) else None


def battery_of(graph: Graph, robot: str) -> URIRef | None:
    """Return the battery device of robot `robot` (local name), or None."""
    for device in graph.objects(AC[robot], AC.has_device):
        if isinstance(device, URIRef) and _kind(graph, device) == "Battery":
            return device
    return None
