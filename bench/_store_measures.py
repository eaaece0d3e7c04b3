"""Measures of the store for space_bench: SPARQL on 100k triples, writes beside a slow query,
a bulk load through `tspace write`, and the store's memory."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from _harness import code_env
from rdflib import Literal, Namespace

from space import QueryError, SpaceError, TripleSpace

EX = Namespace("urn:bench:")
ROBOTS = 100
DEVICES = 10_000  # x 10 triples = 100,000
QUERIES = {
    "selective join": "SELECT ?d ?l WHERE { ?d ex:robot ex:r7 . ?d ex:level ?l }",
    "filter": "SELECT ?d WHERE { ?d ex:charge ?c FILTER(?c < 5) }",
    "aggregate": "SELECT ?r (COUNT(?d) AS ?n) WHERE { ?d ex:robot ?r } GROUP BY ?r",
    "property path": "SELECT ?x WHERE { ex:d0 ex:partOf+ ?x }",
}


def _device(i: int) -> list[tuple]:
    d = EX[f"d{i}"]
    return [
        (d, EX.robot, EX[f"r{i % ROBOTS}"]),
        (d, EX.level, Literal(["low", "normal", "high"][i % 3])),
        (d, EX.charge, Literal(i % 100)),
        (d, EX.name, Literal(f"device {i}")),
        (d, EX.kind, EX[f"k{i % 17}"]),
        (d, EX.mode, Literal("active")),
        (d, EX.speed, Literal(i % 7)),
        (d, EX.place, EX[f"room{i % 50}"]),
        (d, EX.partOf, EX[f"d{i + 1}"]) if i < 999 else (d, EX.serial, Literal(i)),
        (d, EX.seen, Literal(i * 10)),
    ]


def load_100k(endpoint: str, space: str) -> None:
    """Write the 100,000-triple device data set, 1,000 triples a changeset, 16 in flight."""
    with TripleSpace.open(endpoint, space=space, prefixes={"ex": str(EX)}) as ts:
        pending = []
        for first in range(0, DEVICES, 100):
            triples = [t for i in range(first, first + 100) for t in _device(i)]
            pending.append(ts.send_later(ts.changeset(triples), timeout=120))
            if len(pending) >= 16:
                pending.pop(0).result()
        for p in pending:
            p.result()


def sparql_times(endpoint: str, space: str, runs: int) -> dict[str, float]:
    """Return the median seconds of each query in QUERIES, through the store (NaN: it failed)."""
    times: dict[str, list[float]] = {}
    with TripleSpace.open(endpoint, space=space, prefixes={"ex": str(EX)}) as ts:
        for _ in range(runs):
            for name, text in QUERIES.items():
                start = time.perf_counter()
                try:
                    rows = len(ts.query_sparql(f"PREFIX ex: <{EX}>\n{text}", timeout=600))
                except QueryError as exc:
                    print(f"  ({name} failed: {exc})", file=sys.stderr)
                    times.setdefault(name, []).append(float("nan"))
                    continue
                times.setdefault(name, []).append(time.perf_counter() - start)
                assert rows > 0, name
    return {name: sorted(v)[len(v) // 2] for name, v in times.items()}


def writes_beside_a_slow_query(
    endpoint: str, seconds: float = 5.0
) -> tuple[float, list[float], list[float]]:
    """Return (query s, write ms beside it, write ms alone) of 100 acked writes each.

    The max matters: writes are sequential, so a store that answers the query on
    its writer delays only the first write (by the whole query), which p99 of 100
    (the second worst) does not show.

    The query counts a four-way cross join, its size calibrated on this store
    first; the writes (another client, another space) start once it runs and are
    spread over its expected duration. The same 100 writes, spaced the same, are
    timed first with no query running: the machine's own tail, to tell from what
    the query adds.
    """
    text = "SELECT (COUNT(*) AS ?n) WHERE { ?a ?p ?b . ?c ?q ?d . ?e ?r ?f . ?g ?s ?h }"
    with TripleSpace.open(endpoint, space="slowq") as ts:
        n = 10
        ts.write([(EX[f"x{i}"], EX.v, Literal(i)) for i in range(n)])
        took = _timed(ts, text)
        while took < seconds * 0.6:
            grow = max(n + 2, int(n * min(2.0, (seconds / max(took, 1e-3)) ** 0.25)))
            ts.write([(EX[f"x{i}"], EX.v, Literal(i)) for i in range(n, grow)])
            n = grow
            took = _timed(ts, text)
        holder: list[float] = []
        query = threading.Thread(target=lambda: holder.append(_timed(ts, text)))
        with TripleSpace.open(endpoint, space="beside") as writer:
            alone = _paced_writes(writer, took * 0.8 / 100)
            query.start()
            time.sleep(0.3)  # the query must be running at the store before the writes start
            beside = _paced_writes(writer, took * 0.8 / 100)
            query.join()
    return holder[0], beside, alone


def _paced_writes(writer: TripleSpace, spacing: float) -> list[float]:
    """Return the ms each of 100 acked one-triple writes took, one every `spacing` s."""
    delays = []
    for i in range(100):
        begun = time.perf_counter()
        writer.write([(EX.w, EX.n, Literal(i))], timeout=300)
        delays.append((time.perf_counter() - begun) * 1000)
        time.sleep(max(0.0, spacing - (time.perf_counter() - begun)))
    return delays


def _timed(ts: TripleSpace, text: str) -> float:
    start = time.perf_counter()
    try:
        ts.query_sparql(text, timeout=120)
    except (QueryError, SpaceError) as exc:
        print(f"  (slow query: {exc})", file=sys.stderr)
    return time.perf_counter() - start


def bulk_write(endpoint: str, code: Path | None, triples: int) -> float:
    """Return triples/s of `tspace write big.ttl` (whole process) of a generated Turtle file."""
    with tempfile.NamedTemporaryFile("w", suffix=".ttl", delete=False) as f:
        f.write(f"@prefix ex: <{EX}> .\n")
        for i in range(triples // 10):
            f.write(f'ex:b{i} ex:n {i} ; ex:s "v{i}" ; ex:k ex:k{i % 9} ; ex:a {i % 3} ; ')
            f.write(f'ex:b "{i}x" ; ex:c ex:c{i % 5} ; ex:d {i}.5 ; ex:e "e" ; ex:f ex:f1 ; ')
            f.write(f"ex:g {i * 2} .\n")
        path = f.name
    cmd = [sys.executable, "-m", "space.cli", "write", path, "--connect", endpoint]
    cmd += ["--space", "bulk", "--timeout", "600"]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=code_env(code), check=False)
    took = time.perf_counter() - start
    Path(path).unlink()
    if done.returncode != 0:
        print(f"  (tspace write failed: {done.stderr.strip()[-300:]})", file=sys.stderr)
        return 0.0
    return triples / took


def rss_mb(pid: int) -> float:
    """Return a process's resident set size in MB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def cpu_seconds(pid: int) -> float:
    """Return the CPU time (user + system, every thread) a process has used so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
