"""Benchmark the triple space: notification latency, write throughput, 10k-triple query.

Run: python bench/space_bench.py [--runs 5]
Every figure is a median over runs; the store, the subscriber and the writer
are separate processes talking through the router on loopback.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from collections import deque
from pathlib import Path

from _harness import median, percentile, print_table, serve
from rdflib import Literal, Namespace, URIRef

from space import TripleSpace
from space.request import Pending

BENCH = Path(__file__).parent
T = URIRef("urn:bench:t")
EX = Namespace("urn:bench:")
WINDOW = 16  # acknowledgements outstanding in the pipelined mode
THROUGHPUT = {
    "acked": "acked one by one, changesets",
    "pipelined": f"acked, {WINDOW} in flight, changesets",
    "nowait": "fire-and-forget, changesets",
}


def latency(endpoint: str, space: str, count: int, nowait: bool) -> tuple[float, float]:
    """Return p50, p99 (ms) from a write starting to the subscriber process receiving it."""
    sub = subprocess.Popen(
        [sys.executable, str(BENCH / "_latency_subscriber.py"), endpoint, space],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert sub.stdout is not None
    assert sub.stdout.readline().strip() == "ready"
    with TripleSpace.open(endpoint, space=space, agent="bench") as ts:
        for i in range(count):
            triple = (EX[f"s{i % 10}"], T, Literal(time.monotonic_ns()))
            if nowait:
                ts.write_nowait([triple])
                time.sleep(0.002)  # one changeset at a time, as a sensor would
            else:
                ts.write([triple])
        ts.write([(EX.end, T, Literal(-1))])
    delays = [int(x) / 1e6 for x in sub.stdout.readline().split()]
    sub.wait(timeout=10)
    return percentile(delays, 50), percentile(delays, 99)


def throughput(endpoint: str, space: str, changesets: int, size: int, mode: str) -> float:
    """Return triples per second written and persisted (the last ack covers them all).

    `mode`: "acked" waits for each changeset's acknowledgement before the next;
    "pipelined" keeps up to `WINDOW` acknowledgements outstanding (`send_later`),
    every one read; "nowait" is fire-and-forget.
    """
    with TripleSpace.open(endpoint, space=space, agent="bench") as ts:
        batches = [
            [(EX[f"s{j}"], EX[f"p{k % 5}"], Literal(j * size + k)) for k in range(size)]
            for j in range(changesets)
        ]
        start = time.perf_counter()
        in_flight: deque[Pending] = deque()
        for batch in batches:
            if mode == "nowait":
                ts.write_nowait(batch)
            elif mode == "acked":
                ts.write(batch)
            else:
                in_flight.append(ts.send_later(ts.changeset(batch), timeout=30))
                if len(in_flight) >= WINDOW:
                    in_flight.popleft().result()
        while in_flight:
            in_flight.popleft().result()
        # every changeset is new data, so the store's sequence number counts them
        while ts.snapshot((EX.nothing, None, None), timeout=30)[1] < changesets:
            time.sleep(0.005)
        return changesets * size / (time.perf_counter() - start)


def query_10k(endpoint: str, space: str) -> tuple[float, float]:
    """Return seconds for `tspace query --template` of 10,000 triples (whole CLI process)
    and for the same query through the library."""
    with TripleSpace.open(endpoint, space=space, agent="bench") as ts:
        for j in range(100):
            ts.write([(EX[f"s{j}_{k}"], EX.match, Literal(k)) for k in range(100)])
        ts.write([(EX[f"o{k}"], EX.other, Literal(k)) for k in range(100)])
        start = time.perf_counter()
        assert len(ts.query((None, EX.match, None))) == 10_000
        library = time.perf_counter() - start
    cmd = [
        sys.executable,
        "-m",
        "space.cli",
        "query",
        "--template",
        "?s <urn:bench:match> ?o",
        "--connect",
        endpoint,
        "--space",
        space,
    ]
    start = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    cli = time.perf_counter() - start
    assert len(out.stdout.splitlines()) == 10_002
    return cli, library


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--count", type=int, default=1000, help="changesets per latency run")
    args = parser.parse_args()
    rows: dict[str, list[float]] = {}
    with serve() as endpoint:
        for run in range(args.runs):
            p50, p99 = latency(endpoint, f"lat{run}", args.count, nowait=False)
            rows.setdefault("latency write()->notify p50 (ms)", []).append(p50)
            rows.setdefault("latency write()->notify p99 (ms)", []).append(p99)
            p50, p99 = latency(endpoint, f"latn{run}", args.count, nowait=True)
            rows.setdefault("latency write_nowait()->notify p50 (ms)", []).append(p50)
            rows.setdefault("latency write_nowait()->notify p99 (ms)", []).append(p99)
            for mode, label in THROUGHPUT.items():
                rows.setdefault(f"throughput, {label} of 100 (triples/s)", []).append(
                    throughput(endpoint, f"thr{mode}{run}", 200, 100, mode)
                )
            cli, lib = query_10k(endpoint, f"q{run}")
            rows.setdefault("tspace query, 10,000 triples, whole CLI (s)", []).append(cli)
            rows.setdefault("TripleSpace.query, 10,000 triples (s)", []).append(lib)
    print_table(
        f"tspace space benchmark, medians of {args.runs} runs",
        ["measure", "median", "min", "max"],
        [(name, median(v), min(v), max(v)) for name, v in rows.items()],
    )


if __name__ == "__main__":
    main()
