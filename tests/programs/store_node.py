"""The robots of one host in the replica fault test: writers and takers on the local replica.

store_node.py HOST OUTDIR ENDPOINT

Writers add unique triples, one changeset each; takers race the other hosts'
takers for items 0..ITEMS-1 (seeded once by host `a`), in the same order, so
every item is contended. Every outcome is a line of OUTDIR/HOST-ops.jsonl:
`{"op", "id", "item", "ok", "error", "t"}`, `ok` only for an acknowledgement.
SIGUSR1 stops them.
"""

from __future__ import annotations

import json
import signal
import sys
import threading
import time
from pathlib import Path

from rdflib import Literal, URIRef

from space import SpaceError, TripleSpace

ITEMS = 300
WRITERS = 3
TAKERS = 2
PAUSE = 0.02
A, ITEM, SEEDED = URIRef("urn:a"), URIRef("urn:Item"), URIRef("urn:seeded")
P = URIRef("urn:p")


def item(i: int) -> URIRef:
    return URIRef(f"urn:item{i}")


class Robots:
    def __init__(self, host: str, out: Path, endpoint: str) -> None:
        self.host = host
        self.ts = TripleSpace.open(endpoint, space="f", agent=host)
        self.lines = open(out / f"{host}-ops.jsonl", "a", buffering=1)
        self.lock = threading.Lock()
        self.quiet = threading.Event()

    def record(self, op: str, ident: str, ok: bool, error: str = "", it: int = -1) -> None:
        line = {"op": op, "id": ident, "item": it, "ok": ok, "error": error, "t": time.time()}
        with self.lock:
            self.lines.write(json.dumps(line) + "\n")

    def seed(self) -> None:
        cs = self.ts.changeset([(item(i), A, ITEM) for i in range(ITEMS)] + [(SEEDED, A, ITEM)])
        while True:  # the same changeset until acknowledged: applied once
            try:
                if len(self.ts.query((SEEDED, None, None), timeout=2)):
                    return
                self.ts.send(cs, timeout=2)
                self.record("seed", cs.id, True)
                return
            except SpaceError as error:
                self.record("seed", cs.id, False, _why(error))
                time.sleep(0.2)

    def writer(self, n: int) -> None:
        i = 0
        while not self.quiet.is_set():
            cs = self.ts.changeset([(URIRef(f"urn:w/{self.host}/{n}/{i}"), P, Literal(i))])
            try:
                self.ts.send(cs, timeout=2)
                self.record("write", cs.id, True)
            except SpaceError as error:
                self.record("write", cs.id, False, _why(error))
            i += 1
            time.sleep(PAUSE)

    def taker(self, n: int) -> None:
        i = 0
        while not self.quiet.is_set() and i < ITEMS:
            try:
                got = self.ts.take((item(i), A, ITEM), timeout=2)
            except SpaceError as error:
                self.record("take", "", False, _why(error), i)
                time.sleep(PAUSE)
                continue
            if len(got):
                self.record("take", "", True, it=i)
            i += 1  # taken by us or by another: the next one
            time.sleep(PAUSE)

    def run(self) -> None:
        signal.signal(signal.SIGUSR1, lambda *_: self.quiet.set())
        if self.host == "a":
            self.seed()
        threads = [threading.Thread(target=self.writer, args=(n,)) for n in range(WRITERS)]
        threads += [threading.Thread(target=self.taker, args=(n,)) for n in range(TAKERS)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        self.ts.close()
        self.lines.close()


def _why(error: SpaceError) -> str:
    return f"{type(error).__name__}: {error}"


if __name__ == "__main__":
    Robots(sys.argv[1], Path(sys.argv[2]), sys.argv[3]).run()
