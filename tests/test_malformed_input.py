"""Garbage from the network is logged once and skipped; the store keeps serving, state intact."""

import itertools
import subprocess
import threading

import msgpack
import pytest
import zenoh
from rdflib import Literal, Namespace

from conftest import AC_NS, tspace_cmd, wait_for
from space import Change, Changeset, ChangesetRejected, MalformedPayload, QueryError
from space.zconfig import make_config

AC = Namespace(AC_NS)
GARBAGE = [
    b"",
    b"\xc1\xff not msgpack",
    b"\x81\x90\x00",  # a map keyed by a list
    msgpack.packb([1, 2, 3]),
    msgpack.packb({"add": "not a list"}),
    msgpack.packb({"add": [["<a>", "<b>"]]}),
    msgpack.packb({"add": [['"literal subject"', "<http://p>", "<http://o>"]]}),
    msgpack.packb({"add": [["<http://s>", "<http://p>", "no term"]]}),
    msgpack.packb({"ts": "not a timestamp", "add": []}),
    msgpack.packb({"v": 1, "add": [["<http://s>", "<http://p>", "<http://o>"]]}),  # no id
    msgpack.packb({"v": 99, "id": "x", "add": [["<http://s>", "<http://p>", "<http://o>"]]}),
]
# Well-formed msgpack on the store's changes key, none of it published by a store.
FORGED_CHANGES = [
    b"\x81\x90\x00",  # a map keyed by a list: msgpack, but no Python dict (TypeError)
    msgpack.packb({"seq": 10**9}),  # no id
    msgpack.packb({"id": "forged", "v": 1}),  # no seq
    msgpack.packb({"id": "forged", "v": 1, "seq": "10"}),
    msgpack.packb({"id": "forged", "v": 1, "seq": 10**9}),  # a seq the store never gave
    msgpack.packb(
        {"id": "forged", "v": 1, "seq": 10**9 + 1, "add": [[f"<{AC_NS}x>", f"<{AC_NS}y>", '"z"']]}
    ),
]


@pytest.mark.parametrize("payload", GARBAGE)
def test_garbage_write_is_rejected_and_state_is_intact(ts, server, payload):
    ts.write([(AC.robot1, AC.battery_level, Literal("normal"))])
    before = set(ts.query(None))
    ts.session.put(f"tspace/{ts.space}/@/write", payload)  # fire-and-forget garbage
    replies = list(ts.session.get(f"tspace/{ts.space}/@/write", payload=payload, timeout=5))
    assert len(replies) == 1 and replies[0].err is not None
    assert set(ts.query(None)) == before
    ts.write([(AC.robot1, AC.still, Literal("alive"))])
    assert len(ts.query(None)) == len(before) + 1


def test_garbage_query_gets_an_error_reply(ts):
    for payload in GARBAGE:
        replies = list(ts.session.get(f"tspace/{ts.space}/@/query", payload=payload, timeout=5))
        assert len(replies) == 1 and replies[0].err is not None


def test_bad_sparql_raises_query_error_naming_the_position(ts):
    with pytest.raises(QueryError, match="line 1, column 15"):
        ts.query_sparql("SELECT WHERE {")


def test_bad_triple_key_get_is_answered_with_an_error(ts):
    replies = list(ts.session.get(f"tspace/{ts.space}/t/zz:nope/**", timeout=5))
    assert [r.err is not None for r in replies] == [True]


def test_get_on_triple_keys_returns_matching_triples(ts):
    ts.write(
        [
            (AC.robot1, AC.battery_level, Literal("low")),
            (AC.robot2, AC.battery_level, Literal("full")),
        ]
    )
    replies = list(ts.session.get(f"tspace/{ts.space}/t/ac:robot1/**", timeout=5))
    assert [str(r.ok.key_expr) for r in replies] == [
        f'tspace/{ts.space}/t/ac:robot1/ac:battery_level/"low"'
    ]


def test_bad_space_name_in_key_is_rejected(ts):
    replies = list(ts.session.get("tspace/bad name!/@/query", payload=b"x", timeout=5))
    assert all(r.err is not None for r in replies)


def test_rejected_changeset_raises(ts):
    from space.changeset import Changeset

    cs = Changeset(timestamp="garbage")
    with pytest.raises(ChangesetRejected):
        ts.send(cs)


def test_store_logs_one_line_per_malformed_message(ts, server):
    marker = "\xc1marker-payload"
    ts.session.put(f"tspace/{ts.space}/@/write", marker.encode("latin-1"))
    ts.write([(AC.a, AC.b, Literal("sync"))])  # the store lives on

    def logged() -> list[str]:  # a put and a query travel apart: the line may come after the ack
        return [
            line for line in server.logs().splitlines() if "malformed" in line and ts.space in line
        ]

    lines = wait_for(logged, 10, "the store's line about the malformed message")
    assert all("Traceback" not in line for line in lines)
    assert zenoh  # the session used above is a plain Zenoh session


@pytest.mark.parametrize("payload", FORGED_CHANGES[:4])
def test_a_published_changeset_needs_its_id_and_seq(payload):
    with pytest.raises(MalformedPayload):
        Changeset.decode(payload, published=True)


def test_forged_changes_do_not_deafen_subscribers(ts, server):
    """A forged far-future seq once made every subscriber skip every later real change."""
    seen: list[Change] = []
    ts.subscribe("?b ac:battery_level ?l", seen.append)
    cmd = tspace_cmd(
        "watch", "?b ac:battery_level ?l", "--connect", server.endpoint, "--space", ts.space
    )
    watcher = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    threading.Thread(
        target=lambda: lines.extend(iter(watcher.stdout.readline, "")), daemon=True
    ).start()
    level = (AC.robot1_battery, AC.battery_level)
    try:
        probes = itertools.count()

        def watcher_listens() -> bool:
            ts.write([(AC[f"probe{next(probes)}"], AC.battery_level, Literal("normal"))])
            return any("normal" in line for line in lines)

        wait_for(watcher_listens, 20, "the watcher's first line")
        with zenoh.open(make_config(connect=[server.endpoint])) as plain:
            for payload in FORGED_CHANGES:
                plain.put(f"tspace/{ts.space}/@/changes", payload)
            plain.put(f"tspace/{ts.space}/@/seq", msgpack.packb({"seq": 10**9}))  # heartbeat
            plain.put(f"tspace/{ts.space}/@/seq", msgpack.packb({"seq": "nonsense"}))
        ts.write([(*level, Literal("low"))])
        ts.apply([(*level, Literal("very low"))], [(*level, Literal("low"))])

        def delivered(value: str) -> bool:
            return any(change.added == [(*level, Literal(value))] for change in seen)

        wait_for(lambda: delivered("low") and delivered("very low"), what="the real changes")
        wait_for(lambda: any('"very low"' in line for line in lines), what="the watcher's line")
        assert all(change.id != "forged" for change in seen)
        assert [c.seq for c in seen] == sorted(c.seq for c in seen) and seen[-1].seq < 10**9
        assert not any('"z"' in line for line in lines)
    finally:
        watcher.terminate()
        _, errors = watcher.communicate(timeout=10)
    assert "Traceback" not in errors
