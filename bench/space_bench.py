"""Benchmark the triple space: notification latency, write throughput, 10k-triple query.

Run: python bench/space_bench.py [--runs 5] [--store] [--old DIR --plot docs/store-bench.png]
With --old (a worktree of the code before: `git worktree add /tmp/old a5d5dd9`) every run
measures the server from that tree and from this one, interleaved; the latency's writer and
subscriber run from the same tree as the server (the client's path is part of that figure),
the other clients are this tree's (the wire format is compatible both ways), so the rest of
the difference is the store's. `--latency-only`: only the write -> notification latency.
`--write-path`: only the store's own time for a write, in-process, in each tree
(`_write_path.py`: a one-triple write; 200 inferred values replaced, and its commit alone; 200
asserted settings flipped, a reasoner's answer).
Every figure is a median over runs; the store, the subscriber and the writer
are separate processes talking through the router on loopback.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections import deque
from pathlib import Path

import _store_measures as store
from _harness import code_env, median, percentile, serve_process
from _output import bench_parser, parse, plot_tables, png, print_table
from rdflib import Literal, Namespace, URIRef

from space import Pending, TripleSpace

BENCH = Path(__file__).parent
T = URIRef("urn:bench:t")
EX = Namespace("urn:bench:")
WINDOW = 16  # acknowledgements outstanding in the pipelined mode
THROUGHPUT = {
    "acked": "acked one by one, changesets",
    "pipelined": f"acked, {WINDOW} in flight, changesets",
    "nowait": "fire-and-forget, changesets",
}


def latency(
    endpoint: str, space: str, count: int, nowait: bool, code: Path | None = None
) -> tuple[float, float]:
    """Return p50, p99 (ms) from a write starting to the subscriber process receiving it.

    The writer and the subscriber are processes running from `code` (default this tree).
    """
    child = [sys.executable, str(BENCH / "_latency_subscriber.py")]
    env = code_env(code)
    sub = subprocess.Popen(
        [*child, "subscribe", endpoint, space], stdout=subprocess.PIPE, text=True, env=env
    )
    assert sub.stdout is not None
    assert sub.stdout.readline().strip() == "ready"
    mode = ["nowait"] if nowait else []
    subprocess.run([*child, "write", endpoint, space, str(count), *mode], check=True, env=env)
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


def measure(endpoint: str, pid: int, code: Path | None, run: int, args) -> dict[str, float]:
    """Return every figure of one run against one server."""
    rows: dict[str, float] = {}
    if args.million:  # a tree whose `tspace write` sends one changeset fails: 0 triples/s
        used = store.cpu_seconds(pid)
        rows["tspace write of 1,000,000 triples, fresh store (triples/s)"] = store.bulk_write(
            endpoint, code, 1_000_000
        )
        rows["store CPU for them (us/triple)"] = store.cpu_seconds(pid) - used
        rows["store RSS holding those 1,000,000 triples (MB)"] = store.rss_mb(pid)
        return rows
    p50, p99 = latency(endpoint, f"lat{run}", args.count, nowait=False, code=code)
    rows["latency write()->notify p50 (ms)"] = p50
    rows["latency write()->notify p99 (ms)"] = p99
    if args.latency_only:
        return rows
    for mode in ("acked", "pipelined"):
        used = store.cpu_seconds(pid)
        rows[f"throughput, {THROUGHPUT[mode]} of 100 (triples/s)"] = throughput(
            endpoint, f"thr{mode}{run}", 200, 100, mode
        )
        # the store's CPU for those 20,000 triples: steadier than wall time on a shared machine
        rows[f"store CPU, {THROUGHPUT[mode]} of 100 (us/triple)"] = (
            (store.cpu_seconds(pid) - used) / 20_000 * 1e6
        )
    cli, lib = query_10k(endpoint, f"q{run}")
    rows["tspace query, 10,000 triples, whole CLI (s)"] = cli
    rows["TripleSpace.query, 10,000 triples (s)"] = lib
    if args.store:
        space = f"sparql{run}"
        started = time.perf_counter()
        store.load_100k(endpoint, space)
        rows["write 100,000 triples, 1,000 a changeset, 16 in flight (s)"] = (
            time.perf_counter() - started
        )
        for name, seconds in store.sparql_times(endpoint, space, 3).items():
            rows[f"SPARQL on 100k: {name} (ms)"] = seconds * 1000
        took, beside, alone = store.writes_beside_a_slow_query(endpoint)
        rows["a slow query's duration (s)"] = took
        for label, delays in (("beside it", beside), ("alone, just before it", alone)):
            rows[f"100 acked writes {label}, p50 (ms)"] = percentile(delays, 50)
            rows[f"100 acked writes {label}, p99 (ms)"] = percentile(delays, 99)
            rows[f"100 acked writes {label}, max (ms)"] = max(delays)
        name = f"tspace write of {args.bulk:,} triples (triples/s)"
        if code is not None and args.bulk > 100_000:
            # the old `tspace write` sends one changeset, which its store refuses above 100,000
            rows[name] = float("nan")
        else:
            rows[name] = store.bulk_write(endpoint, code, args.bulk)
        rows[f"store RSS holding ~{(100_000 + args.bulk) // 1000:,}k triples (MB)"] = store.rss_mb(
            pid
        )
    return rows


def write_path(code: Path | None) -> dict[str, float]:
    """Return the store's own microseconds for a write, in-process, run from `code`."""
    child = [sys.executable, str(BENCH / "_write_path.py"), "30"]
    out = subprocess.run(child, capture_output=True, text=True, check=True, env=code_env(code))
    return json.loads(out.stdout)


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--count", type=int, default=1000, help="changesets per latency run")
    parser.add_argument(
        "--old", type=Path, help="a source tree of the code before (git worktree add DIR REV)"
    )
    parser.add_argument(
        "--store",
        action="store_true",
        help="also SPARQL on 100k, writes beside a slow query, "
        "a bulk tspace write and the store's RSS after it (the old tree's bulk write "
        "is skipped above 100,000 triples: its one changeset would be refused)",
    )
    parser.add_argument("--bulk", type=int, default=100_000, help="triples of the bulk write")
    parser.add_argument(
        "--million",
        action="store_true",
        help="only `tspace write` of 1,000,000 triples into a fresh store, and its RSS then",
    )
    parser.add_argument(
        "--latency-only", action="store_true", help="only the write -> notification latency"
    )
    parser.add_argument(
        "--write-path",
        action="store_true",
        help="only the store's own time for a write, in-process, no Zenoh hop (_write_path.py)",
    )
    args = parse(parser, own_plot=True)
    codes: dict[str, Path | None] = {"new": None}
    if args.old is not None:
        codes = {"old": args.old.resolve(), "new": None}
    results: dict[str, dict[str, list[float]]] = {name: {} for name in codes}
    for run in range(args.runs):
        for name, code in codes.items():  # interleaved, so that the machine's moods hit both
            if args.write_path:
                for measure_name, value in write_path(code).items():
                    results[name].setdefault(measure_name, []).append(value)
                continue
            with serve_process(code) as (endpoint, pid):
                for measure_name, value in measure(endpoint, pid, code, run, args).items():
                    results[name].setdefault(measure_name, []).append(value)
                    print(f"  run {run + 1} {name}: {measure_name} = {value:.3f}", file=sys.stderr)
    names = [m for m in results["new"] if m in results.get("old", results["new"])]
    names += [m for m in results["new"] if m not in names]
    header = ["measure", *(f"{n} median" for n in codes), *(f"{n} min..max" for n in codes)]
    rows = []
    for m in names:
        values = [results[n].get(m, [float("nan")]) for n in codes]
        rows.append(
            (m, *(median(v) for v in values), *(f"{min(v):.3f}..{max(v):.3f}" for v in values))
        )
    title = f"tspace space benchmark, medians of {args.runs} runs"
    print_table(title, header, rows)
    path = png(args, "space_bench.png")
    if path is not None and "old" in results:
        plot(results, names, path)
    elif path is not None and plot_tables([(title, header, rows)], path):
        print(f"plot: {path}")


def plot(results: dict[str, dict[str, list[float]]], names: list[str], path: Path) -> None:
    """Draw new/old per measure (medians) as horizontal bars; > 1 means the new one is larger."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [m for m in names if m in results["old"]]
    ratios = [median(results["new"][m]) / median(results["old"][m]) for m in names]
    fig, ax = plt.subplots(figsize=(9, 0.4 * len(names) + 1))
    ax.barh(names, ratios, color=["tab:green" if "/s" in m else "tab:blue" for m in names])
    ax.axvline(1.0, color="black", linewidth=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("new / old (median; triples/s: higher is better, times and MB: lower)")
    ax.invert_yaxis()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"plot: {path}")


if __name__ == "__main__":
    main()
