"""Answer reads from the database: templates, snapshots, SPARQL, the log, and plain Zenoh GETs.

Every function here runs on a reader thread (`readers.py`), never on the
writer's: each reads one Oxigraph snapshot, so a read sees whole changesets
only, and the sequence number it reports is the one of that very snapshot
(templates and snapshots) or a lower bound of it (SPARQL).
"""

from __future__ import annotations

import json
import re
import time

import pyoxigraph as ox
import zenoh

from space import keys
from space._request import TIME_LIMIT
from space.changeset import pack
from space.errors import MalformedPayload, QueryError, QueryTimeLimit
from space.prefixes import PrefixMap
from space.store import oxterms
from space.store.db import StoreDB
from space.store.db_layout import META, SEQ, graph, space_node
from space.store.intake import QueryRequest
from space.store.lifespans import remaining
from space.terms import from_nt, to_nt

MAX_KEY_REPLIES = 100_000  # replies to one GET on triple keys
_XSD_STRING = oxterms.XSD_STRING
_S, _P, _O = (ox.Variable(v) for v in "spo")


def time_limit_message(limit: float) -> str:
    """Return the one error a caller gets when its read runs past `limit` seconds."""
    return (
        f"{TIME_LIMIT}the query ran past its time limit of {limit:g} s and was abandoned "
        "(a request's 'limit', at most tspace serve --query-timeout)"
    )


class Deadline:
    """When a read must stop; checked between results, since Oxigraph cannot be interrupted."""

    def __init__(self, limit: float) -> None:
        self.limit = limit
        self.at = time.monotonic() + limit

    def check(self) -> None:
        """Raise QueryTimeLimit once the deadline has passed."""
        if time.monotonic() > self.at:
            raise QueryTimeLimit(time_limit_message(self.limit))


def read(db: StoreDB, space: str, req: QueryRequest, deadline: Deadline) -> bytes:
    """Answer `query`, `read`, `snapshot` and `prefixes` from one snapshot, with its seq."""
    if req.op == "prefixes":
        return pack({"seq": _seq(db, space), "prefixes": PrefixMap(db.prefixes(space)).as_dict()})
    graphs = ("t", "i") if req.graph == "all" or req.op == "snapshot" else (req.graph,)
    seq, found = _consistent(db, space, graphs, req.template, deadline)
    if req.op == "read":
        found = {g: _one_subject(ts) for g, ts in found.items()}
    reply: dict = {"seq": seq, **found}
    if req.lifespans:
        now = time.time()
        asserted = found.get("t") or []
        reply["lifespan"] = [remaining(db, space, oxterms.triple(t), now) for t in asserted]
    return pack(reply)


def _consistent(
    db: StoreDB, space: str, graphs: tuple[str, ...], pattern: tuple, deadline: Deadline
) -> tuple[int, dict[str, list[list[str]]]]:
    """Return the matching triples of each graph and the seq of the very snapshot they come from.

    Each `quads_for_pattern` call reads its own snapshot, taken when it is called:
    the seq is read before and after opening them all; equal, no commit came
    between, so it is theirs. A commit in between (rare: one batch's commit
    takes about a millisecond) makes it try again, then read everything with
    one SPARQL query instead, slower but one snapshot by construction.
    """
    for _ in range(3):
        before = _seq(db, space)
        iterators = {g: db.store.quads_for_pattern(*pattern, graph(space, g)) for g in graphs}
        if _seq(db, space) == before:
            found: dict[str, list[list[str]]] = {}
            text = oxterms.text
            for g, quads in iterators.items():
                rows = found[g] = []
                for n, q in enumerate(quads):
                    if n % 4096 == 0:
                        deadline.check()
                    rows.append([text(q.subject), text(q.predicate), text(q.object)])
            return before, found
    return _one_query(db, space, graphs, pattern, deadline)


def _one_query(
    db: StoreDB, space: str, graphs: tuple[str, ...], pattern: tuple, deadline: Deadline
) -> tuple[int, dict[str, list[list[str]]]]:
    branches = [
        f'{{ GRAPH <{graph(space, g).value}> {{ ?s ?p ?o }} BIND("{g}" AS ?g) }}' for g in graphs
    ]
    node, seq_p = space_node(space).value, SEQ.value
    branches.append(f"{{ GRAPH <{META.value}> {{ <{node}> <{seq_p}> ?seq }} }}")
    text = "SELECT ?g ?s ?p ?o ?seq WHERE { " + " UNION ".join(branches) + " }"
    subs = {v: t for v, t in zip((_S, _P, _O), pattern, strict=True) if t is not None}
    found: dict[str, list[list[str]]] = {g: [] for g in graphs}
    seq = 0
    for n, row in enumerate(db.store.query(text, substitutions=subs)):
        if n % 4096 == 0:
            deadline.check()
        which = row["g"]
        if which is None:
            seq = max(seq, int(row["seq"].value))  # older seqs wait for compaction
            continue
        found[which.value].append(
            [oxterms.text(row["s"]), oxterms.text(row["p"]), oxterms.text(row["o"])]
        )
    return seq, found


def _one_subject(triples: list[list[str]]) -> list[list[str]]:
    """Keep the triples of the first subject in a stable order (otsopack's `read`)."""
    if not triples:
        return []
    first = min(t[0] for t in triples)
    return [t for t in triples if t[0] == first]


def _seq(db: StoreDB, space: str) -> int:
    """Return a space's sequence number: the largest of its seq quads (see `render.py`)."""
    found = db.store.quads_for_pattern(space_node(space), SEQ, None, META)
    return max((int(q.object.value) for q in found), default=0)


def sparql(db: StoreDB, space: str, text: str, deadline: Deadline) -> bytes:
    """Run SPARQL over the union of a space's graphs; results as JSON, or N-Triples.

    Raises:
        QueryError: the text is not SPARQL or fails to evaluate.
        QueryTimeLimit: past the deadline.
    """
    seq = _seq(db, space)
    graphs = [graph(space, "t"), graph(space, "i")]
    try:
        result = db.store.query(
            text,
            prefixes=PrefixMap(db.prefixes(space)).as_dict(),
            default_graph=graphs,
            named_graphs=graphs,
        )
        if isinstance(result, ox.QueryBoolean):
            kind, body = "ASK", json.dumps({"head": {}, "boolean": bool(result)}).encode()
        elif isinstance(result, ox.QuerySolutions):
            kind, body = "SELECT", _select_json(result, deadline)
        else:
            kind = "CONSTRUCT"
            lines = []
            for n, t in enumerate(result):
                if n % 1024 == 0:
                    deadline.check()
                s, p, o = (oxterms.text(x) for x in (t.subject, t.predicate, t.object))
                lines.append(f"{s} {p} {o} .\n")
            body = "".join(lines).encode()
    except SyntaxError as exc:
        raise QueryError(f"SPARQL syntax: {_position(str(exc))}") from None
    except (OSError, ValueError, TypeError) as exc:
        raise QueryError(f"SPARQL: {exc}") from None
    deadline.check()
    return pack({"seq": seq, "type": kind, "body": body})


def _position(message: str) -> str:
    """Turn Oxigraph's "error at 1:15: ..." into "line 1, column 15: ..."."""
    match = _AT_RE.match(message)
    if match is None:
        return message
    return f"line {match.group(1)}, column {match.group(2)}: {match.group(3)}"


_AT_RE = re.compile(r"^error at (\d+):(\d+): (.*)$", re.S)


def _select_json(result: ox.QuerySolutions, deadline: Deadline) -> bytes:
    names = [v.value for v in result.variables]
    bindings = []
    for n, solution in enumerate(result):
        if n % 1024 == 0:
            deadline.check()
        row = {}
        for name in names:
            value = solution[name]
            if value is not None:
                row[name] = _json_term(value)
        bindings.append(row)
    return json.dumps({"head": {"vars": names}, "results": {"bindings": bindings}}).encode()


def _json_term(node: object) -> dict:
    if isinstance(node, ox.NamedNode):
        if node.value.startswith(oxterms.SKOLEM):
            return {"type": "bnode", "value": node.value[len(oxterms.SKOLEM) :]}
        return {"type": "uri", "value": node.value}
    if isinstance(node, ox.BlankNode):
        return {"type": "bnode", "value": node.value}
    if isinstance(node, ox.Literal):
        term = {"type": "literal", "value": node.value}
        if node.language:
            term["xml:lang"] = node.language
        elif node.datatype.value != _XSD_STRING:
            term["datatype"] = node.datatype.value
        return term
    return {"type": "literal", "value": str(node)}


def log_entries(db: StoreDB, space: str, first: int, last: int) -> bytes:
    """Return `{seq, changes}`: the logged changesets `first..last` still kept."""
    seq = _seq(db, space)
    rows = db.log(space, first, min(last, seq))
    return pack({"seq": seq, "changes": [payload for _seq, payload in rows]})


def key_get(db: StoreDB, spaces: list[str], query: zenoh.Query, root: str) -> None:
    """Reply to a GET on triple keys with one reply per matching triple, on its key.

    The selector may hold wildcards anywhere (`tspace/*/t/**`, `tspace/hall/**`):
    `spaces` are the spaces it may name.

    Raises:
        MalformedPayload: a concrete chunk is not a term, or too many triples match.
    """
    selector = zenoh.KeyExpr(str(query.key_expr))
    chunks = str(query.key_expr).split("/")[1:]
    graphs = [g for g in keys.GRAPHS if len(chunks) < 2 or _may_match(chunks[1], g)]
    sent = 0
    for space in spaces:
        prefixes = PrefixMap(db.prefixes(space))
        pattern = _key_pattern(chunks[2:5] if len(chunks) > 2 else [], prefixes)
        for which in graphs:
            for t in db.match(space, which, pattern):
                rdf = tuple(from_nt(oxterms.text(x)) for x in t)
                key = keys.triple_key(space, which, rdf, prefixes, root)  # type: ignore[arg-type]
                if selector.intersects(zenoh.KeyExpr(key)):
                    sent += 1
                    if sent > MAX_KEY_REPLIES:
                        raise MalformedPayload(
                            f"more than {MAX_KEY_REPLIES} triples match {selector}: narrow it"
                        )
                    query.reply(key, b"")


def _may_match(chunk: str, value: str) -> bool:
    return "*" in chunk or "$" in chunk or chunk == value


def _key_pattern(chunks: list[str], prefixes: PrefixMap) -> tuple:
    pattern: list = [None, None, None]
    for i, chunk in enumerate(chunks):
        if chunk == "**":
            break
        if "*" in chunk or "$" in chunk:
            continue
        pattern[i] = oxterms.term(to_nt(keys.chunk_term(chunk, prefixes)))
    return tuple(pattern)
