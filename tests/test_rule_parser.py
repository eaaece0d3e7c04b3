"""The Jena rule syntax: what parses, into what, and the errors with file, line and column."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from rdflib import Literal, Namespace, URIRef

from space.reasoning import (
    RuleEngine,
    RuleError,
    RuleSyntaxError,
    default_registry,
    load_rules,
    parse_rules,
)
from space.reasoning.rules import Call, Functor, Pattern, Var

DATA = Path(__file__).parent / "data" / "rules"
XSD_NS = "http://www.w3.org/2001/XMLSchema#"
EX = Namespace("http://example.org/")
REG = default_registry()


def parse(text: str) -> list:
    return parse_rules(text, REG, source="t.rules")


def test_named_and_unnamed_rules_with_prefixes_and_comments():
    rules = parse(
        """@prefix ex: <http://example.org/>.
        # a comment
        [r1: (?a ex:p ?b) -> (?b ex:q ?a)]   // another comment
        [(?a rdf:type ex:C) -> (?a rdf:type <http://example.org/D>)]
        """
    )
    assert [r.name for r in rules] == ["r1", None]
    assert rules[0].body == (Pattern(Var("a"), EX.p, Var("b"), rules[0].body[0].where),)
    assert rules[1].head[0].o == EX.D
    assert rules[1].label.startswith("<rule at t.rules:4:")


def test_literals_numbers_and_functors():
    (rule,) = parse(
        """@prefix ex: <http://example.org/>.
        [r: (?a ex:p 'x'), (?a ex:q "y"@en), (?a ex:r '5'^^xsd:int), (?a ex:s 5), (?a ex:t 2.5)
            -> (?a ex:u f(?a, 'z'))]"""
    )
    objects = [p.o for p in rule.body]
    assert objects == [
        Literal("x"),
        Literal("y", lang="en"),
        Literal("5", datatype=URIRef(XSD_NS + "int")),
        Literal("5", datatype=URIRef(XSD_NS + "int")),  # Jena types a bare integer xsd:int
        Literal("2.5", datatype=URIRef(XSD_NS + "float")),  # and a bare decimal xsd:float
    ]
    assert rule.head[0].o == Functor("f", (Var("a"), Literal("z")))


def test_paper_figure_5_parses_with_drop_six_on_the_speed_triple():
    (rule,) = load_rules([Path(__file__).parents[1] / "rules" / "paper.rules"], REG)[:1]
    assert rule.name == "verylow_battery_causes_low_speed_existing"
    drop = rule.head[0]
    assert isinstance(drop, Call) and drop.name == "drop"
    assert rule.body[int(drop.args[0])].p == URIRef(
        "https://w3id.org/tspace/selfconfig#motion_speed"
    )


def test_include_resolves_relative_to_the_including_file_and_shares_prefixes():
    rules = load_rules([DATA / "base.rules"], REG)
    assert [r.name for r in rules] == ["grandparent", "parent"]
    assert rules[0].where.file.endswith("child.rules")


def test_include_cycle_and_missing_file_are_errors():
    with pytest.raises(RuleSyntaxError, match="include cycle"):
        load_rules([DATA / "cycle_a.rules"], REG)
    with pytest.raises(
        RuleSyntaxError, match=r"^t.rules:1:1: cannot include nowhere.rules: no such file$"
    ):
        parse("@include <nowhere.rules>.")
    with pytest.raises(RuleSyntaxError, match=r"^nowhere.rules: no such file$"):
        load_rules(["nowhere.rules"], REG)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[r1: (?a ?b ?c) -> foo(?a)]", "t.rules:1:20: in rule 'r1': unknown builtin 'foo'"),
        (
            "[r1: (?a ?b ?c) notEqual(?a) -> ]",
            "t.rules:1:17: in rule 'r1': notEqual() takes 2 arguments, got 1",
        ),
        (
            "[r1: (?a ?b ?c) isLiteral(?a, ?b) -> ]",
            "t.rules:1:17: in rule 'r1': isLiteral() takes 1 argument, got 2",
        ),
        (
            "[r1: (?a ?b ?c) -> drop(3)]",
            "t.rules:1:20: in rule 'r1': drop(3): the body has only item 0",
        ),
        (
            "[r1: (?a ?b ?c) (?c ?b ?a) -> drop(2)]",
            "t.rules:1:31: in rule 'r1': drop(2): the body has items 0..1",
        ),
        (
            "[r1: (?a ?b ?c) notEqual(?a, 1) -> drop(1)]",
            "in rule 'r1': drop(1): body item 1 is not a triple",
        ),
        (
            "\n[r2: (?a ?b ?c) -> print(?d)]",
            "t.rules:2:20: in rule 'r2': variable ?d in the head is not bound by the body",
        ),
        ("[r3: (?a x:b ?c) -> ]", "t.rules:1:10: in rule 'r3': unknown prefix 'x:'"),
        ("[r4: (?a ?b ?c) -> notEqual(?a, ?b)]", "notEqual() cannot be used in a rule's head"),
        (
            "[r5: [(?a ?b ?c) -> (?a ?b ?c)] -> ]",
            "t.rules:1:6: in rule 'r5': a rule cannot be nested in a body",
        ),
        ("[r6: (?a ?b ?c * )]", "t.rules:1:16: in rule 'r6': wildcard variables"),
        ("[r7: (?a ?b) -> ]", "t.rules:1:6: in rule 'r7': a triple has 3 nodes, this one has 2"),
        ("[(?a ?b ?c) lessThan(?x, 1) -> ]", "lessThan() needs ?x bound, but nothing binds it"),
    ],
)
def test_rule_errors_name_file_line_column_and_rule(text, message):
    with pytest.raises(RuleError) as caught:
        parse(text)
    assert message in str(caught.value)


def test_syntax_error_says_where_and_in_which_rule():
    text = "[ok: (?a ?b ?c) -> (?a ?b ?c)]\n\n[broken: (?a ?b ?c -> (?a ?b ?c)]"
    with pytest.raises(RuleSyntaxError) as caught:
        parse(text)
    assert str(caught.value) == (
        "t.rules:3:20: in rule 'broken': syntax error: unexpected '->' (a '(' is not closed)"
    )


def test_unterminated_rule_is_a_syntax_error_at_the_end():
    with pytest.raises(
        RuleSyntaxError, match=r"t.rules:1:27: in rule 'r9': syntax error: string not closed"
    ):
        parse("[r9: (?a ?b ?c) -> (?a ?b 'x")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "[r1: (?a ?b ?c) -> (?a ?b ?c)\n\n[r2: (?a ?b ?c) -> (?a ?b ?c)]\n",
            "t.rules:4:1: syntax error: unexpected end of file:"
            " expected ']' to close rule 'r1' opened at line 1",
        ),
        (
            "[ok: (?a ?b ?c) -> (?a ?b ?c)]\n[(?a ?b ?c) -> (?a ?b ?c)",
            "t.rules:2:26: syntax error: unexpected end of file:"
            " expected ']' to close the rule opened at line 2",
        ),
        (
            "[r1: (?a ?b ?c) -> (?a ?b",
            "t.rules:1:26: in rule 'r1': syntax error: unexpected end of file:"
            " expected ')' to close the '(' opened at line 1",
        ),
        (
            "[r1: (?a ?b ?c) -> (?a ?b ?c) .\n(?a ?b ?c) -> (?a ?b ?c)\n",
            "t.rules:3:1: syntax error: unexpected end of file:"
            " expected '.' to end the rule started at line 2",
        ),
    ],
)
def test_an_early_end_of_file_says_so_and_what_is_left_open(text, message):
    with pytest.raises(RuleSyntaxError) as caught:
        parse(text)
    assert str(caught.value) == message


def test_a_rule_name_used_twice_is_accepted_with_a_warning_naming_both_places(tmp_path, caplog):
    rules = parse(
        "@prefix ex: <http://example.org/>\n[r1: (?a ex:p ?b) -> (?b ex:q ?a)]\n"
        "  [r1: (?a ex:q ?b) -> (?a ex:r ?b)]"
    )
    assert [r.label for r in rules] == ["r1 (t.rules:2)", "r1 (t.rules:3)"]
    assert "t.rules:3:3: rule name 'r1' is used again, first at t.rules:2:1" in caplog.text
    (tmp_path / "inner.rules").write_text("[r1: (?a ?b ?c) -> (?a ?b ?c)]\n")
    outer = tmp_path / "outer.rules"
    outer.write_text("@include <inner.rules>.\n[r1: (?a ?b ?c) -> (?c ?b ?a)]\n")
    caplog.clear()
    assert len(load_rules([outer], REG)) == 2
    again = r"outer.rules:2:1: rule name 'r1' is used again, first at .*inner.rules:1:1"
    assert re.search(again, caplog.text)
    # Firings name each rule by name and file:line.
    engine = RuleEngine(rules, owl=False)
    engine.load([(EX.a, EX.p, EX.b)])
    assert engine.why((EX.b, EX.q, EX.a)).rule == "r1 (t.rules:2)"
    assert engine.why((EX.b, EX.r, EX.a)).rule == "r1 (t.rules:3)"
    assert [r.name for r in parse("[(?a ?b ?c) -> (?a ?b ?c)] [(?a ?b ?c) -> (?c ?b ?a)]")] == [
        None,
        None,
    ]
