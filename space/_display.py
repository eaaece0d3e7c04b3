"""Print terms, triples and results the way people read them (prefixed names)."""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence

from rdflib import BNode, Literal, URIRef
from rdflib.term import Node

from space.prefixes import PrefixMap
from space.terms import Triple, to_nt


def term_text(term: Node | None, prefixes: PrefixMap) -> str:
    """Return a term as Turtle would write it: `ac:robot1`, `"very low"`, `<iri>`."""
    if term is None:
        return ""
    if isinstance(term, URIRef):
        return prefixes.compact(str(term)) or f"<{term}>"
    if isinstance(term, Literal) and term.datatype is not None and not term.language:
        nt = to_nt(term)
        dt = prefixes.compact(str(term.datatype))
        return f"{nt[: nt.rindex('^^')]}^^{dt}" if dt else nt
    return to_nt(term)


def triple_text(triple: Triple, prefixes: PrefixMap) -> str:
    """Return `s p o` with prefixed names."""
    return " ".join(term_text(t, prefixes) for t in triple)


def table(
    header: Sequence[str],
    rows: Iterable[Sequence[Node | None]],
    prefixes: PrefixMap,
    *,
    sort: bool = False,
) -> str:
    """Return an aligned text table of terms (or plain `str` cells), rows sorted if `sort`."""
    cells = [[t if type(t) is str else term_text(t, prefixes) for t in row] for row in rows]
    if sort:
        cells.sort()
    widths = [max([len(h), *(len(r[i]) for r in cells)]) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True)).rstrip()]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in cells]
    return "\n".join(lines)


def sparql_json(variables: Sequence[str], rows: Iterable[Sequence[Node | None]]) -> str:
    """Return rows as SPARQL 1.1 Query Results JSON."""
    bindings = []
    for row in rows:
        bindings.append(
            {v: _json_term(t) for v, t in zip(variables, row, strict=True) if t is not None}
        )
    return json.dumps(
        {"head": {"vars": list(variables)}, "results": {"bindings": bindings}}, indent=2
    )


def _json_term(term: Node) -> dict[str, str]:
    if isinstance(term, URIRef):
        return {"type": "uri", "value": str(term)}
    if isinstance(term, BNode):
        return {"type": "bnode", "value": str(term)}
    assert isinstance(term, Literal)
    out = {"type": "literal", "value": str(term)}
    if term.language:
        out["xml:lang"] = term.language
    elif term.datatype is not None:
        out["datatype"] = str(term.datatype)
    return out
