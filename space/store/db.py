"""The store's durable memory: one on-disk Oxigraph database holding every space and its log.

The layout of spaces in it (graphs, log entries) is `db_layout`.

`commit` writes a batch of changesets, each with its log entry and sequence
number, as ONE N-Quads load or SPARQL UPDATE (`render.py`): Oxigraph applies
either atomically (one RocksDB write batch), so after `kill -9` a changeset is wholly there with its
log entry and seq, or not at all. A commit is in RocksDB's write-ahead log,
not fsynced: it survives the death of the process, not of the machine;
`durable=True` (`tspace serve --fsync`) also calls `Store.flush()` before a
commit returns.
"""

from __future__ import annotations

import base64
import gc
import logging
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pyoxigraph as ox

from space.errors import SpaceError
from space.store.background import lower_background_threads
from space.store.db_layout import (
    DROPPED,
    FUNCTIONAL,
    INT,
    META,
    PAYLOAD,
    PREFIX,
    REQUESTS,
    ROOT,
    SEQ,
    STORE,
    Entry,
    entry_node,
    graph,
    log_graph,
    request_node,
    space_node,
)
from space.store.flusher import Flusher
from space.store.oxterms import OxTerm, OxTriple
from space.store.request_ids import RequestIds
from space.store.values import Values

log = logging.getLogger("tspace.store")

COMPACT_EVERY = 1000  # commits of a space between compactions of its log and seqs


class CommitFailed(SpaceError):
    """The database could not commit (disk full, read-only directory, I/O error)."""


class NotFlushed(CommitFailed):
    """With `durable` (`--fsync`): the batch is in the database, but its flush to disk failed."""


class DataDirInUse(SpaceError):
    """Another store process has the data directory open."""


@dataclass
class Loaded:
    """What a space's state is rebuilt from when the store opens it."""

    seq: int = 0
    prefixes: dict[str, str] = field(default_factory=dict)
    stamps: dict[tuple[OxTerm, OxTerm], str] = field(default_factory=dict)
    functional: set[OxTerm] = field(default_factory=set)


class StoreDB:
    """Open (creating if needed) the Oxigraph database under `data_dir`.

    Writes (`commit`) come from one thread; reads may come from any
    thread, each call reading one consistent snapshot.

    A database that cannot be opened for writing (a read-only directory) is
    opened read-only, with `open_error` saying why: the store then serves reads
    and refuses writes until `probe` succeeds.

    Raises:
        DataDirInUse: another process holds the directory.
        OldDataDir: (from `migrate`) an old SQLite directory that was not migrated.
        NewerDataDir: (from `migrate`) a newer tspace wrote it.
        OSError: the directory cannot be created or read.
    """

    def __init__(self, data_dir: Path, *, durable: bool = False, log_keep: int = 100_000) -> None:
        from space.store.migrate import format_marks, open_store

        data_dir.mkdir(parents=True, exist_ok=True)
        self.data_dir = data_dir
        self.path = data_dir / "oxigraph"
        self.durable = durable
        self.log_keep = log_keep
        self.open_error = ""  # why the database could only be opened read-only
        try:
            self.store: ox.Store = open_store(data_dir, self.path)
        except OSError as exc:
            if not self.path.exists():
                raise
            self.store = ox.Store.read_only(str(self.path))
            format_marks(self.store, data_dir)  # not migrated, but a newer one is refused
            self.open_error = f"the database opened read-only: {exc}"
        self._commits: dict[str, int] = {}  # per space, since its last compaction
        self._cut: dict[str, int] = {}  # per space, the log's last cut (entries <= it are gone)
        # A cluster replica's revision quad(s) as its last commit left them (None: not read).
        self.revision_objects: list[str] | None = None
        self.values = Values()  # functional pairs' objects, triples of the latest commits
        self.requests = RequestIds(self._logged_requests)  # which request ids the logs hold
        self._flusher = Flusher(lambda: self.store if hasattr(self, "store") else None)
        lower_background_threads()

    def close(self) -> None:
        """Flush and let go of the database (the last reference closes it)."""
        self._flusher.close()
        self.requests.clear()
        try:
            self.store.flush()
        except OSError as exc:
            log.error("could not flush the database on close: %s", exc)
        del self.store

    def spaces(self) -> list[str]:
        """Return the names of the spaces that were ever written."""
        prefix = f"{ROOT}space:"
        names = (
            q.subject.value[len(prefix) :]
            for q in self.store.quads_for_pattern(None, SEQ, None, META)
        )
        return list(dict.fromkeys(names))

    def load(self, space: str) -> Loaded:
        """Return a space's seq, prefixes, functional stamps and functional properties."""
        node = space_node(space)
        loaded = Loaded()
        for q in self.store.quads_for_pattern(node, SEQ, None, META):
            loaded.seq = max(loaded.seq, int(q.object.value))  # older ones wait for compaction
        for q in self.store.quads_for_pattern(node, PREFIX, None, META):
            name, _, ns = q.object.value.partition(" ")
            loaded.prefixes[name] = ns
        for q in self.store.quads_for_pattern(None, None, None, graph(space, "stamps")):
            loaded.stamps[(q.subject, q.predicate)] = q.object.value
        loaded.functional = self.functional(space)
        return loaded

    def functional(self, space: str) -> set[OxTerm]:
        """Return the properties declared `owl:FunctionalProperty` in either graph of a space."""
        p, o = (ox.NamedNode(x) for x in FUNCTIONAL)
        return {
            q.subject
            for which in ("t", "i")
            for q in self.store.quads_for_pattern(None, p, o, graph(space, which))
        }

    def has(self, space: str, which: str, t: OxTriple) -> bool:
        """Return whether a graph (`t` or `i`) of a space holds a triple."""
        settled = self.values.settled.get(space)
        if settled is not None:
            held = settled.get((which, t))
            if held is not None:
                return held
        return ox.Quad(t[0], t[1], t[2], graph(space, which)) in self.store

    def has_subject(self, space: str, s: OxTerm) -> bool:
        """Return whether the asserted graph of a space holds any triple about `s`."""
        return (
            next(self.store.quads_for_pattern(s, None, None, graph(space, "t")), None) is not None
        )

    def objects(self, space: str, s: OxTerm, p: OxTerm) -> list[OxTerm]:
        """Return the asserted objects of `(s p ?)` in a space (remembered: `values.py`)."""
        held = self.values.get(space, s, p)
        if held is None:
            g = graph(space, "t")
            held = tuple(q.object for q in self.store.quads_for_pattern(s, p, None, g))
            self.values.put(space, s, p, held)
        return list(held)

    def match(
        self, space: str, which: str, pattern: tuple[OxTerm | None, ...]
    ) -> Iterator[OxTriple]:
        """Yield the triples of a graph (`t` or `i`) matching a pattern (None: any)."""
        for q in self.store.quads_for_pattern(*pattern, graph(space, which)):
            yield q.subject, q.predicate, q.object

    def commit(
        self,
        entries: list[Entry],
        extra: tuple[list[ox.Quad], list[ox.Quad]] = ([], []),
        *,
        revision: int | None = None,
    ) -> None:
        """Write a batch of changesets with their log entries and seqs, atomically.

        `extra`: quads to delete and to insert in the same update (leases).
        `revision`: a cluster replica's applied etcd revision, written in the
        same update (`space.store.cluster_db`), so a restart resumes there.

        Raises:
            NotFlushed: the batch is in the database (and remembered so), only its flush
                to disk failed (`durable`).
            CommitFailed: nothing of the batch was written.
        """
        from space.store import render

        if not entries and not any(extra) and revision is None:
            return
        try:
            if revision is None and not extra[0] and render.plain(entries):
                self.store.load(render.nquads(entries, extra[1]), format=ox.RdfFormat.N_QUADS)
            else:
                ops = [render.update(entries, extra)] if entries or any(extra) else []
                if revision is not None:
                    from space.store.cluster_db import revision_ops

                    ops += revision_ops(self, revision)
                self.store.update(" ;\n".join(ops))
        except (OSError, RuntimeError) as exc:
            raise CommitFailed(f"the database could not commit: {exc}") from exc
        self.requests.committed(entries)  # first: a log entry it missed would be applied twice
        self.values.committed(entries)
        if revision is not None:
            from space.store.cluster_db import revision_written

            revision_written(self, revision)
        if self.durable:
            try:
                self.store.flush()
            except (OSError, RuntimeError) as exc:
                raise NotFlushed(f"applied, but not flushed to disk: {exc}") from exc
        else:
            self._flusher.wrote(sum(e.size() for e in entries) + len(extra[1]))
        for e in entries:
            self._commits[e.space] = self._commits.get(e.space, 0) + 1
        for space, seq in {e.space: e.seq for e in entries}.items():
            if self._commits[space] >= COMPACT_EVERY:
                self._commits[space] = 0
                self._compact(space, seq)

    def probe(self) -> None:
        """Reopen the database and commit one small change: does it commit again?

        After a failed write RocksDB refuses every later one until reopened, so
        the store is reopened here. Call it only while no read is running (the
        old store must be let go of before the directory can be opened again).
        If it cannot be opened for writing, it is opened read-only meanwhile, so
        reads go on serving what is on disk.

        Raises:
            CommitFailed: it does not commit yet.
        """
        with self._flusher.paused():
            self._reopen()

    def _reopen(self) -> None:
        from space.store.migrate import open_store

        self.store = None  # type: ignore[assignment]
        self.revision_objects = None  # read again from what the reopened database holds
        self.values.clear()
        self.requests.clear()
        gc.collect()
        p, m, st = f"{ROOT}probe", META.value, STORE.value
        try:
            self.store = open_store(self.data_dir, self.path)
            self.store.update(
                f"DELETE WHERE {{ GRAPH <{m}> {{ <{st}> <{p}> ?x }} }} ;\n"
                f'INSERT DATA {{ GRAPH <{m}> {{ <{st}> <{p}> "{time.time()}" }} }}'
            )
            self.store.flush()
        except (OSError, RuntimeError, SpaceError) as exc:
            if self.store is None:
                self.store = ox.Store.read_only(str(self.path))
            raise CommitFailed(f"the database could not commit: {exc}") from exc

    def _compact(self, space: str, seq: int) -> None:
        """Forget a space's older sequence numbers, and log entries older than the `log_keep`
        latest (their request ids with them).

        An entry's seq is in its IRI only (`db_layout`): the entries since the last cut
        are named by their IRIs; the first cut of a process (or after a space's seq went
        back or leapt) reads the whole log to find the old ones, which costs a replica's
        worker ~0.3 s at 100,000 entries, where the entries named cost ~0.02 s.
        """
        g, m, node = log_graph(space).value, META.value, space_node(space).value
        ops = [
            f"DELETE {{ GRAPH <{m}> {{ <{node}> <{SEQ.value}> ?n }} }} WHERE {{ GRAPH <{m}> "
            f"{{ <{node}> <{SEQ.value}> ?n FILTER(?n < {seq}) }} }}"
        ]
        cut, last = seq - self.log_keep, self._cut.get(space, -1)
        if 0 <= last < cut <= last + 2 * COMPACT_EVERY:
            named = " ".join(f"<{g}:{n}>" for n in range(last + 1, cut + 1))
            ops.append(
                f"DELETE {{ GRAPH <{g}> {{ ?e ?p ?o }} }} WHERE {{ VALUES ?e {{ {named} }} "
                f"GRAPH <{g}> {{ ?e ?p ?o }} }}"
            )
        elif cut > 0:
            number = f'<{INT.value}>(STRAFTER(STR(?e), "{g}:"))'
            ops.append(
                f"DELETE {{ GRAPH <{g}> {{ ?e ?p ?o }} }} WHERE {{ GRAPH <{g}> "
                f"{{ ?e ?p ?o }} FILTER({number} <= {cut}) }}"
            )
        try:
            self.store.update(" ;\n".join(ops))
        except OSError as exc:  # the log is only longer than it should be; say so
            log.error("could not compact the log of %s: %s", space, exc)
            return
        if cut > 0:
            self._cut[space] = cut
            self.requests.cut(space, cut)

    def log(self, space: str, first: int, last: int) -> list[tuple[int, bytes]]:
        """Return the logged changesets `first..last` (inclusive) still kept."""
        rows = []
        g = log_graph(space)
        for seq in range(max(first, 1), last + 1):
            for q in self.store.quads_for_pattern(entry_node(space, seq), None, None, g):
                if q.predicate == PAYLOAD or q.predicate.value.startswith(REQUESTS):
                    rows.append((seq, base64.b64decode(q.object.value)))
        return rows

    def outcome(self, space: str, request: str) -> tuple[int, bytes, bytes] | None:
        """Return `(seq, payload, dropped)` of the changeset that answered a request id, if logged.

        `dropped` is the msgpack list the writer was told was not applied (b"" if none).
        """
        if not self.requests.may_hold(space, request):
            return None
        g = log_graph(space)
        for q in self.store.quads_for_pattern(None, request_node(request), None, g):
            dropped = b""
            for d in self.store.quads_for_pattern(q.subject, DROPPED, None, g):
                dropped = base64.b64decode(d.object.value)
            seq = int(q.subject.value.rsplit(":", 1)[1])
            return seq, base64.b64decode(q.object.value), dropped
        return None

    def _logged_requests(self, space: str) -> Iterator[tuple[int, str]]:
        """Yield `(seq, request-id IRI)` of each entry of a space's log that answered an id."""
        g = log_graph(space)
        rows = self.store.query(
            f"SELECT ?e ?p WHERE {{ GRAPH <{g.value}> {{ ?e ?p ?o }} "
            f'FILTER(STRSTARTS(STR(?p), "{REQUESTS}")) }}'
        )
        for row in rows:
            yield int(row[0].value.rsplit(":", 1)[1]), row[1].value

    def prefixes(self, space: str) -> dict[str, str]:
        """Return the prefix bindings registered in a space."""
        return self.load(space).prefixes
