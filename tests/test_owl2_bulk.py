"""Bulk input through Oxigraph's parsers, and the live graph view of an engine."""

from __future__ import annotations

import pytest
from rdflib import OWL, RDF, RDFS, BNode, Literal, Namespace, URIRef

from space.errors import InputError
from space.reasoning import RuleEngine, read_graph, read_triples
from space.reasoning.terms import simple

EX = Namespace("http://example.org/")


def test_read_triples_equals_rdflib_on_turtle_and_ntriples(tmp_path):
    ttl = tmp_path / "a.ttl"
    ttl.write_text(
        "@prefix ex: <http://example.org/> .\n"
        'ex:r ex:battery 40 ; ex:name "robot"@en , "plain" ; ex:at [ ex:x 1.5 ] .\n'
        'ex:r ex:mode "on"^^<http://www.w3.org/2001/XMLSchema#string> .\n'
    )
    nt = tmp_path / "b.nt"
    nt.write_text("<http://example.org/s> <http://example.org/p> <http://example.org/o> .\n")
    ours = read_triples([ttl, nt])
    # xsd:string literals are simple literals (RDF 1.1), as the engine holds them.
    theirs = [tuple(simple(x) for x in t) for t in read_graph([ttl, nt])]
    strip = lambda ts: {t for t in ts if not any(isinstance(x, BNode) for x in t)}  # noqa: E731
    assert strip(ours) == strip(theirs)
    assert len(ours) == len(theirs)
    assert (EX.r, EX.mode, Literal("on")) in ours


def test_blank_nodes_of_two_files_stay_apart(tmp_path):
    for name in ("a.ttl", "b.ttl"):
        (tmp_path / name).write_text("_:b0 <http://example.org/p> <http://example.org/o> .\n")
    triples = read_triples([tmp_path / "a.ttl", tmp_path / "b.ttl"])
    assert len({s for s, _, _ in triples}) == 2


def test_a_malformed_file_is_named_with_its_line(tmp_path):
    bad = tmp_path / "bad.nt"
    bad.write_text("<http://example.org/s> <http://example.org/p> .\n")
    with pytest.raises(InputError, match=r"bad\.nt.*line|bad\.nt.*1"):
        read_triples([bad])
    with pytest.raises(InputError, match="no such file"):
        read_triples([tmp_path / "missing.ttl"])


def test_graph_is_a_live_read_only_view():
    tbox = [(EX.Speaker, RDFS.subClassOf, EX.Device)]
    e = RuleEngine([], tbox)
    e.load([(EX.s, RDF.type, EX.Speaker)])
    g = e.graph
    assert (EX.s, RDF.type, EX.Device) in g
    e.apply(added=[(EX.t, RDF.type, EX.Speaker)], removed=[(EX.s, RDF.type, EX.Speaker)])
    # The same object shows the new state: nothing was rebuilt.
    assert e.graph is g
    assert set(g.subjects(RDF.type, EX.Device)) == {EX.t}
    assert len(g) == e.count() == len(list(e.triples()))
    with pytest.raises(TypeError, match="read-only"):
        g.add((EX.a, EX.b, EX.c))
    assert (URIRef("http://example.org/never"), OWL.sameAs, None) not in g
