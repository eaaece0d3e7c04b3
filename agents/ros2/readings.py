"""What a ROS 2 message says about the robot, as the space's vocabulary says it.

Pure functions from a decoded message (and what the view knows: levels,
devices, places) to single-valued states `(subject, predicate) -> object`,
the shape `Agent.set_values` writes. Values are already rounded the way the
hardware monitor reports them, so that equal readings compare equal and a
100 Hz topic changes the space only when what it says changes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from decimal import Decimal
from typing import Any

from rdflib import Literal, URIRef
from rdflib.term import Node

from agents.sim.battery import level_of
from agents.sim.devices import MODES
from agents.view import AC

Readings = dict[tuple[Node, Node], Node | None]

# sensor_msgs/msg/BatteryState.power_supply_status
CHARGING, FULL = 1, 4
# diagnostic_msgs/msg/DiagnosticStatus.level -> ac:fault
FAULT_OF_LEVEL = {0: "none", 1: "warning", 2: "error", 3: "warning"}
# lifecycle_msgs/msg/State primary states -> ac:actual_mode
MODE_OF_STATE = {1: "disabled", 2: "stand-by", 3: "active", 4: "disabled"}
STATE_OF_MODE = {"disabled": 1, "stand-by": 2, "active": 3}
STEP = 5


def battery(message: Any, device: URIRef, levels: Mapping[str, float]) -> Readings:
    """Return the charge (5 % steps) and level a BatteryState reports; {} if it has no charge.

    `percentage` is 0-1 in ROS (NaN when unmeasured: then charge / capacity is used).
    A battery on its charger (CHARGING or FULL) is never in the lowest level.
    """
    fraction = float(message.percentage)
    if math.isnan(fraction) and message.capacity > 0 and not math.isnan(message.charge):
        fraction = float(message.charge) / float(message.capacity)
    if math.isnan(fraction):
        return {}
    percent = min(100.0, max(0.0, fraction * 100.0))
    charging = message.power_supply_status in (CHARGING, FULL)
    return {
        (device, AC.charge_percent): Literal(int(percent // STEP * STEP)),
        (device, AC.battery_level): Literal(level_of(percent, levels, charging=charging)),
    }


def status_device(name: str, devices: Mapping[str, URIRef]) -> URIRef | None:
    """Return the device a DiagnosticStatus name is about: exact, or its last `/` or `: ` part."""
    for candidate in (name, name.rsplit("/", 1)[-1], name.rsplit(": ", 1)[-1]):
        found = devices.get(candidate.strip())
        if found is not None:
            return found
    return None


def diagnostics(message: Any, devices: Mapping[str, URIRef]) -> Readings:
    """Return the faults (and reported modes) of the mapped devices a DiagnosticArray names.

    A status's level gives `ac:fault`; a `mode` key whose value is a running mode
    gives `ac:actual_mode` (for devices that are not managed nodes).
    """
    found: Readings = {}
    for status in message.status:
        device = status_device(status.name, devices)
        if device is None:
            continue
        found[(device, AC.fault)] = Literal(FAULT_OF_LEVEL.get(int(status.level), "warning"))
        for pair in status.values:
            if pair.key == "mode" and pair.value in MODES:
                found[(device, AC.actual_mode)] = Literal(pair.value)
    return found


def place(message: Any, robot: URIRef, places: set[URIRef]) -> Readings:
    """Return the robot's location named by a String (a place's local name); {} if unknown."""
    name = message.data.strip().removeprefix("ac:")
    where = AC[name] if name else None
    if where is None or where not in places:
        return {}
    return {(robot, AC.location): where}


def pose(message: Any, robot: URIRef) -> Readings:
    """Return the robot's position on the map (cm precision) from a PoseStamped."""
    position = message.pose.position
    if math.isnan(position.x) or math.isnan(position.y):
        return {}
    return {
        (robot, AC.position_x): Literal(Decimal(f"{position.x:.2f}")),
        (robot, AC.position_y): Literal(Decimal(f"{position.y:.2f}")),
    }
