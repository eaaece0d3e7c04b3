"""OWL RL's equality joins wait while no owl:sameAs triple is stored (`RuleIndex.gate`).

Every new triple would start eq-rep-s/p/o, whose joins need an owl:sameAs triple to
match. The property test runs random updates, where owl:sameAs appears in the middle of
one (asserted by a production rule's firing, or inferred from a functional property),
against the same engine with the gate open: states, deltas (in order) and firings
(in order) must be equal.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import OWL, RDF, Literal, Namespace

from space.reasoning import RuleEngine, default_registry, parse_rules

EX = Namespace("http://example.org/")
ONTOLOGY = [
    (EX.owner, RDF.type, OWL.FunctionalProperty),  # two owners: they are the same (prp-fp)
    (EX.Robot, RDF.type, OWL.Class),
]
# A production rule that says two robots are the same in the middle of an update, after
# `tag` fired and before `mark`: the equality joins must start exactly from there.
RULES = """@prefix ex: <http://example.org/>.
[tag: (?r ex:level "low"), (?r ex:tag ?t), notEqual(?t, "done") -> drop(1), (?r ex:tag "done")]
[merge: (?a ex:twin ?b), (?a ex:level "low") -> drop(0), (?a owl:sameAs ?b)]
[mark: (?r ex:level "low"), (?r ex:mark ?m), notEqual(?m, "x") -> drop(1), (?r ex:mark "x")]
"""
NODES = [EX.r1, EX.r2, EX.r3, EX.o1, EX.o2]
FACT = st.one_of(
    st.tuples(st.sampled_from(NODES[:3]), st.just(EX.level), st.just(Literal("low"))),
    st.tuples(st.sampled_from(NODES[:3]), st.just(EX.tag), st.sampled_from([Literal("a")])),
    st.tuples(st.sampled_from(NODES[:3]), st.just(EX.mark), st.sampled_from([Literal("m")])),
    st.tuples(st.sampled_from(NODES[:3]), st.just(EX.twin), st.sampled_from(NODES[:3])),
    st.tuples(st.sampled_from(NODES[:3]), st.just(EX.owner), st.sampled_from(NODES[3:])),
    st.tuples(st.sampled_from(NODES[:3]), st.just(RDF.type), st.just(EX.Robot)),
    st.tuples(st.sampled_from(NODES[:3]), st.just(OWL.sameAs), st.sampled_from(NODES[:3])),
)


def engines() -> tuple[RuleEngine, RuleEngine]:
    """Return an engine as built (gated) and the same with the gate held open."""
    gated, open_ = (RuleEngine(parse_rules(RULES, default_registry()), ONTOLOGY) for _ in "ab")
    assert gated._index._gate is not None
    open_._index._ungated = open_._index.anywhere  # as before: every triple starts them
    return gated, open_


def seen(delta) -> tuple:
    firings = [(f.rule, f.triggers, f.asserted, f.retracted) for f in delta.firings]
    return (delta.added, delta.removed, delta.asserted_added, delta.asserted_removed,
            delta.inferred_added, delta.inferred_removed, firings)  # fmt: skip


def test_a_sameas_asserted_by_a_firing_starts_the_equality_joins_from_then_on():
    gated, open_ = engines()
    assert len(gated._index.starts(0, 0)) == len(open_._index.starts(0, 0)) - 3  # eq-rep-s/p/o
    data = [(EX.r1, EX.twin, EX.r2), (EX.r2, EX.mark, Literal("m")), (EX.r2, EX.tag, Literal("a"))]
    deltas = [e.load(data) for e in (gated, open_)]
    assert seen(deltas[0]) == seen(deltas[1])
    deltas = [e.apply(added=[(EX.r1, EX.level, Literal("low"))]) for e in (gated, open_)]
    assert seen(deltas[0]) == seen(deltas[1])
    # After `merge`, eq-rep-s gives r2 r1's level and r1 r2's tag and mark: both robots'
    # tag and mark rules fire (not before: `merge` is first in rule order).
    assert [f.rule for f in deltas[0].firings] == ["merge", "tag", "tag", "mark", "mark"]
    assert (EX.r1, EX.mark, Literal("x")) in gated
    assert set(gated.triples()) == set(open_.triples())


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(FACT, max_size=8),
    st.lists(st.tuples(st.lists(FACT, max_size=4), st.lists(FACT, max_size=3)), max_size=4),
)
def test_random_updates_see_the_same_states_deltas_and_firings_as_without_the_gate(loaded, updates):
    gated, open_ = engines()
    assert seen(gated.load(loaded)) == seen(open_.load(loaded))
    for added, removed in updates:
        deltas = [e.apply(added=added, removed=removed) for e in (gated, open_)]
        assert seen(deltas[0]) == seen(deltas[1])
        assert set(gated.triples()) == set(open_.triples())
