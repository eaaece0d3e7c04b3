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


def nquads(entries: list[Entry], extra: list[ox.Quad] = ()) -> str:  # type: ignore[assignment]
    """Return the N-Quads document of a batch of plain entries (see `plain`), `extra` quads
    (leases) with them."""
    parts: list[str] = [f"{q} .\n" for q in extra]
    for e in entries:
        if e.plain:
            g = f" <{graph(e.space, 't').value}> .\n"
            parts.append("".join([f"{s} {p} {o}{g}" for s, p, o in e.plain]))
        parts.extend(f"{q} .\n" for q in _meta(e))
        parts.extend(f"{q} .\n" for q in log_quads(e.space, e.seq, e.request, e.payload, e.dropped))
    return "".join(parts)


def update(
    entries: list[Entry],
    extra: tuple[list[ox.Quad], list[ox.Quad]] = ([], []),
    *,
    fresh: bool = False,
) -> str:
    """Return the SPARQL UPDATE of a batch: each entry's DELETE DATA, then its INSERT DATA.

    `extra`: quads to delete and to insert after them (leases). `fresh`: the
    space was just cleared (a replica's copy), so nothing is removed.
    """
    ops = [op for e in entries for op in _operations(e, fresh=fresh)]
    for verb, quads in zip(("DELETE", "INSERT"), extra, strict=True):
        if quads:
            ops.append(f"{verb} DATA {{ {_quads(quads)} }}")
    return " ;\n".join(ops)


def _quads(quads: list[ox.Quad]) -> str:
    """Return quads as GRAPH blocks, one per graph (a write's leases share theirs)."""
    by_graph: dict[str, list[str]] = {}
    for q in quads:
        by_graph.setdefault(str(q.graph_name), []).append(f"{q.subject} {q.predicate} {q.object}")
    return " ".join(f"GRAPH {g} {{ {' . '.join(ts)} }}" for g, ts in by_graph.items())


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
