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

from space.store.db_layout import (
    INT,
    META,
    PREFIX,
    SEQ,
    Entry,
    graph,
    log_graph,
    log_rows,
    space_node,
)

Row = tuple[str, str, str]
_SEQ, _PREFIX, _META = f"<{SEQ.value}>", f"<{PREFIX.value}>", f"<{META.value}>"


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
        for g, rows in (
            (f"<{graph(e.space, 't').value}>", e.plain),
            (_META, _meta(e)),
            (f"<{log_graph(e.space).value}>", _logged(e)),
        ):
            parts.extend([f"{s} {p} {o} {g} .\n" for s, p, o in rows])
    return "".join(parts)


def update(
    entries: list[Entry],
    extra: tuple[list[ox.Quad], list[ox.Quad]] = ([], []),
    *,
    fresh: bool = False,
) -> str:
    """Return the SPARQL UPDATE of a batch: its net removals, then its net additions.

    Applying the entries one after another (each one's removals, then its
    additions) leaves each quad as the last entry that names it left it, so
    the batch is one DELETE DATA and one INSERT DATA of those last states:
    two operations to parse instead of two per entry, and a quad removed and
    added again within the batch is not touched. Each space's sequence number
    is written once, the batch's last (readers take the largest).

    `extra`: quads to delete and to insert after them (leases). `fresh`: the
    space was just cleared (a replica's copy), so nothing is removed.
    """
    net: dict[tuple[str, str], bool] = {}  # (graph, "s p o") -> present afterwards
    last = {e.space: e for e in entries}
    for e in entries:
        if not fresh:
            for g, triples in _removals(e):
                for s, p, o in triples:
                    net[(g, f"{s} {p} {o}")] = False
        for g, triples in _additions(e, seq=last[e.space] is e):
            for s, p, o in triples:
                net[(g, f"{s} {p} {o}")] = True
    for present, quads in zip((False, True), extra, strict=True):
        for q in quads:
            net[(str(q.graph_name), f"{q.subject} {q.predicate} {q.object}")] = present
    ops = []
    for verb, present in (("DELETE", False), ("INSERT", True)):
        by_graph: dict[str, list[str]] = {}
        for (g, text), now in net.items():
            if now is present:
                by_graph.setdefault(g, []).append(text)
        if by_graph:
            body = " ".join(f"GRAPH {g} {{ {' . '.join(ts)} }}" for g, ts in by_graph.items())
            ops.append(f"{verb} DATA {{ {body} }}")
    return " ;\n".join(ops)


def _removals(e: Entry) -> list[tuple[str, Iterable]]:
    return [
        (f"<{graph(e.space, 't').value}>", e.removed),
        (f"<{graph(e.space, 'i').value}>", e.inferred_removed),
        (f"<{graph(e.space, 'stamps').value}>", e.stamps_removed),
    ]


def _additions(e: Entry, *, seq: bool) -> list[tuple[str, Iterable]]:
    meta = _meta(e)
    t = f"<{graph(e.space, 't').value}>"
    return [
        (t, e.added),
        (t, e.plain),
        (f"<{graph(e.space, 'i').value}>", e.inferred_added),
        (f"<{graph(e.space, 'stamps').value}>", e.stamps_added),
        (_META, meta if seq else meta[1:]),
        (f"<{log_graph(e.space).value}>", _logged(e)),
    ]


def _meta(e: Entry) -> list[Row]:
    """Return an entry's rows in the `meta` graph: the space's seq, then its new prefixes."""
    node = f"<{space_node(e.space).value}>"
    rows = [(node, _SEQ, f'"{e.seq}"^^<{INT.value}>')]
    rows += [(node, _PREFIX, str(ox.Literal(f"{n} {ns}"))) for n, ns in e.prefixes.items()]
    return rows


def _logged(e: Entry) -> list[Row]:
    return log_rows(e.space, e.seq, e.request, e.payload, e.dropped)
