"""Three hosts `a`, `b`, `c` in network namespaces, each with an etcd member: what fleets share.

`LogFleet` (tests/logfleet.py: a log node a host) and `StoreFleet`
(tests/storefleet.py: a `tspace serve --cluster` replica and robots a host)
both start their members, find the leader and read what each host's writers
recorded the same way; `run_faults` is the fault script both fault tests run.
"""

from __future__ import annotations

import json
import signal
import sys
import time
from abc import ABC, abstractmethod
from pathlib import Path

from netns import REPO, Network, Proc

from space.store.etcd_member import Member, member_argv

LEADER = REPO / "tests" / "programs" / "etcd_leader.py"
NAMES = ("a", "b", "c")
MINORITY = "no quorum: 1 of 3 members reachable"


class EtcdHosts(ABC):
    """The etcd members of a `Network` of hosts `a`, `b`, `c`, and the outcomes writers record."""

    def __init__(self, net: Network) -> None:
        self.net = net
        self.out: Path = net.workdir / "ops"
        self.out.mkdir(parents=True, exist_ok=True)
        self.members = {
            h: Member(h, net[h].address, 2379, 2380, net.workdir / f"{h}-etcd") for h in NAMES
        }
        self.etcd: dict[str, Proc] = {}

    def endpoints(self, first: str) -> list[str]:
        """Return the members' targets, `first`'s own member first."""
        own = self.members[first].endpoint
        return [own] + [m.endpoint for m in self.members.values() if m.endpoint != own]

    def start_etcd(self, host: str) -> None:
        """Start (or restart: etcd then ignores the initial-cluster flags) the member on `host`."""
        argv = member_argv(self.members[host], list(self.members.values()), "tspace-faults")
        self.etcd[host] = self.net[host].popen("etcd", argv)

    def kill_etcd(self, host: str) -> None:
        """kill -9 the member on `host`."""
        self.etcd[host].stop(signal.SIGKILL)

    @abstractmethod
    def restart_worker(self, host: str) -> None:
        """kill -9 what writes and applies on `host` (not its member), and start it again."""

    def leader(self) -> str:
        """Return the host whose member leads now (asked of each host in turn, waited for)."""
        deadline = time.monotonic() + 10
        while True:
            for asker in NAMES:
                argv = [sys.executable, str(LEADER), *self.endpoints(asker)]
                proc = self.net[asker].popen("leader", argv)
                proc.popen.wait(timeout=20)
                last = proc.logs().strip().splitlines()
                if last and last[-1].lstrip("-").isdigit() and int(last[-1]) >= 0:
                    order = [asker] + [h for h in NAMES if h != asker]
                    return order[int(last[-1])]
            if time.monotonic() > deadline:
                raise TimeoutError("no etcd member leads")
            time.sleep(0.2)

    def ops(self, host: str) -> list[dict]:
        """Return every outcome the writers on `host` recorded (a line cut by kill -9 left out)."""
        path = self.out / f"{host}-ops.jsonl"
        lines = path.read_text().splitlines() if path.exists() else []
        return [json.loads(x) for x in lines if x.endswith("}")]

    def wait_acked(self, host: str, timeout: float, after: float = 0.0) -> None:
        """Wait until a write on `host` was acknowledged after time `after`."""
        self.net.wait(
            lambda: any(o["ok"] and o["t"] > after for o in self.ops(host)),
            timeout,
            f"an acknowledged write on {host}",
        )


def run_faults(fleet: EtcdHosts, window: float, recover: float) -> None:
    """Put `fleet` through a minority cut, a leader cut, a flapping link and two kills -9.

    Each cut lasts `window` seconds, during which the majority side must keep
    acknowledging; after each cut every host must be acknowledged again
    within `recover` seconds, and within `recover` + 5 s after the kills (a
    restarted process first catches up). The kill of the leading member must
    be followed by an acknowledged write elsewhere within 3 s.
    """
    net = fleet.net
    # A minority cut: c is refused with the one clear error; a and b go on.
    with net["c"].outage(window):
        net.wait(
            lambda: any(MINORITY in o["error"] for o in fleet.ops("c")),
            window,
            "c to be refused with NoQuorum",
        )
        fleet.wait_acked("a", window, after=time.time())
    fleet.wait_acked("c", recover, after=time.time())

    # The leader's host is cut: the other two go on.
    leader = fleet.leader()
    others = [h for h in NAMES if h != leader]
    with net[leader].outage(window):
        fleet.wait_acked(others[0], window, after=time.time())
    fleet.wait_acked(leader, recover, after=time.time())

    # A flapping link.
    for _ in range(3):
        with net["b"].outage(1.5):
            pass
        time.sleep(1.5)  # the link up between cuts is the point
    fleet.wait_acked("b", recover, after=time.time())

    # kill -9 of the leading member, then of b's writer and replica; both come back.
    leader = fleet.leader()
    fleet.kill_etcd(leader)
    killed = time.time()
    others = [h for h in NAMES if h != leader]
    fleet.wait_acked(others[0], 3.0, after=killed)
    fleet.start_etcd(leader)
    fleet.restart_worker("b")
    fleet.wait_acked("b", recover + 5, after=time.time())
    fleet.wait_acked(leader, recover + 5, after=time.time())
