"""CDR and RIHS01 type hashes for ROS 2 types, through rosbags: no ROS installation.

The types are rosbags' Jazzy or Kilted store plus the definitions shipped in
`agents/ros2/interfaces/<pkg>/{msg,srv}/` (services are not in rosbags' stores;
nav2_msgs is not either). A service `pkg/srv/X` becomes the messages
`X_Request`, `X_Response`, `X_Event` and `X` itself, as rosidl describes it, so
that its hash is the one rmw_zenoh puts in the service's key.

rosbags hashes a `.msg` `char` as IDL char; rosidl reads `char` in `.msg` files
as uint8, and the published hashes follow rosidl (service_msgs/ServiceEventInfo,
and so every service, depends on it), so the store is built with `char` as uint8.
Both are one byte in CDR.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import TypesysError

from agents.ros2.errors import MalformedMessage, UnknownRosType

INTERFACES = Path(__file__).with_name("interfaces")
DISTROS = {"jazzy": Stores.ROS2_JAZZY, "kilted": Stores.ROS2_KILTED}
_EMPTY_MEMBER = "uint8 structure_needs_at_least_one_member\n"
_DTYPES = {
    "bool": np.bool_, "byte": np.uint8, "char": np.uint8, "uint8": np.uint8, "int8": np.int8,
    "uint16": np.uint16, "int16": np.int16, "uint32": np.uint32, "int32": np.int32,
    "uint64": np.uint64, "int64": np.int64, "float32": np.float32, "float64": np.float64,
}  # fmt: skip
_DECODE_ERRORS = (
    SerdeError,
    struct.error,
    IndexError,
    ValueError,
    UnicodeDecodeError,
    AssertionError,
)


def _uint8_for_char(desc: Any) -> Any:
    kind, rest = desc
    if kind == Nodetype.BASE and rest[0] == "char":
        return (Nodetype.BASE, ("uint8", rest[1]))
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        return (kind, (_uint8_for_char(rest[0]), rest[1]))
    return desc


def _fields(text: str, package: str) -> Any:
    """Return rosbags' field list of a message body, relative names resolved in `package`."""
    ((_, definition),) = get_types_from_msg(text, f"{package}/msg/Body").items()
    return definition


def service_types(name: str, text: str) -> dict[str, Any]:
    """Return the four message types rosidl makes of a `.srv` named `pkg/srv/X`."""
    package = name.split("/")[0]
    lines = text.splitlines(keepends=True)
    cut = next((i for i, line in enumerate(lines) if line.strip() == "---"), len(lines))
    request, response = "".join(lines[:cut]), "".join(lines[cut + 1 :])
    ref = (Nodetype.NAME, name)
    types = {
        f"{name}_Request": _fields(request if request.strip() else _EMPTY_MEMBER, package),
        f"{name}_Response": _fields(response if response.strip() else _EMPTY_MEMBER, package),
    }
    types[f"{name}_Event"] = (
        [],
        [
            ("info", (Nodetype.NAME, "service_msgs/msg/ServiceEventInfo")),
            ("request", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{name}_Request"), 1))),
            ("response", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{name}_Response"), 1))),
        ],
    )
    types[name] = (
        [],
        [
            ("request_message", (ref[0], f"{name}_Request")),
            ("response_message", (ref[0], f"{name}_Response")),
            ("event_message", (ref[0], f"{name}_Event")),
        ],
    )
    return types


def shipped_types(roots: Iterable[Path]) -> dict[str, Any]:
    """Read every `<pkg>/msg/*.msg` and `<pkg>/srv/*.srv` under `roots`."""
    types: dict[str, Any] = {}
    for root in roots:
        for path in sorted(root.glob("*/msg/*.msg")):
            name = f"{path.parts[-3]}/msg/{path.stem}"
            types[name] = _fields(path.read_text(encoding="utf-8"), path.parts[-3])
        for path in sorted(root.glob("*/srv/*.srv")):
            name = f"{path.parts[-3]}/srv/{path.stem}"
            types.update(service_types(name, path.read_text(encoding="utf-8")))
    return types


class Codec:
    """Encode, decode and hash ROS 2 messages of one distribution.

    Building one reads the type store (~0.1 s): make one per process.

    Args:
        distro: "jazzy" or "kilted".
        extra: more folders laid out as `<pkg>/msg/*.msg`, `<pkg>/srv/*.srv`.

    Raises:
        ValueError: unknown distribution, or a shipped definition rosbags rejects.
    """

    def __init__(self, distro: str = "jazzy", extra: Iterable[Path] = ()) -> None:
        if distro not in DISTROS:
            raise ValueError(f"unknown ROS 2 distribution {distro!r}: one of {sorted(DISTROS)}")
        self.distro = distro
        base = get_typestore(DISTROS[distro])
        defs = {
            name: (consts, [(f, _uint8_for_char(d)) for f, d in fields])
            for name, (consts, fields) in base.fielddefs.items()
        }
        try:
            defs.update(shipped_types([INTERFACES, *extra]))
            self._store = get_typestore(Stores.EMPTY)
            self._store.register(defs)
        except TypesysError as exc:
            raise ValueError(f"message definitions: {exc}") from exc
        self._hashes: dict[str, str] = {}

    def knows(self, ros_type: str) -> bool:
        """Return True if `ros_type` (`pkg/msg/X` or `pkg/srv/X`) can be used."""
        return ros_type in self._store.fielddefs

    def _check(self, ros_type: str) -> None:
        if ros_type not in self._store.fielddefs:
            raise UnknownRosType(
                f"unknown ROS type {ros_type!r} (not in rosbags' {self.distro} store, "
                f"nor shipped as .msg/.srv)"
            )

    def type_hash(self, ros_type: str) -> str:
        """Return the RIHS01 hash of a message or service type.

        Raises:
            UnknownRosType: the type is not known.
        """
        found = self._hashes.get(ros_type)
        if found is None:
            self._check(ros_type)
            found = self._hashes[ros_type] = self._store.hash_rihs01(ros_type)
        return found

    def new(self, ros_type: str, **values: Any) -> Any:
        """Return a message with `values` set and every other field at its zero value.

        Nested messages may be given as dicts.

        Raises:
            UnknownRosType: the type is not known.
        """
        self._check(ros_type)
        _, fields = self._store.fielddefs[ros_type]
        args = {}
        for name, desc in fields:
            value = values.pop(name, None)
            if isinstance(value, Mapping) and desc[0] == Nodetype.NAME:
                value = self.new(desc[1], **value)
            args[name] = self._zero(desc) if value is None else value
        if values:
            raise TypeError(f"{ros_type} has no fields {sorted(values)}")
        return self._store.types[ros_type](**args)

    def _zero(self, desc: Any) -> Any:
        kind, rest = desc
        if kind == Nodetype.BASE:
            base = rest[0]
            return "" if base == "string" else False if base == "bool" else _DTYPES[base](0).item()
        if kind == Nodetype.NAME:
            return self.new(rest)
        (sub_kind, sub), size = rest
        if sub_kind == Nodetype.BASE and sub[0] != "string":
            return np.zeros(size if kind == Nodetype.ARRAY else 0, dtype=_DTYPES[sub[0]])
        if kind == Nodetype.ARRAY:
            return [self._zero((sub_kind, sub)) for _ in range(size)]
        return []

    def encode(self, ros_type: str, message: Any) -> bytes:
        """Return the CDR of a message, with its 4-byte encapsulation header (little endian).

        Raises:
            UnknownRosType: the type is not known.
        """
        self._check(ros_type)
        return bytes(self._store.serialize_cdr(message, ros_type))

    def decode(self, ros_type: str, data: bytes) -> Any:
        """Return the message a CDR payload (with its encapsulation header) holds.

        Raises:
            UnknownRosType: the type is not known.
            MalformedMessage: the payload is not a valid `ros_type`.
        """
        self._check(ros_type)
        if len(data) < 4 or data[0] != 0 or data[1] not in (0, 1):
            raise MalformedMessage(f"{ros_type}: no CDR encapsulation header")
        try:
            return self._store.deserialize_cdr(data, ros_type)
        except _DECODE_ERRORS as exc:
            raise MalformedMessage(f"{ros_type}: {type(exc).__name__}: {exc}") from exc
