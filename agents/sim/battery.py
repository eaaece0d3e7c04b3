"""A simulated battery: its charge drains with the load and rises on the dock.

Rates are in percent per simulated second, so a scenario at `--time-scale 60`
lives an hour a minute. The level names and thresholds are the integrator's
(`ac:BatteryLevel` individuals); `DEFAULT_LEVELS` applies when the space has none.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

DEFAULT_LEVELS: dict[str, float] = {"very low": 10, "low": 25, "normal": 95, "full": 101}

IDLE_DRAIN = 0.01
MOVING_DRAIN = 0.02
CHARGE_RATE = 0.1


def level_of(percent: float, levels: Mapping[str, float] = DEFAULT_LEVELS) -> str:
    """Return the name of the level a charge falls in: the lowest bound it is below.

    Args:
        percent: state of charge, 0-100.
        levels: level name -> `below_percent` (the level holds below that charge).
    """
    ordered = sorted(levels.items(), key=lambda item: item[1])
    for name, below in ordered:
        if percent < below:
            return name
    return ordered[-1][0]


@dataclass
class Battery:
    """State of charge of one battery, in percent.

    Attributes:
        percent: the charge, kept within 0-100.
        charging: whether the robot is on its dock, charging.
    """

    percent: float = 80.0
    charging: bool = False

    def step(self, dt: float, device_drain: float = 0.0, moving: bool = False) -> None:
        """Advance `dt` simulated seconds under a load.

        Args:
            dt: simulated seconds since the last step.
            device_drain: percent per second drawn by the devices (see `devices.drain`).
            moving: whether the base is driving (costs `MOVING_DRAIN` more).
        """
        if self.charging:
            rate = CHARGE_RATE
        else:
            rate = -(IDLE_DRAIN + device_drain + (MOVING_DRAIN if moving else 0.0))
        self.percent = min(100.0, max(0.0, self.percent + rate * dt))

    def reported_percent(self, step: int = 5) -> int:
        """Return the charge rounded down to `step` percent: what is worth publishing."""
        return int(self.percent // step * step)
