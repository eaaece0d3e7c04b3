"""An engine updated with N-Triples texts (`apply_texts`, the reasoner agent's way) tells
the same as one updated with rdflib terms (`apply`): the same deltas, loops and states, in
texts; a malformed text changes nothing.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import Literal, Namespace

from space.errors import MalformedPayload
from space.reasoning import RuleLoopError, build_engine, default_registry, parse_rules
from space.terms import triple_to_nt

EX = Namespace("http://example.org/")
RULES = """@prefix ex: <http://example.org/>.
[low: (?r ex:level "low"), (?r ex:mode ?m), notEqual(?m, "safe") -> drop(1), (?r ex:mode "safe")]
[copy: (?r ex:mode ?m) -> (?r ex:shown ?m)]
[made: (?r ex:level ?l) -> (?r ex:state "idle")]
[flip: (?r ex:spin "yes"), (?r ex:turn "a") -> drop(1), (?r ex:turn "b")]
[flop: (?r ex:spin "yes"), (?r ex:turn "b") -> drop(1), (?r ex:turn "a")]
[num: (?r ex:count ?n), greaterThan(?n, 2) -> (?r ex:many "yes")]
"""
BACKWARD = "[calm: (?r ex:calm 'yes') <- (?r ex:state 'idle')]\n"
NODES = [EX.r1, EX.r2]
PREDICATES = "level mode spin turn shown count".split()
VALUES = [Literal(v) for v in ("low", "safe", "a", "b", "yes", 'caf\u00e9 "x"\n')] + [
    Literal(3),
    Literal("4", datatype=EX.unknown),
    Literal("hi", lang="en"),
]
FACT = st.tuples(
    st.sampled_from(NODES), st.sampled_from([EX[p] for p in PREDICATES]), st.sampled_from(VALUES)
)


def texts(triples: object) -> list[tuple[str, str, str]]:
    return [tuple(triple_to_nt(t)) for t in triples]  # type: ignore[attr-defined]


def told(engine: object, added: list, removed: list, *, as_texts: bool) -> tuple:
    """Return what one update tells its caller, in N-Triples texts either way."""
    try:
        if as_texts:
            delta = engine.apply_texts(texts(added), texts(removed))  # type: ignore[attr-defined]
        else:
            delta = engine.apply(added=added, removed=removed)  # type: ignore[attr-defined]
        loop = None
    except RuleLoopError as error:
        delta, loop = error.kept, error.rules
    convert = (lambda x: list(x)) if as_texts else texts
    return (
        loop,
        sorted(
            (tuple(c.triple) if as_texts else tuple(triple_to_nt(c.triple)), c.origin.value)
            for c in delta.added
        ),
        sorted(
            (tuple(c.triple) if as_texts else tuple(triple_to_nt(c.triple)), c.origin.value)
            for c in delta.removed
        ),
        convert(delta.asserted_added),
        convert(delta.asserted_removed),
        sorted(convert(delta.inferred_added)),
        sorted(convert(delta.inferred_removed)),
        [f.rule for f in delta.firings],
    )


@pytest.mark.parametrize("backward", [False, True], ids=["forward", "hybrid"])
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    updates=st.lists(
        st.tuples(st.lists(FACT, max_size=4), st.lists(FACT, max_size=2)), min_size=1, max_size=6
    )
)
def test_an_update_in_texts_tells_what_one_in_rdflib_terms_tells(
    backward: bool, updates: list
) -> None:
    rules = parse_rules(RULES + (BACKWARD if backward else ""), default_registry())
    by_terms, by_texts = (build_engine(rules, max_firings=40) for _ in "ab")
    for added, removed in updates:
        assert told(by_texts, added, removed, as_texts=True) == told(
            by_terms, added, removed, as_texts=False
        )
        assert sorted(texts(by_texts.triples())) == sorted(texts(by_terms.triples()))
        for s in NODES:
            assert sorted(by_texts.match_texts(f"<{s}>")) == sorted(texts(by_terms.match(s)))
        for triple in [*added, *removed]:
            assert by_texts.holds_texts(*texts([triple])[0]) == (triple in by_terms)


def test_a_malformed_text_changes_nothing_and_is_named() -> None:
    engine = build_engine(parse_rules(RULES, default_registry()))
    good = ("<http://example.org/r1>", "<http://example.org/level>", '"low"')
    engine.apply_texts([("<http://example.org/r1>", "<http://example.org/mode>", '"fast"')])
    before = sorted(texts(engine.triples()))
    for bad in (
        ("<http://example.org/r1>", "<http://example.org/level>", '"unterminated'),
        ('"a literal"', "<http://example.org/level>", '"low"'),
        ("<http://example.org/r1>", "_:b1", '"low"'),
        ("<http://example.org/r1>", "<http://example.org/level>"),
        ("<http://example.org/r1>", "<http://example.org/level>", 7),
    ):
        with pytest.raises(MalformedPayload):
            engine.apply_texts([good, bad])
        assert sorted(texts(engine.triples())) == before
    delta = engine.apply_texts([good])  # the engine goes on
    assert ("<http://example.org/r1>", "<http://example.org/mode>", '"safe"') in (
        delta.asserted_added
    )
    assert engine.match_texts("<http://example.org/never>") is not None
    assert list(engine.match_texts("<http://example.org/never>")) == []
    assert list(engine.match_texts('"not a term')) == []
    assert not engine.holds_texts(*good[:2], '"not a term')


def test_texts_of_one_term_in_other_forms_come_back_in_the_engines_one():
    """Oxigraph writes a UTC dateTime with Z and 1.0 as "1"^^xsd:double; the engine has one
    text per term, the one its deltas carry."""
    engine = build_engine(parse_rules(RULES, default_registry()))
    xsd = "http://www.w3.org/2001/XMLSchema#"
    s, p = "<http://example.org/r1>", "<http://example.org/at>"
    given = [(s, p, f'"2026-01-02T03:04:05Z"^^<{xsd}dateTime>'), (s, p, f'"1"^^<{xsd}double>')]
    same = [
        (s, p, f'"2026-01-02T03:04:05+00:00"^^<{xsd}dateTime>'),
        (s, p, f'"1.0"^^<{xsd}double>'),
    ]
    assert engine.terms.canonical(given) == engine.terms.canonical(same) == same
    delta = engine.apply_texts(given)
    assert sorted(c.triple for c in delta.added if c.triple[0] == s) == sorted(same)
