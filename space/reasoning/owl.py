"""Compile the OWL 2 RL rules an ontology needs into ordinary rules (named as in the OWL 2 spec).

Each axiom of the ontology becomes instance rules whose body starts with the
axiom triple itself, e.g. `cax-sco` for `ac:Speaker rdfs:subClassOf
ac:InteractionDevice` is `[(ac:Speaker rdfs:subClassOf ac:InteractionDevice),
(?x rdf:type ac:Speaker) -> (?x rdf:type ac:InteractionDevice)]`. So a rule is
indexed by its constant predicate and object, `why` names the axiom, and
retracting the axiom retracts what it entailed. Axioms added after the engine
was built are closed over at schema level (`scm-*`) but compile no new
instance rules: build a new engine for a new ontology.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from rdflib import OWL, RDF, RDFS, Graph
from rdflib.collection import Collection
from rdflib.term import Node

from space.reasoning.builtins.compare import NotEqual
from space.reasoning.builtins.kinds import NotLiteral
from space.reasoning.rules import Call, Item, Pattern, Rule, Term, Var

X, Y, Z = Var("x"), Var("y"), Var("z")
TYPE, SAME = RDF.type, OWL.sameAs


def _p(s: Term, p: Term, o: Term) -> Pattern:
    return Pattern(s, p, o)


def _rule(name: str, body: Sequence[Item], head: Sequence[Item]) -> Rule:
    return Rule(name, tuple(body), tuple(head))


def _object_guard(var: Var) -> Call:
    """Keep literals out of the subject position (OWL RL would put them there)."""
    return Call(NotLiteral(), (var,))


def owl_rules(tbox: Graph) -> list[Rule]:
    """Return the OWL RL rules for the axioms of `tbox`, plus equality and schema rules."""
    return [
        *_class_axioms(tbox),
        *_property_axioms(tbox),
        *_class_expressions(tbox),
        *_equality(),
        *_schema(),
    ]


def _class_axioms(g: Graph) -> Iterator[Rule]:
    for c, d in g.subject_objects(RDFS.subClassOf):
        yield _rule("cax-sco", [_p(c, RDFS.subClassOf, d), _p(X, TYPE, c)], [_p(X, TYPE, d)])
    for c, d in g.subject_objects(OWL.equivalentClass):
        axiom = _p(c, OWL.equivalentClass, d)
        yield _rule("cax-eqc1", [axiom, _p(X, TYPE, c)], [_p(X, TYPE, d)])
        yield _rule("cax-eqc2", [axiom, _p(X, TYPE, d)], [_p(X, TYPE, c)])


def _property_axioms(g: Graph) -> Iterator[Rule]:
    for p, q in g.subject_objects(RDFS.subPropertyOf):
        yield _rule("prp-spo1", [_p(p, RDFS.subPropertyOf, q), _p(X, p, Y)], [_p(X, q, Y)])
    for p, q in g.subject_objects(OWL.equivalentProperty):
        axiom = _p(p, OWL.equivalentProperty, q)
        yield _rule("prp-eqp1", [axiom, _p(X, p, Y)], [_p(X, q, Y)])
        yield _rule("prp-eqp2", [axiom, _p(X, q, Y)], [_p(X, p, Y)])
    for p, c in g.subject_objects(RDFS.domain):
        yield _rule("prp-dom", [_p(p, RDFS.domain, c), _p(X, p, Y)], [_p(X, TYPE, c)])
    for p, c in g.subject_objects(RDFS.range):
        body = [_p(p, RDFS.range, c), _p(X, p, Y), _object_guard(Y)]
        yield _rule("prp-rng", body, [_p(Y, TYPE, c)])
    for p, q in g.subject_objects(OWL.inverseOf):
        axiom = _p(p, OWL.inverseOf, q)
        yield _rule("prp-inv1", [axiom, _p(X, p, Y), _object_guard(Y)], [_p(Y, q, X)])
        yield _rule("prp-inv2", [axiom, _p(X, q, Y), _object_guard(Y)], [_p(Y, p, X)])
    for p in g.subjects(TYPE, OWL.SymmetricProperty):
        body = [_p(p, TYPE, OWL.SymmetricProperty), _p(X, p, Y), _object_guard(Y)]
        yield _rule("prp-symp", body, [_p(Y, p, X)])
    for p in g.subjects(TYPE, OWL.TransitiveProperty):
        body = [_p(p, TYPE, OWL.TransitiveProperty), _p(X, p, Y), _p(Y, p, Z)]
        yield _rule("prp-trp", body, [_p(X, p, Z)])
    for p in g.subjects(TYPE, OWL.FunctionalProperty):
        body = [
            _p(p, TYPE, OWL.FunctionalProperty),
            _p(X, p, Y),
            _p(X, p, Z),
            Call(NotEqual(), (Y, Z)),
            _object_guard(Y),
        ]
        yield _rule("prp-fp", body, [_p(Y, SAME, Z)])
    for p in g.subjects(TYPE, OWL.InverseFunctionalProperty):
        body = [
            _p(p, TYPE, OWL.InverseFunctionalProperty),
            _p(X, p, Z),
            _p(Y, p, Z),
            Call(NotEqual(), (X, Y)),
        ]
        yield _rule("prp-ifp", body, [_p(X, SAME, Y)])


def _class_expressions(g: Graph) -> Iterator[Rule]:
    for r, p in g.subject_objects(OWL.onProperty):
        on = _p(r, OWL.onProperty, p)
        for v in g.objects(r, OWL.hasValue):
            has = _p(r, OWL.hasValue, v)
            yield _rule("cls-hv1", [has, on, _p(X, TYPE, r)], [_p(X, p, v)])
            yield _rule("cls-hv2", [has, on, _p(X, p, v)], [_p(X, TYPE, r)])
        for c in g.objects(r, OWL.someValuesFrom):
            some = _p(r, OWL.someValuesFrom, c)
            if c == OWL.Thing:
                yield _rule("cls-svf2", [some, on, _p(X, p, Y)], [_p(X, TYPE, r)])
            else:
                body = [some, on, _p(X, p, Y), _p(Y, TYPE, c)]
                yield _rule("cls-svf1", body, [_p(X, TYPE, r)])
        for c in g.objects(r, OWL.allValuesFrom):
            body = [_p(r, OWL.allValuesFrom, c), on, _p(X, TYPE, r), _p(X, p, Y), _object_guard(Y)]
            yield _rule("cls-avf", body, [_p(Y, TYPE, c)])
    for c, members in g.subject_objects(OWL.intersectionOf):
        classes = _members(g, members)
        axiom = _p(c, OWL.intersectionOf, members)
        yield _rule("cls-int1", [axiom, *(_p(X, TYPE, m) for m in classes)], [_p(X, TYPE, c)])
        for m in classes:
            yield _rule("cls-int2", [axiom, _p(X, TYPE, c)], [_p(X, TYPE, m)])
    for c, members in g.subject_objects(OWL.unionOf):
        axiom = _p(c, OWL.unionOf, members)
        for m in _members(g, members):
            yield _rule("cls-uni", [axiom, _p(X, TYPE, m)], [_p(X, TYPE, c)])


def _members(g: Graph, head: Node) -> list[Node]:
    return list(Collection(g, head))


def _equality() -> Iterator[Rule]:
    s2, p, o = Var("s2"), Var("p"), Var("o")
    yield _rule("eq-sym", [_p(X, SAME, Y)], [_p(Y, SAME, X)])
    yield _rule("eq-trans", [_p(X, SAME, Y), _p(Y, SAME, Z)], [_p(X, SAME, Z)])
    yield _rule("eq-rep-s", [_p(X, SAME, s2), _p(X, p, o)], [_p(s2, p, o)])
    yield _rule("eq-rep-p", [_p(p, SAME, Y), _p(X, p, o)], [_p(X, Y, o)])
    yield _rule("eq-rep-o", [_p(o, SAME, Y), _p(X, p, o)], [_p(X, p, Y)])


def _schema() -> Iterator[Rule]:
    sco, spo, eqc, eqp = (
        RDFS.subClassOf,
        RDFS.subPropertyOf,
        OWL.equivalentClass,
        OWL.equivalentProperty,
    )
    yield _rule("scm-sco", [_p(X, sco, Y), _p(Y, sco, Z)], [_p(X, sco, Z)])
    yield _rule("scm-eqc1", [_p(X, eqc, Y)], [_p(X, sco, Y), _p(Y, sco, X)])
    yield _rule("scm-eqc2", [_p(X, sco, Y), _p(Y, sco, X)], [_p(X, eqc, Y)])
    yield _rule("scm-spo", [_p(X, spo, Y), _p(Y, spo, Z)], [_p(X, spo, Z)])
    yield _rule("scm-eqp1", [_p(X, eqp, Y)], [_p(X, spo, Y), _p(Y, spo, X)])
    yield _rule("scm-eqp2", [_p(X, spo, Y), _p(Y, spo, X)], [_p(X, eqp, Y)])
    for axis, name in ((RDFS.domain, "dom"), (RDFS.range, "rng")):
        yield _rule(f"scm-{name}1", [_p(X, axis, Y), _p(Y, sco, Z)], [_p(X, axis, Z)])
        yield _rule(f"scm-{name}2", [_p(Y, axis, Z), _p(X, spo, Y)], [_p(X, axis, Z)])
