"""OWL 2 RL rules beyond the basics: conflicts, chains, keys, cardinality; exact on deletion."""

from __future__ import annotations

import random
import warnings

import owlrl
import pytest
from rdflib import OWL, RDF, RDFS, BNode, Graph, Literal, Namespace
from rdflib.collection import Collection

from space.reasoning import RuleEngine, UnsupportedAxiom

EX = Namespace("http://example.org/")


def engine(tbox: Graph) -> RuleEngine:
    e = RuleEngine([], tbox)
    e.load([])
    return e


def graph(*triples) -> Graph:
    g = Graph()
    for t in triples:
        g.add(t)
    return g


def listed(g: Graph, *items) -> BNode:
    head = BNode()
    Collection(g, head, list(items))
    return head


def test_disjoint_classes_conflict_names_the_rule_and_goes_with_its_cause():
    e = engine(graph((EX.StandbyDevice, OWL.disjointWith, EX.ActiveDevice)))
    assert e.conflicts() == ()
    e.apply(added=[(EX.screen, RDF.type, EX.StandbyDevice), (EX.screen, RDF.type, EX.ActiveDevice)])
    (conflict,) = e.conflicts()
    assert conflict.rule == "cax-dw"
    assert set(conflict.triples) == {
        (EX.StandbyDevice, OWL.disjointWith, EX.ActiveDevice),
        (EX.screen, RDF.type, EX.StandbyDevice),
        (EX.screen, RDF.type, EX.ActiveDevice),
    }
    # Nothing else is lost: both memberships still hold.
    assert (EX.screen, RDF.type, EX.ActiveDevice) in e
    e.apply(removed=[(EX.screen, RDF.type, EX.ActiveDevice)])
    assert e.conflicts() == ()


def test_conflict_through_inference_goes_when_the_premise_of_the_inference_goes():
    e = engine(
        graph(
            (EX.Speaker, RDFS.subClassOf, EX.Device),
            (EX.Device, OWL.disjointWith, EX.Person),
        )
    )
    e.apply(added=[(EX.bob, RDF.type, EX.Speaker), (EX.bob, RDF.type, EX.Person)])
    assert [c.rule for c in e.conflicts()] == ["cax-dw"]
    e.apply(removed=[(EX.bob, RDF.type, EX.Speaker)])
    assert e.conflicts() == ()


def test_property_chain_and_its_retraction():
    g = Graph()
    g.add((EX.uncle, OWL.propertyChainAxiom, listed(g, EX.parent, EX.brother)))
    e = engine(g)
    e.apply(added=[(EX.ann, EX.parent, EX.bob), (EX.bob, EX.brother, EX.carl)])
    assert (EX.ann, EX.uncle, EX.carl) in e
    assert e.why((EX.ann, EX.uncle, EX.carl)).rule == "prp-spo2"
    e.apply(removed=[(EX.bob, EX.brother, EX.carl)])
    assert (EX.ann, EX.uncle, EX.carl) not in e


def test_keys_make_individuals_the_same_until_a_key_value_goes():
    g = Graph()
    g.add((EX.Robot, OWL.hasKey, listed(g, EX.serial)))
    e = engine(g)
    e.apply(
        added=[
            (EX.r1, RDF.type, EX.Robot),
            (EX.r2, RDF.type, EX.Robot),
            (EX.r1, EX.serial, Literal("A7")),
            (EX.r2, EX.serial, Literal("A7")),
        ]
    )
    assert (EX.r1, OWL.sameAs, EX.r2) in e
    e.apply(removed=[(EX.r2, EX.serial, Literal("A7"))])
    assert (EX.r1, OWL.sameAs, EX.r2) not in e


def test_max_cardinality_one_and_zero():
    g = Graph()
    one, zero = BNode(), BNode()
    for r, n, prop in ((one, 1, EX.dock), (zero, 0, EX.patient)):
        g.add((r, RDF.type, OWL.Restriction))
        g.add((r, OWL.onProperty, prop))
        g.add((r, OWL.maxCardinality, Literal(n)))
        g.add((EX.Robot, RDFS.subClassOf, r))
    e = engine(g)
    e.apply(added=[(EX.r, RDF.type, EX.Robot), (EX.r, EX.dock, EX.d1), (EX.r, EX.dock, EX.d2)])
    assert (EX.d1, OWL.sameAs, EX.d2) in e
    assert e.conflicts() == ()
    e.apply(added=[(EX.r, EX.patient, EX.p)])
    assert [c.rule for c in e.conflicts()] == ["cls-maxc1"]


def test_functional_data_property_with_two_values_is_a_conflict():
    e = engine(graph((EX.battery, RDF.type, OWL.FunctionalProperty)))
    e.apply(added=[(EX.r, EX.battery, Literal(40)), (EX.r, EX.battery, Literal(40.0))])
    assert e.conflicts() == ()  # one value, written twice
    e.apply(added=[(EX.r, EX.battery, Literal(35))])
    assert {c.rule for c in e.conflicts()} == {"prp-fp"}


def test_axiomatic_triples_and_schema_reflexivity():
    e = engine(graph((EX.Robot, RDF.type, OWL.Class), (EX.p, RDF.type, OWL.ObjectProperty)))
    assert (OWL.Thing, RDF.type, OWL.Class) in e
    assert (RDFS.label, RDF.type, OWL.AnnotationProperty) in e
    assert (EX.Robot, RDFS.subClassOf, OWL.Thing) in e
    assert (EX.p, OWL.equivalentProperty, EX.p) in e
    assert (EX.Robot, OWL.sameAs, EX.Robot) in e
    assert (EX.nobody, OWL.sameAs, EX.nobody) not in e


def test_constructs_outside_rl_are_named_in_a_warning():
    r = BNode()
    g = graph(
        (r, RDF.type, OWL.Restriction),
        (r, OWL.onProperty, EX.has_wheel),
        (r, OWL.minCardinality, Literal(2)),
        (EX.Robot, RDFS.subClassOf, r),
        (EX.near, RDF.type, OWL.ReflexiveProperty),
    )
    with pytest.warns(UnsupportedAxiom) as caught:
        RuleEngine([], g)
    messages = [str(w.message) for w in caught]
    assert any("owl:minCardinality" in m and "has_wheel" in m for m in messages)
    assert any("owl:ReflexiveProperty" in m and "near" in m for m in messages)


def restriction(g: Graph, prop, **facets) -> BNode:
    """Add an owl:Restriction on `prop` with the given facets (owl:name -> object)."""
    r = BNode()
    g.add((r, RDF.type, OWL.Restriction))
    g.add((r, OWL.onProperty, prop))
    for name, value in facets.items():
        g.add((r, OWL[name], value))
    return r


def unsupported(g: Graph) -> list[str]:
    """Return the UnsupportedAxiom messages building an engine for `g` gives."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        RuleEngine([], g)
    return [str(w.message) for w in caught if issubclass(w.category, UnsupportedAxiom)]


@pytest.mark.parametrize(
    ("facets", "named"),
    [
        ({"cardinality": Literal(1)}, "owl:cardinality"),
        ({"qualifiedCardinality": Literal(1), "onClass": EX.Wheel}, "owl:qualifiedCardinality"),
        ({"minQualifiedCardinality": Literal(1), "onClass": EX.Wheel}, "owl:minQualified"),
        ({"maxCardinality": Literal(2)}, "owl:maxCardinality 2"),
        ({"maxQualifiedCardinality": Literal(4), "onClass": EX.Wheel}, "maxQualifiedCardinality 4"),
        ({"hasSelf": Literal(True)}, "owl:hasSelf"),
    ],
)
def test_each_restriction_outside_rl_is_named_with_its_property(facets, named):
    g = Graph()
    g.add((EX.Robot, RDFS.subClassOf, restriction(g, EX.has_wheel, **facets)))
    messages = unsupported(g)
    assert any(named in m and "has_wheel" in m for m in messages), messages


def test_a_disjoint_union_is_named():
    g = Graph()
    g.add((EX.Device, OWL.disjointUnionOf, listed(g, EX.Sensor, EX.Actuator)))
    assert any("owl:disjointUnionOf" in m and "Device" in m for m in unsupported(g))


def test_class_expressions_on_the_side_of_a_subclass_axiom_rl_leaves_out_are_named():
    g = Graph()
    g.bind("ex", EX)
    g.add((EX.Robot, RDFS.subClassOf, restriction(g, EX.has_base, someValuesFrom=EX.Base)))
    union = BNode()
    g.add((union, OWL.unionOf, listed(g, EX.Sensor, EX.Actuator)))
    g.add((EX.Device, RDFS.subClassOf, union))
    g.add((restriction(g, EX.carries, allValuesFrom=EX.Tray), RDFS.subClassOf, EX.Carrier))
    g.add((EX.Docked, OWL.equivalentClass, restriction(g, EX.dock, someValuesFrom=EX.Dock)))
    messages = unsupported(g)
    assert any("someValuesFrom" in m and "has_base" in m and "superclass of" in m for m in messages)
    assert any("owl:unionOf" in m and "superclass of ex:Device" in m for m in messages)
    assert any("allValuesFrom" in m and "subclass of ex:Carrier" in m for m in messages)
    assert any("someValuesFrom" in m and "superclass of ex:Docked" in m for m in messages)
    assert len(messages) == 4, messages


def test_the_rl_sides_of_class_expressions_and_the_rl_axioms_build_without_a_warning():
    g = Graph()
    g.add((restriction(g, EX.has_base, someValuesFrom=EX.Base), RDFS.subClassOf, EX.Robot))
    g.add((EX.Carrier, RDFS.subClassOf, restriction(g, EX.carries, allValuesFrom=EX.Tray)))
    g.add((EX.Standby, OWL.equivalentClass, restriction(g, EX.mode, hasValue=Literal("idle"))))
    g.add((EX.Robot, RDFS.subClassOf, restriction(g, EX.dock, maxCardinality=Literal(1))))
    g.add((EX.uncle, OWL.propertyChainAxiom, listed(g, EX.parent, EX.brother)))
    g.add((EX.Robot, OWL.hasKey, listed(g, EX.serial)))
    g.add((EX.Robot, OWL.disjointWith, EX.Person))
    g.add((EX.left, OWL.propertyDisjointWith, EX.right))
    every = BNode()
    g.add((every, RDF.type, OWL.AllDisjointClasses))
    g.add((every, OWL.members, listed(g, EX.Sensor, EX.Actuator, EX.Person)))
    assert unsupported(g) == []
    e = engine(g)
    e.apply(
        added=[
            (EX.s, RDF.type, EX.Sensor),
            (EX.s, RDF.type, EX.Actuator),
            (EX.a, EX.left, EX.b),
            (EX.a, EX.right, EX.b),
        ]
    )
    assert {c.rule for c in e.conflicts()} == {"cax-adc", "prp-pdw"}


def _random_ontology(seed: int, rich: bool = False) -> tuple[Graph, list]:
    """Return a small random RL ontology and random instance data over it (with `rich`,
    every kind of OWL 2 RL axiom)."""
    rnd = random.Random(seed)
    classes = [EX[f"C{i}"] for i in range(6)]
    props = [EX[f"p{i}"] for i in range(5)]
    people = [EX[f"i{i}"] for i in range(8)]
    g = Graph()
    for _ in range(6):
        g.add((rnd.choice(classes), RDFS.subClassOf, rnd.choice(classes)))
    for _ in range(3):
        g.add((rnd.choice(props), RDFS.subPropertyOf, rnd.choice(props)))
    g.add((rnd.choice(props), RDFS.domain, rnd.choice(classes)))
    g.add((rnd.choice(props), RDFS.range, rnd.choice(classes)))
    g.add((rnd.choice(props), OWL.inverseOf, rnd.choice(props)))
    g.add((rnd.choice(props), RDF.type, OWL.TransitiveProperty))
    g.add((rnd.choice(props), RDF.type, OWL.SymmetricProperty))
    g.add((rnd.choice(props), OWL.propertyChainAxiom, listed(g, *rnd.sample(props, 2))))
    g.add((rnd.choice(classes), OWL.intersectionOf, listed(g, *rnd.sample(classes, 2))))
    g.add((rnd.choice(classes), OWL.unionOf, listed(g, *rnd.sample(classes, 2))))
    r = BNode()
    g.add((r, OWL.onProperty, rnd.choice(props)))
    g.add((r, OWL.someValuesFrom, rnd.choice(classes)))
    g.add((r, RDFS.subClassOf, rnd.choice(classes)))
    if rich:
        _add_rich_axioms(g, rnd, classes, props, people)
    data = _add_key(g, rnd, classes, props, people)
    data += [(rnd.choice(people), RDF.type, rnd.choice(classes)) for _ in range(8)]
    data += [(rnd.choice(people), rnd.choice(props), rnd.choice(people)) for _ in range(10)]
    return g, list(dict.fromkeys(data))


def _add_rich_axioms(g: Graph, rnd: random.Random, classes: list, props: list, people: list):
    """Add the rest of OWL 2 RL: equivalences, equality, values, universals, maxima and
    disjointness (whose conflicts neither reasoner lists among the instances)."""
    g.add((rnd.choice(classes), OWL.equivalentClass, rnd.choice(classes)))
    g.add((rnd.choice(props), OWL.equivalentProperty, rnd.choice(props)))
    g.add((rnd.choice(props), RDF.type, OWL.FunctionalProperty))
    g.add((rnd.choice(props), RDF.type, OWL.InverseFunctionalProperty))
    facets = [
        {"hasValue": rnd.choice(people)},
        {"allValuesFrom": rnd.choice(classes)},
        {"maxCardinality": Literal(1)},
        {"maxQualifiedCardinality": Literal(1), "onClass": rnd.choice(classes)},
    ]
    for facet in rnd.sample(facets, 2):
        r = restriction(g, rnd.choice(props), **facet)
        if "hasValue" in facet:
            g.add((rnd.choice(classes), OWL.equivalentClass, r))
        else:
            g.add((rnd.choice(classes), RDFS.subClassOf, r))
    g.add((rnd.choice(classes), OWL.disjointWith, rnd.choice(classes)))
    g.add((rnd.choice(props), OWL.propertyDisjointWith, rnd.choice(props)))


def _add_key(g: Graph, rnd: random.Random, classes: list, props: list, people: list) -> list:
    """Add an owl:hasKey of one or two properties; return data giving two members the same
    key values (random data seldom does) and a third member only the first value."""
    keyed, keys = rnd.choice(classes), rnd.sample(props, rnd.randint(1, 2))
    g.add((keyed, OWL.hasKey, listed(g, *keys)))
    twins, other = rnd.sample(people, 2), rnd.choice(people)
    values = [(k, rnd.choice(people)) for k in keys]
    data = [(t, RDF.type, keyed) for t in (*twins, other)]
    return [*data, *((t, k, v) for t in twins for k, v in values), (other, *values[0])]


class _W3CKeys(owlrl.OWLRL_Semantics):
    """owlrl with prp-key as the W3C writes it: owlrl 7.6.2 checks key properties
    `range(0, len(pis) - 1)`, so it ignores the last one (with a one-property key, any two
    members are made the same once one has a value); see
    test_owlrl_ignores_the_last_property_of_a_key_which_prp_key_requires."""

    def _properties(self, triple: tuple, cycle_num: int) -> None:
        c, pred, head = triple
        if pred != OWL.hasKey:
            super()._properties(triple, cycle_num)
            return
        keys = self._list(head)
        members = list(self.graph.subjects(RDF.type, c))
        for x in members:
            for y in members:
                if x != y and all(
                    any((y, k, z) in self.graph for z in self.graph.objects(x, k)) for k in keys
                ):
                    self.store_triple((x, OWL.sameAs, y))


_ROBOTS = [(EX.a, RDF.type, EX.Robot), (EX.b, RDF.type, EX.Robot), (EX.a, EX.serial, EX.s1)]


@pytest.mark.parametrize(
    ("keys", "data"),
    [
        ([EX.serial], _ROBOTS),  # the smallest: b has no serial at all
        ([EX.maker, EX.serial], [*_ROBOTS, (EX.a, EX.maker, EX.acme), (EX.b, EX.maker, EX.acme)]),
    ],
)
def test_owlrl_ignores_the_last_property_of_a_key_which_prp_key_requires(keys, data):
    """prp-key (OWL 2 Profiles, table 5) makes x and y the same only when they share a value
    of every key property; owlrl 7.6.2 skips the last one, so the oracle uses _W3CKeys."""
    g = Graph()
    g.add((EX.Robot, OWL.hasKey, listed(g, *keys)))
    e = RuleEngine([], g)
    e.load(data)
    assert (EX.a, OWL.sameAs, EX.b) not in set(e.triples())  # b has no serial s1
    for semantics, same in ((owlrl.OWLRL_Semantics, True), (_W3CKeys, False)):
        theirs = graph(*g, *data)
        owlrl.DeductiveClosure(semantics).expand(theirs)
        assert ((EX.a, OWL.sameAs, EX.b) in theirs) is same
    e.apply(added=[(EX.b, EX.serial, EX.s1)])  # every key value shared: the same robot
    assert (EX.a, OWL.sameAs, EX.b) in set(e.triples())
    e.apply(removed=[(EX.a, EX.serial, EX.s1)])  # and no longer once a value goes
    assert (EX.a, OWL.sameAs, EX.b) not in set(e.triples())


def _instances(triples) -> set:
    """Keep what both reasoners must agree on: memberships of named classes and property values."""
    return {
        t
        for t in triples
        if str(t[0]).startswith(str(EX))
        and str(t[2]).startswith(str(EX))
        and (t[1] == RDF.type or str(t[1]).startswith(str(EX)))
    }


@pytest.mark.parametrize(
    ("seed", "rich"), [*((s, False) for s in range(12)), *((s, True) for s in range(24))]
)
def test_instances_equal_owlrl_on_generated_ontologies(seed, rich):
    g, data = _random_ontology(seed, rich)
    assert unsupported(g) == []  # all in OWL 2 RL: nothing the oracle uses is left out
    e = RuleEngine([], g)
    e.load(data)
    theirs = Graph()
    for t in (*g, *data):
        theirs.add(t)
    owlrl.DeductiveClosure(_W3CKeys).expand(theirs)
    assert _instances(e.triples()) == _instances(theirs)
    # And after deleting half of the data, a fresh closure's.
    e.apply(removed=data[::2])
    fresh = RuleEngine([], g)
    fresh.load(data[1::2])
    assert set(e.triples()) == set(fresh.triples())
