"""OWL 2 RL property rules, compiled for the axioms of one ontology: table 5 (prp-*)."""

from __future__ import annotations

from collections.abc import Iterator
from itertools import combinations

from rdflib import OWL, RDFS, Graph

from space.reasoning.conflicts import false
from space.reasoning.owl_build import (
    SAME,
    TYPE,
    X,
    Y,
    Z,
    differ,
    is_literal,
    members,
    not_literal,
    p,
    rule,
)
from space.reasoning.rules import Pattern, Rule, Var


def property_axioms(g: Graph) -> Iterator[Rule]:
    """Yield the prp-* rules for the property axioms of `g`."""
    yield from _hierarchy(g)
    yield from _characteristics(g)
    yield from _disjointness(g)
    yield from _chains_and_keys(g)


def _hierarchy(g: Graph) -> Iterator[Rule]:
    for a, b in g.subject_objects(RDFS.subPropertyOf):
        if a != b:
            yield rule("prp-spo1", [p(a, RDFS.subPropertyOf, b), p(X, a, Y)], [p(X, b, Y)])
    for a, b in g.subject_objects(OWL.equivalentProperty):
        if a == b:
            continue
        axiom = p(a, OWL.equivalentProperty, b)
        yield rule("prp-eqp1", [axiom, p(X, a, Y)], [p(X, b, Y)])
        yield rule("prp-eqp2", [axiom, p(X, b, Y)], [p(X, a, Y)])
    for a, c in g.subject_objects(RDFS.domain):
        yield rule("prp-dom", [p(a, RDFS.domain, c), p(X, a, Y)], [p(X, TYPE, c)])
    for a, c in g.subject_objects(RDFS.range):
        body = [p(a, RDFS.range, c), p(X, a, Y), not_literal(Y)]
        yield rule("prp-rng", body, [p(Y, TYPE, c)])
    for a, b in g.subject_objects(OWL.inverseOf):
        axiom = p(a, OWL.inverseOf, b)
        yield rule("prp-inv1", [axiom, p(X, a, Y), not_literal(Y)], [p(Y, b, X)])
        yield rule("prp-inv2", [axiom, p(X, b, Y), not_literal(Y)], [p(Y, a, X)])


def _characteristics(g: Graph) -> Iterator[Rule]:
    def typed(kind: object) -> Iterator[tuple[object, Pattern]]:
        for a in g.subjects(TYPE, kind):
            yield a, p(a, TYPE, kind)

    for a, axiom in typed(OWL.SymmetricProperty):
        yield rule("prp-symp", [axiom, p(X, a, Y), not_literal(Y)], [p(Y, a, X)])
    for a, axiom in typed(OWL.TransitiveProperty):
        yield rule("prp-trp", [axiom, p(X, a, Y), p(Y, a, Z)], [p(X, a, Z)])
    for a, axiom in typed(OWL.FunctionalProperty):
        body = [axiom, p(X, a, Y), p(X, a, Z), differ(Y, Z), not_literal(Y)]
        yield rule("prp-fp", body, [p(Y, SAME, Z)])
        # Two different literal values cannot be the same (dt-diff with eq-diff1).
        body = [axiom, p(X, a, Y), p(X, a, Z), differ(Y, Z), is_literal(Y), is_literal(Z)]
        yield rule("prp-fp", body, [false("prp-fp", [X, Y, Z])])
    for a, axiom in typed(OWL.InverseFunctionalProperty):
        body = [axiom, p(X, a, Z), p(Y, a, Z), differ(X, Y)]
        yield rule("prp-ifp", body, [p(X, SAME, Y)])
    for a, axiom in typed(OWL.IrreflexiveProperty):
        yield rule("prp-irp", [axiom, p(X, a, X)], [false("prp-irp", [X])])
    for a, axiom in typed(OWL.AsymmetricProperty):
        yield rule("prp-asyp", [axiom, p(X, a, Y), p(Y, a, X)], [false("prp-asyp", [X, Y])])


def _disjointness(g: Graph) -> Iterator[Rule]:
    for a, b in g.subject_objects(OWL.propertyDisjointWith):
        body = [p(a, OWL.propertyDisjointWith, b), p(X, a, Y), p(X, b, Y)]
        yield rule("prp-pdw", body, [false("prp-pdw", [X, Y])])
    for d in g.subjects(TYPE, OWL.AllDisjointProperties):
        for head in g.objects(d, OWL.members):
            for a, b in combinations(members(g, head), 2):
                body = [p(d, OWL.members, head), p(X, a, Y), p(X, b, Y)]
                yield rule("prp-adp", body, [false("prp-adp", [X, Y, a, b])])
    # By its three triples, typed owl:NegativePropertyAssertion or not (as prp-npa1/2 read it).
    for n, source in g.subject_objects(OWL.sourceIndividual):
        prop = g.value(n, OWL.assertionProperty)
        if prop is None:
            continue
        for kind, name in ((OWL.targetIndividual, "prp-npa1"), (OWL.targetValue, "prp-npa2")):
            for target in g.objects(n, kind):
                body = [
                    p(n, OWL.sourceIndividual, source),
                    p(n, OWL.assertionProperty, prop),
                    p(n, kind, target),
                    p(source, prop, target),
                ]
                yield rule(name, body, [false(name, [n])])


def _chains_and_keys(g: Graph) -> Iterator[Rule]:
    for a, head in g.subject_objects(OWL.propertyChainAxiom):
        chain = members(g, head)
        if not chain:
            continue
        links = [Var(f"u{i}") for i in range(len(chain) + 1)]
        body = [p(a, OWL.propertyChainAxiom, head)]
        body += [p(links[i], link, links[i + 1]) for i, link in enumerate(chain)]
        yield rule("prp-spo2", body, [p(links[0], a, links[-1])])
    for c, head in g.subject_objects(OWL.hasKey):
        keys = members(g, head)
        if not keys:
            continue
        values = [Var(f"z{i}") for i in range(len(keys))]
        body = [p(c, OWL.hasKey, head), p(X, TYPE, c), p(Y, TYPE, c)]
        body += [p(X, k, v) for k, v in zip(keys, values, strict=True)]
        body += [p(Y, k, v) for k, v in zip(keys, values, strict=True)]
        yield rule("prp-key", [*body, differ(X, Y)], [p(X, SAME, Y)])
