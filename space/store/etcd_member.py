"""etcd member processes: the settings tspace runs etcd with, and a local cluster for tests.

In production etcd runs as its own service on each store host (docs/cluster.md);
`member_argv` is the one place that says which flags we rely on, so the docs,
the tests and the benchmark start etcd the same way. `LocalCluster` starts n
members on loopback ports (tests, `bench/cluster_bench.py`) and kills them all
on close, also when a test fails.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType

ETCD = "etcd"
# Raft timing for one LAN: a dead leader is noticed in 0.5 s instead of 1 s, and the
# next acknowledged write follows within about a second (DESIGN.md, measured here).
HEARTBEAT_MS = 50
ELECTION_MS = 500
# A group commit puts many changesets' keys in one transaction.
MAX_TXN_OPS = 16384
MAX_REQUEST_BYTES = 8 * 1024 * 1024
QUOTA_BYTES = 4 * 1024 * 1024 * 1024


def etcd_missing() -> str | None:
    """Return why etcd cannot be started here, or None if it can."""
    if shutil.which(ETCD) is None:
        return "etcd is not installed (apt-get install etcd-server)"
    return None


@dataclass
class Member:
    """One etcd member: its name, address, ports and data directory."""

    name: str
    address: str
    client_port: int
    peer_port: int
    data_dir: Path

    @property
    def client_url(self) -> str:
        """Return the URL clients use (`http://ADDRESS:PORT`)."""
        return f"http://{self.address}:{self.client_port}"

    @property
    def peer_url(self) -> str:
        """Return the URL other members use."""
        return f"http://{self.address}:{self.peer_port}"

    @property
    def endpoint(self) -> str:
        """Return the gRPC target (`ADDRESS:PORT`) tspace's client dials."""
        return f"{self.address}:{self.client_port}"


def member_argv(member: Member, members: Sequence[Member], token: str) -> list[str]:
    """Return the etcd command line for `member` of a new cluster of `members`."""
    initial = ",".join(f"{m.name}={m.peer_url}" for m in members)
    return [
        ETCD,
        f"--name={member.name}",
        f"--data-dir={member.data_dir}",
        f"--listen-client-urls={member.client_url}",
        f"--advertise-client-urls={member.client_url}",
        f"--listen-peer-urls={member.peer_url}",
        f"--initial-advertise-peer-urls={member.peer_url}",
        f"--initial-cluster={initial}",
        f"--initial-cluster-token={token}",
        "--initial-cluster-state=new",
        f"--heartbeat-interval={HEARTBEAT_MS}",
        f"--election-timeout={ELECTION_MS}",
        "--pre-vote=true",  # a member back from a cut does not depose a working leader
        f"--max-txn-ops={MAX_TXN_OPS}",
        f"--max-request-bytes={MAX_REQUEST_BYTES}",
        f"--quota-backend-bytes={QUOTA_BYTES}",
        "--logger=zap",
        "--log-level=warn",
    ]


def free_ports(n: int) -> list[int]:
    """Return n TCP ports free on 127.0.0.1 now (held together, so distinct)."""
    socks = [socket.socket() for _ in range(n)]
    try:
        for s in socks:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


@dataclass
class LocalCluster:
    """n etcd members on loopback ports under `workdir`; a context manager that kills them.

    Construct, then `start()`; `kill(name)` is kill -9 of one member, `restart(name)`
    brings it back on the same ports and data.
    """

    workdir: Path
    size: int = 3
    address: str = "127.0.0.1"
    members: list[Member] = field(default_factory=list)
    procs: dict[str, subprocess.Popen] = field(default_factory=dict)

    def __post_init__(self) -> None:
        ports = free_ports(2 * self.size)
        self.token = f"tspace-{os.getpid()}-{ports[0]}"
        self.members = [
            Member(
                name=f"m{i}",
                address=self.address,
                client_port=ports[2 * i],
                peer_port=ports[2 * i + 1],
                data_dir=self.workdir / f"etcd-m{i}",
            )
            for i in range(self.size)
        ]

    @property
    def endpoints(self) -> list[str]:
        """Return every member's gRPC target, in member order."""
        return [m.endpoint for m in self.members]

    def member(self, name: str) -> Member:
        """Return the member called `name`."""
        return next(m for m in self.members if m.name == name)

    def start(self) -> None:
        """Start every member (returns at once; clients wait for a leader themselves)."""
        for m in self.members:
            self._spawn(m)

    def _spawn(self, m: Member) -> None:
        m.data_dir.parent.mkdir(parents=True, exist_ok=True)
        with open(self.workdir / f"etcd-{m.name}.log", "ab") as log:
            self.procs[m.name] = subprocess.Popen(
                member_argv(m, self.members, self.token),
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )

    def kill(self, name: str) -> None:
        """kill -9 one member and wait for it to be gone."""
        proc = self.procs.pop(name)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()

    def restart(self, name: str) -> None:
        """Start a killed member again, same ports, same data."""
        self._spawn(self.member(name))

    def logs(self) -> str:
        """Return every member's log, for a failing test's message."""
        return "\n".join(
            f"--- {m.name}\n" + (self.workdir / f"etcd-{m.name}.log").read_text(errors="replace")
            for m in self.members
            if (self.workdir / f"etcd-{m.name}.log").exists()
        )

    def close(self) -> None:
        """Kill every member still running."""
        for name in list(self.procs):
            proc = self.procs.pop(name)
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()

    def __enter__(self) -> LocalCluster:
        self.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()
