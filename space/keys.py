"""Triples and templates <-> Zenoh key expressions.

A triple travels as `<prefix>/<space>/<graph>/<s>/<p>/<o>`, one chunk per term,
so that a plain Zenoh subscriber filters by subject and/or predicate with `*`
and `**`. A chunk is the term's N-Triples text with IRIs compacted through the
space's prefix table, then percent-escaped where Zenoh forbids a character
(`/ * $ ? #` and `%` itself). The service keys start with `@`, a verbatim chunk
that `*` and `**` never match, so a wildcard on the data never sees them.
See docs/wire-format.md.
"""

from __future__ import annotations

import re

from rdflib import BNode, Literal, URIRef
from rdflib.term import Node

from space.errors import InputError, MalformedPayload
from space.prefixes import PrefixMap
from space.terms import CACHED, Triple, from_nt, to_nt

ROOT = "tspace"
ASSERTED = "t"
INFERRED = "i"
GRAPHS = (ASSERTED, INFERRED)

_SPACE_RE = re.compile(r"^[A-Za-z0-9_.\-]+$")
_FORBIDDEN = {"%": "%25", "/": "%2F", "*": "%2A", "$": "%24", "?": "%3F", "#": "%23"}
_ESCAPED_RE = re.compile(r"%(25|2F|2A|24|3F|23)", re.I)
_TYPED_PNAME_RE = re.compile(r'^(".*")\^\^([^<>"]+)$', re.S)


def check_space(name: str) -> str:
    """Return a space name that is one legal key chunk.

    Raises:
        InputError: (a ValueError) the name has a character a key chunk cannot hold.
    """
    if not isinstance(name, str) or not _SPACE_RE.match(name):
        raise InputError(f"space name {name!r}: use letters, digits, '_', '-' or '.'")
    return name


def service_key(space: str, service: str, root: str = ROOT) -> str:
    """Return the key of a store service (`write`, `query`, `changes`, ...)."""
    return f"{root}/{space}/@/{service}"


def end_key(space: str, root: str = ROOT) -> str:
    """Return the key of the end of a changeset's parts: every scoped subscriber hears it.

    One chunk after `@/changes`, so no part selector (two chunks or more) matches it.
    """
    return f"{root}/{space}/@/changes/end"


def part_key(space: str, s_chunk: str, p_chunk: str, root: str = ROOT) -> str:
    """Return the key of a changeset's part about one subject and the predicates `p_chunk` names.

    `s_chunk`: a term chunk (`term_chunk`); `p_chunk`: one, or several joined by `/`
    (`space._parts.grouped`). A pair's own key (one predicate) is also how a
    subscriber names it; key-expression chunks (`*`, `ac:robot7_$*`) select several.
    """
    return f"{root}/{space}/@/changes/{s_chunk}/{p_chunk}"


def escape(text: str) -> str:
    """Percent-escape the characters Zenoh forbids in a key chunk."""
    for char, escaped in _FORBIDDEN.items():  # `%` first; str.replace is the fast way
        if char in text:
            text = text.replace(char, escaped)
    return text


def unescape(chunk: str) -> str:
    """Undo `escape`."""
    return _ESCAPED_RE.sub(lambda m: chr(int(m.group(1), 16)), chunk)


_MEMO_MAX = CACHED


def term_chunk(term: Node, prefixes: PrefixMap) -> str:
    """Return the key chunk of a term.

    Memoized in the prefix map (emptied when its bindings change): the store
    makes a key for every triple it publishes, and the same terms recur.
    """
    memo = prefixes.chunks
    chunk = memo.get(term)
    if chunk is None:
        if len(memo) >= _MEMO_MAX:
            memo.clear()
        chunk = memo[term] = _term_chunk(term, prefixes)
    return chunk


def _term_chunk(term: Node, prefixes: PrefixMap) -> str:
    if isinstance(term, URIRef):
        text = prefixes.compact(str(term)) or f"<{term}>"
    elif isinstance(term, Literal) and term.datatype is not None and not term.language:
        nt = to_nt(term)
        pname = prefixes.compact(str(term.datatype))
        text = nt[: nt.rindex("^^")] + "^^" + pname if pname and nt.endswith(">") else nt
    else:
        text = to_nt(term)
    return escape(text)


def chunk_term(chunk: str, prefixes: PrefixMap) -> Node:
    """Parse a key chunk back into a term.

    Raises:
        MalformedPayload: the chunk is not a term or names an unknown prefix.
    """
    text = unescape(chunk)
    if text[:1] in ("<", '"') or text.startswith("_:"):
        typed = _TYPED_PNAME_RE.match(text) if text[0] == '"' else None
        if typed:
            datatype = prefixes.expand(typed.group(2))
            if datatype is None:
                raise MalformedPayload(f"unknown prefix in key chunk {chunk!r}")
            text = f"{typed.group(1)}^^<{datatype}>"
        return from_nt(text)
    iri = prefixes.expand(text)
    if iri is None:
        raise MalformedPayload(f"unknown prefix in key chunk {chunk!r}")
    return iri


def triple_key(
    space: str, graph: str, triple: Triple, prefixes: PrefixMap, root: str = ROOT
) -> str:
    """Return the key of one triple in the asserted (`t`) or inferred (`i`) graph."""
    return (
        f"{root}/{space}/{graph}/{term_chunk(triple[0], prefixes)}"
        f"/{term_chunk(triple[1], prefixes)}/{term_chunk(triple[2], prefixes)}"
    )


def parse_triple_key(key: str, prefixes: PrefixMap) -> tuple[str, str, Triple]:
    """Return `(space, graph, triple)` of a triple key.

    Raises:
        MalformedPayload: the key is not `<root>/<space>/<graph>/<s>/<p>/<o>`.
    """
    parts = str(key).split("/")
    if len(parts) != 6 or parts[2] not in GRAPHS:
        raise MalformedPayload(f"not a triple key: {key!r}")
    s, p, o = (chunk_term(chunk, prefixes) for chunk in parts[3:])
    if isinstance(s, Literal) or not isinstance(p, URIRef):
        raise MalformedPayload(f"not a valid RDF triple key: {key!r}")
    return parts[1], parts[2], (s, p, o)


def template_key(
    space: str, graph: str, template: tuple, prefixes: PrefixMap, root: str = ROOT
) -> str:
    """Return the key expression that selects the triples a template may match.

    Variables and None become `*`; a literal object is kept (exact match).
    """
    chunks = [
        "*" if t is None or not isinstance(t, URIRef | Literal | BNode) else term_chunk(t, prefixes)
        for t in template
    ]
    return f"{root}/{space}/{graph}/{'/'.join(chunks)}"
