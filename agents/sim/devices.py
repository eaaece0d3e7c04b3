"""Simulated device drivers: they obey running modes after a delay and can fault.

A driver switches to a commanded mode (`active`, `stand-by`, `disabled`) after
`switch_delay` simulated seconds (default `SWITCH_DELAY`), as real drivers take
time to power up or down; what it reports (`actual_mode`) is what it is, not
what it was told. Faults come from an injection (the HMI's `ac:simulate_fault`)
or at random at `fault_rate` per simulated hour.
"""

from __future__ import annotations

import random
from collections.abc import Iterable
from dataclasses import dataclass, field

MODES = ("active", "stand-by", "disabled")
FAULTS = ("none", "warning", "error")
SWITCH_DELAY = 0.5

# Percent of battery per simulated second drawn by a device in each mode.
DRAIN = {"active": 0.002, "stand-by": 0.0005, "disabled": 0.0}


@dataclass
class Driver:
    """One device's simulated driver.

    Attributes:
        mode: the mode the device is in.
        fault: its diagnostics ("none", "warning", "error").
        fault_rate: random errors per simulated hour (0: never).
        switch_delay: simulated seconds a mode switch takes.
    """

    mode: str = "active"
    fault: str = "none"
    fault_rate: float = 0.0
    switch_delay: float = SWITCH_DELAY
    rng: random.Random = field(default_factory=random.Random)
    _commanded: str | None = None
    _switch_at: float = 0.0

    def command(self, mode: str, now: float) -> None:
        """Ask the driver to switch to `mode`; it does so `switch_delay` later.

        Raises:
            ValueError: `mode` is not one of `MODES`.
        """
        if mode not in MODES:
            raise ValueError(f"unknown running mode {mode!r}")
        if mode == self.mode:
            self._commanded = None
        elif mode != self._commanded:
            self._commanded, self._switch_at = mode, now + self.switch_delay

    def inject(self, fault: str) -> None:
        """Make the driver report `fault` from now on ("none" clears it).

        Raises:
            ValueError: `fault` is not one of `FAULTS`.
        """
        if fault not in FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault

    def step(self, now: float, dt: float) -> None:
        """Advance to simulated time `now`, `dt` seconds after the last step."""
        if self._commanded is not None and now >= self._switch_at:
            self.mode, self._commanded = self._commanded, None
        if self.fault_rate > 0 and self.fault == "none" and self.mode == "active":
            if self.rng.random() < self.fault_rate * dt / 3600.0:
                self.fault = "error"


def drain(drivers: Iterable[Driver]) -> float:
    """Return the percent of battery per second the drivers draw together."""
    return sum(DRAIN[d.mode] for d in drivers)


def obstacles_seen(crowd_level: str | None, mode: str) -> str | None:
    """Return what an active laser reports in a place of `crowd_level`, None when off."""
    if mode != "active":
        return None
    return "surrounded" if crowd_level == "crowded" else "clear"
