"""Say a rule firing as a sentence: what changed in the world, then what the robot does.

"battery very low → robot1 goes to the dock at low speed; screen, speakers,
microphone stand-by". The live view of `tspace up` and the HMI show firings
this way (the raw triples stay one click or one flag away); both call
`firing_sentence`, so they never word a firing differently. The wording knows
the vocabulary (docs/vocabulary.md); a property it does not know is said as
"subject property value".
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from rdflib import RDF, BNode, Graph, Literal, URIRef
from rdflib.term import Node

from agents.firings import without_records
from agents.vocabulary import AC
from space import Triple

TASKS = {
    "GoingToDock": "goes to the dock",
    "Docking": "docks",
    "Charging": "charges",
    "Idle": "idles",
    "AttendingPatient": "attends",
    "Guiding": "guides",
}
# Bookkeeping a sentence leaves out: what follows from it is what a reader wants.
QUIET = {AC.charge_percent, AC.actual_mode, AC.task_elapsed, AC.task_started}
QUIET_CAUSES = {AC.task_elapsed, AC.task_started, AC.resume_task}


def _name(term: Node, robot: str | None = None) -> str:
    """Return a term as a person reads it: an `ac:` IRI by its local name, without `robot_`."""
    if isinstance(term, Literal):
        return str(term)
    text = str(term)
    local = text.rsplit("#", 1)[-1].rsplit("/", 1)[-1] if isinstance(term, URIRef) else text
    if robot and local.startswith(robot + "_"):
        local = local[len(robot) + 1 :]
    return local


def _words(predicate: Node) -> str:
    return _name(predicate).replace("_", " ")


def _robot_of(graph: Graph, subject: Node) -> str | None:
    """Return the local name of the robot a subject is, or has it as a device."""
    if (subject, RDF.type, AC.Robot) in graph or (subject, AC.has_device, None) in graph:
        return _name(subject)
    owner = next(iter(graph.subjects(AC.has_device, subject)), None)
    return _name(owner) if owner is not None else None


def _kept(triples: Iterable[Triple]) -> list[Triple]:
    """Leave out what a reader does not care about: records, types, blank nodes."""
    triples = without_records(triples)
    return [
        t
        for t in triples
        if t[1] != RDF.type
        and str(t[1]).startswith(str(AC))
        and not any(isinstance(x, BNode) for x in t)
    ]


def _task(graph: Graph, task: Node, person: Node | None) -> str:
    kind = graph.value(task, AC.type)
    phrase = TASKS.get(str(kind), f"does {kind or _name(task)}")
    if person is not None and phrase in ("attends", "guides"):
        phrase += f" {_name(person)}"
    return phrase


def what_changed(triples: Iterable[Triple], graph: Graph) -> str:
    """Say what a change of the world was: "battery very low", "robot1 at room_101"."""
    kept = _kept(triples)
    said = []
    levels = {s for s, p, _o in kept if p == AC.battery_level}
    for s, p, o in kept:
        robot = _robot_of(graph, s)
        if (p == AC.charge_percent and s in levels) or p in QUIET_CAUSES:
            continue
        subject = _name(s, robot)
        if p == AC.battery_level:
            said.append(f"{subject} {_name(o)}")
        elif p == AC.charge_percent:
            said.append(f"{subject} {_name(o)}%")
        elif p == AC.location:
            said.append(f"{subject} at {_name(o)}")
        elif p == AC.target_place:
            said.append(f"{subject} heading to {_name(o)}")
        elif p in (AC.current_task, AC.requested_task):
            verb = "asked to" if p == AC.requested_task else "now"
            said.append(f"{subject} {verb} {_task(graph, o, None)}")
        elif p == AC.interacting_with:
            said.append(f"{subject} serves {_name(o)}")
        elif p == AC.actual_mode:
            said.append(f"{subject} reports {_name(o)}")
        else:
            said.append(f"{subject} {_words(p)} {_name(o)}")
    return ", ".join(dict.fromkeys(said))


def what_follows(added: Sequence[Triple], removed: Sequence[Triple], graph: Graph) -> str:
    """Say what a firing made the robot do: its task and speed, device modes, other values."""
    kept = _kept(added)
    robots: dict[str, list[str]] = {}
    modes: dict[tuple[str | None, str], list[str]] = {}
    others: list[str] = []
    speech: list[str] = []
    for s, p, o in kept:
        robot = _robot_of(graph, s)
        if p == AC.current_task:
            person = graph.value(s, AC.interacting_with)
            robots.setdefault(_name(s), []).insert(0, _task(graph, o, person))
        elif p == AC.motion_speed:
            robots.setdefault(robot or _name(s), []).append(f"at {_name(o)} speed")
        elif p == AC.running_mode:
            modes.setdefault((robot, _name(o)), []).append(_name(s, robot))
        elif p == AC.announcement:
            speech.append(f"{robot or _name(s)} says “{o}”")
        elif p not in QUIET:
            others.append(f"{_name(s, robot)} {_words(p)} {_name(o)}")
    parts = []
    for robot, said in robots.items():
        if said and said[0].startswith("at "):
            said.insert(0, "moves")
        parts.append(" ".join([robot, *said]))
    parts += [f"{', '.join(sorted(devices))} {mode}" for (_r, mode), devices in modes.items()]
    parts += others
    changed = {(s, p) for s, p, _o in kept}
    parts += [
        f"{_name(s, _robot_of(graph, s))} {_words(p)} no longer {_name(o)}"
        for s, p, o in _kept(removed)
        if (s, p) not in changed and p not in QUIET
    ]
    return "; ".join([*parts, *speech])


def firing_sentence(
    cause: Sequence[Triple],
    added: Sequence[Triple],
    removed: Sequence[Triple],
    graph: Graph,
    rules: Sequence[str] = (),
) -> str:
    """Return a firing as one sentence: "battery very low → robot1 goes to the dock; ...".

    Args:
        cause: the triples the change that made the rules fire added (empty if unknown).
        added, removed: what the firing's changeset added and removed.
        graph: the space now, to know robots' devices and tasks' kinds.
        rules: the names of the rules that fired: said when the cause is unknown.
    """
    effect = what_follows(added, removed, graph) or "nothing visible changes"
    reason = what_changed(cause, graph) or (", ".join(rules) if rules else "the state loaded")
    return f"{reason} → {effect}"
