"""The etcd log across three hosts in network namespaces, under cuts and kills.

Each host runs an etcd member and a log node (writers, takers, a replica).
One run goes through a minority cut, a cut of the leader's host, a flapping
link, kill -9 of the leading member and of a replica, then checks every
acknowledged operation on every replica: none lost, none applied twice, no
item taken twice, replicas identical within 2 s once writing stops.
The long version is bench/cluster_faults.py.
"""

from __future__ import annotations

import time

import pytest
from logfleet import LogFleet, check
from netns import Network, require_netns

from space.store.etcd_member import etcd_missing

pytestmark = pytest.mark.netns

MINORITY = "no quorum: 1 of 3 members reachable"


@pytest.fixture
def fleet(tmp_path):
    require_netns()
    if etcd_missing():
        pytest.skip(etcd_missing())
    with Network(["a", "b", "c"], tmp_path / "n") as net:
        fleet = LogFleet(net)
        fleet.start()
        yield fleet


def test_cuts_and_kills_lose_nothing_double_nothing_take_nothing_twice(fleet):
    net = fleet.net
    # A minority cut: c refuses with the one clear error, a and b go on.
    began = time.time()
    with net["c"].outage(4.0):
        net.wait(
            lambda: any(o["error"] == f"NoQuorum: {MINORITY}" for o in fleet.ops("c")),
            4.0,
            "c to refuse with NoQuorum",
        )
        fleet.wait_acked("a", 4.0, after=time.time())
    assert not any(o["ok"] and began + 1.0 < o["t"] < time.time() - 1 for o in fleet.ops("c"))
    fleet.wait_acked("c", 10, after=time.time())

    # The leader's host is cut: the other two elect a leader and go on.
    leader = fleet.leader()
    others = [h for h in ("a", "b", "c") if h != leader]
    with net[leader].outage(4.0):
        fleet.wait_acked(others[0], 4.0, after=time.time())
    fleet.wait_acked(leader, 10, after=time.time())

    # A flapping link.
    for _ in range(3):
        with net["b"].outage(1.5):
            pass
        time.sleep(1.5)  # the link up between cuts is the point
    fleet.wait_acked("b", 10, after=time.time())

    # kill -9 of the leading member, then of a replica; both come back.
    leader = fleet.leader()
    fleet.kill_etcd(leader)
    killed = time.time()
    others = [h for h in ("a", "b", "c") if h != leader]
    fleet.wait_acked(others[0], 3.0, after=killed)
    fleet.start_etcd(leader)
    fleet.kill_node("b")
    fleet.start_node("b")
    fleet.wait_acked("b", 15, after=time.time())
    fleet.wait_acked(leader, 15, after=time.time())

    settle = fleet.quiesce()
    fleet.stop()
    verdict = check(fleet)
    assert verdict.violations == []
    assert verdict.acknowledged > 500 and verdict.taken > 50, verdict
    assert verdict.refused["NoQuorum"] > 0 and verdict.refused["WriteConflict"] > 0, verdict
    assert settle <= 2.0, f"replicas identical only {settle:.1f} s after writing stopped"
