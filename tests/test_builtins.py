"""Each builtin, as a rule author sees it: which matches it accepts and what it binds."""

from __future__ import annotations

from datetime import UTC, datetime

import pytest
from rdflib import XSD, BNode, Literal, Namespace, URIRef

from space.reasoning import Builtin, RuleEngine, default_registry, parse_rules
from space.reasoning.builtins import Args, Context

XSD_NS = "http://www.w3.org/2001/XMLSchema#"
EX = Namespace("http://example.org/")
PREFIX = "@prefix ex: <http://example.org/>.\n"


def derive(rule: str, data: list, registry=None) -> set:
    """Run one rule over data; return the objects of its ex:out triples."""
    registry = registry or default_registry()
    engine = RuleEngine(parse_rules(PREFIX + rule, registry), registry=registry, owl=False)
    engine.load(data)
    return set(engine.graph.objects(None, EX.out))


VALUES = [
    (EX.a, EX.v, Literal(1)),
    (EX.b, EX.v, Literal("1.0", datatype=URIRef(XSD_NS + "decimal"))),
    (EX.c, EX.v, Literal(2)),
    (EX.d, EX.v, Literal("low")),
]


def test_equal_and_not_equal_compare_by_value():
    same = "[r: (?x ex:v ?a), (?y ex:v ?b), equal(?a, ?b), notEqual(?x, ?y) -> (ex:r ex:out ?x)]"
    assert derive(same, VALUES) == {EX.a, EX.b}  # 1 equals 1.0
    assert derive("[r: (?x ex:v ?a), notEqual(?a, 'low') -> (ex:r ex:out ?x)]", VALUES) == {
        EX.a,
        EX.b,
        EX.c,
    }


def test_a_simple_literal_is_an_xsd_string():
    typed = Literal("low", datatype=URIRef(XSD_NS + "string"))
    data = [(EX.a, EX.v, typed), (EX.b, EX.v, Literal("low")), (EX.c, EX.v, Literal("high"))]
    same = "[r: (?x ex:v ?a), (?y ex:v ?b), equal(?a, ?b), notEqual(?x, ?y) -> (ex:r ex:out ?x)]"
    assert derive(same, data) == {EX.a, EX.b}
    assert derive("[r: (?x ex:v ?a), notEqual(?a, 'low') -> (ex:r ex:out ?x)]", data) == {EX.c}
    assert derive("[r: (?x ex:v 'low') -> (ex:r ex:out ?x)]", [data[0]]) == {EX.a}
    missing = "[r: (?x ex:v ?a), noValue(?x, ex:v, 'low'^^xsd:string) -> (ex:r ex:out ?x)]"
    assert derive(missing, data) == {EX.c}


@pytest.mark.parametrize(
    ("name", "expected"),
    [("lessThan", {EX.c}), ("greaterThan", {EX.a, EX.b}), ("le", {EX.c}), ("ge", {EX.a, EX.b})],
)
def test_orderings_compare_numbers_and_skip_strings(name, expected):
    rule = f"[r: (?x ex:v ?a), {name}(1.5, ?a) -> (ex:r ex:out ?x)]"
    assert derive(rule, VALUES) == expected


def test_orderings_on_date_times():
    early = Literal(datetime(2024, 1, 1, tzinfo=UTC))
    late = Literal(datetime(2024, 6, 1, tzinfo=UTC))
    data = [(EX.a, EX.t, early), (EX.b, EX.t, late)]
    rule = "[r: (?x ex:t ?a), (?y ex:t ?b), lessThan(?a, ?b) -> (?x ex:out ?y)]"
    assert derive(rule, data) == {EX.b}


@pytest.mark.parametrize(
    ("call", "result"),
    [
        # Jena types an integer result xsd:int; min and max give the argument itself.
        ("sum(?a, ?b, ?c)", Literal("9", datatype=XSD.int)),
        ("difference(?a, ?b, ?c)", Literal("3", datatype=XSD.int)),
        ("product(?a, ?b, ?c)", Literal("18", datatype=XSD.int)),
        ("quotient(?a, ?b, ?c)", Literal("2", datatype=XSD.int)),
        ("min(?a, ?b, ?c)", Literal(3)),
        ("max(?a, ?b, ?c)", Literal(6)),
    ],
)
def test_arithmetic_binds_its_last_argument(call, result):
    data = [(EX.x, EX.a, Literal(6)), (EX.x, EX.b, Literal(3))]
    rule = f"[r: (?x ex:a ?a), (?x ex:b ?b), {call} -> (?x ex:out ?c)]"
    assert derive(rule, data) == {result}


@pytest.mark.parametrize(
    ("a", "b", "result"),
    [
        ("7", "2", Literal("3", datatype=XSD.int)),
        ("-7", "2", Literal("-3", datatype=XSD.int)),
        ("7", "-2", Literal("-3", datatype=XSD.int)),
        ("7.0e0", "2", Literal(3.5)),
        ("7", "2.0", Literal(3.5)),
    ],
)
def test_quotient_of_two_integers_is_truncated_as_in_jena(a, b, result):
    rule = f"[r: (?x ex:p ?y), quotient({a}, {b}, ?c) -> (?x ex:out ?c)]"
    assert derive(rule, [(EX.x, EX.p, EX.y)]) == {result}


def test_arithmetic_checks_a_bound_result_and_add_one_counts():
    data = [(EX.x, EX.a, Literal(6)), (EX.x, EX.b, Literal(3)), (EX.x, EX.c, Literal(9))]
    checked = "[r: (?x ex:a ?a), (?x ex:b ?b), (?x ex:c ?c), sum(?a, ?b, ?c) -> (?x ex:out 'yes')]"
    assert derive(checked, data) == {Literal("yes")}
    assert derive("[r: (?x ex:a ?a), addOne(?a, ?n) -> (?x ex:out ?n)]", data) == {
        Literal("7", datatype=XSD.int)
    }
    assert derive("[r: (?x ex:a ?a), quotient(?a, 0, ?n) -> (?x ex:out ?n)]", data) == set()


def test_string_builtins():
    data = [(EX.x, EX.name, Literal("robot-42"))]
    joined = "[r: (?x ex:name ?n), strConcat(?n, '!', ?s) -> (?x ex:out ?s)]"
    assert derive(joined, data) == {Literal("robot-42!")}
    uri = "[r: (?x ex:name ?n), uriConcat('http://example.org/', ?n, ?u) -> (?x ex:out ?u)]"
    assert derive(uri, data) == {URIRef("http://example.org/robot-42")}
    groups = "[r: (?x ex:name ?n), regex(?n, '(\\\\w+)-(\\\\d+)', ?w, ?d) -> (?x ex:out ?d)]"
    assert derive(groups, data) == {Literal("42")}
    assert derive("[r: (?x ex:name ?n), regex(?n, 'robot') -> (?x ex:out 1)]", data) == set()


def test_kind_tests():
    node = BNode()
    data = [
        (EX.x, EX.p, Literal("s")),
        (EX.x, EX.p, node),
        (EX.x, EX.p, EX.y),
        (EX.x, EX.p, Literal("5", datatype=URIRef(XSD_NS + "int"))),
    ]
    assert derive(
        "[r: (?x ex:p ?o), isLiteral(?o), isDType(?o, xsd:int) -> (?x ex:out ?o)]", data
    ) == {Literal("5", datatype=URIRef(XSD_NS + "int"))}
    assert derive("[r: (?x ex:p ?o), isBNode(?o) -> (?x ex:out ?o)]", data) == {node}
    assert derive("[r: (?x ex:p ?o), notLiteral(?o), notBNode(?o) -> (?x ex:out ?o)]", data) == {
        EX.y
    }
    not_int = "[r: (?x ex:p ?o), isLiteral(?o), notDType(?o, xsd:int) -> (?x ex:out ?o)]"
    assert derive(not_int, data) == {Literal("s")}


def test_bound_and_unbound():
    data = [(EX.x, EX.p, EX.y)]
    assert derive("[r: (?x ex:p ?o), bound(?o) -> (?x ex:out 'b')]", data) == {Literal("b")}
    assert derive("[r: (?x ex:p ?o), unbound(?z) -> (?x ex:out 'u')]", data) == {Literal("u")}
    assert derive("[r: (?x ex:p ?o), unbound(?o) -> (?x ex:out 'u')]", data) == set()


def test_make_temp_skolem_instance_and_now():
    data = [(EX.a, EX.p, EX.b)]
    temps = derive("[r: (?x ex:p ?y), makeTemp(?t) -> (?x ex:out ?t)]", data)
    assert len(temps) == 1 and isinstance(next(iter(temps)), BNode)
    skolem = "[r: (?x ex:p ?y), makeSkolem(?t, ?x, ?y) -> (?x ex:out ?t)]"
    assert derive(skolem, data) == derive(skolem, data)  # same arguments, same node
    instance = "[r: (?x ex:p ?y), makeInstance(?x, ex:p, ?v) -> (?x ex:out ?v)]"
    assert derive(instance, data) == derive(instance, data)
    (now,) = derive("[r: (?x ex:p ?y), now(?t) -> (?x ex:out ?t)]", data)
    assert abs((now.toPython() - datetime.now(UTC)).total_seconds()) < 5


def test_print_writes_its_arguments():
    lines: list[str] = []
    rules = parse_rules(PREFIX + "[r: (?x ex:p ?y) -> print('saw', ?x)]", default_registry())
    engine = RuleEngine(rules, owl=False, printer=lines.append)
    engine.load([(EX.a, EX.p, EX.b)])
    assert lines == ['"saw" <http://example.org/a>']


def test_no_value_accepts_only_when_nothing_matches():
    rule = "[r: (?x ex:p ?y), noValue(?x, ex:q) -> (?x ex:out 'none')]"
    assert derive(rule, [(EX.a, EX.p, EX.b)]) == {Literal("none")}
    assert derive(rule, [(EX.a, EX.p, EX.b), (EX.a, EX.q, EX.c)]) == set()


class IsEven(Builtin):
    """Accept an even integer (a builtin a test adds to its own registry)."""

    name = "isEven"
    arity = (1, 1)

    def run(self, ctx: Context, args: Args) -> Args | None:
        value = ctx.terms.keys[args[0]]
        return args if isinstance(value, int) and value % 2 == 0 else None


def test_a_registry_takes_new_builtins_without_touching_the_default():
    registry = default_registry()
    registry.register(IsEven())
    data = [(EX.a, EX.v, Literal(2)), (EX.b, EX.v, Literal(3))]
    assert derive("[r: (?x ex:v ?n), isEven(?n) -> (?x ex:out ?n)]", data, registry) == {Literal(2)}
    assert "isEven" not in default_registry()
