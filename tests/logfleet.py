"""Three hosts, each with an etcd member and a log node (tests/programs/log_node.py), and a checker.

Shared by tests/test_cluster_faults.py (short) and bench/cluster_faults.py
(the long runs). The checker reads what every node recorded: the operations
etcd acknowledged, and every revision each replica applied, and returns the
violations: an acknowledged changeset missing from a replica or applied
twice, an item taken twice, replicas that differ.
"""

from __future__ import annotations

import json
import signal
import sys
import time
from collections import Counter
from dataclasses import dataclass, field

from etcdhosts import NAMES, EtcdHosts
from netns import REPO, Network, Proc

NODE = REPO / "tests" / "programs" / "log_node.py"


class LogFleet(EtcdHosts):
    """The etcd members and log nodes of a `Network` of hosts `a`, `b`, `c`."""

    def __init__(self, net: Network) -> None:
        super().__init__(net)
        self.nodes: dict[str, Proc] = {}

    def start(self) -> None:
        """Start every member and node; return once every node had a write acknowledged."""
        for h in NAMES:
            self.start_etcd(h)
        for h in NAMES:
            self.start_node(h)
        for h in NAMES:
            self.wait_acked(h, 30)
            self.net.wait(lambda h=h: self.revision(h) > 0, 30, f"a replica applying on {h}")

    def start_node(self, host: str) -> None:
        """Start (or restart: it resumes from what it applied) the log node on `host`."""
        argv = [sys.executable, str(NODE), host, str(self.out), *self.endpoints(host)]
        self.nodes[host] = self.net[host].popen("node", argv)

    def restart_worker(self, host: str) -> None:
        """kill -9 the log node on `host` and start it again."""
        self.nodes[host].stop(signal.SIGKILL)
        self.start_node(host)

    def applied(self, host: str) -> list[dict]:
        """Return every whole line the replica on `host` applied."""
        path = self.out / f"{host}-applied.jsonl"
        lines = []
        for x in path.read_text().splitlines() if path.exists() else ():
            try:
                lines.append(json.loads(x))
            except json.JSONDecodeError:
                continue  # a line cut by kill -9
        return lines

    def revision(self, host: str) -> int:
        """Return the last revision the replica on `host` applied."""
        lines = self.applied(host)
        return lines[-1]["rev"] if lines else 0

    def quiesce(self) -> float:
        """Stop every writer and taker; return how long until all replicas were identical."""
        for proc in self.nodes.values():
            proc.popen.send_signal(signal.SIGUSR1)
        began = time.monotonic()
        time.sleep(0.6)  # writes in flight (0.5 s per attempt) settle into the log or fail
        self.net.wait(self._caught_up, 30, "identical replicas")
        return time.monotonic() - began

    def _caught_up(self) -> bool:
        """Return True when every replica applied the last revision any replica logged.

        (A re-listed replica may be past it: a re-list reads at the current revision.)
        """
        logged = [x["rev"] for h in NAMES for x in self.applied(h) if "payloads" in x]
        return all(self.revision(h) >= max(logged, default=0) for h in NAMES)

    def stop(self) -> None:
        """End every node (after `quiesce`)."""
        for proc in self.nodes.values():
            proc.stop()


@dataclass
class Verdict:
    """What the checker found."""

    acknowledged: int = 0
    taken: int = 0
    refused: Counter = field(default_factory=Counter)
    reasons: Counter = field(default_factory=Counter)  # the messages of ClusterError refusals
    violations: list[str] = field(default_factory=list)


def check(fleet: LogFleet) -> Verdict:
    """Check every node's acknowledged operations against every replica."""
    verdict = Verdict()
    sequences = {}
    for h in NAMES:
        lines = fleet.applied(h)
        revisions = [x["rev"] for x in lines]
        if revisions != sorted(set(revisions)):
            verdict.violations.append(f"{h} applied a revision twice or out of order")
        sequences[h] = [(x["rev"], p) for x in lines for p in x.get("payloads", ())]
        if any("relist" in x for x in lines):
            verdict.violations.append(f"{h} re-listed (its history was compacted away)")
    first = sequences[NAMES[0]]
    for h in NAMES[1:]:
        if sequences[h] != first:
            verdict.violations.append(f"{h}'s applied log differs from {NAMES[0]}'s")
    counts = Counter(p for _, p in first)
    doubled = [p for p, n in counts.items() if n > 1]
    if doubled:
        verdict.violations.append(f"applied twice: {doubled[:5]}")
    takes = Counter(p.rsplit(":", 1)[1] for p in counts if p.startswith("take:"))
    twice = [item for item, n in takes.items() if n > 1]
    if twice:
        verdict.violations.append(f"items taken twice: {twice[:5]}")
    for h in NAMES:
        for op in fleet.ops(h):
            if op["ok"]:
                verdict.acknowledged += 1
                verdict.taken += op["op"] == "take"
                if counts[op["payload"]] != 1:
                    verdict.violations.append(f"acknowledged but not applied: {op['payload']}")
            else:
                kind = op["error"].split(":")[0]
                verdict.refused[kind] += 1
                if kind == "ClusterError":
                    verdict.reasons[op["error"]] += 1
    return verdict
