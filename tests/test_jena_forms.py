"""Jena's rule forms run by this engine: axioms, builtin-only bodies, backward and nested rules,
list-mapping builtins, table and hide."""

from __future__ import annotations

from rdflib import OWL, RDF, RDFS, Literal, Namespace

from space.reasoning import RuleEngine, default_registry, load_rules, parse_rules

EX = Namespace("http://example.org/")
REG = default_registry()
HEAD = "@prefix ex: <http://example.org/>\n"


def engine(text: str, data=()) -> RuleEngine:
    built = RuleEngine(parse_rules(HEAD + text, REG, source="t.rules"), owl=False)
    built.load(data)
    return built


def test_axioms_and_builtin_only_bodies_fire_at_load():
    e = engine(
        "-> (ex:a ex:p ex:b) .\n"
        "[t: makeTemp(?x) -> (?x ex:is ex:temp)]\n"
        "[c: now(?t) -> (ex:clock ex:at ?t)]\n"
        "[f: (ex:a ex:p ?y) -> (?y ex:q ex:a)]\n"
    )
    assert (EX.a, EX.p, EX.b) in e
    assert (EX.b, EX.q, EX.a) in e  # the axiom feeds the other rules
    assert len(list(e.graph.subjects(EX["is"], EX.temp))) == 1
    assert len(list(e.graph.objects(EX.clock, EX.at))) == 1
    assert e.why((EX.a, EX.p, EX.b)).rule == "<rule at t.rules:2:1>"


def test_a_novalue_only_rule_fires_at_load_and_again_when_its_triple_goes():
    e = engine("[n: noValue(ex:door ex:state) -> (ex:door ex:state 'unknown')]\n")
    assert set(e.graph.objects(EX.door, EX.state)) == {Literal("unknown")}
    e.apply(removed=[(EX.door, EX.state, Literal("unknown"))])
    assert set(e.graph.objects(EX.door, EX.state)) == {Literal("unknown")}


def test_a_backward_rule_runs_forward():
    e = engine("[b: (?x ex:grand ?z) <- (?x ex:parent ?y), (?y ex:parent ?z)]\n")
    e.apply(added=[(EX.a, EX.parent, EX.b), (EX.b, EX.parent, EX.c)])
    assert (EX.a, EX.grand, EX.c) in e
    assert e.rules[0].backward


def test_a_nested_rule_fires_while_its_parent_matches_and_its_conclusions_go_with_it():
    e = engine("[dom: (?p rdfs:domain ?c) -> [(?x rdf:type ?c) <- (?x ?p ?y)]]\n")
    e.apply(added=[(EX.drives, RDFS.domain, EX.Driver), (EX.ann, EX.drives, EX.car)])
    assert (EX.ann, RDF.type, EX.Driver) in e
    e.apply(removed=[(EX.drives, RDFS.domain, EX.Driver)])
    assert (EX.ann, RDF.type, EX.Driver) not in e


def test_list_map_builtins_follow_the_list():
    e = engine(
        "[u: (?c ex:unionOf ?l) -> listMapAsSubject(?l, rdfs:subClassOf, ?c)]\n"
        "[o: (?c ex:members ?l) -> listMapAsObject(?c, ex:has, ?l)]\n"
        "[d: (?c ex:allDifferent ?l) -> assertDisjointPairs(?l)]\n",
        [
            (EX.U, EX.unionOf, EX.l1),
            (EX.U, EX.members, EX.l1),
            (EX.U, EX.allDifferent, EX.l1),
            (EX.l1, RDF.first, EX.A),
            (EX.l1, RDF.rest, EX.l2),
            (EX.l2, RDF.first, EX.B),
            (EX.l2, RDF.rest, RDF.nil),
        ],
    )
    assert {(EX.A, RDFS.subClassOf, EX.U), (EX.B, RDFS.subClassOf, EX.U)} <= set(e.graph)
    assert set(e.graph.objects(EX.U, EX.has)) == {EX.A, EX.B}
    assert set(e.graph.objects(EX.A, OWL.differentFrom)) == {EX.B}
    assert not any("jena-list" in str(p) for _, p, _ in e.graph)  # the marks stay hidden


def test_table_is_accepted_and_hide_hides_from_listings_but_not_from_rules():
    e = engine(
        "-> table(ex:p). -> tableAll(). -> hide(ex:secret).\n"
        "[s: (?x ex:p ?y) -> (?x ex:secret ?y)]\n"
        "[t: (?x ex:secret ?y) -> (?x ex:seen ?y)]\n",
        [(EX.a, EX.p, EX.b)],
    )
    assert (EX.a, EX.seen, EX.b) in e
    assert (EX.a, EX.secret, EX.b) not in set(e.graph)


def test_hide_hides_every_triple_naming_the_node_as_jena_filters_its_answers():
    # Jena's rdfs-fb-tgc and OWL rule sets hide rb:xsdBase: its own typing as a property
    # (concluded by rules about properties) is as hidden as its uses as a predicate.
    e = engine(
        "-> hide(ex:secret).\n"
        "[s: (?x ex:p ?y) -> (?x ex:secret ?y)]\n"
        "[prop: (?x ?p ?y) -> (?p rdf:type rdf:Property)]\n"
        "[about: (?x ex:p ?y) -> (?y ex:about ex:secret)]\n",
        [(EX.a, EX.p, EX.b)],
    )
    assert (EX.p, RDF.type, RDF.Property) in e
    assert (EX.secret, RDF.type, RDF.Property) not in e  # as a subject
    assert (EX.b, EX.about, EX.secret) not in e  # as an object
    assert not any(EX.secret in t for t in e.graph)
    assert e.count() == len(set(e.graph))
    assert not any(EX.secret in t for t in e.triples())


def test_hidden_triples_are_not_reported_in_an_update():
    e = engine("-> hide(ex:secret).\n[s: (?x ex:p ?y) -> (?x ex:secret ?y)]\n", [])
    delta = e.apply(added=[(EX.a, EX.p, EX.b)])
    assert [c.triple for c in delta.added] == [(EX.a, EX.p, EX.b)]
    assert delta.inferred_added == ()


def test_hidden_predicates_are_not_matched_either():
    e = engine(
        "-> hide(ex:secret).\n[s: (?x ex:p ?y) -> (?x ex:secret ?y)]\n", [(EX.a, EX.p, EX.b)]
    )
    assert list(e.match(EX.a, None, None)) == [(EX.a, EX.p, EX.b)]


def test_include_takes_a_file_url_relative_to_the_including_file(tmp_path):
    (tmp_path / "inner.rules").write_text("[inner: (?a ex:p ?b) -> (?b ex:p ?a)]\n")
    outer = tmp_path / "outer.rules"
    outer.write_text(HEAD + "@include <file:inner.rules>\n[outer: (?a ex:q ?b) -> (?a ex:p ?b)]\n")
    rules = load_rules([outer], REG)
    assert [r.name for r in rules] == ["inner", "outer"]  # included rules first, as in Jena


def test_a_shared_name_labels_a_rule_with_a_numeric_constant_by_file_and_line_too():
    rules = parse_rules(
        HEAD + "[r: (?x ex:n 1) -> (?x ex:one ex:yes)]\n[r: (?x ex:p ?y) -> (?x ex:q ?y)]\n",
        REG,
        source="t.rules",
        warn=lambda message: None,
    )
    e = RuleEngine(rules, owl=False)
    e.load([(EX.a, EX.n, Literal(1))])
    assert e.why((EX.a, EX.one, EX.yes)).rule == "r (t.rules:2)"  # type: ignore[union-attr]
