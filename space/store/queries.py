"""Answer reads: templates, SPARQL, `take`, and plain Zenoh GETs on triple keys."""

from __future__ import annotations

import zenoh
from rdflib import Graph

from space import keys
from space.changeset import Changeset
from space.errors import MalformedPayload, QueryError
from space.store.state import SpaceState
from space.template import Template
from space.terms import Triple, from_nt, triple_to_nt

_GRAPH_NAMES = {"all": "all", "asserted": keys.ASSERTED, "inferred": keys.INFERRED}


def answer_query(state: SpaceState, request: object) -> tuple[dict, Changeset | None]:
    """Answer a decoded `@/query` request; return the reply and, for `take`, the removal.

    Raises:
        MalformedPayload: the request is not one of the documented shapes.
        QueryError: the SPARQL text is invalid or fails.
    """
    if not isinstance(request, dict):
        raise MalformedPayload("a query request is a msgpack map")
    op = request.get("op")
    if op == "prefixes":
        return {"seq": state.seq, "prefixes": state.prefixes.as_dict()}, None
    if op == "sparql":
        return _sparql(state, request.get("text")), None
    if op not in ("query", "read", "take", "snapshot"):
        raise MalformedPayload(f"unknown query op {op!r}")
    template = _template(request.get("template"))
    if op == "snapshot" or (op == "query" and request.get("graph", "all") == "all"):
        found = state.match_by_graph(template)
        return {
            "seq": state.seq,
            **{g: [triple_to_nt(t) for t in ts] for g, ts in found.items()},
        }, None
    graph = _GRAPH_NAMES.get(str(request.get("graph", "asserted" if op == "take" else "all")))
    if graph is None:
        raise MalformedPayload(f"unknown graph {request.get('graph')!r}")
    triples = state.match(template, graph)
    if op == "read":
        triples = _one_subject(triples)
    reply = {
        "seq": state.seq,
        keys.ASSERTED if graph != keys.INFERRED else keys.INFERRED: [
            triple_to_nt(t) for t in triples
        ],
    }
    take = None
    if op == "take":
        take = Changeset(agent=str(request.get("agent") or ""), removed=triples)
        take.timestamp = str(request.get("ts") or "")
    return reply, take


def _template(wire: object) -> Template:
    if wire is None:
        return Template()
    if not isinstance(wire, list | tuple) or len(wire) != 3:
        raise MalformedPayload(f"a template is three terms or nulls, got {wire!r}")
    return Template(*(None if t is None else from_nt(t) for t in wire))


def _one_subject(triples: list[Triple]) -> list[Triple]:
    """Keep the triples of the first subject in a stable order (otsopack's `read`)."""
    if not triples:
        return []
    first = min(str(t[0]) for t in triples)
    return [t for t in triples if str(t[0]) == first]


def _sparql(state: SpaceState, text: object) -> dict:
    if not isinstance(text, str) or not text.strip():
        raise MalformedPayload("a SPARQL request needs its text")
    try:
        result = state.union.query(text, initNs=state.prefixes.as_dict())
        if result.type in ("CONSTRUCT", "DESCRIBE"):
            graph = result.graph if result.graph is not None else Graph()
            body = graph.serialize(format="nt", encoding="utf-8")
        else:
            body = result.serialize(format="json")
    except Exception as exc:  # rdflib raises many unrelated types for a bad query
        raise QueryError(f"SPARQL: {exc}") from exc
    return {"seq": state.seq, "type": result.type, "body": body}


def answer_key_get(state: SpaceState, query: zenoh.Query, root: str) -> None:
    """Reply to a GET on triple keys (`<root>/<space>/t/<s>/<p>/<o>`) with each matching triple.

    Raises:
        MalformedPayload: a concrete chunk of the key is not a term.
    """
    selector = zenoh.KeyExpr(str(query.key_expr))
    chunks = str(query.key_expr).split("/")
    graph = chunks[2]
    pattern: list = [None, None, None]
    for i, chunk in enumerate(chunks[3:6]):
        if chunk == "**":
            break
        if not any(c in chunk for c in "*$"):
            pattern[i] = keys.chunk_term(chunk, state.prefixes)
    for t in state.match(Template(*pattern), graph):
        key = keys.triple_key(state.name, graph, t, state.prefixes, root)
        if selector.intersects(key):
            query.reply(key, b"")
