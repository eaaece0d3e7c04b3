"""The floor under end_to_end.py: its three hops through the store, with agents doing nothing.

end_to_end.py's path is three changesets in a row, each committed and published by
the store before the next process reacts: the hw_monitor's "very low" -> the
reasoner's answer -> an agent's act. This bench keeps that shape and takes away
everything but the space: the bench writes stage 1 (the start, like the
hw_monitor), relay B writes stage 2 when it sees stage 1 (the reasoner's place),
relay C writes stage 3 when it sees stage 2 (an acting agent's place), and the
bench's plain Zenoh subscriber on `@/changes` stamps stage 3's arrival (as
end_to_end.py stamps an act). The relays are `TripleSpace` clients doing what an
agent's library does (a subscription, a write on a declared querier) and no work
of their own. What this takes is the least any robot's rules could take on this
machine with this design.

Cases (milliseconds from the start's HLC time to stage 3 published, p50/p99):

- `zenoh`: no store: three plain Zenoh puts through a router, each relay putting
  the next from its subscriber's callback: the network's floor;
- `store`: the three hops through `tspace serve`;
- `store + N bystanders`: the same with N more clients subscribed to the space
  that decode every change and do nothing, as end_to_end.py's other agents
  (default 2: five client processes, as there).

Run: python bench/chain_floor.py [--runs 200] [--bystanders 2] [--old TREE] [--json]
[--no-plot]. `--old TREE` runs the store and the relays from another source tree too
(a worktree of the code before), in turn with this one.
"""

from __future__ import annotations

import argparse
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import msgpack
import zenoh
from _harness import code_env, free_port, median, percentile, reap, serve_process
from _output import bench_parser, parse, print_table
from rdflib import Literal, URIRef

from space import TripleSpace, make_config
from space.changeset import hlc_key
from space.terms import to_nt

SPACE = "chain"
S, STAGE = URIRef("urn:chain:s"), URIRef("urn:chain:stage")
STAGE_NT = to_nt(STAGE)


def relay(endpoint: str, role: str) -> None:
    """Run one relay: on stage n-1 write stage n (`role` "2" or "3"), or watch (`"0"`).

    As an agent does: changes delivered on the relay's own thread where the library
    can (`dispatch_thread=False`), else on the handle's dispatcher thread.
    """
    step = int(role)
    own = hasattr(TripleSpace, "deliver")  # an older tree (`--old`) has no such API
    options = {"dispatch_thread": False} if own else {}
    with TripleSpace.open(endpoint, space=SPACE, agent=f"relay{role}", **options) as ts:

        def on_change(change: object) -> None:
            if step == 0:
                return
            for _s, _p, o in change.added:  # type: ignore[attr-defined]
                if int(o) == step - 1:
                    ts.send_later(ts.changeset([(S, STAGE, Literal(step))], [(S, STAGE, o)]))

        ts.subscribe((S, STAGE, None), on_change)
        print("ready", flush=True)
        closed = threading.Event()  # the bench closed our stdin
        threading.Thread(target=lambda: (sys.stdin.read(), closed.set()), daemon=True).start()
        while not closed.is_set():
            if own:
                ts.deliver(0.1)
            else:
                closed.wait(0.1)


def zenoh_relay(endpoint: str, role: str) -> None:
    """Run one plain-Zenoh relay: put `chain/<role>` from the callback of `chain/<role - 1>`."""
    with zenoh.open(make_config(connect=[endpoint])) as session:
        publisher = session.declare_publisher(f"chain/{role}")
        subscriber = session.declare_subscriber(
            f"chain/{int(role) - 1}", lambda sample: publisher.put(sample.payload.to_bytes())
        )
        print("ready", flush=True)
        sys.stdin.read()
        subscriber.undeclare()
        publisher.undeclare()


@contextmanager
def relays(
    endpoint: str, roles: list[str], plain: bool = False, code: Path | None = None
) -> Iterator[None]:
    """Run one relay process per role (its library from `code` if given); stop them after."""
    mode = "--zenoh-relay" if plain else "--relay"
    procs = [
        subprocess.Popen(
            [sys.executable, __file__, mode, role, "--connect", endpoint],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=code_env(code),
        )
        for role in roles
    ]
    try:
        for proc in procs:
            assert proc.stdout is not None
            if proc.stdout.readline().strip() != b"ready":
                raise SystemExit("chain_floor: a relay did not start")
        yield
    finally:
        for proc in procs:
            assert proc.stdin is not None
            proc.stdin.close()
        reap(procs)


def store_chain(runs: int, bystanders: int, code: Path | None = None) -> list[float]:
    """Time `runs` chains through `tspace serve`; return ms from start to stage 3 published.

    `code`: the source tree the store and the relays run from (default: this one).
    """
    arrivals: queue.SimpleQueue[tuple[float, bytes]] = queue.SimpleQueue()
    with (
        serve_process(code) as (endpoint, _pid),
        TripleSpace.open(endpoint, space=SPACE, agent="bench") as ts,
        relays(endpoint, ["2", "3", *["0"] * bystanders], code=code),
    ):
        sub = ts.session.declare_subscriber(
            f"tspace/{SPACE}/@/changes",
            lambda sample: arrivals.put((time.time(), sample.payload.to_bytes())),
        )
        try:
            results = []
            for run in range(runs + 5):  # the first five warm up
                ts.apply([(S, STAGE, Literal(1))], [(S, STAGE, Literal(3))] if run else [])
                start = None
                while True:
                    arrival, payload = arrivals.get(timeout=30)
                    wire = msgpack.unpackb(payload)
                    added = wire.get("add") or ()
                    if any(p == STAGE_NT and o.startswith('"1"') for _, p, o in added):
                        start = hlc_key(wire["ts"])[0] / 2**32
                    if start and any(p == STAGE_NT and o.startswith('"3"') for _, p, o in added):
                        break
                if run >= 5:
                    results.append((arrival - start) * 1e3)
                time.sleep(0.02)  # the relays' acks are in: runs do not overlap
            return results
        finally:
            sub.undeclare()


def zenoh_chain(runs: int) -> list[float]:
    """Time `runs` chains of three plain Zenoh puts through a router (ms)."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    arrivals: queue.SimpleQueue[float] = queue.SimpleQueue()
    with (
        zenoh.open(make_config(mode="router", listen=[endpoint])),
        relays(endpoint, ["2", "3"], plain=True),
        zenoh.open(make_config(connect=[endpoint])) as session,
    ):
        sub = session.declare_subscriber("chain/3", lambda _sample: arrivals.put(time.time()))
        publisher = session.declare_publisher("chain/1")
        time.sleep(0.5)  # the relays' subscriptions have reached the router
        results = []
        for run in range(runs + 5):
            start = time.time()
            publisher.put(b"x" * 200)
            arrival = arrivals.get(timeout=30)
            if run >= 5:
                results.append((arrival - start) * 1e3)
            time.sleep(0.02)
        publisher.undeclare()
        sub.undeclare()
    return results


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=200, help="chains per case")
    parser.add_argument("--bystanders", type=int, default=2, help="idle subscribers beside")
    parser.add_argument(
        "--old", type=Path, metavar="TREE", help="also run the store and relays from TREE"
    )
    parser.add_argument("--relay", help=argparse.SUPPRESS)
    parser.add_argument("--zenoh-relay", help=argparse.SUPPRESS)
    parser.add_argument("--connect", help=argparse.SUPPRESS)
    args = parse(parser)
    if args.relay is not None:
        return relay(args.connect, args.relay)
    if args.zenoh_relay is not None:
        return zenoh_relay(args.connect, args.zenoh_relay)
    cases = {"zenoh, 3 puts through a router": zenoh_chain(args.runs)}
    trees: list[tuple[str, Path | None]] = [("", None)]
    if args.old is not None:
        trees = [(" (old)", args.old.resolve()), (" (new)", None)]
    for bystanders in dict.fromkeys((0, args.bystanders)):
        for label, code in trees:  # in turn: a slow spell of a shared machine hits both
            name = "store, 3 hops" + (f" + {bystanders} bystanders" if bystanders else "")
            cases[name + label] = store_chain(args.runs, bystanders, code)
    title = f"start -> stage 3 published (ms; {args.runs} chains a case)"
    header = ["case", "runs", "p50 (ms)", "p90 (ms)", "p99 (ms)"]
    rows = [
        [name, len(v), median(v), percentile(v, 90), percentile(v, 99)] for name, v in cases.items()
    ]
    print_table(title, header, rows)


if __name__ == "__main__":
    main()
