"""Render a batch of decided changesets as ONE atomic database operation.

A batch whose changesets only add asserted triples, all of them in their own
N-Triples text (`Entry.plain`, see `oxterms.plain_rows`), becomes one N-Quads
document for `Store.load`: Oxigraph parses it in Rust, and no term of it ever
becomes a Python object. Any other batch (removals, inferred triples,
functional timestamps) becomes one SPARQL UPDATE. Both are applied by
Oxigraph atomically, each changeset with its log entry and sequence number.

A space's sequence number is a `space:<space> seq N` quad added with every
changeset and never removed by a commit (a load cannot remove): readers take
the largest, and `StoreDB` drops the older ones from time to time.
"""

from __future__ import annotations

from collections.abc import Iterable

import pyoxigraph as ox

from space.store.db import INT, META, PREFIX, SEQ, Entry, graph, log_graph, log_quads, space_node


def plain(entries: list[Entry]) -> bool:
    """Return whether a batch can be loaded as one N-Quads document."""
    return all(
        not (
            e.added
            or e.removed
            or e.inferred_added
            or e.inferred_removed
            or e.stamps_added
            or e.stamps_removed
        )
        for e in entries
    )


def nquads(entries: list[Entry]) -> str:
    """Return the N-Quads document of a batch of plain entries (see `plain`)."""
    parts: list[str] = []
    for e in entries:
        if e.plain:
            g = f" <{graph(e.space, 't').value}> .\n"
            parts.append("".join([f"{s} {p} {o}{g}" for s, p, o in e.plain]))
        parts.extend(f"{q} .\n" for q in _meta(e))
        parts.extend(f"{q} .\n" for q in log_quads(e.space, e.seq, e.request, e.payload, e.dropped))
    return "".join(parts)


def update(entries: list[Entry], *, fresh: bool = False) -> str:
    """Return the SPARQL UPDATE of a batch: each entry's DELETE DATA, then its INSERT DATA.

    `fresh`: the space was just cleared (a replica's copy), so nothing is removed.
    """
    return " ;\n".join(op for e in entries for op in _operations(e, fresh=fresh))


def _meta(e: Entry) -> list[ox.Quad]:
    node = space_node(e.space)
    quads = [ox.Quad(node, SEQ, ox.Literal(str(e.seq), datatype=INT), META)]
    quads += [ox.Quad(node, PREFIX, ox.Literal(f"{n} {ns}"), META) for n, ns in e.prefixes.items()]
    return quads


def _block(g: ox.NamedNode, triples: Iterable) -> str:
    body = " .\n".join(f"{s} {p} {o}" for s, p, o in triples)
    return f"GRAPH <{g.value}> {{ {body} }}" if body else ""


def _operations(e: Entry, *, fresh: bool) -> list[str]:
    """Return the DELETE DATA and INSERT DATA of one entry (removals first, as in a changeset)."""
    deletes = (
        []
        if fresh
        else [
            _block(graph(e.space, "t"), e.removed),
            _block(graph(e.space, "i"), e.inferred_removed),
            _block(graph(e.space, "stamps"), e.stamps_removed),
        ]
    )
    logged = [q.triple for q in log_quads(e.space, e.seq, e.request, e.payload, e.dropped)]
    inserts = [
        _block(graph(e.space, "t"), e.added),
        _block(graph(e.space, "t"), e.plain),
        _block(graph(e.space, "i"), e.inferred_added),
        _block(graph(e.space, "stamps"), e.stamps_added),
        _block(META, [q.triple for q in _meta(e)]),
        _block(log_graph(e.space), logged),
    ]
    ops = []
    if any(deletes):
        ops.append("DELETE DATA { " + " ".join(d for d in deletes if d) + " }")
    ops.append("INSERT DATA { " + " ".join(i for i in inserts if i) + " }")
    return ops
