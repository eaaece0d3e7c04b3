"""Terms and key expressions: what travels on the wire reads back the same."""

import pytest
import zenoh
from rdflib import BNode, Literal, URIRef

from space.errors import MalformedPayload
from space.keys import parse_triple_key, template_key, triple_key
from space.prefixes import PrefixMap
from space.terms import from_nt, to_nt

AC = "https://w3id.org/tspace/selfconfig#"
TERMS = [
    URIRef("http://example.org/a/b#c"),
    Literal("very low"),
    Literal('quote " and \\ and\nnewline'),
    Literal(5),
    Literal("5.0", datatype=URIRef("http://www.w3.org/2001/XMLSchema#decimal")),
    Literal("bonjour", lang="fr"),
    BNode("b42"),
    Literal("50% a/b*c?d#e$f"),
]


@pytest.mark.parametrize("term", TERMS, ids=repr)
def test_term_round_trips_through_ntriples(term):
    back = from_nt(to_nt(term))
    assert back == term and type(back) is type(term)


@pytest.mark.parametrize("text", ["", "plain", "<unclosed", '"unclosed', "_:"])
def test_malformed_term_text_is_rejected(text):
    with pytest.raises(MalformedPayload):
        from_nt(text)


@pytest.mark.parametrize("obj", TERMS, ids=repr)
def test_triple_key_is_a_legal_zenoh_key_and_reversible(obj):
    prefixes = PrefixMap({"ac": AC})
    triple = (URIRef(AC + "robot1"), URIRef(AC + "battery_level"), obj)
    key = triple_key("default", "t", triple, prefixes)
    assert str(zenoh.KeyExpr(key)) == key
    assert parse_triple_key(key, prefixes) == ("default", "t", triple)


def test_subject_and_predicate_are_readable_and_filterable():
    prefixes = PrefixMap({"ac": AC})
    triple = (URIRef(AC + "robot1_battery"), URIRef(AC + "battery_level"), Literal("low"))
    key = triple_key("default", "t", triple, prefixes)
    assert key == 'tspace/default/t/ac:robot1_battery/ac:battery_level/"low"'
    assert zenoh.KeyExpr("tspace/default/t/*/ac:battery_level/*").intersects(key)
    assert zenoh.KeyExpr("tspace/default/*/ac:robot1_battery/**").intersects(key)
    assert not zenoh.KeyExpr("tspace/other/t/**").intersects(key)


def test_unprefixed_iri_is_escaped_not_dropped():
    triple = (
        URIRef("http://x.org/a/b"),
        URIRef("http://x.org/p?q=1"),
        URIRef("http://x.org/#frag"),
    )
    key = triple_key("s", "t", triple, PrefixMap())
    assert "/" not in key.split("/", 3)[3].replace("%2F", "").split("/", 2)[0]
    assert parse_triple_key(key, PrefixMap())[2] == triple


def test_template_key_turns_variables_into_wildcards():
    prefixes = PrefixMap({"ac": AC})
    key = template_key("s", "t", (None, URIRef(AC + "battery_level"), None), prefixes)
    assert key == "tspace/s/t/*/ac:battery_level/*"


def test_key_with_unknown_prefix_is_rejected():
    with pytest.raises(MalformedPayload):
        parse_triple_key("tspace/s/t/zz:a/zz:b/zz:c", PrefixMap())


TRICKY = [
    'café "x"',
    "naïve\\path",
    "tab\there\nnewline",
    "日本語 ☃ 𝄞",
    "quote ' and \\u0041 literal",
]


def test_every_string_round_trips_through_the_term_codec():
    for text in TRICKY:
        for term in (
            Literal(text),
            Literal(text, lang="fr"),
            Literal(text, datatype=URIRef("http://www.w3.org/2001/XMLSchema#token")),
        ):
            assert from_nt(to_nt(term)) == term


def test_a_template_reads_non_ascii_and_escapes_as_turtle_does():
    from space import Template

    template = Template.parse('?s ?p "café \\"x\\" \\u00e9\\n"')
    assert template.pattern()[2] == Literal('café "x" é\n')


def test_a_rule_file_reads_literals_as_jena_does():
    """Jena's rule tokenizer keeps the character after a backslash as it is (no \\t, no \\u)."""
    from space.reasoning import default_registry, parse_rules

    rules = parse_rules(
        '[r: (?s <http://e/p> "café \\"x\\"\\t") -> (?s <http://e/q> "ok")]', default_registry()
    )
    assert rules[0].body[0].o == Literal('café "x"t')
