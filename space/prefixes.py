"""Prefix tables: the short names that make IRIs readable in keys and output."""

from __future__ import annotations

import re
from collections.abc import Mapping

from rdflib import URIRef

_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_.\-]*$")

WELL_KNOWN: dict[str, str] = {
    "rdf": "http://www.w3.org/1999/02/22-rdf-syntax-ns#",
    "rdfs": "http://www.w3.org/2000/01/rdf-schema#",
    "owl": "http://www.w3.org/2002/07/owl#",
    "xsd": "http://www.w3.org/2001/XMLSchema#",
}


class PrefixMap:
    """A prefix table that compacts IRIs to `pfx:local` and expands them back.

    The first binding of a name wins, so every process that has seen the same
    bindings compacts an IRI to the same text.
    """

    def __init__(self, bindings: Mapping[str, str] | None = None) -> None:
        self._by_name: dict[str, str] = dict(WELL_KNOWN)
        # Longest namespace first, so nested namespaces compact to the most specific one.
        self._by_ns: list[tuple[str, str]] = []
        self.chunks: dict[object, str] = {}
        self._rebuild()
        if bindings:
            self.update(bindings)

    def _rebuild(self) -> None:
        self.chunks = {}  # callers' memo of texts made with these bindings (`keys.term_chunk`)
        self._by_ns = sorted(((ns, n) for n, ns in self._by_name.items()), key=lambda x: -len(x[0]))

    def update(self, bindings: Mapping[str, str]) -> dict[str, str]:
        """Add the bindings whose name is new; return those actually added."""
        added = {}
        for name, ns in bindings.items():
            if not isinstance(name, str) or not _NAME_RE.match(name) or name in self._by_name:
                continue
            if not isinstance(ns, str) or not ns:
                continue
            added[name] = ns
            self._by_name[name] = ns
        if added:
            self._rebuild()
        return added

    def as_dict(self) -> dict[str, str]:
        """Return the bindings, name -> namespace IRI."""
        return dict(self._by_name)

    def compact(self, iri: str) -> str | None:
        """Return `pfx:local` for an IRI, or None when no namespace covers it."""
        for ns, name in self._by_ns:
            if iri.startswith(ns) and len(iri) > len(ns):
                return f"{name}:{iri[len(ns) :]}"
        return None

    def expand(self, pname: str) -> URIRef | None:
        """Return the IRI of `pfx:local`, or None when the prefix is unknown."""
        name, sep, local = pname.partition(":")
        ns = self._by_name.get(name) if sep else None
        return URIRef(ns + local) if ns is not None else None
