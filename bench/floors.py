"""Measure the floors under the store's figures: what Oxigraph and Zenoh do on their own.

Run: python bench/floors.py [--runs 3] [--million]

1. Oxigraph's write methods, with no tspace code at all: N-Quads `Store.load`
   into one named graph (what the store's commit does for plain changesets),
   against the default graph, an in-memory store, `Store.extend` of quads made
   beforehand, and the non-transactional `bulk_load` (SST files ingested), at
   100, 1,600 (16 changesets of 100: the store's group commit at 16 in flight)
   and 10,000 triples a call, into a store already holding 100,000. Each row
   gives triples/s of wall time and triples per CPU-second of the process (all
   its threads, RocksDB's own included): on a machine shared with other work the
   second is the steadier one, and 2 cores cannot go faster than twice it.
   `--million` adds 1M triples into a fresh store, 10,000 a commit with the
   store's background flush every 50,000 triples (what `tspace write` of 1M
   costs Oxigraph), and the same in one `bulk_load`.
2. A changeset with removals, as the reasoner's answer when 200 rules fire: 200 values
   of one subject removed and 200 added, into a named graph already holding 100,000
   triples, written the ways pyoxigraph 0.5 allows: one SPARQL UPDATE (DELETE DATA then
   INSERT DATA, what the store commits; with and without a 60 KB literal as its log
   entry's payload), the same update again when it changes nothing (the parse and
   Oxigraph's lookups alone), and two ways that are not atomic, to tell the parts apart:
   DELETE DATA then `load` of the additions, and `remove` of each quad then `extend`.
   Milliseconds of wall time and of CPU per changeset.
3. Zenoh: a writer's GET to a queryable in a router process that hands it to
   a thread (as the store's callbacks do), which replies and puts a sample that
   a subscriber process receives: p50/p99 from the GET to the subscriber's
   callback, with no storing, checking or decoding at all.
"""

from __future__ import annotations

import queue
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pyoxigraph as ox
import zenoh
from _harness import free_port, median, percentile, reap
from _output import bench_parser, parse, png, print_table

from space import make_config

GRAPH = "urn:tspace:graph:floor:asserted"
NQ = ox.RdfFormat.N_QUADS


WAYS = {  # name -> (method, graph: named or default, on disk, triples a call)
    "load, named graph, 100 a commit": ("load", True, True, 100),
    "load, named graph, 1,600 a commit": ("load", True, True, 1600),
    "load, named graph, 10,000 a commit": ("load", True, True, 10_000),
    "load, named graph, 1,600 a commit, in memory": ("load", True, False, 1600),
    "load, default graph, 1,600 a commit": ("load", False, True, 1600),
    "extend (quads made before), named graph, 1,600": ("extend", True, True, 1600),
    "bulk_load (not atomic), named graph, 1,600 a call": ("bulk_load", True, True, 1600),
    "bulk_load (not atomic), named graph, 10,000 a call": ("bulk_load", True, True, 10_000),
}


def oxigraph(method: str, named: bool, disk: bool, batch: int, total: int) -> tuple[float, float]:
    """Return (triples/s of wall time, triples per CPU-second) of writing `total` new triples,
    `batch` per call, into a store already holding 100,000."""
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as d:
        store = ox.Store(d) if disk else ox.Store()
        store.load(_doc(0, 100_000, named), format=ox.RdfFormat.N_QUADS)
        fmt = ox.RdfFormat.N_QUADS if named else ox.RdfFormat.N_TRIPLES
        docs: list = [_doc(100_000 + i, batch, named) for i in range(0, total, batch)]
        if method == "extend":
            docs = [list(ox.parse(doc, format=fmt)) for doc in docs]
        write = getattr(store, method)
        wall, cpu = time.perf_counter(), time.process_time()
        for doc in docs:
            write(doc) if method == "extend" else write(doc, format=fmt)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        del write, store  # closes the database before its directory goes
    return total / wall, total / cpu


CHANGESET = {  # name -> how a changeset of 200 removed + 200 added is written
    "UPDATE, DELETE DATA + INSERT DATA (the store's commit)": "update",
    "the same, + a 60 KB literal (its log entry's payload)": "update+payload",
    "the same UPDATE again: nothing changes (parse, lookups)": "again",
    "DELETE DATA, then load of the additions (not atomic)": "delete+load",
    "remove() of each, then extend (not atomic, 201 commits)": "remove+extend",
}


def changesets(rounds: int) -> dict[str, tuple[float, float]]:
    """Return each way's (ms of wall time, ms of CPU) per changeset of 200 values replaced,
    into a store already holding 100,000 triples; the ways interleaved round by round."""
    times: dict[str, list[tuple[float, float]]] = {}
    payload = '"' + "A" * 60_000 + '"'
    g = f"<{GRAPH}>"
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as d:
        store = ox.Store(d)
        store.load(_doc(0, 100_000), format=ox.RdfFormat.N_QUADS)
        store.flush()
        store.optimize()  # the load's compactions done before the clock runs
        value, last = 0, ""

        def rows(v: int) -> list[str]:
            xsd = "http://www.w3.org/2001/XMLSchema#integer"
            return [f'<urn:floor:base> <urn:floor:set{k}> "{v + k}"^^<{xsd}>' for k in range(200)]

        store.load("".join(f"{r} {g} .\n" for r in rows(0)), format=NQ)
        for _ in range(rounds):
            for name, way in CHANGESET.items():
                old, new = rows(value), rows(value + 1000)
                log = f"GRAPH <urn:floor:log> {{ <urn:floor:e{value}> <urn:floor:p> {payload} }}"
                text = (
                    f"DELETE DATA {{ GRAPH {g} {{ {' . '.join(old)} }} }} ;\n"
                    f"INSERT DATA {{ GRAPH {g} {{ {' . '.join(new)} }} "
                    f"{log if way == 'update+payload' else ''} }}"
                )
                additions = "".join(f"{r} {g} .\n" for r in new)
                gone = list(ox.parse("".join(f"{r} {g} .\n" for r in old), format=NQ))
                added = list(ox.parse(additions, format=NQ))
                if way == "again":  # the previous way's update, applied once more
                    text = last
                wall, cpu = time.perf_counter(), time.process_time()
                if way.startswith("update") or way == "again":
                    store.update(text)
                elif way == "delete+load":
                    store.update(text.split(" ;\n")[0])
                    store.load(additions, format=NQ)
                else:
                    for quad in gone:
                        store.remove(quad)
                    store.extend(added)
                wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
                times.setdefault(name, []).append((wall * 1000, cpu * 1000))
                if way != "again":
                    value += 1000
                last = text
        del store
    return {
        name: (median([w for w, _ in v]), median([c for _, c in v])) for name, v in times.items()
    }


def million(bulk: bool) -> tuple[float, float]:
    """Return (triples/s, triples per CPU-second) of 1M triples into a fresh on-disk store:
    10,000 a commit with a flush every 50,000 (as the store does), or one `bulk_load`."""
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as d:
        store = ox.Store(d)
        docs = [_doc(0, 1_000_000)] if bulk else [_doc(i, 10_000) for i in range(0, 10**6, 10**4)]
        wall, cpu = time.perf_counter(), time.process_time()
        for n, doc in enumerate(docs):
            if bulk:
                store.bulk_load(doc, format=ox.RdfFormat.N_QUADS)
            else:
                store.load(doc, format=ox.RdfFormat.N_QUADS)
                if n % 5 == 4:
                    store.flush()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        del store
    return 10**6 / wall, 10**6 / cpu


def _doc(first: int, count: int, named: bool = True) -> str:
    xsd = "http://www.w3.org/2001/XMLSchema#integer"
    end = f" <{GRAPH}> .\n" if named else " .\n"
    return "".join(
        f'<urn:floor:s{i // 100}> <urn:floor:p{i % 5}> "{i}"^^<{xsd}>{end}'
        for i in range(first, first + count)
    )


def serve(endpoint: str) -> None:
    """Child: a router whose queryable's thread replies and publishes what it got."""
    requests: queue.SimpleQueue[zenoh.Query] = queue.SimpleQueue()
    with zenoh.open(make_config(mode="router", listen=[endpoint])) as session:
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

    with zenoh.open(make_config(connect=[endpoint])) as session:
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
        with zenoh.open(make_config(connect=[endpoint])) as session:
            time.sleep(0.5)  # the subscriber's interest reaches the router
            for _ in range(count):
                list(session.get("floor/write", payload=str(time.monotonic_ns()).encode()))
            list(session.get("floor/write", payload=b"-1"))
        out = children[1].stdout.readline()  # type: ignore[union-attr]
        delays = [int(x) / 1e6 for x in out.split()]
        return percentile(delays, 50), percentile(delays, 99)
    finally:
        reap(children)  # a failed run: do not leave them behind


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--count", type=int, default=1000, help="GETs per Zenoh run")
    parser.add_argument("--million", action="store_true", help="also 1M into a fresh store")
    parser.add_argument(
        "--changesets", type=int, default=20, help="rounds of the changeset-with-removals ways"
    )
    args = parse(parser, own_plot=True)
    rows: dict[str, list[tuple[float, float]]] = {}
    zenoh_rows: dict[str, list[float]] = {}
    changeset_rows: dict[str, list[tuple[float, float]]] = {}
    for _ in range(args.runs):
        for name, (method, named, disk, batch) in WAYS.items():
            total = 32_000 if batch < 10_000 else 100_000
            rows.setdefault(name, []).append(oxigraph(method, named, disk, batch, total))
        if args.million:
            rows.setdefault("1M into a fresh store, 10,000 a commit, flush", []).append(
                million(bulk=False)
            )
            rows.setdefault("1M into a fresh store, one bulk_load", []).append(million(bulk=True))
        for name, (wall, cpu) in changesets(args.changesets).items():
            changeset_rows.setdefault(name, []).append((wall, cpu))
        p50, p99 = zenoh_hop(args.count)
        zenoh_rows.setdefault("Zenoh GET -> thread -> put -> subscriber p50 (ms)", []).append(p50)
        zenoh_rows.setdefault("Zenoh GET -> thread -> put -> subscriber p99 (ms)", []).append(p99)
    table = []
    for name, values in rows.items():
        wall, cpu = [v[0] for v in values], [v[1] for v in values]
        table.append((name, f"{median(wall):,.0f}", f"{median(cpu):,.0f}", _range(cpu)))
    print_table(
        f"Oxigraph alone (pyoxigraph {ox.__version__}), medians of {args.runs} runs",
        ["way of writing", "triples/s", "triples/CPU-s", "triples/CPU-s min..max"],
        table,
    )
    path = png(args, "floors.png")
    if path is not None:
        plot({name: median([v[1] for v in values]) for name, values in rows.items()}, path)
    table = [
        (name, median([w for w, _ in v]), median([c for _, c in v]), _range([c for _, c in v], 2))
        for name, v in changeset_rows.items()
    ]
    print_table(
        f"A changeset of 200 values replaced, into 100,000 triples (pyoxigraph {ox.__version__}), "
        f"medians of {args.runs} runs of {args.changesets}",
        ["way of writing", "wall ms", "CPU ms", "CPU ms min..max"],
        table,
    )
    table = [(m, median(v), f"{min(v):.3f}..{max(v):.3f}") for m, v in zenoh_rows.items()]
    print_table(
        f"Zenoh alone, medians of {args.runs} runs",
        ["measure", "median (ms)", "min..max (ms)"],
        table,
    )


def plot(per_cpu: dict[str, float], path: Path) -> None:
    """Draw each way's triples per CPU-second against issue 9's 200,000 triples/s."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 0.4 * len(per_cpu) + 1.2))
    ax.barh(list(per_cpu), list(per_cpu.values()), color="tab:blue")
    ax.axvline(200_000, color="tab:red", linewidth=1, label="target: 200,000 triples/s")
    ax.xaxis.set_major_formatter(lambda x, _pos: f"{x / 1000:,.0f}k")
    ax.set_xlabel("triples per CPU-second of the process (Oxigraph alone, no tspace code)")
    ax.invert_yaxis()
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"plot: {path}")


def _range(values: list[float], digits: int = 0) -> str:
    return f"{min(values):,.{digits}f}..{max(values):,.{digits}f}"


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] in ("serve", "listen"):
        {"serve": serve, "listen": listen}[sys.argv[1]](sys.argv[2])
    else:
        main()
