"""A store's decided changeset as etcd keys and guards, and a re-listed state back as triples.

The store decides a changeset on its state at revision R (functional values
replaced, the later HLC stamp winning, a take's items); `entry_for` turns
that decision into the log entry: the keys the changeset writes and the
guards its decision rests on (docs/cluster.md, "The keyspace"). A functional
property's value lives in its (subject, property) key only, not in a triple
key as well: one key per reading, which is most of what robots write.

Terms are N-Triples texts, as the store's net changeset carries them; a
triple key's value is its N-Triples line, so a re-listed state is a document
Oxigraph's parser loads in bulk.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import msgpack

from space.store.cluster_keys import (
    functional_key,
    prefix_key,
    request_key,
    state_prefix,
    triple_key,
)
from space.store.etcd_log import Entry

Text = tuple[str, str, str]  # (s, p, o) as N-Triples terms


@dataclass
class Decision:
    """A changeset the store decided at `revision`: its net changes and what they relied on."""

    space: str
    payload: bytes  # the net changeset, as replicas apply and subscribers receive it
    revision: int
    stamp: str = ""  # the changeset's HLC timestamp
    functional: frozenset[str] = frozenset()  # predicates that are functional in this space
    added: list[Text] = field(default_factory=list)
    removed: list[Text] = field(default_factory=list)
    inferred_added: list[Text] = field(default_factory=list)
    inferred_removed: list[Text] = field(default_factory=list)
    replaced: list[tuple[str, str]] = field(default_factory=list)  # functional (s, p) written
    taken: list[Text] = field(default_factory=list)  # removed by a take
    prefixes: dict[str, str] = field(default_factory=dict)  # bindings new in this changeset
    request: str = ""  # the writer's request id: committed once, whichever replica decides


def logged_payload(payload: bytes, dropped: bytes, origin: str) -> bytes:
    """Return the payload etcd logs for a changeset: with the writer that decided it
    (`ORIGIN`), and what its writer was told was not applied, if anything (`DROPPED`).

    A replica answers its writers as it applies the entries whose payloads are its own
    flights' (`cluster_apply`). A retry decided on two replicas on the same state is the
    same changeset: only its origin keeps the replica whose entry etcd refused (the
    request id committed) from taking the other's for its own, and answering it as new.
    What was dropped is logged so that every replica's log tells a retry the same.
    """
    wire = msgpack.unpackb(payload)
    wire[ORIGIN] = origin
    if dropped:
        wire[DROPPED] = msgpack.unpackb(dropped)
    return msgpack.packb(wire)


# The keys of a logged payload that `ClusterSpace.install_at` takes out.
DROPPED = "dropped"
ORIGIN = "origin"


def line(t: Text) -> str:
    """Return a triple's N-Triples line."""
    return f"{t[0]} {t[1]} {t[2]} .\n"


def key_of(root: bytes, space: str, t: Text, functional: frozenset[str]) -> bytes:
    """Return the key that holds asserted triple `t` (its (s, p) key if `p` is functional)."""
    if t[1] in functional:
        return functional_key(root, space, t[0], t[1])
    return triple_key(root, space, "t", *t)


def entry_for(root: bytes, d: Decision) -> Entry:
    """Return the log entry that commits decision `d`, guarded by what it read."""
    entry = Entry(d.space, d.payload)
    for t in d.removed:
        entry.deletes.append(key_of(root, d.space, t, d.functional))
    for t in d.inferred_removed:
        entry.deletes.append(triple_key(root, d.space, "i", *t))
    for t in d.added:
        key = key_of(root, d.space, t, d.functional)
        value = msgpack.packb([line(t), d.stamp]) if t[1] in d.functional else line(t).encode()
        entry.puts[key] = value
    for t in d.inferred_added:
        entry.puts[triple_key(root, d.space, "i", *t)] = line(t).encode()
    if d.request:
        key = request_key(root, d.space, d.request)
        entry.guards[key] = 0  # absent: no replica committed this request in the last minute
        entry.leased.append(key)
    for name, iri in d.prefixes.items():
        entry.puts[prefix_key(root, d.space, name)] = iri.encode()
    entry.deletes = [k for k in entry.deletes if k not in entry.puts]
    for s, p in d.replaced:
        entry.guards[functional_key(root, d.space, s, p)] = d.revision
    for t in d.taken:
        key = key_of(root, d.space, t, d.functional)
        entry.guards[key] = d.revision
        entry.present.append(key)
    return entry


@dataclass
class SpaceImage:
    """One space as re-listed from etcd: N-Triples documents and functional stamps."""

    asserted: list[str] = field(default_factory=list)  # N-Triples lines
    inferred: list[str] = field(default_factory=list)
    stamps: list[tuple[str, str]] = field(default_factory=list)  # (N-Triples line, HLC stamp)
    prefixes: dict[str, str] = field(default_factory=dict)


def read_state(root: bytes, pairs: Iterable[tuple[bytes, bytes]]) -> dict[str, SpaceImage]:
    """Return every space's image from the `(key, value)` pairs a re-list read."""
    spaces: dict[str, SpaceImage] = {}
    state, fn, prefix = state_prefix(root), root + b"fn/", root + b"prefix/"
    for key, value in pairs:
        if key.startswith(prefix):
            space, name = key[len(prefix) :].decode().split("/", 1)
            spaces.setdefault(space, SpaceImage()).prefixes[name] = value.decode()
            continue
        if key.startswith(state):
            space, graph, _ = key[len(state) :].decode().split("/")
            image = spaces.setdefault(space, SpaceImage())
            (image.asserted if graph == "t" else image.inferred).append(value.decode())
        elif key.startswith(fn):
            space = key[len(fn) :].decode().split("/")[0]
            text, stamp = msgpack.unpackb(value)
            image = spaces.setdefault(space, SpaceImage())
            image.asserted.append(text)
            image.stamps.append((text, stamp))
    return spaces
