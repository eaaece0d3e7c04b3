"""The ROS 2 bridge agent: one robot on rmw_zenoh, seen and driven through the space.

ROS -> space: the mapped topics' messages become the robot's states (battery
charge and level, device faults and modes, location, position), at most
`max_rate` writes a second per topic and only when what they say changed.
Space -> ROS: a device's `running_mode` becomes lifecycle transitions of its
managed node, the base's `motion_speed` a nav2 SpeedLimit (and a controller
parameter), the current task a String; the mode a node reports (or that it did
not answer) is written back. Everything it declares on the ROS graph carries an
rmw_zenoh liveliness token. Zenoh callbacks decode and compare only; writes and
service calls happen on the agent's loop and the drivers' threads.
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
from dataclasses import dataclass, replace
from typing import Any

from rdflib import RDF, Literal, URIRef

from agents.base import Agent, Values, local_name
from agents.ros2.codec import Codec
from agents.ros2.drivers import ManagedNode, Parameter
from agents.ros2.graph import Graph
from agents.ros2.mapping import Inbound, Mapping, read_mapping
from agents.ros2.node import Node, Publisher
from agents.ros2.readings import (
    MODE_OF_STATE,
    STATE_OF_MODE,
    Readings,
    battery,
    diagnostics,
    place,
    pose,
)
from agents.ros2.rmw import Entity, EntityKind, Qos
from agents.sim.battery import DEFAULT_LEVELS
from agents.view import AC
from space import Change, SpaceError

PLACES = (AC.Place, AC.Room, AC.Dock, AC.Corridor)
WATCHED = {AC.running_mode, AC.motion_speed, AC.current_task, AC.meters_per_second}


@dataclass
class Topic:
    """One inbound topic: the last reading offered, and when the space may be written next."""

    spec: Inbound
    last: Readings | None = None
    pending: bool = False
    next_write: float = 0.0
    received: int = 0


@dataclass
class Outbound:
    """One topic the bridge publishes: its publisher and the last message sent."""

    publisher: Publisher
    last: Any = None


class Ros2Bridge(Agent):
    """Bridge a ROS 2 robot on rmw_zenoh and the space, as a mapping file says."""

    kind = "ros2"

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.mapping: Mapping | None = None
        self.codec: Codec | None = None
        self.node: Node | None = None
        self.graph: Graph | None = None
        self.topics: list[Topic] = []
        self.managed: dict[URIRef, ManagedNode] = {}
        self.parameters: dict[URIRef, Parameter] = {}
        self.speed: dict[URIRef, Outbound] = {}
        self.tasks: list[Outbound] = []
        self._wished: dict[URIRef, int | None] = {}
        self._levels: dict[str, float] = dict(DEFAULT_LEVELS)
        self._places: set[URIRef] = set()

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the mapping file and the ROS domain."""
        parser.add_argument("--mapping", required=True, metavar="FILE", help="the mapping file")
        parser.add_argument(
            "--domain",
            type=int,
            metavar="ID",
            help="ROS domain id (default: $ROS_DOMAIN_ID, else the mapping's, else 0)",
        )

    def setup(self) -> None:
        """Read the mapping and the types, then open the space (see `Agent.setup`).

        Raises:
            MappingError: the mapping file is unreadable or malformed.
            UnknownRosType: a type the mapping needs is not known.
        """
        mapping = read_mapping(self.args.mapping, local_name(self.robot))
        domain = self.args.domain
        if domain is None and os.environ.get("ROS_DOMAIN_ID", "").isdigit():
            domain = int(os.environ["ROS_DOMAIN_ID"])
        if domain is not None:
            mapping = replace(mapping, domain=domain)
        self.mapping, self.codec = mapping, Codec(mapping.distro)
        for spec in mapping.inbound:
            self.codec.type_hash(spec.ros_type)
        super().setup()

    def shutdown(self) -> None:
        """Stop the drivers, leave the ROS graph, then close the space."""
        if self.topics:
            received = sum(t.received for t in self.topics)
            self.log.info("received %d messages on %d topics", received, len(self.topics))
        for driver in [*self.managed.values(), *self.parameters.values()]:
            driver.close()
        if self.node is not None:
            self.node.close()
        if self.graph is not None:
            self.graph.close()
        self.node = self.graph = None
        super().shutdown()

    # Joining the ROS graph

    def on_start(self) -> None:
        """Join the ROS graph: node, subscriptions, publishers, clients; then drive."""
        assert self.ts is not None and self.mapping is not None and self.codec is not None
        m = self.mapping
        self._learn()
        self.node = Node(
            self.ts.session, self.codec, m.domain, m.namespace, m.node, itertools.count()
        )
        self.node.open()
        for spec in m.inbound:
            topic = Topic(spec)
            self.topics.append(topic)
            self.node.subscribe(
                spec.topic, spec.ros_type, lambda msg, _att, t=topic: self._on_message(t, msg)
            )
        for s in m.speed_limits:
            device = AC[s.device]
            self.speed[device] = Outbound(
                self.node.publisher(s.topic, "nav2_msgs/msg/SpeedLimit", Qos(depth=1))
            )
            if s.parameter_node and s.parameter:
                self.parameters[device] = Parameter(
                    self.node,
                    s.parameter_node,
                    s.parameter,
                    m.service_timeout,
                    lambda ok, why, d=device: self.call_soon(
                        lambda: self._on_parameter(d, ok, why)
                    ),
                )
        for name in m.tasks:
            self.tasks.append(
                Outbound(self.node.publisher(name, "std_msgs/msg/String", Qos(depth=1)))
            )
        for spec in m.lifecycle:
            device = AC[spec.device]
            self.managed[device] = ManagedNode(
                self.node,
                spec.node,
                m.service_timeout,
                lambda state, why, d=device: self.call_soon(lambda: self._on_state(d, state, why)),
            )
        for driver in [*self.managed.values(), *self.parameters.values()]:
            driver.start()
        # Last: its callbacks read what was just built, from Zenoh's threads.
        self.graph = Graph(self._on_graph).open(self.ts.session, m.domain)
        for device, driver in self.managed.items():
            wish = self._wish(device)
            self._wished[device] = wish
            driver.want(wish)
        self.log.info(
            "ROS 2 node %s on domain %d (%s): %d topics in, %d lifecycle nodes, %d out",
            self.node.entity.full_node_name,
            m.domain,
            m.distro,
            len(self.topics),
            len(self.managed),
            len(self.speed) + len(self.tasks),
        )
        self._drive()

    def _on_graph(self, entity: Entity, alive: bool) -> None:
        """Follow the graph (on a Zenoh thread): log arrivals, resend to new subscribers."""
        if not alive or self.node is None or entity.zid == self.node.entity.zid:
            return
        endpoint = entity.endpoint
        if entity.kind is EntityKind.SUBSCRIBER and endpoint is not None:
            for out in [*self.speed.values(), *self.tasks]:
                ours = out.publisher.entity.endpoint
                if ours is not None and ours.name == endpoint.name:
                    self.call_soon(lambda o=out: self._resend(o))
        elif entity.kind is EntityKind.PUBLISHER and endpoint is not None:
            for topic in self.topics:
                if topic.spec.topic == endpoint.name:
                    self.log.info(
                        "publisher of %s (%s) on node %s",
                        endpoint.name,
                        endpoint.ros_type,
                        entity.full_node_name,
                    )
        elif entity.kind is EntityKind.SERVICE and endpoint is not None:
            for device, driver in self.managed.items():
                if endpoint.name == f"{driver.node}/change_state":
                    self.log.info("managed node %s is up", driver.node)
                    driver.want(self._wished.get(device))

    # ROS -> space

    def _learn(self) -> None:
        """Copy from the view what the Zenoh threads need (levels, places), as new objects."""
        self._levels = self.view.levels(AC.BatteryLevel, AC.below_percent) or dict(DEFAULT_LEVELS)
        self._places = {
            p
            for cls in PLACES
            for p in self.view.graph.subjects(RDF.type, cls)
            if isinstance(p, URIRef)
        }

    def _readings(self, spec: Inbound, message: Any) -> Readings:
        if spec.kind == "battery":
            assert spec.device is not None
            return battery(message, AC[spec.device], self._levels)
        if spec.kind == "diagnostics":
            return diagnostics(message, {k: AC[v] for k, v in spec.devices.items()})
        if spec.kind == "place":
            return place(message, self.robot, self._places)
        return pose(message, self.robot)

    def _on_message(self, topic: Topic, message: Any) -> None:
        """Turn a message into readings (on a Zenoh thread); hand over only what changed."""
        topic.received += 1
        try:
            readings = self._readings(topic.spec, message)
        except (ValueError, TypeError, AttributeError, OverflowError) as exc:
            self.log.warning("%s: message skipped: %s", topic.spec.topic, exc)
            return
        if readings and readings != topic.last:
            topic.last = readings
            self.call_soon(lambda: self._flush(topic))

    def _flush(self, topic: Topic, now: float | None = None) -> None:
        """Write a topic's last readings if its rate allows, else leave them for `tick`."""
        now = time.monotonic() if now is None else now
        if now < topic.next_write:
            topic.pending = True
            return
        topic.pending = False
        topic.next_write = now + 1.0 / topic.spec.max_rate
        if topic.last:
            try:
                self.set_values(topic.last, cause=None)
            except SpaceError:
                topic.last = None  # not written: the next message offers it again
                raise

    # Space -> ROS

    def on_change(self, change: Change) -> None:
        """Drive the robot when a change touches what the bridge obeys."""
        if any(
            p in WATCHED
            for _, p, _ in [
                *change.added,
                *change.inferred_added,
                *change.removed,
                *change.inferred_removed,
            ]
        ):
            self._drive()
        if any(p in (AC.below_percent, RDF.type) for _, p, _ in change.added):
            self._learn()

    def tick(self) -> None:
        """Write readings whose rate window opened."""
        now = time.monotonic()
        for topic in self.topics:
            if topic.pending and now >= topic.next_write:
                self._flush(topic, now)

    def _wish(self, device: URIRef) -> int | None:
        mode = self.view.text(device, AC.running_mode)
        return STATE_OF_MODE.get(mode) if mode is not None else None

    def _drive(self) -> None:
        """Pass running modes, speeds and the task to the robot where they changed."""
        assert self.codec is not None
        for device, driver in self.managed.items():
            wish = self._wish(device)
            if wish != self._wished.get(device):
                self._wished[device] = wish
                self.log.info("%s: toward lifecycle state %s", driver.node, wish)
                driver.want(wish)
        speeds = self.view.levels(AC.SpeedLevel, AC.meters_per_second)
        for device, out in self.speed.items():
            limit = speeds.get(self.view.text(device, AC.motion_speed) or "")
            if limit is not None and limit != out.last:
                out.last = limit
                self._resend(out)
                if device in self.parameters:
                    self.parameters[device].want(limit)
        task = self.view.task_type(self.view.value(self.robot, AC.current_task))
        for out in self.tasks:
            if task is not None and task != out.last:
                out.last = task
                self._resend(out)

    def _resend(self, out: Outbound) -> None:
        """Publish an outbound topic's current value (again, for a late subscriber)."""
        assert self.codec is not None
        if out.last is None:
            return
        endpoint = out.publisher.entity.endpoint
        assert endpoint is not None
        if endpoint.ros_type == "nav2_msgs/msg/SpeedLimit":
            ns = time.time_ns()
            stamp = {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}
            message = self.codec.new(
                endpoint.ros_type,
                header={"stamp": stamp},
                percentage=False,
                speed_limit=float(out.last),
            )
        else:
            message = self.codec.new(endpoint.ros_type, data=str(out.last))
        out.publisher.publish(message)
        self.log.info("published %s on %s", out.last, endpoint.name)

    # Answers

    def _on_state(self, device: URIRef, state: int | None, why: str | None) -> None:
        """Write the mode a managed node says it is in, or that it did not answer."""
        values: Values = {(device, AC.ros_status): Literal("ok" if why is None else why)}
        if state is not None and state in MODE_OF_STATE:
            values[(device, AC.actual_mode)] = Literal(MODE_OF_STATE[state])
        if why is not None:
            self.log.warning("%s: %s", local_name(device), why)
        self.set_values(values)

    def _on_parameter(self, device: URIRef, ok: bool, why: str) -> None:
        status = "ok" if ok else f"parameter not set: {why}"
        if not ok:
            self.log.warning("%s: %s", local_name(device), status)
        self.set_values({(device, AC.ros_status): Literal(status)})
