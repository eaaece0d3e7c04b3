"""`cluster_bench.py --store`: the same figures measured through three store replicas.

Three etcd members and three `tspace serve --cluster` replicas on this
machine, each replica behind its own router. One client process keeps
`inflight` writes in flight, spread over the three replicas, one per robot: a
robot sends its next reading as soon as its last is answered (Zenoh callbacks:
no reply waits behind another's);
each write is one robot's battery level, a functional property, so each is a
compare-and-swap in etcd. An ack comes once the replica that took the write
applied the revision it committed at (docs/cluster.md).

Failover: with writers running, kill -9 of the etcd leader; the figure is the
time from the kill to the first ack of a write sent after it.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import queue
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import zenoh
from _harness import code_env, cpu_seconds, free_port, percentile, reap
from rdflib import Literal, URIRef
from rdflib.namespace import OWL, RDF

from space import SpaceError, TripleSpace, keys
from space.changeset import unpack
from space.store.etcd_client import EtcdClient
from space.store.etcd_member import LocalCluster

LEVEL = URIRef("https://w3id.org/tspace/selfconfig#batteryLevel")


@contextlib.contextmanager
def replicas(
    cluster: LocalCluster, workdir: Path, n: int = 3, code: Path | None = None
) -> Iterator[tuple[list[str], list[int]]]:
    """Run `n` replicas of `cluster` (from source tree `code` if given); yield their routers'
    endpoints and pids; stop them after."""
    endpoints = [f"tcp/127.0.0.1:{free_port()}" for _ in range(n)]
    members = ",".join(cluster.endpoints)
    procs = []
    for i, endpoint in enumerate(endpoints):
        data = workdir / f"replica{i}"
        cmd = [sys.executable, "-m", "space.cli", "serve", "--listen", endpoint]
        cmd += ["--data", str(data), "--cluster", members]
        log = open(workdir / f"replica{i}.log", "wb")
        proc = subprocess.Popen(
            cmd,
            stdout=log,
            stderr=subprocess.STDOUT,
            env=code_env(code),
            cwd=str(code) if code is not None else None,
        )
        procs.append((proc, log))
    try:
        for endpoint in endpoints:
            _wait_answers(endpoint)
        yield endpoints, [proc.pid for proc, _ in procs]
    finally:
        for proc, _ in procs:
            proc.send_signal(signal.SIGTERM)
        reap([proc for proc, _ in procs], timeout=15)
        for _, log in procs:
            log.close()


def _wait_answers(endpoint: str, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while True:
        try:
            with TripleSpace.open(endpoint, space="ping") as ts:
                ts.snapshot(timeout=1)
            return
        except SpaceError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.1)


class _Answer:
    """One write in flight: when its reply came, and whether it was an acknowledgement."""

    def __init__(self, robot: int, acks: list, refused: list, free: queue.SimpleQueue) -> None:
        self.robot, self.acks, self.refused, self.free = robot, acks, refused, free
        self.sent = time.monotonic()
        self.acked = 0.0

    def reply(self, reply: zenoh.Reply) -> None:
        if reply.ok is not None and "seq" in (unpack(reply.ok.payload.to_bytes()) or {}):
            self.acked = time.monotonic()

    def done(self) -> None:  # every reply is in
        (self.acks.append((self.sent, self.acked)) if self.acked else self.refused.append(1))
        self.free.put(self.robot)


def write(
    handles: list[TripleSpace], seconds: float, inflight: int, acks: list, first: int = 0
) -> int:
    """Keep `inflight` robots writing for `seconds`, each its next reading once its last is
    answered (no reply waits behind another's); record (sent, acked); return failures."""
    free: queue.SimpleQueue = queue.SimpleQueue()
    for robot in range(inflight):
        free.put(robot)
    refused: list[int] = []
    key = keys.service_key("bench", "write")
    stop = time.monotonic() + seconds
    n = first
    while time.monotonic() < stop:
        try:
            r = free.get(timeout=max(0.0, stop - time.monotonic()))
        except queue.Empty:
            break
        ts = handles[r % len(handles)]  # a robot talks to its own host's replica
        cs = ts.changeset([(URIRef(f"http://ex.org/robot{r}"), LEVEL, Literal(n))])
        answer = _Answer(r, acks, refused, free)
        # On Zenoh's own thread (indirect=False): the default starts a Python thread for every
        # request, which cost this client a third of its CPU, taken from the replicas' cores.
        ts.session.get(
            key,
            zenoh.handlers.Callback(answer.reply, answer.done, indirect=False),
            payload=cs.encode(),
            timeout=5,
            consolidation=zenoh.ConsolidationMode.NONE,
            congestion_control=zenoh.CongestionControl.BLOCK,
        )
        n += 1
    for _ in range(inflight):  # every robot's last write answered (or timed out)
        free.get(timeout=10)
    return len(refused)


def throughput(
    endpoints: list[str], seconds: float, inflight: int, pids: dict[str, list[int]] | None = None
) -> dict[str, float]:
    """Measure; with `pids` ({"replicas": [...], "etcd": [...], "client": [...]}), also their
    CPU per ack."""
    handles = [TripleSpace.open(e, space="bench", agent="bench") for e in endpoints]
    pids = pids or {}
    try:
        handles[0].write([(LEVEL, RDF.type, OWL.FunctionalProperty)])
        write(handles, 1.0, inflight, [])  # warm up
        acks: list[tuple[float, float]] = []
        cpu = {name: cpu_seconds(p) for name, p in pids.items()}
        began = time.monotonic()
        failures = write(handles, seconds, inflight, acks, first=10**6)
        elapsed = time.monotonic() - began
        latencies = [(b - a) * 1e3 for a, b in acks]
        result = {
            "rate": len(acks) / elapsed,
            "p50": percentile(latencies, 50),
            "p99": percentile(latencies, 99),
            "failed": failures,
            "latencies": latencies,  # type: ignore[dict-item]
        }
        for name, p in pids.items():  # CPU ms per acknowledged changeset
            result[f"cpu {name}"] = (cpu_seconds(p) - cpu[name]) * 1e3 / max(1, len(acks))
        return result
    finally:
        for h in handles:
            h.close()


def failover(cluster: LocalCluster, endpoints: list[str], inflight: int) -> float:
    """Return seconds from kill -9 of etcd's leader to the first ack of a write sent after."""
    handles = [TripleSpace.open(e, space="bench", agent="bench") for e in endpoints]
    try:
        acks: list[tuple[float, float]] = []
        import threading

        writer = threading.Thread(target=write, args=(handles, 6.0, inflight, acks, 2 * 10**6))
        writer.start()
        time.sleep(1.5)
        leader = asyncio.run(_leader(cluster.endpoints))
        killed = time.monotonic()
        cluster.kill(cluster.members[leader].name)
        writer.join()
        after = [acked for sent, acked in acks if sent >= killed]
        return min(after) - killed if after else float("inf")
    finally:
        for h in handles:
            h.close()


async def _leader(endpoints: list[str]) -> int:
    client = EtcdClient(endpoints)
    await client.open()
    try:
        leader = await client.leader()
        assert leader is not None, "no etcd leader to kill"
        return leader
    finally:
        await client.close()


def embedded_once(seconds: float, inflight: int) -> dict[str, float]:
    """The same writers against one embedded store (`tspace serve`, no etcd), for reference."""
    from _harness import serve_process

    with serve_process() as (endpoint, _pid):
        return throughput([endpoint], seconds, inflight)


def run_once(
    workdir: Path, seconds: float, inflight: int, code: Path | None = None, *, kill: bool = True
) -> dict[str, float]:
    """One run: fresh etcd and replicas (from source tree `code` if given); throughput, then
    (if `kill`) failover."""
    with LocalCluster(workdir / "etcd") as cluster:
        with replicas(cluster, workdir, code=code) as (endpoints, pids):
            members = [proc.pid for proc in cluster.procs.values()]
            kinds = {"replicas": pids, "etcd": members, "client": [os.getpid()]}
            result = throughput(endpoints, seconds, inflight, kinds)
            if kill:
                result["failover"] = failover(cluster, endpoints, inflight)
    return result
