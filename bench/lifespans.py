"""Lifespans: write throughput with and without them, expiry lateness, writes during a mass expiry.

Run: `.venv/bin/python bench/lifespans.py [--rounds 3] [--old /work/wt/store]`.

One store (`tspace serve` on a fresh data dir) per run. Measures, in one run:

1. acked writes/s of 1-triple changesets, permanent and with a lifespan (3600 s,
   so nothing expires meanwhile), interleaved round by round; with `--old DIR`
   also permanent writes against the store from DIR (the code before), in the same rounds;
2. with 100,000 leased triples live (100 changesets of 1,000), the lateness of
   200 probe expiries: when the retraction reached a subscriber minus (the probe's
   send time + its lifespan) -- an upper bound, it includes the write's and the
   notification's own latency;
3. acked write latency, 1 triple at a time, while 10,000 triples written with
   the same lifespan by 10,000 changesets expire, beside the same writes with nothing
   expiring;
Objects are IRIs, not numbers: the store's canonical form of a typed literal
(`oxterms._canonical`) costs more with every distinct literal seen (10 ms each
after 20,000; reported to the store's owner), which would swamp what is measured here.

4. memory per leased triple: the store's RSS growth for 100,000 leased triples
   minus that for 100,000 permanent ones, and the in-memory index alone (tracemalloc).
"""

from __future__ import annotations

import argparse
import threading
import time
import tracemalloc
import uuid
from pathlib import Path

import pyoxigraph as ox
from _harness import OUT, median, percentile, print_table, serve_process
from rdflib import URIRef

from space import Change, TripleSpace
from space.store.lifespans import Leases

EX = "http://example.org/"
P = URIRef(EX + "p")


def rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def acked_rate(ts: TripleSpace, count: int, lifespan: float | None) -> float:
    tag = uuid.uuid4().hex[:8]
    started = time.perf_counter()
    for i in range(count):
        ts.write([(URIRef(f"{EX}{tag}/{i}"), P, URIRef(f"{EX}o{i}"))], lifespan=lifespan or 0)
    return count / (time.perf_counter() - started)


def bulk(ts: TripleSpace, total: int, per: int, lifespan: float | None) -> None:
    tag = uuid.uuid4().hex[:8]
    pending = []
    for start in range(0, total, per):
        triples = [
            (URIRef(f"{EX}{tag}/{i}"), P, URIRef(f"{EX}o{i}")) for i in range(start, start + per)
        ]
        pending.append(ts.send_later(ts.changeset(triples, lifespan=lifespan or 0), timeout=120))
        if len(pending) >= 4:
            pending.pop(0).result()
    for p in pending:
        p.result()


def lateness(ts: TripleSpace, probes: int) -> list[float]:
    """Return how late each probe's expiry reached a subscriber, in ms."""
    due: dict[str, float] = {}
    late: list[float] = []
    done = threading.Event()

    def on_change(change: Change) -> None:
        if change.agent == "tspace-store" and change.cause in due:
            late.append((time.time() - due.pop(change.cause)) * 1000)
            if len(late) == probes:
                done.set()

    sub = ts.subscribe((None, URIRef(EX + "probe"), None), on_change)
    try:
        for i in range(probes):
            life = 1.0 + i * 0.01  # spread over 2 s, beside the writes
            cs = ts.changeset(
                [(URIRef(f"{EX}probe/{i}"), URIRef(EX + "probe"), URIRef(f"{EX}o{i}"))]
            )
            cs.lifespan = life
            due[cs.id] = time.time() + life
            ts.send(cs)
        done.wait(30)
    finally:
        sub.close()
    return late


def writes_during_mass_expiry(ts: TripleSpace, mass: int) -> tuple[list[float], list[float], float]:
    """Return write latencies (ms) with nothing expiring, then during a mass expiry; its span (s).

    The mass is 100 changesets of `mass / 100` triples, written within a fraction of a
    second with one lifespan, so they fall due together.
    """
    quiet = [one_write(ts) for _ in range(300)]
    tag = uuid.uuid4().hex[:8]
    expired: list[float] = []
    mark = URIRef(EX + "mass")

    def on_change(change: Change) -> None:
        if change.agent == "tspace-store":
            expired.extend(time.time() for _ in change.removed)

    sub = ts.subscribe((None, mark, None), on_change)
    try:
        life, per = 4.0, mass // 100
        started = time.time()
        pending = []
        for start in range(0, mass, per):
            rows = [
                (URIRef(f"{EX}{tag}/{i}"), mark, URIRef(f"{EX}o{i}"))
                for i in range(start, start + per)
            ]
            pending.append(ts.send_later(ts.changeset(rows, lifespan=life), timeout=60))
        for p in pending:
            p.result()
        while time.time() < started + life - 0.5:
            time.sleep(0.01)
        busy: list[float] = []
        deadline = time.time() + 30
        while len(expired) < mass and time.time() < deadline:
            busy.append(one_write(ts))
        busy += [one_write(ts) for _ in range(20)]
        span = (max(expired) - min(expired)) if expired else float("nan")
    finally:
        sub.close()
    return quiet, busy, span


def one_write(ts: TripleSpace) -> float:
    started = time.perf_counter()
    ts.write([(URIRef(EX + "w"), URIRef(EX + "n"), URIRef(EX + uuid.uuid4().hex))])
    return (time.perf_counter() - started) * 1000


def index_bytes(count: int) -> float:
    """Return the bytes per leased triple of the store's in-memory index alone."""
    leases = Leases()
    triples = [
        (ox.NamedNode(f"{EX}s{i}"), ox.NamedNode(EX + "p"), ox.Literal(str(i)))
        for i in range(count)
    ]
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    for start in range(0, count, 1000):
        leases.decide("bench", uuid.uuid4().hex, 3600.0, triples[start : start + 1000], [])
    leases.take_changes()
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    return (after - before) / count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--writes", type=int, default=500)
    parser.add_argument("--live", type=int, default=100_000)
    parser.add_argument("--mass", type=int, default=10_000)
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    args = parser.parse_args()
    rates: dict[str, list[float]] = {"permanent": [], "lifespan": [], "permanent (before)": []}
    with serve_process() as (endpoint, pid), TripleSpace.open(endpoint, space="bench") as ts:
        old = serve_process(args.old) if args.old else None
        old_ts = None
        if old is not None:
            old_endpoint, _ = old.__enter__()
            old_ts = TripleSpace.open(old_endpoint, space="bench")
        try:
            for r in range(args.rounds):
                order = ["permanent", "lifespan"] if r % 2 == 0 else ["lifespan", "permanent"]
                for mode in order:
                    life = 3600.0 if mode == "lifespan" else None
                    rates[mode].append(acked_rate(ts, args.writes, life))
                if old_ts is not None:
                    rates["permanent (before)"].append(acked_rate(old_ts, args.writes, None))
        finally:
            if old_ts is not None:
                old_ts.close()
            if old is not None:
                old.__exit__(None, None, None)
        rows = [(m, median(v), min(v), max(v)) for m, v in rates.items() if v]
        text = [print_table("acked 1-triple writes/s", ["mode", "median", "min", "max"], rows)]

        rss0 = rss_kb(pid)
        bulk(ts, args.live, 1000, None)
        rss1 = rss_kb(pid)
        bulk(ts, args.live, 1000, 3600.0)
        rss2 = rss_kb(pid)
        per = ((rss2 - rss1) - (rss1 - rss0)) * 1024 / args.live
        late = lateness(ts, 200)
        text.append(
            print_table(
                f"expiry lateness, ms, {args.live} leased triples live ({len(late)} probes)",
                ["p50", "p99", "max"],
                [(percentile(late, 50), percentile(late, 99), max(late))],
            )
        )
        quiet, busy, span = writes_during_mass_expiry(ts, args.mass)
        text.append(
            print_table(
                f"acked write latency, ms, beside a mass expiry of {args.mass} triples "
                f"(swept in {span:.2f} s)",
                ["when", "writes", "p50", "p99", "max"],
                [
                    (
                        "nothing expiring",
                        len(quiet),
                        median(quiet),
                        percentile(quiet, 99),
                        max(quiet),
                    ),
                    ("during the expiry", len(busy), median(busy), percentile(busy, 99), max(busy)),
                ],
            )
        )
        text.append(
            print_table(
                "memory per leased triple, bytes",
                ["store RSS (leased - permanent)", "in-memory index"],
                [(per, index_bytes(args.live))],
            )
        )
    OUT.mkdir(exist_ok=True)
    (OUT / "lifespans.txt").write_text("\n\n".join(text) + "\n")


if __name__ == "__main__":
    main()
