"""A rule set mixing forward and backward rules runs in two layers, as Jena's hybrid mode."""

from __future__ import annotations

import pytest
from rdflib import RDF, RDFS, Literal, Namespace

from space.reasoning import (
    HybridEngine,
    RuleEngine,
    RuleLoopError,
    build_engine,
    default_registry,
    parse_rules,
)
from space.reasoning.delta import Origin
from space.reasoning.hybrid import mixes_forms

EX = Namespace("http://example.org/")
RULES = (
    "@prefix ex: <http://example.org/>.\n"
    "[fwd: (?x ex:p ?y) -> (?x ex:q ?y)]\n"
    "[back: (?x ex:r ?y) <- (?x ex:q ?y)]\n"
    "[sees: (?x ex:r ?y) -> (?x ex:s ?y)]\n"
)


def _engine() -> HybridEngine:
    rules = parse_rules(RULES, default_registry())
    assert mixes_forms(rules)
    return HybridEngine(rules, owl=False)


def test_forward_rules_do_not_see_what_backward_rules_conclude():
    engine = _engine()
    engine.load([(EX.a, EX.p, Literal(1))])
    assert (EX.a, EX.q, Literal(1)) in engine
    assert (EX.a, EX.r, Literal(1)) in engine  # the backward rule answers over the forward layer
    assert (EX.a, EX.s, Literal(1)) not in engine  # the forward rule `sees` never sees it


def test_updates_pass_through_both_layers_and_say_where_a_triple_comes_from():
    engine = _engine()
    engine.load()
    delta = engine.apply(added=[(EX.a, EX.p, Literal(1))])
    origins = {c.triple: c.origin for c in delta.added}
    assert origins[(EX.a, EX.p, Literal(1))] is Origin.ASSERTED
    assert origins[(EX.a, EX.r, Literal(1))] is Origin.INFERRED
    why = engine.why((EX.a, EX.r, Literal(1)))
    assert why is not None and why.rule == "back"
    assert engine.why((EX.a, EX.q, Literal(1))).rule == "fwd"  # type: ignore[union-attr]
    delta = engine.apply(removed=[(EX.a, EX.p, Literal(1))])
    assert {c.triple for c in delta.removed} == {
        (EX.a, EX.p, Literal(1)),
        (EX.a, EX.q, Literal(1)),
        (EX.a, EX.r, Literal(1)),
    }
    assert not list(engine.triples())


MIRRORED = (
    "@prefix ex: <http://example.org/>.\n"
    "[fwd: (?x ex:p ?y) -> (?x ex:q ?y)]\n"
    "[back: (?x ex:r ?y) <- (?x ex:q ?y)]\n"
    "[nested: (?x ex:kind ex:Tagged) -> [(?x ex:tag ?y) <- (?x ex:r ?y)]]\n"
    "[prod: (?x ex:q ?y), noValue(?x ex:seen ?y) -> (?x ex:seen ?y)]\n"
    "[idle: (?x ex:idle ?y) <- (?x ex:q ?y), noValue(?x ex:tag ?y)]\n"
)


def test_a_caller_mirroring_the_deltas_stays_equal_to_the_engine():
    # The reasoner agent keeps the space equal to the engine from the deltas alone:
    # the whole state from added/removed, the inferred graph from inferred_added/removed,
    # including a triple a caller asserts that a backward rule concludes too.
    engine = HybridEngine(parse_rules(MIRRORED, default_registry()), owl=False)
    a, b = EX.a, Literal(1)
    steps = [
        ([(a, EX.p, b)], []),
        ([(a, EX.kind, EX.Tagged)], []),
        ([(a, EX.r, b)], []),  # asserted, and concluded by `back`: now asserted
        ([], [(a, EX.r, b)]),  # retracted: inferred again
        ([], [(a, EX.kind, EX.Tagged)]),  # the nested rule goes with its parent's match
        ([(a, EX.tag, b)], [(a, EX.p, b)]),
        ([], [(a, EX.tag, b)]),
    ]
    state: set = set()
    inferred: set = set()
    for step, (added, removed) in enumerate([([], []), *steps]):
        delta = engine.load() if step == 0 else engine.apply(added=added, removed=removed)
        state |= {c.triple for c in delta.added}
        state -= {c.triple for c in delta.removed}
        inferred |= set(delta.inferred_added)
        inferred -= set(delta.inferred_removed)
        assert state == set(engine.triples()), step
        assert inferred == set(engine.triples(Origin.INFERRED)), step
        assert set(engine.triples(Origin.ASSERTED)) == state - inferred, step
    assert (a, EX.seen, b) in engine  # the production rule's head, asserted: it stays


def test_the_nested_rule_runs_in_the_backward_layer_and_goes_with_its_parent():
    engine = HybridEngine(parse_rules(MIRRORED, default_registry()), owl=False)
    engine.load([(EX.a, EX.p, Literal(1)), (EX.a, EX.kind, EX.Tagged)])
    assert (EX.a, EX.tag, Literal(1)) in engine
    assert engine.why((EX.a, EX.tag, Literal(1))).rule.startswith("nested")  # type: ignore[union-attr]
    engine.apply(removed=[(EX.a, EX.kind, EX.Tagged)])
    assert (EX.a, EX.tag, Literal(1)) not in engine


def test_a_rule_loop_in_the_forward_layer_keeps_the_callers_change_through_both_layers():
    rules = (
        "@prefix ex: <http://example.org/>.\n"
        "[back: (?x ex:r ?y) <- (?x ex:p ?y)]\n"
        "[spin: (?x ex:n ?v), sum(?v, 1, ?w) -> drop(0), (?x ex:n ?w)]\n"
    )
    engine = HybridEngine(parse_rules(rules, default_registry()), owl=False, max_firings=50)
    engine.load()
    with pytest.raises(RuleLoopError) as caught:
        engine.apply(added=[(EX.a, EX.p, Literal(1)), (EX.a, EX.n, Literal(0))])
    kept = caught.value.kept
    assert kept is not None
    assert {c.triple for c in kept.added} == {
        (EX.a, EX.p, Literal(1)),
        (EX.a, EX.n, Literal(0)),
        (EX.a, EX.r, Literal(1)),  # the backward layer saw the kept change
    }
    assert set(engine.triples()) == {c.triple for c in kept.added}


def test_build_engine_runs_forward_rules_in_one_engine_and_backward_ones_in_two_layers():
    registry = default_registry()
    forward = parse_rules("[f: (?x <urn:p> ?y) -> (?x <urn:q> ?y)]", registry)
    assert type(build_engine(forward, owl=False)) is RuleEngine  # the paper's rules: no cost
    backward = parse_rules("[b: (?x <urn:q> ?y) <- (?x <urn:p> ?y)]", registry)
    assert isinstance(build_engine(backward, owl=False), HybridEngine)
    nested = parse_rules("[n: (?c <urn:k> ?d) -> [(?x <urn:q> ?d) <- (?x <urn:p> ?c)]]", registry)
    assert isinstance(build_engine(nested, owl=False), HybridEngine)


def test_a_backward_rule_with_novalue_withdraws_its_conclusion_as_jena_asks_it_again():
    rules = parse_rules(
        "@prefix ex: <http://example.org/>.\n"
        "[free: (?r ex:free ex:yes) <- (?r ex:kind ex:Robot), noValue(?r ex:busy)]\n"
        "[f: (?r ex:at ?p) -> (?r ex:was ?p)]\n",
        default_registry(),
    )
    engine = build_engine(rules, owl=False)
    free = (EX.r, EX.free, EX.yes)
    assert free in engine.load([(EX.r, EX.kind, EX.Robot)]).inferred_added
    delta = engine.apply(added=[(EX.r, EX.busy, EX.task)])
    assert free not in engine  # Jena's answer once ex:busy holds
    assert delta.inferred_removed == (free,)
    assert free in engine.apply(removed=[(EX.r, EX.busy, EX.task)]).inferred_added
    engine.apply(removed=[(EX.r, EX.kind, EX.Robot)])  # a premise goes: the conclusion too
    assert free not in engine
    assert set(engine.triples()) == set()


def test_owl_rl_runs_in_the_forward_layer_and_builds_on_forward_rules_only():
    ontology = [(EX.Sub, RDFS.subClassOf, EX.Super)]
    rules = parse_rules(
        "@prefix ex: <http://example.org/>.\n"
        "[back: (?x rdf:type ex:Sub) <- (?x ex:tagged ex:b)]\n"
        "[fwd: (?x ex:marked ex:f) -> (?x rdf:type ex:Sub)]\n",
        default_registry(),
    )
    engine = build_engine(rules, ontology)
    engine.load([(EX.a, EX.tagged, EX.b), (EX.c, EX.marked, EX.f)])
    assert (EX.a, RDF.type, EX.Sub) in engine and (EX.c, RDF.type, EX.Super) in engine
    assert (EX.a, RDF.type, EX.Super) not in engine  # as Jena's OWL rules in a hybrid set


def test_a_backward_rule_counting_values_follows_the_count_as_jena_counts_again():
    rules = parse_rules(
        "@prefix ex: <http://example.org/>.\n"
        "[many: (?x ex:many ex:yes) <- (?x ex:kind ex:R), countLiteralValues(?x, ex:v, ?n),"
        " greaterThan(?n, 1)]\n",
        default_registry(),
    )
    engine = build_engine(rules, owl=False)
    many = (EX.a, EX.many, EX.yes)
    engine.load([(EX.a, EX.kind, EX.R)])
    engine.apply(added=[(EX.a, EX.v, Literal(1))])
    assert many not in engine
    delta = engine.apply(added=[(EX.a, EX.v, Literal(2))])  # the values come after the match
    assert many in engine and delta.inferred_added == (many,)
    delta = engine.apply(added=[(EX.a, EX.v, Literal(3))])  # 3 > 1 still: no change
    assert many in engine and not delta.inferred_added and not delta.inferred_removed
    engine.apply(removed=[(EX.a, EX.v, Literal(2)), (EX.a, EX.v, Literal(3))])
    assert many not in engine
