"""The robot vocabulary (`ac:`, docs/vocabulary.md) in one place, and how robots are named.

Every agent, the runtime and the simulators take the namespace from here, so a
renamed namespace or a new firing-record property is one edit.
"""

from __future__ import annotations

from decimal import Decimal

from rdflib import RDF, Literal, Namespace, URIRef

from space import PrefixMap


class Vocabulary(Namespace):
    """An rdflib `Namespace` that makes each of its terms once.

    `AC.level` on a plain Namespace builds and checks a new URIRef (3.5 us); an
    agent's tick reads dozens, and a changeset's handling hundreds.
    """

    def __getattr__(self, name: str) -> URIRef:
        term = super().__getattr__(name)
        self.__dict__[name] = term
        return term


AC = Vocabulary("https://w3id.org/tspace/selfconfig#")
PREFIXES = PrefixMap({"ac": str(AC)})
# rdf:type, looked up once: an rdflib namespace's attribute costs ~1 us, and agents test it
# once a triple.
RDF_TYPE = RDF.type

# Subjects of the reasoner's firing records (`ac:firing_N`, `ac:firing_ROBOT_N`).
RECORD_PREFIX = str(AC) + "firing_"
FIRING_PROPERTIES = frozenset({AC.rule_names, AC.cause, AC.fired_at, AC.firing_seq, AC.robot})


_LITERALS: dict[tuple[type, str], Literal] = {}
_LITERALS_MAX = 4096  # a robot's readings: its few modes, levels and grid values


def literal(value: str | float | Decimal) -> Literal:
    """Return the Literal of a reading, each made once.

    A monitor writes the same few values every tick, and `Literal(...)` takes
    4 us to make and check each. Keyed by type and text: `Decimal("0.3")` and
    `Decimal("0.30")` are equal numbers but two literals.
    """
    key = (type(value), str(value))
    found = _LITERALS.get(key)
    if found is None:
        if len(_LITERALS) >= _LITERALS_MAX:
            _LITERALS.clear()
        found = _LITERALS[key] = Literal(value)
    return found


def robot_iri(text: str) -> URIRef:
    """Return the IRI of a robot given as an IRI, `ac:name` or a bare local name."""
    if "://" in text or text.startswith("urn:"):
        return URIRef(text)
    return AC[text.removeprefix("ac:")]


def local_name(iri: URIRef) -> str:
    """Return the part of an IRI after its last `#` or `/`."""
    return str(iri).rsplit("#", 1)[-1].rsplit("/", 1)[-1]
