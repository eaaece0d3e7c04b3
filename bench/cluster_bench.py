"""Cluster log on etcd: changesets/s and ack latency with 64 in flight; leader kill -9 -> next ack.

Three etcd 3.4 members on this machine's loopback (`space.store.etcd_member`,
the settings tspace runs etcd with), one client process with the replicated
log (`space.store.etcd_log`, group commit). Each writer is one robot writing
its own functional reading, as the store appends it (`cluster_entries`): the
changeset's payload for the log and the (subject, property) key rewritten,
guarded by the revision its value was read at (compare-and-swap). A writer
waits for its ack before its next write.

Beside it, in the same run, the same writers with one transaction per
changeset (no group commit), to tell the machine from the code.

Failover: with the writers running, kill -9 the leader; the figure is the time
from the kill to the first ack of a write sent after it.

Targets (issue 10): >= 5,000 changesets/s, ack p99 <= 20 ms, failover <= 3 s.

With `--store`, the same figures through three `tspace serve --cluster`
replicas and Zenoh clients (`_cluster_store.py`): what a robot sees.

    .venv/bin/python bench/cluster_bench.py [--runs 3] [--seconds 5] [--inflight 64] [--store]
        [--old TREE]   # with --store: the replicas of the code in TREE too, in the same run
"""

from __future__ import annotations

import asyncio
import os
import tempfile
import uuid
from collections.abc import Sequence
from pathlib import Path

from _harness import cpu_seconds, median, percentile
from _output import bench_parser, parse, png, print_table
from aetcd import rpc

from space.errors import NoQuorum, WriteConflict
from space.store.cluster_entries import Decision, entry_for
from space.store.cluster_keys import ROOT, functional_key
from space.store.etcd_client import EtcdClient
from space.store.etcd_log import ClusterLog, Entry
from space.store.etcd_member import LocalCluster

PAYLOAD = 600  # bytes: an encoded changeset of one reading, its prefixes, id, agent and HLC
FUNCTIONAL = frozenset({"<https://w3id.org/tspace/selfconfig#batteryLevel>"})


class Robot:
    """One writer: a robot's battery level, a functional property, rewritten each time."""

    def __init__(self, n: int) -> None:
        self.s = f"<http://ex.org/robot{n}-{uuid.uuid4().hex[:8]}>"  # new in every run
        self.p = "<https://w3id.org/tspace/selfconfig#batteryLevel>"
        self.fn = functional_key(ROOT, "bench", self.s, self.p)
        self.read = 0  # the revision this robot's last write committed at: its replica's view
        self.old: tuple[str, str, str] | None = None
        self.level = 0

    def entry(self) -> Entry:
        """Return the entry the store makes of this reading (space.store.cluster_entries)."""
        self.level += 1
        new = (self.s, self.p, f'"{self.level}"^^<http://www.w3.org/2001/XMLSchema#integer>')
        decision = Decision(
            "bench",
            os.urandom(PAYLOAD),
            self.read,
            f"7452{self.level:012d}/0",
            FUNCTIONAL,
            added=[new],
            removed=[self.old] if self.old else [],
            replaced=[(self.s, self.p)],
        )
        self.old = new
        return entry_for(ROOT, decision)


async def write_loop(clog: ClusterLog, robot: Robot, stop: float, acks: list[tuple[float, float]]):
    """Write until `stop`; record (sent, acked) for every acknowledged write."""
    loop = asyncio.get_running_loop()
    while loop.time() < stop:
        sent = loop.time()
        try:
            pos = await clog.append(robot.entry())
        except NoQuorum:
            continue  # during a failover: the write was not acknowledged, send the next
        except WriteConflict:
            # An earlier write refused with NoQuorum had committed after all: read again,
            # as the store's replica would (its state then has that write).
            reply = await clog.client.range(rpc.RangeRequest(key=robot.fn))
            robot.read = reply.kvs[0].mod_revision if reply.kvs else 0
            continue
        robot.read = pos.revision
        acks.append((sent, loop.time()))


async def wait_writable(client: EtcdClient) -> None:
    while True:
        try:
            await client.range(rpc.RangeRequest(key=b"probe"))
            return
        except NoQuorum:
            await asyncio.sleep(0.1)


async def throughput_run(
    endpoints: list[str],
    seconds: float,
    inflight: int,
    grouped: bool = True,
    pids: Sequence[int] = (),
) -> dict[str, float]:
    """Measure with group commit, or (not `grouped`) one transaction per changeset; with `pids`
    (the members'), also their CPU per changeset."""
    client = EtcdClient(endpoints)
    await client.open()
    await wait_writable(client)
    clog = ClusterLog(client) if grouped else ClusterLog(client, batch=1, inflight=inflight)
    await clog.start()
    try:
        loop = asyncio.get_running_loop()
        acks: list[tuple[float, float]] = []
        warm = loop.time() + 1.0
        await asyncio.gather(*(write_loop(clog, Robot(i), warm, []) for i in range(inflight)))
        before = clog.transactions
        cpu = cpu_seconds(pids)
        began = loop.time()
        robots = [Robot(1000 + i) for i in range(inflight)]
        await asyncio.gather(*(write_loop(clog, r, began + seconds, acks) for r in robots))
        elapsed = loop.time() - began
        latencies = [(b - a) * 1e3 for a, b in acks]
        return {
            "rate": len(acks) / elapsed,
            "p50": percentile(latencies, 50),
            "p99": percentile(latencies, 99),
            "batch": len(acks) / max(1, clog.transactions - before),
            "cpu": (cpu_seconds(pids) - cpu) * 1e3 / max(1, len(acks)),
            "latencies": latencies,  # type: ignore[dict-item]
        }
    finally:
        await clog.close()
        await client.close()


async def failover_run(cluster: LocalCluster, inflight: int) -> float:
    client = EtcdClient(cluster.endpoints)
    await client.open()
    await wait_writable(client)
    clog = ClusterLog(client)
    await clog.start()
    try:
        loop = asyncio.get_running_loop()
        acks: list[tuple[float, float]] = []
        stop = loop.time() + 6.0
        writers = asyncio.gather(
            *(write_loop(clog, Robot(2000 + i), stop, acks) for i in range(inflight))
        )
        await asyncio.sleep(1.0)
        leader = await client.leader()
        assert leader is not None, "no leader to kill"
        killed = loop.time()
        await asyncio.to_thread(cluster.kill, cluster.members[leader].name)
        await writers
        after = [acked for sent, acked in acks if sent >= killed]
        if not after:
            return float("inf")
        return min(after) - killed
    finally:
        await clog.close()
        await client.close()


def plot(
    latencies: list[float],
    failovers: list[float],
    path: Path,
    name: str = "cluster",
    before: list[float] | None = None,
) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    curves = [("before", before), ("now", latencies)] if before else [("", latencies)]
    for label, curve in curves:
        values = sorted(curve)  # type: ignore[arg-type]
        ys = [(i + 1) / len(values) for i in range(len(values))]
        left.step(values, ys, where="post", label=label or None)
    if before:
        left.set_xscale("log")
        left.legend()
    left.axvline(20, linestyle="--", color="grey")
    left.annotate("target p99 20 ms", (20, 0.1), rotation=90)
    left.set_xlabel("append -> ack (ms)" if name == "cluster" else "send -> ack (ms)")
    left.set_ylabel("share of changesets")
    where = "through 3 replicas" if name != "cluster" else "3 etcd members"
    left.set_title(f"Ack latency, {where}, 64 in flight")
    left.grid(True, alpha=0.3)
    right.bar(range(1, len(failovers) + 1), failovers)
    right.axhline(3.0, linestyle="--", color="grey")
    right.set_xlabel("run")
    right.set_ylabel("leader kill -9 -> next ack (s)")
    right.set_title("Failover")
    figure.savefig(path, dpi=120, bbox_inches="tight")
    return path


def main(runs: int, seconds: float, inflight: int, draw: Path | None) -> None:
    rows, latencies, failovers = [], [], []
    for run in range(runs):
        with tempfile.TemporaryDirectory(prefix="tspace-cluster-") as tmp:
            with LocalCluster(Path(tmp)) as cluster:
                single = asyncio.run(throughput_run(cluster.endpoints, seconds, inflight, False))
                pids = [proc.pid for proc in cluster.procs.values()]
                result = asyncio.run(
                    throughput_run(cluster.endpoints, seconds, inflight, pids=pids)
                )
                latencies += result.pop("latencies")  # type: ignore[arg-type]
                failover = asyncio.run(failover_run(cluster, inflight))
        failovers.append(failover)
        rows.append(
            [
                run + 1,
                single["rate"],
                single["p99"],
                *(result[k] for k in ("rate", "p50", "p99", "batch", "cpu")),
                failover,
            ]
        )
        print(rows[-1], flush=True)
    rows.append(["median", *(median([r[i] for r in rows]) for i in range(1, 9))])
    print_table(
        f"etcd log, 3 members on one host, {inflight} in flight, {seconds:g} s per run "
        "(targets: >= 5000/s, p99 <= 20 ms, failover <= 3 s)",
        [
            "run",
            "1 txn each: cs/s",
            "1 txn each: p99 ms",
            "grouped: cs/s",
            "grouped: p50 ms",
            "grouped: p99 ms",
            "grouped: cs per txn",
            "etcd cpu ms/cs",
            "failover s",
        ],
        rows,
    )
    if draw is not None:
        print(f"plot: {plot(latencies, failovers, draw)}")


def main_store(
    runs: int, seconds: float, inflight: int, old: Path | None, draw: Path | None
) -> None:
    """Through the store; with `old` (a source tree), its replicas too, in the same run."""
    from _cluster_store import embedded_once, run_once

    rows, latencies, failovers, before = [], [], [], []
    for run in range(runs):
        one = embedded_once(seconds, inflight)
        row: list = [run + 1, one["rate"], one["p99"]]
        if old is not None:
            with tempfile.TemporaryDirectory(prefix="tspace-cluster-store-") as tmp:
                o = run_once(Path(tmp), seconds, inflight, old, kill=False)
            before += o.pop("latencies")  # type: ignore[arg-type]
            row += [
                o["rate"],
                o["p50"],
                o["p99"],
                o["cpu replicas"],
                o["cpu etcd"],
                o["cpu client"],
            ]
        with tempfile.TemporaryDirectory(prefix="tspace-cluster-store-") as tmp:
            r = run_once(Path(tmp), seconds, inflight)
        latencies += r.pop("latencies")  # type: ignore[arg-type]
        failovers.append(r["failover"])
        row += [r["rate"], r["p50"], r["p99"], r["cpu replicas"], r["cpu etcd"], r["cpu client"]]
        row += [r["failed"], r["failover"]]
        if old is not None:
            row.append(r["rate"] / o["rate"])
        rows.append([*row, os.getloadavg()[0]])
        print(rows[-1], flush=True)
    rows.append(["median", *(median([r[i] for r in rows]) for i in range(1, len(rows[0])))])
    header = ["run", "embedded cs/s", "embedded p99 ms"]
    for name in ["before"] * (old is not None) + ["cluster"]:
        header += [f"{name} cs/s", f"{name} p50 ms", f"{name} p99 ms"]
        header += [f"{name} cpu ms/cs: replicas", "etcd ms/cs", "client ms/cs"]
    header += ["refused (cs)", "failover s"]
    if old is not None:
        header.append("cs/s x before")
    print_table(
        f"through the store, {inflight} in flight, {seconds:g} s per run: one embedded store, "
        + ("then 3 etcd members and 3 replicas of the code before, " if old else "then ")
        + "3 etcd members and 3 replicas on this host "
        "(targets: >= 5000/s, p99 <= 20 ms, failover <= 3 s); cpu: CPU time of the 3 replicas, "
        "of the 3 etcd members, of this client, per acknowledged changeset",
        [*header, "load (1 min)"],
        rows,
    )
    if draw is not None:
        print(f"plot: {plot(latencies, failovers, draw, 'cluster-store', before or None)}")


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--inflight", type=int, default=64)
    parser.add_argument("--store", action="store_true", help="through store replicas and Zenoh")
    parser.add_argument("--old", type=Path, help="with --store: replicas of this source tree too")
    args = parse(parser, own_plot=True)
    if args.store:
        draw = png(args, "cluster-store.png")
        main_store(args.runs, args.seconds, args.inflight, args.old, draw)
    else:
        main(args.runs, args.seconds, args.inflight, png(args, "cluster.png"))
