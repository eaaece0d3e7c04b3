"""A replica's link to etcd as a threaded store uses it: appends from threads, applies in order."""

from __future__ import annotations

import queue
import threading

import pytest

from space.errors import NoQuorum
from space.store.cluster_node import ClusterNode
from space.store.etcd_applier import Batch
from space.store.etcd_log import Entry


def _node(cluster, name: str, applied: queue.SimpleQueue) -> ClusterNode:
    def apply(revision: int, batches: list[Batch]) -> None:
        for b in batches:
            for p in b.payloads:
                applied.put((revision, p))

    return ClusterNode(
        cluster.endpoints, node=name, revision=0, apply=apply, relist=lambda listing: None
    )


def test_appends_from_threads_are_applied_on_every_node_in_one_order(etcd_cluster):
    queues = [queue.SimpleQueue(), queue.SimpleQueue()]
    nodes = [_node(etcd_cluster, f"n{i}", q) for i, q in enumerate(queues)]
    for n in nodes:
        n.start()
    try:
        futures = []

        def writer(k: int) -> None:
            futures.extend(nodes[k % 2].append(Entry("s", f"{k}-{i}".encode())) for i in range(50))

        threads = [threading.Thread(target=writer, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        positions = [f.result(timeout=10) for f in futures]
        assert len(set(positions)) == 200
        seen = [[q.get(timeout=10) for _ in range(200)] for q in queues]
        assert seen[0] == seen[1]
        assert [r for r, _ in seen[0]] == sorted(r for r, _ in seen[0])
        assert nodes[0].read_barrier() >= max(p.revision for p in positions)
        assert nodes[0].members() == (3, 3)
    finally:
        for n in nodes:
            n.close()


def test_a_minority_node_refuses_reads_and_writes(etcd_cluster):
    node = _node(etcd_cluster, "n", queue.SimpleQueue())
    node.start()
    try:
        node.append(Entry("s", b"before")).result(timeout=10)
        etcd_cluster.kill("m1")
        etcd_cluster.kill("m2")
        with pytest.raises(NoQuorum, match="no quorum: 1 of 3 members reachable"):
            node.read_barrier()
        with pytest.raises(NoQuorum, match="no quorum: 1 of 3 members reachable"):
            node.append(Entry("s", b"after")).result(timeout=10)
        assert node.members() == (1, 3)
    finally:
        node.close()
