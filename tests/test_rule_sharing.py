"""Rules whose joins start alike share that start (`space/reasoning/sharing.py`), changing nothing.

Each test checks that the rules do share (the engine's index says how many joins
run a shared prefix), then what a user sees: conclusions, retractions, firings.
The property test runs random rule sets built around a common core, with their
variables renamed and their bodies reordered, against the same engine with
sharing turned off: states, deltas and firing order must be equal.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import RDF, Literal, Namespace

from space.reasoning import RuleEngine, RuleLoopError, default_registry, parse_rules, sharing

EX = Namespace("http://example.org/")
PREFIX = "@prefix ex: <http://example.org/>.\n"
LOW = Literal("low")


def engine(rules: str, **options) -> RuleEngine:
    return RuleEngine(parse_rules(PREFIX + rules, default_registry()), owl=False, **options)


# Different variable names and body orders; the same join from (?b ex:level "low") up to
# the robot's type: `slow`'s whole join is the start of `dim`'s.
MONOTONIC = """
[slow: (?r ex:has ?b), (?b ex:level "low"), (?r rdf:type ex:Robot) -> (?r ex:speed "slow")]
[dim: (?robot rdf:type ex:Robot), (?bat ex:level "low"), (?robot ex:has ?bat), (?robot ex:screen ?s)
    -> (?s ex:brightness "dim")]
"""
ROBOT = [
    (EX.r1, RDF.type, EX.Robot),
    (EX.r1, EX.has, EX.b1),
    (EX.r1, EX.screen, EX.s1),
    (EX.r2, RDF.type, EX.Robot),
    (EX.r2, EX.has, EX.b2),
    (EX.r2, EX.screen, EX.s2),
]
CONCLUSIONS = {(EX.r1, EX.speed, Literal("slow")), (EX.s1, EX.brightness, Literal("dim"))}


def test_rules_sharing_a_prefix_each_conclude_and_one_deleted_premise_retracts_both():
    e = engine(MONOTONIC)
    assert e._index.shared >= 2
    e.load(ROBOT)
    delta = e.apply(added=[(EX.b1, EX.level, LOW)])
    assert {change.triple for change in delta.added} == {(EX.b1, EX.level, LOW), *CONCLUSIONS}
    assert e.why((EX.s1, EX.brightness, Literal("dim"))).premises == (
        (EX.r1, RDF.type, EX.Robot),
        (EX.b1, EX.level, LOW),
        (EX.r1, EX.has, EX.b1),
        (EX.r1, EX.screen, EX.s1),
    )
    delta = e.apply(removed=[(EX.r1, RDF.type, EX.Robot)])  # a premise of the shared prefix
    assert CONCLUSIONS <= {change.triple for change in delta.removed}
    assert not CONCLUSIONS & set(e.triples())
    e.apply(added=[(EX.r1, RDF.type, EX.Robot)])
    assert CONCLUSIONS <= set(e.triples())
    e.apply(removed=[(EX.b1, EX.level, LOW)])  # the seed itself
    assert not CONCLUSIONS & set(e.triples())
    e.apply(added=[(EX.b2, EX.level, LOW)])  # the other robot's: nothing of the first comes back
    assert set(e.match(None, EX.brightness, None)) == {(EX.s2, EX.brightness, Literal("dim"))}
    assert set(e.match(None, EX.speed, None)) == {(EX.r2, EX.speed, Literal("slow"))}


def test_each_rule_of_a_group_binds_its_own_variables_from_the_shared_prefix():
    e = engine(MONOTONIC)
    e.load(ROBOT)
    e.apply(added=[(EX.b1, EX.level, LOW), (EX.b2, EX.level, LOW)])
    assert set(e.match(None, EX.speed, None)) == {
        (EX.r1, EX.speed, Literal("slow")),
        (EX.r2, EX.speed, Literal("slow")),
    }
    assert set(e.match(None, EX.brightness, None)) == {
        (EX.s1, EX.brightness, Literal("dim")),
        (EX.s2, EX.brightness, Literal("dim")),
    }


PRODUCTION = """
[quiet: (?r rdf:type ex:Robot), (?r ex:has ?b), (?b ex:level "low"), (?r ex:volume ?v),
    notEqual(?v, "low") -> drop(3), (?r ex:volume "low")]
[slow: (?bat ex:level "low"), (?robot ex:has ?bat), (?robot rdf:type ex:Robot),
    (?robot ex:speed ?s), notEqual(?s, "low") -> drop(3), (?robot ex:speed "low")]
[dark: (?x ex:has ?y), (?y ex:level "low"), (?x rdf:type ex:Robot), (?x ex:light ?l),
    notEqual(?l, "low") -> drop(3), (?x ex:light "low")]
"""


def test_production_rules_sharing_a_prefix_fire_in_rule_order_each_on_its_own_setting():
    e = engine(PRODUCTION)
    assert e._index.shared >= 3
    settings_ = [(EX.r1, p, Literal("normal")) for p in (EX.volume, EX.speed, EX.light)]
    e.load([*ROBOT, *settings_])
    delta = e.apply(added=[(EX.b1, EX.level, LOW)])
    assert [f.rule for f in delta.firings] == ["quiet", "slow", "dark"]
    assert [f.retracted for f in delta.firings] == [(t,) for t in settings_]
    assert set(delta.asserted_added) == {(EX.r1, t[1], LOW) for t in settings_}
    assert delta.firings[1].triggers[0] == (EX.b1, EX.level, LOW)  # in slow's body order
    assert not set(e.match(EX.r2, None, LOW))


def test_a_head_added_between_two_rules_of_a_group_is_seen_by_the_second():
    # `near` (the leader) concludes a new ex:near for the battery's robot; `park`, in the same
    # group, must see it in the same join as its own body would (its firing's triggers).
    rules = """
    [near: (?b ex:level "low"), (?r ex:has ?b), (?r rdf:type ex:Robot) -> (?r ex:near ex:dock)]
    [park: (?b ex:level "low"), (?r ex:has ?b), (?r rdf:type ex:Robot), (?r ex:near ?p),
        (?p rdf:type ex:Dock), noValue(?r ex:parked ?p) -> (?r ex:parked ?p)]
    """
    shared, plain = engine(rules), _without_sharing(lambda: engine(rules))
    assert shared._index.shared >= 2
    for e in (shared, plain):
        e.load([*ROBOT, (EX.dock, RDF.type, EX.Dock)])
    deltas = [e.apply(added=[(EX.b1, EX.level, LOW)]) for e in (shared, plain)]
    assert (EX.r1, EX.parked, EX.dock) in shared
    assert _firings(deltas[0]) == _firings(deltas[1])


def test_production_rules_of_one_shape_join_as_one_batch_and_fire_as_their_own_joins_would():
    # The paper's rules: one shape, a setting each. Two robots: the shared start finds two.
    rules = "".join(
        f'[set{i}: (?r rdf:type ex:Robot), (?r ex:has ?b), (?b ex:level "low"),'
        f' (?r ex:setting{i} ?v), notEqual(?v, "low") -> drop(3), (?r ex:setting{i} "low")]\n'
        for i in range(4)
    )
    batched, plain = engine(rules), _without_sharing(lambda: engine(rules))
    buckets = [*batched._index.by_po.values(), *batched._index.by_p.values()]
    assert any(compiled is None for bucket in buckets for compiled, _ in bucket)  # a batch
    normal = Literal("normal")
    data = [*ROBOT, (EX.r1, EX.setting0, normal), (EX.r1, EX.setting2, LOW)]
    data += [(EX.r1, EX.setting3, normal), (EX.r2, EX.setting1, normal)]
    data += [(EX.r2, EX.setting3, normal)]
    for e in (batched, plain):
        e.load(data)
    change = [(EX.b1, EX.level, LOW), (EX.b2, EX.level, LOW)]
    deltas = [e.apply(added=change) for e in (batched, plain)]
    assert _firings(deltas[0]) == _firings(deltas[1])
    fired = [(f.rule, f.asserted[0][0]) for f in deltas[0].firings]
    assert sorted(fired) == sorted(
        [("set0", EX.r1), ("set1", EX.r2), ("set3", EX.r1), ("set3", EX.r2)]
    )
    assert [rule for rule, _ in fired] == ["set0", "set1", "set3", "set3"]  # rule order
    assert set(batched.match(None, None, None)) == set(plain.match(None, None, None))
    assert not set(batched.match(None, None, normal))


def _without_sharing(build):
    """Build an engine whose joins share nothing: the engine as it was before sharing."""
    groups = sharing._groups
    sharing._groups = lambda members: {}
    try:
        built = build()
    finally:
        sharing._groups = groups
    assert built._index.shared == 0
    return built


def _firings(delta):
    return [(f.rule, f.triggers, f.asserted, f.retracted) for f in delta.firings]


# ---- random rule sets around one core, against the engine without sharing

CORE = ("(?{a} ex:has ?{b})", '(?{b} ex:level "low")', "(?{a} rdf:type ex:Robot)")
EXTRA = ("(?{b} ex:p ?{c})", "(?{a} ex:q ?{c})", "(?{c} rdf:type ex:K)", "(?{a} ex:has ?{c})")
NODES = [EX.r1, EX.r2, EX.b1, EX.b2, EX.c1]
FACTS = [
    *[(s, EX.has, o) for s in (EX.r1, EX.r2) for o in (EX.b1, EX.b2, EX.c1)],
    *[(s, EX.level, LOW) for s in (EX.b1, EX.b2, EX.c1)],
    *[(s, RDF.type, EX.Robot) for s in (EX.r1, EX.r2)],
    *[(s, EX.p, o) for s in (EX.b1, EX.b2) for o in (EX.c1, EX.r1)],
    *[(s, EX.q, o) for s in (EX.r1, EX.r2) for o in (EX.c1, EX.b2)],
    (EX.c1, RDF.type, EX.K),
    (EX.b2, RDF.type, EX.K),
]


@st.composite
def rule_sets(draw) -> str:
    rules = []
    for i in range(draw(st.integers(2, 4))):
        names = dict(zip("abc", draw(st.permutations(["x", "y", "z"])), strict=True))
        core = draw(st.lists(st.sampled_from(CORE), min_size=2, max_size=3, unique=True))
        extra = draw(st.lists(st.sampled_from(EXTRA), max_size=2, unique=True))
        body = draw(st.permutations(core + extra))
        text = ", ".join(p.format(**names) for p in body)
        bound = {v for p in body for v in "abc" if "{" + v + "}" in p}
        head_var = names[sorted(bound)[-1]]
        if draw(st.booleans()) and extra:
            last = body.index(extra[0])  # drop one extra premise, assert a mark
            rules.append(f"[r{i}: {text} -> drop({last}), (?{head_var} ex:mark{i} 'x')]")
        else:
            rules.append(f"[r{i}: {text} -> (?{head_var} ex:out{i} ?{names['a']})]")
    return "\n".join(rules)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    rules=rule_sets(),
    initial=st.lists(st.sampled_from(FACTS), max_size=8, unique=True),
    steps=st.lists(
        st.tuples(st.booleans(), st.lists(st.sampled_from(FACTS), min_size=1, max_size=3)),
        min_size=1,
        max_size=5,
    ),
)
def test_sharing_changes_no_state_delta_or_firing(rules, initial, steps):
    shared = engine(rules, max_firings=50)
    plain = _without_sharing(lambda: engine(rules, max_firings=50))
    for e in (shared, plain):
        e.load(initial)
    for add, triples in steps:
        results = []
        for e in (shared, plain):
            try:
                delta = e.apply(added=triples) if add else e.apply(removed=triples)
            except RuleLoopError as loop:
                results.append(("loop", loop.rules))
                continue
            results.append(
                (
                    sorted(delta.added),
                    sorted(delta.removed),
                    _firings(delta),
                    sorted(e.triples()),
                )
            )
        assert results[0] == results[1]


@pytest.mark.parametrize("reorder", [False, True])
def test_rules_differing_in_a_prefix_constant_share_nothing_wrongly(reorder):
    # Same structure, different class: a shared join on ex:Robot must not serve ex:Drone.
    rules = [
        '[a: (?b ex:level "low"), (?r ex:has ?b), (?b rdf:type ex:Cell), (?r rdf:type ex:Robot)'
        ' -> (?r ex:slow "yes")]',
        '[b: (?b ex:level "low"), (?r ex:has ?b), (?b rdf:type ex:Cell), (?r rdf:type ex:Drone)'
        ' -> (?r ex:land "yes")]',
    ]
    e = engine("\n".join(reversed(rules) if reorder else rules))
    assert e._index.shared >= 2
    e.load([(EX.r1, RDF.type, EX.Robot), (EX.r1, EX.has, EX.b1), (EX.b1, RDF.type, EX.Cell)])
    e.apply(added=[(EX.b1, EX.level, LOW)])
    assert (EX.r1, EX.slow, Literal("yes")) in e
    assert (EX.r1, EX.land, Literal("yes")) not in e


def test_a_head_the_leader_adds_to_the_shared_prefix_is_seen_by_the_next_rule_at_once():
    # `spare` (the leader) adds a second robot holding the battery: a new match of the
    # shared prefix. `name`, next in the group, must see it in this same join, before `after`
    # runs, as its whole join would: the printed order tells.
    rules = """
    [spare: (?b ex:level "low"), (?r ex:has ?b), (?r rdf:type ex:Robot) -> (ex:r9 ex:has ?b)]
    [name: (?b ex:level "low"), (?r ex:has ?b), (?r rdf:type ex:Robot), (?r ex:name ?n)
        -> print('name', ?n)]
    [after: (?b ex:level "low") -> print('after')]
    """
    printed: tuple[list[str], list[str]] = ([], [])
    shared = engine(rules, printer=printed[0].append)
    plain = _without_sharing(lambda: engine(rules, printer=printed[1].append))
    assert shared._index.shared >= 2
    for e in (shared, plain):
        names = [(EX.r1, EX.name, Literal("one")), (EX.r9, EX.name, Literal("nine"))]
        robots = [(EX.r1, RDF.type, EX.Robot), (EX.r9, RDF.type, EX.Robot)]
        e.load([(EX.r1, EX.has, EX.b1), *names, *robots])
        e.apply(added=[(EX.b1, EX.level, LOW)])
    assert printed[0] == printed[1]
    assert printed[0].index('"name" "nine"') < printed[0].index('"after"')


def test_a_rule_sharing_only_the_common_start_shares_it_with_two_that_share_more():
    # `a` and `b` share five steps from each of their first three seeds, `c` the first three:
    # grouping `a` with `b` alone on five steps left `c` to join the robot, its battery and its
    # type by itself, the very case sharing is for. All three share the three steps.
    start = '(?b ex:level "low"), (?r ex:has ?b), (?r rdf:type ex:Robot)'
    rules = f"""
    [a: {start}, (?r ex:base ?m), (?m ex:speed ?s) -> (?r ex:a ?s)]
    [b: {start}, (?r ex:base ?m), (?m ex:speed ?s) -> (?r ex:b ?s)]
    [c: {start}, (?r ex:screen ?s) -> (?r ex:c ?s)]
    """
    shared, plain = engine(rules), _without_sharing(lambda: engine(rules))
    assert shared._index.shared == 3 * 3 + 2 * 2  # seeds 0-2 of each; a's and b's seeds 3-4
    base = [(EX.r1, EX.base, EX.m1), (EX.m1, EX.speed, Literal(1))]
    for e in (shared, plain):
        e.load([*ROBOT, *base])
    added = [
        {c.triple for c in e.apply(added=[(EX.b1, EX.level, LOW)]).added} for e in (shared, plain)
    ]
    assert added[0] == added[1]
    assert {(EX.r1, p) for p in (EX.a, EX.b, EX.c)} <= {(s, p) for s, p, _ in added[0]}
