"""The navigation monitor: semantic places in, a simulated base driving between them.

It translates the target place the behaviour agent sets (`ac:target_place`)
into map coordinates (`ac:map_x`, `ac:map_y` of the place, from the robot
file), drives the base there at the commanded maximum speed (`ac:motion_speed`
of the base, a level the integrator maps to m/s with `ac:SpeedLevel`), and
reports the robot's location (nearest place), position and navigation status,
and the speed limit it applies (`ac:speed_limit`, m/s).
Disabled navigation (the base's `ac:running_mode` or the navigation skill's
`ac:skill_status`) stops the base; enabled again, it resumes the trip.
"""

from __future__ import annotations

import argparse
import sys
from decimal import Decimal

from rdflib import Literal, URIRef
from rdflib.term import Node

from agents.base import Agent, run_agent
from agents.sim.base import DEFAULT_SPEEDS, Base, nearest
from agents.vocabulary import AC, literal

POSITION_GRID = 0.5


def _metres(value: float) -> Literal:
    """Return a position as an xsd:decimal, on a grid coarse enough not to flood the space."""
    return literal(Decimal(f"{round(value / POSITION_GRID) * POSITION_GRID:.1f}"))


class NavMonitor(Agent):
    """Drive a simulated base to semantic places and report where the robot is."""

    kind = "nav_monitor"
    # Besides its robot: where the places are, and the speed levels.
    shared = (AC.map_x, AC.map_y, AC.level, AC.meters_per_second)
    ticks_on_reads = True

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.base = Base()
        self.places: dict[URIRef, tuple[float, float]] = {}
        self.target: URIRef | None = None
        self._placed = False
        self._last = 0.0

    def on_start(self) -> None:
        """Start the simulation clock."""
        self._last = self.clock.now()

    def tick(self) -> None:
        """Follow the commanded target, speed and enablement; publish what changed."""
        now = self.clock.now()
        dt, self._last = now - self._last, now
        self.places = self._map()
        if not self._placed and not self._place():
            return
        self.base.enabled = self._enabled()
        self.base.max_speed = self._max_speed()
        self._follow(self._target())
        self.base.step(dt)
        self.set_values(self._readings())

    def _map(self) -> dict[URIRef, tuple[float, float]]:
        """Return the places of the map (read every tick: the map may be written late)."""
        places = {}
        for place in self.view.subjects(AC.map_x):
            x, y = self.view.number(place, AC.map_x), self.view.number(place, AC.map_y)
            if isinstance(place, URIRef) and x is not None and y is not None:
                places[place] = (x, y)
        return places

    def _place(self) -> bool:
        """Put the base where the space last saw the robot; False while it says nothing."""
        x = self.view.number(self.robot, AC.position_x)
        y = self.view.number(self.robot, AC.position_y)
        location = self.view.value(self.robot, AC.location)
        if x is not None and y is not None:
            self.base.x, self.base.y = x, y
        elif isinstance(location, URIRef) and location in self.places:
            self.base.x, self.base.y = self.places[location]
        else:
            return False
        self._placed = True
        where = (self.base.x, self.base.y)
        self.log.info("%d places; robot at (%.1f, %.1f)", len(self.places), *where)
        return True

    def _target(self) -> URIRef | None:
        target = self.view.value(self.robot, AC.target_place)
        if target is not None and target not in self.places:
            return None
        return target  # type: ignore[return-value]

    def _follow(self, target: URIRef | None) -> None:
        """Start, stop or resume the trip so that the base heads for `target`."""
        if target != self.target:
            self.target = target
            if target is None:
                self.base.stop()
            else:
                self.log.info("heading to %s", target)
                self.base.go_to(*self.places[target])
        elif target is not None and self.base.status == "aborted" and self.base.enabled:
            self.log.info("navigation enabled again: resuming the trip to %s", target)
            self.base.go_to(*self.places[target])

    def _enabled(self) -> bool:
        base = self.view.device(self.robot, AC.MobileBase)
        if self.view.text(base, AC.running_mode) == "disabled":
            return False
        for skill in self.view.objects(self.robot, AC.has_skill):
            if self.view.has_type(skill, AC.NavigationSkill):
                if self.view.text(skill, AC.skill_status) == "disabled":
                    return False
        return True

    def _max_speed(self) -> float:
        speeds = self.view.levels(AC.SpeedLevel, AC.meters_per_second) or DEFAULT_SPEEDS
        level = self.view.text(self.view.device(self.robot, AC.MobileBase), AC.motion_speed)
        return speeds.get(level or "normal", DEFAULT_SPEEDS["normal"])

    def _readings(self) -> dict[tuple[Node, Node], Node | None]:
        values: dict[tuple[Node, Node], Node | None] = {
            (self.robot, AC.navigation_status): literal(self.base.status),
            (self.robot, AC.position_x): _metres(self.base.x),
            (self.robot, AC.position_y): _metres(self.base.y),
        }
        place = nearest(self.places, self.base.x, self.base.y)
        if place is not None:
            values[(self.robot, AC.location)] = URIRef(place)
        base = self.view.device(self.robot, AC.MobileBase)
        if base is not None:
            values[(base, AC.actual_speed)] = literal(Decimal(f"{self.base.speed:.2f}"))
            values[(base, AC.speed_limit)] = literal(Decimal(f"{self.base.max_speed:.2f}"))
        return values


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the navigation monitor (see `--help`)."""
    return run_agent(NavMonitor, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
