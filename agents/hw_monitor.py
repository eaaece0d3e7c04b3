"""The hardware monitor: simulated drivers of one robot's devices, seen through the space.

It publishes what the devices sense (battery level and charge, faults, what the
laser sees) and obeys the running modes the rules command (`ac:running_mode`),
reporting the mode each device is actually in (`ac:actual_mode`). Values are
written only when they change, as levels the ontology defines. On restart it
takes the battery charge and device modes back from the space; a charge or
level another agent writes (the HMI, a scenario) becomes the battery's.
"""

from __future__ import annotations

import argparse
import random
import sys

from rdflib import URIRef
from rdflib.term import Node

from agents.base import Agent, run_agent
from agents.sim.battery import CHARGE_RATE, DEFAULT_LEVELS, Battery, level_of, middle_of
from agents.sim.devices import FAULTS, MODES, SWITCH_DELAY, Driver, drain, obstacles_seen
from agents.vocabulary import AC, literal
from space import Change

_BATTERY = (AC.charge_percent, AC.battery_level)  # what another agent may set a battery to


class HwMonitor(Agent):
    """Simulate and monitor a robot's devices: levels, faults and running modes."""

    kind = "hw_monitor"
    # Besides its robot: the places' crowds its lasers see, the levels and the task types.
    shared = (AC.crowd_level, AC.level, AC.below_percent, AC.type)
    ticks_on_reads = True

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.drivers: dict[URIRef, Driver] = {}
        self.battery = Battery(args.charge, charge_rate=args.charge_rate)
        self._injected: dict[URIRef, str] = {}
        self._refused: dict[tuple[URIRef, str], str] = {}
        self._rng = random.Random(args.seed)
        self._last = 0.0

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the simulation options."""
        parser.add_argument(
            "--charge",
            type=float,
            default=80.0,
            metavar="PERCENT",
            help="battery charge at first start, when the space has none (default 80)",
        )
        parser.add_argument(
            "--fault-rate",
            type=float,
            default=0.0,
            metavar="PER_HOUR",
            help="random wheel motor errors per simulated hour (default 0)",
        )
        parser.add_argument(
            "--charge-rate",
            type=float,
            default=CHARGE_RATE,
            metavar="PERCENT",
            help=f"charge gained per simulated second on the dock (default {CHARGE_RATE:g})",
        )
        parser.add_argument(
            "--switch-delay",
            type=float,
            default=SWITCH_DELAY,
            metavar="SECONDS",
            help=f"simulated seconds a device takes to switch modes (default {SWITCH_DELAY:g})",
        )
        parser.add_argument("--seed", type=int, help="random seed of the fault simulation")

    def on_start(self) -> None:
        """Start the simulation clock and meet the devices the space knows."""
        self._last = self.clock.now()
        self._discover()

    def _discover(self) -> None:
        """Create a driver per new device, in the state the space last reported.

        Called every tick: a robot written into the space after this agent
        started gets its drivers then.
        """
        for device in self.view.objects(self.robot, AC.has_device):
            if not isinstance(device, URIRef) or device in self.drivers:
                continue
            mode = self.view.text(device, AC.actual_mode) or "active"
            fault = self.view.text(device, AC.fault) or "none"
            rate = self.args.fault_rate if self.view.has_type(device, AC.WheelMotor) else 0.0
            self.drivers[device] = Driver(
                mode if mode in MODES else "active",
                fault if fault in FAULTS else "none",
                fault_rate=rate,
                switch_delay=self.args.switch_delay,
                rng=self._rng,
            )
            self._injected[device] = self.view.text(device, AC.simulate_fault) or "none"
            self.log.info("driver for %s (%s, fault %s)", device, mode, fault)
            if self.view.has_type(device, AC.Battery):
                charge = self.view.number(device, AC.charge_percent)
                if charge is not None:
                    self.battery.adopt(charge)
                self.log.info("battery at %.0f %%", self.battery.reported_percent())

    def on_change(self, change: Change) -> None:
        """Adopt a battery charge or level that another agent wrote (the HMI, a scenario).

        Without this the next reading would overwrite it with the simulated charge.
        """
        if change.agent == self.name or not any(p in _BATTERY for _s, p, _o in change.added):
            return  # most changes: not a battery's, no device lookup
        battery = self.view.device(self.robot, AC.Battery)
        written = {p: o for s, p, o in change.added if s == battery}
        if AC.charge_percent in written:
            try:
                percent = float(written[AC.charge_percent])
            except ValueError:
                self.log.warning("ignoring charge %r: not a number", written[AC.charge_percent])
                return
        elif AC.battery_level in written:
            levels = self.view.levels(AC.BatteryLevel, AC.below_percent) or DEFAULT_LEVELS
            try:
                percent = middle_of(str(written[AC.battery_level]), levels)
            except KeyError:
                self.log.warning("ignoring unknown battery level %r", written[AC.battery_level])
                return
        else:
            return
        self.battery.adopt(percent)
        self.log.info("battery set to %.0f %% by %s", percent, change.agent)

    def tick(self) -> None:
        """Obey commands, advance the drivers and the battery, publish what changed."""
        self._discover()
        now = self.clock.now()
        dt, self._last = now - self._last, now
        for device, driver in self.drivers.items():
            self._obey(device, driver, now)
            driver.step(now, dt)
        moving = self.view.text(self.robot, AC.navigation_status) == "navigating"
        self.battery.charging = self._on_charger(moving)
        self.battery.step(dt, drain(self.drivers.values()), moving)
        self.set_values(self._readings())

    def _on_charger(self, moving: bool) -> bool:
        """Return True while charging: the task is Charging, or any power task at the dock.

        A robot standing on its dock is on its charger, whatever the power task
        says (GoingToDock as it arrives, Docking).
        """
        task = self.view.task_type(self.view.value(self.robot, AC.current_task))
        if task == "Charging":
            return True
        dock = self.view.value(self.robot, AC.dock)
        docked = dock is not None and self.view.value(self.robot, AC.location) == dock
        return docked and not moving and task in ("GoingToDock", "Docking")

    def _obey(self, device: URIRef, driver: Driver, now: float) -> None:
        """Pass the commanded mode and any fault injection from the space to the driver."""
        mode = self.view.text(device, AC.running_mode)
        if mode is not None and not self._refuse(device, "mode", mode, MODES):
            driver.command(mode, now)
        fault = self.view.text(device, AC.simulate_fault) or "none"
        if fault != self._injected.get(device) and not self._refuse(device, "fault", fault, FAULTS):
            self._injected[device] = fault
            driver.inject(fault)
            self.log.info("%s: simulated fault %r", device, fault)

    def _refuse(self, device: URIRef, what: str, value: str, allowed: tuple[str, ...]) -> bool:
        """Return True (and warn once per value) if a command from the space is invalid."""
        if value in allowed:
            self._refused.pop((device, what), None)
            return False
        if self._refused.get((device, what)) != value:
            self._refused[(device, what)] = value
            self.log.warning("%s: ignoring unknown %s %r", device, what, value)
        return True

    def _readings(self) -> dict[tuple[Node, Node], Node | None]:
        """Return every state this monitor reports, as the space should hold it."""
        values: dict[tuple[Node, Node], Node | None] = {}
        for device, driver in self.drivers.items():
            values[(device, AC.actual_mode)] = literal(driver.mode)
            values[(device, AC.fault)] = literal(driver.fault)
        battery = self.view.device(self.robot, AC.Battery)
        if battery is not None:
            levels = self.view.levels(AC.BatteryLevel, AC.below_percent) or DEFAULT_LEVELS
            level = level_of(self.battery.percent, levels, charging=self.battery.charging)
            values[(battery, AC.battery_level)] = literal(level)
            values[(battery, AC.charge_percent)] = literal(self.battery.reported_percent())
        for laser in self.view.devices(self.robot, AC.LaserScanner):
            place = self.view.value(self.robot, AC.location)
            seen = obstacles_seen(self.view.text(place, AC.crowd_level), self.drivers[laser].mode)
            if seen is not None:
                values[(laser, AC.obstacles)] = literal(seen)
        return values


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the hardware monitor (see `--help`)."""
    return run_agent(HwMonitor, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
