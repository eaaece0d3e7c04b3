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
3. acked write latency, 1 triple at a time, while 10,000 triples fall due at one
   instant, written 100 a changeset, then 1 a changeset (`--per`), beside the same
   writes with nothing expiring; with `--old DIR`, the same on the store before
   (after the same 100,000 leased triples);
4. memory per leased triple: the store's RSS growth for 100,000 leased triples
   minus that for 100,000 permanent ones, and the in-memory index alone (tracemalloc).

`--cluster`: instead, the expiry lateness of the same probes on three `tspace serve
--cluster` replicas of a 3-member etcd cluster on this machine (each expiry committed through
etcd once, docs/lifespans.md), probes written to and watched on one replica, per run.

Objects are IRIs, not numbers, as they were when the figures in docs/performance.md were
first taken (a distinct typed literal per write no longer costs more as they add up: 30,000
distinct doubles were acked at 1,000-1,200/s throughout, 2026-11-27).
"""

from __future__ import annotations

import contextlib
import tempfile
import threading
import time
import tracemalloc
import uuid
from pathlib import Path

import pyoxigraph as ox
from _harness import median, percentile, serve_process
from _output import OUT, bench_parser, parse, print_table
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


def writes_during_mass_expiry(
    ts: TripleSpace, mass: int, per: int
) -> tuple[list[float], list[float], float]:
    """Return write latencies (ms) with nothing expiring, then during a mass expiry; its span (s).

    The mass is `mass / per` changesets of `per` triples, written with lifespans
    that make them all fall due at one instant, some seconds after the last is sent.
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
        # How fast this store takes such changesets now, to make them all due after the last.
        started = time.time()
        bulk(ts, 20 * per, per, None)
        pace = (time.time() - started) / 20
        due_at = time.time() + 3.0 + 3 * pace * (mass / per)
        pending = []
        for start in range(0, mass, per):
            rows = [
                (URIRef(f"{EX}{tag}/{i}"), mark, URIRef(f"{EX}o{i}"))
                for i in range(start, start + per)
            ]
            life = due_at - time.time()
            if life < 1.0:
                raise SystemExit("writing the mass took too long for its lifespans: no figure")
            pending.append(ts.send_later(ts.changeset(rows, lifespan=life), timeout=60))
            if len(pending) >= 64:
                pending.pop(0).result()
        for p in pending:
            p.result()
        while time.time() < due_at - 0.5:
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


def mass_table(
    mass: int, per: int, runs: dict[str, list[tuple[list[float], list[float], float]]]
) -> str:
    """Print the writes beside a mass expiry: each run's p50/p99/max, and the medians."""
    rows = []
    for label, measured in runs.items():
        for when, index in (("nothing expiring", 0), ("during the expiry", 1)):
            p50 = [median(r[index]) for r in measured]
            p99 = [percentile(r[index], 99) for r in measured]
            top = [max(r[index]) for r in measured]
            rows.append(
                (
                    f"{label}, {when}",
                    " / ".join(f"{x:.1f}" for x in p99),
                    median(p50),
                    median(p99),
                    median(top),
                    median([r[2] for r in measured]) if index else "",
                )
            )
    return print_table(
        f"acked 1-triple write latency, ms, beside a mass expiry of {mass} triples written "
        f"{per} a changeset ({len(next(iter(runs.values())))} runs, interleaved)",
        ["store, when", "p99 of each run (ms)", "p50 (ms)", "p99 (ms)", "max (ms)", "swept in (s)"],
        rows,
    )


def cluster_lateness(runs: int, probes: int) -> str:
    """Print the expiry lateness on three replicas (fresh etcd and replicas per run)."""
    from _cluster_store import replicas

    from space.store.etcd_member import LocalCluster

    rows = []
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as work, LocalCluster(Path(work) / "etcd") as cluster:
            with replicas(cluster, Path(work)) as (endpoints, _pids):
                with TripleSpace.open(endpoints[0], space="bench") as ts:
                    late = lateness(ts, probes)
        rows.append((len(late), percentile(late, 50), percentile(late, 99), max(late)))
    return print_table(
        f"expiry lateness on 3 cluster replicas, ms ({probes} probes a run)",
        ["expired", "p50 (ms)", "p99 (ms)", "max (ms)"],
        rows,
    )


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--writes", type=int, default=500)
    parser.add_argument("--live", type=int, default=100_000)
    parser.add_argument("--mass", type=int, default=10_000)
    parser.add_argument(
        "--per",
        type=int,
        nargs="+",
        default=[100, 1],
        help="triples per changeset of the mass expiry, one run each (default 100 1)",
    )
    parser.add_argument("--mass-runs", type=int, default=3, help="runs of each mass expiry")
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    parser.add_argument(
        "--cluster", type=int, default=0, help="runs of the expiry lateness on 3 replicas only"
    )
    args = parse(parser)
    if args.cluster:
        OUT.mkdir(exist_ok=True)
        (OUT / "lifespans-cluster.txt").write_text(cluster_lateness(args.cluster, 200) + "\n")
        return
    rates: dict[str, list[float]] = {"permanent": [], "lifespan": [], "permanent (before)": []}
    with contextlib.ExitStack() as stack:
        endpoint, pid = stack.enter_context(serve_process())
        ts = stack.enter_context(TripleSpace.open(endpoint, space="bench"))
        old_ts = None
        if args.old:
            old_endpoint, _ = stack.enter_context(serve_process(args.old))
            old_ts = stack.enter_context(TripleSpace.open(old_endpoint, space="bench"))
        for r in range(args.rounds):
            order = ["permanent", "lifespan"] if r % 2 == 0 else ["lifespan", "permanent"]
            for mode in order:
                life = 3600.0 if mode == "lifespan" else None
                rates[mode].append(acked_rate(ts, args.writes, life))
            if old_ts is not None:
                rates["permanent (before)"].append(acked_rate(old_ts, args.writes, None))
        rows = [(m, median(v), min(v), max(v)) for m, v in rates.items() if v]
        text = [
            print_table(
                "acked 1-triple writes",
                ["mode", "median writes/s", "min writes/s", "max writes/s"],
                rows,
            )
        ]

        rss0 = rss_kb(pid)
        bulk(ts, args.live, 1000, None)
        rss1 = rss_kb(pid)
        bulk(ts, args.live, 1000, 3600.0)
        rss2 = rss_kb(pid)
        per_triple = ((rss2 - rss1) - (rss1 - rss0)) * 1024 / args.live
        late = lateness(ts, 200)
        text.append(
            print_table(
                f"expiry lateness, ms, {args.live} leased triples live ({len(late)} probes)",
                ["leased triples live", "p50 (ms)", "p99 (ms)", "max (ms)"],
                [(args.live, percentile(late, 50), percentile(late, 99), max(late))],
            )
        )
        if old_ts is not None:
            bulk(old_ts, args.live, 1000, 3600.0)  # the same leases live on the store before
        stores = [("this", ts)] + ([("before", old_ts)] if old_ts is not None else [])
        for per in args.per:
            runs: dict[str, list[tuple[list[float], list[float], float]]] = {}
            for _ in range(args.mass_runs):  # interleaved, so the machine's load hits both
                for label, space in stores:
                    runs.setdefault(label, []).append(
                        writes_during_mass_expiry(space, args.mass, per)
                    )
            text.append(mass_table(args.mass, per, runs))
        text.append(
            print_table(
                "memory per leased triple, bytes",
                ["measure", "bytes per leased triple"],
                [
                    ("store RSS (leased - permanent)", per_triple),
                    ("in-memory index", index_bytes(args.live)),
                ],
            )
        )
    OUT.mkdir(exist_ok=True)
    (OUT / "lifespans.txt").write_text("\n\n".join(text) + "\n")


if __name__ == "__main__":
    main()
