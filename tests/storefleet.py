"""Three hosts, each an etcd member, a `tspace serve --cluster` replica and robots; a checker.

The replica fault test (tests/test_cluster_store_faults.py) runs the checker
against the real replicas: every acknowledged write is in every replica's log
exactly once, no item was taken twice (acknowledged twice, or removed by two
changesets), every replica's log is the same sequence, and every replica
catches up once writing stops (none stuck).
"""

from __future__ import annotations

import signal
import sys
import time
from collections import Counter
from dataclasses import dataclass, field

from etcdhosts import NAMES, EtcdHosts
from netns import PORT, REPO, Network, Proc

from space import SpaceError, TripleSpace

ROBOTS = REPO / "tests" / "programs" / "store_node.py"


class StoreFleet(EtcdHosts):
    """The etcd members, replicas and robots of a `Network` of hosts `a`, `b`, `c`."""

    def __init__(self, net: Network) -> None:
        super().__init__(net)
        self.replicas: dict[str, Proc] = {}
        self.robots: dict[str, Proc] = {}

    def start(self) -> None:
        """Start every member, replica and host's robots; return once each host had an ack."""
        for h in NAMES:
            self.start_etcd(h)
        for h in NAMES:
            self.start_replica(h)
        for h in NAMES:
            argv = [sys.executable, str(ROBOTS), h, str(self.out), f"tcp/127.0.0.1:{PORT}"]
            self.robots[h] = self.net[h].popen("robots", argv)
        for h in NAMES:
            self.wait_acked(h, 60)

    def start_replica(self, host: str) -> None:
        """Start (or restart: it resumes from the revision it applied) the replica on `host`."""
        args = ["--cluster", ",".join(self.endpoints(host))]
        self.replicas[host] = self.net[host].serve(args=args)

    def restart_worker(self, host: str) -> None:
        """kill -9 the replica (and its router) on `host` and start it again."""
        self.replicas[host].stop(signal.SIGKILL)
        self.start_replica(host)

    def seqs(self) -> dict[str, int]:
        """Return each replica's sequence number of the space (-1: it does not answer)."""
        found = {}
        for h in NAMES:
            try:
                with TripleSpace.open(self.net[h].control, space="f") as ts:
                    found[h] = ts.seq(timeout=2)
            except SpaceError:
                found[h] = -1
        return found

    def quiesce(self) -> float:
        """Stop the robots; return how long until every replica had the same sequence number."""
        for proc in self.robots.values():
            proc.popen.send_signal(signal.SIGUSR1)
        for proc in self.robots.values():
            proc.popen.wait(timeout=30)
        began = time.monotonic()
        self.net.wait(lambda: len(set(self.seqs().values())) == 1, 30, "identical replicas")
        return time.monotonic() - began


@dataclass
class Verdict:
    """What the checker found."""

    acknowledged: int = 0
    taken: int = 0
    refused: Counter = field(default_factory=Counter)
    violations: list[str] = field(default_factory=list)


def check(fleet: StoreFleet) -> Verdict:
    """Check every acknowledged operation against every replica's log and state."""
    verdict = Verdict()
    logs: dict[str, list] = {}
    for h in NAMES:
        with TripleSpace.open(fleet.net[h].control, space="f") as ts:
            changes, seq = ts.history(1, 0, timeout=30)
        if [c.seq for c in changes] != list(range(1, seq + 1)):
            verdict.violations.append(f"{h}'s log is not 1..{seq} without a gap")
        logs[h] = changes
    ids = {h: [c.id for c in changes] for h, changes in logs.items()}
    for h in NAMES[1:]:
        if ids[h] != ids[NAMES[0]]:
            verdict.violations.append(f"{h}'s log differs from {NAMES[0]}'s")
    counts = Counter(ids[NAMES[0]])
    doubled = [i for i, n in counts.items() if n > 1]
    if doubled:
        verdict.violations.append(f"applied twice: {doubled[:5]}")
    removals = Counter(
        str(s) for c in logs[NAMES[0]] for s, _, _ in c.removed if str(s).startswith("urn:item")
    )
    twice = [s for s, n in removals.items() if n > 1]
    if twice:
        verdict.violations.append(f"items removed twice: {twice[:5]}")
    taken: Counter = Counter()
    for h in NAMES:
        for op in fleet.ops(h):
            if not op["ok"]:
                verdict.refused[op["error"].split(":")[0]] += 1
                continue
            verdict.acknowledged += 1
            if op["op"] == "take":
                verdict.taken += 1
                taken[op["item"]] += 1
            elif counts[op["id"]] != 1:
                verdict.violations.append(f"acknowledged but not applied once: {op['id']}")
    twice_acked = [i for i, n in taken.items() if n > 1]
    if twice_acked:
        verdict.violations.append(f"items taken twice: {twice_acked[:5]}")
    return verdict
