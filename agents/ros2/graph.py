"""The ROS graph as rmw_zenoh's liveliness tokens tell it: who is there, offering what.

A liveliness subscriber with history is declared first, so the entities alive
now and every arrival or departure after are seen, with no gap. The callback
only parses and stores under a lock; readers take copies.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

import zenoh

from agents.ros2.errors import MalformedToken
from agents.ros2.rmw import ADMIN_SPACE, Entity, EntityKind, parse_token

log = logging.getLogger("ros2.graph")


class Graph:
    """The entities of one ROS domain, kept current from liveliness tokens.

    Args:
        on_change: called (on a Zenoh thread; it must not block) with each entity
            that appears (True) or goes (False).
    """

    def __init__(self, on_change: Callable[[Entity, bool], None] | None = None) -> None:
        self._entities: dict[str, Entity] = {}
        self._lock = threading.Lock()
        self._on_change = on_change
        self._subscriber: zenoh.Subscriber | None = None

    def open(self, session: zenoh.Session, domain: int) -> Graph:
        """Start following the tokens of `domain` on `session`; return self."""
        self._subscriber = session.liveliness().declare_subscriber(
            f"{ADMIN_SPACE}/{domain}/**", self._on_sample, history=True
        )
        return self

    def close(self) -> None:
        """Stop following."""
        if self._subscriber is not None:
            self._subscriber.undeclare()
            self._subscriber = None

    def _on_sample(self, sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        alive = sample.kind == zenoh.SampleKind.PUT
        try:
            entity = parse_token(key)
        except MalformedToken as exc:
            log.warning("%s; ignored", exc)
            return
        with self._lock:
            if alive:
                self._entities[key] = entity
            else:
                self._entities.pop(key, None)
        if self._on_change is not None:
            self._on_change(entity, alive)

    def entities(self, kind: EntityKind | None = None) -> list[Entity]:
        """Return the entities alive now (of one kind), in key order."""
        with self._lock:
            found = [self._entities[k] for k in sorted(self._entities)]
        return [e for e in found if kind is None or e.kind is kind]

    def offers(self, kind: EntityKind, name: str) -> list[Entity]:
        """Return the publishers or servers (`kind`) of the topic or service `name`."""
        return [e for e in self.entities(kind) if e.endpoint and e.endpoint.name == name]

    def nodes(self) -> list[str]:
        """Return the fully qualified names of the nodes alive, as `ros2 node list` shows them."""
        return sorted({e.full_node_name for e in self.entities(EntityKind.NODE)})

    def topics(self) -> dict[str, set[str]]:
        """Return topic name -> types, as `ros2 topic list -t` shows them."""
        found: dict[str, set[str]] = {}
        for e in self.entities():
            if e.endpoint and e.kind in (EntityKind.PUBLISHER, EntityKind.SUBSCRIBER):
                found.setdefault(e.endpoint.name, set()).add(e.endpoint.ros_type)
        return found
