"""A fresh engine's load goes set-at-a-time and ends where the incremental path ends.

Same triples, asserted set, derivations and conflicts as asserting the same
triples one update at a time (`apply` on an engine not loaded), on every W3C
OWL 2 case and on generated LUBM-like data; and later deletes and adds stay
exact: the state after each is a fresh materialisation's.
"""

from __future__ import annotations

import importlib.util
import random
import sys
from pathlib import Path

import pytest
from owl2cases import ALL, parse, read_cases
from rdflib import OWL, RDF, RDFS, Literal, Namespace

from space.reasoning import (
    Builtin,
    Origin,
    RuleEngine,
    build_engine,
    default_registry,
    parse_rules,
    read_graph,
    read_triples,
    seminaive,
)
from space.reasoning.support import add, each

ROOT = Path(__file__).resolve().parents[1]
EX = Namespace("http://example.org/")


def _lubm():
    spec = importlib.util.spec_from_file_location("lubm", ROOT / "bench" / "lubm.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["lubm"] = module
    spec.loader.exec_module(module)
    return module


def state(engine: RuleEngine) -> tuple:
    """The engine's whole state, decoded (ids may differ between two engines)."""
    decode = engine.terms.triple
    derivations = {
        decode(t): {(r, tuple(map(decode, p))) for r, p in each(found)}
        for t, found in engine._support.derivations.items()
    }
    dependents = {
        decode(t): set(map(decode, each(users)))
        for t, users in engine._support.dependents.items()
        if users
    }
    return (
        set(map(decode, engine._store)),
        set(map(decode, engine._asserted)),
        derivations,
        dependents,
        set(engine.conflicts()),  # sorted, but ties (two XMLLiterals) keep store order
    )


def both(ontology, data=()) -> tuple[RuleEngine, RuleEngine]:
    """Return an engine loaded in bulk and one given the same triples incrementally."""
    bulk, incremental = RuleEngine([], ontology), RuleEngine([], ontology)
    assert seminaive.eligible(bulk)
    bulk_delta = bulk.load(data)
    incremental_delta = incremental.apply(added=data)
    assert set(bulk_delta.added) == set(incremental_delta.added)
    assert set(bulk_delta.inferred_added) == set(incremental_delta.inferred_added)
    assert not (bulk_delta.removed or bulk_delta.asserted_added or bulk_delta.asserted_removed)
    assert_built_as_support_adds(bulk)
    return bulk, incremental


def assert_built_as_support_adds(engine: RuleEngine) -> None:
    """A bulk load inlines `support.add` (`seminaive._add`): each entry must be what
    `add` builds from the same items (bare, list or set; no repeats), or the two drifted."""
    for mapping in (engine._support.derivations, engine._support.dependents):
        for key, held in mapping.items():
            rebuilt: dict = {}
            for item in each(held):
                add(rebuilt, key, item)
            assert type(rebuilt[key]) is type(held) and rebuilt[key] == held, key


W3C = read_cases() if ALL.exists() else []


@pytest.mark.skipif(not ALL.exists(), reason=f"the W3C OWL 2 test cases are not at {ALL}")
@pytest.mark.filterwarnings("ignore::space.reasoning.UnsupportedAxiom")
def test_every_w3c_case_loads_to_the_incremental_state():
    for case in W3C:
        bulk, incremental = both(parse(case.premise))
        assert state(bulk) == state(incremental), case.identifier


@pytest.fixture(scope="module")
def university(tmp_path_factory) -> tuple[Path, Path]:
    return _lubm().write(2, tmp_path_factory.mktemp("lubm"))


def test_lubm_loads_to_the_incremental_state_and_updates_stay_exact(university):
    ontology, data = university
    tbox, triples = read_graph([ontology]), read_triples([data])
    bulk, incremental = both(tbox, triples)
    assert state(bulk) == state(incremental)
    rnd = random.Random(7)
    # Schema triples too: retracting an axiom retracts what it entailed.
    picked = rnd.sample(triples, 25) + rnd.sample(list(tbox), 5)
    for triple in picked:
        for change in ({"removed": [triple]}, {"added": [triple]}):
            a, b = bulk.apply(**change), incremental.apply(**change)
            assert set(a.added) == set(b.added) and set(a.removed) == set(b.removed)
        assert state(bulk) == state(incremental)
    # And both are a fresh materialisation's after a real change.
    gone = rnd.sample(triples, 200)
    bulk.apply(removed=gone)
    fresh = RuleEngine([], tbox)
    fresh.load([t for t in triples if t not in set(gone)])
    assert set(bulk.triples()) == set(fresh.triples())


def test_load_files_reads_straight_into_the_engine(university):
    ontology, data = university
    tbox = read_graph([ontology])
    by_files, by_triples = RuleEngine([], tbox), RuleEngine([], tbox)
    delta = by_files.load_files([data])
    assert set(delta.added) == set(by_triples.load(read_triples([data])).added)
    assert state(by_files) == state(by_triples)
    assert len(list(by_files.triples(Origin.ASSERTED))) == len(tbox) + len(read_triples([data]))


def test_a_conflict_found_in_bulk_goes_with_its_cause():
    ontology = [(EX.Standby, OWL.disjointWith, EX.Active)]
    data = [(EX.pump, RDF.type, EX.Standby), (EX.pump, RDF.type, EX.Active)]
    bulk, incremental = both(ontology, data)
    assert [c.rule for c in bulk.conflicts()] == ["cax-dw"]
    assert state(bulk) == state(incremental)
    bulk.apply(removed=[data[1]])
    assert bulk.conflicts() == ()


def test_a_triple_derived_many_ways_stays_until_its_last_way_goes():
    # The pump is a Device 12 ways, and one axiom makes 13 Devices: each held bare, in a
    # list, then in a set (support.py), and taken out again one by one.
    ontology = [(EX[f"Kind{i}"], RDFS.subClassOf, EX.Device) for i in range(12)]
    kinds = [(EX.pump, RDF.type, EX[f"Kind{i}"]) for i in range(12)]
    others = [(EX[f"valve{i}"], RDF.type, EX.Kind0) for i in range(12)]
    bulk, incremental = both(ontology, kinds + others)
    device = (EX.pump, RDF.type, EX.Device)
    for change in [{"removed": [ontology[0]]}, {"added": [ontology[0]]}] + [
        {"removed": [t]} for t in kinds
    ]:
        assert device in set(bulk.triples())
        bulk.apply(**change)
        incremental.apply(**change)
        assert state(bulk) == state(incremental)
    assert device not in set(bulk.triples())
    fresh = RuleEngine([], ontology)
    fresh.load(others)
    # A fresh load's, to the dependents: an axiom no longer supports what lost its derivation
    # through another premise.
    assert state(bulk) == state(fresh)


def test_production_rules_keep_the_incremental_path():
    text = "[r: (?x ex:p ?y), noValue(?x ex:q ?y) -> (?x ex:q ?y)]"
    rules = parse_rules(text, default_registry(), prefixes={"ex": str(EX)})
    engine = RuleEngine(rules, [])
    assert not seminaive.eligible(engine)
    engine.load([(EX.a, EX.p, EX.b)])
    assert (EX.a, EX.q, EX.b) in engine


def test_a_hybrid_engines_backward_layer_sees_the_bulk_load_once():
    text = "[b: (?x ex:seen ex:yes) <- (?x rdf:type ex:Device)]"
    prefixes = {"ex": str(EX), "rdf": str(RDF)}
    rules = parse_rules(text, default_registry(), prefixes=prefixes)
    engine = build_engine(rules, [(EX.Speaker, RDFS.subClassOf, EX.Device)])
    delta = engine.load([(EX.s, RDF.type, EX.Speaker)])
    assert (EX.s, EX.seen, EX.yes) in engine
    assert (EX.s, EX.seen, EX.yes) in {change.triple for change in delta.added}
    assert not engine.apply()  # nothing left over from the load for the next update
    engine.apply(removed=[(EX.s, RDF.type, EX.Speaker)])
    assert (EX.s, EX.seen, EX.yes) not in engine


class Boom(Builtin):
    """Fail on a literal "boom": a builtin that raises in the middle of a load."""

    name = "boom"
    arity = (1, 1)

    def run(self, ctx, args):
        if str(ctx.terms.term(args[0])) == "boom":
            raise ValueError("boom")
        return args


def test_a_load_that_fails_leaves_nothing_and_can_be_done_again():
    registry = default_registry()
    registry.register(Boom())
    text = "[r: (?x ex:p ?y), boom(?y) -> (?x ex:q ?y)]"
    rules = parse_rules(text, registry, prefixes={"ex": str(EX)})
    engine = RuleEngine(rules, [(EX.Speaker, RDFS.subClassOf, EX.Device)], registry=registry)
    assert seminaive.eligible(engine)
    good = [(EX.a, EX.p, Literal("fine")), (EX.a, RDF.type, EX.Speaker)]
    with pytest.raises(ValueError, match="boom"):
        engine.load([*good, (EX.b, EX.p, Literal("boom"))])
    assert engine.count() == 0
    engine.load(good)
    assert (EX.a, EX.q, Literal("fine")) in engine
    assert (EX.a, RDF.type, EX.Device) in engine
