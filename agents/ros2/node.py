"""A ROS 2 node held on a Zenoh session, as rmw_zenoh would hold it.

The node and each of its publishers, subscribers and clients is announced by a
liveliness token, so `ros2 node list` / `ros2 topic list` on an rmw_zenoh
robot see it. The node owns every Zenoh object it declares and undeclares them
in reverse order in `close()`. Subscriber callbacks run on Zenoh's threads:
they decode and hand the message over, never block.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import zenoh

from agents.ros2.attachment import Attachment, gid_for
from agents.ros2.codec import Codec
from agents.ros2.errors import (
    MalformedAttachment,
    MalformedMessage,
    ServiceFailed,
    ServiceTimeout,
)
from agents.ros2.rmw import Endpoint, Entity, EntityKind, Qos, data_key, join_name, ros_type_name

log = logging.getLogger("ros2")
DEFAULT_QOS = Qos()
OnMessage = Callable[[Any, Attachment | None], None]


@dataclass
class Publisher:
    """A ROS 2 publisher: `publish` encodes, stamps the attachment and puts."""

    entity: Entity
    key: str
    codec: Codec
    zpub: zenoh.Publisher
    gid: bytes
    sequence: int = 0

    def publish(self, message: Any) -> bytes:
        """Publish a message; return the CDR sent. Call it from one thread (the bridge's loop)."""
        assert self.entity.endpoint is not None
        payload = self.codec.encode(self.entity.endpoint.ros_type, message)
        self.sequence += 1
        self.zpub.put(payload, attachment=Attachment.now(self.sequence, self.gid).encode())
        return payload


@dataclass
class Client:
    """A ROS 2 service client: `call` is a Zenoh get to every complete server, blocking."""

    entity: Entity
    key: str
    codec: Codec
    session: zenoh.Session
    gid: bytes
    _sequence: itertools.count

    def call(self, request: Any, timeout: float) -> Any:
        """Send a request and return the decoded response.

        Blocking (up to `timeout` s): call it from a worker thread, never a callback.

        Raises:
            ServiceTimeout: no server answered in time.
            ServiceFailed: a server answered with an error.
            MalformedMessage: the response is not the service's response type.
        """
        assert self.entity.endpoint is not None
        service = self.entity.endpoint.ros_type
        sequence = next(self._sequence)
        payload = self.codec.encode(f"{service}_Request", request)
        replies = self.session.get(
            self.key,
            target=zenoh.QueryTarget.ALL_COMPLETE,
            consolidation=zenoh.ConsolidationMode.NONE,
            payload=payload,
            attachment=Attachment.now(sequence, self.gid).encode(),
            timeout=timeout,
        )
        for reply in replies:
            if reply.ok is None:
                raise ServiceFailed(f"{self.entity.endpoint.name}: {reply.err}")
            sample = reply.ok
            if sample.attachment is not None:
                answer = Attachment.decode(sample.attachment.to_bytes())
                if answer.sequence != sequence:
                    log.warning(
                        "%s: reply to request %d, not %d; ignored",
                        self.entity.endpoint.name,
                        answer.sequence,
                        sequence,
                    )
                    continue
            return self.codec.decode(f"{service}_Response", sample.payload.to_bytes())
        raise ServiceTimeout(f"{self.entity.endpoint.name}: no answer within {timeout:g} s")


class Node:
    """One ROS 2 node of this process.

    Args:
        session: the Zenoh session (the caller owns it; close the node first).
        codec: types and hashes.
        domain: the ROS domain id.
        namespace: the node's namespace ("/robot1").
        name: the node's name.
        ids: the session's entity id counter, shared by its nodes.
    """

    def __init__(
        self,
        session: zenoh.Session,
        codec: Codec,
        domain: int,
        namespace: str,
        name: str,
        ids: itertools.count,
    ) -> None:
        self.session, self.codec, self.domain = session, codec, domain
        self.namespace, self.name = namespace, name
        self._ids = ids
        self._zid = str(session.zid())
        self._node_id = next(ids)
        self._owned: list[Any] = []
        self.entity = self._entity(EntityKind.NODE, None, self._node_id)

    def _entity(
        self, kind: EntityKind, endpoint: Endpoint | None, eid: int | None = None
    ) -> Entity:
        return Entity(
            domain=self.domain,
            zid=self._zid,
            node_id=self._node_id,
            entity_id=next(self._ids) if eid is None else eid,
            kind=kind,
            namespace=self.namespace,
            node=self.name,
            endpoint=endpoint,
        )

    def _announce(self, entity: Entity) -> None:
        self._owned.append(self.session.liveliness().declare_token(entity.token()))

    def open(self) -> Node:
        """Announce the node; return it."""
        self._announce(self.entity)
        return self

    def _endpoint(self, name: str, ros_type: str, qos: Qos) -> Endpoint:
        full = join_name(self.namespace, name)
        return Endpoint(full, ros_type, self.codec.type_hash(ros_type), qos)

    def publisher(self, topic: str, ros_type: str, qos: Qos = DEFAULT_QOS) -> Publisher:
        """Declare a publisher of `ros_type` on `topic` (relative to the namespace)."""
        endpoint = self._endpoint(topic, ros_type, qos)
        entity = self._entity(EntityKind.PUBLISHER, endpoint)
        key = data_key(self.domain, endpoint.name, ros_type, endpoint.type_hash)
        zpub = self.session.declare_publisher(
            key, congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        self._owned.append(zpub)
        self._announce(entity)
        return Publisher(entity, key, self.codec, zpub, gid_for(entity.token()))

    def subscribe(
        self, topic: str, ros_type: str, on_message: OnMessage, qos: Qos = DEFAULT_QOS
    ) -> Entity:
        """Subscribe to `topic`; `on_message(message, attachment)` runs on a Zenoh thread.

        The subscription matches any type and hash on that name so that a
        publisher of another type or version is reported, not silently missed;
        its samples are logged (once per key) and skipped, as are malformed ones.
        """
        endpoint = self._endpoint(topic, ros_type, qos)
        entity = self._entity(EntityKind.SUBSCRIBER, endpoint)
        wanted = data_key(self.domain, endpoint.name, ros_type, endpoint.type_hash)
        pattern = f"{self.domain}/{endpoint.name.strip('/')}/*/*"
        warned: set[str] = set()

        def skip(key: str, why: str) -> None:
            if key not in warned:
                warned.add(key)
                log.warning("%s: %s; skipped", endpoint.name, why)

        def on_sample(sample: zenoh.Sample) -> None:
            key = str(sample.key_expr)
            if key != wanted:
                *_, dds_type, type_hash = key.split("/")
                try:
                    seen = ros_type_name(dds_type)
                except ValueError:
                    seen = dds_type
                if seen != ros_type:
                    skip(key, f"unexpected type {seen} (the mapping says {ros_type})")
                else:
                    skip(
                        key,
                        f"type hash {type_hash} differs from {self.codec.distro}'s "
                        f"{endpoint.type_hash}: another ROS 2 version of {ros_type}",
                    )
                return
            attachment = None
            if sample.attachment is not None:
                try:
                    attachment = Attachment.decode(sample.attachment.to_bytes())
                except MalformedAttachment as exc:
                    # The message does not depend on it (rmw_zenoh before 0.2.4 wrote
                    # named pairs): say so once, take the message.
                    if key not in warned:
                        warned.add(key)
                        log.warning(
                            "%s: %s (an older rmw_zenoh?); messages still taken", endpoint.name, exc
                        )
            try:
                message = self.codec.decode(ros_type, sample.payload.to_bytes())
            except MalformedMessage as exc:
                log.warning("%s: malformed message skipped: %s", endpoint.name, exc)
                return
            on_message(message, attachment)

        self._owned.append(self.session.declare_subscriber(pattern, on_sample))
        self._announce(entity)
        return entity

    def client(self, service: str, srv_type: str) -> Client:
        """Declare a client of `service` (relative to the namespace) of type `pkg/srv/X`."""
        endpoint = self._endpoint(service, srv_type, Qos())
        entity = self._entity(EntityKind.CLIENT, endpoint)
        key = data_key(self.domain, endpoint.name, srv_type, endpoint.type_hash)
        self._announce(entity)
        return Client(
            entity, key, self.codec, self.session, gid_for(entity.token()), itertools.count(1)
        )

    def close(self) -> None:
        """Undeclare every token, publisher and subscriber, newest first."""
        while self._owned:
            self._owned.pop().undeclare()
