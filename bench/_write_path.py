"""Child process of space_bench's `--write-path`: the store's own time for a write, in-process.

Run from the tree under test (PYTHONPATH), it drives that tree's writer (`space.store.writer`)
as the server's worker thread does, with no Zenoh hop and no thread hand-off: decode and check,
decide, commit (Oxigraph on disk), publish on a session with a subscriber on `@/changes`.
Two cases, into a space already holding 100,000 inferred triples:

- `one triple`: a sensor's write, one triple of one of 10 subjects (space_bench's latency
  write), as the store sees it: the store's share of write -> notification;
- `200 replaced`: the reasoner's answer when 200 rules fire, 200 inferred values removed and
  200 added (issue 13's "+200 rules all firing"), whole path and `StoreDB.commit` alone;
- `200 settings flipped`: end_to_end's "+200 firing" answer as the store sees it, 200
  asserted settings of one subject going from "normal" to "low" and back at each write (the
  values a reasoner's rules set come and go): the writer thread's CPU, whole write;
- `200 replaced, parts`: the same answer again, 100 times, with a subscriber to its parts
  in another session (the store then cuts it by subject, 200 pairs of one subject in a few
  parts of at most 4 KB of predicates in their keys, and puts each):
  the writer thread's CPU in `PartPublisher.publish`, median of the last 50 (its keys come
  back every time, as those of a reasoner's answer do);
- `fleet`: fleet.py's sustained load as the saturated store takes it: 200 robots' sensor
  changes (a reading replaced), one changeset each, decided and committed in one batch:
  the writer thread's CPU a write;
- `bulk`: 200,000 new triples in changesets of 10,000, as `tspace write` of a big file
  sends them (10 triples a subject, space_bench's document): CPU microseconds a triple of
  the writer thread (decoding and checking, deciding, committing) and of the whole process
  (RocksDB's background threads too), and triples a second.

- `served`: the store served as `tspace serve` serves it (a router session, the worker
  thread, Zenoh's callbacks), with space_bench's latency writer and subscriber processes
  (1,000 acked one-triple writes): medians of the writer thread's decoding and deciding
  (`Writer.write`), its commit and its put on `@/changes` for each write, and write ->
  notification as the subscriber saw it. The same code as `one triple`, with the other
  threads and processes beside it.

Prints one JSON object: median microseconds of each.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable
from pathlib import Path

import pyoxigraph as ox
import zenoh
from _harness import free_port

import space.store.db as db_module
import space.store.writer as writer_module
from space.changeset import WIRE_VERSION, pack
from space.store import intake
from space.store.parts import PartPublisher
from space.store.publish import Publisher
from space.store.server import StoreServer
from space.store.writer import Request, Writer
from space.zconfig import make_config

INT = "http://www.w3.org/2001/XMLSchema#integer"
BULK = 200_000  # triples of the bulk case
_COMMIT = db_module.StoreDB.commit  # as the module defines it, before it is timed


def _timed(f: Callable, calls: list[float], clock: Callable = time.perf_counter) -> Callable:
    """Return `f` noting the seconds (of `clock`) of each call in `calls`."""

    def timed(*args: object, **kwargs: object) -> object:
        start = clock()
        try:
            return f(*args, **kwargs)
        finally:
            calls.append(clock() - start)

    return timed


def main(rounds: int) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conf = make_config(mode="peer", listen=[endpoint])
    commits: list[float] = []
    committing = db_module.StoreDB.commit
    db_module.StoreDB.commit = _timed(committing, commits)  # type: ignore[method-assign]
    with (
        zenoh.open(conf) as session,
        tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as data,
    ):
        server = StoreServer(session, Path(data))
        server._db = db = db_module.StoreDB(Path(data))
        writer = Writer(
            session,
            db,
            spaces=server._spaces,
            space=server._space,
            publisher=server._publisher,
            max_spaces=10,
            leases=server._leases,
        )
        g = "<urn:tspace:graph:w:inferred>"
        db.store.load(
            "".join(
                f'<urn:b:s{i // 10}> <urn:b:p{i % 10}> "{i}"^^<{INT}> {g} .\n'
                for i in range(100_000)
            ),
            format=ox.RdfFormat.N_QUADS,
        )
        db.store.flush()
        db.store.optimize()  # the load's compactions done before the clock runs
        subscriber = session.declare_subscriber("tspace/w/@/changes", lambda _s: None)

        def write(wire: dict, clock: Callable[[], float] = time.perf_counter) -> float:
            req = _request(session, "w", "bench", wire)
            start = clock()
            pending: list = []
            writer.write(req, pending)
            writer.commit(pending)
            return clock() - start

        def value(i: int) -> str:
            return f'"{time.monotonic_ns() + i}"^^<{INT}>'

        one = [
            write({"add": [[f"<urn:bench:s{i % 10}>", "<urn:bench:t>", value(0)]]})
            for i in range(rounds * 10)
        ]
        old: list[list[str]] = []
        whole = []
        commits.clear()
        for _ in range(rounds + 1):
            new = [["<urn:b:base>", f"<urn:b:setting_{k}>", value(k)] for k in range(200)]
            whole.append(write({"iadd": new, "idel": old}))
            old = new
        flips = [
            write(_flipped(k % 2 == 1, first=k == 0), clock=time.thread_time)
            for k in range(rounds + 1)
        ]
        fleet = _fleet_batches(writer, session, rounds)
        figures = {
            "one triple, whole write (us)": _median_us(one[rounds:]),
            "fleet: 200 sensor writes in one batch, writer thread (us CPU a write)": fleet,
            "200 settings flipped, whole write (us CPU)": _median_us(flips[1:]),
            "200 replaced, whole write (us)": _median_us(whole[1:]),
            "200 replaced, StoreDB.commit (us)": _median_us(commits[1:]),
            "200 replaced, parts: PartPublisher.publish (us CPU)": _parts(session, write, endpoint),
        }
        commits.clear()
        decoding: list[float] = []
        writer_module.intake.write_request = _timed(  # type: ignore[attr-defined]
            intake.write_request, decoding, time.thread_time
        )
        db_module.StoreDB.commit = _timed(committing, commits, time.thread_time)  # type: ignore[method-assign]
        wall, cpu, thread = time.perf_counter(), time.process_time(), time.thread_time()
        for first in range(0, BULK, 10_000):
            rows = [row for i in range(first // 10, first // 10 + 1000) for row in _bulk_rows(i)]
            wire = {"v": WIRE_VERSION, "id": uuid.uuid4().hex, "agent": "bulk", "add": rows}
            pending = []
            writer.write(Request("write", "bulk", pack(wire), None, "tspace/bulk/@/write"), pending)
            writer.commit(pending)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        thread = time.thread_time() - thread
        writer_module.intake.write_request = intake.write_request  # type: ignore[attr-defined]
        per = 1e6 / BULK
        figures.update(
            {
                "bulk: writer thread, decode and check (us CPU/triple)": sum(decoding) * per,
                "bulk: writer thread, decide (us CPU/triple)": (
                    thread - sum(decoding) - sum(commits)
                )
                * per,
                "bulk: writer thread, commit (us CPU/triple)": sum(commits) * per,
                "bulk: whole process (us CPU/triple)": cpu * per,
                "bulk: in-process rate (triples/s)": BULK / wall,
            }
        )
        subscriber.undeclare()
        server._publisher.close()
        db.close()
    figures.update(served(1000))
    print(json.dumps(figures))


def _fleet_batches(writer: Writer, session: zenoh.Session, rounds: int) -> float:
    """Return the median writer-thread CPU microseconds a write of fleet.py's sustained load.

    200 robots' sensor changes (each one reading replaced by the next, one changeset
    each, with an id and a stamp), decided and committed as one batch, as the saturated
    store's worker takes them (see the module's doc).
    """

    def reading(k: int, r: int) -> list[str]:
        return [f"<urn:f:robot{k}_battery>", "<urn:f:charge_percent>", f'"{r}"^^<{INT}>']

    def batch(r: int) -> float:
        pending: list = []
        start = time.thread_time()
        for k in range(200):
            wire: dict = {"add": [reading(k, r)]}
            if r:
                wire["del"] = [reading(k, r - 1)]
            writer.write(_request(session, "fleet", f"robot{k}", wire), pending)
        writer.commit(pending)
        return (time.thread_time() - start) / 200

    per_write = [batch(r) for r in range(rounds + 2)]
    return _median_us(per_write[2:])


def _request(session: zenoh.Session, space: str, agent: str, wire: dict) -> Request:
    """Return a write request of `wire` (its triples) as a client sends it: an id and a stamp."""
    wire.update(v=WIRE_VERSION, id=uuid.uuid4().hex, agent=agent)
    wire["ts"] = str(session.new_timestamp())
    return Request("write", space, pack(wire), None, f"tspace/{space}/@/write")


def _parts(session: zenoh.Session, write: Callable[[dict], float], endpoint: str) -> float:
    """Return the median CPU microseconds of publishing a 200-part answer (see the module's doc)."""
    calls: list[float] = []
    publish = PartPublisher.publish
    PartPublisher.publish = _timed(publish, calls, time.thread_time)  # type: ignore[method-assign]
    with zenoh.open(make_config(mode="peer", connect=[endpoint])) as other:
        subscriber = other.declare_subscriber("tspace/w/@/changes/*/*/**", lambda _s: None)
        watcher = session.declare_publisher("tspace/w/@/changes/*/*/**")
        deadline = time.monotonic() + 10
        while not watcher.matching_status.matching and time.monotonic() < deadline:
            time.sleep(0.01)
        watcher.undeclare()
        old: list[list[str]] = []
        for r in range(100):
            new = [["<urn:b:base>", f"<urn:b:setting_{k}>", f'"{r}.{k}"'] for k in range(200)]
            write({"iadd": new, "idel": old})
            old = new
        subscriber.undeclare()
    PartPublisher.publish = publish  # type: ignore[method-assign]
    return _median_us(calls[-50:])


def served(count: int) -> dict[str, float]:
    """Return the medians of a served one-triple write's stages (see the module's doc)."""
    stages: dict[str, list[float]] = {"write": [], "commit": [], "put": []}
    writer_module.Writer.write = _timed(writer_module.Writer.write, stages["write"])  # type: ignore[method-assign]
    db_module.StoreDB.commit = _timed(_COMMIT, stages["commit"])  # type: ignore[method-assign]
    streams = Publisher._stream

    def stream(self: Publisher, space: str, service: str) -> object:
        publisher = streams(self, space, service)
        return _TimedPut(publisher, stages["put"]) if service == "changes" else publisher

    Publisher._stream = stream  # type: ignore[method-assign,assignment]
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    child = [sys.executable, str(Path(__file__).parent / "_latency_subscriber.py")]
    with (
        zenoh.open(make_config(mode="router", listen=[endpoint])) as session,
        tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as data,
    ):
        server = StoreServer(session, Path(data))
        server.start()
        try:
            sub = subprocess.Popen(
                [*child, "subscribe", endpoint, "lat"], stdout=subprocess.PIPE, text=True
            )
            assert sub.stdout is not None and sub.stdout.readline().strip() == "ready"
            subprocess.run([*child, "write", endpoint, "lat", str(count)], check=True)
            delays = [int(x) / 1e6 for x in sub.stdout.readline().split()]
            sub.wait(timeout=10)
        finally:
            server.close()
    return {
        "served: decode and decide, Writer.write (us)": _median_us(stages["write"]),
        "served: StoreDB.commit (us)": _median_us(stages["commit"]),
        "served: put on @/changes (us)": _median_us(stages["put"]),
        "served: write -> notification p50 (ms)": statistics.median(delays),
    }


class _TimedPut:
    """A publisher whose puts are timed."""

    def __init__(self, publisher: zenoh.Publisher, calls: list[float]) -> None:
        self._publisher = publisher
        self._calls = calls

    def put(self, payload: bytes) -> None:
        start = time.perf_counter()
        self._publisher.put(payload)
        self._calls.append(time.perf_counter() - start)


def _flipped(low: bool, *, first: bool = False) -> dict:
    """Return end_to_end's "+200 firing" answer: 200 asserted settings of a base to "low"
    (`low`) or back to "normal", each replacing the other (`first`: only add them)."""
    base, values = "<urn:b:robot1_base>", ('"normal"', '"low"')
    new, old = (values[1], values[0]) if low else values
    rows = [[base, f"<urn:b:setting_{k}>", new] for k in range(200)]
    if first:
        return {"add": rows}
    return {"add": rows, "del": [[base, f"<urn:b:setting_{k}>", old] for k in range(200)]}


def _bulk_rows(i: int) -> list[list[str]]:
    """Return the 10 triples of subject `i` of space_bench's bulk document, as N-Triples."""
    b, x = f"<urn:bench:b{i}>", "http://www.w3.org/2001/XMLSchema#"
    objects = [
        f'"{i}"^^<{x}integer>',
        f'"v{i}"',
        f"<urn:bench:k{i % 9}>",
        f'"{i % 3}"^^<{x}integer>',
        f'"{i}x"',
        f"<urn:bench:c{i % 5}>",
        f'"{i}.5"^^<{x}decimal>',
        '"e"',
        "<urn:bench:f1>",
        f'"{i * 2}"^^<{x}integer>',
    ]
    return [[b, f"<urn:bench:{p}>", o] for p, o in zip("nskabcdefg", objects, strict=True)]


def _median_us(values: list[float]) -> float:
    return statistics.median(values) * 1e6


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
