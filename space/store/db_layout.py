"""How the store lays spaces out in its one Oxigraph database: graph and log IRIs.

Layout (every IRI under `urn:tspace:`, space names being IRI-safe):

- `graph:<space>:asserted`, `graph:<space>:inferred`: the space's triples; SPARQL
  reads their union as its default graph.
- `graph:<space>:stamps`: for each functional `(s p)` its writer's HLC timestamp,
  as the triple `s p "<timestamp>"`, so the later-timestamp rule survives restarts.
- `meta`: `space:<space> seq N` (the space's sequence number: the largest N, older
  ones are dropped at compaction) and its prefixes.
- `log:<space>`: per changeset ONE quad `log:<space>:<seq> req:<request id> "<payload>"`
  (the published payload, base64 msgpack; the predicate is `payload` when it answered
  no request id), and, when its writer was told something was not applied, a
  `dropped` quad. One quad, not one per field: every replica of a cluster commits
  every changeset's log entry, and each quad is six index entries in RocksDB.

Apart from `StoreDB` because the database, the N-Quads and SPARQL it is written
with (`render`), the cluster's additions (`cluster_db`) and the migration from
SQLite (`migrate`) all name the same graphs; none of them needs the database
object to do so.
"""

from __future__ import annotations

import base64
import re
from dataclasses import dataclass, field
from functools import lru_cache
from urllib.parse import quote

import pyoxigraph as ox

from space.store.oxterms import OxTriple

NQUADS = ox.RdfFormat.N_QUADS
FORMAT = "3"  # 1 was SQLite (space.sqlite3); 2 logged a changeset in 3-4 quads (`migrate`)
ROOT = "urn:tspace:"
META = ox.NamedNode(ROOT + "meta")
SEQ = ox.NamedNode(ROOT + "seq")
PREFIX = ox.NamedNode(ROOT + "prefix")
FORMAT_P = ox.NamedNode(ROOT + "format")
STORE = ox.NamedNode(ROOT + "store")
PAYLOAD = ox.NamedNode(ROOT + "payload")
DROPPED = ox.NamedNode(ROOT + "dropped")
REQUESTS = ROOT + "req:"  # + a request id, percent-encoded: the predicate of its log entry
INT = ox.NamedNode("http://www.w3.org/2001/XMLSchema#integer")
_PAYLOAD, _DROPPED = (f"<{x.value}>" for x in (PAYLOAD, DROPPED))
FUNCTIONAL = (
    "http://www.w3.org/1999/02/22-rdf-syntax-ns#type",
    "http://www.w3.org/2002/07/owl#FunctionalProperty",
)


@lru_cache(maxsize=4096)
def graph(space: str, which: str) -> ox.NamedNode:
    """Return the IRI of a space's graph: `t` (asserted), `i` (inferred) or `stamps`."""
    name = {"t": "asserted", "i": "inferred"}.get(which, which)
    return ox.NamedNode(f"{ROOT}graph:{space}:{name}")


@lru_cache(maxsize=4096)
def space_node(space: str) -> ox.NamedNode:
    return ox.NamedNode(f"{ROOT}space:{space}")


@lru_cache(maxsize=4096)
def log_graph(space: str) -> ox.NamedNode:
    return ox.NamedNode(f"{ROOT}log:{space}")


def entry_node(space: str, seq: int) -> ox.NamedNode:
    return ox.NamedNode(f"{ROOT}log:{space}:{seq}")


def request_node(request: str) -> ox.NamedNode:
    """Return the predicate of the log entry that answered request id `request`."""
    return ox.NamedNode(request_iri(request))


_UNRESERVED = re.compile(r"[A-Za-z0-9_.~-]+").fullmatch  # what percent-encoding leaves as is


def request_iri(request: str) -> str:
    """Return the IRI a request id's log entry is found by (its predicate)."""
    # Request ids are mostly hex: quote() of one is itself, and costs more than this check.
    return REQUESTS + (request if _UNRESERVED(request) else quote(request, safe=""))


@dataclass
class Entry:
    """One net changeset to commit: its triples, stamps, prefixes and log entry."""

    space: str
    seq: int
    request: str
    payload: bytes
    dropped: bytes = b""  # msgpack of what the writer was told was not applied (if anything)
    removed: list[OxTriple] = field(default_factory=list)
    added: list[OxTriple] = field(default_factory=list)
    plain: list[list[str]] = field(default_factory=list)  # asserted additions, N-Triples texts
    inferred_removed: list[OxTriple] = field(default_factory=list)
    inferred_added: list[OxTriple] = field(default_factory=list)
    prefixes: dict[str, str] = field(default_factory=dict)
    stamps_removed: list[OxTriple] = field(default_factory=list)
    stamps_added: list[OxTriple] = field(default_factory=list)

    def size(self) -> int:
        """Return the triples it adds or removes (plain ones included)."""
        return (
            len(self.plain)
            + len(self.added)
            + len(self.removed)
            + len(self.inferred_added)
            + len(self.inferred_removed)
        )


def log_rows(
    space: str, seq: int, request: str, payload: bytes, dropped: bytes = b""
) -> list[tuple[str, str, str]]:
    """Return the N-Triples `(s, p, o)` of one log entry, in `log_graph(space)`: its seq
    and request id with its payload, and what was dropped (if anything).

    Texts, not pyoxigraph terms: the store writes them into its commit's text as
    they are (`render`), a few microseconds less a changeset than terms printed.
    """
    entry = f"<{ROOT}log:{space}:{seq}>"
    answered = f"<{request_iri(request)}>" if request else _PAYLOAD
    rows = [(entry, answered, f'"{base64.b64encode(payload).decode("ascii")}"')]
    if dropped:
        rows.append((entry, _DROPPED, f'"{base64.b64encode(dropped).decode("ascii")}"'))
    return rows


def log_quads(
    space: str, seq: int, request: str, payload: bytes, dropped: bytes = b""
) -> list[ox.Quad]:
    """Return the quads of one log entry (`log_rows` read by Oxigraph's parser, which takes a
    payload of any length)."""
    g = log_graph(space).value
    rows = log_rows(space, seq, request, payload, dropped)
    return list(ox.parse("".join(f"{s} {p} {o} <{g}> .\n" for s, p, o in rows), format=NQUADS))
