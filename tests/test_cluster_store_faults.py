"""Store replicas on etcd across three hosts in network namespaces, under cuts and kills.

Each host runs an etcd member, a `tspace serve --cluster` replica and robots
(writers, and takers racing the other hosts' for the same items) that talk to
their own host's replica through Zenoh. One run goes through a minority cut, a
cut of the leader's host, a flapping link, kill -9 of the leading member and
of a replica; then the checker reads every replica: no acknowledged write
lost or applied twice, no item taken twice, every replica's log the same,
all of them identical within 2 s once writing stops.
"""

from __future__ import annotations

import time

import pytest
from netns import Network, require_netns
from storefleet import StoreFleet, check

from space.store.etcd_member import etcd_missing

pytestmark = pytest.mark.netns

MINORITY = "no quorum: 1 of 3 members reachable"


@pytest.fixture
def fleet(tmp_path):
    require_netns()
    if etcd_missing():
        pytest.skip(etcd_missing())
    with Network(["a", "b", "c"], tmp_path / "n") as net:
        fleet = StoreFleet(net)
        fleet.start()
        yield fleet


def test_replicas_under_cuts_and_kills_lose_nothing_and_take_nothing_twice(fleet):
    net = fleet.net
    # A minority cut: c's robots are refused with the one clear error; a and b go on.
    with net["c"].outage(5.0):
        net.wait(
            lambda: any(MINORITY in o["error"] for o in fleet.ops("c")),
            5.0,
            "c's robots to be refused with NoQuorum",
        )
        fleet.wait_acked("a", 5.0, after=time.time())
    fleet.wait_acked("c", 15, after=time.time())

    # The leader's host is cut: the other two go on.
    leader = fleet.leader()
    others = [h for h in ("a", "b", "c") if h != leader]
    with net[leader].outage(5.0):
        fleet.wait_acked(others[0], 5.0, after=time.time())
    fleet.wait_acked(leader, 15, after=time.time())

    # A flapping link.
    for _ in range(3):
        with net["b"].outage(1.5):
            pass
        time.sleep(1.5)  # the link up between cuts is the point
    fleet.wait_acked("b", 15, after=time.time())

    # kill -9 of the leading member, then of a replica; both come back.
    leader = fleet.leader()
    fleet.kill_etcd(leader)
    killed = time.time()
    others = [h for h in ("a", "b", "c") if h != leader]
    fleet.wait_acked(others[0], 3.0, after=killed)
    fleet.start_etcd(leader)
    fleet.kill_replica("b")
    fleet.start_replica("b")
    fleet.wait_acked("b", 20, after=time.time())

    settle = fleet.quiesce()
    verdict = check(fleet)
    assert verdict.violations == []
    assert verdict.acknowledged > 300 and verdict.taken > 50, verdict
    assert verdict.refused["NoQuorum"] > 0, verdict
    assert settle <= 2.0, f"replicas identical only {settle:.1f} s after writing stopped"
