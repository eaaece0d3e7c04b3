"""Measure the floors under the store's figures: Oxigraph's own write rate, Zenoh's own hop.

Run: python bench/floors.py [--runs 3]

1. Oxigraph: N-Quads `Store.load` into one named graph of an on-disk store
   (what the store's commit does for plain changesets), 16 changesets of 100
   triples at a time and 10,000 at a time, into a store already holding
   100,000: triples/s with no Python work per triple at all.
2. Zenoh: a writer's GET to a queryable in a router process that hands it to
   a thread (as the store's callbacks do), which replies and puts a sample that
   a subscriber process receives: p50/p99 from the GET to the subscriber's
   callback, with no storing, checking or decoding at all.
"""

from __future__ import annotations

import argparse
import json
import queue
import subprocess
import sys
import tempfile
import threading
import time

import pyoxigraph as ox
import zenoh
from _harness import free_port, median, percentile, print_table

GRAPH = "urn:tspace:graph:floor:asserted"


def oxigraph(batch: int, total: int) -> float:
    """Return triples/s of loading `total` new triples, `batch` per Store.load, on disk."""
    with tempfile.TemporaryDirectory() as d:
        store = ox.Store(d)
        store.load(_doc(0, 100_000), format=ox.RdfFormat.N_QUADS)
        docs = [_doc(100_000 + i, batch) for i in range(0, total, batch)]
        start = time.perf_counter()
        for doc in docs:
            store.load(doc, format=ox.RdfFormat.N_QUADS)
        took = time.perf_counter() - start
        del store
    return total / took


def _doc(first: int, count: int) -> str:
    xsd = "http://www.w3.org/2001/XMLSchema#integer"
    return "".join(
        f'<urn:floor:s{i // 100}> <urn:floor:p{i % 5}> "{i}"^^<{xsd}> <{GRAPH}> .\n'
        for i in range(first, first + count)
    )


def _config(mode: str, endpoint: str) -> zenoh.Config:
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(mode))
    key = "listen/endpoints" if mode == "router" else "connect/endpoints"
    conf.insert_json5(key, json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


def serve(endpoint: str) -> None:
    """Child: a router whose queryable's thread replies and publishes what it got."""
    requests: queue.SimpleQueue[zenoh.Query] = queue.SimpleQueue()
    with zenoh.open(_config("router", endpoint)) as session:
        with session.declare_queryable("floor/write", requests.put):
            print("ready", flush=True)
            while True:
                query = requests.get()
                payload = query.payload.to_bytes() if query.payload is not None else b""
                session.put("floor/changes", payload)
                query.reply("floor/write", b"ok")
                query.drop()
                if payload == b"-1":
                    return


def listen(endpoint: str) -> None:
    """Child: print the delay of every sample (monotonic ns in its payload), -1 ends."""
    done = threading.Event()
    delays: list[int] = []

    def on_sample(sample: zenoh.Sample) -> None:
        now = time.monotonic_ns()
        sent = int(sample.payload.to_bytes())
        if sent < 0:
            done.set()
        else:
            delays.append(now - sent)

    with zenoh.open(_config("client", endpoint)) as session:
        with session.declare_subscriber("floor/changes", on_sample):
            print("ready", flush=True)
            done.wait()
    print(" ".join(map(str, delays)), flush=True)


def zenoh_hop(count: int) -> tuple[float, float]:
    """Return p50, p99 (ms) from a GET to the subscriber process receiving the put."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    children: list[subprocess.Popen] = []
    try:
        for role in ("serve", "listen"):  # the router first: the listener connects to it
            child = subprocess.Popen(
                [sys.executable, __file__, role, endpoint], stdout=subprocess.PIPE, text=True
            )
            children.append(child)
            assert child.stdout is not None and child.stdout.readline().strip() == "ready"
        with zenoh.open(_config("client", endpoint)) as session:
            time.sleep(0.5)  # the subscriber's interest reaches the router
            for _ in range(count):
                list(session.get("floor/write", payload=str(time.monotonic_ns()).encode()))
            list(session.get("floor/write", payload=b"-1"))
        out = children[1].stdout.readline()  # type: ignore[union-attr]
        delays = [int(x) / 1e6 for x in out.split()]
        return percentile(delays, 50), percentile(delays, 99)
    finally:
        for child in children:
            try:
                child.wait(timeout=10)
            except subprocess.TimeoutExpired:  # a failed run: do not leave it behind
                child.kill()
                child.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--count", type=int, default=1000, help="GETs per Zenoh run")
    args = parser.parse_args()
    rows: dict[str, list[float]] = {}
    for _ in range(args.runs):
        rows.setdefault("Oxigraph load, 16 x 100 triples a commit (triples/s)", []).append(
            oxigraph(1600, 32_000)
        )
        rows.setdefault("Oxigraph load, 10,000 triples a commit (triples/s)", []).append(
            oxigraph(10_000, 100_000)
        )
        p50, p99 = zenoh_hop(args.count)
        rows.setdefault("Zenoh GET -> thread -> put -> subscriber p50 (ms)", []).append(p50)
        rows.setdefault("Zenoh GET -> thread -> put -> subscriber p99 (ms)", []).append(p99)
    table = [(m, median(v), f"{min(v):.3f}..{max(v):.3f}") for m, v in rows.items()]
    print_table(f"floors, medians of {args.runs} runs", ["measure", "median", "min..max"], table)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] in ("serve", "listen"):
        {"serve": serve, "listen": listen}[sys.argv[1]](sys.argv[2])
    else:
        main()
