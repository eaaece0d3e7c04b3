"""Reads run beside writes, on a snapshot, within a time limit; a runaway never stops the store."""

import threading
import time

import pytest
from rdflib import Literal, Namespace

from conftest import AC_NS, Server
from space import QueryTimeLimit, TripleSpace

AC = Namespace(AC_NS)

# Every solution of a three-way cross join of N triples: N**3 rows, yielded one by one.
CROSS = "SELECT * WHERE { ?a ?p ?b . ?c ?q ?d . ?e ?r ?f }"
# The same join counted: Oxigraph computes it before its one result, so it cannot stop early.
COUNTED = "SELECT (COUNT(*) AS ?n) WHERE { ?a ?p ?b . ?c ?q ?d . ?e ?r ?f . ?g ?s ?h }"


@pytest.fixture(scope="module")
def limited(tmp_path_factory):
    srv = Server(tmp_path_factory.mktemp("limited") / "data", "--query-timeout", "1")
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="big") as ts:
            ts.write([(AC[f"s{i}"], AC.n, Literal(i)) for i in range(300)])
        yield srv
    finally:
        srv.stop()


def test_a_query_past_the_stores_limit_gets_one_error_naming_it(limited):
    with TripleSpace.open(limited.endpoint, space="big") as ts:
        started = time.monotonic()
        with pytest.raises(QueryTimeLimit, match="time limit of 1 s"):
            ts.query_sparql(CROSS, timeout=30)
        assert time.monotonic() - started < 10
        # the store lives on: a cheap query right after is answered
        assert len(ts.query_sparql("SELECT ?s WHERE { ?s ?p 7 }", timeout=10)) == 1


def test_a_request_may_ask_for_a_shorter_limit(limited):
    with TripleSpace.open(limited.endpoint, space="big") as ts:
        # the store stops 0.25 s before the caller's timeout, so that the caller hears why
        with pytest.raises(QueryTimeLimit, match=r"time limit of 0\.25 s"):
            ts.query_sparql(CROSS, timeout=0.5)


def test_a_query_that_cannot_be_stopped_is_answered_at_its_limit_and_writes_go_on(limited):
    with (
        TripleSpace.open(limited.endpoint, space="big") as reader,
        TripleSpace.open(limited.endpoint, space="other") as writer,
    ):
        outcome: list = []

        def run() -> None:
            started = time.monotonic()
            try:
                reader.query_sparql(COUNTED, timeout=30)
                outcome.append("answered")
            except QueryTimeLimit as exc:
                outcome.append((time.monotonic() - started, str(exc)))

        thread = threading.Thread(target=run)
        thread.start()
        delays = []
        for i in range(50):
            begun = time.monotonic()
            writer.write([(AC.w, AC.n, Literal(i))])
            delays.append(time.monotonic() - begun)
        thread.join(30)
        elapsed, message = outcome[0]
        assert "1 s" in message
        assert elapsed < 5, "the caller hears of the limit when it passes, not when Oxigraph ends"
        # writes were not queued behind the runaway (generous bound: a loaded CI machine)
        assert sorted(delays)[int(len(delays) * 0.99) - 1] < 0.5, delays
        assert len(writer.query((AC.w, AC.n, None))) == 50
