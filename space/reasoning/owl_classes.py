"""OWL 2 RL class rules, compiled for the axioms of one ontology: tables 6 and 7 (cls-*, cax-*)."""

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
    cardinality,
    differ,
    is_literal,
    members,
    not_literal,
    p,
    rule,
)
from space.reasoning.rules import Pattern, Rule, Var

Y1, Y2 = Var("y1"), Var("y2")


def class_axioms(g: Graph) -> Iterator[Rule]:
    """Yield cax-sco, cax-eqc1/2, cax-dw and cax-adc for the axioms of `g`."""
    for c, d in g.subject_objects(RDFS.subClassOf):
        if c != d and d != OWL.Thing:
            yield rule("cax-sco", [p(c, RDFS.subClassOf, d), p(X, TYPE, c)], [p(X, TYPE, d)])
    for c, d in g.subject_objects(OWL.equivalentClass):
        if c == d:
            continue
        axiom = p(c, OWL.equivalentClass, d)
        yield rule("cax-eqc1", [axiom, p(X, TYPE, c)], [p(X, TYPE, d)])
        yield rule("cax-eqc2", [axiom, p(X, TYPE, d)], [p(X, TYPE, c)])
    for c, d in g.subject_objects(OWL.disjointWith):
        body = [p(c, OWL.disjointWith, d), p(X, TYPE, c), p(X, TYPE, d)]
        yield rule("cax-dw", body, [false("cax-dw", [X])])
    for a in g.subjects(TYPE, OWL.AllDisjointClasses):
        for head in g.objects(a, OWL.members):
            for c, d in combinations(members(g, head), 2):
                body = [p(a, OWL.members, head), p(X, TYPE, c), p(X, TYPE, d)]
                yield rule("cax-adc", body, [false("cax-adc", [X, c, d])])
    for c, d in g.subject_objects(OWL.complementOf):
        body = [p(c, OWL.complementOf, d), p(X, TYPE, c), p(X, TYPE, d)]
        yield rule("cls-com", body, [false("cls-com", [X])])


def class_expressions(g: Graph) -> Iterator[Rule]:
    """Yield the cls-* rules for the class expressions of `g`."""
    for r, prop in g.subject_objects(OWL.onProperty):
        yield from _restriction(g, r, prop)
    for c, head in g.subject_objects(OWL.intersectionOf):
        classes = members(g, head)
        axiom = p(c, OWL.intersectionOf, head)
        yield rule("cls-int1", [axiom, *(p(X, TYPE, m) for m in classes)], [p(X, TYPE, c)])
        for m in classes:
            yield rule("cls-int2", [axiom, p(X, TYPE, c)], [p(X, TYPE, m)])
    for c, head in g.subject_objects(OWL.unionOf):
        axiom = p(c, OWL.unionOf, head)
        for m in members(g, head):
            yield rule("cls-uni", [axiom, p(X, TYPE, m)], [p(X, TYPE, c)])
    for c, head in g.subject_objects(OWL.oneOf):
        axiom = p(c, OWL.oneOf, head)
        instances = members(g, head)
        if instances:
            yield rule("cls-oo", [axiom], [p(i, TYPE, c) for i in instances])


def _restriction(g: Graph, r: object, prop: object) -> Iterator[Rule]:
    on = p(r, OWL.onProperty, prop)
    for v in g.objects(r, OWL.hasValue):
        has = p(r, OWL.hasValue, v)
        yield rule("cls-hv1", [has, on, p(X, TYPE, r)], [p(X, prop, v)])
        yield rule("cls-hv2", [has, on, p(X, prop, v)], [p(X, TYPE, r)])
    for c in g.objects(r, OWL.someValuesFrom):
        some = p(r, OWL.someValuesFrom, c)
        if c == OWL.Thing:
            yield rule("cls-svf2", [some, on, p(X, prop, Y)], [p(X, TYPE, r)])
        else:
            yield rule("cls-svf1", [some, on, p(X, prop, Y), p(Y, TYPE, c)], [p(X, TYPE, r)])
    for c in g.objects(r, OWL.allValuesFrom):
        body = [p(r, OWL.allValuesFrom, c), on, p(X, TYPE, r), p(X, prop, Y), not_literal(Y)]
        yield rule("cls-avf", body, [p(Y, TYPE, c)])
    limit = cardinality(g, r, OWL.maxCardinality)
    axiom = p(r, OWL.maxCardinality, g.value(r, OWL.maxCardinality))
    if limit == 0:
        body = [axiom, on, p(X, TYPE, r), p(X, prop, Y)]
        yield rule("cls-maxc1", body, [false("cls-maxc1", [X, Y])])
    elif limit == 1:
        body = [axiom, on, p(X, TYPE, r), p(X, prop, Y1), p(X, prop, Y2), differ(Y1, Y2)]
        yield rule("cls-maxc2", [*body, not_literal(Y1)], [p(Y1, SAME, Y2)])
        clash = [*body, is_literal(Y1), is_literal(Y2)]
        yield rule("cls-maxc2", clash, [false("cls-maxc2", [X, Y1, Y2])])
    limit = cardinality(g, r, OWL.maxQualifiedCardinality)
    axiom = p(r, OWL.maxQualifiedCardinality, g.value(r, OWL.maxQualifiedCardinality))
    for c in g.objects(r, OWL.onClass):
        of = p(r, OWL.onClass, c)
        thing = c == OWL.Thing
        n = "2" if thing else "1"
        if limit == 0:
            body = [axiom, on, of, p(X, TYPE, r), p(X, prop, Y), *_typed(Y, c)]
            yield rule(f"cls-maxqc{n}", body, [false(f"cls-maxqc{n}", [X, Y])])
        elif limit == 1:
            n = "4" if thing else "3"
            body = [axiom, on, of, p(X, TYPE, r), p(X, prop, Y1), *_typed(Y1, c)]
            body += [p(X, prop, Y2), *_typed(Y2, c), differ(Y1, Y2), not_literal(Y1)]
            yield rule(f"cls-maxqc{n}", body, [p(Y1, SAME, Y2)])


def _typed(var: Var, c: object) -> list[Pattern]:
    """Return `(var rdf:type c)`, or nothing when c is owl:Thing (cls-maxqc2/4)."""
    return [] if c == OWL.Thing else [p(var, TYPE, c)]
