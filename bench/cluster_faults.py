"""The etcd log under long faults: 3 hosts in network namespaces, each an etcd member and a node.

Every node writes and races the others to take the same items while the
faults run (tests/logfleet.py); after each scenario writing stops and the
checker compares every acknowledged operation with every replica. The short
version of this is tests/test_cluster_faults.py. Needs root.

Scenarios (issue 10): a minority cut (10 s), a cut of the leader's host
(10 s), flapping links (a random host cut every 5 s for 60 s, 2.5 s each),
kill -9 of the leading member and of a replica, 5 times.

With `--store`, each host runs a `tspace serve --cluster` replica and robots
that write and take through it (tests/storefleet.py); the checker then reads
every replica's log and state.

    .venv/bin/python bench/cluster_faults.py [--flap-seconds 60] [--store]
"""

from __future__ import annotations

import random
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

from _output import bench_parser, parse, print_table

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import logfleet
import storefleet
from etcdhosts import NAMES
from logfleet import LogFleet
from netns import Network, netns_unavailable
from storefleet import StoreFleet

Fleet = LogFleet | StoreFleet


def minority_cut(fleet: Fleet, seconds: float) -> None:
    with fleet.net["c"].outage(seconds):
        pass


def leader_cut(fleet: Fleet, seconds: float) -> None:
    with fleet.net[fleet.leader()].outage(seconds):
        pass


def flapping(fleet: Fleet, seconds: float) -> None:
    rng = random.Random(7)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        with fleet.net[rng.choice(NAMES)].outage(2.5):
            pass
        time.sleep(2.5)  # the links are up between cuts


def kills(fleet: Fleet, rounds: int) -> None:
    for _ in range(rounds):
        leader = fleet.leader()
        fleet.kill_etcd(leader)
        fleet.wait_acked(next(h for h in NAMES if h != leader), 10, after=time.time())
        fleet.start_etcd(leader)
        victim = random.choice(NAMES)
        fleet.restart_worker(victim)
        fleet.wait_acked(victim, 20, after=time.time())


def run(name: str, scenario: Callable[[Fleet], None], store: bool) -> list[object]:
    with tempfile.TemporaryDirectory(prefix="tsf-") as tmp:
        with Network(list(NAMES), Path(tmp)) as net:
            fleet: Fleet = StoreFleet(net) if store else LogFleet(net)
            fleet.start()
            began = time.monotonic()
            scenario(fleet)
            for h in NAMES:
                fleet.wait_acked(h, 30, after=time.time())
            elapsed = time.monotonic() - began
            settle = fleet.quiesce()
            if isinstance(fleet, StoreFleet):
                verdict = storefleet.check(fleet)
            else:
                fleet.stop()
                verdict = logfleet.check(fleet)
    refused = ", ".join(f"{k} {v}" for k, v in sorted(verdict.refused.items()))
    return [
        name,
        f"{elapsed:.0f}",
        verdict.acknowledged,
        verdict.taken,
        refused,
        len(verdict.violations),
        f"{settle:.2f}",
        "; ".join(verdict.violations[:3]) or "-",
        "; ".join(f"{n}x {m}" for m, n in getattr(verdict, "reasons", Counter()).most_common(3))
        or "-",
    ]


def main(flap: float, cut: float, store: bool) -> None:
    reason = netns_unavailable()
    if reason:
        sys.exit(f"cannot run: {reason}")
    scenarios: list[tuple[str, Callable[[Fleet], None]]] = [
        (f"minority cut {cut:g} s", lambda f: minority_cut(f, cut)),
        (f"leader cut {cut:g} s", lambda f: leader_cut(f, cut)),
        (f"flapping {flap:g} s", lambda f: flapping(f, flap)),
        ("kill -9 x5", lambda f: kills(f, 5)),
    ]
    rows = []
    for name, scenario in scenarios:
        rows.append(run(name, scenario, store))
        print(rows[-1], flush=True)
    print_table(
        ("store replicas" if store else "etcd log")
        + " under faults, 3 hosts (netns), writers and takers on every host",
        [
            "scenario",
            "duration s",
            "acked (changesets)",
            "taken (items)",
            "refused (changesets by reason)",
            "violations (count)",
            "identical after s",
            "first violations",
            "other refusals",
        ],
        rows,
    )


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--flap-seconds", type=float, default=60.0)
    parser.add_argument("--cut-seconds", type=float, default=10.0)
    parser.add_argument("--store", action="store_true", help="tspace serve --cluster replicas")
    args = parse(parser)
    main(args.flap_seconds, args.cut_seconds, args.store)
