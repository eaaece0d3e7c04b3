"""A rule set mixing forward and backward rules runs in two layers, as Jena's hybrid mode."""

from __future__ import annotations

from rdflib import Literal, Namespace

from space.reasoning import default_registry, parse_rules
from space.reasoning.delta import Origin
from space.reasoning.hybrid import HybridEngine, mixes_forms

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
