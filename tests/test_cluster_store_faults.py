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

import pytest
from etcdhosts import run_faults
from netns import Network, require_netns
from storefleet import StoreFleet, check

from space.store.etcd_member import etcd_missing

pytestmark = pytest.mark.netns


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
    run_faults(fleet, window=5.0, recover=15)
    settle = fleet.quiesce()
    verdict = check(fleet)
    assert verdict.violations == []
    assert verdict.acknowledged > 300 and verdict.taken > 50, verdict
    assert verdict.refused["NoQuorum"] > 0, verdict
    assert settle <= 2.0, f"replicas identical only {settle:.1f} s after writing stopped"
