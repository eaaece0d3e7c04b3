"""Encode terms as small integers, so joins compare and hash ints instead of rdflib objects.

Each term also gets a value key, computed once, that makes `1`, `1.0` and
`"1"^^xsd:int` equal for the builtins that compare by value. A literal typed
xsd:string is the simple literal of the same text (RDF 1.1, and `space.terms` on
the wire), so both get one id: they match, compare and `noValue` alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date, datetime, time
from decimal import Decimal

from rdflib import XSD, Literal
from rdflib.term import Node


@dataclass(frozen=True)
class FunctorValue:
    """A functor built by a rule head: a name and encoded arguments, visible to rules only."""

    name: str
    args: tuple[int, ...]


Value = Node | FunctorValue
_XSD_STRING = XSD.string  # looked up once: the namespace's attribute access is Python code


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
