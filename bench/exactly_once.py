"""Takes under store crashes, full size: 3 takers x 1,000 items x 5 rounds, 4 kills a round.

Run: python bench/exactly_once.py [--takers 3 --items 1000 --rounds 5 --kills 4] [--old DIR]
The takers talk to an edge router (`tspace serve --no-store`); the store is a second process
meshed with it, killed with SIGKILL and restarted while they take. Each taker tries every item
once, in its own random order; an item must end up taken by exactly one of them. Prints, per
round, the items taken by nobody and those taken twice. `tests/test_store_exactly_once.py`
runs a smaller round in CI. With --old the store runs from that source tree.
"""

from __future__ import annotations

import argparse
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

from _harness import code_env, free_port
from _output import bench_parser, parse, print_table
from rdflib import Literal, Namespace

from space import SpaceError, TripleSpace

EX = Namespace("urn:bench:")


class Proc:
    """A `tspace serve` child, restartable on the same port and data directory."""

    def __init__(self, data: Path, code: Path | None, *extra: str) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        self.cmd = [sys.executable, "-m", "space.cli", "serve", "--listen", self.endpoint]
        self.cmd += ["--data", str(data), *extra]
        self.code = code
        self.log = data.parent / f"serve-{data.name}.log"
        self.proc: subprocess.Popen | None = None

    def start(self) -> None:
        """Start the process (not waiting for it)."""
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                self.cmd, stderr=log, env=code_env(self.code), start_new_session=True
            )

    def kill(self, sig: int = signal.SIGKILL) -> None:
        """Stop the process with `sig` and wait for it."""
        assert self.proc is not None
        self.proc.send_signal(sig)
        self.proc.wait(timeout=30)


def wait_for_store(endpoint: str, deadline: float = 60.0) -> None:
    """Wait until a store answers through the router at `endpoint`."""
    end = time.monotonic() + deadline
    while True:
        try:
            with TripleSpace.open(endpoint, space="ping") as ts:
                ts.snapshot(timeout=2)
            return
        except SpaceError:
            if time.monotonic() > end:
                raise
            time.sleep(0.1)


def taker(endpoint: str, space: str, items: int, taken: list[int], done: list[int]) -> None:
    with TripleSpace.open(endpoint, space=space, agent="taker") as ts:
        order = list(range(items))
        random.shuffle(order)
        for i in order:
            try:
                got = ts.take((EX[f"item{i}"], EX.state, None), timeout=120)
            except SpaceError as exc:
                print(f"  take of item{i} failed: {exc}", file=sys.stderr)
                continue
            taken.extend(int(str(s)[len(str(EX)) + 4 :]) for s in got.subjects())
            done.append(i)


def one_round(edge: Proc, store: Proc, space: str, args: argparse.Namespace) -> tuple[int, int]:
    with TripleSpace.open(edge.endpoint, space=space) as ts:
        for first in range(0, args.items, 500):
            last = min(args.items, first + 500)
            ts.write(
                [(EX[f"item{i}"], EX.state, Literal("ready")) for i in range(first, last)],
                timeout=120,
            )
    taken: list[int] = []
    done: list[int] = []
    threads = [
        threading.Thread(target=taker, args=(edge.endpoint, space, args.items, taken, done))
        for _ in range(args.takers)
    ]
    for t in threads:
        t.start()
    total = args.takers * args.items
    for k in range(args.kills):
        while len(done) < total * (k + 1) // (args.kills + 1):
            time.sleep(0.01)
        store.kill()
        store.start()
    for t in threads:
        t.join()
    counts = Counter(taken)
    lost = args.items - len(counts)
    twice = sum(1 for c in counts.values() if c > 1)
    return lost, twice


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--takers", type=int, default=3)
    parser.add_argument("--items", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--kills", type=int, default=4)
    parser.add_argument("--old", type=Path, help="run the store from this source tree")
    args = parse(parser)
    with tempfile.TemporaryDirectory() as tmp:
        edge = Proc(Path(tmp) / "edge", None, "--no-store")
        edge.start()
        store = Proc(Path(tmp) / "data", args.old, "--connect", edge.endpoint)
        store.start()
        try:
            wait_for_store(edge.endpoint)
            started = time.monotonic()
            rows: list[list[object]] = []
            for r in range(args.rounds):
                lost, twice = one_round(edge, store, f"once{r}", args)
                rows.append([f"round {r + 1}", lost, twice])
                print(f"round {r + 1}: {lost} lost, {twice} taken twice", flush=True)
            rows.append(["total", sum(r[1] for r in rows), sum(r[2] for r in rows)])  # type: ignore[misc]
            print_table(
                f"{args.takers} takers x {args.items} items x {args.rounds} rounds, "
                f"{args.kills} kills a round ({time.monotonic() - started:.0f} s)",
                ["round", "lost (items)", "taken twice (items)"],
                rows,
            )
        except BaseException:
            print(store.log.read_text(errors="replace")[-3000:], file=sys.stderr)
            raise
        finally:
            store.kill(signal.SIGTERM)
            edge.kill(signal.SIGTERM)


if __name__ == "__main__":
    main()
