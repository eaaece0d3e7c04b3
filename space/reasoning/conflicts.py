"""Inconsistency as a result: the rules whose head is `false` in OWL 2 RL, and what they found.

A rule with a `false` head derives a hidden triple `(CONFLICT CONFLICT f(...))`
whose functor names the rule and holds its bindings. Being derived, it is kept
and retracted like any inference (DRed), so a conflict lasts exactly as long
as the triples that clash; its derivation's premises are those triples.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rdflib import URIRef

from space.reasoning.rules import Functor, Pattern, Term
from space.reasoning.support import Support
from space.reasoning.terms import TermTable
from space.reasoning.triples import TripleStore
from space.terms import Triple

if TYPE_CHECKING:
    from space.reasoning.compile import CompiledRule

CONFLICT = URIRef("https://w3id.org/tspace/reasoning#conflict")


@dataclass(frozen=True, order=True)
class Conflict:
    """Triples that cannot all hold: the OWL 2 RL rule that says so, and the triples.

    `triples` are the rule's premises in body order, the axiom first (e.g. for
    `cax-dw`: the disjointness, then the two memberships).
    """

    rule: str
    triples: tuple[Triple, ...]

    def __str__(self) -> str:
        shown = "; ".join(" ".join(term.n3() for term in t) for t in self.triples)
        return f"{self.rule}: {shown}"


def false(rule: str, bindings: Sequence[Term]) -> Pattern:
    """Return the head that stands for `false` in rule `rule`, unique per match of `bindings`."""
    return Pattern(CONFLICT, CONFLICT, Functor(rule, tuple(bindings)))


def read_conflicts(
    terms: TermTable, store: TripleStore, support: Support, rules: Sequence[CompiledRule]
) -> tuple[Conflict, ...]:
    """Return the conflicts that hold now, sorted; costs what the conflicts are, not the state
    nor the rules (the reasoner asks at every answer).

    `rules`: the engine's, by their order.
    """
    key = terms.find(CONFLICT)
    if key is None:
        return ()
    found = []
    for value in store.spo.get(key, {}).get(key, ()):
        derivation = support.first((key, key, value))
        if derivation is None:
            continue
        rule, premises = derivation
        found.append(Conflict(rules[rule].label, tuple(terms.triple(p) for p in premises)))  # type: ignore[misc]
    return tuple(sorted(found))
