"""Takes and writes retried across store crashes apply exactly once.

Clients talk to an edge router; the store (a second process meshed with it)
is killed with SIGKILL and restarted while they work, so replies are lost and
requests are sent again. A smaller round runs here; `bench/exactly_once.py`
runs the full size (3 takers x 1,000 items x 5 rounds, 4 kills a round).
"""

from __future__ import annotations

import random
import signal
import threading
from collections import Counter

from rdflib import Literal, Namespace

from conftest import AC_NS, Server, wait_for
from space import Changeset, TripleSpace

AC = Namespace(AC_NS)
TAKERS, ITEMS, ROUNDS, KILLS = 3, 120, 2, 2


def _take_all(endpoint: str, space: str, taken: list[int], done: list[int]) -> None:
    with TripleSpace.open(endpoint, space=space, agent="taker") as ts:
        order = list(range(ITEMS))
        random.shuffle(order)
        for i in order:
            got = ts.take((AC[f"item{i}"], AC.state, None), timeout=60)
            taken.extend(int(str(s)[len(AC_NS) + 4 :]) for s in got.subjects())
            done.append(i)


def _kill_while(store: Server, done: list[int], total: int) -> None:
    for k in range(KILLS):
        wait_for(lambda k=k: len(done) >= total * (k + 1) // (KILLS + 1), 120, "takes to go on")
        store.stop(signal.SIGKILL)
        store.start(wait=False)


def test_takes_survive_store_kills_with_none_lost_and_none_taken_twice(tmp_path):
    edge = Server(tmp_path / "edge", "--no-store")
    edge.start(wait=False)
    store = Server(tmp_path / "data", "--connect", edge.endpoint)
    store.start()
    wait_for(edge.reachable, 20, "the store through the edge router")
    try:
        for round_ in range(ROUNDS):
            space = f"once{round_}"
            with TripleSpace.open(edge.endpoint, space=space) as ts:
                for first in range(0, ITEMS, 60):
                    ts.write(
                        [
                            (AC[f"item{i}"], AC.state, Literal("ready"))
                            for i in range(first, first + 60)
                        ]
                    )
            taken: list[int] = []
            done: list[int] = []
            takers = [
                threading.Thread(target=_take_all, args=(edge.endpoint, space, taken, done))
                for _ in range(TAKERS)
            ]
            for t in takers:
                t.start()
            _kill_while(store, done, TAKERS * ITEMS)
            for t in takers:
                t.join(180)
            counts = Counter(taken)
            assert sorted(counts) == list(range(ITEMS)), "an item was taken by nobody"
            assert max(counts.values()) == 1, "an item was taken twice"
            with TripleSpace.open(edge.endpoint, space=space) as ts:
                assert len(ts.query((None, AC.state, None), timeout=30)) == 0
    finally:
        store.stop()
        edge.stop()


def test_writes_retried_across_store_kills_are_applied_once(tmp_path):
    edge = Server(tmp_path / "edge", "--no-store")
    edge.start(wait=False)
    store = Server(tmp_path / "data", "--connect", edge.endpoint)
    store.start()
    wait_for(edge.reachable, 20, "the store through the edge router")
    acked: list[str] = []
    try:
        with TripleSpace.open(edge.endpoint, space="w") as ts:

            def write_all() -> None:
                for i in range(300):
                    acked.append(ts.write([(AC.counter, AC.n, Literal(i))], timeout=60))

            writer = threading.Thread(target=write_all)
            writer.start()
            _kill_while(store, acked, 300)
            writer.join(180)
            assert len(acked) == 300
            seq = ts.snapshot(timeout=30)[1]
            log, _ = ts._fetch_log(1, seq)  # (payloads, seq) since scoped subscriptions
            ids = Counter(Changeset.decode(p).id for p in log)
            assert set(ids) == set(acked), "every acknowledged write is in the log"
            assert max(ids.values()) == 1, "a write was applied twice"
            assert seq == 300
    finally:
        store.stop()
        edge.stop()
