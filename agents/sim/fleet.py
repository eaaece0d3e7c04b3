"""Simulated fleets: copies of a robot description, renamed and placed on the map.

A benchmark or a test needs fifty robots, not fifty Turtle files. `clone_robot`
copies one robot of a description (the robot, its devices and skills, and their
state) under a new name; `fleet_description` builds a site with N such robots.
A copy is the same kind of robot, so the same rules serve it, and its devices
are its own, so a change on one copy commands that copy only.
"""

from __future__ import annotations

from pathlib import Path

from rdflib import RDF, RDFS, Graph, Literal, URIRef
from rdflib.term import Node

from agents.resources import data_file
from agents.vocabulary import AC


def _local(iri: Node) -> str:
    return str(iri).rsplit("#", 1)[-1]


def robot_parts(graph: Graph, robot: URIRef) -> set[URIRef]:
    """Return the robot and the individuals that are its own: its devices and skills."""
    parts = {robot}
    for predicate in (AC.has_device, AC.has_skill):
        parts.update(o for o in graph.objects(robot, predicate) if isinstance(o, URIRef))
    return parts


def clone_robot(graph: Graph, robot: URIRef, name: str, *, place: URIRef | None = None) -> Graph:
    """Return a copy of `robot`'s description in `graph` for a robot named `ac:NAME`.

    Devices and skills are renamed with the robot (`ac:robot1_battery` becomes
    `ac:NAME_battery`), so the copy shares nothing it could be commanded through.
    Shared individuals it refers to (tasks, places, its site) stay as they are.

    Args:
        graph: a description holding `robot` (e.g. `ontology/robots/hospital_fleet.ttl`).
        robot: the robot to copy.
        name: the copy's local name in the `ac:` namespace.
        place: where the copy starts (its `ac:location` and position), if not
            where `robot` is.

    Raises:
        ValueError: `robot` has no devices in `graph`.
    """
    parts = robot_parts(graph, robot)
    if len(parts) == 1:
        raise ValueError(f"{robot} has no devices in the description")
    stem = _local(robot)
    renamed = {
        part: AC[name + _local(part)[len(stem) :]]
        if _local(part).startswith(stem)
        else AC[f"{name}_{_local(part)}"]
        for part in parts
    }
    copy = Graph()
    for s, p, o in graph:
        if s in renamed:
            copy.add((renamed[s], p, renamed.get(o, o)))  # type: ignore[arg-type]
    clone = AC[name]
    copy.set((clone, RDFS.label, Literal(name)))
    if place is not None:
        copy.set((clone, AC.location, place))
        for axis, predicate in ((AC.map_x, AC.position_x), (AC.map_y, AC.position_y)):
            coordinate = graph.value(place, axis)
            if coordinate is None:
                raise ValueError(f"{place} has no {_local(axis)} in the description")
            copy.set((clone, predicate, coordinate))
    return copy


def fleet_description(
    count: int,
    *,
    template: Path | None = None,
    robot: URIRef = AC.robot1,
    prefix: str = "robot",
) -> Graph:
    """Return a site with `count` copies of one robot: `ac:PREFIX1` ... `ac:PREFIXcount`.

    The site, places and people of `template` (default: the shipped
    `ontology/robots/hospital_fleet.ttl`) are kept and its robots replaced
    by the copies, which start spread over the site's places (not its docks).
    Load it with `ontology/selfconfig.ttl` and `ontology/robots/common.ttl`.

    Raises:
        ValueError: `count` is below 1, or `template` has no `robot`.
    """
    if count < 1:
        raise ValueError(f"a fleet has at least one robot, not {count}")
    source = Graph().parse(template or data_file("ontology/robots/hospital_fleet.ttl"))
    robots = set(source.subjects(RDF.type, AC.Robot))
    owned = set().union(*(robot_parts(source, r) for r in robots))
    out = Graph()
    for triple in source:
        if triple[0] not in owned:
            out.add(triple)
    places = sorted(
        p
        for p in source.subjects(AC.map_x, None)
        if isinstance(p, URIRef) and (p, RDF.type, AC.Dock) not in source
    )
    for k in range(1, count + 1):
        out += clone_robot(source, robot, f"{prefix}{k}", place=places[(k - 1) % len(places)])
    return out
