"""Read RDF files in bulk through Oxigraph's parsers, each distinct term converted once.

rdflib's parsers cost most of a large load (25 s of 89 at a million
triples); Oxigraph's parse the same files in a fraction of that. The engine
holds rdflib terms at its edge, so each distinct Oxigraph term becomes an
rdflib term (or, read for an engine, its integer id) once, and a triple costs
three dictionary lookups.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

import pyoxigraph as ox
from rdflib import XSD, BNode, Literal, URIRef
from rdflib.term import Node

from space.errors import InputError
from space.reasoning.errors import unreadable
from space.reasoning.terms import TermTable
from space.reasoning.triples import T
from space.terms import Triple

V = TypeVar("V")

_FORMATS = {
    ".nt": ox.RdfFormat.N_TRIPLES,
    ".ttl": ox.RdfFormat.TURTLE,
    ".n3": ox.RdfFormat.N3,
    ".rdf": ox.RdfFormat.RDF_XML,
    ".owl": ox.RdfFormat.RDF_XML,
    ".xml": ox.RdfFormat.RDF_XML,
    ".nq": ox.RdfFormat.N_QUADS,
    ".trig": ox.RdfFormat.TRIG,
    ".jsonld": ox.RdfFormat.JSON_LD,
}
_STRING = str(XSD.string)


def read_triples(paths: Iterable[str | Path]) -> list[Triple]:
    """Read RDF files (format from the suffix, Turtle by default) into rdflib triples.

    Blank nodes are renamed per file, so two files' `_:b0` stay apart; named
    graphs of a dataset file are merged.

    Raises:
        InputError: a file is missing or malformed (the message names it, with
            Oxigraph's line and column).
    """
    return _read(paths, _term)


def read_ids(paths: Iterable[str | Path], terms: TermTable) -> list[T]:
    """Read RDF files as `read_triples` does, straight into the ids of `terms` (an engine's).

    Raises:
        InputError: as `read_triples`.
    """
    term_id = terms.id
    return _read(paths, lambda term, path: term_id(_term(term, path)))


def _read(paths: Iterable[str | Path], convert: Callable[[object, str | Path], V]) -> list:
    """Parse files into triples of converted terms, converting each distinct term once."""
    cache: dict[object, V] = {}
    out: list[tuple[V, V, V]] = []
    append = out.append
    for path in paths:
        fmt = _FORMATS.get(Path(path).suffix.lower(), ox.RdfFormat.TURTLE)
        base = Path(path).resolve().as_uri()
        try:
            for quad in ox.parse(path=path, format=fmt, base_iri=base, rename_blank_nodes=True):
                s, p, o = quad.subject, quad.predicate, quad.object
                s2, p2, o2 = cache.get(s), cache.get(p), cache.get(o)
                if s2 is None:
                    s2 = cache[s] = convert(s, path)
                if p2 is None:
                    p2 = cache[p] = convert(p, path)
                if o2 is None:
                    o2 = cache[o] = convert(o, path)
                append((s2, p2, o2))
        except OSError as exc:
            raise InputError(unreadable(path, exc)) from exc
        except (SyntaxError, ValueError) as exc:
            raise InputError(f"{path}: {exc}") from exc
    return out


def _term(term: object, path: str | Path) -> Node:
    if isinstance(term, ox.NamedNode):
        return URIRef(term.value)
    if isinstance(term, ox.BlankNode):
        return BNode(term.value)
    if isinstance(term, ox.Literal):
        if term.language:
            return Literal(term.value, lang=term.language)
        datatype = term.datatype.value
        if datatype == _STRING:
            return Literal(term.value)
        return Literal(term.value, datatype=URIRef(datatype))
    raise InputError(f"{path}: {term} is an RDF 1.2 triple term, which the engine does not hold")
