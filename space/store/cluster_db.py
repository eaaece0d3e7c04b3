"""What a cluster replica keeps in its Oxigraph store beyond an embedded store's data.

A replica applies etcd's log into its own database; the etcd revision it
applied is written in the same update as the changesets of that revision
(`StoreDB.commit(..., revision=)`), so after a crash or a cut it resumes from
exactly there: nothing applied twice, nothing skipped. A re-list (etcd
compacted the replica's place in the log away) replaces every space whole, all
spaces and the new revision in one update.
"""

from __future__ import annotations

import pyoxigraph as ox

from space.store.cluster_entries import SpaceImage
from space.store.db import StoreDB
from space.store.db_layout import INT, META, SEQ, STORE, Entry, graph, log_graph, space_node
from space.store.render import update

REVISION = ox.NamedNode("urn:tspace:revision")


def revision_ops(db: StoreDB, revision: int) -> list[str]:
    """Return the SPARQL operations that record the applied etcd revision.

    The revision held is removed by its exact quad (DELETE DATA), as the last
    commit left it (`db.revision_objects`, noted by `revision_written`):
    rewritten at every commit, its key range fills with RocksDB tombstones, and
    a lookup there (or a DELETE WHERE) costs ~1 ms a commit, which a replica
    pays for every batch it applies.
    """
    m, st, r = META.value, STORE.value, REVISION.value
    held = db.revision_objects
    if held is None:
        held = [str(q.object) for q in _revisions(db)]
    ops = [f"DELETE DATA {{ GRAPH <{m}> {{ <{st}> <{r}> {o} }} }}" for o in held]
    ops.append(f"INSERT DATA {{ GRAPH <{m}> {{ <{st}> <{r}> {_object(revision)} }} }}")
    return ops


def revision_written(db: StoreDB, revision: int) -> None:
    """Note that a commit of `revision_ops(db, revision)` succeeded (the quad the next removes)."""
    db.revision_objects = [_object(revision)]


def _object(revision: int) -> str:
    return f'"{revision}"^^<{INT.value}>'


def _revisions(db: StoreDB) -> list[ox.Quad]:
    return list(db.store.quads_for_pattern(STORE, REVISION, None, META))


def applied_revision(db: StoreDB) -> int:
    """Return the etcd revision this replica applied last (0: none, a new replica)."""
    return max((int(q.object.value) for q in _revisions(db)), default=0)


def space_seqs(db: StoreDB) -> dict[str, int]:
    """Return every space's sequence number as the database has it."""
    prefix = "urn:tspace:space:"
    seqs: dict[str, int] = {}
    for q in db.store.quads_for_pattern(None, SEQ, None, META):
        name = q.subject.value[len(prefix) :]
        seqs[name] = max(seqs.get(name, 0), int(q.object.value))  # older ones await compaction
    return seqs


def replace_all(
    db: StoreDB, images: dict[str, SpaceImage], seqs: dict[str, int], revision: int
) -> None:
    """Make the database exactly the re-listed state at `revision`, in one update.

    Spaces the database holds that the listing lacks are emptied. A re-listed
    space keeps no log (its history is in the other replicas' stores): a late
    subscriber asking for older changesets gets none and reads the state.

    Raises:
        CommitFailed: nothing was written.
    """
    from space.store.db import CommitFailed

    ops: list[str] = []
    for space in sorted({*images, *space_seqs(db)}):
        image = images.get(space, SpaceImage())
        graphs = (*(graph(space, w) for w in ("t", "i", "stamps")), log_graph(space))
        ops += [f"DROP SILENT GRAPH <{g.value}>" for g in graphs]
        node = space_node(space).value
        ops.append(f"DELETE WHERE {{ GRAPH <{META.value}> {{ <{node}> ?p ?o }} }}")
        seq = seqs.get(space, 0)
        if not seq:
            continue
        entry = Entry(space=space, seq=seq, request="", payload=b"", prefixes=image.prefixes)
        entry.added = _parse(image.asserted)
        entry.inferred_added = _parse(image.inferred)
        for text, stamp in image.stamps:
            for s, p, _o in _parse([text]):
                entry.stamps_added.append((s, p, ox.Literal(stamp)))
        # `update` logs the entry; a re-listed space has no log entry to give.
        ops.append(update([entry], fresh=True))
        ops.append(f"DROP SILENT GRAPH <{log_graph(space).value}>")
    ops += revision_ops(db, revision)
    db.values.clear()
    db.requests.clear()
    try:
        db.store.update(" ;\n".join(ops))
        db.store.flush()
    except (OSError, RuntimeError) as exc:
        raise CommitFailed(f"the database could not commit: {exc}") from exc
    revision_written(db, revision)


def _parse(lines: list[str]) -> list[tuple]:
    if not lines:
        return []
    text = "".join(lines).encode()
    return [
        (t.subject, t.predicate, t.object) for t in ox.parse(text, format=ox.RdfFormat.N_TRIPLES)
    ]
