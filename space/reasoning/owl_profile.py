"""Name the OWL constructs of an ontology that OWL 2 RL has no rule for, instead of ignoring them.

The rules are complete for OWL 2 RL; these constructs are outside it (they
need existentials or counting above one), so nothing is derived from them.
Some class expressions are in OWL 2 RL on one side of a subclass axiom only:
an existential or a union as a subclass (its members are recognised), a
universal, a complement or a maximum as a superclass (its members are
constrained); on the other side nothing is derived from them either.
Building an engine warns about each (`UnsupportedAxiom`), naming the
construct and the class or property it is on.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator

from rdflib import OWL, RDF, RDFS, BNode, Graph
from rdflib.term import Node

from space.reasoning.owl_build import cardinality

_OUTSIDE = {
    OWL.minCardinality: "owl:minCardinality (an existential)",
    OWL.cardinality: "owl:cardinality (an existential)",
    OWL.qualifiedCardinality: "owl:qualifiedCardinality (an existential)",
    OWL.minQualifiedCardinality: "owl:minQualifiedCardinality (an existential)",
    OWL.hasSelf: "owl:hasSelf",
    OWL.disjointUnionOf: "owl:disjointUnionOf",
    OWL.withRestrictions: "owl:withRestrictions (datatype restriction)",
    OWL.datatypeComplementOf: "owl:datatypeComplementOf",
    OWL.onDataRange: "owl:onDataRange (qualified data cardinality)",
}
_SUBCLASS_ONLY = {
    OWL.someValuesFrom: "owl:someValuesFrom (an existential)",
    OWL.unionOf: "owl:unionOf",
    OWL.oneOf: "owl:oneOf",
}
_SUPERCLASS_ONLY = {
    OWL.allValuesFrom: "owl:allValuesFrom",
    OWL.complementOf: "owl:complementOf",
    OWL.maxCardinality: "owl:maxCardinality",
    OWL.maxQualifiedCardinality: "owl:maxQualifiedCardinality",
}
_TYPES = {OWL.ReflexiveProperty: "owl:ReflexiveProperty (every individual would relate to itself)"}


class UnsupportedAxiom(UserWarning):
    """An ontology uses an OWL construct outside OWL 2 RL: nothing is derived from it."""


def outside_rl(g: Graph) -> Iterator[str]:
    """Yield one message per use of a construct outside OWL 2 RL, naming it and its subject."""
    for prop, what in _OUTSIDE.items():
        for s in g.subjects(prop):
            yield f"{what} on {_name(g, s)} is outside OWL 2 RL: ignored"
    for kind, what in _TYPES.items():
        for s in g.subjects(RDF.type, kind):
            yield f"{what} {_name(g, s)} is outside OWL 2 RL: ignored"
    for prop in (OWL.maxCardinality, OWL.maxQualifiedCardinality):
        for s in g.subjects(prop):
            n = cardinality(g, s, prop)
            if n is None or n > 1:
                what = f"{g.qname(prop)} {g.value(s, prop)} on {_name(g, s)}"
                yield f"{what} is outside OWL 2 RL (0 or 1 only): ignored"
    yield from _misplaced(g)


def _misplaced(g: Graph) -> Iterator[str]:
    """Yield one message per anonymous class expression on the side of a subclass axiom RL
    leaves out (a named class defined by one, `C owl:unionOf (...)`, is taken as a name)."""
    pairs = [*g.subject_objects(RDFS.subClassOf), *g.subject_objects(OWL.equivalentClass)]
    pairs += [(b, a) for a, b in g.subject_objects(OWL.equivalentClass)]
    for sub, sup in pairs:
        for side, anon, other, left_out in (
            ("superclass", sup, sub, _SUBCLASS_ONLY),
            ("subclass", sub, sup, _SUPERCLASS_ONLY),
        ):
            if not isinstance(anon, BNode):
                continue
            for prop, what in left_out.items():
                if (anon, prop, None) in g:
                    where = f"as a {side} of {_name(g, other)}"
                    yield f"{what} ({_name(g, anon)}) {where} is outside OWL 2 RL: ignored there"


def warn_outside_rl(g: Graph) -> list[str]:
    """Warn (`UnsupportedAxiom`) about each construct outside OWL 2 RL; return the messages."""
    messages = sorted(set(outside_rl(g)))
    for message in messages:
        warnings.warn(UnsupportedAxiom(message), stacklevel=3)
    return messages


def _name(g: Graph, node: Node) -> str:
    """Return how to find a node: its IRI, or the property a restriction is on."""
    on = g.value(node, OWL.onProperty)
    if on is not None:
        return f"a restriction on {g.namespace_manager.normalizeUri(on)}"
    if isinstance(node, BNode):
        return f"an anonymous node (_:{node})"
    return g.namespace_manager.normalizeUri(node)
