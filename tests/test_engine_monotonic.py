"""The monotonic layer: closure kept up to date on additions and deletions, and why."""

from __future__ import annotations

import pytest
from rdflib import Literal, Namespace

from space.errors import InputError
from space.reasoning import Origin, RuleEngine, RuleError, default_registry, parse_rules

EX = Namespace("http://example.org/")
RULES = """@prefix ex: <http://example.org/>.
[ancestor_base: (?a ex:parent ?b) -> (?a ex:ancestor ?b)]
[ancestor_step: (?a ex:parent ?b), (?b ex:ancestor ?c) -> (?a ex:ancestor ?c)]
[adult: (?a ex:age ?n), ge(?n, 18) -> (?a ex:kind ex:Adult)]
"""


def engine(rules: str = RULES) -> RuleEngine:
    return RuleEngine(parse_rules(rules, default_registry()), owl=False)


def ancestors(e: RuleEngine) -> set:
    return set(e.graph.subject_objects(EX.ancestor))


def test_load_runs_rules_to_a_fixpoint_and_marks_origins():
    e = engine()
    delta = e.load([(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.c)])
    assert ancestors(e) == {(EX.a, EX.b), (EX.b, EX.c), (EX.a, EX.c)}
    origins = {c.triple: c.origin for c in delta.added}
    assert origins[(EX.a, EX.parent, EX.b)] is Origin.ASSERTED
    assert origins[(EX.a, EX.ancestor, EX.c)] is Origin.INFERRED
    assert set(delta.inferred_added) == {(s, EX.ancestor, o) for s, o in ancestors(e)}
    assert delta.asserted_added == () and delta.firings == ()


def test_apply_adds_only_what_is_new():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b)])
    delta = e.apply(added=[(EX.b, EX.parent, EX.c)])
    assert {c.triple for c in delta.added} == {
        (EX.b, EX.parent, EX.c),
        (EX.b, EX.ancestor, EX.c),
        (EX.a, EX.ancestor, EX.c),
    }
    assert delta.removed == ()


def test_deleting_a_premise_retracts_what_it_alone_supported():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.c), (EX.c, EX.parent, EX.d)])
    delta = e.apply(removed=[(EX.b, EX.parent, EX.c)])
    assert ancestors(e) == {(EX.a, EX.b), (EX.c, EX.d)}
    assert {c.triple for c in delta.removed if c.origin is Origin.INFERRED} == {
        (EX.b, EX.ancestor, EX.c),
        (EX.b, EX.ancestor, EX.d),
        (EX.a, EX.ancestor, EX.c),
        (EX.a, EX.ancestor, EX.d),
    }


def test_a_cycle_does_not_keep_itself_alive():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.a)])
    assert (EX.a, EX.ancestor, EX.a) in e
    e.apply(removed=[(EX.b, EX.parent, EX.a)])
    assert ancestors(e) == {(EX.a, EX.b)}


def test_a_triple_with_another_derivation_survives():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.c), (EX.a, EX.parent, EX.c)])
    delta = e.apply(removed=[(EX.b, EX.parent, EX.c)])
    assert (EX.a, EX.ancestor, EX.c) in e
    assert (EX.a, EX.ancestor, EX.c) not in {c.triple for c in delta.removed}


def test_an_asserted_triple_that_is_also_inferred_stays_as_inferred_when_retracted():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b), (EX.a, EX.ancestor, EX.b)])
    delta = e.apply(removed=[(EX.a, EX.ancestor, EX.b)])
    assert (EX.a, EX.ancestor, EX.b) in e
    assert delta.inferred_added == ((EX.a, EX.ancestor, EX.b),)
    assert not e.why((EX.a, EX.ancestor, EX.b)).asserted


def test_removing_an_inferred_triple_changes_nothing():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b)])
    assert not e.apply(removed=[(EX.a, EX.ancestor, EX.b)])
    assert (EX.a, EX.ancestor, EX.b) in e


def test_why_names_the_rule_and_premises_or_asserted():
    e = engine()
    e.load([(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.c), (EX.x, EX.age, Literal(30))])
    why = e.why((EX.a, EX.ancestor, EX.c))
    assert why.rule == "ancestor_step" and not why.asserted
    assert why.premises == ((EX.a, EX.parent, EX.b), (EX.b, EX.ancestor, EX.c))
    assert e.why((EX.a, EX.parent, EX.b)).asserted
    assert e.why((EX.x, EX.kind, EX.Adult)).rule == "adult"
    assert e.why((EX.c, EX.ancestor, EX.a)) is None


def test_builtin_guards_follow_changing_values():
    e = engine()
    e.load([(EX.x, EX.age, Literal(17))])
    assert (EX.x, EX.kind, EX.Adult) not in e
    e.apply(added=[(EX.x, EX.age, Literal(18))], removed=[(EX.x, EX.age, Literal(17))])
    assert (EX.x, EX.kind, EX.Adult) in e
    e.apply(removed=[(EX.x, EX.age, Literal(18))])
    assert (EX.x, EX.kind, EX.Adult) not in e


def test_functor_values_are_seen_by_rules_but_not_in_the_graph():
    rules = """@prefix ex: <http://example.org/>.
    [pack: (?a ex:p ?b) -> (?a ex:pair pair(?a, ?b))]
    [unpack: (?a ex:pair pair(?x, ?y)) -> (?y ex:back ?x)]"""
    e = engine(rules)
    e.load([(EX.a, EX.p, EX.b)])
    assert (EX.b, EX.back, EX.a) in e
    assert not list(e.graph.triples((None, EX.pair, None)))


def test_variable_predicates_and_load_once():
    e = engine(
        "@prefix ex: <http://example.org/>.\n[copy: (?s ?p ?o), (?p ex:copyTo ?q) -> (?s ?q ?o)]"
    )
    e.load([(EX.p, EX.copyTo, EX.q), (EX.a, EX.p, EX.b)])
    assert (EX.a, EX.q, EX.b) in e
    with pytest.raises(RuleError, match="use apply"):
        e.load([])


def test_bad_triples_are_rejected():
    e = engine()
    with pytest.raises(InputError):
        e.apply(added=[(Literal("x"), EX.p, EX.o)])
    with pytest.raises(InputError):
        e.apply(added=[(EX.a, EX.p)])
