"""The etcd log across three hosts in network namespaces, under cuts and kills.

Each host runs an etcd member and a log node (writers, takers, a replica).
One run goes through a minority cut, a cut of the leader's host, a flapping
link, kill -9 of the leading member and of a replica, then checks every
acknowledged operation on every replica: none lost, none applied twice, no
item taken twice, replicas identical within 2 s once writing stops.
The long version is bench/cluster_faults.py.
"""

from __future__ import annotations

import pytest
from etcdhosts import run_faults
from logfleet import LogFleet, check
from netns import Network, require_netns

from space.store.etcd_member import etcd_missing

pytestmark = pytest.mark.netns


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
    run_faults(fleet, window=4.0, recover=10)
    settle = fleet.quiesce()
    fleet.stop()
    verdict = check(fleet)
    assert verdict.violations == []
    assert verdict.acknowledged > 500 and verdict.taken > 50, verdict
    assert verdict.refused["NoQuorum"] > 0 and verdict.refused["WriteConflict"] > 0, verdict
    assert settle <= 2.0, f"replicas identical only {settle:.1f} s after writing stopped"
