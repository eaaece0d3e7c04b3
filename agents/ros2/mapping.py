"""The mapping file: which ROS 2 topics and nodes of a robot mean what in the space.

A TOML file (docs/ros2.md has the format and deploy/hospital-ros2-mapping.toml
the hospital's). `{robot}` in any string is the robot's local name, so one file
serves every robot of a fleet. Each table says what one converter reads or
drives; their message types are fixed by the converter:

    [[battery]]      sensor_msgs/msg/BatteryState     -> charge_percent, battery_level
    [[diagnostics]]  diagnostic_msgs/msg/DiagnosticArray -> fault (and actual_mode)
    [[place]]        std_msgs/msg/String (a place's local name) -> location
    [[pose]]         geometry_msgs/msg/PoseStamped    -> position_x, position_y
    [[lifecycle]]    running_mode -> lifecycle_msgs/srv/ChangeState of a managed node
    [[speed_limit]]  motion_speed -> nav2_msgs/msg/SpeedLimit (and SetParameters)
    [[task]]         current_task's type -> std_msgs/msg/String
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agents.ros2.codec import DISTROS
from agents.ros2.errors import MappingError
from agents.ros2.rmw import join_name

TYPES = {
    "battery": "sensor_msgs/msg/BatteryState",
    "diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "place": "std_msgs/msg/String",
    "pose": "geometry_msgs/msg/PoseStamped",
    "speed_limit": "nav2_msgs/msg/SpeedLimit",
    "task": "std_msgs/msg/String",
}
_KEYS = {
    "ros": {"domain", "distro", "namespace", "node", "service_timeout", "max_rate"},
    "battery": {"topic", "device", "max_rate"},
    "diagnostics": {"topic", "devices", "max_rate"},
    "place": {"topic", "max_rate"},
    "pose": {"topic", "max_rate"},
    "lifecycle": {"node", "device"},
    "speed_limit": {"topic", "device", "parameter_node", "parameter"},
    "task": {"topic"},
}


@dataclass(frozen=True)
class Inbound:
    """A topic whose messages become triples.

    Attributes:
        kind: the converter ("battery", "diagnostics", "place", "pose").
        topic: the fully qualified topic name.
        ros_type: its message type.
        max_rate: most writes per second into the space.
        device: the device local name it is about (battery), or None.
        devices: status name -> device local name (diagnostics).
    """

    kind: str
    topic: str
    ros_type: str
    max_rate: float
    device: str | None = None
    devices: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Lifecycle:
    """A device driven through the lifecycle of a managed node (`/robot1/screen`)."""

    device: str
    node: str


@dataclass(frozen=True)
class SpeedLimit:
    """Where the base's `motion_speed` goes: a topic, and maybe a controller parameter."""

    topic: str
    device: str
    parameter_node: str | None = None
    parameter: str | None = None


@dataclass(frozen=True)
class Mapping:
    """A mapping file, read for one robot.

    Attributes:
        domain: ROS domain id.
        distro: "jazzy" or "kilted" (which type store, hence which hashes).
        namespace: the robot's namespace (`/robot1`).
        node: the bridge's node name in that namespace.
        service_timeout: seconds a service call may take before it is reported failed.
        inbound: topics to triples.
        lifecycle: devices driven through managed nodes.
        speed_limits: motion speeds to speed limits.
        tasks: topics the current task's type is published on.
    """

    domain: int
    distro: str
    namespace: str
    node: str
    service_timeout: float
    inbound: tuple[Inbound, ...]
    lifecycle: tuple[Lifecycle, ...]
    speed_limits: tuple[SpeedLimit, ...]
    tasks: tuple[str, ...]


def _text(value: Any, robot: str, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise MappingError(f"{where} must be a non-empty string, got {value!r}")
    return value.replace("{robot}", robot)


def _number(value: Any, where: str, *, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or (positive and value <= 0):
        raise MappingError(f"{where} must be a positive number, got {value!r}")
    return float(value)


def _tables(data: dict[str, Any], name: str) -> list[dict[str, Any]]:
    found = data.get(name, [])
    if isinstance(found, dict):
        found = [found]
    if not isinstance(found, list) or not all(isinstance(t, dict) for t in found):
        raise MappingError(f"[[{name}]] must be tables")
    for index, table in enumerate(found):
        unknown = set(table) - _KEYS[name]
        if unknown:
            raise MappingError(f"[[{name}]] #{index + 1}: unknown keys {sorted(unknown)}")
    return found


def parse_mapping(text: str, robot: str, origin: str = "<mapping>") -> Mapping:
    """Parse a mapping for one robot.

    Raises:
        MappingError: not TOML (with line and column), an unknown table or key,
            a missing or ill-typed value, or an invalid ROS name.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MappingError(f"{origin}: {exc}") from exc
    unknown = set(data) - set(_KEYS)
    if unknown:
        raise MappingError(f"{origin}: unknown tables {sorted(unknown)} (known: {sorted(_KEYS)})")
    try:
        return _mapping(data, robot)
    except MappingError as exc:
        raise MappingError(f"{origin}: {exc}") from exc
    except ValueError as exc:
        raise MappingError(f"{origin}: {exc}") from exc


def _mapping(data: dict[str, Any], robot: str) -> Mapping:
    ros = data.get("ros", {})
    if not isinstance(ros, dict) or set(ros) - _KEYS["ros"]:
        raise MappingError(f"[ros]: unknown keys {sorted(set(ros) - _KEYS['ros'])}")
    domain = ros.get("domain", 0)
    if isinstance(domain, bool) or not isinstance(domain, int) or not 0 <= domain <= 232:
        raise MappingError(f"[ros] domain must be an integer 0-232, got {domain!r}")
    namespace = join_name("/", _text(ros.get("namespace", "/{robot}"), robot, "[ros] namespace"))
    rate = _number(ros.get("max_rate", 5.0), "[ros] max_rate")

    def topic(table: dict[str, Any], where: str) -> str:
        return join_name(namespace, _text(table.get("topic"), robot, f"{where} topic"))

    inbound = []
    for kind in ("battery", "diagnostics", "place", "pose"):
        for table in _tables(data, kind):
            where = f"[[{kind}]]"
            devices = table.get("devices", {})
            if not isinstance(devices, dict):
                raise MappingError(f"{where} devices must be a table of name = device")
            inbound.append(
                Inbound(
                    kind=kind,
                    topic=topic(table, where),
                    ros_type=TYPES[kind],
                    max_rate=_number(table.get("max_rate", rate), f"{where} max_rate"),
                    device=_text(table.get("device"), robot, f"{where} device")
                    if kind == "battery"
                    else None,
                    devices={
                        k: _text(v, robot, f"{where} devices.{k}") for k, v in devices.items()
                    },
                )
            )
    lifecycle = tuple(
        Lifecycle(
            device=_text(t.get("device"), robot, "[[lifecycle]] device"),
            node=join_name(namespace, _text(t.get("node"), robot, "[[lifecycle]] node")),
        )
        for t in _tables(data, "lifecycle")
    )
    speed_limits = []
    for t in _tables(data, "speed_limit"):
        node = t.get("parameter_node")
        speed_limits.append(
            SpeedLimit(
                topic=topic(t, "[[speed_limit]]"),
                device=_text(t.get("device"), robot, "[[speed_limit]] device"),
                parameter_node=None
                if node is None
                else join_name(namespace, _text(node, robot, "[[speed_limit]] parameter_node")),
                parameter=None
                if t.get("parameter") is None
                else _text(t["parameter"], robot, "[[speed_limit]] parameter"),
            )
        )
    distro = ros.get("distro", "jazzy")
    if distro not in DISTROS:
        raise MappingError(f"[ros] distro must be one of {sorted(DISTROS)}, got {distro!r}")
    return Mapping(
        domain=domain,
        distro=distro,
        namespace=namespace,
        node=_text(ros.get("node", "tspace_bridge"), robot, "[ros] node"),
        service_timeout=_number(ros.get("service_timeout", 2.0), "[ros] service_timeout"),
        inbound=tuple(inbound),
        lifecycle=lifecycle,
        speed_limits=tuple(speed_limits),
        tasks=tuple(topic(t, "[[task]]") for t in _tables(data, "task")),
    )


def read_mapping(path: str | Path, robot: str) -> Mapping:
    """Read a mapping file for one robot (see `parse_mapping`).

    Raises:
        MappingError: the file cannot be read or is malformed.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise MappingError(f"cannot read mapping file {path}: {exc.strerror}") from exc
    return parse_mapping(text, robot, str(path))
