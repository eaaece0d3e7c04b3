"""One host of the cluster fault tests: writers, takers and a replica on the etcd log.

log_node.py NODE OUTDIR ENDPOINT...   (this host's member first)

Writers append unique changesets; takers race to take items `0..ITEMS-1`
(seeded by node `a`), each deciding on its replica's view at the revision it
applied and guarding the take (present, unchanged since then). Every outcome
is a line in OUTDIR/NODE-ops.jsonl: `{"op", "payload", "ok", "error", "t"}`
(`ok` only once etcd acknowledged). The replica writes every applied
revision as one line of OUTDIR/NODE-applied.jsonl (one write, so a kill -9
leaves whole lines, and a restart resumes after the last one). SIGUSR1 stops
the writers and takers (the replica goes on applying); SIGTERM ends it.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import signal
import sys
import time
from pathlib import Path

from space.errors import ClusterError, NoQuorum, WriteConflict
from space.store.cluster_keys import ROOT, triple_key
from space.store.etcd_applier import Applier, Batch, Listing
from space.store.etcd_client import EtcdClient
from space.store.etcd_log import ClusterLog, Entry

ITEMS = 300
WRITERS = 3
TAKERS = 2
PAUSE = 0.02
SEEDED = ROOT + b"test/seeded"


def whole_lines(path: Path) -> list[str]:
    """Cut off a last line that kill -9 left half written (not applied); return the lines."""
    text = path.read_bytes() if path.exists() else b""
    if not text.endswith(b"\n"):
        text = text[: text.rfind(b"\n") + 1]
        path.write_bytes(text)
    return text.decode().splitlines()


def item_key(i: int) -> bytes:
    return triple_key(ROOT, "f", "t", f"<item{i}>", "<a>", "<Item>")


class Node:
    def __init__(self, name: str, out: Path, endpoints: list[str]) -> None:
        self.name, self.out = name, out
        self.boot = os.urandom(3).hex()  # payloads stay unique across a restart
        self.client = EtcdClient(endpoints)
        self.items: set[int] = set()
        whole_lines(out / f"{name}-ops.jsonl")
        self.ops = open(out / f"{name}-ops.jsonl", "a", buffering=1)
        self.applier: Applier | None = None
        self.last_error = ""

    def resume(self) -> int:
        """Return the revision of the last whole line applied before, and its items."""
        path = self.out / f"{self.name}-applied.jsonl"
        revision = 0
        for line in whole_lines(path):
            done = json.loads(line)
            revision = done["rev"]
            if "relist" in done:
                self.items = set(done["relist"])
            for p in done.get("payloads", ()):
                if p.startswith("seed:"):
                    self.items.update(range(ITEMS))
                elif p.startswith("take:"):
                    self.items.discard(int(p.rsplit(":", 1)[1]))
        return revision

    def apply(self, revision: int, batches: list[Batch]) -> None:
        payloads = [p.decode() for b in batches for p in b.payloads]
        for p in payloads:
            if p.startswith("seed:"):
                self.items.update(range(ITEMS))
            elif p.startswith("take:"):
                self.items.discard(int(p.rsplit(":", 1)[1]))
        self.applied.write(json.dumps({"rev": revision, "payloads": payloads}) + "\n")

    def relist(self, listing: Listing) -> None:
        keys = {k for k, _ in listing.pairs}
        self.items = {i for i in range(ITEMS) if item_key(i) in keys}
        line = {"rev": listing.revision, "relist": sorted(self.items)}
        self.applied.write(json.dumps(line) + "\n")

    def record(self, op: str, payload: str, ok: bool, error: str = "") -> None:
        line = {"op": op, "payload": payload, "ok": ok, "error": error, "t": time.time()}
        self.ops.write(json.dumps(line) + "\n")

    async def attempt(self, clog: ClusterLog, op: str, entry: Entry) -> bool:
        payload = entry.payload.decode()
        try:
            await clog.append(entry)
        except (NoQuorum, ClusterError, WriteConflict) as error:
            self.last_error = f"{type(error).__name__}: {error}"
            self.record(op, payload, False, self.last_error)
            return False
        self.record(op, payload, True)
        return True

    async def writer(self, clog: ClusterLog, n: int) -> None:
        for i in range(1_000_000):
            payload = f"w:{self.name}:{self.boot}:{n}:{i}".encode()
            await self.attempt(clog, "write", Entry("f", payload))
            await asyncio.sleep(PAUSE)

    async def taker(self, clog: ClusterLog, n: int) -> None:
        assert self.applier is not None
        while True:
            await asyncio.sleep(PAUSE)
            if not self.items:
                continue
            item = min(self.items)  # every taker wants the same item: the most contention
            key = item_key(item)
            since = self.applier.revision
            payload = f"take:{self.name}:{self.boot}:{n}:{item}".encode()
            entry = Entry("f", payload, deletes=[key], guards={key: since}, present=[key])
            if await self.attempt(clog, "take", entry):
                continue
            await asyncio.sleep(PAUSE)

    async def run(self) -> None:
        await self.client.open()
        clog = ClusterLog(self.client, node=self.name)
        await clog.start()
        start = self.resume()
        self.applied = open(self.out / f"{self.name}-applied.jsonl", "a", buffering=1)
        self.applier = Applier(
            self.client, node=self.name, revision=start, apply=self.apply, relist=self.relist
        )
        await self.applier.start()
        if self.name == "a" and start == 0:
            # Once only, also when a restarts before applying anything: SEEDED never written.
            puts = {item_key(i): b"item" for i in range(ITEMS)} | {SEEDED: b""}
            seed = Entry("f", b"seed:", puts=puts, guards={SEEDED: 0})
            while not await self.attempt(clog, "seed", seed):
                if "WriteConflict" in self.last_error:
                    break
                await asyncio.sleep(0.2)
        quiet, stop = asyncio.Event(), asyncio.Event()
        asyncio.get_running_loop().add_signal_handler(signal.SIGUSR1, quiet.set)
        asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, stop.set)
        tasks = [asyncio.create_task(self.writer(clog, n)) for n in range(WRITERS)]
        tasks += [asyncio.create_task(self.taker(clog, n)) for n in range(TAKERS)]
        await asyncio.wait(
            [asyncio.create_task(quiet.wait()), asyncio.create_task(stop.wait())],
            return_when=asyncio.FIRST_COMPLETED,
        )
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        await stop.wait()
        await clog.close()
        await self.applier.close()
        await self.client.close()
        self.ops.close()
        self.applied.close()


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    node = Node(sys.argv[1], Path(sys.argv[2]), sys.argv[3:])
    asyncio.run(node.run())
