"""OWL 2 RL rules that do not depend on the ontology's axioms: equality, schema, axiomatic triples.

Tables 4 (eq-*), 8 (dt-type1) and 9 (scm-*), plus the axiom-specific schema
rules over lists (scm-int, scm-uni) and eq-diff2/3 over owl:AllDifferent.
eq-ref is not stored (every term would get a triple): `RuleEngine.__contains__`
answers `(x owl:sameAs x)` for every term in the state, and `x owl:differentFrom
x` is the conflict eq-diff1 would find with it.
"""

from __future__ import annotations

from collections.abc import Iterator
from itertools import combinations

from rdflib import OWL, RDF, RDFS, XSD, Graph

from space.reasoning.conflicts import false
from space.reasoning.owl_build import SAME, TYPE, X, Y, Z, members, p, rule
from space.reasoning.rules import Rule, Var

SCO, SPO, EQC, EQP = (
    RDFS.subClassOf,
    RDFS.subPropertyOf,
    OWL.equivalentClass,
    OWL.equivalentProperty,
)
ANNOTATIONS = (
    RDFS.label,
    RDFS.comment,
    RDFS.seeAlso,
    RDFS.isDefinedBy,
    OWL.deprecated,
    OWL.versionInfo,
    OWL.priorVersion,
    OWL.backwardCompatibleWith,
    OWL.incompatibleWith,
)
# The datatypes of OWL 2 RL (Profiles, 4.2), typed by dt-type1.
DATATYPES = (
    RDF.PlainLiteral,
    RDF.XMLLiteral,
    RDFS.Literal,
    *(
        XSD[name]
        for name in (
            "decimal integer nonNegativeInteger nonPositiveInteger positiveInteger "
            "negativeInteger long int short byte unsignedLong unsignedInt unsignedShort "
            "unsignedByte float double string normalizedString token language Name NCName "
            "NMTOKEN boolean hexBinary base64Binary anyURI dateTime dateTimeStamp"
        ).split()
    ),
)


def axiomatic() -> Iterator[Rule]:
    """Yield the body-less rules whose heads hold from the start (cls-thing, prp-ap, ...)."""
    yield rule("cls-thing", [], [p(OWL.Thing, TYPE, OWL.Class)])
    yield rule("cls-nothing1", [], [p(OWL.Nothing, TYPE, OWL.Class)])
    yield rule("prp-ap", [], [p(a, TYPE, OWL.AnnotationProperty) for a in ANNOTATIONS])
    yield rule("dt-type1", [], [p(d, TYPE, RDFS.Datatype) for d in DATATYPES])


def equality(g: Graph) -> Iterator[Rule]:
    """Yield eq-sym, eq-trans, eq-rep-*, eq-diff1..3 and the cls-nothing2 conflict."""
    s2, prop, o = Var("s2"), Var("p"), Var("o")
    yield rule("eq-sym", [p(X, SAME, Y)], [p(Y, SAME, X)])
    yield rule("eq-trans", [p(X, SAME, Y), p(Y, SAME, Z)], [p(X, SAME, Z)])
    yield rule("eq-rep-s", [p(X, SAME, s2), p(X, prop, o)], [p(s2, prop, o)])
    yield rule("eq-rep-p", [p(prop, SAME, Y), p(X, prop, o)], [p(X, Y, o)])
    yield rule("eq-rep-o", [p(o, SAME, Y), p(X, prop, o)], [p(X, prop, Y)])
    body = [p(X, SAME, Y), p(X, OWL.differentFrom, Y)]
    yield rule("eq-diff1", body, [false("eq-diff1", [X, Y])])
    # With eq-ref (x sameAs x), which is not stored.
    yield rule("eq-diff1", [p(X, OWL.differentFrom, X)], [false("eq-diff1", [X, X])])
    yield rule("cls-nothing2", [p(X, TYPE, OWL.Nothing)], [false("cls-nothing2", [X])])
    for a in g.subjects(TYPE, OWL.AllDifferent):
        for kind, name in ((OWL.members, "eq-diff2"), (OWL.distinctMembers, "eq-diff3")):
            for head in g.objects(a, kind):
                for y1, y2 in combinations(members(g, head), 2):
                    body = [p(a, kind, head), p(y1, SAME, y2)]
                    yield rule(name, body, [false(name, [a, y1, y2])])


def schema(g: Graph) -> Iterator[Rule]:
    """Yield the scm-* rules (those over lists for the axioms of `g`)."""
    c1, c2, p1, p2 = Var("c1"), Var("c2"), Var("p1"), Var("p2")
    yield rule(
        "scm-cls",
        [p(X, TYPE, OWL.Class)],
        [p(X, SCO, X), p(X, EQC, X), p(X, SCO, OWL.Thing), p(OWL.Nothing, SCO, X)],
    )
    yield rule("scm-sco", [p(X, SCO, Y), p(Y, SCO, Z)], [p(X, SCO, Z)])
    yield rule("scm-eqc1", [p(X, EQC, Y)], [p(X, SCO, Y), p(Y, SCO, X)])
    yield rule("scm-eqc2", [p(X, SCO, Y), p(Y, SCO, X)], [p(X, EQC, Y)])
    for kind, name in ((OWL.ObjectProperty, "scm-op"), (OWL.DatatypeProperty, "scm-dp")):
        yield rule(name, [p(X, TYPE, kind)], [p(X, SPO, X), p(X, EQP, X)])
    yield rule("scm-spo", [p(X, SPO, Y), p(Y, SPO, Z)], [p(X, SPO, Z)])
    yield rule("scm-eqp1", [p(X, EQP, Y)], [p(X, SPO, Y), p(Y, SPO, X)])
    yield rule("scm-eqp2", [p(X, SPO, Y), p(Y, SPO, X)], [p(X, EQP, Y)])
    for axis, name in ((RDFS.domain, "dom"), (RDFS.range, "rng")):
        yield rule(f"scm-{name}1", [p(X, axis, Y), p(Y, SCO, Z)], [p(X, axis, Z)])
        yield rule(f"scm-{name}2", [p(Y, axis, Z), p(X, SPO, Y)], [p(X, axis, Z)])
    on1, on2 = p(c1, OWL.onProperty, p1), p(c2, OWL.onProperty, p2)
    body = [p(c1, OWL.hasValue, X), on1, p(c2, OWL.hasValue, X), on2, p(p1, SPO, p2)]
    yield rule("scm-hv", body, [p(c1, SCO, c2)])
    same_on = p(c2, OWL.onProperty, p1)
    body = [p(c1, OWL.someValuesFrom, X), on1, p(c2, OWL.someValuesFrom, Y), same_on, p(X, SCO, Y)]
    yield rule("scm-svf1", body, [p(c1, SCO, c2)])
    body = [p(c1, OWL.someValuesFrom, X), on1, p(c2, OWL.someValuesFrom, X), on2, p(p1, SPO, p2)]
    yield rule("scm-svf2", body, [p(c1, SCO, c2)])
    body = [p(c1, OWL.allValuesFrom, X), on1, p(c2, OWL.allValuesFrom, Y), same_on, p(X, SCO, Y)]
    yield rule("scm-avf1", body, [p(c1, SCO, c2)])
    body = [p(c1, OWL.allValuesFrom, X), on1, p(c2, OWL.allValuesFrom, X), on2, p(p1, SPO, p2)]
    yield rule("scm-avf2", body, [p(c2, SCO, c1)])
    for c, head in g.subject_objects(OWL.intersectionOf):
        heads = [p(c, SCO, m) for m in members(g, head)]
        if heads:
            yield rule("scm-int", [p(c, OWL.intersectionOf, head)], heads)
    for c, head in g.subject_objects(OWL.unionOf):
        heads = [p(m, SCO, c) for m in members(g, head)]
        if heads:
            yield rule("scm-uni", [p(c, OWL.unionOf, head)], heads)
