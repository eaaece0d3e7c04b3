"""Where this engine knowingly differs from Jena 4.5: each row of docs/rules.md's table, pinned."""

from __future__ import annotations

import pytest
from rdflib import XSD, BNode, Literal, Namespace

from space.reasoning import RuleEngine, RuleError, default_registry, parse_rules

EX = Namespace("http://example.org/")
REG = default_registry()


def run(text: str, data=()) -> RuleEngine:
    engine = RuleEngine(parse_rules(text, REG, source="t.rules"), owl=False)
    engine.load(data)
    return engine


def test_unknown_builtins_and_arities_are_refused_when_read_not_when_fired():
    with pytest.raises(RuleError, match=r"t\.rules:1:14: unknown builtin 'frob'"):
        parse_rules("(?a ?b ?c) , frob(?a) -> (?a ?b ?c) .", REG, source="t.rules")
    with pytest.raises(RuleError, match=r"addOne\(\) takes 2 arguments, got 1"):
        parse_rules("(?a ?b ?c), addOne(?a) -> (?a ?b ?c) .", REG, source="t.rules")


def test_a_comment_after_text_and_a_glued_arrow_are_read_where_jena_refuses_the_file():
    engine = run(
        "@prefix ex: <http://example.org/>\n"
        "[r: (?a ex:p ?b)   # Jena: '#' would be a clause here\n"
        "  notEqual(?a, ?b)->(?b ex:q ?a)]  // and this too\n",
        [(EX.a, EX.p, EX.b)],
    )
    assert (EX.b, EX.q, EX.a) in engine


def test_a_language_tag_glued_to_a_string_tags_it():
    (rule,) = parse_rules("(?a ?b 'chat'@fr) -> (?a ?b ?b) .", REG)
    assert rule.body[0].o == Literal("chat", lang="fr")


def test_decimal_arithmetic_gives_a_double_where_jena_truncates_to_an_integer():
    engine = run(
        "@prefix ex: <http://example.org/>\n"
        "(?x ex:a ?a), sum(?a, '1.5'^^xsd:decimal, ?c) -> (?x ex:c ?c) .",
        [(EX.x, EX.a, Literal("1", datatype=XSD.int))],
    )
    assert set(engine.graph.objects(EX.x, EX.c)) == {Literal(2.5)}


def test_backward_conclusions_are_seen_by_forward_rules_unlike_jenas_hybrid_engine():
    engine = run(
        "@prefix ex: <http://example.org/>\n"
        "[b: (?x ex:q ?y) <- (?x ex:p ?y)]\n"
        "[f: (?x ex:q ?y) -> (?x ex:r ?y)]\n",
        [(EX.a, EX.p, EX.b)],
    )
    assert (EX.a, EX.r, EX.b) in engine  # Jena (hybrid): no ex:r, forward rules miss ex:q


def test_java_regex_classes_are_translated_and_what_python_lacks_is_refused_on_load():
    engine = run(
        "@prefix ex: <http://example.org/>\n"
        "(?x ex:name ?n), regex(?n, '(\\\\p{Alpha}+)-(\\\\p{Digit}+)', ?w, ?d) -> (?x ex:num ?d) .",
        [(EX.r, EX.name, Literal("robot-42"))],
    )
    assert set(engine.graph.objects(EX.r, EX.num)) == {Literal("42")}
    with pytest.raises(RuleError, match=r"t.rules:1:13: regex\(\): .*\\p\{InGreek\} is not supp"):
        text = "(?x ?p ?n), regex(?n, '\\\\p{InGreek}') -> (?x ?p ?p) ."
        parse_rules(text, REG, source="t.rules")


def test_an_unbound_head_variable_is_the_same_blank_node_when_derived_again():
    engine = run("[r: (?a <http://example.org/p> ?b) -> (?a <http://example.org/q> ?c)]")
    engine.apply(added=[(EX.a, EX.p, EX.b)])
    (first,) = engine.graph.objects(EX.a, EX.q)
    engine.apply(removed=[(EX.a, EX.p, EX.b)])
    assert not list(engine.graph.objects(EX.a, EX.q))
    engine.apply(added=[(EX.a, EX.p, EX.b)])
    assert list(engine.graph.objects(EX.a, EX.q)) == [first]  # Jena: a new blank node


def test_a_regex_with_more_outputs_than_groups_binds_what_it_has_as_jena():
    engine = run(
        "@prefix ex: <http://example.org/>\n"
        "(?x ex:name ?n), regex(?n, 'robot-(.*)', ?id, ?more) -> (?x ex:id ?id) .\n"
        "(?x ex:name ?n), regex(?n, 'robot-(.*)', ?id, ?more) -> (?x ex:more ?more) .",
        [(EX.r, EX.name, Literal("robot-42"))],
    )
    assert list(engine.graph.objects(EX.r, EX.id)) == [Literal("42")]
    # ?more stays unbound, and an unbound head variable is a blank node (as in Jena)
    assert [type(o) for o in engine.graph.objects(EX.r, EX.more)] == [BNode]
