"""Wire terms (N-Triples texts) <-> pyoxigraph terms: the store's one term conversion.

Every term that enters the store is checked here (a valid IRI, literal or
blank node label, within `MAX_TERM` characters), so nothing invalid reaches
the database: an IRI such as `<http://a b>` is refused at the edge instead of
breaking every later CONSTRUCT of its space.

Blank nodes are stored skolemized, as `urn:tspace:bnode:<label>` IRIs: SPARQL
UPDATE (the one atomic call that both removes and adds) cannot name a stored
blank node, so a blank node must be an IRI inside the database. Every answer
turns those IRIs back into `_:<label>`.
"""

from __future__ import annotations

import re
import threading
from functools import lru_cache

import pyoxigraph as ox

from space.errors import MalformedPayload

OxTerm = ox.NamedNode | ox.BlankNode | ox.Literal
OxTriple = tuple[OxTerm, OxTerm, OxTerm]

MAX_TERM = 16_384  # characters of one term's N-Triples text (docs/wire-format.md)
SKOLEM = "urn:tspace:bnode:"
XSD_STRING = "http://www.w3.org/2001/XMLSchema#string"
_CACHED = 8192

_LITERAL_RE = re.compile(
    r'^"((?:[^"\\\n\r]|\\.)*)"(?:\^\^<([^<>"{}|^`\\\x00-\x20]*)>|@([A-Za-z]+(?:-[A-Za-z0-9]+)*))?$',
    re.S,
)
_IRI_RE = re.compile(r'^<([^<>"{}|^`\\\x00-\x20]*)>$')
_BNODE_RE = re.compile(r"^_:([A-Za-z0-9_](?:[A-Za-z0-9_.\-]*[A-Za-z0-9_\-])?)$")
_UNESCAPE_RE = re.compile(r'\\(u[0-9A-Fa-f]{4}|U[0-9A-Fa-f]{8}|[tbnrf"\'\\])')
_SIMPLE = {"t": "\t", "b": "\b", "n": "\n", "r": "\r", "f": "\f", '"': '"', "'": "'", "\\": "\\"}


def _unescape(text: str) -> str:
    if "\\" not in text:
        return text
    rest = _UNESCAPE_RE.sub("", text)
    if "\\" in rest:
        raise MalformedPayload(f"bad escape in literal {text[:80]!r}")

    def one(match: re.Match[str]) -> str:
        code = match.group(1)
        if code[0] in "uU":
            point = int(code[1:], 16)
            if point > 0x10FFFF or 0xD800 <= point <= 0xDFFF:
                raise MalformedPayload(f"bad code point escape \\{code}")
            return chr(point)
        return _SIMPLE[code]

    return _UNESCAPE_RE.sub(one, text)


def term(text: object) -> OxTerm:
    """Return the pyoxigraph term of one N-Triples term text.

    Raises:
        MalformedPayload: not a string, too long, or not a valid IRI, literal or blank node.
    """
    if not isinstance(text, str) or not text:
        raise MalformedPayload(f"a term is a non-empty N-Triples string, got {_short(text)}")
    return _term(text)


@lru_cache(maxsize=_CACHED)
def _term(text: str) -> OxTerm:
    if len(text) > MAX_TERM:
        raise MalformedPayload(f"a term is at most {MAX_TERM} characters, got {len(text)}")
    try:
        first = text[0]
        if first == "<":
            match = _IRI_RE.match(text)
            if match is None:
                raise MalformedPayload(f"not an N-Triples IRI: {_short(text)}")
            return ox.NamedNode(match.group(1))
        if first == '"':
            match = _LITERAL_RE.match(text)
            if match is None:
                raise MalformedPayload(f"not an N-Triples literal: {_short(text)}")
            lexical, datatype, lang = match.groups()
            value = _unescape(lexical)
            if lang:
                return ox.Literal(value, language=lang)
            if datatype and datatype != XSD_STRING:
                return canonical(ox.Literal(value, datatype=ox.NamedNode(datatype)))
            return ox.Literal(value)
        match = _BNODE_RE.match(text)
        if match is not None:
            return ox.NamedNode(SKOLEM + match.group(1))
    except ValueError as exc:  # pyoxigraph's verdict on an IRI or a language tag
        raise MalformedPayload(f"invalid RDF term {_short(text)}: {exc}") from None
    raise MalformedPayload(f"not an N-Triples term: {_short(text)}")


def triple(parts: object) -> OxTriple:
    """Return the pyoxigraph triple of a `[s, p, o]` list of N-Triples texts.

    Raises:
        MalformedPayload: not three terms, a literal as subject, or a predicate that is not an IRI.
    """
    if not isinstance(parts, list | tuple) or len(parts) != 3:
        raise MalformedPayload(f"a triple is a list of three terms, got {_short(parts)}")
    s, p, o = term(parts[0]), term(parts[1]), term(parts[2])
    if isinstance(s, ox.Literal) or not isinstance(p, ox.NamedNode) or p.value.startswith(SKOLEM):
        raise MalformedPayload(f"not a valid RDF triple: {_short(parts)}")
    return s, p, o


def triples(rows: list) -> list[OxTriple]:
    """Return the pyoxigraph triples of a list of `[s, p, o]` texts, parsed in bulk.

    Each text is first matched whole as one term (so no text can carry a second
    term, a comment or a line end into the document), then the lot is parsed by
    Oxigraph's N-Triples parser at once. Anything it refuses is parsed again
    term by term, for an error that names the term.

    Raises:
        MalformedPayload: as `triple`.
    """
    if all(_well_formed(row) for row in rows):
        document = "".join(f"{s} {p} {o} .\n" for s, p, o in rows)
        try:
            parsed = [
                (_skolem(q.subject), q.predicate, canonical(_skolem(q.object)))
                for q in ox.parse(document, format=ox.RdfFormat.N_TRIPLES)
            ]
        except (SyntaxError, ValueError):
            parsed = []
        if len(parsed) == len(rows):
            return parsed  # type: ignore[return-value]
    return [triple(row) for row in rows]


def _well_formed(row: object) -> bool:
    if not isinstance(row, list | tuple) or len(row) != 3:
        return False
    if isinstance(row[1], str) and row[1].startswith("<" + SKOLEM):
        return False
    for t in row:
        if not isinstance(t, str) or not t or len(t) > MAX_TERM:
            return False
        first = t[0]
        match = (
            _IRI_RE.match(t)
            if first == "<"
            else _LITERAL_RE.match(t)
            if first == '"'
            else _BNODE_RE.match(t)
        )
        if match is None:
            return False
    return True


def canonical(node: OxTerm) -> OxTerm:
    """Return a literal as the database will hold it: XSD values in their canonical form.

    Oxigraph stores numbers, booleans, dates and durations by value, so
    `"2.0"^^xsd:decimal` comes back as `"2"^^xsd:decimal`. Turning every such
    literal into that form where it enters keeps what is published, acknowledged
    and read the same term.
    """
    if isinstance(node, ox.Literal) and node.datatype.value.startswith(_XSD):
        return _canonical(node.value, node.datatype.value)
    return node


@lru_cache(maxsize=_CACHED)
def _canonical(value: str, datatype: str) -> ox.Literal:
    scratch = getattr(_SCRATCH, "store", None)
    if scratch is None:
        scratch = _SCRATCH.store = ox.Store()  # in memory, one per thread
    quad = ox.Quad(_SCRATCH_NODE, _SCRATCH_NODE, ox.Literal(value, datatype=ox.NamedNode(datatype)))
    scratch.add(quad)
    held = next(iter(scratch)).object
    scratch.clear()
    return held  # type: ignore[return-value]


_XSD = "http://www.w3.org/2001/XMLSchema#"
_SCRATCH = threading.local()
_SCRATCH_NODE = ox.NamedNode("urn:tspace:canonical")


def _skolem(node: object) -> OxTerm:
    if isinstance(node, ox.BlankNode):
        return ox.NamedNode(SKOLEM + node.value)
    return node  # type: ignore[return-value]


@lru_cache(maxsize=_CACHED)
def text(node: OxTerm) -> str:
    """Return the N-Triples text of a stored term (skolem IRIs back as blank nodes)."""
    if isinstance(node, ox.NamedNode) and node.value.startswith(SKOLEM):
        return "_:" + node.value[len(SKOLEM) :]
    if isinstance(node, ox.BlankNode):
        return "_:" + node.value
    return str(node)


def triple_text(t: OxTriple) -> list[str]:
    """Return the `[s, p, o]` N-Triples texts of a stored triple."""
    return [text(t[0]), text(t[1]), text(t[2])]


def sparql(node: OxTerm) -> str:
    """Return a term as SPARQL text (skolem IRIs stay IRIs: that is what the database holds)."""
    return str(node)


def _short(value: object) -> str:
    shown = repr(value)
    return shown if len(shown) <= 120 else shown[:117] + "..."
