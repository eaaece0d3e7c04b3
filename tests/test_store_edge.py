"""What one client sends through raw Zenoh never hurts another: limits, terms, keys, spaces."""

from __future__ import annotations

import uuid

import msgpack
import pytest
import zenoh
from rdflib import Literal, Namespace, URIRef

from conftest import AC_NS, Server, wait_for
from space import ChangesetRejected, TripleSpace
from space._replies import every_reply

AC = Namespace(AC_NS)
S, P = f"<{AC_NS}s>", f"<{AC_NS}p>"


def _write(ts: TripleSpace, wire: dict) -> list[zenoh.Reply]:
    payload = msgpack.packb({"v": 1, "id": uuid.uuid4().hex, **wire})
    return list(ts.session.get(f"tspace/{ts.space}/@/write", payload=payload, timeout=5))


def _error(replies: list[zenoh.Reply]) -> str:
    assert len(replies) == 1 and replies[0].err is not None, replies
    return replies[0].err.payload.to_string()


def test_a_huge_literal_is_refused_with_the_limit_and_the_store_lives_on(ts):
    message = _error(_write(ts, {"add": [[S, P, '"' + "x" * 66_000 + '"']]}))
    assert "at most 16384 characters" in message
    ts.write([(AC.s, AC.p, Literal("fine"))])
    assert len(ts.query((AC.s, None, None))) == 1


def test_an_invalid_iri_is_refused_and_construct_keeps_working(ts):
    assert "IRI" in _error(_write(ts, {"add": [["<http://a b>", P, '"x"']]}))
    assert "invalid RDF term" in _error(_write(ts, {"add": [["<relative>", P, '"x"']]}))
    assert "subtag" in _error(_write(ts, {"add": [[S, P, '"x"@abcdefghij']]}))
    ts.write([(AC.s, AC.p, Literal("ok"))])
    result = ts.query_sparql("CONSTRUCT WHERE { ?s ?p ?o }")
    assert len(result.graph) == 1


@pytest.mark.parametrize(
    "wire",
    [
        {"add": [[S, P, None]]},
        {"add": [[S, P, {"a": "map"}]]},
        {"add": [[S, P, 2**63]]},
        {"ts": None, "agent": 2**40, "add": [[S, P, '"x"']]},
        {"add": [[[[[[[[[["deep"]]]]]]]]]]},
        {"prefixes": {"ac": "not an iri"}},
        {"cause": ["list"]},
    ],
)
def test_a_malformed_field_gets_an_error_and_its_batch_neighbours_are_applied(ts, wire):
    for i in range(20):
        ts.send_nowait(ts.changeset([(AC.n, AC.v, Literal(i))]))
    assert _error(_write(ts, wire))
    ts.write([(AC.n, AC.v, Literal(20))])
    assert len(ts.query((AC.n, AC.v, None))) == 21


def test_a_take_with_a_malformed_timestamp_is_refused_and_nothing_is_taken(ts):
    ts.write([(AC.item, AC.state, Literal("ready"))])
    request = {"op": "take", "template": [f"<{AC_NS}item>", None, None], "ts": "garbage"}
    replies = list(ts.session.get(f"tspace/{ts.space}/@/query", payload=msgpack.packb(request)))
    assert "timestamp" in _error(replies)
    assert len(ts.query((AC.item, None, None))) == 1


def test_wildcard_gets_are_answered_and_no_fire_and_forget_write_is_lost(ts):
    ts.write([(AC.robot, AC.n, Literal(-1))])
    for i in range(400):
        ts.send_nowait(ts.changeset([(AC.robot, AC.n, Literal(i))]))
        if i % 50 == 0:
            for selector in (f"tspace/{ts.space}/**", "tspace/*/t/**", f"tspace/{ts.space}/*/**"):
                every_reply(ts.session.get, selector, 5)
    wait_for(lambda: len(ts.query((AC.robot, AC.n, None))) == 401, 20, "every write")
    keys = [str(r.ok.key_expr) for r in every_reply(ts.session.get, f"tspace/{ts.space}/**", 5)]
    assert len(keys) == 401 and all(k.startswith(f"tspace/{ts.space}/t/") for k in keys)


def test_reading_never_written_spaces_creates_nothing(server):
    with TripleSpace.open(server.endpoint, space="probe") as ts:
        names = [f"ghost{uuid.uuid4().hex[:8]}" for _ in range(300)]
        for name in names:
            with TripleSpace(ts.session, name) as other:
                assert other.snapshot()[1] == 0
        spaces = msgpack.unpackb(
            next(iter(ts.session.get("tspace/@repl/spaces"))).ok.payload.to_bytes()
        )
        assert not set(names) & set(spaces)


def test_spaces_beyond_the_limit_are_refused_with_the_option_named(tmp_path):
    srv = Server(tmp_path / "data", "--max-spaces", "3")
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint) as ts:
            for i in range(3):
                TripleSpace(ts.session, f"s{i}").write([(AC.a, AC.b, Literal(i))])
            with pytest.raises(ChangesetRejected, match="--max-spaces"):
                TripleSpace(ts.session, "s3").write([(AC.a, AC.b, Literal(3))])
            TripleSpace(ts.session, "s0").write([(AC.a, AC.b, Literal(9))])  # known: fine
    finally:
        srv.stop()


def test_uri_with_escapes_round_trips(ts):
    iri = URIRef("http://example.org/a%20b/ü")
    ts.write([(iri, AC.p, Literal("x"))])
    assert len(ts.query((iri, None, None))) == 1
