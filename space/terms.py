"""RDF terms <-> their N-Triples text, the form terms take on the wire and on disk.

N-Triples is the one term syntax every RDF tool reads, so a program that knows
nothing of tspace can still produce and read our payloads. Parsing is cached:
the same few thousand terms (devices, levels, predicates) recur in every change.
The caches are small on purpose: one-off terms (a firing record's time, seq and
cause) pass through them at every answer, and 65,536 entries each grew every
process by tens of MB before levelling off.
"""

from __future__ import annotations

import re
from functools import lru_cache

from rdflib import BNode, Literal, URIRef
from rdflib.term import Node

from space.errors import MalformedPayload

Triple = tuple[Node, Node, Node]
TextTriple = tuple[str, str, str]  # a triple's N-Triples texts, as on the wire

_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\r": "\\r", "\t": "\\t"}
_ESCAPE_RE = re.compile(r'[\\"\n\r\t]')
_UNESCAPE_RE = re.compile(r'\\(u[0-9A-Fa-f]{4}|U[0-9A-Fa-f]{8}|[tbnrf"\'\\])')
_SIMPLE = {"t": "\t", "b": "\b", "n": "\n", "r": "\r", "f": "\f", '"': '"', "'": "'", "\\": "\\"}
_LITERAL_RE = re.compile(
    r'^"((?:[^"\\]|\\.)*)"(?:\^\^<([^>]*)>|@([A-Za-z]+(?:-[A-Za-z0-9]+)*))?$', re.S
)
_XSD_STRING = "http://www.w3.org/2001/XMLSchema#string"
CACHED = 4096  # terms (or triples) each cache holds: a fleet's recurring ones, not its history


def unescape(text: str) -> str:
    """Return the string an N-Triples or Turtle string body (between its quotes) stands for.

    The one reader of `\\t \\n \\" \\uXXXX ...` escapes for the term syntax, templates and
    rule files alike; an escape it does not know stays as written.
    """
    if "\\" not in text:
        return text

    def one(match: re.Match[str]) -> str:
        code = match.group(1)
        return chr(int(code[1:], 16)) if code[0] in "uU" else _SIMPLE[code]

    return _UNESCAPE_RE.sub(one, text)


@lru_cache(maxsize=CACHED)
def to_nt(term: Node) -> str:
    """Return the N-Triples text of an rdflib term."""
    if isinstance(term, URIRef):
        return f"<{term}>"
    if isinstance(term, Literal):
        if term.language:
            return literal_nt(str(term)) + f"@{term.language}"
        return literal_nt(str(term), None if term.datatype is None else str(term.datatype))
    if isinstance(term, BNode):
        return f"_:{term}"
    raise TypeError(f"not an RDF term: {term!r}")


def literal_nt(lexical: str, datatype: str | None = None) -> str:
    """Return the N-Triples text of a literal from its lexical form and datatype IRI, with
    no rdflib term made (for writers of texts: the reasoner's firing records)."""
    text = '"' + _ESCAPE_RE.sub(lambda m: _ESCAPES[m.group(0)], lexical) + '"'
    if datatype is not None and datatype != _XSD_STRING:
        return f"{text}^^<{datatype}>"
    return text


@lru_cache(maxsize=CACHED)
def from_nt(text: str) -> Node:
    """Parse the N-Triples text of one term.

    Raises:
        MalformedPayload: the text is not an N-Triples term.
    """
    if not isinstance(text, str) or not text:
        raise MalformedPayload(f"not an N-Triples term: {text!r}")
    first = text[0]
    if first == "<" and text[-1] == ">" and len(text) > 2:
        return URIRef(text[1:-1])
    if first == '"':
        match = _LITERAL_RE.match(text)
        if match is None:
            raise MalformedPayload(f"not an N-Triples literal: {text!r}")
        lexical, datatype, lang = match.groups()
        value = unescape(lexical)
        if lang:
            return Literal(value, lang=lang)
        if datatype and datatype != _XSD_STRING:
            return Literal(value, datatype=URIRef(datatype))
        return Literal(value)
    if text.startswith("_:") and len(text) > 2:
        return BNode(text[2:])
    raise MalformedPayload(f"not an N-Triples term: {text!r}")


def triple_from_nt(parts: object) -> Triple:
    """Parse a `[s, p, o]` list of N-Triples texts, checking positions.

    Raises:
        MalformedPayload: not three terms, or a literal as subject or predicate.
    """
    if not isinstance(parts, list | tuple) or len(parts) != 3:
        raise MalformedPayload(f"a triple is a list of three terms, got {parts!r}")
    try:
        return _triple(*parts)
    except TypeError:  # an unhashable part: not a term's text
        raise MalformedPayload(f"not an N-Triples term in {parts!r}") from None


@lru_cache(maxsize=CACHED)
def _triple(s_text: str, p_text: str, o_text: str) -> Triple:
    """Parse and check one triple's texts (cached whole: changes repeat the same triples)."""
    s, p, o = from_nt(s_text), from_nt(p_text), from_nt(o_text)
    if isinstance(s, Literal) or not isinstance(p, URIRef):
        raise MalformedPayload(f"not a valid RDF triple: {[s_text, p_text, o_text]!r}")
    return s, p, o


def triple_to_nt(triple: Triple) -> list[str]:
    """Return the `[s, p, o]` N-Triples texts of a triple."""
    return [to_nt(triple[0]), to_nt(triple[1]), to_nt(triple[2])]


def text_of(triple: Triple) -> TextTriple:
    """Return the `(s, p, o)` N-Triples texts of a triple of rdflib terms, as a tuple: the
    form a reader of texts keeps (`text_triple`) and compares with."""
    return (to_nt(triple[0]), to_nt(triple[1]), to_nt(triple[2]))


def text_triple(parts: object) -> TextTriple:
    """Return a `[s, p, o]` list of N-Triples texts as a tuple, checking its shape only.

    For a reader that keeps terms in their wire form: each text is parsed (and
    so checked whole) where it is first met, by that reader (`from_nt`).

    Raises:
        MalformedPayload: not three non-empty strings; a literal as subject; a
            predicate that is not an IRI.
    """
    if type(parts) in _SEQUENCES and len(parts) == 3:  # type: ignore[arg-type]
        s, p, o = parts  # type: ignore[misc]
        if type(s) is str and type(p) is str and type(o) is str and s and p and o:
            if s[0] in "<_" and p[0] == "<" and o[0] in '<_"':
                return (s, p, o)
            raise MalformedPayload(f"not a valid RDF triple: {list(parts)!r}")  # type: ignore[call-overload]
    raise MalformedPayload(f"a triple is a list of three N-Triples terms, got {parts!r}")


_SEQUENCES = (list, tuple)  # exactly: a subclass could redefine what unpacking gives
