"""Encode terms as small integers, so joins compare and hash ints instead of rdflib objects.

Each term also gets a value key, computed once, that makes `1`, `1.0` and
`"1"^^xsd:int` equal for the builtins that compare by value. A literal typed
xsd:string is the simple literal of the same text (RDF 1.1, and `space.terms` on
the wire), so both get one id: they match, compare and `noValue` alike.

A term also has its N-Triples text (`text_id`, `texts`): a caller that keeps
terms in their wire form (the reasoner agent) goes from text to id and back
with a dict and a list, parsing a term once, when it is first seen.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import date, datetime, time
from decimal import Decimal

from rdflib import XSD, Literal
from rdflib.term import Node

from space.errors import MalformedPayload
from space.terms import TextTriple, from_nt, to_nt


@dataclass(frozen=True)
class FunctorValue:
    """A functor built by a rule head: a name and encoded arguments, visible to rules only."""

    name: str
    args: tuple[int, ...]


Value = Node | FunctorValue
_XSD_STRING = XSD.string  # looked up once: the namespace's attribute access is Python code
_NT = to_nt.__wrapped__  # each term once: not through (and not evicting) the shared cache


def simple(term: Value) -> Value:
    """Return the simple literal for a literal typed xsd:string, else the term itself."""
    if isinstance(term, Literal) and term.datatype == _XSD_STRING:
        return Literal(str(term))
    return term


def value_key(term: Value) -> object:
    """Return what `equal` compares: the number or time of a typed literal, else the term."""
    if not isinstance(term, Literal):
        return term
    value = term.value
    if isinstance(value, bool):
        return ("boolean", value)
    if isinstance(value, int | float | Decimal | datetime | date | time):
        return value
    return ("literal", str(term), term.language, term.datatype)


class TermTable:
    """Give every term an integer id, both ways, and its value key.

    Ids are never reused, so an id held by a derivation stays meaningful.
    """

    def __init__(self) -> None:
        self._ids: dict[Value, int] = {}
        self._terms: list[Value] = []
        self.keys: list[object] = []
        self.functors: set[int] = set()
        self.hidden: set[int] = set()  # nodes `hide` keeps out of listings (as Jena's FB graph)
        self._by_text: dict[str, int] = {}
        self._texts: list[str] = []  # by id, filled up to the newest id by `texts()`

    def __len__(self) -> int:
        return len(self._terms)

    def id(self, term: Value) -> int:
        """Return the id of a term, giving it one if it has none."""
        found = self._ids.get(term)
        if found is not None:
            return found
        plain = simple(term)
        if plain is not term:
            found = self._ids[term] = self.id(plain)
            return found
        new = len(self._terms)
        self._ids[term] = new
        self._terms.append(term)
        self.keys.append(value_key(term))
        if isinstance(term, FunctorValue):
            self.functors.add(new)
        return new

    def text_id(self, text: str) -> int:
        """Return the id of a term given as N-Triples text, parsing it only when new here.

        Raises:
            MalformedPayload: the text is not an N-Triples term.
        """
        found = self._by_text.get(text)
        if found is None:
            found = self._by_text[text] = self.id(from_nt(text))
        return found

    def encode_texts(self, triples: Iterable[Sequence[str]]) -> list[tuple[int, int, int]]:
        """Return the ids of triples given as N-Triples texts, all of them or none.

        Raises:
            MalformedPayload: a text is not an N-Triples term, a subject is a literal or
                a predicate not an IRI (terms met before the bad one keep their ids).
        """
        id_of, out = self.text_id, []
        try:
            for s, p, o in triples:
                if s[0] == '"' or p[0] != "<":
                    raise MalformedPayload(f"not a valid RDF triple: {[s, p, o]!r}")
                out.append((id_of(s), id_of(p), id_of(o)))
        except (TypeError, ValueError, IndexError):  # not three texts
            raise MalformedPayload(f"not a triple of N-Triples texts in {triples!r}") from None
        return out

    def canonical(self, triples: Iterable[Sequence[str]]) -> list[TextTriple]:
        """Return triples given as N-Triples texts in this table's form of each term.

        One term has several texts (Oxigraph writes a UTC dateTime with `Z` and
        `1.0` as `"1"^^xsd:double`, rdflib `+00:00` and `"1.0"`); the table gives
        each id one. A caller that keys texts of its own (who wrote what) and compares
        them with the engine's needs them in that form.

        Raises:
            MalformedPayload: as `encode_texts`.
        """
        ids = self.encode_texts(triples)
        texts = self.texts()  # after: the new terms' texts too
        return [(texts[s], texts[p], texts[o]) for s, p, o in ids]

    def find_text(self, text: str) -> int | None:
        """Return the id of a term given as N-Triples text, or None if it was never seen."""
        found = self._by_text.get(text)
        if found is None:
            try:
                found = self.find(from_nt(text))
            except MalformedPayload:  # not a term, so never seen
                return None
        return found

    def texts(self) -> list[str]:
        """Return the N-Triples texts by id (read only; a functor's is empty: never listed)."""
        texts, terms = self._texts, self._terms
        for i in range(len(texts), len(terms)):
            term = terms[i]
            texts.append("" if isinstance(term, FunctorValue) else _NT(term))
        return texts

    def text_triple(self, t: tuple[int, int, int]) -> TextTriple:
        """Return the N-Triples texts of an encoded triple."""
        texts = self.texts()
        return (texts[t[0]], texts[t[1]], texts[t[2]])

    def find(self, term: Value) -> int | None:
        """Return the id of a term, or None if it was never seen."""
        found = self._ids.get(term)
        return found if found is not None else self._ids.get(simple(term))

    def shown(self, t: tuple[int, int, int]) -> bool:
        """Tell whether a triple is listed: no functor value, no hidden node in it (Jena lists
        neither; rules see both)."""
        functors, hidden = self.functors, self.hidden
        if t[2] in functors or t[0] in functors:
            return False
        return not hidden or (t[0] not in hidden and t[1] not in hidden and t[2] not in hidden)

    @property
    def names(self) -> list[Value]:
        """Return the terms by id (read only): for loops that decode many triples."""
        return self._terms

    def term(self, i: int) -> Value:
        """Return the term of an id."""
        return self._terms[i]

    def triple(self, t: tuple[int, int, int]) -> tuple[Value, Value, Value]:
        """Return the terms of an encoded triple."""
        terms = self._terms
        return (terms[t[0]], terms[t[1]], terms[t[2]])

    def same_value(self, a: int, b: int) -> bool:
        """Tell whether two terms are equal by value (`1` equals `1.0`)."""
        return a == b or self.keys[a] == self.keys[b]
