"""A simulated mobile base: it drives in a straight line to a target at a maximum speed.

Stands for the navigation stack the nav monitor commands (path planning and
localisation are out of scope): good enough to see a speed limit change how
long a trip takes, and a disabled base stop where it is.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

DEFAULT_SPEEDS: dict[str, float] = {"low": 0.3, "normal": 0.7, "high": 1.2}
ARRIVAL_TOLERANCE = 0.05


@dataclass
class Base:
    """Position and motion of one base on the metric map.

    Attributes:
        x, y: position, metres.
        max_speed: the commanded speed limit, m/s.
        target: where it drives to, or None.
        status: "idle", "navigating", "reached" or "aborted".
        enabled: a disabled base does not move.
    """

    x: float = 0.0
    y: float = 0.0
    max_speed: float = DEFAULT_SPEEDS["normal"]
    target: tuple[float, float] | None = None
    status: str = "idle"
    enabled: bool = True

    @property
    def speed(self) -> float:
        """Return the speed it moves at now, m/s."""
        return self.max_speed if self.status == "navigating" and self.enabled else 0.0

    def go_to(self, x: float, y: float) -> None:
        """Start driving to (x, y)."""
        self.target = (x, y)
        self.status = "navigating"

    def stop(self) -> None:
        """Stop where it is because nowhere is to be reached any more (not a failure)."""
        if self.status == "navigating":
            self.status = "idle"
        self.target = None

    def abort(self) -> None:
        """Stop where it is; the trip counts as aborted."""
        if self.status == "navigating":
            self.status = "aborted"
        self.target = None

    def step(self, dt: float) -> None:
        """Drive for `dt` simulated seconds; a disabled base aborts its trip."""
        if self.status != "navigating" or self.target is None:
            return
        if not self.enabled:
            self.abort()
            return
        tx, ty = self.target
        distance = math.hypot(tx - self.x, ty - self.y)
        travel = self.max_speed * dt
        if travel + ARRIVAL_TOLERANCE >= distance:
            self.x, self.y, self.target, self.status = tx, ty, None, "reached"
        else:
            self.x += (tx - self.x) * travel / distance
            self.y += (ty - self.y) * travel / distance


def nearest(places: Mapping[str, tuple[float, float]], x: float, y: float) -> str | None:
    """Return the place nearest to (x, y), None if there are none; ties go to the first name."""
    if not places:
        return None
    return min(sorted(places), key=lambda n: math.hypot(places[n][0] - x, places[n][1] - y))
