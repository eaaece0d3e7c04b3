"""Garbage from the network is logged once and skipped; the store keeps serving, state intact."""

import msgpack
import pytest
import zenoh
from rdflib import Literal, Namespace

from conftest import AC_NS
from space import ChangesetRejected, QueryError

AC = Namespace(AC_NS)
GARBAGE = [
    b"",
    b"\xc1\xff not msgpack",
    msgpack.packb([1, 2, 3]),
    msgpack.packb({"add": "not a list"}),
    msgpack.packb({"add": [["<a>", "<b>"]]}),
    msgpack.packb({"add": [['"literal subject"', "<http://p>", "<http://o>"]]}),
    msgpack.packb({"add": [["<http://s>", "<http://p>", "no term"]]}),
    msgpack.packb({"ts": "not a timestamp", "add": []}),
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
    with pytest.raises(QueryError, match="line:1"):
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
    ts.write([(AC.a, AC.b, Literal("sync"))])  # processed after the garbage
    lines = [
        line for line in server.logs().splitlines() if "malformed" in line and ts.space in line
    ]
    assert len(lines) >= 1
    assert all("Traceback" not in line for line in lines)
    assert zenoh  # the session used above is a plain Zenoh session
