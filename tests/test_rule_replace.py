"""A production rule that drops one premise and asserts one triple fires on a short path
(`RuleEngine._replace`): the same state, deltas, firings, explanations and undo as `_fire`.

The property test runs random updates on rules where the short path must step aside:
the dropped triple supports an inferred one (`low`, `copy`) or is itself inferred
(`hide`), the head is already there (`made`, `idle`), two rules replace the same triple
(`low`, `calm`), two rules flip a triple back and forth (`flip`, `flop`: a loop, undone).
It compares the engine as built with the same engine firing every rule through `_fire`.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import Literal, Namespace

from space.reasoning import RuleEngine, RuleLoopError, default_registry, parse_rules
from space.reasoning.triples import TripleStore

EX = Namespace("http://example.org/")
RULES = """@prefix ex: <http://example.org/>.
[low: (?r ex:level "low"), (?r ex:mode ?m), notEqual(?m, "safe") -> drop(1), (?r ex:mode "safe")]
[copy: (?r ex:mode ?m) -> (?r ex:shown ?m)]
[back: (?r ex:shown "safe"), (?r ex:tag ?t), notEqual(?t, "seen") -> drop(1), (?r ex:tag "seen")]
[made: (?r ex:level ?l) -> (?r ex:state "idle")]
[idle: (?r ex:go "yes"), (?r ex:state ?s), notEqual(?s, "idle") -> drop(1), (?r ex:state "idle")]
[flip: (?r ex:spin "yes"), (?r ex:turn "a") -> drop(1), (?r ex:turn "b")]
[flop: (?r ex:spin "yes"), (?r ex:turn "b") -> drop(1), (?r ex:turn "a")]
[calm: (?r ex:calm "yes"), (?r ex:mode ?m), notEqual(?m, "fast") -> drop(1), (?r ex:mode "fast")]
[hide: (?r ex:quiet "yes"), (?r ex:shown ?m) -> drop(1), (?r ex:seen ?m)]
[wind: (?r ex:wind ?w) -> drop(0), (?r ex:turn "a")]
"""
NODES = [EX.r1, EX.r2]
PREDICATES = "level mode tag go state spin turn quiet shown wind calm".split()
VALUES = [Literal(v) for v in ("low", "safe", "fast", "seen", "a", "b", "busy", "yes")]
FACT = st.tuples(
    st.sampled_from(NODES),
    st.sampled_from([EX[p] for p in PREDICATES]),
    st.sampled_from(VALUES),
)  # "a" and "b" turns flip, with "yes" for spin


def engines() -> tuple[RuleEngine, RuleEngine]:
    """Return an engine as built and the same one firing every rule through `_fire`."""
    short, general = (
        RuleEngine(parse_rules(RULES, default_registry()), max_firings=40) for _ in "ab"
    )
    replacing = [c.label for c in short._compiled if c.replaces]
    assert replacing == ["low", "back", "idle", "flip", "flop", "calm", "hide", "wind"]
    general._replace = general._fire  # type: ignore[method-assign]
    return short, general


def seen(engine: RuleEngine, added: list, removed: list) -> tuple:
    """Return what one update gives a caller: its delta (or loop), the state, why each holds."""
    try:
        delta, loop = engine.apply(added=added, removed=removed), None
    except RuleLoopError as error:
        delta, loop = error.kept, (str(error), error.rules)
    firings = [(f.rule, f.triggers, f.asserted, f.retracted) for f in delta.firings]
    state = sorted(engine.match())
    return (delta.added, delta.removed, delta.asserted_added, delta.asserted_removed,
            delta.inferred_added, delta.inferred_removed, firings, loop, state,
            [engine.why(t) for t in state])  # fmt: skip


def test_a_replacing_firing_takes_the_short_path_and_the_paths_agree(monkeypatch):
    replaced: list = []
    monkeypatch.setattr(TripleStore, "replace", counted(TripleStore.replace, replaced))
    short, general = engines()
    low, safe, busy, idle, yes = (Literal(v) for v in ("low", "safe", "busy", "idle", "yes"))
    data = [
        (EX.r1, EX.mode, Literal("fast")),
        (EX.r1, EX.level, low),
        (EX.r1, EX.tag, Literal("a")),
    ]
    data += [(EX.r2, EX.go, yes), (EX.r2, EX.state, busy)]
    # `low` drops a mode that supports the inferred `shown`: the general path retracts it;
    # `back` (its tag) and `idle` (r2's state) take the short path.
    assert seen(short, data, []) == seen(general, data, [])
    assert [old[1] for old, _ in replaced] == [term_id(short, EX.tag), term_id(short, EX.state)]
    assert short.why((EX.r2, EX.state, Literal("idle"))).rule == "idle"
    # r1's state "idle" is inferred already (`made`): the head is not new, the general path.
    later = [(EX.r1, EX.go, yes), (EX.r1, EX.state, busy)]
    assert seen(short, later, []) == seen(general, later, [])
    assert len(replaced) == 2
    assert (EX.r1, EX.state, idle) in short and (EX.r1, EX.state, busy) not in short
    # Asserted by the caller and inferred (`copy`): `hide`'s drop leaves it, inferred.
    quiet = [(EX.r1, EX.shown, safe), (EX.r1, EX.quiet, yes)]
    assert seen(short, quiet, []) == seen(general, quiet, [])
    assert len(replaced) == 2
    assert (EX.r1, EX.shown, safe) in short and short.why((EX.r1, EX.shown, safe)).rule == "copy"
    # `wind` asserts r2's turn; then two rules flip it back and forth, on the short path,
    # until the update is a loop: their firings are undone, the turn is `wind`'s again.
    assert seen(short, [(EX.r2, EX.wind, yes)], []) == seen(general, [(EX.r2, EX.wind, yes)], [])
    spin = [(EX.r2, EX.spin, yes)]
    assert seen(short, spin, []) == seen(general, spin, [])
    assert len(replaced) == 3 + 40  # then the 41st firing is one over the limit
    assert (EX.r2, EX.spin, yes) in short and (EX.r2, EX.turn, Literal("a")) in short
    assert short.why((EX.r2, EX.turn, Literal("a"))).rule == "wind"
    assert (EX.r1, EX.mode, safe) in short


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.lists(FACT, max_size=5), st.lists(FACT, max_size=3)), max_size=6))
def test_random_updates_give_the_same_on_both_paths(updates):
    short, general = engines()
    for added, removed in updates:
        assert seen(short, added, removed) == seen(general, added, removed)


def term_id(engine: RuleEngine, term) -> int:
    return engine.terms.id(term)


def counted(method, calls: list):
    def wrapper(self, *args):
        calls.append(args)
        return method(self, *args)

    return wrapper
