"""BulkMemory against rdflib's own graph operations."""

from __future__ import annotations

from rdflib import Graph, Literal, URIRef
from rdflib.plugins.stores.memory import SimpleMemory

from space._memory import BulkMemory

EX = "http://example.org/"


def _t(s: str, p: str, o: object) -> tuple:
    return (URIRef(EX + s), URIRef(EX + p), o if isinstance(o, URIRef) else Literal(o))


def test_bulk_updates_read_like_rdflib() -> None:
    bulk, plain = Graph(store=BulkMemory()), Graph(store=SimpleMemory())
    added = [_t("a", "p", 1), _t("a", "p", 2), _t("b", "q", URIRef(EX + "a")), _t("a", "p", 1)]
    removed = [_t("a", "p", 2), _t("c", "p", 3)]  # one present, one absent
    bulk.store.update((), added)
    bulk.store.update(removed, [_t("c", "r", "x")])
    for t in added:
        plain.add(t)
    for t in removed:
        plain.remove(t)
    plain.add(_t("c", "r", "x"))
    assert set(bulk) == set(plain) and len(bulk) == len(plain) == 3
    for pattern in [(None, None, None), (URIRef(EX + "a"), None, None), (None, None, Literal(1))]:
        assert set(bulk.triples(pattern)) == set(plain.triples(pattern))
    assert bulk.store.has(_t("a", "p", 1)) and not bulk.store.has(_t("a", "p", 2))
    assert bulk.store.objects_of(URIRef(EX + "a"), URIRef(EX + "p")) == [Literal(1)]
    assert set(bulk.query("SELECT ?s WHERE { ?s ?p 1 }")) == {(URIRef(EX + "a"),)}


def test_graph_remove_by_triple_and_by_pattern() -> None:
    graph = Graph(store=BulkMemory())
    for t in [_t("a", "p", 1), _t("a", "p", 2), _t("b", "p", 1)]:
        graph.add(t)
    graph.remove(_t("a", "p", 1))
    graph.remove((URIRef(EX + "a"), None, None))
    assert set(graph) == {_t("b", "p", 1)}


def test_a_value_rewritten_many_times_leaves_no_trace_of_its_old_values() -> None:
    # A robot's reading is replaced every tick in every agent's mirror: each old value
    # left in the indexes (an empty entry per index) grew an agent's memory without end
    # and made `subjects_of(p)` step over every value the reading ever had.
    store = Graph(store=BulkMemory()).store
    reading, level = URIRef(EX + "battery"), URIRef(EX + "level")
    for value in range(1, 1001):
        store.update([(reading, level, Literal(value - 1))], [(reading, level, Literal(value))])
    store.remove((reading, None, None))
    store.update((), [(reading, level, Literal("final"))])
    assert store.subjects_of(level, None) == [reading]
    assert (len(store._pos[level]), len(store._osp), len(store._spo)) == (1, 1, 1)
