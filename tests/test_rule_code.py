"""Compiled rules are shared: by rules of one shape, by engines, by a reload of the same rules."""

from __future__ import annotations

from pathlib import Path

from rdflib import RDF, Literal, Namespace

from space.reasoning import RuleEngine, default_registry, parse_rules, read_graph
from space.reasoning.rulecode import shape

ROOT = Path(__file__).resolve().parents[1]
EX = Namespace("http://example.org/")
SETTINGS = """@prefix ex: <http://example.org/>.
[low_a: (?r ex:battery "low"), (?r ex:a ?v), notEqual(?v, "off") -> drop(1), (?r ex:a "off")]
[low_b: (?r ex:battery "low"), (?r ex:b ?v), notEqual(?v, "off") -> drop(1), (?r ex:b "off")]
[high: (?r ex:battery "high"), (?r ex:a ?v) -> (?r ex:seen ?v)]
"""


def rules():
    return parse_rules(SETTINGS, default_registry(), source="<settings>")


def code(engine: RuleEngine, label: str):
    """Return the code objects of a rule's compiled functions in an engine."""
    compiled = next(c for c in engine._compiled if c.label == label)
    return compiled.heads.__code__


def test_rules_differing_only_in_constants_run_one_code_each_with_its_own_constants():
    low_a, low_b, high = rules()
    assert shape(low_a).key == shape(low_b).key
    assert shape(low_a).key != shape(high).key
    engine = RuleEngine(rules(), owl=False)
    assert code(engine, "low_a") is code(engine, "low_b")
    engine.load([(EX.r, EX.a, Literal("on")), (EX.r, EX.b, Literal("on"))])
    delta = engine.apply(added=[(EX.r, EX.battery, Literal("low"))])
    assert [f.rule for f in delta.firings] == ["low_a", "low_b"]
    assert set(engine.match(EX.r, None, None)) == {
        (EX.r, EX.battery, Literal("low")),
        (EX.r, EX.a, Literal("off")),
        (EX.r, EX.b, Literal("off")),
    }


def test_engines_share_the_code_of_the_same_rules_and_keep_their_own_state():
    first, second = RuleEngine(rules(), owl=False), RuleEngine(rules(), owl=False)
    assert code(first, "high") is code(second, "high")
    first.load([(EX.r, EX.a, Literal("on"))])
    second.load([(EX.s, EX.a, Literal("on"))])
    first.apply(added=[(EX.r, EX.battery, Literal("high"))])
    second.apply(added=[(EX.r, EX.battery, Literal("high"))])  # no ex:a of ex:r here
    assert (EX.r, EX.seen, Literal("on")) in first
    assert (EX.r, EX.seen, Literal("on")) not in second
    assert set(second.match(None, EX.seen, None)) == set()


def test_owl_rules_of_one_axiom_kind_share_code_across_ontologies():
    one = RuleEngine([], [(EX.Speaker, RDF.type, EX.Device)])
    tbox = read_graph([ROOT / "ontology" / "selfconfig.ttl"])
    project = RuleEngine([], tbox)
    subclass = [c.heads.__code__ for c in project._compiled if c.label == "cax-sco"]
    assert len(subclass) > 10 and len(set(subclass)) == 1
    assert {c.heads.__code__ for c in one._compiled if c.label == "eq-sym"} == {
        c.heads.__code__ for c in project._compiled if c.label == "eq-sym"
    }
