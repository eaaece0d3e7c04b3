"""Open the Oxigraph database of a data directory, migrating an older one first.

Before Oxigraph, a data directory held `space.sqlite3`. Opening such a
directory must never show an empty space: its triples, prefixes, functional
timestamps and log are copied into Oxigraph on first open (the SQLite file is
left as it was, renamed `space.sqlite3.migrated`), and the format marker is
written last, so a migration cut short starts again from scratch next time.

Format 2 logged a changeset in three or four quads (`n`, `payload`, `request`,
`dropped`); format 3 in one (`db_layout`). Its log entries are rewritten on
first open, a thousand to an update, each entry wholly in one: one cut short
goes on from the entries still in format 2 next time, and the marker says 3
once none is left.
`python -m space.store.migrate DIR` does the same without serving.
"""

from __future__ import annotations

import argparse
import itertools
import logging
import sqlite3
import sys
from pathlib import Path

import pyoxigraph as ox

from space.changeset import unpack
from space.errors import MalformedPayload, SpaceError
from space.store import db, db_layout, oxterms

log = logging.getLogger("tspace.store")

OLD_FILE = "space.sqlite3"


class OldDataDir(SpaceError):
    """A data directory in an older format that could not be migrated."""


class NewerDataDir(SpaceError):
    """A data directory written by a newer tspace, in a format this one cannot read."""


def open_store(data_dir: Path, path: Path) -> ox.Store:
    """Open (creating if needed) the Oxigraph store at `path`, migrating `data_dir`'s SQLite.

    Raises:
        DataDirInUse: another process holds the database.
        OldDataDir: the old database could not be read.
        NewerDataDir: a newer tspace wrote it (nothing is changed).
    """
    try:
        store = ox.Store(str(path))
    except OSError as exc:
        if "lock" in str(exc).lower():
            raise db.DataDirInUse(
                f"data directory {path.parent} is in use by another store process"
            ) from None
        raise
    try:
        marks = format_marks(store, data_dir)
    except NewerDataDir:
        del store  # let go of the directory: the caller may open it read-only
        raise
    old = data_dir / OLD_FILE
    if not marks and old.exists():
        _migrate(old, store)
    elif marks and marks[0].object.value == "2":
        _one_quad_log(store)
    if [q.object.value for q in marks] != [db_layout.FORMAT]:
        for q in marks:
            store.remove(q)
        store.add(
            ox.Quad(
                db_layout.STORE, db_layout.FORMAT_P, ox.Literal(db_layout.FORMAT), db_layout.META
            )
        )
        store.flush()
    return store


def format_marks(store: ox.Store, data_dir: Path) -> list[ox.Quad]:
    """Return the format marker(s) of a store (none: new, or SQLite's to migrate).

    Raises:
        NewerDataDir: a newer tspace wrote it.
    """
    marks = list(store.quads_for_pattern(db_layout.STORE, db_layout.FORMAT_P, None, db_layout.META))
    newer = {q.object.value for q in marks} - {"2", db_layout.FORMAT}
    if newer:
        raise NewerDataDir(
            f"data directory {data_dir} is in store format {', '.join(sorted(newer))}, newer "
            f"than this tspace's ({db_layout.FORMAT}): serve it with the tspace that wrote it"
        )
    return marks


_N2, _REQUEST2 = (ox.NamedNode(db_layout.ROOT + x) for x in ("n", "request"))


def _one_quad_log(store: ox.Store) -> None:
    """Rewrite every log entry of format 2 (`n`, `payload`, `request` quads) as one quad."""
    prefix = db_layout.ROOT + "log:"
    graphs = [g for g in store.named_graphs() if g.value.startswith(prefix)]
    log.warning("rewriting the log of %d space(s) one quad to a changeset (once)", len(graphs))
    for g in graphs:
        while True:
            old = list(itertools.islice(store.quads_for_pattern(None, _N2, None, g), 1000))
            if not old:
                break
            gone, new = [], []
            for n in old:
                quads = list(store.quads_for_pattern(n.subject, None, None, g))
                by = {q.predicate: q for q in quads}
                payload, request = by.get(db_layout.PAYLOAD), by.get(_REQUEST2)
                gone += [q for q in quads if q.predicate in (_N2, _REQUEST2, db_layout.PAYLOAD)]
                if payload is not None:
                    answered = db_layout.request_node(request.object.value) if request else None
                    new.append(ox.Quad(n.subject, answered or db_layout.PAYLOAD, payload.object, g))
            store.update(
                " ;\n".join(
                    f"{verb} DATA {{ {' '.join(map(_in_graph, quads))} }}"
                    for verb, quads in (("DELETE", gone), ("INSERT", new))
                    if quads
                )
            )


def _in_graph(q: ox.Quad) -> str:
    return f"GRAPH {q.graph_name} {{ {q.subject} {q.predicate} {q.object} }}"


def _migrate(old: Path, store: ox.Store) -> None:
    """Copy every space of an SQLite database into an (emptied) Oxigraph store."""
    log.warning("migrating %s to Oxigraph (once)", old)
    store.clear()
    try:
        conn = sqlite3.connect(f"file:{old}?mode=ro", uri=True)
        try:
            spaces = [r[0] for r in conn.execute("SELECT DISTINCT space FROM log")]
            skipped = 0
            for space in spaces:
                skipped += _copy_space(conn, store, space)
        finally:
            conn.close()
    except sqlite3.Error as exc:
        raise OldDataDir(
            f"{old} (a data directory from before Oxigraph) could not be read ({exc}); repair it, "
            f"then migrate it with: python -m space.store.migrate {old.parent}"
        ) from exc
    store.flush()
    old.rename(old.with_name(OLD_FILE + ".migrated"))
    if skipped:
        log.warning("migration skipped %d triple(s) that are not valid RDF", skipped)
    log.warning("migrated %d space(s) from %s", len(spaces), old)


def _copy_space(conn: sqlite3.Connection, store: ox.Store, space: str) -> int:
    """Copy one space; return how many invalid triples were skipped."""
    seq = conn.execute("SELECT MAX(seq) FROM log WHERE space=?", (space,)).fetchone()[0] or 0
    keep = conn.execute(
        "SELECT seq, payload FROM log WHERE space=? ORDER BY seq", (space,)
    ).fetchall()
    prefixes = dict(conn.execute("SELECT name, ns FROM prefixes WHERE space=?", (space,)))
    rows = conn.execute("SELECT g, s, p, o, ts FROM triples WHERE space=?", (space,))
    quads, skipped = [], 0
    for g, s, p, o, ts in rows:
        try:
            t = oxterms.triple([s, p, o])
        except MalformedPayload:
            skipped += 1
            continue
        quads.append(ox.Quad(*t, db_layout.graph(space, g)))
        if ts and g == "t":
            quads.append(ox.Quad(t[0], t[1], ox.Literal(ts), db_layout.graph(space, "stamps")))
    node = db_layout.space_node(space)
    quads.append(
        ox.Quad(node, db_layout.SEQ, ox.Literal(str(seq), datatype=db_layout.INT), db_layout.META)
    )
    quads += [
        ox.Quad(node, db_layout.PREFIX, ox.Literal(f"{n} {ns}"), db_layout.META)
        for n, ns in prefixes.items()
    ]
    for n, payload in keep:
        quads += db_layout.log_quads(space, n, _request_id(payload), payload)
    store.bulk_extend(quads)
    return skipped


def _request_id(payload: bytes) -> str:
    """Return the changeset id of a logged payload (so a retry of it is still recognised)."""
    try:
        wire = unpack(payload)
    except MalformedPayload:
        return ""
    ident = wire.get("id") if isinstance(wire, dict) else None
    return ident if isinstance(ident, str) else ""


def main(argv: list[str] | None = None) -> int:
    """Migrate a data directory in place (`python -m space.store.migrate DIR`)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data_dir", type=Path)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        store = open_store(args.data_dir, args.data_dir / "oxigraph")
    except SpaceError as exc:
        print(f"tspace: {exc}", file=sys.stderr)
        return 1
    del store
    return 0


if __name__ == "__main__":
    sys.exit(main())
