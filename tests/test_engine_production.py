"""The production layer: drop, remove and noValue; firing order; the loop guard; the Delta."""

from __future__ import annotations

import pytest
from rdflib import Literal, Namespace

from space.reasoning import RuleEngine, RuleLoopError, default_registry, parse_rules

EX = Namespace("http://example.org/")
PREFIX = "@prefix ex: <http://example.org/>.\n"


def engine(rules: str, **options) -> RuleEngine:
    return RuleEngine(parse_rules(PREFIX + rules, default_registry()), owl=False, **options)


SWITCH = """
[off_when_low: (?d ex:battery 'low'), (?d ex:mode ?m), notEqual(?m, 'off')
    -> drop(1), (?d ex:mode 'off')]
[on_when_ok: (?d ex:battery 'ok'), (?d ex:mode ?m), notEqual(?m, 'on')
    -> drop(1), (?d ex:mode 'on')]
"""


def test_drop_replaces_a_triple_and_the_delta_says_so():
    e = engine(SWITCH)
    e.load([(EX.d, EX.battery, Literal("ok")), (EX.d, EX.mode, Literal("on"))])
    delta = e.apply(
        added=[(EX.d, EX.battery, Literal("low"))], removed=[(EX.d, EX.battery, Literal("ok"))]
    )
    assert set(e.graph.objects(EX.d, EX.mode)) == {Literal("off")}
    assert delta.asserted_added == ((EX.d, EX.mode, Literal("off")),)
    assert delta.asserted_removed == ((EX.d, EX.mode, Literal("on")),)
    (firing,) = delta.firings
    assert firing.rule == "off_when_low"
    assert firing.triggers == ((EX.d, EX.battery, Literal("low")), (EX.d, EX.mode, Literal("on")))
    assert firing.retracted == ((EX.d, EX.mode, Literal("on")),)
    assert firing.asserted == ((EX.d, EX.mode, Literal("off")),)
    why = e.why((EX.d, EX.mode, Literal("off")))
    assert why.asserted and why.rule == "off_when_low"


def test_a_callers_triple_that_rules_take_away_is_reported_removed():
    """Loading a state whose rules drop part of it: the reasoner must remove it from the space."""
    e = engine(SWITCH)
    delta = e.load([(EX.d, EX.battery, Literal("low")), (EX.d, EX.mode, Literal("on"))])
    assert set(e.graph.objects(EX.d, EX.mode)) == {Literal("off")}
    assert delta.asserted_removed == ((EX.d, EX.mode, Literal("on")),)
    assert delta.asserted_added == ((EX.d, EX.mode, Literal("off")),)
    delta = e.apply(
        added=[(EX.d, EX.mode, Literal("on"))], removed=[(EX.d, EX.mode, Literal("off"))]
    )
    assert delta.asserted_removed == ((EX.d, EX.mode, Literal("on")),)


def test_rules_fire_again_when_their_match_comes_back():
    e = engine(SWITCH)
    e.load([(EX.d, EX.battery, Literal("ok")), (EX.d, EX.mode, Literal("on"))])
    for level, mode in [("low", "off"), ("ok", "on"), ("low", "off")]:
        old = "ok" if level == "low" else "low"
        e.apply(
            added=[(EX.d, EX.battery, Literal(level))], removed=[(EX.d, EX.battery, Literal(old))]
        )
        assert set(e.graph.objects(EX.d, EX.mode)) == {Literal(mode)}


def test_drop_is_silent_but_remove_wakes_no_value_rules():
    rules = """
    [clear_by_drop: (?x ex:clear 'drop'), (?x ex:flag ?f) -> drop(1)]
    [clear_by_remove: (?x ex:clear 'remove'), (?x ex:flag ?f) -> remove(1)]
    [unflagged: (?x ex:clear ?how), noValue(?x, ex:flag) -> (?x ex:noticed ?how)]
    """
    for how, noticed in (("drop", False), ("remove", True)):
        e = engine(rules)
        e.load([(EX.x, EX.flag, Literal(1))])
        e.apply(added=[(EX.x, EX.clear, Literal(how))])
        assert (EX.x, EX.flag, Literal(1)) not in e
        assert ((EX.x, EX.noticed, Literal(how)) in e) is noticed


def test_a_removal_by_the_caller_wakes_no_value_rules():
    e = engine("[lonely: (?x ex:kind ex:Robot), noValue(?x, ex:task) -> (?x ex:idle 'yes')]")
    e.load([(EX.r, EX.kind, EX.Robot), (EX.r, EX.task, EX.t)])
    assert (EX.r, EX.idle, Literal("yes")) not in e
    e.apply(removed=[(EX.r, EX.task, EX.t)])
    assert (EX.r, EX.idle, Literal("yes")) in e


def test_rules_fire_in_file_order_then_most_recent_first():
    rules = """
    [second: (?x ex:go ?n) -> (?x ex:log ?n)]
    [first: (?x ex:go ?n), noValue(?x, ex:never) -> (?x ex:seen ?n)]
    [last: (?x ex:go ?n), noValue(?x, ex:never) -> (?x ex:late ?n)]
    """
    e = engine(rules)
    e.load([])
    delta = e.apply(added=[(EX.a, EX.go, Literal(1)), (EX.b, EX.go, Literal(2))])
    fired = [(f.rule, f.triggers[0][0]) for f in delta.firings]
    assert fired == [("first", EX.b), ("first", EX.a), ("last", EX.b), ("last", EX.a)]


def test_each_match_fires_once():
    e = engine("[count: (?x ex:p ?y), noValue(?x, ex:q) -> (?x ex:r ?y)]")
    e.load([(EX.a, EX.p, EX.b)])
    assert len(e.apply(added=[(EX.c, EX.p, EX.d)]).firings) == 1
    assert e.apply(added=[(EX.z, EX.other, EX.d)]).firings == ()


def test_a_stale_activation_does_not_fire():
    rules = """
    [take: (?x ex:offer ?o), (?y ex:want ?o) -> drop(0), (?y ex:got ?o)]
    """
    e = engine(rules)
    e.load([(EX.shop, EX.offer, EX.apple)])
    delta = e.apply(added=[(EX.ann, EX.want, EX.apple), (EX.bob, EX.want, EX.apple)])
    assert len(delta.firings) == 1
    assert len(set(e.graph.subjects(EX.got, EX.apple))) == 1


def test_production_rules_see_inferred_triples():
    rules = """
    [device: (?x ex:kind ex:Speaker) -> (?x ex:kind ex:Device)]
    [standby: (?x ex:kind ex:Device), (?x ex:mode ?m), notEqual(?m, 'standby')
        -> drop(1), (?x ex:mode 'standby')]
    """
    e = engine(rules)
    e.load([(EX.s, EX.mode, Literal("on"))])
    delta = e.apply(added=[(EX.s, EX.kind, EX.Speaker)])
    assert set(e.graph.objects(EX.s, EX.mode)) == {Literal("standby")}
    assert delta.inferred_added == ((EX.s, EX.kind, EX.Device),)


def test_a_runaway_rule_set_is_stopped_its_firings_undone_the_callers_triples_kept():
    rules = """
    [ping: (?x ex:state 'a') -> drop(0), (?x ex:state 'b')]
    [pong: (?x ex:state 'b') -> drop(0), (?x ex:state 'a')]
    [kind: (?x ex:state ?s) -> (?x ex:kind ex:Stateful)]
    """
    e = engine(rules, max_firings=50)
    e.load([(EX.x, EX.other, Literal(1))])
    before = set(e.graph)
    with pytest.raises(RuleLoopError) as caught:
        e.apply(added=[(EX.x, EX.state, Literal("a"))])
    assert set(caught.value.rules) == {"ping", "pong"}
    assert "ping" in str(caught.value) and "pong" in str(caught.value)
    mine, concluded = (EX.x, EX.state, Literal("a")), (EX.x, EX.kind, EX.Stateful)
    assert set(e.graph) == before | {mine, concluded}
    assert caught.value.kept is not None
    assert caught.value.kept.asserted_added == ()  # the caller knows its own triples
    assert caught.value.kept.inferred_added == (concluded,)
    assert caught.value.kept.firings == ()
    e.apply(added=[(EX.x, EX.other, Literal(2))])
    assert (EX.x, EX.other, Literal(2)) in e
