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


def level_of(
    percent: float, levels: Mapping[str, float] = DEFAULT_LEVELS, *, charging: bool = False
) -> str:
    """Return the name of the level a charge falls in: the lowest bound it is below.

    A charging battery is never in the lowest level: that level is the alarm
    that sends a robot to its dock (the paper's Figure 6 rule, which does not
    exclude Charging), and a robot on its charger has answered it.

    Args:
        percent: state of charge, 0-100.
        levels: level name -> `below_percent` (the level holds below that charge).
        charging: whether the battery is on its charger.
    """
    ordered = sorted(levels.items(), key=lambda item: item[1])
    index = next((i for i, (_, below) in enumerate(ordered) if percent < below), len(ordered) - 1)
    if charging:
        index = max(index, min(1, len(ordered) - 1))
    return ordered[index][0]


def middle_of(level: str, levels: Mapping[str, float] = DEFAULT_LEVELS) -> int:
    """Return a charge in the middle of a level, for a level set without a charge.

    Raises:
        KeyError: `level` is not one of `levels`.
    """
    below = max((v for v in levels.values() if v < levels[level]), default=0.0)
    return min(100, int((below + levels[level]) / 2))


@dataclass
class Battery:
    """State of charge of one battery, in percent.

    Attributes:
        percent: the charge, kept within 0-100.
        charging: whether the robot is on its dock, charging.
        charge_rate: percent per simulated second gained while charging.
    """

    percent: float = 80.0
    charging: bool = False
    charge_rate: float = CHARGE_RATE

    def step(self, dt: float, device_drain: float = 0.0, moving: bool = False) -> None:
        """Advance `dt` simulated seconds under a load.

        Args:
            dt: simulated seconds since the last step.
            device_drain: percent per second drawn by the devices (see `devices.drain`).
            moving: whether the base is driving (costs `MOVING_DRAIN` more).
        """
        if self.charging:
            rate = self.charge_rate
        else:
            rate = -(IDLE_DRAIN + device_drain + (MOVING_DRAIN if moving else 0.0))
        self.percent = min(100.0, max(0.0, self.percent + rate * dt))

    def adopt(self, published: float, step: int = 5) -> None:
        """Take a charge read from the space as this battery's.

        A published charge is rounded down to `step`, so the true one lies
        between it and the next step: take the middle, or the first drain
        would publish a step less at once.
        """
        self.percent = min(100.0, max(0.0, published + (step - published % step) / 2))

    def reported_percent(self, step: int = 5) -> int:
        """Return the charge rounded down to `step` percent: what is worth publishing."""
        return int(self.percent // step * step)
