"""Read RDF files and triples into rdflib graphs, for the engine's ontology and data."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from rdflib import BNode, Graph, URIRef

from space._turtle import read_turtle
from space.errors import InputError
from space.reasoning.errors import unreadable
from space.reasoning.terms import FunctorValue
from space.terms import Triple


def read_graph(paths: Iterable[str | Path]) -> Graph:
    """Read RDF files (format from the suffix, Turtle by default) into one graph.

    Raises:
        InputError: a file is missing or malformed.
    """
    graph = Graph()
    for path in paths:
        if _format(Path(path)) == "turtle":
            # One-line errors with file and line (binary, not UTF-8, ill-typed literals too).
            try:
                graph += read_turtle(str(path), base=Path(path).resolve().as_uri())
            except InputError as exc:
                if isinstance(exc.__cause__, OSError):  # said as every unreadable file is
                    raise InputError(unreadable(path, exc.__cause__)) from exc.__cause__
                raise
            continue
        try:
            # Opened here, not by rdflib, which names a missing relative path by a wrong
            # absolute one; the base for relative IRIs stays the file's own IRI.
            with open(path, "rb") as handle:
                base = Path(path).resolve().as_uri()
                graph.parse(file=handle, format=_format(Path(path)), publicID=base)
        except OSError as exc:
            raise InputError(unreadable(path, exc)) from exc
        except (SyntaxError, ValueError) as exc:
            raise InputError(f"{path}: {exc}") from exc
    return graph


def _format(path: Path) -> str:
    suffix = path.suffix.lower()
    return {
        ".nt": "nt",
        ".rdf": "xml",
        ".owl": "xml",
        ".xml": "xml",
        ".n3": "n3",
        ".jsonld": "json-ld",
    }.get(suffix, "turtle")


def rdf_graph(triples: Iterable[Triple]) -> Graph:
    """Return the triples that are RDF (no literal subject, no functor) as a Graph."""
    graph = Graph()
    for triple in triples:
        s, p, o = triple
        # A rule may put a literal or a functor where RDF allows none: not in a Graph.
        if (
            isinstance(s, URIRef | BNode)
            and isinstance(p, URIRef)
            and not isinstance(o, FunctorValue)
        ):
            graph.add(triple)
    return graph
