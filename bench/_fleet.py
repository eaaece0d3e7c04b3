"""Plumbing of bench/fleet.py: what the store publishes, many robots' sensors, the reasoner."""

from __future__ import annotations

import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import msgpack
import zenoh
from _harness import reap
from rdflib import Graph, Literal, Namespace, URIRef

from agents.sim.fleet import fleet_description
from space import TripleSpace

REPO = Path(__file__).resolve().parents[1]
AC = Namespace("https://w3id.org/tspace/selfconfig#")
RULES = REPO / "rules" / "fleet.rules"
ONTOLOGY = [REPO / "ontology" / "selfconfig.ttl", REPO / "ontology" / "robots" / "common.ttl"]
LEVELS = (Literal("normal"), Literal("very low"))
MARKER_EVERY = 20  # one battery change in 20 sensor changes of a robot


class Observer:
    """What the store publishes on a space, with arrival times: a plain Zenoh subscriber.

    The callback only enqueues; `drain()` decodes in the caller's thread.
    """

    def __init__(self, session: zenoh.Session, space: str) -> None:
        self.arrived: dict[str, float] = {}  # changeset id -> arrival
        self.answered: dict[str, float] = {}  # cause -> arrival of the reasoner's answer
        self.at_seq: dict[int, float] = {}  # sequence number -> arrival
        self._inbox: queue.SimpleQueue[tuple[float, bytes]] = queue.SimpleQueue()
        self._sub = session.declare_subscriber(
            f"tspace/{space}/@/changes",
            lambda s: self._inbox.put((time.monotonic(), s.payload.to_bytes())),
        )

    def close(self) -> None:
        """Stop recording."""
        self._sub.undeclare()

    @property
    def last_seq(self) -> int:
        """Return the highest sequence number seen."""
        return max(self.at_seq, default=0)

    def drain(self, timeout: float = 0.0) -> None:
        """Decode what arrived, waiting up to `timeout` for a first arrival."""
        try:
            item = self._inbox.get(timeout=timeout) if timeout else self._inbox.get_nowait()
            while True:
                arrival, payload = item
                cs = msgpack.unpackb(payload)
                self.arrived[cs["id"]] = arrival
                self.at_seq[cs["seq"]] = arrival
                if cs.get("agent") == "reasoner":
                    self.answered.setdefault(cs.get("cause") or "", arrival)
                item = self._inbox.get_nowait()
        except queue.Empty:
            return

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Decode arrivals until `condition()`; return False if `timeout` passed first."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                return False
            self.drain(timeout=0.05)
        return True

    def wait_answer(self, timeout: float = 60) -> None:
        """Wait for the reasoner's first answer (to the state it loaded).

        Raises:
            TimeoutError: no answer within `timeout`.
        """
        if not self.wait(lambda: bool(self.answered), timeout):
            raise TimeoutError(f"the reasoner did not answer within {timeout} s")


class Fleet:
    """Every robot's sensors, played by one process: one changeset per change, as hw_monitor.

    `sent` and `markers` (battery changes) map each changeset id to its send time.
    """

    def __init__(self, ts: TripleSpace, description: Graph, count: int) -> None:
        self.ts = ts
        self.batteries = [AC[f"robot{k}_battery"] for k in range(1, count + 1)]
        self.level = {b: description.value(b, AC.battery_level) for b in self.batteries}
        self.charge = {b: description.value(b, AC.charge_percent) for b in self.batteries}
        self.sent: dict[str, float] = {}
        self.markers: dict[str, float] = {}

    def battery(self, k: int) -> str:
        """Turn robot k's battery level over ("normal" <-> "very low"); return the id."""
        b = self.batteries[k]
        old = self.level[b]
        self.level[b] = new = LEVELS[old == LEVELS[0]]
        cid = self._send(b, AC.battery_level, old, new)
        self.markers[cid] = self.sent[cid]
        return cid

    def sensor(self, k: int) -> str:
        """Change robot k's charge reading (no rule reads it; the reasoner applies it)."""
        b = self.batteries[k]
        old = self.charge[b]
        self.charge[b] = new = Literal(80 if old != Literal(80) else 75)
        return self._send(b, AC.charge_percent, old, new)

    def _send(self, s: URIRef, p: URIRef, old: object, new: Literal) -> str:
        cs = self.ts.changeset([(s, p, new)], [(s, p, old)] if old is not None else [])
        self.sent[cs.id] = time.monotonic()
        return self.ts.send_nowait(cs)

    def play(self, seconds: float, rate: float, stop: threading.Event | None = None) -> float:
        """Write `rate` changesets per second, robots in turn, for `seconds` (or until `stop`).

        Each robot's every `MARKER_EVERY`th change is a battery change. Returns
        the rate achieved.
        """
        start = time.monotonic()
        i = 0
        while not (stop is not None and stop.is_set()):
            due = start + i / rate
            if due > start + seconds:
                break
            ahead = due - time.monotonic()
            if ahead > 0:
                time.sleep(ahead)  # the sensors' pace
            k, n = i % len(self.batteries), i // len(self.batteries)
            if n % MARKER_EVERY == k % MARKER_EVERY:
                self.battery(k)
            else:
                self.sensor(k)
            i += 1
        return i / (time.monotonic() - start)


def describe(ts: TripleSpace, count: int) -> Graph:
    """Write the ontology and a site with `count` robots into the space; return the site."""
    ontology = Graph()
    for path in ONTOLOGY:
        ontology.parse(path)
    ts.write(ontology, timeout=30)
    site = fleet_description(count)
    ts.write(site, timeout=30)
    return site


def reasoner_argv(connect: str, space: str) -> list[str]:
    """Return the argv of the fleet's reasoner."""
    return [
        sys.executable,
        "-m",
        "agents.reasoner",
        "--connect",
        connect,
        "--space",
        space,
        "--rules",
        str(RULES),
    ]


def stop_process(proc: subprocess.Popen) -> None:
    """Stop a child process (SIGTERM, then SIGKILL after 10 s) and reap it."""
    proc.terminate()
    reap([proc])


def rss_mb(pid: int) -> float:
    """Return a process's resident memory in MB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise ValueError(f"no VmRSS for pid {pid}")
