"""Fuzz the wire format: whatever a client sends, it gets one answer and the store lives on."""

from __future__ import annotations

import msgpack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import Literal, Namespace

from conftest import AC_NS

AC = Namespace(AC_NS)

INTS = st.integers(min_value=-(2**63), max_value=2**64 - 1)  # what msgpack holds
TERMS = st.one_of(
    st.sampled_from(
        [
            f"<{AC_NS}s>",
            "<http://a b>",
            "<rel>",
            '"x"',
            '"x"@en',
            '"5"^^<http://www.w3.org/2001/XMLSchema#integer>',
            "_:b0",
            "_:",
            '"unterminated',
            "<>",
        ]
    ),
    st.text(max_size=40),
    INTS,
    st.none(),
    st.binary(max_size=20),
)
TRIPLES = st.lists(st.one_of(st.lists(TERMS, min_size=0, max_size=4), TERMS), max_size=5)
SCALARS = st.one_of(st.none(), st.booleans(), INTS, st.floats(), st.text(max_size=30))
WRITES = st.fixed_dictionaries(
    {},
    optional={
        "v": st.one_of(st.just(1), SCALARS),
        "id": st.one_of(st.text(min_size=1, max_size=30), SCALARS),
        "agent": SCALARS,
        "ts": st.one_of(st.just("7710779730219079252/79c651f11de1a2a3"), SCALARS),
        "cause": SCALARS,
        "prefixes": st.one_of(
            st.dictionaries(
                st.text(max_size=5), st.one_of(st.text(max_size=20), SCALARS), max_size=3
            ),
            SCALARS,
        ),
        "add": st.one_of(TRIPLES, SCALARS),
        "del": st.one_of(TRIPLES, SCALARS),
        "iadd": st.one_of(TRIPLES, SCALARS),
        "idel": st.one_of(TRIPLES, SCALARS),
    },
)
QUERIES = st.fixed_dictionaries(
    {},
    optional={
        "op": st.one_of(
            st.sampled_from(["query", "read", "take", "snapshot", "sparql", "prefixes"]), SCALARS
        ),
        "template": st.one_of(st.lists(st.one_of(TERMS, st.none()), max_size=4), SCALARS),
        "graph": st.one_of(st.sampled_from(["all", "asserted", "inferred"]), SCALARS),
        "text": st.one_of(
            st.sampled_from(["SELECT * WHERE { ?s ?p ?o }", "ASK {}", "SELECT"]), SCALARS
        ),
        "limit": SCALARS,
        "id": SCALARS,
        "ts": SCALARS,
    },
)
FUZZ = settings(max_examples=120, deadline=None, suppress_health_check=list(HealthCheck))


def _one_answer(ts, service: str, payload: bytes) -> None:
    replies = list(ts.session.get(f"tspace/{ts.space}/@/{service}", payload=payload, timeout=10))
    assert len(replies) == 1, f"{len(replies)} replies to {payload!r}"
    if replies[0].err is not None:
        assert replies[0].err.payload.to_string() != "Timeout", payload


@FUZZ
@given(wire=WRITES)
def test_any_write_request_gets_one_answer(ts, wire):
    _one_answer(ts, "write", msgpack.packb(wire, use_bin_type=True))


@FUZZ
@given(wire=QUERIES)
def test_any_query_request_gets_one_answer(ts, wire):
    _one_answer(ts, "query", msgpack.packb(wire, use_bin_type=True))


@FUZZ
@given(raw=st.binary(max_size=64))
def test_any_bytes_get_one_answer(ts, raw):
    for service in ("write", "query", "log"):
        _one_answer(ts, service, raw)


def test_the_store_still_works_after_the_fuzzing(ts):
    ts.write([(AC.after, AC.fuzz, Literal(1))])
    assert len(ts.query((AC.after, None, None))) == 1
