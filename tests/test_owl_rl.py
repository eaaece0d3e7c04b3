"""OWL RL entailments: each axiom kind, kept incrementally, and owlrl as the oracle."""

from __future__ import annotations

from pathlib import Path

import owlrl
import pytest
from rdflib import OWL, RDF, RDFS, BNode, Graph, Literal, Namespace

from space.reasoning import RuleEngine, read_graph

EX = Namespace("http://example.org/")
ROOT = Path(__file__).resolve().parents[1]
AC = "https://w3id.org/tspace/selfconfig#"


def engine(*axioms) -> RuleEngine:
    tbox = Graph()
    for axiom in axioms:
        tbox.add(axiom)
    e = RuleEngine([], tbox)
    e.load([])
    return e


def test_subclass_domain_range_and_subproperty():
    e = engine(
        (EX.Speaker, RDFS.subClassOf, EX.InteractionDevice),
        (EX.InteractionDevice, RDFS.subClassOf, EX.Device),
        (EX.has_speaker, RDFS.subPropertyOf, EX.has_device),
        (EX.has_device, RDFS.domain, EX.Robot),
        (EX.has_device, RDFS.range, EX.Device),
    )
    e.apply(added=[(EX.r, EX.has_speaker, EX.s), (EX.s, RDF.type, EX.Speaker)])
    for triple in [
        (EX.r, EX.has_device, EX.s),
        (EX.r, RDF.type, EX.Robot),
        (EX.s, RDF.type, EX.InteractionDevice),
        (EX.s, RDF.type, EX.Device),
        (EX.Speaker, RDFS.subClassOf, EX.Device),
    ]:
        assert triple in e
    why = e.why((EX.s, RDF.type, EX.InteractionDevice))
    assert why.rule == "cax-sco"
    assert (EX.Speaker, RDFS.subClassOf, EX.InteractionDevice) in why.premises


def test_equivalence_inverse_and_symmetry():
    e = engine(
        (EX.Person, OWL.equivalentClass, EX.Human),
        (EX.knows, OWL.equivalentProperty, EX.acquainted),
        (EX.parent, OWL.inverseOf, EX.child),
        (EX.near, RDF.type, OWL.SymmetricProperty),
    )
    e.apply(
        added=[
            (EX.a, RDF.type, EX.Human),
            (EX.a, EX.knows, EX.b),
            (EX.a, EX.parent, EX.c),
            (EX.a, EX.near, EX.d),
        ]
    )
    for triple in [
        (EX.a, RDF.type, EX.Person),
        (EX.a, EX.acquainted, EX.b),
        (EX.c, EX.child, EX.a),
        (EX.d, EX.near, EX.a),
    ]:
        assert triple in e


def test_transitivity_is_retracted_through_recursion():
    e = engine((EX.inside, RDF.type, OWL.TransitiveProperty))
    chain = [(EX.a, EX.inside, EX.b), (EX.b, EX.inside, EX.c), (EX.c, EX.inside, EX.d)]
    e.apply(added=chain)
    assert (EX.a, EX.inside, EX.d) in e
    e.apply(removed=[(EX.b, EX.inside, EX.c)])
    assert set(e.graph.subject_objects(EX.inside)) == {(EX.a, EX.b), (EX.c, EX.d)}


def test_functional_property_makes_individuals_the_same_and_replaces_them():
    e = engine((EX.dock, RDF.type, OWL.FunctionalProperty))
    e.apply(added=[(EX.r, EX.dock, EX.d1), (EX.r, EX.dock, EX.d2), (EX.d1, EX.label, Literal("A"))])
    assert (EX.d1, OWL.sameAs, EX.d2) in e
    assert (EX.d2, EX.label, Literal("A")) in e
    e.apply(removed=[(EX.r, EX.dock, EX.d2)])
    assert (EX.d1, OWL.sameAs, EX.d2) not in e
    assert (EX.d2, EX.label, Literal("A")) not in e


def test_has_value_restrictions_classify_both_ways():
    restriction = BNode()
    e = engine(
        (EX.StandbyDevice, OWL.equivalentClass, restriction),
        (restriction, RDF.type, OWL.Restriction),
        (restriction, OWL.onProperty, EX.mode),
        (restriction, OWL.hasValue, Literal("stand-by")),
    )
    e.apply(added=[(EX.s, EX.mode, Literal("stand-by")), (EX.t, RDF.type, EX.StandbyDevice)])
    assert (EX.s, RDF.type, EX.StandbyDevice) in e
    assert (EX.t, EX.mode, Literal("stand-by")) in e
    e.apply(removed=[(EX.s, EX.mode, Literal("stand-by"))])
    assert (EX.s, RDF.type, EX.StandbyDevice) not in e


def covered(triple) -> bool:
    """Tell whether a triple is of the kinds both reasoners derive (instances and schema)."""
    s, p, o = triple
    if isinstance(s, Literal) or s == o or o == OWL.Thing or s == OWL.Nothing:
        return False
    if p == RDF.type:
        return str(o).startswith(AC) or isinstance(o, BNode)
    schema = (RDFS.subClassOf, RDFS.subPropertyOf, RDFS.domain, RDFS.range, OWL.sameAs)
    return str(p).startswith(AC) or p in schema


def owlrl_closure(*graphs: Graph) -> set:
    g = Graph()
    for graph in graphs:
        for triple in graph:
            g.add(triple)
    owlrl.DeductiveClosure(owlrl.OWLRL_Semantics).expand(g)
    return {t for t in g if covered(t)}


@pytest.fixture(scope="module")
def project():
    ontology = read_graph([ROOT / "ontology" / "selfconfig.ttl"])
    robot = read_graph([ROOT / "ontology" / "robots" / "hospital.ttl"])
    return ontology, robot


def test_entailments_equal_owlrl_on_the_project_ontology(project):
    ontology, robot = project
    e = RuleEngine([], ontology)
    e.load(robot)
    ours = {t for t in e.graph if covered(t)}
    assert ours == owlrl_closure(ontology, robot)


def test_entailments_still_equal_owlrl_after_incremental_updates(project):
    ontology, robot = project
    ac = Namespace(AC)
    e = RuleEngine([], ontology)
    e.load(robot)
    e.apply(
        added=[(ac.robot1_screen, ac.running_mode, Literal("stand-by"))],
        removed=[
            (ac.robot1_screen, ac.running_mode, Literal("active")),
            (ac.robot1, ac.has_device, ac.robot1_laser),
            (ac.robot1_laser, RDF.type, ac.LaserScanner),
        ],
    )
    asserted = Graph()
    for triple in e.triples(origin=None):
        if e.why(triple).asserted:
            asserted.add(triple)
    ours = {t for t in e.graph if covered(t)}
    assert ours == owlrl_closure(asserted)
    assert (ac.robot1_screen, RDF.type, ac.StandbyDevice) in e
