"""An old SQLite data directory is migrated on first open, never opened as an empty space."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
from pathlib import Path

import msgpack
from rdflib import Literal, Namespace

from conftest import AC_NS, Server, newer_format_dir, serve_refusal, tspace_cmd, wait_for
from space import Changeset, TripleSpace

AC = Namespace(AC_NS)
# The schema the store used before Oxigraph (space/store/db.py up to a5d5dd9).
OLD_SCHEMA = """
CREATE TABLE triples (space TEXT NOT NULL, g TEXT NOT NULL, s TEXT NOT NULL, p TEXT NOT NULL,
    o TEXT NOT NULL, ts TEXT NOT NULL DEFAULT '', PRIMARY KEY (space, g, s, p, o)) WITHOUT ROWID;
CREATE TABLE log (space TEXT NOT NULL, seq INTEGER NOT NULL, payload BLOB NOT NULL,
    PRIMARY KEY (space, seq)) WITHOUT ROWID;
CREATE TABLE prefixes (space TEXT NOT NULL, name TEXT NOT NULL, ns TEXT NOT NULL,
    PRIMARY KEY (space, name)) WITHOUT ROWID;
"""
TS = "7710779730219079252/79c651f11de1a2a3"


def _old_dir(data: Path) -> None:
    data.mkdir(parents=True)
    conn = sqlite3.connect(data / "space.sqlite3")
    conn.executescript(OLD_SCHEMA)
    level, functional = (
        f"<{AC_NS}battery_level>",
        "<http://www.w3.org/2002/07/owl#FunctionalProperty>",
    )
    rdf_type = "<http://www.w3.org/1999/02/22-rdf-syntax-ns#type>"
    rows = [
        ("t", level, rdf_type, functional, ""),
        ("t", f"<{AC_NS}b1>", level, '"low"', TS),
        ("t", f"<{AC_NS}b1>", f"<{AC_NS}name>", '"battery"@en', ""),
        ("i", f"<{AC_NS}b1>", rdf_type, f"<{AC_NS}Device>", ""),
        ("t", "<http://a b>", f"<{AC_NS}bad>", '"accepted before"', ""),  # not RDF: skipped
    ]
    conn.executemany("INSERT INTO triples VALUES ('old', ?, ?, ?, ?, ?)", rows)
    conn.execute("INSERT INTO prefixes VALUES ('old', 'ac', ?)", (AC_NS,))
    for seq in (1, 2, 3):
        wire = {"v": 1, "id": f"cs{seq}", "agent": "a", "ts": TS, "seq": seq}
        if seq == 3:  # a log entry longer than any one term, its id to be escaped
            wire["id"] = 'cs"3\n'
            wire["add"] = [[f"<{AC_NS}d{i}>", f"<{AC_NS}name>", f'"{i:050}"'] for i in range(400)]
        payload = msgpack.packb(wire)
        conn.execute("INSERT INTO log VALUES ('old', ?, ?)", (seq, payload))
    conn.commit()
    conn.close()


def test_an_old_data_directory_is_migrated_with_its_state_log_and_seq(tmp_path: Path):
    data = tmp_path / "data"
    _old_dir(data)
    srv = Server(data)
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="old") as ts:
            graph, seq = ts.snapshot()
            assert seq == 3
            assert len(graph) == 4
            assert len(ts.query("?b ac:battery_level 'low'")) == 1  # prefixes came along
            assert len(ts.query(None, graph="inferred")) == 1
            logged = [Changeset.decode(p) for p in ts._fetch_log(1, 3)[0]]
            assert [c.id for c in logged] == ["cs1", "cs2", 'cs"3\n']
            assert len(logged[2].added) == 400
            # the functional property and its timestamp came along: an older value loses
            ack = ts.send(ts.changeset([(AC.b1, AC.battery_level, Literal("high"))]))
            assert ack.seq == 4 and ack.dropped == []
            old = Changeset(
                agent="x", timestamp=TS[:-1] + "0", added=[(AC.b1, AC.battery_level, Literal("x"))]
            )
            assert ts.send(old).dropped
        assert "migrated 1 space(s)" in srv.logs()
        assert (data / "space.sqlite3.migrated").exists() and not (data / "space.sqlite3").exists()
        srv.stop(signal.SIGKILL)
        srv.start()
        with TripleSpace.open(srv.endpoint, space="old") as ts:
            assert ts.snapshot()[1] == 4
    finally:
        srv.stop()


def test_an_unreadable_old_database_is_refused_in_one_line_naming_the_command(tmp_path: Path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "space.sqlite3").write_bytes(b"not a database at all" * 100)
    assert "python -m space.store.migrate" in serve_refusal(data)


def _format2_dir(data: Path) -> None:
    """A data directory as the store wrote it before the one-quad log (format 2)."""
    import base64

    import pyoxigraph as ox

    root = "urn:tspace:"
    store = ox.Store(str(data / "oxigraph"))
    meta, log = ox.NamedNode(root + "meta"), ox.NamedNode(root + "log:old")
    store.add(
        ox.Quad(ox.NamedNode(root + "store"), ox.NamedNode(root + "format"), ox.Literal("2"), meta)
    )
    space = ox.NamedNode(root + "space:old")
    seq_p = ox.NamedNode(root + "seq")
    store.add(ox.Quad(space, seq_p, ox.Literal("2", datatype=ox.NamedNode(XSD_INT)), meta))
    store.add(
        ox.Quad(
            ox.NamedNode(f"{AC_NS}b1"),
            ox.NamedNode(f"{AC_NS}name"),
            ox.Literal("b"),
            ox.NamedNode(root + "graph:old:asserted"),
        )
    )
    ids = {1: "cs1", 2: 'cs"2 x/y'}
    for seq, ident in ids.items():
        entry = ox.NamedNode(f"{root}log:old:{seq}")
        wire = {
            "v": 1,
            "id": ident,
            "agent": "a",
            "ts": TS,
            "seq": seq,
            "add": [[f"<{AC_NS}b1>", f"<{AC_NS}name>", '"b"']],
        }
        rows = {
            "n": ox.Literal(str(seq), datatype=ox.NamedNode(XSD_INT)),
            "payload": ox.Literal(base64.b64encode(msgpack.packb(wire)).decode()),
            "request": ox.Literal(ident),
        }
        if seq == 2:
            dropped = [{"triple": ["<a>", "<b>", '"c"'], "reason": "why"}]
            rows["dropped"] = ox.Literal(base64.b64encode(msgpack.packb(dropped)).decode())
        for p, o in rows.items():
            store.add(ox.Quad(entry, ox.NamedNode(root + p), o, log))
    store.flush()
    del store


XSD_INT = "http://www.w3.org/2001/XMLSchema#integer"


def test_a_format_2_log_is_rewritten_one_quad_a_changeset_keeping_replays_and_retries(
    tmp_path: Path,
):
    import pyoxigraph as ox

    data = tmp_path / "data"
    data.mkdir()
    _format2_dir(data)
    srv = Server(data)
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="old") as ts:
            assert ts.snapshot()[1] == 2
            logged = [Changeset.decode(p) for p in ts._fetch_log(1, 2)[0]]
            assert [c.id for c in logged] == ["cs1", 'cs"2 x/y']
            # a retry of a logged request id gets the first outcome, and is not applied again
            again = ts.send(
                Changeset(id='cs"2 x/y', agent="a", added=[(AC.b2, AC.name, Literal("c"))])
            )
            assert again.again and again.seq == 2 and again.dropped[0].reason == "why"
            assert ts.send(ts.changeset([(AC.b3, AC.name, Literal("d"))])).seq == 3
        assert "rewriting the log of 1 space(s)" in srv.logs()
    finally:
        srv.stop()
    store = ox.Store(str(data / "oxigraph"))
    log = ox.NamedNode("urn:tspace:log:old")
    rows = {
        (q.subject.value.rsplit(":", 1)[1], q.predicate.value)
        for q in store.quads_for_pattern(None, None, None, log)
    }
    assert rows - {r for r in rows if r[0] == "3"} == {
        ("1", "urn:tspace:req:cs1"),
        ("2", "urn:tspace:req:cs%222%20x%2Fy"),
        ("2", "urn:tspace:dropped"),
    }
    assert len([r for r in rows if r[0] == "3"]) == 1  # one quad a changeset
    marker = store.quads_for_pattern(None, ox.NamedNode("urn:tspace:format"), None, None)
    assert [q.object.value for q in marker] == ["3"]


def test_a_directory_of_a_newer_format_is_refused_in_one_line_and_left_as_it_was(
    tmp_path: Path,
):
    """A tspace older than its data directory must not read it as its own format, nor
    rewrite its marker: the newer tspace that wrote it would then misread it too."""
    import pyoxigraph as ox

    data = tmp_path / "data"
    marker = newer_format_dir(data)
    line = serve_refusal(data)
    assert "format 99" in line and "newer" in line
    store = ox.Store(str(data / "oxigraph"))
    assert list(store.quads_for_pattern(marker.subject, marker.predicate, None, None)) == [marker]


def _big_format2_dir(data: Path, entries: int) -> dict[int, tuple[str, bytes, bytes]]:
    """A format 2 directory whose space `big` logged `entries` changesets; return each seq's
    request id, payload and what its writer was told was dropped."""
    import base64

    import pyoxigraph as ox

    root = "urn:tspace:"
    store = ox.Store(str(data / "oxigraph"))
    meta, log = ox.NamedNode(root + "meta"), ox.NamedNode(root + "log:big")
    quads = [
        ox.Quad(ox.NamedNode(root + "store"), ox.NamedNode(root + "format"), ox.Literal("2"), meta),
        ox.Quad(
            ox.NamedNode(root + "space:big"),
            ox.NamedNode(root + "seq"),
            ox.Literal(str(entries), datatype=ox.NamedNode(XSD_INT)),
            meta,
        ),
    ]
    logged = {}
    for seq in range(1, entries + 1):
        ident = f"robot {seq % 7}/{seq}"  # to be percent-encoded in the IRI
        payload = msgpack.packb({"v": 1, "id": ident, "agent": "a", "ts": TS, "seq": seq})
        dropped = msgpack.packb([{"reason": f"why {seq}"}]) if seq % 5 == 0 else b""
        logged[seq] = (ident, payload, dropped)
        rows = {
            "n": ox.Literal(str(seq), datatype=ox.NamedNode(XSD_INT)),
            "payload": ox.Literal(base64.b64encode(payload).decode()),
            "request": ox.Literal(ident),
        }
        if dropped:
            rows["dropped"] = ox.Literal(base64.b64encode(dropped).decode())
        entry = ox.NamedNode(f"{root}log:big:{seq}")
        quads += [ox.Quad(entry, ox.NamedNode(root + p), o, log) for p, o in rows.items()]
    store.bulk_extend(quads)
    store.flush()
    del store
    return logged


def _log_left(data: Path) -> tuple[str, int, int]:
    """Return the format marker, and the entries of format 2 and 3 in the log, as on disk."""
    import pyoxigraph as ox

    store = ox.Store.read_only(str(data / "oxigraph"))
    log = ox.NamedNode("urn:tspace:log:big")
    marker = [
        q.object.value
        for q in store.quads_for_pattern(None, ox.NamedNode("urn:tspace:format"), None, None)
    ]
    old = sum(1 for _ in store.quads_for_pattern(None, ox.NamedNode("urn:tspace:n"), None, log))
    new = sum(
        1
        for q in store.quads_for_pattern(None, None, None, log)
        if q.predicate.value.startswith("urn:tspace:req:")
    )
    return ",".join(marker), old, new


def test_a_log_rewrite_killed_midway_goes_on_from_where_it_stopped(tmp_path: Path):
    """kill -9 during the rewrite of a format 2 log: the next open finishes it, and every
    changeset is still found by its seq and by its request id, with what was dropped."""
    from space.store.db import StoreDB

    data = tmp_path / "data"
    data.mkdir()
    entries = 20_000
    logged = _big_format2_dir(data, entries)
    argv = [tspace_cmd()[0], "-m", "space.store.migrate", str(data)]
    proc = subprocess.Popen(argv, stderr=subprocess.DEVNULL)
    try:
        wait_for(lambda: _log_left(data)[2] > 0, 60, "a first thousand entries rewritten")
        proc.kill()
    finally:
        proc.wait()
    marker, old, new = _log_left(data)
    assert marker == "2" and old > 0 and old + new == entries  # cut midway, nothing lost
    done = subprocess.run(argv, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert _log_left(data) == ("3", 0, entries)
    db = StoreDB(data)
    try:
        assert db.log("big", 1, entries) == [(s, p) for s, (_, p, _) in logged.items()]
        for seq, (ident, payload, dropped) in logged.items():
            assert db.outcome("big", ident) == (seq, payload, dropped)
    finally:
        db.close()
