"""Write the engine's conflicts into the space, as resources an agent or the HMI can subscribe to.

A conflict (`space.reasoning.Conflict`: an OWL 2 RL rule with head `false` and
the triples that clash) becomes, in the inferred graph:

    tr:conflict_<hash> a tr:Conflict ; tr:rule "cax-dw" ;
        tr:involves ac:robot1_screen ;                # each individual concerned
        tr:clash tr:conflict_<hash>_0 , ... .         # each triple, reified
    tr:conflict_<hash>_0 a rdf:Statement ; rdf:subject ... ; rdf:predicate ... ; rdf:object ... .

The name is a hash of the rule and the triples, so the same conflict has the
same name in every reasoner and after a restart. It leaves the space when the
engine no longer holds it (one of its triples was retracted). See
docs/vocabulary.md.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable

from rdflib import OWL, RDF, RDFS, Literal, Namespace, URIRef
from rdflib.term import Node

from space import Triple, triple_to_nt
from space.reasoning import Conflict

TR = Namespace("https://w3id.org/tspace/reasoning#")
_VOCABULARIES = (str(RDF), str(RDFS), str(OWL))


def conflict_triples(conflict: Conflict) -> tuple[Triple, ...]:
    """Return the triples that describe one conflict in the space."""
    lines = sorted(" ".join(triple_to_nt(t)) for t in conflict.triples)
    text = "\n".join([conflict.rule, *lines])
    node = TR[f"conflict_{hashlib.sha1(text.encode()).hexdigest()[:16]}"]
    out: list[Triple] = [(node, RDF.type, TR.Conflict), (node, TR.rule, Literal(conflict.rule))]
    involved: dict[Node, None] = {}
    for i, (s, p, o) in enumerate(conflict.triples):
        statement = URIRef(f"{node}_{i}")
        out += [
            (node, TR.clash, statement),
            (statement, RDF.type, RDF.Statement),
            (statement, RDF.subject, s),
            (statement, RDF.predicate, p),
            (statement, RDF.object, o),
        ]
        for term in (s, o):
            if not isinstance(term, Literal) and not str(term).startswith(_VOCABULARIES):
                involved.setdefault(term)
    out += [(node, TR.involves, term) for term in involved]
    return tuple(out)


class ConflictRecords:
    """Remember the conflicts written, to write only what changed."""

    def __init__(self) -> None:
        self._held: dict[Conflict, tuple[Triple, ...]] = {}

    def update(self, now: Iterable[Conflict]) -> tuple[list[Triple], list[Triple], list[Conflict]]:
        """Return the triples to add, those to remove, and the new conflicts."""
        current = set(now)
        new = [c for c in current if c not in self._held]
        gone = [c for c in self._held if c not in current]
        added = [t for c in new for t in self._held.setdefault(c, conflict_triples(c))]
        removed = [t for c in gone for t in self._held.pop(c)]
        return added, removed, sorted(new)

    def triples(self) -> set[Triple]:
        """Return the triples of the conflicts held."""
        return {t for triples in self._held.values() for t in triples}
