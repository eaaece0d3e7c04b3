"""Two replicas' writers on a real etcd cluster, their events handled in the order a test chooses.

A replica's worker handles what etcd's threads report (a revision from its
watch, an entry's commit or conflict) in the order it arrives; some orders are
rare on a quiet machine and common under load. Here each replica is a real
`ClusterWriter` (Oxigraph on disk, a real `ClusterNode`, real Zenoh queries
carrying the requests and their answers), and the test plays its worker.
"""

from __future__ import annotations

import queue
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import zenoh
from rdflib import Literal, URIRef

from conftest import free_port
from space import Changeset, keys
from space.changeset import unpack
from space.store.cluster_expiry import ClusterExpiry
from space.store.cluster_keys import ROOT
from space.store.cluster_node import ClusterNode
from space.store.cluster_state import ClusterSpace
from space.store.cluster_writer import ClusterWriter
from space.store.db import StoreDB
from space.store.publish import Publisher
from space.store.writer import Request
from space.zconfig import make_config

EX = "http://example.org/"


class Replica:
    """One replica's writer, its events held for the test to hand over."""

    def __init__(self, session: zenoh.Session, endpoints: list[str], data: Path) -> None:
        self.db = StoreDB(data)
        self.events: queue.SimpleQueue = queue.SimpleQueue()
        self.spaces: dict[str, ClusterSpace] = {}
        put = self.events.put
        self.node = ClusterNode(
            endpoints,
            node=data.name,
            revision=0,
            apply=lambda r, batches: put(("apply", r, batches)),
            relist=lambda listing: put(("relist", listing)),
        )
        self.publisher = Publisher(session, keys.ROOT)
        self.writer = ClusterWriter(
            session,
            self.db,
            self.node,
            root=ROOT,
            events=self.events,
            spaces=self.spaces,
            space=self._space,
            publisher=self.publisher,
            max_spaces=10,
            expiry=ClusterExpiry(ROOT, self.db),
        )
        self.node.start()

    def _space(self, name: str) -> ClusterSpace:
        if name not in self.spaces:
            self.spaces[name] = ClusterSpace(name, self.db)
        return self.spaces[name]

    def next_event(self) -> tuple:
        return self.events.get(timeout=10)

    def handle(self, item: tuple) -> None:
        """Handle one event as the replica's worker does, then apply what is pending."""
        if item[0] == "redecide":
            req, attempt, followers = item[1]
            for r in (req, *followers):
                self.writer.write(r, attempt)
        else:
            self.writer.event(item)
        self.writer.apply_pending()

    def run_until(self, done: Callable[[], bool]) -> None:
        while not done():
            self.handle(self.next_event())

    def close(self) -> None:
        self.node.close()
        self.publisher.close()
        self.db.close()


class Writes:
    """Writes sent as Zenoh queries; each one's query handed to a replica, its answer kept."""

    def __init__(self, session: zenoh.Session) -> None:
        self.session = session
        self._queries: queue.SimpleQueue = queue.SimpleQueue()
        self._queryable = session.declare_queryable(f"{keys.ROOT}/*/@/write", self._queries.put)

    def send(self, replica: Replica, space: str, payload: bytes) -> Callable[[], dict | None]:
        """Send a write to `replica`'s writer; return what polls for its answer."""
        replies = self.session.get(f"{keys.ROOT}/{space}/@/write", payload=payload, timeout=30)
        query = self._queries.get(timeout=10)
        key = str(query.key_expr)
        replica.writer.write(Request("write", space, payload, query, key))
        replica.writer.flush()
        answers: list[dict] = []

        def answer() -> dict | None:
            if not answers:
                reply = replies.try_recv()
                if reply is None:
                    return None
                answers.append(unpack(reply.ok.payload.to_bytes()))  # type: ignore[arg-type,union-attr]
            return answers[0]

        return answer

    def close(self) -> None:
        self._queryable.undeclare()


@contextmanager
def _two_replicas(
    endpoints: list[str], tmp_path: Path
) -> Iterator[tuple[Replica, Replica, Writes]]:
    conf = make_config(mode="peer", connect=[], listen=[f"tcp/127.0.0.1:{free_port()}"])
    with zenoh.open(conf) as session:
        writes = Writes(session)
        a = Replica(session, endpoints, tmp_path / "a")
        try:
            c = Replica(session, endpoints, tmp_path / "c")
            try:
                yield a, c, writes
            finally:
                c.close()
        finally:
            a.close()
            writes.close()


def test_a_retry_decided_alike_on_another_replica_is_answered_again(etcd_cluster, tmp_path):
    """The retry, decided on the state before the first commit, is the same changeset as the
    first: the replica that decided it must not take the first's log entry for its own when
    its watch brings that entry before etcd refused the retry's (the request id committed)."""
    with _two_replicas(etcd_cluster.endpoints, tmp_path) as (a, c, writes):
        cs = Changeset(
            id="robot 7/level #1",
            agent="test",
            timestamp=str(writes.session.new_timestamp()),
            added=[(URIRef(EX + "item1"), URIRef(EX + "at"), Literal("dock"))],
        ).encode()
        first = writes.send(a, "retry", cs)
        a.run_until(lambda: first() is not None)
        assert first() == {"id": "robot 7/level #1", "seq": 1}
        # c applied nothing yet: it decides the retry on the state the first was decided on
        again = writes.send(c, "retry", cs)
        held: list[tuple] = []
        while {"apply", "done"} - {item[0] for item in held}:
            held.append(c.next_event())
        held.sort(key=lambda item: item[0] != "apply")  # the first's entry, then the refusal
        for item in held:
            c.handle(item)
        c.run_until(lambda: again() is not None)
        assert again() == {"id": "robot 7/level #1", "seq": 1, "again": True}
        assert c.spaces["retry"].seq == 1  # applied once
        [(seq, logged)] = c.db.log("retry", 1, 1)  # as subscribers get it: no writer's token
        assert seq == 1 and set(unpack(logged)) == {*unpack(cs), "seq"}  # type: ignore[misc]
