"""What the store replicas say of their etcd cluster, for `tspace up`'s view and the HMI.

Each replica (`tspace serve --cluster`) publishes on `@cluster/NODE`, every
half second, how many etcd members it reaches and whether that is a quorum.
`ClusterWatch` keeps the latest of each replica; an embedded store publishes
nothing, so there is nothing to show (`line()` is "").
"""

from __future__ import annotations

import threading
import time

import zenoh

from space import keys
from space.changeset import unpack
from space.errors import MalformedPayload

STALE_AFTER = 3.0  # seconds without a word from a replica: it is shown as silent


class ClusterWatch:
    """Follow the replicas' reports; `statuses()` and `line()` from any thread; `close()`."""

    def __init__(self, session: zenoh.Session, root: str = keys.ROOT) -> None:
        self._lock = threading.Lock()
        self._latest: dict[str, tuple[float, dict]] = {}
        self._sub = session.declare_subscriber(f"{root}/@cluster/*", self._on_sample)

    def close(self) -> None:
        """Stop following."""
        self._sub.undeclare()

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            status = unpack(sample.payload.to_bytes())
        except MalformedPayload:
            return
        if not isinstance(status, dict) or not isinstance(status.get("node"), str):
            return
        with self._lock:
            self._latest[status["node"]] = (time.monotonic(), status)

    def statuses(self) -> list[dict]:
        """Return each replica's last report, with `silent` set when it is older than 3 s."""
        now = time.monotonic()
        with self._lock:
            items = sorted(self._latest.items())
        return [{**status, "silent": now - at > STALE_AFTER} for _, (at, status) in items]

    def line(self) -> str:
        """Return the cluster on one line ("" for an embedded store)."""
        parts = []
        for s in self.statuses():
            if s["silent"]:
                parts.append(f"{s['node']}: silent")
            elif s.get("quorum"):
                parts.append(f"{s['node']}: {s.get('reachable')} of {s.get('members')} reachable")
            else:
                parts.append(
                    f"{s['node']}: no quorum: {s.get('reachable')} of {s.get('members')} "
                    "members reachable"
                )
        return f"store replicas (etcd members) - {'; '.join(parts)}" if parts else ""
