"""rmw_zenoh's naming on the wire: data keys, liveliness tokens and QoS strings.

A ROS 2 robot on rmw_zenoh (Jazzy >= 0.2.4, Kilted, Rolling) names every topic
and service `<domain>/<name without leading slash>/<pkg>::<msg|srv>::dds_::<Type>_/RIHS01_<hash>`
and announces every entity with a liveliness token

    @ros2_lv/<domain>/<zid>/<nid>/<eid>/<NN|MP|MS|SS|SC>/<enclave>/<namespace>/<node>
             [/<name>/<type>/<hash>/<qos>]

in which `/` inside a name is written `%` and an empty name is `%`. Both are
built and parsed here and nowhere else; docs/ros2.md gives the sources.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum

from agents.ros2.errors import MalformedToken

ADMIN_SPACE = "@ros2_lv"
EMPTY = "%"
_NAME_RE = re.compile(r"^/?[A-Za-z_~{][A-Za-z0-9_/{}~]*$")


class EntityKind(Enum):
    """What a liveliness token announces, as rmw_zenoh writes it."""

    NODE = "NN"
    PUBLISHER = "MP"
    SUBSCRIBER = "MS"
    SERVICE = "SS"
    CLIENT = "SC"


def mangle(name: str) -> str:
    """Return a ROS name as one key chunk: `/` becomes `%`, the empty name `%`."""
    return name.replace("/", "%") if name else EMPTY


def demangle(chunk: str) -> str:
    """Return the ROS name a key chunk holds (inverse of `mangle`)."""
    return "" if chunk == EMPTY else chunk.replace("%", "/")


def join_name(namespace: str, name: str) -> str:
    """Return the fully qualified name of `name` in `namespace` (`/robot1`, `battery_state`).

    An absolute `name` stays as it is; a relative one goes under the namespace.

    Raises:
        ValueError: the result is not a valid ROS name.
    """
    full = name if name.startswith("/") else f"{namespace.rstrip('/')}/{name}"
    if not _NAME_RE.match(full) or "//" in full or (full.endswith("/") and full != "/"):
        raise ValueError(f"not a valid ROS name: {full!r}")
    return full


def dds_type_name(ros_type: str) -> str:
    """Return rmw_zenoh's spelling of a type: `sensor_msgs/msg/X` -> `sensor_msgs::msg::dds_::X_`.

    Raises:
        ValueError: `ros_type` is not `pkg/msg/Name` or `pkg/srv/Name`.
    """
    parts = ros_type.split("/")
    if len(parts) != 3 or parts[1] not in ("msg", "srv") or not all(parts):
        raise ValueError(f"not a ROS 2 type name (pkg/msg/Name): {ros_type!r}")
    pkg, kind, name = parts
    return f"{pkg}::{kind}::dds_::{name}_"


def ros_type_name(dds_name: str) -> str:
    """Return `pkg/msg/Name` for rmw_zenoh's `pkg::msg::dds_::Name_` (inverse of `dds_type_name`).

    Raises:
        ValueError: `dds_name` is not in rmw_zenoh's spelling.
    """
    parts = dds_name.split("::")
    if len(parts) != 4 or parts[2] != "dds_" or not parts[3].endswith("_"):
        raise ValueError(f"not an rmw_zenoh type name: {dds_name!r}")
    return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"


def data_key(domain: int, full_name: str, ros_type: str, type_hash: str) -> str:
    """Return the key a topic is published on, or a service is queried on."""
    return f"{domain}/{full_name.strip('/')}/{dds_type_name(ros_type)}/{type_hash}"


@dataclass(frozen=True)
class Qos:
    """The QoS an endpoint announces; defaults are ROS 2's default profile.

    Attributes:
        reliable: RELIABLE (True) or BEST_EFFORT.
        transient_local: TRANSIENT_LOCAL (True) or VOLATILE.
        keep_all: KEEP_ALL (True) or KEEP_LAST.
        depth: history depth of KEEP_LAST.
    """

    reliable: bool = True
    transient_local: bool = False
    keep_all: bool = False
    depth: int = 10

    def encode(self) -> str:
        """Return the token's QoS chunk; a value equal to the default is left empty.

        `<reliability>:<durability>:<history>,<depth>:<deadline>:<lifespan>:<liveliness>`
        with rmw's enum values (reliable 1, best effort 2; transient local 1,
        volatile 2; keep last 1, keep all 2). Deadline, lifespan and liveliness
        are always the defaults here.
        """
        reliability = "" if self.reliable else "2"
        durability = "1" if self.transient_local else ""
        history = "2" if self.keep_all else ""
        depth = "" if self.keep_all else str(self.depth)
        return f"{reliability}:{durability}:{history},{depth}:,:,:,,"

    @classmethod
    def decode(cls, chunk: str) -> Qos:
        """Parse a token's QoS chunk.

        Raises:
            MalformedToken: the chunk does not have the shape `encode` writes.
        """
        parts = chunk.split(":")
        if len(parts) < 3 or "," not in parts[2]:
            raise MalformedToken(f"QoS {chunk!r} is not rel:dur:hist,depth:...")
        history, _, depth = parts[2].partition(",")
        try:
            return cls(
                reliable=parts[0] in ("", "0", "1"),
                transient_local=parts[1] == "1",
                keep_all=history == "2",
                depth=int(depth) if depth else 10,
            )
        except ValueError as exc:
            raise MalformedToken(f"QoS {chunk!r}: depth {depth!r} is not a number") from exc


@dataclass(frozen=True)
class Endpoint:
    """A topic or service an entity other than a node is about."""

    name: str
    ros_type: str
    type_hash: str
    qos: Qos = Qos()


@dataclass(frozen=True)
class Entity:
    """One entity of the ROS graph, as its liveliness token describes it.

    Attributes:
        domain: the ROS domain id.
        zid: the Zenoh session id of the process holding it.
        node_id, entity_id: ids unique within that session (equal for a node).
        kind: what it is.
        namespace: the node's namespace ("/" or "/robot1").
        node: the node's name.
        enclave: the security enclave ("" when none).
        endpoint: the topic or service, for all but nodes.
    """

    domain: int
    zid: str
    node_id: int
    entity_id: int
    kind: EntityKind
    namespace: str
    node: str
    enclave: str = ""
    endpoint: Endpoint | None = None

    def token(self) -> str:
        """Return the liveliness key announcing this entity."""
        namespace = "" if self.namespace == "/" else self.namespace
        chunks = [
            ADMIN_SPACE,
            str(self.domain),
            self.zid,
            str(self.node_id),
            str(self.entity_id),
            self.kind.value,
            mangle(self.enclave),
            mangle(namespace),
            mangle(self.node),
        ]
        if self.endpoint is not None:
            e = self.endpoint
            chunks += [mangle(e.name), dds_type_name(e.ros_type), e.type_hash, e.qos.encode()]
        return "/".join(chunks)

    @property
    def full_node_name(self) -> str:
        """Return the node's fully qualified name (`/robot1/screen`)."""
        return join_name(self.namespace, self.node)


def parse_token(key: str) -> Entity:
    """Return the entity a liveliness key announces.

    Raises:
        MalformedToken: the key is not an rmw_zenoh liveliness token.
    """
    parts = key.split("/")
    if len(parts) < 9 or parts[0] != ADMIN_SPACE:
        raise MalformedToken(f"not an rmw_zenoh liveliness token: {key!r}")
    try:
        kind = EntityKind(parts[5])
        domain, node_id, entity_id = int(parts[1]), int(parts[3]), int(parts[4])
    except ValueError as exc:
        raise MalformedToken(f"liveliness token {key!r}: {exc}") from exc
    namespace = demangle(parts[7]) or "/"
    endpoint = None
    if kind is not EntityKind.NODE:
        if len(parts) != 13:
            raise MalformedToken(f"liveliness token {key!r} lacks name/type/hash/qos")
        try:
            ros_type = ros_type_name(parts[10])
        except ValueError as exc:
            raise MalformedToken(str(exc)) from exc
        endpoint = Endpoint(demangle(parts[9]), ros_type, parts[11], Qos.decode(parts[12]))
    return Entity(
        domain=domain,
        zid=parts[2],
        node_id=node_id,
        entity_id=entity_id,
        kind=kind,
        namespace=namespace,
        node=demangle(parts[8]),
        enclave=demangle(parts[6]),
        endpoint=endpoint,
    )
